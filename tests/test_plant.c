/*
 * The MuJoCo plant (--physics mujoco) under the firmware, driven through
 * the command set with a fake clock: grasping a box, a cylinder and a
 * sphere (HOLDING, the width within WSG_PLANT_TOL_MM of the object's, the
 * force at the limit), no object (NO PART), a box wider than the window (a
 * collision), slip under a pull and under gravity with low friction (PART
 * LOST), what the pads feel, a scene of the test's own with other finger
 * joints, and determinism: two runs of the same commands give the same
 * numbers to the bit. Skips (77) in a build without MuJoCo.
 */
#define _GNU_SOURCE

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <unistd.h>

#include "tdev.h"
#include "wsg/plant.h"

/* How far the held width may lie from the object's (docs/plants.md): the
 * contact's softness under the force limit. */
#define WSG_PLANT_TOL_MM 0.5

static struct wsg_plant *plant_on(struct tdev *t, const char *scene,
                                  const char *left, const char *right)
{
    struct wsg_plant *p = NULL;
    char err[256] = "";
    int r = wsg_plant_mujoco_open(&p, wsg_axis_cfg(tdev_axis(t)), scene, left,
                                  right, err, sizeof err);

    if (r != 0)
        fprintf(stderr, "mujoco: %s\n", err);
    REQUIRE(r == 0);
    wsg_axis_set_plant(tdev_axis(t), p);
    return p;
}

static void place(struct wsg_plant *p, enum wsg_object_kind k, double a,
                  double b, double c, double kg, double mu)
{
    struct wsg_object o;

    memset(&o, 0, sizeof o);
    o.kind = k;
    o.size[0] = a;
    o.size[1] = b;
    o.size[2] = c;
    o.mass = kg;
    o.friction = mu;
    REQUIRE(p->ops->place(p, &o) == 0);
}

static uint16_t grasp(struct tdev *t, float width, float speed)
{
    tdev_clear(t);
    REQUIRE(tdev_cmd2f(t, WSG_CMD_GRASP, width, speed) == WSG_E_CMD_PENDING);
    return tdev_final(t, WSG_CMD_GRASP, 20000);
}

static uint16_t release(struct tdev *t, float width, float speed)
{
    tdev_clear(t);
    REQUIRE(tdev_cmd2f(t, WSG_CMD_RELEASE, width, speed) == WSG_E_CMD_PENDING);
    return tdev_final(t, WSG_CMD_RELEASE, 20000);
}

/* Open to width by a preposition (Release wants a part held). */
static uint16_t open_to(struct tdev *t, float width)
{
    long k;

    /* Fingers that snap on after a part lost finish that first. */
    for (k = 0; k < 5000 && wsg_axis_busy(tdev_axis(t)); k++)
        tdev_steps(t, 1);
    tdev_clear(t);
    REQUIRE(tdev_move(t, 0, width, 100) == WSG_E_CMD_PENDING);
    return tdev_final(t, WSG_CMD_PREPOSITION, 20000);
}

/* A fresh gripper on the built-in scene, homed open. */
static struct wsg_plant *start(struct tdev *t)
{
    struct wsg_plant *p;

    tdev_init(t);
    p = plant_on(t, NULL, NULL, NULL);
    tdev_clear(t);
    CHECK_EQ(tdev_home(t, WSG_HOME_POSITIVE), WSG_E_SUCCESS);
    CHECK(fabs(wsg_axis_width(tdev_axis(t)) - 110.0) < 0.05);
    return p;
}

static void held(struct tdev *t, double width, const char *what)
{
    struct wsg_axis *ax = tdev_axis(t);
    double w = wsg_axis_width(ax), f = wsg_axis_force(ax);

    fprintf(stderr, "%s: width %.3f force %.2f\n", what, w, f);
    CHECK_EQ(wsg_axis_grasp_state(ax), WSG_GS_HOLDING);
    CHECK(fabs(w - width) <= WSG_PLANT_TOL_MM);
    CHECK(fabs(f - wsg_axis_force_limit(ax)) <=
          0.1 * wsg_axis_force_limit(ax));
}

static void test_shapes(void)
{
    struct tdev t;
    struct wsg_plant *p = start(&t);

    place(p, WSG_OBJECT_BOX, 40, 20, 30, 0.1, 1.0);
    CHECK_EQ(grasp(&t, 40, 50), WSG_E_SUCCESS);
    tdev_steps(&t, 200);
    held(&t, 40, "box");
    CHECK_EQ(release(&t, 60, 50), WSG_E_SUCCESS);

    place(p, WSG_OBJECT_CYLINDER, 30, 40, 0, 0.1, 1.0);
    CHECK_EQ(grasp(&t, 30, 50), WSG_E_SUCCESS);
    tdev_steps(&t, 200);
    held(&t, 30, "cylinder");
    CHECK_EQ(release(&t, 60, 50), WSG_E_SUCCESS);

    place(p, WSG_OBJECT_SPHERE, 25, 0, 0, 0.05, 1.0);
    CHECK_EQ(grasp(&t, 25, 50), WSG_E_SUCCESS);
    tdev_steps(&t, 200);
    held(&t, 25, "sphere");
    p->ops->destroy(p);
}

/* Nothing in the window: the grasp closes through its clamping travel. A
 * box wider than the window stops the fingers before it: a collision. */
static void test_no_part(void)
{
    struct tdev t;
    struct wsg_plant *p = start(&t);

    CHECK_EQ(grasp(&t, 40, 50), WSG_E_CMD_FAILED);
    CHECK_EQ(wsg_axis_grasp_state(tdev_axis(&t)), WSG_GS_NO_PART);
    CHECK(!wsg_axis_grasp_collided(tdev_axis(&t)));
    CHECK_EQ(open_to(&t, 100), WSG_E_SUCCESS);
    place(p, WSG_OBJECT_BOX, 80, 20, 30, 0.1, 1.0);
    CHECK_EQ(grasp(&t, 40, 50), WSG_E_CMD_FAILED);
    CHECK_EQ(wsg_axis_grasp_state(tdev_axis(&t)), WSG_GS_NO_PART);
    CHECK(wsg_axis_grasp_collided(tdev_axis(&t)));
    p->ops->destroy(p);
}

/* Held with too little force for the pull (or the weight, on a slippery
 * part), the part slips out: PART LOST, counted. */
static void test_slip(void)
{
    struct tdev t;
    struct wsg_plant *p = start(&t);
    struct wsg_axis *ax = tdev_axis(&t);
    long k;

    place(p, WSG_OBJECT_BOX, 40, 20, 30, 0.1, 1.0);
    CHECK_EQ(grasp(&t, 40, 50), WSG_E_SUCCESS);
    tdev_steps(&t, 500);
    CHECK_EQ(wsg_axis_grasp_state(ax), WSG_GS_HOLDING);
    /* 40 N on each pad, friction 1: some 80 N hold it. */
    REQUIRE(p->ops->pull(p, 20.0) == 0);
    tdev_steps(&t, 500);
    CHECK_EQ(wsg_axis_grasp_state(ax), WSG_GS_HOLDING);
    REQUIRE(p->ops->pull(p, 200.0) == 0);
    for (k = 0; k < 2000 && wsg_axis_grasp_state(ax) == WSG_GS_HOLDING; k++)
        tdev_steps(&t, 1);
    CHECK_EQ(wsg_axis_grasp_state(ax), WSG_GS_PART_LOST);
    CHECK_EQ(wsg_axis_stats(ax).lost_part, 1);
    CHECK_EQ(open_to(&t, 100), WSG_E_SUCCESS);

    /* 5 N on pads with friction 0.01: a 1 kg part falls out. */
    tdev_clear(&t);
    REQUIRE(tdev_cmd1f(&t, WSG_CMD_SET_FORCE_LIMIT, 5.0f) == WSG_E_SUCCESS);
    place(p, WSG_OBJECT_BOX, 40, 20, 30, 1.0, 0.01);
    CHECK_EQ(grasp(&t, 40, 50), WSG_E_SUCCESS);
    for (k = 0; k < 3000 && wsg_axis_grasp_state(ax) == WSG_GS_HOLDING; k++)
        tdev_steps(&t, 1);
    CHECK_EQ(wsg_axis_grasp_state(ax), WSG_GS_PART_LOST);
    p->ops->destroy(p);
}

/* Each pad feels the part: force near the grip, a patch of the box's
 * face in size. */
static void test_contact(void)
{
    struct tdev t;
    struct wsg_plant *p = start(&t);
    struct wsg_contact c[2];
    int k;

    place(p, WSG_OBJECT_BOX, 40, 10, 20, 0.1, 1.0);
    CHECK_EQ(grasp(&t, 40, 50), WSG_E_SUCCESS);
    tdev_steps(&t, 300);
    for (k = 0; k < 2; k++) {
        REQUIRE(wsg_axis_contact(tdev_axis(&t), k, &c[k]) == 0);
        fprintf(stderr, "pad %d: %.2f N at %.2f,%.2f, %.2f x %.2f mm\n", k,
                c[k].force, c[k].x, c[k].y, c[k].w, c[k].h);
        CHECK(fabs(c[k].force - 40.0) <= 4.0);
        CHECK(fabs(c[k].w - 10.0) <= 1.0 && fabs(c[k].h - 20.0) <= 1.0);
        CHECK(fabs(c[k].x) <= 1.0 && fabs(c[k].y) <= 1.0);
    }
    p->ops->destroy(p);
}

/* The same commands give the same numbers, to the bit. */
static void run_once(double out[3])
{
    struct tdev t;
    struct wsg_plant *p = start(&t);

    place(p, WSG_OBJECT_CYLINDER, 30, 40, 0, 0.2, 0.8);
    CHECK_EQ(grasp(&t, 30, 80), WSG_E_SUCCESS);
    tdev_steps(&t, 123);
    out[0] = wsg_axis_width(tdev_axis(&t));
    out[1] = wsg_axis_force(tdev_axis(&t));
    out[2] = (double)wsg_axis_time(tdev_axis(&t));
    p->ops->destroy(p);
}

static void test_determinism(void)
{
    double a[3], b[3];

    run_once(a);
    run_once(b);
    CHECK(memcmp(a, b, sizeof a) == 0);
}

/* A scene of the test's own: fingers on joints of other names, a wider
 * pad, no actuators. */
static void test_own_scene(void)
{
    static const char xml[] =
        "<mujoco><option timestep=\"0.0005\"/><worldbody>"
        "<body name=\"a\" pos=\"-0.055 0 0\"><joint name=\"jl\" "
        "type=\"slide\" axis=\"1 0 0\" limited=\"true\" range=\"0 "
        "0.055\" armature=\"0.5\"/><geom type=\"box\" pos=\"-0.003 0 "
        "-0.02\" size=\"0.003 0.015 0.02\" mass=\"0.1\" friction=\"0.01\" "
        "solref=\"0.002 1\" "
        "solimp=\"0.95 0.99 0.0002\" "
        "contype=\"1\" conaffinity=\"2\"/></body>"
        "<body name=\"b\" pos=\"0.055 0 0\"><joint name=\"jr\" "
        "type=\"slide\" axis=\"-1 0 0\" limited=\"true\" range=\"0 "
        "0.055\" armature=\"0.5\"/><geom type=\"box\" pos=\"0.003 0 "
        "-0.02\" size=\"0.003 0.015 0.02\" mass=\"0.1\" friction=\"0.01\" "
        "solref=\"0.002 1\" "
        "solimp=\"0.95 0.99 0.0002\" "
        "contype=\"1\" conaffinity=\"2\"/></body>"
        "</worldbody></mujoco>";
    char path[] = "/tmp/wsg-scene-XXXXXX";
    struct tdev t;
    struct wsg_plant *p;
    int fd = mkstemp(path);

    REQUIRE(fd >= 0);
    REQUIRE(write(fd, xml, sizeof xml - 1) == (ssize_t)(sizeof xml - 1));
    close(fd);
    tdev_init(&t);
    p = plant_on(&t, path, "jl", "jr");
    tdev_clear(&t);
    CHECK_EQ(tdev_home(&t, WSG_HOME_POSITIVE), WSG_E_SUCCESS);
    place(p, WSG_OBJECT_BOX, 50, 20, 30, 0.1, 1.0);
    CHECK_EQ(grasp(&t, 50, 50), WSG_E_SUCCESS);
    tdev_steps(&t, 200);
    held(&t, 50, "own scene box");
    p->ops->destroy(p);
    unlink(path);
}

int main(void)
{
    if (!wsg_plant_mujoco_available()) {
        fprintf(stderr, "built without MuJoCo: skipped\n");
        return 77;
    }
    test_shapes();
    test_no_part();
    test_slip();
    test_contact();
    test_determinism();
    test_own_scene();
    TEST_EXIT();
}
