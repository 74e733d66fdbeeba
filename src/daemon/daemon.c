/*
 * Assembly of the daemon: each gripper's device is configured from the
 * options, its lookup routes final results by tag to the gripper's own
 * transport that owns the session, and its transports are opened in a
 * fixed order after the loop (whose signal mask must be in place before
 * anything can be announced). A fleet opens the same interfaces for every
 * gripper, each with its own addresses (wsg_options_gripper), and the
 * control channel once for the process, last.
 */
#include "daemon.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>

/* Descriptors a gripper can hold with every interface open and no client:
 * TCP and UDP sockets, the pty's master and inotify, a CAN socket. */
#define WSG_FDS_PER_GRIPPER 5u
/* The process's own: epoll, timerfd, signalfd, stdio, control, the log,
 * and room for clients. */
#define WSG_FDS_SPARE 64u

static struct wsg_session *gripper_lookup(void *ctx, uint32_t tag)
{
    struct wsg_gripper *g = ctx;

    return wsg_transport_lookup(g->transports, g->ntransports, tag);
}

static void daemon_log_flush(void *ctx)
{
    wsg_log_flush(ctx);
}

static int open_transport(struct wsg_transport *t, size_t index,
                          const struct wsg_transport_ops *ops,
                          const struct wsg_transport_env *env)
{
    char err[512];
    int r;

    memset(t, 0, sizeof *t);
    t->ops = ops;
    t->tag_base = (uint32_t)(index + 1) << WSG_TAG_TRANSPORT_SHIFT;
    t->gripper = env->gripper;
    err[0] = '\0';
    r = ops->open(t, env, err, sizeof err);
    if (r < 0)
        fprintf(stderr, "wsgemu: %s\n", err[0] ? err : strerror(-r));
    return r;
}

/* A fleet needs a descriptor or more per interface and gripper: take what
 * the hard limit allows, and say so up front when even that is short. */
static int raise_fd_limit(const struct wsg_options *o)
{
    struct rlimit rl;
    rlim_t need = (rlim_t)o->grippers * WSG_FDS_PER_GRIPPER + WSG_FDS_SPARE;

    if (getrlimit(RLIMIT_NOFILE, &rl) < 0)
        return -errno;
    if (rl.rlim_cur >= need)
        return 0;
    if (rl.rlim_max != RLIM_INFINITY && rl.rlim_max < need) {
        fprintf(stderr,
                "wsgemu: %u grippers need up to %lu file descriptors; the "
                "hard limit is %lu (raise it: ulimit -Hn)\n",
                o->grippers, (unsigned long)need, (unsigned long)rl.rlim_max);
        return -EMFILE;
    }
    rl.rlim_cur = need;
    if (setrlimit(RLIMIT_NOFILE, &rl) < 0)
        return -errno;
    return 0;
}

static int open_gripper(struct wsg_daemon *d, struct wsg_gripper *g,
                        unsigned index)
{
    struct wsg_options o;
    struct wsg_transport_env env;
    char path[WSG_OPTIONS_PATH_MAX];
    size_t i;
    int r;

    wsg_options_gripper(&d->opt, index, &o, path, sizeof path);
    g->index = index;
    wsg_device_init(&g->dev, &o.axis);
    g->dev.disconnect_fast_stop = o.disconnect_fast_stop;
    /* The stored settings of the web page (the axis config already holds
     * the model's defaults overridden by the options). */
    g->dev.info.serial = o.serial;
    if (o.device_tag) {
        g->dev.tag_len = strlen(o.device_tag);
        memcpy(g->dev.tag, o.device_tag, g->dev.tag_len);
        g->dev.tag[g->dev.tag_len] = '\0';
    }
    if (o.initial_part.given)
        wsg_axis_set_part(&g->dev.axis, o.initial_part.value,
                          o.initial_part_stiffness);
    if (d->log.f)
        wsg_log_attach(&d->log, &g->tap, &g->dev,
                       d->opt.grippers > 1 ? (int)index : -1);
    g->dev.lookup = gripper_lookup;
    g->dev.lookup_ctx = g;
    r = wsg_gripper_set_latency(g, o.latency_ms, o.latency_jitter_ms);
    if (r < 0) {
        fprintf(stderr, "wsgemu: --latency: %s\n", strerror(-r));
        return r;
    }

    env.loop = &d->loop;
    env.dev = &g->dev;
    env.opt = &o;
    env.gripper = g;
    {
        /* In this order on the ready line. */
        const struct {
            int on;
            const struct wsg_transport_ops *ops;
        } want[] = {{o.tcp_enabled, &wsg_tcp_ops},
                    {o.udp_enabled, &wsg_udp_ops},
                    {o.pty_path != NULL, &wsg_pty_ops},
                    {o.can_iface != NULL, &wsg_can_ops}};

        for (i = 0; i < sizeof want / sizeof want[0]; i++) {
            if (!want[i].on)
                continue;
            r = open_transport(&g->transports[g->ntransports], g->ntransports,
                               want[i].ops, &env);
            if (r < 0)
                return r;
            g->ntransports++;
        }
    }
    return 0;
}

int wsg_daemon_open(struct wsg_daemon *d)
{
    unsigned i;
    int r;

    d->ngrippers = 0;
    d->nshared = 0;
    if (d->opt.grippers > 1) {
        r = raise_fd_limit(&d->opt);
        if (r < 0)
            return r;
    }
    d->grippers = calloc(d->opt.grippers, sizeof *d->grippers);
    if (!d->grippers) {
        fprintf(stderr, "wsgemu: no memory for %u grippers\n",
                d->opt.grippers);
        return -ENOMEM;
    }
    if (d->opt.log_path) {
        char err[512];

        r = wsg_log_open(&d->log, d->opt.log_path, err, sizeof err);
        if (r < 0) {
            fprintf(stderr, "wsgemu: %s\n", err);
            return r;
        }
    }
    r = wsg_loop_init(&d->loop, d->opt.step_us);
    if (r < 0) {
        fprintf(stderr, "wsgemu: cannot set up the event loop: %s\n",
                strerror(-r));
        return r;
    }
    r = wsg_loop_set_scale(&d->loop, d->opt.time_scale);
    if (r < 0) {
        fprintf(stderr, "wsgemu: time scale %g: must be in %g..%g\n",
                d->opt.time_scale, WSG_LOOP_SCALE_MIN, WSG_LOOP_SCALE_MAX);
        return r;
    }
    if (d->log.f) {
        d->loop.settled = daemon_log_flush;
        d->loop.settled_ctx = &d->log;
    }
    for (i = 0; i < d->opt.grippers; i++) {
        /* Counted before it is complete: close undoes what it opened. */
        d->ngrippers = i + 1;
        wsg_loop_set_grippers(&d->loop, d->grippers, d->ngrippers);
        r = open_gripper(d, &d->grippers[i], i);
        if (r < 0)
            return r;
    }
    if (d->opt.control_enabled) {
        struct wsg_transport_env env;

        memset(&env, 0, sizeof env);
        env.loop = &d->loop;
        env.opt = &d->opt;
        /* Last: the ready line ends with control=. */
        r = open_transport(&d->shared[0], 0, &wsg_control_ops, &env);
        if (r < 0)
            return r;
        d->nshared = 1;
        wsg_loop_set_shared(&d->loop, d->shared, d->nshared);
    }
    return 0;
}

/* Append to a growing buffer; -ENOMEM when it cannot grow. */
static int put(char **buf, size_t *cap, size_t *used, const char *s)
{
    size_t n = strlen(s);

    if (*used + n + 1 > *cap) {
        size_t ncap = (*cap ? *cap : 256) * 2;
        char *nb;

        while (ncap < *used + n + 1)
            ncap *= 2;
        nb = realloc(*buf, ncap);
        if (!nb)
            return -ENOMEM;
        *buf = nb;
        *cap = ncap;
    }
    memcpy(*buf + *used, s, n + 1);
    *used += n;
    return 0;
}

static int put_field(char **buf, size_t *cap, size_t *used,
                     const struct wsg_transport *t, int first)
{
    char v[WSG_OPTIONS_PATH_MAX + 32];
    int r;

    if (first) {
        r = put(buf, cap, used, " ");
        if (r == 0)
            r = put(buf, cap, used, t->ops->name);
        if (r == 0)
            r = put(buf, cap, used, "=");
    } else {
        r = put(buf, cap, used, ",");
    }
    if (r == 0)
        r = t->ops->describe(t, v, sizeof v);
    return r < 0 ? r : put(buf, cap, used, v);
}

/* "ready tcp=A udp=B ... control=C"; in a fleet each gripper field lists
 * every gripper's value, comma-separated, in gripper order. */
int wsg_daemon_announce(struct wsg_daemon *d)
{
    char *line = NULL;
    size_t cap = 0, used = 0;
    size_t j, i;
    int r;

    r = put(&line, &cap, &used, "ready");
    for (j = 0; r == 0 && d->ngrippers > 0 && j < d->grippers[0].ntransports;
         j++)
        for (i = 0; r == 0 && i < d->ngrippers; i++)
            r = put_field(&line, &cap, &used, &d->grippers[i].transports[j],
                          i == 0);
    for (j = 0; r == 0 && j < d->nshared; j++)
        r = put_field(&line, &cap, &used, &d->shared[j], 1);
    if (r < 0) {
        fprintf(stderr, "wsgemu: ready line: %s\n", strerror(-r));
        free(line);
        return r;
    }
    /* Scripts block on this line: it must not sit in a pipe's buffer. */
    printf("%s\n", line);
    fflush(stdout);
    free(line);
    return 0;
}

int wsg_daemon_run(struct wsg_daemon *d)
{
    int r = wsg_loop_run(&d->loop);

    if (r < 0)
        fprintf(stderr, "wsgemu: event loop: %s\n", strerror(-r));
    return r;
}

static void close_gripper(struct wsg_gripper *g)
{
    /* In reverse, and before the loop's epoll descriptor goes. */
    while (g->ntransports > 0) {
        struct wsg_transport *t = &g->transports[--g->ntransports];

        t->ops->close(t);
    }
    /* What still waits has no one to go to. */
    wsg_gripper_fini(g);
}

void wsg_daemon_close(struct wsg_daemon *d)
{
    while (d->nshared > 0) {
        struct wsg_transport *t = &d->shared[--d->nshared];

        wsg_loop_set_shared(&d->loop, d->shared, d->nshared);
        t->ops->close(t);
    }
    while (d->ngrippers > 0)
        close_gripper(&d->grippers[--d->ngrippers]);
    wsg_loop_fini(&d->loop);
    /* Last: closing peers may still log their final packets. */
    if (d->grippers && d->log.f) {
        size_t i;

        for (i = 0; i < d->opt.grippers; i++)
            wsg_log_detach(&d->grippers[i].tap, &d->grippers[i].dev);
    }
    wsg_log_close(&d->log);
    free(d->grippers);
    d->grippers = NULL;
}
