/*
 * The UDP interface, as on a real gripper: requests arrive on one port
 * (1500), and every answer goes to the sender's IP address at the
 * configured remote port (1501), not to the datagram's source port: drivers
 * send from an ephemeral port and receive on a socket bound to 1501.
 *
 * Opt-in (remote port 0, "--udp ADDR:PORT:source"), and not what a real
 * gripper does: answers go to the port the peer's datagram came from, so
 * a client that sends and receives on one socket (socat, nc, a container
 * behind NAT, whose reply port is not its own) hears them. The peer is
 * still its IP address; its answers, final results and streams follow the
 * source port of its last datagram.
 *
 * One packet per datagram. Each datagram is parsed on its own: several
 * packets in one are each answered, and a packet cut off at the end of a
 * datagram is answered E_CMD_FORMAT_ERROR, never joined with the next.
 *
 * A peer is an IP address (that is where its answers go): it has a session
 * with its own auto-update streams and receives the final results of the
 * motions it started. The peer table is bounded; a new address evicts the
 * one heard from least recently.
 */
#define _GNU_SOURCE

#include <arpa/inet.h>
#include <errno.h>
#include <netinet/in.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/epoll.h>
#include <sys/socket.h>
#include <unistd.h>

#include "transport.h"

#define WSG_UDP_PEER_BITS           5
#define WSG_UDP_PEERS               (1u << WSG_UDP_PEER_BITS)
#define WSG_UDP_PEER_MASK           (WSG_UDP_PEERS - 1u)
#define WSG_UDP_GEN_MASK            (WSG_TAG_LOCAL_MASK >> WSG_UDP_PEER_BITS)
#define WSG_UDP_DATAGRAMS_PER_EVENT 64
#define WSG_UDP_ADDR_LEN            (INET_ADDRSTRLEN + 6)

struct wsg_udp;

struct wsg_udp_peer {
    struct wsg_udp *udp;
    int used;
    uint64_t heard;        /* the udp->clock of its last datagram */
    struct sockaddr_in to; /* sender's IP, the remote (or source) port */
    /* The address its last datagram came to (the capture's local side):
     * the bound one, or, bound to every address, the one it sent to. */
    struct sockaddr_in local;
    struct wsg_session session;
};

struct wsg_udp {
    struct wsg_watch watch;
    struct wsg_device *dev;
    struct wsg_reactor *reactor;
    struct wsg_transport *t;
    struct sockaddr_in bound; /* where it listens (the capture's address) */
    uint8_t *rx;              /* the shared receive buffer */
    size_t rxlen;
    uint32_t tag_base;
    int check_crc;
    uint16_t remote_port; /* 0: answer to the source port */
    uint32_t next_gen;
    uint64_t clock;
    uint64_t send_drops; /* answers the socket would not take */
    char local[WSG_UDP_ADDR_LEN];
    struct wsg_udp_peer peers[WSG_UDP_PEERS];
};

/* The session's send callback: one packet, one datagram. UDP may lose
 * datagrams anyway, so one the socket will not take now is dropped. */
static void udp_packet(struct wsg_session *s, const uint8_t *pkt, size_t len)
{
    struct wsg_udp_peer *p = s->ctx;
    ssize_t n;

    if (p->udp->t->tap && *p->udp->t->tap->on) {
        struct wsg_tap_flow f = {0};

        wsg_tap_flow_addrs(&f, WSG_TAP_UDP, &p->local, &p->to);
        wsg_transport_tap(p->udp->t, &f, WSG_TAP_OUT, pkt, len);
    }
    n = sendto(p->udp->watch.fd, pkt, len, MSG_DONTWAIT | MSG_NOSIGNAL,
               (const struct sockaddr *)&p->to, sizeof p->to);
    if (n != (ssize_t)len)
        p->udp->send_drops++;
}

static struct wsg_udp_peer *udp_peer(struct wsg_udp *udp,
                                     const struct sockaddr_in *from)
{
    struct wsg_udp_peer *p, *oldest = NULL;
    unsigned i;

    for (i = 0; i < WSG_UDP_PEERS; i++) {
        p = &udp->peers[i];
        if (p->used && p->to.sin_addr.s_addr == from->sin_addr.s_addr) {
            if (udp->remote_port == 0)
                p->to.sin_port = from->sin_port; /* its last sender */
            return p;
        }
        if (!oldest || !p->used || (oldest->used && p->heard < oldest->heard))
            oldest = p;
    }
    /* A new address: a free slot or the least recently heard peer, whose
     * streams end with it. */
    p = oldest;
    if (p->used)
        wsg_device_session_closed(udp->dev, &p->session);
    i = (unsigned)(p - udp->peers);
    memset(&p->to, 0, sizeof p->to);
    p->to.sin_family = AF_INET;
    p->to.sin_addr = from->sin_addr;
    p->to.sin_port =
        udp->remote_port ? htons(udp->remote_port) : from->sin_port;
    p->udp = udp;
    p->used = 1;
    wsg_session_init(&p->session,
                     udp->tag_base | udp->next_gen << WSG_UDP_PEER_BITS | i, 0,
                     udp_packet, p);
    {
        /* For the communication log: replies go to this address. */
        char ip[INET_ADDRSTRLEN] = "?";

        inet_ntop(AF_INET, &from->sin_addr, ip, sizeof ip);
        snprintf(p->session.peer, sizeof p->session.peer, "udp %s", ip);
    }
    udp->next_gen = (udp->next_gen + 1) & WSG_UDP_GEN_MASK;
    return p;
}

static void udp_handle(struct wsg_transport *t, struct wsg_watch *w,
                       uint32_t events)
{
    struct wsg_udp *udp = t->state;
    int i;

    (void)w;
    if (!(events & EPOLLIN))
        return;
    /* Bounded, so a flood cannot starve the model's steps. */
    for (i = 0; i < WSG_UDP_DATAGRAMS_PER_EVENT; i++) {
        struct sockaddr_in from, local = udp->bound;
        struct iovec iov = {udp->rx, udp->rxlen};
        union {
            char buf[CMSG_SPACE(sizeof(struct in_pktinfo))];
            struct cmsghdr align;
        } ctl;
        struct msghdr mh;
        struct cmsghdr *cm;
        struct wsg_udp_peer *p;
        ssize_t n;

        memset(&mh, 0, sizeof mh);
        mh.msg_name = &from;
        mh.msg_namelen = sizeof from;
        mh.msg_iov = &iov;
        mh.msg_iovlen = 1;
        mh.msg_control = ctl.buf;
        mh.msg_controllen = sizeof ctl.buf;
        n = recvmsg(udp->watch.fd, &mh, MSG_DONTWAIT);
        if (n < 0) {
            if (errno == EINTR)
                continue;
            return; /* EAGAIN, or an ICMP error of an earlier send */
        }
        if (mh.msg_namelen < sizeof from || from.sin_family != AF_INET)
            continue;
        for (cm = CMSG_FIRSTHDR(&mh); cm; cm = CMSG_NXTHDR(&mh, cm)) {
            struct in_pktinfo pi;

            if (cm->cmsg_level != IPPROTO_IP || cm->cmsg_type != IP_PKTINFO)
                continue;
            memcpy(&pi, CMSG_DATA(cm), sizeof pi);
            local.sin_addr = pi.ipi_addr;
        }
        if (t->tap && *t->tap->on) {
            struct wsg_tap_flow f = {0};

            wsg_tap_flow_addrs(&f, WSG_TAP_UDP, &local, &from);
            wsg_transport_tap(t, &f, WSG_TAP_IN, udp->rx, (size_t)n);
        }
        p = udp_peer(udp, &from);
        p->local = local;
        p->heard = ++udp->clock;
        wsg_device_input_datagram(udp->dev, &p->session, udp->check_crc,
                                  udp->rx, (size_t)n);
    }
}

static struct wsg_session *udp_lookup(struct wsg_transport *t, uint32_t tag)
{
    struct wsg_udp *udp = t->state;
    struct wsg_udp_peer *p = &udp->peers[tag & WSG_UDP_PEER_MASK];

    return p->used && p->session.tag == tag ? &p->session : NULL;
}

static int udp_describe(const struct wsg_transport *t, char *buf, size_t len)
{
    const struct wsg_udp *udp = t->state;
    int r = udp->remote_port ? snprintf(buf, len, "%s>%u", udp->local,
                                        (unsigned)udp->remote_port)
                             : snprintf(buf, len, "%s>source", udp->local);

    return r < 0 || (size_t)r >= len ? -ENOSPC : 0;
}

static void udp_close(struct wsg_transport *t)
{
    struct wsg_udp *udp = t->state;

    if (!udp)
        return;
    if (udp->watch.fd >= 0) {
        wsg_reactor_del(udp->reactor, &udp->watch);
        close(udp->watch.fd);
    }
    free(udp);
    t->state = NULL;
}

static int udp_open(struct wsg_transport *t,
                    const struct wsg_transport_env *env, const void *config,
                    char *err, size_t errlen)
{
    const struct wsg_udp_config *cfg = config;
    const struct wsg_endpoint *ep = &cfg->ep;
    struct wsg_udp *udp;
    struct sockaddr_in sa;
    socklen_t salen = sizeof sa;
    char ip[INET_ADDRSTRLEN], where[WSG_UDP_ADDR_LEN];
    int r;

    memset(&sa, 0, sizeof sa);
    sa.sin_family = AF_INET;
    memcpy(&sa.sin_addr.s_addr, ep->addr, 4);
    sa.sin_port = htons(ep->port);
    inet_ntop(AF_INET, &sa.sin_addr, ip, sizeof ip);

    udp = calloc(1, sizeof *udp);
    if (!udp) {
        r = -ENOMEM;
        goto fail;
    }
    t->state = udp;
    udp->t = t;
    udp->dev = env->dev;
    udp->reactor = env->reactor;
    udp->rx = env->rx;
    udp->rxlen = env->rxlen;
    udp->tag_base = t->tag_base;
    udp->check_crc = cfg->check_crc;
    udp->remote_port = cfg->remote_port;
    wsg_transport_watch_init(
        t, &udp->watch,
        socket(AF_INET, SOCK_DGRAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0));
    if (udp->watch.fd < 0)
        goto fail_errno;
    if (bind(udp->watch.fd, (struct sockaddr *)&sa, sizeof sa) < 0)
        goto fail_errno;
    if (getsockname(udp->watch.fd, (struct sockaddr *)&sa, &salen) < 0)
        goto fail_errno;
    udp->bound = sa;
    /* Bound to every address: each datagram says which one it came to, so
     * that a capture shows the address the peer sent to, not 0.0.0.0. */
    if (sa.sin_addr.s_addr == htonl(INADDR_ANY)) {
        int on = 1;

        if (setsockopt(udp->watch.fd, IPPROTO_IP, IP_PKTINFO, &on, sizeof on) <
            0)
            goto fail_errno;
    }
    snprintf(udp->local, sizeof udp->local, "%s:%u", ip,
             (unsigned)ntohs(sa.sin_port));
    r = wsg_reactor_add(udp->reactor, &udp->watch, EPOLLIN);
    if (r < 0)
        goto fail;
    return 0;

fail_errno:
    r = -errno;
fail:
    snprintf(where, sizeof where, "%s:%u", ip, (unsigned)ep->port);
    wsg_transport_listen_error(err, errlen, "udp", where, ep->port, NULL, r);
    udp_close(t);
    return r;
}

static void udp_configure(struct wsg_transport *t,
                          const struct wsg_transport_settings *s)
{
    struct wsg_udp *udp = t->state;

    /* Read per datagram: the next one is checked the new way. */
    udp->check_crc = s->check_crc;
}

const struct wsg_transport_ops wsg_udp_ops = {
    .name = "udp",
    .open = udp_open,
    .close = udp_close,
    .handle = udp_handle,
    .describe = udp_describe,
    .lookup = udp_lookup,
    .reap = NULL,
    .configure = udp_configure,
};
