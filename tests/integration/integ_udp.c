/*
 * integ_udp: what is particular to the UDP interface.
 *
 * - answers go to the sender's IP address at the remote port the daemon
 *   was given, not to the datagram's source port;
 * - one packet per datagram: a datagram holding several packets gets each
 *   one answered; a datagram with half a packet is answered
 *   E_CMD_FORMAT_ERROR under its ID (or dropped when even the ID is
 *   missing) and never joined with the next datagram;
 * - the ready line reads udp=ADDR:PORT>REMOTE; the defaults are
 *   127.0.0.1:1500>1501 next to TCP when no interface is named;
 * - with REMOTE "source" (opt-in) answers go to the datagram's source
 *   port: a socket that sends and receives on one port gets them, final
 *   results and streams included, and when the same address sends from
 *   another port, they follow it there. The ready line reads >source.
 */
#define _GNU_SOURCE

#include "check.h"
#include "emu.h"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <unistd.h>

/* Bytes straight into one datagram from the client's sending socket. */
static void datagram(struct emu_client *c, const uint8_t *p, size_t n)
{
    REQUIRE(send(c->fd2, p, n, 0) == (ssize_t)n);
}

static void test_reply_port(struct emu *e)
{
    struct emu_client c;
    struct pollfd pfd;
    uint8_t buf[64];

    REQUIRE(emu_open(&c, e, &emu_udp) == 0);
    CHECK_EQ(emu_request(&c, WSG_CMD_LOOP, "port", 4, NULL, EMU_REPLY_MS),
             WSG_E_SUCCESS);
    /* Nothing came back to the source port. */
    pfd.fd = c.fd2;
    pfd.events = POLLIN;
    CHECK_EQ(poll(&pfd, 1, EMU_QUIET_MS), 0);
    CHECK_EQ(recv(c.fd2, buf, sizeof buf, MSG_DONTWAIT), -1);
    emu_close(&c);
}

static void test_datagrams(struct emu *e)
{
    struct emu_client c;
    struct wsg_client_frame f;
    uint8_t dg[256];
    size_t n, m;

    REQUIRE(emu_open(&c, e, &emu_udp) == 0);

    /* Three packets in one datagram: three answers, in order. */
    n = wsg_frame_encode(dg, sizeof dg, WSG_CMD_LOOP, (const uint8_t *)"one",
                         3);
    n += wsg_frame_encode(dg + n, sizeof dg - n, WSG_CMD_GET_WIDTH, NULL, 0);
    n += wsg_frame_encode(dg + n, sizeof dg - n, WSG_CMD_LOOP,
                          (const uint8_t *)"three", 5);
    datagram(&c, dg, n);
    CHECK_EQ(emu_recv(&c, &f, EMU_REPLY_MS), 1);
    CHECK(f.id == WSG_CMD_LOOP && f.len == 5 &&
          memcmp(EMU_PARAMS(&f), "one", 3) == 0);
    CHECK_EQ(emu_recv(&c, &f, EMU_REPLY_MS), 1);
    CHECK(f.id == WSG_CMD_GET_WIDTH && f.status == WSG_E_SUCCESS);
    CHECK_EQ(emu_recv(&c, &f, EMU_REPLY_MS), 1);
    CHECK(f.id == WSG_CMD_LOOP && f.len == 7 &&
          memcmp(EMU_PARAMS(&f), "three", 5) == 0);

    /* Half a packet, then its other half in the next datagram: the first
     * is answered E_CMD_FORMAT_ERROR under its ID, the second (no
     * preamble of its own) is not taken as the rest of it. */
    n = wsg_frame_encode(dg, sizeof dg, WSG_CMD_LOOP, (const uint8_t *)"split",
                         5);
    m = n / 2;
    datagram(&c, dg, m);
    datagram(&c, dg + m, n - m);
    CHECK_EQ(emu_recv(&c, &f, EMU_REPLY_MS), 1);
    CHECK_EQ(f.id, WSG_CMD_LOOP);
    CHECK_EQ(f.status, WSG_E_CMD_FORMAT_ERROR);
    CHECK_EQ(f.len, 2);
    /* A preamble alone, without even an ID: dropped in silence. */
    datagram(&c, dg, 3);
    /* Nothing else came of those; the next packet is answered as usual. */
    REQUIRE(emu_sync(&c, EMU_REPLY_MS) == 0);
    CHECK_EQ(c.link.seen[WSG_CMD_LOOP],
             4); /* one, three, split's error, sync */
    /* A complete packet after a cut one in the same datagram: the cut one
     * swallows what follows it (SIZE says so), so one answer: its error. */
    n = wsg_frame_encode(dg, sizeof dg, WSG_CMD_GET_SPEED, NULL, 0);
    dg[4] = 40; /* SIZE 40: the datagram ends first */
    n += wsg_frame_encode(dg + n, sizeof dg - n, WSG_CMD_LOOP,
                          (const uint8_t *)"x", 1);
    datagram(&c, dg, n);
    CHECK_EQ(emu_recv(&c, &f, EMU_REPLY_MS), 1);
    CHECK_EQ(f.id, WSG_CMD_GET_SPEED);
    CHECK_EQ(f.status, WSG_E_CMD_FORMAT_ERROR);
    REQUIRE(emu_sync(&c, EMU_REPLY_MS) == 0);
    CHECK_EQ(c.link.seen[WSG_CMD_GET_SPEED], 1);
    CHECK_EQ(c.link.bad, 0);
    emu_close(&c);
}

/* A socket on an ephemeral port, connected to the daemon's: it sends and
 * receives on the same port, as socat's UDP: and nc -u do. */
static int source_socket(uint16_t port)
{
    struct sockaddr_in sa;
    int fd = socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);

    REQUIRE(fd >= 0);
    memset(&sa, 0, sizeof sa);
    sa.sin_family = AF_INET;
    sa.sin_port = htons(port);
    sa.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    REQUIRE(connect(fd, (struct sockaddr *)&sa, sizeof sa) == 0);
    return fd;
}

/* One packet out, the next datagram in: its ID and status, -1 on none. */
static int exchange(int fd, uint8_t id, const void *payload, size_t len,
                    int timeout_ms, uint16_t *status)
{
    uint8_t pkt[64], buf[256];
    struct pollfd pfd = {fd, POLLIN, 0};
    size_t n = wsg_frame_encode(pkt, sizeof pkt, id, payload, len);
    ssize_t r;

    if (n && send(fd, pkt, n, 0) != (ssize_t)n)
        return -1;
    if (poll(&pfd, 1, timeout_ms) != 1)
        return -1;
    r = recv(fd, buf, sizeof buf, 0);
    if (r < 8)
        return -1;
    *status = (uint16_t)(buf[6] | buf[7] << 8);
    return buf[3];
}

static void test_source(const char *exe)
{
    static const char *const args[] = {"--udp", "127.0.0.1:0:source", NULL};
    struct emu e;
    char v[64], *gt;
    uint16_t port, st = 0;
    uint8_t home = 0, auto_width[3] = {0x01, 100, 0}; /* every 100 ms */
    int a, b, id;

    REQUIRE(emu_start(&e, exe, args) == 0);
    REQUIRE(emu_field(&e, "udp", v, sizeof v));
    gt = strchr(v, '>');
    REQUIRE(gt != NULL);
    CHECK(strcmp(gt, ">source") == 0);
    *gt = '\0';
    port = (uint16_t)atoi(strrchr(v, ':') + 1);

    a = source_socket(port);
    CHECK_EQ(exchange(a, WSG_CMD_LOOP, "src", 3, EMU_REPLY_MS, &st),
             WSG_CMD_LOOP);
    CHECK_EQ(st, WSG_E_SUCCESS);
    /* A motion's final result comes to the same port. */
    CHECK_EQ(exchange(a, WSG_CMD_HOMING, &home, 1, EMU_REPLY_MS, &st),
             WSG_CMD_HOMING);
    CHECK_EQ(st, WSG_E_CMD_PENDING);
    {
        struct pollfd pfd = {a, POLLIN, 0};
        uint8_t buf[64];

        CHECK_EQ(poll(&pfd, 1, EMU_HOMING_MS), 1);
        CHECK(recv(a, buf, sizeof buf, 0) >= 8 && buf[3] == WSG_CMD_HOMING &&
              buf[6] == 0 && buf[7] == 0);
    }
    /* The same address from another port: answers and its stream follow
     * it there, none go to the old port any more. */
    b = source_socket(port);
    id = exchange(b, WSG_CMD_GET_WIDTH, auto_width, 3, EMU_REPLY_MS, &st);
    CHECK_EQ(id, WSG_CMD_GET_WIDTH);
    {
        struct pollfd pfd = {b, POLLIN, 0};
        uint8_t buf[64];

        /* Two stream packets, at 100 ms each, within a generous bound. */
        CHECK_EQ(poll(&pfd, 1, EMU_REPLY_MS), 1);
        CHECK(recv(b, buf, sizeof buf, 0) >= 8 && buf[3] == WSG_CMD_GET_WIDTH);
        CHECK_EQ(poll(&pfd, 1, EMU_REPLY_MS), 1);
        CHECK(recv(b, buf, sizeof buf, 0) >= 8 && buf[3] == WSG_CMD_GET_WIDTH);
        pfd.fd = a;
        CHECK_EQ(poll(&pfd, 1, 0), 0);
    }
    close(a);
    close(b);
    CHECK_EQ(emu_stop(&e), 0);
}

static void test_defaults(const char *exe)
{
    static const char *const none[] = {NULL};
    struct emu e;

    /* Port 1000 needs root: only where the test runs as root. */
    if (geteuid() != 0) {
        printf("not root: default ports not checked\n");
        return;
    }
    if (emu_start(&e, exe, none) != 0) {
        printf("default ports busy: not checked\n");
        return;
    }
    CHECK(strcmp(e.line, "ready tcp=127.0.0.1:1000 udp=127.0.0.1:1500>1501") ==
          0);
    CHECK_EQ(emu_stop(&e), 0);
}

int main(int argc, char **argv)
{
    const char *exe = emu_exe(argc, argv);
    char v[64];
    struct emu e;

    REQUIRE(emu_start_tp(&e, exe, &emu_udp, NULL) == 0);
    REQUIRE(emu_field(&e, "udp", v, sizeof v));
    CHECK(strstr(v, "127.0.0.1:") == v && strchr(v, '>'));
    CHECK(emu_field(&e, "tcp", v, sizeof v) == NULL); /* only what's asked */
    test_reply_port(&e);
    test_datagrams(&e);
    CHECK_EQ(emu_stop(&e), 0);
    test_source(exe);
    test_defaults(exe);
    TEST_EXIT();
}
