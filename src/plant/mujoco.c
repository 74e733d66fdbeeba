/*
 * The MuJoCo plant: the fingers and an object as rigid bodies with contact
 * (Debian's libmujoco-dev). The scene is the model's own (two flat pads of
 * a DSA's size on slide joints, hanging from a fixed base, gravity on) or
 * the user's MJCF with two named slide joints. The drive is what the real
 * one is: position control of each finger towards the firmware's setpoint
 * with the force limit as its bound, applied to the joints (the scene
 * needs no actuators), so a part stops the fingers where the limit
 * balances the contact. Physics runs only in step(dt), in n equal steps
 * that make up dt exactly; no clock, no I/O there. Placing an object
 * reloads the model with it (MuJoCo 2.2 compiles models whole), keeping
 * the fingers where they are.
 */
#define _GNU_SOURCE

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <mujoco/mujoco.h>

#include "wsg/plant.h"

/* The built-in scene's pads: a DSA's sensing area (6 x 14 cells of
 * 3.4 mm), 4 mm thick. */
#define MJ_PAD_W     0.0204
#define MJ_PAD_L     0.0476
#define MJ_PAD_T     0.004
#define MJ_FINGER_KG 0.1
/* The built-in scene's physics step: half the model's step at most. */
#define MJ_STEP_MAX 0.0005
/* Drive gains per finger: stiff enough that free motion tracks the
 * profile within microns, so only a block saturates the force bound. */
#define MJ_KP 1.0e5 /* N/m */
#define MJ_KD 500.0 /* N s/m: about critical with the drive's inertia */
/* Fingers slower than this (m/s) with the drive at its bound stand at a
 * block. */
#define MJ_V_STILL 0.002
/* A held block is gone when a finger runs on faster than this (m/s): a
 * part that slips out lets the drive accelerate the fingers at once. */
#define MJ_V_SLIP 0.02
/* A patch from a single contact point (a sphere's) is one DSA cell. */
#define MJ_PATCH_MIN_MM 3.4
#define MJ_XML_MAX      8192

struct mj_plant {
    struct wsg_plant base;
    mjModel *m;
    mjData *d;
    double stroke; /* m */
    double ts;     /* the scene's own physics step, s */
    char *scene;   /* the user's MJCF path, or NULL */
    char left[64], right[64];
    int qa[2], da[2]; /* the finger joints' qpos and dof addresses */
    int fbody[2];     /* the bodies the finger joints move */
    struct wsg_object obj;
    int has_obj;
    int obj_body, obj_qa, obj_da;
    int hand; /* the object is held where placed (see place) */
    double hand_pose[7];
    double pull; /* N */
};

static double clampd(double v, double lo, double hi)
{
    return v < lo ? lo : v > hi ? hi : v;
}

/* The object's geom, in the MJCF of both scenes. */
static int object_xml(const struct mj_plant *p, char *buf, size_t n,
                      const double pos[3])
{
    const struct wsg_object *o = &p->obj;
    char geom[256];
    double s0 = o->size[0] / 2000.0, s1 = o->size[1] / 2000.0,
           s2 = o->size[2] / 2000.0;

    switch (o->kind) {
    case WSG_OBJECT_BOX:
        snprintf(geom, sizeof geom, "type=\"box\" size=\"%.9g %.9g %.9g\"", s0,
                 s1, s2);
        break;
    case WSG_OBJECT_CYLINDER: /* axis along the fingers (z) */
        snprintf(geom, sizeof geom, "type=\"cylinder\" size=\"%.9g %.9g\"", s0,
                 s1);
        break;
    case WSG_OBJECT_SPHERE:
        snprintf(geom, sizeof geom, "type=\"sphere\" size=\"%.9g\"", s0);
        break;
    default:
        buf[0] = '\0';
        return 0;
    }
    return snprintf(buf, n,
                    "<body name=\"wsg_object\" pos=\"%.9g %.9g %.9g\">"
                    "<freejoint/><geom name=\"wsg_object\" %s mass=\"%.9g\" "
                    "friction=\"%.9g 0.005 0.0001\" contype=\"2\" "
                    "conaffinity=\"1\" condim=\"4\" solref=\"0.002 1\" "
                    "solimp=\"0.95 0.99 0.0002\"/></body>",
                    pos[0], pos[1], pos[2], geom, o->mass,
                    o->friction) >= (int)n
               ? -ENAMETOOLONG
               : 0;
}

/* The model's own scene: base fixed at the origin, fingers hanging down
 * (-z) and closing along x, a floor far below for what falls. */
static int builtin_xml(const struct mj_plant *p, char *buf, size_t n,
                       const char *object)
{
    double h = p->stroke / 2.0, ts = p->ts;
    int r = snprintf(
        buf, n,
        "<mujoco model=\"wsg\"><option timestep=\"%.9g\" gravity=\"0 0 "
        "-9.81\"/>"
        "<default><geom solref=\"0.002 1\" solimp=\"0.95 0.99 0.0002\"/>"
        "</default><worldbody>"
        "<geom name=\"floor\" type=\"plane\" pos=\"0 0 -0.5\" size=\"1 1 "
        "0.1\" contype=\"1\" conaffinity=\"2\"/>"
        "<body name=\"wsg_left\" pos=\"%.9g 0 0\"><joint name=\"wsg_left\" "
        "type=\"slide\" axis=\"1 0 0\" limited=\"true\" range=\"0 %.9g\" "
        "armature=\"0.5\" solreflimit=\"0.002 1\" solimplimit=\"0.95 0.99 "
        "0.0002\"/><geom name=\"wsg_pad_left\" type=\"box\" "
        "pos=\"%.9g 0 %.9g\" size=\"%.9g %.9g %.9g\" mass=\"%.9g\" "
        "friction=\"0.01 0.005 0.0001\" contype=\"1\" conaffinity=\"2\"/>"
        "</body>"
        "<body name=\"wsg_right\" pos=\"%.9g 0 0\"><joint name=\"wsg_right\" "
        "type=\"slide\" axis=\"-1 0 0\" limited=\"true\" range=\"0 %.9g\" "
        "armature=\"0.5\" solreflimit=\"0.002 1\" solimplimit=\"0.95 0.99 "
        "0.0002\"/><geom name=\"wsg_pad_right\" type=\"box\" "
        "pos=\"%.9g 0 %.9g\" size=\"%.9g %.9g %.9g\" mass=\"%.9g\" "
        "friction=\"0.01 0.005 0.0001\" contype=\"1\" conaffinity=\"2\"/>"
        "</body>%s</worldbody></mujoco>",
        ts, -h, h, -MJ_PAD_T / 2, -MJ_PAD_L / 2, MJ_PAD_T / 2, MJ_PAD_W / 2,
        MJ_PAD_L / 2, MJ_FINGER_KG, h, h, MJ_PAD_T / 2, -MJ_PAD_L / 2,
        MJ_PAD_T / 2, MJ_PAD_W / 2, MJ_PAD_L / 2, MJ_FINGER_KG, object);

    return r >= (int)n ? -ENAMETOOLONG : 0;
}

/* A user's scene with the object beside it: a wrapper that includes the
 * file and adds a body to the world. */
static int user_xml(const struct mj_plant *p, char *buf, size_t n,
                    const char *object)
{
    /* MuJoCo resolves the include beside the wrapper, which load_xml
     * names in the scene's folder. */
    const char *slash = strrchr(p->scene, '/');
    const char *f = slash ? slash + 1 : p->scene;
    char name[1024];
    size_t k = 0;
    int r;

    /* The file's name as an XML attribute: what XML quotes, quoted. */
    for (; *f; f++) {
        const char *e = *f == '&'    ? "&amp;"
                        : *f == '<'  ? "&lt;"
                        : *f == '>'  ? "&gt;"
                        : *f == '"'  ? "&quot;"
                        : *f == '\'' ? "&apos;"
                                     : NULL;
        size_t len = e ? strlen(e) : 1;

        if (k + len >= sizeof name)
            return -ENAMETOOLONG;
        memcpy(name + k, e ? e : f, len);
        k += len;
    }
    name[k] = '\0';
    r = snprintf(buf, n,
                 "<mujoco><include file=\"%s\"/><worldbody>%s</worldbody>"
                 "</mujoco>",
                 name, object);
    return r >= (int)n ? -ENAMETOOLONG : 0;
}

/* Compile xml into a model, through a virtual file named beside the
 * user's scene (so that its relative paths resolve as they would). */
static mjModel *load_xml(const struct mj_plant *p, const char *xml, char *err,
                         size_t errlen)
{
    static mjVFS vfs; /* large: not on the stack; only used here */
    char name[1024];
    mjModel *m;
    const char *slash = p->scene ? strrchr(p->scene, '/') : NULL;
    int len = (int)strlen(xml), i;

    if (slash)
        snprintf(name, sizeof name, "%.*s/wsg-scene.xml",
                 (int)(slash - p->scene), p->scene);
    else
        snprintf(name, sizeof name, "wsg-scene.xml");
    mj_defaultVFS(&vfs);
    if (mj_makeEmptyFileVFS(&vfs, name, len) != 0) {
        snprintf(err, errlen, "cannot make the scene's virtual file");
        return NULL;
    }
    i = mj_findFileVFS(&vfs, name);
    if (i < 0) {
        mj_deleteVFS(&vfs);
        snprintf(err, errlen, "cannot find the scene's virtual file");
        return NULL;
    }
    memcpy(vfs.filedata[i], xml, (size_t)len);
    m = mj_loadXML(name, &vfs, err, (int)errlen);
    mj_deleteVFS(&vfs);
    return m;
}

static int find_joint(const mjModel *m, const char *name, int *qa, int *da,
                      int *body, char *err, size_t errlen)
{
    int j = mj_name2id(m, mjOBJ_JOINT, name);

    if (j < 0) {
        snprintf(err, errlen, "the scene has no joint \"%s\"", name);
        return -ENOENT;
    }
    if (m->jnt_type[j] != mjJNT_SLIDE) {
        snprintf(err, errlen, "joint \"%s\" is not a slide joint", name);
        return -EINVAL;
    }
    *qa = m->jnt_qposadr[j];
    *da = m->jnt_dofadr[j];
    *body = m->jnt_bodyid[j];
    return 0;
}

/* (Re)build the model with the object now placed; the fingers keep their
 * travel and speed. */
static int rebuild(struct mj_plant *p, char *err, size_t errlen)
{
    char obj[1024], *xml;
    double pos[3] = {0, 0, -MJ_PAD_L / 2}, q[2] = {0, 0}, v[2] = {0, 0};
    mjModel *m;
    mjData *d;
    int r, k, qa[2], da[2], fb[2];

    xml = malloc(MJ_XML_MAX);
    if (!xml) {
        snprintf(err, errlen, "out of memory");
        return -ENOMEM;
    }
    if (p->d) {
        for (k = 0; k < 2; k++) {
            q[k] = p->d->qpos[p->qa[k]];
            v[k] = p->d->qvel[p->da[k]];
        }
        /* Between the pads' centres. */
        for (k = 0; k < 3; k++)
            pos[k] = 0.5 * (p->d->xpos[3 * p->fbody[0] + k] +
                            p->d->xpos[3 * p->fbody[1] + k]);
        if (!p->scene)
            pos[2] = -MJ_PAD_L / 2;
    }
    r = p->has_obj ? object_xml(p, obj, sizeof obj, pos) : 0;
    if (!p->has_obj)
        obj[0] = '\0';
    if (r == 0)
        r = p->scene ? user_xml(p, xml, MJ_XML_MAX, obj)
                     : builtin_xml(p, xml, MJ_XML_MAX, obj);
    if (r < 0) {
        free(xml);
        snprintf(err, errlen, "scene text too long");
        return r;
    }
    m = load_xml(p, xml, err, errlen);
    free(xml);
    if (!m)
        return -EINVAL;
    if ((r = find_joint(m, p->left, &qa[0], &da[0], &fb[0], err, errlen)) <
            0 ||
        (r = find_joint(m, p->right, &qa[1], &da[1], &fb[1], err, errlen)) <
            0) {
        mj_deleteModel(m);
        return r;
    }
    d = mj_makeData(m);
    if (!d) {
        mj_deleteModel(m);
        snprintf(err, errlen, "out of memory");
        return -ENOMEM;
    }
    if (p->d) {
        for (k = 0; k < 2; k++) {
            d->qpos[qa[k]] = q[k];
            d->qvel[da[k]] = v[k];
        }
        mj_deleteData(p->d);
        mj_deleteModel(p->m);
    } else {
        p->ts = m->opt.timestep;
    }
    p->m = m;
    p->d = d;
    memcpy(p->qa, qa, sizeof qa);
    memcpy(p->da, da, sizeof da);
    memcpy(p->fbody, fb, sizeof fb);
    p->obj_body = -1;
    if (p->has_obj) {
        int b = mj_name2id(m, mjOBJ_BODY, "wsg_object");
        int j = b >= 0 ? m->body_jntadr[b] : -1;
        p->obj_body = b;
        p->obj_qa = j >= 0 ? m->jnt_qposadr[j] : 0;
        p->obj_da = j >= 0 ? m->jnt_dofadr[j] : 0;
        p->hand = 1;
    }
    mj_forward(m, d);
    if (p->obj_body >= 0)
        memcpy(p->hand_pose, d->qpos + p->obj_qa, sizeof p->hand_pose);
    return 0;
}

/* The width (mm, physical) the joints make: the stroke minus both
 * travels. */
static double width_mm(const struct mj_plant *p)
{
    return (p->stroke - p->d->qpos[p->qa[0]] - p->d->qpos[p->qa[1]]) * 1e3;
}

/* Normal force (N) on finger k's body from its contacts, and the patch in
 * the pad's frame (x across: body y; y along the finger towards the tip:
 * body -z), in mm. */
static double pad_contact(const struct mj_plant *p, int k,
                          struct wsg_contact *c)
{
    const mjModel *m = p->m;
    mjData *d = p->d;
    double sum = 0.0, cx = 0.0, cy = 0.0, lo[2] = {1e9, 1e9},
           hi[2] = {-1e9, -1e9};
    int i, b = p->fbody[k];

    for (i = 0; i < d->ncon; i++) {
        const mjContact *con = &d->contact[i];
        double f[6], rel[3], loc[3];
        int g1 = m->geom_bodyid[con->geom1], g2 = m->geom_bodyid[con->geom2];
        if (g1 != b && g2 != b)
            continue;
        if (g1 == p->fbody[1 - k] || g2 == p->fbody[1 - k])
            continue;
        mj_contactForce(m, d, i, f);
        if (f[0] <= 0.0)
            continue;
        rel[0] = con->pos[0] - d->xpos[3 * b];
        rel[1] = con->pos[1] - d->xpos[3 * b + 1];
        rel[2] = con->pos[2] - d->xpos[3 * b + 2];
        mju_mulMatTVec(loc, d->xmat + 9 * b, rel, 3, 3);
        loc[2] += MJ_PAD_L / 2; /* from the pad's centre */
        sum += f[0];
        cx += f[0] * loc[1];
        cy += f[0] * -loc[2];
        lo[0] = fmin(lo[0], loc[1]);
        hi[0] = fmax(hi[0], loc[1]);
        lo[1] = fmin(lo[1], -loc[2]);
        hi[1] = fmax(hi[1], -loc[2]);
    }
    if (c) {
        memset(c, 0, sizeof *c);
        if (sum > 0.0) {
            c->force = sum;
            c->x = cx / sum * 1e3;
            c->y = cy / sum * 1e3;
            c->w = fmax((hi[0] - lo[0]) * 1e3, MJ_PATCH_MIN_MM);
            c->h = fmax((hi[1] - lo[1]) * 1e3, MJ_PATCH_MIN_MM);
        }
    }
    return sum;
}

/* The drive's force on finger k (N, along its travel) for command dr. */
static double drive_force(const struct mj_plant *p, const struct wsg_drive *dr,
                          int k)
{
    double q = p->d->qpos[p->qa[k]], qd = p->d->qvel[p->da[k]], f = dr->force;
    double x, qs, vs;

    if (dr->mode == WSG_DRIVE_OFF)
        return 0.0; /* motor off */
    x = clampd(dr->x - dr->offset, 0.0, p->stroke * 1e3);
    qs = (p->stroke - x * 1e-3) / 2.0;
    vs = -dr->v * 1e-3 / 2.0;
    return clampd(MJ_KP * (qs - q) + MJ_KD * (vs - qd), -f, f);
}

static void mj_step_plant(struct wsg_plant *pl, const struct wsg_drive *dr,
                          double dt)
{
    struct mj_plant *p = (struct mj_plant *)pl;
    int n, i, k;

    if (dt <= 0.0)
        return;
    /* Steps that make up dt exactly: an integer divisor of the model's
     * step, no longer than the scene's own. */
    n = (int)ceil(dt / p->ts - 1e-9);
    if (n < 1)
        n = 1;
    p->m->opt.timestep = dt / n;
    for (i = 0; i < n; i++) {
        for (k = 0; k < 2; k++)
            p->d->qfrc_applied[p->da[k]] = drive_force(p, dr, k);
        if (p->obj_body >= 0) {
            /* Someone holds the placed object still until both pads press
             * on it; the pull acts out of the fingers (down). */
            if (p->hand) {
                memcpy(p->d->qpos + p->obj_qa, p->hand_pose,
                       sizeof p->hand_pose);
                memset(p->d->qvel + p->obj_da, 0, 6 * sizeof(mjtNum));
            }
            p->d->xfrc_applied[6 * p->obj_body + 2] = -p->pull;
        }
        mj_step(p->m, p->d);
        if (p->hand && p->obj_body >= 0 && pad_contact(p, 0, NULL) > 0.0 &&
            pad_contact(p, 1, NULL) > 0.0)
            p->hand = 0;
    }
}

static void mj_sense(const struct wsg_plant *pl, const struct wsg_drive *dr,
                     struct wsg_plant_fingers *o)
{
    const struct mj_plant *p = (const struct mj_plant *)pl;
    double w = width_mm(p) + dr->offset, f[2], still = 1, sat = 1;
    double qd0 = p->d->qvel[p->da[0]], qd1 = p->d->qvel[p->da[1]];
    int k;

    for (k = 0; k < 2; k++) {
        f[k] = pad_contact(p, k, NULL);
        if (fabs(p->d->qvel[p->da[k]]) > MJ_V_STILL)
            still = 0;
    }
    o->width = w;
    /* Fingers that stand still read 0, as the gripper's speed does. */
    o->speed = still ? 0.0 : -(qd0 + qd1) * 1e3;
    o->force = 0.5 * (f[0] + f[1]);
    o->blocked = 0;
    switch (dr->mode) {
    case WSG_DRIVE_OFF:
        break;
    case WSG_DRIVE_RELAX:
        o->blocked = 1;
        break;
    case WSG_DRIVE_AT:
        /* Touching in dir, or at the joints' limit in dir. */
        o->blocked = dr->dir < 0
                         ? (f[0] > 0.0 && f[1] > 0.0) || w - dr->offset <= 1e-3
                         : w - dr->offset >= p->stroke * 1e3 - 1e-3;
        break;
    default:
        /* Held: both fingers still with the drive at its bound towards
         * the setpoint, or a final setpoint at the end stop reached. */
        for (k = 0; k < 2; k++) {
            double x = clampd(dr->x - dr->offset, 0.0, p->stroke * 1e3);
            double e = (p->stroke - x * 1e-3) / 2.0 - p->d->qpos[p->qa[k]];
            if (e * (dr->dir < 0 ? 1.0 : -1.0) * MJ_KP < 0.9 * dr->force)
                sat = 0;
        }
        if (dr->mode == WSG_DRIVE_CLAMP || dr->mode == WSG_DRIVE_PUSH)
            o->blocked = sat && fabs(qd0) < MJ_V_SLIP && fabs(qd1) < MJ_V_SLIP;
        else
            o->blocked = still && sat;
        if (dr->mode == WSG_DRIVE_MOVE && dr->end && still) {
            double end = dr->dir < 0 ? 0.0 : p->stroke * 1e3;
            if (fabs(dr->x - dr->offset - end) <= 1e-3 &&
                fabs(w - dr->offset - end) <= 0.1)
                o->blocked = 1;
        }
        if (o->blocked)
            o->speed = 0.0;
        break;
    }
}

static void mj_contact(const struct wsg_plant *pl, const struct wsg_drive *dr,
                       int finger, struct wsg_contact *c)
{
    (void)dr;
    pad_contact((const struct mj_plant *)pl, finger, c);
}

static int mj_place(struct wsg_plant *pl, const struct wsg_object *o)
{
    struct mj_plant *p = (struct mj_plant *)pl;
    struct wsg_object old = p->obj;
    int had = p->has_obj, r, i, n;
    char err[256];

    if (o->kind != WSG_OBJECT_NONE) {
        n = o->kind == WSG_OBJECT_BOX        ? 3
            : o->kind == WSG_OBJECT_CYLINDER ? 2
                                             : 1;
        for (i = 0; i < n; i++)
            if (!(o->size[i] > 0.0 && o->size[i] <= WSG_OBJECT_SIZE_MAX))
                return -ERANGE;
        if (!(o->mass > 0.0 && o->mass <= 100.0) ||
            !(o->friction >= 0.0 && o->friction <= 10.0))
            return -ERANGE;
    }
    p->obj = *o;
    p->has_obj = o->kind != WSG_OBJECT_NONE;
    p->pull = 0.0;
    r = rebuild(p, err, sizeof err);
    if (r < 0) {
        if (getenv("WSG_MJ_DEBUG"))
            fprintf(stderr, "place: %s\n", err);
        p->obj = old;
        p->has_obj = had;
        rebuild(p, err, sizeof err);
    }
    return r;
}

static int mj_object(const struct wsg_plant *pl, struct wsg_object *o)
{
    const struct mj_plant *p = (const struct mj_plant *)pl;

    int k;

    if (!p->has_obj)
        return 0;
    *o = p->obj;
    for (k = 0; k < 3; k++)
        o->pos[k] =
            p->obj_body >= 0 ? p->d->xpos[3 * p->obj_body + k] * 1e3 : 0.0;
    return 1;
}

static int mj_pull(struct wsg_plant *pl, double n)
{
    struct mj_plant *p = (struct mj_plant *)pl;

    if (!(n >= 0.0 && n <= 10000.0))
        return -ERANGE;
    if (!p->has_obj)
        return -ENOENT;
    p->pull = n;
    return 0;
}

static void mj_destroy(struct wsg_plant *pl)
{
    struct mj_plant *p = (struct mj_plant *)pl;

    if (!p)
        return;
    if (p->d)
        mj_deleteData(p->d);
    if (p->m)
        mj_deleteModel(p->m);
    free(p->scene);
    free(p);
}

static const struct wsg_plant_ops mj_ops = {
    "mujoco", mj_step_plant, mj_sense, mj_contact,
    mj_place, mj_object,     mj_pull,  mj_destroy};

/* Built as the daemon's module (mujoco_load.c), the version it checks. */
const char wsg_plant_mujoco_version[] = WSG_VERSION;

int wsg_plant_mujoco_available(void)
{
    return 1;
}

int wsg_plant_mujoco_open(struct wsg_plant **out,
                          const struct wsg_axis_config *cfg, const char *scene,
                          const char *left, const char *right, char *err,
                          size_t errlen)
{
    struct mj_plant *p = calloc(1, sizeof *p);
    int r;

    if (!p) {
        snprintf(err, errlen, "out of memory");
        return -ENOMEM;
    }
    p->base.ops = &mj_ops;
    p->stroke = cfg->stroke * 1e-3;
    p->obj_body = -1;
    p->ts = fmin(MJ_STEP_MAX, cfg->step_us * 1e-6 / 2.0);
    if (scene) {
        p->scene = strdup(scene);
        if (!p->scene) {
            free(p);
            return -ENOMEM;
        }
    }
    snprintf(p->left, sizeof p->left, "%s", left ? left : "wsg_left");
    snprintf(p->right, sizeof p->right, "%s", right ? right : "wsg_right");
    if ((left && strlen(left) >= sizeof p->left) ||
        (right && strlen(right) >= sizeof p->right)) {
        snprintf(err, errlen, "joint name too long");
        mj_destroy(&p->base);
        return -ENAMETOOLONG;
    }
    r = rebuild(p, err, errlen);
    if (r < 0) {
        mj_destroy(&p->base);
        return r;
    }
    /* Powered up, the fingers stand where they were left: mid-stroke, as
     * in the built-in plant. */
    p->d->qpos[p->qa[0]] = p->d->qpos[p->qa[1]] = p->stroke / 4.0;
    mj_forward(p->m, p->d);
    *out = &p->base;
    return 0;
}
