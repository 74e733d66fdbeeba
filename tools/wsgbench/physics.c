/*
 * wsgbench's physics rows: what the MuJoCo plant (--physics mujoco) costs.
 * Two emulators of the bench's own, one after the other, each holding a
 * 40 mm part (the built-in plant's `part 40`, the MuJoCo plant's `object
 * box 40 20 30`): CPU % of one core of each (the built-in plant holding
 * is idle), steps/s and overruns of the MuJoCo one, stepped at the model's
 * rate, and its CPU against the built-in plant's at that rate (the moving
 * row, from this same run); then Homing, Grasp and Release at x100 with
 * physics. A wsgemu built without MuJoCo refuses
 * --physics mujoco: there are no physics rows then, saying why; nor
 * attached (--attach), where the emulators are not the bench's own.
 */
#define _GNU_SOURCE

#include "wsgbench.h"

#include <arpa/inet.h>
#include <math.h>
#include <netinet/in.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

struct held {
    double cpu, rate, ovr;
};

/* Start a wsgemu (argv), place what world says, home and grasp 40 mm,
 * then measure for the moving window while it holds. 0, 1 when the
 * emulator did not start (no MuJoCo), or -1 (reported). */
static int hold(struct bench *b, const char *name, char **argv,
                const char *world, struct held *h)
{
    struct server s;
    struct link l, ctl;
    char line[256];
    uint8_t dir = 0, pl[8];
    int st, rc = -1;

    link_init(&l, L_TCP, name);
    link_init(&ctl, L_TCP, name);
    if (server_start(b, &s, name, argv, READY_MS) < 0)
        return 1;
    if (link_ready(&ctl, s.line, "control") < 0 ||
        link_ready(&l, s.line, "tcp") < 0)
        goto cleanup;
    if (ctl_cmd(&ctl, world, line, sizeof line) < 0)
        goto cleanup;
    if (strncmp(line, "ok", 2) != 0) {
        msg("%s: \"%s\" answered \"%.80s\"", name, world, line);
        goto cleanup;
    }
    st = link_motion(&l, WSG_CMD_HOMING, &dir, 1);
    if (st == WSG_E_SUCCESS) {
        wsg_put_f32(pl, 40.0f);
        wsg_put_f32(pl + 4, 100.0f);
        st = link_motion(&l, WSG_CMD_GRASP, pl, sizeof pl);
    }
    if (st != WSG_E_SUCCESS) {
        if (st >= 0)
            msg("%s: homing and grasp ended with %s", name,
                wsg_status_name((unsigned)st));
        goto cleanup;
    }
    sleep_s(0.1);
    rc = measure_moving(&ctl, s.pid, b->o.move_s, &h->rate, &h->ovr, &h->cpu);
cleanup:
    link_close(&l);
    wsg_client_close(&ctl.c);
    if (server_stop(&s) < 0)
        rc = -1;
    return rc;
}

/* Homing, Grasp and Release of a 40 mm box at x100 with physics: wall
 * time and simulated time. 0 or -1 (reported). */
static int cycle_x100(struct bench *b, double *wall, double *sim)
{
    char *argv[] = {
        b->emu_exe,     "--tcp", "127.0.0.1:0", "--control", "127.0.0.1:0",
        "--time-scale", "100",   "--physics",   "mujoco",    NULL};
    struct server s;
    struct link l, ctl;
    char line[256];
    uint8_t dir = 0, pl[8];
    double sim0, sim1;
    uint64_t w0, w1;
    int st = WSG_E_SUCCESS, rc = -1, i;
    static const struct {
        uint8_t id;
        float width, speed;
    } cycle[] = {{WSG_CMD_HOMING, 0, 0},
                 {WSG_CMD_GRASP, 40, 100},
                 {WSG_CMD_RELEASE, 100, 100}};

    link_init(&l, L_TCP, "wsgemu physics x100");
    link_init(&ctl, L_TCP, "wsgemu physics x100 control");
    if (server_start(b, &s, "wsgemu --physics mujoco x100", argv, READY_MS) <
        0)
        return -1;
    if (link_ready(&ctl, s.line, "control") < 0 ||
        link_ready(&l, s.line, "tcp") < 0)
        goto cleanup;
    if (ctl_cmd(&ctl, "object box 40 20 30", line, sizeof line) < 0 ||
        strncmp(line, "ok", 2) != 0 || ctl_time(&ctl, &sim0, &w0) < 0)
        goto cleanup;
    for (i = 0; i < 3 && st == WSG_E_SUCCESS; i++) {
        if (cycle[i].id == WSG_CMD_HOMING) {
            st = link_motion(&l, cycle[i].id, &dir, 1);
        } else {
            wsg_put_f32(pl, cycle[i].width);
            wsg_put_f32(pl + 4, cycle[i].speed);
            st = link_motion(&l, cycle[i].id, pl, sizeof pl);
        }
        if (st != WSG_E_SUCCESS && st >= 0)
            msg("wsgemu physics x100: %02Xh ended with %s", cycle[i].id,
                wsg_status_name((unsigned)st));
    }
    if (st != WSG_E_SUCCESS || ctl_time(&ctl, &sim1, &w1) < 0)
        goto cleanup;
    *wall = (double)(w1 - w0) / 1e6;
    *sim = sim1 - sim0;
    rc = 0;
cleanup:
    link_close(&l);
    wsg_client_close(&ctl.c);
    if (server_stop(&s) < 0)
        rc = -1;
    return rc;
}

int bench_physics(struct bench *b)
{
    char *plain[] = {b->emu_exe,    "--tcp",     "127.0.0.1:0", "--control",
                     "127.0.0.1:0", "--physics", "builtin",     NULL};
    char *mj[] = {b->emu_exe,    "--tcp",     "127.0.0.1:0", "--control",
                  "127.0.0.1:0", "--physics", "mujoco",      NULL};
    struct held hb = {NAN, NAN, NAN}, hm = {NAN, NAN, NAN};
    double wall = NAN, sim = NAN;
    int rc = 0, r;
    double moving = NAN;
    struct row *row;
    int i;

    for (i = 0; i < b->nrows; i++)
        if (strcmp(b->rows[i].label, "moving: CPU % of one core") == 0)
            moving = b->rows[i].emu;
    /* Attached, or without MuJoCo: no rows at all (none n/a). */
    if (b->attach)
        return 0;
    if (hold(b, "wsgemu builtin holding", plain, "part 40", &hb) != 0)
        rc = -1;
    r = hold(b, "wsgemu mujoco holding", mj, "object box 40 20 30", &hm);
    if (r == 1) {
        msg("physics: wsgemu --physics mujoco did not start (built without "
            "MuJoCo?): no physics rows");
        return rc;
    }
    if (r < 0 || cycle_x100(b, &wall, &sim) < 0)
        rc = -1;
    add_row(b, "builtin holding: CPU % of one core", hb.cpu, NOT_APPLIED, 1);
    row = add_row(b, "mujoco holding: CPU % of one core", hm.cpu, NOT_APPLIED,
                  1);
    set_target(row, T_LT, 5, 0, "< 5");
    row = add_row(b, "mujoco holding: model steps/s", hm.rate, NOT_APPLIED, 0);
    set_target(row, T_NEAR, 1000, 0, "1000 +- 2%");
    row->tol = 20;
    row = add_row(b, "mujoco holding: step overruns", hm.ovr, NOT_APPLIED, 0);
    set_target(row, T_EQ, 0, 0, "0");
    /* The built-in plant holding is idle (no steps); at the model's step
     * rate it is the moving row's, measured earlier in this run. */
    add_row(b, "mujoco holding / builtin moving CPU",
            moving > 0 ? hm.cpu / moving : NAN, NOT_APPLIED, 1);
    add_row(b, "mujoco x100: cycle wall (ms)", wall, NOT_APPLIED, 1);
    row = add_row(b, "mujoco x100: speed-up",
                  wall > 0 ? sim / (wall / 1e3) : NAN, NOT_APPLIED, 1);
    set_target(row, T_GE, 50, 0, ">= 50");
    return rc;
}
