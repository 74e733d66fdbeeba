/*
 * The interface every host interface of the emulator implements (TCP, UDP,
 * pty, CAN): an ops table plus a small record. A transport keeps all its
 * state in its own struct behind t->state, is opened from a config struct
 * of its own (struct wsg_tcp_config, ...), and registers its descriptors
 * with the reactor through watches made by wsg_transport_watch_init, whose
 * events reach its handle() between the host's enter and leave hooks.
 *
 * A transport knows neither the scheduler nor the options: the daemon
 * gives it a host (what to call around its events, and when it has marked
 * a peer gone) and the environment it needs (the reactor, the process's
 * file watches, the device, a receive buffer).
 *
 * Session tags carry the transport's index in their top bits, so the
 * device's single lookup callback finds the owning transport in O(1) and the
 * transport resolves the rest (typically a slot index plus a generation).
 */
#ifndef WSG_TRANSPORT_H
#define WSG_TRANSPORT_H

#include <stddef.h>
#include <stdint.h>

#include "fswatch.h"
#include "reactor.h"
#include "wsg/device.h"
#include "wsg/gcl.h"

#define WSG_TRANSPORT_MAX 8u
/* tag = (index + 1) << 28 | local: never 0, at most 15 transports. */
#define WSG_TAG_TRANSPORT_SHIFT 28
#define WSG_TAG_LOCAL_MASK      ((1u << WSG_TAG_TRANSPORT_SHIFT) - 1u)

struct wsg_transport;

/* An IPv4 endpoint as given on the command line. */
struct wsg_endpoint {
    uint8_t addr[4]; /* a.b.c.d in this order */
    uint16_t port;   /* host order; 0 lets the kernel pick */
};

/* Each transport's own settings. */
struct wsg_tcp_config {
    struct wsg_endpoint ep;
    unsigned max_clients; /* connections at once; more are refused */
    int check_crc;
    int text;                  /* GCL instead of the binary protocol */
    struct wsg_gcl_config gcl; /* with text */
};

struct wsg_udp_config {
    struct wsg_endpoint ep; /* where it listens */
    uint16_t remote_port;   /* where answers go, at the sender's IP; 0:
                               to the port it last sent from (source) */
    int check_crc;
};

struct wsg_pty_config {
    const char *path; /* the link to the slave side */
    int check_crc;
    int mode; /* permission bits for the slave; -1: as the system made it */
    long gid; /* the slave's group; -1: as the system made it */
};

struct wsg_can_config {
    const char *iface;
    uint32_t id; /* commands on id, answers on id + 1 */
    int check_crc;
};

/* What a transport gets from the daemon when it opens; copy what it needs
 * (env lives only during open). */
struct wsg_transport_env {
    struct wsg_reactor *reactor;
    struct wsg_fswatch *fswatch; /* file watches (the pty's) */
    struct wsg_device *dev;
    uint8_t *rx; /* a receive buffer, shared: one handler runs at a time */
    size_t rxlen;
};

/* The transport's host (the daemon, for its gripper): called around each
 * event, so the gripper's time is current and it is rescheduled after;
 * and when a peer has been marked gone, even from within a step's send, so
 * that reap() runs after the batch. Any may be NULL. */
struct wsg_transport_host {
    void (*enter)(void *ctx);
    void (*leave)(void *ctx);
    void (*defer)(void *ctx);
    void *ctx;
};

/* What the web page's settings change on a running transport. */
struct wsg_transport_settings {
    int check_crc; /* check received checksums */
    int text;      /* TCP: GCL instead of the binary protocol */
};

/* A view of the bytes a transport receives and sends, as they cross its
 * descriptors (the capture, --capture): a tap is called with each read's
 * bytes and each packet written (queued or not), and when a TCP connection
 * opens and closes. The transport owns the flow; the tap keeps what it
 * needs of a connection's history (TCP sequence numbers) in its tap_seq,
 * so the tap holds no table of its own. */
enum wsg_tap_kind { WSG_TAP_TCP = 1, WSG_TAP_UDP, WSG_TAP_PTY, WSG_TAP_CAN };
enum wsg_tap_event {
    WSG_TAP_IN,   /* bytes the gripper received */
    WSG_TAP_OUT,  /* bytes the gripper sent */
    WSG_TAP_OPEN, /* a TCP connection was accepted */
    WSG_TAP_CLOSE /* it ends */
};
struct wsg_tap_flow {
    uint8_t kind;        /* enum wsg_tap_kind */
    uint8_t local_ip[4]; /* TCP, UDP: a.b.c.d in this order */
    uint8_t peer_ip[4];  /* TCP, UDP */
    uint16_t local_port; /* host order */
    uint16_t peer_port;  /* UDP: the datagram's source, or where the
                            answer goes */
    uint32_t can_id;     /* CAN: the frame's identifier */
    uint32_t tap_seq[2]; /* the tap's: bytes seen in and out */
};
struct wsg_tap {
    void (*fn)(void *ctx, struct wsg_tap_flow *f, enum wsg_tap_event ev,
               const uint8_t *data, size_t len);
    void *ctx;
    const int *on; /* nonzero while the tap wants anything */
};

struct wsg_transport_ops {
    const char *name; /* key on the ready line: "tcp" */
    /* Open from cfg (this transport's config struct); on failure put a
     * one-line reason (naming the address) in err and return -errno. */
    int (*open)(struct wsg_transport *t, const struct wsg_transport_env *env,
                const void *cfg, char *err, size_t errlen);
    /* Close every peer (wsg_device_session_closed first), free all. */
    void (*close)(struct wsg_transport *t);
    /* An event on one of the transport's watches. Must not free anything
     * a later event of the same batch may name: peers that go away are
     * only marked (wsg_transport_defer), and freed by reap. */
    void (*handle)(struct wsg_transport *t, struct wsg_watch *w,
                   uint32_t events);
    /* The value for the ready line, e.g. "127.0.0.1:41234". */
    int (*describe)(const struct wsg_transport *t, char *buf, size_t len);
    /* Optional (NULL: no sessions). A live session by tag, else NULL. */
    struct wsg_session *(*lookup)(struct wsg_transport *t, uint32_t tag);
    /* Optional. After a batch: finish closing marked peers. */
    void (*reap)(struct wsg_transport *t);
    /* Optional (the control channel's drop). End every connection as if
     * its peer had gone: the device is told at once, the sockets are
     * closed by reap. Returns how many were dropped. */
    unsigned (*drop_all)(struct wsg_transport *t);
    /* Optional (the web page's settings). Take s: the checksum check at
     * once, for the packets being received too; the text interface for
     * connections accepted from now on (one open keeps the protocol it
     * started with: switching in the middle of a stream would misread
     * it). */
    void (*configure)(struct wsg_transport *t,
                      const struct wsg_transport_settings *s);
};

struct wsg_transport {
    const struct wsg_transport_ops *ops;
    void *state;       /* the transport's own struct */
    uint32_t tag_base; /* (index + 1) << WSG_TAG_TRANSPORT_SHIFT */
    struct wsg_transport_host host;
    const struct wsg_tap *tap; /* NULL: none */
};

/* Show the tap (if one is on) an event of flow f. */
static inline void wsg_transport_tap(const struct wsg_transport *t,
                                     struct wsg_tap_flow *f,
                                     enum wsg_tap_event ev,
                                     const uint8_t *data, size_t len)
{
    if (t->tap && *t->tap->on)
        t->tap->fn(t->tap->ctx, f, ev, data, len);
}
struct sockaddr_in;
/* Fill a flow's addresses from socket addresses (either may be NULL). */
void wsg_tap_flow_addrs(struct wsg_tap_flow *f, enum wsg_tap_kind kind,
                        const struct sockaddr_in *local,
                        const struct sockaddr_in *peer);

/* A watch of t on fd: its events go to t->ops->handle, between the host's
 * enter and leave. */
void wsg_transport_watch_init(struct wsg_transport *t, struct wsg_watch *w,
                              int fd);
/* t marked a peer gone: have it reaped after the batch. */
void wsg_transport_defer(struct wsg_transport *t);

extern const struct wsg_transport_ops wsg_tcp_ops;
extern const struct wsg_transport_ops wsg_udp_ops;
extern const struct wsg_transport_ops wsg_pty_ops;
extern const struct wsg_transport_ops wsg_can_ops;

struct sockaddr_in;

/* Room for "a.b.c.d:port". */
#define WSG_ADDR_LEN 24
/* "a.b.c.d:port" of an IPv4 address. */
void wsg_transport_format_addr(char *buf, size_t len,
                               const struct sockaddr_in *sa);
/* A non-blocking TCP socket listening on ep (SO_REUSEADDR: a restarted
 * emulator must not wait out TIME_WAIT); local gets the address it listens
 * on, the port the kernel picked for port 0. Returns the descriptor, or
 * -errno with the reason, naming proto and the address, in err. */
int wsg_transport_listen_tcp(const struct wsg_endpoint *ep, int backlog,
                             const char *proto, char *local, size_t locallen,
                             char *err, size_t errlen);

/* The message for a socket that cannot listen on ADDR:PORT: the reason,
 * the step that failed when it is not the bind (step NULL), and for a port
 * below 1024 refused with EACCES, what to do about it, over several lines
 * (WSG_TRANSPORT_ERR_MAX holds it). err is -errno. */
#define WSG_TRANSPORT_ERR_MAX 1024
void wsg_transport_listen_error(char *buf, size_t len, const char *proto,
                                const char *where, uint16_t port,
                                const char *step, int err);

/* Route a tag to the transport that issued it. */
struct wsg_session *wsg_transport_lookup(struct wsg_transport *ts, size_t n,
                                         uint32_t tag);
/* Every transport's reap (after a batch). */
void wsg_transport_reap(struct wsg_transport *ts, size_t n);

#endif
