/*
 * The model's limits, as the fuzz harnesses that drive it check them
 * (fuzz_bench.c, fuzz_gcl.c). ax->width is the width as reported; the
 * physical distance is that minus ref_offset, which a homing that blocked
 * on a part or an obstacle makes nonzero (3.2.1; docs/behaviour.md): after
 * that the reported width may leave 0..stroke, as on the real gripper. So
 * the physical width is checked always, the reported one while the
 * reference is true.
 */
#ifndef WSG_FUZZ_AXIS_H
#define WSG_FUZZ_AXIS_H

#include <math.h>

#include "axis_impl.h"
#include "fuzz_check.h"

/* Slack for the model's floating point. */
#define FUZZ_AXIS_EPS 1e-6

static inline void fuzz_check_axis(const struct wsg_axis *ax)
{
    const struct wsg_axis_config *c = &ax->cfg;
    double phys = ax->width - ax->ref_offset;

    FUZZ_CHECK(isfinite(ax->width) && isfinite(ax->speed));
    FUZZ_CHECK(isfinite(ax->force) && isfinite(ax->temperature));
    FUZZ_CHECK(isfinite(ax->ref_offset));
    FUZZ_CHECK(phys >= -FUZZ_AXIS_EPS && phys <= c->stroke + FUZZ_AXIS_EPS);
    if (ax->ref_offset == 0.0)
        FUZZ_CHECK(ax->width >= -FUZZ_AXIS_EPS &&
                   ax->width <= c->stroke + FUZZ_AXIS_EPS);
    FUZZ_CHECK(fabs(ax->speed) <= c->max_speed + FUZZ_AXIS_EPS);
    FUZZ_CHECK(ax->force >= -FUZZ_AXIS_EPS &&
               ax->force <= c->ovr_force + FUZZ_AXIS_EPS);
}

#endif
