/*
 * One emulated gripper of the daemon: its device (model and sessions), the
 * interfaces it is reached on, and what the loop needs to schedule it. A
 * daemon runs one, or a fleet of them (--grippers N) in one process; each
 * gripper is independent of the others, down to its own ports, session
 * tags and simulated time.
 *
 * The loop steps only the grippers on its active list. A gripper off the
 * list lets its simulated time lag behind the loop's grid and catches up in
 * one step-free jump (wsg_device_advance_idle) when something touches it,
 * which is exact because an idle model cannot change.
 *
 * With --latency, what the gripper sends waits in a delay line per
 * interface (the device's output hook puts it there) and leaves when the
 * gripper's simulated time reaches its due time: the loop releases it after
 * each step, and keeps stepping a gripper while anything waits. With
 * latency 0 there is no hook and no line: packets leave as they are made.
 */
#ifndef WSG_DAEMON_GRIPPER_H
#define WSG_DAEMON_GRIPPER_H

#include <stddef.h>
#include <stdint.h>

#include "delay.h"
#include "log.h"
#include "transport.h"
#include "wsg/device.h"

struct wsg_gripper {
    struct wsg_device dev;
    unsigned index; /* 0.. in the fleet, in ready line order */
    struct wsg_transport transports[WSG_TRANSPORT_MAX];
    size_t ntransports;
    /* Scheduling (the loop's): the grid step the device's time stands at,
     * and the links of the active and touched lists. */
    uint64_t at;
    struct wsg_gripper *next_active;
    struct wsg_gripper *next_touched;
    uint8_t active;
    uint8_t touched;
    struct wsg_log_tap tap; /* the communication log's view of it */
    /* --latency: delay[i] holds what transports[i] is to send; NULL
     * without a latency, so a fleet pays nothing for the option. */
    struct wsg_delay *delay;
};

/* Delay every packet of g by ms plus a draw of 0..jitter_ms (simulated
 * time), in order per interface. The draws are seeded from g's number and
 * the interface's place, so a run (and each gripper of a fleet) meets the
 * same delays for the same traffic. Call once, before anything is sent;
 * with both 0 nothing changes. Returns 0 or -ENOMEM. */
int wsg_gripper_set_latency(struct wsg_gripper *g, uint32_t ms,
                            uint32_t jitter_ms);
/* Send what is due at g's simulated time, to sessions still there (a
 * session that is gone loses its packets). */
void wsg_gripper_release(struct wsg_gripper *g);
/* Steps matter: the model or a stream has work, or packets wait. */
int wsg_gripper_busy(const struct wsg_gripper *g);
/* Packets waiting in g's delay lines, and those dropped because a line
 * was full (64 KiB). */
size_t wsg_gripper_delayed(const struct wsg_gripper *g);
uint64_t wsg_gripper_delay_dropped(const struct wsg_gripper *g);
/* Free the delay lines (after the transports are closed); safe on a
 * gripper without them. */
void wsg_gripper_fini(struct wsg_gripper *g);

#endif
