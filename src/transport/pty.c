/*
 * The serial interface: a pseudo-terminal whose slave side (/dev/pts/N) is
 * linked from the path given with --pty, so a driver opens that path as it
 * would /dev/ttyUSB0 and sets whatever termios it likes. The emulator owns
 * the master side: one line, one wsg_session (not connection-oriented: no
 * 07h, and a close is no disconnect), one stream parser.
 *
 * A serial line has no connection, but the host's port can be closed. While
 * it is, the emulator sends nothing (its packets are lost, as on a real
 * line) and must not wake: after the last close of the slave the master
 * polls POLLHUP for good, so it leaves the epoll set and an inotify IN_OPEN
 * watch on the slave (through the process's one inotify instance, shared by a
 * fleet's ptys) brings it back when a driver opens the port again. A
 * slave that was never opened shows no HUP, so the line starts out closed
 * and waiting for IN_OPEN too.
 *
 * The kernel keeps the slave's input (what the emulator wrote and the host
 * had not read) across a close and hands it to the next opener, cut
 * anywhere in a packet. A real port loses it, so at each close the
 * emulator flushes it through the master. A poll of the master after
 * leaving the epoll set tells whether a driver opened the port again
 * meanwhile (its IN_OPEN may have been taken while the master was still
 * in the set), so no open is missed.
 *
 * Every packet leaves in one write() when the terminal takes it whole; the
 * rest waits in a bounded queue for EPOLLOUT. A host that keeps the port
 * open but does not read costs whole packets beyond the bound (counted),
 * never a broken one.
 *
 * The slave is made the service user's, mode 0620 or 0600 as the system's
 * devpts says; --pty-mode and --pty-group change its mode and group, so
 * that a user in that group (dialout) may open it. They are applied to the
 * slave by its path, not through a descriptor: opening the slave here would
 * count as the host opening the port.
 *
 * Tag: transport base | 1, the only session.
 */
#define _GNU_SOURCE

#include <errno.h>
#include <fcntl.h>
#include <poll.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/epoll.h>
#include <sys/inotify.h>
#include <sys/stat.h>
#include <termios.h>
#include <unistd.h>

#include "outq.h"
#include "transport.h"

#define WSG_PTY_READ_CHUNK      4096u
#define WSG_PTY_READS_PER_EVENT 16
#define WSG_PTY_READS_AT_CLOSE  64 /* 256 KiB: more than a pty holds */
#define WSG_PTY_SLAVE_LEN       64

struct wsg_pty {
    struct wsg_watch master; /* the master side of the pseudo-terminal */
    struct wsg_watch notify; /* a file watch: IN_OPEN of the slave */
    struct wsg_transport *t;
    struct wsg_reactor *reactor;
    struct wsg_fswatch *fswatch;
    struct wsg_device *dev;
    char *path; /* as given: the ready line shows it so */
    int check_crc;
    int linked;       /* path is our symlink */
    int wd;           /* the file watch's descriptor; -1: none */
    int active;       /* master in the epoll set: the host has the port open */
    int hup;          /* the host closed it: settle takes the master out */
    uint32_t events;  /* as registered with epoll while active */
    uint64_t dropped; /* packets discarded at the queue's bound */
    uint64_t reported; /* of those, already reported */
    char slave[WSG_PTY_SLAVE_LEN];
    struct wsg_parser parser;
    struct wsg_session session;
    struct wsg_tap_flow flow; /* what the capture sees of it */
    struct wsg_outq out;      /* last: its buffer needs no initial value */
};

static void report_drops(struct wsg_pty *pty)
{
    if (pty->dropped == pty->reported)
        return;
    fprintf(stderr,
            "wsgemu: pty %s: host not reading: %llu packets discarded "
            "(output queue full)\n",
            pty->path, (unsigned long long)(pty->dropped - pty->reported));
    pty->reported = pty->dropped;
}

/* Hang up after the batch (settle), also when a step's send failed. */
static void hang_up_later(struct wsg_pty *pty)
{
    pty->hup = 1;
    wsg_transport_defer(pty->t);
}

static void set_events(struct wsg_pty *pty, uint32_t events)
{
    int r;

    if (!pty->active || pty->events == events)
        return;
    r = wsg_reactor_mod(pty->reactor, &pty->master, events);
    if (r < 0) {
        /* Cannot happen with a registered descriptor; if it does, start
         * over as if the port had been closed. */
        fprintf(stderr, "wsgemu: pty %s: epoll: %s\n", pty->path,
                strerror(-r));
        hang_up_later(pty);
        return;
    }
    pty->events = events;
}

static void write_failed(struct wsg_pty *pty, int err)
{
    /* Linux takes writes even while the port is closed (hang_up flushes
     * them), so an error is unexpected; EIO may mean a closed port
     * elsewhere. Either way, start over: hang up, wait for an open. */
    if (err != EIO)
        fprintf(stderr, "wsgemu: pty %s: write: %s\n", pty->path,
                strerror(err));
    hang_up_later(pty);
}

/* After a send or a flush: watch EPOLLOUT while bytes wait. A host that
 * keeps the port open but does not read loses whole packets beyond the
 * queue's bound, never part of one: what it reads later still parses. */
static void sent(struct wsg_pty *pty, int r)
{
    if (r == -ENOBUFS) {
        pty->dropped++;
    } else if (r < 0) {
        write_failed(pty, -r);
    } else if (r) {
        set_events(pty, pty->events | EPOLLOUT);
    } else {
        set_events(pty, pty->events & ~(uint32_t)EPOLLOUT);
        report_drops(pty);
    }
}

/* The session's send callback: one packet. */
static void pty_packet(struct wsg_session *s, const uint8_t *pkt, size_t len)
{
    struct wsg_pty *pty = s->ctx;

    /* Nobody has the port open: the packet is lost on the line. */
    if (!pty->active || pty->hup)
        return;
    wsg_transport_tap(pty->t, &pty->flow, WSG_TAP_OUT, pkt, len);
    sent(pty, wsg_outq_send(&pty->out, pty->master.fd, pkt, len));
}

static void flush_queue(struct wsg_pty *pty)
{
    sent(pty, wsg_outq_flush(&pty->out, pty->master.fd));
}

/* Read and dispatch. After the host's last close the master returns what
 * was sent before it, then EIO; that is read to the end (the master leaves
 * the epoll set next, and the rest would reach the next opener's session
 * as stale input). A closed port cannot send more than the pty holds. */
static void read_input(struct wsg_pty *pty, int closing)
{
    int max = closing ? WSG_PTY_READS_AT_CLOSE : WSG_PTY_READS_PER_EVENT;
    uint8_t buf[WSG_PTY_READ_CHUNK];
    int i;

    for (i = 0; i < max; i++) {
        ssize_t n = read(pty->master.fd, buf, sizeof buf);

        if (n > 0) {
            wsg_transport_tap(pty->t, &pty->flow, WSG_TAP_IN, buf, (size_t)n);
            wsg_device_input(pty->dev, &pty->session, &pty->parser, buf,
                             (size_t)n);
            continue;
        }
        if (n < 0 && errno == EINTR)
            continue;
        if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK))
            return;
        /* EIO (or 0): nobody has the port open. */
        if (n < 0 && errno != EIO)
            fprintf(stderr, "wsgemu: pty %s: read: %s\n", pty->path,
                    strerror(errno));
        hang_up_later(pty);
        return;
    }
}

/* Is the slave closed by everyone? With no events asked for, poll reports
 * only POLLHUP (and errors): 1 with it while closed, 0 while a host has the
 * port open. A master whose poll fails counts as closed: IN_OPEN will tell
 * when that changes. */
static int master_hung_up(const struct wsg_pty *pty)
{
    struct pollfd p;
    int r;

    p.fd = pty->master.fd;
    p.events = 0;
    p.revents = 0;
    do
        r = poll(&p, 1, 0);
    while (r < 0 && errno == EINTR);
    return r < 0 ||
           (r == 1 && (p.revents & (POLLHUP | POLLERR | POLLNVAL)) != 0);
}

/* Throw away what the host did not read before it closed the port: the
 * terminal would hand it to the next opener, starting anywhere in a packet,
 * where a real port loses it. It waits in two places, both reachable from
 * the master: TCOFLUSH empties the slave's input buffers, and setting the
 * slave's termios unchanged with TCSAFLUSH empties its line discipline.
 * (Opening the slave to flush it there would race with a driver's open:
 * measured, one reopen in a few hundred then found the master still
 * hung up.) The termios are only written back while nobody has the port
 * open, so a driver's own settings are not undone. */
static void flush_slave_input(struct wsg_pty *pty)
{
    struct termios tio;

    tcflush(pty->master.fd, TCOFLUSH);
    if (tcgetattr(pty->master.fd, &tio) == 0 && master_hung_up(pty))
        tcsetattr(pty->master.fd, TCSAFLUSH, &tio);
}

/* The port is open: serve it. */
static void activate(struct wsg_pty *pty)
{
    int r;

    if (pty->active)
        return;
    pty->events = EPOLLIN;
    r = wsg_reactor_add(pty->reactor, &pty->master, pty->events);
    if (r < 0) {
        fprintf(stderr, "wsgemu: pty %s: epoll: %s\n", pty->path,
                strerror(-r));
        return;
    }
    pty->active = 1;
}

/* The host closed the port: stop watching the master (its POLLHUP would
 * wake us forever), forget what was on the way in both directions, and
 * wait for the next open. Not a disconnect: no FAST STOP, the session and
 * its streams stay. */
static void hang_up(struct wsg_pty *pty)
{
    pty->hup = 0;
    if (pty->active) {
        wsg_reactor_del(pty->reactor, &pty->master);
        pty->active = 0;
    }
    report_drops(pty);
    wsg_outq_clear(&pty->out);
    /* A packet half sent by the old opener must not swallow the start of
     * the next one's. */
    wsg_parser_init(&pty->parser, pty->check_crc);
    /* Opened again between the HUP and now: its IN_OPEN may have been
     * taken while the master was still active, but the HUP is gone. */
    if (!master_hung_up(pty)) {
        activate(pty);
        return;
    }
    flush_slave_input(pty);
}

static void on_notify(struct wsg_pty *pty)
{
    /* While active (or about to hang up, which checks again itself) an
     * open changes nothing. A spurious one while closed costs one HUP. */
    if (!pty->active && !pty->hup)
        activate(pty);
}

static void pty_handle(struct wsg_transport *t, struct wsg_watch *w,
                       uint32_t events)
{
    struct wsg_pty *pty = t->state;
    int closing = (events & (EPOLLHUP | EPOLLERR)) != 0;

    if (w == &pty->notify) {
        on_notify(pty);
        return;
    }
    if (!pty->active || pty->hup)
        return;
    /* Queued output first: new replies belong behind it. */
    if (events & EPOLLOUT)
        flush_queue(pty);
    /* What the host sent before it closed still reaches the gripper. */
    if (events & (EPOLLIN | EPOLLHUP | EPOLLERR))
        read_input(pty, closing);
    if (closing)
        hang_up_later(pty);
}

static void pty_reap(struct wsg_transport *t)
{
    struct wsg_pty *pty = t->state;

    if (pty->hup)
        hang_up(pty);
}

static struct wsg_session *pty_lookup(struct wsg_transport *t, uint32_t tag)
{
    struct wsg_pty *pty = t->state;

    return pty->session.tag == tag ? &pty->session : NULL;
}

/* The session lives as long as the transport: its streams run on while the
 * port is closed, like a real gripper's on its serial line. */
static int pty_describe(const struct wsg_transport *t, char *buf, size_t len)
{
    const struct wsg_pty *pty = t->state;
    int r = snprintf(buf, len, "%s", pty->path);

    return r < 0 || (size_t)r >= len ? -ENOSPC : 0;
}

/* Remove path if it is still our link (another emulator may have taken it
 * over since). */
static void unlink_ours(struct wsg_pty *pty)
{
    char target[WSG_PTY_SLAVE_LEN];
    ssize_t n;

    if (!pty->linked)
        return;
    pty->linked = 0;
    n = readlink(pty->path, target, sizeof target - 1);
    if (n < 0)
        return;
    target[n] = '\0';
    if (strcmp(target, pty->slave) == 0)
        unlink(pty->path);
}

/* PATH becomes a symlink to the slave. An old symlink (a previous run's) is
 * replaced; anything else is the user's and stays. */
static int make_link(struct wsg_pty *pty, char *err, size_t errlen)
{
    struct stat st;
    int r;

    if (symlink(pty->slave, pty->path) == 0)
        goto done;
    if (errno != EEXIST)
        goto fail;
    if (lstat(pty->path, &st) < 0)
        goto fail;
    if (!S_ISLNK(st.st_mode)) {
        snprintf(err, errlen,
                 "cannot open pty %s: it exists and is not a symlink "
                 "(remove it or give another path)",
                 pty->path);
        return -EEXIST;
    }
    if (unlink(pty->path) < 0 && errno != ENOENT)
        goto fail;
    if (symlink(pty->slave, pty->path) < 0)
        goto fail;
done:
    pty->linked = 1;
    return 0;
fail:
    r = -errno;
    snprintf(err, errlen, "cannot open pty %s: symlink to %s: %s", pty->path,
             pty->slave, strerror(-r));
    return r;
}

static void pty_free(struct wsg_pty *pty)
{
    unlink_ours(pty);
    if (pty->active)
        wsg_reactor_del(pty->reactor, &pty->master);
    wsg_fswatch_del(pty->fswatch, pty->wd);
    if (pty->master.fd >= 0)
        close(pty->master.fd);
    free(pty->path);
    free(pty);
}

static void pty_close(struct wsg_transport *t)
{
    struct wsg_pty *pty = t->state;

    if (!pty)
        return;
    report_drops(pty);
    wsg_device_session_closed(pty->dev, &pty->session);
    pty_free(pty);
    t->state = NULL;
}

/* Raw from the start, so a driver that sets nothing gets the bytes as
 * sent. Set through the master, since nobody may open the slave before
 * the link exists. 115200 8N1 is the gripper's default; a driver sets its
 * own anyway. */
static int make_raw(int fd)
{
    struct termios tio;

    if (tcgetattr(fd, &tio) < 0)
        return -errno;
    cfmakeraw(&tio);
    tio.c_cflag |= CLOCAL | CREAD;
    tio.c_cc[VMIN] = 1;
    tio.c_cc[VTIME] = 0;
    if (cfsetspeed(&tio, B115200) < 0)
        return -errno;
    if (tcsetattr(fd, TCSANOW, &tio) < 0)
        return -errno;
    return 0;
}

static int pty_open(struct wsg_transport *t,
                    const struct wsg_transport_env *env, const void *config,
                    char *err, size_t errlen)
{
    const struct wsg_pty_config *cfg = config;
    struct wsg_pty *pty;
    const char *step = "setup";
    int r;

    /* The queue is the bulk of the struct and needs no initial value. */
    pty = malloc(sizeof *pty);
    if (!pty) {
        r = -ENOMEM;
        goto fail;
    }
    memset(pty, 0, offsetof(struct wsg_pty, out));
    wsg_outq_init(&pty->out, 0);
    wsg_transport_watch_init(t, &pty->master, -1);
    wsg_transport_watch_init(t, &pty->notify, -1);
    pty->wd = -1;
    pty->t = t;
    pty->flow.kind = WSG_TAP_PTY;
    pty->reactor = env->reactor;
    pty->fswatch = env->fswatch;
    pty->dev = env->dev;
    pty->check_crc = cfg->check_crc;
    pty->path = strdup(cfg->path);
    if (!pty->path) {
        r = -ENOMEM;
        goto fail;
    }

    step = "posix_openpt";
    pty->master.fd = posix_openpt(O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
    if (pty->master.fd < 0)
        goto fail_errno;
    step = "grantpt";
    if (grantpt(pty->master.fd) < 0)
        goto fail_errno;
    step = "unlockpt";
    if (unlockpt(pty->master.fd) < 0)
        goto fail_errno;
    step = "ptsname";
    r = ptsname_r(pty->master.fd, pty->slave, sizeof pty->slave);
    if (r != 0) {
        r = -r;
        goto fail;
    }
    step = "chown";
    if (cfg->gid >= 0 && chown(pty->slave, (uid_t)-1, (gid_t)cfg->gid) < 0)
        goto fail_errno;
    /* After the chown, which may clear bits the mode wants. */
    step = "chmod";
    if (cfg->mode >= 0 && chmod(pty->slave, (mode_t)cfg->mode) < 0)
        goto fail_errno;
    step = "termios";
    r = make_raw(pty->master.fd);
    if (r < 0)
        goto fail;
    step = "inotify";
    r = wsg_fswatch_add(pty->fswatch, pty->slave, IN_OPEN, &pty->notify);
    if (r < 0)
        goto fail;
    pty->wd = r;
    wsg_parser_init(&pty->parser, pty->check_crc);
    wsg_session_init(&pty->session, t->tag_base | 1u, 0, pty_packet, pty);
    /* For the communication log. */
    snprintf(pty->session.peer, sizeof pty->session.peer, "pty %s", pty->path);
    t->state = pty;
    /* Last, so nothing can fail after the link exists. */
    r = make_link(pty, err, errlen);
    if (r < 0) {
        pty_free(pty);
        t->state = NULL;
        return r;
    }
    /* Nobody has opened the slave yet: wait for IN_OPEN. */
    return 0;

fail_errno:
    r = -errno;
fail:
    snprintf(err, errlen, "cannot open pty %s: %s: %s",
             cfg->path ? cfg->path : "?", step, strerror(-r));
    if (pty)
        pty_free(pty);
    t->state = NULL;
    return r;
}

static void pty_configure(struct wsg_transport *t,
                          const struct wsg_transport_settings *s)
{
    struct wsg_pty *pty = t->state;

    pty->check_crc = s->check_crc;
    pty->parser.check_crc = s->check_crc ? 1 : 0;
}

const struct wsg_transport_ops wsg_pty_ops = {
    .name = "pty",
    .open = pty_open,
    .close = pty_close,
    .handle = pty_handle,
    .describe = pty_describe,
    .lookup = pty_lookup,
    .reap = pty_reap,
    .configure = pty_configure,
};
