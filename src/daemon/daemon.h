/*
 * The daemon's whole context in one struct, built in main: options, the
 * emulated device, the loop and the open transports. Nothing of it is
 * global, so the parts can be driven and torn down in any test harness.
 */
#ifndef WSG_DAEMON_H
#define WSG_DAEMON_H

#include <stddef.h>

#include "log.h"
#include "loop.h"
#include "options.h"
#include "transport.h"
#include "wsg/device.h"

struct wsg_daemon {
    struct wsg_options opt;
    struct wsg_device dev;
    struct wsg_loop loop;
    struct wsg_transport transports[WSG_TRANSPORT_MAX];
    size_t ntransports;
    struct wsg_log log; /* the communication log (--log); closed: f NULL */
};

/* Set up the device, the loop and every transport the options enable. On
 * failure print "wsgemu: ..." and return -errno; wsg_daemon_close is safe
 * either way. */
int wsg_daemon_open(struct wsg_daemon *d);
/* Print the ready line on stdout and flush it. */
int wsg_daemon_announce(struct wsg_daemon *d);
/* Serve until SIGINT/SIGTERM (0) or a failure (-errno, printed). */
int wsg_daemon_run(struct wsg_daemon *d);
void wsg_daemon_close(struct wsg_daemon *d);

#endif
