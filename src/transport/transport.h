/*
 * The interface every host interface of the emulator implements (TCP, UDP,
 * pty, CAN, and the control channel): an ops table plus a small record. A
 * transport keeps all its state in its own struct behind t->state and
 * registers its descriptors with the loop through struct wsg_watch.
 *
 * Session tags carry the transport's index in their top bits, so the
 * device's single lookup callback finds the owning transport in O(1) and the
 * transport resolves the rest (typically a slot index plus a generation).
 */
#ifndef WSG_TRANSPORT_H
#define WSG_TRANSPORT_H

#include <stddef.h>
#include <stdint.h>

#include "loop.h"
#include "options.h"
#include "wsg/device.h"

#define WSG_TRANSPORT_MAX 8u
/* tag = (index + 1) << 28 | local: never 0, at most 15 transports. */
#define WSG_TAG_TRANSPORT_SHIFT 28
#define WSG_TAG_LOCAL_MASK      ((1u << WSG_TAG_TRANSPORT_SHIFT) - 1u)

struct wsg_transport;
struct wsg_gripper;

/* What a transport gets from the daemon when it opens. opt holds this
 * gripper's own interface settings (a fleet counts them up per gripper)
 * and lives only during open: keep copies, not pointers. */
struct wsg_transport_env {
    struct wsg_loop *loop;
    struct wsg_device *dev; /* NULL for the control channel */
    const struct wsg_options *opt;
    struct wsg_gripper *gripper;
};

struct wsg_transport_ops {
    const char *name; /* key on the ready line: "tcp" */
    /* Open from env->opt; on failure put a one-line reason (naming the
     * address) in err and return -errno. */
    int (*open)(struct wsg_transport *t, const struct wsg_transport_env *env,
                char *err, size_t errlen);
    /* Close every peer (wsg_device_session_closed first), free all. */
    void (*close)(struct wsg_transport *t);
    /* An epoll event on one of the transport's watches. Must not free
     * anything a later event of the same epoll_wait batch may name: peers
     * that go away are only marked, and freed by settle. */
    void (*handle)(struct wsg_transport *t, struct wsg_watch *w,
                   uint32_t events);
    /* The value for the ready line, e.g. "127.0.0.1:41234". */
    int (*describe)(const struct wsg_transport *t, char *buf, size_t len);
    /* Optional (NULL: no sessions). A live session by tag, else NULL. */
    struct wsg_session *(*lookup)(struct wsg_transport *t, uint32_t tag);
    /* Optional. Between epoll batches: finish closing marked peers. */
    void (*settle)(struct wsg_transport *t);
    /* Optional (the control channel's drop). End every connection as if
     * its peer had gone: only marked, so settle closes them the usual way
     * and a close without 07h brings the FAST STOP rule. Returns how many
     * were dropped. */
    unsigned (*drop_all)(struct wsg_transport *t);
};

struct wsg_transport {
    const struct wsg_transport_ops *ops;
    void *state;       /* the transport's own struct */
    uint32_t tag_base; /* (index + 1) << WSG_TAG_TRANSPORT_SHIFT */
    /* Whose interface it is (NULL: the process's, the control channel):
     * the loop brings that gripper's time up to date before its events. */
    struct wsg_gripper *gripper;
};

extern const struct wsg_transport_ops wsg_tcp_ops;
extern const struct wsg_transport_ops wsg_udp_ops;
extern const struct wsg_transport_ops wsg_pty_ops;
extern const struct wsg_transport_ops wsg_can_ops;
/* Not a gripper interface: the control channel (control.c), opened last so
 * that it ends the ready line. */
extern const struct wsg_transport_ops wsg_control_ops;

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
 * below 1024 refused with EACCES, what to do about it. err is -errno. */
void wsg_transport_listen_error(char *buf, size_t len, const char *proto,
                                const char *where, uint16_t port,
                                const char *step, int err);

/* Route a tag to the transport that issued it. */
struct wsg_session *wsg_transport_lookup(struct wsg_transport *ts, size_t n,
                                         uint32_t tag);
void wsg_transport_settle(struct wsg_transport *ts, size_t n);

#endif
