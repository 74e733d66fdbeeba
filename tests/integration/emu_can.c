/*
 * The CAN client transport of the integration tests, used the way a driver
 * uses a gripper on a CAN bus: a raw SocketCAN socket on the interface the
 * ready line names (can=IFACE:ID) sends every packet as consecutive 8-byte
 * frames on ID, and takes the frames on ID + 1, whose data the shared
 * framing of emu.c reassembles by the SIZE field.
 *
 * The daemon is started on $WSG_TEST_CAN_IFACE (default vcan0) with an
 * identifier derived from the test's process ID ($WSG_TEST_CAN_ID to pin
 * it), so two test processes on one bus do not answer each other's
 * frames. Where the kernel has no SocketCAN or the interface is missing the
 * test skips (77): tests/can/run.sh is what runs these tests for real, on
 * a native vcan or in a VM.
 */
#define _GNU_SOURCE

#include "emu_can.h"

#include <errno.h>
#include <linux/can.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <poll.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <unistd.h>

#define EMU_CAN_DEFAULT_IFACE "vcan0"

/* ---- raw frames ---- */

const char *emu_can_iface(void)
{
    const char *iface = getenv("WSG_TEST_CAN_IFACE");

    return iface && iface[0] ? iface : EMU_CAN_DEFAULT_IFACE;
}

int emu_can_available(const char *iface)
{
    int fd = socket(PF_CAN, SOCK_RAW | SOCK_CLOEXEC, CAN_RAW);

    if (fd < 0) {
        printf("SKIP: no SocketCAN in this kernel (%s); tests/can/run.sh "
               "runs the CAN tests in a VM\n",
               strerror(errno));
        return 77;
    }
    close(fd);
    if (if_nametoindex(iface) == 0) {
        printf("SKIP: no CAN interface %s (ip link add dev %s type vcan && "
               "ip link set up %s; or tests/can/run.sh)\n",
               iface, iface, iface);
        return 77;
    }
    return 0;
}

int emu_can_socket(const char *iface, int rx_id)
{
    struct sockaddr_can sa;
    struct can_filter filter;
    int big = 1 << 20;
    int fd = socket(PF_CAN, SOCK_RAW | SOCK_CLOEXEC, CAN_RAW);

    if (fd < 0) {
        fprintf(stderr, "emu: can socket: %s\n", strerror(errno));
        return -1;
    }
    /* A test reads a burst of answers after sending all its requests: room
     * for more than the default's 250-odd frames where the kernel lets us
     * (FORCE needs root, plain is capped at rmem_max). */
    if (setsockopt(fd, SOL_SOCKET, SO_RCVBUFFORCE, &big, sizeof big) < 0)
        setsockopt(fd, SOL_SOCKET, SO_RCVBUF, &big, sizeof big);
    /* Standard data frames on rx_id only: a test that sends on the
     * command ID must not read its own traffic or another test's. */
    if (rx_id == EMU_CAN_RX_ALL) {
        /* the default filter: everything */
    } else if (rx_id >= 0) {
        filter.can_id = (canid_t)rx_id;
        filter.can_mask = CAN_SFF_MASK | CAN_EFF_FLAG | CAN_RTR_FLAG;
        if (setsockopt(fd, SOL_CAN_RAW, CAN_RAW_FILTER, &filter,
                       sizeof filter) < 0)
            goto fail;
    } else if (setsockopt(fd, SOL_CAN_RAW, CAN_RAW_FILTER, NULL, 0) < 0) {
        goto fail;
    }
    memset(&sa, 0, sizeof sa);
    sa.can_family = AF_CAN;
    sa.can_ifindex = (int)if_nametoindex(iface);
    if (sa.can_ifindex == 0 || bind(fd, (struct sockaddr *)&sa, sizeof sa) < 0)
        goto fail;
    return fd;

fail:
    fprintf(stderr, "emu: can %s: %s\n", iface, strerror(errno));
    close(fd);
    return -1;
}

int emu_can_send_frame(int fd, uint32_t id, const void *data, size_t len)
{
    double deadline = emu_now_ms() + EMU_REPLY_MS;
    struct can_frame f;

    if (len > 8)
        return -1;
    memset(&f, 0, sizeof f);
    f.can_id = id;
    f.can_dlc = (uint8_t)len;
    if (len)
        memcpy(f.data, data, len);
    for (;;) {
        ssize_t n = write(fd, &f, sizeof f);

        if (n == (ssize_t)sizeof f)
            return 0;
        if (n < 0 && errno == EINTR)
            continue;
        /* The interface's queue is full: it drains on its own. */
        if (n < 0 && (errno == ENOBUFS || errno == EAGAIN) &&
            emu_now_ms() < deadline) {
            emu_sleep_ms(1);
            continue;
        }
        fprintf(stderr, "emu: can write: %s\n",
                n < 0 ? strerror(errno) : "short write");
        return -1;
    }
}

int emu_can_send_packet(int fd, uint32_t id, const uint8_t *pkt, size_t len)
{
    size_t off;

    for (off = 0; off < len; off += 8)
        if (emu_can_send_frame(fd, id, pkt + off,
                               len - off < 8 ? len - off : 8) != 0)
            return -1;
    return 0;
}

int emu_can_recv_frame(int fd, struct emu_can_frame *f, int timeout_ms)
{
    double deadline = emu_now_ms() + timeout_ms;

    for (;;) {
        double left = deadline - emu_now_ms();
        struct pollfd pfd = {fd, POLLIN, 0};
        struct can_frame cf;
        ssize_t n;
        int r = poll(&pfd, 1, left > 0 ? (int)(left + 0.999) : 0);

        if (r < 0 && errno == EINTR)
            continue;
        if (r < 0)
            return -1;
        if (r == 0)
            return 0;
        n = read(fd, &cf, sizeof cf);
        if (n < 0 && errno == EINTR)
            continue;
        if (n != (ssize_t)sizeof cf)
            return -1;
        f->id = cf.can_id;
        f->len = cf.can_dlc > 8 ? 8 : cf.can_dlc;
        memcpy(f->data, cf.data, 8);
        return 1;
    }
}

/* ---- the client transport ---- */

/* 0x100..0x6FF from the process ID, or $WSG_TEST_CAN_ID. */
static unsigned test_can_id(void)
{
    const char *s = getenv("WSG_TEST_CAN_ID");
    char *end;
    unsigned long v;

    if (s && s[0]) {
        v = strtoul(s, &end, 0);
        if (*end == '\0' && v <= 0x7FE)
            return (unsigned)v;
        fprintf(stderr, "emu: ignoring WSG_TEST_CAN_ID=%s (not 0..0x7FE)\n",
                s);
    }
    return 0x100u + (unsigned)getpid() % 0x600u;
}

static int can_daemon_args(struct emu *e)
{
    const char *iface = emu_can_iface();
    int r = emu_can_available(iface);

    if (r != 0)
        return r;
    snprintf(e->tp_arg[0], sizeof e->tp_arg[0], "%s:0x%03X", iface,
             test_can_id());
    e->tp_argv[0] = "--can";
    e->tp_argv[1] = e->tp_arg[0];
    e->tp_argv[2] = NULL;
    return 0;
}

/* addr: "IFACE:0xID" from the ready line. */
static int can_open(struct emu_client *c, const char *addr)
{
    char iface[IFNAMSIZ];
    const char *colon = strrchr(addr, ':');
    unsigned long id;
    char *end;

    if (!colon || colon == addr || (size_t)(colon - addr) >= sizeof iface) {
        fprintf(stderr, "emu: bad can field \"%s\"\n", addr);
        return -1;
    }
    id = strtoul(colon + 1, &end, 16);
    if (strncmp(colon + 1, "0x", 2) != 0 || *end != '\0' || id > 0x7FE) {
        fprintf(stderr, "emu: bad can ID in \"%s\"\n", addr);
        return -1;
    }
    memcpy(iface, addr, (size_t)(colon - addr));
    iface[colon - addr] = '\0';
    c->fd = emu_can_socket(iface, (int)id + 1);
    if (c->fd < 0)
        return -1;
    c->tp_id = (uint32_t)id;
    return 0;
}

static int can_send(struct emu_client *c, const uint8_t *pkt, size_t len)
{
    return emu_can_send_packet(c->fd, c->tp_id, pkt, len);
}

/* The data of the answer frames that are there, in order: at least one
 * frame's, waiting up to timeout_ms for it. */
static long can_recv(struct emu_client *c, uint8_t *buf, size_t cap,
                     int timeout_ms)
{
    struct emu_can_frame f;
    size_t n = 0;
    int r = emu_can_recv_frame(c->fd, &f, timeout_ms);

    if (r <= 0)
        return r == 0 ? -1 : -2;
    for (;;) {
        /* The filter passes standard data frames on ID + 1 only. */
        if (f.len > cap - n)
            return -2; /* cap is always a multiple of a frame's 8 */
        memcpy(buf + n, f.data, f.len);
        n += f.len;
        if (cap - n < 8)
            break;
        r = emu_can_recv_frame(c->fd, &f, 0);
        if (r < 0)
            return -2;
        if (r == 0)
            break;
    }
    return (long)n;
}

static void can_close(struct emu_client *c, int abort)
{
    (void)abort; /* a bus has nothing to reset */
    close(c->fd);
}

const struct emu_transport emu_can = {
    .field = "can",
    .open = can_open,
    .send = can_send,
    .recv = can_recv,
    .close = can_close,
    .daemon_args = can_daemon_args,
    .connection = 0,
    .single_peer = 1,
};
