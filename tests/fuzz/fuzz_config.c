/*
 * Harness 3: arbitrary bytes as a config file (--config): the daemon's
 * settings table and its parsers read it over the defaults, then the
 * settings are checked against the model. Whatever the file, reading it
 * ends in a verdict, and a file that is accepted leaves settings the
 * model takes: every model-dependent value within the model's range, the
 * time scale and latency within theirs, a step length above zero, text
 * settings terminated inside their buffer.
 */
#define _GNU_SOURCE /* fmemopen */

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "options.h"
#include "sched.h"

#ifndef FUZZ_ENTRY
#define FUZZ_ENTRY LLVMFuzzerTestOneInput
#endif

int FUZZ_ENTRY(const uint8_t *data, size_t size);

#define FUZZ_CHECK(c)                                                         \
    do {                                                                      \
        if (!(c)) {                                                           \
            fprintf(fuzz_err, "fuzz_config: invariant failed: %s\n", #c);     \
            abort();                                                          \
        }                                                                     \
    } while (0)

/* A text setting points into o's buffer (or at a default string), and is
 * terminated there. */
static int text_ok(const struct wsg_options *o, const char *t)
{
    if (!t)
        return 1;
    if (t < o->strbuf || t >= o->strbuf + sizeof o->strbuf)
        return 1; /* a default, not copied */
    return memchr(t, '\0', (size_t)(o->strbuf + sizeof o->strbuf - t)) != NULL;
}

static void in_range(const struct wsg_axis_config *c, enum wsg_axis_setting s,
                     double v, FILE *fuzz_err)
{
    struct wsg_axis_range r = wsg_axis_config_range(c, s);

    FUZZ_CHECK(v >= r.min && v <= r.max);
}

int FUZZ_ENTRY(const uint8_t *data, size_t size)
{
    static struct wsg_options o;
    static FILE *fuzz_err;
    FILE *f, *quiet, *saved = stderr;
    enum wsg_options_result res;

    if (size == 0)
        return 0; /* fmemopen takes no empty buffer */
    if (!fuzz_err)
        fuzz_err = fdopen(2, "w");
    /* The parser's messages go to stdio's stderr; a file of garbage would
     * flood the run's log with them. The sanitizers and this harness write
     * to descriptor 2 directly and are still heard. */
    quiet = fopen("/dev/null", "w");
    if (!quiet)
        return 0;
    stderr = quiet;
    memset(&o, 0, sizeof o);
    wsg_options_defaults(&o);
    f = fmemopen((void *)(uintptr_t)data, size, "r");
    if (f) {
        res = wsg_options_read_config(&o, f, "fuzz.conf");
        fclose(f);
        if (res == WSG_OPTIONS_RUN)
            res = wsg_options_finish(&o);
        if (res == WSG_OPTIONS_RUN) {
            const struct wsg_axis_config *c = &o.axis;

            in_range(c, WSG_AXIS_ACCELERATION, c->default_acc, fuzz_err);
            in_range(c, WSG_AXIS_FORCE_LIMIT, c->default_force, fuzz_err);
            in_range(c, WSG_AXIS_CLAMP_TRAVEL, c->clamp_travel, fuzz_err);
            in_range(c, WSG_AXIS_WIDTH_TOLERANCE, c->width_tolerance,
                     fuzz_err);
            if (o.initial_part.given)
                in_range(c, WSG_AXIS_WIDTH, o.initial_part.value, fuzz_err);
            FUZZ_CHECK(c->step_us > 0);
            FUZZ_CHECK(o.time_scale >= WSG_SCHED_SCALE_MIN &&
                       o.time_scale <= WSG_SCHED_SCALE_MAX);
            FUZZ_CHECK(o.latency_ms <= 10000 && o.latency_jitter_ms <= 10000);
            FUZZ_CHECK(o.grippers >= 1);
            FUZZ_CHECK(text_ok(&o, o.pty_path) && text_ok(&o, o.can_iface) &&
                       text_ok(&o, o.log_path) && text_ok(&o, o.device_tag) &&
                       text_ok(&o, o.model));
            FUZZ_CHECK(!o.device_tag || strlen(o.device_tag) <= 64);
        }
    }
    stderr = saved;
    fclose(quiet);
    return 0;
}
