/*
 * The control channel (--control [ADDR:]PORT): a line protocol on a TCP
 * port of its own, for tests and people with nc, that changes the world
 * around the gripper (a part, an obstacle, faults), controls simulated time
 * and reports the model's state. It has no sessions and speaks no gripper
 * protocol; it is built as a transport only so that the loop serves its
 * descriptors and the ready line names it (opened last: "control=...").
 *
 * One command per line, each answered with one line: "ok ..." or
 * "error <reason>". The commands are listed in README.md; control.c parses
 * and runs them.
 */
#ifndef WSG_DAEMON_CONTROL_H
#define WSG_DAEMON_CONTROL_H

#include "transport.h"

/* Longest command line, without its newline; longer ones are answered with
 * an error and discarded up to their newline. */
#define WSG_CTL_LINE_MAX 256u
/* Control clients at once; one more is told so and closed. */
#define WSG_CTL_CLIENTS_MAX 16u

#endif
