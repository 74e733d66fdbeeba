/*
 * The script runner: the service on the reactor that gives preempted
 * scripts the processor again. A script host that used up its slice asks
 * for a turn (wsg_runner_wake); the runner signals an eventfd and, when
 * the loop gets to it among the other ready descriptors, gives every
 * gripper that asked one more slice. So a script that never waits costs
 * its slices, and the interfaces are served between them.
 */
#ifndef WSG_DAEMON_RUNNER_H
#define WSG_DAEMON_RUNNER_H

#include "reactor.h"
#include "sched.h"

struct wsg_gripper;

struct wsg_runner {
    struct wsg_watch watch; /* eventfd; fd -1: not open */
    struct wsg_sched *sched;
    struct wsg_gripper *ready; /* grippers whose script wants a turn */
    int signalled;             /* the eventfd holds a count */
};

/* 0 or -errno; wsg_runner_fini is safe either way. */
int wsg_runner_init(struct wsg_runner *r, struct wsg_reactor *reactor,
                    struct wsg_sched *sched);
void wsg_runner_fini(struct wsg_runner *r);
/* g's script was preempted: give it a slice once the loop comes round. */
void wsg_runner_wake(struct wsg_runner *r, struct wsg_gripper *g);
/* g goes away: forget its turn. */
void wsg_runner_forget(struct wsg_runner *r, struct wsg_gripper *g);

#endif
