/*
 * wsgemu's entry point: parse the options, open everything, announce
 * readiness (the ready line, and READY=1 to a service manager), serve until
 * SIGINT/SIGTERM. Exit status 0 after a signal, 1 when something cannot be
 * opened or fails, 2 for bad options.
 */
#define _GNU_SOURCE

#include <signal.h>
#include <string.h>

#include "daemon.h"
#include "notify.h"

int main(int argc, char **argv)
{
    struct wsg_daemon d;
    struct sigaction sa;
    int status = 1;

    /* Before anything else: a signal sent while the options are read is
     * kept for the event loop, not the death of a half-started daemon. */
    if (wsg_daemon_block_signals() < 0)
        return 1;
    memset(&d, 0, sizeof d);
    wsg_options_defaults(&d.opt);
    switch (wsg_options_parse(&d.opt, argc, argv)) {
    case WSG_OPTIONS_RUN:
        break;
    case WSG_OPTIONS_EXIT:
        return 0;
    default:
        return 2;
    }

    /* A peer that vanishes must cost a send() error, not the process. */
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = SIG_IGN;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGPIPE, &sa, NULL);

    if (wsg_daemon_open(&d) < 0)
        goto out;
    if (wsg_daemon_announce(&d) < 0)
        goto out;
    if (wsg_daemon_run(&d) == 0)
        status = 0;
    /* A service manager (Type=notify) learns that the end is on purpose. */
    wsg_notify("STOPPING=1");
out:
    wsg_daemon_close(&d);
    return status;
}
