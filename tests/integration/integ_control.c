/*
 * integ_control: the control channel (--control) and time control.
 *
 * - the ready line ends with control=127.0.0.1:PORT;
 * - "state" is one valid JSON object with every documented key;
 * - lockstep: paused, a homing from 55 mm advances only with "time step";
 *   its trapezoid (100 mm/s, 150 mm/s^2: 0.667 s and 33.3 mm accelerating,
 *   21.7 mm at speed) lasts 0.884 s, so no result after 800 ms of steps and
 *   the result after 100 more; "time" reports the stepped time exactly;
 * - a held part removed with "part none" is lost (41h = 3, 42h lost 1);
 * - "fault temp-fault on" sets 40h bit 14 and refuses motions with
 *   E_ACCESS_DENIED, "off" clears it; "fault power on" aborts a motion;
 * - "time scale 10" runs a homing in well under the real-time duration; a
 *   scale set while paused waits for "time resume"; --time-scale 5 is the
 *   scale "state" reports;
 * - "drop" ends every TCP connection, leaving the gripper in FAST STOP;
 * - "reset" is a power cycle: not referenced, acceleration 150 again,
 *   streams ended;
 * - errors: an unknown command, bad arguments, a too long line; several
 *   lines in one write are all answered, in order, an empty one too;
 * - every answer reflects its command at once (time paused, or packets in
 *   one write): 40h/41h/44h after a motion command, Stop, FAST STOP,
 *   "ack", a close without 07h and a control fault; a motion right after
 *   "ack" is accepted.
 */
#include "check.h"
#include "emu.h"
#include "emu_ctl.h"
#include "wsg/axis.h"

#include <arpa/inet.h>
#include <errno.h>
#include <netinet/in.h>
#include <poll.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <unistd.h>

static const char *const args[] = {"--tcp", "127.0.0.1:0", "--control",
                                   "127.0.0.1:0", NULL};

static long long ctl_time(struct ctl *c)
{
    return ctl_time_us(ctl_cmd(c, "time"));
}

/* ---- a minimal JSON checker: the grammar, nothing more ---- */

static const char *json_value(const char *p);

static const char *json_ws(const char *p)
{
    while (*p == ' ' || *p == '\t' || *p == '\n' || *p == '\r')
        p++;
    return p;
}

static const char *json_string(const char *p)
{
    if (*p++ != '"')
        return NULL;
    while (*p && *p != '"') {
        if ((unsigned char)*p < 0x20)
            return NULL;
        if (*p == '\\') {
            p++;
            if (!*p)
                return NULL;
        }
        p++;
    }
    return *p == '"' ? p + 1 : NULL;
}

static const char *json_number(const char *p)
{
    const char *s = p;

    if (*p == '-')
        p++;
    if (*p == '0')
        p++;
    else if (*p >= '1' && *p <= '9')
        while (*p >= '0' && *p <= '9')
            p++;
    else
        return NULL;
    if (*p == '.') {
        p++;
        if (!(*p >= '0' && *p <= '9'))
            return NULL;
        while (*p >= '0' && *p <= '9')
            p++;
    }
    if (*p == 'e' || *p == 'E') {
        p++;
        if (*p == '+' || *p == '-')
            p++;
        if (!(*p >= '0' && *p <= '9'))
            return NULL;
        while (*p >= '0' && *p <= '9')
            p++;
    }
    return p > s ? p : NULL;
}

static const char *json_seq(const char *p, char close, int object)
{
    p = json_ws(p + 1);
    if (*p == close)
        return p + 1;
    for (;;) {
        if (object) {
            p = json_string(json_ws(p));
            if (!p)
                return NULL;
            p = json_ws(p);
            if (*p++ != ':')
                return NULL;
        }
        p = json_value(p);
        if (!p)
            return NULL;
        p = json_ws(p);
        if (*p == close)
            return p + 1;
        if (*p++ != ',')
            return NULL;
    }
}

static const char *json_value(const char *p)
{
    p = json_ws(p);
    switch (*p) {
    case '{':
        return json_seq(p, '}', 1);
    case '[':
        return json_seq(p, ']', 0);
    case '"':
        return json_string(p);
    case 't':
        return strncmp(p, "true", 4) == 0 ? p + 4 : NULL;
    case 'f':
        return strncmp(p, "false", 5) == 0 ? p + 5 : NULL;
    case 'n':
        return strncmp(p, "null", 4) == 0 ? p + 4 : NULL;
    default:
        return json_number(p);
    }
}

static int json_valid_object(const char *p)
{
    p = json_ws(p);
    if (*p != '{')
        return 0;
    p = json_value(p);
    return p && *json_ws(p) == '\0';
}

/* The number after "key": in a flat search (keys are unique in state). */
/* The state's JSON, after "ok ". */
static const char *ctl_state(struct ctl *c)
{
    const char *ans = ctl_cmd(c, "state");

    return strncmp(ans, "ok ", 3) == 0 ? ans + 3 : "";
}

/* ---- gripper helpers ---- */

static uint32_t flags_of(struct emu_client *c)
{
    uint32_t fl = 0;

    CHECK(emu_get_flags(c, &fl) == 0);
    return fl;
}

static int home(struct emu_client *c, uint8_t dir)
{
    int imm;

    return emu_motion(c, WSG_CMD_HOMING, &dir, 1, EMU_HOMING_MS, &imm);
}

static int move_to(struct emu_client *c, float width, float speed)
{
    uint8_t p[16];
    size_t n = emu_move_payload(p, 0, width, speed);
    int imm;

    return emu_motion(c, WSG_CMD_PREPOSITION, p, n, emu_ms(10000), &imm);
}

/* ---- the tests ---- */

static void test_ready_and_state(struct emu *e, struct ctl *k)
{
    char v[64];
    const char *field = strstr(e->line, " control=");

    CHECK(emu_field(e, "control", v, sizeof v) != NULL);
    CHECK(strncmp(v, "127.0.0.1:", 10) == 0 && atoi(v + 10) > 0);
    /* The last field of the line. */
    CHECK(field && !strchr(field + 1, ' '));

    const char *js = ctl_state(k);
    static const char *const keys[] = {
        "\"width\":",        "\"speed\":",
        "\"force\":",        "\"temperature\":",
        "\"flags\":",        "\"flag_names\":",
        "\"grasp_state\":",  "\"grasp_state_name\":",
        "\"stats\":",        "\"total\":",
        "\"no_part\":",      "\"lost_part\":",
        "\"time\":",         "\"delayed\":",
        "\"delay_dropped\":"};
    CHECK(json_valid_object(js));
    for (size_t i = 0; i < sizeof keys / sizeof keys[0]; i++) {
        if (!strstr(js, keys[i]))
            fprintf(stderr, "state lacks %s: %s\n", keys[i], js);
        CHECK(strstr(js, keys[i]) != NULL);
    }
    CHECK_NEAR(ctl_json_num(js, "width"), 55.0, 1e-6);
    CHECK_EQ(ctl_json_num(js, "flags"), 0);
    CHECK_EQ(ctl_json_num(js, "grasp_state"), 0);
}

static void test_errors(struct ctl *k)
{
    char line[512], big[400];

    CHECK(strncmp(ctl_cmd(k, "frobnicate"), "error ", 6) == 0);
    CHECK(strncmp(ctl_cmd(k, "part"), "error ", 6) == 0);
    CHECK(strncmp(ctl_cmd(k, "part -3"), "error ", 6) == 0);
    CHECK(strncmp(ctl_cmd(k, "part 20 0"), "error ", 6) == 0);
    CHECK(strncmp(ctl_cmd(k, "obstacle wide"), "error ", 6) == 0);
    CHECK(strncmp(ctl_cmd(k, "fault power maybe"), "error ", 6) == 0);
    CHECK(strncmp(ctl_cmd(k, "fault gremlins on"), "error ", 6) == 0);
    CHECK(strncmp(ctl_cmd(k, "time scale 0"), "error ", 6) == 0);
    CHECK(strncmp(ctl_cmd(k, "time scale fast"), "error ", 6) == 0);
    /* Stepping while running would race the timer. */
    CHECK(strncmp(ctl_cmd(k, "time step 10"), "error ", 6) == 0);
    CHECK(strncmp(ctl_cmd(k, "state now"), "error ", 6) == 0);

    /* Too long: one error for the whole line, then business as usual. */
    memset(big, 'x', sizeof big - 1);
    big[sizeof big - 1] = '\0';
    CHECK(strncmp(ctl_cmd(k, big), "error ", 6) == 0);
    CHECK(ctl_is_ok(ctl_cmd(k, "time")));

    /* Several lines in one write, answered in order, CRLF line ends too;
     * an empty line is answered like any other, so a script reading one
     * answer per line stays in step. */
    REQUIRE(ctl_write(k, "obstacle 30\r\n\nnope\nobstacle none\n") == 0);
    REQUIRE(ctl_line(k, line, sizeof line) == 0);
    CHECK(strcmp(line, "ok obstacle 30") == 0);
    REQUIRE(ctl_line(k, line, sizeof line) == 0);
    CHECK(strcmp(line, "error empty line (try help)") == 0);
    REQUIRE(ctl_line(k, line, sizeof line) == 0);
    CHECK(strncmp(line, "error ", 6) == 0);
    REQUIRE(ctl_line(k, line, sizeof line) == 0);
    CHECK(strcmp(line, "ok obstacle none") == 0);
}

static void test_lockstep(struct emu_client *c, struct ctl *k)
{
    struct wsg_client_frame f;
    uint8_t dir = 0;

    CMD_OK(k, "time pause");
    long long t0 = ctl_time(k);
    CHECK(t0 >= 0);

    /* Paused means paused: real time passes, simulated time does not. */
    emu_sleep_ms(50);
    CHECK_EQ(ctl_time(k), t0);

    REQUIRE(emu_request(c, WSG_CMD_HOMING, &dir, 1, NULL, EMU_REPLY_MS) ==
            WSG_E_CMD_PENDING);
    for (int i = 0; i < 8; i++) {
        CHECK_EQ(ctl_time_us(ctl_cmd(k, "time step 100")),
                 t0 + (i + 1) * 100000LL);
        /* The steps ran before the answer: a result would be here. */
        CHECK_EQ(emu_recv_id(c, WSG_CMD_HOMING, &f, 30), 0);
    }
    CHECK(flags_of(c) & WSG_SF_MOVING);
    CHECK_EQ(ctl_time_us(ctl_cmd(k, "time step 100")), t0 + 900000LL);
    CHECK_EQ(emu_recv_id(c, WSG_CMD_HOMING, &f, EMU_REPLY_MS), 1);
    CHECK_EQ(f.status, WSG_E_SUCCESS);
    CHECK_EQ(ctl_time(k), t0 + 900000LL);
    CHECK_NEAR(ctl_json_num(ctl_state(k), "width"), 110.0, 1e-3);
    CHECK(strstr(ctl_state(k), "\"paused\":true") != NULL);

    /* A new scale while paused waits for the resume. */
    CHECK(strcmp(ctl_cmd(k, "time scale 2"), "ok scale 2 paused") == 0);
    emu_sleep_ms(20);
    CHECK_EQ(ctl_time(k), t0 + 900000LL);
    CMD_OK(k, "time scale 1");

    CMD_OK(k, "time resume");
    CHECK(strstr(ctl_state(k), "\"paused\":false") != NULL);
}

/* --time-scale sets the scale the channel reports and runs at. */
static void test_option_scale(const char *exe)
{
    static const char *const a[] = {"--tcp",       "127.0.0.1:0",  "--control",
                                    "127.0.0.1:0", "--time-scale", "5",
                                    NULL};
    struct emu e;
    struct ctl k;

    REQUIRE(emu_start(&e, exe, a) == 0);
    REQUIRE(ctl_open(&k, &e) == 0);
    CHECK(strstr(ctl_state(&k), "\"scale\":5") != NULL);
    ctl_close(&k);
    CHECK_EQ(emu_stop(&e), 0);
}

static void test_part_lost(struct emu_client *c, struct ctl *k)
{
    struct wsg_client_frame f;
    uint8_t p[16];
    uint8_t keep = 0;
    int imm;

    CMD_OK(k, "part 40");
    size_t n = emu_grasp_payload(p, 40.0f, 100.0f);
    CHECK_EQ(emu_motion(c, WSG_CMD_GRASP, p, n, EMU_MOVE_MS, &imm),
             WSG_E_SUCCESS);
    CHECK_EQ(emu_get_grasp_state(c), WSG_GS_HOLDING);

    CMD_OK(k, "part none");
    int gs = -1;
    double deadline = emu_now_ms() + EMU_REPLY_MS;
    for (;;) {
        gs = emu_get_grasp_state(c);
        if (gs == WSG_GS_PART_LOST || emu_now_ms() >= deadline)
            break;
        emu_sleep_ms(10);
    }
    CHECK_EQ(gs, WSG_GS_PART_LOST);
    REQUIRE(emu_request(c, WSG_CMD_GET_GRASP_STATS, &keep, 1, &f,
                        EMU_REPLY_MS) == WSG_E_SUCCESS);
    REQUIRE(EMU_NPARAMS(&f) == 8);
    uint8_t *q = EMU_PARAMS(&f);
    CHECK_EQ(q[0] | q[1] << 8 | q[2] << 16 | (uint32_t)q[3] << 24, 1);
    CHECK_EQ(q[6] | q[7] << 8, 1); /* lost */
    const char *js = ctl_state(k);
    CHECK_EQ(ctl_json_num(js, "grasp_state"), WSG_GS_PART_LOST);
    CHECK_EQ(ctl_json_num(js, "lost_part"), 1);
    CHECK(strstr(js, "\"part_lost\"") != NULL);
    /* The fingers snap on through where the part was; let them settle. */
    CHECK(emu_wait_flags(c, WSG_SF_MOVING, 0, EMU_MOVE_MS, NULL) == 0);
}

static void test_faults(struct emu_client *c, struct ctl *k)
{
    uint8_t dir = 0;

    CMD_OK(k, "fault temp-fault on");
    CHECK(flags_of(c) & (1u << 14));
    CHECK(ctl_json_num(ctl_state(k), "flags") >= (double)(1u << 14));
    CHECK_EQ(emu_request(c, WSG_CMD_HOMING, &dir, 1, NULL, EMU_REPLY_MS),
             WSG_E_ACCESS_DENIED);
    CMD_OK(k, "fault temp-fault off");
    CHECK_EQ(flags_of(c) & (1u << 14), 0);

    CMD_OK(k, "fault temp-warning on");
    CHECK(flags_of(c) & WSG_SF_TEMP_WARNING);
    CMD_OK(k, "fault temp-warning off");
    CHECK_EQ(flags_of(c) & WSG_SF_TEMP_WARNING, 0);

    /* A power fault during a motion ends it. */
    uint8_t p[16];
    size_t n = emu_move_payload(p, 0, 100.0f, 10.0f);
    struct wsg_client_frame f;
    int st = emu_request(c, WSG_CMD_PREPOSITION, p, n, NULL, EMU_REPLY_MS);
    if (st != WSG_E_CMD_PENDING)
        fprintf(stderr, "preposition: status %d, state %s\n", st,
                ctl_state(k));
    REQUIRE(st == WSG_E_CMD_PENDING);
    emu_sleep_ms(50);
    CMD_OK(k, "fault power on");
    CHECK_EQ(emu_recv_id(c, WSG_CMD_PREPOSITION, &f, EMU_REPLY_MS), 1);
    CHECK_EQ(f.status, WSG_E_CMD_ABORTED);
    CHECK(flags_of(c) & WSG_SF_POWER_FAULT);
    CHECK_EQ(emu_request(c, WSG_CMD_PREPOSITION, p, n, NULL, EMU_REPLY_MS),
             WSG_E_ACCESS_DENIED);
    CMD_OK(k, "fault power off");
    uint32_t fl = flags_of(c);
    CHECK_EQ(fl & WSG_SF_POWER_FAULT, 0);
    /* The model may also FAST STOP on a power fault (its business, not
     * the channel's): acknowledged here so the next test can move. */
    if (fl & WSG_SF_FAST_STOP) {
        static const uint8_t ack[3] = {'a', 'c', 'k'};
        CHECK_EQ(
            emu_request(c, WSG_CMD_ACK_FAST_STOP, ack, 3, NULL, EMU_REPLY_MS),
            WSG_E_SUCCESS);
    }
}

/* Packets, each encoded whole, sent in one write: the daemon reads them in
 * one go, with no model step between them. */
static void send_batch(struct emu_client *c, const uint8_t *ids,
                       const void *const *payloads, const size_t *lens, int n)
{
    uint8_t buf[1024];
    size_t used = 0;
    int i;

    for (i = 0; i < n; i++) {
        size_t m = wsg_frame_encode(buf + used, sizeof buf - used, ids[i],
                                    payloads[i], lens[i]);
        REQUIRE(m > 0);
        used += m;
    }
    REQUIRE(emu_send_raw(c, buf, used) == 0);
}

/* The next packet with this ID: its status, and its first parameter byte
 * (41h) or u32/float (40h, 44h) in *v. */
static int next_of(struct emu_client *c, uint8_t id, double *v)
{
    struct wsg_client_frame f;
    int r = emu_recv_id(c, id, &f, EMU_REPLY_MS);

    if (r != 1)
        fprintf(stderr, "next_of: no %02Xh packet (%d)\n", id, r);
    REQUIRE(r == 1);
    if (v && f.status == WSG_E_SUCCESS) {
        if (id == WSG_CMD_GET_GRASP_STATE)
            *v = EMU_PARAMS(&f)[0];
        else if (id == WSG_CMD_GET_SYSTEM_STATE)
            *v = wsg_get_u32(EMU_PARAMS(&f));
        else
            *v = wsg_get_f32(EMU_PARAMS(&f));
    }
    return (int)f.status;
}

/* The answers to 40h, 41h and 44h sent after a command, at rest: the
 * flags under mask as want, the grasping state gs, speed 0. */
static void expect_at_rest(struct emu_client *c, uint32_t mask, uint32_t want,
                           int gs)
{
    double fl = 0, g = -1, sp = -1;

    CHECK_EQ(next_of(c, WSG_CMD_GET_SYSTEM_STATE, &fl), WSG_E_SUCCESS);
    CHECK_EQ((uint32_t)fl & mask, want);
    CHECK_EQ(next_of(c, WSG_CMD_GET_GRASP_STATE, &g), WSG_E_SUCCESS);
    CHECK_EQ(g, gs);
    CHECK_EQ(next_of(c, WSG_CMD_GET_SPEED, &sp), WSG_E_SUCCESS);
    CHECK_NEAR(sp, 0.0, 1e-6);
}

/* The answers to 40h and 41h sent after "ack" and a motion: moving, out
 * of FAST STOP, positioning. */
static void expect_moving(struct emu_client *c)
{
    double fl = 0, g = -1;

    CHECK_EQ(next_of(c, WSG_CMD_GET_SYSTEM_STATE, &fl), WSG_E_SUCCESS);
    CHECK_EQ((uint32_t)fl & (WSG_SF_MOVING | WSG_SF_FAST_STOP), WSG_SF_MOVING);
    CHECK_EQ(next_of(c, WSG_CMD_GET_GRASP_STATE, &g), WSG_E_SUCCESS);
    CHECK_EQ(g, WSG_GS_POSITIONING);
}

/* Every answer reflects its command at once: with time paused (no step
 * at all), or in the same write, 40h/41h/44h read right after Stop, FAST
 * STOP, "ack", a motion command, a close without 07h or a control fault
 * show the new state, and a motion sent right after "ack" is accepted. */
static void test_at_once(struct emu *e, struct emu_client *c, struct ctl *k)
{
    static const uint8_t ack[3] = {'a', 'c', 'k'};
    const uint8_t q[3] = {WSG_CMD_GET_SYSTEM_STATE, WSG_CMD_GET_GRASP_STATE,
                          WSG_CMD_GET_SPEED};
    uint8_t mv[16], ids[5];
    const void *pl[5];
    size_t ln[5], n = emu_move_payload(mv, 0, 60.0f, 10.0f);
    double fl = 0, gs = 0, sp = 0;
    float v = 0;
    struct emu_client m;
    int i;

    REQUIRE(home(c, WSG_HOME_POSITIVE) == WSG_E_SUCCESS);
    CMD_OK(k, "time pause");
    /* A motion, then the three readings: moving, positioning. */
    ids[0] = WSG_CMD_PREPOSITION, pl[0] = mv, ln[0] = n;
    for (i = 0; i < 3; i++)
        ids[i + 1] = q[i], pl[i + 1] = NULL, ln[i + 1] = 0;
    send_batch(c, ids, pl, ln, 4);
    CHECK_EQ(next_of(c, WSG_CMD_PREPOSITION, NULL), WSG_E_CMD_PENDING);
    CHECK_EQ(next_of(c, q[0], &fl), WSG_E_SUCCESS);
    CHECK((uint32_t)fl & WSG_SF_MOVING);
    CHECK_EQ(next_of(c, q[1], &gs), WSG_E_SUCCESS);
    CHECK_EQ(gs, WSG_GS_POSITIONING);
    CHECK_EQ(next_of(c, q[2], &sp), WSG_E_SUCCESS);
    CMD_OK(k, "time step 100"); /* under way at 10 mm/s */
    CHECK(emu_get_float(c, WSG_CMD_GET_SPEED, &v) == 0);
    CHECK(v < -5.0f || v > 5.0f);

    /* Stop: standing still, idle, the axis stopped; the motion's final
     * result after Stop's own answer. */
    ids[0] = WSG_CMD_STOP, pl[0] = NULL, ln[0] = 0;
    send_batch(c, ids, pl, ln, 4);
    CHECK_EQ(next_of(c, WSG_CMD_STOP, NULL), WSG_E_SUCCESS);
    CHECK_EQ(next_of(c, WSG_CMD_PREPOSITION, NULL), WSG_E_CMD_ABORTED);
    expect_at_rest(c, WSG_SF_MOVING | WSG_SF_AXIS_STOPPED, WSG_SF_AXIS_STOPPED,
                   WSG_GS_IDLE);

    /* A motion, one step, then FAST STOP: error state at once. */
    ids[0] = WSG_CMD_PREPOSITION, pl[0] = mv, ln[0] = n;
    send_batch(c, ids, pl, ln, 1);
    CHECK_EQ(next_of(c, WSG_CMD_PREPOSITION, NULL), WSG_E_CMD_PENDING);
    CMD_OK(k, "time step 100");
    ids[0] = WSG_CMD_FAST_STOP, pl[0] = NULL, ln[0] = 0;
    send_batch(c, ids, pl, ln, 4);
    CHECK_EQ(next_of(c, WSG_CMD_FAST_STOP, NULL), WSG_E_SUCCESS);
    CHECK_EQ(next_of(c, WSG_CMD_PREPOSITION, NULL), WSG_E_CMD_ABORTED);
    expect_at_rest(c, WSG_SF_MOVING | WSG_SF_FAST_STOP, WSG_SF_FAST_STOP,
                   WSG_GS_ERROR);

    /* FAST STOP, "ack" and a motion in one write, no step: the motion is
     * accepted, and 40h shows it moving, out of FAST STOP. */
    ids[0] = WSG_CMD_FAST_STOP, pl[0] = NULL, ln[0] = 0;
    ids[1] = WSG_CMD_ACK_FAST_STOP, pl[1] = ack, ln[1] = 3;
    ids[2] = WSG_CMD_PREPOSITION, pl[2] = mv, ln[2] = n;
    ids[3] = q[0], pl[3] = NULL, ln[3] = 0;
    ids[4] = q[1], pl[4] = NULL, ln[4] = 0;
    send_batch(c, ids, pl, ln, 5);
    CHECK_EQ(next_of(c, WSG_CMD_FAST_STOP, NULL), WSG_E_SUCCESS);
    CHECK_EQ(next_of(c, WSG_CMD_ACK_FAST_STOP, NULL), WSG_E_SUCCESS);
    CHECK_EQ(next_of(c, WSG_CMD_PREPOSITION, NULL), WSG_E_CMD_PENDING);
    expect_moving(c);

    /* Another client closes without 07h: FAST STOP, already there for the
     * next command, and the running motion aborted. */
    REQUIRE(emu_open(&m, e, &emu_tcp) == 0);
    REQUIRE(emu_sync(&m, EMU_REPLY_MS) == 0);
    emu_abort(&m);
    emu_sleep_ms(50); /* the daemon sees the close before the next read */
    CHECK_EQ(next_of(c, WSG_CMD_PREPOSITION, NULL), WSG_E_CMD_ABORTED);
    send_batch(c, q, (const void *const[]){NULL, NULL, NULL},
               (const size_t[]){0, 0, 0}, 3);
    expect_at_rest(c, WSG_SF_MOVING | WSG_SF_FAST_STOP, WSG_SF_FAST_STOP,
                   WSG_GS_ERROR);
    /* ...which "ack" and a motion sent at once get past. */
    send_batch(c, ids + 1, pl + 1, ln + 1, 4);
    CHECK_EQ(next_of(c, WSG_CMD_ACK_FAST_STOP, NULL), WSG_E_SUCCESS);
    CHECK_EQ(next_of(c, WSG_CMD_PREPOSITION, NULL), WSG_E_CMD_PENDING);
    expect_moving(c);

    /* A power fault from the control channel: when "ok" arrives, the
     * motion is aborted and FAST STOP shows. */
    CMD_OK(k, "fault power on");
    CHECK_EQ(next_of(c, WSG_CMD_PREPOSITION, NULL), WSG_E_CMD_ABORTED);
    send_batch(c, q, (const void *const[]){NULL, NULL, NULL},
               (const size_t[]){0, 0, 0}, 3);
    expect_at_rest(c, WSG_SF_MOVING | WSG_SF_POWER_FAULT | WSG_SF_FAST_STOP,
                   WSG_SF_POWER_FAULT | WSG_SF_FAST_STOP, WSG_GS_ERROR);
    CMD_OK(k, "fault power off");
    CHECK_EQ(emu_request(c, WSG_CMD_ACK_FAST_STOP, ack, 3, NULL, EMU_REPLY_MS),
             WSG_E_SUCCESS);
    CHECK_EQ(flags_of(c) & WSG_SF_FAST_STOP, 0);
    CMD_OK(k, "time resume");
    emu_drop_kept(c);
}

/* A motion with time paused: its E_CMD_PENDING, then time stepped far
 * enough for any motion here, then its final result. */
static int motion_paused(struct emu_client *c, struct ctl *k, uint8_t id,
                         const uint8_t *p, size_t n)
{
    CHECK_EQ(emu_request(c, id, p, n, NULL, EMU_REPLY_MS), WSG_E_CMD_PENDING);
    CMD_OK(k, "time step 3000");
    return next_of(c, id, NULL);
}

/* The answers to 40h, 41h and 45h read right after a control command:
 * flags under mask as want, the grasping state gs, the force f. */
static void expect_now(struct emu_client *c, uint32_t mask, uint32_t want,
                       int gs, double f)
{
    const uint8_t q[3] = {WSG_CMD_GET_SYSTEM_STATE, WSG_CMD_GET_GRASP_STATE,
                          WSG_CMD_GET_FORCE};
    double fl = 0, g = -1, force = -1;

    send_batch(c, q, (const void *const[]){NULL, NULL, NULL},
               (const size_t[]){0, 0, 0}, 3);
    CHECK_EQ(next_of(c, q[0], &fl), WSG_E_SUCCESS);
    CHECK_EQ((uint32_t)fl & mask, want);
    CHECK_EQ(next_of(c, q[1], &g), WSG_E_SUCCESS);
    CHECK_EQ(g, gs);
    CHECK_EQ(next_of(c, q[2], &force), WSG_E_SUCCESS);
    CHECK_NEAR(force, f, 1e-3);
}

/* The control channel's promise, command by command, with time paused so
 * that no model step can do the work: its effects are there when its
 * answer is. */
static void test_world_at_once(struct emu_client *c, struct ctl *k)
{
    const uint32_t mb =
        WSG_SF_MOVING | WSG_SF_BLOCKED_MINUS | WSG_SF_BLOCKED_PLUS;
    uint8_t p[16], dir = WSG_HOME_POSITIVE;
    double lost;
    size_t n;

    CMD_OK(k, "time pause");
    CHECK_EQ(motion_paused(c, k, WSG_CMD_HOMING, &dir, 1), WSG_E_SUCCESS);

    /* part none while holding: lost, the fingers on their way through the
     * clamping travel, no force */
    CMD_OK(k, "part 40");
    n = emu_grasp_payload(p, 40.0f, 100.0f);
    CHECK_EQ(motion_paused(c, k, WSG_CMD_GRASP, p, n), WSG_E_SUCCESS);
    expect_now(c, mb, WSG_SF_BLOCKED_MINUS, WSG_GS_HOLDING, 40.0);
    lost = ctl_json_num(ctl_state(k), "lost_part");
    CMD_OK(k, "part none");
    expect_now(c, mb, WSG_SF_MOVING, WSG_GS_PART_LOST, 0.0);
    CHECK_EQ(ctl_json_num(ctl_state(k), "lost_part"), lost + 1);
    CMD_OK(k, "time step 3000");

    /* obstacle none under a clamp: the fingers snap on towards the target
     * at once */
    CMD_OK(k, "obstacle 50");
    n = emu_move_payload(p, 0, 70.0f, 100.0f);
    CHECK_EQ(motion_paused(c, k, WSG_CMD_PREPOSITION, p, n),
             WSG_E_AXIS_BLOCKED);
    expect_now(c, mb, WSG_SF_BLOCKED_PLUS, WSG_GS_IDLE, 40.0);
    CMD_OK(k, "obstacle none");
    expect_now(c, mb, WSG_SF_MOVING, WSG_GS_IDLE, 0.0);
    CMD_OK(k, "time step 3000");
    CHECK_NEAR(ctl_json_num(ctl_state(k), "width"), 70.0, 1e-3);

    /* an obstacle placed where the fingers hold nothing changes nothing
     * until they reach it */
    CMD_OK(k, "obstacle 60");
    expect_now(c, mb, 0, WSG_GS_IDLE, 0.0);
    CMD_OK(k, "obstacle none");

    /* a temperature fault while holding: the grip goes at once */
    CMD_OK(k, "part 40");
    n = emu_grasp_payload(p, 40.0f, 100.0f);
    CHECK_EQ(motion_paused(c, k, WSG_CMD_GRASP, p, n), WSG_E_SUCCESS);
    CMD_OK(k, "fault temp-fault on");
    expect_now(c, WSG_SF_TEMP_FAULT | mb,
               WSG_SF_TEMP_FAULT | WSG_SF_BLOCKED_MINUS, WSG_GS_ERROR, 0.0);
    CMD_OK(k, "fault temp-fault off");
    expect_now(c, WSG_SF_TEMP_FAULT, 0, WSG_GS_ERROR, 0.0);
    CMD_OK(k, "part none");

    /* a power cycle: not referenced, idle, at once */
    CMD_OK(k, "reset");
    expect_now(c, WSG_SF_REFERENCED | mb, 0, WSG_GS_IDLE, 0.0);
    CHECK_EQ(motion_paused(c, k, WSG_CMD_HOMING, &dir, 1), WSG_E_SUCCESS);
    CMD_OK(k, "time resume");
    emu_drop_kept(c);
}

static void test_scale(struct emu_client *c, struct ctl *k)
{
    int st = move_to(c, 10.0f, 400.0f);
    if (st != WSG_E_SUCCESS)
        fprintf(stderr, "move: status %d, state %s\n", st, ctl_state(k));
    REQUIRE(st == WSG_E_SUCCESS);
    /* From 10 to 110 mm: 0.667 s accelerating over 33.3 mm, 66.7 mm at
     * 100 mm/s: 1.333 s of simulated time. */
    CMD_OK(k, "time scale 10");
    CHECK(strstr(ctl_state(k), "\"scale\":10") != NULL);
    long long s0 = ctl_time(k);
    double t0 = emu_now_ms();
    CHECK_EQ(home(c, WSG_HOME_POSITIVE), WSG_E_SUCCESS);
    double dt = emu_now_ms() - t0;
    long long ds = ctl_time(k) - s0;
    printf("homing at scale 10: %.0f ms real, %lld us simulated\n", dt, ds);
    CHECK(dt < 1333.0 / 2);
    CHECK(ds >= 1333000);
    CMD_OK(k, "time scale 1");
}

static void test_drop(struct emu *e, struct emu_client *c, struct ctl *k)
{
    struct emu_client m;
    struct wsg_client_frame f;

    char line[1024];

    CHECK_EQ(flags_of(c) & WSG_SF_FAST_STOP, 0);
    /* With time paused, "drop" and "state" in one write: the close's FAST
     * STOP is there when "ok dropped" is, not only after the batch. */
    CMD_OK(k, "time pause");
    REQUIRE(ctl_write(k, "drop\nstate\n") == 0);
    REQUIRE(ctl_line(k, line, sizeof line) == 0);
    CHECK(strcmp(line, "ok dropped 1") == 0);
    REQUIRE(ctl_line(k, line, sizeof line) == 0);
    CHECK((uint32_t)ctl_json_num(line, "flags") & WSG_SF_FAST_STOP);
    CHECK(strstr(line, "\"fast_stop\"") != NULL);
    CMD_OK(k, "time resume");
    /* The server closed: end of stream, not a timeout. */
    CHECK_EQ(emu_recv(c, &f, EMU_REPLY_MS), -1);
    CHECK(c->link.eof);
    emu_close(c);

    REQUIRE(emu_open(&m, e, &emu_tcp) == 0);
    /* At once, as for any close without 07h: "ok dropped" came after it. */
    CHECK(flags_of(&m) & WSG_SF_FAST_STOP);
    emu_close(&m);
}

static void test_reset(struct emu *e, struct ctl *k)
{
    struct emu_client m;
    struct wsg_client_frame f;
    float acc = 0;
    uint8_t p[4];
    float v = 500.0f;
    uint8_t ack[3] = {'a', 'c', 'k'};
    uint8_t stream[3] = {1, 100, 0}; /* every 100 ms */

    REQUIRE(emu_open(&m, e, &emu_tcp) == 0);
    CHECK_EQ(
        emu_request(&m, WSG_CMD_ACK_FAST_STOP, ack, 3, NULL, EMU_REPLY_MS),
        WSG_E_SUCCESS);
    memcpy(p, &v, 4); /* the test hosts are little-endian like the wire */
    CHECK_EQ(
        emu_request(&m, WSG_CMD_SET_ACCELERATION, p, 4, NULL, EMU_REPLY_MS),
        WSG_E_SUCCESS);
    CHECK(emu_get_float(&m, WSG_CMD_GET_ACCELERATION, &acc) == 0);
    CHECK_NEAR(acc, 500.0, 0.01);
    CHECK(flags_of(&m) & WSG_SF_REFERENCED);
    CHECK_EQ(emu_request(&m, WSG_CMD_GET_WIDTH, stream, 3, NULL, EMU_REPLY_MS),
             WSG_E_SUCCESS);
    CHECK_EQ(emu_recv_id(&m, WSG_CMD_GET_WIDTH, &f, EMU_REPLY_MS), 1);

    CMD_OK(k, "reset");
    CHECK_EQ(flags_of(&m) & WSG_SF_REFERENCED, 0);
    CHECK_EQ(ctl_json_num(ctl_state(k), "flags"), 0);
    CHECK(emu_get_float(&m, WSG_CMD_GET_ACCELERATION, &acc) == 0);
    CHECK_NEAR(acc, 150.0, 0.01);
    /* The stream ended with the power cycle. */
    emu_drop_kept(&m);
    REQUIRE(emu_sync(&m, EMU_REPLY_MS) == 0);
    emu_drop_kept(&m);
    CHECK_EQ(emu_recv_id(&m, WSG_CMD_GET_WIDTH, &f, EMU_QUIET_MS), 0);
    emu_close(&m);
}

int main(int argc, char **argv)
{
    const char *exe = emu_exe(argc, argv);
    struct emu e;
    struct emu_client c;
    struct ctl k, k2;

    REQUIRE(emu_start(&e, exe, args) == 0);
    REQUIRE(ctl_open(&k, &e) == 0);
    REQUIRE(emu_open(&c, &e, &emu_tcp) == 0);

    test_ready_and_state(&e, &k);
    /* A second control client at once. */
    REQUIRE(ctl_open(&k2, &e) == 0);
    CHECK(ctl_is_ok(ctl_cmd(&k2, "time")));
    test_errors(&k2);
    ctl_close(&k2);

    test_lockstep(&c, &k);
    test_part_lost(&c, &k);
    test_faults(&c, &k);
    test_at_once(&e, &c, &k);
    test_world_at_once(&c, &k);
    test_scale(&c, &k);
    test_drop(&e, &c, &k);
    test_reset(&e, &k);

    ctl_close(&k);
    CHECK_EQ(emu_stop(&e), 0);

    test_option_scale(exe);
    TEST_EXIT();
}
