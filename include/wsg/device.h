/*
 * One emulated gripper as its interfaces see it: the axis model plus what the
 * gripper stores (type, serial number, device tag), the command dispatcher,
 * and the per-peer sessions with their auto-update streams.
 *
 * A transport owns a wsg_parser and a wsg_session per peer, feeds received
 * bytes to wsg_device_input and sends what comes back through the session's
 * send callback, one call per packet. Final results of motion commands are
 * routed by session tag through the lookup callback, because the peer that
 * asked may have gone by the time the motion ends. An optional output hook
 * takes every packet instead, for whoever makes the gripper answer later
 * (the daemon's --latency); it hands them on through wsg_device_transmit.
 *
 * The device holds its axis model by value, in storage whose layout only
 * the model knows; wsg_device_axis hands out the model to drive and read.
 */
#ifndef WSG_DEVICE_H
#define WSG_DEVICE_H

#include <stddef.h>
#include <stdint.h>

#include "wsg/axis.h"
#include "wsg/finger.h"
#include "wsg/proto.h"

enum wsg_stream_id {
    WSG_STREAM_SYSTEM_STATE = 0, /* 40h */
    WSG_STREAM_GRASP_STATE,      /* 41h */
    WSG_STREAM_WIDTH,            /* 43h */
    WSG_STREAM_SPEED,            /* 44h */
    WSG_STREAM_FORCE,            /* 45h */
    WSG_STREAM_COUNT
};

struct wsg_stream {
    uint8_t on;
    uint8_t change_only;
    uint32_t period_us;
    uint64_t due_us; /* simulated time of the next packet */
    float last;      /* value last sent (flags and states as float) */
};

struct wsg_session;
/* Send one complete packet. Must not call back into the device. */
typedef void (*wsg_send_fn)(struct wsg_session *s, const uint8_t *pkt,
                            size_t len);

/* Session flags. */
#define WSG_SESSION_CONNECTION 0x01u /* TCP: 07h available, close matters */
#define WSG_SESSION_TEXT       0x02u /* GCL: it sends and receives lines */

/* A text session's writer (wsg/gcl.h): the device's answers and stream
 * packets for the session, as the binary protocol has them, to be written
 * as text (sent with wsg_device_send) instead of sent. */
typedef void (*wsg_format_fn)(void *ctx, struct wsg_session *s, uint8_t id,
                              uint16_t status, const uint8_t *params,
                              size_t len);

struct wsg_session {
    uint32_t tag;  /* unique among live sessions; never 0 */
    char peer[64]; /* for logs: "tcp 127.0.0.1:51234", set by the transport */
    unsigned flags;
    int announced; /* got Disconnect Announcement (07h) */
    wsg_send_fn send;
    void *ctx;            /* the transport's */
    wsg_format_fn format; /* NULL: binary */
    void *format_ctx;
    unsigned nstreams;
    struct wsg_stream streams[WSG_STREAM_COUNT];
    /* On the device's list of streaming sessions while nstreams > 0, so
     * polling costs what is subscribed, not what is connected. */
    struct wsg_session *stream_next;
    struct wsg_session **stream_pprev; /* NULL: not on the list */
};

struct wsg_device_info {
    uint8_t type; /* 1: WSG 50 (see NOTES: 2 WSG 32, 5 WSG 25) */
    uint8_t hwrev;
    uint16_t swrev; /* major<<12 | minor<<8 | patch<<4 */
    uint32_t serial;
};

struct wsg_device {
    /* The axis model: reach it through wsg_device_axis. */
    struct wsg_axis_storage axis_storage;
    struct wsg_device_info info;
    char tag[WSG_TAG_MAX + 1];
    size_t tag_len;           /* 0: no device tag set */
    int disconnect_fast_stop; /* TCP close without 07h: FAST STOP */
    int cmd_failure;          /* SF_CMD_FAILURE: last command failed */
    /* Communication log (NULL: off): every packet received (a parsed frame,
     * or a checksum or size error with its ID) and every packet sent, with
     * the session it belongs to. */
    void (*trace_in)(void *ctx, const struct wsg_session *s,
                     const struct wsg_frame *f, enum wsg_parse_event ev);
    void (*trace_out)(void *ctx, const struct wsg_session *s,
                      const uint8_t *pkt, size_t len);
    /* A text session's line received (without its newline). */
    void (*trace_line)(void *ctx, const struct wsg_session *s,
                       const char *line, size_t len);
    /* An event of the session (who: its peer), of the model ("gripper")
     * or of whoever changed the world ("control"), as text: "connected",
     * "closed without 07h", "fast-stop cause=23h", "ack". */
    void (*trace_event)(void *ctx, const char *who, const char *text);
    void *trace_ctx;
    /* Resolve a session tag for a final result; NULL when it is gone. */
    struct wsg_session *(*lookup)(void *ctx, uint32_t tag);
    void *lookup_ctx;
    /* Output hook (NULL: off, every packet leaves at once): takes every
     * packet the gripper sends (replies, final results, stream packets)
     * when it is due, and sends it later with wsg_device_transmit. It
     * must not keep s or pkt beyond the call, only s->tag and a copy. */
    void (*delay)(void *ctx, struct wsg_session *s, const uint8_t *pkt,
                  size_t len);
    void *delay_ctx;
    struct wsg_session *streaming; /* sessions with nstreams > 0 */
    /* Command IDs registered by a script on the gripper (a bit per ID):
     * their packets go to user_cmd instead of the command table, and the
     * script answers them with wsg_device_send. NULL: no script host. */
    uint8_t user_ids[32];
    void (*user_cmd)(void *ctx, struct wsg_session *s,
                     const struct wsg_frame *f);
    void *user_ctx;
    /* Flags the gripper's owner adds to the model's: D19
     * SF_SCRIPT_RUNNING and D20 SF_SCRIPT_FAILURE, from the script host.
     * A power cycle (wsg_device_reset) keeps them: the script runs on. */
    uint32_t ext_flags;
    uint32_t last_tag; /* the session that sent the last packet; 0: none */
    /* The finger interface (wsg/finger.h): updated after the axis in
     * every step and settle. */
    struct wsg_fingers fingers;
};

void wsg_device_init(struct wsg_device *d, const struct wsg_axis_config *cfg);
/* Power cycle: session settings back to defaults, not referenced, no
 * session streams. */
void wsg_device_reset(struct wsg_device *d);

/* The device's axis model (inline: the dispatcher and the stream polling
 * reach it on every call). The model is initialised by wsg_device_init. */
static inline struct wsg_axis *wsg_device_axis(struct wsg_device *d)
{
    return (struct wsg_axis *)(void *)&d->axis_storage;
}

static inline const struct wsg_axis *
wsg_device_axis_const(const struct wsg_device *d)
{
    return (const struct wsg_axis *)(const void *)&d->axis_storage;
}

void wsg_session_init(struct wsg_session *s, uint32_t tag, unsigned flags,
                      wsg_send_fn send, void *ctx);
/* A connection was accepted (s->peer set), for the communication log. */
void wsg_device_session_opened(struct wsg_device *d,
                               const struct wsg_session *s);
/* The peer went away (TCP close): FAST STOP at once unless it announced
 * it. The transport must no longer resolve s's tag (its lookup returns
 * NULL), since a motion s owned ends here. */
void wsg_device_session_closed(struct wsg_device *d, struct wsg_session *s);

/* An event for the communication log (trace_event); who NULL: the
 * gripper itself. */
void wsg_device_event(struct wsg_device *d, const char *who, const char *text);
/* A text session's line received, for the communication log. */
void wsg_device_trace_line(struct wsg_device *d, const struct wsg_session *s,
                           const char *line, size_t len);
/* Put one packet on the wire now: the communication log's trace_out, then
 * s->send. What the device sends goes through here, directly or, with an
 * output hook, when the hook releases it. */
void wsg_device_transmit(struct wsg_device *d, struct wsg_session *s,
                         const uint8_t *pkt, size_t len);

/* Feed received bytes: every frame, checksum error and oversize is
 * dispatched and answered through s->send. */
void wsg_device_input(struct wsg_device *d, struct wsg_session *s,
                      struct wsg_parser *p, const uint8_t *data, size_t len);
/* Feed one datagram (UDP): each packet in it is answered; a packet cut
 * off at its end is answered E_CMD_FORMAT_ERROR under its ID (dropped if
 * even the ID is missing) and never joined with the next datagram. */
void wsg_device_input_datagram(struct wsg_device *d, struct wsg_session *s,
                               int check_crc, const uint8_t *data, size_t len);
/* Dispatch one parsed frame (the table's length and state checks, then the
 * handler) and send its reply. */
void wsg_device_dispatch(struct wsg_device *d, struct wsg_session *s,
                         const struct wsg_frame *f);

/* The system state flags as 40h reports them: the model's, the last
 * command's failure (D12) and the owner's (ext_flags). */
uint32_t wsg_device_flags(const struct wsg_device *d);
/* Whether a motion may start now, as the dispatcher checks a motion
 * command: E_ACCESS_DENIED in FAST STOP or with a fault that blocks
 * movement, E_NOT_INITIALIZED when needs_homing and not referenced, else
 * E_SUCCESS. */
uint16_t wsg_device_motion_check(const struct wsg_device *d, int needs_homing);

/* Hand packets with this ID to user_cmd (on) or to the command table
 * again (off). Returns 0, or -EEXIST for an ID the command table answers:
 * a script cannot take over a built-in command. */
int wsg_device_register(struct wsg_device *d, uint8_t id, int on);
int wsg_device_registered(const struct wsg_device *d, uint8_t id);
/* Forget every registered ID (the script ended). */
void wsg_device_unregister_all(struct wsg_device *d);
/* The session with this tag, NULL when it is gone (or tag is 0). */
struct wsg_session *wsg_device_session(struct wsg_device *d, uint32_t tag);
/* Send one packet the caller built whole (a script's), through the output
 * hook like any reply. */
void wsg_device_send(struct wsg_device *d, struct wsg_session *s,
                     const uint8_t *pkt, size_t len);

/* One model step, then the fingers' update; final results leave through
 * lookup/send. */
void wsg_device_step(struct wsg_device *d);
/* Apply what was requested (a step of zero length): the axis's settle,
 * then the fingers' update. Whoever changes the world or records a request
 * outside a command settles with this. */
void wsg_device_settle(struct wsg_device *d);
/* Send the stream packets of s that are due at the device's time. */
void wsg_device_poll_streams(struct wsg_device *d, struct wsg_session *s);
/* The same for every streaming session. */
void wsg_device_poll_streaming(struct wsg_device *d);
/* Stop every session's streams (a power cycle). */
void wsg_device_end_streams(struct wsg_device *d);
/* Nothing for steps to do: model idle. Streams are counted apart
 * (wsg_device_busy counts both). */
int wsg_device_idle(const struct wsg_device *d);
/* Steps matter: the model is not idle or a session streams. */
int wsg_device_busy(const struct wsg_device *d);
/* The device's next deadline, in model steps from its time: 1 while the
 * model is not idle (it needs every step), else the steps until the first
 * stream packet is due (a change-only stream counts only with a changed
 * value), UINT64_MAX when nothing is due. Steps before it change nothing
 * but the time: a caller may jump them with wsg_device_advance_idle, so a
 * gripper with one 1 s stream is woken once a second, not every step. */
uint64_t wsg_device_next(const struct wsg_device *d);
/* Advance simulated time by n steps while idle (the state cannot change, so
 * the loop may skip stepping through a quiet gap). */
void wsg_device_advance_idle(struct wsg_device *d, uint64_t nsteps);

#endif
