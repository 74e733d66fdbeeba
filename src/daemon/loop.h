/*
 * The daemon's single epoll loop: the transports' file descriptors, a
 * timerfd that paces the models' fixed steps on an absolute grid, and a
 * signalfd for SIGINT/SIGTERM. It serves one gripper or a fleet of them
 * (--grippers). Only grippers whose model has work, whose sessions
 * stream auto-updates or that have packets waiting to leave (--latency)
 * are on the active list and stepped; the timer runs
 * only while that list is not empty, so an idle emulator does not wake and
 * a fleet costs what moves, not what exists.
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
/* The shared receive buffer: the largest datagram. */
#define WSG_LOOP_RX_MAX 65536u
/* The shortest timer period: a faster scale runs several steps per tick
 * rather than waking more often than this. */
#define WSG_LOOP_PERIOD_MIN_NS 50000ull
/* Scales accepted by wsg_loop_set_scale. */
#define WSG_LOOP_SCALE_MIN 0.001
#define WSG_LOOP_SCALE_MAX 1000.0

struct wsg_transport;
struct wsg_gripper;

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
    /* One inotify instance for every file watch of the process (the
     * kernel allows few instances per user, and a fleet has a pty each):
     * fswatch[wd] is the watch an event of that descriptor goes to. */
    struct wsg_watch inotify; /* fd -1 until the first file watch */
    struct wsg_watch **fswatch;
    size_t nfswatch;
    struct wsg_gripper *grippers;
    size_t ngrippers;
    /* Transports of the process, not of a gripper (the control channel). */
    struct wsg_transport *shared;
    size_t nshared;
    struct wsg_gripper *active;  /* stepped on every tick */
    struct wsg_gripper *touched; /* to settle after this batch */
    size_t nactive;
    uint64_t grid;       /* simulated time in steps: grid points passed */
    uint64_t step_ns;    /* simulated time of one model step */
    double scale;        /* simulated seconds per real second */
    uint64_t period_ns;  /* real time between timer ticks */
    unsigned tick_steps; /* model steps per tick */
    uint64_t due_ns;     /* CLOCK_MONOTONIC time of the next tick not run */
    int armed;
    int paused; /* simulated time stands still (steps only by hand) */
    int stop;
    uint64_t steps;       /* grid steps run with the timer or by hand */
    uint64_t dev_steps;   /* model steps run, over all grippers */
    uint64_t overruns;    /* grid steps skipped: the loop fell behind */
    uint64_t idle_steps;  /* grid steps passed with nothing active */
    uint64_t late_max_ns; /* worst lateness of a tick run by the timer */
    uint8_t *rx;          /* receive buffer the transports share */
    size_t rxlen;
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
int wsg_loop_init(struct wsg_loop *l, uint32_t step_us);
void wsg_loop_fini(struct wsg_loop *l);
/* The grippers the loop steps, and the process's own transports whose
 * peers it settles after each batch. */
void wsg_loop_set_grippers(struct wsg_loop *l, struct wsg_gripper *g,
                           size_t n);
void wsg_loop_set_shared(struct wsg_loop *l, struct wsg_transport *t,
                         size_t n);
/* Before anything acts on g from outside the loop's own dispatch (the
 * control channel), and when a transport marks a peer of g to be closed
 * (even from a step's send): bring g's simulated time up to the grid and
 * queue it to be settled after the batch. */
void wsg_loop_touch(struct wsg_loop *l, struct wsg_gripper *g);
/* After acting on g: step it from the next tick if it now has work. */
void wsg_loop_check(struct wsg_loop *l, struct wsg_gripper *g);
/* Simulated time at scale times real time, re-gridded from now. 0, or
 * -EINVAL for a scale outside [WSG_LOOP_SCALE_MIN, WSG_LOOP_SCALE_MAX]. A
 * paused loop stays paused and takes the scale on when resumed. */
int wsg_loop_set_scale(struct wsg_loop *l, double scale);
/* Stop simulated time (streams too: they run in it). 0 or -errno. */
int wsg_loop_pause(struct wsg_loop *l);
/* Run simulated time again from now, keeping the model's time. */
int wsg_loop_resume(struct wsg_loop *l);
/* While paused: run nsteps grid steps right away, each a model step, the
 * stream polls and the release of delayed packets of every active gripper
 * (steps with nothing active are only counted). Returns 0, or -EBUSY when
 * not paused. */
int wsg_loop_step(struct wsg_loop *l, uint64_t nsteps);
/* Serve until SIGINT or SIGTERM: returns 0 then, -errno on failure. */
int wsg_loop_run(struct wsg_loop *l);

/* Watch path for the inotify events in mask: each delivers EPOLLIN to w's
 * owner (w->fd is not used). Returns the watch descriptor or -errno. */
int wsg_loop_fswatch_add(struct wsg_loop *l, const char *path, uint32_t mask,
                         struct wsg_watch *w);
void wsg_loop_fswatch_del(struct wsg_loop *l, int wd);

int wsg_loop_watch_add(struct wsg_loop *l, struct wsg_watch *w,
                       uint32_t events);
int wsg_loop_watch_mod(struct wsg_loop *l, struct wsg_watch *w,
                       uint32_t events);
int wsg_loop_watch_del(struct wsg_loop *l, struct wsg_watch *w);

#endif
