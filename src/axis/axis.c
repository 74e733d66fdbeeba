/*
 * The finger axis model.
 *
 * Motions follow a trapezoidal (acceleration-limited) profile from rest,
 * evaluated analytically from the time since the motion started, so a
 * motion's duration is exact to one step whatever the step length. Contact
 * is the only thing that cuts a profile short: closing onto the part builds
 * up force as stiffness times compression until the force limit is reached,
 * and there the axis blocks. What happens at a block depends on the motion:
 * homing takes its reference, a preposition stops or clamps, a grasp holds
 * or reports no part by the clamping-travel window of NOTES.md.
 *
 * Speed mode (a script's mc.speed) is the one motion without a profile: the
 * velocity ramps to a set speed with the maximum acceleration, step by
 * step, and a block does not end it: the fingers stay pushed against it
 * for as long as the set speed points into it.
 *
 * Handlers record requests; wsg_axis_settle applies them in a fixed order
 * (FAST STOP, acknowledge, stop, new motion), and wsg_axis_step settles and
 * then advances the physics. The dispatcher settles after every command, so
 * the next answer already reflects it.
 *
 * The ranges of the values a model takes (wsg_axis_config_range) live here
 * once: the session commands clamp into them, and the daemon's options
 * check their settings against them.
 *
 * The state's layout (axis_impl.h) is this folder's alone: the getters
 * here are how everyone else reads it, and the compile-time checks below
 * hold struct wsg_axis_storage, in which a holder keeps it, to its size
 * and alignment.
 */
#include <errno.h>
#include <math.h>
#include <stddef.h>
#include <string.h>

#include "axis_impl.h"
#include "wsg/proto.h"

/* A holder's struct wsg_axis_storage must take the struct: big enough and
 * aligned at least as strictly (C99 has no _Static_assert or _Alignof: an
 * array of negative size fails the build, and the offset of a member after
 * a char is its type's alignment). Growing the struct past it means
 * raising WSG_AXIS_STORAGE_WORDS. */
struct wsg_axis_align_need {
    char c;
    struct wsg_axis a;
};
struct wsg_axis_align_have {
    char c;
    struct wsg_axis_storage s;
};
typedef char wsg_axis_storage_fits
    [sizeof(struct wsg_axis) <= sizeof(struct wsg_axis_storage) ? 1 : -1];
typedef char
    wsg_axis_storage_aligned[offsetof(struct wsg_axis_align_need, a) <=
                                     offsetof(struct wsg_axis_align_have, s)
                                 ? 1
                                 : -1];

/* Widths closer than this are the same position (well below the 0.01 mm
 * change threshold of 43h). */
#define WSG_AXIS_EPS 1e-6
/* Thermal model: the drive settles towards ambient plus this many degC
 * times (F/F_nom)^2 - 1 above nominal force, so that holding with the
 * WSG 50's full overdrive force (1.5 times nominal) settles at ambient +
 * 75 degC, past the fault level, and holding at nominal heats nothing. */
#define WSG_AXIS_HEAT_GAIN 60.0
/* The temperature flags clear this much below the level that set them. */
#define WSG_AXIS_TEMP_HYSTERESIS 5.0

struct wsg_axis_model {
    const char *name;
    uint8_t type;
    double stroke, min_speed, max_speed, min_acc, max_acc;
    double min_force, nom_force, ovr_force;
};

/* WSG 50 figures from NOTES.md; the smaller models from the catalogue,
 * their overdrive force at 1.5 times nominal like the WSG 50's. */
static const struct wsg_axis_model wsg_axis_models[] = {
    {"wsg50", 1, 110.0, 5.0, 420.0, 100.0, 5000.0, 5.0, 80.0, 120.0},
    {"wsg50-210", 1, 210.0, 5.0, 420.0, 100.0, 5000.0, 5.0, 80.0, 120.0},
    {"wsg32", 2, 68.0, 5.0, 400.0, 100.0, 5000.0, 5.0, 50.0, 75.0},
    {"wsg25", 5, 64.0, 5.0, 250.0, 100.0, 5000.0, 5.0, 20.0, 30.0},
};

static double wsg_clamp(double v, double lo, double hi)
{
    return v < lo ? lo : v > hi ? hi : v;
}

static double wsg_axis_sign(double v)
{
    return v < 0 ? -1.0 : v > 0 ? 1.0 : 0.0;
}

int wsg_axis_config_init(struct wsg_axis_config *cfg, const char *model)
{
    const struct wsg_axis_model *m = NULL;
    size_t i;

    if (!model)
        model = "wsg50";
    for (i = 0; i < sizeof wsg_axis_models / sizeof wsg_axis_models[0]; i++)
        if (strcmp(wsg_axis_models[i].name, model) == 0)
            m = &wsg_axis_models[i];
    if (!m)
        return -EINVAL;
    memset(cfg, 0, sizeof *cfg);
    cfg->type = m->type;
    cfg->stroke = m->stroke;
    cfg->min_speed = m->min_speed;
    cfg->max_speed = m->max_speed;
    cfg->min_acc = m->min_acc;
    cfg->max_acc = m->max_acc;
    cfg->min_force = m->min_force;
    cfg->nom_force = m->nom_force;
    cfg->ovr_force = m->ovr_force;
    cfg->default_acc = 150.0;
    cfg->default_force = m->nom_force / 2.0;
    cfg->homing_speed = 100.0;
    cfg->clamp_travel = 10.0;
    cfg->width_tolerance = 10.0;
    cfg->part_stiffness = 50.0;
    cfg->homing_dir = WSG_HOME_POSITIVE;
    cfg->force_sensor = 0;
    cfg->step_us = 1000;
    cfg->ambient = 25.0;
    cfg->temp_warning = 65.0;
    cfg->temp_fault = 75.0;
    cfg->heat_tau = 60.0;
    return 0;
}

struct wsg_axis_range wsg_axis_config_range(const struct wsg_axis_config *cfg,
                                            enum wsg_axis_setting s)
{
    struct wsg_axis_range r = {0.0, cfg->stroke};

    switch (s) {
    case WSG_AXIS_ACCELERATION:
        r.min = cfg->min_acc;
        r.max = cfg->max_acc;
        break;
    case WSG_AXIS_FORCE_LIMIT:
        r.min = cfg->min_force;
        r.max = cfg->nom_force; /* overdrive is a session's, not a default */
        break;
    case WSG_AXIS_CLAMP_TRAVEL:
    case WSG_AXIS_WIDTH_TOLERANCE:
    case WSG_AXIS_WIDTH:
        break;
    }
    return r;
}

int wsg_axis_config_set(struct wsg_axis_config *cfg, enum wsg_axis_setting s,
                        double v, struct wsg_axis_range *valid)
{
    struct wsg_axis_range r = wsg_axis_config_range(cfg, s);

    if (valid)
        *valid = r;
    /* An error, not a clamp: a value the gripper would not take is a
     * mistake in the setup. Written so that NaN fails too. */
    if (!(v >= r.min && v <= r.max))
        return -ERANGE;
    switch (s) {
    case WSG_AXIS_ACCELERATION:
        cfg->default_acc = v;
        break;
    case WSG_AXIS_FORCE_LIMIT:
        cfg->default_force = v;
        break;
    case WSG_AXIS_CLAMP_TRAVEL:
        cfg->clamp_travel = v;
        break;
    case WSG_AXIS_WIDTH_TOLERANCE:
        cfg->width_tolerance = v;
        break;
    case WSG_AXIS_WIDTH:
        break;
    }
    return 0;
}

double wsg_axis_config_get(const struct wsg_axis_config *cfg,
                           enum wsg_axis_setting s)
{
    switch (s) {
    case WSG_AXIS_ACCELERATION:
        return cfg->default_acc;
    case WSG_AXIS_FORCE_LIMIT:
        return cfg->default_force;
    case WSG_AXIS_CLAMP_TRAVEL:
        return cfg->clamp_travel;
    case WSG_AXIS_WIDTH_TOLERANCE:
        return cfg->width_tolerance;
    case WSG_AXIS_WIDTH:
        break;
    }
    return 0.0;
}

/* A width clamped into the stroke, as motion commands take widths. */
static double wsg_axis_clamp_width(const struct wsg_axis *ax, double width)
{
    struct wsg_axis_range r = wsg_axis_config_range(&ax->cfg, WSG_AXIS_WIDTH);

    return wsg_clamp(width, r.min, r.max);
}

static void wsg_profile_init(struct wsg_profile *pr, double from, double to,
                             double vmax, double acc, int decel)
{
    double d = fabs(to - from);

    pr->start = from;
    pr->dist = d;
    pr->dir = to >= from ? 1.0 : -1.0;
    pr->acc = acc;
    pr->decel = decel;
    pr->t = 0.0;
    if (decel) {
        if (d * acc >= vmax * vmax) {
            pr->t_acc = vmax / acc;
            pr->t_total = 2.0 * pr->t_acc + (d - vmax * vmax / acc) / vmax;
        } else { /* triangular: never reaches vmax */
            pr->t_acc = sqrt(d / acc);
            vmax = acc * pr->t_acc;
            pr->t_total = 2.0 * pr->t_acc;
        }
    } else { /* into an end stop at speed */
        double d_acc = vmax * vmax / (2.0 * acc);
        if (d >= d_acc) {
            pr->t_acc = vmax / acc;
            pr->t_total = pr->t_acc + (d - d_acc) / vmax;
        } else {
            pr->t_acc = sqrt(2.0 * d / acc);
            vmax = acc * pr->t_acc;
            pr->t_total = pr->t_acc;
        }
    }
    pr->vmax = vmax;
}

/* Position and signed speed at pr->t; returns 1 when the profile is over. */
static int wsg_profile_eval(const struct wsg_profile *pr, double *x, double *v)
{
    double t = pr->t, s, speed;

    if (t >= pr->t_total) {
        *x = pr->start + pr->dir * pr->dist;
        *v = 0.0;
        return 1;
    }
    if (t < pr->t_acc) {
        s = 0.5 * pr->acc * t * t;
        speed = pr->acc * t;
    } else if (!pr->decel || t < pr->t_total - pr->t_acc) {
        s = 0.5 * pr->acc * pr->t_acc * pr->t_acc + pr->vmax * (t - pr->t_acc);
        speed = pr->vmax;
    } else {
        double td = pr->t_total - t;
        s = pr->dist - 0.5 * pr->acc * td * td;
        speed = pr->acc * td;
    }
    *x = pr->start + pr->dir * s;
    *v = pr->dir * speed;
    return 0;
}

static void wsg_axis_done(struct wsg_axis *ax, const struct wsg_motion *m,
                          uint16_t status)
{
    if (m->kind == WSG_MOTION_SNAP || m->kind == WSG_MOTION_NONE)
        return;
    if (ax->on_done)
        ax->on_done(ax->done_ctx, m->tag, m->cmd_id, status);
}

void wsg_axis_init(struct wsg_axis *ax, const struct wsg_axis_config *cfg,
                   wsg_axis_done_fn on_done, void *ctx)
{
    memset(ax, 0, sizeof *ax);
    ax->cfg = *cfg;
    ax->on_done = on_done;
    ax->done_ctx = ctx;
    /* Power-up finger position is wherever they were left: mid-stroke. */
    ax->width = cfg->stroke / 2.0;
    wsg_plant_builtin_init(&ax->builtin, cfg->stroke, cfg->part_stiffness);
    ax->temperature = cfg->ambient;
    wsg_axis_reset(ax);
}

void wsg_axis_on_event(struct wsg_axis *ax, wsg_axis_event_fn fn, void *ctx)
{
    ax->on_event = fn;
    ax->event_ctx = ctx;
}

static void wsg_axis_event(struct wsg_axis *ax, enum wsg_axis_event ev)
{
    if (ax->on_event)
        ax->on_event(ax->event_ctx, ev);
}

void wsg_axis_reset(struct wsg_axis *ax)
{
    /* A power cycle ends what runs, and whoever waits for it hears so. */
    wsg_axis_done(ax, &ax->motion, WSG_E_CMD_ABORTED);
    wsg_axis_done(ax, &ax->req_motion, WSG_E_CMD_ABORTED);
    wsg_axis_done(ax, &ax->req_cancelled, WSG_E_CMD_ABORTED);
    ax->speed = 0.0;
    ax->force = 0.0;
    ax->referenced = 0;
    ax->fast_stop = 0;
    ax->event_flags = 0;
    ax->grasp_state = WSG_GS_IDLE;
    memset(&ax->stats, 0, sizeof ax->stats);
    memset(&ax->motion, 0, sizeof ax->motion);
    ax->clamping = 0;
    ax->push_dir = 0;
    ax->acc = ax->cfg.default_acc;
    ax->force_limit = ax->cfg.default_force;
    ax->overdrive = 0;
    ax->soft_limits = 0;
    ax->faults_seen = 0; /* faults still present apply again */
    ax->req_fast_stop = ax->req_ack = ax->req_stop = 0;
    memset(&ax->req_motion, 0, sizeof ax->req_motion);
    memset(&ax->req_cancelled, 0, sizeof ax->req_cancelled);
}

/* A position in the world (part, obstacle, end stops) as the gripper
 * sees it: its reference is off by ref_offset after a homing that blocked
 * on something before the end stop (3.2.1 warns of that). */
static double wsg_axis_rep(const struct wsg_axis *ax, double phys)
{
    return phys + ax->ref_offset;
}

/* The mechanical end stop in direction dir, where the gripper sees it:
 * the firmware knows its stroke; the plant has the stop itself. */
static double wsg_axis_end_stop(const struct wsg_axis *ax, double dir)
{
    return wsg_axis_rep(ax, dir < 0 ? 0.0 : ax->cfg.stroke);
}

/* The plant the drive moves: an attached one, or the built-in one held in
 * the struct (so that a copy of the struct still finds its own). */
static struct wsg_plant *wsg_axis_plant_of(struct wsg_axis *ax)
{
    return ax->plant ? ax->plant : &ax->builtin.base;
}

static const struct wsg_plant *wsg_axis_plant_c(const struct wsg_axis *ax)
{
    return ax->plant ? ax->plant : &ax->builtin.base;
}

/* A drive command of mode m, pushing in dir with force f, from where the
 * fingers are. */
static struct wsg_drive wsg_axis_drive(const struct wsg_axis *ax,
                                       enum wsg_drive_mode m, double dir,
                                       double f)
{
    struct wsg_drive d;

    memset(&d, 0, sizeof d);
    d.mode = m;
    d.x = ax->width;
    d.dir = dir;
    d.force = f;
    d.limit = ax->force_limit;
    d.width = ax->width;
    d.grip = ax->force;
    d.offset = ax->ref_offset;
    return d;
}

/* What the plant says of the fingers under drive d, now. */
static struct wsg_plant_fingers wsg_axis_sense(const struct wsg_axis *ax,
                                               const struct wsg_drive *d)
{
    const struct wsg_plant *p = wsg_axis_plant_c(ax);
    struct wsg_plant_fingers o;

    p->ops->sense(p, d, &o);
    return o;
}

/* Command the drive for one step of dt and read the fingers back. */
static struct wsg_plant_fingers
wsg_axis_drive_step(struct wsg_axis *ax, const struct wsg_drive *d, double dt)
{
    struct wsg_plant *p = wsg_axis_plant_of(ax);

    p->ops->step(p, d, dt);
    return wsg_axis_sense(ax, d);
}

/* The force on fingers standing free: what the part presses with. */
static double wsg_axis_free_force(const struct wsg_axis *ax)
{
    struct wsg_drive d = wsg_axis_drive(ax, WSG_DRIVE_OFF, 0.0, 0.0);

    return wsg_axis_sense(ax, &d).force;
}

static void wsg_axis_start(struct wsg_axis *ax, const struct wsg_motion *m)
{
    int decel = m->kind != WSG_MOTION_HOMING;

    /* A motion that replaces a running one (a script's mc.move over its
     * own movement; the dispatcher refuses that with E_ALREADY_RUNNING)
     * must not drop the old one's owner without its final result. */
    wsg_axis_done(ax, &ax->motion, WSG_E_CMD_ABORTED);
    ax->motion = *m;
    ax->clamping = 0;
    ax->push_dir = 0;
    if (m->kind == WSG_MOTION_SPEED) {
        /* The velocity controller takes over from whatever moved the
         * fingers, at their velocity, against what they touch. */
        ax->force = wsg_axis_free_force(ax);
    } else {
        /* A profile starts from rest: a motion that replaces a moving one
         * (a script's, over speed mode) starts where the fingers are. */
        wsg_profile_init(&ax->motion.prof, ax->width, m->target, m->speed,
                         ax->acc, decel);
        /* A grasp that starts where its target is (at an end stop) still
         * has a side: it pushes towards its nominal width, closing if that
         * is not wider than the fingers (as wsg_axis_request_grasp
         * chose). */
        if (m->kind == WSG_MOTION_GRASP && ax->motion.prof.dist < WSG_AXIS_EPS)
            ax->motion.prof.dir = m->nominal <= ax->width ? -1.0 : 1.0;
        ax->speed = 0.0;
        ax->force = 0.0;
    }
    if (m->kind == WSG_MOTION_SNAP)
        return;
    ax->event_flags &= ~(WSG_SF_AXIS_STOPPED | WSG_SF_TARGET_POS_REACHED |
                         WSG_SF_BLOCKED_MINUS | WSG_SF_BLOCKED_PLUS);
    switch (m->own ? WSG_MOTION_SPEED : m->kind) {
    case WSG_MOTION_SPEED: /* the controller's own: not a grasping state */
        break;
    case WSG_MOTION_MOVE:
        ax->grasp_state = WSG_GS_POSITIONING;
        break;
    case WSG_MOTION_GRASP:
        ax->grasp_state = WSG_GS_GRASPING;
        break;
    case WSG_MOTION_RELEASE:
        ax->grasp_state = WSG_GS_RELEASING;
        break;
    default:
        ax->grasp_state = WSG_GS_IDLE;
        break;
    }
}

/* Motor off: the motion ends where the fingers are. */
static void wsg_axis_halt(struct wsg_axis *ax)
{
    memset(&ax->motion, 0, sizeof ax->motion);
    ax->speed = 0.0;
    ax->force = 0.0;
    ax->clamping = 0;
    ax->push_dir = 0;
}

static void wsg_axis_clamp(struct wsg_axis *ax, double f, double target,
                           double speed, double dir)
{
    ax->clamping = 1;
    ax->clamp_force = f;
    ax->clamp_target = target;
    ax->clamp_speed = speed;
    ax->clamp_dir = dir < 0 ? -1 : 1;
    ax->force = f;
    ax->speed = 0.0;
    ax->event_flags |= dir < 0 ? WSG_SF_BLOCKED_MINUS : WSG_SF_BLOCKED_PLUS;
}

/* Blocked with the motor turned off: no force, the block is flagged. */
static void wsg_axis_block_release(struct wsg_axis *ax, double dir)
{
    ax->force = 0.0;
    ax->event_flags |= dir < 0 ? WSG_SF_BLOCKED_MINUS : WSG_SF_BLOCKED_PLUS;
}

/* The motion m blocked at the current width. */
static void wsg_axis_blocked(struct wsg_axis *ax)
{
    struct wsg_motion m = ax->motion;
    double dir = m.prof.dir, f = ax->force_limit;

    memset(&ax->motion, 0, sizeof ax->motion);
    ax->speed = 0.0;
    switch (m.kind) {
    case WSG_MOTION_HOMING: {
        /* The blocking position is the new origin (3.2.1): right at the
         * end stop, wrong by as much as an obstacle stood before it. */
        double home = m.nominal > 0 ? ax->cfg.stroke : 0.0;
        ax->ref_offset += home - ax->width;
        ax->width = home;
        ax->referenced = 1;
        ax->force = 0.0;
        ax->grasp_state = WSG_GS_IDLE;
        wsg_axis_done(ax, &m, WSG_E_SUCCESS);
        break;
    }
    case WSG_MOTION_MOVE:
        if (!m.own)
            ax->grasp_state = WSG_GS_IDLE;
        if (m.move_flags & WSG_MOVE_STOP_ON_BLOCK)
            wsg_axis_block_release(ax, dir);
        else
            wsg_axis_clamp(ax, f, m.target, m.speed, dir);
        wsg_axis_done(ax, &m, WSG_E_AXIS_BLOCKED);
        break;
    case WSG_MOTION_GRASP:
        ax->stats.total++;
        if (dir < 0 ? ax->width <= m.nominal + m.tolerance
                    : ax->width >= m.nominal - m.tolerance) {
            ax->grasp_state = WSG_GS_HOLDING;
            ax->event_flags |= WSG_SF_TARGET_POS_REACHED;
            wsg_axis_clamp(ax, f, m.target, m.speed, dir);
            wsg_axis_done(ax, &m, WSG_E_SUCCESS);
        } else { /* blocked before the part's window: not the part */
            ax->stats.no_part++;
            ax->grasp_state = WSG_GS_NO_PART;
            ax->grasp_collided = 1;
            wsg_axis_block_release(ax, dir);
            wsg_axis_done(ax, &m, WSG_E_CMD_FAILED);
        }
        break;
    case WSG_MOTION_RELEASE:
        ax->grasp_state = WSG_GS_IDLE;
        wsg_axis_block_release(ax, dir);
        wsg_axis_done(ax, &m, WSG_E_AXIS_BLOCKED);
        break;
    case WSG_MOTION_SNAP:
        /* A clamp found a block again: clamp silently. */
        wsg_axis_clamp(ax, ax->clamp_force, m.target, m.speed, dir);
        break;
    default:
        break;
    }
}

/* The motion reached the end of its profile unblocked. */
static void wsg_axis_arrived(struct wsg_axis *ax)
{
    struct wsg_motion m = ax->motion;

    wsg_axis_halt(ax);
    switch (m.kind) {
    case WSG_MOTION_MOVE:
    case WSG_MOTION_RELEASE:
        if (!m.own)
            ax->grasp_state = WSG_GS_IDLE;
        ax->event_flags |= WSG_SF_TARGET_POS_REACHED;
        wsg_axis_done(ax, &m, WSG_E_SUCCESS);
        break;
    case WSG_MOTION_GRASP:
        /* Fell through the clamping travel: no part (3.2.6). */
        ax->stats.total++;
        ax->stats.no_part++;
        ax->grasp_state = WSG_GS_NO_PART;
        ax->grasp_collided = 0;
        wsg_axis_done(ax, &m, WSG_E_CMD_FAILED);
        break;
    default:
        break;
    }
}

/* End the running motion where the fingers are, motor off, and give its
 * owner the final result. */
static void wsg_axis_abort(struct wsg_axis *ax, uint16_t status)
{
    struct wsg_motion m = ax->motion;

    wsg_axis_halt(ax);
    wsg_axis_done(ax, &m, status);
}

/* Stop the fastest way, motor off; only an acknowledge clears it. */
static void wsg_axis_fast_stop(struct wsg_axis *ax)
{
    ax->fast_stop = 1;
    ax->grasp_state = WSG_GS_ERROR;
    wsg_axis_abort(ax, WSG_E_CMD_ABORTED);
}

/* A new set speed over speed mode: no restart. The velocity ramps on from
 * where it is, and a push into the same contact goes on (blocked stays
 * blocked, which a script's PD loop reads after every mc.speed). The
 * newest request owns it; an earlier owner of another tag hears
 * E_CMD_ABORTED, as for any motion replaced. */
static void wsg_axis_speed_change(struct wsg_axis *ax,
                                  const struct wsg_motion *m)
{
    if (m->tag != ax->motion.tag)
        wsg_axis_done(ax, &ax->motion, WSG_E_CMD_ABORTED);
    ax->motion.tag = m->tag;
    ax->motion.speed = m->speed;
}

static void wsg_axis_apply_requests(struct wsg_axis *ax)
{
    if (ax->req_cancelled.kind != WSG_MOTION_NONE) {
        wsg_axis_done(ax, &ax->req_cancelled, WSG_E_CMD_ABORTED);
        memset(&ax->req_cancelled, 0, sizeof ax->req_cancelled);
    }
    if (ax->req_fast_stop) {
        ax->req_fast_stop = 0;
        wsg_axis_fast_stop(ax);
    }
    if (ax->req_ack) {
        ax->req_ack = 0;
        if (ax->fast_stop) {
            ax->fast_stop = 0;
            ax->grasp_state = WSG_GS_IDLE;
        }
    }
    if (ax->req_stop) {
        ax->req_stop = 0;
        ax->event_flags |= WSG_SF_AXIS_STOPPED;
        if (ax->grasp_state != WSG_GS_ERROR)
            ax->grasp_state = WSG_GS_IDLE;
        wsg_axis_abort(ax, WSG_E_CMD_ABORTED);
    }
    if (ax->req_motion.kind != WSG_MOTION_NONE) {
        struct wsg_motion m = ax->req_motion;
        memset(&ax->req_motion, 0, sizeof ax->req_motion);
        if (m.kind == WSG_MOTION_SPEED && ax->motion.kind == WSG_MOTION_SPEED)
            wsg_axis_speed_change(ax, &m);
        else
            wsg_axis_start(ax, &m);
    }
}

/* A soft limit stops the motion the fastest way: FAST STOP, and the
 * motion ends E_RANGE_ERROR (3.2.2). */
static void wsg_axis_soft_limit_stop(struct wsg_axis *ax)
{
    ax->fast_stop = 1;
    ax->grasp_state = WSG_GS_ERROR;
    wsg_axis_event(ax, WSG_AXIS_FAST_STOP_SOFT_LIMIT);
    wsg_axis_abort(ax, WSG_E_RANGE_ERROR);
}

/* Entering the area beyond a soft limit: FAST STOP at the limit (3.3.5). */
static int wsg_axis_soft_limit_hit(struct wsg_axis *ax, double x, double v)
{
    double limit;

    if (!ax->soft_limits || ax->motion.kind == WSG_MOTION_HOMING)
        return 0;
    /* Fingers already beyond a limit (set while they were there) stop
     * where they are: they may only move out of the restricted area. */
    if (v < 0 && x < ax->soft_minus - WSG_AXIS_EPS)
        limit = ax->width < ax->soft_minus ? ax->width : ax->soft_minus;
    else if (v > 0 && x > ax->soft_plus + WSG_AXIS_EPS)
        limit = ax->width > ax->soft_plus ? ax->width : ax->soft_plus;
    else
        return 0;
    ax->width = limit;
    wsg_axis_soft_limit_stop(ax);
    return 1;
}

/* A motion heading deeper into the area beyond a soft limit the fingers
 * are already in (limits set while they were there, or a clamp that snaps
 * on): stopped at once, as at the limit (3.3.5, D4/D5). */
static void wsg_axis_soft_limit_check(struct wsg_axis *ax)
{
    double dir = ax->motion.prof.dir, target = ax->motion.target;

    if (!ax->soft_limits || ax->motion.kind == WSG_MOTION_NONE ||
        ax->motion.kind == WSG_MOTION_HOMING)
        return;
    /* Speed mode heads for the end stop its set speed points to. */
    if (ax->motion.kind == WSG_MOTION_SPEED) {
        dir = wsg_axis_sign(ax->motion.speed);
        target = dir != 0.0 ? wsg_axis_end_stop(ax, dir) : ax->width;
    }
    if ((dir < 0 && ax->width < ax->soft_minus - WSG_AXIS_EPS &&
         target < ax->width - WSG_AXIS_EPS) ||
        (dir > 0 && ax->width > ax->soft_plus + WSG_AXIS_EPS &&
         target > ax->width + WSG_AXIS_EPS))
        wsg_axis_soft_limit_stop(ax);
}

/* One step of a motion with a profile: the drive follows the profile's
 * point, and the plant says whether the fingers got there. Returns 1 when
 * the plant was stepped. */
static int wsg_axis_advance(struct wsg_axis *ax, double dt)
{
    struct wsg_motion *m = &ax->motion;
    /* Homing's direction is its own: a homing that starts at its end stop
     * has a profile of length 0, with no direction to speak of. */
    double dir = m->kind == WSG_MOTION_HOMING ? m->nominal : m->prof.dir;
    double x, v;
    double f = m->kind == WSG_MOTION_SNAP ? ax->clamp_force : ax->force_limit;
    struct wsg_drive d;
    struct wsg_plant_fingers o;
    int over;

    m->prof.t += dt;
    over = wsg_profile_eval(&m->prof, &x, &v);
    if (wsg_axis_soft_limit_hit(ax, x, v))
        return 0;
    /* The part, the obstacle: the first one the fingers reach blocks them
     * where the force limit is reached. The mechanical end stop is
     * homing's goal; any other motion only meets it when a wrong reference
     * put its target beyond it, or a grasp whose clamping travel reaches
     * past it (a block like any other, which the grasping window judges). */
    d = wsg_axis_drive(ax, WSG_DRIVE_MOVE, dir, f);
    d.x = x;
    d.v = v;
    d.end =
        over && (m->kind == WSG_MOTION_HOMING || m->kind == WSG_MOTION_GRASP);
    o = wsg_axis_drive_step(ax, &d, dt);
    ax->width = o.width;
    if (o.blocked) {
        ax->force = m->kind == WSG_MOTION_HOMING ? 0.0 : o.force;
        wsg_axis_blocked(ax);
        return 1;
    }
    ax->speed = o.speed;
    ax->force = o.force;
    /* Arrived when the profile is over and the fingers stand (a plant
     * with inertia lets them settle first). */
    if (over && o.speed == 0.0)
        wsg_axis_arrived(ax);
    return 1;
}

/* Where fingers that speed mode pushes in direction dir with force f
 * stand, if something holds them (*x): the plant's PUSH. */
static int wsg_axis_push_at(const struct wsg_axis *ax, double dir, double f,
                            double *x)
{
    struct wsg_drive d = wsg_axis_drive(ax, WSG_DRIVE_PUSH, dir, f);
    struct wsg_plant_fingers o;

    d.x = wsg_axis_end_stop(ax, dir);
    o = wsg_axis_sense(ax, &d);

    *x = o.width;
    return o.blocked;
}

/* Standing fingers whose set speed points into a block right at them (a
 * clamp that speed mode took over, a push resumed): they push at once, as
 * a moving one would on its next step. */
static int wsg_axis_at_block(const struct wsg_axis *ax, double dir, double f)
{
    struct wsg_drive d = wsg_axis_drive(ax, WSG_DRIVE_AT, dir, f);

    return wsg_axis_sense(ax, &d).blocked;
}

static void wsg_axis_push(struct wsg_axis *ax, double dir)
{
    ax->push_dir = dir < 0 ? -1 : 1;
    ax->speed = 0.0;
    ax->force = ax->force_limit;
    ax->event_flags |= dir < 0 ? WSG_SF_BLOCKED_MINUS : WSG_SF_BLOCKED_PLUS;
}

/* Speed mode between steps: a push follows the force limit and the world
 * (wsg_axis_push_at) and ends when the set speed turns away from its block
 * or the block goes (the fingers free, from rest); standing fingers push
 * into a block at them; standing free, they feel the part they touch. */
static void wsg_axis_speed_settle(struct wsg_axis *ax)
{
    double d = wsg_axis_sign(ax->motion.speed), f = ax->force_limit, x;

    if (ax->motion.kind != WSG_MOTION_SPEED)
        return;
    if (ax->push_dir &&
        (d != ax->push_dir || !wsg_axis_push_at(ax, d, f, &x))) {
        ax->push_dir = 0;
        ax->event_flags &= ~(WSG_SF_BLOCKED_MINUS | WSG_SF_BLOCKED_PLUS);
    }
    if (!ax->push_dir && ax->speed == 0.0 && d != 0.0 &&
        wsg_axis_at_block(ax, d, f))
        wsg_axis_push(ax, d);
    if (ax->push_dir) {
        if (!wsg_axis_push_at(ax, d, f, &x))
            x = ax->width; /* a block at them holds them, or they stand */
        if (wsg_axis_soft_limit_hit(ax, x, x - ax->width))
            return;
        ax->width = x;
        ax->force = f;
    } else if (ax->speed == 0.0) {
        ax->force = wsg_axis_free_force(ax);
    }
}

/* Speed mode in free motion: the velocity ramps to the set speed with the
 * maximum acceleration, exactly within the step (the ramp may end inside
 * it), and the fingers stop at the first block as any motion does. They
 * push into it if the set speed points there (decelerating the other way,
 * they just stand). */
static int wsg_axis_speed_advance(struct wsg_axis *ax, double dt)
{
    double v0 = ax->speed, vs = ax->motion.speed, a = ax->cfg.max_acc;
    double dv = vs - v0, v1, s, x, dir;
    struct wsg_drive d;
    struct wsg_plant_fingers o;

    if (ax->push_dir || (v0 == 0.0 && vs == 0.0))
        return 0;
    if (fabs(dv) > a * dt) {
        v1 = v0 + (dv > 0 ? a : -a) * dt;
        s = 0.5 * (v0 + v1) * dt;
    } else {
        double t1 = fabs(dv) / a;
        v1 = vs;
        s = 0.5 * (v0 + vs) * t1 + vs * (dt - t1);
    }
    ax->speed = v1;
    if (s == 0.0)
        return 0; /* turned round within the step */
    x = ax->width + s;
    dir = wsg_axis_sign(s);
    if (wsg_axis_soft_limit_hit(ax, x, s))
        return 0;
    d = wsg_axis_drive(ax, WSG_DRIVE_SPEED, dir, ax->force_limit);
    d.x = x;
    d.v = v1;
    o = wsg_axis_drive_step(ax, &d, dt);
    ax->width = o.width;
    if (!o.blocked) {
        ax->force = o.force;
        return 1;
    }
    ax->speed = 0.0;
    if (wsg_axis_sign(vs) == dir)
        wsg_axis_push(ax, dir);
    else
        ax->force = o.force;
    return 1;
}

/* Speed mode stands still and steps would change nothing: at set speed 0,
 * or pushing steadily against its block. */
static int wsg_axis_speed_steady(const struct wsg_axis *ax)
{
    double d = wsg_axis_sign(ax->motion.speed), x;

    if (ax->push_dir)
        return d == ax->push_dir &&
               wsg_axis_push_at(ax, d, ax->force_limit, &x) &&
               fabs(x - ax->width) <= WSG_AXIS_EPS &&
               ax->force == ax->force_limit;
    return ax->speed == 0.0 && d == 0.0 &&
           fabs(ax->force - wsg_axis_free_force(ax)) <= WSG_AXIS_EPS;
}

/* A clamping axis holds its block; if the block is gone the fingers snap on
 * to the target (3.2.2), and a held part is lost (3.4.2). */
static void wsg_axis_hold(struct wsg_axis *ax)
{
    struct wsg_motion snap;
    struct wsg_drive d =
        wsg_axis_drive(ax, WSG_DRIVE_CLAMP, ax->clamp_dir, ax->clamp_force);
    struct wsg_plant_fingers o;

    d.x = ax->clamp_target;
    o = wsg_axis_sense(ax, &d);
    if (o.blocked) {
        ax->width = o.width;
        ax->force = o.force; /* the built-in plant's: the clamp's force */
        return;
    }
    if (ax->grasp_state == WSG_GS_HOLDING) {
        ax->grasp_state = WSG_GS_PART_LOST;
        ax->stats.lost_part++;
    }
    ax->event_flags &= ~(WSG_SF_BLOCKED_MINUS | WSG_SF_BLOCKED_PLUS);
    memset(&snap, 0, sizeof snap);
    snap.kind = WSG_MOTION_SNAP;
    snap.target = ax->clamp_target;
    snap.speed = ax->clamp_speed;
    wsg_axis_start(ax, &snap);
    ax->clamping = 0;
}

/* Faults newly present have their consequences (Appendix B): a power or
 * current fault is a severe error, a FAST STOP to be acknowledged; a
 * temperature fault turns the power electronics off: the motion ends, the
 * grip goes, and movement stays refused until the fault clears. */
static void wsg_axis_apply_faults(struct wsg_axis *ax)
{
    uint32_t all = ax->faults | ax->thermal_faults;
    uint32_t fresh = all & ~ax->faults_seen;

    ax->faults_seen = all;
    if (fresh & (WSG_SF_POWER_FAULT | WSG_SF_CURR_FAULT)) {
        wsg_axis_event(ax, WSG_AXIS_FAST_STOP_FAULT);
        wsg_axis_fast_stop(ax);
    } else if (fresh & WSG_SF_TEMP_FAULT) {
        ax->grasp_state = WSG_GS_ERROR;
        wsg_axis_abort(ax, WSG_E_CMD_ABORTED);
    }
}

/* Where the drive's temperature settles at the present force. */
static double wsg_axis_heat_target(const struct wsg_axis *ax)
{
    double r = ax->force / ax->cfg.nom_force;

    return ax->cfg.ambient +
           (r > 1.0 ? WSG_AXIS_HEAT_GAIN * (r * r - 1.0) : 0.0);
}

static void wsg_axis_thermal(struct wsg_axis *ax, double dt)
{
    double t;
    uint32_t f = ax->thermal_faults;

    ax->temperature +=
        (wsg_axis_heat_target(ax) - ax->temperature) * (dt / ax->cfg.heat_tau);
    t = ax->temperature;
    if (t >= ax->cfg.temp_warning)
        f |= WSG_SF_TEMP_WARNING;
    else if (t < ax->cfg.temp_warning - WSG_AXIS_TEMP_HYSTERESIS)
        f &= ~(uint32_t)WSG_SF_TEMP_WARNING;
    if (t >= ax->cfg.temp_fault)
        f |= WSG_SF_TEMP_FAULT;
    else if (t < ax->cfg.temp_fault - WSG_AXIS_TEMP_HYSTERESIS)
        f &= ~(uint32_t)WSG_SF_TEMP_FAULT;
    ax->thermal_faults = f;
}

/* Out of overdrive, the drive cannot push harder than the nominal force
 * (3.3.8, D8): a clamp that holds with more drops to it at once, and a
 * part squeezed by it springs back to where the nominal force holds it. */
static void wsg_axis_limit_clamp(struct wsg_axis *ax)
{
    double old = ax->clamp_force, f = ax->cfg.nom_force;
    struct wsg_drive d;

    if (!ax->clamping || ax->overdrive || old <= f)
        return;
    d = wsg_axis_drive(ax, WSG_DRIVE_RELAX, ax->clamp_dir, f);
    d.force_was = old;
    ax->width = wsg_axis_sense(ax, &d).width;
    ax->clamp_force = f;
    ax->force = f;
}

void wsg_axis_settle(struct wsg_axis *ax)
{
    wsg_axis_apply_requests(ax);
    wsg_axis_apply_faults(ax);
    wsg_axis_limit_clamp(ax);
    /* The world may have changed under a clamp (a part taken away, an
     * obstacle removed): lost, or snapping on, from now. */
    if (ax->motion.kind == WSG_MOTION_NONE && ax->clamping)
        wsg_axis_hold(ax);
    wsg_axis_speed_settle(ax);
    wsg_axis_soft_limit_check(ax);
}

/* A step of the plant with the fingers standing: a clamp holds towards
 * its target with its force, speed mode pushes with the force limit, or
 * the motor is off. */
static void wsg_axis_hold_step(struct wsg_axis *ax, double dt)
{
    struct wsg_plant *p = wsg_axis_plant_of(ax);
    struct wsg_drive d = wsg_axis_drive(ax, WSG_DRIVE_OFF, 0.0, 0.0);

    if (ax->clamping) {
        d = wsg_axis_drive(ax, WSG_DRIVE_CLAMP, ax->clamp_dir,
                           ax->clamp_force);
        d.x = ax->clamp_target;
    } else if (ax->motion.kind == WSG_MOTION_SPEED && ax->push_dir) {
        d = wsg_axis_drive(ax, WSG_DRIVE_PUSH, ax->push_dir, ax->force_limit);
        d.x = wsg_axis_end_stop(ax, ax->push_dir);
    }
    p->ops->step(p, &d, dt);
}

void wsg_axis_step(struct wsg_axis *ax)
{
    double dt = ax->cfg.step_us * 1e-6;

    int stepped = 0;

    ax->time_us += ax->cfg.step_us;
    wsg_axis_settle(ax);
    if (ax->motion.kind == WSG_MOTION_SPEED)
        stepped = wsg_axis_speed_advance(ax, dt);
    else if (ax->motion.kind != WSG_MOTION_NONE)
        stepped = wsg_axis_advance(ax, dt);
    /* The world moves on while the fingers stand (a plant with physics):
     * the drive holds a clamp or a push, or is off. One plant step each
     * model step, whichever path took it. */
    if (!stepped)
        wsg_axis_hold_step(ax, dt);
    wsg_axis_thermal(ax, dt);
}

int wsg_axis_idle(const struct wsg_axis *ax)
{
    struct wsg_drive d;
    struct wsg_plant_fingers o;

    if (ax->req_fast_stop || ax->req_ack || ax->req_stop ||
        ax->req_motion.kind || ax->req_cancelled.kind)
        return 0;
    if (ax->motion.kind == WSG_MOTION_SPEED
            ? !wsg_axis_speed_steady(ax)
            : ax->motion.kind != WSG_MOTION_NONE)
        return 0;
    /* A plant with physics moves on its own: never idle. */
    if (ax->plant)
        return 0;
    if (ax->clamping) {
        d = wsg_axis_drive(ax, WSG_DRIVE_CLAMP, ax->clamp_dir,
                           ax->clamp_force);
        d.x = ax->clamp_target;
        o = wsg_axis_sense(ax, &d);
        if (!o.blocked || fabs(o.width - ax->width) > WSG_AXIS_EPS)
            return 0;
    }
    /* Faults to apply, a drive still warming or cooling. */
    if ((ax->faults | ax->thermal_faults) != ax->faults_seen ||
        fabs(wsg_axis_heat_target(ax) - ax->temperature) > 0.01)
        return 0;
    return 1;
}

uint32_t wsg_axis_flags(const struct wsg_axis *ax)
{
    uint32_t f = ax->event_flags | ax->faults | ax->thermal_faults;

    if (ax->referenced)
        f |= WSG_SF_REFERENCED;
    /* Speed mode drives the fingers unless they stand at set speed 0 or
     * are pushed against a block. */
    if (ax->motion.kind != WSG_MOTION_NONE &&
        !(ax->motion.kind == WSG_MOTION_SPEED &&
          (ax->push_dir || (ax->speed == 0.0 && ax->motion.speed == 0.0))))
        f |= WSG_SF_MOVING;
    if (ax->soft_limits && ax->width <= ax->soft_minus + WSG_AXIS_EPS)
        f |= WSG_SF_SOFT_LIMIT_MINUS;
    if (ax->soft_limits && ax->width >= ax->soft_plus - WSG_AXIS_EPS)
        f |= WSG_SF_SOFT_LIMIT_PLUS;
    if (ax->overdrive)
        f |= WSG_SF_OVERDRIVE_MODE;
    if (ax->cfg.force_sensor && (ax->grasp_state == WSG_GS_GRASPING ||
                                 ax->grasp_state == WSG_GS_HOLDING))
        f |= WSG_SF_FORCECNTL_MODE;
    /* As the commands see it: an acknowledge or a FAST STOP recorded but
     * not yet settled already counts (the dispatcher settles after every
     * command; a caller driving the model directly may not). */
    if (wsg_axis_fast_stopped(ax))
        f |= WSG_SF_FAST_STOP;
    return f;
}

int wsg_axis_fast_stopped(const struct wsg_axis *ax)
{
    return ax->req_fast_stop || (ax->fast_stop && !ax->req_ack);
}

int wsg_axis_busy(const struct wsg_axis *ax)
{
    if (ax->req_motion.kind != WSG_MOTION_NONE)
        return 1;
    /* A request cancelled before it started owes its E_CMD_ABORTED at the
     * next step, and there is one slot for it: a second request now could
     * be cancelled too and overwrite it, losing a final result. */
    if (ax->req_cancelled.kind != WSG_MOTION_NONE)
        return 1;
    if (ax->req_stop || ax->req_fast_stop)
        return 0;
    return ax->motion.kind != WSG_MOTION_NONE;
}

const struct wsg_axis_config *wsg_axis_cfg(const struct wsg_axis *ax)
{
    return &ax->cfg;
}

uint64_t wsg_axis_time(const struct wsg_axis *ax)
{
    return ax->time_us;
}

double wsg_axis_width(const struct wsg_axis *ax)
{
    return ax->width;
}

double wsg_axis_speed(const struct wsg_axis *ax)
{
    return ax->speed;
}

double wsg_axis_force(const struct wsg_axis *ax)
{
    return ax->force;
}

double wsg_axis_temperature(const struct wsg_axis *ax)
{
    return ax->temperature;
}

enum wsg_grasp_state wsg_axis_grasp_state(const struct wsg_axis *ax)
{
    return ax->grasp_state;
}

struct wsg_grasp_stats wsg_axis_stats(const struct wsg_axis *ax)
{
    return ax->stats;
}

uint32_t wsg_axis_faults(const struct wsg_axis *ax)
{
    return ax->faults | ax->thermal_faults;
}

int wsg_axis_referenced(const struct wsg_axis *ax)
{
    return ax->referenced;
}

int wsg_axis_speed_mode(const struct wsg_axis *ax)
{
    return ax->motion.kind == WSG_MOTION_SPEED;
}

int wsg_axis_pressing(const struct wsg_axis *ax)
{
    return ax->clamping ||
           (ax->motion.kind == WSG_MOTION_SPEED && ax->push_dir != 0);
}

double wsg_axis_acc(const struct wsg_axis *ax)
{
    return ax->acc;
}

double wsg_axis_force_limit(const struct wsg_axis *ax)
{
    return ax->force_limit;
}

int wsg_axis_soft_limits(const struct wsg_axis *ax, double *minus,
                         double *plus)
{
    if (!ax->soft_limits)
        return 0;
    *minus = ax->soft_minus;
    *plus = ax->soft_plus;
    return 1;
}

int wsg_axis_part(const struct wsg_axis *ax, double *width, double *stiffness)
{
    if (!ax->builtin.part)
        return 0;
    *width = ax->builtin.part_width;
    *stiffness = ax->builtin.part_stiffness;
    return 1;
}

int wsg_axis_contact(const struct wsg_axis *ax, int finger,
                     struct wsg_contact *c)
{
    const struct wsg_plant *p;
    struct wsg_drive d;

    if (finger != 0 && finger != 1)
        return -EINVAL;
    /* The plant knows the pads: the built-in one's part presses on both
     * with the grip force, a physics plant's contacts where they are. */
    d = wsg_axis_drive(ax, WSG_DRIVE_OFF, 0.0, 0.0);
    p = wsg_axis_plant_c(ax);
    p->ops->contact(p, &d, finger, c);
    return 0;
}

int wsg_axis_grasp_collided(const struct wsg_axis *ax)
{
    return ax->grasp_collided;
}

int wsg_axis_obstacle(const struct wsg_axis *ax, double *width)
{
    if (!ax->builtin.obstacle)
        return 0;
    *width = ax->builtin.obstacle_width;
    return 1;
}

/* A request answered E_CMD_PENDING; the next step starts it. */
static uint16_t wsg_axis_request(struct wsg_axis *ax, enum wsg_motion_kind k,
                                 uint8_t id, double target, double speed,
                                 uint32_t tag)
{
    struct wsg_motion *m = &ax->req_motion;

    memset(m, 0, sizeof *m);
    m->kind = k;
    m->cmd_id = id;
    m->tag = tag;
    m->target = target;
    m->speed = speed;
    return WSG_E_CMD_PENDING;
}

static int wsg_axis_outside_soft_limits(const struct wsg_axis *ax, double w)
{
    return ax->soft_limits && (w < ax->soft_minus - WSG_AXIS_EPS ||
                               w > ax->soft_plus + WSG_AXIS_EPS);
}

uint16_t wsg_axis_request_homing(struct wsg_axis *ax, int dir, uint32_t tag)
{
    double target;
    uint16_t st;

    if (dir == WSG_HOME_DEFAULT)
        dir = ax->cfg.homing_dir;
    if (dir != WSG_HOME_POSITIVE && dir != WSG_HOME_NEGATIVE)
        return WSG_E_INVALID_PARAMETER;
    target = wsg_axis_end_stop(ax, dir == WSG_HOME_POSITIVE ? 1.0 : -1.0);
    st = wsg_axis_request(ax, WSG_MOTION_HOMING, WSG_CMD_HOMING, target,
                          ax->cfg.homing_speed, tag);
    ax->req_motion.nominal = dir == WSG_HOME_POSITIVE ? 1.0 : -1.0;
    return st;
}

uint16_t wsg_axis_request_move(struct wsg_axis *ax, uint8_t flags,
                               double width, double speed, uint32_t tag)
{
    uint16_t st;

    if (isnan(width) || isnan(speed))
        return WSG_E_INVALID_PARAMETER;
    if (flags & WSG_MOVE_RELATIVE)
        width += ax->width;
    width = wsg_axis_clamp_width(ax, width);
    if (wsg_axis_outside_soft_limits(ax, width))
        return WSG_E_RANGE_ERROR;
    speed = wsg_clamp(speed, ax->cfg.min_speed, ax->cfg.max_speed);
    st = wsg_axis_request(ax, WSG_MOTION_MOVE, WSG_CMD_PREPOSITION, width,
                          speed, tag);
    ax->req_motion.move_flags = flags;
    return st;
}

/* A window value: below 0 the configuration's, else clamped into the
 * range the configuration's own takes (wsg_axis_config_range). */
static double wsg_axis_window_value(const struct wsg_axis *ax, double v,
                                    enum wsg_axis_setting s, double cfg_value)
{
    struct wsg_axis_range r = wsg_axis_config_range(&ax->cfg, s);

    return v < 0 ? cfg_value : wsg_clamp(v, r.min, r.max);
}

uint16_t wsg_axis_request_grasp_in(struct wsg_axis *ax, double width,
                                   double speed,
                                   const struct wsg_grasp_window *w,
                                   uint32_t tag)
{
    double target, travel = ax->cfg.clamp_travel;
    double tolerance = ax->cfg.width_tolerance;
    uint16_t st;

    if (isnan(width) || isnan(speed))
        return WSG_E_INVALID_PARAMETER;
    if (w) {
        if (isnan(w->travel) || isnan(w->tolerance))
            return WSG_E_INVALID_PARAMETER;
        travel = wsg_axis_window_value(ax, w->travel, WSG_AXIS_CLAMP_TRAVEL,
                                       travel);
        tolerance = wsg_axis_window_value(ax, w->tolerance,
                                          WSG_AXIS_WIDTH_TOLERANCE, tolerance);
    }
    width = wsg_axis_clamp_width(ax, width);
    if (wsg_axis_outside_soft_limits(ax, width))
        return WSG_E_RANGE_ERROR;
    speed = wsg_clamp(speed, ax->cfg.min_speed, ax->cfg.max_speed);
    /* Close onto a part narrower than the fingers, open into a part around
     * them, in both cases through the clamping travel beyond it. */
    target = width <= ax->width ? width - travel : width + travel;
    target = wsg_axis_clamp_width(ax, target);
    st = wsg_axis_request(ax, WSG_MOTION_GRASP, WSG_CMD_GRASP, target, speed,
                          tag);
    ax->req_motion.nominal = width;
    /* Kept with the motion: the window is judged when it blocks. */
    ax->req_motion.tolerance = tolerance;
    return st;
}

uint16_t wsg_axis_request_grasp(struct wsg_axis *ax, double width,
                                double speed, uint32_t tag)
{
    return wsg_axis_request_grasp_in(ax, width, speed, NULL, tag);
}

uint16_t wsg_axis_request_release(struct wsg_axis *ax, double width,
                                  double speed, uint32_t tag)
{
    if (isnan(width) || isnan(speed))
        return WSG_E_INVALID_PARAMETER;
    width = wsg_axis_clamp_width(ax, width);
    if (wsg_axis_outside_soft_limits(ax, width))
        return WSG_E_RANGE_ERROR;
    speed = wsg_clamp(speed, ax->cfg.min_speed, ax->cfg.max_speed);
    return wsg_axis_request(ax, WSG_MOTION_RELEASE, WSG_CMD_RELEASE, width,
                            speed, tag);
}

uint16_t wsg_axis_request_speed(struct wsg_axis *ax, double v, uint32_t tag)
{
    double vmax = ax->cfg.max_speed;

    if (isnan(v))
        return WSG_E_INVALID_PARAMETER;
    /* No minimum: a PD loop near its target asks for small speeds. */
    wsg_axis_request(ax, WSG_MOTION_SPEED, 0, 0.0, wsg_clamp(v, -vmax, vmax),
                     tag);
    return WSG_E_SUCCESS;
}

void wsg_axis_request_own(struct wsg_axis *ax)
{
    ax->req_motion.own = 1;
}

/* A motion accepted in this step but not started owes an E_CMD_ABORTED. */
static void wsg_axis_cancel_request(struct wsg_axis *ax)
{
    if (ax->req_motion.kind == WSG_MOTION_NONE)
        return;
    ax->req_cancelled = ax->req_motion;
    memset(&ax->req_motion, 0, sizeof ax->req_motion);
}

void wsg_axis_request_stop(struct wsg_axis *ax)
{
    wsg_axis_cancel_request(ax);
    ax->req_stop = 1;
}

void wsg_axis_request_fast_stop(struct wsg_axis *ax)
{
    wsg_axis_cancel_request(ax);
    ax->req_fast_stop = 1;
    ax->req_ack = 0; /* an acknowledge before it does not clear it */
}

void wsg_axis_request_ack(struct wsg_axis *ax)
{
    ax->req_ack = 1;
}

void wsg_axis_set_acc(struct wsg_axis *ax, double acc)
{
    struct wsg_axis_range r =
        wsg_axis_config_range(&ax->cfg, WSG_AXIS_ACCELERATION);

    if (isnan(acc))
        return;
    ax->acc = wsg_clamp(acc, r.min, r.max);
}

void wsg_axis_set_force_limit(struct wsg_axis *ax, double force)
{
    struct wsg_axis_range r =
        wsg_axis_config_range(&ax->cfg, WSG_AXIS_FORCE_LIMIT);

    if (isnan(force))
        return;
    /* Overdrive lets a session go past nominal (3.3.8). */
    if (ax->overdrive)
        r.max = ax->cfg.ovr_force;
    ax->force_limit = wsg_clamp(force, r.min, r.max);
}

int wsg_axis_configure(struct wsg_axis *ax, enum wsg_axis_setting s, double v,
                       struct wsg_axis_range *valid)
{
    int r = wsg_axis_config_set(&ax->cfg, s, v, valid);

    if (r < 0 || s == WSG_AXIS_WIDTH)
        return r;
    if (s == WSG_AXIS_ACCELERATION)
        wsg_axis_set_acc(ax, v);
    else if (s == WSG_AXIS_FORCE_LIMIT)
        wsg_axis_set_force_limit(ax, v);
    return 0;
}

void wsg_axis_set_overdrive(struct wsg_axis *ax, int on)
{
    ax->overdrive = on ? 1 : 0;
    /* Leaving overdrive reduces a limit above nominal (3.3.8). */
    if (!on && ax->force_limit > ax->cfg.nom_force)
        ax->force_limit = ax->cfg.nom_force;
}

void wsg_axis_set_soft_limits(struct wsg_axis *ax, double minus, double plus)
{
    ax->soft_limits = 1;
    ax->soft_minus = minus;
    ax->soft_plus = plus;
}

void wsg_axis_clear_soft_limits(struct wsg_axis *ax)
{
    ax->soft_limits = 0;
}

void wsg_axis_clear_stats(struct wsg_axis *ax)
{
    memset(&ax->stats, 0, sizeof ax->stats);
}

void wsg_axis_advance_idle(struct wsg_axis *ax, uint64_t nsteps)
{
    ax->time_us += nsteps * ax->cfg.step_us;
}

void wsg_axis_set_part(struct wsg_axis *ax, double width, double stiffness)
{
    if (width < 0 || isnan(width)) {
        ax->builtin.part = 0;
        return;
    }
    ax->builtin.part = 1;
    ax->builtin.part_width = width;
    ax->builtin.part_stiffness =
        stiffness > 0 ? stiffness : ax->cfg.part_stiffness;
}

void wsg_axis_set_part_patch(struct wsg_axis *ax, double w, double h)
{
    ax->builtin.patch_w = w > 0.0 ? w : WSG_AXIS_PATCH_MM;
    ax->builtin.patch_h = h > 0.0 ? h : WSG_AXIS_PATCH_MM;
}

void wsg_axis_set_obstacle(struct wsg_axis *ax, double width)
{
    if (width < 0 || isnan(width)) {
        ax->builtin.obstacle = 0;
        return;
    }
    ax->builtin.obstacle = 1;
    ax->builtin.obstacle_width = width;
}

void wsg_axis_set_fault(struct wsg_axis *ax, uint32_t fault, int on)
{
    fault &= WSG_FAULTS;
    if (on)
        ax->faults |= fault;
    else
        ax->faults &= ~fault;
}

void wsg_axis_set_plant(struct wsg_axis *ax, struct wsg_plant *p)
{
    struct wsg_drive d;

    ax->plant = p;
    /* The firmware counts from where this plant's fingers stand. */
    d = wsg_axis_drive(ax, WSG_DRIVE_OFF, 0.0, 0.0);
    ax->width = wsg_axis_sense(ax, &d).width;
}

struct wsg_plant *wsg_axis_plant(struct wsg_axis *ax)
{
    return wsg_axis_plant_of(ax);
}
