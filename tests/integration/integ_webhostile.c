/*
 * integ_webhostile: the web page's limits (--web) against peers that take
 * all they can, so that everyone else is still served.
 *
 * A peer is an address: the test's connections are made from loopback
 * addresses of their own (127.0.0.2 and up, bound before connecting; the
 * daemon listens on 127.0.0.1). Where they cannot be bound the test is
 * skipped.
 *
 * - event streams: a peer has at most 16; its 17th is refused with 503
 *   and a Retry-After; 64 in all: with four peers at 16, a fifth peer's
 *   stream is 503 too;
 * - connections: a peer has at most 64: the peer holding 16 streams opens
 *   48 more that send a request's head a byte a second (slowloris); its
 *   65th connection is closed without an answer, while another peer
 *   (127.0.0.1) is answered at once (GET /state.json and GET /);
 * - the deadline: each slow connection is closed by the daemon 10 s
 *   after it opened (not before 9 s, by 10 s and a bound), although it
 *   never stopped sending; the 64 streams, idle by design all that time,
 *   are not cut: the next change reaches every one of them; the slow
 *   peer is answered again;
 * - with the streams closed, a new one is taken (200).
 *
 * Built without libmicrohttpd (WSG_TEST_HAVE_WEB 0) it is skipped.
 */
#define _GNU_SOURCE

#include "check.h"
#include "emu.h"
#include "emu_ctl.h"
#include "emu_http.h"

#include <arpa/inet.h>
#include <errno.h>
#include <netinet/in.h>
#include <poll.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <unistd.h>

#ifndef WSG_TEST_HAVE_WEB
#define WSG_TEST_HAVE_WEB 0
#endif

/* The daemon's limits (docs/web.md, Security). */
#define PEER_STREAMS 16
#define STREAMS      64
#define PEER_CONNS   64
#define DEADLINE_MS  10000
/* The peers that fill the streams; the first is also the slow one. */
#define NPEERS (STREAMS / PEER_STREAMS)
#define NSLOW  (PEER_CONNS - PEER_STREAMS)
/* Room for one event's data (a log event is up to 16 KiB). */
#define EV_MAX 20000

static const char *const args[] = {"--tcp",       "127.0.0.1:0", "--control",
                                   "127.0.0.1:0", "--web",       "127.0.0.1:0",
                                   NULL};
static const char *const peers[] = {"127.0.0.2", "127.0.0.3", "127.0.0.4",
                                    "127.0.0.5"};
static const char *const other = "127.0.0.6";

static char web[64];
static struct http_answer ans;

/* GET path from the address from: the status, or -1 (no answer). */
static int get_from(const char *from, const char *path)
{
    int r;

    http_source(from);
    r = http_request(web, "GET", path, NULL, NULL, &ans, EMU_REPLY_MS);
    http_source(NULL);
    return r < 0 ? -1 : ans.status;
}

/* Whether a socket can be bound to 127.0.0.2 here. */
static int can_bind_peers(void)
{
    struct sockaddr_in sa;
    int fd = socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0), r;

    if (fd < 0)
        return 0;
    memset(&sa, 0, sizeof sa);
    sa.sin_family = AF_INET;
    inet_pton(AF_INET, "127.0.0.2", &sa.sin_addr);
    r = bind(fd, (struct sockaddr *)&sa, sizeof sa);
    close(fd);
    return r == 0;
}

/* A stream of a peer's: open, its first state event read. */
static int open_stream(struct http_stream *s, const char *from)
{
    char name[64];
    static char data[EV_MAX];
    int r;

    http_source(from);
    r = http_stream_open(s, web, "/events", EMU_REPLY_MS);
    http_source(NULL);
    if (r < 0 || s->status != 200)
        return -1;
    return http_stream_event(s, name, sizeof name, data, sizeof data,
                             EMU_REPLY_MS) == 1
               ? 0
               : -1;
}

/* A refused stream: 503, a Retry-After of some seconds, a JSON error. */
static void check_refused(const char *from)
{
    char v[32];

    CHECK_EQ(get_from(from, "/events"), 503);
    CHECK(http_header(&ans, "Retry-After", v, sizeof v) && atoi(v) > 0);
    CHECK(strstr(ans.body, "\"error\":\"") != NULL);
}

/* Wait for a state event whose data has want: 1, or 0 within
 * timeout_ms. */
static int stream_until(struct http_stream *s, const char *want,
                        int timeout_ms)
{
    static char data[EV_MAX];
    double end = emu_now_ms() + timeout_ms, left;
    char name[64];

    while ((left = end - emu_now_ms()) > 0) {
        if (http_stream_event(s, name, sizeof name, data, sizeof data,
                              (int)left) != 1)
            return 0;
        if (strcmp(name, "state") == 0 && strstr(data, want))
            return 1;
    }
    return 0;
}

/* A connection of from's that sends the start of a request's head. */
static int open_slow(const char *from)
{
    char head[128];
    int fd, n;

    http_source(from);
    fd = http_open(web);
    http_source(NULL);
    if (fd < 0)
        return -1;
    n = snprintf(head, sizeof head, "GET /state.json HTTP/1.1\r\nHost: %s\r\n",
                 web);
    if (send(fd, head, (size_t)n, MSG_NOSIGNAL) != n) {
        close(fd);
        return -1;
    }
    return fd;
}

/* Whether the daemon closed fd (an end of file or a reset), without
 * waiting. */
static int closed_by_peer(int fd)
{
    struct pollfd p = {fd, POLLIN, 0};
    char buf[256];
    ssize_t n;

    if (poll(&p, 1, 0) <= 0)
        return 0;
    n = recv(fd, buf, sizeof buf, MSG_DONTWAIT);
    return n == 0 || (n < 0 && errno != EAGAIN && errno != EWOULDBLOCK);
}

static void test_limits(struct ctl *k)
{
    struct http_stream *s = calloc(STREAMS, sizeof *s);
    int slow[NSLOW], i, p, open, early = 0, answered = 0;
    double opened[NSLOW], cut[NSLOW], end, next;

    REQUIRE(s != NULL);
    /* A peer's streams, then one more: refused. */
    for (i = 0; i < PEER_STREAMS; i++)
        REQUIRE(open_stream(&s[i], peers[0]) == 0);
    check_refused(peers[0]);
    /* Every peer's: the cap in all, then another peer's: refused. */
    for (p = 1; p < NPEERS; p++)
        for (i = 0; i < PEER_STREAMS; i++)
            REQUIRE(open_stream(&s[p * PEER_STREAMS + i], peers[p]) == 0);
    check_refused(other);

    /* The first peer's connections up to its limit, all of them slow. */
    for (i = 0; i < NSLOW; i++) {
        slow[i] = open_slow(peers[0]);
        REQUIRE(slow[i] >= 0);
        opened[i] = emu_now_ms();
        cut[i] = 0;
    }
    /* One more from it: closed without an answer (the daemon takes the
     * connections in the order they came). */
    CHECK(get_from(peers[0], "/state.json") < 0);
    /* Anyone else: served at once. */
    CHECK_EQ(get_from(NULL, "/state.json"), 200);
    CHECK_EQ(get_from(NULL, "/"), 200);

    /* A byte a second from each slow connection until the daemon closes
     * it, which the deadline bounds. */
    end = emu_now_ms() + DEADLINE_MS + emu_ms(5000);
    next = emu_now_ms();
    open = NSLOW;
    while (open > 0 && emu_now_ms() < end) {
        if (emu_now_ms() >= next) {
            next += 1000;
            for (i = 0; i < NSLOW; i++)
                if (!cut[i] && send(slow[i], "X", 1, MSG_NOSIGNAL) < 0 &&
                    errno != EAGAIN)
                    cut[i] = emu_now_ms();
            /* Still served while they hold their slots. */
            if (get_from(NULL, "/state.json") == 200)
                answered++;
        }
        for (i = 0; i < NSLOW; i++)
            if (!cut[i] && closed_by_peer(slow[i]))
                cut[i] = emu_now_ms();
        for (open = 0, i = 0; i < NSLOW; i++)
            open += !cut[i];
        emu_sleep_ms(20);
    }
    CHECK_EQ(open, 0);
    for (i = 0; i < NSLOW; i++) {
        if (cut[i] && cut[i] - opened[i] < DEADLINE_MS - 1000)
            early++;
        close(slow[i]);
    }
    /* Cut by the deadline, not sooner (by something else). */
    CHECK_EQ(early, 0);
    CHECK(answered >= DEADLINE_MS / 1000 - 1);
    CHECK_EQ(get_from(peers[0], "/state.json"), 200);

    /* The streams, idle all along, were left alone. */
    CMD_OK(k, "part 30");
    for (open = 0, i = 0; i < STREAMS; i++)
        open +=
            stream_until(&s[i], "\"part\":{\"width\":30.000", EMU_REPLY_MS);
    CHECK_EQ(open, STREAMS);
    CMD_OK(k, "part none");
    for (i = 0; i < STREAMS; i++)
        http_stream_close(&s[i]);

    /* Their slots are free again (once the daemon has seen them go). */
    end = emu_now_ms() + EMU_REPLY_MS;
    while (open_stream(&s[0], other) < 0 && emu_now_ms() < end) {
        http_stream_close(&s[0]);
        emu_sleep_ms(50);
    }
    CHECK_EQ(s[0].status, 200);
    http_stream_close(&s[0]);
    free(s);
}

int main(int argc, char **argv)
{
    const char *exe = emu_exe(argc, argv);
    struct emu e;
    struct ctl k;

    if (!WSG_TEST_HAVE_WEB)
        test_skip("wsgemu was built without libmicrohttpd");
    if (!can_bind_peers())
        test_skip("cannot bind 127.0.0.2: no peers of their own here");
    REQUIRE(emu_start(&e, exe, args) == 0);
    REQUIRE(emu_field(&e, "web", web, sizeof web) != NULL);
    REQUIRE(ctl_open(&k, &e) == 0);

    test_limits(&k);

    ctl_close(&k);
    CHECK_EQ(emu_stop(&e), 0);
    TEST_EXIT();
}
