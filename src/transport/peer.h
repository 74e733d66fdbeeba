/*
 * Stream peers: the clients of a listening TCP socket, as the gripper's TCP
 * port and the control channel both keep them. A set holds up to a maximum
 * of peers in numbered slots, each with its watch, its bounded output queue
 * (wsg_outq) and EPOLLOUT watched exactly while bytes wait in it.
 *
 * A peer that ends (EOF, an error, a queue that overflows, its owner's
 * decision) is only marked dead, with one line on stderr when there is a
 * reason worth telling: events later in the same batch may still name it,
 * and its owner may be in the middle of a call that sends to it. Dead peers
 * keep their slots, and count toward the maximum, until the owner reaps the
 * set after the batch; the owner hears of each peer just before it is freed.
 * A peer dropped for not reading can be closed with a reset instead of a
 * FIN (reset_on_overflow, see wsg_peer_free in peer.c).
 *
 * The set knows descriptors and the reactor, nothing of what its owner
 * speaks over them: reading, parsing and sessions stay with the owner, which
 * embeds a struct wsg_peer at the end of a struct of its own that the set
 * allocates and frees.
 */
#ifndef WSG_TRANSPORT_PEER_H
#define WSG_TRANSPORT_PEER_H

#include <stddef.h>
#include <stdint.h>

#include "outq.h"
#include "reactor.h"

/* Slots of a set at most. */
#define WSG_PEER_MAX 256u
/* Room for a peer's name: "a.b.c.d:port" (WSG_ADDR_LEN). */
#define WSG_PEER_NAME_LEN 24

struct wsg_peer_set;

struct wsg_peer {
    struct wsg_watch watch; /* first: epoll hands back &watch */
    struct wsg_peer_set *set;
    unsigned slot;
    uint32_t gen; /* see wsg_peer_config.gen_mask */
    int dead;
    /* Dropped for not reading: closed with a reset (see wsg_peer_free). */
    int reset;
    /* Ended by the other side (a hang-up, a reset, a send refused because
     * it has gone): what it sent before may still wait unread in the
     * socket, for the owner's closed() to take. */
    int gone;
    uint32_t events; /* as registered with epoll */
    char name[WSG_PEER_NAME_LEN];
    struct wsg_outq out; /* last: its buffer needs no initial value */
};

/* The owner's struct around a peer, from the member that holds it. */
#define WSG_PEER_OWNER(p, type, member)                                       \
    ((type *)(void *)((char *)(p)-offsetof(type, member)))

struct wsg_peer_config {
    /* Each peer lives in an owner's struct of size bytes that ends with
     * its struct wsg_peer, at offset. The set allocates it with the
     * owner's part zeroed, and frees it. */
    size_t size, offset;
    /* Peers at once, dead ones not yet reaped included; at most
     * WSG_PEER_MAX. */
    unsigned max;
    /* Nonzero: each peer opened takes the next generation, counted modulo
     * gen_mask + 1, so that a slot's next occupant can be told from its
     * last (a session tag carries both). 0: every generation is 0. */
    uint32_t gen_mask;
    /* The head of the line a peer closed with a reason logs, before
     * ": REASON"; a %s in it stands for the peer's name. */
    const char *log;
    /* Close a peer whose queue overflowed with a reset. */
    int reset_on_overflow;
    /* Fill in the watch of a new peer on fd: the callback and context its
     * events go to. */
    void (*watch)(struct wsg_watch *w, int fd, void *ctx);
    /* Whether a send's errno only says that the peer has gone: it is
     * closed without a line. NULL: EPIPE and ECONNRESET. */
    int (*gone)(int err);
    /* Optional. A peer was marked dead: see that the set is reaped after
     * the batch. */
    void (*defer)(void *ctx);
    /* Optional. A peer is about to be freed (reaped, or the set closed):
     * marked dead, its descriptor still open (and readable: see gone). */
    void (*closed)(struct wsg_peer *p, void *ctx);
    void *ctx;
};

struct wsg_peer_set {
    struct wsg_peer_config cfg;
    struct wsg_reactor *reactor;
    unsigned n;     /* occupied slots */
    unsigned ndead; /* of them, marked dead and not yet reaped */
    uint32_t next_gen;
    struct wsg_peer *slots[WSG_PEER_MAX];
};

/* An empty set (cfg is copied; a max above WSG_PEER_MAX is cut to it). */
void wsg_peer_set_init(struct wsg_peer_set *s, struct wsg_reactor *r,
                       const struct wsg_peer_config *cfg);
/* Close and free every peer, live or dead (cfg.closed for each). */
void wsg_peer_set_fini(struct wsg_peer_set *s);
/* No room for another peer until one is reaped. */
int wsg_peer_full(const struct wsg_peer_set *s);
/* Take the connected, non-blocking fd as a peer in the lowest free slot,
 * watched for input; name may be NULL. Returns 0 with *out set, -EBUSY
 * when the set is full, -ENOMEM, or -errno from epoll. On failure fd is
 * the caller's to close. */
int wsg_peer_open(struct wsg_peer_set *s, int fd, const char *name,
                  struct wsg_peer **out);
/* The live peer in slot, else NULL (none, dead, or slot out of range). */
struct wsg_peer *wsg_peer_live(const struct wsg_peer_set *s, unsigned slot);
/* Mark p dead, to be freed when the set is reaped; why, if not NULL, is
 * logged. Once: a dead peer stays as it is. */
void wsg_peer_kill(struct wsg_peer *p, const char *why);
/* Send one packet (nothing to a dead peer): it leaves at once or waits in
 * the queue, EPOLLOUT watched meanwhile; a queue that overflows, or a send
 * that fails, kills p. */
void wsg_peer_send(struct wsg_peer *p, const uint8_t *pkt, size_t len);
/* An event on p's watch: waiting output goes out first (new output belongs
 * behind it). Returns 1 when the owner should read (p is alive, and data, a
 * hang-up or an error has come: recv tells which), else 0. */
int wsg_peer_ready(struct wsg_peer *p, uint32_t events);
/* After a batch: free the dead peers (cfg.closed for each first). */
void wsg_peer_reap(struct wsg_peer_set *s);

#endif
