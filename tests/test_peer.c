/*
 * The stream-peer set (src/transport/peer.c) alone, on socketpairs, a TCP
 * connection over loopback and a reactor: slots up to the maximum, with
 * dead peers counting until they are reaped; generations; one closing line
 * in the owner's wording, none for a peer that merely went away; the owner
 * told of each peer before it is freed, its descriptor still open; EPOLLOUT
 * watched exactly while output waits, and the output arriving whole and in
 * order; a queue that overflows ending in a reset, or a FIN where the owner
 * wants no reset.
 */
#define _GNU_SOURCE

#include <arpa/inet.h>
#include <errno.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <poll.h>
#include <string.h>
#include <sys/epoll.h>
#include <sys/socket.h>
#include <unistd.h>

#include "check.h"
#include "peer.h"

struct owner {
    int id;
    struct wsg_peer peer;
};

struct world {
    struct wsg_reactor r;
    struct wsg_peer_set set;
    int defers;
    int closed;
    int closed_fd_open; /* every closed peer still had its descriptor */
    unsigned last_closed_slot;
    int reads;
};

static void on_event(struct wsg_watch *w, uint32_t events)
{
    struct world *wd = w->ctx;

    if (wsg_peer_ready((struct wsg_peer *)w, events))
        wd->reads++;
    wsg_reactor_stop(&wd->r);
}

static void watch(struct wsg_watch *w, int fd, void *ctx)
{
    wsg_watch_init(w, fd, on_event, ctx);
}

static void defer(void *ctx)
{
    struct world *wd = ctx;

    wd->defers++;
}

static void closed(struct wsg_peer *p, void *ctx)
{
    struct world *wd = ctx;

    CHECK(p->dead);
    if (fcntl(p->watch.fd, F_GETFD) < 0)
        wd->closed_fd_open = 0;
    wd->last_closed_slot = p->slot;
    wd->closed++;
}

static void world_init(struct world *wd, unsigned max, uint32_t gen_mask,
                       const char *log, int reset)
{
    struct wsg_peer_config cfg = {
        .size = sizeof(struct owner),
        .offset = offsetof(struct owner, peer),
        .max = max,
        .gen_mask = gen_mask,
        .log = log,
        .reset_on_overflow = reset,
        .watch = watch,
        .defer = defer,
        .closed = closed,
        .ctx = wd,
    };

    memset(wd, 0, sizeof *wd);
    wd->closed_fd_open = 1;
    REQUIRE(wsg_reactor_init(&wd->r) == 0);
    wsg_peer_set_init(&wd->set, &wd->r, &cfg);
}

static void world_fini(struct world *wd)
{
    wsg_peer_set_fini(&wd->set);
    wsg_reactor_fini(&wd->r);
}

/* One batch of the reactor (on_event stops it). */
static void run_batch(struct world *wd)
{
    wd->r.stop = 0;
    REQUIRE(wsg_reactor_run(&wd->r) == 0);
}

/* A peer on one end of a non-blocking socketpair; the other end in *other. */
static struct wsg_peer *open_pair(struct world *wd, const char *name,
                                  int *other)
{
    struct wsg_peer *p;
    int sv[2];

    REQUIRE(socketpair(AF_UNIX, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0,
                       sv) == 0);
    REQUIRE(wsg_peer_open(&wd->set, sv[0], name, &p) == 0);
    *other = sv[1];
    return p;
}

/* What the code under test writes to stderr, while fn runs. */
struct capture {
    int saved;
    FILE *f;
};

static void capture_start(struct capture *c)
{
    fflush(stderr);
    c->f = tmpfile();
    REQUIRE(c->f != NULL);
    c->saved = dup(2);
    REQUIRE(c->saved >= 0 && dup2(fileno(c->f), 2) == 2);
}

static void capture_end(struct capture *c, char *buf, size_t len)
{
    size_t n;

    fflush(stderr);
    dup2(c->saved, 2);
    close(c->saved);
    rewind(c->f);
    n = fread(buf, 1, len - 1, c->f);
    buf[n] = '\0';
    fclose(c->f);
}

static void test_slots(void)
{
    struct world wd;
    struct wsg_peer *a, *b, *p;
    struct capture cap;
    char log[256];
    int fa, fb, fc, fd;

    world_init(&wd, 2, 3, "test %s: closing", 1);
    a = open_pair(&wd, "a", &fa);
    b = open_pair(&wd, "b", &fb);
    CHECK_EQ(a->slot, 0);
    CHECK_EQ(a->gen, 0);
    CHECK_EQ(b->slot, 1);
    CHECK_EQ(b->gen, 1);
    CHECK(wsg_peer_full(&wd.set));
    CHECK(wsg_peer_live(&wd.set, 0) == a);
    CHECK(wsg_peer_live(&wd.set, 2) == NULL);
    CHECK(wsg_peer_live(&wd.set, 100000) == NULL);
    /* The owner's struct around the peer, its part zeroed. */
    CHECK_EQ(WSG_PEER_OWNER(a, struct owner, peer)->id, 0);
    WSG_PEER_OWNER(a, struct owner, peer)->id = 7;
    CHECK_EQ(wsg_peer_ready(a, EPOLLIN), 1);

    capture_start(&cap);
    wsg_peer_kill(a, "why");
    wsg_peer_kill(a, "again"); /* once */
    capture_end(&cap, log, sizeof log);
    CHECK(strcmp(log, "test a: closing: why\n") == 0);
    CHECK_EQ(wd.defers, 1);
    CHECK(a->dead);
    CHECK_EQ(wsg_peer_ready(a, EPOLLIN), 0);
    /* Dead, but its slot taken until the reap. */
    CHECK(wsg_peer_live(&wd.set, 0) == NULL);
    CHECK(wsg_peer_full(&wd.set));
    CHECK_EQ(wd.set.ndead, 1);
    CHECK_EQ(wd.closed, 0);

    wsg_peer_reap(&wd.set);
    CHECK_EQ(wd.closed, 1);
    CHECK_EQ(wd.last_closed_slot, 0);
    CHECK(wd.closed_fd_open);
    CHECK_EQ(wd.set.n, 1);
    CHECK_EQ(wd.set.ndead, 0);
    CHECK(!wsg_peer_full(&wd.set));
    /* Closed with it: its other end sees the end of the stream. */
    {
        char ch;

        CHECK_EQ(recv(fa, &ch, 1, 0), 0);
    }

    /* The freed slot again, with the next generation. */
    p = open_pair(&wd, "c", &fc);
    CHECK_EQ(p->slot, 0);
    CHECK_EQ(p->gen, 2);
    CHECK_EQ(WSG_PEER_OWNER(p, struct owner, peer)->id, 0);
    {
        int sv[2];
        struct wsg_peer *q = b;

        REQUIRE(socketpair(AF_UNIX, SOCK_STREAM, 0, sv) == 0);
        CHECK_EQ(wsg_peer_open(&wd.set, sv[0], "d", &q), -EBUSY);
        CHECK(q == NULL);
        close(sv[0]);
        close(sv[1]);
    }
    /* Killed without a reason: no line. Generations wrap at the mask. */
    capture_start(&cap);
    wsg_peer_kill(p, NULL);
    wsg_peer_kill(b, NULL);
    capture_end(&cap, log, sizeof log);
    CHECK(strcmp(log, "") == 0);
    wsg_peer_reap(&wd.set);
    CHECK_EQ(wd.closed, 3);
    CHECK_EQ(wd.set.n, 0);
    p = open_pair(&wd, "e", &fd);
    CHECK_EQ(p->gen, 3);
    close(fd);
    p = open_pair(&wd, "f", &fd);
    CHECK_EQ(p->gen, 0);
    close(fd);

    /* Live peers too are told of and freed when the set closes. */
    world_fini(&wd);
    CHECK_EQ(wd.closed, 5);
    CHECK(wd.closed_fd_open);
    close(fa);
    close(fb);
    close(fc);
}

/* A send to a peer that has gone: closed without a line; a send error the
 * owner counts as worth telling: the line, in a wording without a name. */
static void test_gone(void)
{
    struct world wd;
    struct wsg_peer *p;
    struct capture cap;
    char log[256];
    const uint8_t pkt[4] = {1, 2, 3, 4};
    int other;

    world_init(&wd, 4, 0, "test: closing a client", 0);
    p = open_pair(&wd, NULL, &other);
    close(other);
    capture_start(&cap);
    wsg_peer_send(p, pkt, sizeof pkt);
    capture_end(&cap, log, sizeof log);
    CHECK(p->dead);
    CHECK(!p->reset);
    CHECK(strcmp(log, "") == 0);
    CHECK_EQ(p->gen, 0);

    p = open_pair(&wd, NULL, &other);
    CHECK_EQ(p->gen, 0);
    capture_start(&cap);
    wsg_peer_kill(p, "dropped");
    capture_end(&cap, log, sizeof log);
    CHECK(strcmp(log, "test: closing a client: dropped\n") == 0);
    close(other);
    world_fini(&wd);
}

/* Output the socket does not take waits, EPOLLOUT watched meanwhile, and
 * leaves in order when the other end reads. */
static void test_queue(void)
{
    struct world wd;
    struct wsg_peer *p;
    uint8_t pkt[1000];
    uint8_t buf[4096];
    size_t sent = 0, got = 0;
    int sndbuf = 4096;
    int other, i, ok = 1;

    world_init(&wd, 1, 0, "test %s: closing", 1);
    p = open_pair(&wd, "q", &other);
    CHECK_EQ(p->events, EPOLLIN | EPOLLRDHUP);
    REQUIRE(setsockopt(p->watch.fd, SOL_SOCKET, SO_SNDBUF, &sndbuf,
                       sizeof sndbuf) == 0);
    /* Each byte of the stream is its offset, modulo 251 (a prime, so a
     * packet out of place shows). */
    for (i = 0; i < 40 && !(p->events & EPOLLOUT); i++) {
        size_t k;

        for (k = 0; k < sizeof pkt; k++)
            pkt[k] = (uint8_t)((sent + k) % 251u);
        wsg_peer_send(p, pkt, sizeof pkt);
        sent += sizeof pkt;
    }
    REQUIRE(!p->dead);
    CHECK(p->events & EPOLLOUT);
    CHECK(p->out.len > 0);
    /* Read what comes; each batch flushes what the socket takes. */
    for (i = 0; i < 1000 && got < sent; i++) {
        ssize_t n = recv(other, buf, sizeof buf, MSG_DONTWAIT);

        if (n > 0) {
            ssize_t k;

            for (k = 0; k < n; k++)
                if (buf[k] != (uint8_t)((got + (size_t)k) % 251u))
                    ok = 0;
            got += (size_t)n;
            continue;
        }
        if (p->events & EPOLLOUT)
            run_batch(&wd);
    }
    CHECK_EQ(got, sent);
    CHECK(ok);
    CHECK(!p->dead);
    CHECK_EQ(p->out.len, 0);
    CHECK_EQ(p->events, EPOLLIN | EPOLLRDHUP);
    CHECK_EQ(wd.reads, 0);
    /* Input reaches the owner through ready(). */
    REQUIRE(send(other, "x", 1, 0) == 1);
    run_batch(&wd);
    CHECK_EQ(wd.reads, 1);
    close(other);
    world_fini(&wd);
}

/* A TCP connection over loopback: the peer on the accepted side. */
static struct wsg_peer *open_tcp(struct world *wd, int *client)
{
    struct sockaddr_in sa;
    socklen_t len = sizeof sa;
    struct wsg_peer *p;
    int small = 4096;
    int lfd, fd;

    memset(&sa, 0, sizeof sa);
    sa.sin_family = AF_INET;
    sa.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    lfd = socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
    REQUIRE(lfd >= 0);
    REQUIRE(bind(lfd, (struct sockaddr *)&sa, sizeof sa) == 0);
    REQUIRE(listen(lfd, 1) == 0);
    REQUIRE(getsockname(lfd, (struct sockaddr *)&sa, &len) == 0);
    *client = socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
    REQUIRE(*client >= 0);
    /* Small buffers, so the queue fills after little data. */
    setsockopt(*client, SOL_SOCKET, SO_RCVBUF, &small, sizeof small);
    REQUIRE(connect(*client, (struct sockaddr *)&sa, sizeof sa) == 0);
    fd = accept4(lfd, NULL, NULL, SOCK_NONBLOCK | SOCK_CLOEXEC);
    REQUIRE(fd >= 0);
    close(lfd);
    setsockopt(fd, SOL_SOCKET, SO_SNDBUF, &small, sizeof small);
    REQUIRE(wsg_peer_open(&wd->set, fd, "127.0.0.1:1", &p) == 0);
    return p;
}

/* The end the client sees after reading all there is: 0 for a FIN,
 * -ECONNRESET for a reset, 1 if nothing came within a few seconds. */
static int client_end(int fd)
{
    char buf[65536];
    int i;

    for (i = 0; i < 1000; i++) {
        struct pollfd pfd = {fd, POLLIN, 0};
        ssize_t n;

        if (poll(&pfd, 1, 3000) <= 0)
            return 1;
        n = recv(fd, buf, sizeof buf, 0);
        if (n == 0)
            return 0;
        if (n < 0)
            return -errno;
    }
    return 1;
}

/* A peer that does not read overflows its queue: dropped, with the line,
 * and reset or sent a FIN as the owner chose. */
static void test_overflow(int reset)
{
    struct world wd;
    struct wsg_peer *p;
    struct capture cap;
    uint8_t pkt[1024];
    char log[256];
    int client, i;

    world_init(&wd, 1, 0, "test %s: closing", reset);
    p = open_tcp(&wd, &client);
    memset(pkt, 0x5a, sizeof pkt);
    capture_start(&cap);
    for (i = 0; i < 100000 && !p->dead; i++)
        wsg_peer_send(p, pkt, sizeof pkt);
    capture_end(&cap, log, sizeof log);
    REQUIRE(p->dead);
    CHECK_EQ(p->reset, reset);
    CHECK(strcmp(log, "test 127.0.0.1:1: closing: output queue over 64 KiB "
                      "(client not reading)\n") == 0);
    CHECK_EQ(wd.defers, 1);
    wsg_peer_reap(&wd.set);
    CHECK_EQ(wd.closed, 1);
    CHECK_EQ(client_end(client), reset ? -ECONNRESET : 0);
    close(client);
    world_fini(&wd);
}

int main(void)
{
    alarm(50); /* a reactor that never wakes must not hang ctest */
    test_slots();
    test_gone();
    test_queue();
    test_overflow(1);
    test_overflow(0);
    TEST_EXIT();
}
