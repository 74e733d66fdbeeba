/*
 * wsgbench's GCL rows: the round trip of POS? over a connection that
 * speaks GCL (wsgemu --text-interface on) beside that of 43h over the
 * binary protocol, each on a wsgemu of its own started here alike (the
 * text interface is the whole TCP port's, so one daemon cannot serve
 * both), in alternating rounds so that the machine's noise hits both.
 * What the line codec, the parser and the text answer add to a reading:
 * the rows' reference column is the binary 43h, not wsgref. A driver that
 * polls POS? at 20 Hz (GCL.md's timing habits) must not pay much more
 * than one that polls 43h: median at most 1.25 times.
 */
#define _GNU_SOURCE /* sched_setaffinity, pipe2, prctl, strndup */

#include "wsgbench.h"

#include <errno.h>
#include <netinet/in.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define GCL_TEXT 0 /* the samples of the GCL daemon */
#define GCL_BIN  1 /* those of the binary one */

/* A wsgemu of its own and one connection to it. */
struct gdaemon {
    struct server s;
    struct link l;
    int started;
};

static int gd_start(struct bench *b, struct gdaemon *d, int text,
                    const char *name)
{
    char *targv[] = {b->emu_exe,         "--tcp", "127.0.0.1:0",
                     "--text-interface", "on",    NULL};
    char *bargv[] = {b->emu_exe, "--tcp", "127.0.0.1:0", NULL};
    struct sockaddr_in sa;
    char *v;
    int rc = -1;

    link_init(&d->l, L_TCP, name);
    d->started = 0;
    if (server_start(b, &d->s, name, text ? targv : bargv, READY_MS) < 0)
        return -1;
    d->started = 1;
    v = field(d->s.line, "tcp");
    if (!v)
        msg("%s: no tcp= in its ready line", name);
    else if (parse_ipport(v, &sa) == 0 && link_tcp(&d->l, &sa) == 0)
        rc = 0;
    free(v);
    return rc;
}

/* The connection closed as its protocol announces a close (BYE() or 07h),
 * then the server. 0, or -1 when it did not end as it should (reported). */
static int gd_stop(struct gdaemon *d, int text)
{
    char line[64];

    if (text) {
        if (d->l.c.fd >= 0 && wsg_client_line_send(&d->l.c, "BYE()\n") == 0)
            wsg_client_line_read(&d->l.c, line, sizeof line,
                                 wsg_client_deadline(REPLY_MS));
        wsg_client_close(&d->l.c);
    } else {
        link_close(&d->l);
    }
    if (!d->started)
        return 0;
    d->started = 0;
    return server_stop(&d->s);
}

/* POS? in one write, its answer line "POS=54.2". */
static int gcl_sample(struct link *l, double *us)
{
    uint64_t t0 = now_ns();
    char line[64];
    int r;

    r = wsg_client_line_send(&l->c, "POS?\n");
    if (r < 0) {
        msg("%s: send: %s", l->who, strerror(-r));
        return -1;
    }
    r = wsg_client_line_read(&l->c, line, sizeof line,
                             t0 + REPLY_MS * NS_PER_MS);
    if (r == 0)
        msg("%s: no answer to POS? within %d ms", l->who, REPLY_MS);
    else if (r < 0)
        msg("%s: %s", l->who,
            r == -EPIPE ? "connection closed" : strerror(-r));
    if (r <= 0)
        return -1;
    if (strncmp(line, "POS=", 4) != 0) {
        msg("%s: answer to POS? is \"%.40s\", not POS=...", l->who, line);
        return -1;
    }
    *us = (double)(now_ns() - t0) / 1e3;
    return 0;
}

/* The GCL daemon's POS? (side GCL_TEXT) or the binary one's 43h. */
static int gcl_take(void *ctx, int side, double *us)
{
    struct gdaemon *d = ctx;

    return side == GCL_TEXT ? gcl_sample(&d[GCL_TEXT].l, us)
                            : sample(&d[GCL_BIN].l, us);
}

int bench_gcl(struct bench *b)
{
    struct gdaemon d[2];
    struct dist dd[2] = {{NAN, NAN, NAN}, {NAN, NAN, NAN}};
    int s, rc = -1;
    struct row *r;

    d[GCL_TEXT].started = d[GCL_BIN].started = 0;
    link_init(&d[GCL_TEXT].l, L_TCP, "wsgemu --text-interface");
    link_init(&d[GCL_BIN].l, L_TCP, "wsgemu");
    if (gd_start(b, &d[GCL_TEXT], 1, "wsgemu --text-interface") < 0 ||
        gd_start(b, &d[GCL_BIN], 0, "wsgemu") < 0)
        goto cleanup;
    rc = alternate(b, gcl_take, NULL, d, dd);
cleanup:
    for (s = 0; s < 2; s++)
        if (gd_stop(&d[s], s == GCL_TEXT) < 0)
            rc = -1;
    r = add_row(b, "GCL POS? round trip median (us)", dd[GCL_TEXT].p50,
                dd[GCL_BIN].p50, 1);
    set_target(r, T_LE, 1.25, 1, "ratio <= 1.25");
    add_row(b, "GCL POS? round trip p99 (us)", dd[GCL_TEXT].p99,
            dd[GCL_BIN].p99, 1);
    return rc;
}
