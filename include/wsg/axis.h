/*
 * The finger axis model: a fixed-step simulation of one WSG gripper's
 * fingers, their drive and a part between them.
 *
 * Command handlers only record requests (wsg_axis_request_*) and change
 * session settings through setters; the state changes only in
 * wsg_axis_step(), which advances simulated time by exactly one fixed
 * step, and in wsg_axis_settle(), a step of zero length that applies the
 * requests. The model reads no clock and does no I/O: the caller drives
 * it, a test with a fake clock, the daemon from a timerfd. Results of
 * motion commands leave through a callback. The struct's layout is the
 * model's own (src/axis/axis_impl.h): everyone else reads the state
 * through getters, and a holder keeps it in a struct wsg_axis_storage.
 *
 * Units: mm, mm/s, mm/s^2, N, microseconds. Width is the distance between
 * the fingers (0 = closed).
 */
#ifndef WSG_AXIS_H
#define WSG_AXIS_H

#include <stdint.h>

#include "wsg/schema.h"

/* The system state flags (WSG_SF_*, Appendix B) and the grasping states
 * (enum wsg_grasp_state, 41h) are the schema's. */

/* Faults that can be injected; each is also its flag. */
#define WSG_FAULTS                                                            \
    (WSG_SF_TEMP_WARNING | WSG_SF_TEMP_FAULT | WSG_SF_POWER_FAULT |           \
     WSG_SF_CURR_FAULT | WSG_SF_FINGER_FAULT)
/* Faults that disable every movement-related command (injected ones and
 * the model's own temperature fault alike). */
#define WSG_FAULTS_BLOCKING                                                   \
    (WSG_SF_TEMP_FAULT | WSG_SF_POWER_FAULT | WSG_SF_CURR_FAULT |             \
     WSG_SF_FINGER_FAULT)

enum wsg_homing_dir {
    WSG_HOME_DEFAULT = 0,
    WSG_HOME_POSITIVE = 1,
    WSG_HOME_NEGATIVE = 2
};

/* Preposition FLAGS (21h). */
#define WSG_MOVE_RELATIVE      0x01u
#define WSG_MOVE_STOP_ON_BLOCK 0x02u

/* What the gripper's web page and model type fix; see wsg_axis_config_init. */
struct wsg_axis_config {
    uint8_t type;  /* Get System Information TYPE (NOTES.md) */
    double stroke; /* mm */
    double min_speed, max_speed;
    double min_acc, max_acc;
    double min_force, nom_force, ovr_force;
    double default_acc;     /* session default, restored on reset */
    double default_force;   /* session default force limit */
    double homing_speed;    /* mm/s */
    double clamp_travel;    /* mm: grasp clamping travel */
    double width_tolerance; /* mm: part width tolerance */
    double part_stiffness;  /* N/mm: default for a placed part */
    double ambient;         /* degC: temperature at rest */
    double temp_warning;    /* degC: SF_TEMP_WARNING at and above */
    double temp_fault;      /* degC: SF_TEMP_FAULT at and above */
    double heat_tau;        /* s: thermal time constant of the drive */
    int homing_dir;         /* WSG_HOME_POSITIVE or WSG_HOME_NEGATIVE */
    int force_sensor;       /* force measurement fingers fitted (tare) */
    uint32_t step_us;       /* fixed step length */
};

struct wsg_grasp_stats {
    uint32_t total;
    uint16_t no_part;
    uint16_t lost_part;
};

/* Called from wsg_axis_step when a motion command ends. tag is what the
 * request carried (the dispatcher's record of who asked). */
typedef void (*wsg_axis_done_fn)(void *ctx, uint32_t tag, uint8_t cmd_id,
                                 uint16_t status);

/* What the model did on its own that its owner may want to tell (the
 * communication log): a FAST STOP it entered without a request, and why.
 * A requested FAST STOP (23h, a disconnect) is not reported: whoever
 * requested it knows its cause. */
enum wsg_axis_event {
    WSG_AXIS_FAST_STOP_FAULT,     /* a power or current fault appeared */
    WSG_AXIS_FAST_STOP_SOFT_LIMIT /* the fingers reached a soft limit */
};
typedef void (*wsg_axis_event_fn)(void *ctx, enum wsg_axis_event ev);

/* The model's state. Its layout is private to src/axis (axis_impl.h):
 * everyone else reads it through the getters below and changes it through
 * the requests and setters, so the model alone keeps its invariants. */
struct wsg_axis;

/* Room for one struct wsg_axis inside an object that holds the model by
 * value (the device) without seeing its layout, so that holding it costs
 * no allocation. axis.c checks at compile time that the struct fits and
 * that this is aligned for it; the words' types are those the struct
 * holds. Only the model reads or writes it, through a struct wsg_axis *
 * to it. */
#define WSG_AXIS_STORAGE_WORDS 108
struct wsg_axis_storage {
    union {
        double d;
        uint64_t u;
        void *p;
        void (*f)(void);
    } w[WSG_AXIS_STORAGE_WORDS];
};

/* Models selectable by name: "wsg50" (default), "wsg50-210", "wsg32",
 * "wsg25". Returns 0 or -EINVAL for an unknown name. */
int wsg_axis_config_init(struct wsg_axis_config *cfg, const char *model);

/* The values whose valid range depends on the model: the defaults the web
 * page sets, and a width between the fingers (a part's, a target's). The
 * model knows its ranges, so whoever takes such a value (the daemon's
 * options, the session commands, the control channel) asks it here. */
enum wsg_axis_setting {
    WSG_AXIS_ACCELERATION,    /* default_acc, mm/s^2: min_acc..max_acc */
    WSG_AXIS_FORCE_LIMIT,     /* default_force, N: min_force..nom_force */
    WSG_AXIS_CLAMP_TRAVEL,    /* clamp_travel, mm: 0..stroke */
    WSG_AXIS_WIDTH_TOLERANCE, /* width_tolerance, mm: 0..stroke */
    WSG_AXIS_WIDTH            /* a width, mm: 0..stroke (no config value) */
};

struct wsg_axis_range {
    double min, max;
};

/* The valid range of setting s for cfg's model. */
struct wsg_axis_range wsg_axis_config_range(const struct wsg_axis_config *cfg,
                                            enum wsg_axis_setting s);
/* Check v against that range and make it cfg's value (WSG_AXIS_WIDTH is
 * only checked). Returns 0, or -ERANGE (NaN too) with cfg unchanged; the
 * range goes to valid unless it is NULL. */
int wsg_axis_config_set(struct wsg_axis_config *cfg, enum wsg_axis_setting s,
                        double v, struct wsg_axis_range *valid);

/* cfg's value of setting s (0 for WSG_AXIS_WIDTH, which has none). */
double wsg_axis_config_get(const struct wsg_axis_config *cfg,
                           enum wsg_axis_setting s);
/* Change a setting of a running model's configuration (the web page's
 * settings), checked as wsg_axis_config_set checks it. An acceleration
 * or force limit also becomes the session's value at once, as Set
 * Acceleration (30h) and Set Force Limit (32h) make it; a power cycle
 * restores the new defaults. A clamping travel or tolerance counts from
 * the next grasp. Returns 0, or -ERANGE with nothing changed. */
int wsg_axis_configure(struct wsg_axis *ax, enum wsg_axis_setting s, double v,
                       struct wsg_axis_range *valid);

void wsg_axis_init(struct wsg_axis *ax, const struct wsg_axis_config *cfg,
                   wsg_axis_done_fn on_done, void *ctx);
/* Have fn told of the model's own events (NULL: no one); a power cycle
 * keeps it. Called from within a step or settle: it must not call back
 * into the model. */
void wsg_axis_on_event(struct wsg_axis *ax, wsg_axis_event_fn fn, void *ctx);
/* Power cycle: session settings back to defaults, not referenced. */
void wsg_axis_reset(struct wsg_axis *ax);

/* Advance simulated time by one step (cfg.step_us): settle, then move. */
void wsg_axis_step(struct wsg_axis *ax);
/* A step of zero length: apply the recorded requests (FAST STOP,
 * acknowledge, stop, a new motion), the consequences of faults, of leaving
 * overdrive and of soft limits, and changes of the world under a clamp (a
 * part lost) now, advancing neither time nor the fingers' motion, so that
 * the next answer shows them (a 40h right after "ack" sees FAST STOP
 * cleared). */
void wsg_axis_settle(struct wsg_axis *ax);
/* Nothing moving, pending or changing: steps would not change the state, so
 * a caller may skip them (only time_us would advance). */
int wsg_axis_idle(const struct wsg_axis *ax);

/* The state as the commands report it. */
uint32_t wsg_axis_flags(const struct wsg_axis *ax);
/* In FAST STOP, counting requests not applied yet. */
int wsg_axis_fast_stopped(const struct wsg_axis *ax);
/* Moving or about to move: a new motion command gets E_ALREADY_RUNNING. */
int wsg_axis_busy(const struct wsg_axis *ax);

/* Reading the model: everyone outside the model reads its state through
 * these. Each is a plain read of one value, cheap enough for the stream
 * polling and the dispatcher's checks. */
/* The configuration it was made with (limits, step length, sensor). */
const struct wsg_axis_config *wsg_axis_cfg(const struct wsg_axis *ax);
/* Simulated time in microseconds: steps taken and idle time advanced. */
uint64_t wsg_axis_time(const struct wsg_axis *ax);
/* The values the commands report: width (43h, as the gripper sees it,
 * off by a wrong reference), speed (44h, signed), force (45h),
 * temperature (46h, degC), grasping state (41h) and statistics (42h). */
double wsg_axis_width(const struct wsg_axis *ax);
double wsg_axis_speed(const struct wsg_axis *ax);
double wsg_axis_force(const struct wsg_axis *ax);
double wsg_axis_temperature(const struct wsg_axis *ax);
enum wsg_grasp_state wsg_axis_grasp_state(const struct wsg_axis *ax);
struct wsg_grasp_stats wsg_axis_stats(const struct wsg_axis *ax);
/* Faults present (WSG_FAULTS bits): injected ones and the model's own
 * temperature flags. */
uint32_t wsg_axis_faults(const struct wsg_axis *ax);
/* Homed: the commands that need a reference may run. */
int wsg_axis_referenced(const struct wsg_axis *ax);
/* Speed mode runs (wsg_axis_request_speed; a script's mc.speed); a
 * request not settled yet does not count. */
int wsg_axis_speed_mode(const struct wsg_axis *ax);
/* The fingers are held by a block with the drive pushing into it: a clamp
 * (a grasp holding, a preposition blocked without stop on block) or speed
 * mode pushing into a contact. The physical state a script's mc.blocked()
 * reads: unlike the BLOCKED flags of 40h, which a blocked motion leaves set
 * until the next one starts, it is 0 once the drive no longer pushes (stop
 * on block, Stop, a part lost and the fingers snapping on, speed mode set
 * to 0 or away from the contact). */
int wsg_axis_pressing(const struct wsg_axis *ax);
/* Session settings. */
double wsg_axis_acc(const struct wsg_axis *ax);
double wsg_axis_force_limit(const struct wsg_axis *ax);
/* 1 with the limits in *minus and *plus when soft limits are set, else 0
 * with both untouched. */
int wsg_axis_soft_limits(const struct wsg_axis *ax, double *minus,
                         double *plus);
/* 1 with its width and stiffness when a part is placed, else 0 with both
 * untouched. */
int wsg_axis_part(const struct wsg_axis *ax, double *width, double *stiffness);
/* What one finger's pad feels, for the sensors a finger carries (an FMF's
 * force, a DSA pad's cells): force in N pressing on the pad, and the patch
 * of the pad the part touches, its centre (x across the pad, y along the
 * finger, in mm from the pad's centre) and size (w by h mm). All 0 when
 * nothing touches the pad. */
struct wsg_contact {
    double force;
    double x, y;
    double w, h;
};
/* finger 0 or 1: 0 with *c filled, else -EINVAL with *c untouched. */
int wsg_axis_contact(const struct wsg_axis *ax, int finger,
                     struct wsg_contact *c);

/* Requests. The motion requests validate against the current state and
 * return the immediate status (E_CMD_PENDING when accepted); speeds and
 * widths are clamped to the model's limits as the manual says. */
uint16_t wsg_axis_request_homing(struct wsg_axis *ax, int dir, uint32_t tag);
uint16_t wsg_axis_request_move(struct wsg_axis *ax, uint8_t flags,
                               double width, double speed, uint32_t tag);
uint16_t wsg_axis_request_grasp(struct wsg_axis *ax, double width,
                                double speed, uint32_t tag);
/* The grasping window one grasp is judged by (NOTES.md): the clamping
 * travel beyond the nominal width and the part width tolerance, in mm. A
 * value below 0 takes the configuration's (clamp_travel,
 * width_tolerance); others are clamped to 0..stroke. */
struct wsg_grasp_window {
    double travel;
    double tolerance;
};
/* A grasp with its own window (a script's grasping.clamp, a connection's
 * own settings); w NULL is wsg_axis_request_grasp. NaN in w is
 * E_INVALID_PARAMETER. */
uint16_t wsg_axis_request_grasp_in(struct wsg_axis *ax, double width,
                                   double speed,
                                   const struct wsg_grasp_window *w,
                                   uint32_t tag);
uint16_t wsg_axis_request_release(struct wsg_axis *ax, double width,
                                  double speed, uint32_t tag);
/* Speed mode (a script's mc.speed): drive the fingers at v mm/s, negative
 * closing, until a stop, a FAST STOP, a fault or a soft limit ends it. The
 * velocity reaches v with the model's maximum acceleration (cfg.max_acc,
 * not the session's: speed mode is the velocity controller itself); |v| is
 * clamped to cfg.max_speed, and any smaller speed down to 0 is taken. A
 * block does not end it: the fingers stay pushed against it with the force
 * limit for as long as v points into it. Over speed mode it only changes
 * the set speed; over another motion it replaces it, which ends
 * E_CMD_ABORTED. Final results carry command ID 0 (no command of the
 * command set). Returns E_INVALID_PARAMETER for NaN, else E_SUCCESS: the
 * caller checks FAST STOP, faults and the reference as for any motion. */
uint16_t wsg_axis_request_speed(struct wsg_axis *ax, double v, uint32_t tag);
/* The move just requested is the motion controller's own (a script's
 * mc.move), not the grasping state machine's: the grasping state (41h)
 * stays what it was while it runs and when it ends, as on the gripper,
 * where only the grasping commands (25h, 26h, 21h and a script's grasping
 * functions) drive it. Speed mode is always the controller's own. */
void wsg_axis_request_own(struct wsg_axis *ax);
void wsg_axis_request_stop(struct wsg_axis *ax);
void wsg_axis_request_fast_stop(struct wsg_axis *ax);
void wsg_axis_request_ack(struct wsg_axis *ax);

/* Session settings (clamped as the manual says). */
void wsg_axis_set_acc(struct wsg_axis *ax, double acc);
void wsg_axis_set_force_limit(struct wsg_axis *ax, double force);
void wsg_axis_set_overdrive(struct wsg_axis *ax, int on);
void wsg_axis_set_soft_limits(struct wsg_axis *ax, double minus, double plus);
void wsg_axis_clear_soft_limits(struct wsg_axis *ax);
/* Grasping statistics back to zero (42h with RESET). */
void wsg_axis_clear_stats(struct wsg_axis *ax);

/* Advance simulated time by nsteps steps without stepping. Only while
 * wsg_axis_idle holds: then steps would change nothing but the time, so a
 * caller may jump a quiet gap at once. */
void wsg_axis_advance_idle(struct wsg_axis *ax, uint64_t nsteps);

/* The world (control channel, tests). width < 0 removes the part. */
void wsg_axis_set_part(struct wsg_axis *ax, double width, double stiffness);
/* The size of the patch the part presses on each pad, w by h mm, centred
 * (default WSG_AXIS_PATCH_MM square); values <= 0 or NaN restore it. */
#define WSG_AXIS_PATCH_MM 10.0
void wsg_axis_set_part_patch(struct wsg_axis *ax, double w, double h);
/* A rigid obstacle that blocks the fingers at width, moving either way;
 * width < 0 removes it. */
void wsg_axis_set_obstacle(struct wsg_axis *ax, double width);
/* Whether the last grasp that found no part was blocked before its part's
 * window (1: a collision, GCL's ERR 29) rather than closing through its
 * clamping travel (0: no part, ERR 18). Both end 25h with E_CMD_FAILED. */
int wsg_axis_grasp_collided(const struct wsg_axis *ax);
/* The obstacle's width: 1, or 0 when there is none. */
int wsg_axis_obstacle(const struct wsg_axis *ax, double *width);
/* Inject or clear faults (WSG_FAULTS bits). A temperature, power or
 * current fault stops a running motion (E_CMD_ABORTED) at the next settle
 * or step. */
void wsg_axis_set_fault(struct wsg_axis *ax, uint32_t fault, int on);

#endif
