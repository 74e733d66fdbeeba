/*
 * The fuzz bench: a gripper, two sessions, and every invariant the harnesses
 * check. See fuzz_bench.h for the input's shape.
 *
 * How answers are counted: the device reports every parser event (frame,
 * checksum error, oversize) through trace_in before it answers it, so the
 * bench checks that each event got exactly one packet, with the event's ID,
 * before the next event or the end of the chunk. Final results of motion
 * commands leave the model through the device's lookup callback, which the
 * bench provides: each call is one final result (sent if the session is
 * still there, dropped if it was closed), matched against the E_CMD_PENDING
 * answers given under that session's tag. Stream packets are recognised by
 * the phase they are sent in (the bench polls streams after each step).
 * Which commands have final results or streams, and the parameters every
 * successful answer must have, are the schema's (wsg/schema.h).
 *
 * The bench is one static object: libFuzzer runs one input at a time, and
 * fuzz_bench_begin resets all of it.
 */
#include "fuzz_bench.h"
#include "fuzz_axis.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "axis_impl.h"
#include "fuzz_check.h"
#include "wsg/device.h"

/* Tags are unique per run; a closed session's peer gets a fresh one. */
#define FUZZ_TAGS 4096u
/* At the end: a full stroke of the longest model at the lowest speed is
 * 42 s of 1 ms steps; motions that are still running after this never end. */
#define FUZZ_END_STEPS 100000L
/* Floating-point slack for limits the model clamps to. */

enum fuzz_phase {
    FUZZ_PH_IDLE,  /* nothing may be sent */
    FUZZ_PH_INPUT, /* immediate answers to received bytes */
    FUZZ_PH_STEP,  /* final results of motion commands */
    FUZZ_PH_STREAM /* auto-update packets */
};

struct fuzz_sess {
    struct wsg_session s;
    struct wsg_parser parser;
    int closing; /* being closed: its tag resolves no more, as in a
                    transport */
};

static struct {
    struct wsg_device dev;
    struct fuzz_sess sess[2];
    int check_crc;
    enum fuzz_phase phase;
    struct fuzz_sess *cur; /* the session being fed */
    int datagram;          /* the chunk is one datagram */
    int tail_sent;         /* its cut-off packet was answered */
    /* The parser event waiting for its answer. */
    int event;
    enum wsg_parse_event event_ev;
    uint8_t event_id;
    unsigned answers;
    /* The final result looked up and not sent yet. */
    struct wsg_session *final_sess;
    uint32_t next_tag;
    int32_t owed[FUZZ_TAGS]; /* E_CMD_PENDING answers minus final results */
    int trace;               /* FUZZ_TRACE set: print every event and packet */
} B;

/* What the schema says of the command: final results come only for
 * asynchronous ones, stream packets only for those that stream. */
static int fuzz_is_motion(uint8_t id)
{
    return (wsg_schema[id].flags & WSG_CMDF_ASYNC) != 0;
}

static int fuzz_is_stream(uint8_t id)
{
    return (wsg_schema[id].flags & WSG_CMDF_STREAM) != 0;
}

/* Parameters are the reply layout of the ID. */
static int fuzz_reply_fits(uint8_t id, size_t plen)
{
    return wsg_layout_fits(&wsg_schema[id].reply, plen);
}

/* Flag combinations the manual rules out, in any reported state word. */
static void fuzz_check_flags(uint32_t f)
{
    const struct wsg_axis *ax = wsg_device_axis(&B.dev);

    FUZZ_CHECK((f & ~(uint32_t)WSG_SF_ALL) == 0);
    /* FAST STOP halts the axis in the step that applies it. Between its
     * request and that step the flags already show it (they report what
     * the commands see) while the fingers still move. */
    FUZZ_CHECK(!((f & WSG_SF_MOVING) && (f & WSG_SF_FAST_STOP)) ||
               ax->req_fast_stop);
    FUZZ_CHECK(!(f & (WSG_SF_SOFT_LIMIT_MINUS | WSG_SF_SOFT_LIMIT_PLUS)) ||
               ax->soft_limits);
    /* D9 comes from the force measurement fingers fitted now. */
    FUZZ_CHECK(!(f & WSG_SF_FORCECNTL_MODE) ||
               wsg_fingers_fmf(&B.dev.fingers));
    /* The emulator runs no scripts. */
    FUZZ_CHECK(!(f & (WSG_SF_SCRIPT_RUNNING | WSG_SF_SCRIPT_FAILURE)));
}

/* The model within its limits (fuzz_axis.h), its grasping state and its
 * flags. */
static void fuzz_check_model(void)
{
    const struct wsg_axis *ax = wsg_device_axis(&B.dev);

    fuzz_check_axis(ax);
    FUZZ_CHECK((unsigned)ax->grasp_state <= WSG_GS_ERROR);
    fuzz_check_flags(wsg_device_flags(&B.dev));
}

static void fuzz_trace_in(void *ctx, const struct wsg_session *s,
                          const struct wsg_frame *f, enum wsg_parse_event ev)
{
    (void)ctx;
    FUZZ_CHECK(B.phase == FUZZ_PH_INPUT && s == &B.cur->s);
    /* The previous event was answered exactly once, and a datagram's
     * cut-off packet is only answered after its last whole one. */
    FUZZ_CHECK(!B.event || B.answers == 1);
    FUZZ_CHECK(!B.tail_sent);
    FUZZ_CHECK(ev == WSG_PARSE_FRAME || ev == WSG_PARSE_BAD_CRC ||
               ev == WSG_PARSE_OVERSIZE);
    /* The parser never delivers more than the largest request. */
    FUZZ_CHECK(ev != WSG_PARSE_FRAME || f->len <= WSG_PAYLOAD_MAX);
    if (B.trace)
        fprintf(stderr, "t=%lu in  s%u ev%d id %02x len %u\n",
                (unsigned long)wsg_device_axis(&B.dev)->time_us,
                (unsigned)s->tag, (int)ev, f->id, (unsigned)f->len);
    B.event = 1;
    B.event_ev = ev;
    B.event_id = f->id;
    B.answers = 0;
}

/* An immediate answer to the parser event it follows. */
static void fuzz_answer(struct wsg_session *s, uint8_t id, uint16_t status,
                        size_t plen, const uint8_t *params)
{
    FUZZ_CHECK(s == &B.cur->s);
    if (!B.event || B.answers == 1) {
        /* Only a datagram's cut-off packet is answered without an event of
         * its own, once, as a format error. */
        FUZZ_CHECK(B.datagram && !B.tail_sent);
        FUZZ_CHECK(status == WSG_E_CMD_FORMAT_ERROR && plen == 0);
        B.tail_sent = 1;
        return;
    }
    B.answers++;
    FUZZ_CHECK(id == B.event_id);
    if (B.event_ev == WSG_PARSE_BAD_CRC)
        FUZZ_CHECK(status == WSG_E_CHECKSUM_ERROR);
    if (B.event_ev == WSG_PARSE_OVERSIZE)
        FUZZ_CHECK(status == WSG_E_CMD_FORMAT_ERROR);
    if (status == WSG_E_CMD_PENDING) {
        FUZZ_CHECK(fuzz_is_motion(id) && s->tag < FUZZ_TAGS);
        B.owed[s->tag]++;
    }
    if (status == WSG_E_SUCCESS) {
        FUZZ_CHECK(fuzz_reply_fits(id, plen));
        if (id == WSG_CMD_GET_SYSTEM_STATE)
            fuzz_check_flags(wsg_get_u32(params));
    }
}

static void fuzz_send(struct wsg_session *s, const uint8_t *pkt, size_t len)
{
    size_t plen;
    uint16_t status;
    uint8_t id;

    /* Every packet: whole, a valid checksum, a known status, parameters
     * only with E_SUCCESS. */
    FUZZ_CHECK(len >= WSG_HEADER_LEN + 2u + WSG_CRC_LEN);
    FUZZ_CHECK(len <= WSG_FRAME_MAX);
    FUZZ_CHECK(pkt[0] == WSG_PREAMBLE_BYTE && pkt[1] == WSG_PREAMBLE_BYTE &&
               pkt[2] == WSG_PREAMBLE_BYTE);
    FUZZ_CHECK(wsg_get_u16(pkt + 4) == len - WSG_HEADER_LEN - WSG_CRC_LEN);
    FUZZ_CHECK(wsg_crc_update(WSG_CRC_INIT, pkt, len) == 0);
    id = pkt[3];
    status = wsg_get_u16(pkt + 6);
    plen = len - WSG_HEADER_LEN - 2u - WSG_CRC_LEN;
    FUZZ_CHECK(status <= WSG_E_FILE_EXISTS);
    FUZZ_CHECK(plen == 0 || status == WSG_E_SUCCESS);
    if (B.trace)
        fprintf(stderr, "t=%lu out s%u ph%d id %02x %s\n",
                (unsigned long)wsg_device_axis(&B.dev)->time_us,
                (unsigned)s->tag, (int)B.phase, id, wsg_status_name(status));

    /* A final result the model just handed to lookup: from a step, or
     * settled around a received command (a Stop ends a motion, a command
     * lets a closed connection's FAST STOP through). */
    if (B.final_sess &&
        (B.phase == FUZZ_PH_STEP || B.phase == FUZZ_PH_INPUT)) {
        FUZZ_CHECK(s == B.final_sess);
        FUZZ_CHECK(fuzz_is_motion(id) && status != WSG_E_CMD_PENDING);
        FUZZ_CHECK(plen == 0);
        B.final_sess = NULL;
        return;
    }
    switch (B.phase) {
    case FUZZ_PH_INPUT:
        fuzz_answer(s, id, status, plen, pkt + 8);
        break;
    case FUZZ_PH_STREAM:
        FUZZ_CHECK(fuzz_is_stream(id) && status == WSG_E_SUCCESS);
        FUZZ_CHECK(fuzz_reply_fits(id, plen));
        if (id == WSG_CMD_GET_SYSTEM_STATE)
            fuzz_check_flags(wsg_get_u32(pkt + 8));
        break;
    default:
        abort();
    }
}

static struct wsg_session *fuzz_lookup(void *ctx, uint32_t tag)
{
    int i;

    (void)ctx;
    /* Final results come one at a time, only for a command that was
     * answered E_CMD_PENDING under this tag, from a step or from the
     * settling around a received command (never between commands). */
    FUZZ_CHECK(B.phase == FUZZ_PH_STEP ||
               (B.phase == FUZZ_PH_INPUT && B.event));
    FUZZ_CHECK(!B.final_sess);
    FUZZ_CHECK(tag < FUZZ_TAGS && B.owed[tag] > 0);
    B.owed[tag]--;
    if (B.trace)
        fprintf(stderr, "t=%lu final for tag %u: width %g ref_offset %g\n",
                (unsigned long)wsg_device_axis(&B.dev)->time_us, (unsigned)tag,
                wsg_device_axis(&B.dev)->width,
                wsg_device_axis(&B.dev)->ref_offset);
    for (i = 0; i < 2; i++)
        if (B.sess[i].s.tag == tag && !B.sess[i].closing) {
            B.final_sess = &B.sess[i].s;
            return B.final_sess;
        }
    return NULL; /* the peer is gone: the result is dropped */
}

/* Session 0 is a connection (TCP: Disconnect and close matter), session 1
 * a datagram peer (UDP), so both kinds of Disconnect answer are reached. */
static void fuzz_session_open(int i, uint32_t tag)
{
    wsg_session_init(&B.sess[i].s, tag, i == 0 ? WSG_SESSION_CONNECTION : 0,
                     fuzz_send, &B.sess[i]);
    wsg_parser_init(&B.sess[i].parser, B.check_crc);
    B.sess[i].closing = 0;
}

void fuzz_bench_begin(uint8_t cfg)
{
    static const char *const models[] = {"wsg50", "wsg50-210", "wsg32",
                                         "wsg25"};
    struct wsg_axis_config c;

    memset(&B, 0, sizeof B);
    FUZZ_CHECK(wsg_axis_config_init(&c, models[cfg & 3u]) == 0);
    c.force_sensor = (cfg >> 2) & 1u;
    B.check_crc = !((cfg >> 3) & 1u);
    wsg_device_init(&B.dev, &c);
    B.dev.trace_in = fuzz_trace_in;
    B.dev.lookup = fuzz_lookup;
    fuzz_session_open(0, 1);
    fuzz_session_open(1, 2);
    B.next_tag = 3;
    /* Read once per input: getenv on every packet would slow the fuzzer. */
    B.trace = getenv("FUZZ_TRACE") != NULL;
}

static void fuzz_step(void)
{
    int i;

    B.phase = FUZZ_PH_STEP;
    wsg_device_step(&B.dev);
    /* A final result looked up for a live session was sent. */
    FUZZ_CHECK(!B.final_sess);
    B.phase = FUZZ_PH_STREAM;
    for (i = 0; i < 2; i++)
        wsg_device_poll_streams(&B.dev, &B.sess[i].s);
    B.phase = FUZZ_PH_IDLE;
    fuzz_check_model();
}

/* A physical width in 0..max from one input byte. */
static double fuzz_width(const uint8_t *data, size_t len, double max)
{
    return (len ? data[0] : 128) / 255.0 * max;
}

/* The world event of a control byte's bits 4-7: values 0-8 are none, so
 * most chunks are plain traffic. */
static void fuzz_world(unsigned ev, const uint8_t *data, size_t len)
{
    static const uint32_t faults[] = {WSG_SF_TEMP_WARNING, WSG_SF_TEMP_FAULT,
                                      WSG_SF_POWER_FAULT, WSG_SF_CURR_FAULT,
                                      WSG_SF_FINGER_FAULT};
    struct wsg_axis *ax = wsg_device_axis(&B.dev);
    unsigned i;
    int k;

    if (B.trace && ev >= 9)
        fprintf(stderr, "t=%lu world %u (s%u) motion %d fast_stop %d\n",
                (unsigned long)ax->time_us, ev, (unsigned)B.cur->s.tag,
                (int)ax->motion.kind, ax->fast_stop);
    switch (ev) {
    case 10:
        /* A part, stiffness from the second byte (0: the default). It is
         * placed between the fingers, no wider than their opening: the
         * model takes a wider one as already squeezed past any force limit
         * (see the README's fuzzing notes). */
        wsg_axis_set_part(ax,
                          fuzz_width(data, len, ax->width - ax->ref_offset),
                          len > 1 ? data[1] : 0);
        break;
    case 11:
        wsg_axis_set_part(ax, -1, 0);
        break;
    case 12: /* faults: bits 0-4 select, bit 7 sets or clears */
        for (i = 0; i < 5; i++)
            if (len && (data[0] >> i) & 1u)
                wsg_axis_set_fault(ax, faults[i], data[0] >> 7);
        break;
    case 13:
        wsg_axis_set_obstacle(ax, fuzz_width(data, len, ax->cfg.stroke));
        break;
    case 14:
        wsg_axis_set_obstacle(ax, -1);
        break;
    case 15: /* the peer goes; a new one connects under a fresh tag */
        if (B.next_tag >= FUZZ_TAGS)
            break;
        k = (int)(B.cur - B.sess);
        B.cur->closing = 1;
        wsg_device_session_closed(&B.dev, &B.cur->s); /* settles itself */
        fuzz_session_open(k, B.next_tag++);
        return;
    default:
        return;
    }
    wsg_axis_settle(wsg_device_axis(&B.dev));
}

void fuzz_bench_chunk(uint8_t ctl, const uint8_t *data, size_t len)
{
    static const long steps[] = {0, 1, 2, 5, 10, 50, 200, 1000};
    unsigned ev = ctl >> 4;
    long n;

    B.cur = &B.sess[ctl & FUZZ_CTL_SESSION];
    B.datagram = ev == 9;
    B.tail_sent = 0;
    B.event = 0;
    B.answers = 0;
    B.phase = FUZZ_PH_INPUT;
    if (B.datagram)
        wsg_device_input_datagram(&B.dev, &B.cur->s, B.check_crc, data, len);
    else
        wsg_device_input(&B.dev, &B.cur->s, &B.cur->parser, data, len);
    /* The chunk's last event was answered too. */
    FUZZ_CHECK(!B.event || B.answers == 1);
    /* World events settle as the control channel does: a fault's
     * consequences (a motion aborted) may send final results. */
    B.phase = FUZZ_PH_STEP;
    fuzz_world(ev, data, len);
    FUZZ_CHECK(!B.final_sess);
    B.phase = FUZZ_PH_IDLE;
    for (n = steps[(ctl >> 1) & 7u]; n > 0; n--)
        fuzz_step();
}

/* No motion running, requested or owing its abort. */
static int fuzz_quiet(void)
{
    const struct wsg_axis *ax = wsg_device_axis(&B.dev);

    return ax->motion.kind == WSG_MOTION_NONE &&
           ax->req_motion.kind == WSG_MOTION_NONE &&
           ax->req_cancelled.kind == WSG_MOTION_NONE && !ax->req_stop &&
           !ax->req_fast_stop;
}

struct wsg_device *fuzz_bench_device(void)
{
    return &B.dev;
}

void fuzz_bench_end(void)
{
    long n;
    uint32_t t;

    for (n = 0; n < FUZZ_END_STEPS && !fuzz_quiet(); n++)
        fuzz_step();
    FUZZ_CHECK(fuzz_quiet());
    /* Every E_CMD_PENDING got its final result (sent or, for a closed
     * session, dropped), and no more than one. */
    for (t = 0; t < FUZZ_TAGS; t++) {
        if (B.trace && B.owed[t])
            fprintf(stderr, "tag %u owed %d\n", (unsigned)t, (int)B.owed[t]);
        FUZZ_CHECK(B.owed[t] == 0);
    }
}
