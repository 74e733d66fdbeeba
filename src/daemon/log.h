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
 * seconds, PEER the session's peer ("tcp 127.0.0.1:51234"; in a fleet
 * prefixed with the gripper's number: "#3 tcp 127.0.0.1:51234"), DIR "in" for
 * a packet the gripper received and "out" for one it sent, ID the command ID
 * as "20h", NAME the command's name ("Homing", "unknown" for an ID the
 * schema lacks), STATUS a reply's status name (E_SUCCESS, ...). PARAMS are
 * decoded by the schema's layout for the command as name=value (floats
 * with 3 decimals, bit vectors and enums with the names of their values:
 * "flags=0x01(auto-update)", "grasp-state=4(HOLDING)") where the payload
 * fits it, else the raw payload as hex bytes "data=01 02 ...". A
 * received packet with a bad checksum shows "checksum-error", one with a
 * SIZE too large "oversize", instead of its parameters. A packet with an ID
 * a script registered is the script's own: its payload shows as hex, with
 * no status. What a script prints shows as "HH:MM:SS.mmm t=SIM script
 * print TEXT", a line per line it printed.
 *
 * Events of a session, of the gripper and of the world show as
 *   HH:MM:SS.mmm t=SIM WHO event TEXT
 * WHO being the session's peer, "gripper" for what the model did by
 * itself, "control" for the control channel, "web" for the web page's
 * STOP and ACK. TEXT is one of:
 *   connected                    a TCP connection accepted
 *   closed (07h)                 it closed after a Disconnect Announcement
 *   closed without 07h           it closed without one
 *   fast-stop cause=CAUSE        FAST STOP entered; CAUSE disconnect, 23h,
 *                                fault (power or current) or soft-limit
 *   ack fast-stop cleared        24h acknowledged a FAST STOP
 *   ack nothing to clear         24h with no FAST STOP to acknowledge
 *   stop                         the web page's STOP
 *   part W S | part none | obstacle W | obstacle none | fault NAME on|off
 *   | reset                      a control command that changed the world
 */
#ifndef WSG_DAEMON_LOG_H
#define WSG_DAEMON_LOG_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <time.h>

#include "wsg/device.h"

/* The stdio buffer: a batch of events rarely produces more. */
#define WSG_LOG_BUFSIZE 65536u

struct wsg_log {
    FILE *f;          /* NULL: closed */
    int own;          /* opened here (fclose it), not stderr */
    const char *path; /* the file's (own only), for the bound's rename */
    uint64_t max;     /* bytes a file may reach (--log-max); 0: no bound */
    uint64_t size;    /* bytes in the file now */
    char *buf;        /* setvbuf's buffer, owned */
    time_t sec;       /* wall clock second that clock[] shows */
    char clock[9];    /* "HH:MM:SS" of sec, cached: localtime per line costs */
    /* A second reader of every line (the web page's log view), newline
     * included; NULL: none. Lines are made only when f or sink wants
     * them. */
    void (*sink)(void *ctx, const char *line, size_t len);
    void *sink_ctx;
};

/* One device's hook into the log (its trace context). */
struct wsg_log_tap {
    struct wsg_log *log;
    const struct wsg_device *dev; /* whose simulated time lines show */
    int index;                    /* gripper number in a fleet; -1: none */
};

/* Open path ("-": stderr), which must outlive the log. Returns 0, or
 * -errno with the reason in err. */
int wsg_log_open(struct wsg_log *l, const char *path, char *err,
                 size_t errcap);
/* Bound the file (not stderr) to max bytes (--log-max; 0: none): a line
 * that would take it past max first moves it to PATH.old, replacing the
 * one before, and goes into a new file at PATH. So the log keeps the
 * newest lines, between max and 2 * max bytes of them, at lines' ends.
 * PATH.old, not PATH.1: that is logrotate's, which must not be lost. */
void wsg_log_limit(struct wsg_log *l, uint64_t max);
/* Open path again (after logrotate renamed it: SIGHUP), appending if it
 * exists. The old file is closed only once the new one is open. stderr
 * stays as it is. Returns 0, or -errno with the reason in err. */
int wsg_log_reopen(struct wsg_log *l, const char *path, char *err,
                   size_t errcap);
/* Hook d's trace callbacks into the log through tap (which must live as
 * long as the hook). */
void wsg_log_attach(struct wsg_log *l, struct wsg_log_tap *tap,
                    struct wsg_device *d, int index);
/* Unhook d if tap is its hook; safe on a zeroed tap. */
void wsg_log_detach(struct wsg_log_tap *tap, struct wsg_device *d);
/* Text that is not a packet (what a script prints), a line per line of
 * it: "HH:MM:SS.mmm t=SIM WHO print TEXT". Nothing when tap is not
 * attached. */
void wsg_log_text(struct wsg_log_tap *tap, const char *who, const char *text,
                  size_t len);
/* An event line (see above) from outside the device: the control
 * channel's "control event part 40 200". Nothing when tap is not attached. */
void wsg_log_event(struct wsg_log_tap *tap, const char *who, const char *text);
/* Have every line also handed to fn (NULL: no more). */
void wsg_log_sink(struct wsg_log *l,
                  void (*fn)(void *ctx, const char *line, size_t len),
                  void *ctx);
/* Write out what is buffered (after a batch of events). */
void wsg_log_flush(struct wsg_log *l);
/* Flush and close; safe on a log never opened (zeroed). */
void wsg_log_close(struct wsg_log *l);

#endif
