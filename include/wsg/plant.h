/*
 * The plant: the gripper's hardware and the world around it, which the
 * firmware (src/axis/axis.c) drives. Each step the firmware commands the
 * finger drive (struct wsg_drive: a setpoint and speed, or a way to hold,
 * and the force limit); the plant moves the fingers (step) and tells where
 * they stand, how fast, with what force and whether something blocks them
 * (sense), and what each finger's pad feels (contact).
 *
 * Two plants: the built-in one (src/axis/plant_builtin.c), kinematic
 * fingers and a part that is a one-dimensional spring, with an obstacle;
 * and a MuJoCo one (src/plant/mujoco.c, optional at build time), rigid
 * bodies with contact in a scene. A plant changes only in step(dt) and in
 * the setters of its world (place, pull); sense and contact only read.
 * Neither reads a clock. Positions are the firmware's: mm of width, the
 * reference's offset included (drive.offset = reported - physical).
 */
#ifndef WSG_PLANT_H
#define WSG_PLANT_H

#include <stddef.h>

#include "wsg/axis.h"

/* How the drive is commanded; sense answers for the mode it is given. */
enum wsg_drive_mode {
    WSG_DRIVE_OFF,   /* motor off: the fingers stand; force is the contact */
    WSG_DRIVE_MOVE,  /* follow setpoint x (a profile) until a block takes
                        the force limit; with end set, x is final and an
                        end stop right at it blocks too */
    WSG_DRIVE_SPEED, /* follow x (a velocity ramp); an end stop blocks */
    WSG_DRIVE_AT,    /* is there a block right at the fingers in dir? */
    WSG_DRIVE_CLAMP, /* hold a block found in dir with force: still held? */
    WSG_DRIVE_PUSH,  /* speed mode pushing in dir with the force limit */
    WSG_DRIVE_RELAX  /* a clamp's force drops from force_was to force */
};

struct wsg_drive {
    enum wsg_drive_mode mode;
    double x, v;  /* setpoint width (mm) and speed (mm/s) */
    double dir;   /* -1 closing, +1 opening */
    double force; /* N the drive pushes a block with */
    double force_was;
    double limit;  /* N: the session's force limit (caps a free contact) */
    int end;       /* MOVE: the setpoint is the profile's last */
    double width;  /* where the firmware last saw the fingers */
    double grip;   /* N: the force the firmware reports (contact) */
    double offset; /* mm: reported minus physical width */
};

/* What sense tells. */
struct wsg_plant_fingers {
    double width, speed, force;
    int blocked;
};

/* Objects the control channel places between the fingers. */
enum wsg_object_kind {
    WSG_OBJECT_NONE,
    WSG_OBJECT_BOX,      /* size: width (between the pads), depth, height */
    WSG_OBJECT_CYLINDER, /* size: diameter, length (along the fingers) */
    WSG_OBJECT_SPHERE    /* size: diameter */
};

/* The largest size of an object (mm): well beyond any stroke, small
 * enough that it never reaches the model's floor (0.5 m below), whose
 * contacts would make each step cost many times more. */
#define WSG_OBJECT_SIZE_MAX 300.0

struct wsg_object {
    enum wsg_object_kind kind;
    double size[3]; /* mm */
    double mass;    /* kg */
    double friction;
    /* Where its centre is now (object fills it in; place ignores it): mm
     * in the scene's frame; the model's scene has its base at 0, x across
     * the fingers, z up. */
    double pos[3];
};

struct wsg_plant;

struct wsg_plant_ops {
    const char *name;
    /* Advance the world by dt seconds with the drive commanded. */
    void (*step)(struct wsg_plant *p, const struct wsg_drive *d, double dt);
    /* The fingers under drive d now (no time passes). */
    void (*sense)(const struct wsg_plant *p, const struct wsg_drive *d,
                  struct wsg_plant_fingers *out);
    /* What finger 0 or 1's pad feels (wsg_axis_contact). */
    void (*contact)(const struct wsg_plant *p, const struct wsg_drive *d,
                    int finger, struct wsg_contact *c);
    /* Place an object (kind NONE removes it): 0 or -errno (-ENOTSUP). */
    int (*place)(struct wsg_plant *p, const struct wsg_object *o);
    /* The object placed: 1 with *o (its position now), or 0. */
    int (*object)(const struct wsg_plant *p, struct wsg_object *o);
    /* Pull on the object out of the fingers with n newtons (0: none). */
    int (*pull)(struct wsg_plant *p, double n);
    void (*destroy)(struct wsg_plant *p);
};

struct wsg_plant {
    const struct wsg_plant_ops *ops;
};

/* Drive ax's fingers with plant p (NULL: the built-in one again). The
 * plant stays the caller's; a power cycle keeps it. */
void wsg_axis_set_plant(struct wsg_axis *ax, struct wsg_plant *p);
struct wsg_plant *wsg_axis_plant(struct wsg_axis *ax);

/* The MuJoCo plant for a gripper of cfg: scene NULL builds the model's
 * own (fingers on a fixed base, gravity on), else the MJCF file scene
 * whose slide joints left and right carry the fingers (each joint's value
 * a finger's travel from open, m). Returns 0 with *p, or -errno with a
 * reason in err (-ENOTSUP when built without MuJoCo). */
int wsg_plant_mujoco_open(struct wsg_plant **p,
                          const struct wsg_axis_config *cfg, const char *scene,
                          const char *left, const char *right, char *err,
                          size_t errlen);
/* 1 when the build has the MuJoCo plant. */
int wsg_plant_mujoco_available(void);

#endif
