/*
 * integ_webevents: the web page's event stream (GET /events, read as a
 * browser's EventSource reads it) while a client floods the gripper with
 * Loop (06h) packets of 1 to 256 bytes over TCP, whose log lines (each
 * with its payload's first bytes in hex, 60 to 200 characters) fill the
 * stream's "log" events.
 *
 * - during the flood every event is well formed: "event: state" or
 *   "event: log" first, then "data: " lines without a CR (a browser ends
 *   a line at a CR too), and a log event's "id: N" last, N the log offset
 *   it has reached: the previous event's id plus the bytes of the lines
 *   it carries (each line's newline included), so nothing is lost,
 *   doubled or made up;
 * - then the stream is reconnected with Last-Event-ID, at each offset of
 *   a window as long as the longest line: each start cuts the first line
 *   one byte shorter, so every way a full event can end is packed,
 *   among them the line that fills an event to its last bytes (which the
 *   room left behind for its id line must still hold); each first log
 *   event is well formed and ends at its offset plus its lines' bytes;
 * - the daemon still answers over TCP and exits 0 afterwards.
 *
 * Built without libmicrohttpd (WSG_TEST_HAVE_WEB 0) it is skipped.
 */
#include "check.h"
#include "emu.h"
#include "emu_http.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#ifndef WSG_TEST_HAVE_WEB
#define WSG_TEST_HAVE_WEB 0
#endif

/* The daemon's largest log event (WSG_WEB_LOG_EVENT_MAX), and room for
 * one here. */
#define LOG_EVENT_MAX 16384u
#define EV_MAX        20000
/* The flood: rounds of Loop packets, each answered before the next round
 * (the replies are read, so nothing backs up on the TCP side). */
#define ROUNDS    30
#define PER_ROUND 100
/* How far before the newest line the reconnections start: more than a
 * full event, well inside the 256 KiB the daemon keeps. */
#define BACK 40000ull

static const char *const args[] = {"--tcp", "127.0.0.1:0", "--web",
                                   "127.0.0.1:0", NULL};

static char web[64];

/* What a well-formed event carried. */
struct ev {
    int log;                  /* "event: log", else "event: state" */
    unsigned long long id;    /* a log event's id */
    unsigned long long bytes; /* its data lines' bytes, each plus one */
    size_t longest;           /* its longest data line */
    int note;                 /* a line saying how much was missed */
    size_t before_id;         /* its bytes before the id line */
};

static int digits(const char *p, size_t n)
{
    size_t i;

    for (i = 0; i < n; i++)
        if (p[i] < '0' || p[i] > '9')
            return 0;
    return n > 0 && n <= 20;
}

/* "(N bytes of log missed)": the daemon's note for a reader that fell
 * behind what it keeps. */
static int is_note(const char *p, size_t n)
{
    static const char tail[] = " bytes of log missed)";
    const size_t t = sizeof tail - 1;
    size_t k = 1;

    if (n < 2 + t || p[0] != '(' || memcmp(p + n - t, tail, t) != 0)
        return 0;
    while (k < n - t && p[k] >= '0' && p[k] <= '9')
        k++;
    return k == n - t && k > 1;
}

/* Check one event's text (its lines, each ending in \n) and describe it
 * in e. 1: well formed; 0: not (it is shown). */
static int well_formed(const char *t, size_t len, struct ev *e)
{
    size_t i = 0, lines = 0;
    int has_id = 0;

    memset(e, 0, sizeof e[0]);
    if (memchr(t, '\r', len) || memchr(t, '\0', len))
        goto bad;
    while (i < len) {
        const char *line = t + i, *eol = memchr(line, '\n', len - i);
        size_t n;

        if (!eol)
            goto bad; /* the last line without its newline */
        n = (size_t)(eol - line);
        if (has_id)
            goto bad; /* the id line is the last */
        if (lines == 0) {
            if (n == 10 && memcmp(line, "event: log", 10) == 0)
                e->log = 1;
            else if (!(n == 12 && memcmp(line, "event: state", 12) == 0))
                goto bad;
        } else if (n >= 6 && memcmp(line, "data: ", 6) == 0) {
            if (!e->log && lines > 1)
                goto bad; /* a state is one line of JSON */
            if (e->log && lines == 1 && is_note(line + 6, n - 6))
                e->note = 1;
            e->bytes += n - 6 + 1;
            if (n - 6 > e->longest)
                e->longest = n - 6;
        } else if (e->log && n > 4 && memcmp(line, "id: ", 4) == 0 &&
                   digits(line + 4, n - 4)) {
            e->id = strtoull(line + 4, NULL, 10);
            e->before_id = i;
            has_id = 1;
        } else {
            goto bad;
        }
        lines++;
        i += n + 1;
    }
    if (lines < 2 || (e->log && !has_id))
        goto bad;
    if (e->note)
        e->bytes = 0; /* the lines after it start wherever the log does */
    return 1;
bad:
    fprintf(stderr, "malformed event (%zu bytes): %.300s\n", len, t);
    return 0;
}

/* The stream's next log event within timeout_ms (state events passed
 * over), checked. 1: one; 0: none in time; -1: the stream ended, or an
 * event was malformed. */
static int next_log(struct http_stream *s, struct ev *e, int timeout_ms)
{
    static char buf[EV_MAX];
    double end = emu_now_ms() + timeout_ms, left;
    size_t len;
    int r;

    for (;;) {
        left = end - emu_now_ms();
        r = http_stream_raw(s, buf, sizeof buf, &len,
                            left > 0 ? (int)left : 0);
        if (r != 1)
            return r;
        if (!well_formed(buf, len, e))
            return -1;
        if (e->log)
            return 1;
    }
}

/* A log event that follows another at offset *at: it goes on exactly
 * there, unless it says what was missed. */
static void follow(const struct ev *e, unsigned long long *at, int *seen)
{
    if (*seen && !e->note && e->id != *at + e->bytes) {
        fprintf(stderr, "log event from %llu with %llu bytes has id %llu\n",
                *at, e->bytes, e->id);
        CHECK(e->id == *at + e->bytes);
    }
    CHECK(!*seen || e->id >= *at);
    *at = e->id;
    *seen = 1;
}

/* The flood, with the stream read between rounds; the longest log line
 * seen into *longest, the stream's last id into *at. */
static void flood(struct emu_client *c, struct http_stream *s,
                  unsigned long long *at, size_t *longest)
{
    struct wsg_client_frame f;
    uint8_t payload[WSG_PAYLOAD_MAX];
    unsigned round, i, n = 0;
    int seen = 0, r, got;
    struct ev e;

    for (round = 0; round < ROUNDS; round++) {
        for (i = 0; i < PER_ROUND; i++, n++) {
            /* 1..256 bytes, in an order that varies the lines' ends. */
            size_t len = 1u + (n * 7919u) % WSG_PAYLOAD_MAX, k;

            for (k = 0; k < len; k++)
                payload[k] = (uint8_t)(n + k);
            REQUIRE(emu_send(c, WSG_CMD_LOOP, payload, len) == 0);
        }
        for (i = 0; i < PER_ROUND; i++) {
            got = emu_recv_id(c, WSG_CMD_LOOP, &f, EMU_REPLY_MS);
            REQUIRE(got == 1);
            CHECK_EQ(f.status, WSG_E_SUCCESS);
        }
        /* What was pushed meanwhile; the rest comes with the next
         * round. */
        while ((r = next_log(s, &e, 0)) == 1) {
            follow(&e, at, &seen);
            if (e.longest > *longest)
                *longest = e.longest;
        }
        REQUIRE(r == 0);
    }
    /* The stream catches up with the log once the flood is over. */
    while ((r = next_log(s, &e, EMU_QUIET_MS)) == 1) {
        follow(&e, at, &seen);
        if (e.longest > *longest)
            *longest = e.longest;
    }
    REQUIRE(r == 0);
    CHECK(seen);
}

/* Reconnect with Last-Event-ID at each offset from..to: the first log
 * event is well formed and ends where its lines do. */
static void reconnect(unsigned long long from, unsigned long long to)
{
    static struct http_stream s;
    char hdr[64];
    unsigned long long off;
    size_t fullest = 0;
    struct ev e;
    int bad = 0;

    for (off = from; off <= to && bad < 5; off++) {
        snprintf(hdr, sizeof hdr, "Last-Event-ID: %llu\r\n", off);
        REQUIRE(http_stream_open_with(&s, web, "/events", hdr, EMU_REPLY_MS) ==
                0);
        CHECK_EQ(s.status, 200);
        REQUIRE(next_log(&s, &e, EMU_REPLY_MS) == 1);
        CHECK(!e.note);
        if (e.id != off + e.bytes) {
            fprintf(stderr,
                    "from %llu: a log event with %llu bytes has id %llu\n",
                    off, e.bytes, e.id);
            bad++;
        }
        CHECK(e.id == off + e.bytes);
        /* A full event: the offsets are more than one event back. */
        CHECK(e.bytes > 12000);
        if (e.before_id > fullest)
            fullest = e.before_id;
        http_stream_close(&s);
    }
    /* The window packed an event whose lines came within an id line of
     * the end of the buffer: the case that must leave the id its room. */
    CHECK(fullest > LOG_EVENT_MAX - 34 && fullest < LOG_EVENT_MAX);
}

int main(int argc, char **argv)
{
    const char *exe = emu_exe(argc, argv);
    static struct http_stream s;
    unsigned long long at = 0;
    size_t longest = 0;
    struct emu_client c;
    struct emu e;

    if (!WSG_TEST_HAVE_WEB)
        test_skip("wsgemu was built without libmicrohttpd");
    REQUIRE(emu_start(&e, exe, args) == 0);
    REQUIRE(emu_field(&e, "web", web, sizeof web) != NULL);
    REQUIRE(emu_open(&c, &e, &emu_tcp) == 0);
    REQUIRE(http_stream_open(&s, web, "/events", EMU_REPLY_MS) == 0);
    CHECK_EQ(s.status, 200);

    flood(&c, &s, &at, &longest);
    /* Lines as long as the packets make them: the flood was one. */
    CHECK(longest > 150 && longest < 1024);
    REQUIRE(at > BACK + 20000);
    REQUIRE(emu_sync(&c, EMU_REPLY_MS) == 0);

    /* Each start one byte later: the event's end moves by a byte until
     * one more line fits, so a window as long as a line and its framing
     * packs a line that fills the event to its last bytes. */
    reconnect(at - BACK, at - BACK + longest + 8);

    /* Still alive, the first stream still open, and exits cleanly. */
    CHECK(emu_sync(&c, EMU_REPLY_MS) == 0);
    emu_close(&c);
    CHECK_EQ(emu_stop(&e), 0);
    http_stream_close(&s);
    TEST_EXIT();
}
