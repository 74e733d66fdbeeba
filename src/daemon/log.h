/*
 * The communication log (--log FILE): one line per packet in each
 * direction, like the log panel of WSG Commander, written through the
 * device's trace hooks. Lines go into a large stdio buffer that the loop
 * flushes when a batch of events is done, so logging costs a formatted line
 * per packet and one write per batch, not a write per packet.
 *
 * Line format (fields separated by one space):
 *   HH:MM:SS.mmm t=SIM PEER DIR ID NAME [STATUS] [PARAMS]
 * HH:MM:SS.mmm is the local wall clock, SIM the device's simulated time in
 * seconds, PEER the session's peer ("tcp 127.0.0.1:51234"), DIR "in" for a
 * packet the gripper received and "out" for one it sent, ID the command ID
 * as "20h", NAME the command's name ("Homing", "unknown" for an ID the
 * table lacks), STATUS a reply's status name (E_SUCCESS, ...). PARAMS are
 * decoded as name=value (floats with 3 decimals, flags by name) where the
 * command is known, else the raw payload as hex bytes "data=01 02 ...". A
 * received packet with a bad checksum shows "checksum-error", one with a
 * SIZE too large "oversize", instead of its parameters.
 */
#ifndef WSG_DAEMON_LOG_H
#define WSG_DAEMON_LOG_H

#include <stddef.h>
#include <stdio.h>
#include <time.h>

#include "wsg/device.h"

/* The stdio buffer: a batch of events rarely produces more. */
#define WSG_LOG_BUFSIZE 65536u

struct wsg_log {
    FILE *f;   /* NULL: closed */
    int own;   /* opened here (fclose it), not stderr */
    char *buf; /* setvbuf's buffer, owned */
    const struct wsg_device *dev;
    time_t sec;    /* wall clock second that clock[] shows */
    char clock[9]; /* "HH:MM:SS" of sec, cached: localtime per line costs */
};

/* Open path ("-": stderr) and hook the log into d's trace callbacks.
 * Returns 0, or -errno with the reason in err. */
int wsg_log_open(struct wsg_log *l, struct wsg_device *d, const char *path,
                 char *err, size_t errcap);
/* Write out what is buffered (after a batch of events). */
void wsg_log_flush(struct wsg_log *l);
/* Unhook, flush and close; safe on a log never opened (zeroed). */
void wsg_log_close(struct wsg_log *l, struct wsg_device *d);

#endif
