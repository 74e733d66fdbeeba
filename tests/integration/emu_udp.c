/*
 * The UDP client transport of the integration tests, set up the way drivers
 * use a real gripper's UDP interface: requests leave from an ephemeral
 * port, replies arrive on a separate socket bound to the port the gripper
 * answers to (its "remote port", 1501 on a real gripper).
 *
 * The gripper answers at the sender's IP address, so clients that must be
 * told apart (several clients of one test) each use their own loopback
 * address: the first 127.0.0.1, the next 127.0.0.2, and so on, all with the
 * same reply port, which the daemon is started with.
 */
#define _GNU_SOURCE

#include <arpa/inet.h>
#include <errno.h>
#include <netinet/in.h>
#include <poll.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <unistd.h>

#include "emu.h"

static int udp_socket(uint32_t ip, uint16_t port)
{
    struct sockaddr_in sa;
    int fd = socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);

    if (fd < 0)
        return -1;
    memset(&sa, 0, sizeof sa);
    sa.sin_family = AF_INET;
    sa.sin_addr.s_addr = htonl(ip);
    sa.sin_port = htons(port);
    if (bind(fd, (struct sockaddr *)&sa, sizeof sa) < 0) {
        fprintf(stderr, "emu: udp bind %s:%u: %s\n", inet_ntoa(sa.sin_addr),
                (unsigned)port, strerror(errno));
        close(fd);
        return -1;
    }
    return fd;
}

/* Reserve the reply port on 127.0.0.1 and start the daemon answering to
 * it. The reserved socket becomes the first client's receive socket. */
static int udp_daemon_args(struct emu *e)
{
    struct sockaddr_in sa;
    socklen_t len = sizeof sa;

    e->tp_fd = udp_socket(INADDR_LOOPBACK, 0);
    if (e->tp_fd < 0 ||
        getsockname(e->tp_fd, (struct sockaddr *)&sa, &len) < 0)
        return -1;
    e->tp_port = ntohs(sa.sin_port);
    snprintf(e->tp_arg[0], sizeof e->tp_arg[0], "127.0.0.1:0:%u",
             (unsigned)e->tp_port);
    e->tp_argv[0] = "--udp";
    e->tp_argv[1] = e->tp_arg[0];
    e->tp_argv[2] = NULL;
    return 0;
}

/* addr: "ADDR:PORT>REMOTE" from the ready line. */
static int udp_open(struct emu_client *c, const char *addr)
{
    struct emu *e = c->emu;
    char host[64];
    const char *colon = strchr(addr, ':');
    struct sockaddr_in to;
    uint32_t ip = INADDR_LOOPBACK + e->tp_clients;
    unsigned port, remote;

    if (!colon || (size_t)(colon - addr) >= sizeof host ||
        sscanf(colon + 1, "%u>%u", &port, &remote) != 2) {
        fprintf(stderr, "emu: bad udp field \"%s\"\n", addr);
        return -1;
    }
    memcpy(host, addr, (size_t)(colon - addr));
    host[colon - addr] = '\0';
    memset(&to, 0, sizeof to);
    to.sin_family = AF_INET;
    to.sin_port = htons((uint16_t)port);
    if (inet_pton(AF_INET, host, &to.sin_addr) != 1 || remote != e->tp_port) {
        fprintf(stderr, "emu: udp field \"%s\" is not what was asked for\n",
                addr);
        return -1;
    }
    if (e->tp_clients == 0 && e->tp_fd >= 0) {
        c->fd = e->tp_fd; /* the reserved reply socket */
        e->tp_fd = -1;
    } else {
        c->fd = udp_socket(ip, e->tp_port);
    }
    e->tp_clients++;
    if (c->fd < 0)
        return -1;
    c->fd2 = udp_socket(ip, 0);
    if (c->fd2 < 0 || connect(c->fd2, (struct sockaddr *)&to, sizeof to) < 0) {
        close(c->fd);
        c->fd = -1;
        return -1;
    }
    return 0;
}

static int udp_send(struct emu_client *c, const uint8_t *pkt, size_t len)
{
    /* One packet, one datagram. */
    return send(c->fd2, pkt, len, 0) == (ssize_t)len ? 0 : -1;
}

static long udp_recv(struct emu_client *c, uint8_t *buf, size_t cap,
                     int timeout_ms)
{
    struct pollfd pfd = {c->fd, POLLIN, 0};
    ssize_t n;
    int r;

    do
        r = poll(&pfd, 1, timeout_ms);
    while (r < 0 && errno == EINTR);
    if (r < 0)
        return -2;
    if (r == 0)
        return -1;
    n = recv(c->fd, buf, cap, 0);
    return n < 0 ? -2 : (long)n;
}

static void udp_close(struct emu_client *c, int abort)
{
    (void)abort; /* no connection to reset */
    close(c->fd);
    if (c->fd2 >= 0)
        close(c->fd2);
    c->fd2 = -1;
}

const struct emu_transport emu_udp = {
    .field = "udp",
    .open = udp_open,
    .send = udp_send,
    .recv = udp_recv,
    .close = udp_close,
    .daemon_args = udp_daemon_args,
};
