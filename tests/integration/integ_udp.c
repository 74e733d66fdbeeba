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
 *   127.0.0.1:1500>1501 next to TCP when no interface is named.
 */
#define _GNU_SOURCE

#include "check.h"
#include "emu.h"

#include <poll.h>
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
    test_defaults(exe);
    TEST_EXIT();
}
