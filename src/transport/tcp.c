/*
 * The TCP interface (the real gripper's port 1000): a listening socket and
 * up to WSG_TCP_CONN_MAX connections, each with its own parser, session and
 * bounded output queue.
 *
 * Drivers read a reply with a single recv(), so every packet leaves in one
 * send() whenever the socket takes it whole. When it does not, the rest and
 * every later packet wait in the connection's queue, in order, until
 * EPOLLOUT; a client that lets its queue grow past WSG_OUTQ_MAX (64 KiB) is
 * dropped rather than slowing anyone else down. Nothing ever blocks.
 *
 * That bound is only real if the kernel's side is bounded too: with send
 * buffer autotuning a socket of a client that never reads absorbs megabytes
 * (up to tcp_wmem's maximum) before the queue sees a byte, so every accepted
 * socket gets a fixed SO_SNDBUF. Output held for one connection is then at
 * most the kernel's buffer plus the queue.
 *
 * At most --max-clients connections are served; a further one is accepted
 * and closed at once (the client sees the end of the stream instead of
 * hanging in the backlog), and the refusal is logged once per burst.
 *
 * A connection that ends (EOF, error, dropped) is only marked during the
 * event batch, because the device may be in the middle of a call that sends
 * to it and later events of the batch may name it; settle then reports it to
 * the device (the FAST STOP rule) and frees it.
 *
 * Tags: transport base | generation << 8 | slot. The slot makes lookup
 * O(1); the generation, counted per accepted connection, keeps a slot's
 * next occupant from receiving a result meant for its previous one.
 */
#define _GNU_SOURCE

#include <arpa/inet.h>
#include <errno.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/epoll.h>
#include <sys/socket.h>
#include <unistd.h>

#include "outq.h"
#include "transport.h"

#define WSG_TCP_SLOT_BITS         8
#define WSG_TCP_CONN_MAX          (1u << WSG_TCP_SLOT_BITS)
#define WSG_TCP_SLOT_MASK         (WSG_TCP_CONN_MAX - 1u)
#define WSG_TCP_GEN_MASK          (WSG_TAG_LOCAL_MASK >> WSG_TCP_SLOT_BITS)
#define WSG_TCP_READ_CHUNK        4096u
#define WSG_TCP_READS_PER_EVENT   16
#define WSG_TCP_ACCEPTS_PER_EVENT 16
#define WSG_TCP_BACKLOG           64
/* Per accepted socket. Linux doubles it for its bookkeeping. */
#define WSG_TCP_SNDBUF 65536

struct wsg_tcp;

struct wsg_tcp_conn {
    struct wsg_watch watch; /* first: epoll hands back &watch */
    struct wsg_tcp *tcp;
    unsigned slot;
    int dead;
    /* Dropped for not reading: closed with a reset (see conn_free). */
    int reset;
    /* The device already knows it is gone (the control channel's drop
     * tells it at once, before the close that follows the batch). */
    int reported;
    uint32_t events; /* as registered with epoll */
    char peer[WSG_ADDR_LEN];
    struct wsg_parser parser;
    struct wsg_session session;
    struct wsg_outq out; /* last: its buffer needs no initial value */
};

struct wsg_tcp {
    struct wsg_watch watch; /* the listening socket */
    struct wsg_transport *t;
    struct wsg_reactor *reactor;
    struct wsg_device *dev;
    uint32_t tag_base;
    int check_crc;
    /* Held to be given up when accept hits EMFILE, so the pending
     * connection can be taken and closed instead of waking us forever. */
    int spare_fd;
    uint32_t next_gen;
    unsigned max_clients;
    /* Refused since the last time a connection ended: only the first of a
     * burst is logged, so a connection storm cannot flood stderr. */
    unsigned refused;
    unsigned nconns;
    unsigned ndead;
    char local[WSG_ADDR_LEN];
    struct wsg_tcp_conn *slots[WSG_TCP_CONN_MAX];
};

static void conn_kill(struct wsg_tcp_conn *c, const char *why)
{
    if (c->dead)
        return;
    c->dead = 1;
    c->tcp->ndead++;
    /* Settled after the batch, also when a step's send ended it. */
    wsg_transport_defer(c->tcp->t);
    if (why)
        fprintf(stderr, "wsgemu: tcp %s: closing: %s\n", c->peer, why);
}

static void conn_set_events(struct wsg_tcp_conn *c, uint32_t events)
{
    int r;

    if (c->events == events)
        return;
    r = wsg_reactor_mod(c->tcp->reactor, &c->watch, events);
    if (r < 0) {
        conn_kill(c, strerror(-r));
        return;
    }
    c->events = events;
}

static int send_errno_is_peer_gone(int e)
{
    return e == EPIPE || e == ECONNRESET || e == ETIMEDOUT ||
           e == EHOSTUNREACH || e == ENETUNREACH;
}

static void conn_send_failed(struct wsg_tcp_conn *c, int err)
{
    conn_kill(c, send_errno_is_peer_gone(err) ? NULL : strerror(err));
}

/* After a send or a flush: watch EPOLLOUT while bytes wait; a client whose
 * queue overflows is dropped rather than slowing anyone else down. */
static void conn_sent(struct wsg_tcp_conn *c, int r)
{
    if (r == -ENOBUFS) {
        c->reset = 1;
        conn_kill(c, "output queue over 64 KiB (client not reading)");
    } else if (r < 0)
        conn_send_failed(c, -r);
    else if (r)
        conn_set_events(c, c->events | EPOLLOUT);
    else
        conn_set_events(c, c->events & ~(uint32_t)EPOLLOUT);
}

/* The session's send callback: one packet. */
static void conn_packet(struct wsg_session *s, const uint8_t *pkt, size_t len)
{
    struct wsg_tcp_conn *c = s->ctx;

    if (!c->dead)
        conn_sent(c, wsg_outq_send(&c->out, c->watch.fd, pkt, len));
}

static void conn_flush(struct wsg_tcp_conn *c)
{
    if (!c->dead)
        conn_sent(c, wsg_outq_flush(&c->out, c->watch.fd));
}

static void conn_read(struct wsg_tcp_conn *c)
{
    uint8_t buf[WSG_TCP_READ_CHUNK];
    int i;

    /* Bounded, so one busy client cannot starve the others or the model's
     * steps; the level-triggered watch brings us back for the rest. */
    for (i = 0; i < WSG_TCP_READS_PER_EVENT && !c->dead; i++) {
        ssize_t n = recv(c->watch.fd, buf, sizeof buf, MSG_DONTWAIT);

        if (n > 0) {
            wsg_device_input(c->tcp->dev, &c->session, &c->parser, buf,
                             (size_t)n);
            if ((size_t)n < sizeof buf)
                return;
            continue;
        }
        if (n == 0) {
            conn_kill(c, NULL);
            return;
        }
        if (errno == EINTR)
            continue;
        if (errno == EAGAIN || errno == EWOULDBLOCK)
            return;
        conn_kill(c, errno == ECONNRESET || errno == ETIMEDOUT
                         ? NULL
                         : strerror(errno));
        return;
    }
}

static void conn_free(struct wsg_tcp *tcp, struct wsg_tcp_conn *c)
{
    wsg_reactor_del(tcp->reactor, &c->watch);
    if (c->reset) {
        /* A plain close would queue the FIN behind the output the client
         * does not read: it would never learn that it was dropped, and
         * the kernel would keep that output for an orphaned socket until
         * its retries run out. Linger 0 resets at once and frees it. */
        struct linger lg = {1, 0};

        setsockopt(c->watch.fd, SOL_SOCKET, SO_LINGER, &lg, sizeof lg);
    }
    close(c->watch.fd);
    tcp->slots[c->slot] = NULL;
    tcp->nconns--;
    tcp->refused = 0; /* room again: the next refusal starts a burst */
    if (c->dead)
        tcp->ndead--;
    free(c);
}

/* Report the close to the device while the session still exists, then make
 * it unreachable. */
static void conn_close(struct wsg_tcp *tcp, struct wsg_tcp_conn *c)
{
    if (!c->dead) {
        c->dead = 1;
        tcp->ndead++;
    }
    if (!c->reported)
        wsg_device_session_closed(tcp->dev, &c->session);
    conn_free(tcp, c);
}

static int free_slot(const struct wsg_tcp *tcp)
{
    unsigned i;

    for (i = 0; i < WSG_TCP_CONN_MAX; i++)
        if (!tcp->slots[i])
            return (int)i;
    return -1;
}

static uint32_t next_tag(struct wsg_tcp *tcp, unsigned slot)
{
    uint32_t gen = tcp->next_gen;

    tcp->next_gen = (gen + 1) & WSG_TCP_GEN_MASK;
    return tcp->tag_base | gen << WSG_TCP_SLOT_BITS | slot;
}

static void accept_overflow(struct wsg_tcp *tcp, int err)
{
    int fd;

    if (tcp->spare_fd < 0)
        return;
    close(tcp->spare_fd);
    fd = accept4(tcp->watch.fd, NULL, NULL, SOCK_CLOEXEC);
    if (fd >= 0)
        close(fd);
    tcp->spare_fd = open("/dev/null", O_RDONLY | O_CLOEXEC);
    fprintf(stderr, "wsgemu: tcp %s: refused a connection: %s\n", tcp->local,
            strerror(err));
}

static void conn_accept(struct wsg_tcp *tcp, int fd,
                        const struct sockaddr_in *peer)
{
    struct wsg_tcp_conn *c;
    char name[WSG_ADDR_LEN];
    int one = 1;
    int sndbuf = WSG_TCP_SNDBUF;
    int slot;
    int r;

    wsg_transport_format_addr(name, sizeof name, peer);
    slot = tcp->nconns < tcp->max_clients ? free_slot(tcp) : -1;
    if (slot < 0) {
        /* Accepted only to be closed at once: the client sees a clean
         * refusal instead of hanging in the backlog. Dead connections
         * still count: their slots are freed at the end of the batch. */
        if (tcp->refused++ == 0)
            fprintf(stderr,
                    "wsgemu: tcp %s: refused: %u connections open "
                    "(--max-clients); further refusals are not logged "
                    "until one ends\n",
                    name, tcp->nconns);
        close(fd);
        return;
    }
    /* The queue is the bulk of the struct and needs no initial value. */
    c = malloc(sizeof *c);
    if (!c) {
        fprintf(stderr, "wsgemu: tcp %s: refused: %s\n", name,
                strerror(ENOMEM));
        close(fd);
        return;
    }
    memset(c, 0, offsetof(struct wsg_tcp_conn, out));
    wsg_outq_init(&c->out, 1);
    /* Small replies must leave at once, not wait for Nagle. */
    if (setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one) < 0)
        fprintf(stderr, "wsgemu: tcp %s: TCP_NODELAY: %s\n", name,
                strerror(errno));
    if (setsockopt(fd, SOL_SOCKET, SO_SNDBUF, &sndbuf, sizeof sndbuf) < 0)
        fprintf(stderr, "wsgemu: tcp %s: SO_SNDBUF: %s\n", name,
                strerror(errno));
    wsg_transport_watch_init(tcp->t, &c->watch, fd);
    c->tcp = tcp;
    c->slot = (unsigned)slot;
    c->events = EPOLLIN | EPOLLRDHUP;
    memcpy(c->peer, name, sizeof name);
    r = wsg_reactor_add(tcp->reactor, &c->watch, c->events);
    if (r < 0) {
        fprintf(stderr, "wsgemu: tcp %s: refused: %s\n", name, strerror(-r));
        close(fd);
        free(c);
        return;
    }
    wsg_parser_init(&c->parser, tcp->check_crc);
    wsg_session_init(&c->session, next_tag(tcp, (unsigned)slot),
                     WSG_SESSION_CONNECTION, conn_packet, c);
    /* For the communication log. */
    snprintf(c->session.peer, sizeof c->session.peer, "tcp %s", c->peer);
    tcp->slots[slot] = c;
    tcp->nconns++;
}

static void on_listen(struct wsg_tcp *tcp)
{
    int i;

    for (i = 0; i < WSG_TCP_ACCEPTS_PER_EVENT; i++) {
        struct sockaddr_in peer;
        socklen_t plen = sizeof peer;
        int fd = accept4(tcp->watch.fd, (struct sockaddr *)&peer, &plen,
                         SOCK_NONBLOCK | SOCK_CLOEXEC);

        if (fd < 0) {
            if (errno == EAGAIN || errno == EWOULDBLOCK)
                return;
            if (errno == EMFILE || errno == ENFILE) {
                accept_overflow(tcp, errno);
                return;
            }
            /* ECONNABORTED, EINTR, a network error on one pending
             * connection: the next one may be fine. */
            continue;
        }
        conn_accept(tcp, fd, &peer);
    }
}

static void tcp_handle(struct wsg_transport *t, struct wsg_watch *w,
                       uint32_t events)
{
    struct wsg_tcp *tcp = t->state;
    struct wsg_tcp_conn *c;

    if (w == &tcp->watch) {
        on_listen(tcp);
        return;
    }
    c = (struct wsg_tcp_conn *)w;
    if (c->dead)
        return;
    /* Queued output first: new replies belong behind it. */
    if (events & EPOLLOUT)
        conn_flush(c);
    /* HUP and ERR are read too: data that came before the close (a 07h
     * Disconnect Announcement) must count, and recv reports the error. */
    if (events & (EPOLLIN | EPOLLRDHUP | EPOLLHUP | EPOLLERR))
        conn_read(c);
}

static struct wsg_session *tcp_lookup(struct wsg_transport *t, uint32_t tag)
{
    struct wsg_tcp *tcp = t->state;
    struct wsg_tcp_conn *c = tcp->slots[tag & WSG_TCP_SLOT_MASK];

    if (!c || c->dead || c->session.tag != tag)
        return NULL;
    return &c->session;
}

static void tcp_reap(struct wsg_transport *t)
{
    struct wsg_tcp *tcp = t->state;
    unsigned i;

    for (i = 0; i < WSG_TCP_CONN_MAX && tcp->ndead > 0; i++) {
        struct wsg_tcp_conn *c = tcp->slots[i];

        if (c && c->dead)
            conn_close(tcp, c);
    }
}

static unsigned tcp_drop_all(struct wsg_transport *t)
{
    struct wsg_tcp *tcp = t->state;
    unsigned i, n = 0;

    for (i = 0; i < WSG_TCP_CONN_MAX; i++) {
        struct wsg_tcp_conn *c = tcp->slots[i];

        if (c && !c->dead) {
            conn_kill(c, "dropped by the control channel");
            /* Its consequences (FAST STOP unless it announced the close)
             * are there when the control channel answers, not only after
             * the batch, when the socket is closed. */
            wsg_device_session_closed(tcp->dev, &c->session);
            c->reported = 1;
            n++;
        }
    }
    return n;
}

static int tcp_describe(const struct wsg_transport *t, char *buf, size_t len)
{
    const struct wsg_tcp *tcp = t->state;
    int r = snprintf(buf, len, "%s", tcp->local);

    return r < 0 || (size_t)r >= len ? -ENOSPC : 0;
}

static void tcp_close(struct wsg_transport *t)
{
    struct wsg_tcp *tcp = t->state;
    unsigned i;

    if (!tcp)
        return;
    for (i = 0; i < WSG_TCP_CONN_MAX; i++)
        if (tcp->slots[i])
            conn_close(tcp, tcp->slots[i]);
    if (tcp->watch.fd >= 0) {
        wsg_reactor_del(tcp->reactor, &tcp->watch);
        close(tcp->watch.fd);
    }
    if (tcp->spare_fd >= 0)
        close(tcp->spare_fd);
    free(tcp);
    t->state = NULL;
}

static int tcp_open(struct wsg_transport *t,
                    const struct wsg_transport_env *env, const void *config,
                    char *err, size_t errlen)
{
    const struct wsg_tcp_config *cfg = config;
    struct wsg_tcp *tcp = calloc(1, sizeof *tcp);
    int r;

    if (!tcp) {
        snprintf(err, errlen, "cannot listen on tcp: %s", strerror(ENOMEM));
        return -ENOMEM;
    }
    tcp->t = t;
    tcp->reactor = env->reactor;
    tcp->dev = env->dev;
    tcp->tag_base = t->tag_base;
    tcp->check_crc = cfg->check_crc;
    tcp->max_clients = cfg->max_clients;
    if (tcp->max_clients == 0 || tcp->max_clients > WSG_TCP_CONN_MAX)
        tcp->max_clients = WSG_TCP_CONN_MAX;
    wsg_transport_watch_init(t, &tcp->watch, -1);
    tcp->spare_fd = open("/dev/null", O_RDONLY | O_CLOEXEC);
    r = wsg_transport_listen_tcp(&cfg->ep, WSG_TCP_BACKLOG, "tcp", tcp->local,
                                 sizeof tcp->local, err, errlen);
    if (r < 0)
        goto fail;
    tcp->watch.fd = r;
    r = wsg_reactor_add(tcp->reactor, &tcp->watch, EPOLLIN);
    if (r < 0) {
        snprintf(err, errlen, "cannot listen on tcp %s: epoll: %s", tcp->local,
                 strerror(-r));
        close(tcp->watch.fd);
        goto fail;
    }
    t->state = tcp;
    return 0;

fail:
    if (tcp->spare_fd >= 0)
        close(tcp->spare_fd);
    free(tcp);
    t->state = NULL;
    return r;
}

const struct wsg_transport_ops wsg_tcp_ops = {
    .name = "tcp",
    .open = tcp_open,
    .close = tcp_close,
    .handle = tcp_handle,
    .describe = tcp_describe,
    .lookup = tcp_lookup,
    .reap = tcp_reap,
    .drop_all = tcp_drop_all,
};
