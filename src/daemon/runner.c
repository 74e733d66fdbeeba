/*
 * The script runner (runner.h): a list of grippers that want a turn and an
 * eventfd that makes the loop come round to them. A turn is taken from
 * the list first, so a script preempted again during its turn is on the
 * next round's list, not this one's: one slice per script per round.
 */
#include "runner.h"

#include <errno.h>
#include <stdint.h>
#include <sys/epoll.h>
#include <sys/eventfd.h>
#include <unistd.h>

#include "gripper.h"
#include "script.h"

static void runner_signal(struct wsg_runner *r)
{
    uint64_t one = 1;

    if (r->signalled)
        return;
    /* Cannot fail short of a counter at its maximum, which a flag that
     * is cleared on every read never lets it reach. */
    if (write(r->watch.fd, &one, sizeof one) == (ssize_t)sizeof one)
        r->signalled = 1;
}

static void runner_event(struct wsg_watch *w, uint32_t events)
{
    struct wsg_runner *r = w->ctx;
    struct wsg_gripper *g, *next;
    uint64_t count;

    (void)events;
    if (read(w->fd, &count, sizeof count) < 0 && errno != EAGAIN)
        return;
    r->signalled = 0;
    g = r->ready;
    r->ready = NULL;
    for (; g; g = next) {
        next = g->next_ready;
        g->next_ready = NULL;
        g->ready = 0;
        wsg_sched_touch(r->sched, g);
        wsg_script_run(g->script);
        wsg_axis_settle(wsg_device_axis(&g->dev));
    }
}

int wsg_runner_init(struct wsg_runner *r, struct wsg_reactor *reactor,
                    struct wsg_sched *sched)
{
    int fd = eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC);

    r->ready = NULL;
    r->signalled = 0;
    r->sched = sched;
    wsg_watch_init(&r->watch, fd, runner_event, r);
    if (fd < 0)
        return -errno;
    return wsg_reactor_add(reactor, &r->watch, EPOLLIN);
}

void wsg_runner_fini(struct wsg_runner *r)
{
    if (r->watch.fd >= 0)
        close(r->watch.fd);
    r->watch.fd = -1;
    r->ready = NULL;
}

void wsg_runner_wake(struct wsg_runner *r, struct wsg_gripper *g)
{
    if (!g->ready) {
        g->ready = 1;
        g->next_ready = r->ready;
        r->ready = g;
    }
    runner_signal(r);
}

void wsg_runner_forget(struct wsg_runner *r, struct wsg_gripper *g)
{
    struct wsg_gripper **pp;

    for (pp = &r->ready; *pp; pp = &(*pp)->next_ready)
        if (*pp == g) {
            *pp = g->next_ready;
            break;
        }
    g->next_ready = NULL;
    g->ready = 0;
}
