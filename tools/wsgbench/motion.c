/*
 * wsgbench's figures of the emulator's model while the fingers move: its
 * step rate and overruns from the control channel's stats, and a Homing,
 * Grasp and Release cycle at time scale 100 (its own, or the attached
 * emulator's, put back afterwards).
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

/* ---- 5. the model's step rate while moving ---- */

/* Measure for secs: steps/s and overruns from the control channel's stats,
 * CPU % of pid (none when pid is not > 0). */
int measure_moving(struct link *ctl, pid_t pid, double secs, double *rate,
                   double *overruns, double *cpu)
{
    double s0, o0, s1, o1;
    struct proc_sample a, z;
    uint64_t t0, t1;

    if ((pid > 0 && proc_read(pid, &a) < 0) || ctl_stats(ctl, &s0, &o0) < 0)
        return -1;
    t0 = now_ns();
    sleep_s(secs);
    if ((pid > 0 && proc_read(pid, &z) < 0) || ctl_stats(ctl, &s1, &o1) < 0)
        return -1;
    t1 = now_ns();
    *rate = (s1 - s0) / ((double)(t1 - t0) / 1e9);
    *overruns = o1 - o0;
    *cpu = pid > 0 ? cpu_percent(&a, &z) : NAN;
    return 0;
}

void put_move(uint8_t *pl, double width, double speed)
{
    pl[0] = 0; /* absolute, clamp on block */
    wsg_put_f32(pl + 1, (float)width);
    wsg_put_f32(pl + 5, (float)speed);
}

/* A speed that keeps the fingers moving across the stroke for longer than
 * the window (plus time to set it up), at least the model's 5 mm/s. */
double slow_speed(double window_s)
{
    double v = STROKE_MM / (window_s + 2.0);

    return v < 5.0 ? 5.0 : v;
}

int bench_moving(struct bench *b)
{
    struct link l, ctl;
    uint8_t dir = 0, pl[9];
    double rate = NAN, ovr = NAN, cpu = NAN;
    struct wsg_client_frame f;
    int st, rc = -1;
    char *c = field(b->srv[EMU].line, "control");
    struct sockaddr_in sa;
    struct row *r;

    link_init(&l, L_TCP, "wsgemu");
    link_init(&ctl, L_TCP, "wsgemu control");
    if (attach_lacks(b, "tcp", "moving") ||
        attach_lacks(b, "control", "moving")) {
        rc = 0;
        goto cleanup;
    }
    attach_nopid(b, "the emulator's CPU while moving");
    if (!c || parse_ipport(c, &sa) < 0) {
        msg("wsgemu: no control= in its ready line");
        goto cleanup;
    }
    if (link_tcp(&ctl, &sa) < 0 || open_link(b, &l, EMU, L_TCP) < 0)
        goto cleanup;
    st = link_motion(&l, WSG_CMD_HOMING, &dir, 1);
    if (st != WSG_E_SUCCESS) {
        if (st >= 0)
            msg("wsgemu: Homing ended with %s", wsg_status_name((unsigned)st));
        goto cleanup;
    }
    put_move(pl, 0.0, slow_speed(b->o.move_s));
    if (link_sendf(&l, WSG_CMD_PREPOSITION, pl, sizeof pl) < 0 ||
        link_recv_id(&l, WSG_CMD_PREPOSITION, &f, REPLY_MS) < 0)
        goto cleanup;
    if (f.status != WSG_E_CMD_PENDING) {
        msg("wsgemu: Preposition answered %s", wsg_status_name(f.status));
        goto cleanup;
    }
    sleep_s(0.1);
    rc = measure_moving(&ctl, b->pid[EMU], b->o.move_s, &rate, &ovr, &cpu);
    /* Stop rather than wait out the motion: E_SUCCESS for 22h, the
     * motion's final result (E_CMD_ABORTED) for 21h. */
    if (link_sendf(&l, WSG_CMD_STOP, NULL, 0) < 0 ||
        link_recv_id(&l, WSG_CMD_PREPOSITION, &f, MOTION_MS) < 0)
        rc = -1;
cleanup:
    r = add_row(b, "moving: model steps/s", rate, NOT_APPLIED, 0);
    set_target(r, T_NEAR, 1000, 0, "1000 +- 2%");
    r->tol = 20;
    r = add_row(b, "moving: step overruns", ovr, NOT_APPLIED, 0);
    set_target(r, T_EQ, 0, 0, "0");
    add_row(b, "moving: CPU % of one core", cpu, NOT_APPLIED, 1);
    link_close(&l);
    wsg_client_close(&ctl.c);
    free(c);
    return rc;
}

/* ---- 6. time scale ---- */

/* Attached: the emulator's scale now (control "stats"), then x100. 0, or
 * -1 (reported); *scaled is set once "time scale 100" has been sent. */
static int scale_up(struct link *ctl, char *prior, size_t cap, int *scaled)
{
    char line[1024];
    double v;

    if (ctl_cmd(ctl, "stats", line, sizeof line) < 0)
        return -1;
    if (strncmp(line, "ok {", 4) != 0 || wsg_json_num(line, "scale", &v) < 0) {
        msg("control: \"stats\" answered \"%.120s\" (want ok {...\"scale\":"
            "X...})",
            line);
        return -1;
    }
    snprintf(prior, cap, "%.17g", v);
    snprintf(live_restore, sizeof live_restore, "time scale %s\n", prior);
    live_restore_len = strlen(live_restore);
    live_ctl = ctl->c.fd;
    *scaled = 1;
    if (ctl_cmd(ctl, "time scale 100", line, sizeof line) < 0)
        return -1;
    if (strcmp(line, "ok scale 100") != 0) {
        msg("control: \"time scale 100\" answered \"%.80s\" (want ok scale "
            "100; is its time paused?)",
            line);
        return -1;
    }
    return 0;
}

/* Attached: the scale it had before. 0, or -1 (reported). */
static int scale_back(struct link *ctl, const char *prior)
{
    char cmd[48], line[128];

    live_ctl = -1;
    snprintf(cmd, sizeof cmd, "time scale %s", prior);
    if (ctl_cmd(ctl, cmd, line, sizeof line) < 0) {
        msg("the attached emulator may still run at x100");
        return -1;
    }
    if (strncmp(line, "ok scale", 8) != 0) {
        msg("control: \"%s\" answered \"%.80s\": the attached emulator may "
            "still run at x100",
            cmd, line);
        return -1;
    }
    return 0;
}

/* Homing, Grasp and Release of a 40 mm part at x100: an emulator started
 * with --time-scale 100, or the attached one set to it for the cycle. */
int bench_timescale(struct bench *b)
{
    char *argv[] = {b->emu_exe,    "--tcp",        "127.0.0.1:0", "--control",
                    "127.0.0.1:0", "--time-scale", "100",         NULL};
    struct server s;
    struct link l, ctl;
    struct sockaddr_in sa;
    char line[128], prior[32] = "1", *c = NULL;
    const char *ready;
    uint8_t dir = 0, pl[8];
    double sim0, sim1, wall = NAN, sim = NAN;
    uint64_t w0, w1;
    int st, i, rc = -1, started = 0, scaled = 0;
    struct row *r;
    static const struct {
        uint8_t id;
        float width, speed;
    } cycle[] = {{WSG_CMD_HOMING, 0, 0},
                 {WSG_CMD_GRASP, 40, 100},
                 {WSG_CMD_RELEASE, 100, 100}};

    link_init(&l, L_TCP, "wsgemu x100");
    link_init(&ctl, L_TCP, "wsgemu x100 control");
    if (b->attach) {
        if (attach_lacks(b, "tcp", "x100") ||
            attach_lacks(b, "control", "x100")) {
            rc = 0;
            goto row;
        }
        ready = b->srv[EMU].line;
    } else {
        if (server_start(b, &s, "wsgemu --time-scale 100", argv, READY_MS) < 0)
            goto row;
        started = 1;
        ready = s.line;
    }
    c = field(ready, "control");
    if (!c || parse_ipport(c, &sa) < 0) {
        msg("wsgemu x100: no control= in its ready line");
        goto cleanup;
    }
    if (link_tcp(&ctl, &sa) < 0)
        goto cleanup;
    free(c);
    c = field(ready, "tcp");
    if (!c || parse_ipport(c, &sa) < 0 || link_tcp(&l, &sa) < 0)
        goto cleanup;
    if (b->attach && scale_up(&ctl, prior, sizeof prior, &scaled) < 0)
        goto cleanup;
    if (ctl_cmd(&ctl, "part 40", line, sizeof line) < 0)
        goto cleanup;
    if (strncmp(line, "ok", 2) != 0) {
        msg("control: \"part 40\" answered \"%.80s\"", line);
        goto cleanup;
    }
    if (ctl_time(&ctl, &sim0, &w0) < 0)
        goto cleanup;
    for (i = 0; i < 3; i++) {
        if (cycle[i].id == WSG_CMD_HOMING) {
            st = link_motion(&l, cycle[i].id, &dir, 1);
        } else {
            wsg_put_f32(pl, cycle[i].width);
            wsg_put_f32(pl + 4, cycle[i].speed);
            st = link_motion(&l, cycle[i].id, pl, sizeof pl);
        }
        if (st != WSG_E_SUCCESS) {
            if (st >= 0)
                msg("wsgemu x100: %02Xh ended with %s", cycle[i].id,
                    wsg_status_name((unsigned)st));
            goto cleanup;
        }
    }
    if (ctl_time(&ctl, &sim1, &w1) < 0)
        goto cleanup;
    wall = (double)(w1 - w0) / 1e6;
    sim = sim1 - sim0;
    rc = 0;
cleanup:
    link_close(&l);
    if (scaled && scale_back(&ctl, prior) < 0)
        rc = -1;
    wsg_client_close(&ctl.c);
    if (started && server_stop(&s) < 0)
        rc = -1;
row:
    free(c);
    add_row(b, "x100: home+grasp+release wall (ms)", wall, NOT_APPLIED, 1);
    add_row(b, "x100: same, simulated (s)", sim, NOT_APPLIED, 3);
    r = add_row(b, "x100: speed-up (simulated/wall)",
                rc == 0 ? sim / (wall / 1e3) : NAN, NOT_APPLIED, 1);
    set_target(r, T_GE, 50, 0, ">= 50");
    return rc;
}
