/*
 * One emulated gripper of the daemon: its device (model and sessions), the
 * interfaces it is reached on, and what the loop needs to schedule it. A
 * daemon runs one, or a fleet of them (--grippers N) in one process; each
 * gripper is independent of the others, down to its own ports, session
 * tags and simulated time.
 *
 * The scheduler (sched.h) runs a gripper only when it has a deadline: it
 * consumes the elapsed steps with wsg_gripper_process, which steps the
 * model where something can change and jumps the stretches where nothing
 * is due (an idle model cannot change), and asks wsg_gripper_next when
 * the gripper next needs to run.
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

#include "capture.h"
#include "delay.h"
#include "fdev.h"
#include "log.h"
#include "runner.h"
#include "script.h"
#include "transport.h"
#include "wsg/device.h"

struct wsg_gripper {
    struct wsg_device dev;
    unsigned index; /* 0.. in the fleet, in ready line order */
    struct wsg_transport transports[WSG_TRANSPORT_MAX];
    size_t ntransports;
    /* The scheduler's: the grid step of its deadline, its place in the
     * deadline heap, and the link of the list of grippers touched in this
     * batch. Its time is its model's (wsg_axis_time). */
    struct wsg_sched *sched;
    uint64_t due;
    size_t heap_idx;
    struct wsg_gripper *next_touched;
    uint8_t touched;
    struct wsg_log_tap tap;         /* the communication log's view of it */
    struct wsg_capture_tap capture; /* what its transports show the capture */
    /* --latency: delay[i] holds what transports[i] is to send; NULL
     * without a latency, so a fleet pays nothing for the option. */
    struct wsg_delay *delay;
    /* Its script host, made on first use (NULL: none yet), and where a
     * preempted script asks for its next turn. */
    struct wsg_script *script;
    size_t script_memory;   /* --script-memory, bytes */
    const char *script_dir; /* --script-dir; NULL: none */
    struct wsg_runner *runner;
    struct wsg_gripper *next_ready; /* the runner's list */
    uint8_t ready;
    /* --physics mujoco: the plant its fingers move in (NULL: built-in). */
    struct wsg_plant *plant;
    /* The device models of fingers with custom electronics (NULL: none). */
    struct wsg_fdev *fdev[2];
};

/* Fit finger i (0 or 1) of g with a kind (wsg/finger.h), settled now; a
 * device takes the model in file model (its memory WSG_FDEV_MEMORY). A
 * device model it had goes. 0, or -errno with the reason in err (the
 * model cannot be read or does not compile: the finger stays as it was). */
int wsg_gripper_finger(struct wsg_gripper *g, int i, int kind,
                       const char *model, char *err, size_t errcap);

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
/* g's next deadline in model steps from its time (at least 1): the
 * device's (wsg_device_next), the first delayed packet's or the end of
 * its script's sleep, whichever comes first; UINT64_MAX when nothing is
 * due. */
uint64_t wsg_gripper_next(const struct wsg_gripper *g);
/* Consume n steps of elapsed time: model steps, stream polls, releases
 * of delayed packets and a script's wake-up at every step where something
 * is due, one jump over each stretch where nothing is. Returns the model
 * steps run. */
uint64_t wsg_gripper_process(struct wsg_gripper *g, uint64_t n);
/* Packets waiting in g's delay lines, and those dropped because a line
 * was full (64 KiB). */
size_t wsg_gripper_delayed(const struct wsg_gripper *g);
uint64_t wsg_gripper_delay_dropped(const struct wsg_gripper *g);
/* g's script host, made on first use: 0, or -ENOMEM. What the script
 * prints goes to the communication log. */
int wsg_gripper_script(struct wsg_gripper *g, struct wsg_script **out);
/* Free the delay lines and the script host (after the transports are
 * closed); safe on a gripper without them. */
void wsg_gripper_fini(struct wsg_gripper *g);

#endif
