/*
 * integ_basic: the daemon as a process and the packet layer on the wire.
 *
 * - the ready line: "ready" then name=value fields, tcp= with the port the
 *   kernel picked for port 0 (two daemons at once get two ports), nothing
 *   else on stdout;
 * - every reply arrives whole in a single recv() (drivers read that way);
 * - Loop (06h) echoes 0..256 bytes, including bytes that look like a
 *   preamble; 257 bytes are E_CMD_FORMAT_ERROR and the stream resyncs;
 * - an unknown ID answers exactly the bytes of the manual's chapter 1.2;
 *   the manual's chapter 1.1 example packets pass the checksum check;
 * - a bad checksum answers E_CHECKSUM_ERROR under the received ID;
 * - --no-crc ignores 00 00 / FF FF checksums but still sends valid ones;
 * - SIGTERM and SIGINT exit 0; bad options exit 2 with a message.
 */
#include "check.h"
#include "emu.h"

#include <ctype.h>
#include <signal.h>
#include <stdlib.h>
#include <string.h>

static const char *const tcp_args[] = {"--tcp", "127.0.0.1:0", NULL};

/* The interface under test (argv[2]): every check that is not about TCP
 * or the command line runs over each of them. */
static const struct emu_transport *tp;

/* The ready line: "ready" and space-separated name=value fields, names of
 * lower-case letters, values non-empty, no name twice. */
static int ready_line_ok(const char *line)
{
    char names[16][32];
    int nn = 0;
    if (strncmp(line, "ready ", 6) != 0)
        return 0;
    const char *p = line + 6;
    for (;;) {
        const char *end = strchr(p, ' ');
        size_t tl = end ? (size_t)(end - p) : strlen(p);
        const char *eq = memchr(p, '=', tl);
        if (!eq || eq == p || eq == p + tl - 1)
            return 0;
        size_t nl = (size_t)(eq - p);
        if (nl >= sizeof(names[0]) || nn == 16)
            return 0;
        for (size_t i = 0; i < nl; i++)
            if (!islower((unsigned char)p[i]))
                return 0;
        for (int i = 0; i < nn; i++)
            if (strlen(names[i]) == nl && memcmp(names[i], p, nl) == 0)
                return 0;
        memcpy(names[nn], p, nl);
        names[nn++][nl] = '\0';
        if (!end)
            return 1;
        p = end + 1;
    }
}

/* Port of a "127.0.0.1:PORT" value; 0 if it is not that. */
static long tcp_port(const char *v)
{
    if (strncmp(v, "127.0.0.1:", 10) != 0)
        return 0;
    char *end;
    long port = strtol(v + 10, &end, 10);
    if (*end != '\0' || port < 1 || port > 65535)
        return 0;
    return port;
}

static void test_ready_line(const char *exe)
{
    struct emu a, b;
    struct emu_client c;
    char va[64], vb[64];

    REQUIRE(emu_start(&a, exe, tcp_args) == 0);
    REQUIRE(emu_start(&b, exe, tcp_args) == 0);
    printf("ready lines: \"%s\" / \"%s\"\n", a.line, b.line);
    CHECK(ready_line_ok(a.line));
    CHECK(ready_line_ok(b.line));
    REQUIRE(emu_field(&a, "tcp", va, sizeof(va)) != NULL);
    REQUIRE(emu_field(&b, "tcp", vb, sizeof(vb)) != NULL);
    /* Port 0 means "pick a free one": a real port, different for two
     * daemons running at once. */
    CHECK(tcp_port(va) != 0);
    CHECK(tcp_port(vb) != 0);
    CHECK(tcp_port(va) != tcp_port(vb));
    /* The port printed is the one listening. */
    CHECK(emu_open(&c, &a, &emu_tcp) == 0);
    CHECK_EQ(emu_request(&c, WSG_CMD_LOOP, "x", 1, NULL, EMU_REPLY_MS),
             WSG_E_SUCCESS);
    emu_close(&c);
    CHECK(emu_open(&c, &b, &emu_tcp) == 0);
    CHECK_EQ(emu_request(&c, WSG_CMD_LOOP, "y", 1, NULL, EMU_REPLY_MS),
             WSG_E_SUCCESS);
    CHECK_EQ(emu_request(&c, WSG_CMD_DISCONNECT, NULL, 0, NULL, EMU_REPLY_MS),
             WSG_E_SUCCESS);
    emu_close(&c);

    CHECK_EQ(emu_stop(&a), 0);
    CHECK_EQ(emu_stop(&b), 0);
    /* Exactly one line on stdout: nothing after the ready line. */
    CHECK_EQ(a.extra_len, 0);
    CHECK_EQ(b.extra_len, 0);
    if (a.extra_len)
        fprintf(stderr, "more stdout: \"%s\"\n", a.extra);
}

/* One request, one recv(): the whole reply must be there, exactly. */
static void single_recv(struct emu_client *c, uint8_t id, const uint8_t *p,
                        size_t len, size_t want_params)
{
    uint8_t buf[2048];
    struct wsg_client_frame f;
    REQUIRE(emu_send(c, id, p, len) == 0);
    long n = emu_recv_raw(c, buf, sizeof(buf), EMU_REPLY_MS);
    if (n != (long)(WSG_HEADER_LEN + 2 + want_params + WSG_CRC_LEN))
        fprintf(stderr, "  ID %02Xh, %zu bytes sent: recv() got %ld\n",
                (unsigned)id, len, n);
    CHECK_EQ(n, WSG_HEADER_LEN + 2 + want_params + WSG_CRC_LEN);
    if (n <= 0)
        return;
    CHECK(emu_packet_decode(buf, (size_t)n, &f) == 0);
    CHECK_EQ(f.id, id);
}

static void test_single_recv(struct emu *e)
{
    struct emu_client c;
    uint8_t p[256];
    static const size_t loop_sizes[] = {0, 1, 2, 7, 64, 200, 254, 255, 256};

    for (size_t i = 0; i < sizeof(p); i++)
        p[i] = (uint8_t)(i * 7 + 3);
    REQUIRE(emu_open(&c, e, tp) == 0);
    /* Repeated, since a daemon writing in pieces is caught only when the
     * pieces happen to be read apart. */
    for (int round = 0; round < 20; round++) {
        for (size_t i = 0; i < sizeof(loop_sizes) / sizeof(loop_sizes[0]); i++)
            single_recv(&c, WSG_CMD_LOOP, p, loop_sizes[i], loop_sizes[i]);
        single_recv(&c, WSG_CMD_GET_SYSTEM_STATE, NULL, 0, 4);
        single_recv(&c, WSG_CMD_GET_WIDTH, NULL, 0, 4);
        single_recv(&c, WSG_CMD_GET_SYSTEM_INFO, NULL, 0, 8);
        single_recv(&c, WSG_CMD_GET_SYSTEM_LIMITS, NULL, 0, 32);
        single_recv(&c, 0x90, NULL, 0, 0);
    }
    CHECK_EQ(emu_request(&c, WSG_CMD_DISCONNECT, NULL, 0, NULL, EMU_REPLY_MS),
             tp->connection ? WSG_E_SUCCESS : WSG_E_NOT_AVAILABLE);
    emu_close(&c);
}

/* The 256-byte echo does not fit the core's request parser (its limit is
 * the largest request), so the long echoes are checked from raw reads. */
static void loop_raw(struct emu_client *c, const uint8_t *p, size_t len)
{
    uint8_t buf[1024];
    struct wsg_client_frame f;
    size_t want = WSG_HEADER_LEN + 2 + len + WSG_CRC_LEN, got = 0;
    REQUIRE(emu_send(c, WSG_CMD_LOOP, p, len) == 0);
    while (got < want) {
        long n = emu_recv_raw(c, buf + got, sizeof(buf) - got, EMU_REPLY_MS);
        if (n <= 0)
            break;
        got += (size_t)n;
    }
    CHECK_EQ(got, want);
    REQUIRE(emu_packet_decode(buf, got, &f) == 0);
    CHECK_EQ(f.id, WSG_CMD_LOOP);
    CHECK_EQ(f.status, WSG_E_SUCCESS);
    CHECK_EQ(f.len, 2 + len);
    CHECK(memcmp(EMU_PARAMS(&f), p, len) == 0);
}

static void test_loop(struct emu *e)
{
    struct emu_client c;
    struct wsg_client_frame f;
    uint8_t p[300];
    /* Payloads full of preamble bytes: a parser that hunts for AA AA AA
     * inside a packet instead of counting SIZE loses them. */
    static const uint8_t tricky[] = {0xAA, 0xAA, 0xAA, 0x06, 0x02, 0x00,
                                     0xAA, 0xAA, 0xAA, 0xAA, 0x00, 0x00};

    REQUIRE(emu_open(&c, e, tp) == 0);
    for (size_t i = 0; i < sizeof(p); i++)
        p[i] = (uint8_t)(255 - i);
    static const size_t sizes[] = {0, 1, 3, 100, 253, 254};
    for (size_t i = 0; i < sizeof(sizes) / sizeof(sizes[0]); i++) {
        CHECK_EQ(emu_request(&c, WSG_CMD_LOOP, p, sizes[i], &f, EMU_REPLY_MS),
                 WSG_E_SUCCESS);
        CHECK_EQ(f.len, 2 + sizes[i]);
        CHECK(memcmp(EMU_PARAMS(&f), p, sizes[i]) == 0);
    }
    CHECK_EQ(emu_request(&c, WSG_CMD_LOOP, tricky, sizeof(tricky), &f,
                         EMU_REPLY_MS),
             WSG_E_SUCCESS);
    CHECK_EQ(f.len, 2 + sizeof(tricky));
    CHECK(memcmp(EMU_PARAMS(&f), tricky, sizeof(tricky)) == 0);
    CHECK_EQ(c.link.bad, 0);
    emu_close(&c);

    /* 255 and 256 bytes: the manual's maximum. */
    REQUIRE(emu_open(&c, e, tp) == 0);
    loop_raw(&c, p, 255);
    loop_raw(&c, p, 256);
    emu_close(&c);

    /* 257 bytes: "more than 256 bytes of payload" is E_CMD_FORMAT_ERROR
     * (3.1.1), under the received ID. The payload holds no preamble, so the
     * receiver skips it and finds the next packet. */
    REQUIRE(emu_open(&c, e, tp) == 0);
    memset(p, 0x55, sizeof(p));
    CHECK_EQ(emu_request(&c, WSG_CMD_LOOP, p, 257, &f, EMU_REPLY_MS),
             WSG_E_CMD_FORMAT_ERROR);
    CHECK_EQ(f.len, 2);
    CHECK_EQ(emu_request(&c, WSG_CMD_LOOP, "after", 5, &f, EMU_REPLY_MS),
             WSG_E_SUCCESS);
    CHECK(f.len == 7 && memcmp(EMU_PARAMS(&f), "after", 5) == 0);
    /* Only those two replies came back. */
    CHECK_EQ(c.link.seen[WSG_CMD_LOOP], 2);
    CHECK_EQ(c.link.bad, 0);
    emu_close(&c);
}

/* Send raw bytes, expect exactly the bytes want in reply. */
static void exact_reply(struct emu *e, const uint8_t *req, size_t rlen,
                        const uint8_t *want, size_t wlen)
{
    struct emu_client c;
    uint8_t buf[512];
    size_t got = 0;
    REQUIRE(emu_open(&c, e, tp) == 0);
    REQUIRE(emu_send_raw(&c, req, rlen) == 0);
    while (got < wlen) {
        long n = emu_recv_raw(&c, buf + got, sizeof(buf) - got, EMU_REPLY_MS);
        if (n <= 0)
            break;
        got += (size_t)n;
    }
    /* Anything more would be a second, unexpected packet. */
    long more = emu_recv_raw(&c, buf + got, sizeof(buf) - got, emu_ms(100));
    if (more > 0)
        got += (size_t)more;
    CHECK_EQ(got, wlen);
    CHECK(got == wlen && memcmp(buf, want, wlen) == 0);
    if (got != wlen || memcmp(buf, want, wlen) != 0) {
        fprintf(stderr, "  got:");
        for (size_t i = 0; i < got; i++)
            fprintf(stderr, " %02X", buf[i]);
        fprintf(stderr, "\n");
    }
    emu_request(&c, WSG_CMD_DISCONNECT, NULL, 0, NULL, EMU_REPLY_MS);
    emu_close(&c);
}

static void test_unknown_id(struct emu *e)
{
    /* Chapter 1.2, example 2, to the byte. */
    static const uint8_t want[] = {0xAA, 0xAA, 0xAA, 0x90, 0x02,
                                   0x00, 0x0E, 0x00, 0xFD, 0x02};
    uint8_t req[64];
    size_t n = wsg_frame_encode(req, sizeof(req), 0x90, NULL, 0);
    REQUIRE(n > 0);
    exact_reply(e, req, n, want, sizeof(want));
    /* With a payload the command is just as unknown. */
    n = wsg_frame_encode(req, sizeof(req), 0x90, (const uint8_t *)"abc", 3);
    REQUIRE(n > 0);
    exact_reply(e, req, n, want, sizeof(want));
}

static void test_checksum(struct emu *e)
{
    struct emu_client c;
    struct wsg_client_frame f;
    uint8_t pkt[64];
    size_t n;

    REQUIRE(emu_open(&c, e, tp) == 0);
    /* The manual's own example packets (1.1) carry valid checksums: ID 01h
     * is no command, so E_CMD_UNKNOWN, not E_CHECKSUM_ERROR. */
    static const uint8_t ex1[] = {0xAA, 0xAA, 0xAA, 0x01,
                                  0x00, 0x00, 0xE8, 0x10};
    static const uint8_t ex2[] = {0xAA, 0xAA, 0xAA, 0x01, 0x02,
                                  0x00, 0x12, 0x34, 0x6D, 0x66};
    REQUIRE(emu_send_raw(&c, ex1, sizeof(ex1)) == 0);
    CHECK_EQ(emu_recv_id(&c, 0x01, &f, EMU_REPLY_MS), 1);
    CHECK_EQ(f.status, WSG_E_CMD_UNKNOWN);
    REQUIRE(emu_send_raw(&c, ex2, sizeof(ex2)) == 0);
    CHECK_EQ(emu_recv_id(&c, 0x01, &f, EMU_REPLY_MS), 1);
    CHECK_EQ(f.status, WSG_E_CMD_UNKNOWN);

    /* A flipped checksum: E_CHECKSUM_ERROR under the received ID, status
     * only (params come only with E_SUCCESS, 1.2). */
    n = wsg_frame_encode(pkt, sizeof(pkt), WSG_CMD_LOOP,
                         (const uint8_t *)"\1\2\3", 3);
    pkt[n - 1] ^= 0x5A;
    REQUIRE(emu_send_raw(&c, pkt, n) == 0);
    CHECK_EQ(emu_recv_id(&c, WSG_CMD_LOOP, &f, EMU_REPLY_MS), 1);
    CHECK_EQ(f.status, WSG_E_CHECKSUM_ERROR);
    CHECK_EQ(f.len, 2);

    /* 00 00 is what a client with CRC off sends: an error when it is on. */
    n = wsg_frame_encode(pkt, sizeof(pkt), WSG_CMD_GET_SYSTEM_STATE, NULL, 0);
    pkt[n - 2] = pkt[n - 1] = 0;
    REQUIRE(emu_send_raw(&c, pkt, n) == 0);
    CHECK_EQ(emu_recv_id(&c, WSG_CMD_GET_SYSTEM_STATE, &f, EMU_REPLY_MS), 1);
    CHECK_EQ(f.status, WSG_E_CHECKSUM_ERROR);
    CHECK_EQ(f.len, 2);

    /* A damaged payload byte, too. */
    n = wsg_frame_encode(pkt, sizeof(pkt), WSG_CMD_LOOP,
                         (const uint8_t *)"\1\2\3", 3);
    pkt[7] ^= 0x01;
    REQUIRE(emu_send_raw(&c, pkt, n) == 0);
    CHECK_EQ(emu_recv_id(&c, WSG_CMD_LOOP, &f, EMU_REPLY_MS), 1);
    CHECK_EQ(f.status, WSG_E_CHECKSUM_ERROR);

    /* The connection goes on. */
    CHECK_EQ(emu_request(&c, WSG_CMD_LOOP, "ok", 2, &f, EMU_REPLY_MS),
             WSG_E_SUCCESS);
    CHECK(f.len == 4 && memcmp(EMU_PARAMS(&f), "ok", 2) == 0);
    CHECK_EQ(c.link.bad, 0);
    emu_request(&c, WSG_CMD_DISCONNECT, NULL, 0, NULL, EMU_REPLY_MS);
    emu_close(&c);
}

static void test_no_crc(const char *exe)
{
    static const char *const args[] = {"--no-crc", NULL};
    struct emu e;
    struct emu_client c;
    struct wsg_client_frame f;
    uint8_t pkt[64];
    size_t n;

    REQUIRE(emu_start_tp(&e, exe, tp, args) == 0);
    REQUIRE(emu_open(&c, &e, tp) == 0);
    /* Checksum 00 00 (the manual's "these bytes are 0"): accepted, and the
     * reply still carries a valid checksum (decode checks it). */
    n = wsg_frame_encode(pkt, sizeof(pkt), WSG_CMD_LOOP,
                         (const uint8_t *)"nocrc", 5);
    pkt[n - 2] = pkt[n - 1] = 0x00;
    REQUIRE(emu_send_raw(&c, pkt, n) == 0);
    CHECK_EQ(emu_recv_id(&c, WSG_CMD_LOOP, &f, EMU_REPLY_MS), 1);
    CHECK_EQ(f.status, WSG_E_SUCCESS);
    CHECK(f.len == 7 && memcmp(EMU_PARAMS(&f), "nocrc", 5) == 0);

    /* FF FF, the other value clients send (NOTES). */
    n = wsg_frame_encode(pkt, sizeof(pkt), WSG_CMD_GET_SYSTEM_STATE, NULL, 0);
    pkt[n - 2] = pkt[n - 1] = 0xFF;
    REQUIRE(emu_send_raw(&c, pkt, n) == 0);
    CHECK_EQ(emu_recv_id(&c, WSG_CMD_GET_SYSTEM_STATE, &f, EMU_REPLY_MS), 1);
    CHECK_EQ(f.len, 2 + 4);
    CHECK_EQ(f.status, WSG_E_SUCCESS);

    /* A valid checksum is fine too; every reply had a valid one. */
    CHECK_EQ(emu_request(&c, WSG_CMD_LOOP, "v", 1, &f, EMU_REPLY_MS),
             WSG_E_SUCCESS);
    CHECK_EQ(c.link.bad, 0);
    emu_request(&c, WSG_CMD_DISCONNECT, NULL, 0, NULL, EMU_REPLY_MS);
    emu_close(&c);
    CHECK_EQ(emu_stop(&e), 0);
}

static void test_signals(const char *exe)
{
    struct emu e;
    struct emu_client c;

    /* SIGTERM with a client connected. */
    REQUIRE(emu_start(&e, exe, tcp_args) == 0);
    REQUIRE(emu_open(&c, &e, &emu_tcp) == 0);
    CHECK_EQ(emu_request(&c, WSG_CMD_LOOP, "t", 1, NULL, EMU_REPLY_MS),
             WSG_E_SUCCESS);
    CHECK_EQ(emu_stop_sig(&e, SIGTERM), 0);
    /* The daemon is gone: the connection ends. */
    struct wsg_client_frame f;
    CHECK_EQ(emu_recv(&c, &f, EMU_REPLY_MS), -1);
    emu_close(&c);

    REQUIRE(emu_start(&e, exe, tcp_args) == 0);
    CHECK_EQ(emu_stop_sig(&e, SIGINT), 0);
}

static void bad_option(const char *exe, const char *const *args)
{
    char out[512], err[512];
    int st =
        emu_run(exe, args, emu_ms(5000), out, sizeof(out), err, sizeof(err));
    printf("%s %s: status %d, stderr \"%s\"\n", args[0],
           args[1] ? args[1] : "", st, err);
    CHECK_EQ(st, 2);
    CHECK(strlen(err) > 0);
    CHECK(strstr(out, "ready") == NULL);
}

/* The options of the contract, all at once, are accepted. */
static void test_good_options(const char *exe)
{
    static const char *const args[] = {
        "--tcp",     "127.0.0.1:0", "--no-crc", "--no-disconnect-fast-stop",
        "--step-us", "2000",        NULL};
    struct emu e;
    struct emu_client c;
    REQUIRE(emu_start(&e, exe, args) == 0);
    CHECK(ready_line_ok(e.line));
    REQUIRE(emu_open(&c, &e, &emu_tcp) == 0);
    CHECK_EQ(emu_request(&c, WSG_CMD_LOOP, "g", 1, NULL, EMU_REPLY_MS),
             WSG_E_SUCCESS);
    emu_close(&c);
    CHECK_EQ(emu_stop(&e), 0);
}

static void test_bad_options(const char *exe)
{
    static const char *const a1[] = {"--bogus", NULL};
    static const char *const a2[] = {"--tcp", "nope", NULL};
    static const char *const a3[] = {"--tcp", NULL};
    static const char *const a4[] = {"--tcp", "127.0.0.1:70000", NULL};
    static const char *const a5[] = {"--step-us", "abc", "--tcp",
                                     "127.0.0.1:0", NULL};
    bad_option(exe, a1);
    bad_option(exe, a2);
    bad_option(exe, a3);
    bad_option(exe, a4);
    bad_option(exe, a5);
}

/* An idle emulator (nothing moving, no stream, one client connected and
 * quiet) must not spin nor wake for model steps: over a second it is
 * scheduled a handful of times at most (a 1 ms step timer would make it
 * about 1000) and uses no CPU time worth a tick. */
static void test_idle(struct emu *e)
{
    struct emu_client c;
    long sw0, sw1, t0, t1;

    REQUIRE(emu_open(&c, e, tp) == 0);
    CHECK_EQ(emu_request(&c, WSG_CMD_GET_WIDTH, NULL, 0, NULL, EMU_REPLY_MS),
             WSG_E_SUCCESS);
    emu_sleep_ms(100);
    REQUIRE(emu_proc_activity(e->pid, &sw0, &t0) == 0);
    emu_sleep_ms(1000);
    REQUIRE(emu_proc_activity(e->pid, &sw1, &t1) == 0);
    CHECK(sw1 - sw0 <= 5);
    CHECK(t1 - t0 <= 2);
    emu_close(&c);
}

int main(int argc, char **argv)
{
    const char *exe = emu_exe(argc, argv);
    struct emu e;

    tp = emu_transport_arg(argc, argv);
    printf("over %s\n", tp->field);
    if (tp == &emu_tcp) { /* the command line and the process, once */
        test_ready_line(exe);
        test_bad_options(exe);
        test_good_options(exe);
        test_signals(exe);
    }

    REQUIRE(emu_start_tp(&e, exe, tp, NULL) == 0);
    /* A reply in one recv(): what drivers on TCP and UDP rely on. A serial
     * line and a CAN bus deliver bytes and frames, not packets. */
    if (tp == &emu_tcp || tp == &emu_udp)
        test_single_recv(&e);
    test_loop(&e);
    test_unknown_id(&e);
    test_checksum(&e);
    test_idle(&e);
    CHECK_EQ(emu_stop(&e), 0);
    test_no_crc(exe);
    TEST_EXIT();
}
