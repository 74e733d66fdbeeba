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
 */
#ifndef WSG_DAEMON_GRIPPER_H
#define WSG_DAEMON_GRIPPER_H

#include <stddef.h>
#include <stdint.h>

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
};

#endif
