/*
 * wsgctl's link to the gripper on the client library (wsgclient.h): open
 * by --tcp, --udp, --serial or --control, send a request and wait through
 * E_CMD_PENDING for its answer within --timeout, and close over TCP with
 * Disconnect Announcement (07h), so wsgctl never puts the gripper into
 * FAST STOP. Failures are said here, in wsgctl's words, and come back as
 * exit statuses.
 */
#define _GNU_SOURCE /* getaddrinfo, sigaction, localtime_r */

#include "wsgctl.h"

#include <errno.h>
#include <netdb.h>
#include <netinet/in.h>
#include <signal.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

/* probe: a name not (yet) resolved is retried by wait-ready, not said. */
static int resolve(const char *host, unsigned long port, int socktype,
                   struct sockaddr_in *sa, int probe)
{
    struct addrinfo hints, *res;
    char serv[16];
    int rc;

    memset(&hints, 0, sizeof hints);
    hints.ai_family = AF_INET; /* the gripper speaks IPv4 */
    hints.ai_socktype = socktype;
    snprintf(serv, sizeof serv, "%lu", port);
    rc = getaddrinfo(host, serv, &hints, &res);
    if (rc != 0) {
        if (!probe)
            err("%s: %s", host, gai_strerror(rc));
        return -1;
    }
    memcpy(sa, res->ai_addr, sizeof *sa);
    freeaddrinfo(res);
    return 0;
}

/* What to check when nothing listens where wsgctl looked: most often no
 * emulator runs, or it runs on another port than the one wsgctl took from
 * its defaults. Said in the same line as the failure, so --json's error
 * carries it too. */
static const char *connect_hint(const struct opts *o, int r)
{
    static char buf[320];

    if (r != -ECONNREFUSED && r != -ETIMEDOUT && r != -EHOSTUNREACH &&
        r != -ENETUNREACH)
        return "";
    if (o->kind == LINK_CONTROL)
        return o->addr_given ? " (is wsgemu running with --control at that "
                               "address?)"
                             : " (is wsgemu running with --control at that "
                               "address? It came from WSG_CONTROL)";
    if (o->addr_given)
        return " (is wsgemu, or the gripper, running and serving TCP at that "
               "address? wsgemu's ready line shows its tcp=ADDR:PORT)";
    snprintf(buf, sizeof buf,
             " (is wsgemu, or the gripper, running and serving TCP at that "
             "address? Without --tcp wsgctl connects to $WSG_HOST:$WSG_PORT, "
             "default %s:%d: give --tcp HOST:PORT or set WSG_HOST and "
             "WSG_PORT to the tcp= of wsgemu's ready line)",
             DEFAULT_HOST, DEFAULT_PORT);
    return buf;
}

static int open_tcp(struct conn *c, const struct opts *o)
{
    const char *addr = o->addr;
    double timeout_s = o->timeout_s;
    int probe = o->probe;
    char host[256];
    unsigned long port;
    struct sockaddr_in sa;
    int r;

    if (split_addr(addr, host, sizeof host, &port, NULL) < 0) {
        err("bad TCP address \"%s\" (HOST:PORT)", addr);
        return -EXIT_USAGE;
    }
    if (resolve(host, port, SOCK_STREAM, &sa, probe) < 0)
        return -EXIT_CONN;
    r = wsg_client_open_tcp(&c->l, &sa, (int)(timeout_s * 1000));
    if (r < 0) {
        if (!probe)
            err("connect to %s: %s%s", addr,
                r == -ETIMEDOUT ? "timed out" : strerror(-r),
                connect_hint(o, r));
        return -EXIT_CONN;
    }
    return 0;
}

/* The gripper answers to the sender's IP at its configured remote port,
 * not to the source port: receive on LOCAL, send from another socket. */
static int open_udp(struct conn *c, const char *addr)
{
    char host[256];
    unsigned long port, local = DEFAULT_UDP_PORT;
    struct sockaddr_in sa;
    int rfd, r;

    if (split_addr(addr, host, sizeof host, &port, &local) < 0 || local == 0) {
        err("bad UDP address \"%s\" (HOST:PORT[:LOCAL])", addr);
        return -EXIT_USAGE;
    }
    if (resolve(host, port, SOCK_DGRAM, &sa, 0) < 0)
        return -EXIT_CONN;
    r = wsg_client_udp_bind(htonl(INADDR_ANY), (uint16_t)local, &rfd, NULL);
    if (r < 0) {
        err("bind UDP port %lu: %s", local, strerror(-r));
        return -EXIT_CONN;
    }
    r = wsg_client_open_udp(&c->l, &sa, rfd, 1);
    if (r < 0) {
        close(rfd);
        err("socket: %s", strerror(-r));
        return -EXIT_CONN;
    }
    return 0;
}

static int open_serial(struct conn *c, const char *path, int probe)
{
    int r = wsg_client_open_serial(&c->l, path);

    if (r < 0 && probe)
        return -EXIT_CONN;
    if (r == -ENOTTY)
        err("%s: not a serial port: %s", path, strerror(-r));
    else if (r < 0)
        err("open %s: %s", path, strerror(-r));
    return r < 0 ? -EXIT_CONN : 0;
}

static int warn_bad(struct wsg_client *l, enum wsg_parse_event ev, uint8_t id)
{
    (void)l;
    err("warning: dropped a packet with ID %02Xh: %s", id,
        ev == WSG_PARSE_BAD_CRC ? "bad checksum" : "oversize");
    return 0; /* and go on */
}

int conn_open(struct conn *c, const struct opts *o)
{
    static const enum wsg_link_kind kinds[] = {[LINK_TCP] = WSG_LINK_TCP,
                                               [LINK_UDP] = WSG_LINK_UDP,
                                               [LINK_SERIAL] = WSG_LINK_SERIAL,
                                               [LINK_CONTROL] = WSG_LINK_TCP};

    memset(c, 0, sizeof *c);
    c->kind = o->kind;
    wsg_client_init(&c->l, kinds[o->kind]);
    c->l.stop = &interrupted;
    c->l.on_bad = warn_bad;
    switch (o->kind) {
    case LINK_TCP:
        return open_tcp(c, o);
    case LINK_UDP:
        return open_udp(c, o->addr);
    case LINK_SERIAL:
        return open_serial(c, o->addr, o->probe);
    case LINK_CONTROL:
        return open_tcp(c, o);
    }
    return -EXIT_USAGE;
}

int conn_send(struct conn *c, uint8_t id, const uint8_t *payload, size_t len)
{
    int r = wsg_client_send_frame(&c->l, id, payload, len);

    if (r == -EMSGSIZE) {
        err("payload too long (%zu bytes)", len);
        return -EXIT_USAGE;
    }
    if (r < 0) {
        err("send: %s", r == -EIO ? "short write" : strerror(-r));
        return -EXIT_CONN;
    }
    return 0;
}

/* A receive's result as wsgctl takes it: 1 got one; 0 deadline passed; -1
 * end of stream or error (reported); -2 interrupted. */
static int conn_result(const struct conn *c, int rc)
{
    if (rc >= 0)
        return rc;
    if (rc == -EINTR)
        return -2;
    if (rc == -EPIPE)
        err(c->kind == LINK_SERIAL ? "the line hung up"
                                   : "the gripper closed the connection");
    else
        err("receive: %s", strerror(-rc));
    return -1;
}

/* Next good frame, as conn_result says. */
int conn_recv(struct conn *c, struct wsg_client_frame *r, uint64_t deadline)
{
    return conn_result(c, wsg_client_recv(&c->l, r, deadline));
}

/* Exit status for a conn_recv failure. */
int recv_fail(int rc, uint8_t id, const struct opts *o)
{
    if (rc == -2)
        return EXIT_INTERRUPTED;
    if (rc == 0)
        err("no answer to %02Xh %s within %.1f s", id,
            wsg_cmd_name(id) ? wsg_cmd_name(id) : "?", o->timeout_s);
    return EXIT_CONN;
}

/* The --timeout from now. */
uint64_t timeout_deadline(const struct opts *o)
{
    return wsg_client_deadline((int)(o->timeout_s * 1000.0));
}

/* --step: the motion was accepted, with the emulator's time paused;
 * advance it by exactly the time asked for, through a connection of its
 * own to the control channel ("time step" answers once the steps ran and
 * what they sent, the final result too, has left). 0 or an exit status
 * (said). */
static int step_time(const struct opts *o)
{
    struct ctx k;
    char cmd[48], line[256];
    const char *rest;
    int rc;

    memset(&k, 0, sizeof k);
    k.o = *o;
    k.o.kind = LINK_CONTROL;
    k.o.addr = o->step_control;
    k.o.jo = NULL;
    rc = conn_open(&k.c, &k.o);
    if (rc < 0)
        return -rc;
    snprintf(cmd, sizeof cmd, "time step %lu", o->step_ms);
    rc = control_line(&k, cmd, line, sizeof line, &rest);
    conn_close(&k.c);
    return rc;
}

/* Send a request and wait for its answer, through E_CMD_PENDING for the
 * final result (on_pending, if given, sees the immediate reply; --step
 * steps the emulator's time then). Frames with other IDs (streams) are
 * skipped. 0 with *r filled, or an exit status. */
int xact(struct ctx *x, uint8_t id, const uint8_t *payload, size_t len,
         struct wsg_client_frame *r, pending_fn on_pending)
{
    uint64_t deadline = timeout_deadline(&x->o);
    int rc = conn_send(&x->c, id, payload, len);

    if (rc < 0)
        return -rc;
    rc = conn_result(&x->c, wsg_client_recv_id(&x->c.l, id, r, deadline));
    if (rc == 1 && r->status == WSG_E_CMD_PENDING) {
        if (on_pending)
            on_pending(&x->o, r);
        if (x->o.step_ms) {
            int st = step_time(&x->o);

            if (st)
                return st;
        }
        rc = conn_result(&x->c, wsg_client_final(&x->c.l, r, deadline));
        if (rc == 0) {
            /* Accepted, but the result never came: the usual reason is
             * an emulator whose time is paused. */
            err("%02Xh %s: accepted (E_CMD_PENDING), but no final result "
                "within %.1f s (with the emulator's time paused it comes "
                "only when time is stepped: --step MS)",
                id, wsg_cmd_name(id) ? wsg_cmd_name(id) : "?", x->o.timeout_s);
            return EXIT_CONN;
        }
    }
    if (rc == 1 && x->o.jo) {
        x->o.jo->has_status = 1;
        x->o.jo->status = r->status;
    }
    return rc == 1 ? 0 : recv_fail(rc, id, &x->o);
}

/* Over TCP, announce the close (07h), so the gripper does not go into
 * FAST STOP; the answer is awaited briefly so the 07h is surely read
 * before the FIN. Over GCL BYE() does it (text_close), and when nothing
 * ever came back, both (close_both_ways). */
void conn_close(struct conn *c)
{
    unsigned heard = 0;

    if (c->text)
        text_close(c);
    for (int i = 0; i < 256; i++)
        heard += c->l.seen[i];
    if (c->kind == LINK_TCP && c->l.fd >= 0 && !c->announced && !heard)
        close_both_ways(c);
    if (c->kind == LINK_TCP && c->l.fd >= 0 && !c->announced) {
        struct wsg_client_frame r;
        int saved = interrupted;

        interrupted = 0;
        if (conn_send(c, WSG_CMD_DISCONNECT, NULL, 0) == 0)
            conn_result(c, wsg_client_recv_id(&c->l, WSG_CMD_DISCONNECT, &r,
                                              wsg_client_deadline(1000)));
        interrupted = saved;
        c->announced = 1;
    }
    wsg_client_close(&c->l);
}
