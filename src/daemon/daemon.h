/*
 * The daemon's whole context in one struct, built in main: options, the
 * emulated grippers (one, or a fleet with --grippers), the loop, the
 * process's own transports (the control channel) and the communication
 * log. Nothing of it is global, so the parts can be driven and torn down in
 * any test harness.
 */
#ifndef WSG_DAEMON_H
#define WSG_DAEMON_H

#include <stddef.h>

#include "gripper.h"
#include "log.h"
#include "loop.h"
#include "options.h"
#include "transport.h"

struct wsg_daemon {
    struct wsg_options opt;
    struct wsg_gripper *grippers; /* opt.grippers of them */
    size_t ngrippers;             /* set up so far */
    struct wsg_loop loop;
    struct wsg_transport shared[1]; /* the control channel */
    size_t nshared;
    struct wsg_log log; /* the communication log (--log); closed: f NULL */
};

/* Set up the grippers, the loop and every transport the options enable. On
 * failure print "wsgemu: ..." and return -errno; wsg_daemon_close is safe
 * either way. */
int wsg_daemon_open(struct wsg_daemon *d);
/* Print the ready line on stdout and flush it. */
int wsg_daemon_announce(struct wsg_daemon *d);
/* Serve until SIGINT/SIGTERM (0) or a failure (-errno, printed). */
int wsg_daemon_run(struct wsg_daemon *d);
void wsg_daemon_close(struct wsg_daemon *d);

#endif
