/*
 * wsgbench's fleet rows: a wsgemu --grippers N of its own, one TCP
 * connection per gripper read through one epoll; idle cost, homing them
 * all, and a tenth and then all of them moving: the cost should follow
 * what moves, not N.
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

/* ---- 8. fleet ---- */

struct fleet {
    struct bench *b;
    struct server s;
    long n;
    struct link *l;
    struct link ctl;
    int epfd;
    uint8_t *got; /* per gripper: which awaited answers came */
};

/* Send one request to grippers lo..hi-1. */
static int fleet_send(struct fleet *f, long lo, long hi, uint8_t id,
                      const uint8_t *payload, size_t len)
{
    for (long i = lo; i < hi; i++)
        if (link_sendf(&f->l[i], id, payload, len) < 0)
            return -1;
    return 0;
}

/* Up to two awaited answers per gripper in lo..hi-1: an ID, and whether
 * the final result is awaited (else the immediate E_CMD_PENDING); a final
 * result must be E_SUCCESS when need_ok. Waiting for both at once keeps
 * an answer from being skipped while the other is awaited. */
struct await {
    uint8_t id;
    int final, need_ok;
};

static int fleet_wait(struct fleet *f, long lo, long hi, const struct await *w,
                      int nw, int timeout_ms)
{
    uint64_t deadline = now_ns() + (uint64_t)timeout_ms * NS_PER_MS;
    uint8_t all = (uint8_t)((1u << nw) - 1u);
    long left = hi - lo, i;

    memset(f->got + lo, 0, (size_t)(hi - lo));
    while (left > 0) {
        struct epoll_event ev[64];
        uint64_t now = now_ns();
        int ne, e;

        if (now >= deadline) {
            msg("fleet: %ld of %ld grippers did not answer %02Xh within %d "
                "ms",
                left, hi - lo, w[0].id, timeout_ms);
            return -1;
        }
        ne = epoll_wait(f->epfd, ev, 64, 100);
        for (e = 0; e < ne; e++) {
            struct link *l;
            struct wsg_client_frame fr;
            long got;
            int k, j;

            i = (long)ev[e].data.u64;
            l = &f->l[i];
            got = link_read(l);
            if (got == 0)
                continue;
            if (got < 0)
                return -1;
            while ((k = link_recv(l, &fr, 0)) == 1) {
                if (i < lo || i >= hi)
                    continue;
                for (j = 0; j < nw; j++) {
                    int pending = fr.status == WSG_E_CMD_PENDING;

                    if (fr.id != w[j].id || (f->got[i] & (1u << j)))
                        continue;
                    if (w[j].final && pending)
                        continue;
                    if ((!w[j].final && !pending) ||
                        (w[j].final && w[j].need_ok &&
                         fr.status != WSG_E_SUCCESS)) {
                        msg("%s: %02Xh answered %s", l->who, fr.id,
                            wsg_status_name(fr.status));
                        return -1;
                    }
                    f->got[i] |= (uint8_t)(1u << j);
                    if (f->got[i] == all)
                        left--;
                }
            }
            if (k < 0)
                return -1;
        }
    }
    return 0;
}

/* Grippers lo..hi-1 move slowly across the stroke; measured for the
 * window; then stopped. */
static int fleet_moving(struct fleet *f, long lo, long hi, double *rate,
                        double *ovr, double *cpu)
{
    static const struct await pending = {WSG_CMD_PREPOSITION, 0, 0};
    static const struct await stopped[2] = {{WSG_CMD_STOP, 1, 1},
                                            {WSG_CMD_PREPOSITION, 1, 0}};
    uint8_t pl[9];

    put_move(pl, 0.0, slow_speed(f->b->o.move_s));
    if (fleet_send(f, lo, hi, WSG_CMD_PREPOSITION, pl, sizeof pl) < 0 ||
        fleet_wait(f, lo, hi, &pending, 1, MOTION_MS) < 0)
        return -1;
    sleep_s(0.1);
    if (measure_moving(&f->ctl, f->s.pid, f->b->o.move_s, rate, ovr, cpu) < 0)
        return -1;
    if (fleet_send(f, lo, hi, WSG_CMD_STOP, NULL, 0) < 0 ||
        fleet_wait(f, lo, hi, stopped, 2, MOTION_MS) < 0)
        return -1;
    return 0;
}

int bench_fleet(struct bench *b)
{
    static const struct await homed = {WSG_CMD_HOMING, 1, 1};
    static const struct await moved = {WSG_CMD_PREPOSITION, 1, 1};
    struct fleet f;
    char nbuf[24], label[48];
    char *argv[] = {b->emu_exe,    "--grippers", nbuf,          "--tcp",
                    "127.0.0.1:0", "--control",  "127.0.0.1:0", NULL};
    double iw = NAN, ic = NAN, rss = NAN, home_s = NAN;
    double r10 = NAN, o10 = NAN, c10 = NAN, ra = NAN, oa = NAN, ca = NAN;
    struct proc_sample a, z;
    struct sockaddr_in sa;
    struct rlimit rl;
    char *tcp = NULL, *c = NULL, *p;
    long i, tenth;
    uint8_t pl[9], dir = 0;
    uint64_t t0;
    int rc = -1, started = 0;
    struct row *r;

    memset(&f, 0, sizeof f);
    f.b = b;
    f.n = b->o.fleet;
    f.epfd = -1;
    tenth = f.n / 10 > 0 ? f.n / 10 : 1;
    link_init(&f.ctl, L_TCP, "fleet control");
    snprintf(nbuf, sizeof nbuf, "%ld", f.n);

    /* One connection per gripper, plus a few. */
    if (getrlimit(RLIMIT_NOFILE, &rl) == 0 && rl.rlim_cur < rl.rlim_max) {
        rl.rlim_cur = rl.rlim_max;
        setrlimit(RLIMIT_NOFILE, &rl);
    }
    if (getrlimit(RLIMIT_NOFILE, &rl) == 0 && rl.rlim_cur != RLIM_INFINITY &&
        rl.rlim_cur < (rlim_t)f.n + 32) {
        msg("fleet: %ld connections need more descriptors than the limit "
            "(%lu)",
            f.n, (unsigned long)rl.rlim_cur);
        goto rows;
    }
    if (server_start(b, &f.s, "wsgemu --grippers", argv, FLEET_MS) < 0) {
        msg("fleet: wsgemu --grippers %ld did not start (does it have "
            "--grippers?)",
            f.n);
        goto rows;
    }
    started = 1;
    f.l = calloc((size_t)f.n, sizeof *f.l);
    f.got = calloc((size_t)f.n, 1);
    for (i = 0; f.l && i < f.n; i++)
        f.l[i].c.fd = f.l[i].c.rfd = -1;
    tcp = field(f.s.line, "tcp");
    c = field(f.s.line, "control");
    f.epfd = epoll_create1(EPOLL_CLOEXEC);
    if (!f.l || !f.got || !tcp || !c || f.epfd < 0 ||
        parse_ipport(c, &sa) < 0 || link_tcp(&f.ctl, &sa) < 0) {
        msg("fleet: no tcp= and control= in the ready line, or no memory");
        goto cleanup;
    }
    /* Idle first: nothing connected but the control channel. */
    sleep_s(0.5);
    if (proc_read(f.s.pid, &a) < 0)
        goto cleanup;
    sleep_s(b->o.idle_s);
    if (proc_read(f.s.pid, &z) < 0)
        goto cleanup;
    iw = wakes_per_s(&a, &z);
    ic = cpu_percent(&a, &z);
    rss = proc_mib(f.s.pid, "VmRSS");

    for (i = 0, p = tcp; i < f.n; i++) {
        struct epoll_event ev = {.events = EPOLLIN, .data.u64 = (uint64_t)i};
        char name[32];

        snprintf(name, sizeof name, "gripper %ld", i);
        link_init(&f.l[i], L_TCP, name);
        if (!p || parse_ipport(p, &sa) < 0) {
            msg("fleet: tcp= lists fewer than %ld addresses", f.n);
            goto cleanup;
        }
        if (link_tcp(&f.l[i], &sa) < 0 ||
            epoll_ctl(f.epfd, EPOLL_CTL_ADD, f.l[i].c.rfd, &ev) < 0)
            goto cleanup;
        p = strchr(p, ',');
        p = p ? p + 1 : NULL;
    }
    t0 = now_ns();
    if (fleet_send(&f, 0, f.n, WSG_CMD_HOMING, &dir, 1) < 0 ||
        fleet_wait(&f, 0, f.n, &homed, 1, FLEET_MS) < 0)
        goto cleanup;
    home_s = (double)(now_ns() - t0) / 1e9;

    /* A tenth moving, stopped, sent back to the end stop quickly; then all
     * of them moving: the cost should follow what moves, not N. */
    if (fleet_moving(&f, 0, tenth, &r10, &o10, &c10) < 0)
        goto cleanup;
    put_move(pl, STROKE_MM, 420.0);
    if (fleet_send(&f, 0, tenth, WSG_CMD_PREPOSITION, pl, sizeof pl) < 0 ||
        fleet_wait(&f, 0, tenth, &moved, 1, MOTION_MS) < 0)
        goto cleanup;
    if (fleet_moving(&f, 0, f.n, &ra, &oa, &ca) < 0)
        goto cleanup;
    rc = 0;
cleanup:
    /* No 07h to a thousand connections: the emulator is stopped first, so
     * FAST STOP on close does not matter. */
    if (started && server_stop(&f.s) < 0)
        rc = -1;
    for (i = 0; f.l && i < f.n; i++)
        if (f.l[i].c.fd >= 0)
            close(f.l[i].c.fd);
    wsg_client_close(&f.ctl.c);
    if (f.epfd >= 0)
        close(f.epfd);
rows:
    snprintf(label, sizeof label, "fleet %ld: idle wakes/s", f.n);
    r = add_row(b, label, iw, NOT_APPLIED, 2);
    set_target(r, T_LT, 1, 0, "< 1");
    snprintf(label, sizeof label, "fleet %ld: idle CPU %% of one core", f.n);
    r = add_row(b, label, ic, NOT_APPLIED, 1);
    set_target(r, T_LT, 1, 0, "< 1");
    snprintf(label, sizeof label, "fleet %ld: RSS (MiB)", f.n);
    r = add_row(b, label, rss, NOT_APPLIED, 2);
    set_target(r, T_LT, 64, 0, "< 64");
    snprintf(label, sizeof label, "fleet %ld: homing all (s)", f.n);
    add_row(b, label, home_s, NOT_APPLIED, 2);
    snprintf(label, sizeof label, "fleet %ld/%ld moving: CPU %%", tenth, f.n);
    add_row(b, label, c10, NOT_APPLIED, 1);
    snprintf(label, sizeof label, "fleet %ld/%ld moving: steps/s", tenth, f.n);
    r = add_row(b, label, r10, NOT_APPLIED, 0);
    set_target(r, T_NEAR, 1000, 0, "1000 +- 2%");
    r->tol = 20;
    snprintf(label, sizeof label, "fleet %ld/%ld moving: overruns", tenth,
             f.n);
    r = add_row(b, label, o10, NOT_APPLIED, 0);
    set_target(r, T_EQ, 0, 0, "0");
    snprintf(label, sizeof label, "fleet %ld/%ld moving: CPU %%", f.n, f.n);
    add_row(b, label, ca, NOT_APPLIED, 1);
    snprintf(label, sizeof label, "fleet %ld/%ld moving: steps/s", f.n, f.n);
    r = add_row(b, label, ra, NOT_APPLIED, 0);
    set_target(r, T_NEAR, 1000, 0, "1000 +- 2%");
    r->tol = 20;
    snprintf(label, sizeof label, "fleet %ld/%ld moving: overruns", f.n, f.n);
    r = add_row(b, label, oa, NOT_APPLIED, 0);
    set_target(r, T_EQ, 0, 0, "0");
    snprintf(label, sizeof label, "fleet CPU all / CPU %ld moving", tenth);
    add_row(b, label, c10 > 0 ? ca / c10 : NAN, NOT_APPLIED, 1);
    free(tcp);
    free(c);
    free(f.l);
    free(f.got);
    return rc;
}
