/*
 * The delay line of --latency (see delay.h). Packets are stored as records,
 * a fixed header followed by the packet's bytes, one after the other in one
 * buffer: they leave in the order they came, so the oldest is always at
 * the head and releasing is a look at one header per step. Since release
 * stops at the first packet not yet due, order needs no other rule: a
 * packet drawn a shorter delay than the one ahead of it leaves with it. When
 * the tail reaches the buffer's end the waiting records move to its front; the
 * buffer is kept at least twice what waits, so each move is paid for by as
 * many bytes queued since the last one.
 */
#include "delay.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>

#include "wsg/proto.h"

/* The first buffer; it doubles as needed. */
#define WSG_DELAY_BUF_MIN 1024u

struct wsg_delay_rec {
    uint64_t due_us;
    uint32_t tag;
    uint32_t len;
};

/* splitmix64: one multiply-xorshift step per draw, every seed (0 too) as
 * good as another, and the same sequence on every platform. */
static uint64_t wsg_delay_draw(uint64_t *state)
{
    uint64_t z = (*state += 0x9E3779B97F4A7C15ull);

    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

void wsg_delay_init(struct wsg_delay *dl, uint32_t ms, uint32_t jitter_ms,
                    uint64_t seed)
{
    memset(dl, 0, sizeof *dl);
    dl->latency_us = (uint64_t)ms * 1000u;
    dl->jitter_ms = jitter_ms;
    dl->rng = seed;
}

void wsg_delay_fini(struct wsg_delay *dl)
{
    free(dl->buf);
    dl->buf = NULL;
    dl->cap = dl->head = dl->tail = 0;
    dl->count = dl->bytes = 0;
}

/* Room for need more bytes at the tail: 0 or -ENOMEM. */
static int wsg_delay_room(struct wsg_delay *dl, size_t need)
{
    size_t used = dl->tail - dl->head;

    if (dl->tail + need <= dl->cap)
        return 0;
    if (2 * (used + need) > dl->cap) {
        size_t ncap = dl->cap ? dl->cap : WSG_DELAY_BUF_MIN;
        uint8_t *nb;

        while (ncap < 2 * (used + need))
            ncap *= 2;
        nb = realloc(dl->buf, ncap);
        if (!nb)
            return -ENOMEM;
        dl->buf = nb;
        dl->cap = ncap;
    }
    memmove(dl->buf, dl->buf + dl->head, used);
    dl->head = 0;
    dl->tail = used;
    return 0;
}

int wsg_delay_push(struct wsg_delay *dl, uint64_t now_us, uint32_t tag,
                   const uint8_t *pkt, size_t len)
{
    struct wsg_delay_rec rec;
    uint64_t due = now_us + dl->latency_us;
    int r;

    if (dl->jitter_ms)
        due += wsg_delay_draw(&dl->rng) % (dl->jitter_ms + 1u) * 1000u;
    /* A packet never overtakes the one ahead of it: one drawn earlier
     * waits behind it and leaves right after it, so its due time is in
     * effect the later of the two. Only with nothing ahead may it go now. */
    if (due <= now_us && dl->count == 0)
        return 1;
    /* Only the device makes packets, none longer than a frame: release
     * copies them out into a frame's room. */
    r = -EMSGSIZE;
    if (len > WSG_FRAME_MAX)
        goto drop;
    r = -ENOBUFS;
    if (len > WSG_DELAY_MAX - dl->bytes)
        goto drop;
    r = wsg_delay_room(dl, sizeof rec + len);
    if (r < 0)
        goto drop;
    rec.due_us = due;
    rec.tag = tag;
    rec.len = (uint32_t)len;
    memcpy(dl->buf + dl->tail, &rec, sizeof rec);
    memcpy(dl->buf + dl->tail + sizeof rec, pkt, len);
    dl->tail += sizeof rec + len;
    dl->count++;
    dl->bytes += len;
    return 0;

drop:
    dl->dropped++;
    dl->burst++;
    return r;
}

size_t wsg_delay_release(struct wsg_delay *dl, uint64_t now_us,
                         wsg_delay_out_fn out, void *ctx)
{
    size_t n = 0;

    while (dl->count > 0) {
        struct wsg_delay_rec rec;
        uint8_t pkt[WSG_FRAME_MAX];

        memcpy(&rec, dl->buf + dl->head, sizeof rec);
        if (rec.due_us > now_us)
            break;
        /* Copied out and taken off first: out may queue on this line,
         * which may move the buffer. */
        memcpy(pkt, dl->buf + dl->head + sizeof rec, rec.len);
        dl->head += sizeof rec + rec.len;
        dl->count--;
        dl->bytes -= rec.len;
        if (dl->count == 0) {
            dl->head = dl->tail = 0;
            dl->burst = 0;
        }
        out(ctx, rec.tag, pkt, rec.len);
        n++;
    }
    return n;
}

size_t wsg_delay_pending(const struct wsg_delay *dl)
{
    return dl->count;
}

uint64_t wsg_delay_next_due(const struct wsg_delay *dl)
{
    struct wsg_delay_rec rec;

    if (dl->count == 0)
        return UINT64_MAX;
    memcpy(&rec, dl->buf + dl->head, sizeof rec);
    return rec.due_us;
}
