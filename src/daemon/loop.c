/*
 * The epoll loop. Model steps follow a fixed grid of CLOCK_MONOTONIC times
 * (due_ns, due_ns + step, ...) set on an absolute periodic timerfd, so the
 * models' simulated time tracks the wall clock without drift from wake-up
 * latency. l->grid counts the grid points passed: the simulated time of
 * every gripper that is stepped. A gripper with nothing to do (idle model,
 * no stream, no packet waiting to leave) is off the active list and not
 * stepped; its device time lags and is brought to the grid in one
 * wsg_device_advance_idle call when an event or the control channel
 * touches it, which keeps simulated time (and with it stream and motion
 * timing) on the same grid. With no active gripper the timer is disarmed
 * and the grid points that pass are counted at the next wake.
 *
 * With a time scale X the grid's period is step / X of real time, and
 * below WSG_LOOP_PERIOD_MIN_NS a tick runs several steps instead, so
 * motions and streams run X times faster while the wake rate stays bounded.
 * Paused, the timer is off and no idle time is counted: simulated time moves
 * only by wsg_loop_step. Changing the scale or resuming starts a new grid
 * from now, so real time that passed under the old rate is not replayed.
 *
 * Peers that go away during a batch of events are only marked by their
 * transport; the loop lets the transports finish closing them after the
 * batch, when no event of the batch can still name them.
 */
#define _GNU_SOURCE

#include "loop.h"

#include <errno.h>
#include <signal.h>
#include <stdlib.h>
#include <string.h>
#include <sys/epoll.h>
#include <sys/inotify.h>
#include <sys/signalfd.h>
#include <sys/timerfd.h>
#include <time.h>
#include <unistd.h>

#include "gripper.h"
#include "transport.h"

#define NS_PER_S  1000000000ull
#define NS_PER_US 1000ull

static uint64_t mono_ns(void)
{
    struct timespec ts;

    /* CLOCK_MONOTONIC cannot fail with a valid pointer. */
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (uint64_t)ts.tv_sec * NS_PER_S + (uint64_t)ts.tv_nsec;
}

static struct timespec ns_to_ts(uint64_t ns)
{
    struct timespec ts;

    ts.tv_sec = (time_t)(ns / NS_PER_S);
    ts.tv_nsec = (long)(ns % NS_PER_S);
    return ts;
}

static int epoll_op(struct wsg_loop *l, int op, struct wsg_watch *w,
                    uint32_t events)
{
    struct epoll_event ev;

    memset(&ev, 0, sizeof ev);
    ev.events = events;
    ev.data.ptr = w;
    if (epoll_ctl(l->epfd, op, w->fd, &ev) < 0)
        return -errno;
    return 0;
}

int wsg_loop_watch_add(struct wsg_loop *l, struct wsg_watch *w,
                       uint32_t events)
{
    return epoll_op(l, EPOLL_CTL_ADD, w, events);
}

int wsg_loop_watch_mod(struct wsg_loop *l, struct wsg_watch *w,
                       uint32_t events)
{
    return epoll_op(l, EPOLL_CTL_MOD, w, events);
}

int wsg_loop_watch_del(struct wsg_loop *l, struct wsg_watch *w)
{
    return epoll_op(l, EPOLL_CTL_DEL, w, 0);
}

int wsg_loop_init(struct wsg_loop *l, uint32_t step_us)
{
    sigset_t mask;
    int r;

    memset(l, 0, sizeof *l);
    l->epfd = -1;
    l->timer.fd = -1;
    l->signal.fd = -1;
    l->inotify.fd = -1;
    l->step_ns = (uint64_t)step_us * NS_PER_US;
    l->scale = 1.0;
    l->period_ns = l->step_ns;
    l->tick_steps = 1;

    /* Blocked before anything else exists, so a SIGTERM sent right after
     * the ready line is queued for the signalfd, never the default
     * action. */
    sigemptyset(&mask);
    sigaddset(&mask, SIGINT);
    sigaddset(&mask, SIGTERM);
    if (sigprocmask(SIG_BLOCK, &mask, NULL) < 0)
        return -errno;

    /* One receive buffer for every transport: the loop runs one handler at
     * a time, and a fleet must not hold a datagram's worth per gripper. */
    l->rxlen = WSG_LOOP_RX_MAX;
    l->rx = malloc(l->rxlen);
    if (!l->rx) {
        r = -ENOMEM;
        goto fail_r;
    }
    l->epfd = epoll_create1(EPOLL_CLOEXEC);
    if (l->epfd < 0)
        goto fail;
    l->signal.fd = signalfd(-1, &mask, SFD_NONBLOCK | SFD_CLOEXEC);
    if (l->signal.fd < 0)
        goto fail;
    l->timer.fd = timerfd_create(CLOCK_MONOTONIC, TFD_NONBLOCK | TFD_CLOEXEC);
    if (l->timer.fd < 0)
        goto fail;
    r = wsg_loop_watch_add(l, &l->signal, EPOLLIN);
    if (r < 0)
        goto fail_r;
    r = wsg_loop_watch_add(l, &l->timer, EPOLLIN);
    if (r < 0)
        goto fail_r;
    /* The grid's origin: the first tick is one period after start. */
    l->due_ns = mono_ns() + l->period_ns;
    return 0;

fail:
    r = -errno;
fail_r:
    wsg_loop_fini(l);
    return r;
}

void wsg_loop_fini(struct wsg_loop *l)
{
    if (l->inotify.fd >= 0)
        close(l->inotify.fd);
    l->inotify.fd = -1;
    free(l->fswatch);
    l->fswatch = NULL;
    l->nfswatch = 0;
    if (l->timer.fd >= 0)
        close(l->timer.fd);
    if (l->signal.fd >= 0)
        close(l->signal.fd);
    if (l->epfd >= 0)
        close(l->epfd);
    l->timer.fd = -1;
    l->signal.fd = -1;
    l->epfd = -1;
    free(l->rx);
    l->rx = NULL;
}

int wsg_loop_fswatch_add(struct wsg_loop *l, const char *path, uint32_t mask,
                         struct wsg_watch *w)
{
    int wd;
    int r;

    if (l->inotify.fd < 0) {
        l->inotify.fd = inotify_init1(IN_NONBLOCK | IN_CLOEXEC);
        if (l->inotify.fd < 0)
            return -errno;
        r = wsg_loop_watch_add(l, &l->inotify, EPOLLIN);
        if (r < 0) {
            close(l->inotify.fd);
            l->inotify.fd = -1;
            return r;
        }
    }
    wd = inotify_add_watch(l->inotify.fd, path, mask);
    if (wd < 0)
        return -errno;
    if ((size_t)wd >= l->nfswatch) {
        size_t n = l->nfswatch ? l->nfswatch : 16;
        struct wsg_watch **t;

        while (n <= (size_t)wd)
            n *= 2;
        t = realloc(l->fswatch, n * sizeof *t);
        if (!t) {
            inotify_rm_watch(l->inotify.fd, wd);
            return -ENOMEM;
        }
        memset(t + l->nfswatch, 0, (n - l->nfswatch) * sizeof *t);
        l->fswatch = t;
        l->nfswatch = n;
    }
    l->fswatch[wd] = w;
    return wd;
}

void wsg_loop_fswatch_del(struct wsg_loop *l, int wd)
{
    if (wd < 0 || (size_t)wd >= l->nfswatch || !l->fswatch[wd])
        return;
    l->fswatch[wd] = NULL;
    inotify_rm_watch(l->inotify.fd, wd);
}

void wsg_loop_set_grippers(struct wsg_loop *l, struct wsg_gripper *g, size_t n)
{
    l->grippers = g;
    l->ngrippers = n;
}

void wsg_loop_set_shared(struct wsg_loop *l, struct wsg_transport *t, size_t n)
{
    l->shared = t;
    l->nshared = n;
}

/* An inactive gripper's time lagged: it was idle all along, so the steps
 * it missed change nothing but its clock. */
static void sync_time(struct wsg_loop *l, struct wsg_gripper *g)
{
    if (g->active || g->at == l->grid)
        return;
    wsg_device_advance_idle(&g->dev, l->grid - g->at);
    g->at = l->grid;
}

static void queue_touched(struct wsg_loop *l, struct wsg_gripper *g)
{
    if (g->touched)
        return;
    g->touched = 1;
    g->next_touched = l->touched;
    l->touched = g;
}

void wsg_loop_touch(struct wsg_loop *l, struct wsg_gripper *g)
{
    sync_time(l, g);
    queue_touched(l, g);
}

void wsg_loop_check(struct wsg_loop *l, struct wsg_gripper *g)
{
    if (g->active || !wsg_gripper_busy(g))
        return;
    sync_time(l, g);
    g->active = 1;
    g->next_active = l->active;
    l->active = g;
    l->nactive++;
}

/* One grid step, k model steps per active gripper (a tick at a fast time
 * scale runs several): each is stepped, its streams polled, what its delay
 * lines hold for that moment sent (--latency), and it leaves the list when
 * nothing is left to do. */
static void run_steps(struct wsg_loop *l, unsigned k)
{
    struct wsg_gripper **pp = &l->active;
    struct wsg_gripper *g;

    while ((g = *pp) != NULL) {
        unsigned i;

        for (i = 0; i < k; i++) {
            wsg_device_step(&g->dev);
            wsg_device_poll_streaming(&g->dev);
            wsg_gripper_release(g);
        }
        l->dev_steps += k;
        g->at += k;
        if (wsg_gripper_busy(g)) {
            pp = &g->next_active;
        } else {
            *pp = g->next_active;
            g->active = 0;
            l->nactive--;
        }
    }
    l->grid += k;
    l->steps += k;
}

/* While disarmed nothing was active: the grid points up to now passed
 * without a step and are only counted; each gripper catches up when it is
 * touched. Done before the batch's events are handled, because their input
 * may end the idleness. */
static void skip_idle(struct wsg_loop *l, uint64_t now)
{
    uint64_t n;

    if (l->paused || l->due_ns > now)
        return;
    n = (now - l->due_ns) / l->period_ns + 1;
    l->grid += n * l->tick_steps;
    l->due_ns += n * l->period_ns;
    l->idle_steps += n * l->tick_steps;
}

static int set_timer(struct wsg_loop *l, int arm)
{
    struct itimerspec its;

    memset(&its, 0, sizeof its);
    if (arm) {
        its.it_value = ns_to_ts(l->due_ns);
        its.it_interval = ns_to_ts(l->period_ns);
    }
    if (timerfd_settime(l->timer.fd, TFD_TIMER_ABSTIME, &its, NULL) < 0)
        return -errno;
    l->armed = arm;
    return 0;
}

static int update_timer(struct wsg_loop *l)
{
    int want = !l->paused && l->active != NULL;

    if (want == l->armed)
        return 0;
    /* Arming at due_ns keeps the grid; if due_ns has passed meanwhile the
     * timer fires at once and the step runs late, not skipped. */
    return set_timer(l, want);
}

static void on_timer(struct wsg_loop *l)
{
    uint64_t expirations;
    uint64_t now;
    unsigned n = 0;

    /* The count is not used: due_ns and the clock say what is due. A read
     * may find nothing when the timer was re-set since it fired. */
    if (read(l->timer.fd, &expirations, sizeof expirations) < 0 &&
        errno != EAGAIN)
        return;
    if (!l->armed)
        return;
    now = mono_ns();
    if (l->due_ns <= now && now - l->due_ns > l->late_max_ns)
        l->late_max_ns = now - l->due_ns;
    while (l->due_ns <= now && n < WSG_LOOP_CATCHUP_MAX) {
        run_steps(l, l->tick_steps);
        l->due_ns += l->period_ns;
        n++;
    }
    if (l->due_ns <= now) {
        /* Too far behind to catch up: drop whole ticks up to the grid point
         * before now, which runs on the next wake. */
        uint64_t skip = (now - l->due_ns) / l->period_ns;

        l->due_ns += skip * l->period_ns;
        l->overruns += skip * l->tick_steps;
    }
}

/* A new grid from now: real time that passed under the old rate (or while
 * paused) is not replayed. The model's time stays where it is. */
static int regrid(struct wsg_loop *l)
{
    int r;

    if (l->armed) {
        r = set_timer(l, 0);
        if (r < 0)
            return r;
    }
    l->due_ns = mono_ns() + l->period_ns;
    return update_timer(l);
}

int wsg_loop_set_scale(struct wsg_loop *l, double scale)
{
    double period;
    unsigned k = 1;

    if (!(scale >= WSG_LOOP_SCALE_MIN && scale <= WSG_LOOP_SCALE_MAX))
        return -EINVAL;
    /* Idle time so far counts at the old rate. */
    if (!l->armed)
        skip_idle(l, mono_ns());
    period = (double)l->step_ns / scale;
    if (period < (double)WSG_LOOP_PERIOD_MIN_NS) {
        k = (unsigned)((double)WSG_LOOP_PERIOD_MIN_NS / period) + 1u;
        period *= k;
    }
    l->scale = scale;
    l->tick_steps = k;
    l->period_ns = (uint64_t)(period + 0.5);
    if (l->paused)
        return 0;
    return regrid(l);
}

int wsg_loop_pause(struct wsg_loop *l)
{
    if (l->paused)
        return 0;
    if (!l->armed)
        skip_idle(l, mono_ns());
    l->paused = 1;
    return l->armed ? set_timer(l, 0) : 0;
}

int wsg_loop_resume(struct wsg_loop *l)
{
    if (!l->paused)
        return 0;
    l->paused = 0;
    return regrid(l);
}

int wsg_loop_step(struct wsg_loop *l, uint64_t nsteps)
{
    if (!l->paused)
        return -EBUSY;
    while (nsteps > 0) {
        /* Nothing to do and no input can arrive meanwhile: the rest would
         * change nothing but the time. */
        if (!l->active) {
            l->grid += nsteps;
            l->idle_steps += nsteps;
            break;
        }
        run_steps(l, 1);
        nsteps--;
    }
    return 0;
}

static void on_signal(struct wsg_loop *l)
{
    struct signalfd_siginfo si;

    while (read(l->signal.fd, &si, sizeof si) == (ssize_t)sizeof si)
        if (si.ssi_signo == SIGINT || si.ssi_signo == SIGTERM)
            l->stop = 1;
}

/* One event to the transport that owns w, with its gripper's time
 * brought up to the grid first and its work checked after: a motion it
 * started is stepped from the next tick, even one in this batch. */
static void dispatch(struct wsg_loop *l, struct wsg_watch *w, uint32_t events)
{
    struct wsg_gripper *g = w->owner->gripper;

    if (g)
        wsg_loop_touch(l, g);
    w->owner->ops->handle(w->owner, w, events);
    if (g)
        wsg_loop_check(l, g);
}

static void on_inotify(struct wsg_loop *l)
{
    /* Aligned as inotify_event requires; the watches are on files, so the
     * events carry no names. */
    union {
        struct inotify_event ev;
        char bytes[4096];
    } buf;

    for (;;) {
        ssize_t n = read(l->inotify.fd, &buf, sizeof buf);
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
            if (ev.wd < 0 || (size_t)ev.wd >= l->nfswatch)
                continue;
            w = l->fswatch[ev.wd];
            if (w && w->owner)
                dispatch(l, w, EPOLLIN);
        }
    }
}

/* Closing a peer may FAST STOP a model, so the active list (and with it
 * the timer) is decided after the closes. */
static void settle(struct wsg_loop *l)
{
    struct wsg_gripper *g;

    wsg_transport_settle(l->shared, l->nshared);
    while ((g = l->touched) != NULL) {
        l->touched = g->next_touched;
        g->touched = 0;
        wsg_transport_settle(g->transports, g->ntransports);
        wsg_loop_check(l, g);
    }
}

int wsg_loop_run(struct wsg_loop *l)
{
    struct epoll_event ev[WSG_LOOP_EVENTS];
    int r;

    r = update_timer(l);
    if (r < 0)
        return r;
    while (!l->stop) {
        int n = epoll_wait(l->epfd, ev, WSG_LOOP_EVENTS, -1);
        int i;

        if (n < 0) {
            if (errno == EINTR)
                continue;
            return -errno;
        }
        if (!l->armed)
            skip_idle(l, mono_ns());
        for (i = 0; i < n; i++) {
            struct wsg_watch *w = ev[i].data.ptr;

            if (w->owner)
                dispatch(l, w, ev[i].events);
            else if (w == &l->timer)
                on_timer(l);
            else if (w == &l->signal)
                on_signal(l);
            else if (w == &l->inotify)
                on_inotify(l);
        }
        settle(l);
        r = update_timer(l);
        if (r < 0)
            return r;
        if (l->settled)
            l->settled(l->settled_ctx);
    }
    return 0;
}
