/*
 * The device: one gripper's model, its stored data, and the sessions that
 * talk to it.
 *
 * Replies leave through the asking session's send callback, one call per
 * packet. Final results of motion commands come out of the model's step
 * with the tag of the session that asked; the transport's lookup turns the
 * tag back into a session, or NULL if the peer is gone and the result has
 * no one to go to. Streams are polled after each step against simulated
 * time, so they keep their period under any time scale.
 *
 * Every packet leaves through emit: at once, or into the output hook when
 * one is set, which transmits it later. Either way the log sees a packet
 * when it goes on the wire, not when it was made.
 */
#include <errno.h>
#include <math.h>
#include <string.h>

#include "cmd.h"

/* Change thresholds of 3.4.4 to 3.4.6; flags and states: any change. */
static const float wsg_stream_threshold[WSG_STREAM_COUNT] = {
    [WSG_STREAM_SYSTEM_STATE] = 0.5f, [WSG_STREAM_GRASP_STATE] = 0.5f,
    [WSG_STREAM_WIDTH] = 0.01f,       [WSG_STREAM_SPEED] = 0.05f,
    [WSG_STREAM_FORCE] = 0.05f,
};

static const uint8_t wsg_stream_cmd[WSG_STREAM_COUNT] = {
    WSG_CMD_GET_SYSTEM_STATE, WSG_CMD_GET_GRASP_STATE, WSG_CMD_GET_WIDTH,
    WSG_CMD_GET_SPEED, WSG_CMD_GET_FORCE};

static void wsg_device_done(void *ctx, uint32_t tag, uint8_t cmd_id,
                            uint16_t status)
{
    struct wsg_device *d = ctx;
    struct wsg_session *s;

    /* Tag 0: a script's motion; it watches the model, no packet is owed
     * and no command of a host failed. */
    if (tag == 0)
        return;
    s = wsg_device_session(d, tag);
    if (s)
        wsg_device_reply(d, s, cmd_id, status, NULL, 0);
    else
        d->cmd_failure = status != WSG_E_SUCCESS;
}

/* A FAST STOP the model entered by itself: its cause for the log. */
static void wsg_device_axis_event(void *ctx, enum wsg_axis_event ev)
{
    wsg_device_event(ctx, NULL,
                     ev == WSG_AXIS_FAST_STOP_FAULT
                         ? "fast-stop cause=fault"
                         : "fast-stop cause=soft-limit");
}

void wsg_device_init(struct wsg_device *d, const struct wsg_axis_config *cfg)
{
    memset(d, 0, sizeof *d);
    wsg_axis_init(wsg_device_axis(d), cfg, wsg_device_done, d);
    wsg_axis_on_event(wsg_device_axis(d), wsg_device_axis_event, d);
    d->info.type = cfg->type;
    d->info.hwrev = 1;
    d->info.swrev = 0x2200; /* firmware 2.2.0 */
    d->info.serial = 1;
    d->disconnect_fast_stop = 1;
    /* --force-sensor on: force measurement fingers, else generic ones. */
    wsg_fingers_init(&d->fingers,
                     cfg->force_sensor ? WSG_FINGER_FMF : WSG_FINGER_GENERIC);
    wsg_fingers_update(&d->fingers, wsg_device_axis(d));
}

void wsg_device_reset(struct wsg_device *d)
{
    int i;

    wsg_axis_reset(wsg_device_axis(d));
    d->cmd_failure = 0;
    /* The fingers are powered again, their tare gone; their kinds stay. */
    for (i = 0; i < WSG_FINGER_COUNT; i++) {
        d->fingers.f[i].tare = 0.0;
        wsg_finger_request_power(&d->fingers, i, 1);
    }
    wsg_device_settle(d);
    /* A gripper that powers up again streams nothing until asked. */
    wsg_device_end_streams(d);
}

void wsg_session_init(struct wsg_session *s, uint32_t tag, unsigned flags,
                      wsg_send_fn send, void *ctx)
{
    memset(s, 0, sizeof *s);
    s->tag = tag;
    s->flags = flags;
    s->send = send;
    s->ctx = ctx;
}

void wsg_device_streams_changed(struct wsg_device *d, struct wsg_session *s)
{
    if (s->nstreams > 0 && !s->stream_pprev) {
        s->stream_next = d->streaming;
        if (d->streaming)
            d->streaming->stream_pprev = &s->stream_next;
        d->streaming = s;
        s->stream_pprev = &d->streaming;
    } else if (s->nstreams == 0 && s->stream_pprev) {
        *s->stream_pprev = s->stream_next;
        if (s->stream_next)
            s->stream_next->stream_pprev = s->stream_pprev;
        s->stream_next = NULL;
        s->stream_pprev = NULL;
    }
}

static void wsg_session_end_streams(struct wsg_device *d,
                                    struct wsg_session *s)
{
    s->nstreams = 0;
    memset(s->streams, 0, sizeof s->streams);
    wsg_device_streams_changed(d, s);
}

void wsg_device_event(struct wsg_device *d, const char *who, const char *text)
{
    if (d->trace_event)
        d->trace_event(d->trace_ctx, who ? who : "gripper", text);
}

static const char *wsg_session_who(const struct wsg_session *s)
{
    return s->peer[0] ? s->peer : "?";
}

void wsg_device_session_opened(struct wsg_device *d,
                               const struct wsg_session *s)
{
    wsg_device_event(d, wsg_session_who(s), "connected");
}

void wsg_device_session_closed(struct wsg_device *d, struct wsg_session *s)
{
    wsg_session_end_streams(d, s);
    if (s->flags & WSG_SESSION_CONNECTION)
        wsg_device_event(d, wsg_session_who(s),
                         s->announced ? "closed (07h)" : "closed without 07h");
    if ((s->flags & WSG_SESSION_CONNECTION) && !s->announced &&
        d->disconnect_fast_stop) {
        wsg_device_event(d, wsg_session_who(s), "fast-stop cause=disconnect");
        /* At once, as for a 23h: the motion is aborted now (its owner
         * told if still there; s itself no longer resolves), and the next
         * answer, to anyone, shows FAST STOP. */
        wsg_axis_request_fast_stop(wsg_device_axis(d));
        wsg_device_settle(d);
    }
}

void wsg_device_end_streams(struct wsg_device *d)
{
    while (d->streaming)
        wsg_session_end_streams(d, d->streaming);
}

void wsg_device_transmit(struct wsg_device *d, struct wsg_session *s,
                         const uint8_t *pkt, size_t len)
{
    if (d->trace_out)
        d->trace_out(d->trace_ctx, s, pkt, len);
    s->send(s, pkt, len);
}

struct wsg_session *wsg_device_session(struct wsg_device *d, uint32_t tag)
{
    return tag && d->lookup ? d->lookup(d->lookup_ctx, tag) : NULL;
}

uint32_t wsg_device_flags(const struct wsg_device *d)
{
    const struct wsg_axis *ax = wsg_device_axis_const(d);
    uint32_t f = wsg_axis_flags(ax) | d->ext_flags |
                 (d->cmd_failure ? WSG_SF_CMD_FAILURE : 0u);
    enum wsg_grasp_state gs = wsg_axis_grasp_state(ax);

    /* Force control is what force measurement fingers give a grasp: the
     * fingers fitted now decide D9, whatever the model was made with. */
    f &= ~(uint32_t)WSG_SF_FORCECNTL_MODE;
    if (wsg_fingers_fmf(&d->fingers) &&
        (gs == WSG_GS_GRASPING || gs == WSG_GS_HOLDING))
        f |= WSG_SF_FORCECNTL_MODE;
    /* D17: a finger's electronics failed. */
    if (wsg_fingers_fault(&d->fingers))
        f |= WSG_SF_FINGER_FAULT;
    return f;
}

uint16_t wsg_device_motion_check(const struct wsg_device *d, int needs_homing)
{
    const struct wsg_axis *ax = wsg_device_axis_const(d);

    if (wsg_axis_fast_stopped(ax))
        return WSG_E_ACCESS_DENIED;
    /* Appendix B: a fault disables all movement-related commands. */
    if (wsg_axis_faults(ax) & WSG_FAULTS_BLOCKING)
        return WSG_E_ACCESS_DENIED;
    if (needs_homing && !wsg_axis_referenced(ax))
        return WSG_E_NOT_INITIALIZED;
    return WSG_E_SUCCESS;
}

int wsg_device_register(struct wsg_device *d, uint8_t id, int on)
{
    if (wsg_cmd_table[id].handler)
        return -EEXIST;
    if (on)
        d->user_ids[id >> 3] |= (uint8_t)(1u << (id & 7u));
    else
        d->user_ids[id >> 3] &= (uint8_t) ~(1u << (id & 7u));
    return 0;
}

int wsg_device_registered(const struct wsg_device *d, uint8_t id)
{
    return (d->user_ids[id >> 3] >> (id & 7u)) & 1u;
}

void wsg_device_unregister_all(struct wsg_device *d)
{
    memset(d->user_ids, 0, sizeof d->user_ids);
}

/* A packet is due: to the hook if there is one, else on the wire. */
static void wsg_device_emit(struct wsg_device *d, struct wsg_session *s,
                            const uint8_t *pkt, size_t len)
{
    if (d->delay)
        d->delay(d->delay_ctx, s, pkt, len);
    else
        wsg_device_transmit(d, s, pkt, len);
}

void wsg_device_trace_line(struct wsg_device *d, const struct wsg_session *s,
                           const char *line, size_t len)
{
    if (d->trace_line)
        d->trace_line(d->trace_ctx, s, line, len);
}

void wsg_device_send(struct wsg_device *d, struct wsg_session *s,
                     const uint8_t *pkt, size_t len)
{
    wsg_device_emit(d, s, pkt, len);
}

void wsg_device_reply(struct wsg_device *d, struct wsg_session *s, uint8_t id,
                      uint16_t status, const uint8_t *params, size_t len)
{
    uint8_t pkt[WSG_FRAME_MAX];
    size_t n;

    if (status != WSG_E_CMD_PENDING)
        d->cmd_failure = status != WSG_E_SUCCESS;
    if (s->format) {
        s->format(s->format_ctx, s, id, status, params, len);
        return;
    }
    n = wsg_frame_encode_reply(pkt, sizeof pkt, id, status, params, len);
    if (n)
        wsg_device_emit(d, s, pkt, n);
}

void wsg_device_input(struct wsg_device *d, struct wsg_session *s,
                      struct wsg_parser *p, const uint8_t *data, size_t len)
{
    while (len) {
        enum wsg_parse_event ev;
        struct wsg_frame f;
        size_t n = wsg_parser_feed(p, data, len, &ev, &f);

        data += n;
        len -= n;
        if (ev != WSG_PARSE_NONE && d->trace_in)
            d->trace_in(d->trace_ctx, s, &f, ev);
        switch (ev) {
        case WSG_PARSE_FRAME:
            wsg_device_dispatch(d, s, &f);
            break;
        case WSG_PARSE_BAD_CRC:
            wsg_device_reply(d, s, f.id, WSG_E_CHECKSUM_ERROR, NULL, 0);
            break;
        case WSG_PARSE_OVERSIZE:
            wsg_device_reply(d, s, f.id, WSG_E_CMD_FORMAT_ERROR, NULL, 0);
            break;
        default:
            break;
        }
    }
}

void wsg_device_input_datagram(struct wsg_device *d, struct wsg_session *s,
                               int check_crc, const uint8_t *data, size_t len)
{
    struct wsg_parser p;
    uint8_t id;

    wsg_parser_init(&p, check_crc);
    wsg_device_input(d, s, &p, data, len);
    if (wsg_parser_partial(&p, &id) == 1)
        wsg_device_reply(d, s, id, WSG_E_CMD_FORMAT_ERROR, NULL, 0);
}

size_t wsg_stream_value(const struct wsg_device *d, enum wsg_stream_id sid,
                        uint8_t *out, float *value)
{
    const struct wsg_axis *ax = wsg_device_axis_const(d);
    enum wsg_grasp_state gs;
    uint32_t flags;

    switch (sid) {
    case WSG_STREAM_SYSTEM_STATE:
        flags = wsg_device_flags(d);
        wsg_put_u32(out, flags);
        *value = (float)flags; /* exact: the flags stay below 2^24 */
        return 4;
    case WSG_STREAM_GRASP_STATE:
        gs = wsg_axis_grasp_state(ax);
        out[0] = (uint8_t)gs;
        *value = (float)gs;
        return 1;
    case WSG_STREAM_WIDTH:
        *value = (float)wsg_axis_width(ax);
        break;
    case WSG_STREAM_SPEED:
        *value = (float)wsg_axis_speed(ax);
        break;
    default:
        *value = (float)wsg_axis_force(ax);
        break;
    }
    wsg_put_f32(out, *value);
    return 4;
}

void wsg_device_poll_streams(struct wsg_device *d, struct wsg_session *s)
{
    uint64_t now = wsg_axis_time(wsg_device_axis(d));
    unsigned i;

    for (i = 0; i < WSG_STREAM_COUNT && s->nstreams; i++) {
        struct wsg_stream *st = &s->streams[i];
        uint8_t params[4];
        uint8_t pkt[WSG_HEADER_LEN + 2 + sizeof params + WSG_CRC_LEN];
        float value;
        size_t len, n;

        if (!st->on || now < st->due_us)
            continue;
        len = wsg_stream_value(d, (enum wsg_stream_id)i, params, &value);
        /* Change-only: the period is a minimum interval; a change after
         * a quiet spell goes out at once. */
        if (st->change_only &&
            fabsf(value - st->last) < wsg_stream_threshold[i])
            continue;
        st->last = value;
        st->due_us += st->period_us;
        if (st->due_us <= now)
            st->due_us = now + st->period_us;
        if (s->format) {
            s->format(s->format_ctx, s, wsg_stream_cmd[i], WSG_E_SUCCESS,
                      params, len);
            continue;
        }
        n = wsg_frame_encode_reply(pkt, sizeof pkt, wsg_stream_cmd[i],
                                   WSG_E_SUCCESS, params, len);
        wsg_device_emit(d, s, pkt, n);
    }
}

void wsg_device_poll_streaming(struct wsg_device *d)
{
    struct wsg_session *s;

    /* Sending never ends a session here (transports only mark a peer that
     * fails), so the list holds still while it is walked. */
    for (s = d->streaming; s; s = s->stream_next)
        wsg_device_poll_streams(d, s);
}

void wsg_device_step(struct wsg_device *d)
{
    wsg_axis_step(wsg_device_axis(d));
    wsg_fingers_update(&d->fingers, wsg_device_axis_const(d));
}

void wsg_device_settle(struct wsg_device *d)
{
    wsg_axis_settle(wsg_device_axis(d));
    wsg_fingers_update(&d->fingers, wsg_device_axis_const(d));
}

/* Bytes on a finger's wire need every step, as a moving axis does. */
int wsg_device_idle(const struct wsg_device *d)
{
    return wsg_axis_idle(wsg_device_axis_const(d)) &&
           !wsg_fingers_busy(&d->fingers);
}

int wsg_device_busy(const struct wsg_device *d)
{
    return d->streaming != NULL || !wsg_device_idle(d);
}

/* Steps from now until a stream of s has a packet due, UINT64_MAX when
 * none will while the model is idle: a change-only stream sends only a
 * changed value, and an idle model changes none. */
static uint64_t wsg_device_stream_next(const struct wsg_device *d,
                                       const struct wsg_session *s)
{
    uint64_t now = wsg_axis_time(wsg_device_axis_const(d));
    uint64_t step = wsg_axis_cfg(wsg_device_axis_const(d))->step_us;
    uint64_t best = UINT64_MAX;
    unsigned i;

    for (i = 0; i < WSG_STREAM_COUNT; i++) {
        const struct wsg_stream *st = &s->streams[i];
        uint8_t params[4];
        float value;
        uint64_t k;

        if (!st->on)
            continue;
        if (st->change_only) {
            wsg_stream_value(d, (enum wsg_stream_id)i, params, &value);
            if (fabsf(value - st->last) < wsg_stream_threshold[i])
                continue;
        }
        /* Polled after a step: the first step that ends at or after the
         * due time, and never this instant (it has been polled). */
        k = st->due_us > now ? (st->due_us - now + step - 1) / step : 1;
        if (k < best)
            best = k;
    }
    return best;
}

uint64_t wsg_device_next(const struct wsg_device *d)
{
    const struct wsg_session *s;
    uint64_t best;

    if (!wsg_device_idle(d))
        return 1;
    best = UINT64_MAX;
    for (s = d->streaming; s && best > 1; s = s->stream_next) {
        uint64_t k = wsg_device_stream_next(d, s);

        if (k < best)
            best = k;
    }
    return best;
}

void wsg_device_advance_idle(struct wsg_device *d, uint64_t nsteps)
{
    wsg_axis_advance_idle(wsg_device_axis(d), nsteps);
    /* Nothing is on the fingers' wires: this only brings their clock. */
    wsg_fingers_update(&d->fingers, wsg_device_axis_const(d));
}
