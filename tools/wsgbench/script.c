/*
 * wsgbench's script rows, each on a wsgemu of its own started with
 * --script (the scripts are tests/scripts/bench_*.lua, or --scripts DIR):
 *  - the round trip of an ID a script registered (bench_echo.lua answers
 *    B0h at once) beside the firmware's 43h, on the same daemon and the
 *    same connection, in alternating rounds: what the script host adds to
 *    a packet (the row's reference column is the 43h, not wsgref);
 *  - the timer wakes of that daemon while its script waits in cmd.read:
 *    a waiting script has no deadline, so there must be none;
 *  - a PD loop (bench_pd.lua, UMI's B1h) driven at rising rates for a
 *    fixed time each: the answers per second that came back, the share of
 *    the packets sent that were answered, and the model steps the daemon
 *    dropped meanwhile (control "stats"), the fingers moving in speed
 *    mode all along; and the highest of those rates it sustained.
 */
#define _GNU_SOURCE /* sched_setaffinity, pipe2, prctl, strndup */

#include "wsgbench.h"

#include <arpa/inet.h>
#include <errno.h>
#include <math.h>
#include <netinet/in.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#define SCRIPT_ECHO   0xB0 /* bench_echo.lua's ID */
#define SCRIPT_PD     0xB1 /* bench_pd.lua's step */
#define PD_REQUEST    25   /* UMI's B1h: 00 and six float32 */
#define PD_ANSWER     19   /* E_SUCCESS, a flags byte, four float32 */
#define PD_GRACE_MS   500  /* answers still counted after the window */
#define PD_SETTLE_MS  2000 /* late answers of a rate before the next */
#define PD_CENTRE_MM  55.0 /* the target: a sine about the middle */
#define PD_AMP_MM     30.0
#define PD_HZ         0.5
#define PD_KP         10.0
#define PD_KD         0.1
#define PD_FORCE_N    40.0
#define PD_SUSTAINED  0.99 /* answered, and rate achieved, to count */
#define PD_RATE_TOP_X 1000 /* the rate the target asks for */

static const int pd_rates[] = {250, 500, 1000, 2000};
#define PD_NRATES ((int)(sizeof pd_rates / sizeof pd_rates[0]))

/* The script's path; -1 (reported) when it cannot be read. */
static int script_file(const struct bench *b, const char *name, char *out,
                       size_t cap)
{
    if (snprintf(out, cap, "%s/%s", b->o.scripts, name) >= (int)cap) {
        msg("--scripts %s: path too long", b->o.scripts);
        return -1;
    }
    if (access(out, R_OK) < 0) {
        msg("cannot read %s: %s (give --scripts DIR: tests/scripts of the "
            "source tree)",
            out, strerror(errno));
        return -1;
    }
    return 0;
}

/* A wsgemu of its own running the script file (in --scripts). */
static int sd_start(struct bench *b, struct emud *d, const char *file,
                    const char *name)
{
    char path[PATH_MAX];
    char *argv[] = {b->emu_exe,    "--tcp",    "127.0.0.1:0", "--control",
                    "127.0.0.1:0", "--script", path,          NULL};

    emud_init(d, name);
    if (script_file(b, file, path, sizeof path) < 0)
        return -1;
    return emud_start(b, d, name, argv);
}

/* The control channel's count of timer wakes. */
static int ctl_wakes(struct link *ctl, double *wakes)
{
    char line[1024];

    if (ctl_cmd(ctl, "stats", line, sizeof line) < 0)
        return -1;
    if (strncmp(line, "ok {", 4) != 0 ||
        wsg_json_num(line, "wakes", wakes) < 0) {
        msg("control: \"stats\" answered \"%.120s\" (want ok "
            "{...\"wakes\":W...})",
            line);
        return -1;
    }
    return 0;
}

/* One request in flight, its answer: ID id, E_SUCCESS and 4 bytes. */
static int rt_sample(struct link *l, const uint8_t *req, size_t n, uint8_t id,
                     double *us)
{
    uint64_t t0 = now_ns();
    struct wsg_client_frame f;
    int r;

    if (link_send(l, req, n) < 0)
        return -1;
    r = link_recv(l, &f, t0 + REPLY_MS * NS_PER_MS);
    if (r == 0)
        msg("%s: no answer to %02Xh within %d ms", l->who, id, REPLY_MS);
    if (r <= 0)
        return -1;
    if (f.id != id || f.len != 6 || f.status != WSG_E_SUCCESS) {
        msg("%s: malformed answer to %02Xh: ID %02Xh, %u bytes, status %s",
            l->who, id, f.id, f.len,
            f.len >= 2 ? wsg_status_name(f.status) : "none");
        return -1;
    }
    *us = (double)(now_ns() - t0) / 1e3;
    return 0;
}

/* One round trip on the script daemon's connection: [EMU] the script's
 * B0h, [REF] the firmware's 43h. */
struct echo_bench {
    struct emud d;
    uint8_t req[WSG_HEADER_LEN + 4 + WSG_CRC_LEN];
};

static int echo_take(void *ctx, int side, double *us)
{
    struct echo_bench *e = ctx;

    return side == EMU
               ? rt_sample(&e->d.l, e->req, sizeof e->req, SCRIPT_ECHO, us)
               : rt_sample(&e->d.l, req_width, sizeof req_width,
                           WSG_CMD_GET_WIDTH, us);
}

/* B0h through bench_echo.lua against 43h, then the daemon at rest with
 * its script in cmd.read. */
static int bench_script_echo(struct bench *b)
{
    static const uint8_t four[4] = {1, 2, 3, 4};
    struct echo_bench e;
    struct emud *d = &e.d;
    double w0, w1, wakes = NAN;
    struct dist dd[2] = {{NAN, NAN, NAN}, {NAN, NAN, NAN}};
    int rc = -1;
    struct row *r;

    wsg_frame_encode(e.req, sizeof e.req, SCRIPT_ECHO, four, sizeof four);
    if (sd_start(b, d, "bench_echo.lua", "wsgemu --script bench_echo") < 0)
        goto cleanup;
    if (alternate(b, echo_take, NULL, &e, dd) < 0)
        goto cleanup;
    /* At rest, the connection open as a driver keeps it. */
    sleep_s(0.3);
    if (ctl_wakes(&d->ctl, &w0) < 0)
        goto cleanup;
    sleep_s(b->o.idle_s);
    if (ctl_wakes(&d->ctl, &w1) < 0)
        goto cleanup;
    wakes = w1 - w0;
    rc = 0;
cleanup:
    if (emud_stop(d) < 0)
        rc = -1;
    r = add_row(b, "script B0h round trip median (us)", dd[EMU].p50,
                dd[REF].p50, 1);
    set_target(r, T_LE, 1.5, 1, "ratio <= 1.5");
    add_row(b, "script B0h round trip p99 (us)", dd[EMU].p99, dd[REF].p99, 1);
    r = add_row(b, "script in cmd.read: timer wakes", wakes, NOT_APPLIED, 0);
    set_target(r, T_EQ, 0, 0, "0");
    return rc;
}

static void put_f32s(uint8_t *p, const double *v, int n)
{
    for (int i = 0; i < n; i++)
        wsg_put_f32(p + 4 * i, (float)v[i]);
}

/* A B1h answer as bench_pd.lua sends it: 0, or -1 (reported). */
static int pd_check(const struct link *l, const struct wsg_client_frame *f)
{
    if (f->id == SCRIPT_PD && f->len == PD_ANSWER &&
        f->status == WSG_E_SUCCESS)
        return 0;
    msg("%s: malformed answer to B1h: ID %02Xh, %u bytes, status %s", l->who,
        f->id, f->len, f->len >= 2 ? wsg_status_name(f->status) : "none");
    return -1;
}

struct pd_result {
    double rate;     /* answers per second within the window */
    double answered; /* % of the packets sent, with PD_GRACE_MS after */
    double overruns; /* model steps dropped meanwhile */
};

/* B1h at rate per second for secs, open loop (a late send goes out at
 * once, so the rate holds on average); answers read as they come. *owed
 * is what a previous rate left unanswered, read and dropped first. */
static int pd_run(struct emud *d, int rate, double secs, long *owed,
                  struct pd_result *res)
{
    uint64_t period = NS_PER_S / (uint64_t)rate, t0, end, next, now;
    double steps0, ovr0, steps1, ovr1;
    long sent = 0, got = 0, in_window = 0;
    struct wsg_client_frame f;
    uint8_t pl[PD_REQUEST];
    int r;

    /* Late answers of the rate before: not this rate's. */
    while (*owed > 0 &&
           (r = link_recv(&d->l, &f, now_ns() + PD_SETTLE_MS * NS_PER_MS)) ==
               1)
        (*owed)--;
    if (ctl_stats(&d->ctl, &steps0, &ovr0) < 0)
        return -1;
    t0 = now_ns();
    end = t0 + (uint64_t)(secs * 1e9);
    next = t0;
    while ((now = now_ns()) < end) {
        if (now >= next) {
            double t = (double)(now - t0) / 1e9, w = 2 * M_PI * PD_HZ;
            double v[6] = {PD_CENTRE_MM + PD_AMP_MM * sin(w * t),
                           PD_AMP_MM * w * cos(w * t),
                           PD_KP,
                           PD_KD,
                           PD_FORCE_N,
                           PD_FORCE_N};

            pl[0] = 0;
            put_f32s(pl + 1, v, 6);
            if (link_sendf(&d->l, SCRIPT_PD, pl, sizeof pl) < 0)
                return -1;
            sent++;
            next += period;
            continue;
        }
        r = link_recv(&d->l, &f, next < end ? next : end);
        if (r < 0 || (r == 1 && pd_check(&d->l, &f) < 0))
            return -1;
        got += r;
    }
    in_window = got;
    now = now_ns();
    while (got < sent) {
        r = link_recv(&d->l, &f, now + PD_GRACE_MS * NS_PER_MS);
        if (r < 0 || (r == 1 && pd_check(&d->l, &f) < 0))
            return -1;
        if (r == 0)
            break;
        got++;
    }
    if (ctl_stats(&d->ctl, &steps1, &ovr1) < 0)
        return -1;
    *owed = sent - got;
    res->rate = (double)in_window / ((double)(end - t0) / 1e9);
    res->answered = sent ? 100.0 * (double)got / (double)sent : NAN;
    res->overruns = ovr1 - ovr0;
    return 0;
}

/* bench_pd.lua homed, then each rate in turn. */
static int bench_script_pd(struct bench *b)
{
    struct pd_result res[PD_NRATES];
    struct emud d;
    struct wsg_client_frame f;
    uint8_t dir = 0;
    long owed = 0;
    int i, st, rc = -1, done = 0;
    double top = NAN;
    char label[48];
    struct row *r;

    for (i = 0; i < PD_NRATES; i++)
        res[i].rate = res[i].answered = res[i].overruns = NAN;
    if (sd_start(b, &d, "bench_pd.lua", "wsgemu --script bench_pd") < 0)
        goto cleanup;
    /* Referenced, so that speed mode may start. */
    st = link_motion(&d.l, WSG_CMD_HOMING, &dir, 1);
    if (st != WSG_E_SUCCESS) {
        if (st >= 0)
            msg("wsgemu --script bench_pd: Homing ended with %s",
                wsg_status_name((unsigned)st));
        goto cleanup;
    }
    for (i = 0; i < PD_NRATES; i++) {
        if (pd_run(&d, pd_rates[i], b->o.script_s, &owed, &res[i]) < 0)
            goto cleanup;
        done = i + 1;
    }
    /* The fingers still run at the last speed: stop them. */
    if (link_sendf(&d.l, WSG_CMD_STOP, NULL, 0) < 0 ||
        link_recv_id(&d.l, WSG_CMD_STOP, &f, PD_SETTLE_MS) < 0)
        goto cleanup;
    rc = 0;
cleanup:
    if (emud_stop(&d) < 0)
        rc = -1;
    if (done == PD_NRATES) {
        top = 0;
        for (i = 0; i < PD_NRATES; i++)
            if (res[i].answered >= 100.0 * PD_SUSTAINED &&
                res[i].rate >= PD_SUSTAINED * pd_rates[i] &&
                res[i].overruns == 0)
                top = pd_rates[i];
    }
    for (i = 0; i < PD_NRATES; i++) {
        snprintf(label, sizeof label, "script PD %d Hz: answers/s",
                 pd_rates[i]);
        add_row(b, label, res[i].rate, NOT_APPLIED, 0);
        snprintf(label, sizeof label, "script PD %d Hz: answered (%%)",
                 pd_rates[i]);
        add_row(b, label, res[i].answered, NOT_APPLIED, 1);
        snprintf(label, sizeof label, "script PD %d Hz: overruns",
                 pd_rates[i]);
        r = add_row(b, label, res[i].overruns, NOT_APPLIED, 0);
        if (pd_rates[i] <= PD_RATE_TOP_X)
            set_target(r, T_EQ, 0, 0, "0");
    }
    r = add_row(b, "script PD: top rate sustained (1/s)", top, NOT_APPLIED, 0);
    set_target(r, T_GE, PD_RATE_TOP_X, 0, ">= 1000");
    return rc;
}

int bench_script(struct bench *b)
{
    int rc = 0;

    if (bench_script_echo(b) < 0)
        rc = -1;
    if (bench_script_pd(b) < 0)
        rc = -1;
    return rc;
}
