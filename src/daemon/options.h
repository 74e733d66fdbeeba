/*
 * The daemon's command line and config file. Everything the options decide
 * is collected in one struct, filled with defaults first; a config file
 * (--config) writes the same fields before the command line overrides them.
 * Both go through one table of settings, so a key of the file and the long
 * option of the same name always mean the same thing.
 */
#ifndef WSG_DAEMON_OPTIONS_H
#define WSG_DAEMON_OPTIONS_H

#include <stddef.h>
#include <stdint.h>

#include "transport.h" /* struct wsg_endpoint */
#include "wsg/axis.h"

#define WSG_STEP_US_DEFAULT    1000u
#define WSG_STEP_US_MIN        100u
#define WSG_STEP_US_MAX        100000u
#define WSG_TCP_PORT_DEFAULT   1000u
#define WSG_UDP_PORT_DEFAULT   1500u
#define WSG_UDP_REMOTE_DEFAULT 1501u
#define WSG_CAN_ID_DEFAULT     0x000u
#define WSG_CAN_ID_MAX         0x7FEu /* answers go on ID + 1, an 11-bit ID too */
/* Room for the strings a config file gives (paths, names, the tag): they
 * must outlive the file's line buffer, and options hold no heap memory. */
#define WSG_OPTIONS_STRBUF 2048u
/* TCP connections served at once (--max-clients). A real gripper serves a
 * handful; 64 leaves room for test rigs that open one per process while a
 * connection-storm or a port scan still finds a limit. The ceiling is the
 * number of connection slots the TCP transport has. */
#define WSG_MAX_CLIENTS_DEFAULT 64u
#define WSG_MAX_CLIENTS_MAX     256u
/* --grippers: a fleet in one process. The ceiling is generous for a CI
 * farm's box; descriptors (a few per gripper) run out well before it. */
#define WSG_GRIPPERS_MAX 10000u
/* Room for a pty path with a fleet's number counted into it. */
#define WSG_OPTIONS_PATH_MAX 4096u

struct wsg_options {
    /* Interfaces. With none given on the command line: TCP and UDP on
     * their defaults, like a gripper fresh from the factory. */
    int tcp_enabled;
    struct wsg_endpoint tcp;
    unsigned max_clients; /* TCP connections at once; more are refused */
    unsigned grippers;    /* --grippers: how many, each its own interfaces */
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
    double initial_part_stiffness; /* N/mm; 0: the model's default */
    uint32_t serial;               /* Get System Information SN */
    const char *device_tag;        /* NULL: none */
    int check_crc;                 /* 0 with --no-crc */
    int disconnect_fast_stop;      /* 0 with --no-disconnect-fast-stop */
    int force_sensor;              /* --force-sensor on: tare, D9 */
    /* --latency MS[:JITTER]: what the gripper sends leaves MS plus up to
     * JITTER ms of simulated time late (0: at once, no delay line). */
    uint32_t latency_ms;
    uint32_t latency_jitter_ms;
    uint32_t step_us;
    const char *model; /* NULL: the default model */
    /* The web page's settings; negative (homing_dir: WSG_HOME_DEFAULT)
     * means the model's default. Checked against the model's limits when
     * the model is known, i.e. after the whole command line. */
    double acceleration;         /* mm/s^2 */
    double force_limit;          /* N */
    int homing_dir;              /* WSG_HOME_POSITIVE / WSG_HOME_NEGATIVE */
    double clamp_travel;         /* mm */
    double width_tolerance;      /* mm */
    struct wsg_axis_config axis; /* the model's config, settings applied */

    /* Where the range-checked settings came from, for error messages:
     * line number in config_path, 0 for the command line. */
    unsigned line_acceleration, line_force_limit, line_clamp_travel,
        line_width_tolerance, line_part;
    char strbuf[WSG_OPTIONS_STRBUF];
    size_t strbuf_used;
};

enum wsg_options_result {
    WSG_OPTIONS_RUN = 0, /* start the emulator */
    WSG_OPTIONS_EXIT,    /* done (--help printed): exit status 0 */
    WSG_OPTIONS_ERROR    /* message printed on stderr: exit status 2 */
};

void wsg_options_defaults(struct wsg_options *o);
/* The options of gripper i of a fleet: o with its interfaces counted up
 * (TCP and UDP ports, the pty path, the CAN ID pair, the serial number).
 * The pty path is written to path. With one gripper: o itself. */
void wsg_options_gripper(const struct wsg_options *o, unsigned i,
                         struct wsg_options *out, char *path, size_t pathlen);
/* Parse argv over the current contents of o (call wsg_options_defaults
 * first). Prints usage or a one-line "wsgemu: ..." error itself. */
enum wsg_options_result wsg_options_parse(struct wsg_options *o, int argc,
                                          char **argv);

#endif
