/*
 * The gripper model driven by a fake clock: motion durations against the
 * trapezoid computed here independently, homing, grasping a part (held, no
 * part, part lost, force build-up), clamp and stop on block, soft limits,
 * FAST STOP, overdrive, and the system state flags at every stage; the
 * model's ranges of the values it takes (config settings, widths); what
 * scripts drive directly: speed mode, motions replacing running ones,
 * pressing, a grasp's own window.
 */
#include <errno.h>

#include "axis_impl.h"
#include "tdev.h"

/* Duration of a rest-to-rest move of d mm at vmax and acc. */
static double trapezoid_s(double d, double vmax, double acc)
{
    if (d * acc >= vmax * vmax)
        return d / vmax + vmax / acc;
    return 2.0 * sqrt(d / acc);
}

/* Steps from the command to its final result, minus the step that starts
 * the motion, in seconds. */
static double timed_move(struct tdev *t, float width, float speed)
{
    long k;

    REQUIRE(tdev_move(t, 0, width, speed) == WSG_E_CMD_PENDING);
    k = tdev_run_until(t, 0, WSG_CMD_PREPOSITION, 100000);
    REQUIRE(k > 0);
    CHECK_EQ(tdev_last(t)->status, WSG_E_SUCCESS);
    return (double)k * tdev_axis(t)->cfg.step_us * 1e-6;
}

/* A model on its own, as a script host drives it: requests and settles
 * directly, final results recorded here. */
struct rec {
    int n;
    uint32_t tag[16];
    uint8_t id[16];
    uint16_t status[16];
};

static void rec_done(void *ctx, uint32_t tag, uint8_t cmd_id, uint16_t status)
{
    struct rec *r = ctx;

    REQUIRE(r->n < 16);
    r->tag[r->n] = tag;
    r->id[r->n] = cmd_id;
    r->status[r->n] = status;
    r->n++;
}

/* A WSG 50 homed open, its results going to r. */
static void bare_init(struct wsg_axis *ax, struct rec *r)
{
    struct wsg_axis_config cfg;

    REQUIRE(wsg_axis_config_init(&cfg, "wsg50") == 0);
    memset(r, 0, sizeof *r);
    wsg_axis_init(ax, &cfg, rec_done, r);
    REQUIRE(wsg_axis_request_homing(ax, WSG_HOME_POSITIVE, 9) ==
            WSG_E_CMD_PENDING);
    while (r->n == 0 && ax->time_us < 10000000u)
        wsg_axis_step(ax);
    REQUIRE(r->n == 1 && r->status[0] == WSG_E_SUCCESS);
    r->n = 0;
}

static void bare_steps(struct wsg_axis *ax, long n)
{
    while (n-- > 0)
        wsg_axis_step(ax);
}

static void test_durations(void)
{
    struct tdev t;
    double dt;

    tdev_init(&t);
    CHECK_EQ(tdev_home(&t, 0), WSG_E_SUCCESS);
    dt = tdev_axis(&t)->cfg.step_us * 1e-6;
    /* 110 -> 10 at 100 mm/s, 150 mm/s^2: reaches vmax */
    CHECK_NEAR(timed_move(&t, 10.0f, 100.0f), trapezoid_s(100.0, 100.0, 150.0),
               dt);
    /* 10 -> 15 at 400 mm/s: triangular */
    CHECK_NEAR(timed_move(&t, 15.0f, 400.0f), trapezoid_s(5.0, 400.0, 150.0),
               dt);
    /* with a higher acceleration */
    CHECK_EQ(tdev_cmd1f(&t, WSG_CMD_SET_ACCELERATION, 2000.0f), WSG_E_SUCCESS);
    CHECK_NEAR(timed_move(&t, 95.0f, 300.0f), trapezoid_s(80.0, 300.0, 2000.0),
               dt);
    /* speed below the minimum is clamped to 5 mm/s */
    CHECK_NEAR(timed_move(&t, 94.0f, 0.0f), trapezoid_s(1.0, 5.0, 2000.0), dt);

    /* the same with a coarser step */
    {
        struct wsg_axis_config cfg;
        REQUIRE(wsg_axis_config_init(&cfg, "wsg50") == 0);
        cfg.step_us = 5000;
        tdev_init_cfg(&t, &cfg);
        CHECK_EQ(tdev_home(&t, 0), WSG_E_SUCCESS);
        CHECK_NEAR(timed_move(&t, 30.0f, 80.0f),
                   trapezoid_s(80.0, 80.0, 150.0), 0.005);
    }
}

static void test_motion_values(void)
{
    struct tdev t;
    double width_before;
    int i;

    tdev_init(&t);
    CHECK_EQ(tdev_home(&t, 0), WSG_E_SUCCESS);
    CHECK_EQ(tdev_move(&t, 0, 10.0f, 50.0f), WSG_E_CMD_PENDING);
    tdev_steps(&t, 1);
    CHECK(tdev_flags(&t) & WSG_SF_MOVING);
    CHECK_EQ(tdev_grasp_state(&t), WSG_GS_POSITIONING);
    /* accelerating at 150 mm/s^2 for 0.2 s: speed 30 mm/s, closing */
    tdev_steps(&t, 199);
    CHECK_NEAR(tdev_getf(&t, WSG_CMD_GET_SPEED), -30.0, 1e-3);
    CHECK_NEAR(tdev_getf(&t, WSG_CMD_GET_WIDTH), 110.0 - 0.5 * 150 * 0.04,
               1e-3);
    /* cruising: the commanded speed, monotonically closing */
    tdev_steps(&t, 400);
    CHECK_NEAR(tdev_getf(&t, WSG_CMD_GET_SPEED), -50.0, 1e-3);
    for (i = 0; i < 10; i++) {
        width_before = tdev_axis(&t)->width;
        tdev_steps(&t, 1);
        CHECK(tdev_axis(&t)->width < width_before);
    }
    CHECK_EQ(tdev_getf(&t, WSG_CMD_GET_FORCE), 0.0f); /* free motion */
    CHECK_EQ(tdev_final(&t, WSG_CMD_PREPOSITION, 10000), WSG_E_SUCCESS);
    CHECK_EQ(tdev_getf(&t, WSG_CMD_GET_SPEED), 0.0f);
    CHECK(!(tdev_flags(&t) & WSG_SF_MOVING));
    CHECK_EQ(tdev_grasp_state(&t), WSG_GS_IDLE);
}

static void test_homing_time(void)
{
    struct tdev t;
    long k;

    /* from fully closed to the open end stop, at the slowest acceleration:
     * well within 4 s */
    tdev_init(&t);
    tdev_axis(&t)->width = 0.0;
    CHECK_EQ(tdev_cmd1f(&t, WSG_CMD_SET_ACCELERATION, 100.0f), WSG_E_SUCCESS);
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_HOMING, "\x01", 1), WSG_E_CMD_PENDING);
    tdev_steps(&t, 1);
    CHECK(tdev_flags(&t) & WSG_SF_MOVING);
    CHECK(!(tdev_flags(&t) & WSG_SF_REFERENCED));
    k = tdev_run_until(&t, 0, WSG_CMD_HOMING, 4000);
    CHECK(k > 0 && k < 4000);
    CHECK_EQ(tdev_last(&t)->status, WSG_E_SUCCESS);
    CHECK_EQ(tdev_flags(&t), WSG_SF_REFERENCED);
    CHECK_NEAR(tdev_axis(&t)->width, 110.0, 1e-9);

    /* every model homes within 4 s from the far end */
    {
        const char *models[] = {"wsg50-210", "wsg32", "wsg25"};
        struct wsg_axis_config cfg;
        size_t i;
        for (i = 0; i < 3; i++) {
            REQUIRE(wsg_axis_config_init(&cfg, models[i]) == 0);
            tdev_init_cfg(&t, &cfg);
            tdev_axis(&t)->width = 0.0;
            CHECK_EQ(tdev_cmd(&t, WSG_CMD_HOMING, "\x00", 1),
                     WSG_E_CMD_PENDING);
            k = tdev_run_until(&t, 0, WSG_CMD_HOMING, 4000);
            CHECK(k > 0);
            CHECK_NEAR(tdev_axis(&t)->width, cfg.stroke, 1e-9);
        }
    }
    CHECK_EQ(wsg_axis_config_init(&(struct wsg_axis_config){0}, "wsg99"),
             -EINVAL);
}

static void test_grasp_hold(void)
{
    struct tdev t;
    double prev = 0;
    int rising = 1, i;

    tdev_init(&t);
    CHECK_EQ(tdev_home(&t, 0), WSG_E_SUCCESS);
    wsg_axis_set_part(tdev_axis(&t), 40.0, 10.0); /* soft: 10 N/mm */
    CHECK_EQ(tdev_cmd2f(&t, WSG_CMD_GRASP, 40.0f, 100.0f), WSG_E_CMD_PENDING);
    tdev_steps(&t, 1);
    CHECK_EQ(tdev_grasp_state(&t), WSG_GS_GRASPING);
    /* run to first contact, then watch the force build up */
    for (i = 0; i < 3000 && tdev_axis(&t)->width > 40.0; i++)
        tdev_steps(&t, 1);
    for (i = 0; i < 3000 && tdev_axis(&t)->motion.kind; i++) {
        tdev_steps(&t, 1);
        if (tdev_axis(&t)->force < prev)
            rising = 0;
        prev = tdev_axis(&t)->force;
    }
    CHECK(rising);
    CHECK(i > 5); /* took several steps, did not jump */
    CHECK_EQ(tdev_last(&t)->id, WSG_CMD_GRASP);
    CHECK_EQ(tdev_last(&t)->status, WSG_E_SUCCESS);
    CHECK_EQ(tdev_grasp_state(&t), WSG_GS_HOLDING);
    /* held with the force limit, 4 mm into a 10 N/mm part */
    CHECK_NEAR(tdev_getf(&t, WSG_CMD_GET_FORCE), 40.0, 1e-3);
    CHECK_NEAR(tdev_getf(&t, WSG_CMD_GET_WIDTH), 36.0, 1e-3);
    CHECK_EQ(tdev_flags(&t), WSG_SF_REFERENCED | WSG_SF_BLOCKED_MINUS |
                                 WSG_SF_TARGET_POS_REACHED);
    /* holding is not moving: steps change nothing */
    CHECK(wsg_device_idle(&t.dev));
    tdev_steps(&t, 100);
    CHECK_NEAR(tdev_axis(&t)->width, 36.0, 1e-9);
    /* each pad feels the grip force over the part's patch, centred */
    {
        struct wsg_contact c;
        CHECK_EQ(wsg_axis_contact(tdev_axis(&t), 0, &c), 0);
        CHECK_NEAR(c.force, 40.0, 1e-3);
        CHECK_NEAR(c.w, WSG_AXIS_PATCH_MM, 1e-9);
        CHECK_NEAR(c.h, WSG_AXIS_PATCH_MM, 1e-9);
        CHECK_NEAR(c.x, 0.0, 1e-9);
        wsg_axis_set_part_patch(tdev_axis(&t), 4.0, 8.0);
        CHECK_EQ(wsg_axis_contact(tdev_axis(&t), 1, &c), 0);
        CHECK_NEAR(c.force, 40.0, 1e-3);
        CHECK_NEAR(c.w, 4.0, 1e-9);
        CHECK_NEAR(c.h, 8.0, 1e-9);
        CHECK_EQ(wsg_axis_contact(tdev_axis(&t), 2, &c), -EINVAL);
    }

    /* the part is removed: lost, the fingers close through the clamping
     * travel, statistics count it */
    wsg_axis_set_part(tdev_axis(&t), -1.0, 0);
    CHECK(!wsg_device_idle(&t.dev));
    tdev_steps(&t, 1);
    CHECK_EQ(tdev_grasp_state(&t), WSG_GS_PART_LOST);
    CHECK(tdev_flags(&t) & WSG_SF_MOVING);
    {
        struct wsg_contact c;
        CHECK_EQ(wsg_axis_contact(tdev_axis(&t), 0, &c), 0);
        CHECK_EQ(c.force, 0.0); /* nothing touches the pads */
        CHECK_EQ(c.w, 0.0);
    }
    CHECK(!(tdev_flags(&t) & WSG_SF_BLOCKED_MINUS));
    tdev_steps(&t, 2000);
    CHECK_NEAR(tdev_axis(&t)->width, 30.0, 1e-9); /* 40 - 10 mm travel */
    CHECK_EQ(tdev_axis(&t)->force, 0.0);
    CHECK_EQ(tdev_grasp_state(&t), WSG_GS_PART_LOST);
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_GET_GRASP_STATS, NULL, 0), WSG_E_SUCCESS);
    CHECK_EQ(wsg_get_u32(tdev_last(&t)->params), 1);
    CHECK_EQ(wsg_get_u16(tdev_last(&t)->params + 4), 0);
    CHECK_EQ(wsg_get_u16(tdev_last(&t)->params + 6), 1);
    /* part lost stays until the next grasp or release */
    CHECK_EQ(tdev_cmd2f(&t, WSG_CMD_RELEASE, 50.0f, 100.0f),
             WSG_E_CMD_PENDING);
    tdev_steps(&t, 1);
    CHECK_EQ(tdev_grasp_state(&t), WSG_GS_RELEASING);
    CHECK_EQ(tdev_final(&t, WSG_CMD_RELEASE, 4000), WSG_E_SUCCESS);
    CHECK_EQ(tdev_grasp_state(&t), WSG_GS_IDLE);
}

static void test_grasp_no_part(void)
{
    struct tdev t;

    tdev_init(&t);
    CHECK_EQ(tdev_home(&t, 0), WSG_E_SUCCESS);
    /* nothing there: the fingers fall through the clamping travel */
    CHECK_EQ(tdev_cmd2f(&t, WSG_CMD_GRASP, 40.0f, 100.0f), WSG_E_CMD_PENDING);
    CHECK_EQ(tdev_final(&t, WSG_CMD_GRASP, 4000), WSG_E_CMD_FAILED);
    CHECK_EQ(tdev_grasp_state(&t), WSG_GS_NO_PART);
    CHECK_NEAR(tdev_axis(&t)->width, 30.0, 1e-9);
    CHECK(!(tdev_flags(&t) & WSG_SF_TARGET_POS_REACHED));

    /* a part much wider than expected blocks outside the window */
    CHECK_EQ(tdev_cmd2f(&t, WSG_CMD_RELEASE, 100.0f, 400.0f),
             WSG_E_CMD_PENDING);
    CHECK_EQ(tdev_final(&t, WSG_CMD_RELEASE, 4000), WSG_E_SUCCESS);
    wsg_axis_set_part(tdev_axis(&t), 80.0, 0);
    CHECK_EQ(tdev_cmd2f(&t, WSG_CMD_GRASP, 40.0f, 100.0f), WSG_E_CMD_PENDING);
    CHECK_EQ(tdev_final(&t, WSG_CMD_GRASP, 4000), WSG_E_CMD_FAILED);
    CHECK_EQ(tdev_grasp_state(&t), WSG_GS_NO_PART);
    CHECK(tdev_axis(&t)->width > 79.0);

    /* within the tolerance above the nominal width: held */
    CHECK_EQ(tdev_cmd2f(&t, WSG_CMD_GRASP, 75.0f, 100.0f), WSG_E_CMD_PENDING);
    CHECK_EQ(tdev_final(&t, WSG_CMD_GRASP, 4000), WSG_E_SUCCESS);
    CHECK_EQ(tdev_grasp_state(&t), WSG_GS_HOLDING);
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_GET_GRASP_STATS, NULL, 0), WSG_E_SUCCESS);
    CHECK_EQ(wsg_get_u32(tdev_last(&t)->params), 3);
    CHECK_EQ(wsg_get_u16(tdev_last(&t)->params + 4), 2);
    /* Stop while holding: idle, the force goes */
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_STOP, NULL, 0), WSG_E_SUCCESS);
    tdev_steps(&t, 1);
    CHECK_EQ(tdev_grasp_state(&t), WSG_GS_IDLE);
    CHECK_EQ(tdev_axis(&t)->force, 0.0);
    CHECK(tdev_flags(&t) & WSG_SF_AXIS_STOPPED);
}

static void test_block(void)
{
    struct tdev t;

    tdev_init(&t);
    CHECK_EQ(tdev_home(&t, 0), WSG_E_SUCCESS);
    wsg_axis_set_part(tdev_axis(&t), 50.0, 0); /* default 50 N/mm */
    /* clamp on block: E_AXIS_BLOCKED, keeps the force limit */
    CHECK_EQ(tdev_move(&t, 0, 20.0f, 100.0f), WSG_E_CMD_PENDING);
    CHECK_EQ(tdev_final(&t, WSG_CMD_PREPOSITION, 4000), WSG_E_AXIS_BLOCKED);
    CHECK_NEAR(tdev_axis(&t)->width, 50.0 - 40.0 / 50.0, 1e-9);
    CHECK_NEAR(tdev_getf(&t, WSG_CMD_GET_FORCE), 40.0, 1e-3);
    CHECK(tdev_flags(&t) & WSG_SF_BLOCKED_MINUS);
    CHECK(!(tdev_flags(&t) & WSG_SF_MOVING));
    /* the block goes: the fingers snap to the target, no further reply */
    wsg_axis_set_part(tdev_axis(&t), -1, 0);
    tdev_clear(&t);
    tdev_steps(&t, 2000);
    CHECK_NEAR(tdev_axis(&t)->width, 20.0, 1e-9);
    CHECK_EQ(t.sess[0].n, 0);
    CHECK(!(tdev_flags(&t) & WSG_SF_BLOCKED_MINUS));

    /* stop on block: the motor stops, no force */
    CHECK_EQ(tdev_move(&t, 0, 90.0f, 400.0f), WSG_E_CMD_PENDING);
    CHECK_EQ(tdev_final(&t, WSG_CMD_PREPOSITION, 4000), WSG_E_SUCCESS);
    wsg_axis_set_part(tdev_axis(&t), 50.0, 0);
    CHECK_EQ(tdev_move(&t, WSG_MOVE_STOP_ON_BLOCK, 20.0f, 100.0f),
             WSG_E_CMD_PENDING);
    CHECK_EQ(tdev_final(&t, WSG_CMD_PREPOSITION, 4000), WSG_E_AXIS_BLOCKED);
    CHECK_EQ(tdev_getf(&t, WSG_CMD_GET_FORCE), 0.0f);
    CHECK(tdev_flags(&t) & WSG_SF_BLOCKED_MINUS);
    wsg_axis_set_part(tdev_axis(&t), -1, 0);
    tdev_steps(&t, 2000);
    CHECK_NEAR(tdev_axis(&t)->width, 50.0 - 40.0 / 50.0, 1e-9); /* stays */
}

static void test_soft_limits(void)
{
    struct tdev t;

    tdev_init(&t);
    CHECK_EQ(tdev_home(&t, 0), WSG_E_SUCCESS);
    /* outside the range after setting: the flag, and moving out only */
    CHECK_EQ(tdev_cmd2f(&t, WSG_CMD_SET_SOFT_LIMITS, 20.0f, 100.0f),
             WSG_E_SUCCESS);
    CHECK(tdev_flags(&t) & WSG_SF_SOFT_LIMIT_PLUS);
    CHECK(!(tdev_flags(&t) & WSG_SF_SOFT_LIMIT_MINUS));
    CHECK_EQ(tdev_move(&t, 0, 105.0f, 50.0f), WSG_E_RANGE_ERROR);
    CHECK_EQ(tdev_move(&t, 0, 60.0f, 100.0f), WSG_E_CMD_PENDING);
    CHECK_EQ(tdev_final(&t, WSG_CMD_PREPOSITION, 4000), WSG_E_SUCCESS);
    CHECK(!(tdev_flags(&t) & WSG_SF_SOFT_LIMIT_PLUS));
    /* a grasp whose clamping travel runs into the restricted area with no
     * part: FAST STOP at the limit (3.3.5) */
    CHECK_EQ(tdev_cmd2f(&t, WSG_CMD_GRASP, 25.0f, 100.0f), WSG_E_CMD_PENDING);
    CHECK_EQ(tdev_final(&t, WSG_CMD_GRASP, 4000), WSG_E_RANGE_ERROR);
    CHECK_NEAR(tdev_axis(&t)->width, 20.0, 1e-9);
    CHECK_EQ(tdev_flags(&t), WSG_SF_REFERENCED | WSG_SF_SOFT_LIMIT_MINUS |
                                 WSG_SF_FAST_STOP | WSG_SF_CMD_FAILURE);
    CHECK_EQ(tdev_move(&t, 0, 60.0f, 100.0f), WSG_E_ACCESS_DENIED);
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_ACK_FAST_STOP, "ack", 3), WSG_E_SUCCESS);
    tdev_steps(&t, 1);
    CHECK_EQ(tdev_move(&t, 0, 60.0f, 100.0f), WSG_E_CMD_PENDING);
    CHECK_EQ(tdev_final(&t, WSG_CMD_PREPOSITION, 4000), WSG_E_SUCCESS);
    /* homing ignores soft limits */
    CHECK_EQ(tdev_home(&t, 2), WSG_E_SUCCESS);
    CHECK_NEAR(tdev_axis(&t)->width, 0.0, 1e-9);
    CHECK(!(tdev_flags(&t) & WSG_SF_FAST_STOP));
}

static void test_overdrive(void)
{
    struct tdev t;
    uint8_t on = 1;

    tdev_init(&t);
    CHECK_EQ(tdev_home(&t, 0), WSG_E_SUCCESS);
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_OVERDRIVE, &on, 1), WSG_E_SUCCESS);
    CHECK_EQ(tdev_cmd1f(&t, WSG_CMD_SET_FORCE_LIMIT, 500.0f), WSG_E_SUCCESS);
    wsg_axis_set_part(tdev_axis(&t), 60.0, 0);
    CHECK_EQ(tdev_cmd2f(&t, WSG_CMD_GRASP, 60.0f, 100.0f), WSG_E_CMD_PENDING);
    CHECK_EQ(tdev_final(&t, WSG_CMD_GRASP, 4000), WSG_E_SUCCESS);
    CHECK_NEAR(tdev_getf(&t, WSG_CMD_GET_FORCE), 120.0, 1e-3);
    CHECK_EQ(tdev_flags(&t), WSG_SF_REFERENCED | WSG_SF_BLOCKED_MINUS |
                                 WSG_SF_TARGET_POS_REACHED |
                                 WSG_SF_OVERDRIVE_MODE);
}

static void test_faults(void)
{
    struct tdev t;

    tdev_init(&t);
    CHECK_EQ(tdev_home(&t, 0), WSG_E_SUCCESS);
    /* a temperature fault disables movement; a warning does not */
    wsg_axis_set_fault(tdev_axis(&t), WSG_SF_TEMP_WARNING, 1);
    CHECK(tdev_flags(&t) & WSG_SF_TEMP_WARNING);
    CHECK_EQ(tdev_move(&t, 0, 50.0f, 100.0f), WSG_E_CMD_PENDING);
    CHECK_EQ(tdev_final(&t, WSG_CMD_PREPOSITION, 4000), WSG_E_SUCCESS);
    wsg_axis_set_fault(tdev_axis(&t), WSG_SF_TEMP_FAULT, 1);
    CHECK_EQ(tdev_move(&t, 0, 60.0f, 100.0f), WSG_E_ACCESS_DENIED);
    wsg_axis_set_fault(tdev_axis(&t), WSG_SF_TEMP_FAULT | WSG_SF_TEMP_WARNING,
                       0);
    CHECK_EQ(tdev_flags(&t) & WSG_FAULTS, 0);
    CHECK_EQ(tdev_move(&t, 0, 60.0f, 100.0f), WSG_E_CMD_PENDING);
}

static void test_obstacle(void)
{
    struct tdev t;

    tdev_init(&t);
    CHECK_EQ(tdev_home(&t, 0), WSG_E_SUCCESS);
    /* Rigid, either way: a closing move blocks at it, clamping with the
     * force limit; an opening one from below blocks at it too. */
    wsg_axis_set_obstacle(tdev_axis(&t), 60.0);
    CHECK_EQ(tdev_move(&t, 0, 20.0f, 100.0f), WSG_E_CMD_PENDING);
    CHECK_EQ(tdev_final(&t, WSG_CMD_PREPOSITION, 4000), WSG_E_AXIS_BLOCKED);
    CHECK_NEAR(tdev_axis(&t)->width, 60.0, 1e-9);
    CHECK_NEAR(tdev_getf(&t, WSG_CMD_GET_FORCE), 40.0, 1e-3);
    CHECK(tdev_flags(&t) & WSG_SF_BLOCKED_MINUS);
    CHECK(wsg_device_idle(&t.dev));
    /* Taken away: the clamp snaps on to its target. */
    wsg_axis_set_obstacle(tdev_axis(&t), -1.0);
    CHECK(!wsg_device_idle(&t.dev));
    tdev_steps(&t, 3000);
    CHECK_NEAR(tdev_axis(&t)->width, 20.0, 1e-9);
    wsg_axis_set_obstacle(tdev_axis(&t), 50.0);
    CHECK_EQ(tdev_move(&t, WSG_MOVE_STOP_ON_BLOCK, 90.0f, 100.0f),
             WSG_E_CMD_PENDING);
    CHECK_EQ(tdev_final(&t, WSG_CMD_PREPOSITION, 4000), WSG_E_AXIS_BLOCKED);
    CHECK_NEAR(tdev_axis(&t)->width, 50.0, 1e-9);
    CHECK(tdev_flags(&t) & WSG_SF_BLOCKED_PLUS);
    CHECK_EQ(tdev_getf(&t, WSG_CMD_GET_FORCE), 0.0f);
    /* The nearest block counts: a part behind the obstacle is not felt. */
    wsg_axis_set_part(tdev_axis(&t), 30.0, 0);
    CHECK_EQ(tdev_cmd2f(&t, WSG_CMD_GRASP, 30.0f, 100.0f), WSG_E_CMD_PENDING);
    CHECK_EQ(tdev_final(&t, WSG_CMD_GRASP, 4000), WSG_E_CMD_FAILED);
    CHECK_NEAR(tdev_axis(&t)->width, 50.0, 1e-9); /* outside the window */
}

/* 3.2.1: homing into an obstacle takes the blocking position as origin,
 * a wrong reference; homing again without it puts things right. */
static void test_homing_into_obstacle(void)
{
    struct tdev t;

    tdev_init(&t);
    wsg_axis_set_obstacle(tdev_axis(&t), 80.0);
    CHECK_EQ(tdev_home(&t, 1), WSG_E_SUCCESS);
    /* It believes it is open at 110 mm, 30 mm off. */
    CHECK_NEAR(tdev_getf(&t, WSG_CMD_GET_WIDTH), 110.0, 1e-3);
    wsg_axis_set_obstacle(tdev_axis(&t), -1.0);
    /* A part of 40 mm is met where the gripper believes 70 mm is. */
    wsg_axis_set_part(tdev_axis(&t), 40.0, 1e6);
    CHECK_EQ(tdev_move(&t, WSG_MOVE_STOP_ON_BLOCK, 50.0f, 100.0f),
             WSG_E_CMD_PENDING);
    CHECK_EQ(tdev_final(&t, WSG_CMD_PREPOSITION, 4000), WSG_E_AXIS_BLOCKED);
    CHECK_NEAR(tdev_getf(&t, WSG_CMD_GET_WIDTH), 70.0, 1e-3);
    wsg_axis_set_part(tdev_axis(&t), -1.0, 0);
    /* Closing "to 10 mm" meets the real end stop where it believes 30 mm
     * is: blocked there. */
    CHECK_EQ(tdev_move(&t, 0, 10.0f, 100.0f), WSG_E_CMD_PENDING);
    CHECK_EQ(tdev_final(&t, WSG_CMD_PREPOSITION, 4000), WSG_E_AXIS_BLOCKED);
    CHECK_NEAR(tdev_getf(&t, WSG_CMD_GET_WIDTH), 30.0, 1e-3);
    /* Homing again, nothing in the way: right again. */
    CHECK_EQ(tdev_home(&t, 2), WSG_E_SUCCESS);
    CHECK_NEAR(tdev_getf(&t, WSG_CMD_GET_WIDTH), 0.0, 1e-3);
    CHECK_NEAR(tdev_axis(&t)->ref_offset, 0.0, 1e-9);
    CHECK_EQ(tdev_move(&t, 0, 40.0f, 100.0f), WSG_E_CMD_PENDING);
    CHECK_EQ(tdev_final(&t, WSG_CMD_PREPOSITION, 4000), WSG_E_SUCCESS);
}

static void test_fault_consequences(void)
{
    struct tdev t;

    /* A power fault during a motion: FAST STOP, the motion aborted,
     * acknowledge needed once it is gone. */
    tdev_init(&t);
    CHECK_EQ(tdev_home(&t, 0), WSG_E_SUCCESS);
    CHECK_EQ(tdev_move(&t, 0, 10.0f, 20.0f), WSG_E_CMD_PENDING);
    tdev_steps(&t, 100);
    wsg_axis_set_fault(tdev_axis(&t), WSG_SF_POWER_FAULT, 1);
    CHECK_EQ(tdev_final(&t, WSG_CMD_PREPOSITION, 10), WSG_E_CMD_ABORTED);
    CHECK_EQ(tdev_flags(&t) & (WSG_SF_POWER_FAULT | WSG_SF_FAST_STOP),
             WSG_SF_POWER_FAULT | WSG_SF_FAST_STOP);
    wsg_axis_set_fault(tdev_axis(&t), WSG_SF_POWER_FAULT, 0);
    tdev_steps(&t, 1);
    CHECK(tdev_flags(&t) & WSG_SF_FAST_STOP);
    CHECK_EQ(tdev_move(&t, 0, 50.0f, 100.0f), WSG_E_ACCESS_DENIED);
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_ACK_FAST_STOP, "ack", 3), WSG_E_SUCCESS);
    tdev_steps(&t, 1);
    CHECK_EQ(tdev_move(&t, 0, 50.0f, 100.0f), WSG_E_CMD_PENDING);
    CHECK_EQ(tdev_final(&t, WSG_CMD_PREPOSITION, 4000), WSG_E_SUCCESS);

    /* A current fault as well. */
    wsg_axis_set_fault(tdev_axis(&t), WSG_SF_CURR_FAULT, 1);
    tdev_steps(&t, 1);
    CHECK(tdev_flags(&t) & WSG_SF_FAST_STOP);
    wsg_axis_set_fault(tdev_axis(&t), WSG_SF_CURR_FAULT, 0);
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_ACK_FAST_STOP, "ack", 3), WSG_E_SUCCESS);
    tdev_steps(&t, 1);

    /* A temperature fault: the motion and the grip end, movement refused
     * until it clears; no FAST STOP, nothing to acknowledge. */
    wsg_axis_set_part(tdev_axis(&t), 30.0, 0);
    CHECK_EQ(tdev_cmd2f(&t, WSG_CMD_GRASP, 30.0f, 100.0f), WSG_E_CMD_PENDING);
    CHECK_EQ(tdev_final(&t, WSG_CMD_GRASP, 4000), WSG_E_SUCCESS);
    wsg_axis_set_fault(tdev_axis(&t), WSG_SF_TEMP_FAULT, 1);
    tdev_steps(&t, 1);
    CHECK_EQ(tdev_getf(&t, WSG_CMD_GET_FORCE), 0.0f);
    CHECK_EQ(tdev_grasp_state(&t), WSG_GS_ERROR);
    CHECK(!(tdev_flags(&t) & WSG_SF_FAST_STOP));
    CHECK_EQ(tdev_cmd2f(&t, WSG_CMD_RELEASE, 60.0f, 100.0f),
             WSG_E_ACCESS_DENIED);
    wsg_axis_set_fault(tdev_axis(&t), WSG_SF_TEMP_FAULT, 0);
    CHECK_EQ(tdev_cmd2f(&t, WSG_CMD_RELEASE, 60.0f, 100.0f),
             WSG_E_CMD_PENDING);
    CHECK_EQ(tdev_final(&t, WSG_CMD_RELEASE, 4000), WSG_E_SUCCESS);
    /* A finger fault refuses movement, stops nothing. */
    wsg_axis_set_fault(tdev_axis(&t), WSG_SF_FINGER_FAULT, 1);
    tdev_steps(&t, 1);
    CHECK_EQ(tdev_flags(&t) & (WSG_SF_FINGER_FAULT | WSG_SF_FAST_STOP),
             WSG_SF_FINGER_FAULT);
    CHECK_EQ(tdev_move(&t, 0, 50.0f, 100.0f), WSG_E_ACCESS_DENIED);
}

/* Overdrive heats the drive: holding at 120 N (1.5 times nominal) it
 * settles towards 100 degC with a 60 s time constant: the warning at
 * 65 degC after 60 ln(75/35) = 45.7 s, the fault at 75 degC after
 * 60 ln(75/25) = 65.9 s. Relieved, it cools. */
static void test_overheating(void)
{
    struct tdev t;
    uint8_t on = 1;
    long warn_ms = -1, fault_ms = -1, k;
    int16_t t10;

    tdev_init(&t);
    CHECK_EQ(tdev_home(&t, 0), WSG_E_SUCCESS);
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_OVERDRIVE, &on, 1), WSG_E_SUCCESS);
    CHECK_EQ(tdev_cmd1f(&t, WSG_CMD_SET_FORCE_LIMIT, 120.0f), WSG_E_SUCCESS);
    wsg_axis_set_part(tdev_axis(&t), 50.0, 0);
    CHECK_EQ(tdev_cmd2f(&t, WSG_CMD_GRASP, 50.0f, 100.0f), WSG_E_CMD_PENDING);
    CHECK_EQ(tdev_final(&t, WSG_CMD_GRASP, 4000), WSG_E_SUCCESS);
    CHECK(!wsg_device_idle(&t.dev)); /* warming up */
    for (k = 1; k <= 80000 && fault_ms < 0; k++) {
        tdev_steps(&t, 1);
        if (warn_ms < 0 &&
            (wsg_axis_flags(tdev_axis(&t)) & WSG_SF_TEMP_WARNING))
            warn_ms = k;
        if (wsg_axis_flags(tdev_axis(&t)) & WSG_SF_TEMP_FAULT)
            fault_ms = k;
    }
    printf("overdrive: warning after %ld ms, fault after %ld ms\n", warn_ms,
           fault_ms);
    CHECK_NEAR(warn_ms, 45700, 200);
    CHECK_NEAR(fault_ms, 65900, 200);
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_GET_TEMPERATURE, NULL, 0), WSG_E_SUCCESS);
    t10 = (int16_t)wsg_get_u16(tdev_last(&t)->params);
    CHECK_NEAR(t10, 750, 2);
    /* The fault turned the drive off: the grip is gone, and it cools. */
    tdev_steps(&t, 1);
    CHECK_EQ(tdev_getf(&t, WSG_CMD_GET_FORCE), 0.0f);
    CHECK_EQ(tdev_cmd2f(&t, WSG_CMD_RELEASE, 60.0f, 100.0f),
             WSG_E_ACCESS_DENIED);
    /* Below 70 degC the fault clears (hysteresis), below 60 the warning. */
    tdev_steps(&t, 60000);
    CHECK(tdev_axis(&t)->temperature < 60.0);
    CHECK_EQ(tdev_flags(&t) & (WSG_SF_TEMP_WARNING | WSG_SF_TEMP_FAULT), 0);
    CHECK_EQ(tdev_cmd2f(&t, WSG_CMD_RELEASE, 60.0f, 100.0f),
             WSG_E_CMD_PENDING);
    /* Holding at nominal force heats nothing. */
    tdev_init(&t);
    CHECK_EQ(tdev_home(&t, 0), WSG_E_SUCCESS);
    CHECK_EQ(tdev_cmd1f(&t, WSG_CMD_SET_FORCE_LIMIT, 80.0f), WSG_E_SUCCESS);
    wsg_axis_set_part(tdev_axis(&t), 50.0, 0);
    CHECK_EQ(tdev_cmd2f(&t, WSG_CMD_GRASP, 50.0f, 100.0f), WSG_E_CMD_PENDING);
    CHECK_EQ(tdev_final(&t, WSG_CMD_GRASP, 4000), WSG_E_SUCCESS);
    CHECK(wsg_device_idle(&t.dev));
    tdev_steps(&t, 10000);
    CHECK_NEAR(tdev_axis(&t)->temperature, 25.0, 1e-9);
}

/* A power cycle during a motion: it ends E_CMD_ABORTED, the gripper is
 * not referenced, the session settings are the defaults again. */
static void test_reset(void)
{
    struct tdev t;

    tdev_init(&t);
    CHECK_EQ(tdev_home(&t, 0), WSG_E_SUCCESS);
    CHECK_EQ(tdev_cmd1f(&t, WSG_CMD_SET_ACCELERATION, 500.0f), WSG_E_SUCCESS);
    CHECK_EQ(tdev_move(&t, 0, 10.0f, 20.0f), WSG_E_CMD_PENDING);
    tdev_steps(&t, 100);
    tdev_clear(&t);
    wsg_device_reset(&t.dev);
    REQUIRE(t.sess[0].n == 1);
    CHECK_EQ(tdev_last(&t)->id, WSG_CMD_PREPOSITION);
    CHECK_EQ(tdev_last(&t)->status, WSG_E_CMD_ABORTED);
    CHECK_EQ(tdev_flags(&t) & (WSG_SF_REFERENCED | WSG_SF_MOVING), 0);
    CHECK_EQ(tdev_getf(&t, WSG_CMD_GET_ACCELERATION), 150.0f);
    tdev_steps(&t, 100);
    CHECK_EQ(t.sess[0].n, 3); /* nothing more came */
}

/* A part placed wider than the opening squeezes with the force limit at
 * most, whatever its stiffness says. */
static void test_part_wider_than_opening(void)
{
    struct tdev t;
    int i;

    tdev_init(&t);
    CHECK_EQ(tdev_home(&t, 0), WSG_E_SUCCESS);
    CHECK_EQ(tdev_move(&t, 0, 50.0f, 100.0f), WSG_E_CMD_PENDING);
    CHECK_EQ(tdev_final(&t, WSG_CMD_PREPOSITION, 4000), WSG_E_SUCCESS);
    wsg_axis_set_part(tdev_axis(&t), 70.0, 0);
    CHECK_EQ(tdev_move(&t, 0, 90.0f, 20.0f), WSG_E_CMD_PENDING);
    for (i = 0; i < 3000; i++) {
        tdev_steps(&t, 1);
        CHECK(tdev_axis(&t)->force <= tdev_axis(&t)->force_limit);
    }
}

/* Overdrive off while holding with more than the nominal force: the force
 * on the part drops to nominal at once (3.3.8, D8), the part springs back
 * to where that force holds it, and the drive stops heating. */
static void test_overdrive_off_while_holding(void)
{
    struct tdev t;
    uint8_t on = 1, off = 0;

    tdev_init(&t);
    CHECK_EQ(tdev_home(&t, 0), WSG_E_SUCCESS);
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_OVERDRIVE, &on, 1), WSG_E_SUCCESS);
    CHECK_EQ(tdev_cmd1f(&t, WSG_CMD_SET_FORCE_LIMIT, 110.0f), WSG_E_SUCCESS);
    wsg_axis_set_part(tdev_axis(&t), 60.0, 0); /* 50 N/mm */
    CHECK_EQ(tdev_cmd2f(&t, WSG_CMD_GRASP, 60.0f, 100.0f), WSG_E_CMD_PENDING);
    CHECK_EQ(tdev_final(&t, WSG_CMD_GRASP, 4000), WSG_E_SUCCESS);
    CHECK_NEAR(tdev_getf(&t, WSG_CMD_GET_FORCE), 110.0, 1e-3);
    CHECK_NEAR(tdev_getf(&t, WSG_CMD_GET_WIDTH), 60.0 - 110.0 / 50.0, 1e-3);
    tdev_steps(&t, 1000); /* warming up */
    CHECK(tdev_axis(&t)->temperature > tdev_axis(&t)->cfg.ambient + 0.5);

    /* no step in between: every reading shows it at once */
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_OVERDRIVE, &off, 1), WSG_E_SUCCESS);
    CHECK_NEAR(tdev_getf(&t, WSG_CMD_GET_FORCE_LIMIT), 80.0, 1e-3);
    CHECK_NEAR(tdev_getf(&t, WSG_CMD_GET_FORCE), 80.0, 1e-3);
    CHECK_NEAR(tdev_getf(&t, WSG_CMD_GET_WIDTH), 60.0 - 80.0 / 50.0, 1e-3);
    CHECK_EQ(tdev_grasp_state(&t), WSG_GS_HOLDING);
    CHECK_EQ(tdev_flags(&t), WSG_SF_REFERENCED | WSG_SF_BLOCKED_MINUS |
                                 WSG_SF_TARGET_POS_REACHED);
    /* still held at nominal force; holding at nominal heats nothing, so
     * the drive cools down instead of warming further */
    {
        double before = tdev_axis(&t)->temperature;
        tdev_steps(&t, 5000);
        CHECK(tdev_axis(&t)->temperature < before);
        CHECK_NEAR(tdev_getf(&t, WSG_CMD_GET_FORCE), 80.0, 1e-3);
        CHECK_EQ(tdev_grasp_state(&t), WSG_GS_HOLDING);
    }
    /* a clamp at or below nominal is not touched by leaving overdrive */
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_OVERDRIVE, &on, 1), WSG_E_SUCCESS);
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_OVERDRIVE, &off, 1), WSG_E_SUCCESS);
    CHECK_NEAR(tdev_getf(&t, WSG_CMD_GET_FORCE), 80.0, 1e-3);
}

/* Soft limits set while the fingers are beyond them and moving deeper:
 * stopped at once, as at a limit crossed (3.3.5, 3.2.2's E_RANGE_ERROR,
 * D4/D5); moving out stays allowed. */
static void test_soft_limits_inside(void)
{
    struct tdev t;
    double w;

    tdev_init(&t);
    CHECK_EQ(tdev_home(&t, 0), WSG_E_SUCCESS);
    /* closing from 110 towards 20 at 50 mm/s, now around 80 */
    CHECK_EQ(tdev_move(&t, 0, 20.0f, 50.0f), WSG_E_CMD_PENDING);
    tdev_steps(&t, 800);
    w = tdev_axis(&t)->width;
    REQUIRE(w > 70.0 && w < 95.0);
    tdev_clear(&t);
    CHECK_EQ(tdev_cmd2f(&t, WSG_CMD_SET_SOFT_LIMITS, 100.0f, 110.0f),
             WSG_E_SUCCESS);
    /* at once, no step: the move ended with a range error, FAST STOP */
    CHECK_EQ(t.sess[0].n, 2);
    CHECK_EQ(t.sess[0].pkts[1].id, WSG_CMD_PREPOSITION);
    CHECK_EQ(t.sess[0].pkts[1].status, WSG_E_RANGE_ERROR);
    CHECK_EQ(tdev_flags(&t) & ~WSG_SF_CMD_FAILURE,
             WSG_SF_REFERENCED | WSG_SF_SOFT_LIMIT_MINUS | WSG_SF_FAST_STOP);
    CHECK_EQ(tdev_grasp_state(&t), WSG_GS_ERROR);
    CHECK_NEAR(tdev_axis(&t)->width, w, 1e-9); /* where it was */
    tdev_clear(&t);
    tdev_steps(&t, 100);
    CHECK_NEAR(tdev_axis(&t)->width, w, 1e-9);
    /* out of the restricted area: allowed after the acknowledge */
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_ACK_FAST_STOP, "ack", 3), WSG_E_SUCCESS);
    CHECK_EQ(tdev_move(&t, 0, 105.0f, 50.0f), WSG_E_CMD_PENDING);
    CHECK_EQ(tdev_final(&t, WSG_CMD_PREPOSITION, 4000), WSG_E_SUCCESS);
    CHECK_NEAR(tdev_axis(&t)->width, 105.0, 1e-9);

    /* the same on the plus side, with a clamp that snaps on deeper: a
     * clamp on an obstacle at 60, target 90, limits set to 20..50, the
     * obstacle goes */
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_CLEAR_SOFT_LIMITS, NULL, 0), WSG_E_SUCCESS);
    CHECK_EQ(tdev_move(&t, 0, 40.0f, 100.0f), WSG_E_CMD_PENDING);
    CHECK_EQ(tdev_final(&t, WSG_CMD_PREPOSITION, 4000), WSG_E_SUCCESS);
    wsg_axis_set_obstacle(tdev_axis(&t), 60.0);
    CHECK_EQ(tdev_move(&t, 0, 90.0f, 100.0f), WSG_E_CMD_PENDING);
    CHECK_EQ(tdev_final(&t, WSG_CMD_PREPOSITION, 4000), WSG_E_AXIS_BLOCKED);
    CHECK_NEAR(tdev_axis(&t)->width, 60.0, 1e-9);
    CHECK_EQ(tdev_cmd2f(&t, WSG_CMD_SET_SOFT_LIMITS, 20.0f, 50.0f),
             WSG_E_SUCCESS);
    CHECK(tdev_flags(&t) & WSG_SF_SOFT_LIMIT_PLUS);
    wsg_axis_set_obstacle(tdev_axis(&t), -1.0);
    tdev_steps(&t, 1000);
    CHECK_NEAR(tdev_axis(&t)->width, 60.0, 1e-9);
    CHECK(tdev_flags(&t) & WSG_SF_FAST_STOP);
    CHECK(!(tdev_flags(&t) & WSG_SF_MOVING));
}

/* A grasp with nothing between the fingers whose clamping travel reaches
 * past an end stop: the fingers meet (or reach the stroke's end) inside
 * the grasping window, so the gripper holds, "gripping itself". */
static void test_grasp_end_stop(void)
{
    struct tdev t;

    tdev_init(&t);
    CHECK_EQ(tdev_home(&t, 0), WSG_E_SUCCESS);
    CHECK_EQ(tdev_cmd2f(&t, WSG_CMD_GRASP, 0.0f, 100.0f), WSG_E_CMD_PENDING);
    CHECK_EQ(tdev_final(&t, WSG_CMD_GRASP, 4000), WSG_E_SUCCESS);
    CHECK_EQ(tdev_grasp_state(&t), WSG_GS_HOLDING);
    CHECK_NEAR(tdev_axis(&t)->width, 0.0, 1e-9);
    CHECK_NEAR(tdev_getf(&t, WSG_CMD_GET_FORCE), 40.0, 1e-3);
    CHECK_EQ(tdev_flags(&t), WSG_SF_REFERENCED | WSG_SF_BLOCKED_MINUS |
                                 WSG_SF_TARGET_POS_REACHED);
    CHECK(wsg_device_idle(&t.dev));
    tdev_steps(&t, 100);
    CHECK_EQ(tdev_grasp_state(&t), WSG_GS_HOLDING);
    /* again from where the fingers already meet */
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_STOP, NULL, 0), WSG_E_SUCCESS);
    CHECK_EQ(tdev_cmd2f(&t, WSG_CMD_GRASP, 0.0f, 100.0f), WSG_E_CMD_PENDING);
    CHECK_EQ(tdev_final(&t, WSG_CMD_GRASP, 4000), WSG_E_SUCCESS);
    CHECK_EQ(tdev_grasp_state(&t), WSG_GS_HOLDING);
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_GET_GRASP_STATS, NULL, 0), WSG_E_SUCCESS);
    CHECK_EQ(wsg_get_u32(tdev_last(&t)->params), 2);
    CHECK_EQ(wsg_get_u16(tdev_last(&t)->params + 4), 0);

    /* a clamping travel that ends short of the end stop: no part */
    CHECK_EQ(tdev_cmd2f(&t, WSG_CMD_RELEASE, 50.0f, 400.0f),
             WSG_E_CMD_PENDING);
    CHECK_EQ(tdev_final(&t, WSG_CMD_RELEASE, 4000), WSG_E_SUCCESS);
    CHECK_EQ(tdev_cmd2f(&t, WSG_CMD_GRASP, 12.0f, 100.0f), WSG_E_CMD_PENDING);
    CHECK_EQ(tdev_final(&t, WSG_CMD_GRASP, 4000), WSG_E_CMD_FAILED);
    CHECK_NEAR(tdev_axis(&t)->width, 2.0, 1e-9);

    /* outside grasps at the open end stop: the same rule */
    CHECK_EQ(tdev_cmd2f(&t, WSG_CMD_GRASP, 105.0f, 100.0f), WSG_E_CMD_PENDING);
    CHECK_EQ(tdev_final(&t, WSG_CMD_GRASP, 4000), WSG_E_SUCCESS);
    CHECK_EQ(tdev_grasp_state(&t), WSG_GS_HOLDING);
    CHECK_NEAR(tdev_axis(&t)->width, 110.0, 1e-9);
    CHECK(tdev_flags(&t) & WSG_SF_BLOCKED_PLUS);
    CHECK_EQ(tdev_cmd2f(&t, WSG_CMD_RELEASE, 50.0f, 400.0f),
             WSG_E_CMD_PENDING);
    CHECK_EQ(tdev_final(&t, WSG_CMD_RELEASE, 4000), WSG_E_SUCCESS);
    CHECK_EQ(tdev_cmd2f(&t, WSG_CMD_GRASP, 95.0f, 100.0f), WSG_E_CMD_PENDING);
    CHECK_EQ(tdev_final(&t, WSG_CMD_GRASP, 4000), WSG_E_CMD_FAILED);
    CHECK_NEAR(tdev_axis(&t)->width, 105.0, 1e-9);
}

/* The world changed under a clamp (the control channel does it between
 * steps): a settle, as after every command, shows it at once. */
static void test_world_at_once(void)
{
    struct tdev t;

    tdev_init(&t);
    CHECK_EQ(tdev_home(&t, 0), WSG_E_SUCCESS);
    wsg_axis_set_part(tdev_axis(&t), 40.0, 0);
    CHECK_EQ(tdev_cmd2f(&t, WSG_CMD_GRASP, 40.0f, 100.0f), WSG_E_CMD_PENDING);
    CHECK_EQ(tdev_final(&t, WSG_CMD_GRASP, 4000), WSG_E_SUCCESS);
    wsg_axis_set_part(tdev_axis(&t), -1.0, 0);
    wsg_axis_settle(tdev_axis(&t));
    CHECK_EQ(tdev_grasp_state(&t), WSG_GS_PART_LOST);
    CHECK(tdev_flags(&t) & WSG_SF_MOVING);
    CHECK_EQ(tdev_axis(&t)->force, 0.0);

    /* a part that grows while held holds the fingers where they are */
    tdev_steps(&t, 2000);
    CHECK_EQ(tdev_cmd2f(&t, WSG_CMD_RELEASE, 60.0f, 400.0f),
             WSG_E_CMD_PENDING);
    CHECK_EQ(tdev_final(&t, WSG_CMD_RELEASE, 4000), WSG_E_SUCCESS);
    wsg_axis_set_part(tdev_axis(&t), 40.0, 0);
    CHECK_EQ(tdev_cmd2f(&t, WSG_CMD_GRASP, 40.0f, 100.0f), WSG_E_CMD_PENDING);
    CHECK_EQ(tdev_final(&t, WSG_CMD_GRASP, 4000), WSG_E_SUCCESS);
    wsg_axis_set_part(tdev_axis(&t), 45.0, 0);
    wsg_axis_settle(tdev_axis(&t));
    tdev_steps(&t, 10);
    CHECK_EQ(tdev_grasp_state(&t), WSG_GS_HOLDING);
    CHECK_NEAR(tdev_axis(&t)->width, 40.0 - 40.0 / 50.0, 1e-9);
}

/* A motion started over a running one (a script's mc.move over its own
 * movement) gives the old one's owner its final E_CMD_ABORTED. */
static void test_replace_aborts(void)
{
    struct wsg_axis ax;
    struct rec r;

    bare_init(&ax, &r);
    CHECK_EQ(wsg_axis_request_move(&ax, 0, 10.0, 50.0, 1), WSG_E_CMD_PENDING);
    wsg_axis_settle(&ax);
    bare_steps(&ax, 300);
    CHECK_EQ(r.n, 0);
    CHECK_EQ(wsg_axis_request_move(&ax, 0, 90.0, 50.0, 2), WSG_E_CMD_PENDING);
    wsg_axis_settle(&ax);
    REQUIRE(r.n == 1);
    CHECK_EQ(r.tag[0], 1);
    CHECK_EQ(r.id[0], WSG_CMD_PREPOSITION);
    CHECK_EQ(r.status[0], WSG_E_CMD_ABORTED);
    /* the new one runs to its end and reports once */
    bare_steps(&ax, 4000);
    REQUIRE(r.n == 2);
    CHECK_EQ(r.tag[1], 2);
    CHECK_EQ(r.status[1], WSG_E_SUCCESS);
    CHECK_NEAR(ax.width, 90.0, 1e-9);

    /* a grasp replaced by a homing: the grasp's owner hears it */
    CHECK_EQ(wsg_axis_request_grasp(&ax, 20.0, 50.0, 3), WSG_E_CMD_PENDING);
    wsg_axis_settle(&ax);
    bare_steps(&ax, 10);
    CHECK_EQ(wsg_axis_request_homing(&ax, WSG_HOME_POSITIVE, 4),
             WSG_E_CMD_PENDING);
    wsg_axis_settle(&ax);
    REQUIRE(r.n == 3);
    CHECK_EQ(r.tag[2], 3);
    CHECK_EQ(r.id[2], WSG_CMD_GRASP);
    CHECK_EQ(r.status[2], WSG_E_CMD_ABORTED);
}

/* Runs a bare model until its next final result; returns the status. */
static uint16_t bare_final(struct wsg_axis *ax, struct rec *r, long max)
{
    int n = r->n;

    while (r->n == n && max-- > 0)
        wsg_axis_step(ax);
    REQUIRE(r->n == n + 1);
    return r->status[n];
}

/* A grasp with its own window: the clamping travel sets where it stops
 * with no part, the tolerance what block holds; below 0 and NULL are the
 * configuration's (10 mm each). */
static void test_grasp_window(void)
{
    struct wsg_axis ax;
    struct rec r;
    struct wsg_grasp_window w = {3.0, -1.0};

    bare_init(&ax, &r);
    /* no part: through 3 mm of travel, not 10 */
    CHECK_EQ(wsg_axis_request_grasp_in(&ax, 40.0, 100.0, &w, 1),
             WSG_E_CMD_PENDING);
    CHECK_EQ(bare_final(&ax, &r, 4000), WSG_E_CMD_FAILED);
    CHECK_NEAR(ax.width, 37.0, 1e-9);
    /* the configuration's travel with NULL and with a value below 0 */
    CHECK_EQ(wsg_axis_request_move(&ax, 0, 60.0, 400.0, 1), WSG_E_CMD_PENDING);
    CHECK_EQ(bare_final(&ax, &r, 4000), WSG_E_SUCCESS);
    CHECK_EQ(wsg_axis_request_grasp_in(&ax, 40.0, 100.0, NULL, 1),
             WSG_E_CMD_PENDING);
    CHECK_EQ(bare_final(&ax, &r, 4000), WSG_E_CMD_FAILED);
    CHECK_NEAR(ax.width, 30.0, 1e-9);
    w.travel = -1.0;
    CHECK_EQ(wsg_axis_request_grasp_in(&ax, 25.0, 100.0, &w, 1),
             WSG_E_CMD_PENDING);
    CHECK_EQ(bare_final(&ax, &r, 4000), WSG_E_CMD_FAILED);
    CHECK_NEAR(ax.width, 15.0, 1e-9);

    /* a part of 80 mm blocks at 79.2: within 10 mm of 75, not within 2 */
    CHECK_EQ(wsg_axis_request_move(&ax, 0, 100.0, 400.0, 1),
             WSG_E_CMD_PENDING);
    CHECK_EQ(bare_final(&ax, &r, 4000), WSG_E_SUCCESS);
    wsg_axis_set_part(&ax, 80.0, 0);
    w.tolerance = 2.0;
    CHECK_EQ(wsg_axis_request_grasp_in(&ax, 75.0, 100.0, &w, 1),
             WSG_E_CMD_PENDING);
    CHECK_EQ(bare_final(&ax, &r, 4000), WSG_E_CMD_FAILED);
    CHECK_EQ(ax.grasp_state, WSG_GS_NO_PART);
    CHECK_NEAR(ax.width, 80.0 - 40.0 / 50.0, 1e-9);
    w.tolerance = -1.0;
    CHECK_EQ(wsg_axis_request_grasp_in(&ax, 75.0, 100.0, &w, 1),
             WSG_E_CMD_PENDING);
    CHECK_EQ(bare_final(&ax, &r, 4000), WSG_E_SUCCESS);
    CHECK_EQ(ax.grasp_state, WSG_GS_HOLDING);

    /* NaN is refused, nothing recorded */
    w.travel = NAN;
    CHECK_EQ(wsg_axis_request_grasp_in(&ax, 75.0, 100.0, &w, 1),
             WSG_E_INVALID_PARAMETER);
    w.travel = 1.0;
    w.tolerance = NAN;
    CHECK_EQ(wsg_axis_request_grasp_in(&ax, 75.0, 100.0, &w, 1),
             WSG_E_INVALID_PARAMETER);
    CHECK_EQ(ax.req_motion.kind, WSG_MOTION_NONE);
}

/* Pressing: held by a block with the drive pushing (a clamp), not after
 * stop on block, a Stop, or a block that went; the BLOCKED flag is not it
 * (a blocked motion leaves it set). */
static void test_pressing(void)
{
    struct wsg_axis ax;
    struct rec r;

    bare_init(&ax, &r);
    CHECK_EQ(wsg_axis_pressing(&ax), 0);
    wsg_axis_set_part(&ax, 40.0, 0);
    CHECK_EQ(wsg_axis_request_grasp(&ax, 40.0, 100.0, 1), WSG_E_CMD_PENDING);
    wsg_axis_settle(&ax);
    bare_steps(&ax, 10);
    CHECK_EQ(wsg_axis_pressing(&ax), 0); /* on its way */
    CHECK_EQ(bare_final(&ax, &r, 4000), WSG_E_SUCCESS);
    CHECK_EQ(wsg_axis_pressing(&ax), 1);
    /* the part goes: lost, the fingers snap on, nothing pushes */
    wsg_axis_set_part(&ax, -1.0, 0);
    wsg_axis_settle(&ax);
    CHECK_EQ(wsg_axis_pressing(&ax), 0);
    bare_steps(&ax, 2000);
    CHECK_EQ(wsg_axis_pressing(&ax), 0);

    /* a preposition clamped on an obstacle presses until a Stop */
    wsg_axis_set_obstacle(&ax, 60.0);
    CHECK_EQ(wsg_axis_request_move(&ax, 0, 90.0, 100.0, 1), WSG_E_CMD_PENDING);
    CHECK_EQ(bare_final(&ax, &r, 4000), WSG_E_AXIS_BLOCKED);
    CHECK_EQ(wsg_axis_pressing(&ax), 1);
    wsg_axis_request_stop(&ax);
    wsg_axis_settle(&ax);
    CHECK_EQ(wsg_axis_pressing(&ax), 0);
    CHECK(wsg_axis_flags(&ax) & WSG_SF_BLOCKED_PLUS);
    /* stop on block: blocked, flagged, not pressing */
    CHECK_EQ(
        wsg_axis_request_move(&ax, WSG_MOVE_STOP_ON_BLOCK, 20.0, 100.0, 1),
        WSG_E_CMD_PENDING);
    CHECK_EQ(bare_final(&ax, &r, 4000), WSG_E_AXIS_BLOCKED);
    CHECK(wsg_axis_flags(&ax) & WSG_SF_BLOCKED_MINUS);
    CHECK_EQ(wsg_axis_pressing(&ax), 0);
}

/* Speed mode in free motion: the velocity ramps with the model's maximum
 * acceleration (5000 mm/s^2 on a WSG 50: 5 mm/s per 1 ms step), not the
 * session's 150; small set speeds are kept, large ones clamped; set speed
 * 0 stands still, and a Stop ends it. */
static void test_speed_ramp(void)
{
    struct wsg_axis ax;
    struct rec r;
    double w;
    int i;

    bare_init(&ax, &r);
    CHECK_EQ(wsg_axis_request_speed(&ax, NAN, 0), WSG_E_INVALID_PARAMETER);
    CHECK_EQ(ax.req_motion.kind, WSG_MOTION_NONE);
    CHECK_EQ(wsg_axis_request_speed(&ax, -100.0, 0), WSG_E_SUCCESS);
    CHECK_EQ(wsg_axis_speed_mode(&ax), 0); /* not settled yet */
    wsg_axis_settle(&ax);
    CHECK_EQ(wsg_axis_speed_mode(&ax), 1);
    CHECK(wsg_axis_flags(&ax) & WSG_SF_MOVING);
    /* The controller's own motion: no grasping state. */
    CHECK_EQ(wsg_axis_grasp_state(&ax), WSG_GS_IDLE);
    CHECK(wsg_axis_busy(&ax));
    CHECK(!wsg_axis_idle(&ax));
    bare_steps(&ax, 1);
    CHECK_NEAR(wsg_axis_speed(&ax), -5.0, 1e-9);
    bare_steps(&ax, 19);
    CHECK_NEAR(wsg_axis_speed(&ax), -100.0, 1e-9);
    CHECK_NEAR(wsg_axis_width(&ax), 110.0 - 0.5 * 5000.0 * 0.02 * 0.02, 1e-9);
    bare_steps(&ax, 10);
    CHECK_NEAR(wsg_axis_width(&ax), 108.0, 1e-9);
    CHECK_EQ(wsg_axis_force(&ax), 0.0);
    /* a ramp that ends inside a step is exact: -100 to -97.5 in 0.5 ms */
    CHECK_EQ(wsg_axis_request_speed(&ax, -97.5, 0), WSG_E_SUCCESS);
    wsg_axis_settle(&ax);
    bare_steps(&ax, 1);
    CHECK_NEAR(wsg_axis_speed(&ax), -97.5, 1e-9);
    CHECK_NEAR(wsg_axis_width(&ax),
               108.0 - (0.5 * (100.0 + 97.5) * 0.0005 + 97.5 * 0.0005), 1e-9);
    /* below the motion commands' 5 mm/s minimum: taken as it is */
    CHECK_EQ(wsg_axis_request_speed(&ax, -0.5, 0), WSG_E_SUCCESS);
    wsg_axis_settle(&ax);
    bare_steps(&ax, 100);
    CHECK_NEAR(wsg_axis_speed(&ax), -0.5, 1e-9);
    w = wsg_axis_width(&ax);
    bare_steps(&ax, 1000);
    CHECK_NEAR(wsg_axis_width(&ax), w - 0.5, 1e-9);
    /* above the maximum: clamped */
    CHECK_EQ(wsg_axis_request_speed(&ax, -1e6, 0), WSG_E_SUCCESS);
    wsg_axis_settle(&ax);
    bare_steps(&ax, 100);
    CHECK_NEAR(wsg_axis_speed(&ax), -420.0, 1e-9);
    /* set speed 0: decelerates, then stands; nothing moving, idle, still on */
    CHECK_EQ(wsg_axis_request_speed(&ax, 0.0, 0), WSG_E_SUCCESS);
    wsg_axis_settle(&ax);
    CHECK(wsg_axis_flags(&ax) & WSG_SF_MOVING);
    for (i = 0; i < 83; i++) {
        bare_steps(&ax, 1);
        CHECK(!wsg_axis_idle(&ax));
    }
    bare_steps(&ax, 1);
    CHECK_EQ(wsg_axis_speed(&ax), 0.0);
    CHECK(!(wsg_axis_flags(&ax) & WSG_SF_MOVING));
    CHECK(wsg_axis_idle(&ax));
    CHECK_EQ(wsg_axis_speed_mode(&ax), 1);
    CHECK(wsg_axis_busy(&ax));
    /* The controller's own motion: no grasping state. */
    CHECK_EQ(wsg_axis_grasp_state(&ax), WSG_GS_IDLE);
    w = wsg_axis_width(&ax);
    bare_steps(&ax, 100);
    CHECK_EQ(wsg_axis_width(&ax), w);
    CHECK_EQ(r.n, 0); /* nothing ended it */
    /* a Stop ends it: stopped, idle, its final result E_CMD_ABORTED */
    wsg_axis_request_stop(&ax);
    wsg_axis_settle(&ax);
    CHECK_EQ(wsg_axis_speed_mode(&ax), 0);
    CHECK(!wsg_axis_busy(&ax));
    CHECK(wsg_axis_flags(&ax) & WSG_SF_AXIS_STOPPED);
    CHECK_EQ(wsg_axis_grasp_state(&ax), WSG_GS_IDLE);
    REQUIRE(r.n == 1);
    CHECK_EQ(r.tag[0], 0);
    CHECK_EQ(r.id[0], 0);
    CHECK_EQ(r.status[0], WSG_E_CMD_ABORTED);
    /* a Stop while it moves halts the fingers at once */
    CHECK_EQ(wsg_axis_request_speed(&ax, 50.0, 0), WSG_E_SUCCESS);
    wsg_axis_settle(&ax);
    bare_steps(&ax, 50);
    w = wsg_axis_width(&ax);
    wsg_axis_request_stop(&ax);
    wsg_axis_settle(&ax);
    CHECK_EQ(wsg_axis_speed(&ax), 0.0);
    bare_steps(&ax, 10);
    CHECK_EQ(wsg_axis_width(&ax), w);
}

/* Speed mode against a part, the end stops and an obstacle: it stops where
 * the force limit holds it, pushes on (not ended, blocked and pressing);
 * the same direction again changes nothing; a new force limit squeezes
 * the part to where that force holds it; away from the contact frees the
 * fingers; a block that goes lets them move on. */
static void test_speed_block(void)
{
    struct wsg_axis ax;
    struct rec r;
    double prev = 0.0;
    int rising = 1, i;

    bare_init(&ax, &r);
    wsg_axis_set_part(&ax, 40.0, 10.0);
    CHECK_EQ(wsg_axis_request_speed(&ax, -50.0, 0), WSG_E_SUCCESS);
    wsg_axis_settle(&ax);
    for (i = 0; i < 3000 && wsg_axis_width(&ax) > 40.0; i++)
        bare_steps(&ax, 1);
    for (i = 0; i < 3000 && !wsg_axis_pressing(&ax); i++) {
        bare_steps(&ax, 1);
        if (wsg_axis_force(&ax) < prev)
            rising = 0;
        prev = wsg_axis_force(&ax);
    }
    CHECK(rising);
    CHECK(i > 5); /* the force built up over several steps */
    CHECK_EQ(wsg_axis_pressing(&ax), 1);
    CHECK_NEAR(wsg_axis_width(&ax), 36.0, 1e-9);
    CHECK_NEAR(wsg_axis_force(&ax), 40.0, 1e-9);
    CHECK_EQ(wsg_axis_speed(&ax), 0.0);
    CHECK_EQ(wsg_axis_flags(&ax), WSG_SF_REFERENCED | WSG_SF_BLOCKED_MINUS);
    CHECK_EQ(wsg_axis_speed_mode(&ax), 1);
    /* The controller's own motion: no grasping state. */
    CHECK_EQ(wsg_axis_grasp_state(&ax), WSG_GS_IDLE);
    CHECK(wsg_axis_idle(&ax));
    bare_steps(&ax, 100);
    CHECK_NEAR(wsg_axis_width(&ax), 36.0, 1e-9);
    CHECK_EQ(r.n, 0);
    /* the same way again, slower: still pushing, still blocked */
    CHECK_EQ(wsg_axis_request_speed(&ax, -20.0, 0), WSG_E_SUCCESS);
    wsg_axis_settle(&ax);
    CHECK_EQ(wsg_axis_pressing(&ax), 1);
    CHECK(wsg_axis_flags(&ax) & WSG_SF_BLOCKED_MINUS);
    CHECK(!(wsg_axis_flags(&ax) & WSG_SF_MOVING));
    CHECK(wsg_axis_idle(&ax));
    /* a new force limit: squeezed to where it holds, at the next settle */
    wsg_axis_set_force_limit(&ax, 60.0);
    CHECK(!wsg_axis_idle(&ax));
    wsg_axis_settle(&ax);
    CHECK_NEAR(wsg_axis_width(&ax), 34.0, 1e-9);
    CHECK_NEAR(wsg_axis_force(&ax), 60.0, 1e-9);
    wsg_axis_set_force_limit(&ax, 20.0);
    wsg_axis_settle(&ax);
    CHECK_NEAR(wsg_axis_width(&ax), 38.0, 1e-9);
    CHECK_NEAR(wsg_axis_force(&ax), 20.0, 1e-9);
    CHECK_EQ(wsg_axis_pressing(&ax), 1);
    CHECK(wsg_axis_idle(&ax));
    /* away from the part: free, moving, the force falls off */
    CHECK_EQ(wsg_axis_request_speed(&ax, 30.0, 0), WSG_E_SUCCESS);
    wsg_axis_settle(&ax);
    CHECK_EQ(wsg_axis_pressing(&ax), 0);
    CHECK_EQ(wsg_axis_flags(&ax) & (WSG_SF_BLOCKED_MINUS | WSG_SF_MOVING),
             WSG_SF_MOVING);
    bare_steps(&ax, 200);
    CHECK(wsg_axis_width(&ax) > 40.0);
    CHECK_EQ(wsg_axis_force(&ax), 0.0);
    /* into the open end stop: pushing there with the force limit */
    CHECK_EQ(wsg_axis_request_speed(&ax, 100.0, 0), WSG_E_SUCCESS);
    wsg_axis_settle(&ax);
    bare_steps(&ax, 2000);
    CHECK_EQ(wsg_axis_pressing(&ax), 1);
    CHECK_NEAR(wsg_axis_width(&ax), 110.0, 1e-9);
    CHECK_NEAR(wsg_axis_force(&ax), 20.0, 1e-9);
    CHECK_EQ(wsg_axis_flags(&ax), WSG_SF_REFERENCED | WSG_SF_BLOCKED_PLUS);
    /* an obstacle on the way back: blocked there */
    wsg_axis_set_obstacle(&ax, 70.0);
    CHECK_EQ(wsg_axis_request_speed(&ax, -100.0, 0), WSG_E_SUCCESS);
    wsg_axis_settle(&ax);
    bare_steps(&ax, 2000);
    CHECK_EQ(wsg_axis_pressing(&ax), 1);
    CHECK_NEAR(wsg_axis_width(&ax), 70.0, 1e-9);
    CHECK(wsg_axis_flags(&ax) & WSG_SF_BLOCKED_MINUS);
    /* taken away: the fingers move on, onto the part */
    wsg_axis_set_obstacle(&ax, -1.0);
    CHECK(!wsg_axis_idle(&ax));
    wsg_axis_settle(&ax);
    CHECK_EQ(wsg_axis_pressing(&ax), 0);
    CHECK(!(wsg_axis_flags(&ax) & WSG_SF_BLOCKED_MINUS));
    CHECK(wsg_axis_flags(&ax) & WSG_SF_MOVING);
    bare_steps(&ax, 2000);
    CHECK_EQ(wsg_axis_pressing(&ax), 1);
    CHECK_NEAR(wsg_axis_width(&ax), 38.0, 1e-9);
    /* the part goes: on into the closed end stop */
    wsg_axis_set_part(&ax, -1.0, 0);
    wsg_axis_settle(&ax);
    CHECK_EQ(wsg_axis_pressing(&ax), 0);
    bare_steps(&ax, 2000);
    CHECK_EQ(wsg_axis_pressing(&ax), 1);
    CHECK_NEAR(wsg_axis_width(&ax), 0.0, 1e-9);
    CHECK_EQ(r.n, 0); /* no block ended it */
    /* set speed 0 at the block: no longer pushing, standing */
    CHECK_EQ(wsg_axis_request_speed(&ax, 0.0, 0), WSG_E_SUCCESS);
    wsg_axis_settle(&ax);
    CHECK_EQ(wsg_axis_pressing(&ax), 0);
    CHECK_EQ(wsg_axis_force(&ax), 0.0);
    CHECK(!(wsg_axis_flags(&ax) & WSG_SF_MOVING));
    CHECK(wsg_axis_idle(&ax));
    /* and into it again: pushing at once */
    CHECK_EQ(wsg_axis_request_speed(&ax, -1.0, 0), WSG_E_SUCCESS);
    wsg_axis_settle(&ax);
    CHECK_EQ(wsg_axis_pressing(&ax), 1);
    CHECK(wsg_axis_idle(&ax));
}

/* Speed mode replaces a running motion, whose owner hears E_CMD_ABORTED,
 * and starts from the fingers' velocity; a clamp it takes over goes on
 * pushing; a motion that replaces speed mode starts from rest. */
static void test_speed_replace(void)
{
    struct wsg_axis ax;
    struct rec r;
    double v;

    bare_init(&ax, &r);
    CHECK_EQ(wsg_axis_request_move(&ax, 0, 10.0, 50.0, 1), WSG_E_CMD_PENDING);
    wsg_axis_settle(&ax);
    bare_steps(&ax, 800);
    v = wsg_axis_speed(&ax);
    CHECK_NEAR(v, -50.0, 1e-9);
    CHECK_EQ(wsg_axis_request_speed(&ax, -30.0, 0), WSG_E_SUCCESS);
    wsg_axis_settle(&ax);
    REQUIRE(r.n == 1);
    CHECK_EQ(r.tag[0], 1);
    CHECK_EQ(r.id[0], WSG_CMD_PREPOSITION);
    CHECK_EQ(r.status[0], WSG_E_CMD_ABORTED);
    CHECK_EQ(wsg_axis_speed_mode(&ax), 1);
    CHECK_NEAR(wsg_axis_speed(&ax), -50.0, 1e-9);
    bare_steps(&ax, 1);
    CHECK_NEAR(wsg_axis_speed(&ax), -45.0, 1e-9);
    /* a new owner of speed mode: the old one hears E_CMD_ABORTED; the same
     * owner again hears nothing */
    CHECK_EQ(wsg_axis_request_speed(&ax, -30.0, 5), WSG_E_SUCCESS);
    wsg_axis_settle(&ax);
    REQUIRE(r.n == 2);
    CHECK_EQ(r.tag[1], 0);
    CHECK_EQ(r.status[1], WSG_E_CMD_ABORTED);
    CHECK_EQ(wsg_axis_request_speed(&ax, -20.0, 5), WSG_E_SUCCESS);
    wsg_axis_settle(&ax);
    CHECK_EQ(r.n, 2);
    CHECK_NEAR(wsg_axis_speed(&ax), -45.0, 1e-9); /* no restart */

    /* a move over speed mode: from rest where the fingers are */
    CHECK_EQ(wsg_axis_request_move(&ax, 0, 90.0, 100.0, 2), WSG_E_CMD_PENDING);
    wsg_axis_settle(&ax);
    REQUIRE(r.n == 3);
    CHECK_EQ(r.tag[2], 5);
    CHECK_EQ(r.status[2], WSG_E_CMD_ABORTED);
    CHECK_EQ(wsg_axis_speed(&ax), 0.0);
    CHECK_EQ(wsg_axis_speed_mode(&ax), 0);
    CHECK_EQ(bare_final(&ax, &r, 4000), WSG_E_SUCCESS);
    CHECK_NEAR(wsg_axis_width(&ax), 90.0, 1e-9);

    /* a grasp holding a part (its result given): speed mode takes the
     * clamp over and pushes on at once */
    wsg_axis_set_part(&ax, 40.0, 0);
    CHECK_EQ(wsg_axis_request_grasp(&ax, 40.0, 100.0, 3), WSG_E_CMD_PENDING);
    CHECK_EQ(bare_final(&ax, &r, 4000), WSG_E_SUCCESS);
    CHECK_EQ(wsg_axis_request_speed(&ax, -10.0, 0), WSG_E_SUCCESS);
    wsg_axis_settle(&ax);
    CHECK_EQ(r.n, 5);
    CHECK_EQ(wsg_axis_pressing(&ax), 1);
    /* The grasping state as the grasp left it. */
    CHECK_EQ(wsg_axis_grasp_state(&ax), WSG_GS_HOLDING);
    CHECK_NEAR(wsg_axis_width(&ax), 40.0 - 40.0 / 50.0, 1e-9);
    CHECK_NEAR(wsg_axis_force(&ax), 40.0, 1e-9);
    CHECK_EQ(wsg_axis_flags(&ax), WSG_SF_REFERENCED | WSG_SF_BLOCKED_MINUS);
    CHECK(wsg_axis_idle(&ax));
    CHECK_EQ(ax.clamping, 0); /* the clamp is speed mode's push now */
    /* a grasp replacing speed mode: its own result only */
    CHECK_EQ(wsg_axis_request_grasp(&ax, 39.0, 100.0, 4), WSG_E_CMD_PENDING);
    wsg_axis_settle(&ax);
    REQUIRE(r.n == 6);
    CHECK_EQ(r.status[5], WSG_E_CMD_ABORTED);
    CHECK_EQ(bare_final(&ax, &r, 4000), WSG_E_SUCCESS);
    CHECK_EQ(r.tag[6], 4);
    CHECK_EQ(wsg_axis_grasp_state(&ax), WSG_GS_HOLDING);
}

/* What ends speed mode besides a Stop: FAST STOP, faults, soft limits. */
static void test_speed_ends(void)
{
    struct wsg_axis ax;
    struct rec r;

    bare_init(&ax, &r);
    CHECK_EQ(wsg_axis_request_speed(&ax, -50.0, 0), WSG_E_SUCCESS);
    wsg_axis_settle(&ax);
    bare_steps(&ax, 100);
    wsg_axis_request_fast_stop(&ax);
    wsg_axis_settle(&ax);
    CHECK_EQ(wsg_axis_speed_mode(&ax), 0);
    CHECK_EQ(wsg_axis_speed(&ax), 0.0);
    CHECK_EQ(wsg_axis_grasp_state(&ax), WSG_GS_ERROR);
    CHECK(wsg_axis_flags(&ax) & WSG_SF_FAST_STOP);
    REQUIRE(r.n == 1);
    CHECK_EQ(r.status[0], WSG_E_CMD_ABORTED);
    wsg_axis_request_ack(&ax);
    wsg_axis_settle(&ax);

    /* a power fault: FAST STOP; a temperature fault: ended, grip gone */
    CHECK_EQ(wsg_axis_request_speed(&ax, -50.0, 0), WSG_E_SUCCESS);
    wsg_axis_settle(&ax);
    bare_steps(&ax, 10);
    wsg_axis_set_fault(&ax, WSG_SF_POWER_FAULT, 1);
    bare_steps(&ax, 1);
    CHECK_EQ(wsg_axis_speed_mode(&ax), 0);
    CHECK(wsg_axis_flags(&ax) & WSG_SF_FAST_STOP);
    CHECK_EQ(r.n, 2);
    wsg_axis_set_fault(&ax, WSG_SF_POWER_FAULT, 0);
    wsg_axis_request_ack(&ax);
    wsg_axis_settle(&ax);
    wsg_axis_set_part(&ax, 60.0, 0);
    CHECK_EQ(wsg_axis_request_speed(&ax, -50.0, 0), WSG_E_SUCCESS);
    wsg_axis_settle(&ax);
    bare_steps(&ax, 2000);
    CHECK_EQ(wsg_axis_pressing(&ax), 1);
    wsg_axis_set_fault(&ax, WSG_SF_TEMP_FAULT, 1);
    wsg_axis_settle(&ax);
    CHECK_EQ(wsg_axis_speed_mode(&ax), 0);
    CHECK_EQ(wsg_axis_pressing(&ax), 0);
    CHECK_EQ(wsg_axis_force(&ax), 0.0);
    CHECK_EQ(wsg_axis_grasp_state(&ax), WSG_GS_ERROR);
    CHECK_EQ(r.n, 3);
    CHECK_EQ(r.status[2], WSG_E_CMD_ABORTED);
    wsg_axis_set_fault(&ax, WSG_SF_TEMP_FAULT, 0);
    wsg_axis_set_part(&ax, -1.0, 0);

    /* a soft limit crossed: FAST STOP at the limit, E_RANGE_ERROR */
    wsg_axis_set_soft_limits(&ax, 20.0, 100.0);
    CHECK_EQ(wsg_axis_request_speed(&ax, -100.0, 0), WSG_E_SUCCESS);
    wsg_axis_settle(&ax);
    bare_steps(&ax, 2000);
    CHECK_EQ(wsg_axis_speed_mode(&ax), 0);
    CHECK_NEAR(wsg_axis_width(&ax), 20.0, 1e-9);
    CHECK_EQ(wsg_axis_flags(&ax) & ~WSG_SF_CMD_FAILURE,
             WSG_SF_REFERENCED | WSG_SF_SOFT_LIMIT_MINUS | WSG_SF_FAST_STOP);
    REQUIRE(r.n == 4);
    CHECK_EQ(r.status[3], WSG_E_RANGE_ERROR);
    wsg_axis_request_ack(&ax);
    wsg_axis_settle(&ax);
    /* limits set with the fingers beyond them while heading deeper: at
     * once; heading out goes on */
    CHECK_EQ(wsg_axis_request_speed(&ax, 10.0, 0), WSG_E_SUCCESS);
    wsg_axis_settle(&ax);
    wsg_axis_set_soft_limits(&ax, 50.0, 100.0);
    wsg_axis_settle(&ax);
    CHECK_EQ(wsg_axis_speed_mode(&ax), 1);
    CHECK_EQ(wsg_axis_request_speed(&ax, -10.0, 0), WSG_E_SUCCESS);
    wsg_axis_settle(&ax);
    CHECK_EQ(wsg_axis_speed_mode(&ax), 0);
    CHECK(wsg_axis_flags(&ax) & WSG_SF_FAST_STOP);
    CHECK_EQ(r.n, 5);
    CHECK_EQ(r.status[4], WSG_E_RANGE_ERROR);
}

/* Speed mode seen by a host: its 21h is refused while it runs, 22h stops
 * it, 40h-45h report it as any motion. */
static void test_speed_host(void)
{
    struct tdev t;
    struct wsg_axis *ax;

    tdev_init(&t);
    CHECK_EQ(tdev_home(&t, 0), WSG_E_SUCCESS);
    ax = tdev_axis(&t);
    wsg_axis_set_part(ax, 50.0, 0);
    CHECK_EQ(wsg_axis_request_speed(ax, -80.0, 0), WSG_E_SUCCESS);
    wsg_axis_settle(ax);
    tdev_steps(&t, 100);
    CHECK_EQ(tdev_flags(&t), WSG_SF_REFERENCED | WSG_SF_MOVING);
    /* The controller's own motion: no grasping state. */
    CHECK_EQ(tdev_grasp_state(&t), WSG_GS_IDLE);
    CHECK_NEAR(tdev_getf(&t, WSG_CMD_GET_SPEED), -80.0, 1e-3);
    CHECK_NEAR(tdev_getf(&t, WSG_CMD_GET_WIDTH), wsg_axis_width(ax), 1e-3);
    CHECK_EQ(tdev_move(&t, 0, 90.0f, 100.0f), WSG_E_ALREADY_RUNNING);
    tdev_steps(&t, 2000);
    CHECK_NEAR(tdev_getf(&t, WSG_CMD_GET_FORCE), 40.0, 1e-3);
    CHECK_NEAR(tdev_getf(&t, WSG_CMD_GET_WIDTH), 50.0 - 40.0 / 50.0, 1e-3);
    CHECK_EQ(tdev_getf(&t, WSG_CMD_GET_SPEED), 0.0f);
    CHECK_EQ(tdev_flags(&t), WSG_SF_REFERENCED | WSG_SF_BLOCKED_MINUS);
    CHECK(wsg_device_idle(&t.dev));
    CHECK_EQ(tdev_cmd2f(&t, WSG_CMD_GRASP, 50.0f, 100.0f),
             WSG_E_ALREADY_RUNNING);
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_STOP, NULL, 0), WSG_E_SUCCESS);
    CHECK_EQ(wsg_axis_speed_mode(ax), 0);
    CHECK(tdev_flags(&t) & WSG_SF_AXIS_STOPPED);
    CHECK_EQ(tdev_grasp_state(&t), WSG_GS_IDLE);
    CHECK_EQ(tdev_getf(&t, WSG_CMD_GET_FORCE), 0.0f);
    CHECK_EQ(tdev_move(&t, 0, 90.0f, 100.0f), WSG_E_CMD_PENDING);
    CHECK_EQ(tdev_final(&t, WSG_CMD_PREPOSITION, 4000), WSG_E_SUCCESS);
}

/* The model's ranges, as the daemon's options check their settings and the
 * session commands clamp into them. */
static void test_config_ranges(void)
{
    static const struct {
        const char *model;
        enum wsg_axis_setting s;
        double min, max;
    } want[] = {
        {"wsg50", WSG_AXIS_ACCELERATION, 100.0, 5000.0},
        {"wsg50", WSG_AXIS_FORCE_LIMIT, 5.0, 80.0},
        {"wsg50", WSG_AXIS_CLAMP_TRAVEL, 0.0, 110.0},
        {"wsg50", WSG_AXIS_WIDTH_TOLERANCE, 0.0, 110.0},
        {"wsg50", WSG_AXIS_WIDTH, 0.0, 110.0},
        {"wsg50-210", WSG_AXIS_WIDTH, 0.0, 210.0},
        {"wsg32", WSG_AXIS_FORCE_LIMIT, 5.0, 50.0},
        {"wsg25", WSG_AXIS_FORCE_LIMIT, 5.0, 20.0},
        {"wsg25", WSG_AXIS_CLAMP_TRAVEL, 0.0, 64.0},
    };
    size_t i;

    for (i = 0; i < sizeof want / sizeof want[0]; i++) {
        struct wsg_axis_config cfg, before;
        struct wsg_axis_range r = {-1.0, -1.0};

        REQUIRE(wsg_axis_config_init(&cfg, want[i].model) == 0);
        r = wsg_axis_config_range(&cfg, want[i].s);
        CHECK_NEAR(r.min, want[i].min, 1e-12);
        CHECK_NEAR(r.max, want[i].max, 1e-12);
        /* Outside (NaN too): refused, the range said, nothing written. */
        before = cfg;
        r.min = r.max = -1.0;
        CHECK_EQ(wsg_axis_config_set(&cfg, want[i].s, want[i].max + 0.5, &r),
                 -ERANGE);
        CHECK_NEAR(r.min, want[i].min, 1e-12);
        CHECK_NEAR(r.max, want[i].max, 1e-12);
        CHECK_EQ(wsg_axis_config_set(&cfg, want[i].s, want[i].min - 0.5, NULL),
                 -ERANGE);
        CHECK_EQ(wsg_axis_config_set(&cfg, want[i].s, NAN, NULL), -ERANGE);
        CHECK(memcmp(&cfg, &before, sizeof cfg) == 0);
        /* Both ends are valid. */
        CHECK_EQ(wsg_axis_config_set(&cfg, want[i].s, want[i].min, NULL), 0);
        CHECK_EQ(wsg_axis_config_set(&cfg, want[i].s, want[i].max, NULL), 0);
    }
    {
        struct wsg_axis_config cfg;
        struct wsg_axis ax;

        REQUIRE(wsg_axis_config_init(&cfg, "wsg32") == 0);
        CHECK_EQ(wsg_axis_config_set(&cfg, WSG_AXIS_ACCELERATION, 200, NULL),
                 0);
        CHECK_NEAR(cfg.default_acc, 200.0, 1e-12);
        CHECK_EQ(wsg_axis_config_set(&cfg, WSG_AXIS_FORCE_LIMIT, 30, NULL), 0);
        CHECK_NEAR(cfg.default_force, 30.0, 1e-12);
        CHECK_EQ(wsg_axis_config_set(&cfg, WSG_AXIS_CLAMP_TRAVEL, 3, NULL), 0);
        CHECK_NEAR(cfg.clamp_travel, 3.0, 1e-12);
        CHECK_EQ(wsg_axis_config_set(&cfg, WSG_AXIS_WIDTH_TOLERANCE, 4, NULL),
                 0);
        CHECK_NEAR(cfg.width_tolerance, 4.0, 1e-12);
        /* A session clamps into the same ranges; overdrive raises the
         * force limit's to the overdrive force. */
        wsg_axis_init(&ax, &cfg, NULL, NULL);
        CHECK_NEAR(ax.acc, 200.0, 1e-12);
        CHECK_NEAR(ax.force_limit, 30.0, 1e-12);
        wsg_axis_set_acc(&ax, 1e9);
        CHECK_NEAR(ax.acc, 5000.0, 1e-12);
        wsg_axis_set_acc(&ax, 0.0);
        CHECK_NEAR(ax.acc, 100.0, 1e-12);
        wsg_axis_set_force_limit(&ax, 1e9);
        CHECK_NEAR(ax.force_limit, 50.0, 1e-12);
        wsg_axis_set_overdrive(&ax, 1);
        wsg_axis_set_force_limit(&ax, 1e9);
        CHECK_NEAR(ax.force_limit, 75.0, 1e-12);
        wsg_axis_set_force_limit(&ax, 0.0);
        CHECK_NEAR(ax.force_limit, 5.0, 1e-12);
    }
}

int main(void)
{
    test_config_ranges();
    test_durations();
    test_motion_values();
    test_homing_time();
    test_grasp_hold();
    test_grasp_no_part();
    test_block();
    test_soft_limits();
    test_overdrive();
    test_faults();
    test_obstacle();
    test_homing_into_obstacle();
    test_fault_consequences();
    test_overheating();
    test_reset();
    test_part_wider_than_opening();
    test_overdrive_off_while_holding();
    test_soft_limits_inside();
    test_grasp_end_stop();
    test_world_at_once();
    test_replace_aborts();
    test_grasp_window();
    test_pressing();
    test_speed_ramp();
    test_speed_block();
    test_speed_replace();
    test_speed_ends();
    test_speed_host();
    TEST_EXIT();
}
