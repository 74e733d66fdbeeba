/*
 * Harness 7: arbitrary bytes as the communication log that the web page's
 * event stream packs into "log" events (wsg_web_sse_log, web_sse.h), with
 * a buffer and a ring of sizes the input picks, read by a reader that
 * sometimes keeps up, sometimes falls behind the ring, and sometimes jumps
 * anywhere (as a hostile Last-Event-ID would have it), now and then from a
 * ring described wrongly. After every packing:
 *
 *   - nothing was written past the buffer (under ASan the buffer is
 *     exactly its size; without it a guard zone behind it must stay as it
 *     was);
 *   - the event is what sse_check.h says: well-formed SSE (no CR or LF
 *     inside a data line), the note of what was missed exactly when the
 *     reader was behind, the log's lines in order (CRs as spaces), whole
 *     but for a first one too long for the event, as many as fit, the id
 *     where they end, ahead of where the reader was;
 *   - a reader that packs until it has caught up gets there.
 *
 * Input: six header bytes, then the log's text. Bytes 0-1 (little-endian)
 * give the buffer's size (modulo 20000: below WSG_WEB_SSE_LOG_MIN too),
 * bytes 2-3 the ring's (1 + modulo 8192), bytes 4-5 seed the generator
 * that decides what the reader does after each line is written. The text
 * is cut into lines after each '\n' (the last one may have none) and
 * written into the ring as the server writes log lines: a line longer
 * than the ring is dropped. The seeds (corpus/sse) are in this form.
 */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fuzz_check.h"
#include "sse_check.h"
#include "web_sse.h"

#ifndef FUZZ_ENTRY
#define FUZZ_ENTRY LLVMFuzzerTestOneInput
#endif

int FUZZ_ENTRY(const uint8_t *data, size_t size);

#define FUZZ_HEADER  6u
#define FUZZ_CAP_MOD 20000u
#define FUZZ_RING    8192u

/* Under ASan the buffer is allocated at its exact size, so a write past it
 * is reported where it happens; elsewhere (the replay in every build) a
 * guard zone behind it is checked. */
#if defined(__has_feature)
#if __has_feature(address_sanitizer)
#define FUZZ_ASAN 1
#endif
#endif
#if defined(__SANITIZE_ADDRESS__) && !defined(FUZZ_ASAN)
#define FUZZ_ASAN 1
#endif
#ifndef FUZZ_ASAN
#define FUZZ_ASAN 0
#endif
#define FUZZ_GUARD (FUZZ_ASAN ? 0u : 512u)
#define FUZZ_FILL  0xA5

static struct {
    char *ring;
    size_t size;
    uint64_t head; /* log bytes written */
    char *out;
    size_t cap;
    uint64_t off; /* the reader */
    uint32_t x;   /* the generator */
} F;

static uint32_t fuzz_rand(void)
{
    /* xorshift32: deterministic per input, never 0 from a nonzero seed. */
    F.x ^= F.x << 13;
    F.x ^= F.x >> 17;
    F.x ^= F.x << 5;
    return F.x;
}

static struct wsg_web_ring fuzz_ring(void)
{
    struct wsg_web_ring r;

    r.buf = F.ring;
    r.size = F.size;
    r.oldest = F.head > F.size ? F.head - F.size : 0;
    r.end = F.head;
    return r;
}

/* The n bytes of the guard zone at p are as they were filled. */
static int fuzz_guard_intact(const char *p, size_t n)
{
    size_t i;

    for (i = 0; i < n; i++)
        if ((unsigned char)p[i] != FUZZ_FILL)
            return 0;
    return 1;
}

/* One event for the reader, checked. */
static size_t fuzz_pack(const struct wsg_web_ring *r)
{
    uint64_t before = F.off;
    const char *why;
    size_t len;

    memset(F.out + F.cap, FUZZ_FILL, FUZZ_GUARD);
    len = wsg_web_sse_log(F.out, F.cap, r, &F.off);
    FUZZ_CHECK(fuzz_guard_intact(F.out + F.cap, FUZZ_GUARD));
    why = sse_check(F.out, len, F.cap, r, before, F.off);
    if (why) {
        fprintf(stderr,
                "fuzz_sse: cap %zu, ring %zu, log %llu..%llu, reader "
                "%llu -> %llu: %s\n",
                F.cap, F.size, (unsigned long long)r->oldest,
                (unsigned long long)r->end, (unsigned long long)before,
                (unsigned long long)F.off, why);
        abort();
    }
    return len;
}

/* Pack until the reader has caught up: each event takes it ahead, so
 * that many events at most. */
static void fuzz_catch_up(void)
{
    const struct wsg_web_ring r = fuzz_ring();
    uint64_t n = F.head > F.off ? F.head - F.off : 0;

    if (F.cap < WSG_WEB_SSE_LOG_MIN)
        return;
    while (F.off < F.head && n-- > 0)
        fuzz_pack(&r);
    FUZZ_CHECK(F.off >= F.head);
}

/* What the reader does after a line was written. */
static void fuzz_reader(void)
{
    uint32_t v = fuzz_rand();
    struct wsg_web_ring r = fuzz_ring();

    switch (v & 15u) {
    case 10:
    case 11:
    case 12:
        fuzz_catch_up();
        break;
    case 13:
        break; /* falls behind */
    case 14:
        /* A Last-Event-ID of anything, past the end too. */
        F.off = (uint64_t)(fuzz_rand() % (uint32_t)(F.head + 16u));
        break;
    case 15:
        /* A ring described wrongly: its oldest byte anywhere. */
        r.oldest = (uint64_t)(fuzz_rand() % (uint32_t)(F.head + 16u));
        fuzz_pack(&r);
        break;
    default:
        fuzz_pack(&r);
        break;
    }
}

/* A line into the ring, as the server writes one. */
static void fuzz_write(const uint8_t *p, size_t len)
{
    size_t at, first;

    if (len > F.size)
        return;
    at = (size_t)(F.head % F.size);
    first = F.size - at < len ? F.size - at : len;
    memcpy(F.ring + at, p, first);
    memcpy(F.ring, p + first, len - first);
    F.head += len;
}

int FUZZ_ENTRY(const uint8_t *data, size_t size)
{
    size_t i = FUZZ_HEADER;

    if (size < FUZZ_HEADER)
        return 0;
    memset(&F, 0, sizeof F);
    F.cap = ((size_t)data[0] | (size_t)data[1] << 8) % FUZZ_CAP_MOD;
    F.size = 1u + ((size_t)data[2] | (size_t)data[3] << 8) % FUZZ_RING;
    F.x = ((uint32_t)data[4] | (uint32_t)data[5] << 8) ^ 0x9E3779B9u;
    F.ring = malloc(F.size);
    F.out = malloc(F.cap + FUZZ_GUARD ? F.cap + FUZZ_GUARD : 1u);
    FUZZ_CHECK(F.ring && F.out);
    while (i < size) {
        const uint8_t *nl = memchr(data + i, '\n', size - i);
        size_t end = nl ? (size_t)(nl - data) + 1 : size;

        fuzz_write(data + i, end - i);
        i = end;
        fuzz_reader();
    }
    /* A reader that fell behind or jumped comes back to the end. */
    if (F.off > F.head)
        F.off = F.head;
    fuzz_catch_up();
    free(F.out);
    free(F.ring);
    return 0;
}
