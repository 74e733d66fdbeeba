/*
 * The bounded output queue of the stream transports (TCP, the serial port).
 * See outq.h for the contract.
 */
#define _GNU_SOURCE

#include "outq.h"

#include <errno.h>
#include <string.h>
#include <sys/socket.h>
#include <unistd.h>

void wsg_outq_init(struct wsg_outq *q, int socket)
{
    q->socket = socket;
    q->head = 0;
    q->len = 0;
}

void wsg_outq_clear(struct wsg_outq *q)
{
    q->head = 0;
    q->len = 0;
}

/* One write of as much as the descriptor takes: bytes written (0 when it
 * is full) or -errno. */
static ssize_t wsg_outq_write(const struct wsg_outq *q, int fd,
                              const uint8_t *p, size_t len)
{
    for (;;) {
        ssize_t n = q->socket ? send(fd, p, len, MSG_NOSIGNAL | MSG_DONTWAIT)
                              : write(fd, p, len);

        if (n >= 0)
            return n;
        if (errno == EINTR)
            continue;
        if (errno == EAGAIN || errno == EWOULDBLOCK)
            return 0;
        return -errno;
    }
}

static int wsg_outq_append(struct wsg_outq *q, const uint8_t *p, size_t len)
{
    if (q->len + len > WSG_OUTQ_MAX)
        return -ENOBUFS;
    if (q->head + q->len + len > WSG_OUTQ_MAX) {
        memmove(q->buf, q->buf + q->head, q->len);
        q->head = 0;
    }
    memcpy(q->buf + q->head + q->len, p, len);
    q->len += len;
    return 1;
}

int wsg_outq_send(struct wsg_outq *q, int fd, const uint8_t *pkt, size_t len)
{
    ssize_t n;

    /* Behind waiting bytes a packet must wait its turn, or it would land
     * in the middle of an earlier one. */
    if (q->len > 0)
        return wsg_outq_append(q, pkt, len);
    n = wsg_outq_write(q, fd, pkt, len);
    if (n < 0)
        return (int)n;
    if ((size_t)n == len)
        return 0;
    return wsg_outq_append(q, pkt + n, len - (size_t)n);
}

int wsg_outq_flush(struct wsg_outq *q, int fd)
{
    ssize_t n;

    if (q->len == 0)
        return 0;
    n = wsg_outq_write(q, fd, q->buf + q->head, q->len);
    if (n < 0)
        return (int)n;
    q->head += (size_t)n;
    q->len -= (size_t)n;
    if (q->len == 0)
        q->head = 0;
    return q->len > 0;
}
