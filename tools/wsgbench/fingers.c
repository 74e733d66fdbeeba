/*
 * wsgbench's finger rows, each on a wsgemu of the bench's own:
 *  - a DSA pad's 168 bytes (63h, --finger0 dsa) against 43h's width, on
 *    the same connection in alternating rounds: what a frame of 84 cells
 *    adds to a round trip (the reference column is the 43h);
 *  - 63h and 73h (a DSA pad and an FMF) polled at 100 Hz, as a tactile
 *    driver polls them, while the fingers move across the stroke: the
 *    model steps dropped meanwhile (control "stats") and CPU % of one
 *    core;
 *  - the example UART tactile tip (packaging/fingers/tactile_tip.lua, a
 *    device model) read through the example script (tip_reader.lua) by a
 *    B0h every 20 ms, each a 50-byte UART transfer: answers missed, model
 *    steps dropped and CPU % of one core.
 * None when attached (--attach): the emulators are not the bench's own.
 */
#define _GNU_SOURCE

#include "wsgbench.h"

#include <arpa/inet.h>
#include <math.h>
#include <netinet/in.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#define DSA_BYTES  168
#define POLL_HZ    100
#define TIP_ID     0xB0
#define TIP_PERIOD 0.020 /* s between two B0h */
#define TIP_ANSWER 56    /* status, alive, 50 bytes, the sensor's 3 */

/* The example device models and script, from the source tree. */
#ifndef WSG_BENCH_FINGERS
#define WSG_BENCH_FINGERS "packaging/fingers"
#endif

/* One request and its answer: ID id, E_SUCCESS and want bytes after the
 * status (want < 0: any). The time in us. 0, or -1 (reported). */
static int request(struct link *l, uint8_t id, long want, double *us)
{
    uint64_t t0 = now_ns();
    struct wsg_client_frame f;
    int r;

    if (link_sendf(l, id, NULL, 0) < 0)
        return -1;
    r = link_recv_id(l, id, &f, REPLY_MS); /* says why it failed */
    if (r < 0)
        return -1;
    if (f.len < 2 || f.status != WSG_E_SUCCESS ||
        (want >= 0 && f.len != (size_t)want + 2)) {
        msg("%s: answer to %02Xh: %u bytes, status %s", l->who, id, f.len,
            f.len >= 2 ? wsg_status_name(f.status) : "none");
        return -1;
    }
    if (us)
        *us = (double)(now_ns() - t0) / 1e3;
    return 0;
}

static int dsa_take(void *ctx, int side, double *us)
{
    struct link *l = ctx;

    return side == EMU ? request(l, 0x63, DSA_BYTES, us)
                       : request(l, WSG_CMD_GET_WIDTH, 4, us);
}

/* 63h's 168 bytes against 43h. */
static int rows_dsa(struct bench *b)
{
    char *argv[] = {b->emu_exe,    "--tcp",     "127.0.0.1:0", "--control",
                    "127.0.0.1:0", "--finger0", "dsa",         NULL};
    struct dist dd[2] = {{NAN, NAN, NAN}, {NAN, NAN, NAN}};
    struct emud d;
    struct row *r;
    int rc = -1;

    if (emud_start(b, &d, "wsgemu --finger0 dsa", argv) == 0 &&
        alternate(b, dsa_take, NULL, &d.l, dd) == 0)
        rc = 0;
    if (emud_stop(&d) < 0)
        rc = -1;
    r = add_row(b, "DSA 63h 168 B round trip median (us)", dd[EMU].p50,
                dd[REF].p50, 1);
    set_target(r, T_LE, 1.1, 1, "ratio <= 1.1");
    add_row(b, "DSA 63h 168 B round trip p99 (us)", dd[EMU].p99, dd[REF].p99,
            1);
    return rc;
}

/* 63h and 73h at POLL_HZ while the fingers move. */
static int rows_poll(struct bench *b)
{
    char *argv[] = {b->emu_exe,    "--tcp",     "127.0.0.1:0", "--control",
                    "127.0.0.1:0", "--finger0", "dsa",         "--finger1",
                    "fmf",         NULL};
    struct emud d;
    struct proc_sample a, z;
    double s0, o0, s1, o1, ovr = NAN, cpu = NAN;
    uint8_t dir = 0, pl[9];
    uint64_t next, end;
    struct wsg_client_frame f;
    int rc = -1, st;

    if (emud_start(b, &d, "wsgemu --finger0 dsa --finger1 fmf", argv) < 0)
        goto cleanup;
    st = link_motion(&d.l, WSG_CMD_HOMING, &dir, 1);
    if (st != WSG_E_SUCCESS) {
        if (st >= 0)
            msg("fingers: homing ended with %s",
                wsg_status_name((unsigned)st));
        goto cleanup;
    }
    /* Across the stroke, slowly enough to move for the whole window. */
    put_move(pl, 0.0, slow_speed(b->o.move_s));
    if (link_sendf(&d.l, WSG_CMD_PREPOSITION, pl, sizeof pl) < 0)
        goto cleanup;
    sleep_s(0.2);
    if (proc_read(d.s.pid, &a) < 0 || ctl_stats(&d.ctl, &s0, &o0) < 0)
        goto cleanup;
    next = now_ns();
    end = next + (uint64_t)(b->o.move_s * 1e9);
    while (now_ns() < end) {
        if (request(&d.l, 0x63, DSA_BYTES, NULL) < 0 ||
            request(&d.l, 0x73, 4, NULL) < 0)
            goto cleanup;
        next += 1000000000ull / POLL_HZ;
        if (next > now_ns())
            sleep_s((double)(next - now_ns()) / 1e9);
    }
    if (proc_read(d.s.pid, &z) < 0 || ctl_stats(&d.ctl, &s1, &o1) < 0)
        goto cleanup;
    ovr = o1 - o0;
    cpu = cpu_percent(&a, &z);
    /* Stop rather than wait out the motion. */
    if (link_sendf(&d.l, WSG_CMD_STOP, NULL, 0) < 0 ||
        link_recv_id(&d.l, WSG_CMD_PREPOSITION, &f, MOTION_MS) < 0)
        goto cleanup;
    rc = 0;
cleanup:
    if (emud_stop(&d) < 0)
        rc = -1;
    add_row(b, "63h+73h 100 Hz moving: CPU % of core", cpu, NOT_APPLIED, 1);
    set_target(add_row(b, "63h+73h 100 Hz moving: step overruns", ovr,
                       NOT_APPLIED, 0),
               T_EQ, 0, 0, "0");
    return rc;
}

/* The UART tactile tip answering 50 bytes every 20 ms. */
static int rows_tip(struct bench *b)
{
    char tip[PATH_MAX], spi[PATH_MAX], script[PATH_MAX];
    char *argv[] = {b->emu_exe,    "--tcp",     "127.0.0.1:0", "--control",
                    "127.0.0.1:0", "--finger0", tip,           "--finger1",
                    spi,           "--script",  script,        NULL};
    struct emud d;
    struct proc_sample a, z;
    double s0, o0, s1, o1, ovr = NAN, cpu = NAN, missed = NAN;
    uint64_t next, end;
    long sent = 0, late = 0;
    int rc = -1, i;

    snprintf(tip, sizeof tip, "device:%s/tactile_tip.lua", WSG_BENCH_FINGERS);
    snprintf(spi, sizeof spi, "device:%s/spi_sensor.lua", WSG_BENCH_FINGERS);
    snprintf(script, sizeof script, "%s/tip_reader.lua", WSG_BENCH_FINGERS);
    if (access(script, R_OK) < 0) {
        msg("fingers: cannot read %s: no device model row", script);
        return 0;
    }
    if (emud_start(b, &d, "wsgemu tactile tip", argv) < 0)
        goto cleanup;
    /* The script powers the tip and waits for it first (some 0.5 s). */
    for (i = 0; i < 50 && request(&d.l, TIP_ID, TIP_ANSWER - 2, NULL) < 0; i++)
        sleep_s(0.1);
    if (i == 50)
        goto cleanup;
    if (proc_read(d.s.pid, &a) < 0 || ctl_stats(&d.ctl, &s0, &o0) < 0)
        goto cleanup;
    next = now_ns();
    end = next + (uint64_t)(b->o.move_s * 1e9);
    while (now_ns() < end) {
        sent++;
        if (request(&d.l, TIP_ID, TIP_ANSWER - 2, NULL) < 0)
            goto cleanup;
        next += (uint64_t)(TIP_PERIOD * 1e9);
        if (next > now_ns())
            sleep_s((double)(next - now_ns()) / 1e9);
        else
            late++;
    }
    if (proc_read(d.s.pid, &z) < 0 || ctl_stats(&d.ctl, &s1, &o1) < 0)
        goto cleanup;
    ovr = o1 - o0;
    cpu = cpu_percent(&a, &z);
    missed = (double)late;
    rc = 0;
cleanup:
    if (emud_stop(&d) < 0)
        rc = -1;
    add_row(b, "UART tip 50 B/20 ms: CPU % of core", cpu, NOT_APPLIED, 1);
    set_target(
        add_row(b, "UART tip 50 B/20 ms: step overruns", ovr, NOT_APPLIED, 0),
        T_EQ, 0, 0, "0");
    add_row(b, "UART tip 50 B/20 ms: late answers", sent > 0 ? missed : NAN,
            NOT_APPLIED, 0);
    return rc;
}

int bench_fingers(struct bench *b)
{
    int rc = 0;

    if (b->attach)
        return 0;
    if (rows_dsa(b) < 0)
        rc = -1;
    if (rows_poll(b) < 0)
        rc = -1;
    if (rows_tip(b) < 0)
        rc = -1;
    return rc;
}
