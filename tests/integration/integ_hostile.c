/*
 * integ_hostile: clients that misbehave, on purpose, against one daemon,
 * while a well-behaved client (the prober, a child process) asks Get
 * Opening Width (43h) every 20 ms and must get every answer within
 * PROBE_MS: whatever one client does, the others are served.
 *
 * - megabytes of random bytes, a megabyte of preamble bytes: the stream
 *   stays usable (every answer a valid packet) and a Loop after it echoes;
 * - SIZE above 256 (0xFFFF, 0x0101): E_CMD_FORMAT_ERROR under the received
 *   ID at once, without a payload being sent (NOTES: nothing is allocated
 *   from a size field; the parser resynchronises on the next preamble);
 * - a cut packet: nothing until it is completed; on TCP the next bytes,
 *   even a whole packet, are taken as its rest;
 * - a bit flipped in every position of a packet: preamble -> no packet,
 *   ID -> E_CHECKSUM_ERROR under the flipped ID, SIZE -> the checksum or
 *   the size check fails, payload and checksum -> E_CHECKSUM_ERROR;
 * - one byte per second: nobody else waits for it, and the packet is
 *   answered when complete;
 * - a client that subscribes to all five streams at 1 ms and never reads
 *   is dropped (its socket sees the reset) at the output bound;
 * - 1,000 connect/disconnect cycles, with 07h (no FAST STOP) and without
 *   (FAST STOP, cleared by "ack"); 200 clients at once; a UDP flood of
 *   valid and garbage datagrams;
 * - --max-clients: the connection over the limit is closed at once, a new
 *   one is accepted after one leaves; the same from a config file.
 *
 * The daemon's resident memory (VmRSS) is read before the phases and after
 * each one (its clients gone) and may not grow by more than RSS_GROWTH_KIB.
 */
#define _GNU_SOURCE

#include "check.h"
#include "emu.h"
#include "wsg/axis.h"

#include <arpa/inet.h>
#include <errno.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <signal.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

/* The bound for a second client's answers on this noisy 2-core
 * machine (NOTES says 250 ms for a real gripper; this is not a benchmark),
 * longer where the time scale declares the machine slower. */
#define PROBE_MS       emu_ms(500)
#define PROBE_EVERY_MS 20
/* Resident memory may grow this much over the whole run: buffers that are
 * reused, not leaked, stay far below it. */
#define RSS_GROWTH_KIB (8 * 1024)
/* How long a never-reading client may take to be dropped. */
#define DROP_MS emu_ms(30000)

/* Set when the daemon runs under a wrapper (WSG_TEST_WRAPPER, e.g.
 * valgrind, see emu.c): its latency and its RSS (the wrapper's) are then
 * not the daemon's own, so those two bounds are reported, not asserted. */
static int wrapped;

/* ---- the prober: a normal client in a child process ---- */

struct probe_result {
    long answers, late, failed;
    double max_ms;
};

struct prober {
    pid_t pid;
    int stop_fd, res_fd;
};

static void prober_run(struct emu *e, int stop_fd, int res_fd)
{
    struct probe_result r = {0, 0, 0, 0.0};
    struct emu_client c;
    struct pollfd pfd = {stop_fd, POLLIN, 0};

    if (emu_open(&c, e, &emu_tcp) != 0)
        r.failed++;
    else {
        while (poll(&pfd, 1, PROBE_EVERY_MS) == 0) {
            struct wsg_client_frame f;
            double t0 = emu_now_ms();
            int st =
                emu_request(&c, WSG_CMD_GET_WIDTH, NULL, 0, &f, EMU_REPLY_MS);
            double dt = emu_now_ms() - t0;

            /* Only the answers count: nothing else is subscribed. */
            emu_drop_kept(&c);
            if (st != WSG_E_SUCCESS) {
                r.failed++;
                break;
            }
            r.answers++;
            if (dt > r.max_ms)
                r.max_ms = dt;
            if (dt > PROBE_MS)
                r.late++;
        }
        /* 07h: the prober's own close must not FAST STOP the gripper. */
        if (emu_request(&c, WSG_CMD_DISCONNECT, NULL, 0, NULL, EMU_REPLY_MS) !=
            WSG_E_SUCCESS)
            r.failed++;
        emu_close(&c);
    }
    if (write(res_fd, &r, sizeof r) != (ssize_t)sizeof r)
        _exit(1);
    /* _exit: the parent's atexit handlers (which stop the daemon) are not
     * the child's to run. */
    _exit(0);
}

static void prober_start(struct prober *p, struct emu *e)
{
    int stop[2], res[2];

    REQUIRE(pipe(stop) == 0 && pipe(res) == 0);
    fflush(NULL);
    p->pid = fork();
    REQUIRE(p->pid >= 0);
    if (p->pid == 0) {
        close(stop[1]);
        close(res[0]);
        prober_run(e, stop[0], res[1]);
    }
    close(stop[0]);
    close(res[1]);
    p->stop_fd = stop[1];
    p->res_fd = res[0];
}

/* Stop the prober and check that it was answered within PROBE_MS every
 * time. */
static void prober_stop(struct prober *p, const char *phase)
{
    struct probe_result r = {0, 0, 0, 0.0};
    struct pollfd pfd = {p->res_fd, POLLIN, 0};
    int st = 0;

    CHECK(write(p->stop_fd, "x", 1) == 1);
    CHECK(poll(&pfd, 1, emu_ms(10000)) == 1);
    CHECK(read(p->res_fd, &r, sizeof r) == (ssize_t)sizeof r);
    CHECK(waitpid(p->pid, &st, 0) == p->pid);
    close(p->stop_fd);
    close(p->res_fd);
    printf("%-24s prober: %ld answers, slowest %.1f ms, %ld over %d ms, "
           "%ld failed\n",
           phase, r.answers, r.max_ms, r.late, PROBE_MS, r.failed);
    CHECK(r.answers > 0);
    if (!wrapped)
        CHECK_EQ(r.late, 0);
    CHECK_EQ(r.failed, 0);
}

/* ---- the daemon's memory ---- */

static long rss_kib(pid_t pid)
{
    char path[64], line[256];
    long kib = -1;
    FILE *f;

    snprintf(path, sizeof path, "/proc/%ld/status", (long)pid);
    f = fopen(path, "r");
    if (!f)
        return -1;
    while (fgets(line, sizeof line, f))
        if (sscanf(line, "VmRSS: %ld", &kib) == 1)
            break;
    fclose(f);
    return kib;
}

static long rss_base;

/* In the sanitizer build the daemon's freed memory waits in ASan's
 * quarantine: its RSS measures that, not the daemon. */
#if defined(__SANITIZE_ADDRESS__)
#define RSS_ASSERTED 0
#else
#define RSS_ASSERTED 1
#endif

static void rss_check(struct emu *e, const char *phase)
{
    long now;

    /* Let the daemon notice the closes of the phase's clients. */
    emu_sleep_ms(300);
    now = rss_kib(e->pid);
    printf("%-24s VmRSS %ld KiB (%+ld KiB since the start)\n", phase, now,
           now - rss_base);
    CHECK(now > 0);
    if (!wrapped && RSS_ASSERTED)
        CHECK(now <= rss_base + RSS_GROWTH_KIB);
}

/* ---- helpers ---- */

static uint32_t rng = 0x12345678u;

static uint8_t rnd8(void)
{
    /* xorshift32: reproducible garbage, the same in every run */
    rng ^= rng << 13;
    rng ^= rng >> 17;
    rng ^= rng << 5;
    return (uint8_t)rng;
}

/* Read and parse whatever is there (answers to garbage), without waiting. */
static long drain(struct emu_client *c)
{
    struct wsg_client_frame f;
    long n = 0;

    emu_drop_kept(c);
    while (emu_recv(c, &f, 0) == 1)
        n++;
    return n;
}

/* Send n bytes in pieces, draining the answers meanwhile: a client that
 * stopped reading would be dropped, and that is another test. */
static void blast(struct emu_client *c, const uint8_t *buf, size_t n)
{
    size_t off = 0;
    double deadline = emu_now_ms() + emu_ms(60000);

    while (off < n && emu_now_ms() < deadline) {
        struct pollfd pfd = {c->fd, POLLIN | POLLOUT, 0};

        if (poll(&pfd, 1, 100) <= 0)
            continue;
        if (pfd.revents & POLLIN)
            drain(c);
        if (pfd.revents & POLLOUT) {
            ssize_t k =
                send(c->fd, buf + off, n - off, MSG_DONTWAIT | MSG_NOSIGNAL);
            if (k > 0)
                off += (size_t)k;
            else if (k < 0 && errno != EAGAIN && errno != EINTR)
                break;
        }
        if (pfd.revents & (POLLERR | POLLHUP))
            break;
    }
    CHECK_EQ(off, n);
}

/* A packet into out; its length. */
static size_t packet(uint8_t *out, size_t cap, uint8_t id, const void *p,
                     size_t len)
{
    size_t n = wsg_frame_encode(out, cap, id, p, len);
    REQUIRE(n > 0);
    return n;
}

static int tcp_state(int fd)
{
    struct tcp_info ti;
    socklen_t len = sizeof ti;

    if (getsockopt(fd, IPPROTO_TCP, TCP_INFO, &ti, &len) < 0)
        return -1;
    return ti.tcpi_state;
}

/* A TCP connection to the daemon with a 4 KiB receive buffer, set before
 * connect so the window is small from the start (shrinking it later makes
 * the kernel refuse data already on its way, and a reset with it). */
static int deaf_connect(struct emu *e)
{
    struct sockaddr_in sa;
    char v[128], *colon;
    int rcv = 4096, fd;

    REQUIRE(emu_field(e, "tcp", v, sizeof v) != NULL);
    colon = strchr(v, ':');
    REQUIRE(colon != NULL);
    *colon = '\0';
    memset(&sa, 0, sizeof sa);
    sa.sin_family = AF_INET;
    sa.sin_port = htons((uint16_t)atoi(colon + 1));
    REQUIRE(inet_pton(AF_INET, v, &sa.sin_addr) == 1);
    fd = socket(AF_INET, SOCK_STREAM, 0);
    REQUIRE(fd >= 0);
    setsockopt(fd, SOL_SOCKET, SO_RCVBUF, &rcv, sizeof rcv);
    REQUIRE(connect(fd, (struct sockaddr *)&sa, sizeof sa) == 0);
    return fd;
}

/* ---- phases ---- */

static void test_garbage(struct emu *e)
{
    static uint8_t buf[4u << 20];
    struct emu_client c;
    uint8_t zeros[WSG_PAYLOAD_MAX + WSG_CRC_LEN];
    struct prober p;

    prober_start(&p, e);
    REQUIRE(emu_open(&c, e, &emu_tcp) == 0);
    for (size_t i = 0; i < sizeof buf; i++)
        buf[i] = rnd8();
    blast(&c, buf, sizeof buf);
    /* Finish whatever packet the garbage left open (no AAh in zeros, so
     * no new one starts), then the stream must be in step again. */
    memset(zeros, 0, sizeof zeros);
    blast(&c, zeros, sizeof zeros);
    CHECK(emu_sync(&c, EMU_REPLY_MS) == 0);
    CHECK_EQ(c.link.bad, 0); /* every answer a valid packet */

    /* A megabyte of preamble bytes: one long preamble (no command has the
     * ID AAh), nothing to answer; the packet after it is answered. */
    memset(buf, 0xAA, 1u << 20);
    blast(&c, buf, 1u << 20);
    CHECK(emu_sync(&c, EMU_REPLY_MS) == 0);
    CHECK_EQ(c.link.keep_n, 0);
    /* Preambles with no packet after them, then a packet. */
    for (size_t i = 0; i + 4 <= (1u << 20); i += 4) {
        buf[i] = buf[i + 1] = buf[i + 2] = 0xAA;
        buf[i + 3] = 0x00;
    }
    /* Each "AA AA AA 00" starts a packet with ID 00 whose SIZE is the next
     * two bytes: AA AA = 43690 > 256, E_CMD_FORMAT_ERROR under ID 00 each
     * time; the stream goes on. A megabyte of it in 32 KiB pieces, each
     * one's answers read before the next: a client that reads its answers
     * (the one that does not is another phase's). */
    for (size_t off = 0; off < (1u << 20); off += 32u << 10) {
        blast(&c, buf + off, 32u << 10);
        CHECK(emu_sync(&c, emu_ms(10000)) == 0);
    }
    blast(&c, zeros, sizeof zeros);
    CHECK(emu_sync(&c, emu_ms(10000)) == 0);
    CHECK_EQ(c.link.bad, 0);
    CHECK_EQ(emu_request(&c, WSG_CMD_DISCONNECT, NULL, 0, NULL, EMU_REPLY_MS),
             WSG_E_SUCCESS);
    emu_close(&c);
    prober_stop(&p, "garbage");
    rss_check(e, "garbage");
}

static void test_size(struct emu *e)
{
    static const uint8_t big[][6] = {{0xAA, 0xAA, 0xAA, 0x06, 0xFF, 0xFF},
                                     {0xAA, 0xAA, 0xAA, 0x43, 0x01, 0x01}};
    struct emu_client c;
    struct wsg_client_frame f;

    REQUIRE(emu_open(&c, e, &emu_tcp) == 0);
    for (size_t i = 0; i < sizeof big / sizeof big[0]; i++) {
        /* The header alone: the answer may not wait for a payload. */
        REQUIRE(emu_send_raw(&c, big[i], sizeof big[i]) == 0);
        CHECK_EQ(emu_recv(&c, &f, EMU_REPLY_MS), 1);
        CHECK_EQ(f.id, big[i][3]);
        CHECK_EQ(f.status, WSG_E_CMD_FORMAT_ERROR);
        CHECK_EQ(f.len, 2);
        CHECK(emu_sync(&c, EMU_REPLY_MS) == 0);
        CHECK_EQ(c.link.keep_n, 0);
    }
    CHECK_EQ(emu_request(&c, WSG_CMD_DISCONNECT, NULL, 0, NULL, EMU_REPLY_MS),
             WSG_E_SUCCESS);
    emu_close(&c);
}

static void test_cut(struct emu *e)
{
    uint8_t inner[16], payload[40], pkt[64];
    struct emu_client c;
    struct wsg_client_frame f;
    size_t ni, n, cut = WSG_HEADER_LEN + 5;

    /* A Loop whose payload holds a whole Get Opening Width packet: sent
     * in two pieces, the second piece is the rest of the Loop, not a
     * request of its own. */
    ni = packet(inner, sizeof inner, WSG_CMD_GET_WIDTH, NULL, 0);
    memset(payload, 0x11, sizeof payload);
    memcpy(payload + 5, inner, ni);
    n = packet(pkt, sizeof pkt, WSG_CMD_LOOP, payload, sizeof payload);

    REQUIRE(emu_open(&c, e, &emu_tcp) == 0);
    REQUIRE(emu_send_raw(&c, pkt, cut) == 0);
    /* Nothing until it is complete. */
    CHECK_EQ(emu_recv(&c, &f, 2 * EMU_QUIET_MS), 0);
    REQUIRE(emu_send_raw(&c, pkt + cut, n - cut) == 0);
    CHECK_EQ(emu_recv(&c, &f, EMU_REPLY_MS), 1);
    CHECK_EQ(f.id, WSG_CMD_LOOP);
    CHECK_EQ(f.status, WSG_E_SUCCESS);
    CHECK_EQ(f.len, 2 + sizeof payload);
    CHECK(memcmp(EMU_PARAMS(&f), payload, sizeof payload) == 0);
    CHECK(emu_sync(&c, EMU_REPLY_MS) == 0);
    CHECK_EQ(c.link.seen[WSG_CMD_GET_WIDTH], 0);

    /* Cut and left alone, then closed: the daemon forgets it. */
    REQUIRE(emu_send_raw(&c, pkt, cut) == 0);
    emu_sleep_ms(EMU_QUIET_MS);
    emu_close(&c);
    /* That close had no 07h: FAST STOP; clear it for the next phases. */
    REQUIRE(emu_open(&c, e, &emu_tcp) == 0);
    CHECK_EQ(
        emu_request(&c, WSG_CMD_ACK_FAST_STOP, "ack", 3, NULL, EMU_REPLY_MS),
        WSG_E_SUCCESS);
    CHECK_EQ(emu_request(&c, WSG_CMD_DISCONNECT, NULL, 0, NULL, EMU_REPLY_MS),
             WSG_E_SUCCESS);
    emu_close(&c);
}

/* One bit flipped in each byte of a packet, each alone. Not a Loop: the
 * sync after each one is a Loop, and the answers must not be confused. */
static void test_every_position(struct emu *e)
{
    static const uint8_t body[4] = {0x77, 0x31, 0x52, 0x13};
    uint8_t pkt[32], bad[32];
    struct emu_client c;
    size_t n = packet(pkt, sizeof pkt, WSG_CMD_GET_WIDTH, body, sizeof body);

    REQUIRE(emu_open(&c, e, &emu_tcp) == 0);
    for (size_t i = 0; i < n; i++) {
        uint8_t flip = 0x01;
        int want_id = WSG_CMD_GET_WIDTH;
        unsigned want_status = WSG_E_CHECKSUM_ERROR;

        if (i < 3) {
            flip = 0x80; /* no preamble, no packet: nothing to answer */
            want_id = -1;
        } else if (i == 3) {
            flip = 0x40; /* under the received ID: 03h */
            want_id = WSG_CMD_GET_WIDTH ^ 0x40;
        } else if (i == 4) {
            flip = 0x04; /* SIZE 0: two payload bytes read as checksum */
        } else if (i == 5) {
            want_status = WSG_E_CMD_FORMAT_ERROR; /* SIZE 260 */
        }
        memcpy(bad, pkt, n);
        bad[i] ^= flip;
        REQUIRE(emu_send_raw(&c, bad, n) == 0);
        /* The rest of a broken packet is garbage up to the next preamble,
         * which the sync Loop brings. */
        CHECK(emu_sync(&c, EMU_REPLY_MS) == 0);
        if (want_id < 0) {
            CHECK_EQ(c.link.keep_n, 0);
        } else {
            CHECK_EQ(c.link.keep_n, 1);
            if (c.link.keep_n >= 1) {
                CHECK_EQ(c.keep[0].id, want_id);
                CHECK_EQ(c.keep[0].status, want_status);
            }
        }
        if (c.link.keep_n != (want_id < 0 ? 0u : 1u))
            fprintf(stderr, "  byte %zu flipped: %u answers\n", i,
                    c.link.keep_n);
        emu_drop_kept(&c);
    }
    CHECK_EQ(emu_request(&c, WSG_CMD_DISCONNECT, NULL, 0, NULL, EMU_REPLY_MS),
             WSG_E_SUCCESS);
    emu_close(&c);
    rss_check(e, "size/cut/every position");
}

/* A client that never reads, with the daemon producing output on its own,
 * and a client sending one byte per second, at the same time. */
static void test_slow_and_deaf(struct emu *e)
{
    static const uint8_t streams[] = {
        WSG_CMD_GET_SYSTEM_STATE, WSG_CMD_GET_GRASP_STATE, WSG_CMD_GET_WIDTH,
        WSG_CMD_GET_SPEED, WSG_CMD_GET_FORCE};
    uint8_t sub[3] = {0x01, 1, 0}; /* auto update, every 1 ms */
    struct emu_client slow;
    struct wsg_client_frame f;
    struct prober p;
    uint8_t pkt[16], req[16];
    size_t n = packet(pkt, sizeof pkt, WSG_CMD_LOOP, NULL, 0), sent = 0;
    double t0, dropped_ms = -1;
    int deaf;

    prober_start(&p, e);
    deaf = deaf_connect(e);
    for (size_t i = 0; i < sizeof streams; i++) {
        size_t k = packet(req, sizeof req, streams[i], sub, sizeof sub);
        REQUIRE(send(deaf, req, k, MSG_NOSIGNAL) == (ssize_t)k);
    }
    REQUIRE(emu_open(&slow, e, &emu_tcp) == 0);
    t0 = emu_now_ms();
    while (emu_now_ms() - t0 < DROP_MS && (sent < n || dropped_ms < 0)) {
        if (sent < n && emu_now_ms() - t0 >= 1000.0 * (double)sent) {
            REQUIRE(emu_send_raw(&slow, pkt + sent, 1) == 0);
            sent++;
            if (sent == n) {
                /* Complete at last: answered like any packet. */
                CHECK_EQ(emu_recv(&slow, &f, EMU_REPLY_MS), 1);
                CHECK_EQ(f.id, WSG_CMD_LOOP);
                CHECK_EQ(f.status, WSG_E_SUCCESS);
            } else {
                CHECK_EQ(emu_recv(&slow, &f, 0), 0);
            }
        }
        /* The deaf client is never read; its state shows the reset. */
        if (dropped_ms < 0 && tcp_state(deaf) != TCP_ESTABLISHED)
            dropped_ms = emu_now_ms() - t0;
        emu_sleep_ms(50);
    }
    printf("never-reading client dropped after %.0f ms\n", dropped_ms);
    CHECK(dropped_ms >= 0);
    CHECK_EQ(sent, n);
    /* The slow client is still served. */
    CHECK(emu_sync(&slow, EMU_REPLY_MS) == 0);
    CHECK_EQ(
        emu_request(&slow, WSG_CMD_DISCONNECT, NULL, 0, NULL, EMU_REPLY_MS),
        WSG_E_SUCCESS);
    emu_close(&slow);
    close(deaf);
    /* Dropped means ended without 07h (docs/behaviour.md): FAST STOP. */
    REQUIRE(emu_open(&slow, e, &emu_tcp) == 0);
    CHECK(emu_wait_flags(&slow, WSG_SF_FAST_STOP, WSG_SF_FAST_STOP,
                         EMU_REPLY_MS, NULL) == 0);
    CHECK_EQ(emu_request(&slow, WSG_CMD_ACK_FAST_STOP, "ack", 3, NULL,
                         EMU_REPLY_MS),
             WSG_E_SUCCESS);
    CHECK_EQ(
        emu_request(&slow, WSG_CMD_DISCONNECT, NULL, 0, NULL, EMU_REPLY_MS),
        WSG_E_SUCCESS);
    emu_close(&slow);
    prober_stop(&p, "slow + never reading");
    rss_check(e, "slow + never reading");
}

static void test_cycles(struct emu *e)
{
    struct emu_client c;
    struct prober p;
    uint32_t flags = 0;
    int bad = 0;

    prober_start(&p, e);
    for (int i = 0; i < 1000 && bad < 5; i++) {
        if (emu_open(&c, e, &emu_tcp) != 0) {
            bad++;
            continue;
        }
        if (i < 900) {
            /* Announced: no FAST STOP. */
            if (emu_request(&c, WSG_CMD_DISCONNECT, NULL, 0, NULL,
                            EMU_REPLY_MS) != WSG_E_SUCCESS)
                bad++;
            if (i == 899) {
                struct emu_client q;
                REQUIRE(emu_open(&q, e, &emu_tcp) == 0);
                CHECK(emu_get_flags(&q, &flags) == 0);
                CHECK_EQ(flags & WSG_SF_FAST_STOP, 0);
                CHECK_EQ(emu_request(&q, WSG_CMD_DISCONNECT, NULL, 0, NULL,
                                     EMU_REPLY_MS),
                         WSG_E_SUCCESS);
                emu_close(&q);
            }
        } else if (i % 2 && emu_request(&c, WSG_CMD_LOOP, "x", 1, NULL,
                                        EMU_REPLY_MS) != WSG_E_SUCCESS) {
            bad++;
        }
        /* The rest: a port probe, connect and close. */
        emu_close(&c);
    }
    CHECK_EQ(bad, 0);
    /* The last closes may still be on their way: a close seen after the
     * "ack" would set FAST STOP again. */
    emu_sleep_ms(EMU_QUIET_MS);
    REQUIRE(emu_open(&c, e, &emu_tcp) == 0);
    /* The closes without 07h were seen: FAST STOP until "ack". */
    CHECK(emu_wait_flags(&c, WSG_SF_FAST_STOP, WSG_SF_FAST_STOP, EMU_REPLY_MS,
                         &flags) == 0);
    CHECK_EQ(
        emu_request(&c, WSG_CMD_ACK_FAST_STOP, "ack", 3, NULL, EMU_REPLY_MS),
        WSG_E_SUCCESS);
    /* The "ack" takes effect at the next model step; until then 40h may
     * still show the flag (reported: the flags lag the answer). */
    CHECK(emu_wait_flags(&c, WSG_SF_FAST_STOP, 0, EMU_REPLY_MS, &flags) == 0);
    CHECK_EQ(emu_request(&c, WSG_CMD_DISCONNECT, NULL, 0, NULL, EMU_REPLY_MS),
             WSG_E_SUCCESS);
    emu_close(&c);
    prober_stop(&p, "1000 cycles");
    rss_check(e, "1000 cycles");
}

#define CROWD 200

static void test_crowd(struct emu *e)
{
    struct emu_client *cs = calloc(CROWD, sizeof *cs);
    struct wsg_client_frame f;
    int answered = 0;

    REQUIRE(cs != NULL);
    for (int i = 0; i < CROWD; i++)
        REQUIRE(emu_open(&cs[i], e, &emu_tcp) == 0);
    /* All of them ask before any answer is read. */
    for (int i = 0; i < CROWD; i++) {
        uint8_t tok[4];
        wsg_put_u32(tok, (uint32_t)i);
        CHECK(emu_send(&cs[i], WSG_CMD_LOOP, tok, sizeof tok) == 0);
    }
    for (int i = 0; i < CROWD; i++) {
        if (emu_recv_id(&cs[i], WSG_CMD_LOOP, &f, EMU_REPLY_MS) == 1 &&
            f.status == WSG_E_SUCCESS && f.len == 6 &&
            wsg_get_u32(EMU_PARAMS(&f)) == (uint32_t)i)
            answered++;
    }
    CHECK_EQ(answered, CROWD);
    /* For the report: the peak with every connection open. */
    printf("%d clients connected: VmRSS %ld KiB\n", CROWD, rss_kib(e->pid));
    for (int i = 0; i < CROWD; i++)
        CHECK(emu_send(&cs[i], WSG_CMD_DISCONNECT, NULL, 0) == 0);
    for (int i = 0; i < CROWD; i++) {
        CHECK_EQ(emu_recv_id(&cs[i], WSG_CMD_DISCONNECT, &f, EMU_REPLY_MS), 1);
        emu_close(&cs[i]);
    }
    free(cs);
    printf("%d clients at once: %d answered\n", CROWD, answered);
    rss_check(e, "200 clients");
}

static void test_udp_flood(struct emu *e)
{
    struct emu_client u;
    struct sockaddr_in to;
    struct prober p;
    char v[128], *colon;
    uint8_t dg[512];
    long valid = 0, garbage = 0, answers;
    int fd;

    REQUIRE(emu_field(e, "udp", v, sizeof v) != NULL);
    colon = strchr(v, ':');
    REQUIRE(colon != NULL);
    memset(&to, 0, sizeof to);
    to.sin_family = AF_INET;
    to.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    to.sin_port = htons((uint16_t)atoi(colon + 1));
    REQUIRE(emu_open(&u, e, &emu_udp) == 0);
    fd = socket(AF_INET, SOCK_DGRAM, 0);
    REQUIRE(fd >= 0);

    prober_start(&p, e);
    for (int i = 0; i < 30000; i++) {
        size_t n;

        if (i % 10 == 0) {
            uint8_t tok[4];
            wsg_put_u32(tok, (uint32_t)i);
            n = packet(dg, sizeof dg, WSG_CMD_LOOP, tok, sizeof tok);
            valid++;
        } else if (i % 10 == 1) {
            n = packet(dg, sizeof dg, WSG_CMD_GET_WIDTH, NULL, 0);
            valid++;
        } else {
            n = 1 + rnd8() % 300u;
            for (size_t k = 0; k < n; k++)
                dg[k] = rnd8();
            if (i % 10 == 2) /* a preamble and a header of garbage */
                memset(dg, 0xAA, 3);
            garbage++;
        }
        if (sendto(fd, dg, n, 0, (struct sockaddr *)&to, sizeof to) < 0 &&
            errno != EAGAIN && errno != ENOBUFS)
            CHECK(!"sendto");
        /* The answers land in the UDP client's socket: read them now and
         * then, so they are parsed (all valid packets) rather than lost. */
        if (i % 100 == 0)
            drain(&u);
    }
    emu_sleep_ms(200);
    answers = drain(&u);
    (void)answers;
    close(fd);
    CHECK_EQ(u.link.bad, 0);
    /* The UDP interface itself is still there. */
    CHECK(emu_sync(&u, EMU_REPLY_MS) == 0);
    emu_close(&u);
    prober_stop(&p, "udp flood");
    printf("udp flood: %ld valid and %ld garbage datagrams\n", valid, garbage);
    rss_check(e, "udp flood");
}

/* ---- --max-clients ---- */

/* Connected, then closed by the daemon at once (EOF or reset). */
static void check_refused(struct emu *e)
{
    struct emu_client c;
    uint8_t buf[64];
    double t0 = emu_now_ms();
    long n;

    REQUIRE(emu_open(&c, e, &emu_tcp) == 0);
    n = emu_recv_raw(&c, buf, sizeof buf, EMU_REPLY_MS);
    printf("connection over the limit: recv %ld after %.1f ms\n", n,
           emu_now_ms() - t0);
    CHECK_EQ(n, 0);
    CHECK(emu_now_ms() - t0 < PROBE_MS);
    emu_close(&c);
}

static void max_clients(struct emu *e, int max)
{
    struct emu_client c[4];

    for (int i = 0; i < max; i++) {
        REQUIRE(emu_open(&c[i], e, &emu_tcp) == 0);
        CHECK_EQ(emu_request(&c[i], WSG_CMD_LOOP, "m", 1, NULL, EMU_REPLY_MS),
                 WSG_E_SUCCESS);
    }
    check_refused(e);
    check_refused(e);
    /* One leaves (announced); once the daemon has seen the close there is
     * room for one more. When that is, this end cannot tell: a connection
     * made before is refused, and another is tried, within a bound. */
    CHECK_EQ(
        emu_request(&c[0], WSG_CMD_DISCONNECT, NULL, 0, NULL, EMU_REPLY_MS),
        WSG_E_SUCCESS);
    emu_close(&c[0]);
    {
        double deadline = emu_now_ms() + EMU_REPLY_MS;
        int st;

        for (;;) {
            emu_sleep_ms(50);
            REQUIRE(emu_open(&c[0], e, &emu_tcp) == 0);
            st = emu_request(&c[0], WSG_CMD_LOOP, "n", 1, NULL, EMU_REPLY_MS);
            if (st == WSG_E_SUCCESS || emu_now_ms() >= deadline)
                break;
            emu_close(&c[0]);
        }
        CHECK_EQ(st, WSG_E_SUCCESS);
    }
    check_refused(e);
    for (int i = 0; i < max; i++) {
        CHECK_EQ(emu_request(&c[i], WSG_CMD_DISCONNECT, NULL, 0, NULL,
                             EMU_REPLY_MS),
                 WSG_E_SUCCESS);
        emu_close(&c[i]);
    }
}

static void test_max_clients(const char *exe)
{
    static const char *const args[] = {"--tcp", "127.0.0.1:0", "--max-clients",
                                       "3", NULL};
    static const char *const zero[] = {"--max-clients", "0", NULL};
    static const char *const many[] = {"--max-clients", "257", NULL};
    char path[] = "/tmp/wsgemu-hostile-XXXXXX";
    const char *cargs[] = {"--config", path, NULL};
    char out[256], err[512];
    struct emu e;
    FILE *f;
    int fd;

    REQUIRE(emu_start(&e, exe, args) == 0);
    max_clients(&e, 3);
    CHECK_EQ(emu_stop(&e), 0);

    /* The config file's key is the option's name. */
    fd = mkstemp(path);
    REQUIRE(fd >= 0);
    f = fdopen(fd, "w");
    REQUIRE(f != NULL);
    fprintf(f, "tcp = 127.0.0.1:0\nmax-clients = 2\n");
    fclose(f);
    REQUIRE(emu_start(&e, exe, cargs) == 0);
    max_clients(&e, 2);
    CHECK_EQ(emu_stop(&e), 0);
    unlink(path);

    CHECK_EQ(
        emu_run(exe, zero, emu_ms(5000), out, sizeof out, err, sizeof err), 2);
    CHECK(strstr(err, "max-clients") != NULL);
    CHECK_EQ(
        emu_run(exe, many, emu_ms(5000), out, sizeof out, err, sizeof err), 2);
}

int main(int argc, char **argv)
{
    const char *exe = emu_exe(argc, argv);
    const char *args[16];
    struct emu e, parts;
    size_t n = 0;
    int r;

    setvbuf(stdout, NULL, _IOLBF, 0);
    signal(SIGPIPE, SIG_IGN);
    wrapped = getenv("WSG_TEST_WRAPPER") && *getenv("WSG_TEST_WRAPPER");
    if (wrapped)
        printf("under WSG_TEST_WRAPPER: latency and RSS bounds not "
               "asserted\n");
    test_max_clients(exe);

    /* TCP with room for the crowd, and UDP (its reply port reserved by
     * the UDP transport's hook). */
    memset(&parts, 0, sizeof parts);
    parts.tp_fd = -1;
    r = emu_udp.daemon_args(&parts);
    if (r == 77)
        test_skip("no UDP here");
    REQUIRE(r == 0);
    for (int k = 0; parts.tp_argv[k]; k++)
        args[n++] = parts.tp_argv[k];
    args[n++] = "--tcp";
    args[n++] = "127.0.0.1:0";
    args[n++] = "--max-clients";
    args[n++] = "250";
    args[n] = NULL;
    REQUIRE(emu_start(&e, exe, args) == 0);
    e.tp_fd = parts.tp_fd;
    e.tp_port = parts.tp_port;
    rss_base = rss_kib(e.pid);
    printf("%s\nVmRSS at the start: %ld KiB\n", e.line, rss_base);
    REQUIRE(rss_base > 0);

    test_garbage(&e);
    test_size(&e);
    test_cut(&e);
    test_every_position(&e);
    test_slow_and_deaf(&e);
    test_cycles(&e);
    test_crowd(&e);
    test_udp_flood(&e);

    CHECK_EQ(emu_stop(&e), 0);
    TEST_EXIT();
}
