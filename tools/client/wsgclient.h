/*
 * The client side of the WSG protocol, shared by wsgctl, wsgbench and the
 * integration tests: a link to a gripper (TCP, UDP, a serial line or a
 * pty, or any transport the caller brings as two hooks), frames sent on
 * it, and frames received from it with a deadline: the next one, or the
 * next with a given ID while the others are kept for later, a request and
 * its answer, a motion's final result. Beside it, the line client of the
 * emulator's control channel (one command line out, one line back).
 *
 * Every wait takes an absolute deadline on the monotonic clock
 * (wsg_client_now_ns), so a caller that waits for several things in turn
 * bounds them all at once. Nothing here prints: failures come back as
 * -errno (-EPIPE: the peer closed; -EINTR: the caller's stop flag was
 * raised; -EBADMSG: a malformed packet, see on_bad), and each client words
 * them for its own users.
 */
#ifndef WSG_CLIENT_H
#define WSG_CLIENT_H

#include <signal.h>
#include <stddef.h>
#include <stdint.h>

#include "wsg/proto.h"

/* How the bytes travel: what send, receive and end of stream mean. */
enum wsg_link_kind {
    WSG_LINK_TCP,
    WSG_LINK_UDP,    /* requests to the peer, answers on their own socket */
    WSG_LINK_SERIAL, /* a tty or pty: raw 115200 8N1 */
    WSG_LINK_HOOKS   /* the caller's read and send hooks */
};

/* A received frame, copied out of the parser. */
struct wsg_client_frame {
    uint8_t id;
    uint16_t len;    /* payload length */
    unsigned status; /* a reply's status (payload 0..1); 0xFFFF if shorter */
    uint64_t t_ns;   /* wsg_client_now_ns() when it was parsed */
    uint8_t payload[WSG_REPLY_PAYLOAD_MAX];
};
/* The parameters after the status. */
#define WSG_CLIENT_PARAMS(f)  ((f)->payload + 2)
#define WSG_CLIENT_NPARAMS(f) ((f)->len >= 2 ? (size_t)(f)->len - 2 : 0)

struct wsg_client;

/* A transport of the caller's (WSG_LINK_HOOKS). read waits up to
 * timeout_ms and reads once: the byte count, 0 at the end of the stream,
 * -1 on timeout, -2 on an error. send writes one packet in one piece: 0 or
 * -1. */
struct wsg_client_hooks {
    long (*read)(void *ctx, uint8_t *buf, size_t cap, int timeout_ms);
    int (*send)(void *ctx, const uint8_t *pkt, size_t len);
    void *ctx;
};

struct wsg_client {
    enum wsg_link_kind kind;
    int fd;             /* where requests go */
    int rfd;            /* where answers come from (UDP: another socket) */
    int own_rfd;        /* UDP: rfd is closed with the client */
    uint32_t peer_addr; /* UDP: the gripper's IPv4 address, network order */
    uint16_t peer_port; /* UDP: its port, network order */
    struct wsg_client_hooks hooks;
    /* When not NULL and raised (a signal handler's flag), waits end with
     * -EINTR; they then poll in slices, so a late signal is seen too. */
    volatile sig_atomic_t *stop;
    /* A malformed packet (bad checksum, oversize): counted in bad, then
     * on_bad, if set, decides: 0 goes on, else the receive returns
     * -EBADMSG. Without on_bad the packet is skipped. */
    int (*on_bad)(struct wsg_client *c, enum wsg_parse_event ev, uint8_t id);
    void *user; /* the caller's, for on_bad */
    int eof;
    unsigned seen[256]; /* good frames parsed, per ID */
    unsigned bad;       /* malformed packets */
    /* Frames skipped by wsg_client_recv_id, oldest first, in the caller's
     * storage (wsg_client_keep); none kept (they are dropped) without. */
    struct wsg_client_frame *keep;
    unsigned keep_cap, keep_n;
    struct wsg_parser parser;
    uint8_t in[4096];
    size_t off, len;
};

/* Monotonic nanoseconds, and a deadline ms from now. */
uint64_t wsg_client_now_ns(void);
uint64_t wsg_client_deadline(int ms);

/* A closed client of this kind: no descriptors, an empty buffer. */
void wsg_client_init(struct wsg_client *c, enum wsg_link_kind kind);
/* Keep up to cap frames skipped by wsg_client_recv_id in keep[]. */
void wsg_client_keep(struct wsg_client *c, struct wsg_client_frame *keep,
                     unsigned cap);

struct sockaddr_in;
/* Connect with a timeout (the socket stays non-blocking, reads follow a
 * poll), TCP_NODELAY as drivers do. 0 or -errno. */
int wsg_client_open_tcp(struct wsg_client *c, const struct sockaddr_in *sa,
                        int timeout_ms);
/* Requests to sa; answers on rfd, a socket bound where the gripper
 * answers, closed with the client when own_rfd. Only datagrams from sa's
 * address count. 0 or -errno. */
int wsg_client_open_udp(struct wsg_client *c, const struct sockaddr_in *sa,
                        int rfd, int own_rfd);
/* A serial line or pty as a driver opens one: raw 115200 8N1, input that
 * was waiting for an earlier client flushed. 0 or -errno. */
int wsg_client_open_serial(struct wsg_client *c, const char *path);
/* A UDP socket bound to addr:port (port 0: any), non-blocking; its port
 * into *bound if not NULL. 0 or -errno. */
int wsg_client_udp_bind(uint32_t addr, uint16_t port, int *fd,
                        uint16_t *bound);
/* Close the descriptors (no 07h: that is the caller's to send). */
void wsg_client_close(struct wsg_client *c);

/* One packet, in one write. 0 or -errno (-EIO: a short write). */
int wsg_client_send(struct wsg_client *c, const void *pkt, size_t len);
/* Encode and send. 0, -EMSGSIZE when it does not fit, or -errno. */
int wsg_client_send_frame(struct wsg_client *c, uint8_t id,
                          const void *payload, size_t len);

/* One read of what is there now, into the (consumed) buffer: the byte
 * count, -EAGAIN when nothing was there after all, -EPIPE at the end of
 * the stream, or -errno. For callers that poll many clients at once. */
long wsg_client_read(struct wsg_client *c);
/* Wait for input until deadline and read it: 1, 0 on timeout, or -errno
 * as wsg_client_read (-EINTR when stop was raised). */
int wsg_client_fill(struct wsg_client *c, uint64_t deadline);

/* Next frame: kept ones first, then what is buffered, then the wire until
 * deadline (one look at the wire when it has passed already; deadline 0:
 * only what is buffered). 1, 0 on timeout, or -errno. */
int wsg_client_recv(struct wsg_client *c, struct wsg_client_frame *f,
                    uint64_t deadline);
/* Next frame with this ID; the others are kept. Same returns. */
int wsg_client_recv_id(struct wsg_client *c, uint8_t id,
                       struct wsg_client_frame *f, uint64_t deadline);
/* Send and wait for the first frame with the same ID. Same returns. */
int wsg_client_request(struct wsg_client *c, uint8_t id, const void *payload,
                       size_t len, struct wsg_client_frame *f,
                       uint64_t deadline);
/* After an immediate E_CMD_PENDING in *f: wait for the motion's final
 * result (the next frame with f's ID that is not E_CMD_PENDING) into *f.
 * With any other status in *f, 1 at once. Same returns. */
int wsg_client_final(struct wsg_client *c, struct wsg_client_frame *f,
                     uint64_t deadline);
/* Fill a frame from an ID and payload (len at most the frame's). */
void wsg_client_frame_set(struct wsg_client_frame *f, uint8_t id,
                          const uint8_t *payload, size_t len);

/* ---- the control channel: lines over the same buffer ---- */

/* Send text as it is (one write). 0 or -errno. */
int wsg_client_line_send(struct wsg_client *c, const char *text);
/* The next line, without its newline, into out (cut to cap-1; the rest
 * of the line is dropped). 1, 0 on timeout, or -errno. */
int wsg_client_line_read(struct wsg_client *c, char *out, size_t cap,
                         uint64_t deadline);
/* "cmd\n" out, one line back. Same returns. */
int wsg_client_line(struct wsg_client *c, const char *cmd, char *out,
                    size_t cap, uint64_t deadline);

#endif
