/*
 * A delay line (--latency MS[:JITTER]): the packets one interface of a
 * gripper sends wait here, in order, until the gripper's simulated time
 * reaches the moment they are due to leave. Real grippers take a few
 * milliseconds to answer; an emulator that answers within the same
 * millisecond lets packets arrive together in one read, which drivers that
 * keep only the first packet of a read, or start a thread per packet, do
 * not survive.
 *
 * A packet made at simulated time t leaves at t + MS plus a draw of
 * 0..JITTER ms, but never before the packet queued before it on the same
 * line: packets keep their order, and a late one holds back those behind
 * it. The draws come from a generator seeded by the owner, so the same
 * traffic meets the same delays on every run.
 *
 * The line holds at most WSG_DELAY_MAX bytes of packets; a packet that does
 * not fit is dropped (whole) and counted. Its buffer grows with use, so a
 * fleet of idle grippers costs nothing. The module knows neither sessions
 * nor time sources: it stores a tag per packet and is told the time.
 */
#ifndef WSG_TRANSPORT_DELAY_H
#define WSG_TRANSPORT_DELAY_H

#include <stddef.h>
#include <stdint.h>

/* Packet bytes waiting per line at most (each packet also takes 16 bytes
 * of bookkeeping, not counted here). */
#define WSG_DELAY_MAX 65536u
/* The largest MS and JITTER the options take. */
#define WSG_DELAY_MS_MAX 10000u

struct wsg_delay {
    uint64_t latency_us; /* MS */
    uint32_t jitter_ms;  /* JITTER: draws of 0..jitter_ms */
    uint64_t rng;        /* the generator's state (splitmix64) */
    uint8_t *buf;        /* records waiting: buf[head..tail) */
    size_t cap, head, tail;
    size_t count;     /* packets waiting */
    size_t bytes;     /* their packet bytes, at most WSG_DELAY_MAX */
    uint64_t dropped; /* packets that did not fit, ever */
    uint64_t burst;   /* of those, since the line was last empty */
};

/* Where a released packet goes: the tag it was queued with. */
typedef void (*wsg_delay_out_fn)(void *ctx, uint32_t tag, const uint8_t *pkt,
                                 size_t len);

/* An empty line with MS and JITTER in milliseconds and the generator's
 * seed. Allocates nothing; a zeroed struct is a valid line of latency 0. */
void wsg_delay_init(struct wsg_delay *dl, uint32_t ms, uint32_t jitter_ms,
                    uint64_t seed);
/* Free the buffer; what waits is lost. Safe on a zeroed struct. */
void wsg_delay_fini(struct wsg_delay *dl);
/* A packet made at now_us: its due time is drawn, and it is queued.
 * Returns 0 when queued, 1 when it is due already (MS 0 and a draw of 0
 * with nothing waiting): not queued, the caller sends it at once; or,
 * dropped and counted, -ENOBUFS when the line is full, -ENOMEM, or
 * -EMSGSIZE for more than WSG_FRAME_MAX bytes (no packet is). */
int wsg_delay_push(struct wsg_delay *dl, uint64_t now_us, uint32_t tag,
                   const uint8_t *pkt, size_t len);
/* Hand every packet due by now_us to out, oldest first, each taken off the
 * line before out sees it (out may queue more). Returns how many. */
size_t wsg_delay_release(struct wsg_delay *dl, uint64_t now_us,
                         wsg_delay_out_fn out, void *ctx);
/* Packets waiting. */
size_t wsg_delay_pending(const struct wsg_delay *dl);
/* When the oldest packet is due (those behind it wait for it), or
 * UINT64_MAX when none waits. */
uint64_t wsg_delay_next_due(const struct wsg_delay *dl);

#endif
