/*
 * The control channel on a bench: a reactor, a scheduler and N grippers of
 * the default model, no interface and no socket, and one session whose
 * answers are collected in a buffer. Used by test_control and the control
 * harness (tests/fuzz/fuzz_control.c); nothing runs the reactor, so time
 * moves only as the commands move it.
 */
#ifndef WSG_TEST_CTLBENCH_H
#define WSG_TEST_CTLBENCH_H

#include <stdlib.h>
#include <string.h>

#include "control.h"
#include "gripper.h"

#define CTLBENCH_OUT_MAX 65536u

struct ctlbench {
    struct wsg_reactor reactor;
    struct wsg_sched sched;
    struct wsg_runner runner; /* a preempted script's turns: never run */
    struct wsg_gripper *grippers;
    size_t ngrippers;
    struct wsg_ctl *ctl;
    struct wsg_ctl_session s;
    size_t answers; /* answer lines so far */
    size_t len;     /* bytes in out */
    char out[CTLBENCH_OUT_MAX + 1];
};

static inline void ctlbench_answer(void *ctx, const char *line, size_t len)
{
    struct ctlbench *b = ctx;

    b->answers++;
    if (len > CTLBENCH_OUT_MAX - b->len)
        len = CTLBENCH_OUT_MAX - b->len;
    memcpy(b->out + b->len, line, len);
    b->len += len;
    b->out[b->len] = '\0';
}

/* 0, or -1 when the bench cannot be set up (descriptors, memory). */
static inline int ctlbench_open(struct ctlbench *b, size_t n)
{
    struct wsg_axis_config cfg;
    size_t i;

    memset(b, 0, sizeof *b);
    b->sched.timer.fd = -1;
    b->runner.watch.fd = -1;
    if (wsg_reactor_init(&b->reactor) < 0)
        return -1;
    if (wsg_sched_init(&b->sched, &b->reactor, 1000) < 0)
        return -1;
    if (wsg_runner_init(&b->runner, &b->reactor, &b->sched) < 0)
        return -1;
    b->grippers = calloc(n, sizeof *b->grippers);
    if (!b->grippers || wsg_axis_config_init(&cfg, "wsg50") < 0)
        return -1;
    b->ngrippers = n;
    for (i = 0; i < n; i++) {
        b->grippers[i].index = (unsigned)i;
        b->grippers[i].runner = &b->runner;
        wsg_device_init(&b->grippers[i].dev, &cfg);
    }
    if (wsg_sched_set_grippers(&b->sched, b->grippers, n) < 0 ||
        wsg_control_new(&b->ctl, &b->reactor, &b->sched) < 0)
        return -1;
    wsg_control_session_init(&b->s, ctlbench_answer, b);
    return 0;
}

static inline void ctlbench_close(struct ctlbench *b)
{
    size_t i;

    wsg_control_close(b->ctl);
    b->ctl = NULL;
    /* A script host made by `script` commands goes with its gripper. */
    for (i = 0; b->grippers && i < b->ngrippers; i++)
        wsg_gripper_fini(&b->grippers[i]);
    wsg_runner_fini(&b->runner);
    wsg_sched_fini(&b->sched);
    wsg_reactor_fini(&b->reactor);
    free(b->grippers);
    b->grippers = NULL;
}

/* Feed text; the answers so far stay in out. */
static inline void ctlbench_feed(struct ctlbench *b, const char *data,
                                 size_t n)
{
    wsg_control_input(b->ctl, &b->s, data, n);
}

/* Run one line and return its answer (without the newline), or "" when it
 * gave none. Valid until the next call. */
static inline const char *ctlbench_cmd(struct ctlbench *b, const char *line)
{
    static char one[CTLBENCH_OUT_MAX + 1];
    size_t from = b->len, n;

    ctlbench_feed(b, line, strlen(line));
    ctlbench_feed(b, "\n", 1);
    n = b->len - from;
    if (n && b->out[from + n - 1] == '\n')
        n--;
    memcpy(one, b->out + from, n);
    one[n] = '\0';
    return one;
}

#endif
