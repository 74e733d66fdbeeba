/*
 * The serial client transport of the integration tests: the daemon's
 * pseudo-terminal, opened through the path of its ready line (pty=PATH, a
 * symlink to /dev/pts/N) the way a driver opens /dev/ttyUSB0, and set to raw
 * 115200 8N1. A serial line has one peer and no connection: closing the port
 * is no disconnect, and 07h answers E_NOT_AVAILABLE.
 *
 * Each daemon gets a fresh directory for its link (mkdtemp), so tests and
 * parallel runs never share a path. The daemon removes the link when it
 * exits; the directories (and a link left by a daemon that was killed) are
 * removed when the test process exits.
 */
#define _GNU_SOURCE /* posix_openpt */

#include <errno.h>
#include <fcntl.h>
#include <poll.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "emu.h"

#define PTY_LINK_NAME "ttyWSG0"
#define PTY_DIRS_MAX  16

/* Directories made for daemons, removed at exit. The daemon and its
 * arguments live in struct emu, but nothing tells the transport when the
 * daemon is gone, so the list is the test process's. */
static char made_dirs[PTY_DIRS_MAX][160];
static int cleanup_registered;

static void remove_dirs(void)
{
    char path[200];
    int i;

    for (i = 0; i < PTY_DIRS_MAX; i++) {
        if (!made_dirs[i][0])
            continue;
        if (snprintf(path, sizeof path, "%s/%s", made_dirs[i], PTY_LINK_NAME) <
            (int)sizeof path)
            unlink(path);
        rmdir(made_dirs[i]);
        made_dirs[i][0] = '\0';
    }
}

static void remember_dir(const char *dir)
{
    int i;

    if (!cleanup_registered) {
        atexit(remove_dirs);
        cleanup_registered = 1;
    }
    for (i = 0; i < PTY_DIRS_MAX; i++) {
        if (!made_dirs[i][0]) {
            snprintf(made_dirs[i], sizeof made_dirs[i], "%s", dir);
            return;
        }
    }
    /* Full: the directory stays behind in /tmp, which is harmless. */
}

/* --pty DIR/ttyWSG0 with a fresh DIR: tp_arg[1] is DIR, tp_arg[0] the
 * path. 77 where there are no pseudo-terminals. */
static int pty_daemon_args(struct emu *e)
{
    int m = posix_openpt(O_RDWR | O_NOCTTY | O_CLOEXEC);

    /* A container without devpts has no pseudo-terminals to emulate a
     * serial port on. */
    if (m < 0) {
        printf("SKIP: no pseudo-terminals here: %s\n", strerror(errno));
        return 77;
    }
    close(m);
    snprintf(e->tp_arg[1], sizeof e->tp_arg[1], "/tmp/wsgemu-pty-XXXXXX");
    if (!mkdtemp(e->tp_arg[1])) {
        fprintf(stderr, "emu: mkdtemp: %s\n", strerror(errno));
        return -1;
    }
    remember_dir(e->tp_arg[1]);
    if (snprintf(e->tp_arg[0], sizeof e->tp_arg[0], "%s/%s", e->tp_arg[1],
                 PTY_LINK_NAME) >= (int)sizeof e->tp_arg[0])
        return -1; /* cannot happen: the template is short */
    e->tp_argv[0] = "--pty";
    e->tp_argv[1] = e->tp_arg[0];
    e->tp_argv[2] = NULL;
    return 0;
}

static int pty_open(struct emu_client *c, const char *addr)
{
    struct wsg_client l;
    int r;

    /* As a driver opens it, raw 115200 8N1: the client library's. */
    wsg_client_init(&l, WSG_LINK_SERIAL);
    r = wsg_client_open_serial(&l, addr);
    if (r < 0) {
        fprintf(stderr, "emu: open %s as a serial port: %s\n", addr,
                strerror(-r));
        return -1;
    }
    /* Writes that wait for room, as a driver's do: a test that floods
     * the port is slowed down, not refused. */
    fcntl(l.fd, F_SETFL, fcntl(l.fd, F_GETFL) & ~O_NONBLOCK);
    c->fd = l.fd;
    return 0;
}

static int pty_send(struct emu_client *c, const uint8_t *pkt, size_t len)
{
    ssize_t n;

    do
        n = write(c->fd, pkt, len);
    while (n < 0 && errno == EINTR);
    return n == (ssize_t)len ? 0 : -1;
}

static long pty_recv(struct emu_client *c, uint8_t *buf, size_t cap,
                     int timeout_ms)
{
    double deadline = emu_now_ms() + timeout_ms;

    for (;;) {
        struct pollfd pfd = {c->fd, POLLIN, 0};
        double left = deadline - emu_now_ms();
        int r = poll(&pfd, 1, left > 0 ? (int)(left + 0.999) : 0);
        ssize_t n;

        if (r < 0 && errno == EINTR)
            continue;
        if (r < 0)
            return -2;
        if (r == 0)
            return -1;
        n = read(c->fd, buf, cap);
        if (n < 0 && (errno == EINTR || errno == EAGAIN))
            continue;
        /* The daemon closed the master (it exited): EIO or 0. */
        if (n < 0)
            return errno == EIO ? 0 : -2;
        return (long)n;
    }
}

static void pty_close(struct emu_client *c, int abort)
{
    (void)abort; /* a serial port just closes */
    close(c->fd);
}

const struct emu_transport emu_pty = {
    .field = "pty",
    .open = pty_open,
    .send = pty_send,
    .recv = pty_recv,
    .close = pty_close,
    .daemon_args = pty_daemon_args,
    .connection = 0,
    .single_peer = 1,
};
