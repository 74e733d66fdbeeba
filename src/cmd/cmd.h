/*
 * The command table's private types: a handler per command ID and the rules
 * the dispatcher checks once, centrally, before any handler runs.
 */
#ifndef WSG_CMD_H
#define WSG_CMD_H

#include "wsg/device.h"

/* The parameters of a reply; the status travels separately. */
struct wsg_reply {
    size_t len;
    uint8_t params[WSG_REPLY_PARAMS_MAX];
};

/* Returns the manual's status for the reply; params are sent with
 * E_SUCCESS only. */
typedef uint16_t (*wsg_cmd_handler)(struct wsg_device *d,
                                    struct wsg_session *s,
                                    const struct wsg_frame *f,
                                    struct wsg_reply *r);

/* Command flags. */
#define WSG_CMDF_MOTION 0x01u /* refused in FAST STOP and on faults */
#define WSG_CMDF_HOMED  0x02u /* refused before homing */
#define WSG_CMDF_ASYNC                                                        \
    0x04u                       /* pending, then a final result; not while    \
                                   moving */
#define WSG_CMDF_NO_PARAM 0x08u /* a length error is E_NO_PARAM_EXPECTED */
#define WSG_CMDF_EMPTY_OK 0x10u /* an empty payload is also accepted */
/* A motion command: all of the motion rules. */
#define WSG_CMDF_MOVE (WSG_CMDF_MOTION | WSG_CMDF_ASYNC)

struct wsg_cmd_desc {
    const char *name;
    wsg_cmd_handler handler;
    uint16_t min_len, max_len;
    uint8_t flags;
};

extern const struct wsg_cmd_desc wsg_cmd_table[256];

/* Build and send one reply packet; records SF_CMD_FAILURE. */
void wsg_device_reply(struct wsg_device *d, struct wsg_session *s, uint8_t id,
                      uint16_t status, const uint8_t *params, size_t len);
/* Put s on the device's streaming list or take it off, after its
 * nstreams changed. */
void wsg_device_streams_changed(struct wsg_device *d, struct wsg_session *s);
/* The current value of a stream's quantity, as sent on the wire. */
size_t wsg_stream_value(const struct wsg_device *d, enum wsg_stream_id sid,
                        uint8_t *out, float *value);

#endif
