/*
 * integ_script: scripts on the gripper (src/script), seen from outside. The
 * daemon runs the Lua scripts of tests/scripts (argv[3]); they call the
 * script API and answer registered IDs with what they got, and this
 * program compares that with what the command set and the control channel
 * show. The scripts assert nothing themselves: every verdict is here.
 * Simulated time is paused and stepped through the control channel
 * wherever a script waits or the fingers move, so that every number is
 * the same on every run, however loaded the machine.
 *
 * One program, one part per ctest (argv[2]; none: all of them):
 * - api: every function of the API (api.lua): cmd.*, mc.*, gripper.state,
 *   grasping.*, finger.* (generic fingers and --force-sensor on), bton,
 *   ntob and etob to the byte, the E_* globals against the schema, print
 *   and printf through "script output", no math.nan, socket.gettime() and
 *   socket.sleep in simulated time, the Lua 5.1 names, require beside the
 *   script, cmd.read and sleep inside pcall, a NaN in a motion refused
 *   with E_INVALID_PARAMETER, a normal end (D19 and D20 clear);
 * - public: public_style.lua, written as the published scripts are (a
 *   bare require "socket" and its global, globals from cmd.read, pcall,
 *   printf's %d), driven as their drivers do (ack, homing, B0h, B1h):
 *   answered, the grasping state IDLE while the script moves the fingers;
 *   its B2h reaches ntob(math.nan), which the gripper lacks: no answer,
 *   "Error occured", and the script goes on;
 * - ifaces: registered IDs answered over TCP, UDP and the serial port,
 *   unregistered ones E_CMD_UNKNOWN, packets the firmware refuses (too
 *   long, after 07h) never reaching the script; cmd.send answers the peer
 *   whose packet was read last (two TCP clients interleaved, and across
 *   interfaces), and nobody when that peer has gone; packets that come
 *   while the script sleeps are read in order, and one past the queue is
 *   E_OVERRUN; after "script stop" the IDs are E_CMD_UNKNOWN again;
 * - speed: speed mode from a script: mc.speed(-20) closes at 20 mm/s
 *   (43h/44h/40h; 41h stays IDLE), blocked by a part it pushes with the
 *   force limit (45h, mc.blocked()); mc.stop, FAST STOP, a host's Stop
 *   and the script's end stop it, a new mc.speed replaces it; a host's
 *   motion is refused meanwhile, and one of the host's is replaced by the
 *   script's (E_CMD_ABORTED); a movement outlives the script;
 * - lifecycle: D19 while running, through a power cycle; a runtime error
 *   ends the script with D20, "script status" failed with the message,
 *   the traceback in "script output"; a new run clears D20; a syntax
 *   error and a missing file are refused by "script run"; one script at a
 *   time;
 * - sandbox: os.execute, io, debug, loadlib, binary chunks, modules
 *   outside the script's directory all fail inside the script; a loop is
 *   preempted and every interface answers meanwhile; loops where the
 *   script cannot yield end in an error, and a loop around them does not
 *   hold the daemon; finalizers never run; the memory cap
 *   (--script-memory 2) ends a growing script with D20;
 * - lockstep: a script sleeping 10 ms in a loop has counted exactly 100
 *   after 1000 ms of steps, on every run, and socket.gettime() is the
 *   stepped time exactly;
 * - outside: a file outside the script directory that does not compile
 *   (a key run by path) fails with its name and line, and none of its
 *   text, in the run's answer, the status, the output and the startup
 *   message; inside the script directory Lua's message is whole;
 * - startup: --script registers its IDs before the ready line, a missing
 *   file is exit status 1, a syntax error leaves the daemon running with
 *   D20;
 * - hogs: work inside the library's C functions (hogs.lua: %b() over
 *   200 kB, a set of 100,000 characters, a literal pattern of 100,000
 *   bytes, a plain find of it, a backtracking gsub, cmd.send of 100^5
 *   references to one table, a fresh looping coroutine each time, a
 *   looping message handler, loops where nothing can yield (a
 *   __tostring, a load reader), library calls that work long without
 *   instructions (collectgarbage, tonumber, table.insert and
 *   remove, string.rep of nothing)) leaves every Loop (06h) answered within
 *   HOG_BOUND_MS while it runs, and SIGTERM ends the daemon at once.
 */
#define _GNU_SOURCE /* mkdtemp */

#include "check.h"
#include "emu.h"
#include "emu_ctl.h"
#include "wsg/axis.h"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <unistd.h>

/* The IDs api.lua answers. */
enum {
    ID_ECHO = 0xB0,
    ID_CMD = 0xB1,
    ID_SLEEP = 0xB2,
    ID_REGISTER = 0xB3,
    ID_SEND = 0xB4,
    ID_CONVERT = 0xB5,
    ID_STATUSES = 0xB6,
    ID_PRINT = 0xB7,
    ID_COMPAT = 0xB8,
    ID_GRIPPER = 0xB9,
    ID_FINGER = 0xBA,
    ID_CLOCK = 0xBB,
    ID_READINGS = 0xBC,
    ID_OP = 0xBD,
    ID_MODULES = 0xBE,
    ID_END = 0xBF
};

/* BDh's operations (api.lua's ops). */
enum {
    OP_SPEED = 1,
    OP_STOP,
    OP_MOVE,
    OP_HOMING,
    OP_FORCE,
    OP_PID,
    OP_GRASP_MOVE,
    OP_GRASP,
    OP_CLAMP,
    OP_STOP_CLAMPING,
    OP_RELEASE,
    OP_INTEGERS
};

/* BCh's fields (api.lua), in order. */
enum {
    R_POSITION,
    R_SPEED,
    R_BLOCKED,
    R_BUSY,
    R_AFORCE,
    R_FORCE,
    R_LIMIT,
    R_KP,
    R_KI,
    R_KD,
    R_GRASP_STATE,
    R_FLAGS
};

#define D19 WSG_SF_SCRIPT_RUNNING
#define D20 WSG_SF_SCRIPT_FAILURE

static const char *scripts; /* tests/scripts */

/* Whole answers are compared as strings, so that a failure shows both. */
#define CHECK_STR(a, b)                                                       \
    do {                                                                      \
        const char *got_ = (a), *want_ = (b);                                 \
        check_count++;                                                        \
        if (strcmp(got_, want_) != 0) {                                       \
            check_failures++;                                                 \
            fprintf(stderr,                                                   \
                    "%s:%d: CHECK_STR failed: %s\n  got:  \"%s\"\n"           \
                    "  want: \"%s\"\n",                                       \
                    __FILE__, __LINE__, #a, got_, want_);                     \
        }                                                                     \
    } while (0)

#define CHECK_HAS(a, part)                                                    \
    do {                                                                      \
        const char *got_ = (a), *part_ = (part);                              \
        check_count++;                                                        \
        if (!strstr(got_, part_)) {                                           \
            check_failures++;                                                 \
            fprintf(stderr,                                                   \
                    "%s:%d: CHECK_HAS failed: %s\n  got:  \"%s\"\n"           \
                    "  lacks: \"%s\"\n",                                      \
                    __FILE__, __LINE__, #a, got_, part_);                     \
        }                                                                     \
    } while (0)

/* ---- the script's answers ---- */

/* The text of the script's answer to id (wire.lua): E_CMD_PENDING before
 * each piece but the last, which comes with E_SUCCESS; the pieces joined
 * into text. Waits up to timeout_ms for each piece. 0, or -1 (said). */
static int take(struct emu_client *c, uint8_t id, char *text, size_t cap,
                int timeout_ms)
{
    struct wsg_client_frame f;
    size_t used = 0;

    text[0] = '\0';
    for (;;) {
        size_t n;

        if (emu_recv_id(c, id, &f, timeout_ms) != 1) {
            fprintf(stderr, "no answer to %02Xh within %d ms\n", id,
                    timeout_ms);
            return -1;
        }
        if (f.status != WSG_E_SUCCESS && f.status != WSG_E_CMD_PENDING) {
            fprintf(stderr, "%02Xh answered status %u\n", id, f.status);
            return -1;
        }
        n = EMU_NPARAMS(&f);
        if (n > cap - 1 - used)
            n = cap - 1 - used;
        memcpy(text + used, EMU_PARAMS(&f), n);
        used += n;
        text[used] = '\0';
        if (f.status == WSG_E_SUCCESS)
            return 0;
    }
}

/* Send id with payload p and take the answer. */
static int ask(struct emu_client *c, uint8_t id, const void *p, size_t n,
               char *text, size_t cap)
{
    if (emu_send(c, id, p, n) != 0)
        return -1;
    return take(c, id, text, cap, EMU_REPLY_MS);
}

/* Field i of a '|'-joined answer (empty when there are fewer). */
static const char *field(const char *text, int i)
{
    static char out[512]; /* the test is single-threaded */
    const char *p = text, *end;
    size_t n;

    for (; i > 0 && p; i--) {
        p = strchr(p, '|');
        if (p)
            p++;
    }
    if (!p)
        return "";
    end = strchr(p, '|');
    n = end ? (size_t)(end - p) : strlen(p);
    if (n >= sizeof out)
        n = sizeof out - 1;
    memcpy(out, p, n);
    out[n] = '\0';
    return out;
}

/* A number field; NaN when it is not one. wire.lua writes floats with 17
 * digits, so strtod gives back the very double the script had. */
static double field_num(const char *text, int i)
{
    const char *s = field(text, i);
    char *end;
    double v = strtod(s, &end);

    return end != s && *end == '\0' ? v : NAN;
}

/* ---- the daemon ---- */

static void script_file(char *buf, size_t cap, const char *name)
{
    snprintf(buf, cap, "%s/%s", scripts, name);
}

/* "script run" of a file of tests/scripts (or a path with a slash). */
static const char *run_script(struct ctl *k, const char *name)
{
    char line[600], path[512];

    if (strchr(name, '/'))
        snprintf(path, sizeof path, "%s", name);
    else
        script_file(path, sizeof path, name);
    snprintf(line, sizeof line, "script run %s", path);
    return ctl_cmd(k, line);
}

#define RUN_OK(k, name)                                                       \
    do {                                                                      \
        const char *ans_ = run_script((k), (name));                           \
        if (!ctl_is_ok(ans_))                                                 \
            fprintf(stderr, "script run %s -> %s\n", (name), ans_);           \
        REQUIRE(ctl_is_ok(ans_));                                             \
    } while (0)

/* "script status", the JSON after "ok ". */
static const char *script_status(struct ctl *k)
{
    const char *ans = ctl_cmd(k, "script status");

    return strncmp(ans, "ok ", 3) == 0 ? ans + 3 : "";
}

static long long ctl_time(struct ctl *k)
{
    return ctl_time_us(ctl_cmd(k, "time"));
}

static uint32_t flags_of(struct emu_client *c)
{
    uint32_t fl = 0;

    CHECK(emu_get_flags(c, &fl) == 0);
    return fl;
}

static double float_of(struct emu_client *c, uint8_t id)
{
    float v = NAN;

    CHECK(emu_get_float(c, id, &v) == 0);
    return v;
}

/* The simulated time us as socket.gettime() gives it. */
static double seconds(long long us)
{
    return (double)us / 1e6;
}

/* ---- api.lua's calls ---- */

/* BDh: operation op with floats v[0..n-1] (and a byte after them for
 * mc.move's flags); the answer's text into t. */
static void op(struct emu_client *c, uint8_t opcode, const float *v, size_t n,
               int tail, char *t, size_t cap)
{
    uint8_t p[32];
    size_t len = 1, i;

    p[0] = opcode;
    for (i = 0; i < n; i++, len += 4)
        wsg_put_f32(p + len, v[i]);
    if (tail >= 0)
        p[len++] = (uint8_t)tail;
    REQUIRE(ask(c, ID_OP, p, len, t, cap) == 0);
}

/* The op's result: "1|STATUS" for the motion calls. */
static void op_status(struct emu_client *c, uint8_t opcode, const float *v,
                      size_t n, int tail, int want)
{
    char t[256], w[32];

    op(c, opcode, v, n, tail, t, sizeof t);
    snprintf(w, sizeof w, "1|%d", want);
    CHECK_STR(t, w);
}

static void readings(struct emu_client *c, char *t, size_t cap)
{
    REQUIRE(ask(c, ID_READINGS, NULL, 0, t, cap) == 0);
}

/* mc.position() and mc.speed() against 43h and 44h (float32 on the wire),
 * gripper.state() against 40h, mc.busy(); time is paused, so they are the
 * same moment. */
static void expect_readings(struct emu_client *c, const char *busy)
{
    char t[512];
    double w = float_of(c, WSG_CMD_GET_WIDTH);
    double v = float_of(c, WSG_CMD_GET_SPEED);
    uint32_t fl = flags_of(c);

    readings(c, t, sizeof t);
    CHECK_NEAR(field_num(t, R_POSITION), w, 1e-4);
    CHECK_NEAR(field_num(t, R_SPEED), v, 1e-4);
    CHECK_STR(field(t, R_BUSY), busy);
    CHECK_EQ((long long)field_num(t, R_FLAGS), fl);
}

/* ---- part api ---- */

static void api_cmd(struct emu_client *c, struct ctl *k)
{
    static const uint8_t echo[4] = {1, 2, 3, 250};
    static const uint8_t sent[] = {7, 1, 0, 'A', 'B',  1,   2,
                                   3, 4, 0, 0,   0xC0, 0x3F};
    uint8_t reg[2] = {1, 0xC5}, unreg[2] = {2, 0xC5}, dyn[3] = {9, 9, 9};
    uint8_t ten = 10, home = WSG_HOME_POSITIVE, one = 1, two = 2;
    struct wsg_client_frame f;
    char t[1024];
    long long t0;

    /* cmd.online, cmd.available, cmd.interface */
    REQUIRE(ask(c, ID_CMD, NULL, 0, t, sizeof t) == 0);
    CHECK_STR(t, "true|0|TCP/IP");

    /* cmd.read's table, sent back as it is by cmd.send */
    CHECK_EQ(emu_request(c, ID_ECHO, echo, 4, &f, EMU_REPLY_MS),
             WSG_E_SUCCESS);
    CHECK_EQ(EMU_NPARAMS(&f), 4);
    CHECK(memcmp(EMU_PARAMS(&f), echo, 4) == 0);
    CHECK_EQ(emu_request(c, ID_ECHO, NULL, 0, &f, EMU_REPLY_MS),
             WSG_E_SUCCESS);
    CHECK_EQ(f.len, 2);

    /* cmd.register and cmd.unregister of an ID of nobody's */
    CHECK_EQ(emu_request(c, 0xC5, dyn, 3, NULL, EMU_REPLY_MS),
             WSG_E_CMD_UNKNOWN);
    REQUIRE(ask(c, ID_REGISTER, reg, 2, t, sizeof t) == 0);
    CHECK_STR(t, "true|true");
    REQUIRE(ask(c, 0xC5, dyn, 3, t, sizeof t) == 0);
    CHECK_STR(t, "dyn|3");
    CHECK_HAS(script_status(k),
              "\"registered\":[160,161,176,177,178,179,180,181,182,"
              "183,184,185,186,187,188,189,190,191,197]");
    REQUIRE(ask(c, ID_REGISTER, unreg, 2, t, sizeof t) == 0);
    CHECK_STR(t, "true");
    CHECK_EQ(emu_request(c, 0xC5, dyn, 3, NULL, EMU_REPLY_MS),
             WSG_E_CMD_UNKNOWN);

    /* A command of the firmware is not the script's to take... */
    reg[1] = unreg[1] = WSG_CMD_HOMING;
    REQUIRE(ask(c, ID_REGISTER, reg, 2, t, sizeof t) == 0);
    CHECK_STR(t, "false|cmd.register: 20h is a command of the firmware");
    REQUIRE(ask(c, ID_REGISTER, unreg, 2, t, sizeof t) == 0);
    CHECK_STR(t, "false");
    /* ...and stays the firmware's: a homing, pending, then done. */
    CHECK_EQ(emu_request(c, WSG_CMD_HOMING, &home, 1, NULL, EMU_REPLY_MS),
             WSG_E_CMD_PENDING);
    CMD_OK(k, "time step 3000");
    CHECK_EQ(emu_recv_id(c, WSG_CMD_HOMING, &f, EMU_REPLY_MS), 1);
    CHECK_EQ(f.status, WSG_E_SUCCESS);
    CHECK(flags_of(c) & WSG_SF_REFERENCED);

    /* cmd.send: a number in 0..255 a byte, booleans 0 and 1, a string its
     * bytes, tables their elements (nested), ntob's four bytes, empty
     * table and string nothing; then what each bad argument raised. */
    CHECK_EQ(emu_request(c, ID_SEND, NULL, 0, &f, EMU_REPLY_MS),
             WSG_E_SUCCESS);
    CHECK_EQ(EMU_NPARAMS(&f), sizeof sent);
    CHECK(memcmp(EMU_PARAMS(&f), sent, sizeof sent) == 0);
    REQUIRE(take(c, ID_SEND, t, sizeof t, EMU_REPLY_MS) == 0);
    CHECK_STR(t, "cmd.send: a number must be a whole byte in 0..255 (ntob(x) "
                 "sends a float)|"
                 "cmd.send: a number must be a whole byte in 0..255 (ntob(x) "
                 "sends a float)|"
                 "cmd.send: a number must be a whole byte in 0..255 (ntob(x) "
                 "sends a float)|"
                 "cmd.send: tables nested more than 5 deep|"
                 "cmd.send: cannot send a function|"
                 "cmd.send: cannot send a nil|"
                 "cmd.send: payload longer than 65535 bytes");

    /* Packets that come while the script sleeps (sleep inside pcall) wait
     * in cmd.read's queue: cmd.available() counts them when it wakes, and
     * they are read in the order they came. Nothing is answered before
     * the time has been stepped. */
    t0 = ctl_time(k);
    REQUIRE(emu_send(c, ID_SLEEP, &ten, 1) == 0);
    REQUIRE(emu_send(c, ID_ECHO, &one, 1) == 0);
    REQUIRE(emu_send(c, ID_ECHO, &two, 1) == 0);
    REQUIRE(emu_sync(c, EMU_REPLY_MS) == 0);
    CHECK_EQ(emu_recv_id(c, ID_SLEEP, &f, EMU_QUIET_MS), 0);
    CMD_OK(k, "time step 10");
    REQUIRE(take(c, ID_SLEEP, t, sizeof t, EMU_REPLY_MS) == 0);
    CHECK_STR(field(t, 0), "true");
    CHECK_STR(field(t, 1), "2");
    CHECK_EQ(field_num(t, 2), seconds(t0 + 10000));
    CHECK_EQ(emu_recv(c, &f, EMU_REPLY_MS), 1);
    CHECK(f.id == ID_ECHO && f.len == 3 && EMU_PARAMS(&f)[0] == 1);
    CHECK_EQ(emu_recv(c, &f, EMU_REPLY_MS), 1);
    CHECK(f.id == ID_ECHO && f.len == 3 && EMU_PARAMS(&f)[0] == 2);

    /* socket.sleep(s): the same wait, in seconds */
    t0 = ctl_time(k);
    REQUIRE(emu_send(c, 0xA1, &ten, 1) == 0);
    REQUIRE(emu_sync(c, EMU_REPLY_MS) == 0);
    CMD_OK(k, "time step 10");
    REQUIRE(take(c, 0xA1, t, sizeof t, EMU_REPLY_MS) == 0);
    CHECK_EQ(field_num(t, 0), seconds(t0 + 10000));
}

/* The status codes, as the schema names them. */
static const struct {
    const char *name;
    int value;
} statuses[] = {
#define STATUS_(v, name) {#name, v},
    WSG_SCHEMA_STATUSES(STATUS_)
#undef STATUS_
};

static void api_values(struct emu_client *c, struct ctl *k)
{
    static const uint8_t bytes[] = {0x0E, 0,    0x34, 0x12, 0, 0,
                                    0xC0, 0x3F, 0,    0,    0, 0xC0};
    struct wsg_client_frame f;
    uint8_t x[4];
    char t[2048], want[128], json[512];
    const char *out;
    uint32_t nan_bits;
    unsigned long end;
    size_t i, n;

    /* bton, ntob, etob to the byte: 3.25 there and back, E_CMD_UNKNOWN,
     * 0x1234, 1.5, -2 and a NaN (exponent all ones, mantissa not 0) */
    wsg_put_f32(x, 3.25f);
    CHECK_EQ(emu_request(c, ID_CONVERT, x, 4, &f, EMU_REPLY_MS),
             WSG_E_SUCCESS);
    REQUIRE(EMU_NPARAMS(&f) == 4 + sizeof bytes + 4);
    CHECK(memcmp(EMU_PARAMS(&f), x, 4) == 0);
    CHECK(memcmp(EMU_PARAMS(&f) + 4, bytes, sizeof bytes) == 0);
    nan_bits = wsg_get_u32(EMU_PARAMS(&f) + 4 + sizeof bytes);
    CHECK_EQ(nan_bits & 0x7F800000u, 0x7F800000u);
    CHECK(nan_bits & 0x007FFFFFu);
    REQUIRE(take(c, ID_CONVERT, t, sizeof t, EMU_REPLY_MS) == 0);
    CHECK_STR(t, "3.25|false|bton: element 4 is not a byte|false|bad "
                 "argument #1 to 'etob' (not a status code)|true|number|true");

    /* E_*: every status code of the schema, with its value, and no other */
    REQUIRE(ask(c, ID_STATUSES, NULL, 0, t, sizeof t) == 0);
    for (i = 0, n = 1; t[i]; i++)
        n += t[i] == '|';
    CHECK_EQ(n, sizeof statuses / sizeof statuses[0]);
    for (i = 0; i < sizeof statuses / sizeof statuses[0]; i++) {
        char entry[64], framed[2100];

        snprintf(entry, sizeof entry, "|%s=%d|", statuses[i].name,
                 statuses[i].value);
        snprintf(framed, sizeof framed, "|%s|", t);
        CHECK_HAS(framed, entry);
    }

    /* print and printf, as "script output" has them from where it was */
    out = ctl_cmd(k, "script output");
    REQUIRE(strncmp(out, "ok ", 3) == 0);
    end = (unsigned long)ctl_json_num(out, "end");
    REQUIRE(ask(c, ID_PRINT, NULL, 0, t, sizeof t) == 0);
    CHECK_STR(t, "7");
    snprintf(want, sizeof want, "script output %lu", end);
    out = ctl_cmd(k, want);
    snprintf(json, sizeof json,
             "{\"from\":%lu,\"lost\":0,\"text\":\"line\\t1\\t2.5\\tnil\\ttrue"
             "\\n2|  3.1|s|ff\\n-2%%\\n\",",
             end);
    CHECK_HAS(out, json);

    /* The names of Lua 5.1 and 5.2, and load of text */
    REQUIRE(ask(c, ID_COMPAT, NULL, 0, t, sizeof t) == 0);
    CHECK_STR(t, "6|3|3|1024|2|15|255|240|2147483648|1|4294967295|15|true|"
                 "4294967295|1|3|8|0.5|10|true|true|42");

    /* gripper.state() is 40h, with D19 set and D20 clear */
    REQUIRE(ask(c, ID_GRIPPER, NULL, 0, t, sizeof t) == 0);
    CHECK_EQ(atoll(t), flags_of(c));
    CHECK_EQ(atoll(t) & (D19 | D20), D19);

    /* socket.gettime() is the simulated time, exactly */
    {
        long long now = ctl_time(k);

        REQUIRE(ask(c, ID_CLOCK, NULL, 0, t, sizeof t) == 0);
        CHECK_EQ(field_num(t, 0), seconds(now));
    }

    /* require: wire from beside the script, socket from the host */
    REQUIRE(ask(c, ID_MODULES, NULL, 0, t, sizeof t) == 0);
    CHECK_STR(t, "true|wire|function|true");
}

static void api_motion(struct emu_client *c, struct ctl *k)
{
    char t[512], want[512];
    double lim;

    /* At rest, referenced at 110 mm by the firmware's homing. */
    readings(c, t, sizeof t);
    CHECK_NEAR(field_num(t, R_POSITION), 110.0, 1e-4);
    CHECK_STR(field(t, R_SPEED), "0");
    CHECK_STR(field(t, R_BLOCKED), "false");
    CHECK_STR(field(t, R_BUSY), "false");
    CHECK_STR(field(t, R_AFORCE), "0");
    CHECK_STR(field(t, R_FORCE), "0");
    lim = float_of(c, WSG_CMD_GET_FORCE_LIMIT);
    CHECK_NEAR(field_num(t, R_LIMIT), lim, 1e-4);
    CHECK_STR(field(t, R_KP), "1");
    CHECK_STR(field(t, R_KI), "0");
    CHECK_STR(field(t, R_KD), "0");
    CHECK_STR(field(t, R_GRASP_STATE), "0");
    expect_readings(c, "false");

    /* mc.homing(false): to the negative end; mc.homing(true): back */
    op_status(c, OP_HOMING, NULL, 0, 2, WSG_E_SUCCESS);
    CHECK(flags_of(c) & WSG_SF_MOVING);
    CMD_OK(k, "time step 100");
    expect_readings(c, "true");
    CMD_OK(k, "time step 3000");
    CHECK_NEAR(float_of(c, WSG_CMD_GET_WIDTH), 0.0, 1e-3);
    op_status(c, OP_HOMING, NULL, 0, 1, WSG_E_SUCCESS);
    CMD_OK(k, "time step 3000");
    CHECK_NEAR(float_of(c, WSG_CMD_GET_WIDTH), 110.0, 1e-3);
    expect_readings(c, "false");

    /* Integer arguments past what their parameter holds are errors (a
     * 64-bit direction no longer homes by its low bits); a byte 20h
     * refuses is refused as 20h refuses it. */
    op(c, OP_INTEGERS, NULL, 0, -1, t, sizeof t);
    snprintf(want, sizeof want,
             "8|bad argument #1 to 'homing' (not a byte (0..255))|"
             "bad argument #1 to 'homing' (not a byte (0..255))|"
             "bad argument #3 to 'move' (not a byte (0..255))|"
             "bad argument #3 to 'move' (not a byte (0..255))|"
             "bad argument #1 to 'register' (not a byte (0..255))|"
             "bad argument #1 to 'type' (a finger is 0 or 1)|"
             "bad argument #1 to 'etob' (not a status code)|%d",
             WSG_E_INVALID_PARAMETER);
    CHECK_STR(t, want);
    CHECK(!(flags_of(c) & WSG_SF_MOVING));

    /* mc.move, absolute then relative (flag 1). The motion controller's
     * own motion: a driver polling 41h sees IDLE while the script moves
     * the fingers and after (only grasping commands drive that state). */
    op_status(c, OP_MOVE, (const float[]){30, 50}, 2, 0, WSG_E_SUCCESS);
    CMD_OK(k, "time step 100");
    CHECK(flags_of(c) & WSG_SF_MOVING);
    CHECK_EQ(emu_get_grasp_state(c), WSG_GS_IDLE);
    expect_readings(c, "true");
    CMD_OK(k, "time step 3000");
    CHECK_NEAR(float_of(c, WSG_CMD_GET_WIDTH), 30.0, 1e-3);
    CHECK_EQ(emu_get_grasp_state(c), WSG_GS_IDLE);
    op_status(c, OP_MOVE, (const float[]){-10, 50}, 2, 1, WSG_E_SUCCESS);
    CMD_OK(k, "time step 3000");
    CHECK_NEAR(float_of(c, WSG_CMD_GET_WIDTH), 20.0, 1e-3);
    expect_readings(c, "false");

    /* mc.stop in the middle of a movement */
    op_status(c, OP_MOVE, (const float[]){60, 10}, 2, 0, WSG_E_SUCCESS);
    CMD_OK(k, "time step 100");
    op(c, OP_STOP, NULL, 0, -1, t, sizeof t);
    CHECK_STR(t, "0");
    CHECK_EQ(flags_of(c) & (WSG_SF_MOVING | WSG_SF_AXIS_STOPPED),
             WSG_SF_AXIS_STOPPED);
    readings(c, t, sizeof t);
    CHECK_STR(field(t, R_SPEED), "0");
    expect_readings(c, "false");

    /* A NaN in a motion is the status E_INVALID_PARAMETER, as for a host:
     * the script goes on, nothing moves, a NaN force is not set. */
    lim = float_of(c, WSG_CMD_GET_FORCE_LIMIT);
    op_status(c, OP_SPEED, (const float[]){NAN}, 1, -1,
              WSG_E_INVALID_PARAMETER);
    op_status(c, OP_MOVE, (const float[]){NAN, 50}, 2, 0,
              WSG_E_INVALID_PARAMETER);
    op_status(c, OP_MOVE, (const float[]){50, NAN}, 2, 0,
              WSG_E_INVALID_PARAMETER);
    op_status(c, OP_GRASP_MOVE, (const float[]){NAN, 50}, 2, -1,
              WSG_E_INVALID_PARAMETER);
    op_status(c, OP_GRASP, (const float[]){40, 50, NAN}, 3, -1,
              WSG_E_INVALID_PARAMETER);
    /* (A good force is set first, as grasping.grasp's is: the limit.) */
    op_status(c, OP_CLAMP, (const float[]){NAN, (float)lim}, 2, -1,
              WSG_E_INVALID_PARAMETER);
    op_status(c, OP_CLAMP, (const float[]){5, NAN}, 2, -1,
              WSG_E_INVALID_PARAMETER);
    op_status(c, OP_RELEASE, (const float[]){60, NAN}, 2, -1,
              WSG_E_INVALID_PARAMETER);
    CHECK_EQ(flags_of(c) & WSG_SF_MOVING, 0);
    CHECK_NEAR(float_of(c, WSG_CMD_GET_FORCE_LIMIT), lim, 1e-6);
    expect_readings(c, "false");

    /* mc.force(limit): the limit 33h reads; mc.pid(kp, ki, kd) */
    op(c, OP_FORCE, (const float[]){33}, 1, -1, t, sizeof t);
    CHECK_STR(t, "0");
    CHECK_NEAR(float_of(c, WSG_CMD_GET_FORCE_LIMIT), 33.0, 1e-4);
    op(c, OP_PID, (const float[]){2, 0.5f, 0.25f}, 3, -1, t, sizeof t);
    CHECK_STR(t, "3|2|0.5|0.25");
    readings(c, t, sizeof t);
    CHECK_STR(field(t, R_LIMIT), "33");
    CHECK_STR(field(t, R_KP), "2");
    CHECK_STR(field(t, R_KI), "0.5");
    CHECK_STR(field(t, R_KD), "0.25");

    /* grasping.move, then grasping.grasp of a part at 40 mm with 25 N:
     * holding, pressing with the limit it set */
    op_status(c, OP_GRASP_MOVE, (const float[]){70, 100}, 2, -1,
              WSG_E_SUCCESS);
    /* The grasping state machine's prepositioning, as 21h's. */
    CHECK_EQ(emu_get_grasp_state(c), WSG_GS_POSITIONING);
    CMD_OK(k, "time step 3000");
    CHECK_NEAR(float_of(c, WSG_CMD_GET_WIDTH), 70.0, 1e-3);
    CHECK_EQ(emu_get_grasp_state(c), WSG_GS_IDLE);
    CMD_OK(k, "part 40");
    op_status(c, OP_GRASP, (const float[]){40, 50, 25}, 3, -1, WSG_E_SUCCESS);
    readings(c, t, sizeof t);
    CHECK_STR(field(t, R_GRASP_STATE), "1"); /* GRASPING */
    CMD_OK(k, "time step 3000");
    CHECK_EQ(emu_get_grasp_state(c), WSG_GS_HOLDING);
    CHECK_NEAR(float_of(c, WSG_CMD_GET_FORCE_LIMIT), 25.0, 1e-4);
    CHECK_NEAR(float_of(c, WSG_CMD_GET_FORCE), 25.0, 1e-3);
    readings(c, t, sizeof t);
    CHECK_STR(field(t, R_GRASP_STATE), "4"); /* HOLDING */
    CHECK_STR(field(t, R_BLOCKED), "true");
    CHECK_NEAR(field_num(t, R_AFORCE), 25.0, 1e-3);
    CHECK_NEAR(field_num(t, R_FORCE), 25.0, 1e-3);
    CHECK_STR(field(t, R_LIMIT), "25");

    /* grasping.release: releasing at once, then idle at 60 mm */
    op_status(c, OP_RELEASE, (const float[]){60, 50}, 2, -1, WSG_E_SUCCESS);
    readings(c, t, sizeof t);
    CHECK_STR(field(t, R_GRASP_STATE), "5"); /* RELEASING */
    CMD_OK(k, "time step 3000");
    CHECK_NEAR(float_of(c, WSG_CMD_GET_WIDTH), 60.0, 1e-3);
    CHECK_EQ(emu_get_grasp_state(c), WSG_GS_IDLE);

    /* grasping.clamp: from just over the part, 5 mm of travel with 35 N;
     * grasping.stop_clamping lets go */
    op_status(c, OP_GRASP_MOVE, (const float[]){41, 20}, 2, -1, WSG_E_SUCCESS);
    CMD_OK(k, "time step 3000");
    op_status(c, OP_CLAMP, (const float[]){5, 35}, 2, -1, WSG_E_SUCCESS);
    readings(c, t, sizeof t);
    CHECK_STR(field(t, R_GRASP_STATE), "1");
    CMD_OK(k, "time step 3000");
    CHECK_EQ(emu_get_grasp_state(c), WSG_GS_HOLDING);
    CHECK_NEAR(float_of(c, WSG_CMD_GET_FORCE), 35.0, 1e-3);
    CHECK_NEAR(float_of(c, WSG_CMD_GET_FORCE_LIMIT), 35.0, 1e-4);
    {
        double w = float_of(c, WSG_CMD_GET_WIDTH);

        CHECK(w > 39.0 && w < 40.0);
    }
    op(c, OP_STOP_CLAMPING, NULL, 0, -1, t, sizeof t);
    CHECK_STR(t, "0");
    readings(c, t, sizeof t);
    CHECK_STR(field(t, R_GRASP_STATE), "0");
    CHECK_STR(field(t, R_BUSY), "false");
    CHECK_EQ(emu_get_grasp_state(c), WSG_GS_IDLE);
    CMD_OK(k, "part none");
    CMD_OK(k, "time step 1000");
    expect_readings(c, "false");
}

/* finger.*: fmf with --force-sensor on (finger.data the force it grips
 * with), generic without. */
static void api_finger(struct emu_client *c, int fmf)
{
    static const char *const fmt =
        "%s|%s|%s|%s|2|true|false|false|true|"
        "true:nil|0:nil|1:nil|"
        "nil:finger 1: no SPI set up (finger.interface)|"
        "false|";
    const char *type = fmf ? "fmf" : "generic";
    char t[1024], want[1024];

    /* At rest: an FMF finger measures 0 N, a generic one nothing. Either
     * carries a UART (a byte written is taken) and an SPI once set up. */
    REQUIRE(ask(c, ID_FINGER, NULL, 0, t, sizeof t) == 0);
    snprintf(want, sizeof want, fmt, type, type, fmf ? "0" : "nil",
             fmf ? "0" : "nil");
    /* The error, last, after where it was raised (api.lua:LINE:); the
     * rest as a whole. */
    CHECK_HAS(field(t, 14), ": bad argument #1 to 'type' (a finger is 0 "
                            "or 1)");
    if (strlen(t) > strlen(want))
        t[strlen(want)] = '\0';
    CHECK_STR(t, want);
}

/* An FMF finger's data while holding is the gripping force (45h). */
static void api_finger_holding(struct emu_client *c, struct ctl *k)
{
    uint8_t home = WSG_HOME_POSITIVE, g[8];
    struct wsg_client_frame f;
    char t[1024];
    double force;

    CHECK_EQ(emu_request(c, WSG_CMD_HOMING, &home, 1, NULL, EMU_REPLY_MS),
             WSG_E_CMD_PENDING);
    CMD_OK(k, "time step 3000");
    CHECK_EQ(emu_recv_id(c, WSG_CMD_HOMING, &f, EMU_REPLY_MS), 1);
    CMD_OK(k, "part 40");
    CHECK_EQ(emu_request(c, WSG_CMD_GRASP, g, emu_grasp_payload(g, 40, 50),
                         NULL, EMU_REPLY_MS),
             WSG_E_CMD_PENDING);
    CMD_OK(k, "time step 3000");
    CHECK_EQ(emu_recv_id(c, WSG_CMD_GRASP, &f, EMU_REPLY_MS), 1);
    CHECK_EQ(f.status, WSG_E_SUCCESS);
    force = float_of(c, WSG_CMD_GET_FORCE);
    CHECK(force > 1.0);
    REQUIRE(ask(c, ID_FINGER, NULL, 0, t, sizeof t) == 0);
    CHECK_NEAR(field_num(t, 2), force, 1e-3);
    CHECK_NEAR(field_num(t, 3), force, 1e-3);
}

static void part_api(const char *exe)
{
    static const char *const args[] = {"--tcp", "127.0.0.1:0", "--control",
                                       "127.0.0.1:0", NULL};
    static const char *const fmf_args[] = {
        "--tcp",          "127.0.0.1:0", "--control", "127.0.0.1:0",
        "--force-sensor", "on",          NULL};
    struct emu e;
    struct emu_client c;
    struct ctl k;
    char t[256];

    REQUIRE(emu_start(&e, exe, args) == 0);
    REQUIRE(ctl_open(&k, &e) == 0);
    REQUIRE(emu_open(&c, &e, &emu_tcp) == 0);
    CMD_OK(&k, "time pause");
    /* Before any script, and D19/D20 clear. */
    CHECK_EQ(emu_request(&c, ID_ECHO, NULL, 0, NULL, EMU_REPLY_MS),
             WSG_E_CMD_UNKNOWN);
    CHECK_EQ(flags_of(&c) & (D19 | D20), 0);
    RUN_OK(&k, "api.lua");
    CHECK_EQ(flags_of(&c) & (D19 | D20), D19);

    api_cmd(&c, &k);
    api_values(&c, &k);
    api_motion(&c, &k);
    api_finger(&c, 0);

    /* The script's own end: D19 clear, D20 too, its IDs the firmware's */
    REQUIRE(ask(&c, ID_END, NULL, 0, t, sizeof t) == 0);
    CHECK_STR(t, "bye");
    CHECK_EQ(flags_of(&c) & (D19 | D20), 0);
    CHECK_HAS(script_status(&k), "{\"running\":false,\"failed\":false,"
                                 "\"error\":null,");
    CHECK_EQ(emu_request(&c, ID_ECHO, NULL, 0, NULL, EMU_REPLY_MS),
             WSG_E_CMD_UNKNOWN);
    CHECK_EQ(c.link.bad, 0);
    emu_close(&c);
    ctl_close(&k);
    CHECK_EQ(emu_stop(&e), 0);

    /* Force measurement fingers. */
    REQUIRE(emu_start(&e, exe, fmf_args) == 0);
    REQUIRE(ctl_open(&k, &e) == 0);
    REQUIRE(emu_open(&c, &e, &emu_tcp) == 0);
    CMD_OK(&k, "time pause");
    RUN_OK(&k, "api.lua");
    api_finger(&c, 1);
    api_finger_holding(&c, &k);
    emu_close(&c);
    ctl_close(&k);
    CHECK_EQ(emu_stop(&e), 0);
}

/* ---- part ifaces ---- */

/* Every packet of client c parsed up to now (emu_sync), and what it got
 * per ID since the counts were taken. */
static unsigned seen_since(struct emu_client *c, const unsigned *before,
                           uint8_t id)
{
    REQUIRE(emu_sync(c, EMU_REPLY_MS) == 0);
    return c->link.seen[id] - before[id];
}

/* Two TCP clients, each with a sleep and an echo, interleaved: every
 * answer goes to the client whose packet the script read last. */
static void ifaces_two_clients(struct emu_client *a, struct emu_client *b,
                               struct ctl *k)
{
    uint8_t ten = 10, pa = 0xA1, pb = 0xB1;
    unsigned seen_a[256], seen_b[256];
    struct wsg_client_frame f;
    char t[256];
    long long t0 = ctl_time(k);

    REQUIRE(emu_sync(a, EMU_REPLY_MS) == 0);
    REQUIRE(emu_sync(b, EMU_REPLY_MS) == 0);
    memcpy(seen_a, a->link.seen, sizeof seen_a);
    memcpy(seen_b, b->link.seen, sizeof seen_b);
    /* Each sync makes sure the daemon has the packet before the next. */
    REQUIRE(emu_send(a, ID_SLEEP, &ten, 1) == 0);
    REQUIRE(emu_sync(a, EMU_REPLY_MS) == 0);
    REQUIRE(emu_send(b, ID_SLEEP, &ten, 1) == 0);
    REQUIRE(emu_sync(b, EMU_REPLY_MS) == 0);
    REQUIRE(emu_send(a, ID_ECHO, &pa, 1) == 0);
    REQUIRE(emu_sync(a, EMU_REPLY_MS) == 0);
    REQUIRE(emu_send(b, ID_ECHO, &pb, 1) == 0);
    REQUIRE(emu_sync(b, EMU_REPLY_MS) == 0);

    /* A's sleep ends first: its answer to A, with three packets queued. */
    CMD_OK(k, "time step 10");
    REQUIRE(take(a, ID_SLEEP, t, sizeof t, EMU_REPLY_MS) == 0);
    CHECK_STR(field(t, 1), "3");
    CHECK_EQ(field_num(t, 2), seconds(t0 + 10000));
    /* Then B's sleep, then both echoes, each to its sender. */
    CMD_OK(k, "time step 10");
    REQUIRE(take(b, ID_SLEEP, t, sizeof t, EMU_REPLY_MS) == 0);
    CHECK_STR(field(t, 1), "2");
    CHECK_EQ(field_num(t, 2), seconds(t0 + 20000));
    CHECK_EQ(emu_recv_id(a, ID_ECHO, &f, EMU_REPLY_MS), 1);
    CHECK(f.len == 3 && EMU_PARAMS(&f)[0] == pa);
    CHECK_EQ(emu_recv_id(b, ID_ECHO, &f, EMU_REPLY_MS), 1);
    CHECK(f.len == 3 && EMU_PARAMS(&f)[0] == pb);
    /* ...and nothing went to the other one. */
    CHECK_EQ(seen_since(a, seen_a, ID_SLEEP), 1);
    CHECK_EQ(seen_since(a, seen_a, ID_ECHO), 1);
    CHECK_EQ(seen_since(b, seen_b, ID_SLEEP), 1);
    CHECK_EQ(seen_since(b, seen_b, ID_ECHO), 1);
    emu_drop_kept(a);
    emu_drop_kept(b);
}

/* An answer for a client that has gone goes nowhere: cmd.send returns
 * false, and the client that talked last (b) gets nothing. */
static void ifaces_gone(struct emu *e, struct emu_client *b, struct ctl *k)
{
    uint8_t ten = 10;
    unsigned seen[256];
    struct emu_client a;
    char t[64];

    REQUIRE(emu_open(&a, e, &emu_tcp) == 0);
    REQUIRE(emu_send(&a, ID_SLEEP, &ten, 1) == 0);
    REQUIRE(emu_sync(&a, EMU_REPLY_MS) == 0);
    /* Announced (07h): no FAST STOP for the close. */
    CHECK_EQ(emu_request(&a, WSG_CMD_DISCONNECT, NULL, 0, NULL, EMU_REPLY_MS),
             WSG_E_SUCCESS);
    emu_close(&a);
    /* The close is in the daemon before b's Loop: the kernel has it when
     * close returns. b is the last to have sent anything. */
    REQUIRE(emu_sync(b, EMU_REPLY_MS) == 0);
    memcpy(seen, b->link.seen, sizeof seen);
    CMD_OK(k, "time step 10");
    CHECK_EQ(seen_since(b, seen, ID_SLEEP), 0);
    REQUIRE(ask(b, 0xA0, NULL, 0, t, sizeof t) == 0);
    CHECK_STR(t, "false");
    CHECK_EQ(flags_of(b) & WSG_SF_FAST_STOP, 0);
}

/* The same across interfaces: the serial port's sleep, then TCP's and
 * UDP's echoes queued behind it; each answer on its own interface. */
static void ifaces_across(struct emu_client *c, struct ctl *k)
{
    uint8_t ten = 10, p[3] = {0x11, 0x22, 0x33};
    unsigned seen[3][256];
    struct wsg_client_frame f;
    char t[256];
    int i;

    for (i = 0; i < 3; i++) {
        REQUIRE(emu_sync(&c[i], EMU_REPLY_MS) == 0);
        memcpy(seen[i], c[i].link.seen, sizeof seen[i]);
    }
    REQUIRE(emu_send(&c[2], ID_SLEEP, &ten, 1) == 0);
    REQUIRE(emu_sync(&c[2], EMU_REPLY_MS) == 0);
    for (i = 0; i < 3; i++) {
        REQUIRE(emu_send(&c[i], ID_ECHO, &p[i], 1) == 0);
        REQUIRE(emu_sync(&c[i], EMU_REPLY_MS) == 0);
    }
    CMD_OK(k, "time step 10");
    REQUIRE(take(&c[2], ID_SLEEP, t, sizeof t, EMU_REPLY_MS) == 0);
    CHECK_STR(field(t, 1), "3");
    for (i = 0; i < 3; i++) {
        CHECK_EQ(emu_recv_id(&c[i], ID_ECHO, &f, EMU_REPLY_MS), 1);
        CHECK(f.len == 3 && EMU_PARAMS(&f)[0] == p[i]);
        CHECK_EQ(seen_since(&c[i], seen[i], ID_ECHO), 1);
        CHECK_EQ(seen_since(&c[i], seen[i], ID_SLEEP), i == 2);
        emu_drop_kept(&c[i]);
    }
}

/* Packets that come during a sleep are read in order; one more than the
 * queue holds (64) is answered E_OVERRUN at once. */
static void ifaces_queue(struct emu_client *c, struct ctl *k)
{
    enum { N = 65 };
    uint8_t buf[N * 16], ten = 10;
    struct wsg_client_frame f;
    char t[256];
    size_t used;
    int i;

    used = wsg_frame_encode(buf, sizeof buf, ID_SLEEP, &ten, 1);
    for (i = 1; i <= N; i++) {
        uint8_t b = (uint8_t)i;

        used +=
            wsg_frame_encode(buf + used, sizeof buf - used, ID_ECHO, &b, 1);
    }
    /* In one write: the daemon reads them in one go. */
    REQUIRE(emu_send_raw(c, buf, used) == 0);
    REQUIRE(emu_sync(c, EMU_REPLY_MS) == 0);
    CHECK_EQ(emu_recv(c, &f, EMU_REPLY_MS), 1);
    CHECK(f.id == ID_ECHO && f.status == WSG_E_OVERRUN && f.len == 2);
    CMD_OK(k, "time step 10");
    REQUIRE(take(c, ID_SLEEP, t, sizeof t, EMU_REPLY_MS) == 0);
    CHECK_STR(field(t, 1), "64");
    for (i = 1; i < N; i++) {
        if (emu_recv(c, &f, EMU_REPLY_MS) != 1) {
            CHECK(!"an echo is missing");
            break;
        }
        CHECK(f.id == ID_ECHO && f.status == WSG_E_SUCCESS && f.len == 3);
        CHECK_EQ(EMU_PARAMS(&f)[0], i);
    }
}

static void part_ifaces(const char *exe)
{
    static const struct emu_transport *const tps[3] = {&emu_tcp, &emu_udp,
                                                       &emu_pty};
    static const char *const names[3] = {"TCP/IP", "UDP/IP", "Serial"};
    static const char *const extra[] = {"--control", "127.0.0.1:0", NULL};
    struct emu e;
    struct emu_client c[3], b;
    struct wsg_client_frame f;
    struct ctl k;
    char t[256], want[64];
    int i;

    REQUIRE(emu_start_multi(&e, exe, tps, 3, extra) == 0);
    REQUIRE(ctl_open(&k, &e) == 0);
    for (i = 0; i < 3; i++)
        REQUIRE(emu_open(&c[i], &e, tps[i]) == 0);
    REQUIRE(emu_open(&b, &e, &emu_tcp) == 0);
    CMD_OK(&k, "time pause");
    RUN_OK(&k, "api.lua");

    /* Each interface: the script answers its registered IDs there, names
     * the interface, and an ID nobody registered is E_CMD_UNKNOWN. */
    for (i = 0; i < 3; i++) {
        uint8_t p[3] = {(uint8_t)i, 0x55, 0xAA};

        CHECK_EQ(emu_request(&c[i], ID_ECHO, p, 3, &f, EMU_REPLY_MS),
                 WSG_E_SUCCESS);
        CHECK(EMU_NPARAMS(&f) == 3 && memcmp(EMU_PARAMS(&f), p, 3) == 0);
        REQUIRE(ask(&c[i], ID_CMD, NULL, 0, t, sizeof t) == 0);
        snprintf(want, sizeof want, "true|0|%s", names[i]);
        CHECK_STR(t, want);
        CHECK_EQ(emu_request(&c[i], 0xC0, p, 3, NULL, EMU_REPLY_MS),
                 WSG_E_CMD_UNKNOWN);
    }

    /* What the firmware refuses never reaches the script: a packet
     * longer than any command (E_CMD_FORMAT_ERROR), and one after the
     * Disconnect Announcement (E_ACCESS_DENIED). */
    {
        static uint8_t big[300];
        struct emu_client d;

        CHECK_EQ(
            emu_request(&c[0], ID_ECHO, big, sizeof big, NULL, EMU_REPLY_MS),
            WSG_E_CMD_FORMAT_ERROR);
        REQUIRE(emu_open(&d, &e, &emu_tcp) == 0);
        CHECK_EQ(
            emu_request(&d, WSG_CMD_DISCONNECT, NULL, 0, NULL, EMU_REPLY_MS),
            WSG_E_SUCCESS);
        CHECK_EQ(emu_request(&d, ID_ECHO, NULL, 0, NULL, EMU_REPLY_MS),
                 WSG_E_ACCESS_DENIED);
        emu_close(&d);
        REQUIRE(ask(&c[0], ID_CMD, NULL, 0, t, sizeof t) == 0);
        CHECK_STR(t, "true|0|TCP/IP");
    }

    ifaces_two_clients(&c[0], &b, &k);
    ifaces_gone(&e, &b, &k);
    ifaces_across(c, &k);
    ifaces_queue(&c[0], &k);

    /* Stopped: the IDs are the firmware's again, unknown on every
     * interface. */
    CHECK(strcmp(ctl_cmd(&k, "script stop"), "ok script stopped") == 0);
    for (i = 0; i < 3; i++) {
        CHECK_EQ(emu_request(&c[i], ID_ECHO, NULL, 0, NULL, EMU_REPLY_MS),
                 WSG_E_CMD_UNKNOWN);
        CHECK_EQ(emu_request(&c[i], ID_CMD, NULL, 0, NULL, EMU_REPLY_MS),
                 WSG_E_CMD_UNKNOWN);
        CHECK_EQ(c[i].link.bad, 0);
    }
    CHECK_EQ(flags_of(&c[0]) & (D19 | D20), 0);
    for (i = 0; i < 3; i++)
        emu_close(&c[i]);
    emu_close(&b);
    ctl_close(&k);
    CHECK_EQ(emu_stop(&e), 0);
}

/* ---- part speed ---- */

/* Speed mode (mc.speed(v)) as api.lua drives it, time paused. */
static void part_speed(const char *exe)
{
    static const char *const args[] = {"--tcp", "127.0.0.1:0", "--control",
                                       "127.0.0.1:0", NULL};
    static const uint8_t ack[3] = {'a', 'c', 'k'};
    const uint32_t blocked = WSG_SF_BLOCKED_MINUS | WSG_SF_BLOCKED_PLUS;
    struct emu e;
    struct emu_client c;
    struct ctl k;
    char t[512];
    double w;

    REQUIRE(emu_start(&e, exe, args) == 0);
    REQUIRE(ctl_open(&k, &e) == 0);
    REQUIRE(emu_open(&c, &e, &emu_tcp) == 0);
    CMD_OK(&k, "time pause");
    RUN_OK(&k, "api.lua");

    /* Not before homing, as any motion. */
    op_status(&c, OP_SPEED, (const float[]){-20}, 1, -1,
              WSG_E_NOT_INITIALIZED);
    op_status(&c, OP_HOMING, NULL, 0, 1, WSG_E_SUCCESS);
    CMD_OK(&k, "time step 3000");
    CHECK_NEAR(float_of(&c, WSG_CMD_GET_WIDTH), 110.0, 1e-3);
    op(&c, OP_FORCE, (const float[]){30}, 1, -1, t, sizeof t);

    /* Closing at 20 mm/s towards a part at 40 mm: moving, a speed of -20
     * from the first step on (the maximum acceleration); the grasping
     * state stays IDLE: speed mode is the motion controller's, not the
     * grasping state machine's. */
    CMD_OK(&k, "part 40");
    op_status(&c, OP_SPEED, (const float[]){-20}, 1, -1, WSG_E_SUCCESS);
    CHECK(flags_of(&c) & WSG_SF_MOVING);
    CHECK_EQ(emu_get_grasp_state(&c), WSG_GS_IDLE);
    /* Started, but only the steps move the fingers. */
    readings(&c, t, sizeof t);
    CHECK_STR(field(t, R_BUSY), "true");
    CHECK_STR(field(t, R_SPEED), "0");
    CMD_OK(&k, "time step 500");
    CHECK_NEAR(float_of(&c, WSG_CMD_GET_SPEED), -20.0, 1e-3);
    w = float_of(&c, WSG_CMD_GET_WIDTH);
    CHECK(w > 99.9 && w < 100.1);
    CHECK_EQ(flags_of(&c) & (WSG_SF_MOVING | blocked), WSG_SF_MOVING);
    expect_readings(&c, "true");
    readings(&c, t, sizeof t);
    CHECK_STR(field(t, R_SPEED), "-20");
    CHECK_STR(field(t, R_BLOCKED), "false");

    /* At the part, 3.5 s later: blocked, pushing with the force limit,
     * still in speed mode. */
    CMD_OK(&k, "time step 4000");
    readings(&c, t, sizeof t);
    CHECK_STR(field(t, R_BLOCKED), "true");
    CHECK_STR(field(t, R_BUSY), "true");
    CHECK_STR(field(t, R_SPEED), "0");
    CHECK_NEAR(field_num(t, R_AFORCE), 30.0, 1e-3);
    CHECK_NEAR(float_of(&c, WSG_CMD_GET_FORCE), 30.0, 1e-3);
    CHECK_EQ(flags_of(&c) & (WSG_SF_MOVING | blocked), WSG_SF_BLOCKED_MINUS);
    w = float_of(&c, WSG_CMD_GET_WIDTH);
    CHECK(w > 39.0 && w < 40.0);
    /* A new limit is the push at once (the next step). */
    op(&c, OP_FORCE, (const float[]){25}, 1, -1, t, sizeof t);
    CMD_OK(&k, "time step 100");
    CHECK_NEAR(float_of(&c, WSG_CMD_GET_FORCE), 25.0, 1e-3);

    /* mc.stop ends it: stopped, idle, nothing pushing. */
    op(&c, OP_STOP, NULL, 0, -1, t, sizeof t);
    readings(&c, t, sizeof t);
    CHECK_STR(field(t, R_BUSY), "false");
    CHECK_STR(field(t, R_BLOCKED), "false");
    CHECK_EQ(flags_of(&c) & (WSG_SF_MOVING | WSG_SF_AXIS_STOPPED),
             WSG_SF_AXIS_STOPPED);
    CHECK_EQ(emu_get_grasp_state(&c), WSG_GS_IDLE);
    CMD_OK(&k, "time step 100");
    CHECK_NEAR(float_of(&c, WSG_CMD_GET_FORCE), 0.0, 1e-3);

    /* A new mc.speed replaces the running one, no stop between. */
    op_status(&c, OP_SPEED, (const float[]){20}, 1, -1, WSG_E_SUCCESS);
    CMD_OK(&k, "time step 500");
    CHECK_NEAR(float_of(&c, WSG_CMD_GET_SPEED), 20.0, 1e-3);
    w = float_of(&c, WSG_CMD_GET_WIDTH);
    op_status(&c, OP_SPEED, (const float[]){-10}, 1, -1, WSG_E_SUCCESS);
    CMD_OK(&k, "time step 200");
    CHECK_NEAR(float_of(&c, WSG_CMD_GET_SPEED), -10.0, 1e-3);
    CHECK(float_of(&c, WSG_CMD_GET_WIDTH) < w);
    expect_readings(&c, "true");

    /* FAST STOP ends it; speed mode is refused until it is acknowledged. */
    CHECK_EQ(emu_request(&c, WSG_CMD_FAST_STOP, NULL, 0, NULL, EMU_REPLY_MS),
             WSG_E_SUCCESS);
    readings(&c, t, sizeof t);
    CHECK_STR(field(t, R_BUSY), "false");
    CHECK_STR(field(t, R_SPEED), "0");
    CHECK_EQ(flags_of(&c) & (WSG_SF_MOVING | WSG_SF_FAST_STOP),
             WSG_SF_FAST_STOP);
    op_status(&c, OP_SPEED, (const float[]){-20}, 1, -1, WSG_E_ACCESS_DENIED);
    CHECK_EQ(
        emu_request(&c, WSG_CMD_ACK_FAST_STOP, ack, 3, NULL, EMU_REPLY_MS),
        WSG_E_SUCCESS);
    op_status(&c, OP_SPEED, (const float[]){-20}, 1, -1, WSG_E_SUCCESS);
    CMD_OK(&k, "time step 200");
    CHECK_NEAR(float_of(&c, WSG_CMD_GET_SPEED), -20.0, 1e-3);

    /* A host's motion is refused while the script's runs; its Stop (22h)
     * stops speed mode. */
    {
        uint8_t mv[16];
        size_t n = emu_move_payload(mv, 0, 80.0f, 50.0f);
        struct wsg_client_frame f;

        CHECK_EQ(
            emu_request(&c, WSG_CMD_PREPOSITION, mv, n, NULL, EMU_REPLY_MS),
            WSG_E_ALREADY_RUNNING);
        CHECK_EQ(emu_request(&c, WSG_CMD_STOP, NULL, 0, NULL, EMU_REPLY_MS),
                 WSG_E_SUCCESS);
        readings(&c, t, sizeof t);
        CHECK_STR(field(t, R_BUSY), "false");
        CHECK_EQ(flags_of(&c) & WSG_SF_MOVING, 0);

        /* A script's motion replaces a host's, whose final result is
         * E_CMD_ABORTED. */
        CHECK_EQ(
            emu_request(&c, WSG_CMD_PREPOSITION, mv, n, NULL, EMU_REPLY_MS),
            WSG_E_CMD_PENDING);
        CMD_OK(&k, "time step 100");
        op_status(&c, OP_SPEED, (const float[]){-20}, 1, -1, WSG_E_SUCCESS);
        CHECK_EQ(emu_recv_id(&c, WSG_CMD_PREPOSITION, &f, EMU_REPLY_MS), 1);
        CHECK_EQ(f.status, WSG_E_CMD_ABORTED);
        CMD_OK(&k, "time step 100");
        CHECK_NEAR(float_of(&c, WSG_CMD_GET_SPEED), -20.0, 1e-3);
    }

    /* The script's end stops speed mode: nothing drives it any more. */
    CHECK(strcmp(ctl_cmd(&k, "script stop"), "ok script stopped") == 0);
    CHECK_EQ(flags_of(&c) & WSG_SF_MOVING, 0);
    CMD_OK(&k, "time step 100");
    CHECK_NEAR(float_of(&c, WSG_CMD_GET_SPEED), 0.0, 1e-6);
    CMD_OK(&k, "part none");

    /* ...but a movement it started runs to its end. */
    RUN_OK(&k, "api.lua");
    op_status(&c, OP_MOVE, (const float[]){90, 50}, 2, 0, WSG_E_SUCCESS);
    CMD_OK(&k, "time step 100");
    CHECK(strcmp(ctl_cmd(&k, "script stop"), "ok script stopped") == 0);
    CHECK(flags_of(&c) & WSG_SF_MOVING);
    CMD_OK(&k, "time step 3000");
    CHECK_NEAR(float_of(&c, WSG_CMD_GET_WIDTH), 90.0, 1e-3);
    emu_close(&c);
    ctl_close(&k);
    CHECK_EQ(emu_stop(&e), 0);
}

/* ---- part lifecycle ---- */

/* "script output" from byte 0: the text, JSON-escaped as it comes. */
static const char *script_output(struct ctl *k, unsigned long from)
{
    char line[64];

    snprintf(line, sizeof line, "script output %lu", from);
    return ctl_cmd(k, line);
}

static void part_lifecycle(const char *exe)
{
    static const char *const args[] = {"--tcp", "127.0.0.1:0", "--control",
                                       "127.0.0.1:0", NULL};
    struct emu e;
    struct emu_client c;
    struct ctl k;
    uint8_t ok = 0, fail = 1;
    char st[2048], want[640];
    const char *ans;
    unsigned long end;
    unsigned seen;

    REQUIRE(emu_start(&e, exe, args) == 0);
    REQUIRE(ctl_open(&k, &e) == 0);
    REQUIRE(emu_open(&c, &e, &emu_tcp) == 0);

    /* Running: D19, not D20; the status says so. */
    RUN_OK(&k, "fail.lua");
    CHECK_EQ(flags_of(&c) & (D19 | D20), D19);
    snprintf(st, sizeof st, "%s", script_status(&k));
    CHECK_HAS(st, "{\"running\":true,\"failed\":false,\"error\":null,");
    CHECK_HAS(st, "\"state\":\"reading\",\"registered\":[176],");
    CHECK_EQ(emu_request(&c, ID_ECHO, &ok, 1, NULL, EMU_REPLY_MS),
             WSG_E_SUCCESS);
    /* A power cycle leaves the script alone. */
    CMD_OK(&k, "reset");
    CHECK_EQ(flags_of(&c) & (D19 | D20), D19);
    CHECK_EQ(emu_request(&c, ID_ECHO, &ok, 1, NULL, EMU_REPLY_MS),
             WSG_E_SUCCESS);
    /* One script at a time. */
    ans = run_script(&k, "fail.lua");
    CHECK_HAS(ans, "error script: a script is running");

    /* A runtime error: no answer, the script ended with D20, its message
     * in the status, its traceback in the output, its IDs unknown. */
    end = (unsigned long)ctl_json_num(script_output(&k, 0), "end");
    seen = c.link.seen[ID_ECHO];
    REQUIRE(emu_send(&c, ID_ECHO, &fail, 1) == 0);
    REQUIRE(emu_sync(&c, EMU_REPLY_MS) == 0);
    CHECK_EQ(c.link.seen[ID_ECHO], seen);
    CHECK_EQ(flags_of(&c) & (D19 | D20), D20);
    snprintf(st, sizeof st, "%s", script_status(&k));
    CHECK_HAS(st, "{\"running\":false,\"failed\":true,\"error\":\"");
    CHECK_HAS(st, "fail.lua:");
    CHECK_HAS(st, ": boom: asked to fail\"");
    CHECK_HAS(st, "\"state\":\"stopped\",\"registered\":[],");
    ans = script_output(&k, end);
    CHECK_HAS(ans, "\"text\":\"error: ");
    CHECK_HAS(ans, ": boom: asked to fail\\nstack traceback:");
    /* Both functions named; the words around the names are Lua's and
     * change between its releases. */
    CHECK_HAS(ans, "'explode'");
    CHECK_HAS(ans, "'middle'");
    CHECK_EQ(emu_request(&c, ID_ECHO, &ok, 1, NULL, EMU_REPLY_MS),
             WSG_E_CMD_UNKNOWN);

    /* A new run clears D20 and the error. */
    RUN_OK(&k, "fail.lua");
    CHECK_EQ(flags_of(&c) & (D19 | D20), D19);
    CHECK_HAS(script_status(&k), "{\"running\":true,\"failed\":false,"
                                 "\"error\":null,");
    CHECK_EQ(emu_request(&c, ID_ECHO, &ok, 1, NULL, EMU_REPLY_MS),
             WSG_E_SUCCESS);
    CHECK(strcmp(ctl_cmd(&k, "script stop"), "ok script stopped") == 0);
    CHECK_EQ(flags_of(&c) & (D19 | D20), 0);
    CHECK(strcmp(ctl_cmd(&k, "script stop"), "ok script not running") == 0);

    /* A syntax error: refused with where it is, D20 set, nothing runs. */
    end = (unsigned long)ctl_json_num(script_output(&k, 0), "end");
    ans = run_script(&k, "syntax.lua");
    CHECK_HAS(ans, "error script: ");
    CHECK_HAS(ans, "syntax.lua:4: ");
    CHECK_EQ(flags_of(&c) & (D19 | D20), D20);
    snprintf(st, sizeof st, "%s", script_status(&k));
    CHECK_HAS(st, "{\"running\":false,\"failed\":true,\"error\":\"");
    CHECK_HAS(st, "syntax.lua:4: ");
    CHECK_HAS(script_output(&k, end), "\"text\":\"error: ");
    CHECK_EQ(emu_request(&c, ID_ECHO, &ok, 1, NULL, EMU_REPLY_MS),
             WSG_E_CMD_UNKNOWN);

    /* A file that is not there: refused, why said. */
    ans = run_script(&k, "no-such-script.lua");
    snprintf(want, sizeof want,
             "error script: %s/no-such-script.lua: No "
             "such file or directory",
             scripts);
    CHECK_STR(ans, want);
    /* Still there after all that: a run that works. */
    RUN_OK(&k, "fail.lua");
    CHECK_EQ(flags_of(&c) & (D19 | D20), D19);
    CHECK_EQ(c.link.bad, 0);
    emu_close(&c);
    ctl_close(&k);
    CHECK_EQ(emu_stop(&e), 0);
}

/* ---- part sandbox ---- */

/* The sandbox's directory: DIR/user/ holds copies of sandbox.lua and
 * wire.lua (and later binmod.lua, a precompiled chunk), a link to
 * DIR/outside.lua, a module just outside the script's directory, a link
 * to the directory DIR/outdir and a directory of its own, sub. Removed at
 * exit. */
static char sandbox_dir[128];

static void sandbox_remove(void)
{
    static const char *const files[] = {
        "user/sandbox.lua", "user/wire.lua", "user/binmod.lua",
        "user/linked.lua",  "user/linkdir",  "user/sub/real.lua",
        "outside.lua",      "outdir/mod.lua"};
    static const char *const dirs[] = {"user/sub", "user", "outdir"};
    char path[256];
    size_t i;

    if (!sandbox_dir[0])
        return;
    for (i = 0; i < sizeof files / sizeof files[0]; i++) {
        snprintf(path, sizeof path, "%s/%s", sandbox_dir, files[i]);
        unlink(path);
    }
    for (i = 0; i < sizeof dirs / sizeof dirs[0]; i++) {
        snprintf(path, sizeof path, "%s/%s", sandbox_dir, dirs[i]);
        rmdir(path);
    }
    rmdir(sandbox_dir);
}

static int write_file(const char *path, const void *data, size_t len)
{
    FILE *f = fopen(path, "wb");
    int ok;

    if (!f)
        return -1;
    ok = fwrite(data, 1, len, f) == len;
    return fclose(f) == 0 && ok ? 0 : -1;
}

static int copy_script(const char *name)
{
    char from[512], to[256], buf[16384];
    FILE *f;
    size_t n;

    script_file(from, sizeof from, name);
    snprintf(to, sizeof to, "%s/user/%s", sandbox_dir, name);
    f = fopen(from, "rb");
    if (!f)
        return -1;
    n = fread(buf, 1, sizeof buf, f);
    fclose(f);
    return n == sizeof buf ? -1 : write_file(to, buf, n);
}

static void sandbox_setup(void)
{
    static const char outside[] = "return 'outside'\n";
    static const char sub[] = "return 'sub'\n";
    char path[256], link[256];

    snprintf(sandbox_dir, sizeof sandbox_dir, "/tmp/wsgemu-script-XXXXXX");
    REQUIRE(mkdtemp(sandbox_dir) != NULL);
    atexit(sandbox_remove);
    snprintf(path, sizeof path, "%s/user", sandbox_dir);
    REQUIRE(mkdir(path, 0700) == 0);
    REQUIRE(copy_script("sandbox.lua") == 0);
    REQUIRE(copy_script("wire.lua") == 0);
    snprintf(path, sizeof path, "%s/outside.lua", sandbox_dir);
    REQUIRE(write_file(path, outside, sizeof outside - 1) == 0);
    /* A link beside the script to that module: require does not follow
     * it (nor the host a link that replaced a script it checked). */
    snprintf(link, sizeof link, "%s/user/linked.lua", sandbox_dir);
    REQUIRE(symlink(path, link) == 0);
    /* A link beside the script to a directory outside with a module in
     * it: require follows no link in the middle of a module's path
     * either. A directory of its own is a module's path as before. */
    snprintf(path, sizeof path, "%s/outdir", sandbox_dir);
    REQUIRE(mkdir(path, 0700) == 0);
    snprintf(link, sizeof link, "%s/user/linkdir", sandbox_dir);
    REQUIRE(symlink(path, link) == 0);
    snprintf(path, sizeof path, "%s/outdir/mod.lua", sandbox_dir);
    REQUIRE(write_file(path, outside, sizeof outside - 1) == 0);
    snprintf(path, sizeof path, "%s/user/sub", sandbox_dir);
    REQUIRE(mkdir(path, 0700) == 0);
    snprintf(path, sizeof path, "%s/user/sub/real.lua", sandbox_dir);
    REQUIRE(write_file(path, sub, sizeof sub - 1) == 0);
}

/* What the script cannot reach or load. */
static void sandbox_closed(struct emu_client *c)
{
    struct wsg_client_frame f;
    char t[2048], path[256];
    const char *msg;

    REQUIRE(ask(c, 0xB0, NULL, 0, t, sizeof t) == 0);
    CHECK_STR(t, "nil|error:attempt to call a nil value|nil|nil|nil|nil|"
                 "error:module 'io' not found:|nil|"
                 "error:module 'debug' not found:|nil|nil|nil|nil|"
                 "nil:attempt to load a binary chunk (mode is 't')|"
                 "nil:attempt to load a binary chunk (mode is 't')|"
                 "nil:attempt to load a binary chunk (mode is 't')|"
                 "nil:attempt to load a binary chunk (mode is 't')|"
                 "error:module '../outside' not found:|");

    /* A precompiled chunk, as the script's string.dump made it, beside
     * the script: require must not load it. Nor a module outside its
     * directory, by a package.path of the script's. */
    CHECK_EQ(emu_request(c, 0xB2, NULL, 0, &f, EMU_REPLY_MS), WSG_E_SUCCESS);
    REQUIRE(EMU_NPARAMS(&f) > 4 && memcmp(EMU_PARAMS(&f), "\033Lua", 4) == 0);
    snprintf(path, sizeof path, "%s/user/binmod.lua", sandbox_dir);
    REQUIRE(write_file(path, EMU_PARAMS(&f), EMU_NPARAMS(&f)) == 0);
    REQUIRE(ask(c, 0xB1, sandbox_dir, strlen(sandbox_dir), t, sizeof t) == 0);
    msg = field(t, 0);
    CHECK_HAS(msg, "error:module 'outside' not found:");
    msg = field(t, 1);
    CHECK_HAS(msg, "error:error loading module 'binmod' from file '");
    CHECK_HAS(msg, "binmod.lua': attempt to load a binary chunk (mode is "
                   "'t')");
    msg = field(t, 2);
    CHECK_HAS(msg, "error:error loading module 'linked' from file '");
    CHECK_HAS(msg, "linked.lua': " /* ELOOP's words */);
    CHECK(strstr(msg, "symbolic links") != NULL);
    msg = field(t, 3);
    CHECK_HAS(msg, "error:error loading module 'linkdir.mod' from file '");
    CHECK_HAS(msg, "/user/linkdir/mod.lua': ");
    CHECK(strstr(msg, "symbolic links") != NULL);
    CHECK_STR(field(t, 4), "ok:sub");
}

static void part_sandbox(const char *exe)
{
    static const struct emu_transport *const tps[3] = {&emu_tcp, &emu_udp,
                                                       &emu_pty};
    static const char *const extra[] = {"--control", "127.0.0.1:0",
                                        "--script-memory", "2", NULL};
    struct emu e;
    struct emu_client c[3];
    struct wsg_client_frame f;
    struct ctl k;
    char t[1024], path[256], st[2048];
    double pre, slowest;
    int i, round;

    sandbox_setup();
    snprintf(path, sizeof path, "%s/user/sandbox.lua", sandbox_dir);
    REQUIRE(emu_start_multi(&e, exe, tps, 3, extra) == 0);
    REQUIRE(ctl_open(&k, &e) == 0);
    for (i = 0; i < 3; i++)
        REQUIRE(emu_open(&c[i], &e, tps[i]) == 0);
    RUN_OK(&k, path);
    CHECK_HAS(script_status(&k), "\"memory_max\":2097152,");

    sandbox_closed(&c[0]);

    /* A finalizer never runs (it would loop where no hook reaches); the
     * metatable is set all the same. */
    REQUIRE(ask(&c[0], 0xB6, NULL, 0, t, sizeof t) == 0);
    CHECK_STR(t, "false|true|true");

    /* The pattern functions run what would hold the daemon for hours in
     * one C call a slice at a time (a backtracking gsub of some 20 slices
     * answers); ordinary uses of any size work (within the 2 MiB of
     * this test's script). */
    REQUIRE(ask(&c[0], 0xB9, NULL, 0, t, sizeof t) == 0);
    CHECK_STR(t, "1|0|key|100001|100000|malformed pattern (missing ']')");

    /* Loops where the script cannot yield end in an error, the script
     * goes on; a loop in a coroutine of its own is preempted and ends.
     * Bounded by the host's allowance of stuck slices. */
    REQUIRE(emu_send(&c[0], 0xB5, NULL, 0) == 0);
    REQUIRE(take(&c[0], 0xB5, t, sizeof t, EMU_REPLY_MS) == 0);
    CHECK_HAS(field(t, 0), "error:");
    CHECK_HAS(field(t, 0), "where it cannot be preempted");
    CHECK_HAS(field(t, 1), "error:");
    CHECK_HAS(field(t, 1), "where it cannot be preempted");
    CHECK_HAS(field(t, 2), "nil:");
    CHECK_HAS(field(t, 2), "where it cannot be preempted");
    CHECK_STR(field(t, 3), "4500001500000");
    CHECK_EQ(emu_request(&c[0], 0xB7, NULL, 0, NULL, EMU_REPLY_MS),
             WSG_E_SUCCESS);

    /* A loop catching those errors for ever: the daemon still answers,
     * between stuck stretches. */
    REQUIRE(emu_send(&c[0], 0xB8, NULL, 0) == 0);
    slowest = 0;
    for (round = 0; round < 3; round++)
        for (i = 0; i < 3; i++) {
            double t0 = emu_now_ms();

            CHECK_EQ(emu_request(&c[i], WSG_CMD_GET_WIDTH, NULL, 0, NULL,
                                 EMU_REPLY_MS),
                     WSG_E_SUCCESS);
            if (emu_now_ms() - t0 > slowest)
                slowest = emu_now_ms() - t0;
        }
    printf("43h beside a loop around stuck handlers: slowest %.0f ms\n",
           slowest);
    CHECK(strcmp(ctl_cmd(&k, "script stop"), "ok script stopped") == 0);

    /* A loop in the body is preempted: every interface answers 43h well
     * within a second, the control channel too, and the status counts
     * the preemptions. */
    RUN_OK(&k, path);
    REQUIRE(emu_send(&c[0], 0xB3, NULL, 0) == 0);
    REQUIRE(emu_sync(&c[0], EMU_REPLY_MS) == 0);
    snprintf(st, sizeof st, "%s", script_status(&k));
    CHECK_HAS(st, "\"running\":true,");
    pre = ctl_json_num(st, "preempted");
    slowest = 0;
    for (round = 0; round < 5; round++)
        for (i = 0; i < 3; i++) {
            double t0 = emu_now_ms();

            CHECK_EQ(emu_request(&c[i], WSG_CMD_GET_WIDTH, NULL, 0, &f,
                                 emu_ms(1000)),
                     WSG_E_SUCCESS);
            if (emu_now_ms() - t0 > slowest)
                slowest = emu_now_ms() - t0;
        }
    printf("43h beside a preempted loop: slowest %.1f ms\n", slowest);
    snprintf(st, sizeof st, "%s", script_status(&k));
    CHECK_HAS(st, "\"state\":\"runnable\",");
    CHECK(ctl_json_num(st, "preempted") > pre);
    CHECK(pre > 0);
    CHECK_EQ(flags_of(&c[0]) & (D19 | D20), D19);
    CHECK(strcmp(ctl_cmd(&k, "script stop"), "ok script stopped") == 0);
    CHECK_EQ(flags_of(&c[0]) & (D19 | D20), 0);

    /* Past the memory cap: the script ends with D20 and says why; the
     * daemon goes on. */
    RUN_OK(&k, path);
    REQUIRE(emu_send(&c[0], 0xB4, NULL, 0) == 0);
    CHECK(emu_wait_flags(&c[0], D19 | D20, D20, EMU_REPLY_MS, NULL) == 0);
    snprintf(st, sizeof st, "%s", script_status(&k));
    CHECK_HAS(st, "{\"running\":false,\"failed\":true,\"error\":\"not "
                  "enough memory");
    for (i = 0; i < 3; i++) {
        CHECK_EQ(
            emu_request(&c[i], WSG_CMD_GET_WIDTH, NULL, 0, NULL, EMU_REPLY_MS),
            WSG_E_SUCCESS);
        CHECK_EQ(emu_request(&c[i], 0xB7, NULL, 0, NULL, EMU_REPLY_MS),
                 WSG_E_CMD_UNKNOWN);
        CHECK_EQ(c[i].link.bad, 0);
        emu_close(&c[i]);
    }
    ctl_close(&k);
    CHECK_EQ(emu_stop(&e), 0);
}

/* ---- part lockstep ---- */

/* clock.lua with period ms: started at the time "time" says (the reply
 * is socket.gettime() then, exactly); returns that time, us. */
static long long clock_start(struct emu_client *c, struct ctl *k,
                             unsigned period)
{
    uint8_t p[2] = {(uint8_t)(period & 0xFF), (uint8_t)(period >> 8)};
    char t[128];
    long long t0;

    RUN_OK(k, "clock.lua");
    t0 = ctl_time(k);
    REQUIRE(t0 >= 0);
    REQUIRE(ask(c, 0xB0, p, 2, t, sizeof t) == 0);
    CHECK_EQ(field_num(t, 0), seconds(t0));
    return t0;
}

/* Ask clock.lua for its count at its next wake: the query waits in the
 * queue (the daemon has it before the steps: emu_sync), and the steps
 * that follow wake the script, which answers before "time step" does. */
static void clock_query(struct emu_client *c)
{
    REQUIRE(emu_send(c, 0xB1, NULL, 0) == 0);
    REQUIRE(emu_sync(c, EMU_REPLY_MS) == 0);
}

static void part_lockstep(const char *exe)
{
    static const char *const args[] = {"--tcp", "127.0.0.1:0", "--control",
                                       "127.0.0.1:0", NULL};
    struct wsg_client_frame f;
    struct emu e;
    struct emu_client c;
    struct ctl k;
    char t[128], want[64];
    long long t0;
    int run, s;

    REQUIRE(emu_start(&e, exe, args) == 0);
    REQUIRE(ctl_open(&k, &e) == 0);
    REQUIRE(emu_open(&c, &e, &emu_tcp) == 0);
    CMD_OK(&k, "time pause");

    /* Sleeping 10 ms at a time: 100 wakes in 1000 ms of steps, 200 in
     * 2000, on every run. The query is answered at the wake that ends
     * the stretch (the last 10 ms are stepped after it is queued). */
    for (run = 0; run < 3; run++) {
        t0 = clock_start(&c, &k, 10);
        for (s = 1; s <= 2; s++) {
            CMD_OK(&k, "time step 990");
            clock_query(&c);
            if (s == 1 && run == 0) /* waits for the wake, time paused */
                CHECK_EQ(emu_recv_id(&c, 0xB1, &f, EMU_QUIET_MS), 0);
            CMD_OK(&k, "time step 10");
            REQUIRE(take(&c, 0xB1, t, sizeof t, EMU_REPLY_MS) == 0);
            snprintf(want, sizeof want, "%d", 100 * s);
            CHECK_STR(field(t, 0), want);
            CHECK_EQ(field_num(t, 1), seconds(t0 + s * 1000000LL));
            CHECK_EQ(ctl_time(&k), t0 + s * 1000000LL);
        }
        CHECK(strcmp(ctl_cmd(&k, "script stop"), "ok script stopped") == 0);
    }

    /* Sleeping 250 ms at a time, "time step 250" each: the query sent
     * before each step is answered at the wake inside it, and
     * socket.gettime() is the stepped time to the microsecond. */
    t0 = clock_start(&c, &k, 250);
    for (s = 1; s <= 4; s++) {
        clock_query(&c);
        CHECK_EQ(ctl_time_us(ctl_cmd(&k, "time step 250")), t0 + s * 250000LL);
        REQUIRE(take(&c, 0xB1, t, sizeof t, EMU_REPLY_MS) == 0);
        snprintf(want, sizeof want, "%d", s);
        CHECK_STR(field(t, 0), want);
        CHECK_EQ(field_num(t, 1), seconds(t0 + s * 250000LL));
    }
    CHECK(strcmp(ctl_cmd(&k, "script stop"), "ok script stopped") == 0);
    emu_close(&c);
    ctl_close(&k);
    CHECK_EQ(emu_stop(&e), 0);
}

/* ---- part outside ---- */

/* A file that is no script, such as a key, run by path: it does not
 * compile, and Lua's error would quote the text where the parse failed.
 * Outside the script directory the error names the file and the line,
 * in the answer, the status, the output and the startup's message, but
 * none of the file's text; the same file inside the script directory
 * gets Lua's message in full. */
static void part_outside(const char *exe)
{
    static const char secret[] = "hunter2 s3cr3t-passw0rd\n";
    char top[] = "/tmp/wsgemu-outside.XXXXXX";
    char user[128], key[160], inside[160], out[512], err[2048];
    const char *args[] = {"--tcp",       "127.0.0.1:0",  "--control",
                          "127.0.0.1:0", "--script-dir", user,
                          NULL};
    const char *ans;
    struct emu e;
    struct ctl k;
    FILE *f;

    REQUIRE(mkdtemp(top) != NULL);
    snprintf(user, sizeof user, "%s/user", top);
    snprintf(key, sizeof key, "%s/key.pem", top);
    snprintf(inside, sizeof inside, "%s/key.lua", user);
    REQUIRE(mkdir(user, 0700) == 0);
    f = fopen(key, "w");
    REQUIRE(f && fputs(secret, f) >= 0 && fclose(f) == 0);
    f = fopen(inside, "w");
    REQUIRE(f && fputs(secret, f) >= 0 && fclose(f) == 0);

    REQUIRE(emu_start(&e, exe, args) == 0);
    REQUIRE(ctl_open(&k, &e) == 0);
    ans = run_script(&k, key);
    CHECK_HAS(ans, "error script: ");
    CHECK_HAS(ans, "key.pem:1: ");
    CHECK(strstr(ans, "s3cr3t") == NULL && strstr(ans, "hunter2") == NULL);
    ans = script_status(&k);
    CHECK_HAS(ans, "\"failed\":true,");
    CHECK_HAS(ans, "key.pem:1: ");
    CHECK(strstr(ans, "s3cr3t") == NULL && strstr(ans, "hunter2") == NULL);
    ans = script_output(&k, 0);
    CHECK_HAS(ans, "key.pem:1: ");
    CHECK(strstr(ans, "s3cr3t") == NULL && strstr(ans, "hunter2") == NULL);

    /* In the script directory: Lua's words and where, in full. */
    ans = run_script(&k, inside);
    CHECK_HAS(ans, "key.lua:1: ");
    CHECK_HAS(ans, "near 's3cr3t'");
    ctl_close(&k);
    CHECK_EQ(emu_stop(&e), 0);

    /* The same as the startup script: its message on stderr has no text
     * of the file either. The control channel's port is taken, so the
     * daemon ends by itself (status 1) once the script has run. */
    {
        struct sockaddr_in sa;
        socklen_t len = sizeof sa;
        char port[32];
        const char *start[] = {"--tcp",     "127.0.0.1:0", "--script", key,
                               "--control", port,          NULL};
        int fd = socket(AF_INET, SOCK_STREAM, 0);

        memset(&sa, 0, sizeof sa);
        sa.sin_family = AF_INET;
        sa.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
        REQUIRE(fd >= 0 && bind(fd, (struct sockaddr *)&sa, sizeof sa) == 0 &&
                listen(fd, 1) == 0 &&
                getsockname(fd, (struct sockaddr *)&sa, &len) == 0);
        snprintf(port, sizeof port, "127.0.0.1:%u",
                 (unsigned)ntohs(sa.sin_port));
        CHECK_EQ(emu_run(exe, start, EMU_READY_MS, out, sizeof out, err,
                         sizeof err),
                 1);
        close(fd);
        CHECK_HAS(err, "key.pem:1: ");
        CHECK(strstr(err, "s3cr3t") == NULL && strstr(err, "hunter2") == NULL);
    }

    unlink(key);
    unlink(inside);
    rmdir(user);
    rmdir(top);
}

/* ---- part startup ---- */

static void part_startup(const char *exe)
{
    char api[512], syntax[512], missing[512], out[512], err[2048];
    const char *args[] = {"--tcp",       "127.0.0.1:0", "--control",
                          "127.0.0.1:0", "--script",    api,
                          NULL};
    static const uint8_t p[2] = {0x42, 0x43};
    struct wsg_client_frame f;
    struct emu e;
    struct emu_client c;
    struct ctl k;
    int st;

    script_file(api, sizeof api, "api.lua");
    script_file(syntax, sizeof syntax, "syntax.lua");
    script_file(missing, sizeof missing, "no-such-script.lua");

    /* The script's IDs are registered before the ready line: the first
     * packet after it is the script's. */
    REQUIRE(emu_start(&e, exe, args) == 0);
    REQUIRE(emu_open(&c, &e, &emu_tcp) == 0);
    CHECK_EQ(emu_request(&c, ID_ECHO, p, 2, &f, EMU_REPLY_MS), WSG_E_SUCCESS);
    CHECK(EMU_NPARAMS(&f) == 2 && memcmp(EMU_PARAMS(&f), p, 2) == 0);
    CHECK_EQ(flags_of(&c) & (D19 | D20), D19);
    emu_close(&c);
    CHECK_EQ(emu_stop(&e), 0);

    /* A file that cannot be read: a bad start, status 1, no ready line. */
    args[5] = missing;
    st = emu_run(exe, args, EMU_READY_MS, out, sizeof out, err, sizeof err);
    CHECK_EQ(st, 1);
    CHECK(strstr(out, "ready") == NULL);
    CHECK_HAS(err, "no-such-script.lua");

    /* A script that does not compile: the gripper's business, as on a
     * real one: the daemon serves, with D20 and nothing registered. */
    args[5] = syntax;
    REQUIRE(emu_start(&e, exe, args) == 0);
    REQUIRE(ctl_open(&k, &e) == 0);
    REQUIRE(emu_open(&c, &e, &emu_tcp) == 0);
    CHECK_EQ(flags_of(&c) & (D19 | D20), D20);
    CHECK_EQ(emu_request(&c, ID_ECHO, p, 2, NULL, EMU_REPLY_MS),
             WSG_E_CMD_UNKNOWN);
    CHECK_HAS(script_status(&k), "{\"running\":false,\"failed\":true,");
    /* ...and a good script can be run after it. */
    RUN_OK(&k, "api.lua");
    CHECK_EQ(flags_of(&c) & (D19 | D20), D19);
    CHECK_EQ(emu_request(&c, ID_ECHO, p, 2, NULL, EMU_REPLY_MS),
             WSG_E_SUCCESS);
    emu_close(&c);
    ctl_close(&k);
    CHECK_EQ(emu_stop(&e), 0);
}

/* ---- part public ---- */

/* public_style.lua, written as the published scripts are (a bare require
 * "socket" and the global it makes, globals from cmd.read, pcall around
 * each packet, printf's %d), driven as their drivers drive them: ack,
 * homing, B0h, B1h. Its B2h reaches ntob(math.nan), which a real gripper
 * lacks: the packet fails inside pcall ("Error occured") and gets no
 * answer, and the script goes on. */
static void part_public(const char *exe)
{
    static const char *const args[] = {"--tcp", "127.0.0.1:0", "--control",
                                       "127.0.0.1:0", NULL};
    uint8_t dir = 0, move[8];
    struct wsg_client_frame f;
    struct emu e;
    struct emu_client c;
    struct ctl k;
    const char *out;
    int i;

    REQUIRE(emu_start(&e, exe, args) == 0);
    REQUIRE(ctl_open(&k, &e) == 0);
    REQUIRE(emu_open(&c, &e, &emu_tcp) == 0);
    CHECK_EQ(
        emu_request(&c, WSG_CMD_ACK_FAST_STOP, "ack", 3, NULL, EMU_REPLY_MS),
        WSG_E_SUCCESS);
    REQUIRE(emu_motion(&c, WSG_CMD_HOMING, &dir, 1, EMU_HOMING_MS, NULL) ==
            WSG_E_SUCCESS);
    RUN_OK(&k, "public_style.lua");

    /* B0h: 19 bytes, the position at 110 mm and the script's clock from
     * the global socket that require made. */
    REQUIRE(emu_request(&c, 0xB0, "\0", 1, &f, EMU_REPLY_MS) == WSG_E_SUCCESS);
    CHECK_EQ(f.len, 19);
    if (f.len == 19) {
        CHECK_NEAR(wsg_get_f32(EMU_PARAMS(&f) + 1), 110.0, 1e-3);
        CHECK(wsg_get_f32(EMU_PARAMS(&f) + 13) > 0.0f);
    }

    /* B1h: a prepositioning by mc.move; the grasping state stays IDLE
     * while the script moves the fingers and after. */
    wsg_put_f32(move, 50.0f);
    wsg_put_f32(move + 4, 100.0f);
    REQUIRE(emu_request(&c, 0xB1, move, sizeof move, &f, EMU_REPLY_MS) ==
            WSG_E_SUCCESS);
    CHECK_EQ(f.len, 19);
    CHECK_EQ(emu_get_grasp_state(&c), WSG_GS_IDLE);
    for (i = 0; i < 100 && fabs(float_of(&c, WSG_CMD_GET_WIDTH) - 50.0) > 1e-3;
         i++)
        emu_sleep_ms(emu_ms(50));
    CHECK_NEAR(float_of(&c, WSG_CMD_GET_WIDTH), 50.0, 1e-3);
    CHECK_EQ(emu_get_grasp_state(&c), WSG_GS_IDLE);

    /* B2h: no math.nan on the gripper, so no answer; the script runs on
     * and answers the next packet. */
    REQUIRE(emu_send(&c, 0xB2, NULL, 0) == 0);
    CHECK_EQ(emu_recv_id(&c, 0xB2, &f, EMU_QUIET_MS), 0);
    CHECK(strstr(script_status(&k), "\"running\":true") != NULL);
    REQUIRE(emu_request(&c, 0xB0, "\0", 1, &f, EMU_REPLY_MS) == WSG_E_SUCCESS);
    CHECK_EQ(f.len, 19);
    out = ctl_cmd(&k, "script output");
    CHECK(strstr(out, "#FMF fingers: 0") != NULL);
    CHECK(strstr(out, "Error occured") != NULL);

    CHECK(strcmp(ctl_cmd(&k, "script stop"), "ok script stopped") == 0);
    emu_close(&c);
    ctl_close(&k);
    CHECK_EQ(emu_stop(&e), 0);
}

/* ---- part dialect ---- */

/* The gripper's Lua (Lua 5.2, docs/scripting.md's table of differences),
 * each difference as a script of the gripper's era meets it. */
static void part_dialect(const char *exe)
{
    static const char *const args[] = {"--tcp", "127.0.0.1:0", "--control",
                                       "127.0.0.1:0", NULL};
    struct emu e;
    struct emu_client c;
    struct ctl k;
    char t[1024];

    REQUIRE(emu_start(&e, exe, args) == 0);
    REQUIRE(ctl_open(&k, &e) == 0);
    REQUIRE(emu_open(&c, &e, &emu_tcp) == 0);
    RUN_OK(&k, "dialect.lua");

    /* Numbers are doubles only: 3 and 3.0 print alike, %d takes 2.5. */
    REQUIRE(ask(&c, 0xB0, NULL, 0, t, sizeof t) == 0);
    CHECK_STR(t, "int=3;float=3;half=3.5;ten=5;big=9.007199254741e+15;"
                 "concat=1e+15;d=2;x=ff;key=one;mod=1.5");
    /* No //, no bitwise operators, no attributes; goto compiles. */
    REQUIRE(ask(&c, 0xB1, NULL, 0, t, sizeof t) == 0);
    CHECK_STR(t, "idiv=false;band=false;shl=false;bnot=false;const=false;"
                 "goto=true");
    /* The names of Lua 5.1 and 5.2 (module() with package.seeall
     * included), none of 5.3's or 5.4's, and no setfenv (5.1's only). */
    REQUIRE(ask(&c, 0xB2, NULL, 0, t, sizeof t) == 0);
    CHECK_STR(t, "unpack=6;pow=1024;loadstring=2;module=42;getn=3;maxn=10;"
                 "mathmod=1;log10=3;ldexp=8;bit32=15;gfind=true;"
                 "mathtype=nil;utf8=nil;move=nil;maxint=nil;nan=nil;"
                 "pack=nil;close=nil;setfenv=nil");
    /* Patterns: an empty match right after a match counts; a negative
     * count is no limit. */
    REQUIRE(ask(&c, 0xB3, NULL, 0, t, sizeof t) == 0);
    CHECK_STR(t, "gmatch=[abc][];gsub=xx xx/4;negative=3");

    CHECK(strcmp(ctl_cmd(&k, "script stop"), "ok script stopped") == 0);
    emu_close(&c);
    ctl_close(&k);
    CHECK_EQ(emu_stop(&e), 0);
}

/* ---- part hogs ---- */

/* How long a Loop may wait while a script hogs the processor: the
 * script holds the loop for one slice at a time (docs/scripting.md), a
 * millisecond or less, or 20 slices where it cannot be preempted; this
 * leaves room for a loaded machine and the sanitizers, and the freezes
 * it catches last seconds or for ever. */
#define HOG_BOUND_MS emu_ms(500)
/* How long each hog is watched. Not a bound: what is judged is each
 * Loop's wait. */
#define HOG_WATCH_MS 1500

static const struct {
    int n;
    const char *what;
    const char *error; /* what the hog's first error says; NULL: none */
} hogs[] = {
    {1, "%b() over 200 kB", NULL},
    {2, "a set of 100,000 characters", NULL},
    {3, "a literal pattern of 100,000 bytes", NULL},
    {4, "a plain find of 100,000 bytes", NULL},
    {5, "a backtracking gsub", NULL},
    {6, "cmd.send of 100^5 references", "cmd.send: more than "},
    {7, "a fresh looping coroutine each time", NULL},
    {8, "a looping message handler", NULL},
    {9, "%b() inside a __tostring", "where it cannot be preempted"},
    {10, "loops in a load reader", "where it cannot be preempted"},
    {11, "full collections of 8 MB", NULL},
    {12, "tonumber of a megabyte", NULL},
    {13, "insert and remove at the front of 200,000", NULL},
    {14, "string.rep of nothing 2^31 - 1 times", NULL},
};

/* One hog in a daemon of its own: Loops every 20 ms while it runs, each
 * answered within HOG_BOUND_MS; the script still running (the control
 * channel answers too) and its first error as expected; SIGTERM ends the
 * daemon within HOG_BOUND_MS plus the time an exit takes. */
static void hog_run(const char *exe, size_t i)
{
    static const char *const args[] = {"--tcp", "127.0.0.1:0", "--control",
                                       "127.0.0.1:0", NULL};
    uint8_t which = (uint8_t)hogs[i].n, tok[4] = {'h', 'o', 'g', 0};
    struct wsg_client_frame f;
    struct emu e;
    struct emu_client c;
    struct ctl k;
    double t0, worst = 0, end;
    int loops = 0, lost = 0, st;

    REQUIRE(emu_start(&e, exe, args) == 0);
    REQUIRE(ctl_open(&k, &e) == 0);
    REQUIRE(emu_open(&c, &e, &emu_tcp) == 0);
    RUN_OK(&k, "hogs.lua");
    REQUIRE(emu_send(&c, 0xB0, &which, 1) == 0);
    end = emu_now_ms() + HOG_WATCH_MS;
    while (emu_now_ms() < end) {
        tok[3] = (uint8_t)loops;
        t0 = emu_now_ms();
        st = emu_request(&c, WSG_CMD_LOOP, tok, sizeof tok, &f, HOG_BOUND_MS);
        if (st != WSG_E_SUCCESS || EMU_NPARAMS(&f) != sizeof tok ||
            memcmp(EMU_PARAMS(&f), tok, sizeof tok) != 0) {
            lost++;
            break; /* a frozen daemon: the rest would wait in line */
        }
        if (emu_now_ms() - t0 > worst)
            worst = emu_now_ms() - t0;
        loops++;
        emu_sleep_ms(20);
    }
    printf("hog %d, %s: %d Loops answered, worst %.1f ms%s\n", hogs[i].n,
           hogs[i].what, loops, worst, lost ? ", then one lost" : "");
    CHECK_EQ(lost, 0);
    CHECK(loops > 0);
    if (!lost) {
        char st_json[2048];

        /* The hog's start was answered long ago, behind the Loops. */
        CHECK_EQ(emu_recv_id(&c, 0xB0, &f, HOG_BOUND_MS), 1);
        snprintf(st_json, sizeof st_json, "%s", script_status(&k));
        CHECK_HAS(st_json, "\"running\":true,");
        if (hogs[i].error)
            CHECK_HAS(script_output(&k, 0), hogs[i].error);
        else
            CHECK(strstr(script_output(&k, 0), "hog error") == NULL);
    }
    emu_close(&c);
    ctl_close(&k);
    t0 = emu_now_ms();
    CHECK_EQ(emu_stop(&e), 0);
    printf("hog %d: SIGTERM to exit %.1f ms\n", hogs[i].n, emu_now_ms() - t0);
    CHECK(emu_now_ms() - t0 <= HOG_BOUND_MS + EMU_EXIT_MS / 5);
}

static void part_hogs(const char *exe)
{
    size_t i;

    for (i = 0; i < sizeof hogs / sizeof hogs[0]; i++)
        hog_run(exe, i);
}

int main(int argc, char **argv)
{
    const char *exe = emu_exe(argc, argv);
    const char *part = argc > 2 ? argv[2] : "all";
    int all = strcmp(part, "all") == 0, ran = 0;

    scripts = argc > 3 ? argv[3] : WSG_TEST_SCRIPTS;
    if (access(scripts, R_OK) != 0) {
        printf("SKIP: no scripts directory %s\n", scripts);
        return 77;
    }
    if (all || strcmp(part, "api") == 0) {
        part_api(exe);
        ran++;
    }
    if (all || strcmp(part, "ifaces") == 0) {
        part_ifaces(exe);
        ran++;
    }
    if (all || strcmp(part, "speed") == 0) {
        part_speed(exe);
        ran++;
    }
    if (all || strcmp(part, "lifecycle") == 0) {
        part_lifecycle(exe);
        ran++;
    }
    if (all || strcmp(part, "sandbox") == 0) {
        part_sandbox(exe);
        ran++;
    }
    if (all || strcmp(part, "lockstep") == 0) {
        part_lockstep(exe);
        ran++;
    }
    if (all || strcmp(part, "outside") == 0) {
        part_outside(exe);
        ran++;
    }
    if (all || strcmp(part, "startup") == 0) {
        part_startup(exe);
        ran++;
    }
    if (all || strcmp(part, "public") == 0) {
        part_public(exe);
        ran++;
    }
    if (all || strcmp(part, "dialect") == 0) {
        part_dialect(exe);
        ran++;
    }
    if (all || strcmp(part, "hogs") == 0) {
        part_hogs(exe);
        ran++;
    }
    if (!ran) {
        fprintf(stderr, "integ_script: unknown part \"%s\"\n", part);
        return 2;
    }
    TEST_EXIT();
}
