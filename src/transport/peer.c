/*
 * The stream peers of the TCP port and the control channel: slots,
 * generations, the output queue with its EPOLLOUT, marking dead with a
 * reason, and freeing the dead after the batch. See peer.h for the
 * contract.
 */
#define _GNU_SOURCE

#include "peer.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/epoll.h>
#include <sys/socket.h>
#include <unistd.h>

void wsg_peer_set_init(struct wsg_peer_set *s, struct wsg_reactor *r,
                       const struct wsg_peer_config *cfg)
{
    memset(s, 0, sizeof *s);
    s->cfg = *cfg;
    s->reactor = r;
    if (s->cfg.max > WSG_PEER_MAX)
        s->cfg.max = WSG_PEER_MAX;
}

int wsg_peer_full(const struct wsg_peer_set *s)
{
    return s->n >= s->cfg.max;
}

static int wsg_peer_free_slot(const struct wsg_peer_set *s)
{
    unsigned i;

    for (i = 0; i < s->cfg.max; i++)
        if (!s->slots[i])
            return (int)i;
    return -1;
}

int wsg_peer_open(struct wsg_peer_set *s, int fd, const char *name,
                  struct wsg_peer **out)
{
    struct wsg_peer *p;
    char *mem;
    int slot = wsg_peer_full(s) ? -1 : wsg_peer_free_slot(s);
    int r;

    *out = NULL;
    if (slot < 0)
        return -EBUSY;
    /* The queue is the bulk of it and needs no initial value. */
    mem = malloc(s->cfg.size);
    if (!mem)
        return -ENOMEM;
    memset(mem, 0, s->cfg.offset + offsetof(struct wsg_peer, out));
    p = (struct wsg_peer *)(void *)(mem + s->cfg.offset);
    wsg_outq_init(&p->out, 1);
    s->cfg.watch(&p->watch, fd, s->cfg.ctx);
    p->set = s;
    p->slot = (unsigned)slot;
    p->events = EPOLLIN | EPOLLRDHUP;
    snprintf(p->name, sizeof p->name, "%s", name ? name : "");
    r = wsg_reactor_add(s->reactor, &p->watch, p->events);
    if (r < 0) {
        free(mem);
        return r;
    }
    p->gen = s->next_gen;
    s->next_gen = (s->next_gen + 1) & s->cfg.gen_mask;
    s->slots[slot] = p;
    s->n++;
    *out = p;
    return 0;
}

struct wsg_peer *wsg_peer_live(const struct wsg_peer_set *s, unsigned slot)
{
    struct wsg_peer *p = slot < WSG_PEER_MAX ? s->slots[slot] : NULL;

    return p && !p->dead ? p : NULL;
}

static void wsg_peer_mark(struct wsg_peer *p)
{
    if (p->dead)
        return;
    p->dead = 1;
    p->set->ndead++;
}

void wsg_peer_kill(struct wsg_peer *p, const char *why)
{
    struct wsg_peer_set *s = p->set;
    char head[128];

    if (p->dead)
        return;
    wsg_peer_mark(p);
    /* Freed after the batch, also when a send from deep in the owner's
     * call ended it. */
    if (s->cfg.defer)
        s->cfg.defer(s->cfg.ctx);
    if (!why)
        return;
    /* A format without %s ignores the name (C99 7.19.6.1: arguments past
     * the format's are evaluated and ignored). One fprintf: one line. */
    snprintf(head, sizeof head, s->cfg.log, p->name);
    fprintf(stderr, "%s: %s\n", head, why);
}

static void wsg_peer_set_events(struct wsg_peer *p, uint32_t events)
{
    int r;

    if (p->events == events)
        return;
    r = wsg_reactor_mod(p->set->reactor, &p->watch, events);
    if (r < 0) {
        wsg_peer_kill(p, strerror(-r));
        return;
    }
    p->events = events;
}

static int wsg_peer_gone(const struct wsg_peer_set *s, int err)
{
    if (s->cfg.gone)
        return s->cfg.gone(err);
    return err == EPIPE || err == ECONNRESET;
}

/* After a send or a flush: watch EPOLLOUT while bytes wait; a peer whose
 * queue overflows is dropped rather than slowing anyone else down. */
static void wsg_peer_sent(struct wsg_peer *p, int r)
{
    if (r == -ENOBUFS) {
        p->reset = p->set->cfg.reset_on_overflow;
        wsg_peer_kill(p, "output queue over 64 KiB (client not reading)");
    } else if (r < 0) {
        p->gone = wsg_peer_gone(p->set, -r);
        wsg_peer_kill(p, p->gone ? NULL : strerror(-r));
    } else if (r)
        wsg_peer_set_events(p, p->events | EPOLLOUT);
    else
        wsg_peer_set_events(p, p->events & ~(uint32_t)EPOLLOUT);
}

void wsg_peer_send(struct wsg_peer *p, const uint8_t *pkt, size_t len)
{
    if (!p->dead)
        wsg_peer_sent(p, wsg_outq_send(&p->out, p->watch.fd, pkt, len));
}

int wsg_peer_ready(struct wsg_peer *p, uint32_t events)
{
    if (p->dead)
        return 0;
    if (events & EPOLLOUT)
        wsg_peer_sent(p, wsg_outq_flush(&p->out, p->watch.fd));
    return !p->dead && (events & (EPOLLIN | EPOLLRDHUP | EPOLLHUP | EPOLLERR));
}

/* Tell the owner while the peer still exists, then make it unreachable. */
static void wsg_peer_free(struct wsg_peer_set *s, struct wsg_peer *p)
{
    wsg_peer_mark(p);
    if (s->cfg.closed)
        s->cfg.closed(p, s->cfg.ctx);
    wsg_reactor_del(s->reactor, &p->watch);
    if (p->reset) {
        /* A plain close would queue the FIN behind the output the peer
         * does not read: it would never learn that it was dropped, and
         * the kernel would keep that output for an orphaned socket until
         * its retries run out. Linger 0 resets at once and frees it. */
        struct linger lg = {1, 0};

        setsockopt(p->watch.fd, SOL_SOCKET, SO_LINGER, &lg, sizeof lg);
    }
    close(p->watch.fd);
    s->slots[p->slot] = NULL;
    s->n--;
    s->ndead--;
    free((char *)p - s->cfg.offset);
}

void wsg_peer_reap(struct wsg_peer_set *s)
{
    unsigned i;

    for (i = 0; i < s->cfg.max && s->ndead > 0; i++)
        if (s->slots[i] && s->slots[i]->dead)
            wsg_peer_free(s, s->slots[i]);
}

void wsg_peer_set_fini(struct wsg_peer_set *s)
{
    unsigned i;

    for (i = 0; i < s->cfg.max; i++)
        if (s->slots[i])
            wsg_peer_free(s, s->slots[i]);
}
