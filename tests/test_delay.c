/*
 * The delay line of --latency (src/transport/delay.c) against a fake
 * clock: a packet leaves exactly MS after it was made and not a step
 * before; several leave in order; with JITTER each delay is MS plus a draw
 * of 0..JITTER ms, except that no packet overtakes the one before it; the
 * same seed gives the same draws; MS 0 sends at once; the 64 KiB bound
 * drops whole packets and counts them; a release may queue more.
 */
#include <errno.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "delay.h"
#include "wsg/proto.h"

#define STEP_US 1000u

#define OUTS_MAX 8192

/* What came out, in order. */
struct outs {
    size_t n;
    uint32_t tag[OUTS_MAX];
    uint64_t at[OUTS_MAX]; /* the clock when it came out */
    size_t len[OUTS_MAX];
    uint8_t first[OUTS_MAX]; /* its first byte */
    uint64_t now;
    /* Set: each release queues one more packet with this tag. */
    struct wsg_delay *requeue;
    uint32_t requeue_tag;
};

static void out(void *ctx, uint32_t tag, const uint8_t *pkt, size_t len)
{
    struct outs *o = ctx;

    REQUIRE(o->n < OUTS_MAX);
    o->tag[o->n] = tag;
    o->at[o->n] = o->now;
    o->len[o->n] = len;
    o->first[o->n] = len ? pkt[0] : 0;
    o->n++;
    if (o->requeue && tag != o->requeue_tag)
        CHECK_EQ(wsg_delay_push(o->requeue, o->now, o->requeue_tag, pkt, len),
                 0);
}

static struct outs *outs_new(void)
{
    struct outs *o = calloc(1, sizeof *o);

    REQUIRE(o != NULL);
    return o;
}

/* Advance the fake clock by one step and release what is due. */
static size_t step(struct wsg_delay *dl, struct outs *o)
{
    o->now += STEP_US;
    return wsg_delay_release(dl, o->now, out, o);
}

static void test_exact(void)
{
    struct wsg_delay dl;
    struct outs *o = outs_new();
    const uint8_t pkt[] = {0xAA, 0xAA, 0xAA, 0x40, 0x00, 0x00};
    int i;

    o->now = 7000; /* any time: the delay counts from when it is made */
    wsg_delay_init(&dl, 5, 0, 1);
    CHECK_EQ(wsg_delay_push(&dl, o->now, 42, pkt, sizeof pkt), 0);
    CHECK_EQ(wsg_delay_pending(&dl), 1);
    for (i = 0; i < 4; i++)
        CHECK_EQ(step(&dl, o), 0);
    CHECK_EQ(o->n, 0);
    CHECK_EQ(step(&dl, o), 1);
    REQUIRE(o->n == 1);
    CHECK_EQ(o->tag[0], 42);
    CHECK_EQ(o->at[0], 12000);
    CHECK_EQ(o->len[0], sizeof pkt);
    CHECK_EQ(o->first[0], 0xAA);
    CHECK_EQ(wsg_delay_pending(&dl), 0);

    /* Several at once keep their order and leave together. */
    for (i = 0; i < 10; i++) {
        uint8_t b = (uint8_t)i;

        CHECK_EQ(wsg_delay_push(&dl, o->now, (uint32_t)i + 1, &b, 1), 0);
    }
    o->n = 0;
    for (i = 0; i < 5; i++)
        step(&dl, o);
    REQUIRE(o->n == 10);
    for (i = 0; i < 10; i++) {
        CHECK_EQ(o->tag[i], i + 1);
        CHECK_EQ(o->first[i], i);
        CHECK_EQ(o->at[i], 17000);
    }
    wsg_delay_fini(&dl);
    free(o);
}

/* Packet i made at step i; returns how many distinct delays were seen. */
static unsigned run_jitter(uint32_t ms, uint32_t jitter, uint64_t seed,
                           uint64_t *delays, size_t n)
{
    struct wsg_delay dl;
    struct outs *o = outs_new();
    uint64_t made[1000];
    unsigned seen[64] = {0}, distinct = 0;
    size_t i, pushed = 0;

    REQUIRE(n <= 1000 && jitter < 64);
    wsg_delay_init(&dl, ms, jitter, seed);
    while (o->n < n) {
        if (pushed < n) {
            uint8_t b = (uint8_t)pushed;

            made[pushed] = o->now;
            CHECK_EQ(wsg_delay_push(&dl, o->now, (uint32_t)pushed, &b, 1), 0);
            pushed++;
        }
        step(&dl, o);
        REQUIRE(o->now < 10000000);
    }
    for (i = 0; i < n; i++) {
        uint64_t d;

        /* in order, and never early */
        CHECK_EQ(o->tag[i], i);
        d = o->at[i] - made[i];
        delays[i] = d;
        CHECK(d >= ms * 1000ull);
        if (i > 0)
            CHECK(o->at[i] >= o->at[i - 1]);
        /* within [MS, MS + JITTER], unless held back by the one before */
        if (i == 0 || o->at[i] > o->at[i - 1]) {
            CHECK(d <= (ms + jitter) * 1000ull);
            if (d <= (ms + jitter) * 1000ull && !seen[d / 1000 - ms]++)
                distinct++;
        }
    }
    wsg_delay_fini(&dl);
    free(o);
    return distinct;
}

static void test_jitter(void)
{
    uint64_t a[500], b[500], c[500];
    size_t i, same = 0;

    /* Every delay of 2..6 ms occurs; none outside it. */
    CHECK_EQ(run_jitter(2, 4, 7, a, 500), 5);
    /* The same seed, the same delays; another seed, others. */
    run_jitter(2, 4, 7, b, 500);
    run_jitter(2, 4, 8, c, 500);
    for (i = 0; i < 500; i++) {
        CHECK_EQ(a[i], b[i]);
        same += a[i] == c[i];
    }
    CHECK(same < 400);
}

static void test_zero(void)
{
    struct wsg_delay dl;
    struct outs *o = outs_new();
    uint8_t b = 1;
    int i, now = 0, queued = 0;

    /* MS 0 without jitter: due at once, never queued. */
    wsg_delay_init(&dl, 0, 0, 1);
    CHECK_EQ(wsg_delay_push(&dl, 5000, 1, &b, 1), 1);
    CHECK_EQ(wsg_delay_pending(&dl), 0);
    wsg_delay_fini(&dl);
    /* MS 0 with jitter: a draw of 0 goes at once, the others wait. */
    wsg_delay_init(&dl, 0, 3, 1);
    for (i = 0; i < 100; i++) {
        int r = wsg_delay_push(&dl, o->now, 1, &b, 1);

        CHECK(r == 0 || r == 1);
        now += r == 1;
        queued += r == 0;
        while (wsg_delay_pending(&dl))
            step(&dl, o);
    }
    CHECK(now > 0);
    CHECK(queued > 0);
    CHECK_EQ(o->n, queued);
    /* ... but never past one that waits: made together, the packets
     * leave in order (the caller sends a packet due at once itself). */
    o->n = 0;
    for (i = 0; i < 50; i++) {
        uint8_t k = (uint8_t)i;

        if (wsg_delay_push(&dl, o->now, (uint32_t)i, &k, 1) == 1)
            out(o, (uint32_t)i, &k, 1);
    }
    while (wsg_delay_pending(&dl))
        step(&dl, o);
    REQUIRE(o->n == 50);
    for (i = 0; i < 50; i++)
        CHECK_EQ(o->tag[i], i);
    wsg_delay_fini(&dl);
    /* A zeroed line is one of latency 0, and fini is safe on it. */
    memset(&dl, 0, sizeof dl);
    CHECK_EQ(wsg_delay_push(&dl, 0, 1, &b, 1), 1);
    wsg_delay_fini(&dl);
    free(o);
}

static void test_bound(void)
{
    struct wsg_delay dl;
    struct outs *o = outs_new();
    uint8_t pkt[14] = {0};
    size_t n = 0, i;
    int r;

    wsg_delay_init(&dl, 10, 0, 1);
    while ((r = wsg_delay_push(&dl, o->now, 1, pkt, sizeof pkt)) == 0)
        n++;
    CHECK_EQ(r, -ENOBUFS);
    /* 64 KiB of whole packets wait; the rest is dropped and counted. */
    CHECK_EQ(n, WSG_DELAY_MAX / sizeof pkt);
    CHECK_EQ(dl.dropped, 1);
    CHECK_EQ(wsg_delay_push(&dl, o->now, 1, pkt, sizeof pkt), -ENOBUFS);
    CHECK_EQ(dl.dropped, 2);
    CHECK_EQ(dl.burst, 2);
    /* A smaller one that fits still goes in. */
    CHECK_EQ(
        wsg_delay_push(&dl, o->now, 2, pkt, WSG_DELAY_MAX - n * sizeof pkt),
        0);
    /* Empty again: the burst is over, the count stays. */
    for (i = 0; i < 10; i++)
        step(&dl, o);
    CHECK_EQ(o->n, n + 1);
    CHECK_EQ(wsg_delay_pending(&dl), 0);
    CHECK_EQ(dl.burst, 0);
    CHECK_EQ(dl.dropped, 2);
    CHECK_EQ(wsg_delay_push(&dl, o->now, 1, pkt, sizeof pkt), 0);
    /* Nothing is larger than a frame. */
    CHECK_EQ(wsg_delay_push(&dl, o->now, 1, pkt, WSG_FRAME_MAX + 1),
             -EMSGSIZE);
    wsg_delay_fini(&dl);
    free(o);
}

/* A steady stream through a short line: the buffer is reused, not grown
 * without end, and nothing is lost or reordered. */
static void test_steady(void)
{
    struct wsg_delay dl;
    struct outs *o = outs_new();
    uint8_t pkt[200];
    size_t i, k = 0, next = 0;

    memset(pkt, 0x55, sizeof pkt);
    wsg_delay_init(&dl, 3, 2, 99);
    for (i = 0; i < 20000; i++) {
        pkt[0] = (uint8_t)i;
        CHECK_EQ(
            wsg_delay_push(&dl, o->now, (uint32_t)i, pkt, 1 + i % sizeof pkt),
            0);
        step(&dl, o);
        for (; k < o->n; k++, next++) {
            CHECK_EQ(o->tag[k], next);
            CHECK_EQ(o->len[k], 1 + next % sizeof pkt);
            CHECK_EQ(o->first[k], (uint8_t)next);
        }
        if (o->n > OUTS_MAX / 2)
            o->n = k = 0; /* checked: room for more */
    }
    CHECK(next > 19990);
    CHECK(dl.cap <= 8192);
    wsg_delay_fini(&dl);
    free(o);
}

static void test_requeue(void)
{
    struct wsg_delay dl;
    struct outs *o = outs_new();
    uint8_t b = 3;
    int i;

    wsg_delay_init(&dl, 2, 0, 1);
    o->requeue = &dl;
    o->requeue_tag = 9;
    CHECK_EQ(wsg_delay_push(&dl, o->now, 1, &b, 1), 0);
    for (i = 0; i < 2; i++)
        step(&dl, o);
    /* The release queued one more, for two steps later. */
    REQUIRE(o->n == 1);
    CHECK_EQ(wsg_delay_pending(&dl), 1);
    step(&dl, o);
    CHECK_EQ(o->n, 1);
    step(&dl, o);
    REQUIRE(o->n == 2);
    CHECK_EQ(o->tag[1], 9);
    CHECK_EQ(o->at[1], 4000);
    wsg_delay_fini(&dl);
    free(o);
}

int main(void)
{
    test_exact();
    test_jitter();
    test_zero();
    test_bound();
    test_steady();
    test_requeue();
    TEST_EXIT();
}
