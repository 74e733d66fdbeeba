/*
 * integ_gcl: GCL, the text interface (--text-interface on), over TCP the
 * way its clients use it: one command line out, whole reply lines back.
 * Every reply is compared with the exact line that GCL.md and the
 * interpreter (include/wsg/gcl.h) promise ("ACK MOVE", "FIN MOVE",
 * "ERR MOVE 3", with VERBOSE=1 "ERR MOVE 3 E_NOT_INITIALIZED",
 * "POS=30.0", "@POS=110.0"), so that each check can fail. One program,
 * one ctest per part, each with daemons of its own:
 *
 * - commands: every command of GCL.md and its replies: VERBOSE, HOME with
 *   and without a direction, MOVE with and without a speed (refused before
 *   homing and in FAST STOP), STOP and FASTSTOP of a running MOVE, FSACK,
 *   GRIP in its four forms (nothing between the fingers: HOLDING; a part
 *   placed by the control channel: held, a collision, no part, lost),
 *   RELEASE relative to where the fingers are and only after a GRIP,
 *   PWT and CLT as this connection's own and gone with it, the queries,
 *   TARE and FDATA with force measurement fingers, AUTOSEND counted in
 *   stepped simulated time, BYE and what is refused after it, unknown
 *   commands and bad syntax;
 * - framing: a client that compares each recv() with one whole line (as
 *   minWSG does) over HOME, MOVE, GRIP, queries and errors; several lines
 *   in one segment, CR LF, the 256-byte limit, overlong, binary and garbage
 *   lines (one ERR each, the next line served), a command split over
 *   segments, empty lines;
 * - rules: the suite's own rules under GCL: one answer per command, none
 *   lost in bursts of 200 and 1000 lines in one write, a close without BYE
 *   is FAST STOP (40h D12 in the control channel's state), after BYE it
 *   is not, watched for a window as integ_disconnect does;
 * - fleet: --grippers 2 with GCL on both, each gripper its own;
 * - log: the communication log (--log) shows the text lines ("in
 *   MOVE(30,100)", "out FIN MOVE"), one entry per send, each one whole
 *   line: the daemon's side of "every line in its own write".
 *
 * Where a reply's timing matters (what a running motion answers, the
 * count of AUTOSEND lines, recv() seeing one line only) simulated time is
 * paused and stepped through the control channel, so that a loaded machine
 * cannot change what is seen; the rest runs with time going on, every wait
 * bounded by the suite's scaled limits (emu.h).
 */
#define _GNU_SOURCE /* mkdtemp */

#include "check.h"
#include "emu.h"
#include "emu_ctl.h"
#include "wsg/axis.h"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <unistd.h>

/* ---- a GCL client: lines over the client library's TCP link ---- */

struct gcl {
    struct wsg_client link;
};

/* Connect to gripper nth's value of the ready line's tcp= field. */
static int gcl_open(struct gcl *c, const struct emu *e, unsigned nth)
{
    char v[1024], *p, *comma;
    struct sockaddr_in sa;
    unsigned i;

    wsg_client_init(&c->link, WSG_LINK_TCP);
    if (!emu_field(e, "tcp", v, sizeof v))
        return -1;
    for (p = v, i = 0; i < nth; i++) {
        p = strchr(p, ',');
        if (!p)
            return -1;
        p++;
    }
    comma = strchr(p, ',');
    if (comma)
        *comma = '\0';
    if (emu_ipv4_addr(p, &sa) < 0)
        return -1;
    /* TCP_NODELAY, as the clients set it (wsg_client_open_tcp). */
    return wsg_client_open_tcp(&c->link, &sa, EMU_REPLY_MS) < 0 ? -1 : 0;
}

static void gcl_close(struct gcl *c)
{
    wsg_client_close(&c->link);
}

/* Bytes in one write, binary ones too. */
static void gcl_write(struct gcl *c, const void *data, size_t len)
{
    REQUIRE(wsg_client_send(&c->link, data, len) == 0);
}

static void gcl_say(struct gcl *c, const char *text)
{
    gcl_write(c, text, strlen(text));
}

/* The next line (without its newline) within ms: 1, else 0. */
static int gcl_line(struct gcl *c, char *out, size_t cap, int ms)
{
    uint64_t deadline = wsg_client_deadline(ms);

    return wsg_client_line_read(&c->link, out, cap, deadline) == 1;
}

/* The next line must be the formatted one; at is the caller's line. */
static void expect_line(struct gcl *c, int at, int ms, const char *fmt, ...)
{
    char want[512], got[512];
    va_list ap;
    int ok;

    va_start(ap, fmt);
    vsnprintf(want, sizeof want, fmt, ap);
    va_end(ap);
    ok = gcl_line(c, got, sizeof got, ms);
    check_count++;
    if (!ok || strcmp(got, want) != 0) {
        check_failures++;
        if (ok)
            fprintf(stderr, "%s:%d: expected \"%s\", got \"%s\"\n", __FILE__,
                    at, want, got);
        else
            fprintf(stderr, "%s:%d: expected \"%s\", got nothing\n", __FILE__,
                    at, want);
    }
}

#define EXPECT(c, ...) expect_line((c), __LINE__, EMU_REPLY_MS, __VA_ARGS__)
/* A motion's final line. */
#define EXPECT_FIN(c, ...) expect_line((c), __LINE__, EMU_MOVE_MS, __VA_ARGS__)
/* One command, one reply line. */
#define ASK(c, cmd, want)                                                     \
    do {                                                                      \
        gcl_say((c), cmd "\n");                                               \
        EXPECT((c), "%s", (want));                                            \
    } while (0)
/* A motion that completes: ACK, then FIN. */
#define MOTION(c, cmd, name)                                                  \
    do {                                                                      \
        gcl_say((c), cmd "\n");                                               \
        EXPECT((c), "ACK %s", (name));                                        \
        EXPECT_FIN((c), "FIN %s", (name));                                    \
    } while (0)

/* Nothing more arrives within the quiet window. */
static void expect_quiet(struct gcl *c, int at)
{
    char got[512];

    check_count++;
    if (gcl_line(c, got, sizeof got, EMU_QUIET_MS)) {
        check_failures++;
        fprintf(stderr, "%s:%d: expected nothing, got \"%s\"\n", __FILE__, at,
                got);
    }
}
#define QUIET(c) expect_quiet((c), __LINE__)

/* A query's number: "POS?" -> the value of "POS=...". */
static double query_num(struct gcl *c, const char *key)
{
    char cmd[64], got[512];
    size_t n = strlen(key);

    snprintf(cmd, sizeof cmd, "%s?\n", key);
    gcl_say(c, cmd);
    REQUIRE(gcl_line(c, got, sizeof got, EMU_REPLY_MS));
    if (strncmp(got, key, n) != 0 || got[n] != '=') {
        fprintf(stderr, "%s? answered \"%s\"\n", key, got);
        CHECK(!"a KEY=value answer");
        return -1e9;
    }
    return strtod(got + n + 1, NULL);
}

/* One recv() straight from the socket, as minWSG reads: what it returns
 * must be one whole line. Nothing may be in the link's buffer (the lines
 * before were read whole). */
static void expect_recv(struct gcl *c, int at, const char *want)
{
    struct pollfd p = {c->link.fd, POLLIN, 0};
    char buf[512];
    ssize_t n = -1;

    REQUIRE(c->link.off == c->link.len);
    if (poll(&p, 1, EMU_REPLY_MS) == 1)
        n = recv(c->link.fd, buf, sizeof buf - 1, 0);
    buf[n > 0 ? n : 0] = '\0';
    check_count++;
    if (n <= 0 || strcmp(buf, want) != 0) {
        check_failures++;
        fprintf(stderr, "%s:%d: one recv(): expected \"%s\", got \"%s\"\n",
                __FILE__, at, want, buf);
    }
}
#define EXPECT_RECV(c, want) expect_recv((c), __LINE__, (want))

/* Announce the close, then close. */
static void gcl_bye(struct gcl *c)
{
    ASK(c, "BYE()", "ACK BYE");
    gcl_close(c);
}

/* ---- the control channel ---- */

static const char *ctl_state(struct ctl *k)
{
    const char *js = ctl_cmd(k, "state");

    REQUIRE(strncmp(js, "ok {", 4) == 0);
    return js;
}

static uint32_t state_flags(struct ctl *k)
{
    return (uint32_t)ctl_json_num(ctl_state(k), "flags");
}

/* Poll the state for up to ms: 1 if FAST STOP showed. */
static int fast_stop_within(struct ctl *k, int ms)
{
    double deadline = emu_now_ms() + ms;

    for (;;) {
        if (state_flags(k) & WSG_SF_FAST_STOP)
            return 1;
        if (emu_now_ms() >= deadline)
            return 0;
        emu_sleep_ms(10);
    }
}

static const char *const gcl_args[] = {
    "--tcp",       "127.0.0.1:0", "--text-interface", "on", "--control",
    "127.0.0.1:0", NULL};

/* ---- commands ---- */

/* Before homing: the readings of power-up, motions refused; VERBOSE and
 * the ERR lines with and without the name; unknown commands, bad syntax,
 * bad values. */
static void test_errors(struct gcl *c)
{
    ASK(c, "VERBOSE?", "VERBOSE=0");
    ASK(c, "POS?", "POS=55.0");
    ASK(c, "SPEED?", "SPEED=0.0");
    ASK(c, "FORCE?", "FORCE=0.0");
    ASK(c, "GRIPSTATE?", "GRIPSTATE=0");
    ASK(c, "SYSFLAGS?", "SYSFLAGS=0");
    ASK(c, "MOVE(30)", "ERR MOVE 3");
    ASK(c, "MOVE(30, 100)", "ERR MOVE 3");
    ASK(c, "GRIP()", "ERR GRIP 3");
    ASK(c, "GRIP(20, 40)", "ERR GRIP 3");
    ASK(c, "RELEASE()", "ERR RELEASE 16");
    ASK(c, "FROB()", "ERR FROB 14");
    ASK(c, "MOVE(", "ERR MOVE 15");
    ASK(c, "VERBOSE=1", "VERBOSE=1");
    ASK(c, "VERBOSE?", "VERBOSE=1");
    ASK(c, "MOVE(30)", "ERR MOVE 3 E_NOT_INITIALIZED");
    ASK(c, "RELEASE()", "ERR RELEASE 16 E_ACCESS_DENIED");
    ASK(c, "FROB()", "ERR FROB 14 E_CMD_UNKNOWN");
    ASK(c, "frob?", "ERR FROB 14 E_CMD_UNKNOWN");
    ASK(c, "MOVE(", "ERR MOVE 15 E_CMD_FORMAT_ERROR");
    ASK(c, ")))", "ERR ? 15 E_CMD_FORMAT_ERROR");
    ASK(c, "VERBOSE=2", "ERR VERBOSE 24 E_INVALID_PARAMETER");
    ASK(c, "VERBOSE=0", "VERBOSE=0");
    ASK(c, "VERBOSE=2", "ERR VERBOSE 24");
    /* Bad syntax and forms a command does not take. */
    ASK(c, ")))", "ERR ? 15");
    ASK(c, "hello world", "ERR HELLO 15");
    ASK(c, "POS", "ERR POS 15");
    ASK(c, "POS=3", "ERR POS 15");
    ASK(c, "POS[0]?", "ERR POS 15");
    ASK(c, "MOVE?", "ERR MOVE 15");
    ASK(c, "MOVE()", "ERR MOVE 15");
    ASK(c, "MOVE(1, 2, 3)", "ERR MOVE 15");
    ASK(c, "MOVE(1,)", "ERR MOVE 15");
    ASK(c, "MOVE(1e999)", "ERR MOVE 15");
    ASK(c, "MOVE(nan)", "ERR MOVE 15");
    ASK(c, "HOME(1, 2)", "ERR HOME 15");
    ASK(c, "BYE(1)", "ERR BYE 15");
    ASK(c, "MOVE(\"wide\")", "ERR MOVE 24");
    /* Lower case and blanks are the same command. */
    ASK(c, "  pos ?  ", "POS=55.0");
}

/* HOME(): the configured direction (positive); HOME(0) and HOME(1). */
static void test_home(struct gcl *c)
{
    MOTION(c, "HOME()", "HOME");
    ASK(c, "POS?", "POS=110.0");
    ASK(c, "GRIPSTATE?", "GRIPSTATE=0");
    MOTION(c, "HOME(0)", "HOME");
    ASK(c, "POS?", "POS=0.0");
    MOTION(c, "HOME(1)", "HOME");
    ASK(c, "POS?", "POS=110.0");
}

/* MOVE with and without a speed; what a running MOVE refuses, and STOP. */
static void test_move(struct gcl *c, struct ctl *k)
{
    double w;

    MOTION(c, "MOVE(30, 100)", "MOVE");
    ASK(c, "POS?", "POS=30.0");
    MOTION(c, "MOVE(50)", "MOVE");
    ASK(c, "POS?", "POS=50.0");
    MOTION(c, "MOVE(60.0,100)", "MOVE");
    ASK(c, "POS?", "POS=60.0");

    /* The speed given is the speed driven: cruising at 20 mm/s after
     * 0.5 s (the default 100 mm/s would still accelerate, at 75). */
    CMD_OK(k, "time pause");
    ASK(c, "MOVE(100, 20)", "ACK MOVE");
    CMD_OK(k, "time step 500");
    ASK(c, "SPEED?", "SPEED=20.0");
    ASK(c, "GRIPSTATE?", "GRIPSTATE=6");
    /* One motion at a time. */
    ASK(c, "MOVE(70)", "ERR MOVE 4");
    ASK(c, "GRIP()", "ERR GRIP 4");
    ASK(c, "HOME()", "ERR HOME 4");
    /* STOP: its own ACK, then the MOVE's end. */
    gcl_say(c, "STOP()\n");
    EXPECT(c, "ACK STOP");
    EXPECT(c, "ERR MOVE 19");
    ASK(c, "GRIPSTATE?", "GRIPSTATE=0");
    ASK(c, "SPEED?", "SPEED=0.0");
    w = query_num(c, "POS");
    CHECK(w > 61.0 && w < 70.0);
    CMD_OK(k, "time step 500");
    CHECK_NEAR(query_num(c, "POS"), w, 1e-9); /* stopped */
    QUIET(c);                                 /* no FIN MOVE after all */
    /* With nothing running, STOP is acknowledged all the same. */
    ASK(c, "STOP()", "ACK STOP");
    CMD_OK(k, "time resume");
}

/* FASTSTOP: refuses motion until FSACK; over a running MOVE it ends it. */
static void test_fast_stop(struct gcl *c, struct ctl *k)
{
    ASK(c, "FASTSTOP()", "ACK FASTSTOP");
    CHECK(state_flags(k) & WSG_SF_FAST_STOP);
    CHECK(strstr(ctl_state(k), "\"fast_stop\"") != NULL);
    ASK(c, "GRIPSTATE?", "GRIPSTATE=7");
    ASK(c, "MOVE(30)", "ERR MOVE 16");
    ASK(c, "MOVE(30, 50)", "ERR MOVE 16");
    ASK(c, "GRIP()", "ERR GRIP 16");
    ASK(c, "HOME()", "ERR HOME 16");
    ASK(c, "VERBOSE=1", "VERBOSE=1");
    ASK(c, "MOVE(30)", "ERR MOVE 16 E_ACCESS_DENIED");
    ASK(c, "VERBOSE=0", "VERBOSE=0");
    ASK(c, "FSACK()", "ACK FSACK");
    CHECK_EQ(state_flags(k) & WSG_SF_FAST_STOP, 0);
    /* Nothing to acknowledge: acknowledged all the same. */
    ASK(c, "FSACK()", "ACK FSACK");

    CMD_OK(k, "time pause");
    ASK(c, "MOVE(30, 20)", "ACK MOVE");
    CMD_OK(k, "time step 200");
    gcl_say(c, "FASTSTOP()\n");
    EXPECT(c, "ACK FASTSTOP");
    EXPECT(c, "ERR MOVE 19");
    CHECK(state_flags(k) & WSG_SF_FAST_STOP);
    ASK(c, "FSACK()", "ACK FSACK");
    CMD_OK(k, "time resume");
    MOTION(c, "MOVE(30)", "MOVE");
    ASK(c, "POS?", "POS=30.0");
}

/* GRIP() with nothing between the fingers: they grip each other,
 * HOLDING; RELEASE opens by the pull-back from there, once. */
static void test_grip_nothing(struct gcl *c)
{
    ASK(c, "RELEASE()", "ERR RELEASE 16"); /* no GRIP yet */
    MOTION(c, "GRIP()", "GRIP");
    ASK(c, "GRIPSTATE?", "GRIPSTATE=4");
    ASK(c, "POS?", "POS=0.0");
    ASK(c, "FORCE?", "FORCE=40.0"); /* the default force limit */
    ASK(c, "SPEED?", "SPEED=0.0");
    ASK(c, "GRIP()", "ERR GRIP 16"); /* not while HOLDING */
    ASK(c, "GRIP(20, 30)", "ERR GRIP 16");
    MOTION(c, "RELEASE()", "RELEASE");
    ASK(c, "POS?", "POS=10.0"); /* --release-pullback's default */
    ASK(c, "GRIPSTATE?", "GRIPSTATE=0");
    ASK(c, "FORCE?", "FORCE=0.0");
    ASK(c, "RELEASE()", "ERR RELEASE 16"); /* only after a GRIP */
    ASK(c, "RELEASE(-1)", "ERR RELEASE 16");
}

/* GRIP's forms with a part of 40 mm (50 N/mm: 20 N hold it at 39.6). */
static void test_grip_part(struct gcl *c, struct ctl *k)
{
    MOTION(c, "MOVE(100)", "MOVE");
    CMD_OK(k, "part 40");

    /* GRIP(force): closes until contact. */
    MOTION(c, "GRIP(20)", "GRIP");
    ASK(c, "GRIPSTATE?", "GRIPSTATE=4");
    ASK(c, "FORCE?", "FORCE=20.0");
    ASK(c, "POS?", "POS=39.6");
    ASK(c, "GRIP(20)", "ERR GRIP 16");
    /* RELEASE(pullback): from where the fingers are. */
    MOTION(c, "RELEASE(5)", "RELEASE");
    ASK(c, "POS?", "POS=44.6");
    ASK(c, "GRIPSTATE?", "GRIPSTATE=0");

    /* GRIP(force, width): the part where it is expected. */
    MOTION(c, "GRIP(30, 40)", "GRIP");
    ASK(c, "GRIPSTATE?", "GRIPSTATE=4");
    ASK(c, "FORCE?", "FORCE=30.0");
    ASK(c, "POS?", "POS=39.4");
    /* RELEASE(pullback, speed): at 20 mm/s (the default would still
     * accelerate, at 30 mm/s, after 0.2 s). */
    CMD_OK(k, "time pause");
    ASK(c, "RELEASE(5, 20)", "ACK RELEASE");
    CMD_OK(k, "time step 200");
    ASK(c, "SPEED?", "SPEED=20.0");
    ASK(c, "GRIPSTATE?", "GRIPSTATE=5");
    CMD_OK(k, "time step 1000");
    EXPECT(c, "FIN RELEASE");
    ASK(c, "POS?", "POS=44.4");
    CMD_OK(k, "time resume");

    /* GRIP(force, width, speed): closing at 20 mm/s. */
    MOTION(c, "MOVE(100)", "MOVE");
    CMD_OK(k, "time pause");
    ASK(c, "GRIP(20, 40, 20)", "ACK GRIP");
    CMD_OK(k, "time step 500");
    ASK(c, "SPEED?", "SPEED=-20.0");
    ASK(c, "GRIPSTATE?", "GRIPSTATE=1");
    CMD_OK(k, "time step 4000");
    EXPECT(c, "FIN GRIP");
    ASK(c, "GRIPSTATE?", "GRIPSTATE=4");
    ASK(c, "POS?", "POS=39.6");
    CMD_OK(k, "time resume");

    /* The part taken away while held: PART LOST, the fingers close
     * through the clamping travel; RELEASE still works. */
    CMD_OK(k, "time pause");
    CMD_OK(k, "part none");
    ASK(c, "GRIPSTATE?", "GRIPSTATE=3");
    CMD_OK(k, "time step 2000");
    ASK(c, "POS?", "POS=30.0");
    ASK(c, "GRIPSTATE?", "GRIPSTATE=3");
    CMD_OK(k, "time resume");
    MOTION(c, "RELEASE(20)", "RELEASE");
    ASK(c, "POS?", "POS=50.0");
    ASK(c, "GRIPSTATE?", "GRIPSTATE=0");

    /* A collision: the part (40) wider than width + PWT (20 + 10). */
    MOTION(c, "MOVE(100)", "MOVE");
    CMD_OK(k, "part 40");
    ASK(c, "GRIP(20, 20)", "ACK GRIP");
    EXPECT_FIN(c, "ERR GRIP 29");
    ASK(c, "GRIPSTATE?", "GRIPSTATE=2");
    ASK(c, "POS?", "POS=39.6");
    /* After a GRIP that failed, RELEASE is allowed. */
    MOTION(c, "RELEASE()", "RELEASE");
    ASK(c, "POS?", "POS=49.6");

    /* No part: closed through the clamping travel (40 - 10). */
    CMD_OK(k, "part none");
    ASK(c, "GRIP(20, 40)", "ACK GRIP");
    EXPECT_FIN(c, "ERR GRIP 18");
    ASK(c, "GRIPSTATE?", "GRIPSTATE=2");
    ASK(c, "POS?", "POS=30.0");

    /* The same with the error names. */
    ASK(c, "VERBOSE=1", "VERBOSE=1");
    MOTION(c, "MOVE(100)", "MOVE");
    CMD_OK(k, "part 40");
    ASK(c, "GRIP(20, 20)", "ACK GRIP");
    EXPECT_FIN(c, "ERR GRIP 29 E_AXIS_BLOCKED");
    MOTION(c, "MOVE(100)", "MOVE");
    CMD_OK(k, "part none");
    ASK(c, "GRIP(20, 40)", "ACK GRIP");
    EXPECT_FIN(c, "ERR GRIP 18 E_CMD_FAILED");
    ASK(c, "VERBOSE=0", "VERBOSE=0");
    MOTION(c, "MOVE(100)", "MOVE");
}

/* PWT and CLT: this connection's window, not another's, gone with it. */
static void test_window(struct gcl *c, struct ctl *k, struct emu *e)
{
    struct gcl o;

    REQUIRE(gcl_open(&o, e, 0) == 0);
    ASK(c, "PWT?", "PWT=10.0");
    ASK(c, "CLT?", "CLT=10.0");
    ASK(c, "PWT=2", "PWT=2.0");
    ASK(c, "PWT?", "PWT=2.0");
    ASK(c, "PWT=-1", "ERR PWT 28");
    ASK(c, "CLT=200", "ERR CLT 28");
    ASK(c, "CLT=\"x\"", "ERR CLT 28");
    ASK(c, "CLT?", "CLT=10.0");
    ASK(&o, "PWT?", "PWT=10.0");

    /* Part 40, GRIP(20, 35): within 35 + 10, outside 35 + 2. */
    CMD_OK(k, "part 40");
    ASK(c, "GRIP(20, 35)", "ACK GRIP");
    EXPECT_FIN(c, "ERR GRIP 29");
    ASK(c, "POS?", "POS=39.6");
    MOTION(&o, "MOVE(100)", "MOVE");
    MOTION(&o, "GRIP(20, 35)", "GRIP");
    ASK(&o, "GRIPSTATE?", "GRIPSTATE=4");
    MOTION(&o, "RELEASE()", "RELEASE");
    MOTION(&o, "MOVE(100)", "MOVE");

    /* GRIP(20, 45): the part within 45 - 10, beyond 45 - 2. */
    ASK(c, "CLT=2", "CLT=2.0");
    ASK(c, "GRIP(20, 45)", "ACK GRIP");
    EXPECT_FIN(c, "ERR GRIP 18");
    ASK(c, "POS?", "POS=43.0");
    MOTION(&o, "MOVE(100)", "MOVE");
    ASK(&o, "CLT?", "CLT=10.0");
    MOTION(&o, "GRIP(20, 45)", "GRIP");
    MOTION(&o, "RELEASE()", "RELEASE");
    MOTION(&o, "MOVE(100)", "MOVE");
    gcl_bye(&o);

    /* A new connection has the defaults again, and grips by them. */
    gcl_bye(c);
    REQUIRE(gcl_open(c, e, 0) == 0);
    ASK(c, "PWT?", "PWT=10.0");
    ASK(c, "CLT?", "CLT=10.0");
    MOTION(c, "GRIP(20, 35)", "GRIP");
    MOTION(c, "RELEASE()", "RELEASE");
    CMD_OK(k, "part none");
    MOTION(c, "MOVE(100)", "MOVE");
}

/* The readings against the control channel's state; the daemon's
 * --serial and --tag. */
static void test_queries(struct gcl *c, struct ctl *k)
{
    const char *js;
    double temp;
    unsigned long flags, total;
    unsigned no_part, lost;

    /* Time stands while state and replies are compared: the drive's
     * temperature follows its work. */
    CMD_OK(k, "time pause");
    js = ctl_state(k);
    temp = ctl_json_num(js, "temperature");
    flags = (unsigned long)ctl_json_num(js, "flags");
    total = (unsigned long)ctl_json_num(js, "total");
    no_part = (unsigned)ctl_json_num(js, "no_part");
    lost = (unsigned)ctl_json_num(js, "lost_part");
    /* The grips above: 13, 6 of them without a part (collisions too),
     * one part lost. */
    CHECK_EQ(total, 13);
    CHECK_EQ(no_part, 6);
    CHECK_EQ(lost, 1);
    gcl_say(c, "TEMP?\n");
    EXPECT(c, "TEMP=%.1f", temp);
    gcl_say(c, "SYSFLAGS?\n");
    EXPECT(c, "SYSFLAGS=%lu", flags);
    gcl_say(c, "GRIPSTATS?\n");
    EXPECT(c, "GRIPSTATS=%lu,%u,%u", total, no_part, lost);
    ASK(c, "DEVTYPE?", "DEVTYPE=WSG50");
    ASK(c, "VERSION?", "VERSION=2.2.0");
    ASK(c, "SN?", "SN=4711");
    ASK(c, "TAG?", "TAG=cell-4");
    ASK(c, "TEMP[0]?", "ERR TEMP 15");
    ASK(c, "SN=5", "ERR SN 15");
    CMD_OK(k, "time resume");
}

/* With --force-sensor on: TARE out of force control, FDATA the force. */
static void test_sensor(struct gcl *c, struct ctl *k)
{
    ASK(c, "TARE()", "ACK TARE");
    ASK(c, "FDATA?", "FDATA=0.0");
    ASK(c, "FDATA[0]?", "FDATA[0]=0.0");
    ASK(c, "FDATA[1]?", "FDATA[1]=0.0");
    ASK(c, "FDATA[2]?", "ERR FDATA 25");
    ASK(c, "TARE(1)", "ERR TARE 15");
    CMD_OK(k, "part 40");
    MOTION(c, "GRIP(25)", "GRIP");
    ASK(c, "FDATA?", "FDATA=25.0");
    ASK(c, "FDATA[0]?", "FDATA[0]=25.0");
    ASK(c, "FDATA[1]?", "FDATA[1]=25.0");
    ASK(c, "TARE()", "ERR TARE 16"); /* in force control */
    MOTION(c, "RELEASE()", "RELEASE");
    ASK(c, "TARE()", "ACK TARE");
    CMD_OK(k, "part none");
}

/* Reads n lines; counts those equal to a and to b. */
static void count_lines(struct gcl *c, int n, const char *a, int *na,
                        const char *b, int *nb)
{
    char got[512];
    int i;

    *na = *nb = 0;
    for (i = 0; i < n; i++) {
        if (!gcl_line(c, got, sizeof got, EMU_REPLY_MS)) {
            fprintf(stderr, "line %d of %d: nothing\n", i + 1, n);
            break;
        }
        if (strcmp(got, a) == 0)
            (*na)++;
        else if (b && strcmp(got, b) == 0)
            (*nb)++;
        else
            fprintf(stderr, "line %d of %d: \"%s\"\n", i + 1, n, got);
    }
}

/* AUTOSEND: @ lines at the period, in simulated time. */
static void test_autosend(struct gcl *c, struct ctl *k)
{
    char pos[32];
    int npos, ngs;

    snprintf(pos, sizeof pos, "@POS=%.1f", query_num(c, "POS"));
    ASK(c, "AUTOSEND(\"FOO\", 50)", "ERR AUTOSEND 24");
    ASK(c, "AUTOSEND(1, 50)", "ERR AUTOSEND 24");
    ASK(c, "AUTOSEND(\"POS\", -1)", "ERR AUTOSEND 28");
    ASK(c, "AUTOSEND(\"POS\", 2.5)", "ERR AUTOSEND 28");
    ASK(c, "AUTOSEND(\"POS\")", "ERR AUTOSEND 15");
    ASK(c, "AUTOSEND(POS, 50)", "ERR AUTOSEND 15");

    CMD_OK(k, "time pause");
    ASK(c, "AUTOSEND(\"POS\", 50)", "ACK AUTOSEND");
    ASK(c, "AUTOSEND(\"GRIPSTATE\", 100)", "ACK AUTOSEND");
    QUIET(c); /* time stands: nothing yet */
    /* 500 ms: 10 of POS, 5 of GRIPSTATE. */
    CMD_OK(k, "time step 500");
    count_lines(c, 15, pos, &npos, "@GRIPSTATE=0", &ngs);
    CHECK_EQ(npos, 10);
    CHECK_EQ(ngs, 5);
    /* A query does not end the stream. */
    ASK(c, "POS?", pos + 1);
    CMD_OK(k, "time step 100");
    count_lines(c, 3, pos, &npos, "@GRIPSTATE=0", &ngs);
    CHECK_EQ(npos, 2);
    CHECK_EQ(ngs, 1);
    /* Period 0 ends it. */
    ASK(c, "AUTOSEND(\"POS\", 0)", "ACK AUTOSEND");
    CMD_OK(k, "time step 300");
    count_lines(c, 3, "@GRIPSTATE=0", &ngs, NULL, &npos);
    CHECK_EQ(ngs, 3);
    ASK(c, "AUTOSEND(\"GRIPSTATE\", 0)", "ACK AUTOSEND");
    CMD_OK(k, "time step 500");
    QUIET(c);
    CMD_OK(k, "time resume");
}

/* BYE: a running motion ends; afterwards every command is refused, as
 * after 07h. */
static void test_bye(struct gcl *c, struct ctl *k)
{
    CMD_OK(k, "time pause");
    ASK(c, "MOVE(30, 20)", "ACK MOVE");
    CMD_OK(k, "time step 100");
    gcl_say(c, "BYE()\n");
    EXPECT(c, "ACK BYE");
    EXPECT(c, "ERR MOVE 19");
    CMD_OK(k, "time resume");
    ASK(c, "POS?", "ERR POS 16");
    ASK(c, "MOVE(50)", "ERR MOVE 16");
    ASK(c, "GRIP()", "ERR GRIP 16");
    ASK(c, "RELEASE()", "ERR RELEASE 16");
    ASK(c, "AUTOSEND(\"POS\", 0)", "ERR AUTOSEND 16");
    /* The interpreter's own commands too, and what the binary side
     * refuses after 07h before looking at it. */
    ASK(c, "FDATA?", "ERR FDATA 16");
    ASK(c, "PWT=3", "ERR PWT 16");
    ASK(c, "CLT?", "ERR CLT 16");
    ASK(c, "VERBOSE=1", "ERR VERBOSE 16");
    ASK(c, "FROB()", "ERR FROB 16");
    ASK(c, "MOVE(", "ERR MOVE 16");
    ASK(c, "BYE()", "ERR BYE 16");
    gcl_close(c);
    CHECK_EQ(state_flags(k) & WSG_SF_FAST_STOP, 0);
}

static void part_commands(const char *exe)
{
    /* Simulated time at 10 times real time: the many motions of this
     * part take seconds, not a minute. What they end in does not depend
     * on it, and where timing matters time is paused and stepped. */
    static const char *const extra[] = {
        "--force-sensor", "on",                      /* TARE, FDATA */
        "--serial",       "4711", "--tag", "cell-4", /* SN?, TAG? */
        "--time-scale",   "10",   NULL};
    const char *args[16];
    struct emu e;
    struct ctl k;
    struct gcl c;
    size_t n = 0, i;

    for (i = 0; gcl_args[i]; i++)
        args[n++] = gcl_args[i];
    for (i = 0; extra[i]; i++)
        args[n++] = extra[i];
    args[n] = NULL;
    REQUIRE(emu_start(&e, exe, args) == 0);
    REQUIRE(ctl_open(&k, &e) == 0);
    REQUIRE(gcl_open(&c, &e, 0) == 0);
    test_errors(&c);
    test_home(&c);
    test_move(&c, &k);
    test_fast_stop(&c, &k);
    test_grip_nothing(&c);
    test_grip_part(&c, &k);
    test_window(&c, &k, &e);
    test_queries(&c, &k);
    test_sensor(&c, &k);
    test_autosend(&c, &k);
    test_bye(&c, &k);
    ctl_close(&k);
    CHECK_EQ(emu_stop(&e), 0);
}

/* ---- framing ---- */

static void part_framing(const char *exe)
{
    static const uint8_t loop_pkt[] = {0xAA, 0xAA, 0xAA, 0x06, 0x01,
                                       0x00, 0x41, 0x12, 0x34};
    char line[1100];
    struct emu e;
    struct ctl k;
    struct gcl c;

    REQUIRE(emu_start(&e, exe, gcl_args) == 0);
    REQUIRE(ctl_open(&k, &e) == 0);
    REQUIRE(gcl_open(&c, &e, 0) == 0);
    CMD_OK(&k, "time pause");

    /* Several lines in one segment: each answered, in order. */
    gcl_say(&c, "VERBOSE=1\nHOME()\nPOS?\n");
    EXPECT(&c, "VERBOSE=1");
    EXPECT(&c, "ACK HOME");
    EXPECT(&c, "POS=55.0");
    CMD_OK(&k, "time step 4000");
    EXPECT(&c, "FIN HOME");

    /* minWSG's way: one command, one recv(), one whole line. Time is
     * paused, so ACK and FIN cannot arrive together. */
    gcl_say(&c, "POS?\n");
    EXPECT_RECV(&c, "POS=110.0\n");
    gcl_say(&c, "MOVE(30,100)\n");
    EXPECT_RECV(&c, "ACK MOVE\n");
    CMD_OK(&k, "time step 2000");
    EXPECT_RECV(&c, "FIN MOVE\n");
    gcl_say(&c, "POS?\n");
    EXPECT_RECV(&c, "POS=30.0\n");
    gcl_say(&c, "GRIP()\n");
    EXPECT_RECV(&c, "ACK GRIP\n");
    CMD_OK(&k, "time step 2000");
    EXPECT_RECV(&c, "FIN GRIP\n");
    gcl_say(&c, "GRIPSTATE?\n");
    EXPECT_RECV(&c, "GRIPSTATE=4\n");
    gcl_say(&c, "RELEASE()\n");
    EXPECT_RECV(&c, "ACK RELEASE\n");
    CMD_OK(&k, "time step 2000");
    EXPECT_RECV(&c, "FIN RELEASE\n");
    gcl_say(&c, "MOVE(\n");
    EXPECT_RECV(&c, "ERR MOVE 15 E_CMD_FORMAT_ERROR\n");
    gcl_say(&c, "VERBOSE=0\n");
    EXPECT_RECV(&c, "VERBOSE=0\n");
    gcl_say(&c, "HOME()\n");
    EXPECT_RECV(&c, "ACK HOME\n");
    CMD_OK(&k, "time step 4000");
    EXPECT_RECV(&c, "FIN HOME\n");
    gcl_say(&c, "MOVE(60)\n");
    EXPECT_RECV(&c, "ACK MOVE\n");
    CMD_OK(&k, "time step 2000");
    EXPECT_RECV(&c, "FIN MOVE\n");
    gcl_say(&c, "POS?\n");
    EXPECT_RECV(&c, "POS=60.0\n");
    gcl_say(&c, "MOVE(500,5)\n"); /* slow: the FIN is far off */
    EXPECT_RECV(&c, "ACK MOVE\n");
    gcl_say(&c, "STOP()\n");
    EXPECT(&c, "ACK STOP");
    EXPECT(&c, "ERR MOVE 19");

    /* CR LF. */
    gcl_say(&c, "POS?\r\n");
    EXPECT(&c, "POS=60.0");
    gcl_say(&c, "VERBOSE?\r\nGRIPSTATE?\r\n");
    EXPECT(&c, "VERBOSE=0");
    EXPECT(&c, "GRIPSTATE=0");
    gcl_say(&c, "MOVE(70)\r\n");
    EXPECT(&c, "ACK MOVE");
    CMD_OK(&k, "time step 2000");
    EXPECT(&c, "FIN MOVE");

    /* The limit: 256 bytes without the newline (LF or CR LF) are a line,
     * 257 are too long: one ERR, and the next line is served. */
    memset(line, ' ', sizeof line);
    memcpy(line, "POS?", 4);
    memcpy(line + 256, "\n", 2);
    gcl_say(&c, line);
    EXPECT(&c, "POS=70.0");
    memcpy(line + 256, "\r\n", 3);
    gcl_say(&c, line);
    EXPECT(&c, "POS=70.0");
    line[256] = ' ';
    memcpy(line + 257, "\nPOS?\n", 7);
    gcl_say(&c, line);
    EXPECT(&c, "ERR ? 15");
    EXPECT(&c, "POS=70.0");
    /* Far too long, over several writes: still one ERR. */
    memset(line, 'X', 1000);
    line[1000] = '\0';
    gcl_say(&c, line);
    gcl_say(&c, line);
    gcl_say(&c, line);
    gcl_say(&c, "\nGRIPSTATE?\n");
    EXPECT(&c, "ERR ? 15");
    EXPECT(&c, "GRIPSTATE=0");

    /* Binary bytes: one ERR each line, then business as usual. */
    gcl_write(&c, "PO\0S?\n", 6);
    EXPECT(&c, "ERR ? 15");
    gcl_say(&c, "\x80\xff\xfe\n");
    EXPECT(&c, "ERR ? 15");
    gcl_say(&c, "\x1b[A\n");
    EXPECT(&c, "ERR ? 15");
    gcl_write(&c, loop_pkt, sizeof loop_pkt); /* a binary client's packet */
    gcl_say(&c, "\n");
    EXPECT(&c, "ERR ? 15");
    gcl_say(&c, "POS?\n");
    EXPECT(&c, "POS=70.0");

    /* Garbage. */
    gcl_say(&c, ")))\n=5\nPOS??\n(POS)\n");
    EXPECT(&c, "ERR ? 15");
    EXPECT(&c, "ERR ? 15");
    EXPECT(&c, "ERR POS 15");
    EXPECT(&c, "ERR ? 15");
    /* Empty lines are no command: no answer. */
    gcl_say(&c, "\n\r\n\nPOS?\n");
    EXPECT(&c, "POS=70.0");

    /* A command over several segments; nothing is answered early (a
     * reply to a piece would come before the ACK). */
    gcl_say(&c, "MO");
    emu_sleep_ms(20);
    gcl_say(&c, "VE(4");
    emu_sleep_ms(20);
    gcl_say(&c, "0,10");
    emu_sleep_ms(20);
    gcl_say(&c, "0)\n");
    EXPECT(&c, "ACK MOVE");
    CMD_OK(&k, "time step 2000");
    EXPECT(&c, "FIN MOVE");
    gcl_say(&c, "PO");
    emu_sleep_ms(20);
    gcl_say(&c, "S?\r");
    emu_sleep_ms(20);
    gcl_say(&c, "\n");
    EXPECT(&c, "POS=40.0");
    QUIET(&c);

    CMD_OK(&k, "time resume");
    gcl_bye(&c);
    ctl_close(&k);
    CHECK_EQ(emu_stop(&e), 0);
}

/* ---- the suite's rules ---- */

/* Replies of commands that answer one line each, sent in one write. */
static void test_one_answer(struct gcl *c)
{
    static const struct {
        const char *cmd, *want;
    } t[] = {
        {"POS?", "POS=110.0"},
        {"SYSFLAGS?", "SYSFLAGS=1"}, /* SF_REFERENCED */
        {"SPEED?", "SPEED=0.0"},
        {"FORCE?", "FORCE=0.0"},
        {"GRIPSTATE?", "GRIPSTATE=0"},
        {"VERBOSE?", "VERBOSE=0"},
        {"VERBOSE=0", "VERBOSE=0"},
        {"PWT?", "PWT=10.0"},
        {"PWT=5", "PWT=5.0"},
        {"CLT=5.5", "CLT=5.5"},
        {"TEMP?", "TEMP=25.0"},
        {"DEVTYPE?", "DEVTYPE=WSG50"},
        {"VERSION?", "VERSION=2.2.0"},
        {"SN?", "SN=1"},
        {"TAG?", "ERR TAG 1"}, /* no --tag */
        {"GRIPSTATS?", "GRIPSTATS=0,0,0"},
        {"TARE()", "ERR TARE 1"},     /* no force sensor */
        {"FDATA?", "ERR FDATA 2"},    /* E_NO_SENSOR */
        {"FDATA[0]?", "ERR FDATA 2"}, /* ditto */
        {"FSACK()", "ACK FSACK"},
        {"STOP()", "ACK STOP"},
        {"AUTOSEND(\"POS\", 0)", "ACK AUTOSEND"},
        {"RELEASE()", "ERR RELEASE 16"},
        {"FROB()", "ERR FROB 14"},
        {"MOVE(", "ERR MOVE 15"},
        {")))", "ERR ? 15"},
        {"MOVE(\"x\")", "ERR MOVE 24"},
    };
    char all[2048];
    size_t i, n = 0;

    for (i = 0; i < sizeof t / sizeof t[0]; i++)
        n += (size_t)snprintf(all + n, sizeof all - n, "%s\n", t[i].cmd);
    REQUIRE(n < sizeof all);
    gcl_say(c, all);
    for (i = 0; i < sizeof t / sizeof t[0]; i++)
        EXPECT(c, "%s", t[i].want);
    /* Motions: two lines each, or one ERR. */
    MOTION(c, "MOVE(30)", "MOVE");
    MOTION(c, "GRIP()", "GRIP");
    ASK(c, "GRIP()", "ERR GRIP 16");
    MOTION(c, "RELEASE()", "RELEASE");
    MOTION(c, "HOME()", "HOME");
    QUIET(c);
}

/* Bursts in one write: every line answered, none lost, none extra. */
static void test_burst(struct gcl *c)
{
    static char buf[12000];
    char got[64];
    size_t n = 0;
    int i, ok = 0;

    for (i = 0; i < 200; i++)
        n += (size_t)snprintf(buf + n, sizeof buf - n, "POS?\n");
    gcl_write(c, buf, n);
    for (i = 0; i < 200; i++)
        if (gcl_line(c, got, sizeof got, EMU_REPLY_MS) &&
            strcmp(got, "POS=110.0") == 0)
            ok++;
    CHECK_EQ(ok, 200);
    /* Longer than one read of the daemon's (4096 bytes), a line cut at
     * its edges: 1000 lines, two kinds, in order. */
    for (n = 0, i = 0; i < 1000; i++)
        n += (size_t)snprintf(buf + n, sizeof buf - n, "%s\n",
                              i % 2 ? "GRIPSTATE?" : "SPEED?");
    REQUIRE(n < sizeof buf);
    gcl_write(c, buf, n);
    for (ok = 0, i = 0; i < 1000; i++)
        if (gcl_line(c, got, sizeof got, EMU_REPLY_MS) &&
            strcmp(got, i % 2 ? "GRIPSTATE=0" : "SPEED=0.0") == 0)
            ok++;
    CHECK_EQ(ok, 1000);
    QUIET(c);
}

/* A close without BYE is FAST STOP; with BYE it is not. Returns the
 * longest delay seen from a close to FAST STOP, in ms. */
static double test_close(struct emu *e, struct ctl *k, struct gcl *c)
{
    struct gcl a;
    double t0, dt, worst = 0;

    REQUIRE(gcl_open(&a, e, 0) == 0);
    ASK(&a, "POS?", "POS=110.0");
    t0 = emu_now_ms();
    gcl_close(&a);
    CHECK(fast_stop_within(k, EMU_REPLY_MS));
    worst = emu_now_ms() - t0;
    printf("close without BYE: FAST STOP after %.0f ms\n", worst);
    ASK(c, "GRIPSTATE?", "GRIPSTATE=7");
    ASK(c, "MOVE(50)", "ERR MOVE 16");
    ASK(c, "FSACK()", "ACK FSACK");
    CHECK_EQ(state_flags(k) & WSG_SF_FAST_STOP, 0);

    /* Not a byte sent: no BYE either. */
    REQUIRE(gcl_open(&a, e, 0) == 0);
    t0 = emu_now_ms();
    gcl_close(&a);
    CHECK(fast_stop_within(k, EMU_REPLY_MS));
    dt = emu_now_ms() - t0;
    printf("silent connection: FAST STOP after %.0f ms\n", dt);
    worst = dt > worst ? dt : worst;
    ASK(c, "FSACK()", "ACK FSACK");
    CHECK_EQ(state_flags(k) & WSG_SF_FAST_STOP, 0);
    return worst;
}

static void part_rules(const char *exe)
{
    struct emu e;
    struct ctl k;
    struct gcl c, a;
    double worst;
    int window;

    REQUIRE(emu_start(&e, exe, gcl_args) == 0);
    REQUIRE(ctl_open(&k, &e) == 0);
    REQUIRE(gcl_open(&c, &e, 0) == 0);
    MOTION(&c, "HOME()", "HOME");
    test_one_answer(&c);
    test_burst(&c);
    worst = test_close(&e, &k, &c);

    /* "No FAST STOP" is watched for several times as long as one took to
     * show, never less than the quiet window (integ_disconnect's rule). */
    window = (int)(worst * 5);
    if (window < EMU_QUIET_MS * 2)
        window = EMU_QUIET_MS * 2;
    if (window > emu_ms(3000))
        window = emu_ms(3000);
    REQUIRE(gcl_open(&a, &e, 0) == 0);
    gcl_bye(&a);
    CHECK(!fast_stop_within(&k, window));
    /* ... also with a motion running at the BYE, time going on. */
    REQUIRE(gcl_open(&a, &e, 0) == 0);
    ASK(&a, "MOVE(10, 5)", "ACK MOVE");
    gcl_say(&a, "BYE()\n");
    EXPECT(&a, "ACK BYE");
    EXPECT(&a, "ERR MOVE 19");
    gcl_close(&a);
    CHECK(!fast_stop_within(&k, window));
    ASK(&c, "GRIPSTATE?", "GRIPSTATE=0");
    gcl_bye(&c);
    CHECK(!fast_stop_within(&k, window));
    ctl_close(&k);
    CHECK_EQ(emu_stop(&e), 0);
}

/* ---- a fleet ---- */

static void part_fleet(const char *exe)
{
    static const char *const args[] = {"--grippers",
                                       "2",
                                       "--tcp",
                                       "127.0.0.1:0",
                                       "--text-interface",
                                       "on",
                                       "--homing-direction",
                                       "negative",
                                       "--serial",
                                       "100",
                                       "--control",
                                       "127.0.0.1:0",
                                       NULL};
    struct emu e;
    struct ctl k;
    struct gcl g0, g1;

    REQUIRE(emu_start(&e, exe, args) == 0);
    REQUIRE(ctl_open(&k, &e) == 0);
    REQUIRE(gcl_open(&g0, &e, 0) == 0);
    REQUIRE(gcl_open(&g1, &e, 1) == 0);
    /* Both speak GCL, each its own gripper. */
    ASK(&g0, "SN?", "SN=100");
    ASK(&g1, "SN?", "SN=101");
    ASK(&g0, "VERBOSE=1", "VERBOSE=1");
    ASK(&g1, "VERBOSE?", "VERBOSE=0");
    MOTION(&g0, "HOME()", "HOME"); /* --homing-direction negative */
    ASK(&g0, "POS?", "POS=0.0");
    ASK(&g1, "POS?", "POS=55.0");
    ASK(&g1, "MOVE(30)", "ERR MOVE 3");
    MOTION(&g1, "HOME(1)", "HOME");
    ASK(&g1, "POS?", "POS=110.0");
    ASK(&g0, "POS?", "POS=0.0");

    /* A part in gripper 1 (the control channel's selection). */
    CHECK(strcmp(ctl_cmd(&k, "gripper 1"), "ok gripper 1 of 2") == 0);
    CMD_OK(&k, "part 40");
    MOTION(&g1, "GRIP(20)", "GRIP");
    ASK(&g1, "POS?", "POS=39.6");
    ASK(&g1, "GRIPSTATE?", "GRIPSTATE=4");
    ASK(&g0, "GRIPSTATE?", "GRIPSTATE=0");
    MOTION(&g0, "GRIP()", "GRIP");
    ASK(&g0, "POS?", "POS=0.0");

    /* A close without BYE: FAST STOP of its gripper only. */
    gcl_close(&g1);
    CHECK(fast_stop_within(&k, EMU_REPLY_MS));
    CHECK(strcmp(ctl_cmd(&k, "gripper 0"), "ok gripper 0 of 2") == 0);
    CHECK_EQ(state_flags(&k) & WSG_SF_FAST_STOP, 0);
    MOTION(&g0, "RELEASE(30)", "RELEASE");
    ASK(&g0, "POS?", "POS=30.0");
    REQUIRE(gcl_open(&g1, &e, 1) == 0);
    ASK(&g1, "MOVE(50)", "ERR MOVE 16");
    ASK(&g1, "FSACK()", "ACK FSACK");
    MOTION(&g1, "MOVE(50)", "MOVE");
    gcl_bye(&g1);
    gcl_bye(&g0);
    ctl_close(&k);
    CHECK_EQ(emu_stop(&e), 0);
}

/* ---- the communication log ---- */

static void part_log(const char *exe)
{
    static const char *const sent[] = {"ACK HOME", "FIN HOME", "ACK MOVE",
                                       "FIN MOVE", "POS=30.0", "ERR NOPE 15",
                                       "ERR ? 15", "ERR ? 15", "ACK BYE"};
    const char *tmp = getenv("TMPDIR");
    char dir[256], path[512], text[65536], big[300];
    const char *args[] = {
        "--tcp", "127.0.0.1:0", "--text-interface", "on", "--log", path, NULL};
    const char *p;
    struct emu e;
    struct gcl c;
    size_t nout = 0;
    int lines = 0, nevent = 0;

    snprintf(dir, sizeof dir, "%s/wsgemu-gcl-XXXXXX", tmp ? tmp : "/tmp");
    REQUIRE(mkdtemp(dir) != NULL);
    snprintf(path, sizeof path, "%s/comm.log", dir);
    REQUIRE(emu_start(&e, exe, args) == 0);
    REQUIRE(gcl_open(&c, &e, 0) == 0);
    MOTION(&c, "HOME()", "HOME");
    MOTION(&c, "MOVE(30,100)", "MOVE");
    ASK(&c, "POS?", "POS=30.0");
    ASK(&c, "NOPE(", "ERR NOPE 15");
    memset(big, 'x', sizeof big - 2);
    memcpy(big + sizeof big - 2, "\n", 2);
    gcl_say(&c, big);
    EXPECT(&c, "ERR ? 15");
    gcl_write(&c, "PO\x01S?\n", 6);
    EXPECT(&c, "ERR ? 15");
    gcl_bye(&c);
    CHECK_EQ(emu_stop(&e), 0);
    REQUIRE(emu_slurp(path, text, sizeof text) > 0);
    printf("log:\n%s", text);

    /* The lines in, as sent; the unreadable ones by what they were. */
    CHECK(strstr(text, " in HOME()\n") != NULL);
    CHECK(strstr(text, " in MOVE(30,100)\n") != NULL);
    CHECK(strstr(text, " in POS?\n") != NULL);
    CHECK(strstr(text, " in NOPE(\n") != NULL);
    CHECK(strstr(text, " in (line too long)\n") != NULL);
    CHECK(strstr(text, " in (binary bytes)\n") != NULL);
    CHECK(strstr(text, " in BYE()\n") != NULL);
    CHECK(strstr(text, " out FIN MOVE\n") != NULL);
    /* Every entry one line (wall clock, simulated time, peer), and the
     * replies one entry each, whole, in order: one line per send. */
    for (p = text; *p;) {
        const char *end = strchr(p, '\n'), *out;

        REQUIRE(end != NULL);
        CHECK(end - p > 20 && p[2] == ':' && p[5] == ':' && p[8] == '.');
        CHECK(strncmp(p + 12, " t=", 3) == 0);
        out = strstr(p, " tcp 127.0.0.1:");
        CHECK(out != NULL && out < end);
        out = strstr(p, " out ");
        if (out && out < end) {
            size_t len = (size_t)(end - out - 5);

            if (nout < sizeof sent / sizeof sent[0]) {
                if (len != strlen(sent[nout]) ||
                    memcmp(out + 5, sent[nout], len) != 0)
                    fprintf(stderr, "log reply %zu: \"%.*s\", not \"%s\"\n",
                            nout, (int)len, out + 5, sent[nout]);
                CHECK(len == strlen(sent[nout]) &&
                      memcmp(out + 5, sent[nout], len) == 0);
            }
            nout++;
        }
        out = strstr(p, " event ");
        if (out && out < end)
            nevent++;
        else
            lines++;
        p = end + 1;
    }
    CHECK_EQ(nout, sizeof sent / sizeof sent[0]);
    CHECK_EQ(lines, 7 + 9); /* 7 in, 9 out, besides the events */
    /* The connection's events: opened, and closed after its 07h. */
    CHECK_EQ(nevent, 2);
    CHECK(strstr(text, " event connected\n") != NULL);
    CHECK(strstr(text, " event closed (07h)\n") != NULL);
    unlink(path);
    rmdir(dir);
}

int main(int argc, char **argv)
{
    const char *exe = emu_exe(argc, argv);
    const char *part = argc > 2 ? argv[2] : "all";
    int all = strcmp(part, "all") == 0, ran = 0;

    if (all || strcmp(part, "commands") == 0) {
        part_commands(exe);
        ran++;
    }
    if (all || strcmp(part, "framing") == 0) {
        part_framing(exe);
        ran++;
    }
    if (all || strcmp(part, "rules") == 0) {
        part_rules(exe);
        ran++;
    }
    if (all || strcmp(part, "fleet") == 0) {
        part_fleet(exe);
        ran++;
    }
    if (all || strcmp(part, "log") == 0) {
        part_log(exe);
        ran++;
    }
    if (!ran) {
        fprintf(stderr, "integ_gcl: unknown part \"%s\"\n", part);
        return 2;
    }
    TEST_EXIT();
}
