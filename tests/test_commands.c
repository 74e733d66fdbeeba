/*
 * Every command of the set through the dispatcher: its success path and each
 * error code the manual lists for it that this gripper can produce, the
 * central state rules (FAST STOP, not referenced, already running, after a
 * Disconnect Announcement), clamping to the model's limits, the
 * auto-update streams against the fake clock, and the output hook that
 * takes every packet instead of the wire.
 */
#include "tdev.h"

static const uint8_t ack_key[3] = {'a', 'c', 'k'};

static void fast_stop(struct tdev *t)
{
    CHECK_EQ(tdev_cmd(t, WSG_CMD_FAST_STOP, NULL, 0), WSG_E_SUCCESS);
    tdev_steps(t, 1);
}

static void acknowledge(struct tdev *t)
{
    CHECK_EQ(tdev_cmd(t, WSG_CMD_ACK_FAST_STOP, ack_key, 3), WSG_E_SUCCESS);
    tdev_steps(t, 1);
}

static void test_loop(void)
{
    struct tdev t;
    uint8_t data[WSG_PAYLOAD_MAX], pkt[WSG_PAYLOAD_MAX + 16];
    size_t i, n;

    tdev_init(&t);
    for (i = 0; i < sizeof data; i++)
        data[i] = (uint8_t)i;
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_LOOP, data, 5), WSG_E_SUCCESS);
    CHECK_EQ(tdev_last(&t)->plen, 5);
    CHECK(memcmp(tdev_last(&t)->params, data, 5) == 0);
    /* 256 bytes: the maximum is looped */
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_LOOP, data, 256), WSG_E_SUCCESS);
    CHECK_EQ(tdev_last(&t)->plen, 256);
    CHECK(memcmp(tdev_last(&t)->params, data, 256) == 0);
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_LOOP, NULL, 0), WSG_E_SUCCESS);
    /* 257 bytes: E_CMD_FORMAT_ERROR, refused by its SIZE field */
    n = wsg_frame_encode(pkt, sizeof pkt, WSG_CMD_LOOP, data, 256);
    wsg_put_u16(pkt + 4, 257);
    tdev_clear(&t);
    tdev_feed(&t, 0, pkt, n);
    REQUIRE(t.sess[0].n == 1);
    CHECK_EQ(tdev_last(&t)->id, WSG_CMD_LOOP);
    CHECK_EQ(tdev_last(&t)->status, WSG_E_CMD_FORMAT_ERROR);
}

static void test_unknown_and_checksum(void)
{
    struct tdev t;
    uint8_t pkt[16];
    size_t n;

    tdev_init(&t);
    CHECK_EQ(tdev_cmd(&t, 0x90, NULL, 0), WSG_E_CMD_UNKNOWN);
    CHECK_EQ(tdev_cmd(&t, 0x64, NULL, 0), WSG_E_CMD_UNKNOWN);
    CHECK_EQ(tdev_cmd(&t, 0xB0, NULL, 0), WSG_E_CMD_UNKNOWN);
    CHECK_EQ(tdev_last(&t)->plen, 0); /* no parameters with an error */
    /* a bad checksum: E_CHECKSUM_ERROR under the received ID */
    n = wsg_frame_encode(pkt, sizeof pkt, WSG_CMD_GET_WIDTH, NULL, 0);
    pkt[n - 1] ^= 0x01;
    tdev_clear(&t);
    tdev_feed(&t, 0, pkt, n);
    REQUIRE(t.sess[0].n == 1);
    CHECK_EQ(tdev_last(&t)->id, WSG_CMD_GET_WIDTH);
    CHECK_EQ(tdev_last(&t)->status, WSG_E_CHECKSUM_ERROR);
    /* SF_CMD_FAILURE: set by that error, cleared by the next success */
    CHECK(tdev_flags(&t) & WSG_SF_CMD_FAILURE);
    CHECK(!(tdev_flags(&t) & WSG_SF_CMD_FAILURE));
}

static void test_no_crc(void)
{
    struct tdev t;
    uint8_t pkt[16];
    size_t n;

    tdev_init(&t);
    wsg_parser_init(&t.sess[0].parser, 0);
    n = wsg_frame_encode(pkt, sizeof pkt, WSG_CMD_GET_WIDTH, NULL, 0);
    pkt[n - 2] = pkt[n - 1] = 0; /* hosts send 0000h with CRC off */
    tdev_feed(&t, 0, pkt, n);
    REQUIRE(t.sess[0].n == 1);
    CHECK_EQ(tdev_last(&t)->status, WSG_E_SUCCESS);
}

static void test_disconnect(void)
{
    struct tdev t;

    tdev_init(&t);
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_DISCONNECT, ack_key, 1),
             WSG_E_NO_PARAM_EXPECTED);
    /* not a connection-oriented interface */
    t.sess[1].s.flags = 0;
    CHECK_EQ(tdev_cmd_on(&t, 1, WSG_CMD_DISCONNECT, NULL, 0),
             WSG_E_NOT_AVAILABLE);

    /* a movement in progress is aborted at once */
    CHECK_EQ(tdev_home(&t, 0), WSG_E_SUCCESS);
    CHECK_EQ(tdev_move(&t, 0, 10.0f, 50.0f), WSG_E_CMD_PENDING);
    tdev_steps(&t, 20);
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_DISCONNECT, NULL, 0), WSG_E_SUCCESS);
    CHECK_EQ(tdev_final(&t, WSG_CMD_PREPOSITION, 10), WSG_E_CMD_ABORTED);
    /* every further command of that session: E_ACCESS_DENIED */
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_GET_WIDTH, NULL, 0), WSG_E_ACCESS_DENIED);
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_LOOP, NULL, 0), WSG_E_ACCESS_DENIED);
    /* its close causes no FAST STOP */
    wsg_device_session_closed(&t.dev, &t.sess[0].s);
    tdev_steps(&t, 1);
    CHECK(!(wsg_axis_flags(tdev_axis(&t)) & WSG_SF_FAST_STOP));

    /* a close without the announcement: FAST STOP */
    wsg_device_session_closed(&t.dev, &t.sess[1].s); /* not a connection */
    tdev_steps(&t, 1);
    CHECK(!(wsg_axis_flags(tdev_axis(&t)) & WSG_SF_FAST_STOP));
    t.sess[1].s.flags = WSG_SESSION_CONNECTION;
    wsg_device_session_closed(&t.dev, &t.sess[1].s);
    tdev_steps(&t, 1);
    CHECK(wsg_axis_flags(tdev_axis(&t)) & WSG_SF_FAST_STOP);

    /* unless the option turns it off */
    tdev_init(&t);
    t.dev.disconnect_fast_stop = 0;
    wsg_device_session_closed(&t.dev, &t.sess[0].s);
    tdev_steps(&t, 1);
    CHECK(!(wsg_axis_flags(tdev_axis(&t)) & WSG_SF_FAST_STOP));
}

static void test_homing(void)
{
    struct tdev t;
    uint8_t dir;

    tdev_init(&t);
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_HOMING, NULL, 0), WSG_E_CMD_FORMAT_ERROR);
    dir = 3;
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_HOMING, &dir, 1), WSG_E_INVALID_PARAMETER);
    dir = 0;
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_HOMING, &dir, 1), WSG_E_CMD_PENDING);
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_HOMING, &dir, 1), WSG_E_ALREADY_RUNNING);
    CHECK_EQ(tdev_final(&t, WSG_CMD_HOMING, 4000), WSG_E_SUCCESS);
    CHECK(tdev_flags(&t) & WSG_SF_REFERENCED);
    /* default direction positive: the open end stop */
    CHECK_NEAR(tdev_getf(&t, WSG_CMD_GET_WIDTH), 110.0, 1e-3);
    dir = 2;
    CHECK_EQ(tdev_home(&t, dir), WSG_E_SUCCESS);
    CHECK_NEAR(tdev_getf(&t, WSG_CMD_GET_WIDTH), 0.0, 1e-3);
    /* aborted by Stop */
    dir = 1;
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_HOMING, &dir, 1), WSG_E_CMD_PENDING);
    tdev_steps(&t, 100);
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_STOP, NULL, 0), WSG_E_SUCCESS);
    CHECK_EQ(tdev_final(&t, WSG_CMD_HOMING, 10), WSG_E_CMD_ABORTED);
    /* refused in FAST STOP */
    fast_stop(&t);
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_HOMING, &dir, 1), WSG_E_ACCESS_DENIED);
    acknowledge(&t);
    CHECK_EQ(tdev_home(&t, dir), WSG_E_SUCCESS);
}

static void test_preposition(void)
{
    struct tdev t;
    uint8_t p[9] = {0};

    tdev_init(&t);
    CHECK_EQ(tdev_move(&t, 0, 50.0f, 50.0f), WSG_E_NOT_INITIALIZED);
    CHECK_EQ(tdev_home(&t, 0), WSG_E_SUCCESS);
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_PREPOSITION, p, 8), WSG_E_CMD_FORMAT_ERROR);
    CHECK_EQ(tdev_move(&t, 0x04, 50.0f, 50.0f), WSG_E_INVALID_PARAMETER);
    CHECK_EQ(tdev_move(&t, 0, 50.0f, 400.0f), WSG_E_CMD_PENDING);
    CHECK_EQ(tdev_move(&t, 0, 60.0f, 50.0f), WSG_E_ALREADY_RUNNING);
    CHECK_EQ(tdev_final(&t, WSG_CMD_PREPOSITION, 4000), WSG_E_SUCCESS);
    CHECK_NEAR(tdev_getf(&t, WSG_CMD_GET_WIDTH), 50.0, 1e-3);
    CHECK(tdev_flags(&t) & WSG_SF_TARGET_POS_REACHED);
    /* relative movement */
    CHECK_EQ(tdev_move(&t, WSG_MOVE_RELATIVE, -20.0f, 100.0f),
             WSG_E_CMD_PENDING);
    CHECK_EQ(tdev_final(&t, WSG_CMD_PREPOSITION, 4000), WSG_E_SUCCESS);
    CHECK_NEAR(tdev_getf(&t, WSG_CMD_GET_WIDTH), 30.0, 1e-3);
    /* beyond the stroke: clamped to it */
    CHECK_EQ(tdev_move(&t, 0, 500.0f, 1000.0f), WSG_E_CMD_PENDING);
    CHECK_EQ(tdev_final(&t, WSG_CMD_PREPOSITION, 4000), WSG_E_SUCCESS);
    CHECK_NEAR(tdev_getf(&t, WSG_CMD_GET_WIDTH), 110.0, 1e-3);
    /* soft limits: a target outside them is refused */
    CHECK_EQ(tdev_cmd2f(&t, WSG_CMD_SET_SOFT_LIMITS, 20.0f, 100.0f),
             WSG_E_SUCCESS);
    CHECK_EQ(tdev_move(&t, 0, 10.0f, 50.0f), WSG_E_RANGE_ERROR);
    CHECK_EQ(tdev_move(&t, WSG_MOVE_RELATIVE, 5.0f, 50.0f), WSG_E_RANGE_ERROR);
    CHECK_EQ(tdev_move(&t, 0, 20.0f, 400.0f), WSG_E_CMD_PENDING);
    CHECK_EQ(tdev_final(&t, WSG_CMD_PREPOSITION, 4000), WSG_E_SUCCESS);
    CHECK(tdev_flags(&t) & WSG_SF_SOFT_LIMIT_MINUS);
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_CLEAR_SOFT_LIMITS, NULL, 0), WSG_E_SUCCESS);
    /* aborted by Stop: E_CMD_ABORTED, SF_AXIS_STOPPED */
    CHECK_EQ(tdev_move(&t, 0, 100.0f, 20.0f), WSG_E_CMD_PENDING);
    tdev_steps(&t, 50);
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_STOP, NULL, 0), WSG_E_SUCCESS);
    CHECK_EQ(tdev_final(&t, WSG_CMD_PREPOSITION, 10), WSG_E_CMD_ABORTED);
    CHECK(tdev_flags(&t) & WSG_SF_AXIS_STOPPED);
    CHECK(!(tdev_flags(&t) & WSG_SF_MOVING));
    /* the next movement command clears it */
    CHECK_EQ(tdev_move(&t, 0, 40.0f, 100.0f), WSG_E_CMD_PENDING);
    tdev_steps(&t, 1);
    CHECK(!(tdev_flags(&t) & WSG_SF_AXIS_STOPPED));
    CHECK(tdev_flags(&t) & WSG_SF_MOVING);
    CHECK_EQ(tdev_final(&t, WSG_CMD_PREPOSITION, 4000), WSG_E_SUCCESS);
    /* blocked by a part: E_AXIS_BLOCKED */
    wsg_axis_set_part(tdev_axis(&t), 20.0, 0);
    CHECK_EQ(tdev_move(&t, WSG_MOVE_STOP_ON_BLOCK, 0.0f, 100.0f),
             WSG_E_CMD_PENDING);
    CHECK_EQ(tdev_final(&t, WSG_CMD_PREPOSITION, 4000), WSG_E_AXIS_BLOCKED);
    CHECK(tdev_flags(&t) & WSG_SF_BLOCKED_MINUS);
    /* in FAST STOP: E_ACCESS_DENIED */
    fast_stop(&t);
    CHECK_EQ(tdev_move(&t, 0, 50.0f, 50.0f), WSG_E_ACCESS_DENIED);
    acknowledge(&t);
    CHECK_EQ(tdev_move(&t, 0, 50.0f, 50.0f), WSG_E_CMD_PENDING);
}

static void test_stop_and_fast_stop(void)
{
    struct tdev t;

    tdev_init(&t);
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_STOP, ack_key, 1), WSG_E_NO_PARAM_EXPECTED);
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_STOP, NULL, 0), WSG_E_SUCCESS);
    CHECK_EQ(tdev_home(&t, 0), WSG_E_SUCCESS);
    /* Stop, then a new motion in the same instant: the usual sequence */
    CHECK_EQ(tdev_move(&t, 0, 20.0f, 50.0f), WSG_E_CMD_PENDING);
    tdev_steps(&t, 10);
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_STOP, NULL, 0), WSG_E_SUCCESS);
    CHECK_EQ(tdev_move(&t, 0, 80.0f, 50.0f), WSG_E_CMD_PENDING);
    CHECK_EQ(tdev_final(&t, WSG_CMD_PREPOSITION, 10), WSG_E_CMD_ABORTED);
    CHECK_EQ(tdev_final(&t, WSG_CMD_PREPOSITION, 4000), WSG_E_SUCCESS);
    CHECK_NEAR(tdev_getf(&t, WSG_CMD_GET_WIDTH), 80.0, 1e-3);

    /* FAST STOP aborts a motion and refuses the next until "ack" */
    CHECK_EQ(tdev_move(&t, 0, 20.0f, 50.0f), WSG_E_CMD_PENDING);
    tdev_steps(&t, 10);
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_FAST_STOP, NULL, 0), WSG_E_SUCCESS);
    CHECK_EQ(tdev_final(&t, WSG_CMD_PREPOSITION, 10), WSG_E_CMD_ABORTED);
    CHECK(tdev_flags(&t) & WSG_SF_FAST_STOP);
    CHECK_EQ(tdev_grasp_state(&t), WSG_GS_ERROR);
    CHECK_EQ(tdev_cmd2f(&t, WSG_CMD_GRASP, 10.0f, 50.0f), WSG_E_ACCESS_DENIED);
    CHECK_EQ(tdev_cmd2f(&t, WSG_CMD_RELEASE, 10.0f, 50.0f),
             WSG_E_ACCESS_DENIED);
    /* queries and settings still work in FAST STOP */
    CHECK_EQ(tdev_cmd1f(&t, WSG_CMD_SET_FORCE_LIMIT, 30.0f), WSG_E_SUCCESS);
    /* a wrong key: E_CMD_FORMAT_ERROR, and still in FAST STOP */
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_ACK_FAST_STOP, "ACK", 3),
             WSG_E_CMD_FORMAT_ERROR);
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_ACK_FAST_STOP, ack_key, 2),
             WSG_E_CMD_FORMAT_ERROR);
    tdev_steps(&t, 1);
    CHECK(tdev_flags(&t) & WSG_SF_FAST_STOP);
    /* Right after "ack", before a step: the flags agree with its
     * E_SUCCESS. */
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_ACK_FAST_STOP, ack_key, 3), WSG_E_SUCCESS);
    CHECK(!(tdev_flags(&t) & WSG_SF_FAST_STOP));
    tdev_steps(&t, 1);
    CHECK(!(tdev_flags(&t) & WSG_SF_FAST_STOP));
    CHECK_EQ(tdev_grasp_state(&t), WSG_GS_IDLE);
    /* "ack" with nothing to acknowledge: E_SUCCESS */
    acknowledge(&t);
    /* FAST STOP takes any payload: an emergency stop is never refused */
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_FAST_STOP, ack_key, 3), WSG_E_SUCCESS);
    /* a motion accepted just before a FAST STOP still gets its result */
    acknowledge(&t);
    CHECK_EQ(tdev_move(&t, 0, 30.0f, 50.0f), WSG_E_CMD_PENDING);
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_FAST_STOP, NULL, 0), WSG_E_SUCCESS);
    CHECK_EQ(tdev_final(&t, WSG_CMD_PREPOSITION, 10), WSG_E_CMD_ABORTED);
}

static void test_grasp_release(void)
{
    struct tdev t;
    uint8_t p[9] = {0}; /* up to 9 bytes are sent below */

    tdev_init(&t);
    CHECK_EQ(tdev_cmd2f(&t, WSG_CMD_GRASP, 40.0f, 50.0f),
             WSG_E_NOT_INITIALIZED);
    CHECK_EQ(tdev_cmd2f(&t, WSG_CMD_RELEASE, 40.0f, 50.0f),
             WSG_E_NOT_INITIALIZED);
    CHECK_EQ(tdev_home(&t, 0), WSG_E_SUCCESS);
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_GRASP, p, 4), WSG_E_CMD_FORMAT_ERROR);
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_RELEASE, p, 9), WSG_E_CMD_FORMAT_ERROR);

    /* no part: E_CMD_FAILED */
    CHECK_EQ(tdev_cmd2f(&t, WSG_CMD_GRASP, 40.0f, 100.0f), WSG_E_CMD_PENDING);
    CHECK_EQ(tdev_cmd2f(&t, WSG_CMD_GRASP, 40.0f, 100.0f),
             WSG_E_ALREADY_RUNNING);
    CHECK_EQ(tdev_cmd2f(&t, WSG_CMD_RELEASE, 40.0f, 100.0f),
             WSG_E_ALREADY_RUNNING);
    CHECK_EQ(tdev_final(&t, WSG_CMD_GRASP, 4000), WSG_E_CMD_FAILED);
    CHECK_EQ(tdev_grasp_state(&t), WSG_GS_NO_PART);

    /* a part: held */
    CHECK_EQ(tdev_cmd2f(&t, WSG_CMD_RELEASE, 60.0f, 100.0f),
             WSG_E_CMD_PENDING);
    CHECK_EQ(tdev_final(&t, WSG_CMD_RELEASE, 4000), WSG_E_SUCCESS);
    wsg_axis_set_part(tdev_axis(&t), 40.0, 0);
    CHECK_EQ(tdev_cmd2f(&t, WSG_CMD_GRASP, 40.0f, 100.0f), WSG_E_CMD_PENDING);
    CHECK_EQ(tdev_final(&t, WSG_CMD_GRASP, 4000), WSG_E_SUCCESS);
    CHECK_EQ(tdev_grasp_state(&t), WSG_GS_HOLDING);
    /* release: back to idle */
    CHECK_EQ(tdev_cmd2f(&t, WSG_CMD_RELEASE, 60.0f, 100.0f),
             WSG_E_CMD_PENDING);
    CHECK_EQ(tdev_final(&t, WSG_CMD_RELEASE, 4000), WSG_E_SUCCESS);
    CHECK_EQ(tdev_grasp_state(&t), WSG_GS_IDLE);
    CHECK_NEAR(tdev_getf(&t, WSG_CMD_GET_WIDTH), 60.0, 1e-3);

    /* aborted by Stop */
    CHECK_EQ(tdev_cmd2f(&t, WSG_CMD_GRASP, 40.0f, 10.0f), WSG_E_CMD_PENDING);
    tdev_steps(&t, 50);
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_STOP, NULL, 0), WSG_E_SUCCESS);
    CHECK_EQ(tdev_final(&t, WSG_CMD_GRASP, 10), WSG_E_CMD_ABORTED);
    CHECK_EQ(tdev_cmd2f(&t, WSG_CMD_RELEASE, 80.0f, 10.0f), WSG_E_CMD_PENDING);
    tdev_steps(&t, 50);
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_STOP, NULL, 0), WSG_E_SUCCESS);
    CHECK_EQ(tdev_final(&t, WSG_CMD_RELEASE, 10), WSG_E_CMD_ABORTED);

    /* WIDTH / OPENWIDTH against the soft limits: E_RANGE_ERROR */
    CHECK_EQ(tdev_cmd2f(&t, WSG_CMD_SET_SOFT_LIMITS, 30.0f, 90.0f),
             WSG_E_SUCCESS);
    CHECK_EQ(tdev_cmd2f(&t, WSG_CMD_GRASP, 20.0f, 50.0f), WSG_E_RANGE_ERROR);
    CHECK_EQ(tdev_cmd2f(&t, WSG_CMD_RELEASE, 100.0f, 50.0f),
             WSG_E_RANGE_ERROR);
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_CLEAR_SOFT_LIMITS, NULL, 0), WSG_E_SUCCESS);
    /* in FAST STOP */
    fast_stop(&t);
    CHECK_EQ(tdev_cmd2f(&t, WSG_CMD_GRASP, 40.0f, 50.0f), WSG_E_ACCESS_DENIED);
}

static void test_motion_config(void)
{
    struct tdev t;
    uint8_t b = 0;

    tdev_init(&t);
    /* acceleration: clamped to 100..5000 */
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_SET_ACCELERATION, &b, 1),
             WSG_E_CMD_FORMAT_ERROR);
    CHECK_EQ(tdev_cmd1f(&t, WSG_CMD_SET_ACCELERATION, 1000.0f), WSG_E_SUCCESS);
    CHECK_EQ(tdev_getf(&t, WSG_CMD_GET_ACCELERATION), 1000.0f);
    CHECK_EQ(tdev_cmd1f(&t, WSG_CMD_SET_ACCELERATION, 10.0f), WSG_E_SUCCESS);
    CHECK_EQ(tdev_getf(&t, WSG_CMD_GET_ACCELERATION), 100.0f);
    CHECK_EQ(tdev_cmd1f(&t, WSG_CMD_SET_ACCELERATION, 1e9f), WSG_E_SUCCESS);
    CHECK_EQ(tdev_getf(&t, WSG_CMD_GET_ACCELERATION), 5000.0f);
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_GET_ACCELERATION, &b, 1),
             WSG_E_NO_PARAM_EXPECTED);

    /* force limit: 40 N by default, clamped to 5..80, or 5..120 with
     * overdrive */
    CHECK_EQ(tdev_getf(&t, WSG_CMD_GET_FORCE_LIMIT), 40.0f);
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_SET_FORCE_LIMIT, &b, 1),
             WSG_E_CMD_FORMAT_ERROR);
    CHECK_EQ(tdev_cmd1f(&t, WSG_CMD_SET_FORCE_LIMIT, 1.0f), WSG_E_SUCCESS);
    CHECK_EQ(tdev_getf(&t, WSG_CMD_GET_FORCE_LIMIT), 5.0f);
    CHECK_EQ(tdev_cmd1f(&t, WSG_CMD_SET_FORCE_LIMIT, 100.0f), WSG_E_SUCCESS);
    CHECK_EQ(tdev_getf(&t, WSG_CMD_GET_FORCE_LIMIT), 80.0f);
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_GET_FORCE_LIMIT, &b, 1),
             WSG_E_NO_PARAM_EXPECTED);
    b = 1;
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_OVERDRIVE, &b, 1), WSG_E_SUCCESS);
    CHECK(tdev_flags(&t) & WSG_SF_OVERDRIVE_MODE);
    CHECK_EQ(tdev_cmd1f(&t, WSG_CMD_SET_FORCE_LIMIT, 200.0f), WSG_E_SUCCESS);
    CHECK_EQ(tdev_getf(&t, WSG_CMD_GET_FORCE_LIMIT), 120.0f);
    /* leaving overdrive reduces the limit to nominal */
    b = 0;
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_OVERDRIVE, &b, 1), WSG_E_SUCCESS);
    CHECK(!(tdev_flags(&t) & WSG_SF_OVERDRIVE_MODE));
    CHECK_EQ(tdev_getf(&t, WSG_CMD_GET_FORCE_LIMIT), 80.0f);
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_OVERDRIVE, NULL, 0), WSG_E_CMD_FORMAT_ERROR);
    b = 2;
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_OVERDRIVE, &b, 1), WSG_E_INVALID_PARAMETER);

    /* soft limits */
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_GET_SOFT_LIMITS, NULL, 0),
             WSG_E_NOT_AVAILABLE);
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_SET_SOFT_LIMITS, &b, 1),
             WSG_E_CMD_FORMAT_ERROR);
    CHECK_EQ(tdev_cmd2f(&t, WSG_CMD_SET_SOFT_LIMITS, 60.0f, 10.0f),
             WSG_E_INVALID_PARAMETER);
    CHECK_EQ(tdev_cmd2f(&t, WSG_CMD_SET_SOFT_LIMITS, 10.5f, 99.5f),
             WSG_E_SUCCESS);
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_GET_SOFT_LIMITS, NULL, 0), WSG_E_SUCCESS);
    CHECK_EQ(tdev_last(&t)->plen, 8);
    CHECK_EQ(wsg_get_f32(tdev_last(&t)->params), 10.5f);
    CHECK_EQ(wsg_get_f32(tdev_last(&t)->params + 4), 99.5f);
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_GET_SOFT_LIMITS, &b, 1),
             WSG_E_NO_PARAM_EXPECTED);
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_CLEAR_SOFT_LIMITS, &b, 1),
             WSG_E_NO_PARAM_EXPECTED);
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_CLEAR_SOFT_LIMITS, NULL, 0), WSG_E_SUCCESS);
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_GET_SOFT_LIMITS, NULL, 0),
             WSG_E_NOT_AVAILABLE);
}

static void test_tare(void)
{
    struct tdev t;
    struct wsg_axis_config cfg;
    uint8_t b = 0;

    tdev_init(&t);
    /* no force measurement fingers by default */
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_TARE, NULL, 0), WSG_E_NOT_AVAILABLE);
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_TARE, &b, 1), WSG_E_NO_PARAM_EXPECTED);

    REQUIRE(wsg_axis_config_init(&cfg, "wsg50") == 0);
    cfg.force_sensor = 1;
    tdev_init_cfg(&t, &cfg);
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_TARE, NULL, 0), WSG_E_SUCCESS);
    CHECK_EQ(tdev_home(&t, 0), WSG_E_SUCCESS);
    wsg_axis_set_part(tdev_axis(&t), 50.0, 0);
    CHECK_EQ(tdev_cmd2f(&t, WSG_CMD_GRASP, 50.0f, 100.0f), WSG_E_CMD_PENDING);
    /* grasping is force control mode too: D9 shows it, and tare is
     * refused whenever D9 is set (3.3.9) */
    tdev_steps(&t, 10);
    CHECK_EQ(tdev_grasp_state(&t), WSG_GS_GRASPING);
    CHECK(tdev_flags(&t) & WSG_SF_FORCECNTL_MODE);
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_TARE, NULL, 0), WSG_E_ACCESS_DENIED);
    CHECK_EQ(tdev_final(&t, WSG_CMD_GRASP, 4000), WSG_E_SUCCESS);
    /* force control mode while holding: tare refused */
    CHECK(tdev_flags(&t) & WSG_SF_FORCECNTL_MODE);
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_TARE, NULL, 0), WSG_E_ACCESS_DENIED);
    /* released: out of force control mode, tare allowed again */
    CHECK_EQ(tdev_cmd2f(&t, WSG_CMD_RELEASE, 70.0f, 100.0f),
             WSG_E_CMD_PENDING);
    CHECK_EQ(tdev_final(&t, WSG_CMD_RELEASE, 4000), WSG_E_SUCCESS);
    CHECK(!(tdev_flags(&t) & WSG_SF_FORCECNTL_MODE));
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_TARE, NULL, 0), WSG_E_SUCCESS);
}

static void test_state_queries(void)
{
    struct tdev t;
    uint8_t p[3] = {0, 0, 0};
    const uint8_t ids[] = {WSG_CMD_GET_SYSTEM_STATE, WSG_CMD_GET_GRASP_STATE,
                           WSG_CMD_GET_WIDTH, WSG_CMD_GET_SPEED,
                           WSG_CMD_GET_FORCE};
    size_t i;

    tdev_init(&t);
    for (i = 0; i < sizeof ids; i++) {
        CHECK_EQ(tdev_cmd(&t, ids[i], NULL, 0), WSG_E_SUCCESS);
        CHECK_EQ(tdev_last(&t)->plen, ids[i] == 0x41 ? 1 : 4);
        CHECK_EQ(tdev_cmd(&t, ids[i], p, 3), WSG_E_SUCCESS);
        CHECK_EQ(tdev_cmd(&t, ids[i], p, 2), WSG_E_CMD_FORMAT_ERROR);
        CHECK_EQ(tdev_cmd(&t, ids[i], p, 1), WSG_E_CMD_FORMAT_ERROR);
        p[0] = 4;
        CHECK_EQ(tdev_cmd(&t, ids[i], p, 3), WSG_E_INVALID_PARAMETER);
        p[0] = 0;
    }
    /* before homing nothing is set but the last command's failure, which
     * the next successful command clears; width mid-stroke at power-up */
    CHECK_EQ(tdev_flags(&t), WSG_SF_CMD_FAILURE);
    CHECK_EQ(tdev_flags(&t), 0);
    CHECK_NEAR(tdev_getf(&t, WSG_CMD_GET_WIDTH), 55.0, 1e-3);
    CHECK_EQ(tdev_getf(&t, WSG_CMD_GET_SPEED), 0.0f);
    CHECK_EQ(tdev_getf(&t, WSG_CMD_GET_FORCE), 0.0f);

    /* temperature: int16 in 0.1 degC */
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_GET_TEMPERATURE, NULL, 0), WSG_E_SUCCESS);
    CHECK_EQ(tdev_last(&t)->plen, 2);
    CHECK_EQ((int16_t)wsg_get_u16(tdev_last(&t)->params), 250);
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_GET_TEMPERATURE, p, 1),
             WSG_E_NO_PARAM_EXPECTED);
}

static void test_grasp_stats(void)
{
    struct tdev t;
    uint8_t b[2] = {0, 0}; /* up to 2 bytes are sent below */

    tdev_init(&t);
    CHECK_EQ(tdev_home(&t, 0), WSG_E_SUCCESS);
    CHECK_EQ(tdev_cmd2f(&t, WSG_CMD_GRASP, 40.0f, 200.0f), WSG_E_CMD_PENDING);
    CHECK_EQ(tdev_final(&t, WSG_CMD_GRASP, 4000), WSG_E_CMD_FAILED);
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_GET_GRASP_STATS, NULL, 0), WSG_E_SUCCESS);
    CHECK_EQ(tdev_last(&t)->plen, 8);
    CHECK_EQ(wsg_get_u32(tdev_last(&t)->params), 1);
    CHECK_EQ(wsg_get_u16(tdev_last(&t)->params + 4), 1);
    CHECK_EQ(wsg_get_u16(tdev_last(&t)->params + 6), 0);
    b[0] = 2;
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_GET_GRASP_STATS, b, 1),
             WSG_E_INVALID_PARAMETER);
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_GET_GRASP_STATS, b, 2),
             WSG_E_CMD_FORMAT_ERROR);
    /* D0: reset after reading */
    b[0] = 1;
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_GET_GRASP_STATS, b, 1), WSG_E_SUCCESS);
    CHECK_EQ(wsg_get_u32(tdev_last(&t)->params), 1);
    b[0] = 0;
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_GET_GRASP_STATS, b, 1), WSG_E_SUCCESS);
    CHECK_EQ(wsg_get_u32(tdev_last(&t)->params), 0);
}

static void test_system_config(void)
{
    struct tdev t;
    uint8_t tag[80];
    const struct tdev_pkt *p;

    tdev_init(&t);
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_GET_SYSTEM_INFO, NULL, 0), WSG_E_SUCCESS);
    p = tdev_last(&t);
    CHECK_EQ(p->plen, 8);
    CHECK_EQ(p->params[0], 1); /* WSG 50 */
    CHECK_EQ(wsg_get_u16(p->params + 2), 0x2200);
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_GET_SYSTEM_INFO, tag, 1),
             WSG_E_NO_PARAM_EXPECTED);

    CHECK_EQ(tdev_cmd(&t, WSG_CMD_GET_SYSTEM_LIMITS, NULL, 0), WSG_E_SUCCESS);
    p = tdev_last(&t);
    CHECK_EQ(p->plen, 32);
    CHECK_EQ(wsg_get_f32(p->params), 110.0f);
    CHECK_EQ(wsg_get_f32(p->params + 4), 5.0f);
    CHECK_EQ(wsg_get_f32(p->params + 8), 420.0f);
    CHECK_EQ(wsg_get_f32(p->params + 12), 100.0f);
    CHECK_EQ(wsg_get_f32(p->params + 16), 5000.0f);
    CHECK_EQ(wsg_get_f32(p->params + 20), 5.0f);
    CHECK_EQ(wsg_get_f32(p->params + 24), 80.0f);
    CHECK_EQ(wsg_get_f32(p->params + 28), 120.0f);
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_GET_SYSTEM_LIMITS, tag, 1),
             WSG_E_NO_PARAM_EXPECTED);

    /* device tag */
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_GET_DEVICE_TAG, NULL, 0),
             WSG_E_NOT_AVAILABLE);
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_SET_DEVICE_TAG, "cell 4 left", 11),
             WSG_E_SUCCESS);
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_GET_DEVICE_TAG, NULL, 0), WSG_E_SUCCESS);
    CHECK_EQ(tdev_last(&t)->plen, 11);
    CHECK(memcmp(tdev_last(&t)->params, "cell 4 left", 11) == 0);
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_GET_DEVICE_TAG, tag, 1),
             WSG_E_NO_PARAM_EXPECTED);
    /* 64 characters and trailing NULs: accepted, NULs stripped */
    memset(tag, 'x', 64);
    memset(tag + 64, 0, 16);
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_SET_DEVICE_TAG, tag, 80), WSG_E_SUCCESS);
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_GET_DEVICE_TAG, NULL, 0), WSG_E_SUCCESS);
    CHECK_EQ(tdev_last(&t)->plen, 64);
    /* 65 characters: E_OVERRUN, the old tag stays */
    memset(tag, 'y', 65);
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_SET_DEVICE_TAG, tag, 65), WSG_E_OVERRUN);
    /* a control character: E_INVALID_PARAMETER */
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_SET_DEVICE_TAG, "a\nb", 3),
             WSG_E_INVALID_PARAMETER);
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_GET_DEVICE_TAG, NULL, 0), WSG_E_SUCCESS);
    CHECK_EQ(tdev_last(&t)->params[0], 'x');
}

static void test_streams(void)
{
    struct tdev t;
    uint8_t p[3];
    int i, n;

    tdev_init(&t);
    CHECK_EQ(tdev_home(&t, 0), WSG_E_SUCCESS);
    tdev_clear(&t);
    /* 43h every 10 ms: answered at once, then one packet per period */
    p[0] = 1;
    wsg_put_u16(p + 1, 10);
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_GET_WIDTH, p, 3), WSG_E_SUCCESS);
    CHECK_EQ(wsg_axis_time(tdev_axis(&t)), 0 + wsg_axis_time(tdev_axis(&t)));
    tdev_clear(&t);
    for (i = 0; i < 100; i++) {
        wsg_device_step(&t.dev);
        wsg_device_poll_streams(&t.dev, &t.sess[0].s);
    }
    CHECK_EQ(t.sess[0].n, 10);
    CHECK_EQ(t.sess[0].pkts[0].id, WSG_CMD_GET_WIDTH);
    CHECK_EQ(t.sess[1].n, 0); /* per session */

    /* change-only: silent while nothing changes */
    p[0] = 3;
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_GET_WIDTH, p, 3), WSG_E_SUCCESS);
    tdev_clear(&t);
    for (i = 0; i < 100; i++) {
        wsg_device_step(&t.dev);
        wsg_device_poll_streams(&t.dev, &t.sess[0].s);
    }
    CHECK_EQ(t.sess[0].n, 0);
    /* ... and at most once per period while the width changes */
    CHECK_EQ(tdev_move(&t, 0, 50.0f, 100.0f), WSG_E_CMD_PENDING);
    tdev_clear(&t);
    for (i = 0; i < 200; i++) {
        wsg_device_step(&t.dev);
        wsg_device_poll_streams(&t.dev, &t.sess[0].s);
    }
    n = t.sess[0].n;
    CHECK(n >= 15 && n <= 20);

    /* two streams at once; FLAGS 0 ends one and answers the value */
    p[0] = 1;
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_GET_SYSTEM_STATE, p, 3), WSG_E_SUCCESS);
    CHECK_EQ(t.sess[0].s.nstreams, 2);
    p[0] = 0;
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_GET_WIDTH, p, 3), WSG_E_SUCCESS);
    CHECK_EQ(tdev_last(&t)->plen, 4);
    CHECK_EQ(t.sess[0].s.nstreams, 1);
    tdev_clear(&t);
    for (i = 0; i < 50; i++) {
        wsg_device_step(&t.dev);
        wsg_device_poll_streams(&t.dev, &t.sess[0].s);
    }
    CHECK_EQ(t.sess[0].n, 5);
    for (i = 0; i < t.sess[0].n; i++)
        CHECK_EQ(t.sess[0].pkts[i].id, WSG_CMD_GET_SYSTEM_STATE);
    /* an empty payload is a one-time read and leaves the stream alone */
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_GET_SYSTEM_STATE, NULL, 0), WSG_E_SUCCESS);
    CHECK_EQ(t.sess[0].s.nstreams, 1);
    /* dropped with the session */
    wsg_device_session_closed(&t.dev, &t.sess[0].s);
    CHECK_EQ(t.sess[0].s.nstreams, 0);
}

/* The output hook: what it was given, in order, and what was logged. */
struct hook_seen {
    int n;
    uint8_t id[8];
    uint32_t tag[8];
    int traced;
};

static void hook_delay(void *ctx, struct wsg_session *s, const uint8_t *pkt,
                       size_t len)
{
    struct hook_seen *h = ctx;

    REQUIRE(h->n < 8);
    REQUIRE(len > 3);
    h->id[h->n] = pkt[3];
    h->tag[h->n] = s->tag;
    h->n++;
}

static void hook_trace(void *ctx, const struct wsg_session *s,
                       const uint8_t *pkt, size_t len)
{
    struct hook_seen *h = ctx;

    (void)s;
    (void)pkt;
    (void)len;
    h->traced++;
}

/* A request into session i, whatever it is answered. */
static void feed_cmd(struct tdev *t, int i, uint8_t id, const void *payload,
                     size_t len)
{
    uint8_t pkt[WSG_HEADER_LEN + 16 + WSG_CRC_LEN];
    size_t n = wsg_frame_encode(pkt, sizeof pkt, id, payload, len);

    REQUIRE(n > 0);
    tdev_feed(t, i, pkt, n);
}

static void test_output_hook(void)
{
    struct tdev t;
    struct hook_seen h;
    uint8_t p[3], dir = 0, pkt[16];
    size_t n;
    int i;

    memset(&h, 0, sizeof h);
    tdev_init(&t);
    t.dev.delay = hook_delay;
    t.dev.delay_ctx = &h;
    t.dev.trace_out = hook_trace;
    t.dev.trace_ctx = &h;
    /* A reply, a motion's pending answer and its final result, and a
     * stream's packets all go to the hook, none to the wire or the log
     * (the log shows a packet when it leaves). */
    feed_cmd(&t, 0, WSG_CMD_GET_WIDTH, NULL, 0);
    CHECK_EQ(h.n, 1);
    CHECK_EQ(h.id[0], WSG_CMD_GET_WIDTH);
    CHECK_EQ(h.tag[0], 1);
    feed_cmd(&t, 1, WSG_CMD_HOMING, &dir, 1);
    CHECK_EQ(h.n, 2);
    CHECK_EQ(h.tag[1], 2);
    for (i = 0; i < 10000 && h.n < 3; i++)
        wsg_device_step(&t.dev);
    CHECK_EQ(h.n, 3);
    CHECK_EQ(h.id[2], WSG_CMD_HOMING);
    CHECK_EQ(h.tag[2], 2);
    p[0] = 1;
    wsg_put_u16(p + 1, 10);
    feed_cmd(&t, 0, WSG_CMD_GET_FORCE, p, 3);
    CHECK_EQ(h.n, 4);
    for (i = 0; i < 10; i++) {
        wsg_device_step(&t.dev);
        wsg_device_poll_streaming(&t.dev);
    }
    CHECK_EQ(h.n, 5);
    CHECK_EQ(h.id[4], WSG_CMD_GET_FORCE);
    CHECK_EQ(t.sess[0].n, 0);
    CHECK_EQ(t.sess[1].n, 0);
    CHECK_EQ(h.traced, 0);

    /* What the hook hands back goes on the wire through the log. */
    n = wsg_frame_encode_reply(pkt, sizeof pkt, WSG_CMD_LOOP, WSG_E_SUCCESS,
                               NULL, 0);
    REQUIRE(n > 0);
    wsg_device_transmit(&t.dev, &t.sess[1].s, pkt, n);
    CHECK_EQ(h.traced, 1);
    CHECK_EQ(t.sess[1].n, 1);
    CHECK_EQ(t.sess[1].pkts[0].id, WSG_CMD_LOOP);
}

int main(void)
{
    test_loop();
    test_unknown_and_checksum();
    test_no_crc();
    test_disconnect();
    test_homing();
    test_preposition();
    test_stop_and_fast_stop();
    test_grasp_release();
    test_motion_config();
    test_tare();
    test_state_queries();
    test_grasp_stats();
    test_system_config();
    test_streams();
    test_output_hook();
    TEST_EXIT();
}
