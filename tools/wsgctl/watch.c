/*
 * wsgctl watch: subscribes to an auto-update stream (FLAGS 1), prints
 * each value with a timestamp until SIGINT or --count values, then
 * unsubscribes (FLAGS 0), since a UDP or serial session would go on
 * streaming after wsgctl is gone.
 */
#define _GNU_SOURCE /* getaddrinfo, sigaction, localtime_r */

#include "wsgctl.h"

#include <errno.h>
#include <netdb.h>
#include <netinet/in.h>
#include <signal.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

static void print_stamp(const struct opts *o)
{
    struct timespec ts;
    struct tm tm;
    char buf[32];

    clock_gettime(CLOCK_REALTIME, &ts);
    if (o->quiet) {
        printf("%lld.%03ld ", (long long)ts.tv_sec, ts.tv_nsec / 1000000);
        return;
    }
    localtime_r(&ts.tv_sec, &tm);
    strftime(buf, sizeof buf, "%H:%M:%S", &tm);
    printf("%s.%03ld ", buf, ts.tv_nsec / 1000000);
}

int c_watch(struct ctx *x, int argc, char **argv)
{
    static const struct {
        const char *name;
        uint8_t id;
    } what[] = {{"width", WSG_CMD_GET_WIDTH},
                {"speed", WSG_CMD_GET_SPEED},
                {"force", WSG_CMD_GET_FORCE},
                {"state", WSG_CMD_GET_SYSTEM_STATE},
                {"grasp", WSG_CMD_GET_GRASP_STATE}};
    unsigned long period = 100;
    uint8_t id = 0, pl[3];
    long got = 0;
    int rc = EXIT_OK;
    struct wsg_client_frame r;

    for (size_t i = 0; i < sizeof what / sizeof what[0]; i++)
        if (!strcmp(argv[0], what[i].name))
            id = what[i].id;
    if (!id) {
        err("watch: width, speed, force, state or grasp, not \"%s\"", argv[0]);
        return EXIT_USAGE;
    }
    if (argc == 2 && parse_ulong(argv[1], 65535, &period) < 0) {
        err("watch: PERIOD_MS is 0..65535, not \"%s\"", argv[1]);
        return EXIT_USAGE;
    }
    pl[0] = 1; /* auto update, always (not change-only) */
    wsg_put_u16(pl + 1, (uint16_t)period);
    rc = conn_send(&x->c, id, pl, 3);
    if (rc < 0)
        return -rc;
    /* No value for longer than this: the stream is gone. */
    int gap = (int)(x->o.timeout_s * 1000.0) + (int)period;
    uint64_t deadline = wsg_client_deadline(gap);
    rc = EXIT_OK;
    while (x->o.count == 0 || got < x->o.count) {
        int n = conn_recv(&x->c, &r, deadline);
        if (n == -2)
            break; /* SIGINT: unsubscribe below, exit 0 */
        if (n != 1) {
            rc = recv_fail(n, id, &x->o);
            break;
        }
        if (r.id != id)
            continue;
        if (r.status != WSG_E_SUCCESS) {
            rc = gripper_error(id, r.status);
            break;
        }
        deadline = wsg_client_deadline(gap);
        if (x->o.jo) {
            /* One object a value, as it comes: JSON lines. */
            struct timespec ts;

            clock_gettime(CLOCK_REALTIME, &ts);
            x->o.jo->len = 0;
            x->o.jo->body[0] = '\0';
            jout_add(x->o.jo, ",\"time\":%lld.%03ld", (long long)ts.tv_sec,
                     ts.tv_nsec / 1000000);
            print_values(&x->o, "", id, WSG_CLIENT_PARAMS(&r),
                         WSG_CLIENT_NPARAMS(&r));
            jout_print(x->o.jo, x->command, EXIT_OK, "");
            x->o.jo->streamed = 1;
            x->o.jo->len = 0;
            x->o.jo->body[0] = '\0';
        } else {
            print_stamp(&x->o);
            print_values(&x->o, "", id, WSG_CLIENT_PARAMS(&r),
                         WSG_CLIENT_NPARAMS(&r));
        }
        fflush(stdout);
        got++;
    }
    /* Unsubscribe (FLAGS 0, PERIOD 0): a UDP or serial session would go on
     * streaming after we are gone. Its answer is the value once more. */
    interrupted = 0;
    memset(pl, 0, sizeof pl);
    if (conn_send(&x->c, id, pl, 3) == 0) {
        uint64_t until = wsg_client_deadline(1000);
        while (conn_recv(&x->c, &r, until) == 1) {
            if (r.id == id && r.len >= 2 &&
                wsg_layout_fits(&wsg_schema[id].reply, r.len - 2u)) {
                /* Drain what was in flight before the answer. */
                until = wsg_client_deadline(50);
            }
        }
    }
    return rc;
}
