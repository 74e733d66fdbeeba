/*
 * One inotify instance, created with the first watch, read whole on each
 * readiness; the watches are on files, so its events carry no names.
 */
#include "fswatch.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>
#include <sys/epoll.h>
#include <sys/inotify.h>
#include <unistd.h>

static void fswatch_event(struct wsg_watch *iw, uint32_t events)
{
    struct wsg_fswatch *f = iw->ctx;
    /* Aligned as inotify_event requires. */
    union {
        struct inotify_event ev;
        char bytes[4096];
    } buf;

    (void)events;
    for (;;) {
        ssize_t n = read(f->watch.fd, &buf, sizeof buf);
        size_t off = 0;

        if (n < 0 && errno == EINTR)
            continue;
        if (n <= 0)
            return;
        while (off + sizeof buf.ev <= (size_t)n) {
            struct inotify_event ev;
            struct wsg_watch *w;

            memcpy(&ev, buf.bytes + off, sizeof ev);
            off += sizeof ev + ev.len;
            if (ev.wd < 0 || (size_t)ev.wd >= f->ntab)
                continue;
            w = f->tab[ev.wd];
            if (w)
                w->fn(w, EPOLLIN);
        }
    }
}

void wsg_fswatch_init(struct wsg_fswatch *f, struct wsg_reactor *r)
{
    memset(f, 0, sizeof *f);
    f->reactor = r;
    wsg_watch_init(&f->watch, -1, fswatch_event, f);
}

void wsg_fswatch_fini(struct wsg_fswatch *f)
{
    if (f->watch.fd >= 0)
        close(f->watch.fd);
    f->watch.fd = -1;
    free(f->tab);
    f->tab = NULL;
    f->ntab = 0;
}

int wsg_fswatch_add(struct wsg_fswatch *f, const char *path, uint32_t mask,
                    struct wsg_watch *w)
{
    int wd, r;

    if (f->watch.fd < 0) {
        f->watch.fd = inotify_init1(IN_NONBLOCK | IN_CLOEXEC);
        if (f->watch.fd < 0)
            return -errno;
        r = wsg_reactor_add(f->reactor, &f->watch, EPOLLIN);
        if (r < 0) {
            close(f->watch.fd);
            f->watch.fd = -1;
            return r;
        }
    }
    wd = inotify_add_watch(f->watch.fd, path, mask);
    if (wd < 0)
        return -errno;
    if ((size_t)wd >= f->ntab) {
        size_t n = f->ntab ? f->ntab : 16;
        struct wsg_watch **t;

        while (n <= (size_t)wd)
            n *= 2;
        t = realloc(f->tab, n * sizeof *t);
        if (!t) {
            inotify_rm_watch(f->watch.fd, wd);
            return -ENOMEM;
        }
        memset(t + f->ntab, 0, (n - f->ntab) * sizeof *t);
        f->tab = t;
        f->ntab = n;
    }
    f->tab[wd] = w;
    return wd;
}

void wsg_fswatch_del(struct wsg_fswatch *f, int wd)
{
    if (wd < 0 || (size_t)wd >= f->ntab || !f->tab[wd])
        return;
    f->tab[wd] = NULL;
    inotify_rm_watch(f->watch.fd, wd);
}
