/*
 * A gripper's latency (--latency): the device's output hook puts every
 * packet into the delay line of the interface its session belongs to (the
 * session tag names the transport), and the loop calls the release after
 * each of the gripper's steps, which sends what is due to the session the
 * tag still names. The delay is measured in the gripper's simulated time,
 * so it scales, pauses and steps with everything else.
 */
#include "gripper.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "wsg/plant.h"

/* Mixed with the gripper's number: any fixed value does. */
#define WSG_GRIPPER_SEED 0x5753473530ull /* "WSG50" */

static void gripper_delay(void *ctx, struct wsg_session *s, const uint8_t *pkt,
                          size_t len)
{
    struct wsg_gripper *g = ctx;
    uint32_t idx = s->tag >> WSG_TAG_TRANSPORT_SHIFT;
    struct wsg_delay *dl;
    int r;

    /* Every session's tag names one of g's transports; a packet for one
     * that did not would wait where no release looks, so it goes now. */
    if (idx == 0 || idx > g->ntransports) {
        wsg_device_transmit(&g->dev, s, pkt, len);
        return;
    }
    dl = &g->delay[idx - 1];
    r = wsg_delay_push(dl, wsg_axis_time(wsg_device_axis(&g->dev)), s->tag,
                       pkt, len);
    if (r == 1)
        wsg_device_transmit(&g->dev, s, pkt, len);
    else if (r < 0 && dl->burst == 1)
        /* Once per burst: it goes on until the line has emptied. */
        fprintf(stderr,
                "wsgemu: %s: --latency: %s; dropping packets until those "
                "waiting have left\n",
                s->peer,
                r == -ENOBUFS ? "64 KiB of packets waiting" : strerror(-r));
}

int wsg_gripper_set_latency(struct wsg_gripper *g, uint32_t ms,
                            uint32_t jitter_ms)
{
    unsigned i;

    if (ms == 0 && jitter_ms == 0)
        return 0;
    g->delay = calloc(WSG_TRANSPORT_MAX, sizeof *g->delay);
    if (!g->delay)
        return -ENOMEM;
    for (i = 0; i < WSG_TRANSPORT_MAX; i++)
        wsg_delay_init(&g->delay[i], ms, jitter_ms,
                       WSG_GRIPPER_SEED ^ ((uint64_t)g->index << 8 | i));
    g->dev.delay = gripper_delay;
    g->dev.delay_ctx = g;
    return 0;
}

static void gripper_out(void *ctx, uint32_t tag, const uint8_t *pkt,
                        size_t len)
{
    struct wsg_gripper *g = ctx;
    struct wsg_session *s =
        g->dev.lookup ? g->dev.lookup(g->dev.lookup_ctx, tag) : NULL;

    if (s)
        wsg_device_transmit(&g->dev, s, pkt, len);
}

void wsg_gripper_release(struct wsg_gripper *g)
{
    size_t i;

    if (!g->delay)
        return;
    for (i = 0; i < g->ntransports; i++)
        if (wsg_delay_pending(&g->delay[i]))
            wsg_delay_release(&g->delay[i],
                              wsg_axis_time(wsg_device_axis(&g->dev)),
                              gripper_out, g);
}

size_t wsg_gripper_delayed(const struct wsg_gripper *g)
{
    size_t i, n = 0;

    for (i = 0; g->delay && i < g->ntransports; i++)
        n += wsg_delay_pending(&g->delay[i]);
    return n;
}

uint64_t wsg_gripper_delay_dropped(const struct wsg_gripper *g)
{
    uint64_t n = 0;
    size_t i;

    for (i = 0; g->delay && i < g->ntransports; i++)
        n += g->delay[i].dropped;
    return n;
}

/* Steps from now until the first step that ends at or after due (the
 * release and the script's wake-up run after a step), at least 1. */
static uint64_t steps_until(uint64_t due, uint64_t now, uint64_t step)
{
    return due > now ? (due - now + step - 1) / step : 1;
}

uint64_t wsg_gripper_next(const struct wsg_gripper *g)
{
    uint64_t best = wsg_device_next(&g->dev);
    const struct wsg_axis *ax = wsg_device_axis_const(&g->dev);
    uint64_t now = wsg_axis_time(ax), step = wsg_axis_cfg(ax)->step_us;
    size_t i;

    if (g->script && best > 1) {
        uint64_t due = wsg_script_next(g->script);

        if (due != UINT64_MAX && steps_until(due, now, step) < best)
            best = steps_until(due, now, step);
    }

    for (i = 0; g->delay && i < g->ntransports && best > 1; i++) {
        uint64_t due = wsg_delay_next_due(&g->delay[i]), k;

        if (due == UINT64_MAX)
            continue;
        k = steps_until(due, now, step);
        if (k < best)
            best = k;
    }
    return best;
}

uint64_t wsg_gripper_process(struct wsg_gripper *g, uint64_t n)
{
    uint64_t ran = 0;

    while (n > 0) {
        uint64_t k = wsg_gripper_next(g);

        if (k > 1) {
            uint64_t jump = k - 1 < n ? k - 1 : n;

            wsg_device_advance_idle(&g->dev, jump);
            n -= jump;
            continue;
        }
        wsg_device_step(&g->dev);
        wsg_device_poll_streaming(&g->dev);
        wsg_gripper_release(g);
        if (g->script)
            wsg_script_poll(g->script);
        ran++;
        n--;
    }
    return ran;
}

static void gripper_script_print(void *ctx, const char *text, size_t len)
{
    struct wsg_gripper *g = ctx;

    wsg_log_text(&g->tap, "script", text, len);
}

static void gripper_script_wake(void *ctx)
{
    struct wsg_gripper *g = ctx;

    wsg_runner_wake(g->runner, g);
}

int wsg_gripper_script(struct wsg_gripper *g, struct wsg_script **out)
{
    struct wsg_script_config cfg = {g->script_memory, gripper_script_print,
                                    gripper_script_wake, g, g->script_dir};
    int r = 0;

    if (!g->script)
        r = wsg_script_new(&g->script, &g->dev, &cfg);
    *out = g->script;
    return r;
}

int wsg_gripper_finger(struct wsg_gripper *g, int i, int kind,
                       const char *model, char *err, size_t errcap)
{
    struct wsg_fdev *m = NULL;
    int r;

    if (i < 0 || i > 1 || kind < 0 || kind >= WSG_FINGER_KINDS ||
        (kind == WSG_FINGER_DEVICE && !model)) {
        snprintf(err, errcap, "no such finger or kind");
        return -EINVAL;
    }
    if (kind == WSG_FINGER_DEVICE) {
        /* Attached only once it loads: until then the old one serves. */
        r = wsg_fdev_open(&m, &g->dev.fingers, i, model, NULL, 0, NULL, 0, err,
                          errcap);
        if (r < 0)
            return r;
    }
    wsg_fdev_close(g->fdev[i]); /* detaches it if still attached */
    g->fdev[i] = m;
    if (kind != WSG_FINGER_DEVICE)
        wsg_finger_request_kind(&g->dev.fingers, i,
                                (enum wsg_finger_kind)kind);
    wsg_device_settle(&g->dev);
    return 0;
}

void wsg_gripper_fini(struct wsg_gripper *g)
{
    size_t i;

    for (i = 0; i < 2; i++) {
        wsg_fdev_close(g->fdev[i]);
        g->fdev[i] = NULL;
    }

    if (g->runner)
        wsg_runner_forget(g->runner, g);
    wsg_script_free(g->script);
    g->script = NULL;
    if (g->plant) {
        wsg_axis_set_plant(wsg_device_axis(&g->dev), NULL);
        g->plant->ops->destroy(g->plant);
        g->plant = NULL;
    }
    if (!g->delay)
        return;
    for (i = 0; i < WSG_TRANSPORT_MAX; i++)
        wsg_delay_fini(&g->delay[i]);
    free(g->delay);
    g->delay = NULL;
    g->dev.delay = NULL;
}
