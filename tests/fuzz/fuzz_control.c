/*
 * Harness 4: arbitrary bytes as what a client sends to the control channel
 * (a bench of two grippers, no socket: tests/ctlbench.h). Whatever it
 * sends, every complete line gets exactly one answer, in order; an answer
 * is "ok" or "ok ..." or "error ...", one line, no longer than the
 * channel's limit; a JSON answer (state, stats) has balanced braces and
 * quotes; and the models stay within their stroke whatever the world
 * commands did to them. Gripper 1 moves in the MuJoCo plant where the
 * build has it, so that after `gripper 1` the world's commands (object,
 * pull) and time reach the physics; only in inputs that select it, since
 * loading a scene costs more than the rest of a run.
 */
#define _GNU_SOURCE /* memmem */

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "ctlbench.h"
#include "wsg/plant.h"

#ifndef FUZZ_ENTRY
#define FUZZ_ENTRY LLVMFuzzerTestOneInput
#endif

int FUZZ_ENTRY(const uint8_t *data, size_t size);

/* The longest answer line the channel writes, newline included. */
#define FUZZ_ANSWER_MAX 2048u

static void fuzz_fail(const char *what, const char *line, size_t len)
{
    fprintf(stderr, "fuzz_control: %s: %.*s\n", what, (int)len, line);
    abort();
}

/* Braces and quotes of a JSON answer balance (no escapes are written). */
static int json_balanced(const char *p, size_t len)
{
    int depth = 0, quoted = 0;
    size_t i;

    for (i = 0; i < len; i++) {
        if (p[i] == '"')
            quoted = !quoted;
        else if (!quoted && (p[i] == '{' || p[i] == '['))
            depth++;
        else if (!quoted && (p[i] == '}' || p[i] == ']'))
            depth--;
        if (depth < 0)
            return 0;
    }
    return depth == 0 && !quoted;
}

static void fuzz_answer(void *ctx, const char *line, size_t len)
{
    struct ctlbench *b = ctx;

    b->answers++;
    if (len == 0 || len > FUZZ_ANSWER_MAX || line[len - 1] != '\n')
        fuzz_fail("not one line", line, len);
    if (memchr(line, '\n', len - 1) || memchr(line, '\0', len))
        fuzz_fail("a newline or NUL inside", line, len);
    if (!(len >= 3 && memcmp(line, "ok", 2) == 0 &&
          (line[2] == ' ' || line[2] == '\n')) &&
        !(len > 6 && memcmp(line, "error ", 6) == 0))
        fuzz_fail("neither ok nor error", line, len);
    if (len > 4 && memcmp(line, "ok {", 4) == 0 &&
        !json_balanced(line + 3, len - 4))
        fuzz_fail("unbalanced JSON", line, len);
}

/* A "time step" with physics may cost up to a second (the channel's
 * bound): inputs with more of them run without physics, so that libFuzzer's
 * timeout flags hangs, not physics. */
#define FUZZ_PHYSICS_STEPS 4

static size_t steps_in(const uint8_t *data, size_t size)
{
    const uint8_t *p = data, *end = data + size, *q;
    size_t n = 0;

    while (p < end && (q = memmem(p, (size_t)(end - p), "step", 4))) {
        n++;
        p = q + 4;
    }
    return n;
}

/* Gripper 1 on the MuJoCo plant's own scene (a no-op without it). */
static void fuzz_physics(struct ctlbench *b)
{
    struct wsg_gripper *g = &b->grippers[1];
    struct wsg_axis *ax = wsg_device_axis(&g->dev);
    char err[256];

    if (!wsg_plant_mujoco_available() ||
        wsg_plant_mujoco_open(&g->plant, wsg_axis_cfg(ax), NULL, NULL, NULL,
                              err, sizeof err) < 0) {
        g->plant = NULL;
        return;
    }
    wsg_axis_set_plant(ax, g->plant);
}

int FUZZ_ENTRY(const uint8_t *data, size_t size)
{
    static struct ctlbench b;
    size_t lines = 0, i;

    if (ctlbench_open(&b, 2) < 0) {
        ctlbench_close(&b);
        return 0;
    }
    if (size >= 9 && memmem(data, size, "gripper 1", 9) &&
        steps_in(data, size) <= FUZZ_PHYSICS_STEPS)
        fuzz_physics(&b);
    wsg_control_session_init(&b.s, fuzz_answer, &b);
    /* Paused first: a run's outcome must not depend on the wall clock,
     * and a model set moving is stepped only by the input's "time step". */
    ctlbench_feed(&b, "time pause\n", 11);
    b.answers = 0;
    for (i = 0; i < size; i++)
        lines += data[i] == '\n';
    ctlbench_feed(&b, (const char *)data, size);
    if (b.answers != lines) {
        fprintf(stderr, "fuzz_control: %zu lines, %zu answers\n", lines,
                b.answers);
        abort();
    }
    for (i = 0; i < b.ngrippers; i++) {
        const struct wsg_axis *ax = wsg_device_axis_const(&b.grippers[i].dev);
        double w = wsg_axis_width(ax);

        if (!(w >= -1e-6 && w <= wsg_axis_cfg(ax)->stroke + 1e-6)) {
            fprintf(stderr, "fuzz_control: gripper %zu at width %g\n", i, w);
            abort();
        }
    }
    ctlbench_close(&b);
    return 0;
}
