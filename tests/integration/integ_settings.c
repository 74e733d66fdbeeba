/*
 * integ_settings: the gripper's web-page settings, from the command line
 * and from a config file, each seen through the protocol the way a driver
 * would see it.
 *
 * - --acceleration / --force-limit: 31h / 33h report them;
 * - --serial / --tag: 50h's SN, 52h's text;
 * - --homing-direction negative: a default homing ends at 0 mm;
 * - --model wsg32: 53h's stroke is 68 mm; --part 40: a grasp at 40 mm holds;
 * - --time-scale and crc on|off are taken;
 * - --force-sensor on (force measurement fingers, also as a config key):
 *   Tare (38h) succeeds, but E_ACCESS_DENIED while holding, and 40h shows
 *   SF_FORCECNTL_MODE (D9) while holding; without it, Tare answers
 *   E_NOT_AVAILABLE and D9 never shows;
 * - --version prints the version; --udp PORT:PORT (answers to its own
 *   port) is refused;
 * - --config FILE gives the same results; an option overrides the file,
 *   wherever --config stands on the command line;
 * - bad values exit 2 naming the valid range; a bad file line exits 2
 *   naming FILE:LINE;
 * - a value with a control character (a newline, a tab, ESC, DEL) is
 *   refused for every text setting, on the command line and in the file;
 * - --can's ID is decimal (leading zeros too: 010 is ten, 08 eight) or 0x
 *   hex, nothing else (no blanks, signs, octal or other prefixes).
 */
/* mkstemp, fdopen */
#define _POSIX_C_SOURCE 200809L

#include "check.h"
#include "emu.h"
#include "wsg/axis.h"

#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static const char *exe;

static float get_float(struct emu_client *c, uint8_t id)
{
    float v = -1.0f;

    CHECK_EQ(emu_get_float(c, id, &v), 0);
    return v;
}

/* The settings of the first group, however they were given. */
static void check_group1(const char *const *args)
{
    struct emu e;
    struct emu_client c;
    struct wsg_client_frame f;
    uint8_t dir = 0;
    int imm = -1;

    REQUIRE(emu_start(&e, exe, args) == 0);
    REQUIRE(emu_open(&c, &e, &emu_tcp) == 0);
    CHECK_NEAR(get_float(&c, WSG_CMD_GET_ACCELERATION), 200.0, 1e-3);
    CHECK_NEAR(get_float(&c, WSG_CMD_GET_FORCE_LIMIT), 30.0, 1e-3);
    CHECK_EQ(
        emu_request(&c, WSG_CMD_GET_SYSTEM_INFO, NULL, 0, &f, EMU_REPLY_MS),
        WSG_E_SUCCESS);
    CHECK_EQ(EMU_NPARAMS(&f), 8);
    CHECK_EQ(wsg_get_u32(EMU_PARAMS(&f) + 4), 1234);
    CHECK_EQ(
        emu_request(&c, WSG_CMD_GET_DEVICE_TAG, NULL, 0, &f, EMU_REPLY_MS),
        WSG_E_SUCCESS);
    CHECK_EQ(EMU_NPARAMS(&f), 6);
    CHECK(memcmp(EMU_PARAMS(&f), "cell 4", 6) == 0);
    /* Homing in the default direction (0) goes the configured way. */
    CHECK_EQ(emu_motion(&c, WSG_CMD_HOMING, &dir, 1, emu_ms(10000), &imm),
             WSG_E_SUCCESS);
    CHECK_EQ(imm, WSG_E_CMD_PENDING);
    CHECK_NEAR(get_float(&c, WSG_CMD_GET_WIDTH), 0.0, 0.01);
    emu_close(&c);
    CHECK_EQ(emu_stop(&e), 0);
}

/* The second group: another model, a part between the fingers. */
static void check_group2(const char *const *args)
{
    struct emu e;
    struct emu_client c;
    struct wsg_client_frame f;
    uint8_t dir = 0, p[8];
    size_t n;
    int imm = -1;

    REQUIRE(emu_start(&e, exe, args) == 0);
    REQUIRE(emu_open(&c, &e, &emu_tcp) == 0);
    CHECK_EQ(
        emu_request(&c, WSG_CMD_GET_SYSTEM_LIMITS, NULL, 0, &f, EMU_REPLY_MS),
        WSG_E_SUCCESS);
    CHECK_EQ(EMU_NPARAMS(&f), 32);
    CHECK_NEAR(wsg_get_f32(EMU_PARAMS(&f)), 68.0, 1e-3);
    CHECK_EQ(emu_motion(&c, WSG_CMD_HOMING, &dir, 1, emu_ms(10000), &imm),
             WSG_E_SUCCESS);
    n = emu_grasp_payload(p, 40.0f, 100.0f);
    CHECK_EQ(emu_motion(&c, WSG_CMD_GRASP, p, n, emu_ms(10000), &imm),
             WSG_E_SUCCESS);
    CHECK_EQ(imm, WSG_E_CMD_PENDING);
    CHECK_EQ(
        emu_request(&c, WSG_CMD_GET_GRASP_STATE, NULL, 0, &f, EMU_REPLY_MS),
        WSG_E_SUCCESS);
    CHECK_EQ(EMU_PARAMS(&f)[0], 4); /* HOLDING */
    /* No force measurement fingers by default. */
    CHECK_EQ(emu_request(&c, WSG_CMD_TARE, NULL, 0, NULL, EMU_REPLY_MS),
             WSG_E_NOT_AVAILABLE);
    CHECK_EQ(
        emu_request(&c, WSG_CMD_GET_SYSTEM_STATE, NULL, 0, &f, EMU_REPLY_MS),
        WSG_E_SUCCESS);
    CHECK_EQ(wsg_get_u32(EMU_PARAMS(&f)) & WSG_SF_FORCECNTL_MODE, 0);
    emu_close(&c);
    CHECK_EQ(emu_stop(&e), 0);
}

/* Force measurement fingers fitted (--force-sensor on, or the file's
 * force-sensor = on), a part of 40 mm between them. */
static void check_force_sensor(const char *const *args)
{
    struct emu e;
    struct emu_client c;
    struct wsg_client_frame f;
    uint8_t dir = 0, p[8];
    size_t n = emu_grasp_payload(p, 40.0f, 100.0f);
    int imm = -1;

    REQUIRE(emu_start(&e, exe, args) == 0);
    REQUIRE(emu_open(&c, &e, &emu_tcp) == 0);
    CHECK_EQ(emu_request(&c, WSG_CMD_TARE, NULL, 0, NULL, EMU_REPLY_MS),
             WSG_E_SUCCESS);
    CHECK_EQ(emu_motion(&c, WSG_CMD_HOMING, &dir, 1, emu_ms(10000), &imm),
             WSG_E_SUCCESS);
    CHECK_EQ(emu_motion(&c, WSG_CMD_GRASP, p, n, emu_ms(10000), &imm),
             WSG_E_SUCCESS);
    CHECK_EQ(
        emu_request(&c, WSG_CMD_GET_SYSTEM_STATE, NULL, 0, &f, EMU_REPLY_MS),
        WSG_E_SUCCESS);
    CHECK(wsg_get_u32(EMU_PARAMS(&f)) & WSG_SF_FORCECNTL_MODE);
    /* 3.3.9: not in force control mode, i.e. not while holding. */
    CHECK_EQ(emu_request(&c, WSG_CMD_TARE, NULL, 0, NULL, EMU_REPLY_MS),
             WSG_E_ACCESS_DENIED);
    emu_close(&c);
    CHECK_EQ(emu_stop(&e), 0);
}

static void test_force_sensor(void)
{
    static const char *const a[] = {
        "--tcp", "127.0.0.1:0", "--part", "40", "--force-sensor", "on", NULL};
    char path[256];
    const char *b[] = {"--tcp", "127.0.0.1:0", "--config", path, NULL};

    check_force_sensor(a);
    emu_temp_file(path, sizeof path, "settings",
                  "part = 40\nforce-sensor = on\n");
    check_force_sensor(b);
    unlink(path);
}

static void test_version(void)
{
    static const char *const v[] = {"--version", NULL};
    char out[256], err[256];

    CHECK_EQ(emu_run(exe, v, emu_ms(5000), out, sizeof out, err, sizeof err),
             0);
    CHECK(strncmp(out, "wsgemu ", 7) == 0 && strchr(out, '.') != NULL);
    CHECK(strchr(out, '\n') == out + strlen(out) - 1); /* one line */
}

static void test_options(void)
{
    static const char *const g1[] = {"--tcp",
                                     "127.0.0.1:0",
                                     "--acceleration",
                                     "200",
                                     "--force-limit",
                                     "30",
                                     "--serial",
                                     "1234",
                                     "--tag",
                                     "cell 4",
                                     "--homing-direction",
                                     "negative",
                                     "--time-scale",
                                     "2",
                                     "--crc",
                                     "on",
                                     NULL};
    static const char *const g2[] = {
        "--tcp", "127.0.0.1:0", "--model", "wsg32", "--part", "40", NULL};

    check_group1(g1);
    check_group2(g2);
}

static void test_config(void)
{
    char path[256], path2[256];
    const char *g1[] = {"--config", path, NULL};
    const char *g2[] = {"--config", path2, NULL};

    emu_temp_file(path, sizeof path, "settings",
                  "# settings of integ_settings\n"
                  "\n"
                  "tcp = 127.0.0.1:0\n"
                  "  acceleration=200  \n"
                  "force-limit = 30\n"
                  "serial = 1234\n"
                  "tag = cell 4\n"
                  "homing-direction = negative\n"
                  "no-crc = off\n"
                  "time-scale = 1\n");
    emu_temp_file(path2, sizeof path2, "settings",
                  "tcp = 127.0.0.1:0\nmodel = wsg32\npart = 40:50\n");
    check_group1(g1);
    check_group2(g2);
    unlink(path);
    unlink(path2);
}

/* An option beats the file, before or after --config. */
static void test_override(void)
{
    char path[256];
    const char *after[] = {"--config", path, "--acceleration", "300", NULL};
    const char *before[] = {"--acceleration", "300", "--config", path, NULL};
    const char *const *runs[] = {after, before};
    size_t i;

    emu_temp_file(path, sizeof path, "settings",
                  "tcp = 127.0.0.1:0\nacceleration = 200\nno-crc = on\n");
    for (i = 0; i < 2; i++) {
        struct emu e;
        struct emu_client c;

        REQUIRE(emu_start(&e, exe, runs[i]) == 0);
        REQUIRE(emu_open(&c, &e, &emu_tcp) == 0);
        CHECK_NEAR(get_float(&c, WSG_CMD_GET_ACCELERATION), 300.0, 1e-3);
        emu_close(&c);
        CHECK_EQ(emu_stop(&e), 0);
    }
    /* no-crc = on from the file: a wrong checksum passes... */
    {
        struct emu e;
        struct emu_client c;
        uint8_t pkt[32];
        size_t n;
        const char *args[] = {"--config", path, NULL};
        const char *args_crc[] = {"--config", path, "--crc", "on", NULL};
        struct wsg_client_frame f;

        n = wsg_frame_encode(pkt, sizeof pkt, WSG_CMD_LOOP,
                             (const uint8_t *)"ab", 2);
        pkt[n - 1] ^= 0x5A;
        REQUIRE(emu_start(&e, exe, args) == 0);
        REQUIRE(emu_open(&c, &e, &emu_tcp) == 0);
        REQUIRE(emu_send_raw(&c, pkt, n) == 0);
        CHECK_EQ(emu_recv_id(&c, WSG_CMD_LOOP, &f, EMU_REPLY_MS), 1);
        CHECK_EQ(f.status, WSG_E_SUCCESS);
        emu_close(&c);
        CHECK_EQ(emu_stop(&e), 0);
        /* ... unless --crc on overrides it. */
        REQUIRE(emu_start(&e, exe, args_crc) == 0);
        REQUIRE(emu_open(&c, &e, &emu_tcp) == 0);
        REQUIRE(emu_send_raw(&c, pkt, n) == 0);
        CHECK_EQ(emu_recv_id(&c, WSG_CMD_LOOP, &f, EMU_REPLY_MS), 1);
        CHECK_EQ(f.status, WSG_E_CHECKSUM_ERROR);
        emu_close(&c);
        CHECK_EQ(emu_stop(&e), 0);
    }
    unlink(path);
}

/* Exit status 2, nothing on stdout, and stderr containing want. */
static void bad(const char *const *args, const char *want)
{
    char out[512], err[1024];
    int st =
        emu_run(exe, args, emu_ms(5000), out, sizeof out, err, sizeof err);

    printf("%s %s: status %d, stderr \"%s\"\n", args[0],
           args[1] ? args[1] : "", st, err);
    CHECK_EQ(st, 2);
    CHECK(strstr(out, "ready") == NULL);
    CHECK(strstr(err, want) != NULL);
    if (!strstr(err, want))
        fprintf(stderr, "  expected \"%s\" in it\n", want);
}

static void test_bad_values(void)
{
    static const char *const sensor[] = {"--force-sensor", "maybe", NULL};
    static const char *const udp_self[] = {"--udp", "127.0.0.1:41500:41500",
                                           NULL};
    static const char *const acc[] = {"--acceleration", "6000", NULL};
    static const char *const acc32[] = {"--model", "wsg32", "--acceleration",
                                        "50", NULL};
    static const char *const force[] = {"--force-limit", "100", NULL};
    static const char *const force25[] = {"--force-limit", "30", "--model",
                                          "wsg25", NULL};
    static const char *const nan_[] = {"--force-limit", "nan", NULL};
    static const char *const dir[] = {"--homing-direction", "up", NULL};
    static const char *const tag[] = {
        "--tag",
        "01234567890123456789012345678901234567890123456789012345678901234",
        NULL};
    static const char *const tag2[] = {"--tag", "tab\there", NULL};
    static const char *const serial[] = {"--serial", "-1", NULL};
    static const char *const serial2[] = {"--serial", "4294967296", NULL};
    static const char *const part[] = {"--part", "200", NULL};
    static const char *const part2[] = {"--part", "20:0", NULL};
    static const char *const scale[] = {"--time-scale", "0", NULL};
    static const char *const clamp[] = {"--clamping-travel", "-1", NULL};
    static const char *const tol[] = {"--width-tolerance", "111", NULL};
    static const char *const crc[] = {"--crc", "maybe", NULL};
    static const char *const ctl[] = {"--control", "localhost", NULL};
    static const char *const nofile[] = {"--config", "/nonexistent/wsg.conf",
                                         NULL};

    bad(acc, "100..5000");
    bad(acc32, "100..5000");
    bad(force, "5..80");
    bad(force25, "5..20");
    bad(nan_, "--force-limit");
    bad(dir, "--homing-direction");
    bad(tag, "--tag");
    bad(tag2, "--tag");
    bad(serial, "--serial");
    bad(serial2, "--serial");
    bad(part, "0..110");
    bad(part2, "--part");
    bad(scale, "--time-scale");
    bad(clamp, "--clamping-travel");
    bad(tol, "0..110");
    bad(crc, "--crc");
    bad(sensor, "--force-sensor");
    bad(udp_self, "would answer itself");
    bad(ctl, "--control");
    bad(nofile, "/nonexistent/wsg.conf");
}

static void bad_file(const char *text, const char *want_suffix)
{
    char path[256], want[320];
    const char *args[] = {"--config", path, NULL};

    emu_temp_file(path, sizeof path, "settings", text);
    snprintf(want, sizeof want, "%s:%s", path, want_suffix);
    bad(args, want);
    unlink(path);
}

static void test_bad_files(void)
{
    bad_file("# ok\nmodel = wsg32\nacceleration = fast\n", "3: acceleration");
    bad_file("model = wsg32\nbogus = 1\n", "2: unknown setting 'bogus'");
    bad_file("tcp 127.0.0.1:0\n", "1: expected 'key = value'");
    bad_file("config = other.conf\n", "1: unknown setting 'config'");
    /* Range errors are found once the model is known, and still name the
     * line the value came from. */
    bad_file("\n\nforce-limit = 60\nmodel = wsg25\n", "3: force-limit");
    bad_file("no-crc = perhaps\n", "1: no-crc");
}

/* No value holds a control character, whatever the setting and wherever
 * it comes from: a text setting (paths, names) on the command line and in
 * the file alike. */
static void test_control_chars(void)
{
    static const char *const script[] = {"--script", "/tmp/a\nlog = /tmp/b",
                                         NULL};
    static const char *const log[] = {"--log", "/nonexistent/x\ry", NULL};
    static const char *const pty[] = {"--pty", "/nonexistent/tty\tWSG", NULL};
    static const char *const model[] = {"--model", "wsg50\x1b", NULL};
    static const char *const dir[] = {"--script-dir", "/nonexistent/d\x7f",
                                      NULL};

    bad(script, "--script: a control character (byte 0x0A at 7)");
    bad(log, "--log: a control character (byte 0x0D");
    bad(pty, "--pty: a control character (byte 0x09");
    bad(model, "--model: a control character (byte 0x1B");
    bad(dir, "--script-dir: a control character (byte 0x7F");
    bad_file("script = /tmp/x\x1b[2Jy.lua\n",
             "1: script: a control character (byte 0x1B");
    bad_file("\nlog = /tmp/\x01x.log\n",
             "2: log: a control character (byte 0x01");
}

/* --can IFACE:ID with ID given as id is read as the ID shown. Without a
 * CAN bus here the value shows in the error of a fleet too large for it:
 * 1024 grippers from ID take IDs up to ID + 2047, past 0x7FF for every ID
 * from 2, and the message names ID in hex (it comes before any interface
 * is opened). */
static void can_id_read_as(const char *id, const char *shown)
{
    char arg[64], want[64];
    const char *args[] = {"--grippers", "1024", "--can", arg, NULL};

    snprintf(arg, sizeof arg, "nosuchcan9:%s", id);
    snprintf(want, sizeof want, "CAN IDs %s..", shown);
    bad(args, want);
}

static void test_can_id(void)
{
    static const char *const refused[] = {
        "",     " 5",    "5 ",   "+5",
        "-1",   "0x",    "x10",  "0x 1",
        "0x1G", "1e2",   "0b1",  "0o7",
        "2047", "0x7FF", "3000", "0x10000000000000000"};
    char arg[64];
    const char *args[] = {"--can", arg, NULL};
    size_t i;

    can_id_read_as("010", "0x00A");
    can_id_read_as("08", "0x008");
    can_id_read_as("0009", "0x009");
    can_id_read_as("16", "0x010");
    can_id_read_as("0x10", "0x010");
    can_id_read_as("0X1f", "0x01F");
    can_id_read_as("0x00a", "0x00A");
    can_id_read_as("2046", "0x7FE");
    for (i = 0; i < sizeof refused / sizeof refused[0]; i++) {
        snprintf(arg, sizeof arg, "nosuchcan9:%s", refused[i]);
        bad(args, "11-bit ID of 0..0x7FE");
    }
}

int main(int argc, char **argv)
{
    exe = emu_exe(argc, argv);
    test_options();
    test_config();
    test_override();
    test_force_sensor();
    test_version();
    test_bad_values();
    test_bad_files();
    test_control_chars();
    test_can_id();
    TEST_EXIT();
}
