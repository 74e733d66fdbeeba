/*
 * wsgctl: command-line client of a WSG gripper (or of wsgemu) for people and
 * shell scripts. It names every command of the 2.2.0 command set, takes
 * values in human units and prints them by the protocol schema's reply
 * layouts (wsg/schema.h), waits through E_CMD_PENDING for a motion's
 * final result, follows auto-update streams (watch), sends packets written in
 * WSG Commander's command-editor syntax (raw) and decodes hex dumps of
 * packets (decode). It talks TCP, UDP or a serial line; over TCP it always
 * sends Disconnect Announcement (07h) before closing, so using it never puts
 * the gripper into FAST STOP. Exit statuses are documented in usage().
 */
#define _GNU_SOURCE /* cfmakeraw, getaddrinfo, sigaction, clock_gettime */

#include "ctljson.h"
#include "wsg/device.h"
#include "wsg/proto.h"
#include "wsgclient.h"

#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <netdb.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <signal.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <termios.h>
#include <time.h>
#include <unistd.h>

/* Exit statuses (documented in usage()). */
#define EXIT_OK          0
#define EXIT_GRIPPER     1 /* the gripper answered an error status */
#define EXIT_USAGE       2
#define EXIT_CONN        3 /* cannot connect, I/O error, no answer in time */
#define EXIT_INTERRUPTED 130

#define DEFAULT_TCP      "127.0.0.1:1000"
#define DEFAULT_UDP_PORT 1501 /* where the gripper sends its UDP answers */

/* Set by SIGINT/SIGTERM; a flag, since the handler may do nothing else. */
static volatile sig_atomic_t interrupted;

/* LINK_CONTROL: the emulator's control channel, read only (see
 * control_read). */
enum link_kind { LINK_TCP, LINK_UDP, LINK_SERIAL, LINK_CONTROL };

struct opts {
    enum link_kind kind;
    const char *addr;
    double timeout_s;
    int quiet;
    int relative;
    int stop_on_block;
    int reset;
    long count; /* watch: stop after this many values; 0: until SIGINT */
};

/* The link to the gripper, and whether its close was announced. */
struct conn {
    enum link_kind kind;
    struct wsg_client l;
    int announced; /* TCP: 07h sent, no second one */
};

struct ctx {
    struct opts o;
    struct conn c;
    int have_conn;
    const char *command; /* wsgctl's name of the command running */
};

static void err(const char *fmt, ...)
{
    va_list ap;

    fputs("wsgctl: ", stderr);
    va_start(ap, fmt);
    vfprintf(stderr, fmt, ap);
    va_end(ap);
    fputc('\n', stderr);
}

static void on_signal(int sig)
{
    (void)sig;
    interrupted = 1;
}

/* ---- parsing arguments ---- */

static int parse_double(const char *s, double *v)
{
    char *end;

    errno = 0;
    *v = strtod(s, &end);
    return end != s && *end == '\0' && errno == 0 && isfinite(*v) ? 0 : -1;
}

static int parse_float(const char *s, float *v)
{
    double d;

    if (parse_double(s, &d) < 0)
        return -1;
    *v = (float)d;
    return 0;
}

/* Decimal digits, or 0x (0X) and hex digits, as WSG Commander and the
 * documentation write numbers: strtoul with base 0 would read 010 as octal
 * 8, refuse 08, and take blanks and signs. */
static int parse_ulong(const char *s, unsigned long max, unsigned long *v)
{
    unsigned long n = 0, base = 10;

    if (s[0] == '0' && (s[1] == 'x' || s[1] == 'X')) {
        base = 16;
        s += 2;
    }
    if (*s == '\0')
        return -1;
    for (; *s; s++) {
        unsigned long d;

        if (*s >= '0' && *s <= '9')
            d = (unsigned long)(*s - '0');
        else if (base == 16 && *s >= 'a' && *s <= 'f')
            d = (unsigned long)(*s - 'a' + 10);
        else if (base == 16 && *s >= 'A' && *s <= 'F')
            d = (unsigned long)(*s - 'A' + 10);
        else
            return -1;
        /* n * base + d > max, asked without overflowing */
        if (d > max || n > (max - d) / base)
            return -1;
        n = n * base + d;
    }
    *v = n;
    return 0;
}

/* "HOST:PORT" (and ":LOCAL" for UDP) into its parts; host is copied. */
static int split_addr(const char *addr, char *host, size_t cap,
                      unsigned long *port, unsigned long *local)
{
    const char *c1 = strchr(addr, ':');
    char rest[64], *c2;

    if (!c1 || (size_t)(c1 - addr) >= cap || c1 == addr ||
        strlen(c1 + 1) >= sizeof rest)
        return -1;
    memcpy(host, addr, (size_t)(c1 - addr));
    host[c1 - addr] = '\0';
    strcpy(rest, c1 + 1);
    c2 = strchr(rest, ':');
    if (c2) {
        if (!local)
            return -1;
        *c2++ = '\0';
        if (parse_ulong(c2, 65535, local) < 0)
            return -1;
    }
    return parse_ulong(rest, 65535, port) < 0 || *port == 0 ? -1 : 0;
}

/* ---- the link ---- */

static int resolve(const char *host, unsigned long port, int socktype,
                   struct sockaddr_in *sa)
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
        err("%s: %s", host, gai_strerror(rc));
        return -1;
    }
    memcpy(sa, res->ai_addr, sizeof *sa);
    freeaddrinfo(res);
    return 0;
}

static int open_tcp(struct conn *c, const char *addr, double timeout_s)
{
    char host[256];
    unsigned long port;
    struct sockaddr_in sa;
    int r;

    if (split_addr(addr, host, sizeof host, &port, NULL) < 0) {
        err("bad TCP address \"%s\" (HOST:PORT)", addr);
        return -EXIT_USAGE;
    }
    if (resolve(host, port, SOCK_STREAM, &sa) < 0)
        return -EXIT_CONN;
    r = wsg_client_open_tcp(&c->l, &sa, (int)(timeout_s * 1000));
    if (r < 0) {
        err("connect to %s: %s", addr,
            r == -ETIMEDOUT ? "timed out" : strerror(-r));
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
    if (resolve(host, port, SOCK_DGRAM, &sa) < 0)
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

static int open_serial(struct conn *c, const char *path)
{
    int r = wsg_client_open_serial(&c->l, path);

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

static int conn_open(struct conn *c, const struct opts *o)
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
        return open_tcp(c, o->addr, o->timeout_s);
    case LINK_UDP:
        return open_udp(c, o->addr);
    case LINK_SERIAL:
        return open_serial(c, o->addr);
    case LINK_CONTROL:
        return open_tcp(c, o->addr, o->timeout_s);
    }
    return -EXIT_USAGE;
}

static int conn_send(struct conn *c, uint8_t id, const uint8_t *payload,
                     size_t len)
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
static int conn_recv(struct conn *c, struct wsg_client_frame *r,
                     uint64_t deadline)
{
    return conn_result(c, wsg_client_recv(&c->l, r, deadline));
}

/* Exit status for a conn_recv failure. */
static int recv_fail(int rc, uint8_t id, const struct opts *o)
{
    if (rc == -2)
        return EXIT_INTERRUPTED;
    if (rc == 0)
        err("no answer to %02Xh %s within %.1f s", id,
            wsg_cmd_name(id) ? wsg_cmd_name(id) : "?", o->timeout_s);
    return EXIT_CONN;
}

/* The --timeout from now. */
static uint64_t timeout_deadline(const struct opts *o)
{
    return wsg_client_deadline((int)(o->timeout_s * 1000.0));
}

typedef void (*pending_fn)(const struct opts *o,
                           const struct wsg_client_frame *r);

/* Send a request and wait for its answer, through E_CMD_PENDING for the
 * final result (on_pending, if given, sees the immediate reply). Frames
 * with other IDs (streams) are skipped. 0 with *r filled, or an exit
 * status. */
static int xact(struct ctx *x, uint8_t id, const uint8_t *payload, size_t len,
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
        rc = conn_result(&x->c, wsg_client_final(&x->c.l, r, deadline));
    }
    return rc == 1 ? 0 : recv_fail(rc, id, &x->o);
}

/* Over TCP, announce the close (07h), so the gripper does not go into
 * FAST STOP; the answer is awaited briefly so the 07h is surely read
 * before the FIN. */
static void conn_close(struct conn *c)
{
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

/* ---- printing values ---- */

/* The parameters of a successful answer with this ID, by the schema's
 * reply layout: one line per field, "width 55.00 mm", "grasp-state 4
 * (HOLDING)", each after indent; with --quiet, the bare values on one
 * line ("55.00", "1 1 2.2.0 1"). Returns 1 if they fit the layout and
 * there are any, else 0 (nothing printed). */
static int print_values(const struct opts *o, const char *indent, uint8_t id,
                        const uint8_t *p, size_t n)
{
    static const struct wsg_value_style human = {2, " (", " ", ")", 0, 0};
    static const struct wsg_value_style bare = {2, "", "", "", 1, 0};
    struct wsg_value v[WSG_FIELDS_MAX];
    char buf[4 * WSG_REPLY_PARAMS_MAX + 64];
    int k = wsg_layout_decode(&wsg_schema[id].reply, p, n, v);

    if (k <= 0)
        return 0;
    for (int i = 0; i < k; i++) {
        const char *unit = v[i].field->unit;

        wsg_value_format(&v[i], o->quiet ? &bare : &human, buf, sizeof buf);
        if (o->quiet)
            printf("%s%s", i ? " " : indent, buf);
        else
            printf("%s%s %s%s%s\n", indent, v[i].field->name, buf,
                   unit[0] ? " " : "", unit);
    }
    if (o->quiet)
        putchar('\n');
    return 1;
}

static void print_hex(const uint8_t *p, size_t n)
{
    for (size_t i = 0; i < n; i++)
        printf("%s%02X", i ? " " : "", p[i]);
}

static const char *cmd_name(uint8_t id)
{
    const char *n = wsg_cmd_name(id);

    return n ? n : "(unknown ID)";
}

/* Report an error status; the exit status for it. */
static int gripper_error(uint8_t id, unsigned status)
{
    err("%02Xh %s: %s", id, cmd_name(id), wsg_status_name(status));
    return EXIT_GRIPPER;
}

/* ---- commands ---- */

/* A reading through the emulator's control channel ("state"), printed as
 * the gripper's answer would be. Nothing is sent to the gripper, so
 * nothing happens to it: no 07h at the close (which aborts a running
 * motion, 3.1.2), no session, no FAST STOP. */
static int control_read(struct ctx *x, uint8_t id, const uint8_t *payload,
                        size_t len)
{
    const struct wsg_layout *layout = &wsg_schema[id].reply;
    char line[2048];
    size_t np;
    double v[WSG_FIELDS_MAX];
    uint8_t p[WSG_REPLY_PARAMS_MAX];
    int ok = 1, r;

    /* Readings only: 42h's reset flag (stats --reset) changes the
     * gripper. */
    if (len && !(id == WSG_CMD_GET_GRASP_STATS && len == 1 && !payload[0])) {
        err("--control reads only: %02Xh %s with parameters changes the "
            "gripper",
            id, cmd_name(id));
        return EXIT_USAGE;
    }
    /* A reading answers numbers, which the channel's state may hold; not
     * nothing, not text. */
    if (layout->n == 0 || layout->fields[layout->n - 1].type == WSG_FT_TEXT ||
        layout->fields[layout->n - 1].type == WSG_FT_BYTES) {
        err("--control reads only: %02Xh %s is not a reading", id,
            cmd_name(id));
        return EXIT_USAGE;
    }
    r = wsg_client_line(&x->c.l, "state", line, sizeof line,
                        timeout_deadline(&x->o));
    if (r == 0) {
        err("control channel: no answer to \"state\"");
        return EXIT_CONN;
    }
    if (r < 0) {
        if (r == -EPIPE)
            err("control channel: closed");
        else
            err("control channel: %s", strerror(-r));
        return EXIT_CONN;
    }
    if (strncmp(line, "ok {", 4) != 0) {
        err("control channel: %s", line);
        return EXIT_CONN;
    }
    /* Each field of the reply under its name in the channel's spelling
     * ("no_part"), put on the wire as the gripper would send it. */
    for (size_t i = 0; ok && i < layout->n; i++) {
        char key[24]; /* with quotes and colon, fits wsg_json_num's 32 */

        wsg_schema_key(layout->fields[i].name, key, sizeof key);
        ok = wsg_json_num(line, key, v + i) == 0;
    }
    if (!ok) {
        err("control channel: unexpected state: %s", line);
        return EXIT_CONN;
    }
    np = wsg_layout_encode(layout, v, p);
    print_values(&x->o, "", id, p, np);
    return EXIT_OK;
}

/* A request whose success answer is printed with print_values (or
 * nothing). E_NOT_AVAILABLE on an optional setting (soft limits, tag)
 * prints "none" and is no error when none_ok. */
static int simple(struct ctx *x, uint8_t id, const uint8_t *payload,
                  size_t len, int none_ok)
{
    struct wsg_client_frame r;
    int rc;

    if (x->c.kind == LINK_CONTROL)
        return control_read(x, id, payload, len);
    rc = xact(x, id, payload, len, &r, NULL);
    if (rc)
        return rc;
    if (none_ok && r.status == WSG_E_NOT_AVAILABLE) {
        printf(x->o.quiet ? "none\n" : "%s none\n", x->command);
        return EXIT_OK;
    }
    if (r.status != WSG_E_SUCCESS)
        return gripper_error(id, r.status);
    print_values(&x->o, "", id, WSG_CLIENT_PARAMS(&r), WSG_CLIENT_NPARAMS(&r));
    return EXIT_OK;
}

static int need_float(const char *what, const char *s, float *v)
{
    if (parse_float(s, v) < 0) {
        err("%s: not a number: \"%s\"", what, s);
        return EXIT_USAGE;
    }
    return 0;
}

static int c_home(struct ctx *x, int argc, char **argv)
{
    uint8_t dir = 0;

    if (argc == 1) {
        if (!strcmp(argv[0], "pos"))
            dir = 1;
        else if (!strcmp(argv[0], "neg"))
            dir = 2;
        else {
            err("home: direction is pos or neg, not \"%s\"", argv[0]);
            return EXIT_USAGE;
        }
    }
    return simple(x, WSG_CMD_HOMING, &dir, 1, 0);
}

/* move, grasp, release: WIDTH SPEED. */
static int width_speed(struct ctx *x, uint8_t id, char **argv)
{
    uint8_t pl[9], *q = pl;
    float w, s;

    if (need_float("width", argv[0], &w) || need_float("speed", argv[1], &s))
        return EXIT_USAGE;
    if (id == WSG_CMD_PREPOSITION)
        *q++ =
            (uint8_t)((x->o.relative ? 1 : 0) | (x->o.stop_on_block ? 2 : 0));
    wsg_put_f32(q, w);
    wsg_put_f32(q + 4, s);
    return simple(x, id, pl, (size_t)(q + 8 - pl), 0);
}

static int c_move(struct ctx *x, int argc, char **argv)
{
    (void)argc;
    return width_speed(x, WSG_CMD_PREPOSITION, argv);
}

static int c_grasp(struct ctx *x, int argc, char **argv)
{
    (void)argc;
    return width_speed(x, WSG_CMD_GRASP, argv);
}

static int c_release(struct ctx *x, int argc, char **argv)
{
    (void)argc;
    return width_speed(x, WSG_CMD_RELEASE, argv);
}

static int c_stop(struct ctx *x, int argc, char **argv)
{
    (void)argc;
    (void)argv;
    return simple(x, WSG_CMD_STOP, NULL, 0, 0);
}

static int c_fast_stop(struct ctx *x, int argc, char **argv)
{
    (void)argc;
    (void)argv;
    return simple(x, WSG_CMD_FAST_STOP, NULL, 0, 0);
}

static int c_ack(struct ctx *x, int argc, char **argv)
{
    (void)argc;
    (void)argv;
    return simple(x, WSG_CMD_ACK_FAST_STOP, (const uint8_t *)"ack", 3, 0);
}

static int c_info(struct ctx *x, int argc, char **argv)
{
    (void)argc;
    (void)argv;
    return simple(x, WSG_CMD_GET_SYSTEM_INFO, NULL, 0, 0);
}

static int c_limits(struct ctx *x, int argc, char **argv)
{
    (void)argc;
    (void)argv;
    return simple(x, WSG_CMD_GET_SYSTEM_LIMITS, NULL, 0, 0);
}

static int c_state(struct ctx *x, int argc, char **argv)
{
    int rc;

    (void)argc;
    (void)argv;
    rc = simple(x, WSG_CMD_GET_SYSTEM_STATE, NULL, 0, 0);
    return rc ? rc : simple(x, WSG_CMD_GET_GRASP_STATE, NULL, 0, 0);
}

static int c_width(struct ctx *x, int argc, char **argv)
{
    (void)argc;
    (void)argv;
    return simple(x, WSG_CMD_GET_WIDTH, NULL, 0, 0);
}

static int c_speed(struct ctx *x, int argc, char **argv)
{
    (void)argc;
    (void)argv;
    return simple(x, WSG_CMD_GET_SPEED, NULL, 0, 0);
}

static int c_force(struct ctx *x, int argc, char **argv)
{
    (void)argc;
    (void)argv;
    return simple(x, WSG_CMD_GET_FORCE, NULL, 0, 0);
}

static int c_temperature(struct ctx *x, int argc, char **argv)
{
    (void)argc;
    (void)argv;
    return simple(x, WSG_CMD_GET_TEMPERATURE, NULL, 0, 0);
}

static int c_tag(struct ctx *x, int argc, char **argv)
{
    if (argc == 0)
        return simple(x, WSG_CMD_GET_DEVICE_TAG, NULL, 0, 1);
    return simple(x, WSG_CMD_SET_DEVICE_TAG, (const uint8_t *)argv[0],
                  strlen(argv[0]), 0);
}

/* acc, force-limit: get without a value, set with one. */
static int get_set(struct ctx *x, uint8_t get, uint8_t set, int argc,
                   char **argv)
{
    uint8_t pl[4];
    float v;

    if (argc == 0)
        return simple(x, get, NULL, 0, 0);
    if (need_float("value", argv[0], &v))
        return EXIT_USAGE;
    wsg_put_f32(pl, v);
    return simple(x, set, pl, 4, 0);
}

static int c_acc(struct ctx *x, int argc, char **argv)
{
    return get_set(x, WSG_CMD_GET_ACCELERATION, WSG_CMD_SET_ACCELERATION, argc,
                   argv);
}

static int c_force_limit(struct ctx *x, int argc, char **argv)
{
    return get_set(x, WSG_CMD_GET_FORCE_LIMIT, WSG_CMD_SET_FORCE_LIMIT, argc,
                   argv);
}

static int c_soft_limits(struct ctx *x, int argc, char **argv)
{
    uint8_t pl[8];
    float minus, plus;

    if (argc == 0)
        return simple(x, WSG_CMD_GET_SOFT_LIMITS, NULL, 0, 1);
    if (argc == 1) {
        if (strcmp(argv[0], "clear") != 0) {
            err("soft-limits: MINUS PLUS, or clear");
            return EXIT_USAGE;
        }
        return simple(x, WSG_CMD_CLEAR_SOFT_LIMITS, NULL, 0, 0);
    }
    if (need_float("minus", argv[0], &minus) ||
        need_float("plus", argv[1], &plus))
        return EXIT_USAGE;
    wsg_put_f32(pl, minus);
    wsg_put_f32(pl + 4, plus);
    return simple(x, WSG_CMD_SET_SOFT_LIMITS, pl, 8, 0);
}

static int c_overdrive(struct ctx *x, int argc, char **argv)
{
    uint8_t on;

    (void)argc;
    if (!strcmp(argv[0], "on"))
        on = 1;
    else if (!strcmp(argv[0], "off"))
        on = 0;
    else {
        err("overdrive: on or off, not \"%s\"", argv[0]);
        return EXIT_USAGE;
    }
    return simple(x, WSG_CMD_OVERDRIVE, &on, 1, 0);
}

static int c_stats(struct ctx *x, int argc, char **argv)
{
    uint8_t flags = x->o.reset ? 1 : 0;

    (void)argc;
    (void)argv;
    return simple(x, WSG_CMD_GET_GRASP_STATS, &flags, 1, 0);
}

static int c_loop(struct ctx *x, int argc, char **argv)
{
    struct wsg_client_frame r;
    size_t n = strlen(argv[0]);
    int rc;

    (void)argc;
    if (n > WSG_PAYLOAD_MAX) {
        err("loop: at most %u bytes", WSG_PAYLOAD_MAX);
        return EXIT_USAGE;
    }
    rc = xact(x, WSG_CMD_LOOP, (const uint8_t *)argv[0], n, &r, NULL);
    if (rc)
        return rc;
    if (r.status != WSG_E_SUCCESS)
        return gripper_error(WSG_CMD_LOOP, r.status);
    /* The echo comes back as status plus data, the data being ours. */
    printf("%.*s\n", (int)WSG_CLIENT_NPARAMS(&r),
           (const char *)WSG_CLIENT_PARAMS(&r));
    return EXIT_OK;
}

static int c_tare(struct ctx *x, int argc, char **argv)
{
    (void)argc;
    (void)argv;
    return simple(x, WSG_CMD_TARE, NULL, 0, 0);
}

static int c_bye(struct ctx *x, int argc, char **argv)
{
    int rc;

    (void)argc;
    (void)argv;
    rc = simple(x, WSG_CMD_DISCONNECT, NULL, 0, 0);
    x->c.announced = 1; /* even if refused: a second one would be too */
    return rc;
}

/* ---- raw ---- */

/* One item of WSG Commander's command editor: a byte (32, 0x20), a float
 * (150.0f), or a string in double quotes ("text", one shell argument that
 * contains the quotes). Appends to buf; -1 on a bad item. */
static int raw_item(const char *s, uint8_t *buf, size_t cap, size_t *n)
{
    size_t len = strlen(s);
    unsigned long b;

    if (len >= 2 && s[0] == '"' && s[len - 1] == '"') {
        if (*n + len - 2 > cap)
            return -1;
        memcpy(buf + *n, s + 1, len - 2);
        *n += len - 2;
        return 0;
    }
    if (len >= 2 && (s[len - 1] == 'f' || s[len - 1] == 'F') &&
        strncmp(s, "0x", 2) != 0 && strncmp(s, "0X", 2) != 0) {
        char tmp[64];
        float v;
        if (len >= sizeof tmp)
            return -1;
        memcpy(tmp, s, len - 1);
        tmp[len - 1] = '\0';
        if (parse_float(tmp, &v) < 0 || *n + 4 > cap)
            return -1;
        wsg_put_f32(buf + *n, v);
        *n += 4;
        return 0;
    }
    if (parse_ulong(s, 255, &b) < 0 || *n + 1 > cap)
        return -1;
    buf[(*n)++] = (uint8_t)b;
    return 0;
}

/* "06h Loop: E_SUCCESS" and the parameters, for raw and decode. */
static void print_reply(const struct opts *o, const struct wsg_client_frame *r)
{
    printf("%02Xh %s: %s\n", r->id, cmd_name(r->id),
           wsg_status_name(r->status));
    printf("params (%zu):%s", WSG_CLIENT_NPARAMS(r),
           WSG_CLIENT_NPARAMS(r) ? " " : "");
    print_hex(WSG_CLIENT_PARAMS(r), WSG_CLIENT_NPARAMS(r));
    putchar('\n');
    if (r->status == WSG_E_SUCCESS)
        print_values(o, "", r->id, WSG_CLIENT_PARAMS(r),
                     WSG_CLIENT_NPARAMS(r));
}

static int c_raw(struct ctx *x, int argc, char **argv)
{
    uint8_t pl[WSG_PAYLOAD_MAX];
    size_t n = 0;
    unsigned long id;
    struct wsg_client_frame r;
    int rc;

    if (parse_ulong(argv[0], 255, &id) < 0) {
        err("raw: bad ID \"%s\" (a byte: 32 or 0x20)", argv[0]);
        return EXIT_USAGE;
    }
    for (int i = 1; i < argc; i++) {
        if (raw_item(argv[i], pl, sizeof pl, &n) < 0) {
            err("raw: bad item \"%s\" (byte 32 or 0x20, float 150.0f, "
                "string '\"text\"'), or more than %u bytes",
                argv[i], WSG_PAYLOAD_MAX);
            return EXIT_USAGE;
        }
    }
    rc = xact(x, (uint8_t)id, pl, n, &r, print_reply);
    if (rc)
        return rc;
    print_reply(&x->o, &r);
    return r.status == WSG_E_SUCCESS ? EXIT_OK : gripper_error(r.id, r.status);
}

/* ---- watch ---- */

static void print_stamp(const struct opts *o)
{
    struct timespec ts;
    struct tm tm;
    char buf[32];

    clock_gettime(CLOCK_REALTIME, &ts);
    if (o->quiet) {
        printf("%lld.%03ld ", (long long)ts.tv_sec, ts.tv_nsec / 1000000);
        return;
    }
    localtime_r(&ts.tv_sec, &tm);
    strftime(buf, sizeof buf, "%H:%M:%S", &tm);
    printf("%s.%03ld ", buf, ts.tv_nsec / 1000000);
}

static int c_watch(struct ctx *x, int argc, char **argv)
{
    static const struct {
        const char *name;
        uint8_t id;
    } what[] = {{"width", WSG_CMD_GET_WIDTH},
                {"speed", WSG_CMD_GET_SPEED},
                {"force", WSG_CMD_GET_FORCE},
                {"state", WSG_CMD_GET_SYSTEM_STATE},
                {"grasp", WSG_CMD_GET_GRASP_STATE}};
    unsigned long period = 100;
    uint8_t id = 0, pl[3];
    long got = 0;
    int rc = EXIT_OK;
    struct wsg_client_frame r;

    for (size_t i = 0; i < sizeof what / sizeof what[0]; i++)
        if (!strcmp(argv[0], what[i].name))
            id = what[i].id;
    if (!id) {
        err("watch: width, speed, force, state or grasp, not \"%s\"", argv[0]);
        return EXIT_USAGE;
    }
    if (argc == 2 && parse_ulong(argv[1], 65535, &period) < 0) {
        err("watch: PERIOD_MS is 0..65535, not \"%s\"", argv[1]);
        return EXIT_USAGE;
    }
    pl[0] = 1; /* auto update, always (not change-only) */
    wsg_put_u16(pl + 1, (uint16_t)period);
    rc = conn_send(&x->c, id, pl, 3);
    if (rc < 0)
        return -rc;
    /* No value for longer than this: the stream is gone. */
    int gap = (int)(x->o.timeout_s * 1000.0) + (int)period;
    uint64_t deadline = wsg_client_deadline(gap);
    rc = EXIT_OK;
    while (x->o.count == 0 || got < x->o.count) {
        int n = conn_recv(&x->c, &r, deadline);
        if (n == -2)
            break; /* SIGINT: unsubscribe below, exit 0 */
        if (n != 1) {
            rc = recv_fail(n, id, &x->o);
            break;
        }
        if (r.id != id)
            continue;
        if (r.status != WSG_E_SUCCESS) {
            rc = gripper_error(id, r.status);
            break;
        }
        deadline = wsg_client_deadline(gap);
        print_stamp(&x->o);
        print_values(&x->o, "", id, WSG_CLIENT_PARAMS(&r),
                     WSG_CLIENT_NPARAMS(&r));
        fflush(stdout);
        got++;
    }
    /* Unsubscribe (FLAGS 0, PERIOD 0): a UDP or serial session would go on
     * streaming after we are gone. Its answer is the value once more. */
    interrupted = 0;
    memset(pl, 0, sizeof pl);
    if (conn_send(&x->c, id, pl, 3) == 0) {
        uint64_t until = wsg_client_deadline(1000);
        while (conn_recv(&x->c, &r, until) == 1) {
            if (r.id == id && r.len >= 2 &&
                wsg_layout_fits(&wsg_schema[id].reply, r.len - 2u)) {
                /* Drain what was in flight before the answer. */
                until = wsg_client_deadline(50);
            }
        }
    }
    return rc;
}

/* ---- decode ---- */

/* Hex bytes from text: tokens separated by whitespace or commas, each
 * optionally "0x"-prefixed or "h"-suffixed; a token of several byte pairs
 * ("AAAAAA20") is split. Returns the count, or -1 on a bad token. */
static long read_hex(FILE *in, uint8_t *buf, size_t cap)
{
    char tok[1024];
    size_t n = 0, tl = 0;
    int ch;

    do {
        ch = fgetc(in);
        if (ch != EOF && ch != ',' && ch != ' ' && ch != '\t' && ch != '\n' &&
            ch != '\r' && ch != ';') {
            if (tl + 1 >= sizeof tok)
                return -1;
            tok[tl++] = (char)ch;
            continue;
        }
        if (tl == 0)
            continue;
        tok[tl] = '\0';
        char *t = tok;
        if (t[0] == '0' && (t[1] == 'x' || t[1] == 'X'))
            t += 2;
        size_t len = strlen(t);
        if (len && (t[len - 1] == 'h' || t[len - 1] == 'H'))
            t[--len] = '\0';
        if (len == 1) {
            t[1] = t[0];
            t[0] = '0';
            t[2] = '\0';
            len = 2;
        }
        if (len == 0 || len % 2)
            return -1;
        for (size_t i = 0; i < len; i += 2) {
            char pair[3] = {t[i], t[i + 1], '\0'};
            char *end;
            unsigned long v = strtoul(pair, &end, 16);
            if (*end != '\0' || pair[0] == '+' || pair[0] == '-' || n >= cap)
                return -1;
            buf[n++] = (uint8_t)v;
        }
        tl = 0;
    } while (ch != EOF);
    return (long)n;
}

/* The payload leads with a status the manual names. */
static int leads_with_status(const uint8_t *payload, size_t size)
{
    return size >= 2 &&
           strcmp(wsg_status_name(wsg_get_u16(payload)), "E_UNKNOWN") != 0;
}

/* Could this payload be a reply to ID? A status the manual names first;
 * with E_SUCCESS, the parameters that ID returns. */
static int reply_fits(uint8_t id, const uint8_t *payload, size_t size)
{
    if (!leads_with_status(payload, size))
        return 0;
    if (wsg_get_u16(payload) != WSG_E_SUCCESS)
        return size == 2;
    return wsg_cmd_name(id) != NULL &&
           wsg_layout_fits(&wsg_schema[id].reply, size - 2u);
}

/* "request", "reply", or both where the bytes fit either (a Loop, a
 * Set Device Tag of two bytes); by the length rules of the command table
 * and the reply shapes of the manual. */
static const char *direction(uint8_t id, const uint8_t *payload, size_t size)
{
    int req = wsg_cmd_request_fits(id, size);
    int rep = reply_fits(id, payload, size);

    if (req && rep)
        return "request or reply";
    if (rep)
        return "reply";
    if (req)
        return "request";
    /* Neither: a request the gripper refuses by its length (or an ID it
     * does not know), unless it leads with a status. */
    return leads_with_status(payload, size)
               ? "reply (unexpected length)"
               : "request (refused by its length or ID)";
}

static int c_decode(struct ctx *x, int argc, char **argv)
{
    const size_t cap = 1u << 20; /* 1 MiB of packets is plenty */
    uint8_t *buf = malloc(cap);
    long total;
    size_t i = 0, packets = 0;
    int bad = 0;

    (void)argc;
    (void)argv;
    if (!buf) {
        err("decode: out of memory");
        return EXIT_CONN;
    }
    total = read_hex(stdin, buf, cap);
    if (total < 0) {
        err("decode: input is not hex bytes (or over 1 MiB)");
        free(buf);
        return EXIT_USAGE;
    }
    while (i < (size_t)total) {
        /* Hunt for the preamble; a longer run of AA extends it. */
        if (i + 3 > (size_t)total || buf[i] != 0xAA || buf[i + 1] != 0xAA ||
            buf[i + 2] != 0xAA) {
            size_t skip = i;
            while (i < (size_t)total &&
                   !(i + 3 <= (size_t)total && buf[i] == 0xAA &&
                     buf[i + 1] == 0xAA && buf[i + 2] == 0xAA))
                i++;
            printf("skipped %zu bytes before a preamble\n", i - skip);
            bad = 1;
            continue;
        }
        size_t start = i;
        i += 3;
        while (i < (size_t)total && buf[i] == 0xAA)
            i++;
        /* Let the CRC run over a three-byte preamble, as sent. */
        start = i - 3;
        if (i + 3 > (size_t)total) {
            printf("incomplete packet at the end (%zu bytes)\n",
                   (size_t)total - start);
            bad = 1;
            break;
        }
        uint8_t id = buf[i];
        uint16_t size = wsg_get_u16(buf + i + 1);
        size_t end = i + 3 + size + 2;
        if (end > (size_t)total) {
            printf("%02Xh %s SIZE %u: incomplete (%zu of %zu bytes)\n", id,
                   cmd_name(id), size, (size_t)total - start, end - start);
            bad = 1;
            break;
        }
        const uint8_t *payload = buf + i + 3;
        int ok = wsg_crc_update(WSG_CRC_INIT, buf + start, end - start) == 0;
        const char *dir = direction(id, payload, size);
        int is_reply = strncmp(dir, "reply", 5) == 0;
        packets++;
        printf("%s %02Xh %s SIZE %u", dir, id, cmd_name(id), size);
        if (strcmp(dir, "request") != 0 && leads_with_status(payload, size))
            printf(" status %s", wsg_status_name(wsg_get_u16(payload)));
        printf(" payload%s", size ? " " : "");
        print_hex(payload, size);
        printf(" checksum %02X %02X %s\n", buf[end - 2], buf[end - 1],
               ok ? "ok" : "bad");
        if (!ok)
            bad = 1;
        /* A reply's success: its values too, indented. */
        if (ok && is_reply && wsg_get_u16(payload) == WSG_E_SUCCESS &&
            size > 2) {
            struct opts o = x->o;
            o.quiet = 0;
            if (!print_values(&o, "  ", id, payload + 2, size - 2u))
                printf("  (no decoded values)\n");
        }
        i = end;
    }
    free(buf);
    if (packets == 0 && !bad) {
        printf("no packets\n");
        bad = 1;
    }
    return bad ? EXIT_GRIPPER : EXIT_OK;
}

/* ---- the command table and main ---- */

struct command {
    const char *name;
    int (*run)(struct ctx *x, int argc, char **argv);
    int min, max;     /* positional arguments */
    int conn;         /* needs the link */
    const char *args; /* for usage */
    const char *what;
    const char *example;
};

static const struct command commands[] = {
    {"home", c_home, 0, 1, 1, "[pos|neg]",
     "Homing (20h); default direction from the gripper's configuration",
     "wsgctl home pos"},
    {"move", c_move, 2, 2, 1, "WIDTH SPEED [--relative] [--stop-on-block]",
     "Preposition (21h): width in mm, speed in mm/s", "wsgctl move 40 100"},
    {"grasp", c_grasp, 2, 2, 1, "WIDTH SPEED",
     "Grasp Part (25h); no part found: E_CMD_FAILED, exit 1",
     "wsgctl grasp 30 50"},
    {"release", c_release, 2, 2, 1, "WIDTH SPEED",
     "Release Part (26h): open to WIDTH", "wsgctl release 60 50"},
    {"stop", c_stop, 0, 0, 1, "", "Stop (22h)", "wsgctl stop"},
    {"fast-stop", c_fast_stop, 0, 0, 1, "", "Issue FAST STOP (23h)",
     "wsgctl fast-stop"},
    {"ack", c_ack, 0, 0, 1, "", "Acknowledge FAST STOP or fault (24h)",
     "wsgctl ack"},
    {"info", c_info, 0, 0, 1, "", "Get System Information (50h)",
     "wsgctl info"},
    {"limits", c_limits, 0, 0, 1, "", "Get System Limits (53h)",
     "wsgctl limits"},
    {"state", c_state, 0, 0, 1, "",
     "system state flags by name (40h), then grasping state (41h)",
     "wsgctl state"},
    {"width", c_width, 0, 0, 1, "", "Get Opening Width (43h), mm",
     "wsgctl -q width"},
    {"speed", c_speed, 0, 0, 1, "", "Get Speed (44h), mm/s", "wsgctl speed"},
    {"force", c_force, 0, 0, 1, "", "Get Force (45h), N", "wsgctl force"},
    {"temperature", c_temperature, 0, 0, 1, "", "Get Temperature (46h), degC",
     "wsgctl temperature"},
    {"tag", c_tag, 0, 1, 1, "[TEXT]",
     "Get Device Tag (52h; \"none\" if unset), or set it (51h; \"\" "
     "removes it)",
     "wsgctl tag lab-2"},
    {"acc", c_acc, 0, 1, 1, "[VALUE]",
     "Get (31h) or set (30h) the acceleration, mm/s2", "wsgctl acc 500"},
    {"force-limit", c_force_limit, 0, 1, 1, "[VALUE]",
     "Get (33h) or set (32h) the force limit, N", "wsgctl force-limit 20"},
    {"soft-limits", c_soft_limits, 0, 2, 1, "[MINUS PLUS | clear]",
     "Get (35h; \"none\" if unset), set (34h) or clear (36h), mm",
     "wsgctl soft-limits 5 100"},
    {"overdrive", c_overdrive, 1, 1, 1, "on|off", "Overdrive Mode (37h)",
     "wsgctl overdrive on"},
    {"stats", c_stats, 0, 0, 1, "[--reset]",
     "Get Grasping Statistics (42h): total, no part, lost part",
     "wsgctl stats --reset"},
    {"loop", c_loop, 1, 1, 1, "TEXT", "Loop (06h): prints the echo",
     "wsgctl loop hello"},
    {"tare", c_tare, 0, 0, 1, "", "Tare Force Sensor (38h)", "wsgctl tare"},
    {"bye", c_bye, 0, 0, 1, "",
     "Disconnect Announcement (07h); over UDP/serial E_NOT_AVAILABLE",
     "wsgctl bye"},
    {"watch", c_watch, 1, 2, 1,
     "width|speed|force|state|grasp [PERIOD_MS] [--count N]",
     "auto-update (FLAGS 1, default 100 ms): one timestamped value per "
     "line until SIGINT or N values, then unsubscribes (FLAGS 0)",
     "wsgctl watch width 50 --count 10"},
    {"raw", c_raw, 1, 1 + WSG_PAYLOAD_MAX, 1, "ID [ITEMS...]",
     "send a packet; items as in WSG Commander's command editor: bytes "
     "(32, 0x20), floats (150.0f), strings in double quotes inside one "
     "argument ('\"text\"'; a bare word is refused); prints the answer",
     "wsgctl raw 0x21 0x00 40.0f 100.0f"},
    {"decode", c_decode, 0, 0, 0, "",
     "decode hex packets from stdin (spaces, commas, 0x, h suffix; "
     "any line split); exit 1 if a checksum is bad or a packet incomplete",
     "echo 'AA AA AA 20 02 00 00 00 B3 FD' | wsgctl decode"},
};
#define NCOMMANDS (sizeof commands / sizeof commands[0])

/* What --control can answer: readings the control channel's "state"
 * holds. */
static int control_readable(const struct command *cmd)
{
    return cmd->run == c_state || cmd->run == c_width || cmd->run == c_speed ||
           cmd->run == c_force || cmd->run == c_temperature ||
           cmd->run == c_stats;
}

/* A description, indented 6, in lines of at most 78 columns. */
static void print_wrapped(FILE *f, const char *s)
{
    while (*s) {
        size_t n = strlen(s), cut = n;
        if (n > 72) {
            cut = 72;
            while (cut > 0 && s[cut] != ' ')
                cut--;
            if (cut == 0)
                cut = 72;
        }
        fprintf(f, "      %.*s\n", (int)cut, s);
        s += cut;
        while (*s == ' ')
            s++;
    }
}

static void usage(FILE *f)
{
    fprintf(f,
            "usage: wsgctl [--tcp HOST:PORT | --udp HOST:PORT[:LOCAL] | "
            "--serial PATH |\n"
            "               --control HOST:PORT]\n"
            "              [--timeout S] [-q|--quiet] COMMAND [ARGS]\n"
            "\n"
            "Client of a WSG 50 gripper (or wsgemu), command set 2.2.0.\n"
            "\n"
            "Interfaces (default --tcp " DEFAULT_TCP "):\n"
            "  --tcp HOST:PORT        every close is announced with 07h, so "
            "wsgctl never\n"
            "                         puts the gripper into FAST STOP; but "
            "07h aborts a\n"
            "                         running motion (manual 3.1.2), "
            "another client's too\n"
            "  --udp HOST:PORT[:LOCAL]\n"
            "                         requests to PORT, answers received "
            "on LOCAL\n"
            "                         (default %u, the gripper's remote "
            "port)\n"
            "  --serial PATH          raw 115200 8N1\n"
            "  --control HOST:PORT    wsgemu's control channel: state, "
            "width, speed,\n"
            "                         force, temperature and stats read "
            "without touching\n"
            "                         the gripper (no 07h, no session): "
            "safe while another\n"
            "                         client moves it\n"
            "Options (anywhere; \"--\" ends them):\n"
            "  --timeout S            wait for an answer (through "
            "E_CMD_PENDING) up to S\n"
            "                         seconds, default 10\n"
            "  -q, --quiet            bare values for scripts, one answer "
            "a line: \"55.00\"\n"
            "                         instead of \"width 55.00 mm\"; flags "
            "in hex, enums as\n"
            "                         numbers\n"
            "  -h, --help             this text\n"
            "  -V, --version          wsgctl's version\n"
            "\nCommands:\n",
            DEFAULT_UDP_PORT);
    for (size_t i = 0; i < NCOMMANDS; i++) {
        fprintf(f, "  %s%s%s\n", commands[i].name,
                commands[i].args[0] ? " " : "", commands[i].args);
        print_wrapped(f, commands[i].what);
        fprintf(f, "      e.g. %s\n", commands[i].example);
    }
    fprintf(f, "\nOutput: values with the manual's field names and their "
               "units, one per\n"
               "line (\"width 55.00 mm\", \"grasp-state 4 (HOLDING)\"); "
               "commands that only act\n"
               "print nothing on success. watch prefixes each value with "
               "the local time\n"
               "(HH:MM:SS.mmm; with -q, Unix seconds.mmm). raw prints "
               "\"ID Name: STATUS\" and\n"
               "\"params (N): hex bytes\" for each answer (E_CMD_PENDING "
               "too), then the\n"
               "decoded values of known IDs. Errors go to stderr with the "
               "manual's names\n"
               "(\"wsgctl: 25h Grasp: E_CMD_FAILED\").\n"
               "\nExit status: 0 E_SUCCESS; 1 the gripper answered another "
               "status (decode:\n"
               "a bad checksum or incomplete packet); 2 usage error; 3 "
               "cannot connect,\n"
               "I/O error or no answer within --timeout; 130 interrupted "
               "(watch: 0).\n");
}

int main(int argc, char **argv)
{
    struct ctx x;
    char *pos[2 + WSG_PAYLOAD_MAX];
    int npos = 0, opts_done = 0, rc;
    const struct command *cmd = NULL;

    memset(&x, 0, sizeof x);
    x.o.kind = LINK_TCP;
    x.o.addr = DEFAULT_TCP;
    x.o.timeout_s = 10.0;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        const char *val = i + 1 < argc ? argv[i + 1] : NULL;
        double d;

        if (opts_done || a[0] != '-' || a[1] == '\0' ||
            (a[1] != '-' && a[1] != 'q' && a[1] != 'h' && a[1] != 'V')) {
            /* Negative numbers ("-5") are arguments, not options. */
            if (npos >= (int)(sizeof pos / sizeof pos[0])) {
                err("too many arguments");
                return EXIT_USAGE;
            }
            pos[npos++] = argv[i];
            continue;
        }
        if (!strcmp(a, "--")) {
            opts_done = 1;
        } else if (!strcmp(a, "-h") || !strcmp(a, "--help")) {
            usage(stdout);
            return EXIT_OK;
        } else if (!strcmp(a, "-V") || !strcmp(a, "--version")) {
            printf("wsgctl %s\n", WSG_VERSION);
            return EXIT_OK;
        } else if (!strcmp(a, "-q") || !strcmp(a, "--quiet")) {
            x.o.quiet = 1;
        } else if (!strcmp(a, "--relative")) {
            x.o.relative = 1;
        } else if (!strcmp(a, "--stop-on-block")) {
            x.o.stop_on_block = 1;
        } else if (!strcmp(a, "--reset")) {
            x.o.reset = 1;
        } else if (strcmp(a, "--tcp") && strcmp(a, "--udp") &&
                   strcmp(a, "--serial") && strcmp(a, "--control") &&
                   strcmp(a, "--timeout") && strcmp(a, "--count")) {
            err("unknown option %s (see --help)", a);
            return EXIT_USAGE;
        } else if (!val) {
            err("%s needs a value (see --help)", a);
            return EXIT_USAGE;
        } else if (!strcmp(a, "--tcp") || !strcmp(a, "--udp") ||
                   !strcmp(a, "--serial") || !strcmp(a, "--control")) {
            x.o.kind = a[2] == 't'   ? LINK_TCP
                       : a[2] == 'u' ? LINK_UDP
                       : a[2] == 's' ? LINK_SERIAL
                                     : LINK_CONTROL;
            x.o.addr = val;
            i++;
        } else if (!strcmp(a, "--timeout")) {
            if (parse_double(val, &d) < 0 || d <= 0 || d > 86400) {
                err("--timeout: seconds, not \"%s\"", val);
                return EXIT_USAGE;
            }
            x.o.timeout_s = d;
            i++;
        } else if (!strcmp(a, "--count")) {
            unsigned long n;
            if (parse_ulong(val, 1000000000ul, &n) < 0 || n == 0) {
                err("--count: a positive number, not \"%s\"", val);
                return EXIT_USAGE;
            }
            x.o.count = (long)n;
            i++;
        } else {
            err("unknown option %s (see --help)", a);
            return EXIT_USAGE;
        }
    }
    if (npos == 0) {
        usage(stderr);
        return EXIT_USAGE;
    }
    for (size_t i = 0; i < NCOMMANDS; i++)
        if (!strcmp(pos[0], commands[i].name))
            cmd = &commands[i];
    if (!cmd) {
        err("unknown command \"%s\" (see --help)", pos[0]);
        return EXIT_USAGE;
    }
    if (npos - 1 < cmd->min || npos - 1 > cmd->max) {
        err("usage: wsgctl %s %s", cmd->name, cmd->args);
        return EXIT_USAGE;
    }
    if (x.o.kind == LINK_CONTROL && cmd->conn && !control_readable(cmd)) {
        err("--control reads only (state, width, speed, force, temperature, "
            "stats); %s needs the gripper's interface",
            cmd->name);
        return EXIT_USAGE;
    }

    /* A signal ends a wait, so the close can still be announced; without
     * SA_RESTART, so poll() returns at once. */
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGINT, &sa, NULL);
    sigaction(SIGTERM, &sa, NULL);
    signal(SIGPIPE, SIG_IGN);

    x.command = cmd->name;
    if (cmd->conn) {
        rc = conn_open(&x.c, &x.o);
        if (rc < 0) {
            conn_close(&x.c);
            return -rc;
        }
        x.have_conn = 1;
    }
    rc = cmd->run(&x, npos - 1, pos + 1);
    fflush(stdout);
    if (x.have_conn)
        conn_close(&x.c);
    if (cmd->run == c_watch && rc == EXIT_INTERRUPTED)
        rc = EXIT_OK;
    return rc;
}
