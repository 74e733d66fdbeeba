/*
 * The command table's private types: a handler per command ID with the
 * schema's length rules and flags (wsg/schema.h), which the dispatcher
 * checks once, centrally, before any handler runs.
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

/* The dispatcher's entry for one command ID: the schema's name, length
 * rules and flags (WSG_CMDF_*) with the handler, in one static table, so
 * dispatching reads one entry. */
struct wsg_cmd_desc {
    const char *name;
    wsg_cmd_handler handler;
    uint16_t min_len, max_len;
    uint8_t flags;
};

extern const struct wsg_cmd_desc wsg_cmd_table[256];

/* The finger commands' handlers (fingers.c), 60h..63h and 70h..73h. */
uint16_t wsg_cmd_finger_info(struct wsg_device *d, struct wsg_session *s,
                             const struct wsg_frame *f, struct wsg_reply *r);
uint16_t wsg_cmd_finger_flags(struct wsg_device *d, struct wsg_session *s,
                              const struct wsg_frame *f, struct wsg_reply *r);
uint16_t wsg_cmd_finger_power(struct wsg_device *d, struct wsg_session *s,
                              const struct wsg_frame *f, struct wsg_reply *r);
uint16_t wsg_cmd_finger_data(struct wsg_device *d, struct wsg_session *s,
                             const struct wsg_frame *f, struct wsg_reply *r);

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
