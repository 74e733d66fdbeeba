/*
 * wsgbench's figures of a server at rest, from /proc: idle wakes and CPU,
 * wakes with a 1 s stream and nothing moving, and memory (RSS, peak).
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

/* ---- 4. idle ---- */

int bench_idle(struct bench *b)
{
    struct proc_sample a[2], z[2];
    double w[2] = {NAN, NAN}, c[2] = {NAN, NAN};
    int s, rc = 0;
    struct row *r;

    attach_nopid(b, "the emulator's idle wakes and CPU");
    sleep_s(0.3); /* let the last close settle */
    for (s = 0; s < 2; s++)
        if (b->pid[s] > 0)
            rc |= proc_read(b->pid[s], &a[s]);
    sleep_s(b->o.idle_s);
    for (s = 0; s < 2; s++)
        if (b->pid[s] > 0)
            rc |= proc_read(b->pid[s], &z[s]);
    if (rc < 0) {
        msg("idle: cannot read /proc of the servers");
    } else {
        for (s = 0; s < 2; s++) {
            if (b->pid[s] <= 0)
                continue;
            w[s] = wakes_per_s(&a[s], &z[s]);
            c[s] = cpu_percent(&a[s], &z[s]);
        }
    }
    r = add_row(b, "idle wakes/s", w[EMU], w[REF], 2);
    set_target(r, T_LT, 1, 0, "< 1");
    r = add_row(b, "idle CPU % of one core", c[EMU], c[REF], 1);
    set_target(r, T_LT, 0.05, 0, "0.0");
    return rc < 0 ? -1 : 0;
}

/* A 43h stream of 1 s and nothing moving: the emulator runs the gripper
 * from the stream's deadline, so it wakes about once a second (one wake
 * per packet), not once per model step. */
int bench_slow_stream(struct bench *b)
{
    static const uint8_t sub[3] = {0x01, 0xE8, 0x03}; /* every 1000 ms */
    struct proc_sample a[2], z[2];
    double w[2] = {NAN, NAN};
    struct link l[2];
    int s, rc = -1;
    struct row *r;

    l[EMU].c.fd = l[REF].c.fd = -1;
    l[EMU].c.own_rfd = l[REF].c.own_rfd = 0;
    if (attach_lacks(b, "tcp", "1 s stream") ||
        attach_nopid(b, "the emulator's wakes with a 1 s stream")) {
        rc = 0;
        goto cleanup;
    }
    for (s = 0; s < 2; s++)
        if (open_link(b, &l[s], s, L_TCP) < 0 ||
            link_sendf(&l[s], WSG_CMD_GET_WIDTH, sub, sizeof sub) < 0)
            goto cleanup;
    sleep_s(0.5); /* past the answer to the request itself */
    for (s = 0; s < 2; s++)
        if (b->pid[s] > 0 && proc_read(b->pid[s], &a[s]) < 0)
            goto cleanup;
    sleep_s(b->o.idle_s);
    for (s = 0; s < 2; s++) {
        if (b->pid[s] <= 0)
            continue;
        if (proc_read(b->pid[s], &z[s]) < 0)
            goto cleanup;
        w[s] = wakes_per_s(&a[s], &z[s]);
    }
    rc = 0;
cleanup:
    if (rc < 0)
        msg("1 s stream: cannot subscribe or read /proc of the servers");
    r = add_row(b, "1 s stream, idle: wakes/s", w[EMU], w[REF], 2);
    set_target(r, T_LT, 2, 0, "~1");
    for (s = 0; s < 2; s++)
        if (l[s].c.fd >= 0)
            link_close(&l[s]);
    return rc;
}

/* ---- 7. memory ---- */

int bench_memory(struct bench *b)
{
    double rss[2], hwm[2];
    int s;
    struct row *r;

    attach_nopid(b, "the emulator's RSS");
    for (s = 0; s < 2; s++) {
        rss[s] = b->pid[s] > 0 ? proc_mib(b->pid[s], "VmRSS") : NAN;
        hwm[s] = b->pid[s] > 0 ? proc_mib(b->pid[s], "VmHWM") : NAN;
    }
    r = add_row(b, "RSS (MiB)", rss[EMU], rss[REF], 2);
    set_target(r, T_LT, 4, 0, "< 4");
    add_row(b, "peak RSS, VmHWM (MiB)", hwm[EMU], hwm[REF], 2);
    if ((b->pid[EMU] > 0 && isnan(rss[EMU])) || isnan(rss[REF])) {
        msg("memory: cannot read /proc/PID/status of the servers");
        return -1;
    }
    return 0;
}
