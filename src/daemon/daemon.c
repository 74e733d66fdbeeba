/*
 * Assembly of the daemon: the device is configured from the options, its
 * lookup routes final results by tag to the transport that owns the
 * session, and transports are opened in a fixed order after the loop (whose
 * signal mask must be in place before anything can be announced).
 */
#include "daemon.h"

#include <errno.h>
#include <stdio.h>
#include <string.h>

static struct wsg_session *daemon_lookup(void *ctx, uint32_t tag)
{
    struct wsg_daemon *d = ctx;

    return wsg_transport_lookup(d->transports, d->ntransports, tag);
}

static void daemon_log_flush(void *ctx)
{
    wsg_log_flush(ctx);
}

static int open_transport(struct wsg_daemon *d,
                          const struct wsg_transport_ops *ops)
{
    struct wsg_transport_env env;
    struct wsg_transport *t;
    char err[256];
    int r;

    if (d->ntransports >= WSG_TRANSPORT_MAX)
        return -ENOSPC;
    t = &d->transports[d->ntransports];
    memset(t, 0, sizeof *t);
    t->ops = ops;
    t->tag_base = (uint32_t)(d->ntransports + 1) << WSG_TAG_TRANSPORT_SHIFT;
    env.loop = &d->loop;
    env.dev = &d->dev;
    env.opt = &d->opt;
    err[0] = '\0';
    r = ops->open(t, &env, err, sizeof err);
    if (r < 0) {
        fprintf(stderr, "wsgemu: %s\n", err[0] ? err : strerror(-r));
        return r;
    }
    d->ntransports++;
    return 0;
}

int wsg_daemon_open(struct wsg_daemon *d)
{
    int r;

    d->ntransports = 0;
    wsg_device_init(&d->dev, &d->opt.axis);
    d->dev.disconnect_fast_stop = d->opt.disconnect_fast_stop;
    /* The stored settings of the web page (the axis config already holds
     * the model's defaults overridden by the options). */
    d->dev.info.serial = d->opt.serial;
    if (d->opt.device_tag) {
        d->dev.tag_len = strlen(d->opt.device_tag);
        memcpy(d->dev.tag, d->opt.device_tag, d->dev.tag_len);
        d->dev.tag[d->dev.tag_len] = '\0';
    }
    if (d->opt.initial_part >= 0)
        wsg_axis_set_part(&d->dev.axis, d->opt.initial_part,
                          d->opt.initial_part_stiffness);
    if (d->opt.log_path) {
        char err[512];

        r = wsg_log_open(&d->log, &d->dev, d->opt.log_path, err, sizeof err);
        if (r < 0) {
            fprintf(stderr, "wsgemu: %s\n", err);
            return r;
        }
    }
    d->dev.lookup = daemon_lookup;
    d->dev.lookup_ctx = d;

    r = wsg_loop_init(&d->loop, &d->dev, d->opt.step_us);
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
    wsg_loop_set_transports(&d->loop, d->transports, 0);
    {
        /* In this order on the ready line. */
        const struct {
            int on;
            const struct wsg_transport_ops *ops;
        } want[] = {{d->opt.tcp_enabled, &wsg_tcp_ops},
                    {d->opt.udp_enabled, &wsg_udp_ops},
                    {d->opt.pty_path != NULL, &wsg_pty_ops},
                    {d->opt.can_iface != NULL, &wsg_can_ops},
                    /* Last: the ready line ends with control=. */
                    {d->opt.control_enabled, &wsg_control_ops}};
        size_t i;

        for (i = 0; i < sizeof want / sizeof want[0]; i++) {
            if (!want[i].on)
                continue;
            r = open_transport(d, want[i].ops);
            if (r < 0)
                return r;
        }
    }
    wsg_loop_set_transports(&d->loop, d->transports, d->ntransports);
    return 0;
}

int wsg_daemon_announce(struct wsg_daemon *d)
{
    char line[512];
    int r;

    r = wsg_transport_ready_line(d->transports, d->ntransports, line,
                                 sizeof line);
    if (r < 0) {
        fprintf(stderr, "wsgemu: ready line: %s\n", strerror(-r));
        return r;
    }
    /* Scripts block on this line: it must not sit in a pipe's buffer. */
    printf("%s\n", line);
    fflush(stdout);
    return 0;
}

int wsg_daemon_run(struct wsg_daemon *d)
{
    int r = wsg_loop_run(&d->loop);

    if (r < 0)
        fprintf(stderr, "wsgemu: event loop: %s\n", strerror(-r));
    return r;
}

void wsg_daemon_close(struct wsg_daemon *d)
{
    /* In reverse, and before the loop's epoll descriptor goes. */
    while (d->ntransports > 0) {
        struct wsg_transport *t = &d->transports[--d->ntransports];

        wsg_loop_set_transports(&d->loop, d->transports, d->ntransports);
        t->ops->close(t);
    }
    wsg_loop_fini(&d->loop);
    /* Last: closing peers may still log their final packets. */
    wsg_log_close(&d->log, &d->dev);
}
