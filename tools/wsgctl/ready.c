/*
 * wsgctl wait-ready: wait until the gripper answers, for a script that has
 * just started it (a container, a service, an emulator in a test). It
 * connects and asks a harmless question, Get System State (40h, once: no
 * auto update), again and again until an answer comes or --timeout has
 * passed; any answer will do, an error status too, since it shows the
 * gripper is there. Through --control the question is the channel's
 * "time". Failed attempts are not said (they are what is being waited
 * through); the last one's reason is, when time runs out.
 */
#define _GNU_SOURCE /* nanosleep */

#include "wsgctl.h"

#include <errno.h>
#include <stdio.h>
#include <string.h>
#include <time.h>

/* Between attempts: often enough that the wait ends soon after the
 * gripper is up, seldom enough not to load it. */
#define READY_RETRY_MS 100
/* One attempt's wait for an answer, at most: a gripper that is up answers
 * in milliseconds, and an attempt that hangs should not eat the rest. */
#define READY_ATTEMPT_MS 1000

/* Deadlines are wsg_client_now_ns() nanoseconds. One attempt: 1 the
 * gripper (or the channel) answered, 0 not (yet),
 * or -EXIT_USAGE for an address that will never do. what says why not. */
static int ready_try(struct ctx *x, uint64_t deadline, const char **what)
{
    struct opts o = x->o;
    struct conn c;
    uint64_t now = wsg_client_now_ns(),
             until = wsg_client_deadline(READY_ATTEMPT_MS);
    int rc;

    if (until > deadline)
        until = deadline;
    o.probe = 1;
    o.timeout_s = until > now ? (double)(until - now) / 1e9 : 0.0;
    if (o.timeout_s < 0.001)
        o.timeout_s = 0.001;
    rc = conn_open(&c, &o);
    if (rc == -EXIT_USAGE) {
        conn_close(&c);
        return rc;
    }
    if (rc < 0) {
        *what = "cannot connect";
        conn_close(&c);
        return 0;
    }
    if (o.kind == LINK_CONTROL) {
        char line[256];

        rc = wsg_client_line(&c.l, "time", line, sizeof line, until);
        rc = rc == 1 && !strncmp(line, "ok", 2);
    } else {
        static const uint8_t once[3] = {0, 0, 0}; /* no auto update */
        struct wsg_client_frame r;

        rc =
            wsg_client_send_frame(&c.l, WSG_CMD_GET_SYSTEM_STATE, once,
                                  sizeof once) == 0 &&
            wsg_client_recv_id(&c.l, WSG_CMD_GET_SYSTEM_STATE, &r, until) == 1;
    }
    if (!rc)
        *what = "no answer";
    /* Over TCP the close is announced (07h), as every close of wsgctl. */
    conn_close(&c);
    return rc;
}

int c_wait_ready(struct ctx *x, int argc, char **argv)
{
    uint64_t start = wsg_client_now_ns();
    uint64_t deadline = timeout_deadline(&x->o);
    const char *what = "no answer";
    int rc;

    (void)argc;
    (void)argv;
    for (;;) {
        rc = ready_try(x, deadline, &what);
        if (rc < 0)
            return -rc;
        if (rc == 1) {
            if (x->o.jo)
                jout_add(x->o.jo, ",\"waited\":%.3f",
                         (double)(wsg_client_now_ns() - start) / 1e9);
            return EXIT_OK;
        }
        if (interrupted)
            return EXIT_INTERRUPTED;
        if (wsg_client_deadline(READY_RETRY_MS) >= deadline)
            break;
        {
            struct timespec ts = {0, READY_RETRY_MS * 1000000L};

            nanosleep(&ts, NULL);
        }
    }
    err("%s not ready within %.1f s: %s", x->o.addr, x->o.timeout_s, what);
    return EXIT_CONN;
}
