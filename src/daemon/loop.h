/*
 * The daemon's single epoll loop: the transports' file descriptors, a
 * timerfd that paces the model's fixed steps on an absolute grid, and a
 * signalfd for SIGINT/SIGTERM. The timer runs only while the model has work
 * or a session streams auto-updates, so an idle emulator does not wake.
 */
#ifndef WSG_DAEMON_LOOP_H
#define WSG_DAEMON_LOOP_H

#include <stddef.h>
#include <stdint.h>

#include "wsg/device.h"

/* Steps run per timer wake at most; a loop further behind skips ahead. */
#define WSG_LOOP_CATCHUP_MAX 50u
#define WSG_LOOP_EVENTS      64

struct wsg_transport;

/* What epoll_event.data.ptr points at for every watched descriptor. Owners
 * embed it (first, or found by comparing addresses) in their own structs. */
struct wsg_watch {
    struct wsg_transport *owner; /* NULL: one of the loop's own */
    int fd;
};

struct wsg_loop {
    int epfd;
    struct wsg_watch timer;  /* timerfd */
    struct wsg_watch signal; /* signalfd */
    struct wsg_device *dev;
    struct wsg_transport *transports;
    size_t ntransports;
    uint64_t step_ns;
    uint64_t due_ns; /* CLOCK_MONOTONIC time of the next step not run */
    int armed;
    int stop;
    uint64_t steps;      /* steps run */
    uint64_t overruns;   /* steps skipped because the loop fell behind */
    uint64_t idle_steps; /* steps passed over with wsg_device_advance_idle */
};

/* Block SIGINT/SIGTERM (they arrive through the signalfd) and create the
 * descriptors. Returns 0 or -errno; wsg_loop_fini is safe either way. The
 * signals stay blocked after fini: a second SIGTERM must not turn a clean
 * exit into death by signal. */
int wsg_loop_init(struct wsg_loop *l, struct wsg_device *dev,
                  uint32_t step_us);
void wsg_loop_fini(struct wsg_loop *l);
/* The transports whose events, sessions and closes the loop serves. */
void wsg_loop_set_transports(struct wsg_loop *l, struct wsg_transport *t,
                             size_t n);
/* Serve until SIGINT or SIGTERM: returns 0 then, -errno on failure. */
int wsg_loop_run(struct wsg_loop *l);

int wsg_loop_watch_add(struct wsg_loop *l, struct wsg_watch *w,
                       uint32_t events);
int wsg_loop_watch_mod(struct wsg_loop *l, struct wsg_watch *w,
                       uint32_t events);
int wsg_loop_watch_del(struct wsg_loop *l, struct wsg_watch *w);

#endif
