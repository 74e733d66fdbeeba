/*
 * A bounded output queue in front of a non-blocking descriptor: every
 * packet leaves in one write() when the descriptor takes it whole; what it
 * does not take waits here, in order, and packets sent meanwhile line up
 * behind it, so no packet is ever interleaved with another. The owner
 * watches EPOLLOUT while bytes wait and decides what a full queue means
 * (TCP drops the client, a serial line drops the packet).
 */
#ifndef WSG_TRANSPORT_OUTQ_H
#define WSG_TRANSPORT_OUTQ_H

#include <stddef.h>
#include <stdint.h>

#define WSG_OUTQ_MAX 65536u

struct wsg_outq {
    int socket;       /* send() with MSG_NOSIGNAL rather than write() */
    size_t head, len; /* waiting: buf[head .. head+len) */
    uint8_t buf[WSG_OUTQ_MAX];
};

void wsg_outq_init(struct wsg_outq *q, int socket);
/* Send one packet. Returns 0 when all of it went out, 1 when bytes wait
 * (watch EPOLLOUT), -ENOBUFS when it does not fit behind what waits
 * (nothing of it is queued), or -errno from the write. */
int wsg_outq_send(struct wsg_outq *q, int fd, const uint8_t *pkt, size_t len);
/* Write what waits, in one call. Returns 0 when nothing waits any more,
 * 1 when bytes still wait, or -errno. */
int wsg_outq_flush(struct wsg_outq *q, int fd);
void wsg_outq_clear(struct wsg_outq *q);

#endif
