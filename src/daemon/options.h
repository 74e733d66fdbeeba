/*
 * The daemon's command line. Everything the options decide is collected in
 * one struct, filled with defaults first, so later sources (a config file)
 * can write the same fields before the command line overrides them.
 */
#ifndef WSG_DAEMON_OPTIONS_H
#define WSG_DAEMON_OPTIONS_H

#include <stdint.h>

#include "wsg/axis.h"

#define WSG_STEP_US_DEFAULT    1000u
#define WSG_STEP_US_MIN        100u
#define WSG_STEP_US_MAX        100000u
#define WSG_TCP_PORT_DEFAULT   1000u
#define WSG_UDP_PORT_DEFAULT   1500u
#define WSG_UDP_REMOTE_DEFAULT 1501u
#define WSG_CAN_ID_DEFAULT     0x000u
#define WSG_CAN_ID_MAX         0x7FEu /* answers go on ID + 1, an 11-bit ID too */

/* An IPv4 endpoint as given on the command line. */
struct wsg_endpoint {
    uint8_t addr[4]; /* a.b.c.d in this order */
    uint16_t port;   /* host order; 0 lets the kernel pick */
};

struct wsg_options {
    /* Interfaces. With none given on the command line: TCP and UDP on
     * their defaults, like a gripper fresh from the factory. */
    int tcp_enabled;
    struct wsg_endpoint tcp;
    int udp_enabled;
    struct wsg_endpoint udp;     /* where the emulator listens */
    uint16_t udp_remote_port;    /* where replies go, at the sender's IP */
    const char *pty_path;        /* NULL: no serial port */
    const char *can_iface;       /* NULL: no CAN */
    uint16_t can_id;             /* commands on can_id, answers on can_id+1 */
    int control_enabled;         /* --control given */
    struct wsg_endpoint control; /* the control channel (loopback default) */
    double time_scale;           /* simulated seconds per real second */
    const char *log_path;        /* NULL: no log; "-": stderr */
    const char *config_path;     /* --config FILE, read before the options */
    double initial_part;         /* --part WIDTH; < 0: none */
    uint32_t serial;             /* Get System Information SN */
    const char *device_tag;      /* NULL: none */
    int check_crc;               /* 0 with --no-crc */
    int disconnect_fast_stop;    /* 0 with --no-disconnect-fast-stop */
    uint32_t step_us;
    const char *model;           /* NULL: the default model */
    struct wsg_axis_config axis; /* the model's config, step_us applied */
};

enum wsg_options_result {
    WSG_OPTIONS_RUN = 0, /* start the emulator */
    WSG_OPTIONS_EXIT,    /* done (--help printed): exit status 0 */
    WSG_OPTIONS_ERROR    /* message printed on stderr: exit status 2 */
};

void wsg_options_defaults(struct wsg_options *o);
/* Parse argv over the current contents of o (call wsg_options_defaults
 * first). Prints usage or a one-line "wsgemu: ..." error itself. */
enum wsg_options_result wsg_options_parse(struct wsg_options *o, int argc,
                                          char **argv);

#endif
