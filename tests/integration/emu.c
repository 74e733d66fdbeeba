/*
 * Client library of the integration tests (see emu.h): the daemon as a
 * child process, the TCP transport, and framing over any transport with the
 * core's wsg_parser.
 *
 * Daemons started here are registered and killed at exit, so a test that
 * stops early (REQUIRE) leaves no process behind; on Linux the child also
 * gets SIGKILL if the test process dies (ctest's timeout).
 */
#define _GNU_SOURCE /* prctl(PR_SET_PDEATHSIG) */

#include "emu.h"

#include <arpa/inet.h>
#include <errno.h>
#include <fcntl.h>
#include <netdb.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <signal.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>
#ifdef __linux__
#include <sys/prctl.h>
#endif

/* ---- time ---- */

double emu_now_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec * 1e3 + (double)ts.tv_nsec / 1e6;
}

void emu_sleep_ms(int ms)
{
    struct timespec ts;
    ts.tv_sec = ms / 1000;
    ts.tv_nsec = (long)(ms % 1000) * 1000000L;
    while (nanosleep(&ts, &ts) != 0 && errno == EINTR)
        ;
}

double emu_time_scale(void)
{
    static double scale; /* 0: not read yet */
    const char *s, *w;
    char *end;

    if (scale > 0)
        return scale;
    s = getenv("WSG_TEST_TIME_SCALE");
    if (s && *s) {
        double x = strtod(s, &end);
        /* Below 1 would shorten the bounds the tests were written with. */
        if (*end != '\0' || !(x >= 1.0 && x <= 1000.0)) {
            fprintf(stderr,
                    "emu: WSG_TEST_TIME_SCALE=\"%s\": a number from 1 to "
                    "1000\n",
                    s);
            exit(2);
        }
        scale = x;
    } else {
        /* valgrind runs the daemon some 20-50 times slower; what the tests
         * wait for mostly waits on I/O, so 10 is enough (memcheck.sh). */
        w = getenv("WSG_TEST_WRAPPER");
        scale = w && strstr(w, "valgrind") ? 10.0 : 1.0;
    }
    return scale;
}

int emu_ms(int ms)
{
    return (int)(ms * emu_time_scale() + 0.5);
}

/* Milliseconds left until deadline, never negative. */
static int remaining_ms(double deadline)
{
    double left = deadline - emu_now_ms();
    return left > 0 ? (int)(left + 0.999) : 0;
}

/* ---- children: registered for the exit handler ---- */

#define MAX_CHILDREN 16
static pid_t children[MAX_CHILDREN];
static int cleanup_registered;

static void kill_children(void)
{
    for (int i = 0; i < MAX_CHILDREN; i++) {
        if (children[i] > 0) {
            kill(children[i], SIGKILL);
            waitpid(children[i], NULL, 0);
            children[i] = 0;
        }
    }
}

static void child_add(pid_t pid)
{
    if (!cleanup_registered) {
        atexit(kill_children);
        cleanup_registered = 1;
    }
    for (int i = 0; i < MAX_CHILDREN; i++) {
        if (children[i] == 0) {
            children[i] = pid;
            return;
        }
    }
}

static void child_remove(pid_t pid)
{
    for (int i = 0; i < MAX_CHILDREN; i++)
        if (children[i] == pid)
            children[i] = 0;
}

static void set_cloexec(int fd)
{
    fcntl(fd, F_SETFD, fcntl(fd, F_GETFD) | FD_CLOEXEC);
}

/* Fork and exec exe with args; the child's stdout (and stderr, if err_fd is
 * not NULL) go to fresh pipes. stdin is /dev/null. If WSG_TEST_WRAPPER is
 * set (e.g. "valgrind --error-exitcode=99 -q"), it is split on blanks and
 * the program runs under it: `WRAPPER... exe args...`, the wrapper looked up
 * in PATH. */
static pid_t spawn(const char *exe, const char *const *args, int *out_fd,
                   int *err_fd)
{
    int po[2], pe[2] = {-1, -1};
    char *argv[64];
    static char wrapper[512];
    const char *w = getenv("WSG_TEST_WRAPPER");
    int n = 0;

    if (w && *w) {
        snprintf(wrapper, sizeof wrapper, "%s", w);
        for (char *tok = strtok(wrapper, " \t"); tok && n < 32;
             tok = strtok(NULL, " \t"))
            argv[n++] = tok;
    }
    int first = n;
    argv[n++] = (char *)exe;
    for (int i = 0; args && args[i] && n < 63; i++)
        argv[n++] = (char *)args[i];
    argv[n] = NULL;

    if (pipe(po) != 0)
        return -1;
    if (err_fd && pipe(pe) != 0) {
        close(po[0]);
        close(po[1]);
        return -1;
    }
    fflush(NULL); /* the child must not flush our buffered output again */
    pid_t pid = fork();
    if (pid < 0) {
        close(po[0]);
        close(po[1]);
        if (err_fd) {
            close(pe[0]);
            close(pe[1]);
        }
        return -1;
    }
    if (pid == 0) {
#ifdef __linux__
        prctl(PR_SET_PDEATHSIG, SIGKILL);
#endif
        int devnull = open("/dev/null", O_RDONLY);
        if (devnull > 0) {
            dup2(devnull, 0);
            close(devnull);
        }
        dup2(po[1], 1);
        if (err_fd)
            dup2(pe[1], 2);
        /* Everything else is closed by exec (FD_CLOEXEC below) or is the
         * pipes' ends, closed here. */
        close(po[0]);
        close(po[1]);
        if (err_fd) {
            close(pe[0]);
            close(pe[1]);
        }
        signal(SIGPIPE, SIG_DFL);
        if (first > 0)
            execvp(argv[0], argv);
        else
            execv(exe, argv);
        fprintf(stderr, "emu: exec %s: %s\n", argv[0], strerror(errno));
        _exit(127);
    }
    child_add(pid);
    close(po[1]);
    set_cloexec(po[0]);
    *out_fd = po[0];
    if (err_fd) {
        close(pe[1]);
        set_cloexec(pe[0]);
        *err_fd = pe[0];
    }
    return pid;
}

static int status_code(int st)
{
    if (WIFEXITED(st))
        return WEXITSTATUS(st);
    if (WIFSIGNALED(st))
        return 128 + WTERMSIG(st);
    return -1;
}

/* Reap pid within timeout_ms; -1 (and SIGKILL) if it is still running. */
static int reap(pid_t pid, int timeout_ms)
{
    double deadline = emu_now_ms() + timeout_ms;
    int st;
    for (;;) {
        pid_t r = waitpid(pid, &st, WNOHANG);
        if (r == pid) {
            child_remove(pid);
            return status_code(st);
        }
        if (r < 0 && errno != EINTR) {
            child_remove(pid);
            return -1;
        }
        if (emu_now_ms() >= deadline) {
            kill(pid, SIGKILL);
            waitpid(pid, NULL, 0);
            child_remove(pid);
            return -1;
        }
        emu_sleep_ms(5);
    }
}

static int start(struct emu *e, const char *exe, const char *const *args);

int emu_start(struct emu *e, const char *exe, const char *const *args)
{
    memset(e, 0, sizeof(*e));
    e->tp_fd = -1;
    return start(e, exe, args);
}

int emu_start_tp(struct emu *e, const char *exe,
                 const struct emu_transport *tp, const char *const *extra)
{
    const char *args[32];
    size_t n = 0;
    int r;

    memset(e, 0, sizeof(*e));
    e->tp_fd = -1;
    if (tp->daemon_args) {
        r = tp->daemon_args(e);
        if (r == 77)
            exit(77);
        if (r != 0)
            return -1;
    } else {
        snprintf(e->tp_arg[0], sizeof e->tp_arg[0], "--%s", tp->field);
        e->tp_argv[0] = e->tp_arg[0];
        e->tp_argv[1] = "127.0.0.1:0";
    }
    for (r = 0; e->tp_argv[r] && n < 16; r++)
        args[n++] = e->tp_argv[r];
    for (r = 0; extra && extra[r] && n < 31; r++)
        args[n++] = extra[r];
    args[n] = NULL;
    return start(e, exe, args);
}

const struct emu_transport *emu_transport_arg(int argc, char **argv)
{
    const char *name = argc > 2 ? argv[2] : "tcp";
    int i;

    for (i = 0; emu_transports[i]; i++)
        if (strcmp(emu_transports[i]->field, name) == 0)
            return emu_transports[i];
    fprintf(stderr, "emu: unknown transport \"%s\"\n", name);
    exit(2);
}

int emu_spawn(struct emu *e, const char *exe, const char *const *args)
{
    memset(e, 0, sizeof(*e));
    e->tp_fd = -1;
    e->out_fd = -1;
    e->pid = spawn(exe, args, &e->out_fd, NULL);
    if (e->pid < 0) {
        fprintf(stderr, "emu: cannot start %s: %s\n", exe, strerror(errno));
        e->pid = 0;
        return -1;
    }
    return 0;
}

static int start(struct emu *e, const char *exe, const char *const *args)
{
    e->out_fd = -1;
    e->pid = spawn(exe, args, &e->out_fd, NULL);
    if (e->pid < 0) {
        fprintf(stderr, "emu: cannot start %s: %s\n", exe, strerror(errno));
        return -1;
    }
    return emu_ready(e);
}

int emu_ready(struct emu *e)
{
    /* Read until the first newline; bytes after it are kept in extra. */
    double deadline = emu_now_ms() + EMU_READY_MS;
    size_t n = 0;
    for (;;) {
        char *nl = memchr(e->line, '\n', n);
        if (nl) {
            size_t rest = n - (size_t)(nl - e->line) - 1;
            memcpy(e->extra, nl + 1, rest);
            e->extra_len = rest;
            *nl = '\0';
            return 0;
        }
        if (n >= sizeof(e->line) - 1) {
            fprintf(stderr, "emu: ready line too long\n");
            break;
        }
        struct pollfd pfd = {e->out_fd, POLLIN, 0};
        int left = remaining_ms(deadline);
        int r = poll(&pfd, 1, left);
        if (r < 0 && errno == EINTR)
            continue;
        if (r <= 0) {
            fprintf(stderr, "emu: no ready line within %d ms\n", EMU_READY_MS);
            break;
        }
        ssize_t got = read(e->out_fd, e->line + n, sizeof(e->line) - 1 - n);
        if (got < 0 && errno == EINTR)
            continue;
        if (got <= 0) {
            fprintf(stderr, "emu: stdout closed before the ready line\n");
            break;
        }
        n += (size_t)got;
    }
    e->line[n < sizeof(e->line) ? n : sizeof(e->line) - 1] = '\0';
    fprintf(stderr, "emu: stdout so far: \"%s\"\n", e->line);
    kill(e->pid, SIGKILL);
    fprintf(stderr, "emu: daemon status %d\n", reap(e->pid, EMU_EXIT_MS));
    close(e->out_fd);
    e->out_fd = -1;
    e->pid = 0;
    return -1;
}

/* Read what is left on stdout into extra until EOF or deadline. */
static void drain_stdout(struct emu *e, double deadline)
{
    while (e->out_fd >= 0) {
        struct pollfd pfd = {e->out_fd, POLLIN, 0};
        int r = poll(&pfd, 1, remaining_ms(deadline));
        if (r < 0 && errno == EINTR)
            continue;
        if (r <= 0)
            return;
        char buf[256];
        ssize_t got = read(e->out_fd, buf, sizeof(buf));
        if (got < 0 && errno == EINTR)
            continue;
        if (got <= 0)
            return;
        size_t room = sizeof(e->extra) - 1 - e->extra_len;
        size_t take = (size_t)got < room ? (size_t)got : room;
        memcpy(e->extra + e->extra_len, buf, take);
        e->extra_len += take;
    }
}

int emu_stop_sig(struct emu *e, int sig)
{
    if (e->tp_fd >= 0) {
        close(e->tp_fd);
        e->tp_fd = -1;
    }
    if (e->pid <= 0)
        return -1;
    kill(e->pid, sig);
    /* The daemon closes stdout when it exits: drain until then, so that a
     * daemon blocked on a full pipe cannot miss its deadline. */
    drain_stdout(e, emu_now_ms() + EMU_EXIT_MS);
    int st = reap(e->pid, EMU_EXIT_MS);
    if (st == -1)
        fprintf(stderr, "emu: daemon did not exit within %d ms of signal %d\n",
                EMU_EXIT_MS, sig);
    e->extra[e->extra_len] = '\0';
    if (e->out_fd >= 0)
        close(e->out_fd);
    e->out_fd = -1;
    e->pid = 0;
    return st;
}

int emu_stop(struct emu *e)
{
    return emu_stop_sig(e, SIGTERM);
}

const char *emu_field(const struct emu *e, const char *name, char *buf,
                      size_t cap)
{
    size_t nl = strlen(name);
    const char *p = e->line;
    while (*p) {
        const char *end = strchr(p, ' ');
        size_t tl = end ? (size_t)(end - p) : strlen(p);
        if (tl > nl && strncmp(p, name, nl) == 0 && p[nl] == '=') {
            size_t vl = tl - nl - 1;
            if (vl >= cap)
                return NULL;
            memcpy(buf, p + nl + 1, vl);
            buf[vl] = '\0';
            return buf;
        }
        if (!end)
            break;
        p = end + 1;
    }
    return NULL;
}

int emu_run(const char *exe, const char *const *args, int timeout_ms,
            char *out, size_t outcap, char *err, size_t errcap)
{
    int fds[2];
    char *bufs[2] = {out, err};
    size_t caps[2] = {outcap, errcap}, lens[2] = {0, 0};
    pid_t pid = spawn(exe, args, &fds[0], &fds[1]);
    if (pid < 0)
        return -1;
    double deadline = emu_now_ms() + timeout_ms;
    int open_fds = 2;
    while (open_fds > 0) {
        struct pollfd pfd[2];
        int np = 0, map[2];
        for (int i = 0; i < 2; i++) {
            if (fds[i] >= 0) {
                pfd[np].fd = fds[i];
                pfd[np].events = POLLIN;
                pfd[np].revents = 0;
                map[np++] = i;
            }
        }
        int r = poll(pfd, (nfds_t)np, remaining_ms(deadline));
        if (r < 0 && errno == EINTR)
            continue;
        if (r <= 0)
            break; /* timeout: reap() below kills it */
        for (int k = 0; k < np; k++) {
            if (!pfd[k].revents)
                continue;
            int i = map[k];
            char tmp[512];
            ssize_t got = read(fds[i], tmp, sizeof(tmp));
            if (got < 0 && errno == EINTR)
                continue;
            if (got <= 0) {
                close(fds[i]);
                fds[i] = -1;
                open_fds--;
                continue;
            }
            size_t room = caps[i] > lens[i] + 1 ? caps[i] - lens[i] - 1 : 0;
            size_t take = (size_t)got < room ? (size_t)got : room;
            if (take) /* a stream not kept has no buffer (NULL) */
                memcpy(bufs[i] + lens[i], tmp, take);
            lens[i] += take;
        }
    }
    for (int i = 0; i < 2; i++) {
        if (fds[i] >= 0)
            close(fds[i]);
        if (caps[i])
            bufs[i][lens[i]] = '\0';
    }
    return reap(pid, remaining_ms(deadline) + 100);
}

const char *emu_exe(int argc, char **argv)
{
    if (argc < 2 || access(argv[1], X_OK) != 0) {
        printf("SKIP: no daemon executable given (argv[1])\n");
        exit(77);
    }
    /* Line by line, so that progress and CHECK messages (stderr) come out
     * interleaved in order in ctest's log. */
    setvbuf(stdout, NULL, _IOLBF, 0);
    /* A write to a connection the daemon has reset must fail with EPIPE,
     * not kill the test. */
    signal(SIGPIPE, SIG_IGN);
    return argv[1];
}

/* ---- frames ---- */

int emu_packet_decode(const uint8_t *buf, size_t n, struct wsg_client_frame *f)
{
    if (n < WSG_HEADER_LEN + WSG_CRC_LEN)
        return -1;
    if (buf[0] != WSG_PREAMBLE_BYTE || buf[1] != WSG_PREAMBLE_BYTE ||
        buf[2] != WSG_PREAMBLE_BYTE)
        return -1;
    size_t size = wsg_get_u16(buf + 4);
    if (size > WSG_REPLY_PAYLOAD_MAX ||
        n != WSG_HEADER_LEN + size + WSG_CRC_LEN)
        return -1;
    if (wsg_crc_update(WSG_CRC_INIT, buf, n) != 0)
        return -1;
    wsg_client_frame_set(f, buf[3], buf + WSG_HEADER_LEN, size);
    return 0;
}

/* ---- TCP ---- */

/* "host:port", host possibly in brackets (IPv6). */
static int split_addr(const char *addr, char *host, size_t hcap, char *port,
                      size_t pcap)
{
    const char *colon = strrchr(addr, ':');
    if (!colon)
        return -1;
    const char *h = addr;
    size_t hl = (size_t)(colon - addr);
    if (hl >= 2 && h[0] == '[' && h[hl - 1] == ']') {
        h++;
        hl -= 2;
    }
    if (hl == 0 || hl >= hcap || strlen(colon + 1) >= pcap)
        return -1;
    memcpy(host, h, hl);
    host[hl] = '\0';
    strcpy(port, colon + 1);
    return 0;
}

int emu_ipv4_addr(const char *addr, struct sockaddr_in *sa)
{
    char host[128], port[16];

    if (split_addr(addr, host, sizeof host, port, sizeof port) != 0)
        return -1;
    memset(sa, 0, sizeof *sa);
    sa->sin_family = AF_INET;
    sa->sin_port = htons((uint16_t)atoi(port));
    return inet_pton(AF_INET, host, &sa->sin_addr) == 1 ? 0 : -1;
}

static int tcp_open(struct emu_client *c, const char *addr)
{
    char host[128], port[16];
    struct addrinfo hints, *res, *ai;
    if (split_addr(addr, host, sizeof(host), port, sizeof(port)) != 0) {
        fprintf(stderr, "emu: bad tcp address \"%s\"\n", addr);
        return -1;
    }
    memset(&hints, 0, sizeof(hints));
    hints.ai_family = AF_UNSPEC;
    hints.ai_socktype = SOCK_STREAM;
    hints.ai_flags = AI_NUMERICHOST | AI_NUMERICSERV;
    if (getaddrinfo(host, port, &hints, &res) != 0) {
        fprintf(stderr, "emu: cannot resolve \"%s\"\n", addr);
        return -1;
    }
    c->fd = -1;
    for (ai = res; ai; ai = ai->ai_next) {
        int fd = socket(ai->ai_family, ai->ai_socktype, ai->ai_protocol);
        if (fd < 0)
            continue;
        if (connect(fd, ai->ai_addr, ai->ai_addrlen) == 0) {
            int one = 1;
            /* Like the drivers: each request leaves at once. */
            setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof(one));
            set_cloexec(fd);
            c->fd = fd;
            break;
        }
        close(fd);
    }
    freeaddrinfo(res);
    if (c->fd < 0) {
        fprintf(stderr, "emu: connect %s: %s\n", addr, strerror(errno));
        return -1;
    }
    return 0;
}

static int tcp_send(struct emu_client *c, const uint8_t *pkt, size_t len)
{
    while (len > 0) {
        ssize_t n = send(c->fd, pkt, len, MSG_NOSIGNAL);
        if (n < 0 && errno == EINTR)
            continue;
        if (n <= 0)
            return -1;
        pkt += n;
        len -= (size_t)n;
    }
    return 0;
}

static long tcp_recv(struct emu_client *c, uint8_t *buf, size_t cap,
                     int timeout_ms)
{
    double deadline = emu_now_ms() + timeout_ms;
    for (;;) {
        struct pollfd pfd = {c->fd, POLLIN, 0};
        int r = poll(&pfd, 1, remaining_ms(deadline));
        if (r < 0 && errno == EINTR)
            continue;
        if (r < 0)
            return -2;
        if (r == 0)
            return -1;
        ssize_t n = recv(c->fd, buf, cap, 0);
        if (n < 0 && errno == EINTR)
            continue;
        if (n < 0)
            return errno == ECONNRESET ? 0 : -2;
        return (long)n;
    }
}

static void tcp_close(struct emu_client *c, int abort)
{
    if (abort) {
        /* Linger 0: the close sends a reset instead of a FIN. */
        struct linger lg = {1, 0};
        setsockopt(c->fd, SOL_SOCKET, SO_LINGER, &lg, sizeof(lg));
    }
    close(c->fd);
}

const struct emu_transport emu_tcp = {
    .field = "tcp",
    .open = tcp_open,
    .send = tcp_send,
    .recv = tcp_recv,
    .close = tcp_close,
    .connection = 1,
};

const struct emu_transport *const emu_transports[] = {
    &emu_tcp, &emu_udp, &emu_can, &emu_pty, NULL};

/* ---- clients ---- */

/* The transport as the client library's hooks. */
static long hook_read(void *ctx, uint8_t *buf, size_t cap, int timeout_ms)
{
    struct emu_client *c = ctx;

    return c->fd < 0 ? -2 : c->tp->recv(c, buf, cap, timeout_ms);
}

static int hook_send(void *ctx, const uint8_t *pkt, size_t len)
{
    return emu_send_raw(ctx, pkt, len);
}

/* A malformed packet is said and counted (link.bad), and skipped. */
static int report_bad(struct wsg_client *l, enum wsg_parse_event ev,
                      uint8_t id)
{
    (void)l;
    fprintf(stderr, "emu: received a %s packet, ID %02Xh\n",
            ev == WSG_PARSE_BAD_CRC ? "bad-checksum" : "oversize",
            (unsigned)id);
    return 0;
}

int emu_open_nth(struct emu_client *c, struct emu *e,
                 const struct emu_transport *tp, unsigned n)
{
    char addr[1024];
    char *p, *comma;

    memset(c, 0, offsetof(struct emu_client, link));
    c->fd = -1;
    c->fd2 = -1;
    c->tp = tp;
    c->emu = e;
    c->sync_token = 0;
    wsg_client_init(&c->link, WSG_LINK_HOOKS);
    c->link.hooks.read = hook_read;
    c->link.hooks.send = hook_send;
    c->link.hooks.ctx = c;
    c->link.on_bad = report_bad;
    wsg_client_keep(&c->link, c->keep, EMU_KEEP);
    if (!emu_field(e, tp->field, addr, sizeof(addr))) {
        fprintf(stderr, "emu: no %s= in the ready line \"%s\"\n", tp->field,
                e->line);
        return -1;
    }
    /* A fleet lists one value per gripper, comma-separated. */
    for (p = addr; n > 0; n--) {
        p = strchr(p, ',');
        if (!p) {
            fprintf(stderr, "emu: %s= has too few values in \"%s\"\n",
                    tp->field, e->line);
            return -1;
        }
        p++;
    }
    comma = strchr(p, ',');
    if (comma)
        *comma = '\0';
    return tp->open(c, p);
}

int emu_open(struct emu_client *c, struct emu *e,
             const struct emu_transport *tp)
{
    return emu_open_nth(c, e, tp, 0);
}

/* Closed: what is buffered or kept can still be read, nothing more. */
void emu_close(struct emu_client *c)
{
    if (c->fd >= 0)
        c->tp->close(c, 0);
    c->fd = -1;
    c->link.eof = 1;
}

void emu_abort(struct emu_client *c)
{
    if (c->fd >= 0)
        c->tp->close(c, 1);
    c->fd = -1;
    c->link.eof = 1;
}

int emu_send_raw(struct emu_client *c, const void *pkt, size_t len)
{
    if (c->fd < 0)
        return -1;
    return c->tp->send(c, pkt, len);
}

int emu_send(struct emu_client *c, uint8_t id, const void *payload, size_t len)
{
    /* Larger than any reply: tests send what the daemon must refuse. */
    uint8_t pkt[WSG_HEADER_LEN + 1024 + WSG_CRC_LEN];
    size_t n = wsg_frame_encode(pkt, sizeof(pkt), id, payload, len);
    if (n == 0) {
        fprintf(stderr, "emu: cannot encode %zu bytes for %02Xh\n", len,
                (unsigned)id);
        return -1;
    }
    return emu_send_raw(c, pkt, n);
}

long emu_recv_raw(struct emu_client *c, uint8_t *buf, size_t cap,
                  int timeout_ms)
{
    if (c->fd < 0)
        return -2;
    return c->tp->recv(c, buf, cap, timeout_ms);
}

void emu_drop_kept(struct emu_client *c)
{
    c->link.keep_n = 0;
}

/* The library's 1 / 0 / -errno as this file's 1 / 0 / -1. */
static int got(int r)
{
    return r < 0 ? -1 : r;
}

int emu_recv(struct emu_client *c, struct wsg_client_frame *f, int timeout_ms)
{
    return got(wsg_client_recv(&c->link, f, wsg_client_deadline(timeout_ms)));
}

int emu_recv_id(struct emu_client *c, uint8_t id, struct wsg_client_frame *f,
                int timeout_ms)
{
    return got(
        wsg_client_recv_id(&c->link, id, f, wsg_client_deadline(timeout_ms)));
}

int emu_request(struct emu_client *c, uint8_t id, const void *payload,
                size_t len, struct wsg_client_frame *f, int timeout_ms)
{
    struct wsg_client_frame tmp;
    if (!f)
        f = &tmp;
    if (emu_send(c, id, payload, len) != 0)
        return -1;
    if (emu_recv_id(c, id, f, timeout_ms) != 1)
        return -1;
    return (int)f->status;
}

int emu_sync(struct emu_client *c, int timeout_ms)
{
    uint64_t deadline = wsg_client_deadline(timeout_ms);
    uint8_t tok[6] = {'s', 'y', 'n', 'c', 0, 0};
    struct wsg_client_frame f;
    c->sync_token++;
    wsg_put_u16(tok + 4, c->sync_token);
    if (emu_send(c, WSG_CMD_LOOP, tok, sizeof(tok)) != 0)
        return -1;
    for (;;) {
        if (wsg_client_recv_id(&c->link, WSG_CMD_LOOP, &f, deadline) != 1)
            return -1;
        if (f.status == WSG_E_SUCCESS && f.len == 2 + sizeof(tok) &&
            memcmp(EMU_PARAMS(&f), tok, sizeof(tok)) == 0)
            return 0;
    }
}

/* ---- gripper helpers ---- */

int emu_get_flags(struct emu_client *c, uint32_t *flags)
{
    struct wsg_client_frame f;
    if (emu_request(c, WSG_CMD_GET_SYSTEM_STATE, NULL, 0, &f, EMU_REPLY_MS) !=
            WSG_E_SUCCESS ||
        f.len != 6)
        return -1;
    *flags = wsg_get_u32(EMU_PARAMS(&f));
    return 0;
}

long emu_slurp(const char *path, char *buf, size_t cap)
{
    FILE *f = fopen(path, "r");
    size_t n;

    if (!f)
        return -1;
    n = fread(buf, 1, cap - 1, f);
    buf[n] = '\0';
    fclose(f);
    return (long)n;
}

int emu_get_grasp_state(struct emu_client *c)
{
    struct wsg_client_frame f;

    if (emu_request(c, WSG_CMD_GET_GRASP_STATE, NULL, 0, &f, EMU_REPLY_MS) !=
            WSG_E_SUCCESS ||
        EMU_NPARAMS(&f) < 1)
        return -1;
    return EMU_PARAMS(&f)[0];
}

int emu_get_float(struct emu_client *c, uint8_t id, float *v)
{
    struct wsg_client_frame f;
    if (emu_request(c, id, NULL, 0, &f, EMU_REPLY_MS) != WSG_E_SUCCESS ||
        f.len != 6)
        return -1;
    *v = wsg_get_f32(EMU_PARAMS(&f));
    return 0;
}

int emu_wait_flags(struct emu_client *c, uint32_t mask, uint32_t want,
                   int timeout_ms, uint32_t *flags)
{
    double deadline = emu_now_ms() + timeout_ms;
    uint32_t fl = 0;
    int r = -1;
    for (;;) {
        if (emu_get_flags(c, &fl) == 0 && (fl & mask) == want) {
            r = 0;
            break;
        }
        if (emu_now_ms() >= deadline)
            break;
        emu_sleep_ms(10);
    }
    if (flags)
        *flags = fl;
    return r;
}

int emu_wait_float(struct emu_client *c, uint8_t id, float lo, float hi,
                   int timeout_ms, float *v)
{
    double deadline = emu_now_ms() + timeout_ms;
    float x = 0;
    int r = -1;
    for (;;) {
        if (emu_get_float(c, id, &x) == 0 && x >= lo && x <= hi) {
            r = 0;
            break;
        }
        if (emu_now_ms() >= deadline)
            break;
        emu_sleep_ms(5);
    }
    if (v)
        *v = x;
    return r;
}

int emu_motion(struct emu_client *c, uint8_t id, const void *payload,
               size_t len, int timeout_ms, int *immediate)
{
    struct wsg_client_frame f;
    int st = emu_request(c, id, payload, len, &f, EMU_REPLY_MS);
    if (immediate)
        *immediate = st;
    if (st != WSG_E_CMD_PENDING)
        return st;
    if (wsg_client_final(&c->link, &f, wsg_client_deadline(timeout_ms)) != 1)
        return -1;
    return (int)f.status;
}

size_t emu_move_payload(uint8_t *out, uint8_t flags, float width, float speed)
{
    out[0] = flags;
    wsg_put_f32(out + 1, width);
    wsg_put_f32(out + 5, speed);
    return 9;
}

size_t emu_grasp_payload(uint8_t *out, float width, float speed)
{
    wsg_put_f32(out, width);
    wsg_put_f32(out + 4, speed);
    return 8;
}

int emu_motions_answer(struct emu_client *c, int status)
{
    uint8_t dir = 0, p[16], g[16];
    size_t n = emu_move_payload(p, 0, 50.0f, 100.0f);
    size_t gn = emu_grasp_payload(g, 50.0f, 100.0f);
    const struct {
        uint8_t id;
        const uint8_t *payload;
        size_t len;
    } cmd[] = {{WSG_CMD_HOMING, &dir, 1},
               {WSG_CMD_PREPOSITION, p, n},
               {WSG_CMD_GRASP, g, gn},
               {WSG_CMD_RELEASE, g, gn}};
    int wrong = 0;
    size_t i;

    for (i = 0; i < sizeof cmd / sizeof cmd[0]; i++) {
        int st = emu_request(c, cmd[i].id, cmd[i].payload, cmd[i].len, NULL,
                             EMU_REPLY_MS);
        if (st != status) {
            fprintf(stderr, "emu: %02Xh answered %d, expected %d\n", cmd[i].id,
                    st, status);
            wrong++;
        }
    }
    return wrong;
}

/* Context switches and CPU ticks (user + system) of a process so far. */
int emu_proc_activity(pid_t pid, long *switches, long *ticks)
{
    char path[64], line[256];
    unsigned long ut = 0, st = 0;
    long vol = -1, invol = -1;
    FILE *f;

    snprintf(path, sizeof path, "/proc/%d/status", (int)pid);
    f = fopen(path, "r");
    if (!f)
        return -1;
    while (fgets(line, sizeof line, f)) {
        sscanf(line, "voluntary_ctxt_switches: %ld", &vol);
        sscanf(line, "nonvoluntary_ctxt_switches: %ld", &invol);
    }
    fclose(f);
    snprintf(path, sizeof path, "/proc/%d/stat", (int)pid);
    f = fopen(path, "r");
    if (!f)
        return -1;
    /* utime and stime are fields 14 and 15, after "(comm) state". */
    if (!fgets(line, sizeof line, f) ||
        sscanf(strrchr(line, ')') + 2,
               "%*c %*d %*d %*d %*d %*d %*u %*u %*u %*u %*u %lu %lu", &ut,
               &st) != 2)
        vol = -1;
    fclose(f);
    if (vol < 0 || invol < 0)
        return -1;
    *switches = vol + invol;
    *ticks = (long)(ut + st);
    return 0;
}

int emu_start_multi(struct emu *e, const char *exe,
                    const struct emu_transport *const *tps, size_t ntp,
                    const char *const *extra)
{
    /* The hooks' argument strings live here until the daemon has them. */
    static struct emu parts[8];
    const char *args[48];
    size_t n = 0, i;
    int k, r;

    if (ntp > sizeof parts / sizeof parts[0])
        return -1;
    for (i = 0; i < ntp; i++) {
        memset(&parts[i], 0, sizeof parts[i]);
        parts[i].tp_fd = -1;
        if (tps[i]->daemon_args) {
            r = tps[i]->daemon_args(&parts[i]);
            if (r == 77) {
                printf("SKIP: %s cannot run here\n", tps[i]->field);
                exit(77);
            }
            if (r != 0)
                return -1;
            for (k = 0; parts[i].tp_argv[k] && n < 32; k++)
                args[n++] = parts[i].tp_argv[k];
        } else {
            snprintf(parts[i].tp_arg[0], sizeof parts[i].tp_arg[0], "--%s",
                     tps[i]->field);
            args[n++] = parts[i].tp_arg[0];
            args[n++] = "127.0.0.1:0";
        }
    }
    for (k = 0; extra && extra[k] && n < 47; k++)
        args[n++] = extra[k];
    args[n] = NULL;
    if (emu_start(e, exe, args) != 0)
        return -1;
    /* What a hook reserved for its clients (UDP's reply port). */
    for (i = 0; i < ntp; i++)
        if (parts[i].tp_fd >= 0) {
            e->tp_fd = parts[i].tp_fd;
            e->tp_port = parts[i].tp_port;
        }
    return 0;
}

void emu_temp_file(char *path, size_t cap, const char *tag, const char *text)
{
    const char *dir = getenv("TMPDIR");
    FILE *f = NULL;
    int fd;

    snprintf(path, cap, "%s/wsgemu-%s-XXXXXX", dir ? dir : "/tmp", tag);
    fd = mkstemp(path);
    if (fd >= 0)
        f = fdopen(fd, "w");
    if (!f || fputs(text, f) == EOF || fclose(f) != 0) {
        /* Without its file the test cannot go on (as REQUIRE ends it). */
        fprintf(stderr, "emu: cannot write the temporary file %s: %s\n", path,
                strerror(errno));
        exit(1);
    }
}
