/*
 * A device on a test bench: one gripper, sessions that capture what would
 * go on the wire, and a fake clock (the test calls the steps). Used by the
 * unit tests of the dispatcher and the model; no sockets, no real time.
 */
#ifndef WSG_TEST_TDEV_H
#define WSG_TEST_TDEV_H

#include <string.h>

#include "check.h"
#include "wsg/device.h"

#define TDEV_MAX_PKTS 64
#define TDEV_SESSIONS 2

struct tdev_pkt {
    uint8_t id;
    uint16_t status;
    size_t plen; /* parameter bytes after the status */
    uint8_t params[WSG_REPLY_PARAMS_MAX];
    size_t raw_len;
    uint8_t raw[WSG_FRAME_MAX];
    int reply; /* a command's immediate answer, not a final result */
};

struct tdev_sess {
    struct wsg_session s;
    struct wsg_parser parser;
    int n;          /* packets captured and not yet taken */
    int final_from; /* packets before this hold no final result not taken */
    struct tdev_pkt pkts[TDEV_MAX_PKTS];
};

struct tdev {
    struct wsg_device dev;
    struct tdev_sess sess[TDEV_SESSIONS];
};

/* The device's model, for the tests that look inside it (test_axis.c
 * includes its layout, axis_impl.h); the others use its getters. */
static inline struct wsg_axis *tdev_axis(struct tdev *t)
{
    return wsg_device_axis(&t->dev);
}

static inline void tdev_send(struct wsg_session *s, const uint8_t *pkt,
                             size_t len)
{
    struct tdev_sess *ts = s->ctx;
    struct tdev_pkt *p;

    REQUIRE(ts->n < TDEV_MAX_PKTS);
    REQUIRE(len >= WSG_HEADER_LEN + 2 + WSG_CRC_LEN);
    /* Every packet the emulator sends carries a valid checksum. */
    CHECK_EQ(wsg_crc_update(WSG_CRC_INIT, pkt, len), 0);
    p = &ts->pkts[ts->n++];
    p->id = pkt[3];
    p->status = wsg_get_u16(pkt + 6);
    p->plen = wsg_get_u16(pkt + 4) - 2u;
    memcpy(p->params, pkt + 8, p->plen);
    p->raw_len = len;
    memcpy(p->raw, pkt, len);
    p->reply = 0;
}

static inline struct wsg_session *tdev_lookup(void *ctx, uint32_t tag)
{
    struct tdev *t = ctx;
    int i;

    for (i = 0; i < TDEV_SESSIONS; i++)
        if (t->sess[i].s.tag == tag)
            return &t->sess[i].s;
    return NULL;
}

static inline void tdev_init_cfg(struct tdev *t,
                                 const struct wsg_axis_config *cfg)
{
    int i;

    memset(t, 0, sizeof *t);
    wsg_device_init(&t->dev, cfg);
    t->dev.lookup = tdev_lookup;
    t->dev.lookup_ctx = t;
    for (i = 0; i < TDEV_SESSIONS; i++) {
        wsg_session_init(&t->sess[i].s, (uint32_t)i + 1,
                         WSG_SESSION_CONNECTION, tdev_send, &t->sess[i]);
        wsg_parser_init(&t->sess[i].parser, 1);
    }
}

static inline void tdev_init(struct tdev *t)
{
    struct wsg_axis_config cfg;

    REQUIRE(wsg_axis_config_init(&cfg, "wsg50") == 0);
    tdev_init_cfg(t, &cfg);
}

/* Raw bytes into session i. */
static inline void tdev_feed(struct tdev *t, int i, const uint8_t *data,
                             size_t len)
{
    wsg_device_input(&t->dev, &t->sess[i].s, &t->sess[i].parser, data, len);
}

/* Send a command from session i; returns the status of its first reply. */
static inline uint16_t tdev_cmd_on(struct tdev *t, int i, uint8_t id,
                                   const void *payload, size_t len)
{
    uint8_t pkt[WSG_HEADER_LEN + 512 + WSG_CRC_LEN];
    size_t n = wsg_frame_encode(pkt, sizeof pkt, id, payload, len);
    int before = t->sess[i].n;

    REQUIRE(n > 0);
    tdev_feed(t, i, pkt, n);
    /* Exactly one answer, first; what may follow it at once are final
     * results the command caused (a Stop ends this session's motion). */
    REQUIRE(t->sess[i].n >= before + 1);
    CHECK_EQ(t->sess[i].pkts[before].id, id);
    t->sess[i].pkts[before].reply = 1;
    for (n = (size_t)before + 1; n < (size_t)t->sess[i].n; n++) {
        uint8_t m = t->sess[i].pkts[n].id;
        CHECK(m == WSG_CMD_HOMING || m == WSG_CMD_PREPOSITION ||
              m == WSG_CMD_GRASP || m == WSG_CMD_RELEASE);
        CHECK(t->sess[i].pkts[n].status != WSG_E_CMD_PENDING);
    }
    return t->sess[i].pkts[before].status;
}

static inline uint16_t tdev_cmd(struct tdev *t, uint8_t id,
                                const void *payload, size_t len)
{
    return tdev_cmd_on(t, 0, id, payload, len);
}

/* The last packet session 0 received. */
static inline struct tdev_pkt *tdev_last(struct tdev *t)
{
    REQUIRE(t->sess[0].n > 0);
    return &t->sess[0].pkts[t->sess[0].n - 1];
}

static inline void tdev_clear(struct tdev *t)
{
    int i;

    for (i = 0; i < TDEV_SESSIONS; i++)
        t->sess[i].n = t->sess[i].final_from = 0;
}

/* Step until session i receives a packet with this ID; returns the number
 * of steps taken, or -1 after max_steps. */
static inline long tdev_run_until(struct tdev *t, int i, uint8_t id,
                                  long max_steps)
{
    long k;
    int seen = t->sess[i].n, j;

    for (k = 1; k <= max_steps; k++) {
        wsg_device_step(&t->dev);
        for (j = seen; j < t->sess[i].n; j++)
            if (t->sess[i].pkts[j].id == id)
                return k;
        seen = t->sess[i].n;
    }
    return -1;
}

static inline void tdev_steps(struct tdev *t, long n)
{
    while (n-- > 0)
        wsg_device_step(&t->dev);
}

/* The first final result of the motion command id not taken yet: already
 * sent (a Stop ends a motion at once), or after up to max_steps steps. */
static inline uint16_t tdev_final(struct tdev *t, uint8_t id, long max_steps)
{
    struct tdev_sess *ts = &t->sess[0];
    long k;
    int j;

    for (k = 0;; k++) {
        for (j = ts->final_from; j < ts->n; j++) {
            if (ts->pkts[j].id == id && !ts->pkts[j].reply) {
                ts->final_from = j + 1;
                return ts->pkts[j].status;
            }
        }
        REQUIRE(k < max_steps);
        wsg_device_step(&t->dev);
    }
}

static inline uint16_t tdev_home(struct tdev *t, uint8_t dir)
{
    REQUIRE(tdev_cmd(t, WSG_CMD_HOMING, &dir, 1) == WSG_E_CMD_PENDING);
    return tdev_final(t, WSG_CMD_HOMING, 10000);
}

static inline uint16_t tdev_move(struct tdev *t, uint8_t flags, float width,
                                 float speed)
{
    uint8_t p[9];

    p[0] = flags;
    wsg_put_f32(p + 1, width);
    wsg_put_f32(p + 5, speed);
    return tdev_cmd(t, WSG_CMD_PREPOSITION, p, sizeof p);
}

static inline uint16_t tdev_cmd2f(struct tdev *t, uint8_t id, float a, float b)
{
    uint8_t p[8];

    wsg_put_f32(p, a);
    wsg_put_f32(p + 4, b);
    return tdev_cmd(t, id, p, sizeof p);
}

static inline uint16_t tdev_cmd1f(struct tdev *t, uint8_t id, float a)
{
    uint8_t p[4];

    wsg_put_f32(p, a);
    return tdev_cmd(t, id, p, sizeof p);
}

/* A float returned by a query command. */
static inline float tdev_getf(struct tdev *t, uint8_t id)
{
    REQUIRE(tdev_cmd(t, id, NULL, 0) == WSG_E_SUCCESS);
    REQUIRE(tdev_last(t)->plen >= 4);
    return wsg_get_f32(tdev_last(t)->params);
}

static inline uint32_t tdev_flags(struct tdev *t)
{
    REQUIRE(tdev_cmd(t, WSG_CMD_GET_SYSTEM_STATE, NULL, 0) == WSG_E_SUCCESS);
    return wsg_get_u32(tdev_last(t)->params);
}

static inline uint8_t tdev_grasp_state(struct tdev *t)
{
    REQUIRE(tdev_cmd(t, WSG_CMD_GET_GRASP_STATE, NULL, 0) == WSG_E_SUCCESS);
    return tdev_last(t)->params[0];
}

#endif
