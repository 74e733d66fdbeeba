/*
 * The capture (--capture FILE, the control channel's "capture start FILE"
 * and "capture stop"): what the emulator receives and sends on every
 * interface, as pcapng that Wireshark opens (with the dissector wsg.lua
 * for the gripper's protocol). A service on the reactor: the transports'
 * taps (transport.h) hand it each read's bytes and each packet written,
 * which it frames as records into a 64 KiB stdio buffer that the loop
 * flushes after each batch of events, like the communication log. It
 * allocates nothing per record and keeps no table: a TCP connection's
 * sequence numbers live in the flow its transport owns.
 *
 * Records, by interface (an Interface Description Block each):
 *   0 "ip"   (LINKTYPE_IPV4): TCP and UDP as IPv4 packets between the
 *            peer's real address and port and the gripper's, with TCP's
 *            handshake at accept and FINs at the close, sequence numbers
 *            counting the bytes of each direction, so Wireshark follows
 *            and reassembles the stream;
 *   1 "pty"  (LINKTYPE_USER0): the serial line's bytes as read and written;
 *   2 "can"  (LINKTYPE_CAN_SOCKETCAN): each CAN frame.
 * Every record carries its direction in the packet flags (inbound: the
 * gripper received it) and, as its comment, the gripper's simulated time
 * ("t=1.234000", "#3 t=..." in a fleet).
 *
 * Time stamps are the wall clock (CLOCK_REALTIME, microseconds): a capture
 * then lines up with a tcpdump of the same machine and with the log's wall
 * clock column. Simulated time runs apart from it (--time-scale, time
 * pause and step), so it is in each record's comment, not in its stamp.
 *
 * The file is bounded (--capture-max): a record that would take it past
 * the bound ends the capture there, with a line on stderr; what was
 * written stays a valid file.
 */
#ifndef WSG_DAEMON_CAPTURE_H
#define WSG_DAEMON_CAPTURE_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "transport.h"
#include "wsg/device.h"

#define WSG_CAPTURE_BUFSIZE  65536u
#define WSG_CAPTURE_PATH_MAX 4096u

struct wsg_capture {
    FILE *f;
    char *buf;        /* setvbuf's, owned */
    int on;           /* the taps look at this */
    uint64_t max;     /* bytes the file may reach; 0: no bound */
    uint64_t size;    /* bytes written to the file */
    uint64_t records; /* packet records written */
    int full;         /* stopped at the bound */
    uint16_t ip_id;   /* IPv4 identification, counted */
    char path[WSG_CAPTURE_PATH_MAX];
};

/* One gripper's taps into the capture: its transports point at tap. */
struct wsg_capture_tap {
    struct wsg_tap tap;
    struct wsg_capture *cap;
    const struct wsg_device *dev; /* whose simulated time records show */
    int index;                    /* gripper number in a fleet; -1: none */
};

/* Start writing path (truncated) as a new capture; one that runs is
 * stopped first. Returns 0, or -errno with the reason in err. */
int wsg_capture_start(struct wsg_capture *c, const char *path, char *err,
                      size_t errlen);
/* Flush and close; safe on one never started (zeroed). */
void wsg_capture_stop(struct wsg_capture *c);
/* Write out what is buffered (after a batch of events). */
void wsg_capture_flush(struct wsg_capture *c);
/* Fill in ct for gripper dev (index -1 alone), its tap writing into c. */
void wsg_capture_tap_init(struct wsg_capture_tap *ct, struct wsg_capture *c,
                          const struct wsg_device *dev, int index);
/* Build the records of one tap event into c (the tap's fn, exposed for
 * the tests). */
void wsg_capture_record(struct wsg_capture *c, const struct wsg_tap_flow *f,
                        enum wsg_tap_event ev, const uint8_t *data, size_t len,
                        uint64_t sim_us, int index);
void wsg_capture_event(void *ctx, struct wsg_tap_flow *f,
                       enum wsg_tap_event ev, const uint8_t *data, size_t len);

#endif
