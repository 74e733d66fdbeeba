/*
 * The daemon's single epoll loop: the transports' file descriptors, a
 * timerfd that paces the model's fixed steps on an absolute grid, and a
 * signalfd for SIGINT/SIGTERM. The timer runs only while the model has work
 * or a session streams auto-updates, so an idle emulator does not wake.
 *
 * Time control (the control channel): simulated time runs at a scale of
 * real time, can be paused, and stepped by hand while paused. Only the loop
 * deals with time; the model just counts its steps.
 */
#ifndef WSG_DAEMON_LOOP_H
#define WSG_DAEMON_LOOP_H

#include <stddef.h>
#include <stdint.h>

#include "wsg/device.h"

/* Steps run per timer wake at most; a loop further behind skips ahead. */
#define WSG_LOOP_CATCHUP_MAX 50u
#define WSG_LOOP_EVENTS      64
/* The shortest timer period: a faster scale runs several steps per tick
 * rather than waking more often than this. */
#define WSG_LOOP_PERIOD_MIN_NS 50000ull
/* Scales accepted by wsg_loop_set_scale. */
#define WSG_LOOP_SCALE_MIN 0.001
#define WSG_LOOP_SCALE_MAX 1000.0

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
    uint64_t step_ns;    /* simulated time of one model step */
    double scale;        /* simulated seconds per real second */
    uint64_t period_ns;  /* real time between timer ticks */
    unsigned tick_steps; /* model steps per tick */
    uint64_t due_ns;     /* CLOCK_MONOTONIC time of the next tick not run */
    int armed;
    int paused; /* simulated time stands still (steps only by hand) */
    int stop;
    uint64_t steps;      /* steps run */
    uint64_t overruns;   /* steps skipped because the loop fell behind */
    uint64_t idle_steps; /* steps passed over with wsg_device_advance_idle */
    /* Optional: called after each batch of events is handled (the
     * communication log flushes there: one write per batch, not per
     * packet). */
    void (*settled)(void *ctx);
    void *settled_ctx;
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
/* Simulated time at scale times real time, re-gridded from now. 0, or
 * -EINVAL for a scale outside [WSG_LOOP_SCALE_MIN, WSG_LOOP_SCALE_MAX]. A
 * paused loop stays paused and takes the scale on when resumed. */
int wsg_loop_set_scale(struct wsg_loop *l, double scale);
/* Stop simulated time (streams too: they run in it). 0 or -errno. */
int wsg_loop_pause(struct wsg_loop *l);
/* Run simulated time again from now, keeping the model's time. */
int wsg_loop_resume(struct wsg_loop *l);
/* While paused: run nsteps model steps right away, each followed by the
 * sessions' stream polls (steps the model would skip while idle are only
 * counted). Returns 0, or -EBUSY when not paused. */
int wsg_loop_step(struct wsg_loop *l, uint64_t nsteps);
/* Serve until SIGINT or SIGTERM: returns 0 then, -errno on failure. */
int wsg_loop_run(struct wsg_loop *l);

int wsg_loop_watch_add(struct wsg_loop *l, struct wsg_watch *w,
                       uint32_t events);
int wsg_loop_watch_mod(struct wsg_loop *l, struct wsg_watch *w,
                       uint32_t events);
int wsg_loop_watch_del(struct wsg_loop *l, struct wsg_watch *w);

#endif
