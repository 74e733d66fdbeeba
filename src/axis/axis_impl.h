/*
 * The axis model's layout, private to src/axis: the state struct behind
 * the opaque struct wsg_axis of wsg/axis.h and the motion records it
 * keeps. Only the model's own code includes it, and the white-box tests
 * that look inside it (tests/test_axis.c, the fuzz bench's invariants);
 * everyone else goes through the functions of wsg/axis.h, so the model
 * alone keeps its invariants and its layout can change without them.
 */
#ifndef WSG_AXIS_IMPL_H
#define WSG_AXIS_IMPL_H

#include "plant_builtin.h"
#include "wsg/axis.h"

enum wsg_motion_kind {
    WSG_MOTION_NONE = 0,
    WSG_MOTION_HOMING,
    WSG_MOTION_MOVE,
    WSG_MOTION_GRASP,
    WSG_MOTION_RELEASE,
    WSG_MOTION_SNAP, /* silent: a clamp released or a part lost */
    WSG_MOTION_SPEED /* speed mode: speed is the signed set speed */
};

/* A trapezoidal profile from rest; positions follow analytically from the
 * time since its start, so durations are exact to one step. */
struct wsg_profile {
    double start, dist, dir; /* dir = +1 or -1 */
    double vmax, acc;
    double t_acc, t_total; /* seconds */
    int decel;             /* 0: runs into an end stop at speed */
    double t;              /* seconds since start */
};

struct wsg_motion {
    enum wsg_motion_kind kind;
    uint8_t cmd_id;
    uint32_t tag;
    double target;    /* where the profile ends */
    double nominal;   /* grasp: the part's nominal width; homing: +1/-1 */
    double tolerance; /* grasp: the part width tolerance it is judged by */
    double speed;
    uint8_t move_flags; /* preposition flags */
    /* The motion controller's own (wsg_axis_request_own): leaves the
     * grasping state as it is. */
    int own;
    struct wsg_profile prof;
};

struct wsg_axis {
    struct wsg_axis_config cfg;
    wsg_axis_done_fn on_done;
    void *done_ctx;
    wsg_axis_event_fn on_event; /* NULL: no one listens */
    void *event_ctx;

    /* Physical state, changed only by wsg_axis_step. */
    uint64_t time_us;
    double width, speed, force;
    int referenced;
    int fast_stop;
    uint32_t event_flags; /* AXIS_STOPPED, TARGET_POS_REACHED, BLOCKED_* */
    enum wsg_grasp_state grasp_state;
    /* The last grasp failed blocked before its part's window (a
     * collision), not through its clamping travel (no part). */
    int grasp_collided;
    struct wsg_grasp_stats stats;
    struct wsg_motion motion;
    int clamping;        /* motor pushes against a block */
    double clamp_force;  /* the force limit when the block was found */
    double clamp_target; /* where the fingers snap if the block goes */
    double clamp_speed;
    int clamp_dir;
    /* Speed mode pushing into a block: the direction it pushes (-1, +1),
     * or 0 while the fingers are free. */
    int push_dir;

    /* Session settings, written by the setters (wsg_axis_set_*). */
    double acc;
    double force_limit;
    int overdrive;
    int soft_limits;
    double soft_minus, soft_plus;

    /* The plant the drive moves: plant, or the built-in one held here when
     * plant is NULL (resolved at each use, so that the struct stays
     * movable). */
    struct wsg_plant *plant;
    struct wsg_plant_builtin builtin;
    double ref_offset;       /* reported width - physical width: nonzero after
                                homing into an obstacle */
    uint32_t faults;         /* injected fault flags (WSG_FAULTS) */
    uint32_t thermal_faults; /* TEMP_WARNING/TEMP_FAULT from the model */
    uint32_t faults_seen;    /* faults whose consequences were applied */
    double temperature;      /* degC, reported by 46h */

    /* Requests recorded by wsg_axis_request_*, applied by the next settle
     * or step in order:
     * fast stop, acknowledge, stop, new motion. */
    int req_fast_stop, req_ack, req_stop;
    struct wsg_motion req_motion;
    /* A request answered E_CMD_PENDING and cancelled by a Stop or FAST STOP
     * before it started: it still owes its final E_CMD_ABORTED. */
    struct wsg_motion req_cancelled;
};

#endif
