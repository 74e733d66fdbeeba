/*
 * What the daemon does with a gripper's transports at once: route a
 * session tag to the transport that issued it and reap deferred closes;
 * the watches that take a transport's events to it between its host's
 * hooks; and what they share: the TCP listeners (the interface and the
 * control channel), addresses and listen errors in messages.
 */
#define _GNU_SOURCE

#include "transport.h"

#include <arpa/inet.h>
#include <errno.h>
#include <netinet/in.h>
#include <stdio.h>
#include <string.h>
#include <sys/socket.h>
#include <unistd.h>

struct wsg_session *wsg_transport_lookup(struct wsg_transport *ts, size_t n,
                                         uint32_t tag)
{
    uint32_t idx = tag >> WSG_TAG_TRANSPORT_SHIFT;
    struct wsg_transport *t;

    if (idx == 0 || idx > n)
        return NULL;
    t = &ts[idx - 1];
    return t->ops->lookup ? t->ops->lookup(t, tag) : NULL;
}

void wsg_transport_reap(struct wsg_transport *ts, size_t n)
{
    size_t i;

    for (i = 0; i < n; i++)
        if (ts[i].ops->reap)
            ts[i].ops->reap(&ts[i]);
}

static void wsg_transport_event(struct wsg_watch *w, uint32_t events)
{
    struct wsg_transport *t = w->ctx;

    if (t->host.enter)
        t->host.enter(t->host.ctx);
    t->ops->handle(t, w, events);
    if (t->host.leave)
        t->host.leave(t->host.ctx);
}

void wsg_transport_watch_init(struct wsg_transport *t, struct wsg_watch *w,
                              int fd)
{
    wsg_watch_init(w, fd, wsg_transport_event, t);
}

void wsg_transport_defer(struct wsg_transport *t)
{
    if (t->host.defer)
        t->host.defer(t->host.ctx);
}

void wsg_transport_listen_error(char *buf, size_t len, const char *proto,
                                const char *where, uint16_t port,
                                const char *step, int err)
{
    char self[256];
    ssize_t n;

    /* The commonest first-run failure: the defaults' TCP port 1000 (and
     * the web page's 80) for an ordinary user. Every way out is named,
     * with this program's own path for setcap, which a rebuild undoes. */
    if (err == -EACCES && port < 1024 && !step) {
        n = readlink("/proc/self/exe", self, sizeof self - 1);
        if (n <= 0 || (size_t)n >= sizeof self - 1)
            strcpy(self, "PROGRAM");
        else
            self[n] = '\0';
        snprintf(buf, len,
                 "cannot listen on %s %s: %s: ports below 1024 need root or "
                 "CAP_NET_BIND_SERVICE.\n"
                 "  As an ordinary user give --%s 127.0.0.1:PORT%s with a "
                 "PORT from 1024 up (0: a free one).\n"
                 "  For port %u itself run it as root (sudo), or let this "
                 "program bind low ports:\n"
                 "    sudo setcap cap_net_bind_service=+ep %s\n"
                 "  (setcap is in Debian's libcap2-bin; a rebuild drops the "
                 "capability), or run the\n"
                 "  container image or the Debian package's wsgemu service "
                 "(README: Port 1000).",
                 proto, where, strerror(-err), proto,
                 strcmp(proto, "udp") == 0 ? ":REMOTE" : "", (unsigned)port,
                 self);
    } else if (!step)
        snprintf(buf, len, "cannot listen on %s %s: %s", proto, where,
                 strerror(-err));
    else
        snprintf(buf, len, "cannot listen on %s %s: %s: %s", proto, where,
                 step, strerror(-err));
}

void wsg_transport_format_addr(char *buf, size_t len,
                               const struct sockaddr_in *sa)
{
    char ip[INET_ADDRSTRLEN];

    if (!inet_ntop(AF_INET, &sa->sin_addr, ip, sizeof ip))
        strcpy(ip, "?");
    snprintf(buf, len, "%s:%u", ip, (unsigned)ntohs(sa->sin_port));
}

int wsg_transport_listen_tcp(const struct wsg_endpoint *ep, int backlog,
                             const char *proto, char *local, size_t locallen,
                             char *err, size_t errlen)
{
    struct sockaddr_in sa;
    socklen_t salen = sizeof sa;
    char where[WSG_ADDR_LEN];
    const char *step = "socket";
    int one = 1;
    int fd, r;

    memset(&sa, 0, sizeof sa);
    sa.sin_family = AF_INET;
    memcpy(&sa.sin_addr.s_addr, ep->addr, 4);
    sa.sin_port = htons(ep->port);
    wsg_transport_format_addr(where, sizeof where, &sa);
    fd = socket(AF_INET, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
    if (fd < 0)
        goto fail;
    step = "SO_REUSEADDR";
    if (setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one) < 0)
        goto fail;
    step = NULL; /* the usual failure: the reason says it all */
    if (bind(fd, (struct sockaddr *)&sa, sizeof sa) < 0)
        goto fail;
    step = "listen";
    if (listen(fd, backlog) < 0)
        goto fail;
    step = "getsockname";
    if (getsockname(fd, (struct sockaddr *)&sa, &salen) < 0)
        goto fail;
    wsg_transport_format_addr(local, locallen, &sa);
    return fd;

fail:
    r = -errno;
    wsg_transport_listen_error(err, errlen, proto, where, ep->port, step, r);
    if (fd >= 0)
        close(fd);
    return r;
}

void wsg_tap_flow_addrs(struct wsg_tap_flow *f, enum wsg_tap_kind kind,
                        const struct sockaddr_in *local,
                        const struct sockaddr_in *peer)
{
    f->kind = (uint8_t)kind;
    if (local) {
        memcpy(f->local_ip, &local->sin_addr.s_addr, 4);
        f->local_port = ntohs(local->sin_port);
    }
    if (peer) {
        memcpy(f->peer_ip, &peer->sin_addr.s_addr, 4);
        f->peer_port = ntohs(peer->sin_port);
    }
}
