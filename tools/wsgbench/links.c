/*
 * wsgbench's connections to the servers on the client library
 * (wsgclient.h), named ("wsgemu TCP") for its messages: open over TCP,
 * UDP or the pty, send, receive with a deadline, a motion to its final
 * result, the control channel's lines; and the request every latency,
 * throughput and jitter figure is made of, Get Opening Width (43h).
 */
#define _GNU_SOURCE /* sched_setaffinity, pipe2, prctl, strndup */

#include "wsgbench.h"

#include <arpa/inet.h>
#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <getopt.h>
#include <math.h>
#include <netinet/in.h>
#include <poll.h>
#include <sched.h>
#include <signal.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/epoll.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

/* ---- links ---- */

const char *const kind_name[] = {"TCP", "UDP", "pty"};

/* Malformed packets end the measurement: a server must not send them. */
static int bad_is_fatal(struct wsg_client *c, enum wsg_parse_event ev,
                        uint8_t id)
{
    const struct link *l = c->user;

    msg("%s: malformed packet with ID %02Xh (%s)", l->who, id,
        ev == WSG_PARSE_BAD_CRC ? "bad checksum" : "oversize");
    return 1;
}

void link_init(struct link *l, enum link_kind kind, const char *name)
{
    static const enum wsg_link_kind kinds[] = {[L_TCP] = WSG_LINK_TCP,
                                               [L_UDP] = WSG_LINK_UDP,
                                               [L_PTY] = WSG_LINK_SERIAL};

    wsg_client_init(&l->c, kinds[kind]);
    l->c.on_bad = bad_is_fatal;
    l->c.user = l;
    snprintf(l->who, sizeof l->who, "%s %s", name, kind_name[kind]);
}

/* A receive that failed (not a timeout), reported. */
static void link_error(const struct link *l, int r)
{
    if (r != -EBADMSG) /* already said by bad_is_fatal */
        msg("%s: %s", l->who,
            r == -EPIPE ? "connection closed" : strerror(-r));
}

int link_tcp(struct link *l, const struct sockaddr_in *sa)
{
    int r = wsg_client_open_tcp(&l->c, sa, REPLY_MS);

    if (r < 0)
        msg("%s: connect to port %u: %s", l->who,
            (unsigned)ntohs(sa->sin_port), strerror(-r));
    return r < 0 ? -1 : 0;
}

/* Replies on rfd, which the bench owns (the server was started answering
 * to its port). */
static int link_udp(struct link *l, const struct sockaddr_in *sa, int rfd)
{
    int r = wsg_client_open_udp(&l->c, sa, rfd, 0);

    if (r < 0)
        msg("%s: %s", l->who, strerror(-r));
    return r < 0 ? -1 : 0;
}

static int link_pty(struct link *l, const char *path)
{
    int r = wsg_client_open_serial(&l->c, path);

    if (r < 0)
        msg("%s: %s: %s", l->who, path, strerror(-r));
    return r < 0 ? -1 : 0;
}

static int link_sent(const struct link *l, int r)
{
    if (r < 0)
        msg("%s: send: %s", l->who, r == -EIO ? "short write" : strerror(-r));
    return r < 0 ? -1 : 0;
}

int link_send(struct link *l, const uint8_t *buf, size_t n)
{
    return link_sent(l, wsg_client_send(&l->c, buf, n));
}

int link_sendf(struct link *l, uint8_t id, const uint8_t *payload, size_t len)
{
    return link_sent(l, wsg_client_send_frame(&l->c, id, payload, len));
}

/* One read of what epoll said is there: 1, 0 when nothing was after all,
 * -1 at the end of the stream or on an error (reported). */
int link_read(struct link *l)
{
    long n = wsg_client_read(&l->c);

    if (n == -EAGAIN)
        return 0;
    if (n < 0)
        link_error(l, (int)n);
    return n < 0 ? -1 : 1;
}

/* Wait for input until deadline and read it: 1, 0 on timeout, -1 at the
 * end of the stream or on an error (reported). */
int link_wait(struct link *l, uint64_t deadline)
{
    int r = wsg_client_fill(&l->c, deadline);

    if (r < 0)
        link_error(l, r);
    return r < 0 ? -1 : r;
}

/* Next frame: 1; 0 when none came by deadline (deadline 0: only what is
 * buffered is looked at); -1 on a broken frame, the end of the stream or
 * an error (reported). */
int link_recv(struct link *l, struct wsg_client_frame *f, uint64_t deadline)
{
    int r = wsg_client_recv(&l->c, f, deadline);

    if (r < 0)
        link_error(l, r);
    return r < 0 ? -1 : r;
}

/* Wait for a frame with this ID (others are skipped): 0, or -1 with a
 * message. */
int link_recv_id(struct link *l, uint8_t id, struct wsg_client_frame *f,
                 int timeout_ms)
{
    int r = wsg_client_recv_id(&l->c, id, f, wsg_client_deadline(timeout_ms));

    if (r == 0)
        msg("%s: no answer to %02Xh within %d ms", l->who, id, timeout_ms);
    else if (r < 0)
        link_error(l, r);
    return r == 1 ? 0 : -1;
}

/* A motion command through E_CMD_PENDING to its final result. The final
 * status, or -1 (reported). */
int link_motion(struct link *l, uint8_t id, const uint8_t *payload, size_t len)
{
    struct wsg_client_frame f;

    if (link_sendf(l, id, payload, len) < 0 ||
        link_recv_id(l, id, &f, REPLY_MS) < 0)
        return -1;
    if (f.status == WSG_E_CMD_PENDING &&
        link_recv_id(l, id, &f, MOTION_MS) < 0)
        return -1;
    return (int)f.status;
}

/* Over TCP, Disconnect Announcement first: a plain close would put the
 * emulator into FAST STOP. */
void link_close(struct link *l)
{
    struct wsg_client_frame f;

    if (l->c.kind == WSG_LINK_TCP && l->c.fd >= 0 &&
        link_sendf(l, WSG_CMD_DISCONNECT, NULL, 0) == 0)
        link_recv_id(l, WSG_CMD_DISCONNECT, &f, REPLY_MS);
    wsg_client_close(&l->c);
}

/* A control-channel command and its one-line answer (without newline).
 * 0, or -1 (reported). */
int ctl_cmd(struct link *l, const char *cmd, char *out, size_t cap)
{
    int r =
        wsg_client_line(&l->c, cmd, out, cap, wsg_client_deadline(REPLY_MS));

    if (r == 0)
        msg("control: no answer to \"%s\" within %d ms", cmd, REPLY_MS);
    else if (r < 0)
        link_error(l, r);
    return r == 1 ? 0 : -1;
}

/* The control channel's stats: model steps and overruns since start. */
int ctl_stats(struct link *ctl, double *steps, double *overruns)
{
    char line[1024];

    if (ctl_cmd(ctl, "stats", line, sizeof line) < 0)
        return -1;
    if (strncmp(line, "ok {", 4) != 0 ||
        wsg_json_num(line, "steps", steps) < 0 ||
        wsg_json_num(line, "overruns", overruns) < 0) {
        msg("control: \"stats\" answered \"%.120s\" (want ok {...\"steps\":"
            "S,\"overruns\":O...})",
            line);
        return -1;
    }
    return 0;
}

/* Simulated seconds from the control channel ("time" -> "ok SECONDS"),
 * with the wall time at which it was read (between sending and answer). */
int ctl_time(struct link *ctl, double *sim, uint64_t *wall)
{
    char line[128];
    uint64_t t0 = now_ns();

    if (ctl_cmd(ctl, "time", line, sizeof line) < 0)
        return -1;
    *wall = t0 + (now_ns() - t0) / 2;
    if (sscanf(line, "ok %lf", sim) != 1) {
        msg("control: \"time\" answered \"%.80s\"", line);
        return -1;
    }
    return 0;
}

/* ---- the requests ---- */

uint8_t req_width[WSG_HEADER_LEN + WSG_CRC_LEN];

int check_width(const struct link *l, const struct wsg_client_frame *f)
{
    if (f->id == WSG_CMD_GET_WIDTH && f->len == 6 &&
        f->status == WSG_E_SUCCESS)
        return 0;
    msg("%s: malformed answer to 43h: ID %02Xh, %u bytes, status %s", l->who,
        f->id, f->len, f->len >= 2 ? wsg_status_name(f->status) : "none");
    return -1;
}

int open_link(struct bench *b, struct link *l, int which, enum link_kind kind)
{
    struct sockaddr_in sa;
    char *v;
    int rc = -1;

    link_init(l, kind, b->srv[which].name);
    if (kind == L_PTY)
        return link_pty(l, b->pty_path[which]);
    v = field(b->srv[which].line, kind == L_TCP ? "tcp" : "udp");
    if (!v || parse_ipport(v, &sa) < 0)
        msg("%s: no usable address in \"%s\"", l->who, b->srv[which].line);
    else if (kind == L_TCP)
        rc = link_tcp(l, &sa);
    else
        rc = link_udp(l, &sa, b->udp_rfd[which]);
    free(v);
    return rc;
}

/* One request in flight: send 43h, wait for its answer. */
int sample(struct link *l, double *us)
{
    uint64_t t0 = now_ns();
    struct wsg_client_frame f;
    int r;

    if (link_send(l, req_width, sizeof req_width) < 0)
        return -1;
    r = link_recv(l, &f, t0 + REPLY_MS * NS_PER_MS);
    if (r == 0)
        msg("%s: no answer to 43h within %d ms", l->who, REPLY_MS);
    if (r <= 0 || check_width(l, &f) < 0)
        return -1;
    *us = (double)(now_ns() - t0) / 1e3;
    return 0;
}
