/*
 * The event stream's packing of the communication log into "log" events
 * (src/daemon/web_sse.c), on a ring as the web server keeps it (256 KiB)
 * and a subscriber's buffer (16 KiB) with a guard zone behind it: every
 * event is checked by sse_check.h (within its buffer, well-formed SSE, the
 * log's lines in order, as many as fit, the id where they end) and the
 * guard must be as it was.
 *
 * - lines of every length 0..1023, three times over, written as the log
 *   writes them and read by a reader that keeps up: all read, in order;
 * - read from every offset of a window longer than a line: each start
 *   cuts the first line a byte shorter, so the event's end goes through
 *   every place, and one event is filled to the room kept for its id (the
 *   case where the room used to be worked out below zero);
 * - buffers of every size from the smallest to 2 KiB: a line longer than
 *   an event is cut to fit, never written past it;
 * - a reader behind the ring is told how many bytes it missed and goes on
 *   at the next whole line;
 * - a CR in a line goes out as a space, not as the end of an SSE line;
 * - a buffer below WSG_WEB_SSE_LOG_MIN gets nothing, and a ring described
 *   wrongly (oldest past the end, more than it holds, no bytes) is read
 *   only as far as it can hold.
 */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "sse_check.h"
#include "web_sse.h"

#define RING  (256u * 1024u)
#define CAP   (16u * 1024u)
#define GUARD 4096u
#define FILL  0xA5

static char ring[RING];
static uint64_t head; /* log bytes ever written */
static char out[CAP + GUARD];
static unsigned events;
/* The most bytes an event had before its id line. */
static size_t fullest;

/* Line k of the log: k % 1024 bytes and a newline, written into the ring
 * as the server writes a log line. Printable text, with now and then a CR
 * (a GCL line may carry one), a NUL or a byte above 127. */
static void write_line(unsigned k)
{
    size_t len = k % 1024u, i;

    for (i = 0; i < len; i++) {
        char c = (char)('!' + (k * 31u + i) % 90u);

        if ((k + i) % 97u == 0)
            c = '\r';
        else if ((k + i) % 89u == 0)
            c = '\0';
        else if ((k + i) % 83u == 0)
            c = (char)0xE9;
        ring[(head + i) % RING] = c;
    }
    ring[(head + len) % RING] = '\n';
    head += len + 1;
}

static struct wsg_web_ring the_ring(void)
{
    struct wsg_web_ring r;

    r.buf = ring;
    r.size = RING;
    r.oldest = head > RING ? head - RING : 0;
    r.end = head;
    return r;
}

/* Pack one event for a reader at *off into cap bytes of out and check
 * it: sse_check's rules, and the guard behind cap untouched. */
static size_t pack(const struct wsg_web_ring *r, size_t cap, uint64_t *off)
{
    uint64_t before = *off;
    const char *why;
    size_t len, i, id;
    char idline[40];

    memset(out, FILL, sizeof out);
    len = wsg_web_sse_log(out, cap, r, off);
    for (i = cap; i < sizeof out; i++)
        if ((unsigned char)out[i] != FILL)
            break;
    CHECK(i == sizeof out);
    if (i != sizeof out) {
        fprintf(stderr, "cap %zu from %llu: written past the buffer at %zu\n",
                cap, (unsigned long long)before, i);
        exit(1); /* what follows would only repeat it */
    }
    why = sse_check(out, len, cap, r, before, *off);
    CHECK(why == NULL);
    if (why) {
        fprintf(stderr, "cap %zu from %llu to %llu (log %llu..%llu): %s\n",
                cap, (unsigned long long)before, (unsigned long long)*off,
                (unsigned long long)r->oldest, (unsigned long long)r->end,
                why);
        fprintf(stderr, "%.*s\n", (int)(len < 400 ? len : 400), out);
        exit(1);
    }
    if (len) {
        events++;
        id = (size_t)snprintf(idline, sizeof idline, "id: %llu\n\n",
                              (unsigned long long)*off);
        if (len - id > fullest)
            fullest = len - id;
    }
    return len;
}

/* Every length 0..1023, three times, read as it comes. */
static void test_keep_up(void)
{
    struct wsg_web_ring r;
    uint64_t off = 0;
    unsigned k;

    for (k = 0; k < 3u * 1024u; k++) {
        write_line(k);
        if (k % 16u != 15u)
            continue;
        r = the_ring();
        while (off < head)
            pack(&r, CAP, &off);
    }
    r = the_ring();
    while (off < head)
        pack(&r, CAP, &off);
    CHECK_EQ(off, head);
    /* Each 16 KiB event holds some 30 lines here: the log was read in
     * full events, not a line at a time. */
    CHECK(events < 3u * 1024u / 8u);
}

/* From every offset of a window: every way an event can end. */
static void test_every_start(void)
{
    const struct wsg_web_ring r = the_ring();
    uint64_t s, off;

    fullest = 0;
    for (s = head - 100000u; s < head - 100000u + 1100u; s++) {
        off = s;
        pack(&r, CAP, &off);
        /* Whole events: the window is far from the log's end. */
        CHECK(off - s > CAP / 2);
    }
    /* An event filled to the room kept for its id line. */
    CHECK_EQ(fullest, CAP - WSG_WEB_SSE_TAIL_MAX);
}

/* Small buffers: long lines cut to fit, short ones packed whole. */
static void test_caps(void)
{
    const struct wsg_web_ring r = the_ring();
    size_t cap;
    uint64_t off;
    int i;

    for (cap = WSG_WEB_SSE_LOG_MIN; cap <= 2048u; cap++) {
        off = head - 200000u + cap * 37u;
        for (i = 0; i < 4; i++)
            CHECK(pack(&r, cap, &off) > 0);
    }
}

/* A reader behind the ring; one at its very end. */
static void test_missed(void)
{
    const struct wsg_web_ring r = the_ring();
    char note[64];
    uint64_t off = 0;

    REQUIRE(head > RING);
    pack(&r, CAP, &off);
    snprintf(note, sizeof note, "data: (%llu bytes of log missed)\n",
             (unsigned long long)(head - RING));
    CHECK(strncmp(out + 11, note, strlen(note)) == 0);
    CHECK(off > head - RING && off < head);
    /* One byte behind: still the note, then the next whole line. */
    off = head - RING - 1;
    pack(&r, CAP, &off);
    CHECK(strncmp(out, "event: log\ndata: (1 bytes of log missed)\n", 41) ==
          0);
    /* At the end: an event with its id only (the server does not ask for
     * one then; it is well-formed all the same). */
    off = head;
    pack(&r, CAP, &off);
    CHECK_EQ(off, head);
}

/* A CR would end the SSE line in a browser: "id: 7" after it would set
 * the stream's id. It goes out as a space. */
static void test_cr(void)
{
    static const char log[] = "a\rid: 7\r\nb\n";
    static const char want[] = "event: log\ndata: a id: 7 \ndata: b\n"
                               "id: 11\n\n";
    struct wsg_web_ring r;
    uint64_t off = 0;
    size_t len;

    r.buf = log;
    r.size = sizeof log - 1;
    r.oldest = 0;
    r.end = sizeof log - 1;
    len = pack(&r, CAP, &off);
    CHECK_EQ(len, sizeof want - 1);
    CHECK(memcmp(out, want, sizeof want - 1) == 0);
    CHECK_EQ(off, 11);
}

/* Too small a buffer; rings described wrongly. */
static void test_odd(void)
{
    struct wsg_web_ring r = the_ring(), bad;
    size_t cap, i;
    uint64_t off;

    for (cap = 0; cap < WSG_WEB_SSE_LOG_MIN; cap++) {
        off = head - 5000u;
        CHECK_EQ(pack(&r, cap, &off), 0);
        CHECK_EQ(off, head - 5000u);
        for (i = 0; i < cap; i++)
            if ((unsigned char)out[i] != FILL)
                break;
        CHECK_EQ(i, cap);
    }
    /* oldest past the end; more than the ring holds; no bytes at all;
     * a reader past the end. */
    bad = r;
    bad.oldest = head + 10u;
    off = head - 3000u;
    pack(&bad, CAP, &off);
    bad = r;
    bad.oldest = 0;
    off = 0;
    pack(&bad, CAP, &off);
    CHECK(off > head - RING);
    bad = r;
    bad.size = 0;
    off = head - 10u;
    pack(&bad, CAP, &off);
    CHECK_EQ(off, head);
    bad.buf = NULL;
    bad.size = RING;
    off = 5;
    pack(&bad, CAP, &off);
    CHECK_EQ(off, head);
    off = head + 100u;
    pack(&r, CAP, &off);
    CHECK_EQ(off, head + 100u);
}

int main(void)
{
    test_keep_up();
    test_every_start();
    test_caps();
    test_missed();
    test_cr();
    test_odd();
    TEST_EXIT();
}
