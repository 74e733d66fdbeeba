/*
 * The reactor: one epoll instance that knows only descriptors, the events
 * wanted on them, and for each a callback with its context, plus hooks run
 * after each batch of events (the model of Redis's ae). It knows nothing of
 * grippers, time or transports: the scheduler, the interfaces and the
 * control channel each register their own descriptors and hooks, and none
 * reaches into another's state.
 */
#ifndef WSG_DAEMON_REACTOR_H
#define WSG_DAEMON_REACTOR_H

#include <stddef.h>
#include <stdint.h>

#define WSG_REACTOR_EVENTS 64
#define WSG_REACTOR_HOOKS  8

struct wsg_watch;
/* An event on w's descriptor (EPOLLIN, EPOLLOUT, EPOLLHUP...). */
typedef void (*wsg_watch_fn)(struct wsg_watch *w, uint32_t events);

/* What epoll_event.data.ptr points at. Owners embed it in their structs
 * and find themselves again through ctx (or the struct's first member). */
struct wsg_watch {
    int fd;
    wsg_watch_fn fn;
    void *ctx;
};

struct wsg_reactor_hook {
    void (*fn)(void *ctx);
    void *ctx;
};

struct wsg_reactor {
    int epfd;
    int stop;
    /* Run after every batch, in the order they were added: peers marked
     * gone during the batch are reaped there, when no event of the batch
     * can still name them. */
    struct wsg_reactor_hook after[WSG_REACTOR_HOOKS];
    size_t nafter;
};

/* 0 or -errno; wsg_reactor_fini is safe either way. */
int wsg_reactor_init(struct wsg_reactor *r);
void wsg_reactor_fini(struct wsg_reactor *r);
/* A watch with its descriptor, callback and context filled in. */
void wsg_watch_init(struct wsg_watch *w, int fd, wsg_watch_fn fn, void *ctx);
int wsg_reactor_add(struct wsg_reactor *r, struct wsg_watch *w,
                    uint32_t events);
int wsg_reactor_mod(struct wsg_reactor *r, struct wsg_watch *w,
                    uint32_t events);
int wsg_reactor_del(struct wsg_reactor *r, struct wsg_watch *w);
/* Add a hook run after each batch. 0, or -ENOSPC past WSG_REACTOR_HOOKS. */
int wsg_reactor_after(struct wsg_reactor *r, void (*fn)(void *ctx), void *ctx);
/* Remove a hook added with the same fn and ctx (its owner closes). */
void wsg_reactor_forget(struct wsg_reactor *r, void (*fn)(void *ctx),
                        void *ctx);
/* Dispatch events until wsg_reactor_stop: 0 then, -errno on failure. */
int wsg_reactor_run(struct wsg_reactor *r);
void wsg_reactor_stop(struct wsg_reactor *r);

#endif
