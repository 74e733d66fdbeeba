/*
 * The output queue of the stream transports (src/transport/outq.c) on a
 * socketpair whose sending side is kept small: a packet goes out in one
 * write when the socket takes it; what it does not take waits, in order,
 * with later packets behind it, none ever split among others; a packet
 * that would overflow the 64 KiB bound is refused whole; a flush drains
 * what waits; a peer that is gone is an error, not a signal.
 */
#define _GNU_SOURCE

#include <errno.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <unistd.h>

#include "check.h"
#include "outq.h"

#define PKT 200u

/* Packet i: its number in the first two bytes, then a pattern of it. */
static void make_pkt(uint8_t *p, unsigned i)
{
    unsigned k;

    p[0] = (uint8_t)(i >> 8);
    p[1] = (uint8_t)i;
    for (k = 2; k < PKT; k++)
        p[k] = (uint8_t)(i * 7u + k);
}

/* Read everything the other end has; returns the count. */
static size_t drain(int fd, uint8_t *buf, size_t cap)
{
    size_t got = 0;

    for (;;) {
        ssize_t n = recv(fd, buf + got, cap - got, MSG_DONTWAIT);

        if (n <= 0)
            return got;
        got += (size_t)n;
    }
}

int main(void)
{
    static struct wsg_outq q;
    static uint8_t seen[4 * 65536 + 4096];
    uint8_t p[PKT];
    int sv[2], small = 4096, r, queued = 0;
    unsigned i, sent = 0, refused = 0;
    size_t got = 0, k;

    REQUIRE(socketpair(AF_UNIX, SOCK_STREAM | SOCK_NONBLOCK, 0, sv) == 0);
    REQUIRE(setsockopt(sv[0], SOL_SOCKET, SO_SNDBUF, &small, sizeof small) ==
            0);
    wsg_outq_init(&q, 1);

    /* Nothing waits: a packet goes out whole at once. */
    make_pkt(p, 0);
    CHECK_EQ(wsg_outq_send(&q, sv[0], p, PKT), 0);
    sent = 1;
    got += drain(sv[1], seen + got, sizeof seen - got);
    CHECK_EQ(got, PKT);

    /* Fill the socket, then the queue, until a packet is refused. */
    for (i = 1; i < 2000 && refused == 0; i++) {
        make_pkt(p, i);
        r = wsg_outq_send(&q, sv[0], p, PKT);
        if (r == 1)
            queued = 1;
        if (r == -ENOBUFS) {
            refused = i;
            break;
        }
        CHECK(r == 0 || r == 1);
        /* Once bytes wait, every later packet waits behind them. */
        if (queued)
            CHECK_EQ(r, 1);
        sent++;
    }
    CHECK(queued);
    CHECK(refused > 0);
    CHECK(q.len <= WSG_OUTQ_MAX);
    CHECK(q.len + PKT > WSG_OUTQ_MAX); /* refused only when it had to be */

    /* Drain: flush as the socket takes it, read the other end. */
    for (k = 0; k < 100000 && (q.len > 0 || got < (size_t)sent * PKT); k++) {
        got += drain(sv[1], seen + got, sizeof seen - got);
        r = wsg_outq_flush(&q, sv[0]);
        CHECK(r == 0 || r == 1);
    }
    got += drain(sv[1], seen + got, sizeof seen - got);
    CHECK_EQ(q.len, 0);
    CHECK_EQ(got, (size_t)sent * PKT);
    /* Every packet whole and in order: nothing lost, split or mixed. */
    for (i = 0; i < sent && (size_t)(i + 1) * PKT <= got; i++) {
        make_pkt(p, i);
        if (memcmp(seen + (size_t)i * PKT, p, PKT) != 0) {
            CHECK(!"packet out of order or torn");
            break;
        }
    }
    /* The refused packet was not queued: nothing of it arrived. */
    CHECK_EQ(got % PKT, 0);

    /* Idle again: the next packet goes out at once. */
    make_pkt(p, 9999);
    CHECK_EQ(wsg_outq_send(&q, sv[0], p, PKT), 0);
    CHECK_EQ(drain(sv[1], seen, sizeof seen), PKT);

    /* The peer is gone: an error, and no SIGPIPE (MSG_NOSIGNAL). */
    close(sv[1]);
    r = wsg_outq_send(&q, sv[0], p, PKT);
    CHECK(r == -EPIPE || r == -ECONNRESET);
    close(sv[0]);
    TEST_EXIT();
}
