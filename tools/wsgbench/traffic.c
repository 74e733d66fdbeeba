/*
 * wsgbench's figures of requests and answers, each the emulator beside the
 * reference under the same noise: 43h latency over TCP, UDP and the pty in
 * alternating rounds; pipelined TCP throughput; the jitter of two 10 ms
 * auto-update streams read at once through one epoll.
 */
#define _GNU_SOURCE /* sched_setaffinity, pipe2, prctl, strndup */

#include "wsgbench.h"

#include <arpa/inet.h>
#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <getopt.h>
#include <math.h>
#include <netinet/in.h>
#include <poll.h>
#include <sched.h>
#include <signal.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/epoll.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

/* ---- 1. latency ---- */

int bench_latency(struct bench *b, enum link_kind kind)
{
    struct link l[2];
    double *lat[2] = {NULL, NULL}, dummy;
    size_t per = (size_t)(b->o.samples / ROUNDS), n[2] = {0, 0};
    size_t warm = per < 200 ? 200 : per > 2000 ? 2000 : per, i;
    struct dist d[2] = {{NAN, NAN, NAN}, {NAN, NAN, NAN}};
    char label[48];
    int s, round, rc = -1;
    struct row *r;

    l[EMU].c.fd = l[REF].c.fd = -1;
    l[EMU].c.own_rfd = l[REF].c.own_rfd = 0;
    if (per == 0)
        per = 1;
    if (attach_lacks(b,
                     kind == L_TCP   ? "tcp"
                     : kind == L_UDP ? "udp"
                                     : "pty",
                     kind_name[kind])) {
        rc = 0;
        goto cleanup;
    }
    /* Attached, with no socket on the UDP answers' port: said at start. */
    if (kind == L_UDP && b->udp_rfd[EMU] < 0)
        goto cleanup;
    for (s = 0; s < 2; s++) {
        lat[s] = malloc(per * ROUNDS * sizeof(double));
        if (!lat[s] || open_link(b, &l[s], s, kind) < 0)
            goto cleanup;
        for (i = 0; i < warm; i++)
            if (sample(&l[s], &dummy) < 0)
                goto cleanup;
    }
    /* Alternating rounds, each server first every other round. */
    for (round = 0; round < ROUNDS; round++) {
        for (int k = 0; k < 2; k++) {
            s = (round + k) % 2;
            for (i = 0; i < per; i++)
                if (sample(&l[s], &lat[s][n[s]++]) < 0)
                    goto cleanup;
        }
    }
    d[EMU] = dist_of(lat[EMU], n[EMU]);
    d[REF] = dist_of(lat[REF], n[REF]);
    rc = 0;
cleanup:
    snprintf(label, sizeof label, "%s latency median (us)", kind_name[kind]);
    /* The targets are on TCP; UDP and the pty are shown beside. */
    r = add_row(b, label, d[EMU].p50, d[REF].p50, 1);
    if (kind == L_TCP)
        set_target(r, T_LE, 1.25, 1, "ratio <= 1.25");
    snprintf(label, sizeof label, "%s latency p99 (us)", kind_name[kind]);
    r = add_row(b, label, d[EMU].p99, d[REF].p99, 1);
    if (kind == L_TCP)
        set_target(r, T_LE, 2, 1, "ratio <= 2");
    snprintf(label, sizeof label, "%s latency max (us)", kind_name[kind]);
    add_row(b, label, d[EMU].max, d[REF].max, 1);
    for (s = 0; s < 2; s++) {
        if (l[s].c.fd >= 0)
            link_close(&l[s]);
        free(lat[s]);
    }
    return rc;
}

/* ---- 2. pipelined throughput ---- */

/* Keep k requests in flight for dur_ns: the replies counted in that
 * window; afterwards the ones still owed are collected. */
static int pipelined(struct link *l, long k, uint64_t dur_ns, double *count,
                     double *secs)
{
    uint8_t *batch = malloc((size_t)k * sizeof req_width);
    uint64_t t0, end, now;
    long inflight = k, got, i;
    struct wsg_client_frame f;
    int r, rc = -1;

    if (!batch)
        return -1;
    for (i = 0; i < k; i++)
        memcpy(batch + i * (long)sizeof req_width, req_width,
               sizeof req_width);
    *count = 0;
    t0 = now_ns();
    end = t0 + dur_ns;
    if (link_send(l, batch, (size_t)k * sizeof req_width) < 0)
        goto cleanup;
    while ((now = now_ns()) < end) {
        r = link_wait(l, end);
        if (r < 0)
            goto cleanup;
        got = 0;
        while ((r = link_recv(l, &f, 0)) == 1) {
            if (check_width(l, &f) < 0)
                goto cleanup;
            got++;
        }
        if (r < 0)
            goto cleanup;
        *count += (double)got;
        /* Refill in one write: what a pipelining client does. */
        if (got && link_send(l, batch, (size_t)got * sizeof req_width) < 0)
            goto cleanup;
    }
    *secs = (double)(now - t0) / 1e9;
    /* inflight is still k: every reply received was replaced. */
    for (; inflight > 0; inflight--) {
        r = link_recv(l, &f, now_ns() + REPLY_MS * NS_PER_MS);
        if (r == 0)
            msg("%s: %ld pipelined answers missing", l->who, inflight);
        if (r <= 0 || check_width(l, &f) < 0)
            goto cleanup;
    }
    rc = 0;
cleanup:
    free(batch);
    return rc;
}

int bench_throughput(struct bench *b)
{
    struct link l[2];
    struct row *r;
    int rounds = b->o.quick ? 2 : 6, round, s, rc = -1;
    uint64_t dur = (uint64_t)(b->o.tput_s / rounds * 1e9);
    double count[2] = {0, 0}, secs[2] = {0, 0}, c, t;
    char label[48];
    int done = 0;

    l[EMU].c.fd = l[REF].c.fd = -1;
    l[EMU].c.own_rfd = l[REF].c.own_rfd = 0;
    if (attach_lacks(b, "tcp", "pipelined TCP")) {
        rc = 0;
        goto cleanup;
    }
    for (s = 0; s < 2; s++)
        if (open_link(b, &l[s], s, L_TCP) < 0 ||
            pipelined(&l[s], b->o.inflight, dur / 4, &c, &t) < 0)
            goto cleanup; /* the first quarter round warms up */
    for (round = 0; round < rounds; round++) {
        for (int k = 0; k < 2; k++) {
            s = (round + k) % 2;
            if (pipelined(&l[s], b->o.inflight, dur, &c, &t) < 0)
                goto cleanup;
            count[s] += c;
            secs[s] += t;
        }
    }
    rc = 0;
    done = 1;
cleanup:
    snprintf(label, sizeof label, "TCP pipelined, %ld in flight (1/s)",
             b->o.inflight);
    r = add_row(b, label, done ? count[EMU] / secs[EMU] : NAN,
                done ? count[REF] / secs[REF] : NAN, 0);
    set_target(r, T_GE, 0.8, 1, "ratio >= 0.8");
    for (s = 0; s < 2; s++)
        if (l[s].c.fd >= 0)
            link_close(&l[s]);
    return rc;
}

/* ---- 3. stream jitter ---- */

int bench_jitter(struct bench *b)
{
    static const uint8_t sub[3] = {0x01, STREAM_MS, 0x00};
    struct link l[2];
    size_t cap = (size_t)(b->o.jitter_s * 1000 / STREAM_MS * 2) + 64;
    double *iv[2] = {NULL, NULL};
    size_t n[2] = {0, 0};
    uint64_t last[2] = {0, 0}, end;
    int seen[2] = {0, 0};
    struct dist d[2] = {{NAN, NAN, NAN}, {NAN, NAN, NAN}};
    int epfd = -1, s, rc = -1, done = 0;
    struct row *r;

    l[EMU].c.fd = l[REF].c.fd = -1;
    l[EMU].c.own_rfd = l[REF].c.own_rfd = 0;
    if (attach_lacks(b, "tcp", "43h stream")) {
        rc = 0;
        goto cleanup;
    }
    epfd = epoll_create1(EPOLL_CLOEXEC);
    if (epfd < 0)
        goto cleanup;
    for (s = 0; s < 2; s++) {
        struct epoll_event ev = {.events = EPOLLIN, .data.u32 = (uint32_t)s};

        iv[s] = malloc(cap * sizeof(double));
        if (!iv[s] || open_link(b, &l[s], s, L_TCP) < 0 ||
            epoll_ctl(epfd, EPOLL_CTL_ADD, l[s].c.rfd, &ev) < 0)
            goto cleanup;
    }
    /* Both streams at once, in one epoll: half the wall time, and the
     * same machine noise for both. */
    for (s = 0; s < 2; s++)
        if (link_sendf(&l[s], WSG_CMD_GET_WIDTH, sub, sizeof sub) < 0)
            goto cleanup;
    end = now_ns() + (uint64_t)(b->o.jitter_s * 1e9);
    last[EMU] = last[REF] = now_ns();
    for (;;) {
        struct epoll_event ev[2];
        uint64_t now = now_ns();
        int ne, i;

        if (now >= end)
            break;
        for (s = 0; s < 2; s++)
            if (now - last[s] > STALL_MS * NS_PER_MS) {
                msg("%s: the 43h stream stopped (nothing for %d ms)", l[s].who,
                    STALL_MS);
                goto cleanup;
            }
        ne = epoll_wait(epfd, ev, 2, 100);
        for (i = 0; i < ne; i++) {
            struct wsg_client_frame f;
            long got;
            int k;

            s = (int)ev[i].data.u32;
            got = link_read(&l[s]);
            if (got == 0)
                continue;
            if (got < 0)
                goto cleanup;
            now = now_ns();
            while ((k = link_recv(&l[s], &f, 0)) == 1) {
                if (check_width(&l[s], &f) < 0)
                    goto cleanup;
                /* The first is the answer to the request itself; the
                 * intervals start at the first periodic packet. */
                if (seen[s]++ >= 2 && n[s] < cap)
                    iv[s][n[s]++] =
                        fabs((double)(now - last[s]) / 1e3 - STREAM_MS * 1e3);
                last[s] = now;
            }
            if (k < 0)
                goto cleanup;
        }
    }
    d[EMU] = dist_of(iv[EMU], n[EMU]);
    d[REF] = dist_of(iv[REF], n[REF]);
    rc = 0;
    done = 1;
cleanup:
    add_row(b, "43h stream 10 ms jitter p50 (us)", d[EMU].p50, d[REF].p50, 1);
    r = add_row(b, "43h stream 10 ms jitter p99 (us)", d[EMU].p99, d[REF].p99,
                1);
    set_target(r, T_LT, 1000, 0, "< 1000");
    add_row(b, "43h stream 10 ms jitter max (us)", d[EMU].max, d[REF].max, 1);
    add_row(b, "43h stream intervals (count)", done ? (double)n[EMU] : NAN,
            done ? (double)n[REF] : NAN, 0);
    for (s = 0; s < 2; s++) {
        if (l[s].c.fd >= 0)
            link_close(&l[s]); /* ends the stream with the connection */
        free(iv[s]);
    }
    if (epfd >= 0)
        close(epfd);
    return rc;
}
