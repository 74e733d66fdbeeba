/*
 * integ_physics: the daemon with the MuJoCo plant (--physics mujoco),
 * driven as the public drivers drive a gripper: one request, one recv(),
 * the whole packet; the world set through the control channel as the
 * tests use it (lockstep: "time pause" and "time step").
 *
 * - shapes: `object box|cylinder|sphere` grasped: HOLDING (41h), 43h's
 *   width within 0.5 mm of the object's (docs/plants.md), 45h's force
 *   within 10 % of the limit; `object none`: NO PART;
 * - pull: a held box stays held under a small pull and slips out under a
 *   large one: 41h PART LOST, counted in 42h;
 * - driver: the sequence public drivers send (acknowledge, acceleration,
 *   force limit, homing, preposition, grasp, the state polled, release),
 *   in real time against the MuJoCo plant;
 * - scene: a scene file of the test's own with other joint names
 *   (--scene, --scene-fingers), and a scene whose joints are not there
 *   refused at start;
 * - determinism: two daemons, the same commands in lockstep, the same
 *   reply bytes;
 * - fingers: --finger0 fmf --finger1 dsa read the contact: the FMF's force
 *   near 45h's, the DSA cells under the box's face set and adding up to
 *   the pad's force; both 0 with no object;
 * - wsgctl: its object and pull, through the control channel;
 * - module: an emulator of the built-in plant maps no MuJoCo (it would
 *   cost each emulator of a fleet some 2 MiB), --physics mujoco loads the
 *   plant's module and MuJoCo with it, and a program with no module
 *   beside it or in its prefix refuses --physics mujoco, saying why.
 *
 * Skips (77) in a build without MuJoCo.
 */
#define _POSIX_C_SOURCE 200809L /* mkdtemp */

#include "check.h"
#include "emu.h"
#include "emu_ctl.h"
#include "wsg/finger.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

/* docs/plants.md's tolerances. */
#define TOL_MM     0.5
#define TOL_FORCE  0.1
#define LIMIT_N    40.0 /* the model's default force limit */
#define REPLY_MAX  1024
#define RECORD_MAX 16384

/* What a run sent back, byte for byte (determinism). */
struct record {
    uint8_t buf[RECORD_MAX];
    size_t len;
};

/* One recv(): exactly one whole packet with this ID. Returns its status;
 * the parameters after it in p (may be NULL). */
static int recv_one(struct emu_client *c, uint8_t id, uint8_t *p, size_t *plen,
                    struct record *rec, int timeout_ms)
{
    uint8_t buf[REPLY_MAX];
    struct wsg_client_frame f;
    long n;

    n = emu_recv_raw(c, buf, sizeof buf, timeout_ms);
    REQUIRE(n > 0);
    REQUIRE(emu_packet_decode(buf, (size_t)n, &f) == 0);
    CHECK_EQ(n, WSG_HEADER_LEN + f.len + WSG_CRC_LEN);
    CHECK_EQ(f.id, id);
    REQUIRE(f.len >= 2);
    if (rec && rec->len + (size_t)n <= sizeof rec->buf) {
        memcpy(rec->buf + rec->len, buf, (size_t)n);
        rec->len += (size_t)n;
    }
    if (p)
        memcpy(p, f.payload + 2, f.len - 2u);
    if (plen)
        *plen = f.len - 2u;
    return wsg_get_u16(f.payload);
}

static int one(struct emu_client *c, uint8_t id, const void *payload,
               size_t len, uint8_t *p, size_t *plen, struct record *rec)
{
    REQUIRE(emu_send(c, id, payload, len) == 0);
    return recv_one(c, id, p, plen, rec, EMU_REPLY_MS);
}

static float get_f(struct emu_client *c, uint8_t id, struct record *rec)
{
    uint8_t p[16];
    size_t n;

    CHECK_EQ(one(c, id, NULL, 0, p, &n, rec), WSG_E_SUCCESS);
    REQUIRE(n == 4);
    return wsg_get_f32(p);
}

static int grasp_state(struct emu_client *c, struct record *rec)
{
    uint8_t p[16];
    size_t n;

    CHECK_EQ(one(c, WSG_CMD_GET_GRASP_STATE, NULL, 0, p, &n, rec),
             WSG_E_SUCCESS);
    REQUIRE(n == 1);
    return p[0];
}

/* A motion in lockstep: E_CMD_PENDING, then ms of simulated time, then
 * the final result (one recv). */
static int motion_step(struct emu_client *c, struct ctl *k, uint8_t id,
                       const void *payload, size_t len, int ms,
                       struct record *rec)
{
    char cmd[64];

    CHECK_EQ(one(c, id, payload, len, NULL, NULL, rec), WSG_E_CMD_PENDING);
    snprintf(cmd, sizeof cmd, "time step %d", ms);
    CMD_OK(k, cmd);
    return recv_one(c, id, NULL, NULL, rec, EMU_REPLY_MS);
}

static int grasp_step(struct emu_client *c, struct ctl *k, float w, float v,
                      struct record *rec)
{
    uint8_t g[8];

    return motion_step(c, k, WSG_CMD_GRASP, g, emu_grasp_payload(g, w, v),
                       3000, rec);
}

static int release_step(struct emu_client *c, struct ctl *k, float w, float v,
                        struct record *rec)
{
    uint8_t g[8];

    return motion_step(c, k, WSG_CMD_RELEASE, g, emu_grasp_payload(g, w, v),
                       3000, rec);
}

static int home_step(struct emu_client *c, struct ctl *k, struct record *rec)
{
    uint8_t dir = 1;

    return motion_step(c, k, WSG_CMD_HOMING, &dir, 1, 4000, rec);
}

/* A daemon with the MuJoCo plant, extra options after it, its control
 * channel and a TCP client, paused. */
static void start(struct emu *e, struct ctl *k, struct emu_client *c,
                  const char *exe, const char *const *extra)
{
    const char *a[24] = {"--tcp",       "127.0.0.1:0", "--control",
                         "127.0.0.1:0", "--physics",   "mujoco"};
    size_t n = 6;

    while (extra && *extra && n < 23)
        a[n++] = *extra++;
    a[n] = NULL;
    REQUIRE(emu_start(e, exe, a) == 0);
    REQUIRE(ctl_open(k, e) == 0);
    REQUIRE(emu_open(c, e, &emu_tcp) == 0);
    CMD_OK(k, "time pause");
}

static void stop(struct emu *e, struct ctl *k, struct emu_client *c)
{
    emu_close(c);
    ctl_close(k);
    CHECK_EQ(emu_stop(e), 0);
}

static void held(struct emu_client *c, double width, const char *what)
{
    float w = get_f(c, WSG_CMD_GET_WIDTH, NULL);
    float f = get_f(c, WSG_CMD_GET_FORCE, NULL);

    fprintf(stderr, "%s: width %.3f mm, force %.2f N\n", what, w, f);
    CHECK_EQ(grasp_state(c, NULL), WSG_GS_HOLDING);
    CHECK(fabs(w - width) <= TOL_MM);
    CHECK(fabs(f - LIMIT_N) <= TOL_FORCE * LIMIT_N);
}

static void test_shapes(const char *exe)
{
    struct emu e;
    struct ctl k;
    struct emu_client c;

    start(&e, &k, &c, exe, NULL);
    CHECK_EQ(home_step(&c, &k, NULL), WSG_E_SUCCESS);

    CMD_OK(&k, "object box 40 20 30");
    /* The state names it for the page: shape, sizes, where it is. */
    CHECK(strstr(ctl_cmd(&k, "state"),
                 "\"object\":{\"kind\":\"box\",\"size\":[40,20,30],"
                 "\"mass\":0.1,\"friction\":1,\"pos\":[0.00,0.00,") != NULL);
    CHECK_EQ(grasp_step(&c, &k, 40, 50, NULL), WSG_E_SUCCESS);
    held(&c, 40, "box");
    CHECK_EQ(release_step(&c, &k, 60, 50, NULL), WSG_E_SUCCESS);

    CMD_OK(&k, "object cylinder 30 40");
    CHECK_EQ(grasp_step(&c, &k, 30, 50, NULL), WSG_E_SUCCESS);
    held(&c, 30, "cylinder");
    CHECK_EQ(release_step(&c, &k, 60, 50, NULL), WSG_E_SUCCESS);

    CMD_OK(&k, "object sphere 25 0.05");
    CHECK_EQ(grasp_step(&c, &k, 25, 50, NULL), WSG_E_SUCCESS);
    held(&c, 25, "sphere");
    CHECK_EQ(release_step(&c, &k, 60, 50, NULL), WSG_E_SUCCESS);

    /* Nothing between the fingers: the grasp closes through its
     * clamping travel and finds no part. */
    CMD_OK(&k, "object none");
    CHECK(strstr(ctl_cmd(&k, "state"), "\"object\":null") != NULL);
    CHECK_EQ(grasp_step(&c, &k, 40, 50, NULL), WSG_E_CMD_FAILED);
    CHECK_EQ(grasp_state(&c, NULL), WSG_GS_NO_PART);

    /* The built-in plant's world is refused here, and the object's
     * refused out of range. */
    CHECK(!ctl_is_ok(ctl_cmd(&k, "part 40")));
    CHECK(!ctl_is_ok(ctl_cmd(&k, "obstacle 40")));
    CHECK(!ctl_is_ok(ctl_cmd(&k, "object box 40 20")));
    CHECK(!ctl_is_ok(ctl_cmd(&k, "object sphere 0")));
    CHECK(!ctl_is_ok(ctl_cmd(&k, "object sphere 20 0")));
    CHECK(!ctl_is_ok(ctl_cmd(&k, "object sphere 20 1 11")));
    CHECK(!ctl_is_ok(ctl_cmd(&k, "object cone 20")));
    CHECK(!ctl_is_ok(ctl_cmd(&k, "pull 10")));
    stop(&e, &k, &c);
}

/* The object's z (mm) in a state answer; 1e9 when there is none. */
static double ctl_json_z(const char *state)
{
    const char *p = strstr(state, "\"pos\":[");
    double x, y, z;

    if (!p || sscanf(p + 7, "%lf,%lf,%lf", &x, &y, &z) != 3)
        return 1e9;
    return z;
}

static void test_pull(const char *exe)
{
    struct emu e;
    struct ctl k;
    struct emu_client c;
    uint8_t p[64];
    size_t n;
    double z0, z1;

    start(&e, &k, &c, exe, NULL);
    CHECK_EQ(home_step(&c, &k, NULL), WSG_E_SUCCESS);
    CMD_OK(&k, "object box 40 20 30 0.1 1");
    CHECK_EQ(grasp_step(&c, &k, 40, 50, NULL), WSG_E_SUCCESS);
    CHECK_EQ(grasp_state(&c, NULL), WSG_GS_HOLDING);
    /* 40 N on each pad at friction 1 hold some 80 N. */
    CMD_OK(&k, "pull 20");
    CMD_OK(&k, "time step 500");
    CHECK_EQ(grasp_state(&c, NULL), WSG_GS_HOLDING);
    CHECK(!ctl_is_ok(ctl_cmd(&k, "pull -1")));
    CHECK(!ctl_is_ok(ctl_cmd(&k, "pull nan")));
    z0 = ctl_json_z(ctl_cmd(&k, "state"));
    CMD_OK(&k, "pull 200");
    CMD_OK(&k, "time step 2000");
    CHECK_EQ(grasp_state(&c, NULL), WSG_GS_PART_LOST);
    /* Pulled out of the fingers: the state shows it far below. */
    z1 = ctl_json_z(ctl_cmd(&k, "state"));
    fprintf(stderr, "pull: the box's centre from z %.2f to %.2f mm\n", z0, z1);
    CHECK(z0 > -100.0 && z1 < z0 - 50.0);
    /* 42h counts the part lost (total u32, no part u16, lost u16). */
    CHECK_EQ(one(&c, WSG_CMD_GET_GRASP_STATS, NULL, 0, p, &n, NULL),
             WSG_E_SUCCESS);
    REQUIRE(n == 8);
    CHECK_EQ(wsg_get_u16(p + 6), 1);
    stop(&e, &k, &c);
}

/* Wait in real time (a bound, not an expectation) for 41h to read want. */
static int wait_state(struct emu_client *c, int want, int ms)
{
    double until = emu_now_ms() + ms;
    int s;

    do {
        s = grasp_state(c, NULL);
        if (s == want)
            return s;
        emu_sleep_ms(20);
    } while (emu_now_ms() < until);
    return s;
}

/* The sequence public drivers send at start and for a pick, in real time:
 * 24h "ack", 30h, 32h, 20h (E_CMD_PENDING, then the result), 21h, 25h
 * with 41h polled, 43h/45h read, 26h. */
static void test_driver(const char *exe)
{
    static const char *const extra[] = {"--time-scale", "5", NULL};
    struct emu e;
    struct ctl k;
    struct emu_client c;
    uint8_t b[16], p[64];
    size_t n;
    float w, f;

    start(&e, &k, &c, exe, extra);
    CMD_OK(&k, "time resume");
    CMD_OK(&k, "object box 36 20 30 0.2 1");
    CHECK_EQ(one(&c, WSG_CMD_ACK_FAST_STOP, "ack", 3, p, &n, NULL),
             WSG_E_SUCCESS);
    wsg_put_f32(b, 1000.0f);
    CHECK_EQ(one(&c, WSG_CMD_SET_ACCELERATION, b, 4, p, &n, NULL),
             WSG_E_SUCCESS);
    wsg_put_f32(b, 30.0f);
    CHECK_EQ(one(&c, WSG_CMD_SET_FORCE_LIMIT, b, 4, p, &n, NULL),
             WSG_E_SUCCESS);
    b[0] = 0; /* the default direction */
    CHECK_EQ(one(&c, WSG_CMD_HOMING, b, 1, p, &n, NULL), WSG_E_CMD_PENDING);
    CHECK_EQ(recv_one(&c, WSG_CMD_HOMING, p, &n, NULL, EMU_HOMING_MS),
             WSG_E_SUCCESS);
    /* Preposition to 70 mm, absolute, not stopping on a block. */
    CHECK_EQ(one(&c, WSG_CMD_PREPOSITION, b, emu_move_payload(b, 0, 70, 100),
                 p, &n, NULL),
             WSG_E_CMD_PENDING);
    CHECK_EQ(recv_one(&c, WSG_CMD_PREPOSITION, p, &n, NULL, EMU_MOVE_MS),
             WSG_E_SUCCESS);
    CHECK_NEAR(get_f(&c, WSG_CMD_GET_WIDTH, NULL), 70.0, 0.1);
    CHECK_EQ(
        one(&c, WSG_CMD_GRASP, b, emu_grasp_payload(b, 36, 50), p, &n, NULL),
        WSG_E_CMD_PENDING);
    CHECK_EQ(recv_one(&c, WSG_CMD_GRASP, p, &n, NULL, EMU_MOVE_MS),
             WSG_E_SUCCESS);
    CHECK_EQ(wait_state(&c, WSG_GS_HOLDING, EMU_MOVE_MS), WSG_GS_HOLDING);
    w = get_f(&c, WSG_CMD_GET_WIDTH, NULL);
    f = get_f(&c, WSG_CMD_GET_FORCE, NULL);
    fprintf(stderr, "driver: held at %.3f mm with %.2f N\n", w, f);
    CHECK(fabs(w - 36.0) <= TOL_MM);
    CHECK(fabs(f - 30.0) <= TOL_FORCE * 30.0);
    CHECK_EQ(one(&c, WSG_CMD_RELEASE, b, emu_grasp_payload(b, 60, 100), p, &n,
                 NULL),
             WSG_E_CMD_PENDING);
    CHECK_EQ(recv_one(&c, WSG_CMD_RELEASE, p, &n, NULL, EMU_MOVE_MS),
             WSG_E_SUCCESS);
    CHECK_EQ(wait_state(&c, WSG_GS_IDLE, EMU_MOVE_MS), WSG_GS_IDLE);
    stop(&e, &k, &c);
}

/* A scene of the test's own: pads 6 mm thick on joints jl and jr, no
 * actuators. */
static const char scene_xml[] =
    "<mujoco><option timestep=\"0.0005\"/><worldbody>"
    "<body name=\"a\" pos=\"-0.055 0 0\"><joint name=\"jl\" type=\"slide\" "
    "axis=\"1 0 0\" limited=\"true\" range=\"0 0.055\" armature=\"0.5\"/>"
    "<geom type=\"box\" pos=\"-0.003 0 -0.02\" size=\"0.003 0.015 0.02\" "
    "mass=\"0.1\" friction=\"0.01\" solref=\"0.002 1\" "
    "solimp=\"0.95 0.99 0.0002\" contype=\"1\" conaffinity=\"2\"/></body>"
    "<body name=\"b\" pos=\"0.055 0 0\"><joint name=\"jr\" type=\"slide\" "
    "axis=\"-1 0 0\" limited=\"true\" range=\"0 0.055\" armature=\"0.5\"/>"
    "<geom type=\"box\" pos=\"0.003 0 -0.02\" size=\"0.003 0.015 0.02\" "
    "mass=\"0.1\" friction=\"0.01\" solref=\"0.002 1\" "
    "solimp=\"0.95 0.99 0.0002\" contype=\"1\" conaffinity=\"2\"/></body>"
    "</worldbody></mujoco>";

static void test_scene(const char *exe)
{
    char path[256], odd[300], err[1024];
    const char *extra[] = {"--scene", path, "--scene-fingers", "jl,jr", NULL};
    const char *bad[] = {
        "--tcp", "127.0.0.1:0",     "--physics",          "mujoco", "--scene",
        path,    "--scene-fingers", "wsg_left,wsg_right", NULL};
    struct emu e;
    struct ctl k;
    struct emu_client c;

    emu_temp_file(path, sizeof path, "scene", scene_xml);
    start(&e, &k, &c, exe, extra);
    CHECK_EQ(home_step(&c, &k, NULL), WSG_E_SUCCESS);
    CHECK_NEAR(get_f(&c, WSG_CMD_GET_WIDTH, NULL), 110.0, 0.1);
    CMD_OK(&k, "object box 50 20 30");
    CHECK_EQ(grasp_step(&c, &k, 50, 50, NULL), WSG_E_SUCCESS);
    held(&c, 50, "own scene");
    stop(&e, &k, &c);

    /* A file name with what XML quotes in it loads as well. */
    snprintf(odd, sizeof odd, "%s&<\"'>.xml", path);
    REQUIRE(rename(path, odd) == 0);
    extra[1] = odd;
    start(&e, &k, &c, exe, extra);
    CMD_OK(&k, "object sphere 30");
    CHECK(strstr(ctl_cmd(&k, "state"), "\"kind\":\"sphere\"") != NULL);
    stop(&e, &k, &c);
    REQUIRE(rename(odd, path) == 0);

    /* The scene has no joints of those names: refused at start, as an
     * interface that cannot be opened is (status 1), naming the joint. */
    CHECK_EQ(emu_run(exe, bad, EMU_READY_MS, NULL, 0, err, sizeof err), 1);
    CHECK(strstr(err, "wsg_left") != NULL);
    remove(path);
}

/* One lockstep run: homing, a cylinder grasped, readings, a pull. */
static void run_once(const char *exe, struct record *rec)
{
    struct emu e;
    struct ctl k;
    struct emu_client c;
    int i;

    rec->len = 0;
    start(&e, &k, &c, exe, NULL);
    CHECK_EQ(home_step(&c, &k, rec), WSG_E_SUCCESS);
    CMD_OK(&k, "object cylinder 30 40 0.2 0.8");
    CHECK_EQ(grasp_step(&c, &k, 30, 80, rec), WSG_E_SUCCESS);
    for (i = 0; i < 5; i++) {
        CMD_OK(&k, "time step 37");
        (void)get_f(&c, WSG_CMD_GET_WIDTH, rec);
        (void)get_f(&c, WSG_CMD_GET_SPEED, rec);
        (void)get_f(&c, WSG_CMD_GET_FORCE, rec);
        (void)grasp_state(&c, rec);
    }
    CMD_OK(&k, "pull 150");
    for (i = 0; i < 10; i++) {
        CMD_OK(&k, "time step 21");
        (void)get_f(&c, WSG_CMD_GET_WIDTH, rec);
        (void)get_f(&c, WSG_CMD_GET_FORCE, rec);
        (void)grasp_state(&c, rec);
    }
    stop(&e, &k, &c);
}

static void test_determinism(const char *exe)
{
    static struct record a, b;

    run_once(exe, &a);
    run_once(exe, &b);
    REQUIRE(a.len > 0 && a.len < sizeof a.buf);
    CHECK_EQ(a.len, b.len);
    CHECK(memcmp(a.buf, b.buf, a.len) == 0);
}

/* FMF on finger 0 (63h), DSA on finger 1 (73h), from the pads' contact. */
static void test_fingers(const char *exe)
{
    static const char *const extra[] = {"--finger0", "fmf", "--finger1", "dsa",
                                        NULL};
    struct emu e;
    struct ctl k;
    struct emu_client c;
    uint8_t p[REPLY_MAX];
    size_t n, i;
    float force, fmf;
    double sum = 0.0;
    unsigned set = 0;

    start(&e, &k, &c, exe, extra);
    CHECK_EQ(home_step(&c, &k, NULL), WSG_E_SUCCESS);
    /* Nothing held: 0 N, every cell 0. */
    CHECK_EQ(one(&c, 0x63, NULL, 0, p, &n, NULL), WSG_E_SUCCESS);
    REQUIRE(n == 4);
    CHECK(wsg_get_f32(p) == 0.0f);
    CHECK_EQ(one(&c, 0x73, NULL, 0, p, &n, NULL), WSG_E_SUCCESS);
    REQUIRE(n == 2 * WSG_DSA_CELLS);
    for (i = 0; i < WSG_DSA_CELLS; i++)
        CHECK_EQ(wsg_get_u16(p + 2 * i), 0);

    /* A box 10 mm deep and 20 mm high: its face on each pad's centre. */
    CMD_OK(&k, "object box 40 10 20");
    CHECK_EQ(grasp_step(&c, &k, 40, 50, NULL), WSG_E_SUCCESS);
    CMD_OK(&k, "time step 300");
    force = get_f(&c, WSG_CMD_GET_FORCE, NULL);
    CHECK_EQ(one(&c, 0x63, NULL, 0, p, &n, NULL), WSG_E_SUCCESS);
    REQUIRE(n == 4);
    fmf = wsg_get_f32(p);
    fprintf(stderr, "fingers: 45h %.2f N, FMF %.2f N\n", force, fmf);
    CHECK(fabs(fmf - force) <= 0.05 * force);
    CHECK(fabs(force - LIMIT_N) <= TOL_FORCE * LIMIT_N);
    CHECK_EQ(one(&c, 0x73, NULL, 0, p, &n, NULL), WSG_E_SUCCESS);
    REQUIRE(n == 2 * WSG_DSA_CELLS);
    for (i = 0; i < WSG_DSA_CELLS; i++) {
        unsigned v = wsg_get_u16(p + 2 * i);
        unsigned r = (unsigned)i / WSG_DSA_COLS, col = (unsigned)i % 6;

        /* The corners of the pad lie outside the 10 x 20 mm face. */
        if ((r == 0 || r == WSG_DSA_ROWS - 1) && (col == 0 || col == 5))
            CHECK_EQ(v, 0);
        CHECK(v <= WSG_DSA_MAX);
        set += v > 0;
        sum += v;
    }
    fprintf(stderr, "fingers: %u cells set, %.2f N in all\n", set,
            sum / WSG_DSA_PER_N);
    /* The face covers some 3 x 6 cells of 3.4 mm. */
    CHECK(set >= 6 && set <= 40);
    CHECK(fabs(sum / WSG_DSA_PER_N - force) <= 0.1 * force);

    /* Released and the object gone: 0 again. */
    CHECK_EQ(release_step(&c, &k, 60, 50, NULL), WSG_E_SUCCESS);
    CMD_OK(&k, "object none");
    CMD_OK(&k, "time step 10");
    CHECK_EQ(one(&c, 0x63, NULL, 0, p, &n, NULL), WSG_E_SUCCESS);
    CHECK(wsg_get_f32(p) == 0.0f);
    CHECK_EQ(one(&c, 0x73, NULL, 0, p, &n, NULL), WSG_E_SUCCESS);
    for (i = 0; i < WSG_DSA_CELLS; i++)
        CHECK_EQ(wsg_get_u16(p + 2 * i), 0);
    stop(&e, &k, &c);
}

/* wsgctl's object and pull: the channel's lines, its answers printed
 * without "ok", a refusal exit 1, a usage error 2. $WSGCTL names it (ctest
 * sets it). */
static void test_wsgctl(const char *exe)
{
    const char *wsgctl = getenv("WSGCTL");
    char addr[64], out[512], err[512];
    const char *box[] = {"--control", addr, "object", "box", "40",
                         "20",        "30", "0.2",    NULL};
    const char *pull[] = {"--control", addr, "pull", "5", NULL};
    const char *cone[] = {"--control", addr, "object", "cone", "3", NULL};
    const char *big[] = {"--control", addr, "object", "sphere", "301", NULL};
    const char *none[] = {"--control", addr, "object", "none", NULL};
    struct emu e;
    struct ctl k;
    struct emu_client c;

    if (!wsgctl) {
        fprintf(stderr, "wsgctl: no $WSGCTL, not run\n");
        return;
    }
    start(&e, &k, &c, exe, NULL);
    REQUIRE(emu_field(&e, "control", addr, sizeof addr) != NULL);
    CHECK_EQ(
        emu_run(wsgctl, box, EMU_REPLY_MS, out, sizeof out, err, sizeof err),
        0);
    CHECK(strcmp(out, "object box 40 20 30 0.2 1\n") == 0);
    CHECK(strstr(ctl_cmd(&k, "state"), "\"kind\":\"box\"") != NULL);
    CHECK_EQ(
        emu_run(wsgctl, pull, EMU_REPLY_MS, out, sizeof out, err, sizeof err),
        0);
    CHECK(strcmp(out, "pull 5\n") == 0);
    /* The channel's usage error is wsgctl's (exit 2), a value it refuses
     * a refusal (exit 1). */
    CHECK_EQ(
        emu_run(wsgctl, cone, EMU_REPLY_MS, out, sizeof out, err, sizeof err),
        2);
    CHECK(strstr(err, "usage: object") != NULL);
    CHECK_EQ(
        emu_run(wsgctl, big, EMU_REPLY_MS, out, sizeof out, err, sizeof err),
        1);
    CHECK(strstr(err, "sizes must be") != NULL);
    CHECK_EQ(
        emu_run(wsgctl, none, EMU_REPLY_MS, out, sizeof out, err, sizeof err),
        0);
    CHECK(strstr(ctl_cmd(&k, "state"), "\"object\":null") != NULL);
    stop(&e, &k, &c);
}

/* Whether process pid maps a file whose path contains name. */
static int maps_has(pid_t pid, const char *name)
{
    static char maps[1 << 20];
    char path[64];

    snprintf(path, sizeof path, "/proc/%ld/maps", (long)pid);
    REQUIRE(emu_slurp(path, maps, sizeof maps) > 0);
    return strstr(maps, name) != NULL;
}

static void test_module(const char *exe)
{
    const char *builtin[] = {"--tcp", "127.0.0.1:0", NULL};
    const char *physics[] = {"--tcp", "127.0.0.1:0", "--physics", "mujoco",
                             NULL};
    char dir[] = "/tmp/integ_physics.XXXXXX", copy[64], err[1024];
    struct emu e;
    struct ctl k;
    struct emu_client c;
    FILE *in, *out;
    size_t n;
    char buf[65536];

    REQUIRE(emu_start(&e, exe, builtin) == 0);
    CHECK(!maps_has(e.pid, "mujoco"));
    CHECK_EQ(emu_stop(&e), 0);

    start(&e, &k, &c, exe, NULL);
    CHECK(maps_has(e.pid, "/plants/mujoco.so"));
    CHECK(maps_has(e.pid, "libmujoco"));
    stop(&e, &k, &c);

    /* The program alone in a directory: no module to load. */
    REQUIRE(mkdtemp(dir) != NULL);
    snprintf(copy, sizeof copy, "%s/wsgemu", dir);
    in = fopen(exe, "rb");
    out = fopen(copy, "wb");
    REQUIRE(in && out);
    while ((n = fread(buf, 1, sizeof buf, in)) > 0)
        REQUIRE(fwrite(buf, 1, n, out) == n);
    fclose(in);
    REQUIRE(fclose(out) == 0);
    REQUIRE(chmod(copy, 0755) == 0);
    CHECK_EQ(emu_run(copy, physics, EMU_READY_MS, NULL, 0, err, sizeof err),
             1);
    CHECK(strstr(err, "MuJoCo plant is not installed") != NULL);
    CHECK(strstr(err, "/plants/mujoco.so") != NULL);
    remove(copy);
    rmdir(dir);
}

int main(int argc, char **argv)
{
    const char *exe = emu_exe(argc, argv);
    const char *part = argc > 2 ? argv[2] : "all";

#ifndef WSG_TEST_HAVE_MUJOCO
    (void)exe;
    (void)part;
    fprintf(stderr, "built without MuJoCo: skipped\n");
    return 77;
#else
    if (!strcmp(part, "all") || !strcmp(part, "shapes"))
        test_shapes(exe);
    if (!strcmp(part, "all") || !strcmp(part, "pull"))
        test_pull(exe);
    if (!strcmp(part, "all") || !strcmp(part, "driver"))
        test_driver(exe);
    if (!strcmp(part, "all") || !strcmp(part, "scene"))
        test_scene(exe);
    if (!strcmp(part, "all") || !strcmp(part, "determinism"))
        test_determinism(exe);
    if (!strcmp(part, "all") || !strcmp(part, "fingers"))
        test_fingers(exe);
    if (!strcmp(part, "all") || !strcmp(part, "wsgctl"))
        test_wsgctl(exe);
    if (!strcmp(part, "all") || !strcmp(part, "module"))
        test_module(exe);
    TEST_EXIT();
#endif
}
