/*
 * The gripper's state as one JSON object: what the control channel's
 * `state` answers and what the web page shows and pushes, written in one
 * place so that the two never differ. It reads the model and the
 * scheduler and changes nothing; the caller brings the gripper's time up
 * to date first where it needs to (wsg_sched_touch).
 */
#ifndef WSG_DAEMON_STATE_H
#define WSG_DAEMON_STATE_H

#include <stddef.h>
#include <stdint.h>

#include "gripper.h"
#include "sched.h"

/* Room for the longest object: every flag set, the longest names, the
 * script's name and error as long as they are kept here. It stays one
 * control channel answer ("ok " and the newline within 2048 bytes). */
#define WSG_STATE_JSON_MAX 2040u

/* What wsg_state_format leaves out. */
enum wsg_state_parts {
    WSG_STATE_ALL = 0,
    /* Without "time": two states that differ only in simulated time are
     * the same to a viewer waiting for a change. */
    WSG_STATE_NO_TIME = 1
};

/* Simulated time, us microseconds, as seconds: exact, trailing zeros
 * dropped down to milliseconds ("12.345", "0.900", "1.2345"). */
void wsg_state_format_time(char *buf, size_t len, uint64_t us);
/* g's state into buf (NUL-terminated, cut to fit cap, which
 * WSG_STATE_JSON_MAX always does): width, speed, force, temperature,
 * flags and their names, grasp state and its name, statistics, simulated
 * time, whether time is paused and its scale, the delay line's figures,
 * the script host's script (its name, whether it runs, its error), the
 * fingers (kind, power, fault, the force on each pad), the object of a
 * physics plant (shape, sizes, mass, friction, position; null: none), the
 * part placed between the fingers and the obstacle (null: none). Returns the
 * length. */
size_t wsg_state_format(char *buf, size_t cap, const struct wsg_gripper *g,
                        const struct wsg_sched *s, enum wsg_state_parts parts);

#endif
