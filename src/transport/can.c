/*
 * The CAN interface (SocketCAN): commands arrive on one standard 11-bit
 * identifier, answers leave on that identifier + 1. A packet, preamble and
 * checksum included, travels as consecutive 8-byte frames, the last one
 * shorter; a new packet always starts in a new frame.
 *
 * Reassembly is the core's stream parser fed with each frame's data, so it
 * follows the SIZE field rather than frame lengths (a packet whose length is
 * a multiple of 8 needs no empty frame after it). A sender that stops in the
 * middle of a packet would leave the parser waiting forever and swallow the
 * next packet as payload, so a frame that arrives more than
 * WSG_CAN_REASSEMBLY_TIMEOUT_MS after the previous one starts afresh. The
 * check is made when that frame arrives: no timer is needed for it.
 *
 * The bus is one peer: one session, not connection-oriented (07h answers
 * E_NOT_AVAILABLE, nothing is ever closed, so no FAST STOP comes from CAN).
 *
 * Sending never blocks and never loses a frame to a full interface queue:
 * when the kernel refuses one (ENOBUFS from the device queue, EAGAIN from
 * the socket buffer; neither wakes epoll when space returns), that frame and
 * everything after it wait in a bounded queue of whole packets, and a
 * timerfd retries every WSG_CAN_RETRY_US. The timer is armed only while the
 * queue holds frames, so an idle emulator does not wake. A packet that does
 * not fit in the queue is dropped whole, never cut.
 */
#define _GNU_SOURCE

#include <errno.h>
#include <linux/can.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/epoll.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <sys/timerfd.h>
#include <time.h>
#include <unistd.h>

#include "transport.h"

/* A partial packet is discarded when the next frame comes this much later.
 * Drivers write a packet's frames in one go, so on the bus they follow each
 * other back to back (a full frame takes about 0.25 ms at 500 kbit/s);
 * 100 ms is far beyond that and still short of the 150 ms after which some
 * drivers give up on an answer and send again. */
#define WSG_CAN_REASSEMBLY_TIMEOUT_MS 100u
/* Retry period for frames the interface refused. */
#define WSG_CAN_RETRY_US 1000u
/* Frames waiting for the interface: 256 frames hold seven of the largest
 * packets (a 256-byte Loop echo is 266 bytes, 34 frames) or a hundred
 * short ones. */
#define WSG_CAN_QUEUE_FRAMES   256u
#define WSG_CAN_DATA_MAX       8u
#define WSG_CAN_READS_PER_WAKE 32

struct wsg_can {
    struct wsg_watch watch; /* the raw socket */
    struct wsg_watch timer; /* retry timerfd, armed while qlen > 0 */
    struct wsg_transport *t;
    struct wsg_reactor *reactor;
    struct wsg_device *dev;
    char iface[IFNAMSIZ];
    canid_t rx_id; /* commands */
    canid_t tx_id; /* answers: rx_id + 1 */
    int check_crc;
    int timer_armed;
    int have_rx; /* last_rx_ns is valid */
    uint64_t last_rx_ns;
    unsigned long dropped; /* packets dropped since the last report */
    int send_error;        /* errno of the last hard send error, reported */
    struct wsg_parser parser;
    struct wsg_session session;
    unsigned qhead, qlen; /* ring: queue[qhead .. qhead+qlen) mod size */
    struct can_frame queue[WSG_CAN_QUEUE_FRAMES];
};

static uint64_t mono_ns(void)
{
    struct timespec ts;

    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (uint64_t)ts.tv_sec * 1000000000u + (uint64_t)ts.tv_nsec;
}

static int can_arm_timer(struct wsg_can *can, int arm)
{
    struct itimerspec its;

    if (can->timer_armed == arm)
        return 0;
    memset(&its, 0, sizeof its);
    if (arm) {
        /* Periodic while armed: a retry that fails again needs no
         * re-arming, and disarming when the queue drains stops it. */
        its.it_value.tv_nsec = WSG_CAN_RETRY_US * 1000L;
        its.it_interval = its.it_value;
    }
    if (timerfd_settime(can->timer.fd, 0, &its, NULL) < 0)
        return -errno;
    can->timer_armed = arm;
    return 0;
}

/* One frame to the socket: 1 sent, 0 refused for now (retry later), or
 * -errno for an error that retrying would not mend. */
static int can_write(struct wsg_can *can, const struct can_frame *f)
{
    for (;;) {
        ssize_t n = send(can->watch.fd, f, sizeof *f, MSG_DONTWAIT);

        if (n == (ssize_t)sizeof *f)
            return 1;
        if (n >= 0)
            return -EIO; /* raw CAN sockets send whole frames or nothing */
        if (errno == EINTR)
            continue;
        if (errno == ENOBUFS || errno == EAGAIN || errno == EWOULDBLOCK)
            return 0;
        return -errno;
    }
}

/* A hard error (interface down or gone): what is queued cannot be sent in
 * order any more, so it goes, reported once per run of errors. */
static void can_send_failed(struct wsg_can *can, int err)
{
    if (can->send_error != err)
        fprintf(stderr, "wsgemu: can %s: send: %s: answers are lost\n",
                can->iface, strerror(err));
    can->send_error = err;
    can->qhead = can->qlen = 0;
    can_arm_timer(can, 0);
}

/* Write frames in order until the interface takes no more: how many
 * went, or -1 after a hard error (reported, and the queue is gone). */
static int can_write_run(struct wsg_can *can, const struct can_frame *f,
                         unsigned n)
{
    unsigned i;

    for (i = 0; i < n; i++) {
        int r = can_write(can, &f[i]);

        if (r == 0)
            break;
        if (r < 0) {
            can_send_failed(can, -r);
            return -1;
        }
        can->send_error = 0;
    }
    return (int)i;
}

static void can_flush(struct wsg_can *can)
{
    /* The ring in at most two runs: to its end, then from its start. */
    while (can->qlen > 0) {
        unsigned run = WSG_CAN_QUEUE_FRAMES - can->qhead;
        int k;

        if (run > can->qlen)
            run = can->qlen;
        k = can_write_run(can, &can->queue[can->qhead], run);
        if (k < 0)
            return;
        can->qhead = (can->qhead + (unsigned)k) % WSG_CAN_QUEUE_FRAMES;
        can->qlen -= (unsigned)k;
        if ((unsigned)k < run)
            break;
    }
    if (can->qlen == 0) {
        can->qhead = 0;
        if (can->dropped > 0) {
            fprintf(stderr,
                    "wsgemu: can %s: the interface takes frames again; "
                    "%lu answer packets were dropped\n",
                    can->iface, can->dropped);
            can->dropped = 0;
        }
    }
    if (can_arm_timer(can, can->qlen > 0) < 0 && can->qlen > 0) {
        /* Without the timer nothing would retry: better lose the queue
         * than hold it forever. */
        can_send_failed(can, EIO);
    }
}

static void can_enqueue(struct wsg_can *can, const struct can_frame *f,
                        unsigned n)
{
    unsigned i;

    if (can->qlen + n > WSG_CAN_QUEUE_FRAMES) {
        if (can->dropped++ == 0)
            fprintf(stderr,
                    "wsgemu: can %s: output queue full (is anything "
                    "acknowledging frames on the bus?): dropping answers\n",
                    can->iface);
        return;
    }
    for (i = 0; i < n; i++)
        can->queue[(can->qhead + can->qlen + i) % WSG_CAN_QUEUE_FRAMES] = f[i];
    can->qlen += n;
    if (can_arm_timer(can, 1) < 0)
        can_send_failed(can, EIO);
}

/* The session's send callback: one packet, cut into frames. */
static void can_packet(struct wsg_session *s, const uint8_t *pkt, size_t len)
{
    struct wsg_can *can = s->ctx;
    /* Zeroed whole: no byte of a frame goes out unset. */
    struct can_frame
        f[(WSG_FRAME_MAX + WSG_CAN_DATA_MAX - 1) / WSG_CAN_DATA_MAX] = {{0}};
    unsigned n = 0, i = 0;
    size_t off;

    if (len > WSG_FRAME_MAX)
        return; /* the device never builds one; nothing to cut it into */
    for (off = 0; off < len; off += WSG_CAN_DATA_MAX, n++) {
        size_t chunk =
            len - off < WSG_CAN_DATA_MAX ? len - off : WSG_CAN_DATA_MAX;

        f[n].can_id = can->tx_id;
        f[n].can_dlc = (uint8_t)chunk;
        memcpy(f[n].data, pkt + off, chunk);
    }
    if (can->t->tap && *can->t->tap->on) {
        struct wsg_tap_flow tf = {.kind = WSG_TAP_CAN, .can_id = can->tx_id};

        for (i = 0; i < n; i++)
            wsg_transport_tap(can->t, &tf, WSG_TAP_OUT, f[i].data,
                              f[i].can_dlc);
        i = 0;
    }
    /* Behind queued frames a packet must wait its turn, or its frames would
     * land in the middle of an earlier packet's. */
    if (can->qlen == 0) {
        int k = can_write_run(can, f, n);

        if (k < 0)
            return;
        i = (unsigned)k;
    }
    /* Into an empty queue the rest of a packet always fits (a packet is at
     * most 34 frames), so only whole packets are ever dropped. */
    if (i < n)
        can_enqueue(can, f + i, n - i);
}

static void can_frame_in(struct wsg_can *can, const struct can_frame *f)
{
    uint64_t now = mono_ns();
    unsigned dlc = f->can_dlc;
    uint64_t gap_ms;
    uint8_t id;
    int partial;

    /* The filter already keeps these out; a frame that slips through (a
     * filter that could not be set exactly, an error frame) is not data. */
    if (f->can_id & (CAN_EFF_FLAG | CAN_RTR_FLAG | CAN_ERR_FLAG))
        return;
    if ((f->can_id & CAN_SFF_MASK) != can->rx_id)
        return;
    if (can->t->tap && *can->t->tap->on) {
        struct wsg_tap_flow tf = {.kind = WSG_TAP_CAN, .can_id = can->rx_id};

        wsg_transport_tap(can->t, &tf, WSG_TAP_IN, f->data,
                          f->can_dlc > WSG_CAN_DATA_MAX ? WSG_CAN_DATA_MAX
                                                        : f->can_dlc);
    }
    if (dlc > WSG_CAN_DATA_MAX)
        dlc = WSG_CAN_DATA_MAX;
    gap_ms = (now - can->last_rx_ns) / 1000000u;
    partial = wsg_parser_partial(&can->parser, &id);
    if (can->have_rx && partial && gap_ms > WSG_CAN_REASSEMBLY_TIMEOUT_MS) {
        if (partial == 1)
            fprintf(stderr,
                    "wsgemu: can %s: discarded a partial packet (ID %02Xh): "
                    "no frame for %llu ms (timeout %u ms)\n",
                    can->iface, (unsigned)id, (unsigned long long)gap_ms,
                    WSG_CAN_REASSEMBLY_TIMEOUT_MS);
        else
            fprintf(stderr,
                    "wsgemu: can %s: discarded a partial packet: no frame "
                    "for %llu ms (timeout %u ms)\n",
                    can->iface, (unsigned long long)gap_ms,
                    WSG_CAN_REASSEMBLY_TIMEOUT_MS);
        wsg_parser_init(&can->parser, can->check_crc);
    }
    can->have_rx = 1;
    can->last_rx_ns = now;
    if (dlc > 0)
        wsg_device_input(can->dev, &can->session, &can->parser, f->data, dlc);
}

static void can_read(struct wsg_can *can)
{
    int i;

    /* Bounded, so a flood on the bus cannot starve the model's steps; the
     * level-triggered watch brings us back for the rest. */
    for (i = 0; i < WSG_CAN_READS_PER_WAKE; i++) {
        struct can_frame f;
        ssize_t n = recv(can->watch.fd, &f, sizeof f, MSG_DONTWAIT);

        if (n == (ssize_t)sizeof f) {
            can_frame_in(can, &f);
            continue;
        }
        if (n >= 0)
            continue; /* not a classic CAN frame */
        if (errno == EINTR)
            continue;
        if (errno == EAGAIN || errno == EWOULDBLOCK)
            return;
        /* The socket reports an interface that went down or away once;
         * it may come back, so keep listening. */
        fprintf(stderr, "wsgemu: can %s: receive: %s\n", can->iface,
                strerror(errno));
        return;
    }
}

static void can_on_timer(struct wsg_can *can)
{
    uint64_t expirations;

    /* The count does not matter: one flush sends what the interface
     * takes. EAGAIN: the timer was re-set since it fired. */
    if (read(can->timer.fd, &expirations, sizeof expirations) < 0 &&
        errno != EAGAIN)
        return;
    can_flush(can);
}

static void can_handle(struct wsg_transport *t, struct wsg_watch *w,
                       uint32_t events)
{
    struct wsg_can *can = t->state;

    if (w == &can->timer) {
        can_on_timer(can);
        return;
    }
    if (events & (EPOLLIN | EPOLLERR | EPOLLHUP))
        can_read(can);
}

static struct wsg_session *can_lookup(struct wsg_transport *t, uint32_t tag)
{
    struct wsg_can *can = t->state;

    return can->session.tag == tag ? &can->session : NULL;
}

static int can_describe(const struct wsg_transport *t, char *buf, size_t len)
{
    const struct wsg_can *can = t->state;
    int r = snprintf(buf, len, "%s:0x%03X", can->iface, (unsigned)can->rx_id);

    return r < 0 || (size_t)r >= len ? -ENOSPC : 0;
}

static void can_close(struct wsg_transport *t)
{
    struct wsg_can *can = t->state;

    if (!can)
        return;
    /* The bus is never "closed" by its peer: no FAST STOP rule applies,
     * but the device is told for symmetry with the other transports. */
    wsg_device_session_closed(can->dev, &can->session);
    if (can->timer.fd >= 0) {
        wsg_reactor_del(can->reactor, &can->timer);
        close(can->timer.fd);
    }
    if (can->watch.fd >= 0) {
        wsg_reactor_del(can->reactor, &can->watch);
        close(can->watch.fd);
    }
    free(can);
    t->state = NULL;
}

/* A warning, not a failure: the link may be brought up after the emulator
 * starts (frames sent meanwhile are lost, as on a real bus). */
static void can_warn_if_down(struct wsg_can *can)
{
    struct ifreq ifr;

    memset(&ifr, 0, sizeof ifr);
    memcpy(ifr.ifr_name, can->iface, sizeof ifr.ifr_name);
    if (ioctl(can->watch.fd, SIOCGIFFLAGS, &ifr) == 0 &&
        !(ifr.ifr_flags & IFF_UP))
        fprintf(stderr,
                "wsgemu: can %s: the interface is down (ip link set up %s)\n",
                can->iface, can->iface);
}

static int can_open(struct wsg_transport *t,
                    const struct wsg_transport_env *env, const void *config,
                    char *err, size_t errlen)
{
    const struct wsg_can_config *cfg = config;
    struct can_filter filter;
    struct sockaddr_can sa;
    struct wsg_can *can;
    const char *step = "setup";
    char hint[128] = "";
    int r;

    can = calloc(1, sizeof *can);
    if (!can) {
        r = -ENOMEM;
        goto fail;
    }
    t->state = can;
    can->t = t;
    can->reactor = env->reactor;
    can->dev = env->dev;
    can->check_crc = cfg->check_crc;
    can->rx_id = cfg->id & CAN_SFF_MASK;
    can->tx_id = (cfg->id + 1u) & CAN_SFF_MASK;
    wsg_transport_watch_init(t, &can->watch, -1);
    wsg_transport_watch_init(t, &can->timer, -1);
    /* The option parser allows 15 characters: IFNAMSIZ with its NUL. */
    snprintf(can->iface, sizeof can->iface, "%s", cfg->iface);

    step = NULL;
    can->watch.fd =
        socket(PF_CAN, SOCK_RAW | SOCK_NONBLOCK | SOCK_CLOEXEC, CAN_RAW);
    if (can->watch.fd < 0) {
        r = -errno;
        if (r == -EAFNOSUPPORT || r == -EPROTONOSUPPORT)
            snprintf(hint, sizeof hint,
                     " (this kernel has no SocketCAN: CONFIG_CAN, or the "
                     "can and can-raw modules, are missing)");
        goto fail;
    }
    memset(&sa, 0, sizeof sa);
    sa.can_family = AF_CAN;
    sa.can_ifindex = (int)if_nametoindex(can->iface);
    if (sa.can_ifindex == 0) {
        r = errno == ENXIO || errno == 0 ? -ENODEV : -errno;
        if (r == -ENODEV)
            snprintf(hint, sizeof hint,
                     " (for a virtual bus: ip link add dev %s type vcan && "
                     "ip link set up %s)",
                     can->iface, can->iface);
        goto fail;
    }
    /* Only our command ID, standard frames, no RTR: the kernel drops the
     * rest of the bus's traffic before it wakes us. Error frames are off
     * by default (CAN_RAW_ERR_FILTER 0). */
    filter.can_id = can->rx_id;
    filter.can_mask = CAN_SFF_MASK | CAN_EFF_FLAG | CAN_RTR_FLAG;
    step = "CAN_RAW_FILTER";
    if (setsockopt(can->watch.fd, SOL_CAN_RAW, CAN_RAW_FILTER, &filter,
                   sizeof filter) < 0)
        goto fail_errno;
    step = NULL;
    if (bind(can->watch.fd, (struct sockaddr *)&sa, sizeof sa) < 0) {
        r = -errno;
        if (r == -ENODEV)
            snprintf(hint, sizeof hint, " (not a CAN interface)");
        goto fail;
    }
    step = "timerfd";
    can->timer.fd =
        timerfd_create(CLOCK_MONOTONIC, TFD_NONBLOCK | TFD_CLOEXEC);
    if (can->timer.fd < 0)
        goto fail_errno;
    step = "epoll";
    r = wsg_reactor_add(can->reactor, &can->watch, EPOLLIN);
    if (r < 0)
        goto fail;
    r = wsg_reactor_add(can->reactor, &can->timer, EPOLLIN);
    if (r < 0) {
        wsg_reactor_del(can->reactor, &can->watch);
        goto fail;
    }
    wsg_parser_init(&can->parser, can->check_crc);
    wsg_session_init(&can->session, t->tag_base | 1u, 0, can_packet, can);
    /* For the communication log. */
    snprintf(can->session.peer, sizeof can->session.peer, "can %s:0x%03X",
             can->iface, (unsigned)can->rx_id);
    can_warn_if_down(can);
    return 0;

fail_errno:
    r = -errno;
fail:
    if (step)
        snprintf(err, errlen, "cannot open can %s: %s: %s%s", cfg->iface, step,
                 strerror(-r), hint);
    else
        snprintf(err, errlen, "cannot open can %s: %s%s", cfg->iface,
                 strerror(-r), hint);
    if (can) {
        if (can->timer.fd >= 0)
            close(can->timer.fd);
        if (can->watch.fd >= 0)
            close(can->watch.fd);
        free(can);
    }
    t->state = NULL;
    return r;
}

static void can_configure(struct wsg_transport *t,
                          const struct wsg_transport_settings *s)
{
    struct wsg_can *can = t->state;

    can->check_crc = s->check_crc;
    can->parser.check_crc = s->check_crc ? 1 : 0;
}

const struct wsg_transport_ops wsg_can_ops = {
    .name = "can",
    .open = can_open,
    .close = can_close,
    .handle = can_handle,
    .describe = can_describe,
    .lookup = can_lookup,
    .reap = NULL,
    .configure = can_configure,
};
