/*
 * integ_fingers: the finger commands against the real daemon, read the way
 * the public clients read them: one request, one recv(), the whole packet.
 *
 * - --finger0 dsa --finger1 fmf: 60h and 70h name the types and sizes
 *   (DSA 3/168, FMF 2/4), the older style's 60h with an index too;
 * - with nothing held the pad reads 0 in every cell and the FMF 0 N;
 * - holding a part (lockstep: "time pause" and "time step"), 73h's float
 *   is exactly 45h's force, and 63h's 168 bytes arrive in one recv with
 *   the cells under the default 10 mm patch set and adding up to that
 *   force; "patch 20.4 47.6" covers the pad evenly;
 * - the control channel's `finger` reads both and sets power (73h then
 *   E_NOT_AVAILABLE; 72h 1 powers it again) and kinds (`finger 0 none`:
 *   63h E_NO_SENSOR), `finger 0 cells` gives the pad's frame; `state`
 *   carries the fingers;
 * - a config file's finger1 key fits a finger as the option does, and a
 *   kind that is none of the five is refused at start;
 * - the example device models (packaging/fingers) under the example
 *   script: the tip's taxels and the SPI sensor's value follow the force
 *   held (argv[2]: the source tree).
 */
#include "check.h"
#include "emu.h"
#include "emu_ctl.h"
#include "wsg/finger.h"

#include <stdio.h>
#include <string.h>

static const char *const args[] = {"--tcp",       "127.0.0.1:0", "--control",
                                   "127.0.0.1:0", "--finger0",   "dsa",
                                   "--finger1",   "fmf",         NULL};

/* One request and one recv(): the status, and the parameters in p. */
static int one(struct emu_client *c, uint8_t id, const void *payload,
               size_t len, uint8_t *p, size_t *plen)
{
    uint8_t buf[1024];
    struct wsg_client_frame f;
    long n;

    REQUIRE(emu_send(c, id, payload, len) == 0);
    n = emu_recv_raw(c, buf, sizeof buf, EMU_REPLY_MS);
    REQUIRE(n > 0);
    REQUIRE(emu_packet_decode(buf, (size_t)n, &f) == 0);
    /* exactly one packet, whole */
    CHECK_EQ(n, WSG_HEADER_LEN + f.len + WSG_CRC_LEN);
    CHECK_EQ(f.id, id);
    REQUIRE(f.len >= 2);
    *plen = f.len - 2u;
    memcpy(p, f.payload + 2, *plen);
    return wsg_get_u16(f.payload);
}

static void test_info(struct emu_client *c)
{
    uint8_t p[512], one_idx = 1;
    size_t n;

    CHECK_EQ(one(c, 0x60, NULL, 0, p, &n), WSG_E_SUCCESS);
    CHECK_EQ(n, 3);
    CHECK_EQ(p[0], WSG_FINGER_TYPE_DSA);
    CHECK_EQ(wsg_get_u16(p + 1), 168);
    CHECK_EQ(one(c, 0x70, NULL, 0, p, &n), WSG_E_SUCCESS);
    CHECK_EQ(p[0], WSG_FINGER_TYPE_FMF);
    CHECK_EQ(wsg_get_u16(p + 1), 4);
    CHECK_EQ(one(c, 0x60, &one_idx, 1, p, &n), WSG_E_SUCCESS);
    CHECK_EQ(p[0], WSG_FINGER_TYPE_FMF);
    CHECK_EQ(one(c, 0x61, NULL, 0, p, &n), WSG_E_SUCCESS);
    CHECK_EQ(n, 2);
    CHECK_EQ(wsg_get_u16(p), WSG_FF_POWERED | WSG_FF_DATA);
    /* nothing held */
    CHECK_EQ(one(c, 0x63, NULL, 0, p, &n), WSG_E_SUCCESS);
    REQUIRE(n == 168);
    for (n = 0; n < 168; n++)
        CHECK_EQ(p[n], 0);
    CHECK_EQ(one(c, 0x73, NULL, 0, p, &n), WSG_E_SUCCESS);
    CHECK_EQ(n, 4);
    CHECK(wsg_get_f32(p) == 0.0f);
}

static void test_holding(struct emu *e, struct emu_client *c, struct ctl *k)
{
    struct emu_client m;
    struct wsg_client_frame f;
    uint8_t home = 1, g[8], p[512];
    size_t n, i;
    float force;
    double sum = 0.0;
    const char *ans;

    REQUIRE(emu_open(&m, e, &emu_tcp) == 0);
    CMD_OK(k, "time pause");
    CHECK_EQ(emu_request(&m, WSG_CMD_HOMING, &home, 1, NULL, EMU_REPLY_MS),
             WSG_E_CMD_PENDING);
    CMD_OK(k, "time step 3000");
    CHECK_EQ(emu_recv_id(&m, WSG_CMD_HOMING, &f, EMU_REPLY_MS), 1);
    CMD_OK(k, "part 40");
    CHECK_EQ(emu_request(&m, WSG_CMD_GRASP, g, emu_grasp_payload(g, 40, 50),
                         NULL, EMU_REPLY_MS),
             WSG_E_CMD_PENDING);
    CMD_OK(k, "time step 3000");
    CHECK_EQ(emu_recv_id(&m, WSG_CMD_GRASP, &f, EMU_REPLY_MS), 1);
    CHECK_EQ(f.status, WSG_E_SUCCESS);
    REQUIRE(emu_get_float(&m, WSG_CMD_GET_FORCE, &force) == 0);
    CHECK(force > 1.0f);

    CHECK_EQ(one(c, 0x73, NULL, 0, p, &n), WSG_E_SUCCESS);
    CHECK(wsg_get_f32(p) == force);
    CHECK_EQ(one(c, 0x63, NULL, 0, p, &n), WSG_E_SUCCESS);
    REQUIRE(n == 168);
    for (i = 0; i < WSG_DSA_CELLS; i++) {
        unsigned v = wsg_get_u16(p + 2 * i);
        unsigned r = (unsigned)i / WSG_DSA_COLS, col = (unsigned)i % 6;
        int under = col >= 1 && col <= 4 && r >= 5 && r <= 8;

        CHECK(under ? v > 0 : v == 0);
        CHECK(v <= WSG_DSA_MAX);
        sum += v;
    }
    CHECK_NEAR(sum / WSG_DSA_PER_N, force, 0.05);
    /* the same frame on the control channel */
    ans = ctl_cmd(k, "finger 0 cells");
    CHECK(ctl_is_ok(ans));
    CHECK(strncmp(ans, "ok [0,0,0,0,0,0,", 16) == 0);
    /* a patch as big as the pad: every cell alike */
    CMD_OK(k, "patch 20.4 47.6");
    CMD_OK(k, "time step 1");
    CHECK_EQ(one(c, 0x63, NULL, 0, p, &n), WSG_E_SUCCESS);
    for (i = 1; i < WSG_DSA_CELLS; i++)
        CHECK_EQ(wsg_get_u16(p + 2 * i), wsg_get_u16(p));
    CHECK(wsg_get_u16(p) > 0);
    CMD_OK(k, "patch default");
    CHECK(strstr(ctl_cmd(k, "state"),
                 "\"fingers\":[{\"kind\":\"dsa\",\"powered\":true") != NULL);
    emu_close(&m);
    CMD_OK(k, "time resume");
}

static void test_control(struct emu_client *c, struct ctl *k)
{
    uint8_t p[512], on = 1;
    size_t n;
    const char *ans;

    CMD_OK(k, "finger 1 power off");
    CHECK_EQ(one(c, 0x73, NULL, 0, p, &n), WSG_E_NOT_AVAILABLE);
    CHECK_EQ(n, 0);
    ans = ctl_cmd(k, "finger");
    CHECK(strstr(ans, "\"kind\":\"fmf\",\"type\":2,\"size\":4,\"flags\":0,"
                      "\"powered\":false") != NULL);
    CHECK_EQ(one(c, 0x72, &on, 1, p, &n), WSG_E_SUCCESS);
    CHECK_EQ(one(c, 0x73, NULL, 0, p, &n), WSG_E_SUCCESS);
    CMD_OK(k, "finger 0 none");
    CHECK_EQ(one(c, 0x63, NULL, 0, p, &n), WSG_E_NO_SENSOR);
    CHECK_EQ(one(c, 0x60, NULL, 0, p, &n), WSG_E_SUCCESS);
    CHECK_EQ(p[0], WSG_FINGER_TYPE_NONE);
    CHECK(!ctl_is_ok(ctl_cmd(k, "finger 0 power on")));
    CHECK(!ctl_is_ok(ctl_cmd(k, "finger 2 dsa")));
    CHECK(!ctl_is_ok(ctl_cmd(k, "finger 0 soft")));
    CHECK(!ctl_is_ok(ctl_cmd(k, "finger 0 device")));
    CHECK(!ctl_is_ok(ctl_cmd(k, "finger 0 device /nonexistent.lua")));
    CHECK(!ctl_is_ok(ctl_cmd(k, "patch 0 1")));
    CMD_OK(k, "finger 0 generic");
    CHECK_EQ(one(c, 0x60, NULL, 0, p, &n), WSG_E_SUCCESS);
    CHECK_EQ(p[0], WSG_FINGER_TYPE_GENERIC);
}

/* Device models that would run past their instruction bound: one that
 * catches the bound's error with pcall in a loop fails with it, and
 * xpcall, whose handler Lua calls again for an error inside it, is not
 * there; each is refused when fitted, and the daemon answers on. */
static void test_hostile_models(struct emu_client *c, struct ctl *k)
{
    static const struct {
        const char *src, *reason;
    } models[] = {
        {"while true do pcall(function() while true do end end) end\n",
         "ran over its 1000000 instructions"},
        {"while true do\n"
         "  xpcall(function() error('x') end, function() while true do end "
         "end)\n"
         "end\n",
         "'xpcall' (a nil value)"}};
    char path[256], cmd[300];
    uint8_t p[512];
    size_t i, n;
    const char *ans;

    for (i = 0; i < sizeof models / sizeof models[0]; i++) {
        emu_temp_file(path, sizeof path, "hostile", models[i].src);
        snprintf(cmd, sizeof cmd, "finger 0 device %s", path);
        ans = ctl_cmd(k, cmd);
        CHECK(!ctl_is_ok(ans) && strstr(ans, models[i].reason) != NULL);
        CHECK_EQ(one(c, 0x60, NULL, 0, p, &n), WSG_E_SUCCESS);
        remove(path);
    }
}

static void test_config(const char *exe)
{
    char conf[256];
    struct emu e;
    struct emu_client c;
    uint8_t p[512];
    size_t n;
    static const char *const bad[] = {"--tcp", "127.0.0.1:0", "--finger0",
                                      "glove", NULL};
    const char *cargs[] = {"--tcp", "127.0.0.1:0", "--config", conf, NULL};

    emu_temp_file(conf, sizeof conf, "fingers", "finger1 = dsa\n");
    REQUIRE(emu_start(&e, exe, cargs) == 0);
    REQUIRE(emu_open(&c, &e, &emu_tcp) == 0);
    CHECK_EQ(one(&c, 0x70, NULL, 0, p, &n), WSG_E_SUCCESS);
    CHECK_EQ(p[0], WSG_FINGER_TYPE_DSA);
    CHECK_EQ(one(&c, 0x60, NULL, 0, p, &n), WSG_E_SUCCESS);
    CHECK_EQ(p[0], WSG_FINGER_TYPE_GENERIC);
    emu_close(&c);
    CHECK_EQ(emu_stop(&e), 0);
    remove(conf);
    CHECK_EQ(emu_run(exe, bad, EMU_REPLY_MS, NULL, 0, NULL, 0), 2);
}

/* The example device models driven by the example script, as the public
 * scripts drive theirs: B0h answers the tip's "x", its 5 x 5 taxels (the
 * force on each in mN: the default 10 mm patch covers the tip, 4 mm^2 of
 * its 100 each) and the SPI sensor's 42 and force in 0.01 N. */
static void test_devices(const char *exe, const char *src)
{
    char tip[512], spi[512], script[512];
    const char *dargs[] = {
        "--tcp",     "127.0.0.1:0", "--control",    "127.0.0.1:0",
        "--finger0", tip,           "--finger1",    spi,
        "--script",  script,        "--time-scale", "10",
        NULL};
    struct emu e;
    struct emu_client c;
    struct wsg_client_frame f;
    struct ctl k;
    uint8_t home = 1, g[8], p[512];
    float force;
    size_t n, i;
    unsigned want;

    snprintf(tip, sizeof tip, "device:%s/packaging/fingers/tactile_tip.lua",
             src);
    snprintf(spi, sizeof spi, "device:%s/packaging/fingers/spi_sensor.lua",
             src);
    snprintf(script, sizeof script, "%s/packaging/fingers/tip_reader.lua",
             src);
    REQUIRE(emu_start(&e, exe, dargs) == 0);
    REQUIRE(ctl_open(&k, &e) == 0);
    REQUIRE(emu_open(&c, &e, &emu_tcp) == 0);
    CHECK_EQ(emu_request(&c, WSG_CMD_HOMING, &home, 1, NULL, EMU_REPLY_MS),
             WSG_E_CMD_PENDING);
    CHECK_EQ(emu_recv_id(&c, WSG_CMD_HOMING, &f, EMU_REPLY_MS), 1);
    CMD_OK(&k, "part 40");
    CHECK_EQ(emu_request(&c, WSG_CMD_GRASP, g, emu_grasp_payload(g, 40, 50),
                         NULL, EMU_REPLY_MS),
             WSG_E_CMD_PENDING);
    CHECK_EQ(emu_recv_id(&c, WSG_CMD_GRASP, &f, EMU_REPLY_MS), 1);
    CHECK_EQ(f.status, WSG_E_SUCCESS);
    REQUIRE(emu_get_float(&c, WSG_CMD_GET_FORCE, &force) == 0);
    /* the script's power cycle and polling take under a second */
    CHECK_EQ(emu_request(&c, 0xB0, NULL, 0, &f, EMU_REPLY_MS), WSG_E_SUCCESS);
    REQUIRE(EMU_NPARAMS(&f) == 1 + 50 + 3);
    memcpy(p, EMU_PARAMS(&f), 54);
    CHECK_EQ(p[0], 1);
    want = (unsigned)(force * 40.0 + 0.5);
    for (i = 0; i < 25; i++)
        CHECK_NEAR(wsg_get_u16(p + 1 + 2 * i), want, 1);
    CHECK_EQ(p[51], 42);
    CHECK_NEAR(wsg_get_u16(p + 52), force * 100.0, 1);
    /* 71h: a generic finger with its UART set up; 73h: the model's data */
    CHECK_EQ(emu_request(&c, 0x70, NULL, 0, &f, EMU_REPLY_MS), WSG_E_SUCCESS);
    CHECK_EQ(EMU_PARAMS(&f)[0], WSG_FINGER_TYPE_GENERIC);
    CHECK_EQ(wsg_get_u16(EMU_PARAMS(&f) + 1), 3);
    CHECK_EQ(emu_request(&c, 0x73, NULL, 0, &f, EMU_REPLY_MS), WSG_E_SUCCESS);
    CHECK_EQ(EMU_NPARAMS(&f), 3);
    CHECK_EQ(EMU_PARAMS(&f)[0], 42);
    CHECK_EQ(emu_request(&c, 0x61, NULL, 0, &f, EMU_REPLY_MS), WSG_E_SUCCESS);
    CHECK(wsg_get_u16(EMU_PARAMS(&f)) & WSG_FF_UART);
    (void)n;
    emu_close(&c);
    ctl_close(&k);
    CHECK_EQ(emu_stop(&e), 0);
}

int main(int argc, char **argv)
{
    const char *exe = emu_exe(argc, argv);
    struct emu e;
    struct emu_client c;
    struct ctl k;

    REQUIRE(emu_start(&e, exe, args) == 0);
    REQUIRE(ctl_open(&k, &e) == 0);
    REQUIRE(emu_open(&c, &e, &emu_tcp) == 0);
    test_info(&c);
    test_holding(&e, &c, &k);
    test_control(&c, &k);
    test_hostile_models(&c, &k);
    emu_close(&c);
    ctl_close(&k);
    CHECK_EQ(emu_stop(&e), 0);
    test_config(exe);
    if (argc > 2)
        test_devices(exe, argv[2]);
    TEST_EXIT();
}
