/*
 * The scheduler. Grid step g falls at CLOCK_MONOTONIC time
 * base_ns + (g - base_grid) / tick_steps * period_ns; a change of scale or
 * a resume lays a new base at the current grid, so real time that passed
 * under the old rate (or while paused) is not replayed. The grid is read
 * off the clock whenever something needs the present (a timer wake, a
 * touch); with nothing scheduled it advances freely (idle), and with
 * something due it advances at most WSG_SCHED_CATCHUP_MAX ticks past the
 * earliest deadline, the rest being dropped by moving the base.
 */
#define _GNU_SOURCE

#include "sched.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>
#include <sys/epoll.h>
#include <sys/timerfd.h>
#include <time.h>
#include <unistd.h>

#include "gripper.h"

#define NS_PER_S  1000000000ull
#define NS_PER_US 1000ull
#define HEAP_NONE ((size_t)-1)

static uint64_t mono_ns(void)
{
    struct timespec ts;

    /* CLOCK_MONOTONIC cannot fail with a valid pointer. */
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (uint64_t)ts.tv_sec * NS_PER_S + (uint64_t)ts.tv_nsec;
}

/* ---- the heap of deadlines ---- */

static void heap_set(struct wsg_sched *s, size_t i, struct wsg_gripper *g)
{
    s->heap[i] = g;
    g->heap_idx = i;
}

static void heap_up(struct wsg_sched *s, size_t i)
{
    struct wsg_gripper *g = s->heap[i];

    while (i > 0) {
        size_t p = (i - 1) / 2;

        if (s->heap[p]->due <= g->due)
            break;
        heap_set(s, i, s->heap[p]);
        i = p;
    }
    heap_set(s, i, g);
}

static void heap_down(struct wsg_sched *s, size_t i)
{
    struct wsg_gripper *g = s->heap[i];

    for (;;) {
        size_t c = 2 * i + 1;

        if (c >= s->nheap)
            break;
        if (c + 1 < s->nheap && s->heap[c + 1]->due < s->heap[c]->due)
            c++;
        if (g->due <= s->heap[c]->due)
            break;
        heap_set(s, i, s->heap[c]);
        i = c;
    }
    heap_set(s, i, g);
}

static void heap_remove(struct wsg_sched *s, struct wsg_gripper *g)
{
    size_t i = g->heap_idx;
    struct wsg_gripper *last;

    if (i == HEAP_NONE)
        return;
    g->heap_idx = HEAP_NONE;
    last = s->heap[--s->nheap];
    if (last == g)
        return;
    heap_set(s, i, last);
    heap_down(s, i);
    heap_up(s, last->heap_idx);
}

/* g's deadline is now due (WSG_SCHED_NEVER: none). */
static void schedule(struct wsg_sched *s, struct wsg_gripper *g, uint64_t due)
{
    if (due == WSG_SCHED_NEVER) {
        heap_remove(s, g);
        g->due = due;
        return;
    }
    g->due = due;
    if (g->heap_idx == HEAP_NONE) {
        /* Room for every gripper was made up front. */
        heap_set(s, s->nheap++, g);
        heap_up(s, g->heap_idx);
    } else {
        heap_up(s, g->heap_idx);
        heap_down(s, g->heap_idx);
    }
}

/* ---- time ---- */

/* Run g through the steps up to the grid and reschedule it from there.
 * The gripper's own time is its model's: on the grid, it stands at the
 * step its model's time counts (one clock, read in steps). */
static void run_to_grid(struct wsg_sched *s, struct wsg_gripper *g)
{
    const struct wsg_axis *ax = wsg_device_axis(&g->dev);
    uint64_t at = wsg_axis_time(ax) / wsg_axis_cfg(ax)->step_us, k;

    if (at < s->grid)
        s->stats.dev_steps += wsg_gripper_process(g, s->grid - at);
    k = wsg_gripper_next(g);
    schedule(s, g, k == WSG_SCHED_NEVER ? k : s->grid + k);
}

/* The tick that grid step g falls in, rounded up, as a grid step. */
static uint64_t tick_ceil(const struct wsg_sched *s, uint64_t g)
{
    uint64_t d = g > s->base_grid ? g - s->base_grid : 0;

    return s->base_grid +
           (d + s->tick_steps - 1) / s->tick_steps * s->tick_steps;
}

static uint64_t grid_time_ns(const struct wsg_sched *s, uint64_t g)
{
    return s->base_ns +
           (tick_ceil(s, g) - s->base_grid) / s->tick_steps * s->period_ns;
}

/* Read the grid off the clock. */
static void update_grid(struct wsg_sched *s)
{
    uint64_t now, target, limit;

    if (s->paused)
        return;
    now = mono_ns();
    if (now < s->base_ns)
        return;
    target = s->base_grid +
             (now - s->base_ns) / s->period_ns * (uint64_t)s->tick_steps;
    if (target <= s->grid)
        return;
    if (s->nheap == 0) {
        s->stats.idle_steps += target - s->grid;
    } else {
        /* Past the earliest deadline only so far: the steps beyond are
         * dropped, and simulated time falls behind real time by them. */
        uint64_t from = s->heap[0]->due > s->grid ? s->heap[0]->due : s->grid;

        limit = tick_ceil(s, from) +
                (uint64_t)WSG_SCHED_CATCHUP_MAX * s->tick_steps;
        if (target > limit) {
            uint64_t drop = target - limit;

            s->stats.overruns += drop;
            s->base_ns += drop / s->tick_steps * s->period_ns;
            target = limit;
        }
    }
    s->stats.steps += target - s->grid;
    s->grid = target;
}

/* Run every gripper whose deadline has come. */
static void run_due(struct wsg_sched *s)
{
    while (s->nheap > 0 && s->heap[0]->due <= s->grid)
        run_to_grid(s, s->heap[0]);
}

static int arm(struct wsg_sched *s, uint64_t at_ns)
{
    struct itimerspec its;

    if (at_ns == s->armed_ns)
        return 0;
    memset(&its, 0, sizeof its);
    its.it_value.tv_sec = (time_t)(at_ns / NS_PER_S);
    its.it_value.tv_nsec = (long)(at_ns % NS_PER_S);
    if (timerfd_settime(s->timer.fd, TFD_TIMER_ABSTIME, &its, NULL) < 0)
        return -errno;
    s->armed_ns = at_ns;
    return 0;
}

/* The timer for the earliest deadline, or off. */
static int update_timer(struct wsg_sched *s)
{
    if (s->paused || s->nheap == 0)
        return arm(s, 0);
    /* A deadline already passed fires at once (time 1 is long past). */
    return arm(
        s, s->heap[0]->due <= s->grid ? 1 : grid_time_ns(s, s->heap[0]->due));
}

static void on_timer(struct wsg_watch *w, uint32_t events)
{
    struct wsg_sched *s = w->ctx;
    uint64_t expirations, now;

    (void)events;
    /* The count does not matter: the clock says what is due. */
    if (read(s->timer.fd, &expirations, sizeof expirations) < 0 &&
        errno != EAGAIN)
        return;
    if (s->armed_ns == 0)
        return;
    now = mono_ns();
    if (s->armed_ns > 1 && s->armed_ns != WSG_SCHED_NEVER &&
        now > s->armed_ns && now - s->armed_ns > s->stats.late_max_ns)
        s->stats.late_max_ns = now - s->armed_ns;
    s->armed_ns = 0;
    s->stats.wakes++;
    update_grid(s);
    run_due(s);
}

/* After each batch: reap what the touched grippers' transports marked
 * gone (a close may FAST STOP a model), then their deadlines, then the
 * timer. */
static void after_batch(void *ctx)
{
    struct wsg_sched *s = ctx;
    struct wsg_gripper *g;

    while ((g = s->touched) != NULL) {
        s->touched = g->next_touched;
        g->touched = 0;
        wsg_transport_reap(g->transports, g->ntransports);
        run_to_grid(s, g);
    }
    update_timer(s);
}

int wsg_sched_init(struct wsg_sched *s, struct wsg_reactor *r,
                   uint32_t step_us)
{
    int fd, ret;

    memset(s, 0, sizeof *s);
    s->reactor = r;
    s->step_ns = (uint64_t)step_us * NS_PER_US;
    s->scale = 1.0;
    s->period_ns = s->step_ns;
    s->tick_steps = 1;
    s->base_ns = mono_ns();
    fd = timerfd_create(CLOCK_MONOTONIC, TFD_NONBLOCK | TFD_CLOEXEC);
    wsg_watch_init(&s->timer, fd, on_timer, s);
    if (fd < 0)
        return -errno;
    ret = wsg_reactor_add(r, &s->timer, EPOLLIN);
    if (ret == 0)
        ret = wsg_reactor_after(r, after_batch, s);
    return ret;
}

void wsg_sched_fini(struct wsg_sched *s)
{
    if (s->timer.fd >= 0)
        close(s->timer.fd);
    s->timer.fd = -1;
    free(s->heap);
    s->heap = NULL;
    s->nheap = 0;
}

int wsg_sched_set_grippers(struct wsg_sched *s, struct wsg_gripper *g,
                           size_t n)
{
    struct wsg_gripper **h = realloc(s->heap, (n ? n : 1) * sizeof *h);
    size_t i;

    if (!h)
        return -ENOMEM;
    s->heap = h;
    s->nheap = 0;
    s->grippers = g;
    s->ngrippers = n;
    for (i = 0; i < n; i++) {
        g[i].sched = s;
        g[i].due = WSG_SCHED_NEVER;
        g[i].heap_idx = HEAP_NONE;
    }
    return 0;
}

void wsg_sched_defer(struct wsg_sched *s, struct wsg_gripper *g)
{
    if (g->touched)
        return;
    g->touched = 1;
    g->next_touched = s->touched;
    s->touched = g;
}

void wsg_sched_touch(struct wsg_sched *s, struct wsg_gripper *g)
{
    update_grid(s);
    /* Others due by now run first: the grid must not pass a deadline
     * without the steps it stands for. */
    run_due(s);
    run_to_grid(s, g);
    wsg_sched_defer(s, g);
}

void wsg_sched_check(struct wsg_sched *s, struct wsg_gripper *g)
{
    run_to_grid(s, g);
}

/* A new base at the current grid, from now. */
static int rebase(struct wsg_sched *s)
{
    s->base_ns = mono_ns();
    s->base_grid = s->grid;
    s->armed_ns = WSG_SCHED_NEVER; /* whatever it was: set it anew */
    return update_timer(s);
}

int wsg_sched_set_scale(struct wsg_sched *s, double scale)
{
    double period;
    unsigned k = 1;

    if (!(scale >= WSG_SCHED_SCALE_MIN && scale <= WSG_SCHED_SCALE_MAX))
        return -EINVAL;
    /* Time so far counts at the old rate. */
    update_grid(s);
    run_due(s);
    period = (double)s->step_ns / scale;
    if (period < (double)WSG_SCHED_PERIOD_MIN_NS) {
        k = (unsigned)((double)WSG_SCHED_PERIOD_MIN_NS / period) + 1u;
        period *= k;
    }
    s->scale = scale;
    s->tick_steps = k;
    s->period_ns = (uint64_t)(period + 0.5);
    return rebase(s);
}

int wsg_sched_pause(struct wsg_sched *s)
{
    if (s->paused)
        return 0;
    update_grid(s);
    run_due(s);
    s->paused = 1;
    return update_timer(s);
}

int wsg_sched_resume(struct wsg_sched *s)
{
    if (!s->paused)
        return 0;
    s->paused = 0;
    return rebase(s);
}

int wsg_sched_step(struct wsg_sched *s, uint64_t nsteps)
{
    if (!s->paused)
        return -EBUSY;
    if (s->nheap == 0)
        s->stats.idle_steps += nsteps;
    s->stats.steps += nsteps;
    s->grid += nsteps;
    run_due(s);
    return 0;
}

size_t wsg_sched_active(const struct wsg_sched *s)
{
    return s->nheap;
}
