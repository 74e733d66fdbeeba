/*
 * The finger commands and the finger interface on a fake clock: 60h..63h
 * and 70h..73h in both addressing styles with every error the handlers
 * give (bad index, no finger, no power, a fault, bad lengths and values),
 * force measurement fingers against the force the model holds with (and
 * tare), a DSA pad's cells under the part's contact patch, and the UART
 * and SPI of custom electronics through a test's link: bytes arrive one
 * byte time after another, in simulated time.
 */
#include <string.h>

#include "tdev.h"
#include "wsg/finger.h"

static void settle(struct tdev *t)
{
    wsg_device_settle(&t->dev);
}

static void set_kinds(struct tdev *t, enum wsg_finger_kind a,
                      enum wsg_finger_kind b)
{
    wsg_finger_request_kind(&t->dev.fingers, 0, a);
    wsg_finger_request_kind(&t->dev.fingers, 1, b);
    settle(t);
}

static uint8_t idx[2] = {0, 1};

/* Hold a part of 50 mm with force limit f. */
static void hold(struct tdev *t, float f)
{
    uint8_t p[4];

    CHECK_EQ(tdev_home(t, 0), WSG_E_SUCCESS);
    wsg_put_f32(p, f);
    CHECK_EQ(tdev_cmd(t, WSG_CMD_SET_FORCE_LIMIT, p, 4), WSG_E_SUCCESS);
    wsg_axis_set_part(tdev_axis(t), 50.0, 0);
    CHECK_EQ(tdev_cmd2f(t, WSG_CMD_GRASP, 50.0f, 100.0f), WSG_E_CMD_PENDING);
    CHECK_EQ(tdev_final(t, WSG_CMD_GRASP, 4000), WSG_E_SUCCESS);
    CHECK_EQ(tdev_grasp_state(t), WSG_GS_HOLDING);
}

static void test_info_both_styles(void)
{
    struct tdev t;
    uint8_t bad = 2, two[2] = {0, 0};

    tdev_init(&t);
    /* 4.x: no payload, the ID names the finger */
    CHECK_EQ(tdev_cmd(&t, 0x60, NULL, 0), WSG_E_SUCCESS);
    CHECK_EQ(tdev_last(&t)->plen, 3);
    CHECK_EQ(tdev_last(&t)->params[0], WSG_FINGER_TYPE_GENERIC);
    CHECK_EQ(wsg_get_u16(tdev_last(&t)->params + 1), 0);
    CHECK_EQ(tdev_cmd(&t, 0x70, NULL, 0), WSG_E_SUCCESS);
    CHECK_EQ(tdev_last(&t)->params[0], WSG_FINGER_TYPE_GENERIC);
    /* older clients: the index first */
    CHECK_EQ(tdev_cmd(&t, 0x60, &idx[1], 1), WSG_E_SUCCESS);
    CHECK_EQ(tdev_last(&t)->plen, 3);
    CHECK_EQ(tdev_cmd(&t, 0x60, &bad, 1), WSG_E_INDEX_OUT_OF_BOUNDS);
    CHECK_EQ(tdev_last(&t)->plen, 0);
    CHECK_EQ(tdev_cmd(&t, 0x61, &bad, 1), WSG_E_INDEX_OUT_OF_BOUNDS);
    CHECK_EQ(tdev_cmd(&t, 0x63, &bad, 1), WSG_E_INDEX_OUT_OF_BOUNDS);
    /* lengths */
    CHECK_EQ(tdev_cmd(&t, 0x60, two, 2), WSG_E_CMD_FORMAT_ERROR);
    CHECK_EQ(tdev_cmd(&t, 0x63, two, 2), WSG_E_CMD_FORMAT_ERROR);
    CHECK_EQ(tdev_cmd(&t, 0x70, idx, 1), WSG_E_NO_PARAM_EXPECTED);
    CHECK_EQ(tdev_cmd(&t, 0x71, idx, 1), WSG_E_NO_PARAM_EXPECTED);
    CHECK_EQ(tdev_cmd(&t, 0x73, idx, 1), WSG_E_NO_PARAM_EXPECTED);
    CHECK_EQ(tdev_cmd(&t, 0x62, NULL, 0), WSG_E_CMD_FORMAT_ERROR);
    CHECK_EQ(tdev_cmd(&t, 0x72, two, 2), WSG_E_CMD_FORMAT_ERROR);
    /* flags: powered, nothing else, for a generic finger */
    CHECK_EQ(tdev_cmd(&t, 0x61, NULL, 0), WSG_E_SUCCESS);
    CHECK_EQ(tdev_last(&t)->plen, 2);
    CHECK_EQ(wsg_get_u16(tdev_last(&t)->params), WSG_FF_POWERED);
    /* a generic finger's data: none, as 60h says */
    CHECK_EQ(tdev_cmd(&t, 0x63, NULL, 0), WSG_E_SUCCESS);
    CHECK_EQ(tdev_last(&t)->plen, 0);

    set_kinds(&t, WSG_FINGER_FMF, WSG_FINGER_DSA);
    CHECK_EQ(tdev_cmd(&t, 0x60, NULL, 0), WSG_E_SUCCESS);
    CHECK_EQ(tdev_last(&t)->params[0], WSG_FINGER_TYPE_FMF);
    CHECK_EQ(wsg_get_u16(tdev_last(&t)->params + 1), 4);
    CHECK_EQ(tdev_cmd(&t, 0x70, NULL, 0), WSG_E_SUCCESS);
    CHECK_EQ(tdev_last(&t)->params[0], WSG_FINGER_TYPE_DSA);
    CHECK_EQ(wsg_get_u16(tdev_last(&t)->params + 1), 168);
    CHECK_EQ(tdev_cmd(&t, 0x60, &idx[1], 1), WSG_E_SUCCESS);
    CHECK_EQ(tdev_last(&t)->params[0], WSG_FINGER_TYPE_DSA);
    CHECK_EQ(tdev_cmd(&t, 0x63, NULL, 0), WSG_E_SUCCESS);
    CHECK_EQ(tdev_last(&t)->plen, 4);
    CHECK_EQ(tdev_cmd(&t, 0x73, NULL, 0), WSG_E_SUCCESS);
    CHECK_EQ(tdev_last(&t)->plen, 168);
    CHECK_EQ(tdev_cmd(&t, 0x63, &idx[1], 1), WSG_E_SUCCESS);
    CHECK_EQ(tdev_last(&t)->plen, 168);
    CHECK_EQ(tdev_cmd(&t, 0x61, NULL, 0), WSG_E_SUCCESS);
    CHECK_EQ(wsg_get_u16(tdev_last(&t)->params), WSG_FF_POWERED | WSG_FF_DATA);
}

static void test_missing_and_power(void)
{
    struct tdev t;
    uint8_t off = 0, on = 1, two = 2, p[2];

    tdev_init(&t);
    set_kinds(&t, WSG_FINGER_NONE, WSG_FINGER_FMF);
    /* no finger: 60h says so, the others answer E_NO_SENSOR */
    CHECK_EQ(tdev_cmd(&t, 0x60, NULL, 0), WSG_E_SUCCESS);
    CHECK_EQ(tdev_last(&t)->params[0], WSG_FINGER_TYPE_NONE);
    CHECK_EQ(wsg_get_u16(tdev_last(&t)->params + 1), 0);
    CHECK_EQ(tdev_cmd(&t, 0x61, NULL, 0), WSG_E_SUCCESS);
    CHECK_EQ(wsg_get_u16(tdev_last(&t)->params), 0);
    CHECK_EQ(tdev_cmd(&t, 0x63, NULL, 0), WSG_E_NO_SENSOR);
    CHECK_EQ(tdev_cmd(&t, 0x62, &on, 1), WSG_E_NO_SENSOR);
    /* power off (4.x), read: E_NOT_AVAILABLE at once (settled after the
     * answer), flags without D0 */
    CHECK_EQ(tdev_cmd(&t, 0x72, &off, 1), WSG_E_SUCCESS);
    CHECK_EQ(tdev_last(&t)->plen, 0);
    CHECK_EQ(tdev_cmd(&t, 0x73, NULL, 0), WSG_E_NOT_AVAILABLE);
    CHECK_EQ(tdev_cmd(&t, 0x71, NULL, 0), WSG_E_SUCCESS);
    CHECK_EQ(wsg_get_u16(tdev_last(&t)->params) & WSG_FF_POWERED, 0);
    CHECK_EQ(tdev_cmd(&t, 0x72, &two, 1), WSG_E_INVALID_PARAMETER);
    CHECK_EQ(tdev_cmd(&t, 0x72, &on, 1), WSG_E_SUCCESS);
    CHECK_EQ(tdev_cmd(&t, 0x73, NULL, 0), WSG_E_SUCCESS);
    /* older clients: index, on/off */
    p[0] = 1;
    p[1] = 0;
    CHECK_EQ(tdev_cmd(&t, 0x62, p, 2), WSG_E_SUCCESS);
    CHECK_EQ(tdev_cmd(&t, 0x63, &idx[1], 1), WSG_E_NOT_AVAILABLE);
    p[1] = 7;
    CHECK_EQ(tdev_cmd(&t, 0x62, p, 2), WSG_E_INVALID_PARAMETER);
    p[0] = 2;
    p[1] = 1;
    CHECK_EQ(tdev_cmd(&t, 0x62, p, 2), WSG_E_INDEX_OUT_OF_BOUNDS);
    p[0] = 1;
    CHECK_EQ(tdev_cmd(&t, 0x62, p, 2), WSG_E_SUCCESS);
    CHECK_EQ(tdev_cmd(&t, 0x63, &idx[1], 1), WSG_E_SUCCESS);
    /* a finger fault (injected): E_READ_ERROR, D2 of the flags */
    wsg_axis_set_fault(tdev_axis(&t), WSG_SF_FINGER_FAULT, 1);
    CHECK_EQ(tdev_cmd(&t, 0x73, NULL, 0), WSG_E_READ_ERROR);
    CHECK_EQ(tdev_cmd(&t, 0x71, NULL, 0), WSG_E_SUCCESS);
    CHECK(wsg_get_u16(tdev_last(&t)->params) & WSG_FF_FAULT);
    wsg_axis_set_fault(tdev_axis(&t), WSG_SF_FINGER_FAULT, 0);
    CHECK_EQ(tdev_cmd(&t, 0x73, NULL, 0), WSG_E_SUCCESS);
    /* a power cycle of the gripper powers the fingers again */
    CHECK_EQ(tdev_cmd(&t, 0x72, &off, 1), WSG_E_SUCCESS);
    wsg_device_reset(&t.dev);
    CHECK_EQ(tdev_cmd(&t, 0x73, NULL, 0), WSG_E_SUCCESS);
}

static float fmf_of(struct tdev *t, uint8_t id)
{
    REQUIRE(tdev_cmd(t, id, NULL, 0) == WSG_E_SUCCESS);
    REQUIRE(tdev_last(t)->plen == 4);
    return wsg_get_f32(tdev_last(t)->params);
}

static void test_fmf(void)
{
    struct tdev t;

    tdev_init(&t);
    set_kinds(&t, WSG_FINGER_FMF, WSG_FINGER_FMF);
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_TARE, NULL, 0), WSG_E_SUCCESS);
    CHECK(fmf_of(&t, 0x63) == 0.0f);
    hold(&t, 40.0f);
    /* each finger feels the grip force, which 45h reports */
    CHECK_NEAR(fmf_of(&t, 0x63), 40.0, 1e-4);
    CHECK_NEAR(fmf_of(&t, 0x73), 40.0, 1e-4);
    CHECK(fmf_of(&t, 0x63) == (float)wsg_axis_force(tdev_axis(&t)));
    CHECK(tdev_flags(&t) & WSG_SF_FORCECNTL_MODE);
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_TARE, NULL, 0), WSG_E_ACCESS_DENIED);
    CHECK_EQ(tdev_cmd(&t, 0x61, NULL, 0), WSG_E_SUCCESS);
    CHECK(wsg_get_u16(tdev_last(&t)->params) & WSG_FF_CONTACT);
    /* the part taken away: nothing on the pads after the next step */
    wsg_axis_set_part(tdev_axis(&t), -1.0, 0);
    tdev_steps(&t, 1);
    CHECK(fmf_of(&t, 0x63) == 0.0f);
}

static void test_fmf_tare(void)
{
    struct tdev t;
    uint8_t p[9];

    tdev_init(&t);
    set_kinds(&t, WSG_FINGER_FMF, WSG_FINGER_GENERIC);
    CHECK_EQ(tdev_home(&t, 0), WSG_E_SUCCESS);
    /* a preposition into a part without stop on block presses on it out
     * of force control: tare takes that force as its zero */
    wsg_axis_set_part(tdev_axis(&t), 50.0, 0);
    p[0] = 0;
    wsg_put_f32(p + 1, 20.0f);
    wsg_put_f32(p + 5, 100.0f);
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_PREPOSITION, p, 9), WSG_E_CMD_PENDING);
    tdev_final(&t, WSG_CMD_PREPOSITION, 4000);
    tdev_steps(&t, 5);
    REQUIRE(wsg_axis_force(tdev_axis(&t)) > 1.0);
    CHECK(!(tdev_flags(&t) & WSG_SF_FORCECNTL_MODE));
    CHECK(fmf_of(&t, 0x63) > 1.0f);
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_TARE, NULL, 0), WSG_E_SUCCESS);
    CHECK(fmf_of(&t, 0x63) == 0.0f);
    /* taken off the pad: minus what was tared */
    wsg_axis_set_part(tdev_axis(&t), -1.0, 0);
    tdev_steps(&t, 1);
    CHECK(fmf_of(&t, 0x63) < -1.0f);
    /* a generic finger has nothing to tare; none fitted: not available */
    set_kinds(&t, WSG_FINGER_GENERIC, WSG_FINGER_DSA);
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_TARE, NULL, 0), WSG_E_NOT_AVAILABLE);
}

static void dsa_of(struct tdev *t, uint8_t id, uint16_t *cells)
{
    int k;

    REQUIRE(tdev_cmd(t, id, NULL, 0) == WSG_E_SUCCESS);
    REQUIRE(tdev_last(t)->plen == 168);
    for (k = 0; k < WSG_DSA_CELLS; k++)
        cells[k] = wsg_get_u16(tdev_last(t)->params + 2 * k);
}

static void test_dsa(void)
{
    struct tdev t;
    uint16_t c[WSG_DSA_CELLS], c2[WSG_DSA_CELLS];
    double sum = 0.0;
    int k, r, col;

    tdev_init(&t);
    set_kinds(&t, WSG_FINGER_DSA, WSG_FINGER_DSA);
    dsa_of(&t, 0x63, c);
    for (k = 0; k < WSG_DSA_CELLS; k++)
        CHECK_EQ(c[k], 0); /* nothing held */
    hold(&t, 20.0f);
    dsa_of(&t, 0x63, c);
    dsa_of(&t, 0x73, c2);
    CHECK(memcmp(c, c2, sizeof c) == 0);
    /* the default 10 x 10 mm patch, centred: columns 1..4 (x -5..5 over
     * cells of 3.4 mm from -10.2), rows 5..8 (y -5..5 from -23.8) */
    for (r = 0; r < WSG_DSA_ROWS; r++)
        for (col = 0; col < WSG_DSA_COLS; col++) {
            uint16_t v = c[r * WSG_DSA_COLS + col];
            int in = col >= 1 && col <= 4 && r >= 5 && r <= 8;

            CHECK(in ? v > 0 : v == 0);
            sum += v;
        }
    /* a fully covered cell carries 3.4^2 / 100 of the force */
    CHECK_EQ(c[6 * 6 + 2], (uint16_t)lround(20.0 * 11.56 / 100.0 * 389.5));
    /* symmetric, and all of it adds up to the force */
    CHECK_EQ(c[6 * 6 + 1], c[6 * 6 + 4]);
    CHECK_EQ(c[5 * 6 + 2], c[8 * 6 + 2]);
    CHECK_NEAR(sum / WSG_DSA_PER_N, 20.0, 0.05);
    /* more force, higher values */
    {
        uint8_t p[4];

        CHECK_EQ(tdev_cmd(&t, WSG_CMD_STOP, NULL, 0), WSG_E_SUCCESS);
        CHECK_EQ(tdev_cmd2f(&t, WSG_CMD_RELEASE, 70.0f, 100.0f),
                 WSG_E_CMD_PENDING);
        CHECK_EQ(tdev_final(&t, WSG_CMD_RELEASE, 4000), WSG_E_SUCCESS);
        dsa_of(&t, 0x63, c2);
        for (k = 0; k < WSG_DSA_CELLS; k++)
            CHECK_EQ(c2[k], 0); /* released */
        wsg_put_f32(p, 40.0f);
        CHECK_EQ(tdev_cmd(&t, WSG_CMD_SET_FORCE_LIMIT, p, 4), WSG_E_SUCCESS);
        CHECK_EQ(tdev_cmd2f(&t, WSG_CMD_GRASP, 50.0f, 100.0f),
                 WSG_E_CMD_PENDING);
        CHECK_EQ(tdev_final(&t, WSG_CMD_GRASP, 4000), WSG_E_SUCCESS);
        dsa_of(&t, 0x63, c2);
        CHECK(c2[6 * 6 + 2] > c[6 * 6 + 2]);
    }
    /* a patch as big as the pad: every cell alike; bigger still saturates
     * nothing, as the force spreads over the pad only */
    wsg_axis_set_part_patch(tdev_axis(&t), 20.4, 47.6);
    tdev_steps(&t, 1);
    dsa_of(&t, 0x63, c);
    for (k = 1; k < WSG_DSA_CELLS; k++)
        CHECK_EQ(c[k], c[0]);
    CHECK(c[0] > 0);
    /* a small patch under a big force saturates at 3895 */
    wsg_axis_set_part_patch(tdev_axis(&t), 1.0, 1.0);
    tdev_steps(&t, 1);
    dsa_of(&t, 0x63, c);
    CHECK_EQ(c[6 * 6 + 3], WSG_DSA_MAX);
}

/* A device's electronics for the tests: echo what arrives over the UART,
 * record it with the time, answer SPI with tx + 1, and fail on demand. */
struct echo {
    struct wsg_fingers *fs;
    uint8_t got[64];
    uint64_t at[64];
    size_t n;
    int fail, powered;
};

static int echo_power(void *ctx, int i, int on)
{
    struct echo *e = ctx;

    (void)i;
    e->powered = on;
    return 0;
}

static int echo_uart(void *ctx, int i, const uint8_t *p, size_t n)
{
    struct echo *e = ctx;
    size_t k;

    if (e->fail)
        return -1;
    for (k = 0; k < n && e->n < sizeof e->got; k++) {
        e->at[e->n] = e->fs->now_ns;
        e->got[e->n++] = p[k];
    }
    wsg_finger_device_send(e->fs, i, p, n);
    return 0;
}

static int echo_spi(void *ctx, int i, const uint8_t *tx, uint8_t *rx, size_t n)
{
    struct echo *e = ctx;
    size_t k;

    (void)i;
    if (e->fail)
        return -1;
    for (k = 0; k < n; k++)
        rx[k] = (uint8_t)(tx[k] + 1);
    return 0;
}

static int echo_data(void *ctx, int i, uint8_t *out, size_t cap)
{
    struct echo *e = ctx;

    (void)i;
    if (e->fail)
        return -1;
    out[0] = 0xAB;
    return cap > 1 ? 1 : (int)cap; /* short: the rest is zeros */
}

static const struct wsg_finger_link echo_link = {echo_power, echo_uart,
                                                 echo_spi, echo_data};

static void test_device_uart(void)
{
    struct tdev t;
    struct echo e;
    struct wsg_fingers *fs;
    uint8_t buf[16], off = 0, on = 1;
    int k;

    tdev_init(&t);
    fs = &t.dev.fingers;
    memset(&e, 0, sizeof e);
    e.fs = fs;
    wsg_finger_attach(fs, 0, &echo_link, &e, 4);
    settle(&t);
    CHECK_EQ(fs->f[0].kind, WSG_FINGER_DEVICE);
    CHECK_EQ(e.powered, 1);
    /* a generic finger to 60h, with the device's size */
    CHECK_EQ(tdev_cmd(&t, 0x60, NULL, 0), WSG_E_SUCCESS);
    CHECK_EQ(tdev_last(&t)->params[0], WSG_FINGER_TYPE_GENERIC);
    CHECK_EQ(wsg_get_u16(tdev_last(&t)->params + 1), 4);
    CHECK_EQ(tdev_cmd(&t, 0x63, NULL, 0), WSG_E_SUCCESS);
    CHECK_EQ(tdev_last(&t)->plen, 4);
    CHECK_EQ(tdev_last(&t)->params[0], 0xAB);
    CHECK_EQ(tdev_last(&t)->params[3], 0);
    /* no UART set up: nothing goes */
    CHECK_EQ(wsg_finger_write(fs, 0, (const uint8_t *)"abc", 3), 0);
    CHECK_EQ(wsg_finger_set_uart(fs, 0, 9600), 0);
    CHECK(wsg_finger_set_uart(fs, 0, 10) < 0);
    CHECK_EQ(fs->f[0].byte_ns, 1041667u);
    /* 9600 baud: a byte every 1.041667 ms; 1 ms steps */
    CHECK_EQ(wsg_finger_write(fs, 0, (const uint8_t *)"hello", 5), 5);
    CHECK(!wsg_device_idle(&t.dev));
    CHECK_EQ(wsg_device_next(&t.dev), 1);
    for (k = 1; k <= 5; k++) {
        tdev_steps(&t, 1);
        /* after step k, floor(k ms / byte time) bytes reached the finger */
        CHECK_EQ(e.n, (size_t)(k * 1000000ull / 1041667u));
    }
    tdev_steps(&t, 1);
    CHECK_EQ(e.n, 5);
    CHECK(memcmp(e.got, "hello", 5) == 0);
    /* the byte's time: when it arrived, at the step after */
    CHECK_EQ(e.at[0], 2000000u);
    /* the echo goes back the same way: a byte time after each arrived */
    CHECK_EQ(wsg_finger_available(fs, 0), 3);
    tdev_steps(&t, 6);
    CHECK_EQ(wsg_finger_available(fs, 0), 5);
    CHECK(wsg_device_idle(&t.dev));
    CHECK_EQ(wsg_finger_read(fs, 0, buf, 2), 2);
    CHECK(memcmp(buf, "he", 2) == 0);
    CHECK_EQ(wsg_finger_read(fs, 0, buf, sizeof buf), 3);
    CHECK(memcmp(buf, "llo", 3) == 0);
    CHECK_EQ(wsg_finger_available(fs, 0), 0);
    /* flags: UART */
    CHECK_EQ(tdev_cmd(&t, 0x61, NULL, 0), WSG_E_SUCCESS);
    CHECK(wsg_get_u16(tdev_last(&t)->params) & WSG_FF_UART);
    /* power off: the electronics are told, the wire is quiet */
    CHECK_EQ(tdev_cmd(&t, 0x62, &off, 1), WSG_E_SUCCESS);
    CHECK_EQ(e.powered, 0);
    CHECK_EQ(wsg_finger_write(fs, 0, (const uint8_t *)"x", 1), 0);
    CHECK_EQ(tdev_cmd(&t, 0x62, &on, 1), WSG_E_SUCCESS);
    CHECK_EQ(e.powered, 1);
    /* electronics that fail: D17 and E_READ_ERROR until a power cycle */
    e.fail = 1;
    CHECK_EQ(wsg_finger_write(fs, 0, (const uint8_t *)"x", 1), 1);
    tdev_steps(&t, 2);
    CHECK(tdev_flags(&t) & WSG_SF_FINGER_FAULT);
    CHECK_EQ(tdev_cmd(&t, 0x63, NULL, 0), WSG_E_READ_ERROR);
    e.fail = 0;
    CHECK_EQ(tdev_cmd(&t, 0x62, &off, 1), WSG_E_SUCCESS);
    CHECK_EQ(tdev_cmd(&t, 0x62, &on, 1), WSG_E_SUCCESS);
    CHECK(!(tdev_flags(&t) & WSG_SF_FINGER_FAULT));
    CHECK_EQ(tdev_cmd(&t, 0x63, NULL, 0), WSG_E_SUCCESS);
}

static void test_device_spi(void)
{
    struct tdev t;
    struct echo e;
    struct wsg_fingers *fs;
    uint8_t tx[3] = {1, 2, 41}, rx[3];

    tdev_init(&t);
    fs = &t.dev.fingers;
    memset(&e, 0, sizeof e);
    e.fs = fs;
    wsg_finger_attach(fs, 1, &echo_link, &e, 0);
    settle(&t);
    CHECK_EQ(wsg_finger_spi(fs, 1, tx, rx, 3), WSG_E_NOT_AVAILABLE);
    CHECK(wsg_finger_set_spi(fs, 1, 100, 8, 0) < 0);
    CHECK(wsg_finger_set_spi(fs, 1, 1000000, 8, 4) < 0);
    CHECK_EQ(wsg_finger_set_spi(fs, 1, 1000000, 8, 0), 0);
    CHECK_EQ(wsg_finger_spi(fs, 1, tx, rx, 3), WSG_E_SUCCESS);
    CHECK_EQ(rx[0], 2);
    CHECK_EQ(rx[2], 42);
    /* a finger without electronics: the idle line */
    CHECK_EQ(wsg_finger_set_spi(fs, 0, 1000000, 8, 0), 0);
    CHECK_EQ(wsg_finger_spi(fs, 0, tx, rx, 3), WSG_E_SUCCESS);
    CHECK_EQ(rx[1], 0xFF);
    e.fail = 1;
    CHECK_EQ(wsg_finger_spi(fs, 1, tx, rx, 3), WSG_E_READ_ERROR);
    CHECK(tdev_flags(&t) & WSG_SF_FINGER_FAULT);
    /* a kind set over it detaches the electronics */
    set_kinds(&t, WSG_FINGER_GENERIC, WSG_FINGER_GENERIC);
    CHECK(!(tdev_flags(&t) & WSG_SF_FINGER_FAULT));
    CHECK(fs->f[1].link == NULL);
}

int main(void)
{
    test_info_both_styles();
    test_missing_and_power();
    test_fmf();
    test_fmf_tare();
    test_dsa();
    test_device_uart();
    test_device_spi();
    TEST_EXIT();
}
