/*
 * The command handlers and the dispatch table, one entry per command of the
 * schema (wsg/schema.h), which gives its name, length rules and flags and
 * names its handler here.
 *
 * By the time a handler runs, the dispatcher has checked the payload length
 * and the gripper's state against the command's table entry. Handlers
 * decode their parameters, refuse undefined values, and either answer from
 * the model or record a request for the next step (motion commands answer
 * E_CMD_PENDING; their final result comes from the model).
 */
#include <math.h>
#include <string.h>

#include "cmd.h"

static uint16_t wsg_cmd_loop(struct wsg_device *d, struct wsg_session *s,
                             const struct wsg_frame *f, struct wsg_reply *r)
{
    (void)d;
    (void)s;
    memcpy(r->params, f->payload, f->len);
    r->len = f->len;
    return WSG_E_SUCCESS;
}

static uint16_t wsg_cmd_disconnect(struct wsg_device *d, struct wsg_session *s,
                                   const struct wsg_frame *f,
                                   struct wsg_reply *r)
{
    struct wsg_axis *ax = wsg_device_axis(d);

    (void)f;
    (void)r;
    if (!(s->flags & WSG_SESSION_CONNECTION))
        return WSG_E_NOT_AVAILABLE;
    s->announced = 1;
    /* 3.1.2: a movement in progress is aborted immediately. */
    if ((wsg_axis_flags(ax) & WSG_SF_MOVING) || wsg_axis_busy(ax))
        wsg_axis_request_stop(ax);
    return WSG_E_SUCCESS;
}

static uint16_t wsg_cmd_homing(struct wsg_device *d, struct wsg_session *s,
                               const struct wsg_frame *f, struct wsg_reply *r)
{
    (void)r;
    return wsg_axis_request_homing(wsg_device_axis(d), f->payload[0], s->tag);
}

static uint16_t wsg_cmd_preposition(struct wsg_device *d,
                                    struct wsg_session *s,
                                    const struct wsg_frame *f,
                                    struct wsg_reply *r)
{
    uint8_t flags = f->payload[0];

    (void)r;
    if (flags & ~(WSG_MOVE_RELATIVE | WSG_MOVE_STOP_ON_BLOCK))
        return WSG_E_INVALID_PARAMETER;
    return wsg_axis_request_move(wsg_device_axis(d), flags,
                                 wsg_get_f32(f->payload + 1),
                                 wsg_get_f32(f->payload + 5), s->tag);
}

static uint16_t wsg_cmd_stop(struct wsg_device *d, struct wsg_session *s,
                             const struct wsg_frame *f, struct wsg_reply *r)
{
    (void)s;
    (void)f;
    (void)r;
    wsg_axis_request_stop(wsg_device_axis(d));
    return WSG_E_SUCCESS;
}

static uint16_t wsg_cmd_fast_stop(struct wsg_device *d, struct wsg_session *s,
                                  const struct wsg_frame *f,
                                  struct wsg_reply *r)
{
    (void)f;
    (void)r;
    wsg_device_event(d, s->peer[0] ? s->peer : "?", "fast-stop cause=23h");
    wsg_axis_request_fast_stop(wsg_device_axis(d));
    return WSG_E_SUCCESS;
}

static uint16_t wsg_cmd_ack(struct wsg_device *d, struct wsg_session *s,
                            const struct wsg_frame *f, struct wsg_reply *r)
{
    (void)r;
    if (memcmp(f->payload, "ack", 3) != 0)
        return WSG_E_CMD_FORMAT_ERROR; /* 3.2.5: wrong key */
    /* Nothing to acknowledge is still a success: drivers send it blindly;
     * the log tells the two apart. */
    wsg_device_event(d, s->peer[0] ? s->peer : "?",
                     wsg_axis_fast_stopped(wsg_device_axis(d))
                         ? "ack fast-stop cleared"
                         : "ack nothing to clear");
    wsg_axis_request_ack(wsg_device_axis(d));
    return WSG_E_SUCCESS;
}

static uint16_t wsg_cmd_grasp(struct wsg_device *d, struct wsg_session *s,
                              const struct wsg_frame *f, struct wsg_reply *r)
{
    (void)r;
    return wsg_axis_request_grasp(wsg_device_axis(d), wsg_get_f32(f->payload),
                                  wsg_get_f32(f->payload + 4), s->tag);
}

static uint16_t wsg_cmd_release(struct wsg_device *d, struct wsg_session *s,
                                const struct wsg_frame *f, struct wsg_reply *r)
{
    (void)r;
    return wsg_axis_request_release(wsg_device_axis(d),
                                    wsg_get_f32(f->payload),
                                    wsg_get_f32(f->payload + 4), s->tag);
}

static uint16_t wsg_reply_f32(struct wsg_reply *r, double v)
{
    wsg_put_f32(r->params + r->len, (float)v);
    r->len += 4;
    return WSG_E_SUCCESS;
}

static uint16_t wsg_cmd_set_acc(struct wsg_device *d, struct wsg_session *s,
                                const struct wsg_frame *f, struct wsg_reply *r)
{
    float acc = wsg_get_f32(f->payload);

    (void)s;
    (void)r;
    if (isnan(acc))
        return WSG_E_INVALID_PARAMETER;
    wsg_axis_set_acc(wsg_device_axis(d), acc);
    return WSG_E_SUCCESS;
}

static uint16_t wsg_cmd_get_acc(struct wsg_device *d, struct wsg_session *s,
                                const struct wsg_frame *f, struct wsg_reply *r)
{
    (void)s;
    (void)f;
    return wsg_reply_f32(r, wsg_axis_acc(wsg_device_axis(d)));
}

static uint16_t wsg_cmd_set_force(struct wsg_device *d, struct wsg_session *s,
                                  const struct wsg_frame *f,
                                  struct wsg_reply *r)
{
    float force = wsg_get_f32(f->payload);

    (void)s;
    (void)r;
    if (isnan(force))
        return WSG_E_INVALID_PARAMETER;
    wsg_axis_set_force_limit(wsg_device_axis(d), force);
    return WSG_E_SUCCESS;
}

static uint16_t wsg_cmd_get_force_limit(struct wsg_device *d,
                                        struct wsg_session *s,
                                        const struct wsg_frame *f,
                                        struct wsg_reply *r)
{
    (void)s;
    (void)f;
    return wsg_reply_f32(r, wsg_axis_force_limit(wsg_device_axis(d)));
}

static uint16_t wsg_cmd_set_soft_limits(struct wsg_device *d,
                                        struct wsg_session *s,
                                        const struct wsg_frame *f,
                                        struct wsg_reply *r)
{
    float minus = wsg_get_f32(f->payload), plus = wsg_get_f32(f->payload + 4);

    (void)s;
    (void)r;
    if (isnan(minus) || isnan(plus) || minus > plus)
        return WSG_E_INVALID_PARAMETER;
    wsg_axis_set_soft_limits(wsg_device_axis(d), minus, plus);
    return WSG_E_SUCCESS;
}

static uint16_t wsg_cmd_get_soft_limits(struct wsg_device *d,
                                        struct wsg_session *s,
                                        const struct wsg_frame *f,
                                        struct wsg_reply *r)
{
    double minus, plus;

    (void)s;
    (void)f;
    if (!wsg_axis_soft_limits(wsg_device_axis(d), &minus, &plus))
        return WSG_E_NOT_AVAILABLE;
    wsg_reply_f32(r, minus);
    return wsg_reply_f32(r, plus);
}

static uint16_t wsg_cmd_clear_soft_limits(struct wsg_device *d,
                                          struct wsg_session *s,
                                          const struct wsg_frame *f,
                                          struct wsg_reply *r)
{
    (void)s;
    (void)f;
    (void)r;
    wsg_axis_clear_soft_limits(wsg_device_axis(d));
    return WSG_E_SUCCESS;
}

static uint16_t wsg_cmd_overdrive(struct wsg_device *d, struct wsg_session *s,
                                  const struct wsg_frame *f,
                                  struct wsg_reply *r)
{
    (void)s;
    (void)r;
    if (f->payload[0] & ~1u)
        return WSG_E_INVALID_PARAMETER;
    wsg_axis_set_overdrive(wsg_device_axis(d), f->payload[0] & 1u);
    return WSG_E_SUCCESS;
}

static uint16_t wsg_cmd_tare(struct wsg_device *d, struct wsg_session *s,
                             const struct wsg_frame *f, struct wsg_reply *r)
{
    (void)s;
    (void)f;
    (void)r;
    if (!wsg_fingers_fmf(&d->fingers))
        return WSG_E_NOT_AVAILABLE; /* no force measurement finger */
    /* Only out of force control mode (3.3.9), which is what D9 shows:
     * the flag and the rule are one. */
    if (wsg_device_flags(d) & WSG_SF_FORCECNTL_MODE)
        return WSG_E_ACCESS_DENIED;
    /* Zeroed at the settle after this answer: what each force measurement
     * finger feels then reads 0 N from there on. */
    wsg_finger_request_tare(&d->fingers);
    return WSG_E_SUCCESS;
}

static enum wsg_stream_id wsg_stream_of(uint8_t id)
{
    switch (id) {
    case WSG_CMD_GET_SYSTEM_STATE:
        return WSG_STREAM_SYSTEM_STATE;
    case WSG_CMD_GET_GRASP_STATE:
        return WSG_STREAM_GRASP_STATE;
    case WSG_CMD_GET_WIDTH:
        return WSG_STREAM_WIDTH;
    case WSG_CMD_GET_SPEED:
        return WSG_STREAM_SPEED;
    default:
        return WSG_STREAM_FORCE;
    }
}

/* 40h, 41h, 43h, 44h, 45h: a value now, and with FLAGS D0 a stream of it. */
static uint16_t wsg_cmd_stream(struct wsg_device *d, struct wsg_session *s,
                               const struct wsg_frame *f, struct wsg_reply *r)
{
    enum wsg_stream_id sid = wsg_stream_of(f->id);
    struct wsg_stream *st = &s->streams[sid];
    uint32_t step_us = wsg_axis_cfg(wsg_device_axis(d))->step_us;
    float value;

    r->len = wsg_stream_value(d, sid, r->params, &value);
    if (f->len == 0)
        return WSG_E_SUCCESS; /* a one-time read */
    if (f->payload[0] & ~3u)
        return WSG_E_INVALID_PARAMETER;
    if (st->on)
        s->nstreams--;
    st->on = f->payload[0] & 1u;
    if (st->on)
        s->nstreams++;
    wsg_device_streams_changed(d, s);
    if (!st->on)
        return WSG_E_SUCCESS;
    st->change_only = (f->payload[0] >> 1) & 1u;
    /* PERIOD_MS 0 means as often as the model steps. */
    st->period_us = 1000u * wsg_get_u16(f->payload + 1);
    if (st->period_us < step_us)
        st->period_us = step_us;
    st->due_us = wsg_axis_time(wsg_device_axis(d)) + st->period_us;
    st->last = value;
    return WSG_E_SUCCESS;
}

static uint16_t wsg_cmd_grasp_stats(struct wsg_device *d,
                                    struct wsg_session *s,
                                    const struct wsg_frame *f,
                                    struct wsg_reply *r)
{
    struct wsg_grasp_stats gs = wsg_axis_stats(wsg_device_axis(d));

    (void)s;
    if (f->len && (f->payload[0] & ~1u))
        return WSG_E_INVALID_PARAMETER;
    wsg_put_u32(r->params, gs.total);
    wsg_put_u16(r->params + 4, gs.no_part);
    wsg_put_u16(r->params + 6, gs.lost_part);
    r->len = 8;
    if (f->len && (f->payload[0] & 1u))
        wsg_axis_clear_stats(wsg_device_axis(d)); /* reset after reading */
    return WSG_E_SUCCESS;
}

static uint16_t wsg_cmd_temperature(struct wsg_device *d,
                                    struct wsg_session *s,
                                    const struct wsg_frame *f,
                                    struct wsg_reply *r)
{
    (void)s;
    (void)f;
    wsg_put_u16(r->params, (uint16_t)(int16_t)lround(
                               wsg_axis_temperature(wsg_device_axis(d)) * 10));
    r->len = 2;
    return WSG_E_SUCCESS;
}

static uint16_t wsg_cmd_system_info(struct wsg_device *d,
                                    struct wsg_session *s,
                                    const struct wsg_frame *f,
                                    struct wsg_reply *r)
{
    (void)s;
    (void)f;
    r->params[0] = d->info.type;
    r->params[1] = d->info.hwrev;
    wsg_put_u16(r->params + 2, d->info.swrev);
    wsg_put_u32(r->params + 4, d->info.serial);
    r->len = 8;
    return WSG_E_SUCCESS;
}

static uint16_t wsg_cmd_set_tag(struct wsg_device *d, struct wsg_session *s,
                                const struct wsg_frame *f, struct wsg_reply *r)
{
    size_t n = f->len, i;

    (void)s;
    (void)r;
    while (n && f->payload[n - 1] == 0)
        n--; /* trailing NULs are stripped (3.5.2) */
    if (n > WSG_TAG_MAX)
        return WSG_E_OVERRUN;
    for (i = 0; i < n; i++)
        if (f->payload[i] < 0x20 || f->payload[i] >= 0x7F)
            return WSG_E_INVALID_PARAMETER; /* control or non-ASCII */
    memcpy(d->tag, f->payload, n);
    d->tag[n] = '\0';
    d->tag_len = n;
    return WSG_E_SUCCESS;
}

static uint16_t wsg_cmd_get_tag(struct wsg_device *d, struct wsg_session *s,
                                const struct wsg_frame *f, struct wsg_reply *r)
{
    (void)s;
    (void)f;
    if (!d->tag_len)
        return WSG_E_NOT_AVAILABLE;
    memcpy(r->params, d->tag, d->tag_len);
    r->len = d->tag_len;
    return WSG_E_SUCCESS;
}

static uint16_t wsg_cmd_system_limits(struct wsg_device *d,
                                      struct wsg_session *s,
                                      const struct wsg_frame *f,
                                      struct wsg_reply *r)
{
    const struct wsg_axis_config *c = wsg_axis_cfg(wsg_device_axis(d));

    (void)s;
    (void)f;
    wsg_reply_f32(r, c->stroke);
    wsg_reply_f32(r, c->min_speed);
    wsg_reply_f32(r, c->max_speed);
    wsg_reply_f32(r, c->min_acc);
    wsg_reply_f32(r, c->max_acc);
    wsg_reply_f32(r, c->min_force);
    wsg_reply_f32(r, c->nom_force);
    return wsg_reply_f32(r, c->ovr_force);
}

/* One entry per row of the schema: its name, length rules and flags, and
 * the handler the row names. */
#define WSG_CMD_DESC_(id, sym, handler, name, min, max, flags, req, rep)      \
    [id] = {name, wsg_cmd_##handler, min, max, flags},
const struct wsg_cmd_desc wsg_cmd_table[256] = {
    WSG_SCHEMA_COMMANDS(WSG_CMD_DESC_)};
