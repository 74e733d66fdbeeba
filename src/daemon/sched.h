/*
 * The scheduler: it owns the grippers' simulated time and steps them, and
 * it alone deals with time. Simulated time is one grid of model steps for
 * the whole process, laid on CLOCK_MONOTONIC at a scale, paused or stepped
 * by hand. Each gripper has a deadline: the grid step at which it next
 * needs to run (every step while its model moves, the next stream packet
 * or delayed answer otherwise, none when idle), kept in a min-heap; one
 * absolute timerfd, a watch of the reactor, is armed for the earliest, so
 * nothing wakes before the next deadline and an idle process never wakes.
 *
 * Grippers run from their due step, never from "now": a late wake steps
 * every step that was due (up to WSG_SCHED_CATCHUP_MAX ticks; further
 * behind, whole ticks are dropped and counted as overruns). A gripper
 * that is touched (an event on one of its interfaces, the control
 * channel) is brought to the current grid first, and rescheduled after the
 * batch, when the peers its transports marked gone are reaped.
 */
#ifndef WSG_DAEMON_SCHED_H
#define WSG_DAEMON_SCHED_H

#include <stddef.h>
#include <stdint.h>

#include "reactor.h"

/* Ticks a late wake catches up at most; further behind, whole ticks are
 * dropped (overruns). */
#define WSG_SCHED_CATCHUP_MAX 50u
/* The shortest time between wakes: a faster scale runs several steps per
 * tick rather than waking more often than this. */
#define WSG_SCHED_PERIOD_MIN_NS 50000ull
/* Scales accepted by wsg_sched_set_scale. */
#define WSG_SCHED_SCALE_MIN 0.001
#define WSG_SCHED_SCALE_MAX 1000.0
/* A deadline of none. */
#define WSG_SCHED_NEVER UINT64_MAX

struct wsg_gripper;

struct wsg_sched_stats {
    uint64_t steps;       /* grid steps passed (simulated time in steps) */
    uint64_t dev_steps;   /* model steps run, over all grippers */
    uint64_t overruns;    /* grid steps dropped: the loop fell behind */
    uint64_t idle_steps;  /* grid steps passed with nothing scheduled */
    uint64_t wakes;       /* timer wakes */
    uint64_t late_max_ns; /* worst lateness of a timer wake */
};

struct wsg_sched {
    struct wsg_reactor *reactor;
    struct wsg_watch timer; /* timerfd */
    struct wsg_gripper *grippers;
    size_t ngrippers;
    struct wsg_gripper **heap; /* grippers with a deadline, earliest first */
    size_t nheap;
    struct wsg_gripper *touched; /* to reap and reschedule after the batch */
    uint64_t grid;               /* grid steps passed */
    uint64_t step_ns;            /* simulated time of one model step */
    double scale;                /* simulated seconds per real second */
    uint64_t period_ns;          /* real time of one tick */
    unsigned tick_steps;         /* model steps per tick */
    uint64_t base_ns;   /* CLOCK_MONOTONIC time of grid step base_grid */
    uint64_t base_grid; /* on a tick boundary */
    uint64_t armed_ns;  /* when the timer fires, 0: disarmed */
    int paused;
    struct wsg_sched_stats stats;
};

/* The timerfd on r, time at scale 1. 0 or -errno; fini is safe either
 * way. */
int wsg_sched_init(struct wsg_sched *s, struct wsg_reactor *r,
                   uint32_t step_us);
void wsg_sched_fini(struct wsg_sched *s);
/* The grippers it schedules (their sched is set here): their time is
 * their model's, on the grid from 0. Returns 0
 * or -ENOMEM. */
int wsg_sched_set_grippers(struct wsg_sched *s, struct wsg_gripper *g,
                           size_t n);
/* Before acting on g (an event of its interfaces, the control channel):
 * bring g to the current grid, and reschedule it after the batch. */
void wsg_sched_touch(struct wsg_sched *s, struct wsg_gripper *g);
/* Only reschedule g (and reap its transports) after the batch: safe while
 * g runs (a step's send that marks a peer gone). */
void wsg_sched_defer(struct wsg_sched *s, struct wsg_gripper *g);
/* After acting on g: its deadline from what it has to do now. */
void wsg_sched_check(struct wsg_sched *s, struct wsg_gripper *g);
/* Simulated time at scale times real time, from now. 0, or -EINVAL for a
 * scale outside [WSG_SCHED_SCALE_MIN, WSG_SCHED_SCALE_MAX]. A paused
 * scheduler stays paused and takes the scale on when resumed. */
int wsg_sched_set_scale(struct wsg_sched *s, double scale);
/* Stop simulated time (streams too: they run in it). 0 or -errno. */
int wsg_sched_pause(struct wsg_sched *s);
/* Run simulated time again from now, keeping the grippers' time. */
int wsg_sched_resume(struct wsg_sched *s);
/* While paused: pass nsteps grid steps right away, running every gripper
 * through whatever falls due in them. 0, or -EBUSY when not paused. */
int wsg_sched_step(struct wsg_sched *s, uint64_t nsteps);
/* Grippers with a deadline. */
size_t wsg_sched_active(const struct wsg_sched *s);

#endif
