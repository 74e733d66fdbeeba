/*
 * The built-in plant: the world of the emulator's first model, exact and
 * cheap enough for a fleet. The fingers are kinematic: they stand where
 * the drive's setpoint puts them unless a block stops them first, and a
 * block holds them where the force limit is reached. A part resists
 * closing only, yielding by force over its stiffness; the obstacle is
 * rigid either way; the end stops bound the stroke. Nothing here moves
 * with time (step does nothing): every answer follows from the drive and
 * the world, so the firmware's analytic profiles stay exact to one step.
 */
#include <errno.h>
#include <math.h>
#include <string.h>

#include "plant_builtin.h"

/* Widths closer than this are the same position (as the firmware's). */
#define WSG_PLANT_EPS 1e-6

static double clampd(double v, double lo, double hi)
{
    return v < lo ? lo : v > hi ? hi : v;
}

/* A position in the world as the gripper counts it: its reference is off
 * by offset after a homing that blocked on something before the end stop
 * (3.2.1 warns of that). */
static double rep(const struct wsg_drive *d, double phys)
{
    return phys + d->offset;
}

/* Where the fingers stand on the part when they squeeze it with force f:
 * the part yields by f over its stiffness. */
static double squeezed(const struct wsg_plant_builtin *b,
                       const struct wsg_drive *d, double f)
{
    return rep(d, b->part_width) - f / b->part_stiffness;
}

/* The mechanical end stop in direction dir. */
static double end_stop(const struct wsg_plant_builtin *b,
                       const struct wsg_drive *d, double dir)
{
    return rep(d, dir < 0 ? 0.0 : b->stroke);
}

/* The next block in direction dir from the fingers when pushing with
 * force f: the part resists closing only; the obstacle either way.
 * Returns 0 when nothing but an end stop lies that way. */
static int next_block(const struct wsg_plant_builtin *b,
                      const struct wsg_drive *d, double dir, double f,
                      double *x_block)
{
    double c[2], w = d->width;
    int n = 0, i, found = 0;

    if (dir < 0 && b->part) {
        double p = squeezed(b, d, f);
        /* Fingers that already squeeze the part harder than f (left there
         * by a block under a higher force limit) are blocked where they
         * are, not let through the part. */
        c[n++] = p > w ? w : p;
    }
    if (b->obstacle)
        c[n++] = rep(d, b->obstacle_width);
    for (i = 0; i < n; i++) {
        if (dir < 0 ? c[i] > w + WSG_PLANT_EPS : c[i] < w - WSG_PLANT_EPS)
            continue; /* behind the fingers */
        if (!found || (dir < 0 ? c[i] > *x_block : c[i] < *x_block))
            *x_block = c[i];
        found = 1;
    }
    return found;
}

/* Does a block still hold fingers that push in direction dir with force f
 * where they are, and where exactly? A part follows the fingers while it
 * reaches them (it may grow or shrink); the obstacle and the end stop hold
 * them only where they are. The nearest one counts. */
static int block_at(const struct wsg_plant_builtin *b,
                    const struct wsg_drive *d, double dir, double f,
                    double *x_block)
{
    double c[3], w = d->width;
    int n = 0, i, found = 0;

    if (dir < 0 && b->part) {
        double p = squeezed(b, d, f);
        /* A part narrower than its own squeeze (made so while held) lets
         * the fingers close only as far as the end stop. */
        if (p < end_stop(b, d, -1.0))
            p = end_stop(b, d, -1.0);
        /* Squeezed harder than f (a part that grew while held): it holds
         * the fingers where they are, as next_block says. */
        c[n++] = p > w ? w : p;
    }
    if (b->obstacle && fabs(w - rep(d, b->obstacle_width)) <= WSG_PLANT_EPS)
        c[n++] = rep(d, b->obstacle_width);
    if (fabs(w - end_stop(b, d, dir)) <= WSG_PLANT_EPS)
        c[n++] = end_stop(b, d, dir);
    for (i = 0; i < n; i++) {
        if (!found || (dir < 0 ? c[i] > *x_block : c[i] < *x_block))
            *x_block = c[i];
        found = 1;
    }
    return found;
}

/* The contact force at width x while closing. A part placed wider than
 * the opening (the control channel can do that) would squeeze beyond
 * anything: the drive holds it with its force limit at most. */
static double contact_force(const struct wsg_plant_builtin *b,
                            const struct wsg_drive *d, double x)
{
    double p = rep(d, b->part_width), f;

    if (!b->part || x >= p)
        return 0.0;
    f = b->part_stiffness * (p - x);
    return f < d->limit ? f : d->limit;
}

/* Where fingers that speed mode pushes in direction dir with force f
 * stand, if something holds them. A part that reaches them stands where f
 * squeezes it, so a new force limit (or a part that changed) moves them
 * there at once, unless the obstacle on the way or the end stop holds them
 * first; the obstacle and the end stop hold them only where they are.
 * Unlike block_at's clamp, which holds the force it blocked with, speed
 * mode pushes with the force limit of the moment. */
static int push_at(const struct wsg_plant_builtin *b,
                   const struct wsg_drive *d, double dir, double f, double *x)
{
    double w = d->width, ow = rep(d, b->obstacle_width);
    double end = end_stop(b, d, dir);

    if (dir < 0 && b->part && rep(d, b->part_width) >= w - WSG_PLANT_EPS) {
        double p = clampd(squeezed(b, d, f), end_stop(b, d, -1.0),
                          end_stop(b, d, 1.0));
        /* The obstacle is rigid either way: the fingers do not pass it,
         * squeezing further or pushed back by the part. */
        if (b->obstacle && ow >= fmin(p, w) - WSG_PLANT_EPS &&
            ow <= fmax(p, w) + WSG_PLANT_EPS)
            p = ow;
        *x = p;
        return 1;
    }
    if (b->obstacle && fabs(w - ow) <= WSG_PLANT_EPS) {
        *x = ow;
        return 1;
    }
    if (fabs(w - end) <= WSG_PLANT_EPS) {
        *x = end;
        return 1;
    }
    return 0;
}

static void builtin_step(struct wsg_plant *p, const struct wsg_drive *d,
                         double dt)
{
    (void)p;
    (void)d;
    (void)dt;
}

/* The profile's point x reached unless a block or the end stop comes
 * first; MOVE and SPEED differ only in how they meet the end stop. */
static void sense_follow(const struct wsg_plant_builtin *b,
                         const struct wsg_drive *d,
                         struct wsg_plant_fingers *o)
{
    double dir = d->dir, x = d->x, xb = 0.0, end = end_stop(b, d, dir);
    int at_end;

    if (next_block(b, d, dir, d->force, &xb) &&
        (dir < 0 ? x <= xb + WSG_PLANT_EPS : x >= xb - WSG_PLANT_EPS)) {
        o->blocked = 1;
        o->width = xb;
    } else {
        if (d->mode == WSG_DRIVE_MOVE)
            /* A final setpoint right at the end stop pushes into it. */
            at_end =
                (d->end && fabs(x - end) <= WSG_PLANT_EPS) ||
                (dir < 0 ? x < end - WSG_PLANT_EPS : x > end + WSG_PLANT_EPS);
        else
            at_end = dir < 0 ? x <= end : x >= end;
        o->blocked = at_end;
        o->width = at_end ? end : x;
    }
    if (o->blocked) {
        o->speed = 0.0;
        o->force = d->mode == WSG_DRIVE_MOVE ? d->force
                                             : contact_force(b, d, o->width);
    } else {
        o->speed = d->v;
        o->force = contact_force(b, d, x);
    }
}

static void builtin_sense(const struct wsg_plant *p, const struct wsg_drive *d,
                          struct wsg_plant_fingers *o)
{
    const struct wsg_plant_builtin *b = (const struct wsg_plant_builtin *)p;
    double xb = 0.0;

    o->width = d->width;
    o->speed = 0.0;
    o->force = d->force;
    o->blocked = 0;
    switch (d->mode) {
    case WSG_DRIVE_OFF:
        o->force = contact_force(b, d, d->width);
        break;
    case WSG_DRIVE_MOVE:
    case WSG_DRIVE_SPEED:
        sense_follow(b, d, o);
        break;
    case WSG_DRIVE_AT:
        o->blocked = (next_block(b, d, d->dir, d->force, &xb) &&
                      fabs(xb - d->width) <= WSG_PLANT_EPS) ||
                     fabs(d->width - end_stop(b, d, d->dir)) <= WSG_PLANT_EPS;
        break;
    case WSG_DRIVE_CLAMP:
        if (block_at(b, d, d->dir, d->force, &xb)) {
            o->blocked = 1;
            o->width = xb;
        }
        break;
    case WSG_DRIVE_PUSH:
        if (push_at(b, d, d->dir, d->force, &xb)) {
            o->blocked = 1;
            o->width = xb;
        }
        break;
    case WSG_DRIVE_RELAX:
        /* Out of overdrive (3.3.8, D8) a part squeezed by the old force
         * springs back to where the new one holds it. */
        if (d->dir < 0 && b->part &&
            fabs(d->width - squeezed(b, d, d->force_was)) <= WSG_PLANT_EPS)
            o->width = squeezed(b, d, d->force);
        o->blocked = 1;
        break;
    }
}

static void builtin_contact(const struct wsg_plant *p,
                            const struct wsg_drive *d, int finger,
                            struct wsg_contact *c)
{
    const struct wsg_plant_builtin *b = (const struct wsg_plant_builtin *)p;

    (void)finger;
    memset(c, 0, sizeof *c);
    /* The built-in world is symmetric: a part held between the fingers
     * presses on both pads with the grip force, centred. */
    if (b->part && d->grip > 0.0 && d->width < rep(d, b->part_width)) {
        c->force = d->grip;
        c->w = b->patch_w > 0.0 ? b->patch_w : WSG_AXIS_PATCH_MM;
        c->h = b->patch_h > 0.0 ? b->patch_h : WSG_AXIS_PATCH_MM;
    }
}

/* Shapes have no place in a one-dimensional world: the control channel's
 * "object" is the MuJoCo plant's, and "part" is this one's. */
static int builtin_place(struct wsg_plant *p, const struct wsg_object *o)
{
    (void)p;
    (void)o;
    return -ENOTSUP;
}

static int builtin_object(const struct wsg_plant *p, struct wsg_object *o)
{
    (void)p;
    (void)o;
    return 0;
}

static int builtin_pull(struct wsg_plant *p, double n)
{
    (void)p;
    (void)n;
    return -ENOTSUP;
}

static void builtin_destroy(struct wsg_plant *p)
{
    (void)p; /* held inside the model: nothing to free */
}

static const struct wsg_plant_ops builtin_ops = {
    "builtin",     builtin_step,   builtin_sense, builtin_contact,
    builtin_place, builtin_object, builtin_pull,  builtin_destroy};

void wsg_plant_builtin_init(struct wsg_plant_builtin *b, double stroke,
                            double part_stiffness)
{
    memset(b, 0, sizeof *b);
    b->base.ops = &builtin_ops;
    b->stroke = stroke;
    b->part_stiffness = part_stiffness;
}
