/*
 * The client library of wsgctl, wsgbench and the integration tests (see
 * wsgclient.h): opening links, sending packets, and the one receive loop
 * they share, which reads into a buffer, feeds the core's wsg_parser and
 * hands out frames by deadline, keeping the ones that arrive out of turn.
 */
#define _GNU_SOURCE /* cfmakeraw, SOCK_NONBLOCK, SOCK_CLOEXEC */

#include "wsgclient.h"

#include <arpa/inet.h>
#include <errno.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <stdio.h>
#include <string.h>
#include <sys/socket.h>
#include <termios.h>
#include <time.h>
#include <unistd.h>

#define NS_PER_MS 1000000ull
/* With a stop flag, waits poll in slices this long, so a signal that
 * lands just before poll() is seen. */
#define SLICE_MS 200

uint64_t wsg_client_now_ns(void)
{
    struct timespec ts;

    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (uint64_t)ts.tv_sec * 1000000000ull + (uint64_t)ts.tv_nsec;
}

uint64_t wsg_client_deadline(int ms)
{
    return wsg_client_now_ns() + (uint64_t)(ms > 0 ? ms : 0) * NS_PER_MS;
}

void wsg_client_init(struct wsg_client *c, enum wsg_link_kind kind)
{
    memset(c, 0, offsetof(struct wsg_client, parser));
    c->kind = kind;
    c->fd = c->rfd = -1;
    c->off = c->len = 0;
    wsg_parser_init(&c->parser, 1); /* replies always carry a valid CRC */
    wsg_parser_set_max(&c->parser, WSG_REPLY_PAYLOAD_MAX); /* Loop echo */
}

void wsg_client_keep(struct wsg_client *c, struct wsg_client_frame *keep,
                     unsigned cap)
{
    c->keep = keep;
    c->keep_cap = cap;
    c->keep_n = 0;
}

/* ---- opening and closing ---- */

int wsg_client_open_tcp(struct wsg_client *c, const struct sockaddr_in *sa,
                        int timeout_ms)
{
    int one = 1, soerr = 0, r;
    socklen_t sl = sizeof soerr;
    struct pollfd p;

    c->fd = socket(AF_INET, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
    if (c->fd < 0)
        return -errno;
    c->rfd = c->fd;
    /* Non-blocking, so an unreachable host costs the timeout, not the
     * kernel's minutes. */
    if (connect(c->fd, (const struct sockaddr *)sa, sizeof *sa) < 0) {
        if (errno != EINPROGRESS) {
            r = -errno;
            goto fail;
        }
        p.fd = c->fd;
        p.events = POLLOUT;
        if (poll(&p, 1, timeout_ms) != 1) {
            r = -ETIMEDOUT;
            goto fail;
        }
        getsockopt(c->fd, SOL_SOCKET, SO_ERROR, &soerr, &sl);
        if (soerr) {
            r = -soerr;
            goto fail;
        }
    }
    /* Like the drivers: each request leaves at once. */
    setsockopt(c->fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
    return 0;
fail:
    close(c->fd);
    c->fd = c->rfd = -1;
    return r;
}

int wsg_client_open_udp(struct wsg_client *c, const struct sockaddr_in *sa,
                        int rfd, int own_rfd)
{
    c->fd = socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
    if (c->fd < 0)
        return -errno;
    c->rfd = rfd;
    c->own_rfd = own_rfd;
    c->peer_addr = sa->sin_addr.s_addr;
    c->peer_port = sa->sin_port;
    return 0;
}

int wsg_client_udp_bind(uint32_t addr, uint16_t port, int *fd, uint16_t *bound)
{
    struct sockaddr_in sa;
    socklen_t sl = sizeof sa;
    int r = 0;

    *fd = socket(AF_INET, SOCK_DGRAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
    if (*fd < 0)
        return -errno;
    memset(&sa, 0, sizeof sa);
    sa.sin_family = AF_INET;
    sa.sin_addr.s_addr = addr;
    sa.sin_port = htons(port);
    if (bind(*fd, (struct sockaddr *)&sa, sizeof sa) < 0 ||
        getsockname(*fd, (struct sockaddr *)&sa, &sl) < 0) {
        r = -errno;
        close(*fd);
        *fd = -1;
        return r;
    }
    if (bound)
        *bound = ntohs(sa.sin_port);
    return 0;
}

int wsg_client_open_serial(struct wsg_client *c, const char *path)
{
    struct termios tio;
    int r;

    c->fd = open(path, O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
    if (c->fd < 0)
        return -errno;
    c->rfd = c->fd;
    if (tcgetattr(c->fd, &tio) < 0) {
        r = -errno;
        goto fail;
    }
    /* What a driver does: raw bytes, 115200 8N1. */
    cfmakeraw(&tio);
    tio.c_cflag &= ~(tcflag_t)(CSTOPB | PARENB | CSIZE);
    tio.c_cflag |= CS8 | CLOCAL | CREAD;
    tio.c_cc[VMIN] = 1;
    tio.c_cc[VTIME] = 0;
    cfsetispeed(&tio, B115200);
    cfsetospeed(&tio, B115200);
    if (tcsetattr(c->fd, TCSANOW, &tio) < 0) {
        r = -errno;
        goto fail;
    }
    /* Answers meant for a previous client are not ours. */
    tcflush(c->fd, TCIFLUSH);
    return 0;
fail:
    close(c->fd);
    c->fd = c->rfd = -1;
    return r;
}

void wsg_client_close(struct wsg_client *c)
{
    if (c->own_rfd && c->rfd >= 0 && c->rfd != c->fd)
        close(c->rfd);
    if (c->fd >= 0)
        close(c->fd);
    c->fd = c->rfd = -1;
}

/* ---- sending ---- */

int wsg_client_send(struct wsg_client *c, const void *pkt, size_t len)
{
    struct sockaddr_in to;
    ssize_t w;

    if (c->kind == WSG_LINK_HOOKS)
        return c->hooks.send(c->hooks.ctx, pkt, len) == 0 ? 0 : -EIO;
    memset(&to, 0, sizeof to);
    to.sin_family = AF_INET;
    to.sin_addr.s_addr = c->peer_addr;
    to.sin_port = c->peer_port;
    /* One write per packet: the gripper's readers expect that too. */
    do {
        if (c->kind == WSG_LINK_UDP)
            w = sendto(c->fd, pkt, len, 0, (const struct sockaddr *)&to,
                       sizeof to);
        else if (c->kind == WSG_LINK_TCP)
            w = send(c->fd, pkt, len, MSG_NOSIGNAL);
        else
            w = write(c->fd, pkt, len);
    } while (w < 0 && errno == EINTR);
    if (w < 0)
        return -errno;
    return (size_t)w == len ? 0 : -EIO;
}

int wsg_client_send_frame(struct wsg_client *c, uint8_t id,
                          const void *payload, size_t len)
{
    uint8_t pkt[WSG_FRAME_MAX];
    size_t n = wsg_frame_encode(pkt, sizeof pkt, id, payload, len);

    if (n == 0)
        return -EMSGSIZE;
    return wsg_client_send(c, pkt, n);
}

/* ---- receiving ---- */

long wsg_client_read(struct wsg_client *c)
{
    ssize_t n;

    if (c->kind == WSG_LINK_UDP) {
        struct sockaddr_in from;
        socklen_t fl = sizeof from;

        do
            n = recvfrom(c->rfd, c->in, sizeof c->in, 0,
                         (struct sockaddr *)&from, &fl);
        while (n < 0 && errno == EINTR);
        if (n < 0)
            return -errno;
        /* Only the gripper's answers count. */
        if (n == 0 || from.sin_addr.s_addr != c->peer_addr)
            return -EAGAIN;
        /* Each datagram stands alone: no packet spans two. */
        wsg_parser_init(&c->parser, 1);
        wsg_parser_set_max(&c->parser, WSG_REPLY_PAYLOAD_MAX);
    } else {
        do
            n = read(c->rfd, c->in, sizeof c->in);
        while (n < 0 && errno == EINTR);
        /* A pty whose other side is gone reads EIO. */
        if (n == 0 || (n < 0 && errno == EIO))
            return -EPIPE;
        if (n < 0)
            return -errno;
    }
    c->off = 0;
    c->len = (size_t)n;
    return (long)n;
}

int wsg_client_fill(struct wsg_client *c, uint64_t deadline)
{
    /* One look even when the deadline has passed: what is there already
     * has come in time. */
    for (int first = 1;; first = 0) {
        uint64_t now = wsg_client_now_ns();
        uint64_t left = now < deadline ? deadline - now : 0;
        int ms;
        long n;

        if (c->stop && *c->stop)
            return -EINTR;
        if (!first && left == 0)
            return 0;
        left = (left + NS_PER_MS - 1) / NS_PER_MS;
        ms = left > 86400000u ? 86400000 : (int)left;
        if (c->stop && ms > SLICE_MS)
            ms = SLICE_MS;
        if (c->kind == WSG_LINK_HOOKS) {
            n = c->hooks.read(c->hooks.ctx, c->in, sizeof c->in, ms);
            if (n == -1)
                continue;
            if (n <= 0)
                return n == 0 ? -EPIPE : -EIO;
            c->off = 0;
            c->len = (size_t)n;
            return 1;
        }
        struct pollfd p = {c->rfd, POLLIN, 0};
        int r = poll(&p, 1, ms);
        if (r < 0 && errno == EINTR)
            continue;
        if (r < 0)
            return -errno;
        if (r == 0)
            continue;
        /* A hung-up line would be polled in a busy loop. */
        if (!(p.revents & POLLIN))
            return -EPIPE;
        n = wsg_client_read(c);
        if (n == -EAGAIN)
            continue;
        return n < 0 ? (int)n : 1;
    }
}

void wsg_client_frame_set(struct wsg_client_frame *f, uint8_t id,
                          const uint8_t *payload, size_t len)
{
    f->id = id;
    f->len = (uint16_t)len;
    memcpy(f->payload, payload, len);
    f->status = len >= 2 ? wsg_get_u16(payload) : 0xFFFFu;
    f->t_ns = wsg_client_now_ns();
}

/* The next frame of what is buffered: 1, 0 when the buffer is used up,
 * -EBADMSG when on_bad says so. */
static int next_buffered(struct wsg_client *c, struct wsg_client_frame *f)
{
    while (c->off < c->len) {
        enum wsg_parse_event ev;
        struct wsg_frame wf;

        c->off += wsg_parser_feed(&c->parser, c->in + c->off, c->len - c->off,
                                  &ev, &wf);
        if (ev == WSG_PARSE_FRAME) {
            wsg_client_frame_set(f, wf.id, wf.payload, wf.len);
            c->seen[wf.id]++;
            return 1;
        }
        if (ev == WSG_PARSE_BAD_CRC || ev == WSG_PARSE_OVERSIZE) {
            c->bad++;
            if (c->on_bad && c->on_bad(c, ev, wf.id))
                return -EBADMSG;
        }
    }
    return 0;
}

/* Next frame from the buffer or the wire, not the kept ones. */
static int next_wire(struct wsg_client *c, struct wsg_client_frame *f,
                     uint64_t deadline)
{
    for (;;) {
        int r = next_buffered(c, f);

        if (r != 0)
            return r;
        if (deadline == 0)
            return 0;
        if (c->eof)
            return -EPIPE;
        r = wsg_client_fill(c, deadline);
        if (r < 0 && r != -EINTR)
            c->eof = 1;
        if (r <= 0)
            return r;
    }
}

static void keep_push(struct wsg_client *c, const struct wsg_client_frame *f)
{
    if (c->keep_cap == 0)
        return;
    if (c->keep_n == c->keep_cap) {
        /* Full: the oldest goes. */
        memmove(&c->keep[0], &c->keep[1],
                (c->keep_cap - 1) * sizeof c->keep[0]);
        c->keep_n--;
    }
    c->keep[c->keep_n++] = *f;
}

static void keep_take(struct wsg_client *c, unsigned i,
                      struct wsg_client_frame *f)
{
    *f = c->keep[i];
    memmove(&c->keep[i], &c->keep[i + 1],
            (c->keep_n - i - 1) * sizeof c->keep[0]);
    c->keep_n--;
}

int wsg_client_recv(struct wsg_client *c, struct wsg_client_frame *f,
                    uint64_t deadline)
{
    if (c->keep_n > 0) {
        keep_take(c, 0, f);
        return 1;
    }
    return next_wire(c, f, deadline);
}

int wsg_client_recv_id(struct wsg_client *c, uint8_t id,
                       struct wsg_client_frame *f, uint64_t deadline)
{
    for (unsigned i = 0; i < c->keep_n; i++) {
        if (c->keep[i].id == id) {
            keep_take(c, i, f);
            return 1;
        }
    }
    for (;;) {
        int r = next_wire(c, f, deadline);

        if (r != 1 || f->id == id)
            return r;
        keep_push(c, f);
    }
}

int wsg_client_request(struct wsg_client *c, uint8_t id, const void *payload,
                       size_t len, struct wsg_client_frame *f,
                       uint64_t deadline)
{
    int r = wsg_client_send_frame(c, id, payload, len);

    return r < 0 ? r : wsg_client_recv_id(c, id, f, deadline);
}

int wsg_client_final(struct wsg_client *c, struct wsg_client_frame *f,
                     uint64_t deadline)
{
    uint8_t id = f->id;

    while (f->status == WSG_E_CMD_PENDING) {
        int r = wsg_client_recv_id(c, id, f, deadline);

        if (r != 1)
            return r;
    }
    return 1;
}

/* ---- lines ---- */

int wsg_client_line_send(struct wsg_client *c, const char *text)
{
    return wsg_client_send(c, text, strlen(text));
}

int wsg_client_line_read(struct wsg_client *c, char *out, size_t cap,
                         uint64_t deadline)
{
    size_t n = 0;

    for (;;) {
        while (c->off < c->len) {
            char ch = (char)c->in[c->off++];

            if (ch == '\n') {
                out[n] = '\0';
                return 1;
            }
            if (n + 1 < cap)
                out[n++] = ch;
        }
        int r = wsg_client_fill(c, deadline);
        if (r <= 0)
            return r;
    }
}

int wsg_client_line(struct wsg_client *c, const char *cmd, char *out,
                    size_t cap, uint64_t deadline)
{
    char line[256];
    int r;

    if ((size_t)snprintf(line, sizeof line, "%s\n", cmd) >= sizeof line)
        return -EMSGSIZE;
    r = wsg_client_line_send(c, line);
    return r < 0 ? r : wsg_client_line_read(c, out, cap, deadline);
}
