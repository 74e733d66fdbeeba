/*
 * The capture as pcapng (capture.h says what it records and why): a
 * Section Header Block, three Interface Description Blocks, then an
 * Enhanced Packet Block per record, all little-endian. TCP and UDP
 * records are made IPv4 packets here: the headers are built on the stack
 * around the bytes the transport saw, so that Wireshark's own TCP
 * reassembly and conversations work on them as on a real capture.
 */
#define _GNU_SOURCE

#include "capture.h"

#include <errno.h>
#include <fcntl.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "wsg/axis.h"

#define LINKTYPE_IPV4          228u
#define LINKTYPE_USER0         147u
#define LINKTYPE_CAN_SOCKETCAN 227u

enum { IF_IP, IF_PTY, IF_CAN };

/* TCP flags. */
#define TH_FIN 0x01u
#define TH_SYN 0x02u
#define TH_PSH 0x08u
#define TH_ACK 0x10u

/* The most payload one IPv4 record carries; longer data is cut into
 * several (a transport never hands over that much at once today). */
#define SEG_MAX 65000u

static void put16(uint8_t *p, uint16_t v)
{
    p[0] = (uint8_t)v;
    p[1] = (uint8_t)(v >> 8);
}

static void put32(uint8_t *p, uint32_t v)
{
    put16(p, (uint16_t)v);
    put16(p + 2, (uint16_t)(v >> 16));
}

static void be16(uint8_t *p, uint16_t v)
{
    p[0] = (uint8_t)(v >> 8);
    p[1] = (uint8_t)v;
}

static void be32(uint8_t *p, uint32_t v)
{
    be16(p, (uint16_t)(v >> 16));
    be16(p + 2, (uint16_t)v);
}

static size_t pad4(size_t n)
{
    return (4 - (n & 3u)) & 3u;
}

static void out(struct wsg_capture *c, const void *p, size_t n)
{
    if (n && fwrite(p, 1, n, c->f) != n)
        c->full = c->full ? c->full : 2;
    c->size += n;
}

static void out_pad(struct wsg_capture *c, size_t n)
{
    static const uint8_t zero[4];

    out(c, zero, pad4(n));
}

/* An option: code, length, value, padding. */
static void opt(struct wsg_capture *c, uint16_t code, const void *v, size_t n)
{
    uint8_t h[4];

    put16(h, code);
    put16(h + 2, (uint16_t)n);
    out(c, h, 4);
    out(c, v, n);
    out_pad(c, n);
}

static size_t opt_size(size_t n)
{
    return 4 + n + pad4(n);
}

static void block_head(struct wsg_capture *c, uint32_t type, uint32_t len)
{
    uint8_t h[8];

    put32(h, type);
    put32(h + 4, len);
    out(c, h, 8);
}

static void block_tail(struct wsg_capture *c, uint32_t len)
{
    uint8_t h[4];

    put32(h, len);
    out(c, h, 4);
}

static void write_shb(struct wsg_capture *c)
{
    static const char app[] = "wsgemu " WSG_VERSION;
    uint32_t len = 28 + (uint32_t)opt_size(sizeof app - 1) + 4;
    uint8_t b[16];

    block_head(c, 0x0A0D0D0Au, len);
    put32(b, 0x1A2B3C4Du); /* byte-order magic */
    put16(b + 4, 1);       /* version 1.0 */
    put16(b + 6, 0);
    memset(b + 8, 0xFF, 8); /* section length: not given */
    out(c, b, 16);
    opt(c, 4, app, sizeof app - 1); /* shb_userappl */
    opt(c, 0, NULL, 0);
    block_tail(c, len);
}

static void write_idb(struct wsg_capture *c, uint16_t linktype,
                      const char *name, const char *descr)
{
    size_t nl = strlen(name), dl = strlen(descr);
    uint32_t len = 20 + (uint32_t)(opt_size(nl) + opt_size(dl)) + 4;
    uint8_t b[8];

    block_head(c, 1, len);
    put16(b, linktype);
    put16(b + 2, 0);
    put32(b + 4, 0); /* snaplen: none */
    out(c, b, 8);
    opt(c, 2, name, nl);  /* if_name */
    opt(c, 3, descr, dl); /* if_description */
    opt(c, 0, NULL, 0);
    block_tail(c, len);
}

/* One Enhanced Packet Block: head (a made-up header, hlen bytes) and
 * data, inbound or outbound, with the simulated time as its comment. */
static void write_epb(struct wsg_capture *c, uint32_t ifid, int inbound,
                      const uint8_t *head, size_t hlen, const uint8_t *data,
                      size_t len, const char *comment)
{
    size_t caplen = hlen + len, cl = strlen(comment);
    uint32_t blen = (uint32_t)(32 + caplen + pad4(caplen) + opt_size(4) +
                               opt_size(cl) + 4);
    struct timespec ts;
    uint64_t us;
    uint8_t b[20], flags[4];

    if (c->full)
        return;
    if (c->max && c->size + blen > c->max) {
        fprintf(stderr,
                "wsgemu: capture %s: reached --capture-max (%llu bytes); "
                "capture stopped\n",
                c->path, (unsigned long long)c->max);
        c->full = 1;
        return;
    }
    clock_gettime(CLOCK_REALTIME, &ts);
    us = (uint64_t)ts.tv_sec * 1000000u + (uint64_t)ts.tv_nsec / 1000u;
    block_head(c, 6, blen);
    put32(b, ifid);
    put32(b + 4, (uint32_t)(us >> 32));
    put32(b + 8, (uint32_t)us);
    put32(b + 12, (uint32_t)caplen);
    put32(b + 16, (uint32_t)caplen);
    out(c, b, 20);
    out(c, head, hlen);
    out(c, data, len);
    out_pad(c, caplen);
    put32(flags, inbound ? 1u : 2u); /* epb_flags: the direction */
    opt(c, 2, flags, 4);
    opt(c, 1, comment, cl); /* opt_comment */
    opt(c, 0, NULL, 0);
    block_tail(c, blen);
    c->records++;
}

static uint16_t ip_checksum(const uint8_t *h, size_t n)
{
    uint32_t sum = 0;
    size_t i;

    for (i = 0; i + 1 < n; i += 2)
        sum += (uint32_t)(h[i] << 8 | h[i + 1]);
    while (sum >> 16)
        sum = (sum & 0xFFFFu) + (sum >> 16);
    return (uint16_t)~sum;
}

/* An IPv4 packet from the peer (inbound) or to it, TCP (flags, seq, ack)
 * or UDP, around data. */
static void write_ip(struct wsg_capture *c, const struct wsg_tap_flow *f,
                     int inbound, unsigned th, uint32_t seq, uint32_t ack,
                     const uint8_t *data, size_t len, const char *comment)
{
    uint8_t h[40];
    size_t l4 = f->kind == WSG_TAP_TCP ? 20 : 8;
    const uint8_t *src = inbound ? f->peer_ip : f->local_ip;
    const uint8_t *dst = inbound ? f->local_ip : f->peer_ip;
    uint16_t sport = inbound ? f->peer_port : f->local_port;
    uint16_t dport = inbound ? f->local_port : f->peer_port;

    memset(h, 0, sizeof h);
    h[0] = 0x45;
    be16(h + 2, (uint16_t)(20 + l4 + len));
    be16(h + 4, c->ip_id++);
    be16(h + 6, 0x4000); /* don't fragment */
    h[8] = 64;
    h[9] = f->kind == WSG_TAP_TCP ? 6 : 17;
    memcpy(h + 12, src, 4);
    memcpy(h + 16, dst, 4);
    be16(h + 10, ip_checksum(h, 20));
    be16(h + 20, sport);
    be16(h + 22, dport);
    if (f->kind == WSG_TAP_TCP) {
        be32(h + 24, seq);
        be32(h + 28, ack);
        h[32] = 5 << 4;
        h[33] = (uint8_t)th;
        be16(h + 34, 65535);
        /* Checksum 0: Wireshark does not check it unless asked. */
    } else {
        be16(h + 24, (uint16_t)(8 + len));
    }
    write_epb(c, IF_IP, inbound, h, 20 + l4, data, len, comment);
}

void wsg_capture_record(struct wsg_capture *c, const struct wsg_tap_flow *fl,
                        enum wsg_tap_event ev, const uint8_t *data, size_t len,
                        uint64_t sim_us, int index)
{
    /* The tap's counters live in the transport's flow. */
    struct wsg_tap_flow *f = (struct wsg_tap_flow *)(uintptr_t)fl;
    char comment[48];
    int inbound = ev == WSG_TAP_IN;

    if (!c->on || c->full)
        return;
    if (index >= 0)
        snprintf(comment, sizeof comment, "#%d t=%llu.%06u", index,
                 (unsigned long long)(sim_us / 1000000u),
                 (unsigned)(sim_us % 1000000u));
    else
        snprintf(comment, sizeof comment, "t=%llu.%06u",
                 (unsigned long long)(sim_us / 1000000u),
                 (unsigned)(sim_us % 1000000u));
    switch (f->kind) {
    case WSG_TAP_TCP:
        if (ev == WSG_TAP_OPEN) {
            /* The handshake, both sides starting at 0. */
            write_ip(c, f, 1, TH_SYN, 0, 0, NULL, 0, comment);
            write_ip(c, f, 0, TH_SYN | TH_ACK, 0, 1, NULL, 0, comment);
            write_ip(c, f, 1, TH_ACK, 1, 1, NULL, 0, comment);
            f->tap_seq[0] = f->tap_seq[1] = 1;
        } else if (ev == WSG_TAP_CLOSE) {
            write_ip(c, f, 1, TH_FIN | TH_ACK, f->tap_seq[0], f->tap_seq[1],
                     NULL, 0, comment);
            write_ip(c, f, 0, TH_FIN | TH_ACK, f->tap_seq[1],
                     f->tap_seq[0] + 1, NULL, 0, comment);
            f->tap_seq[0]++;
            f->tap_seq[1]++;
        } else {
            while (len > 0) {
                size_t n = len < SEG_MAX ? len : SEG_MAX;
                uint32_t *mine = &f->tap_seq[inbound ? 0 : 1];
                uint32_t theirs = f->tap_seq[inbound ? 1 : 0];

                write_ip(c, f, inbound, TH_PSH | TH_ACK, *mine, theirs, data,
                         n, comment);
                *mine += (uint32_t)n;
                data += n;
                len -= n;
            }
        }
        break;
    case WSG_TAP_UDP:
        if (ev == WSG_TAP_IN || ev == WSG_TAP_OUT)
            write_ip(c, f, inbound, 0, 0, 0, data,
                     len < SEG_MAX ? len : SEG_MAX, comment);
        break;
    case WSG_TAP_PTY:
        if (ev == WSG_TAP_IN || ev == WSG_TAP_OUT)
            write_epb(c, IF_PTY, inbound, NULL, 0, data,
                      len < SEG_MAX ? len : SEG_MAX, comment);
        break;
    case WSG_TAP_CAN: {
        /* LINKTYPE_CAN_SOCKETCAN: the ID big-endian, the length, three
         * bytes reserved, then at most 8 bytes of data. */
        uint8_t h[8] = {0};

        if (ev != WSG_TAP_IN && ev != WSG_TAP_OUT)
            break;
        if (len > 8)
            len = 8;
        be32(h, f->can_id);
        h[4] = (uint8_t)len;
        write_epb(c, IF_CAN, inbound, h, 8, data, len, comment);
        break;
    }
    default:
        break;
    }
}

void wsg_capture_event(void *ctx, struct wsg_tap_flow *f,
                       enum wsg_tap_event ev, const uint8_t *data, size_t len)
{
    struct wsg_capture_tap *ct = ctx;

    wsg_capture_record(ct->cap, f, ev, data, len,
                       wsg_axis_time(wsg_device_axis_const(ct->dev)),
                       ct->index);
}

void wsg_capture_tap_init(struct wsg_capture_tap *ct, struct wsg_capture *c,
                          const struct wsg_device *dev, int index)
{
    ct->tap.fn = wsg_capture_event;
    ct->tap.ctx = ct;
    ct->tap.on = &c->on;
    ct->cap = c;
    ct->dev = dev;
    ct->index = index;
}

int wsg_capture_start(struct wsg_capture *c, const char *path, char *err,
                      size_t errlen)
{
    size_t n = strlen(path);
    int fd, r;

    wsg_capture_stop(c);
    if (n == 0 || n >= sizeof c->path) {
        snprintf(err, errlen, "capture: the file name is %s",
                 n ? "too long" : "empty");
        return -EINVAL;
    }
    /* Like the log: the named file, truncated, never a FIFO or device
     * that would block the loop. */
    fd = open(path, O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC | O_NONBLOCK,
              0644);
    if (fd < 0) {
        r = -errno;
        snprintf(err, errlen, "capture %s: %s", path, strerror(errno));
        return r;
    }
    c->f = fdopen(fd, "wb");
    c->buf = malloc(WSG_CAPTURE_BUFSIZE);
    if (!c->f || !c->buf) {
        snprintf(err, errlen, "capture %s: %s", path, strerror(ENOMEM));
        if (c->f)
            fclose(c->f);
        else
            close(fd);
        free(c->buf);
        c->f = NULL;
        c->buf = NULL;
        return -ENOMEM;
    }
    setvbuf(c->f, c->buf, _IOFBF, WSG_CAPTURE_BUFSIZE);
    memcpy(c->path, path, n + 1);
    c->size = 0;
    c->records = 0;
    c->full = 0;
    write_shb(c);
    write_idb(c, LINKTYPE_IPV4, "ip", "TCP and UDP (IPv4)");
    write_idb(c, LINKTYPE_USER0, "pty",
              "serial line (pty): bytes read and written");
    write_idb(c, LINKTYPE_CAN_SOCKETCAN, "can", "SocketCAN frames");
    fflush(c->f);
    c->on = 1;
    return 0;
}

void wsg_capture_flush(struct wsg_capture *c)
{
    if (c->f && fflush(c->f) != 0 && !c->full) {
        fprintf(stderr, "wsgemu: capture %s: %s; capture stopped\n", c->path,
                strerror(errno));
        c->full = 2;
    }
}

void wsg_capture_stop(struct wsg_capture *c)
{
    c->on = 0;
    if (c->f) {
        fclose(c->f);
        c->f = NULL;
    }
    free(c->buf);
    c->buf = NULL;
}
