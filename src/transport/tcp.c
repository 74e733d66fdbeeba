/*
 * The TCP interface (the real gripper's port 1000): a listening socket and
 * up to WSG_TCP_CONN_MAX connections, each with its own parser and session.
 * The connections are a set of stream peers (peer.h), which keeps their
 * slots, generations, bounded output queues, closes and reaping; this file
 * accepts them, reads their packets into the device and ties each peer's
 * end to its session.
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
 * to it and later events of the batch may name it; the reap after the batch
 * then reports it to the device (the FAST STOP rule) and frees it. A client
 * that went away (hang-up or reset) may have sent bytes that were not read
 * yet, a 07h above all: they are read and processed before the report
 * (conn_drain). A client dropped for not reading is reset rather than sent
 * a FIN (peer.c says why).
 *
 * With --text-interface every connection speaks GCL (wsg/gcl.h) instead:
 * its bytes go to the interpreter, which answers with lines through the
 * same session, each line in one send().
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

#include "peer.h"
#include "transport.h"

/* 256 slots, all a peer set has (WSG_PEER_MAX). */
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
    struct wsg_tcp *tcp;
    /* The device already knows it is gone (the control channel's drop
     * tells it at once, before the close that follows the batch). */
    int reported;
    int text; /* speaks GCL: the listener's mode when it was accepted */
    struct wsg_parser parser;
    struct wsg_gcl gcl; /* --text-interface: lines instead of packets */
    struct wsg_session session;
    struct wsg_tap_flow flow; /* what the capture sees of it */
    struct wsg_peer peer; /* last: the set allocates the struct around it */
};

struct wsg_tcp {
    struct wsg_watch watch; /* the listening socket */
    struct wsg_transport *t;
    struct wsg_reactor *reactor;
    struct wsg_device *dev;
    uint32_t tag_base;
    int check_crc;
    int text;
    struct wsg_gcl_config gcl;
    /* Held to be given up when accept hits EMFILE, so the pending
     * connection can be taken and closed instead of waking us forever. */
    int spare_fd;
    /* Refused since the last time a connection ended: only the first of a
     * burst is logged, so a connection storm cannot flood stderr. */
    unsigned refused;
    char local[WSG_ADDR_LEN];
    struct wsg_peer_set conns; /* at most --max-clients */
};

static struct wsg_tcp_conn *conn_of(struct wsg_peer *p)
{
    return WSG_PEER_OWNER(p, struct wsg_tcp_conn, peer);
}

static int send_errno_is_peer_gone(int e)
{
    return e == EPIPE || e == ECONNRESET || e == ETIMEDOUT ||
           e == EHOSTUNREACH || e == ENETUNREACH;
}

/* The session's send callback: one packet. */
static void conn_packet(struct wsg_session *s, const uint8_t *pkt, size_t len)
{
    struct wsg_tcp_conn *c = s->ctx;

    if (!c->peer.dead)
        wsg_transport_tap(c->tcp->t, &c->flow, WSG_TAP_OUT, pkt, len);
    wsg_peer_send(&c->peer, pkt, len);
}

/* Bytes from the client: to the interpreter or the device. */
static void conn_feed(struct wsg_tcp_conn *c, const uint8_t *buf, size_t n)
{
    wsg_transport_tap(c->tcp->t, &c->flow, WSG_TAP_IN, buf, n);
    if (c->text)
        wsg_gcl_input(&c->gcl, buf, n);
    else
        wsg_device_input(c->tcp->dev, &c->session, &c->parser, buf, n);
}

static void conn_read(struct wsg_tcp_conn *c)
{
    uint8_t buf[WSG_TCP_READ_CHUNK];
    int i;

    /* Bounded, so one busy client cannot starve the others or the model's
     * steps; the level-triggered watch brings us back for the rest. */
    for (i = 0; i < WSG_TCP_READS_PER_EVENT && !c->peer.dead; i++) {
        ssize_t n = recv(c->peer.watch.fd, buf, sizeof buf, MSG_DONTWAIT);

        if (n > 0) {
            conn_feed(c, buf, (size_t)n);
            if ((size_t)n < sizeof buf)
                return;
            continue;
        }
        if (n == 0) {
            c->peer.gone = 1;
            wsg_peer_kill(&c->peer, NULL);
            return;
        }
        if (errno == EINTR)
            continue;
        if (errno == EAGAIN || errno == EWOULDBLOCK)
            return;
        c->peer.gone = errno == ECONNRESET || errno == ETIMEDOUT;
        wsg_peer_kill(&c->peer, c->peer.gone ? NULL : strerror(errno));
        return;
    }
}

/* The client has gone, and what it sent last may not have been read yet:
 * a client that sends 07h and closes while stream packets are unread
 * resets the connection, and a stream's send can meet that reset before
 * the 07h is read. Linux keeps the bytes that came before a reset or a
 * hang-up readable, so they are taken now, before the close is reported:
 * everything that arrived before the end is processed as it would have
 * been (an announced close is no link loss). Its answers go nowhere: the
 * peer is dead. Bounded like one read event. */
static void conn_drain(struct wsg_tcp_conn *c)
{
    uint8_t buf[WSG_TCP_READ_CHUNK];
    int i;

    for (i = 0; i < WSG_TCP_READS_PER_EVENT; i++) {
        ssize_t n = recv(c->peer.watch.fd, buf, sizeof buf, MSG_DONTWAIT);

        if (n > 0)
            conn_feed(c, buf, (size_t)n);
        else if (n < 0 && errno == EINTR)
            continue;
        if (n < (ssize_t)sizeof buf)
            return;
    }
}

/* A connection about to be freed (reaped, or the transport closed): the
 * device hears of it while the session still exists, unless it already
 * has, and there is room again, so the next refusal starts a burst. */
static void conn_closed(struct wsg_peer *p, void *ctx)
{
    struct wsg_tcp *tcp = ctx;
    struct wsg_tcp_conn *c = conn_of(p);

    if (!c->reported) {
        if (p->gone)
            conn_drain(c);
        wsg_device_session_closed(tcp->dev, &c->session);
    }
    wsg_transport_tap(tcp->t, &c->flow, WSG_TAP_CLOSE, NULL, 0);
    tcp->refused = 0;
}

static void conn_watch(struct wsg_watch *w, int fd, void *ctx)
{
    struct wsg_tcp *tcp = ctx;

    wsg_transport_watch_init(tcp->t, w, fd);
}

/* A connection marked gone, also from within a step's send: settled after
 * the batch. */
static void conn_defer(void *ctx)
{
    struct wsg_tcp *tcp = ctx;

    wsg_transport_defer(tcp->t);
}

static uint32_t conn_tag(const struct wsg_tcp *tcp, const struct wsg_peer *p)
{
    return tcp->tag_base | p->gen << WSG_TCP_SLOT_BITS | p->slot;
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
                        const struct sockaddr_in *addr)
{
    struct wsg_tcp_conn *c;
    struct wsg_peer *p;
    char name[WSG_ADDR_LEN];
    int one = 1;
    int sndbuf = WSG_TCP_SNDBUF;
    int r;

    wsg_transport_format_addr(name, sizeof name, addr);
    if (wsg_peer_full(&tcp->conns)) {
        /* Accepted only to be closed at once: the client sees a clean
         * refusal instead of hanging in the backlog. Dead connections
         * still count: their slots are freed at the end of the batch. */
        if (tcp->refused++ == 0)
            fprintf(stderr,
                    "wsgemu: tcp %s: refused: %u connections open "
                    "(--max-clients); further refusals are not logged "
                    "until one ends\n",
                    name, tcp->conns.n);
        close(fd);
        return;
    }
    r = wsg_peer_open(&tcp->conns, fd, name, &p);
    if (r < 0) {
        fprintf(stderr, "wsgemu: tcp %s: refused: %s\n", name, strerror(-r));
        close(fd);
        return;
    }
    /* Small replies must leave at once, not wait for Nagle. */
    if (setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one) < 0)
        fprintf(stderr, "wsgemu: tcp %s: TCP_NODELAY: %s\n", name,
                strerror(errno));
    if (setsockopt(fd, SOL_SOCKET, SO_SNDBUF, &sndbuf, sizeof sndbuf) < 0)
        fprintf(stderr, "wsgemu: tcp %s: SO_SNDBUF: %s\n", name,
                strerror(errno));
    c = conn_of(p);
    c->tcp = tcp;
    {
        /* The address the client reached, which a listener on 0.0.0.0
         * does not tell. */
        struct sockaddr_in local;
        socklen_t llen = sizeof local;

        if (getsockname(fd, (struct sockaddr *)&local, &llen) < 0)
            memset(&local, 0, sizeof local);
        wsg_tap_flow_addrs(&c->flow, WSG_TAP_TCP, &local, addr);
        wsg_transport_tap(tcp->t, &c->flow, WSG_TAP_OPEN, NULL, 0);
    }
    wsg_parser_init(&c->parser, tcp->check_crc);
    wsg_session_init(&c->session, conn_tag(tcp, p), WSG_SESSION_CONNECTION,
                     conn_packet, c);
    /* For the communication log. */
    snprintf(c->session.peer, sizeof c->session.peer, "tcp %s", p->name);
    wsg_device_session_opened(tcp->dev, &c->session);
    c->text = tcp->text;
    if (c->text)
        wsg_gcl_init(&c->gcl, tcp->dev, &c->session, &tcp->gcl);
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
    struct wsg_peer *p;

    if (w == &tcp->watch) {
        on_listen(tcp);
        return;
    }
    p = (struct wsg_peer *)w;
    /* HUP and ERR are read too: data that came before the close (a 07h
     * Disconnect Announcement) must count, and recv reports the error. */
    if (wsg_peer_ready(p, events))
        conn_read(conn_of(p));
}

static struct wsg_session *tcp_lookup(struct wsg_transport *t, uint32_t tag)
{
    struct wsg_tcp *tcp = t->state;
    struct wsg_peer *p = wsg_peer_live(&tcp->conns, tag & WSG_TCP_SLOT_MASK);

    if (!p || conn_tag(tcp, p) != tag)
        return NULL;
    return &conn_of(p)->session;
}

static void tcp_reap(struct wsg_transport *t)
{
    struct wsg_tcp *tcp = t->state;

    wsg_peer_reap(&tcp->conns);
}

static unsigned tcp_drop_all(struct wsg_transport *t)
{
    struct wsg_tcp *tcp = t->state;
    unsigned i, n = 0;

    for (i = 0; i < tcp->conns.cfg.max; i++) {
        struct wsg_peer *p = wsg_peer_live(&tcp->conns, i);

        if (!p)
            continue;
        wsg_peer_kill(p, "dropped by the control channel");
        /* Its consequences (FAST STOP unless it announced the close) are
         * there when the control channel answers, not only after the
         * batch, when the socket is closed. */
        wsg_device_session_closed(tcp->dev, &conn_of(p)->session);
        conn_of(p)->reported = 1;
        n++;
    }
    return n;
}

static void tcp_configure(struct wsg_transport *t,
                          const struct wsg_transport_settings *s)
{
    struct wsg_tcp *tcp = t->state;
    unsigned i;

    tcp->check_crc = s->check_crc;
    tcp->text = s->text;
    for (i = 0; i < tcp->conns.cfg.max; i++) {
        struct wsg_peer *p = wsg_peer_live(&tcp->conns, i);

        if (p)
            conn_of(p)->parser.check_crc = s->check_crc ? 1 : 0;
    }
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

    if (!tcp)
        return;
    wsg_peer_set_fini(&tcp->conns);
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
    struct wsg_peer_config conns = {
        .size = sizeof(struct wsg_tcp_conn),
        .offset = offsetof(struct wsg_tcp_conn, peer),
        .max = cfg->max_clients,
        .gen_mask = WSG_TCP_GEN_MASK,
        .log = "wsgemu: tcp %s: closing",
        .reset_on_overflow = 1,
        .watch = conn_watch,
        .gone = send_errno_is_peer_gone,
        .defer = conn_defer,
        .closed = conn_closed,
        .ctx = tcp,
    };
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
    tcp->text = cfg->text;
    tcp->gcl = cfg->gcl;
    if (conns.max == 0 || conns.max > WSG_TCP_CONN_MAX)
        conns.max = WSG_TCP_CONN_MAX;
    wsg_peer_set_init(&tcp->conns, tcp->reactor, &conns);
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
    .configure = tcp_configure,
};
