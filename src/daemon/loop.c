/*
 * The epoll loop. Model steps follow a fixed grid of CLOCK_MONOTONIC times
 * (due_ns, due_ns + step, ...) set on an absolute periodic timerfd, so the
 * model's simulated time tracks the wall clock without drift from wake-up
 * latency. While the model is idle and nobody streams, the timer is disarmed
 * and the grid points that pass are accounted for in one
 * wsg_device_advance_idle call at the next wake, which keeps simulated time
 * (and with it stream and motion timing) on the same grid.
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
#include <string.h>
#include <sys/epoll.h>
#include <sys/signalfd.h>
#include <sys/timerfd.h>
#include <time.h>
#include <unistd.h>

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

int wsg_loop_init(struct wsg_loop *l, struct wsg_device *dev, uint32_t step_us)
{
    sigset_t mask;
    int r;

    memset(l, 0, sizeof *l);
    l->epfd = -1;
    l->timer.fd = -1;
    l->signal.fd = -1;
    l->dev = dev;
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
    if (l->timer.fd >= 0)
        close(l->timer.fd);
    if (l->signal.fd >= 0)
        close(l->signal.fd);
    if (l->epfd >= 0)
        close(l->epfd);
    l->timer.fd = -1;
    l->signal.fd = -1;
    l->epfd = -1;
}

void wsg_loop_set_transports(struct wsg_loop *l, struct wsg_transport *t,
                             size_t n)
{
    l->transports = t;
    l->ntransports = n;
}

static void poll_one(void *ctx, struct wsg_session *s)
{
    struct wsg_loop *l = ctx;

    if (s->nstreams > 0)
        wsg_device_poll_streams(l->dev, s);
}

static void count_streaming(void *ctx, struct wsg_session *s)
{
    int *streaming = ctx;

    if (s->nstreams > 0)
        *streaming = 1;
}

static void run_step(struct wsg_loop *l)
{
    wsg_device_step(l->dev);
    wsg_transport_each_session(l->transports, l->ntransports, poll_one, l);
    l->steps++;
}

static void run_tick(struct wsg_loop *l)
{
    unsigned i;

    for (i = 0; i < l->tick_steps; i++)
        run_step(l);
}

static int needs_steps(struct wsg_loop *l)
{
    int streaming = 0;

    if (!wsg_device_idle(l->dev))
        return 1;
    wsg_transport_each_session(l->transports, l->ntransports, count_streaming,
                               &streaming);
    return streaming;
}

/* While disarmed the model was idle: the grid points up to now passed
 * without a step, and only simulated time has to catch up. Done before the
 * batch's events are handled, because their input may end the idleness. */
static void skip_idle(struct wsg_loop *l, uint64_t now)
{
    uint64_t n;

    if (l->paused || l->due_ns > now)
        return;
    n = (now - l->due_ns) / l->period_ns + 1;
    wsg_device_advance_idle(l->dev, n * l->tick_steps);
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
    int want = !l->paused && needs_steps(l);

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
    while (l->due_ns <= now && n < WSG_LOOP_CATCHUP_MAX) {
        run_tick(l);
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
        if (!needs_steps(l)) {
            wsg_device_advance_idle(l->dev, nsteps);
            l->idle_steps += nsteps;
            break;
        }
        run_step(l);
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
                w->owner->ops->handle(w->owner, w, ev[i].events);
            else if (w == &l->timer)
                on_timer(l);
            else if (w == &l->signal)
                on_signal(l);
        }
        /* Closing a peer may FAST STOP the model, so the timer is decided
         * after it. */
        wsg_transport_settle(l->transports, l->ntransports);
        r = update_timer(l);
        if (r < 0)
            return r;
        if (l->settled)
            l->settled(l->settled_ctx);
    }
    return 0;
}
