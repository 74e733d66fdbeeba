/*
 * The reactor's epoll loop: wait for events with no timeout (whoever needs
 * to wake at a time arms a timerfd of its own, so nothing wakes before the
 * next deadline), hand each event to its watch's callback, then run the
 * after-batch hooks.
 */
#include "reactor.h"

#include <errno.h>
#include <string.h>
#include <sys/epoll.h>
#include <unistd.h>

int wsg_reactor_init(struct wsg_reactor *r)
{
    memset(r, 0, sizeof *r);
    r->epfd = epoll_create1(EPOLL_CLOEXEC);
    return r->epfd < 0 ? -errno : 0;
}

void wsg_reactor_fini(struct wsg_reactor *r)
{
    if (r->epfd >= 0)
        close(r->epfd);
    r->epfd = -1;
    r->nafter = 0;
}

void wsg_watch_init(struct wsg_watch *w, int fd, wsg_watch_fn fn, void *ctx)
{
    w->fd = fd;
    w->fn = fn;
    w->ctx = ctx;
}

static int epoll_op(struct wsg_reactor *r, int op, struct wsg_watch *w,
                    uint32_t events)
{
    struct epoll_event ev;

    memset(&ev, 0, sizeof ev);
    ev.events = events;
    ev.data.ptr = w;
    return epoll_ctl(r->epfd, op, w->fd, &ev) < 0 ? -errno : 0;
}

int wsg_reactor_add(struct wsg_reactor *r, struct wsg_watch *w,
                    uint32_t events)
{
    return epoll_op(r, EPOLL_CTL_ADD, w, events);
}

int wsg_reactor_mod(struct wsg_reactor *r, struct wsg_watch *w,
                    uint32_t events)
{
    return epoll_op(r, EPOLL_CTL_MOD, w, events);
}

int wsg_reactor_del(struct wsg_reactor *r, struct wsg_watch *w)
{
    return epoll_op(r, EPOLL_CTL_DEL, w, 0);
}

int wsg_reactor_after(struct wsg_reactor *r, void (*fn)(void *ctx), void *ctx)
{
    if (r->nafter == WSG_REACTOR_HOOKS)
        return -ENOSPC;
    r->after[r->nafter].fn = fn;
    r->after[r->nafter].ctx = ctx;
    r->nafter++;
    return 0;
}

void wsg_reactor_forget(struct wsg_reactor *r, void (*fn)(void *ctx),
                        void *ctx)
{
    size_t i;

    for (i = 0; i < r->nafter; i++) {
        if (r->after[i].fn != fn || r->after[i].ctx != ctx)
            continue;
        memmove(&r->after[i], &r->after[i + 1],
                (r->nafter - i - 1) * sizeof r->after[0]);
        r->nafter--;
        return;
    }
}

void wsg_reactor_stop(struct wsg_reactor *r)
{
    r->stop = 1;
}

int wsg_reactor_run(struct wsg_reactor *r)
{
    struct epoll_event ev[WSG_REACTOR_EVENTS];

    while (!r->stop) {
        int n = epoll_wait(r->epfd, ev, WSG_REACTOR_EVENTS, -1);
        size_t j;
        int i;

        if (n < 0) {
            if (errno == EINTR)
                continue;
            return -errno;
        }
        for (i = 0; i < n; i++) {
            struct wsg_watch *w = ev[i].data.ptr;

            w->fn(w, ev[i].events);
        }
        for (j = 0; j < r->nafter; j++)
            r->after[j].fn(r->after[j].ctx);
    }
    return 0;
}
