/*
 * The finger commands (later firmware's command set, its page 44): Get
 * Finger Info, Get Finger Flags, Finger Power Control and Get Finger Data,
 * 60h..63h for finger 1 and 70h..73h for finger 2.
 *
 * 60h..63h also serve older clients, which name the finger by an index
 * byte (0 or 1) first: the dispatcher's length rules let through both
 * forms and the length tells them apart here. The values come from the
 * finger interface (wsg/finger.h); power is a request the settle after the
 * answer applies, so the next command sees it.
 */
#include "cmd.h"

#include "wsg/finger.h"

/* The finger a request addresses: 70h..73h finger 2, 60h..63h finger 1
 * or, with `indexed` (an index byte first), the one it names. */
static uint16_t finger_of(const struct wsg_frame *f, int indexed, int *i)
{
    if (f->id >= 0x70) {
        *i = 1;
        return WSG_E_SUCCESS;
    }
    if (!indexed) {
        *i = 0;
        return WSG_E_SUCCESS;
    }
    if (f->payload[0] >= WSG_FINGER_COUNT)
        return WSG_E_INDEX_OUT_OF_BOUNDS;
    *i = f->payload[0];
    return WSG_E_SUCCESS;
}

static uint32_t injected(const struct wsg_device *d)
{
    return wsg_axis_faults(wsg_device_axis_const(d));
}

/* 60h/70h: the type byte, then the size of the finger's data. */
uint16_t wsg_cmd_finger_info(struct wsg_device *d, struct wsg_session *s,
                             const struct wsg_frame *f, struct wsg_reply *r)
{
    uint16_t st;
    int i;

    (void)s;
    st = finger_of(f, f->len == 1, &i);
    if (st != WSG_E_SUCCESS)
        return st;
    r->params[0] = (uint8_t)wsg_finger_type(&d->fingers, i);
    wsg_put_u16(r->params + 1, wsg_finger_size(&d->fingers, i));
    r->len = 3;
    return WSG_E_SUCCESS;
}

/* 61h/71h: WSG_FF_* (docs/fingers.md). */
uint16_t wsg_cmd_finger_flags(struct wsg_device *d, struct wsg_session *s,
                              const struct wsg_frame *f, struct wsg_reply *r)
{
    uint16_t st;
    int i;

    (void)s;
    st = finger_of(f, f->len == 1, &i);
    if (st != WSG_E_SUCCESS)
        return st;
    wsg_put_u16(r->params, wsg_finger_flags(&d->fingers, i, injected(d)));
    r->len = 2;
    return WSG_E_SUCCESS;
}

/* 62h/72h: 1 on, 0 off; 62h with two bytes: index, then on/off. */
uint16_t wsg_cmd_finger_power(struct wsg_device *d, struct wsg_session *s,
                              const struct wsg_frame *f, struct wsg_reply *r)
{
    uint8_t on = f->payload[f->len - 1];
    uint16_t st;
    int i;

    (void)s;
    (void)r;
    if (f->id >= 0x70 && f->len != 1)
        return WSG_E_CMD_FORMAT_ERROR;
    st = finger_of(f, f->len == 2, &i);
    if (st != WSG_E_SUCCESS)
        return st;
    if (on > 1)
        return WSG_E_INVALID_PARAMETER;
    if (d->fingers.f[i].kind == WSG_FINGER_NONE)
        return WSG_E_NO_SENSOR;
    wsg_finger_request_power(&d->fingers, i, on);
    return WSG_E_SUCCESS;
}

/* 63h/73h: as many bytes as 60h's size. */
uint16_t wsg_cmd_finger_data(struct wsg_device *d, struct wsg_session *s,
                             const struct wsg_frame *f, struct wsg_reply *r)
{
    uint16_t st;
    int i;

    (void)s;
    st = finger_of(f, f->len == 1, &i);
    if (st != WSG_E_SUCCESS)
        return st;
    return wsg_finger_data(&d->fingers, i, injected(d), r->params, &r->len);
}
