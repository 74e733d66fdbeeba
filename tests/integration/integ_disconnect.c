/*
 * integ_disconnect: what a TCP connection's end does to the gripper.
 *
 * - a connection that closes without Disconnect Announcement (07h) puts the
 *   gripper into FAST STOP (40h bit 12), seen by every other client: a
 *   running motion stops, motion commands answer E_ACCESS_DENIED, a wrong
 *   key is E_CMD_FORMAT_ERROR, 24h "ack" clears it and motion works again;
 *   this holds for a close while moving (FIN), for a reset, and for a
 *   connection that never sent a byte;
 * - 07h answers E_SUCCESS (with a parameter: E_NO_PARAM_EXPECTED), aborts a
 *   running motion, every later command on that connection is
 *   E_ACCESS_DENIED, and its close causes no FAST STOP;
 * - a client that sends 07h and closes at once while stream packets are
 *   still unread (its close resets the connection) causes no FAST STOP,
 *   30 times in a row: what arrived before the reset is processed before
 *   the close, also when a stream's send meets the reset first;
 * - with --no-disconnect-fast-stop no close causes FAST STOP, while 23h
 *   still does.
 *
 * "No FAST STOP" can only be watched for a while: the window is several
 * times the delay measured for the positive case on the same daemon.
 * What must happen while a motion runs is checked with simulated time
 * paused (the control channel) and stepped, so that a slow machine cannot
 * let the motion end first; the windows of "no FAST STOP" run with time
 * going on.
 */
#include "check.h"
#include "emu.h"
#include "emu_ctl.h"
#include "wsg/axis.h"

#include <string.h>

static const char *const ack = "ack";

/* The interface under test (argv[2]). TCP has connections and the FAST
 * STOP rule of their end; elsewhere 07h is not available and a client that
 * goes away changes nothing. */
static const struct emu_transport *tp;
/* The control channel of the daemon under test: simulated time. */
static struct ctl k;

static uint32_t flags_of(struct emu_client *c)
{
    uint32_t fl = 0;
    CHECK(emu_get_flags(c, &fl) == 0);
    return fl;
}

static float width_of(struct emu_client *c)
{
    float w = -1.0f;
    CHECK(emu_get_float(c, WSG_CMD_GET_WIDTH, &w) == 0);
    return w;
}

/* Poll 40h for up to ms: 1 if FAST STOP showed up. */
static int fast_stop_within(struct emu_client *c, int ms)
{
    return emu_wait_flags(c, WSG_SF_FAST_STOP, WSG_SF_FAST_STOP, ms, NULL) ==
           0;
}

static void announce_and_close(struct emu_client *c)
{
    CHECK_EQ(emu_request(c, WSG_CMD_DISCONNECT, NULL, 0, NULL, EMU_REPLY_MS),
             WSG_E_SUCCESS);
    emu_close(c);
}

/* Pause simulated time, start a slow closing preposition (over 2 s) on c
 * and step it over 2 mm, so that a stop on the way is measurable. Time
 * stays paused (the caller resumes it). Returns the width where the fingers
 * were 2 mm ago. */
static float start_slow_move(struct emu_client *c, struct emu_client *mon,
                             float to)
{
    uint8_t p[16];
    size_t n = emu_move_payload(p, 0, to, 20.0f);
    float from = width_of(mon);
    CMD_OK(&k, "time pause");
    REQUIRE(emu_request(c, WSG_CMD_PREPOSITION, p, n, NULL, EMU_REPLY_MS) ==
            WSG_E_CMD_PENDING);
    CMD_OK(&k, "time step 300");
    REQUIRE(flags_of(mon) & WSG_SF_MOVING);
    REQUIRE(width_of(mon) <= from - 2.0f);
    return from - 2.0f;
}

/* In FAST STOP: every motion command is refused with E_ACCESS_DENIED and
 * has no final result. */
static void check_motion_denied(struct emu_client *m)
{
    unsigned s20 = m->link.seen[WSG_CMD_HOMING],
             s21 = m->link.seen[WSG_CMD_PREPOSITION];
    CHECK_EQ(emu_motions_answer(m, WSG_E_ACCESS_DENIED), 0);
    CHECK_EQ(flags_of(m) & WSG_SF_MOVING, 0);
    REQUIRE(emu_sync(m, EMU_REPLY_MS) == 0);
    CHECK_EQ(m->link.seen[WSG_CMD_HOMING] - s20, 1);
    CHECK_EQ(m->link.seen[WSG_CMD_PREPOSITION] - s21, 1);
}

/* Acknowledge (wrong key first) and show that motion works again. */
static void acknowledge(struct emu_client *m)
{
    CHECK_EQ(
        emu_request(m, WSG_CMD_ACK_FAST_STOP, "abc", 3, NULL, EMU_REPLY_MS),
        WSG_E_CMD_FORMAT_ERROR);
    CHECK(flags_of(m) & WSG_SF_FAST_STOP);
    CHECK_EQ(emu_request(m, WSG_CMD_ACK_FAST_STOP, ack, 3, NULL, EMU_REPLY_MS),
             WSG_E_SUCCESS);
    CHECK(emu_wait_flags(m, WSG_SF_FAST_STOP, 0, EMU_REPLY_MS, NULL) == 0);
    uint8_t p[16];
    size_t n = emu_move_payload(p, 0, 90.0f, 400.0f);
    int imm = -1;
    CHECK_EQ(emu_motion(m, WSG_CMD_PREPOSITION, p, n, EMU_MOVE_MS, &imm),
             WSG_E_SUCCESS);
    CHECK_EQ(imm, WSG_E_CMD_PENDING);
    CHECK_NEAR(width_of(m), 90.0, 0.1);
}

/* Returns the longest delay from a close to FAST STOP seen, in ms. */
static double test_close_without_announce(struct emu *e, struct emu_client *m)
{
    struct emu_client a;
    double t0, worst = 0;

    /* 1. Closed (FIN) while moving: FAST STOP, and the motion stops. */
    REQUIRE(emu_open(&a, e, tp) == 0);
    float from = start_slow_move(&a, m, 20.0f);
    unsigned m21 = m->link.seen[WSG_CMD_PREPOSITION];
    t0 = emu_now_ms();
    emu_close(&a);
    CHECK(fast_stop_within(m, EMU_REPLY_MS));
    worst = emu_now_ms() - t0;
    printf("close while moving: FAST STOP after %.0f ms\n", worst);
    CHECK(emu_wait_flags(m, WSG_SF_MOVING, 0, EMU_REPLY_MS, NULL) == 0);
    float w1 = width_of(m);
    CHECK(w1 > 20.5f && w1 <= from); /* stopped on the way */
    /* ... and stays there, with time going on. */
    CMD_OK(&k, "time resume");
    check_motion_denied(m);
    CHECK_NEAR(width_of(m), w1, 0.01);
    /* The closed client's result was not sent to anyone else. */
    CHECK_EQ(m->link.seen[WSG_CMD_PREPOSITION] - m21, 1);
    acknowledge(m);

    /* 2. Reset with unread data in flight (a crashed client). */
    REQUIRE(emu_open(&a, e, tp) == 0);
    CHECK_EQ(emu_request(&a, WSG_CMD_LOOP, "rst", 3, NULL, EMU_REPLY_MS),
             WSG_E_SUCCESS);
    REQUIRE(emu_send(&a, WSG_CMD_GET_SYSTEM_STATE, NULL, 0) == 0);
    t0 = emu_now_ms();
    emu_abort(&a);
    CHECK(fast_stop_within(m, EMU_REPLY_MS));
    double dt = emu_now_ms() - t0;
    printf("reset: FAST STOP after %.0f ms\n", dt);
    worst = dt > worst ? dt : worst;
    check_motion_denied(m);
    acknowledge(m);

    /* 3. A connection that never sent anything: also no 07h. */
    REQUIRE(emu_open(&a, e, tp) == 0);
    t0 = emu_now_ms();
    emu_close(&a);
    CHECK(fast_stop_within(m, EMU_REPLY_MS));
    dt = emu_now_ms() - t0;
    printf("silent connection: FAST STOP after %.0f ms\n", dt);
    worst = dt > worst ? dt : worst;
    acknowledge(m);

    /* "ack" with no FAST STOP pending is E_SUCCESS (NOTES). */
    CHECK_EQ(emu_request(m, WSG_CMD_ACK_FAST_STOP, ack, 3, NULL, EMU_REPLY_MS),
             WSG_E_SUCCESS);
    CHECK_EQ(flags_of(m) & WSG_SF_FAST_STOP, 0);
    return worst;
}

static void test_announce(struct emu *e, struct emu_client *m, int window)
{
    struct emu_client a;
    struct wsg_client_frame f;
    uint8_t dir = 0;

    /* 07h takes no parameter (3.1.2). */
    REQUIRE(emu_open(&a, e, tp) == 0);
    CHECK_EQ(emu_request(&a, WSG_CMD_DISCONNECT, "x", 1, NULL, EMU_REPLY_MS),
             WSG_E_NO_PARAM_EXPECTED);
    CHECK_EQ(emu_request(&a, WSG_CMD_DISCONNECT, NULL, 0, &f, EMU_REPLY_MS),
             WSG_E_SUCCESS);
    CHECK_EQ(f.len, 2);
    /* Afterwards everything is refused, the announcement itself too, and
     * the connection stays open ("the gripper will wait for
     * disconnection"). */
    CHECK_EQ(emu_request(&a, WSG_CMD_LOOP, "z", 1, &f, EMU_REPLY_MS),
             WSG_E_ACCESS_DENIED);
    CHECK_EQ(f.len, 2);
    CHECK_EQ(
        emu_request(&a, WSG_CMD_GET_SYSTEM_STATE, NULL, 0, &f, EMU_REPLY_MS),
        WSG_E_ACCESS_DENIED);
    CHECK_EQ(f.len, 2);
    CHECK_EQ(emu_request(&a, WSG_CMD_HOMING, &dir, 1, NULL, EMU_REPLY_MS),
             WSG_E_ACCESS_DENIED);
    CHECK_EQ(emu_request(&a, WSG_CMD_FAST_STOP, NULL, 0, NULL, EMU_REPLY_MS),
             WSG_E_ACCESS_DENIED);
    CHECK_EQ(emu_request(&a, WSG_CMD_DISCONNECT, NULL, 0, NULL, EMU_REPLY_MS),
             WSG_E_ACCESS_DENIED);
    /* Its 23h was refused: no FAST STOP from that either. */
    CHECK_EQ(flags_of(m) & WSG_SF_FAST_STOP, 0);
    emu_close(&a);
    CHECK(!fast_stop_within(m, window));

    /* 07h aborts a running motion at once, without FAST STOP. */
    REQUIRE(emu_open(&a, e, tp) == 0);
    float from = start_slow_move(&a, m, 40.0f);
    double t0 = emu_now_ms();
    CHECK_EQ(emu_request(&a, WSG_CMD_DISCONNECT, NULL, 0, NULL, EMU_REPLY_MS),
             WSG_E_SUCCESS);
    /* The move would take over 2 s; it stops at once. */
    CHECK(emu_wait_flags(m, WSG_SF_MOVING, 0, EMU_REPLY_MS, NULL) == 0);
    printf("07h while moving: stopped after %.0f ms\n", emu_now_ms() - t0);
    float w = width_of(m);
    CHECK(w > 40.5f && w <= from);
    CMD_OK(&k, "time resume");
    emu_close(&a);
    CHECK(!fast_stop_within(m, window));

    /* Motion is allowed as ever. */
    uint8_t p[16];
    size_t n = emu_move_payload(p, 0, 90.0f, 400.0f);
    CHECK_EQ(emu_motion(m, WSG_CMD_PREPOSITION, p, n, EMU_MOVE_MS, NULL),
             WSG_E_SUCCESS);
}

/* The way a driver deactivates: 07h and close, without reading the
 * stream packets that are still coming (1 ms 43h), so the close resets the
 * connection while the 07h waits in the gripper's socket. FAST STOP is
 * sticky: one close taken for a link loss shows at the end. */
static void test_announce_unread(struct emu *e, struct emu_client *m,
                                 int window)
{
    static const uint8_t every_ms[3] = {0x01, 0x01, 0x00};
    struct emu_client a;
    int i;

    for (i = 0; i < 30; i++) {
        REQUIRE(emu_open(&a, e, tp) == 0);
        REQUIRE(emu_send(&a, WSG_CMD_GET_WIDTH, every_ms, 3) == 0);
        emu_sleep_ms(5 + i % 5); /* packets pile up, unread */
        REQUIRE(emu_send(&a, WSG_CMD_DISCONNECT, NULL, 0) == 0);
        emu_close(&a);
        emu_sleep_ms(i % 3);
    }
    CHECK(!fast_stop_within(m, window));
    CHECK_EQ(flags_of(m) & WSG_SF_FAST_STOP, 0);
}

static void test_no_disconnect_fast_stop(const char *exe, int window)
{
    static const char *const args[] = {"--no-disconnect-fast-stop", NULL};
    struct emu e;
    struct emu_client m, a;

    REQUIRE(emu_start_tp(&e, exe, tp, args) == 0);
    REQUIRE(emu_open(&m, &e, tp) == 0);

    REQUIRE(emu_open(&a, &e, tp) == 0);
    CHECK_EQ(emu_request(&a, WSG_CMD_LOOP, "fin", 3, NULL, EMU_REPLY_MS),
             WSG_E_SUCCESS);
    emu_close(&a);
    REQUIRE(emu_open(&a, &e, tp) == 0);
    CHECK_EQ(emu_request(&a, WSG_CMD_LOOP, "rst", 3, NULL, EMU_REPLY_MS),
             WSG_E_SUCCESS);
    emu_abort(&a);
    REQUIRE(emu_open(&a, &e, tp) == 0);
    emu_close(&a);
    CHECK(!fast_stop_within(&m, window));

    /* FAST STOP itself still works in this mode (so the watch above could
     * have seen one): 23h sets it, motion is refused, "ack" clears it. */
    CHECK_EQ(emu_request(&m, WSG_CMD_FAST_STOP, NULL, 0, NULL, EMU_REPLY_MS),
             WSG_E_SUCCESS);
    CHECK(fast_stop_within(&m, EMU_REPLY_MS));
    uint8_t dir = 0;
    CHECK_EQ(emu_request(&m, WSG_CMD_HOMING, &dir, 1, NULL, EMU_REPLY_MS),
             WSG_E_ACCESS_DENIED);
    CHECK_EQ(
        emu_request(&m, WSG_CMD_ACK_FAST_STOP, ack, 3, NULL, EMU_REPLY_MS),
        WSG_E_SUCCESS);
    CHECK(emu_wait_flags(&m, WSG_SF_FAST_STOP, 0, EMU_REPLY_MS, NULL) == 0);
    CHECK_EQ(m.link.bad, 0);
    emu_close(&m); /* no 07h: harmless in this mode */
    CHECK_EQ(emu_stop(&e), 0);
}

/* Without connections: 07h is E_NOT_AVAILABLE and refuses nothing after
 * it; a client that goes away in the middle of a motion changes nothing:
 * no FAST STOP (watched for a window with time going on), the motion runs
 * to its end. */
static void test_connectionless(struct emu *e)
{
    struct emu_client a;
    uint32_t fl = 0;

    REQUIRE(emu_open(&a, e, tp) == 0);
    CHECK_EQ(emu_request(&a, WSG_CMD_DISCONNECT, "x", 1, NULL, EMU_REPLY_MS),
             WSG_E_NO_PARAM_EXPECTED);
    CHECK_EQ(emu_request(&a, WSG_CMD_DISCONNECT, NULL, 0, NULL, EMU_REPLY_MS),
             WSG_E_NOT_AVAILABLE);
    CHECK_EQ(emu_request(&a, WSG_CMD_LOOP, "z", 1, NULL, EMU_REPLY_MS),
             WSG_E_SUCCESS);
    start_slow_move(&a, &a, 60.0f);
    emu_close(&a);
    REQUIRE(emu_open(&a, e, tp) == 0);
    CHECK(emu_get_flags(&a, &fl) == 0);
    CHECK_EQ(fl & WSG_SF_FAST_STOP, 0);
    CHECK(fl & WSG_SF_MOVING);
    /* Still moving after a while of time going on (the motion has over
     * 2 s to go), and no FAST STOP came of it. */
    CMD_OK(&k, "time step 200");
    CHECK(emu_get_flags(&a, &fl) == 0);
    CHECK_EQ(fl & WSG_SF_FAST_STOP, 0);
    CHECK(fl & WSG_SF_MOVING);
    CMD_OK(&k, "time resume");
    CHECK(emu_wait_flags(&a, WSG_SF_MOVING, 0, EMU_MOVE_MS, &fl) == 0);
    CHECK(fl & WSG_SF_TARGET_POS_REACHED);
    CHECK_NEAR(width_of(&a), 60.0, 0.1);
    CHECK_EQ(a.link.bad, 0);
    emu_close(&a);
}

int main(int argc, char **argv)
{
    const char *exe = emu_exe(argc, argv);
    struct emu e;
    struct emu_client m;

    static const char *const extra[] = {"--control", "127.0.0.1:0", NULL};

    tp = emu_transport_arg(argc, argv);
    printf("over %s\n", tp->field);
    REQUIRE(emu_start_tp(&e, exe, tp, extra) == 0);
    REQUIRE(ctl_open(&k, &e) == 0);
    REQUIRE(emu_open(&m, &e, tp) == 0);
    uint8_t dir = 0;
    REQUIRE(emu_motion(&m, WSG_CMD_HOMING, &dir, 1, EMU_HOMING_MS, NULL) ==
            WSG_E_SUCCESS);
    if (!tp->connection) {
        emu_close(&m);
        test_connectionless(&e);
        ctl_close(&k);
        CHECK_EQ(emu_stop(&e), 0);
        TEST_EXIT();
    }

    double worst = test_close_without_announce(&e, &m);
    /* Watch for "no FAST STOP" several times as long as one took to show,
     * and never less than the quiet window. */
    int window = (int)(worst * 5);
    if (window < EMU_QUIET_MS * 2)
        window = EMU_QUIET_MS * 2;
    if (window > emu_ms(3000))
        window = emu_ms(3000);
    test_announce(&e, &m, window);
    test_announce_unread(&e, &m, window);
    CHECK_EQ(m.link.bad, 0);
    announce_and_close(&m);
    ctl_close(&k);
    CHECK_EQ(emu_stop(&e), 0);

    test_no_disconnect_fast_stop(exe, window);
    TEST_EXIT();
}
