/*
 * Assembly of the daemon: the signal mask first (main blocks the handled
 * signals before anything else, so none takes its default action while
 * the daemon starts), the reactor and its services (the scheduler,
 * the file watches, a signalfd); then each gripper's device configured
 * from the options, its lookup routing final results by tag to the
 * gripper's own transport that owns the session, and its transports
 * opened in a fixed order, each from its own config struct, with the
 * scheduler as their host. A fleet opens the same interfaces for every
 * gripper, each with its own addresses (wsg_options_gripper), and the
 * control channel and the web page once for the process, last.
 */
#define _GNU_SOURCE /* signalfd */

#include "daemon.h"

#include "notify.h"

#include <errno.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/epoll.h>
#include <sys/resource.h>
#include <sys/signalfd.h>
#include <unistd.h>

#include "wsg/plant.h"

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

static void daemon_capture_flush(void *ctx)
{
    wsg_capture_flush(ctx);
}

static void daemon_log_flush(void *ctx)
{
    wsg_log_flush(ctx);
}

/* The scheduler as the host of a gripper's transports. */
static void gripper_enter(void *ctx)
{
    struct wsg_gripper *g = ctx;

    wsg_sched_touch(g->sched, g);
}

static void gripper_leave(void *ctx)
{
    struct wsg_gripper *g = ctx;

    wsg_sched_check(g->sched, g);
}

static void gripper_defer(void *ctx)
{
    struct wsg_gripper *g = ctx;

    wsg_sched_defer(g->sched, g);
}

static void on_signal(struct wsg_watch *w, uint32_t events)
{
    struct wsg_daemon *d = w->ctx;
    struct signalfd_siginfo si;

    (void)events;
    while (read(w->fd, &si, sizeof si) == (ssize_t)sizeof si) {
        if (si.ssi_signo == SIGINT || si.ssi_signo == SIGTERM)
            wsg_reactor_stop(&d->reactor);
        else if (si.ssi_signo == SIGHUP && d->opt.log_path) {
            /* logrotate renamed the file: lines go to a new one at the
             * path. */
            char err[512];

            if (wsg_log_reopen(&d->log, d->opt.log_path, err, sizeof err))
                fprintf(stderr, "wsgemu: %s; logging on to the old file\n",
                        err);
        }
    }
}

static int open_transport(struct wsg_gripper *g,
                          const struct wsg_transport_ops *ops,
                          const struct wsg_transport_env *env, const void *cfg)
{
    struct wsg_transport *t = &g->transports[g->ntransports];
    char err[WSG_TRANSPORT_ERR_MAX];
    int r;

    memset(t, 0, sizeof *t);
    t->ops = ops;
    t->tag_base = (uint32_t)(g->ntransports + 1) << WSG_TAG_TRANSPORT_SHIFT;
    t->host.enter = gripper_enter;
    t->host.leave = gripper_leave;
    t->host.defer = gripper_defer;
    t->host.ctx = g;
    t->tap = &g->capture.tap;
    err[0] = '\0';
    r = ops->open(t, env, cfg, err, sizeof err);
    if (r < 0) {
        fprintf(stderr, "wsgemu: %s\n", err[0] ? err : strerror(-r));
        return r;
    }
    g->ntransports++;
    return 0;
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

/* --physics mujoco: the gripper's fingers move in a MuJoCo scene, the
 * model's own or --scene's, on --scene-fingers' joints. */
static int gripper_plant(struct wsg_gripper *g, const struct wsg_options *o)
{
    char err[512], left[64], right[64];
    const char *l = NULL, *r = NULL, *comma;
    int rc;

    if (!o->physics || strcmp(o->physics, "builtin") == 0) {
        if (o->scene || o->scene_fingers) {
            fprintf(stderr, "wsgemu: --scene and --scene-fingers need "
                            "--physics mujoco\n");
            return -EINVAL;
        }
        return 0;
    }
    if (strcmp(o->physics, "mujoco") != 0) {
        fprintf(stderr,
                "wsgemu: --physics: unknown plant '%s' (known: builtin, "
                "mujoco)\n",
                o->physics);
        return -EINVAL;
    }
    if (o->scene_fingers) {
        comma = strchr(o->scene_fingers, ',');
        if (!comma || comma == o->scene_fingers || !comma[1] ||
            strchr(comma + 1, ',') ||
            (size_t)(comma - o->scene_fingers) >= sizeof left ||
            strlen(comma + 1) >= sizeof right) {
            fprintf(stderr, "wsgemu: --scene-fingers: want LEFT,RIGHT (two "
                            "joint names)\n");
            return -EINVAL;
        }
        memcpy(left, o->scene_fingers, (size_t)(comma - o->scene_fingers));
        left[comma - o->scene_fingers] = '\0';
        strcpy(right, comma + 1);
        l = left;
        r = right;
    }
    rc = wsg_plant_mujoco_open(&g->plant,
                               wsg_axis_cfg(wsg_device_axis(&g->dev)),
                               o->scene, l, r, err, sizeof err);
    if (rc < 0) {
        fprintf(stderr, "wsgemu: --physics mujoco: %s\n", err);
        g->plant = NULL;
        return rc;
    }
    wsg_axis_set_plant(wsg_device_axis(&g->dev), g->plant);
    return 0;
}

static int open_gripper(struct wsg_daemon *d, struct wsg_gripper *g,
                        unsigned index)
{
    struct wsg_options o;
    struct wsg_transport_env env;
    char path[WSG_OPTIONS_PATH_MAX];
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
    for (r = 0; r < 2; r++) {
        char err[512];

        if (!o.finger_kind[r])
            continue;
        if (wsg_gripper_finger(g, r, o.finger_kind[r] - 1, o.finger_model[r],
                               err, sizeof err) < 0) {
            fprintf(stderr, "wsgemu: --finger%d: %s\n", r, err);
            return -EINVAL;
        }
    }
    if (o.initial_part.given)
        wsg_axis_set_part(wsg_device_axis(&g->dev), o.initial_part.value,
                          o.initial_part_stiffness);
    r = gripper_plant(g, &o);
    if (r < 0)
        return r;
    /* The web page's log view reads the same lines (log.h). */
    if (d->log.f || d->opt.web_enabled)
        wsg_log_attach(&d->log, &g->tap, &g->dev,
                       d->opt.grippers > 1 ? (int)index : -1);
    wsg_capture_tap_init(&g->capture, &d->capture, &g->dev,
                         d->opt.grippers > 1 ? (int)index : -1);
    g->dev.lookup = gripper_lookup;
    g->dev.lookup_ctx = g;
    g->runner = &d->runner;
    g->script_memory = (size_t)o.script_memory << 20;
    g->script_dir = o.script_dir;
    r = wsg_gripper_set_latency(g, o.latency_ms, o.latency_jitter_ms);
    if (r < 0) {
        fprintf(stderr, "wsgemu: --latency: %s\n", strerror(-r));
        return r;
    }

    memset(&env, 0, sizeof env);
    env.reactor = &d->reactor;
    env.fswatch = &d->fswatch;
    env.dev = &g->dev;
    env.rx = d->rx;
    env.rxlen = WSG_DAEMON_RX_MAX;
    /* In this order on the ready line. */
    if (o.tcp_enabled) {
        struct wsg_tcp_config c = {
            o.tcp,
            o.max_clients,
            o.check_crc,
            o.text_interface,
            {o.release_pullback, WSG_GCL_DEFAULT_SPEED}};

        r = open_transport(g, &wsg_tcp_ops, &env, &c);
        if (r < 0)
            return r;
    }
    if (o.udp_enabled) {
        struct wsg_udp_config c = {o.udp, o.udp_remote_port, o.check_crc};

        r = open_transport(g, &wsg_udp_ops, &env, &c);
        if (r < 0)
            return r;
    }
    if (o.pty_path) {
        struct wsg_pty_config c = {o.pty_path, o.check_crc,
                                   o.pty_mode_given ? (int)o.pty_mode : -1,
                                   o.pty_group_given ? (long)o.pty_group : -1};

        r = open_transport(g, &wsg_pty_ops, &env, &c);
        if (r < 0)
            return r;
    }
    if (o.can_iface) {
        struct wsg_can_config c = {o.can_iface, o.can_id, o.check_crc};

        r = open_transport(g, &wsg_can_ops, &env, &c);
        if (r < 0)
            return r;
    }
    return 0;
}

/* --script: a file that cannot be read is a bad start (status 1); a
 * script that fails is the gripper's business, as on a real one: D20, its
 * error on stderr and in the log, and the gripper serves on. */
static int start_script(struct wsg_daemon *d, struct wsg_gripper *g)
{
    struct wsg_script *h;
    char err[512];
    int r;

    r = wsg_gripper_script(g, &h);
    if (r < 0) {
        fprintf(stderr, "wsgemu: --script: %s\n", strerror(-r));
        return r;
    }
    wsg_sched_touch(&d->sched, g);
    r = wsg_script_start(h, d->opt.script_path, err, sizeof err);
    wsg_axis_settle(wsg_device_axis(&g->dev));
    wsg_sched_check(&d->sched, g);
    if (r == -EINVAL) {
        fprintf(stderr, "wsgemu: script %s failed: %s\n", d->opt.script_path,
                err);
        return 0;
    }
    if (r < 0)
        fprintf(stderr, "wsgemu: --script: %s\n", err);
    return r;
}

/* The signals the daemon handles (through a descriptor, below). */
static void handled_signals(sigset_t *mask)
{
    sigemptyset(mask);
    sigaddset(mask, SIGINT);
    sigaddset(mask, SIGTERM);
    sigaddset(mask, SIGHUP); /* reopen the log */
}

int wsg_daemon_block_signals(void)
{
    sigset_t mask;

    handled_signals(&mask);
    return sigprocmask(SIG_BLOCK, &mask, NULL) < 0 ? -errno : 0;
}

/* Signals come through a descriptor. They were blocked first thing in
 * main (wsg_daemon_block_signals), so one sent while the options were
 * read, or right after the ready line, waits here, never taking the
 * default action. They stay blocked after close: a second SIGTERM must
 * not turn a clean exit into death by signal. */
static int open_signals(struct wsg_daemon *d)
{
    sigset_t mask;
    int fd, r;

    r = wsg_daemon_block_signals();
    if (r < 0)
        return r;
    handled_signals(&mask);
    fd = signalfd(-1, &mask, SFD_NONBLOCK | SFD_CLOEXEC);
    if (fd < 0)
        return -errno;
    wsg_watch_init(&d->signal, fd, on_signal, d);
    return wsg_reactor_add(&d->reactor, &d->signal, EPOLLIN);
}

/* The reactor and the process's services on it. */
static int open_services(struct wsg_daemon *d)
{
    int r;

    r = wsg_reactor_init(&d->reactor);
    if (r < 0)
        return r;
    r = open_signals(d);
    if (r < 0)
        return r;
    wsg_fswatch_init(&d->fswatch, &d->reactor);
    /* The scheduler's hook first: peers are reaped and grippers
     * rescheduled before the log is flushed. */
    r = wsg_sched_init(&d->sched, &d->reactor, d->opt.step_us);
    if (r < 0)
        return r;
    r = wsg_runner_init(&d->runner, &d->reactor, &d->sched);
    if (r < 0)
        return r;
    if (d->log.f)
        r = wsg_reactor_after(&d->reactor, daemon_log_flush, &d->log);
    if (r < 0)
        return r;
    /* Always: the control channel may start a capture later. */
    return wsg_reactor_after(&d->reactor, daemon_capture_flush, &d->capture);
}

int wsg_daemon_open(struct wsg_daemon *d)
{
    unsigned i;
    int r;

    d->ngrippers = 0;
    d->control = NULL;
    d->web = NULL;
    d->signal.fd = -1;
    d->sched.timer.fd = -1;
    d->fswatch.watch.fd = -1;
    d->runner.watch.fd = -1;
    d->reactor.epfd = -1;
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
        wsg_log_limit(&d->log, d->opt.log_max);
    }
    d->capture.max = d->opt.capture_max;
    if (d->opt.capture_path) {
        char err[WSG_CAPTURE_PATH_MAX + 128];

        r = wsg_capture_start(&d->capture, d->opt.capture_path, err,
                              sizeof err);
        if (r < 0) {
            fprintf(stderr, "wsgemu: %s\n", err);
            return r;
        }
    }
    d->rx = malloc(WSG_DAEMON_RX_MAX);
    if (!d->rx) {
        fprintf(stderr, "wsgemu: no memory for the receive buffer\n");
        return -ENOMEM;
    }
    r = open_services(d);
    if (r < 0) {
        fprintf(stderr, "wsgemu: cannot set up the event loop: %s\n",
                strerror(-r));
        return r;
    }
    r = wsg_sched_set_scale(&d->sched, d->opt.time_scale);
    if (r < 0) {
        fprintf(stderr, "wsgemu: time scale %g: must be in %g..%g\n",
                d->opt.time_scale, WSG_SCHED_SCALE_MIN, WSG_SCHED_SCALE_MAX);
        return r;
    }
    r = wsg_sched_set_grippers(&d->sched, d->grippers, d->opt.grippers);
    if (r < 0) {
        fprintf(stderr, "wsgemu: no memory for %u grippers\n",
                d->opt.grippers);
        return r;
    }
    for (i = 0; i < d->opt.grippers; i++) {
        /* Counted before it is complete: close undoes what it opened. */
        d->ngrippers = i + 1;
        r = open_gripper(d, &d->grippers[i], i);
        if (r < 0)
            return r;
    }
    /* The startup script, on every gripper, once all can be reached:
     * it registers its IDs before the ready line is printed. */
    for (i = 0; d->opt.script_path && i < d->opt.grippers; i++) {
        r = start_script(d, &d->grippers[i]);
        if (r < 0)
            return r;
    }
    if (d->opt.control_enabled) {
        char err[WSG_TRANSPORT_ERR_MAX];

        /* Last but the web page: the ready line ends with control= and
         * web=. */
        r = wsg_control_open(&d->control, &d->reactor, &d->sched,
                             &d->opt.control, err, sizeof err);
        if (r < 0) {
            fprintf(stderr, "wsgemu: %s\n", err);
            return r;
        }
        wsg_control_set_capture(d->control, &d->capture);
    }
    if (d->opt.web_enabled) {
        char err[WSG_TRANSPORT_ERR_MAX];

        r = wsg_web_open(&d->web, d, err, sizeof err);
        if (r < 0) {
            fprintf(stderr, "wsgemu: %s\n", err);
            return r;
        }
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

/* " name=value", or ",value" after the first gripper's. */
static int put_field(char **buf, size_t *cap, size_t *used, const char *name,
                     const char *v, int first)
{
    int r;

    if (first) {
        r = put(buf, cap, used, " ");
        if (r == 0)
            r = put(buf, cap, used, name);
        if (r == 0)
            r = put(buf, cap, used, "=");
    } else {
        r = put(buf, cap, used, ",");
    }
    return r < 0 ? r : put(buf, cap, used, v);
}

void wsg_daemon_reconfigure(struct wsg_daemon *d, unsigned model)
{
    struct wsg_transport_settings ts;
    size_t i, j;
    unsigned q;

    ts.check_crc = d->opt.check_crc;
    ts.text = d->opt.text_interface;
    for (i = 0; i < d->ngrippers; i++) {
        struct wsg_gripper *g = &d->grippers[i];
        struct wsg_axis *ax = wsg_device_axis(&g->dev);

        /* Its time brought up to date first, its deadline checked after,
         * as for any change from outside its interfaces. */
        wsg_sched_touch(&d->sched, g);
        g->dev.disconnect_fast_stop = d->opt.disconnect_fast_stop;
        for (q = WSG_AXIS_ACCELERATION; q <= WSG_AXIS_WIDTH_TOLERANCE; q++)
            if (model & (1u << q))
                wsg_axis_configure(ax, (enum wsg_axis_setting)q,
                                   wsg_axis_config_get(
                                       &d->opt.axis, (enum wsg_axis_setting)q),
                                   NULL);
        for (j = 0; j < g->ntransports; j++) {
            struct wsg_transport *t = &g->transports[j];

            if (t->ops->configure)
                t->ops->configure(t, &ts);
        }
        wsg_axis_settle(ax);
        wsg_sched_check(&d->sched, g);
    }
}

/* A service manager (systemd, Type=notify) waits for this, after the ready
 * line, and shows the line as the service's status. Not being heard costs
 * a warning only: the ready line is out, and systemd ends a service that
 * never says READY=1 by its own timeout. */
static void notify_ready(const char *line)
{
    static const char ready[] = "READY=1\nSTATUS=";
    char *msg = malloc(sizeof ready + strlen(line));
    int r = -ENOMEM;

    if (msg) {
        memcpy(msg, ready, sizeof ready - 1);
        strcpy(msg + sizeof ready - 1, line);
        r = wsg_notify(msg);
        free(msg);
    }
    if (r < 0)
        fprintf(stderr, "wsgemu: NOTIFY_SOCKET: %s\n", strerror(-r));
}

/* "ready tcp=A udp=B ... control=C web=D"; in a fleet each gripper field lists
 * every gripper's value, comma-separated, in gripper order. */
int wsg_daemon_announce(struct wsg_daemon *d)
{
    char *line = NULL, v[WSG_OPTIONS_PATH_MAX + 32];
    size_t cap = 0, used = 0;
    size_t j, i;
    int r;

    r = put(&line, &cap, &used, "ready");
    for (j = 0; r == 0 && d->ngrippers > 0 && j < d->grippers[0].ntransports;
         j++)
        for (i = 0; r == 0 && i < d->ngrippers; i++) {
            const struct wsg_transport *t = &d->grippers[i].transports[j];

            r = t->ops->describe(t, v, sizeof v);
            if (r == 0)
                r = put_field(&line, &cap, &used, t->ops->name, v, i == 0);
        }
    if (r == 0 && d->control) {
        r = wsg_control_describe(d->control, v, sizeof v);
        if (r == 0)
            r = put_field(&line, &cap, &used, "control", v, 1);
    }
    if (r == 0 && d->web) {
        r = wsg_web_describe(d->web, v, sizeof v);
        if (r == 0)
            r = put_field(&line, &cap, &used, "web", v, 1);
    }
    if (r < 0) {
        fprintf(stderr, "wsgemu: ready line: %s\n", strerror(-r));
        free(line);
        return r;
    }
    /* Scripts block on this line: it must not sit in a pipe's buffer. */
    printf("%s\n", line);
    fflush(stdout);
    notify_ready(line);
    free(line);
    return 0;
}

int wsg_daemon_run(struct wsg_daemon *d)
{
    int r = wsg_reactor_run(&d->reactor);

    if (r < 0)
        fprintf(stderr, "wsgemu: event loop: %s\n", strerror(-r));
    return r;
}

static void close_gripper(struct wsg_gripper *g)
{
    /* In reverse, and before the reactor's epoll descriptor goes. */
    while (g->ntransports > 0) {
        struct wsg_transport *t = &g->transports[--g->ntransports];

        t->ops->close(t);
    }
    /* What still waits has no one to go to. */
    wsg_gripper_fini(g);
}

void wsg_daemon_close(struct wsg_daemon *d)
{
    wsg_web_close(d->web);
    d->web = NULL;
    wsg_control_close(d->control);
    d->control = NULL;
    while (d->ngrippers > 0)
        close_gripper(&d->grippers[--d->ngrippers]);
    wsg_runner_fini(&d->runner);
    wsg_sched_fini(&d->sched);
    wsg_fswatch_fini(&d->fswatch);
    if (d->signal.fd >= 0)
        close(d->signal.fd);
    d->signal.fd = -1;
    wsg_reactor_fini(&d->reactor);
    free(d->rx);
    d->rx = NULL;
    /* Last: closing peers may still log their final packets. */
    if (d->grippers && (d->log.f || d->opt.web_enabled)) {
        size_t i;

        for (i = 0; i < d->opt.grippers; i++)
            wsg_log_detach(&d->grippers[i].tap, &d->grippers[i].dev);
    }
    wsg_log_close(&d->log);
    wsg_capture_stop(&d->capture);
    free(d->grippers);
    d->grippers = NULL;
}
