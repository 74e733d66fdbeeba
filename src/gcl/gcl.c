/*
 * The GCL interpreter: a connection's lines become commands. Most become
 * the binary command they stand for (HOME is 20h, POS? 43h, AUTOSEND a
 * 43h subscription...) and go through the device's dispatcher, so the
 * command table's checks and error codes are GCL's too; the answer comes
 * back through the session's format hook, which writes it as the command's
 * text. GRIP alone drives the model itself: it takes a grasping window
 * (the connection's PWT and CLT) that 25h has no field for.
 *
 * What arrives in the format hook while no command runs is asynchronous: a
 * motion's final result (FIN or ERR with its command's name) or a stream
 * packet (@NAME=value). docs/behaviour.md lists every reply.
 */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include "wsg/gcl.h"
#include "wsg/proto.h"

/* An answer line at most: FDATA of a DSA pad is 84 numbers of up to 4
 * digits. */
#define WSG_GCL_OUT_MAX 512u

struct wsg_gcl_command;
typedef void (*gcl_run_fn)(struct wsg_gcl *g, const struct wsg_gcl_command *k,
                           const struct wsg_gcl_cmd *c);
/* Writes a command's answer from the binary one. */
typedef void (*gcl_answer_fn)(struct wsg_gcl *g, uint16_t status,
                              const uint8_t *params, size_t len);

/* One command of the table: its name, the forms it takes, how many
 * arguments, what runs it, and for the commands that become a binary one,
 * its ID, and the key its answer and stream lines carry. */
struct wsg_gcl_command {
    const char *name;
    unsigned forms; /* 1 << WSG_GCL_CALL | ... */
    unsigned min_args, max_args;
    gcl_run_fn run;
    uint8_t id;
    gcl_answer_fn answer;
    const char *key; /* "POS" of POS? and @POS= */
};

/* ---- output ---- */

static void gcl_line(struct wsg_gcl *g, const char *fmt, ...)
{
    char buf[WSG_GCL_OUT_MAX];
    va_list ap;
    size_t n;

    va_start(ap, fmt);
    n = wsg_gcl_line_vformat(buf, sizeof buf, fmt, ap);
    va_end(ap);
    if (n)
        wsg_device_send(g->dev, g->s, (const uint8_t *)buf, n);
}

/* "ERR MOVE 16", with VERBOSE=1 "ERR MOVE 16 E_ACCESS_DENIED". */
static void gcl_err(struct wsg_gcl *g, const char *name, uint16_t status)
{
    const char *e = wsg_status_name(status);

    if (g->verbose && e)
        gcl_line(g, "ERR %s %u %s", name, (unsigned)status, e);
    else
        gcl_line(g, "ERR %s %u", name, (unsigned)status);
}

/* ---- answers ---- */

/* A command that is acknowledged: E_CMD_PENDING (a motion) or E_SUCCESS. */
static void answer_ack(struct wsg_gcl *g, uint16_t status,
                       const uint8_t *params, size_t len)
{
    (void)params;
    (void)len;
    if (status == WSG_E_SUCCESS || status == WSG_E_CMD_PENDING)
        gcl_line(g, "ACK %s", g->cur->name);
    else
        gcl_err(g, g->cur->name, status);
}

/* A float reading: "POS=54.2". */
static void answer_float(struct wsg_gcl *g, uint16_t status,
                         const uint8_t *params, size_t len)
{
    if (status != WSG_E_SUCCESS || len < 4)
        gcl_err(g, g->cur->name, status);
    else
        gcl_line(g, "%s=%.1f", g->cur->key, (double)wsg_get_f32(params));
}

static void answer_u8(struct wsg_gcl *g, uint16_t status,
                      const uint8_t *params, size_t len)
{
    if (status != WSG_E_SUCCESS || len < 1)
        gcl_err(g, g->cur->name, status);
    else
        gcl_line(g, "%s=%u", g->cur->key, (unsigned)params[0]);
}

static void answer_u32(struct wsg_gcl *g, uint16_t status,
                       const uint8_t *params, size_t len)
{
    if (status != WSG_E_SUCCESS || len < 4)
        gcl_err(g, g->cur->name, status);
    else
        gcl_line(g, "%s=%lu", g->cur->key, (unsigned long)wsg_get_u32(params));
}

static void answer_temp(struct wsg_gcl *g, uint16_t status,
                        const uint8_t *params, size_t len)
{
    if (status != WSG_E_SUCCESS || len < 2)
        gcl_err(g, g->cur->name, status);
    else
        gcl_line(g, "TEMP=%.1f", (int16_t)wsg_get_u16(params) / 10.0);
}

static void answer_stats(struct wsg_gcl *g, uint16_t status,
                         const uint8_t *params, size_t len)
{
    if (status != WSG_E_SUCCESS || len < 8)
        gcl_err(g, g->cur->name, status);
    else
        gcl_line(g, "GRIPSTATS=%lu,%u,%u", (unsigned long)wsg_get_u32(params),
                 (unsigned)wsg_get_u16(params + 4),
                 (unsigned)wsg_get_u16(params + 6));
}

/* 50h answers DEVTYPE?, VERSION? and SN?. */
static void answer_info(struct wsg_gcl *g, uint16_t status,
                        const uint8_t *params, size_t len)
{
    static const char *const types[] = {"UNKNOWN", "WSG50", "WSG32", "KMS40",
                                        "WTS",     "WSG25", "WSG70"};
    unsigned v;

    if (status != WSG_E_SUCCESS || len < 8) {
        gcl_err(g, g->cur->name, status);
        return;
    }
    if (strcmp(g->cur->key, "DEVTYPE") == 0) {
        gcl_line(g, "DEVTYPE=%s",
                 params[0] < sizeof types / sizeof types[0] ? types[params[0]]
                                                            : "UNKNOWN");
    } else if (strcmp(g->cur->key, "VERSION") == 0) {
        v = wsg_get_u16(params + 2);
        gcl_line(g, "VERSION=%u.%u.%u", v >> 12, (v >> 8) & 15u,
                 (v >> 4) & 15u);
    } else {
        gcl_line(g, "SN=%lu", (unsigned long)wsg_get_u32(params + 4));
    }
}

static void answer_tag(struct wsg_gcl *g, uint16_t status,
                       const uint8_t *params, size_t len)
{
    if (status != WSG_E_SUCCESS)
        gcl_err(g, g->cur->name, status);
    else
        gcl_line(g, "TAG=%.*s", (int)len, (const char *)params);
}

/* ---- running a command ---- */

/* Dispatch the binary command k stands for, with payload; its answer comes
 * back through the format hook while cur is set. */
static void gcl_dispatch(struct wsg_gcl *g, const struct wsg_gcl_command *k,
                         uint8_t id, const uint8_t *payload, size_t len)
{
    struct wsg_frame f;

    f.id = id;
    f.len = (uint16_t)len;
    f.payload = payload;
    g->cur = k;
    g->cur_id = id;
    g->answered = 0;
    wsg_device_dispatch(g->dev, g->s, &f);
    /* Every command of the table answers; should one not, the client
     * still gets its one line. */
    if (!g->answered)
        gcl_err(g, k->name, WSG_E_CMD_FAILED);
    g->cur = NULL;
}

static void run_plain(struct wsg_gcl *g, const struct wsg_gcl_command *k,
                      const struct wsg_gcl_cmd *c)
{
    (void)c;
    gcl_dispatch(g, k, k->id, NULL, 0);
}

/* FSACK(): 24h with the "ack" it takes. */
static void run_fsack(struct wsg_gcl *g, const struct wsg_gcl_command *k,
                      const struct wsg_gcl_cmd *c)
{
    static const uint8_t ack[3] = {'a', 'c', 'k'};

    (void)c;
    gcl_dispatch(g, k, k->id, ack, sizeof ack);
}

static void put_f32(uint8_t *p, double v)
{
    wsg_put_f32(p, (float)v);
}

static void run_home(struct wsg_gcl *g, const struct wsg_gcl_command *k,
                     const struct wsg_gcl_cmd *c)
{
    /* HOME(1) positive, HOME(0) negative, HOME() the configured. */
    uint8_t dir = c->nargs == 0          ? WSG_HOME_DEFAULT
                  : c->arg[0].num != 0.0 ? WSG_HOME_POSITIVE
                                         : WSG_HOME_NEGATIVE;

    gcl_dispatch(g, k, k->id, &dir, 1);
}

static double gcl_speed(const struct wsg_gcl *g, const struct wsg_gcl_cmd *c,
                        unsigned i)
{
    return c->nargs > i ? c->arg[i].num : g->cfg.default_speed;
}

static void run_move(struct wsg_gcl *g, const struct wsg_gcl_command *k,
                     const struct wsg_gcl_cmd *c)
{
    uint8_t p[9];

    p[0] = 0;
    put_f32(p + 1, c->arg[0].num);
    put_f32(p + 5, gcl_speed(g, c, 1));
    gcl_dispatch(g, k, k->id, p, sizeof p);
}

/* RELEASE opens from where the fingers are, by the pull-back, and only
 * after a GRIP (the grasping state one a grip ends in). */
static void run_release(struct wsg_gcl *g, const struct wsg_gcl_command *k,
                        const struct wsg_gcl_cmd *c)
{
    const struct wsg_axis *ax = wsg_device_axis_const(g->dev);
    enum wsg_grasp_state gs = wsg_axis_grasp_state(ax);
    double pull = c->nargs > 0 ? c->arg[0].num : g->cfg.release_pullback;
    uint8_t p[8];

    if (gs != WSG_GS_HOLDING && gs != WSG_GS_NO_PART &&
        gs != WSG_GS_PART_LOST) {
        gcl_err(g, k->name, WSG_E_ACCESS_DENIED);
        return;
    }
    if (pull < 0) {
        gcl_err(g, k->name, WSG_E_RANGE_ERROR);
        return;
    }
    put_f32(p, wsg_axis_width(ax) + pull);
    put_f32(p + 4, gcl_speed(g, c, 1));
    gcl_dispatch(g, k, k->id, p, sizeof p);
}

/* GRIP(): close until contact, always HOLDING (the fingers may meet).
 * GRIP(force, width[, speed]): a part is expected at width, judged by the
 * connection's window (PWT, CLT). The force, when given, is the force
 * limit from now on, as 32h sets it. */
static void run_grip(struct wsg_gcl *g, const struct wsg_gcl_command *k,
                     const struct wsg_gcl_cmd *c)
{
    struct wsg_axis *ax = wsg_device_axis(g->dev);
    const struct wsg_axis_config *cfg = wsg_axis_cfg(ax);
    struct wsg_grasp_window win;
    double width;
    uint16_t st;

    st = wsg_device_motion_check(g->dev, 1);
    if (st == WSG_E_SUCCESS && wsg_axis_busy(ax))
        st = WSG_E_ALREADY_RUNNING;
    if (st == WSG_E_SUCCESS && wsg_axis_grasp_state(ax) == WSG_GS_HOLDING)
        st = WSG_E_ACCESS_DENIED;
    if (st != WSG_E_SUCCESS) {
        gcl_err(g, k->name, st);
        return;
    }
    if (c->nargs > 0)
        wsg_axis_set_force_limit(ax, c->arg[0].num);
    if (c->nargs > 1) {
        width = c->arg[1].num;
        win.travel = g->clt;
        win.tolerance = g->pwt;
    } else {
        /* Any contact closing, down to the fingers meeting, is the part. */
        width = 0.0;
        win.travel = 0.0;
        win.tolerance = cfg->stroke;
    }
    /* As the model takes it: a width beyond the stroke is the stroke. */
    width = width < 0 ? 0 : width > cfg->stroke ? cfg->stroke : width;
    st = wsg_axis_request_grasp_in(ax, width, gcl_speed(g, c, 2), &win,
                                   g->s->tag);
    if (st == WSG_E_CMD_PENDING)
        gcl_line(g, "ACK %s", k->name);
    else
        gcl_err(g, k->name, st);
    wsg_axis_settle(ax);
}

static void run_bye(struct wsg_gcl *g, const struct wsg_gcl_command *k,
                    const struct wsg_gcl_cmd *c)
{
    (void)c;
    gcl_dispatch(g, k, k->id, NULL, 0);
}

static void run_verbose(struct wsg_gcl *g, const struct wsg_gcl_command *k,
                        const struct wsg_gcl_cmd *c)
{
    if (c->form == WSG_GCL_SET) {
        if (c->arg[0].is_str ||
            (c->arg[0].num != 0.0 && c->arg[0].num != 1.0)) {
            gcl_err(g, k->name, WSG_E_INVALID_PARAMETER);
            return;
        }
        g->verbose = c->arg[0].num != 0.0;
    }
    gcl_line(g, "VERBOSE=%d", g->verbose);
}

/* PWT and CLT: this connection's window for its GRIPs. */
static void run_window(struct wsg_gcl *g, const struct wsg_gcl_command *k,
                       const struct wsg_gcl_cmd *c)
{
    const struct wsg_axis_config *cfg =
        wsg_axis_cfg(wsg_device_axis_const(g->dev));
    int pwt = strcmp(k->name, "PWT") == 0;
    double *v = pwt ? &g->pwt : &g->clt;
    double def = pwt ? cfg->width_tolerance : cfg->clamp_travel;

    if (c->form == WSG_GCL_SET) {
        if (c->arg[0].is_str || c->arg[0].num < 0 ||
            c->arg[0].num > cfg->stroke) {
            gcl_err(g, k->name, WSG_E_RANGE_ERROR);
            return;
        }
        *v = c->arg[0].num;
    }
    gcl_line(g, "%s=%.1f", k->name, *v >= 0 ? *v : def);
}

static void run_get(struct wsg_gcl *g, const struct wsg_gcl_command *k,
                    const struct wsg_gcl_cmd *c)
{
    uint8_t zero = 0;

    (void)c;
    /* 42h takes its reset flag; the others nothing. */
    gcl_dispatch(g, k, k->id, &zero, k->id == WSG_CMD_GET_GRASP_STATS);
}

/* FDATA? (FDATA[i]? for finger i, FDATA? finger 0): a force measurement
 * finger's force (tared), a DSA pad's 84 cells comma-separated; the finger
 * commands' errors otherwise (no finger, no power, a fault), E_NO_SENSOR
 * for a finger without data. */
static void run_fdata(struct wsg_gcl *g, const struct wsg_gcl_command *k,
                      const struct wsg_gcl_cmd *c)
{
    struct wsg_fingers *fs = &g->dev->fingers;
    int i = c->index >= 0 ? c->index : 0;
    uint16_t st;
    char line[WSG_DSA_CELLS * 5 + 16];
    size_t used = 0;
    int j;

    if (c->index > 1) {
        gcl_err(g, k->name, WSG_E_INDEX_OUT_OF_BOUNDS);
        return;
    }
    st = wsg_finger_check(fs, i,
                          wsg_axis_faults(wsg_device_axis_const(g->dev)));
    if (st == WSG_E_SUCCESS && fs->f[i].kind != WSG_FINGER_FMF &&
        fs->f[i].kind != WSG_FINGER_DSA)
        st = WSG_E_NO_SENSOR;
    if (st != WSG_E_SUCCESS) {
        gcl_err(g, k->name, st);
        return;
    }
    if (fs->f[i].kind == WSG_FINGER_FMF) {
        snprintf(line, sizeof line, "%.1f", (double)fs->f[i].fmf);
    } else {
        for (j = 0; j < WSG_DSA_CELLS; j++)
            used +=
                (size_t)snprintf(line + used, sizeof line - used, "%s%u",
                                 j ? "," : "", (unsigned)fs->f[i].cells[j]);
    }
    if (c->index >= 0)
        gcl_line(g, "FDATA[%d]=%s", c->index, line);
    else
        gcl_line(g, "FDATA=%s", line);
}

/* The values AUTOSEND can push, and the stream each one is. */
static const struct {
    const char *key;
    uint8_t id;
} gcl_streams[] = {{"POS", WSG_CMD_GET_WIDTH},
                   {"SPEED", WSG_CMD_GET_SPEED},
                   {"FORCE", WSG_CMD_GET_FORCE},
                   {"GRIPSTATE", WSG_CMD_GET_GRASP_STATE},
                   {"SYSFLAGS", WSG_CMD_GET_SYSTEM_STATE}};

#define GCL_NSTREAMS (sizeof gcl_streams / sizeof gcl_streams[0])

/* AUTOSEND("POS", MS): @POS=value every MS ms; MS 0 ends it. */
static void run_autosend(struct wsg_gcl *g, const struct wsg_gcl_command *k,
                         const struct wsg_gcl_cmd *c)
{
    double ms = c->arg[1].num;
    uint8_t p[3];
    size_t i;

    if (!c->arg[0].is_str || c->arg[1].is_str) {
        gcl_err(g, k->name, WSG_E_INVALID_PARAMETER);
        return;
    }
    for (i = 0; i < GCL_NSTREAMS; i++)
        if (strcmp(gcl_streams[i].key, c->arg[0].str) == 0)
            break;
    if (i == GCL_NSTREAMS) {
        gcl_err(g, k->name, WSG_E_INVALID_PARAMETER);
        return;
    }
    if (ms < 0 || ms > 65535 || ms != floor(ms)) {
        gcl_err(g, k->name, WSG_E_RANGE_ERROR);
        return;
    }
    p[0] = ms > 0 ? 1u : 0u; /* auto-update, every period */
    wsg_put_u16(p + 1, (uint16_t)ms);
    gcl_dispatch(g, k, gcl_streams[i].id, p, sizeof p);
}

#define F_CALL  (1u << WSG_GCL_CALL)
#define F_QUERY (1u << WSG_GCL_QUERY)
#define F_SET   (1u << WSG_GCL_SET)

/* Every command, as GCL.md lists them. */
static const struct wsg_gcl_command gcl_commands[] = {
    {"VERBOSE", F_SET | F_QUERY, 0, 1, run_verbose, 0, NULL, NULL},
    {"BYE", F_CALL, 0, 0, run_bye, WSG_CMD_DISCONNECT, answer_ack, NULL},
    {"HOME", F_CALL, 0, 1, run_home, WSG_CMD_HOMING, answer_ack, NULL},
    {"MOVE", F_CALL, 1, 2, run_move, WSG_CMD_PREPOSITION, answer_ack, NULL},
    {"GRIP", F_CALL, 0, 3, run_grip, WSG_CMD_GRASP, NULL, NULL},
    {"RELEASE", F_CALL, 0, 2, run_release, WSG_CMD_RELEASE, answer_ack, NULL},
    {"STOP", F_CALL, 0, 0, run_plain, WSG_CMD_STOP, answer_ack, NULL},
    {"FASTSTOP", F_CALL, 0, 0, run_plain, WSG_CMD_FAST_STOP, answer_ack, NULL},
    {"FSACK", F_CALL, 0, 0, run_fsack, WSG_CMD_ACK_FAST_STOP, answer_ack,
     NULL},
    {"TARE", F_CALL, 0, 0, run_plain, WSG_CMD_TARE, answer_ack, NULL},
    {"PWT", F_SET | F_QUERY, 0, 1, run_window, 0, NULL, NULL},
    {"CLT", F_SET | F_QUERY, 0, 1, run_window, 0, NULL, NULL},
    {"POS", F_QUERY, 0, 0, run_get, WSG_CMD_GET_WIDTH, answer_float, "POS"},
    {"SPEED", F_QUERY, 0, 0, run_get, WSG_CMD_GET_SPEED, answer_float,
     "SPEED"},
    {"FORCE", F_QUERY, 0, 0, run_get, WSG_CMD_GET_FORCE, answer_float,
     "FORCE"},
    {"GRIPSTATE", F_QUERY, 0, 0, run_get, WSG_CMD_GET_GRASP_STATE, answer_u8,
     "GRIPSTATE"},
    {"SYSFLAGS", F_QUERY, 0, 0, run_get, WSG_CMD_GET_SYSTEM_STATE, answer_u32,
     "SYSFLAGS"},
    {"GRIPSTATS", F_QUERY, 0, 0, run_get, WSG_CMD_GET_GRASP_STATS,
     answer_stats, "GRIPSTATS"},
    {"TEMP", F_QUERY, 0, 0, run_get, WSG_CMD_GET_TEMPERATURE, answer_temp,
     "TEMP"},
    {"DEVTYPE", F_QUERY, 0, 0, run_get, WSG_CMD_GET_SYSTEM_INFO, answer_info,
     "DEVTYPE"},
    {"VERSION", F_QUERY, 0, 0, run_get, WSG_CMD_GET_SYSTEM_INFO, answer_info,
     "VERSION"},
    {"SN", F_QUERY, 0, 0, run_get, WSG_CMD_GET_SYSTEM_INFO, answer_info, "SN"},
    {"TAG", F_QUERY, 0, 0, run_get, WSG_CMD_GET_DEVICE_TAG, answer_tag, "TAG"},
    {"FDATA", F_QUERY, 0, 0, run_fdata, 0, NULL, NULL},
    {"AUTOSEND", F_CALL, 2, 2, run_autosend, 0, answer_ack, NULL},
};

#define GCL_NCOMMANDS (sizeof gcl_commands / sizeof gcl_commands[0])

/* Names of the motions whose final results come later, by binary ID. */
static const char *gcl_motion_name(uint8_t id)
{
    switch (id) {
    case WSG_CMD_HOMING:
        return "HOME";
    case WSG_CMD_PREPOSITION:
        return "MOVE";
    case WSG_CMD_GRASP:
        return "GRIP";
    case WSG_CMD_RELEASE:
        return "RELEASE";
    default:
        return NULL;
    }
}

/* A GRIP that failed: blocked before its window is a collision
 * (E_AXIS_BLOCKED), through its clamping travel no part (E_CMD_FAILED),
 * as the model tells them apart. */
static uint16_t gcl_grip_status(const struct wsg_gcl *g, uint16_t status)
{
    if (status == WSG_E_CMD_FAILED &&
        wsg_axis_grasp_collided(wsg_device_axis_const(g->dev)))
        return WSG_E_AXIS_BLOCKED;
    return status;
}

/* The session's format hook: the device's answer to the command running,
 * or later a final result or a stream packet. */
static void gcl_format(void *ctx, struct wsg_session *s, uint8_t id,
                       uint16_t status, const uint8_t *params, size_t len)
{
    struct wsg_gcl *g = ctx;
    const char *name;
    size_t i;

    (void)s;
    if (g->cur && !g->answered && id == g->cur_id && g->cur->answer) {
        g->answered = 1;
        g->cur->answer(g, status, params, len);
        return;
    }
    name = gcl_motion_name(id);
    if (name && status != WSG_E_CMD_PENDING) {
        if (id == WSG_CMD_GRASP)
            status = gcl_grip_status(g, status);
        if (status == WSG_E_SUCCESS)
            gcl_line(g, "FIN %s", name);
        else
            gcl_err(g, name, status);
        return;
    }
    for (i = 0; i < GCL_NSTREAMS; i++) {
        if (gcl_streams[i].id != id || status != WSG_E_SUCCESS)
            continue;
        if (id == WSG_CMD_GET_SYSTEM_STATE && len >= 4)
            gcl_line(g, "@SYSFLAGS=%lu", (unsigned long)wsg_get_u32(params));
        else if (id == WSG_CMD_GET_GRASP_STATE && len >= 1)
            gcl_line(g, "@GRIPSTATE=%u", (unsigned)params[0]);
        else if (len >= 4)
            gcl_line(g, "@%s=%.1f", gcl_streams[i].key,
                     (double)wsg_get_f32(params));
        return;
    }
}

static void gcl_run(struct wsg_gcl *g, const char *line, size_t n)
{
    struct wsg_gcl_cmd c;
    size_t i;
    int bad = wsg_gcl_parse(line, n, &c) < 0;

    /* After BYE every command is refused, as every packet after 07h is
     * (3.1.2: the gripper waits for the close), whatever runs it: not
     * only those that reach the dispatcher, but VERBOSE, PWT, CLT, FDATA,
     * GRIP and unknown or malformed ones too. */
    if (g->s->announced) {
        gcl_err(g, c.name[0] ? c.name : "?", WSG_E_ACCESS_DENIED);
        return;
    }
    if (bad) {
        gcl_err(g, c.name[0] ? c.name : "?", WSG_E_CMD_FORMAT_ERROR);
        return;
    }
    for (i = 0; i < GCL_NCOMMANDS; i++) {
        const struct wsg_gcl_command *k = &gcl_commands[i];

        if (strcmp(k->name, c.name) != 0)
            continue;
        if (!(k->forms & (1u << c.form)) ||
            (c.form == WSG_GCL_CALL &&
             (c.nargs < k->min_args || c.nargs > k->max_args)) ||
            (c.index >= 0 && k->run != run_fdata)) {
            gcl_err(g, c.name, WSG_E_CMD_FORMAT_ERROR);
            return;
        }
        if (c.form == WSG_GCL_CALL && k->run != run_autosend)
            for (unsigned a = 0; a < c.nargs; a++)
                if (c.arg[a].is_str) {
                    gcl_err(g, c.name, WSG_E_INVALID_PARAMETER);
                    return;
                }
        k->run(g, k, &c);
        return;
    }
    gcl_err(g, c.name, WSG_E_CMD_UNKNOWN);
}

void wsg_gcl_init(struct wsg_gcl *g, struct wsg_device *d,
                  struct wsg_session *s, const struct wsg_gcl_config *cfg)
{
    memset(g, 0, sizeof *g);
    g->dev = d;
    g->s = s;
    g->cfg = *cfg;
    g->pwt = -1.0;
    g->clt = -1.0;
    wsg_gcl_line_init(&g->line);
    s->flags |= WSG_SESSION_TEXT;
    s->format = gcl_format;
    s->format_ctx = g;
}

void wsg_gcl_input(struct wsg_gcl *g, const uint8_t *data, size_t len)
{
    while (len > 0) {
        enum wsg_gcl_event ev;
        const char *line = NULL;
        size_t n = 0,
               used = wsg_gcl_line_feed(&g->line, data, len, &ev, &line, &n);

        data += used;
        len -= used;
        switch (ev) {
        case WSG_GCL_LINE:
            wsg_device_trace_line(g->dev, g->s, line, n);
            g->dev->last_tag = g->s->tag;
            gcl_run(g, line, n);
            /* As the dispatcher does after a command: what it asked for
             * is there for the next line. */
            wsg_axis_settle(wsg_device_axis(g->dev));
            break;
        case WSG_GCL_TOO_LONG:
            wsg_device_trace_line(g->dev, g->s, "(line too long)", 15);
            gcl_err(g, "?", WSG_E_CMD_FORMAT_ERROR);
            break;
        case WSG_GCL_BINARY:
            wsg_device_trace_line(g->dev, g->s, "(binary bytes)", 14);
            gcl_err(g, "?", WSG_E_CMD_FORMAT_ERROR);
            break;
        default:
            break;
        }
    }
}
