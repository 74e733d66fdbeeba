/*
 * The daemon's whole context in one struct, built in main: options, the
 * emulated grippers (one, or a fleet with --grippers), the reactor and the
 * services on it (the scheduler, the file watches, the signals, the
 * control channel, the web page) and the communication log. Nothing of it is
 * global, so the parts can be driven and torn down in any test harness.
 */
#ifndef WSG_DAEMON_H
#define WSG_DAEMON_H

#include <stddef.h>

#include <stdint.h>

#include "capture.h"
#include "control.h"
#include "fswatch.h"
#include "gripper.h"
#include "log.h"
#include "options.h"
#include "reactor.h"
#include "runner.h"
#include "sched.h"
#include "transport.h"
#include "web.h"

/* The shared receive buffer: the largest datagram. */
#define WSG_DAEMON_RX_MAX 65536u

struct wsg_daemon {
    struct wsg_options opt;
    struct wsg_gripper *grippers; /* opt.grippers of them */
    size_t ngrippers;             /* set up so far */
    struct wsg_reactor reactor;
    struct wsg_sched sched;
    struct wsg_runner runner; /* preempted scripts' turns */
    struct wsg_fswatch fswatch;
    struct wsg_watch signal; /* signalfd: SIGINT and SIGTERM end the run */
    uint8_t *rx;             /* one receive buffer for every transport */
    struct wsg_ctl *control; /* NULL: no control channel */
    struct wsg_web *web;     /* NULL: no web page */
    struct wsg_log log; /* the communication log (--log); closed: f NULL */
    /* --capture, or the control channel's capture start; off: on 0. */
    struct wsg_capture capture;
};

/* Block the signals the daemon handles (SIGINT, SIGTERM, SIGHUP): first
 * thing in main, so that one sent while the daemon starts (logrotate's
 * SIGHUP, a service manager's SIGTERM) waits for the event loop instead of
 * killing it. 0 or -errno. */
int wsg_daemon_block_signals(void);
/* Set up the grippers, the reactor and its services, and every transport the
 * options enable. On failure print "wsgemu: ..." and return -errno;
 * wsg_daemon_close is safe either way. */
int wsg_daemon_open(struct wsg_daemon *d);
/* Print the ready line on stdout and flush it. */
int wsg_daemon_announce(struct wsg_daemon *d);
/* Serve until SIGINT/SIGTERM (0) or a failure (-errno, printed). */
int wsg_daemon_run(struct wsg_daemon *d);
void wsg_daemon_close(struct wsg_daemon *d);
/* Make d->opt, changed while the daemon runs (the web page's settings),
 * every running gripper's: the disconnect FAST STOP, every interface's
 * CRC check and text interface (transports' configure), and the model
 * settings whose bit (1u << enum wsg_axis_setting) is in model, from
 * d->opt.axis, as Set Acceleration and Set Force Limit take them. */
void wsg_daemon_reconfigure(struct wsg_daemon *d, unsigned model);

#endif
