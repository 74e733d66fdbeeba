/*
 * The dispatcher: everything the manual says about a command's length and
 * about the gripper's state (FAST STOP, not referenced, already moving) is
 * checked here, once, from the command's table entry, in the order the
 * manual's error lists imply. Handlers only deal with their parameters.
 */
#include "cmd.h"

static uint16_t wsg_cmd_check(const struct wsg_device *d,
                              const struct wsg_session *s,
                              const struct wsg_cmd_desc *c,
                              const struct wsg_frame *f)
{
    uint16_t st;

    if (s->announced)
        return WSG_E_ACCESS_DENIED; /* 3.1.2: waiting for the close */
    if (!c->handler)
        return WSG_E_CMD_UNKNOWN;
    if (!wsg_schema_len_ok(c->min_len, c->max_len, c->flags, f->len))
        return (c->flags & WSG_CMDF_NO_PARAM) ? WSG_E_NO_PARAM_EXPECTED
                                              : WSG_E_CMD_FORMAT_ERROR;
    if (c->flags & WSG_CMDF_MOTION) {
        st = wsg_device_motion_check(d, c->flags & WSG_CMDF_HOMED);
        if (st != WSG_E_SUCCESS)
            return st;
    } else if ((c->flags & WSG_CMDF_HOMED) &&
               !wsg_axis_referenced(wsg_device_axis_const(d))) {
        return WSG_E_NOT_INITIALIZED;
    }
    if ((c->flags & WSG_CMDF_ASYNC) && wsg_axis_busy(wsg_device_axis_const(d)))
        return WSG_E_ALREADY_RUNNING;
    return WSG_E_SUCCESS;
}

void wsg_device_dispatch(struct wsg_device *d, struct wsg_session *s,
                         const struct wsg_frame *f)
{
    const struct wsg_cmd_desc *c = &wsg_cmd_table[f->id];
    struct wsg_reply r;
    uint16_t st;

    d->last_tag = s->tag;
    /* A script's own command: the script answers it, when it reads it. */
    if (d->user_cmd && !s->announced && wsg_device_registered(d, f->id)) {
        d->user_cmd(d->user_ctx, s, f);
        wsg_device_settle(d);
        return;
    }
    r.len = 0;
    st = wsg_cmd_check(d, s, c, f);
    if (st == WSG_E_SUCCESS)
        st = c->handler(d, s, f, &r);
    wsg_device_reply(d, s, f->id, st, r.params,
                     st == WSG_E_SUCCESS ? r.len : 0);
    /* What the command asked for is applied once it is answered, so its
     * reply goes out before any final result it causes (22h E_SUCCESS,
     * then the stopped motion's E_CMD_ABORTED) and the next command, even
     * in the same read, sees the new state. Nothing else leaves requests
     * pending between commands: a close settles itself, and so does the
     * control channel. */
    wsg_device_settle(d);
}
