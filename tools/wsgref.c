/*
 * wsgref: the reference server of wsgbench, the physical limit of this
 * machine for a WSG protocol server. It opens the same interfaces as wsgemu
 * (TCP, UDP, a pty) and prints the same ready line, parses every request
 * with the core's incremental parser and answers each frame with ONE write
 * of a fixed reply precomputed per command ID: 43h gets E_SUCCESS and width
 * 55.0, any other ID E_SUCCESS without parameters. There is no model, no
 * session, no output queue: whatever the emulator costs beyond this is the
 * emulator's own.
 *
 * The one thing it does besides: a 43h request over TCP with FLAGS bit 0
 * set and a 3-byte payload starts an auto-update stream for that client,
 * driven by its own absolute periodic timerfd, which is the reference for
 * the stream jitter; bit 0 clear stops it. Like wsgemu, the request itself
 * is answered at once either way.
 *
 * Usage: wsgref [--tcp [ADDR:]PORT] [--udp ADDR:PORT:REMOTE] [--pty PATH]
 * (port 0: the kernel picks). SIGINT or SIGTERM ends it with status 0.
 */
#define _GNU_SOURCE /* accept4, ptsname_r, cfmakeraw */

#include "wsg/proto.h"

#include <arpa/inet.h>
#include <errno.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/epoll.h>
#include <sys/signalfd.h>
#include <sys/socket.h>
#include <sys/timerfd.h>
#include <termios.h>
#include <time.h>
#include <unistd.h>

#define REF_CLIENTS_MAX 64
#define REF_READ_CHUNK  4096
#define REF_REPLY_MAX   (WSG_HEADER_LEN + 2 + 4 + WSG_CRC_LEN)

enum ref_kind { K_LISTEN, K_CLIENT, K_TIMER, K_UDP, K_PTY, K_SIGNAL };

/* What epoll hands back: the kind of descriptor and, for a client's socket
 * or timer, the client. */
struct ref_watch {
    enum ref_kind kind;
    int fd;
    struct ref_client *client;
};

struct ref_client {
    struct ref_watch sock;
    struct ref_watch timer; /* fd -1 while not streaming */
    struct wsg_parser parser;
};

struct ref {
    int epfd;
    struct ref_watch listen, udp, pty, sig;
    uint16_t udp_remote;
    int pty_slave; /* held open: see open_pty */
    const char *pty_path;
    char pty_name[64];
    int linked;
    struct wsg_parser udp_parser, pty_parser;
    struct ref_client clients[REF_CLIENTS_MAX];
    uint8_t reply[256][REF_REPLY_MAX];
    uint8_t reply_len[256];
};

static int watch_add(struct ref *r, struct ref_watch *w)
{
    struct epoll_event ev;

    memset(&ev, 0, sizeof ev);
    ev.events = EPOLLIN;
    ev.data.ptr = w;
    return epoll_ctl(r->epfd, EPOLL_CTL_ADD, w->fd, &ev) < 0 ? -errno : 0;
}

/* "[ADDR:]PORT" (TCP) or "ADDR:PORT:REMOTE" (UDP, remote != NULL). */
static int parse_addr(const char *s, struct sockaddr_in *sa, uint16_t *remote)
{
    char host[64] = "127.0.0.1";
    const char *port = s, *c = strchr(s, ':');
    unsigned p, rp;
    char tail;

    if (c) {
        if ((size_t)(c - s) >= sizeof host)
            return -EINVAL;
        memcpy(host, s, (size_t)(c - s));
        host[c - s] = '\0';
        port = c + 1;
    }
    memset(sa, 0, sizeof *sa);
    sa->sin_family = AF_INET;
    if (inet_pton(AF_INET, host, &sa->sin_addr) != 1)
        return -EINVAL;
    if (remote) {
        if (sscanf(port, "%u:%u%c", &p, &rp, &tail) != 2 || rp == 0 ||
            rp > 65535)
            return -EINVAL;
        *remote = (uint16_t)rp;
    } else if (sscanf(port, "%u%c", &p, &tail) != 1) {
        return -EINVAL;
    }
    if (p > 65535)
        return -EINVAL;
    sa->sin_port = htons((uint16_t)p);
    return 0;
}

static int open_socket(struct ref *r, struct ref_watch *w, int type,
                       const struct sockaddr_in *sa)
{
    int one = 1;

    w->fd = socket(AF_INET, type | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
    if (w->fd < 0)
        return -errno;
    setsockopt(w->fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
    if (bind(w->fd, (const struct sockaddr *)sa, sizeof *sa) < 0)
        return -errno;
    if (type == SOCK_STREAM && listen(w->fd, 64) < 0)
        return -errno;
    return watch_add(r, w);
}

/* The slave stays open in this process, so the master never polls HUP when
 * the bench closes its side (wsgemu watches IN_OPEN for that instead; a
 * reference does not need to). */
static int open_pty(struct ref *r)
{
    struct termios tio;

    r->pty.fd = posix_openpt(O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
    if (r->pty.fd < 0)
        return -errno;
    if (grantpt(r->pty.fd) < 0 || unlockpt(r->pty.fd) < 0)
        return -errno;
    if (ptsname_r(r->pty.fd, r->pty_name, sizeof r->pty_name) != 0)
        return -EINVAL;
    if (tcgetattr(r->pty.fd, &tio) < 0)
        return -errno;
    cfmakeraw(&tio);
    if (tcsetattr(r->pty.fd, TCSANOW, &tio) < 0)
        return -errno;
    r->pty_slave = open(r->pty_name, O_RDWR | O_NOCTTY | O_CLOEXEC);
    if (r->pty_slave < 0)
        return -errno;
    /* A previous run's link is replaced; anything else is refused. */
    if (symlink(r->pty_name, r->pty_path) < 0) {
        char old[64];
        if (errno != EEXIST || readlink(r->pty_path, old, sizeof old) < 0 ||
            unlink(r->pty_path) < 0 || symlink(r->pty_name, r->pty_path) < 0)
            return -errno;
    }
    r->linked = 1;
    return watch_add(r, &r->pty);
}

static void client_close(struct ref *r, struct ref_client *c)
{
    if (c->timer.fd >= 0)
        close(c->timer.fd);
    close(c->sock.fd); /* also leaves the epoll set */
    c->timer.fd = -1;
    c->sock.fd = -1;
    (void)r;
}

/* Start (period_ms > 0) or stop (0) a client's stream: an absolute
 * periodic timer, so late wakes do not shift the later packets. */
static int stream_set(struct ref *r, struct ref_client *c, unsigned period_ms)
{
    struct itimerspec its;
    struct timespec now;
    int rc;

    if (period_ms == 0) {
        if (c->timer.fd >= 0)
            close(c->timer.fd);
        c->timer.fd = -1;
        return 0;
    }
    if (c->timer.fd < 0) {
        c->timer.fd =
            timerfd_create(CLOCK_MONOTONIC, TFD_NONBLOCK | TFD_CLOEXEC);
        if (c->timer.fd < 0)
            return -errno;
        rc = watch_add(r, &c->timer);
        if (rc < 0)
            return rc;
    }
    clock_gettime(CLOCK_MONOTONIC, &now);
    its.it_interval.tv_sec = period_ms / 1000;
    its.it_interval.tv_nsec = (long)(period_ms % 1000) * 1000000L;
    its.it_value.tv_sec = now.tv_sec + its.it_interval.tv_sec;
    its.it_value.tv_nsec = now.tv_nsec + its.it_interval.tv_nsec;
    if (its.it_value.tv_nsec >= 1000000000L) {
        its.it_value.tv_sec++;
        its.it_value.tv_nsec -= 1000000000L;
    }
    if (timerfd_settime(c->timer.fd, TFD_TIMER_ABSTIME, &its, NULL) < 0)
        return -errno;
    return 0;
}

/* One write of the fixed reply. A full socket buffer loses the packet:
 * the bench never lets it fill, and a queue is not what is measured. */
static void answer(struct ref *r, struct ref_watch *w,
                   const struct sockaddr_in *to, uint8_t id)
{
    ssize_t n;

    if (w->kind == K_UDP)
        n = sendto(w->fd, r->reply[id], r->reply_len[id], 0,
                   (const struct sockaddr *)to, sizeof *to);
    else if (w->kind == K_PTY)
        n = write(w->fd, r->reply[id], r->reply_len[id]);
    else
        n = send(w->fd, r->reply[id], r->reply_len[id],
                 MSG_NOSIGNAL | MSG_DONTWAIT);
    (void)n;
}

static void feed(struct ref *r, struct ref_watch *w, struct wsg_parser *p,
                 const struct sockaddr_in *to, const uint8_t *buf, size_t n)
{
    size_t off = 0;

    while (off < n) {
        enum wsg_parse_event ev;
        struct wsg_frame f;

        off += wsg_parser_feed(p, buf + off, n - off, &ev, &f);
        if (ev != WSG_PARSE_FRAME)
            continue;
        answer(r, w, to, f.id);
        if (f.id == WSG_CMD_GET_WIDTH && f.len == 3 && w->client)
            stream_set(r, w->client,
                       (f.payload[0] & 1) ? wsg_get_u16(f.payload + 1) + 0u
                                          : 0u);
    }
}

static void on_accept(struct ref *r)
{
    int one = 1, fd, i;

    fd = accept4(r->listen.fd, NULL, NULL, SOCK_NONBLOCK | SOCK_CLOEXEC);
    if (fd < 0)
        return;
    for (i = 0; i < REF_CLIENTS_MAX; i++)
        if (r->clients[i].sock.fd < 0)
            break;
    if (i == REF_CLIENTS_MAX) {
        close(fd);
        return;
    }
    setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
    r->clients[i].sock.fd = fd;
    wsg_parser_init(&r->clients[i].parser, 1);
    if (watch_add(r, &r->clients[i].sock) < 0)
        client_close(r, &r->clients[i]);
}

static void on_event(struct ref *r, struct ref_watch *w, int *stop)
{
    uint8_t buf[REF_READ_CHUNK];
    struct sockaddr_in from;
    socklen_t fl = sizeof from;
    uint64_t ticks;
    ssize_t n;

    switch (w->kind) {
    case K_LISTEN:
        on_accept(r);
        break;
    case K_CLIENT:
        n = read(w->fd, buf, sizeof buf);
        if (n > 0)
            feed(r, w, &w->client->parser, NULL, buf, (size_t)n);
        else if (n == 0 || (errno != EAGAIN && errno != EINTR))
            client_close(r, w->client);
        break;
    case K_TIMER:
        if (read(w->fd, &ticks, sizeof ticks) == (ssize_t)sizeof ticks)
            answer(r, &w->client->sock, NULL, WSG_CMD_GET_WIDTH);
        break;
    case K_UDP:
        n = recvfrom(w->fd, buf, sizeof buf, 0, (struct sockaddr *)&from, &fl);
        if (n <= 0)
            break;
        /* Each datagram stands alone; answers go to the remote port. */
        from.sin_port = htons(r->udp_remote);
        wsg_parser_init(&r->udp_parser, 1);
        feed(r, w, &r->udp_parser, &from, buf, (size_t)n);
        break;
    case K_PTY:
        n = read(w->fd, buf, sizeof buf);
        if (n > 0)
            feed(r, w, &r->pty_parser, NULL, buf, (size_t)n);
        break;
    case K_SIGNAL:
        *stop = 1;
        break;
    }
}

static void usage(FILE *f)
{
    fputs("Usage: wsgref [--tcp [ADDR:]PORT] [--udp ADDR:PORT:REMOTE] "
          "[--pty PATH]\n"
          "The reference server of wsgbench: answers every WSG frame with "
          "one fixed\nreply (43h: width 55.0; others: E_SUCCESS), streams "
          "43h over TCP when asked.\nPort 0 picks a free port. Prints "
          "'ready tcp=... udp=...>REMOTE pty=...'.\n",
          f);
}

static void precompute(struct ref *r)
{
    uint8_t width[4];
    unsigned id;

    wsg_put_f32(width, 55.0f);
    for (id = 0; id < 256; id++)
        r->reply_len[id] = (uint8_t)wsg_frame_encode_reply(
            r->reply[id], REF_REPLY_MAX, (uint8_t)id, WSG_E_SUCCESS,
            id == WSG_CMD_GET_WIDTH ? width : NULL,
            id == WSG_CMD_GET_WIDTH ? 4 : 0);
}

int main(int argc, char **argv)
{
    static struct ref r; /* static: 20 KiB of clients off the stack */
    const char *tcp = NULL, *udp = NULL;
    struct sockaddr_in sa;
    socklen_t sl;
    sigset_t mask;
    char line[256], *p = line;
    int i, rc, stop = 0, status = 1;

    for (i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--help") || !strcmp(argv[i], "-h")) {
            usage(stdout);
            return 0;
        }
        if (i + 1 >= argc)
            goto bad_usage;
        if (!strcmp(argv[i], "--tcp"))
            tcp = argv[++i];
        else if (!strcmp(argv[i], "--udp"))
            udp = argv[++i];
        else if (!strcmp(argv[i], "--pty"))
            r.pty_path = argv[++i];
        else
            goto bad_usage;
    }
    if (!tcp && !udp && !r.pty_path)
        goto bad_usage;

    r.listen = (struct ref_watch){K_LISTEN, -1, NULL};
    r.udp = (struct ref_watch){K_UDP, -1, NULL};
    r.pty = (struct ref_watch){K_PTY, -1, NULL};
    r.sig = (struct ref_watch){K_SIGNAL, -1, NULL};
    r.pty_slave = -1;
    for (i = 0; i < REF_CLIENTS_MAX; i++) {
        r.clients[i].sock = (struct ref_watch){K_CLIENT, -1, &r.clients[i]};
        r.clients[i].timer = (struct ref_watch){K_TIMER, -1, &r.clients[i]};
    }
    precompute(&r);
    wsg_parser_init(&r.pty_parser, 1);

    /* Blocked first, so a SIGTERM right after the ready line is queued. */
    sigemptyset(&mask);
    sigaddset(&mask, SIGINT);
    sigaddset(&mask, SIGTERM);
    sigprocmask(SIG_BLOCK, &mask, NULL);
    r.epfd = epoll_create1(EPOLL_CLOEXEC);
    r.sig.fd = signalfd(-1, &mask, SFD_NONBLOCK | SFD_CLOEXEC);
    if (r.epfd < 0 || r.sig.fd < 0 || watch_add(&r, &r.sig) < 0) {
        perror("wsgref: setup");
        goto cleanup;
    }

    p += sprintf(p, "ready");
    if (tcp) {
        rc = parse_addr(tcp, &sa, NULL);
        if (rc == 0)
            rc = open_socket(&r, &r.listen, SOCK_STREAM, &sa);
        sl = sizeof sa;
        if (rc < 0 || getsockname(r.listen.fd, (struct sockaddr *)&sa, &sl)) {
            fprintf(stderr, "wsgref: tcp %s: %s\n", tcp, strerror(-rc));
            goto cleanup;
        }
        p += sprintf(p, " tcp=%s:%u", inet_ntoa(sa.sin_addr),
                     (unsigned)ntohs(sa.sin_port));
    }
    if (udp) {
        rc = parse_addr(udp, &sa, &r.udp_remote);
        if (rc == 0)
            rc = open_socket(&r, &r.udp, SOCK_DGRAM, &sa);
        sl = sizeof sa;
        if (rc < 0 || getsockname(r.udp.fd, (struct sockaddr *)&sa, &sl)) {
            fprintf(stderr, "wsgref: udp %s: %s\n", udp, strerror(-rc));
            goto cleanup;
        }
        p += sprintf(p, " udp=%s:%u>%u", inet_ntoa(sa.sin_addr),
                     (unsigned)ntohs(sa.sin_port), (unsigned)r.udp_remote);
    }
    if (r.pty_path) {
        rc = open_pty(&r);
        if (rc < 0) {
            fprintf(stderr, "wsgref: pty %s: %s\n", r.pty_path, strerror(-rc));
            goto cleanup;
        }
        snprintf(p, sizeof line - (size_t)(p - line), " pty=%s", r.pty_path);
    }
    printf("%s\n", line);
    fflush(stdout);

    while (!stop) {
        struct epoll_event ev[32];
        int n = epoll_wait(r.epfd, ev, 32, -1);

        if (n < 0 && errno != EINTR) {
            perror("wsgref: epoll_wait");
            goto cleanup;
        }
        for (i = 0; i < n; i++)
            on_event(&r, ev[i].data.ptr, &stop);
    }
    status = 0;

cleanup:
    for (i = 0; i < REF_CLIENTS_MAX; i++)
        if (r.clients[i].sock.fd >= 0)
            client_close(&r, &r.clients[i]);
    if (r.linked)
        unlink(r.pty_path);
    if (r.pty_slave >= 0)
        close(r.pty_slave);
    if (r.pty.fd >= 0)
        close(r.pty.fd);
    if (r.udp.fd >= 0)
        close(r.udp.fd);
    if (r.listen.fd >= 0)
        close(r.listen.fd);
    if (r.sig.fd >= 0)
        close(r.sig.fd);
    if (r.epfd >= 0)
        close(r.epfd);
    return status;

bad_usage:
    usage(stderr);
    return 2;
}
