/*
 * integ_motion: motion commands over the wire, with several clients.
 *
 * - before homing, Preposition (21h) is E_NOT_INITIALIZED and SF_REFERENCED
 *   is clear;
 * - Homing (20h) answers E_CMD_PENDING at once and E_SUCCESS within 4 s
 *   of simulated time, from either end stop and in either direction
 *   (default: positive, so ~110 mm); the result goes to the sender only;
 * - a preposition's pending and final packets are the manual's example
 *   bytes of chapter 1.3;
 * - while moving, 20h/21h/25h/26h answer E_ALREADY_RUNNING, from any
 *   client, and produce no second packet;
 * - Stop (22h) aborts a preposition: its final result is E_CMD_ABORTED,
 *   SF_AXIS_STOPPED is set, the fingers stay where they stopped; the next
 *   movement clears it and sets SF_TARGET_POS_REACHED;
 * - several clients at once each get their own replies and results.
 *
 * What must happen while a motion runs is checked with simulated time
 * paused (the control channel) and stepped: on a slow machine, or under
 * valgrind, the motion could otherwise end before the check is made.
 */
#include "check.h"
#include "emu.h"
#include "emu_ctl.h"
#include "wsg/axis.h"

#include <string.h>

/* The interface under test (argv[2]). On a serial line or a CAN bus there
 * is one peer, so the checks between clients run where peers are told
 * apart (TCP connections, UDP addresses). */
static const struct emu_transport *tp;
/* The daemon's control channel: simulated time. */
static struct ctl k;

/* 07h where the interface has connections (elsewhere E_NOT_AVAILABLE). */
static void announce_and_close(struct emu_client *c)
{
    CHECK_EQ(emu_request(c, WSG_CMD_DISCONNECT, NULL, 0, NULL, EMU_REPLY_MS),
             tp->connection ? WSG_E_SUCCESS : WSG_E_NOT_AVAILABLE);
    emu_close(c);
}

static float width_of(struct emu_client *c)
{
    float w = -1.0f;
    CHECK(emu_get_float(c, WSG_CMD_GET_WIDTH, &w) == 0);
    return w;
}

static uint32_t flags_of(struct emu_client *c)
{
    uint32_t fl = 0;
    CHECK(emu_get_flags(c, &fl) == 0);
    return fl;
}

static void test_not_initialized(struct emu_client *a)
{
    uint8_t p[16];
    size_t n = emu_move_payload(p, 0, 50.0f, 100.0f);
    unsigned before = a->link.seen[WSG_CMD_PREPOSITION];

    CHECK_EQ(flags_of(a) & WSG_SF_REFERENCED, 0);
    CHECK_EQ(emu_request(a, WSG_CMD_PREPOSITION, p, n, NULL, EMU_REPLY_MS),
             WSG_E_NOT_INITIALIZED);
    /* An immediate error is the only packet: no final result follows. */
    REQUIRE(emu_sync(a, EMU_REPLY_MS) == 0);
    CHECK_EQ(a->link.seen[WSG_CMD_PREPOSITION] - before, 1);
}

/* Homing in direction dir; checks pending, the final result and the time
 * it took: simulated time, which the contract is about (real time on a
 * loaded machine may be longer, when the daemon falls behind). */
static void homing(struct emu_client *c, uint8_t dir)
{
    struct wsg_client_frame f;
    long long s0 = ctl_time_us(ctl_cmd(&k, "time"));
    CHECK(s0 >= 0);
    CHECK_EQ(emu_request(c, WSG_CMD_HOMING, &dir, 1, &f, EMU_REPLY_MS),
             WSG_E_CMD_PENDING);
    CHECK_EQ(f.len, 2);
    if (f.status != WSG_E_CMD_PENDING)
        return;
    int r = emu_recv_id(c, WSG_CMD_HOMING, &f, EMU_HOMING_MS);
    long long ds = ctl_time_us(ctl_cmd(&k, "time")) - s0;
    printf("homing dir %u: %lld ms of simulated time\n", (unsigned)dir,
           ds / 1000);
    CHECK_EQ(r, 1);
    CHECK_EQ(f.status, WSG_E_SUCCESS);
    CHECK_EQ(f.len, 2);
    CHECK(ds <= 4000000);
}

static void test_homing(struct emu_client *a, struct emu_client *b)
{
    homing(a, WSG_HOME_DEFAULT);
    uint32_t fl = flags_of(a);
    CHECK(fl & WSG_SF_REFERENCED);
    CHECK_EQ(fl & WSG_SF_MOVING, 0);
    /* Default direction positive: open, at the 110 mm stroke. */
    CHECK_NEAR(width_of(a), 110.0, 0.5);

    /* The other client saw nothing of it. */
    if (b) {
        REQUIRE(emu_sync(b, EMU_REPLY_MS) == 0);
        CHECK_EQ(b->link.seen[WSG_CMD_HOMING], 0);
    }

    /* From the open end to the closed one and back: each well within
     * the 4 s of the contract. */
    homing(a, WSG_HOME_NEGATIVE);
    CHECK_NEAR(width_of(a), 0.0, 0.5);
    CHECK(flags_of(a) & WSG_SF_REFERENCED);
    homing(a, WSG_HOME_POSITIVE);
    CHECK_NEAR(width_of(a), 110.0, 0.5);

    /* "Parameter value undefined": E_INVALID_PARAMETER, nothing moves. */
    uint8_t bad = 3;
    CHECK_EQ(emu_request(a, WSG_CMD_HOMING, &bad, 1, NULL, EMU_REPLY_MS),
             WSG_E_INVALID_PARAMETER);
    CHECK_EQ(flags_of(a) & WSG_SF_MOVING, 0);

    if (b) {
        REQUIRE(emu_sync(b, EMU_REPLY_MS) == 0);
        CHECK_EQ(b->link.seen[WSG_CMD_HOMING], 0);
    }
}

/* Chapter 1.3: a preposition's pending and final packets, byte for byte,
 * each read with a single recv() on a connection with no other traffic. */
static void test_manual_bytes(struct emu *e)
{
    static const uint8_t pending[] = {0xAA, 0xAA, 0xAA, 0x21, 0x02,
                                      0x00, 0x1A, 0x00, 0x67, 0xCB};
    static const uint8_t done[] = {0xAA, 0xAA, 0xAA, 0x21, 0x02,
                                   0x00, 0x00, 0x00, 0x28, 0x04};
    struct emu_client c;
    uint8_t p[16], buf[64];
    size_t n = emu_move_payload(p, 0, 60.0f, 400.0f);

    REQUIRE(emu_open(&c, e, tp) == 0);
    REQUIRE(emu_send(&c, WSG_CMD_PREPOSITION, p, n) == 0);
    if (tp == &emu_tcp || tp == &emu_udp) {
        long got = emu_recv_raw(&c, buf, sizeof(buf), EMU_REPLY_MS);
        CHECK_EQ(got, sizeof(pending));
        CHECK(got == sizeof(pending) &&
              memcmp(buf, pending, sizeof(pending)) == 0);
        got = emu_recv_raw(&c, buf, sizeof(buf), EMU_MOVE_MS);
        CHECK_EQ(got, sizeof(done));
        CHECK(got == sizeof(done) && memcmp(buf, done, sizeof(done)) == 0);
    } else { /* bytes or frames: the parser checked them whole */
        struct wsg_client_frame f;
        CHECK_EQ(emu_recv_id(&c, WSG_CMD_PREPOSITION, &f, EMU_REPLY_MS), 1);
        CHECK(f.len == 2 && memcmp(f.payload, pending + 6, 2) == 0);
        CHECK_EQ(emu_recv_id(&c, WSG_CMD_PREPOSITION, &f, EMU_MOVE_MS), 1);
        CHECK(f.len == 2 && memcmp(f.payload, done + 6, 2) == 0);
        CHECK_EQ(c.link.bad, 0);
    }
    CHECK_NEAR(width_of(&c), 60.0, 0.1);
    announce_and_close(&c);
}

static void test_already_running(struct emu_client *a, struct emu_client *b)
{
    uint8_t p[16];
    struct wsg_client_frame f;
    unsigned a20 = a->link.seen[WSG_CMD_HOMING],
             a21 = a->link.seen[WSG_CMD_PREPOSITION];
    unsigned a25 = a->link.seen[WSG_CMD_GRASP],
             a26 = a->link.seen[WSG_CMD_RELEASE];
    unsigned b21 = b ? b->link.seen[WSG_CMD_PREPOSITION] : 0;

    /* From 60 mm to 10 mm at 20 mm/s: moving for over 2 s of simulated
     * time, which stands still from here until the Stop. */
    REQUIRE(fabs(width_of(a) - 60.0) < 1.0);
    CMD_OK(&k, "time pause");
    size_t n = emu_move_payload(p, 0, 10.0f, 20.0f);
    REQUIRE(emu_request(a, WSG_CMD_PREPOSITION, p, n, NULL, EMU_REPLY_MS) ==
            WSG_E_CMD_PENDING);
    /* Under way: 300 ms take the fingers over 2 mm, so "stopped on the way"
     * is measurable. */
    CMD_OK(&k, "time step 300");
    CHECK(flags_of(a) & WSG_SF_MOVING);
    CHECK(width_of(a) <= 58.0f);

    CHECK_EQ(emu_motions_answer(a, WSG_E_ALREADY_RUNNING), 0);
    /* One axis for all clients: another client is refused as well. */
    if (b)
        CHECK_EQ(emu_request(b, WSG_CMD_PREPOSITION, p, n, NULL, EMU_REPLY_MS),
                 WSG_E_ALREADY_RUNNING);
    /* Still moving: the refusals did not disturb the motion. */
    CHECK(flags_of(a) & WSG_SF_MOVING);

    /* Stop: E_SUCCESS, status only; the preposition ends E_CMD_ABORTED.
     * Either packet may come first; recv_id keeps the other. */
    CHECK_EQ(emu_request(a, WSG_CMD_STOP, NULL, 0, &f, EMU_REPLY_MS),
             WSG_E_SUCCESS);
    CHECK_EQ(f.len, 2);
    CHECK_EQ(emu_recv_id(a, WSG_CMD_PREPOSITION, &f, EMU_REPLY_MS), 1);
    CHECK_EQ(f.status, WSG_E_CMD_ABORTED);
    CHECK_EQ(f.len, 2);

    uint32_t fl = flags_of(a);
    CHECK_EQ(fl & (WSG_SF_MOVING | WSG_SF_AXIS_STOPPED), WSG_SF_AXIS_STOPPED);
    CHECK_EQ(fl & WSG_SF_TARGET_POS_REACHED, 0);
    /* Stopped on the way, and stays there while time goes on. */
    float w1 = width_of(a);
    CHECK(w1 > 10.5f && w1 <= 58.0f);
    CMD_OK(&k, "time step 500");
    float w2 = width_of(a);
    CHECK_NEAR(w2, w1, 0.01);
    CMD_OK(&k, "time resume");

    /* Exactly the packets above, none later: the refused commands have no
     * final result, and b got nothing of a's motion. */
    REQUIRE(emu_sync(a, EMU_REPLY_MS) == 0);
    if (b)
        REQUIRE(emu_sync(b, EMU_REPLY_MS) == 0);
    CHECK_EQ(a->link.seen[WSG_CMD_HOMING] - a20, 1);
    CHECK_EQ(a->link.seen[WSG_CMD_PREPOSITION] - a21, 3);
    CHECK_EQ(a->link.seen[WSG_CMD_GRASP] - a25, 1);
    CHECK_EQ(a->link.seen[WSG_CMD_RELEASE] - a26, 1);
    if (b)
        CHECK_EQ(b->link.seen[WSG_CMD_PREPOSITION] - b21, 1);

    /* Stop with a parameter: E_NO_PARAM_EXPECTED (3.2.3). */
    CHECK_EQ(emu_request(a, WSG_CMD_STOP, "x", 1, NULL, EMU_REPLY_MS),
             WSG_E_NO_PARAM_EXPECTED);
    /* Stop while idle: nothing to stop, still E_SUCCESS. */
    CHECK_EQ(emu_request(a, WSG_CMD_STOP, NULL, 0, NULL, EMU_REPLY_MS),
             WSG_E_SUCCESS);

    /* The next movement clears AXIS_STOPPED; reaching the target sets
     * TARGET_POS_REACHED (Appendix B). */
    n = emu_move_payload(p, 0, 80.0f, 400.0f);
    int imm = -1;
    CHECK_EQ(emu_motion(a, WSG_CMD_PREPOSITION, p, n, EMU_MOVE_MS, &imm),
             WSG_E_SUCCESS);
    CHECK_EQ(imm, WSG_E_CMD_PENDING);
    fl = flags_of(a);
    CHECK_EQ(fl & (WSG_SF_AXIS_STOPPED | WSG_SF_MOVING), 0);
    CHECK(fl & WSG_SF_TARGET_POS_REACHED);
    CHECK_NEAR(width_of(a), 80.0, 0.1);
}

static void test_clients(struct emu *e)
{
    enum { N = 3 };
    struct emu_client c[N];
    struct wsg_client_frame f;
    unsigned before[N];

    for (int i = 0; i < N; i++)
        REQUIRE(emu_open(&c[i], e, tp) == 0);

    /* Requests from all clients in flight at once: each gets its own. */
    for (int round = 0; round < 10; round++) {
        for (int i = 0; i < N; i++) {
            uint8_t tok[2] = {(uint8_t)i, (uint8_t)round};
            REQUIRE(emu_send(&c[i], WSG_CMD_LOOP, tok, 2) == 0);
        }
        for (int i = 0; i < N; i++) {
            CHECK_EQ(emu_recv_id(&c[i], WSG_CMD_LOOP, &f, EMU_REPLY_MS), 1);
            CHECK_EQ(f.len, 4);
            CHECK_EQ(EMU_PARAMS(&f)[0], i);
            CHECK_EQ(EMU_PARAMS(&f)[1], round);
        }
    }

    /* Client 1 moves; 0 and 2 keep asking for the state meanwhile and see
     * neither its pending nor its result. */
    for (int i = 0; i < N; i++)
        before[i] = c[i].link.seen[WSG_CMD_PREPOSITION];
    uint8_t p[16];
    size_t n = emu_move_payload(p, 0, 40.0f, 200.0f);
    REQUIRE(emu_request(&c[1], WSG_CMD_PREPOSITION, p, n, NULL,
                        EMU_REPLY_MS) == WSG_E_CMD_PENDING);
    double deadline = emu_now_ms() + EMU_MOVE_MS;
    int r = 0;
    while (r == 0 && emu_now_ms() < deadline) {
        CHECK(flags_of(&c[0]) & WSG_SF_REFERENCED);
        CHECK_EQ(emu_request(&c[2], WSG_CMD_LOOP, "c2", 2, NULL, EMU_REPLY_MS),
                 WSG_E_SUCCESS);
        r = emu_recv_id(&c[1], WSG_CMD_PREPOSITION, &f, 20);
    }
    CHECK_EQ(r, 1);
    CHECK_EQ(f.status, WSG_E_SUCCESS);
    CHECK_NEAR(width_of(&c[2]), 40.0, 0.1);

    /* Client 2 homes: its own pending and result. */
    uint8_t dir = 0;
    int imm = -1;
    CHECK_EQ(emu_motion(&c[2], WSG_CMD_HOMING, &dir, 1, EMU_HOMING_MS, &imm),
             WSG_E_SUCCESS);
    CHECK_EQ(imm, WSG_E_CMD_PENDING);

    for (int i = 0; i < N; i++)
        REQUIRE(emu_sync(&c[i], EMU_REPLY_MS) == 0);
    CHECK_EQ(c[0].link.seen[WSG_CMD_PREPOSITION] - before[0], 0);
    CHECK_EQ(c[1].link.seen[WSG_CMD_PREPOSITION] - before[1], 2);
    CHECK_EQ(c[2].link.seen[WSG_CMD_PREPOSITION] - before[2], 0);
    CHECK_EQ(c[0].link.seen[WSG_CMD_HOMING], 0);
    CHECK_EQ(c[1].link.seen[WSG_CMD_HOMING], 0);
    CHECK_EQ(c[2].link.seen[WSG_CMD_HOMING], 2);
    for (int i = 0; i < N; i++) {
        CHECK_EQ(c[i].link.bad, 0);
        announce_and_close(&c[i]);
    }
}

int main(int argc, char **argv)
{
    const char *exe = emu_exe(argc, argv);
    struct emu e;
    struct emu_client a, b;

    static const char *const extra[] = {"--control", "127.0.0.1:0", NULL};

    tp = emu_transport_arg(argc, argv);
    printf("over %s\n", tp->field);
    REQUIRE(emu_start_tp(&e, exe, tp, extra) == 0);
    REQUIRE(ctl_open(&k, &e) == 0);
    REQUIRE(emu_open(&a, &e, tp) == 0);
    if (!tp->single_peer)
        REQUIRE(emu_open(&b, &e, tp) == 0);

    test_not_initialized(&a);
    test_homing(&a, tp->single_peer ? NULL : &b);
    if (tp->single_peer) /* the line is a's: the check uses it after a */
        announce_and_close(&a);
    test_manual_bytes(&e);
    if (tp->single_peer)
        REQUIRE(emu_open(&a, &e, tp) == 0);
    test_already_running(&a, tp->single_peer ? NULL : &b);
    CHECK_EQ(a.link.bad, 0);
    announce_and_close(&a);
    if (!tp->single_peer) {
        CHECK_EQ(b.link.bad, 0);
        announce_and_close(&b);
        test_clients(&e);
    }

    /* Every connection announced its close: no FAST STOP, and the daemon
     * is still fine. */
    REQUIRE(emu_open(&a, &e, tp) == 0);
    CHECK_EQ(flags_of(&a) & WSG_SF_FAST_STOP, 0);
    announce_and_close(&a);
    ctl_close(&k);
    CHECK_EQ(emu_stop(&e), 0);
    TEST_EXIT();
}
