/*
 * The daemon's command line and config file. Everything the options decide
 * is collected in one struct, filled with defaults first; a config file
 * (--config) writes the same fields before the command line overrides them.
 * One table of settings (struct wsg_setting, below) drives it all: each
 * setting's name, type, place in the struct or parser, range, default,
 * help text and whether it is a config-file key are written there once,
 * and getopt's table, the config file's keys, the defaults and --help are
 * made from it. So a key of the file and the long option of the same name
 * always mean the same thing. Ranges that depend on the model come from
 * the model (wsg_axis_config_range), checked once the model is known.
 */
#ifndef WSG_DAEMON_OPTIONS_H
#define WSG_DAEMON_OPTIONS_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "transport.h" /* struct wsg_endpoint */
#include "wsg/axis.h"

#define WSG_SCRIPT_MEMORY_MIN_MIB 1u
#define WSG_SCRIPT_MEMORY_MAX_MIB 1024u
/* GCL's MOVE, GRIP and RELEASE without a speed, mm/s. */
#define WSG_GCL_DEFAULT_SPEED 100.0
#define WSG_STEP_US_MIN       100u
#define WSG_STEP_US_MAX       100000u
#define WSG_CAN_ID_DEFAULT    0x000u
#define WSG_CAN_ID_MAX        0x7FEu /* answers go on ID + 1, an 11-bit ID too */
/* Room for the strings a config file gives (paths, names, the tag): they
 * must outlive the file's line buffer, and options hold no heap memory. */
#define WSG_OPTIONS_STRBUF 2048u
/* TCP connections served at once (--max-clients): the ceiling is the
 * number of connection slots the TCP transport has. */
#define WSG_MAX_CLIENTS_MAX 256u
/* --grippers: a fleet in one process. The ceiling is generous for a CI
 * farm's box; descriptors (a few per gripper) run out well before it. */
#define WSG_GRIPPERS_MAX 10000u
/* --script-files: what the page lists at most. */
#define WSG_SCRIPT_FILES_MAX 1024u
/* Room for a pty path with a fleet's number counted into it. */
#define WSG_OPTIONS_PATH_MAX 4096u
/* Room for the names --web-host lists, comma-separated. */
#define WSG_WEB_HOSTS_MAX 1024u

/* A setting whose valid range depends on the model, which may be named
 * after it: checked against the model's range once the whole command line
 * is read. */
struct wsg_model_value {
    int given; /* 0: the model's default */
    double value;
    unsigned line; /* where it came from, for errors: line in config_path,
                      0 for the command line */
};

struct wsg_options {
    /* Interfaces. With none given on the command line: TCP and UDP on
     * their defaults, like a gripper fresh from the factory. */
    int tcp_enabled;
    struct wsg_endpoint tcp;
    uint32_t max_clients; /* TCP connections at once; more are refused */
    uint32_t grippers;    /* --grippers: how many, each its own interfaces */
    int udp_enabled;
    struct wsg_endpoint udp;     /* where the emulator listens */
    uint16_t udp_remote_port;    /* where replies go, at the sender's IP */
    const char *pty_path;        /* NULL: no serial port */
    int pty_mode_given;          /* --pty-mode: chmod the slave */
    uint32_t pty_mode;           /* permission bits, 0..0777 */
    int pty_group_given;         /* --pty-group: chown the slave's group */
    uint32_t pty_group;          /* its GID, a name resolved when read */
    const char *can_iface;       /* NULL: no CAN */
    uint16_t can_id;             /* commands on can_id, answers on can_id+1 */
    int control_enabled;         /* --control given */
    struct wsg_endpoint control; /* the control channel (loopback default) */
    int web_enabled;             /* --web given */
    struct wsg_endpoint web;     /* the web page (loopback default) */
    double time_scale;           /* simulated seconds per real second */
    const char *log_path;        /* NULL: no log; "-": stderr */
    uint32_t log_max;            /* --log-max: bytes a log file may reach */
    const char *capture_path;    /* --capture FILE; NULL: none at start */
    uint32_t capture_max;        /* --capture-max: bytes a capture may reach */
    const char *config_path;     /* --config FILE, read before the options */
    struct wsg_model_value initial_part; /* --part WIDTH */
    double initial_part_stiffness;       /* N/mm; 0: the model's default */
    uint32_t serial;                     /* Get System Information SN */
    const char *device_tag;              /* NULL: none */
    int check_crc;                       /* 0 with --no-crc */
    int disconnect_fast_stop;            /* 0 with --no-disconnect-fast-stop */
    int force_sensor;                    /* --force-sensor on: tare, D9 */
    /* --finger0, --finger1: WSG_FINGER_* + 1 (0: not given, the kind
     * --force-sensor implies), and a device model's file. */
    int finger_kind[2];
    const char *finger_model[2];
    int text_interface;      /* --text-interface on: GCL on the TCP port */
    double release_pullback; /* mm: GCL's RELEASE() */
    /* --latency MS[:JITTER]: what the gripper sends leaves MS plus up to
     * JITTER ms of simulated time late (0: at once, no delay line). */
    uint32_t latency_ms;
    uint32_t latency_jitter_ms;
    uint32_t step_us;
    const char *script_path;   /* --script FILE: the startup script */
    uint32_t script_memory;    /* --script-memory MiB */
    const char *script_dir;    /* --script-dir DIR: the page's; NULL: none */
    uint32_t script_quota;     /* --script-quota: bytes of uploaded scripts */
    uint32_t script_files;     /* --script-files: scripts the page may hold */
    const char *model;         /* NULL: the default model */
    const char *physics;       /* --physics: NULL or "builtin", "mujoco" */
    const char *scene;         /* --scene FILE.xml: NULL the built-in */
    const char *scene_fingers; /* --scene-fingers LEFT,RIGHT */
    /* The web page's settings, the model's defaults unless given. */
    struct wsg_model_value acceleration; /* mm/s^2 */
    struct wsg_model_value force_limit;  /* N */
    int homing_dir; /* WSG_HOME_DEFAULT: the model's; POSITIVE, NEGATIVE */
    struct wsg_model_value clamp_travel;    /* mm */
    struct wsg_model_value width_tolerance; /* mm */
    struct wsg_axis_config axis; /* the model's config, settings applied */

    char strbuf[WSG_OPTIONS_STRBUF];
    size_t strbuf_used;
    /* --web-host: the names the web page answers to besides the loopback
     * ones, comma-separated, in lower case; "" none. */
    char web_hosts[WSG_WEB_HOSTS_MAX];
};

/* What a setting's text is and what becomes of it. */
enum wsg_setting_type {
    WSG_SETTING_UINT,   /* decimal digits in min..max, into a uint32_t */
    WSG_SETTING_NUMBER, /* a decimal number in min..max, into a double */
    /* A struct wsg_model_value: a number >= 0 (or what parse reads),
     * checked against the model's range of quantity once it is known. */
    WSG_SETTING_MODEL,
    WSG_SETTING_BOOL, /* on|off (true|false, yes|no, 1|0), into an int */
    /* The BOOL at the same place, negated: a flag on the command line
     * (--no-crc), on|off in a file ("no-crc = on" means --no-crc). */
    WSG_SETTING_NOT,
    WSG_SETTING_TEXT,   /* a non-empty string, into a const char * */
    WSG_SETTING_PARSE,  /* composite values: parse reads and stores them */
    WSG_SETTING_CONFIG, /* --config FILE: read before the other options */
    WSG_SETTING_HELP,   /* --help: print it and exit */
    WSG_SETTING_VERSION /* --version: print it and exit */
};

/* The groups of --help, in this order. */
enum wsg_setting_section {
    WSG_SECTION_INTERFACES,
    WSG_SECTION_GRIPPER,
    WSG_SECTION_EMULATOR
};

struct wsg_setting;
/* Read val (a file's value, an argument, or the setting's default) into
 * o. line: as in struct wsg_model_value. On error the reason, without the
 * setting's name, goes to err, and -EINVAL is returned. */
typedef int (*wsg_setting_parse_fn)(struct wsg_options *o,
                                    const struct wsg_setting *s,
                                    const char *val, unsigned line, char *err,
                                    size_t errcap);

/* Where field f of struct wsg_options is: its offset plus one, so that 0
 * (a member a table row leaves out) means nowhere. */
#define WSG_AT(f) (offsetof(struct wsg_options, f) + 1u)

struct wsg_setting {
    const char *name; /* the long option, and the config file's key */
    char short_name;  /* -h; 0: none */
    enum wsg_setting_type type;
    size_t at;    /* WSG_AT(field): where the value goes (PARSE: if one) */
    size_t given; /* WSG_AT(int flag): set when given, not by default */
    wsg_setting_parse_fn parse; /* PARSE, and MODEL instead of a number */
    double min, max; /* the valid range: UINT, NUMBER, what parse reads */
    enum wsg_axis_setting quantity; /* MODEL: whose range of the model */
    const char *unit; /* in messages: "mm", "microseconds"; NULL none */
    const char *def;  /* the default as it would be given; NULL none */
    int cli_only;     /* 1: not a config-file key */
    enum wsg_setting_section section; /* --help: its group */
    const char *arg;                  /* --help: the value ("[ADDR:]PORT") */
    /* --help: lines of text, with {range} and {default} filled in; NULL
     * (NOT): shown beside its BOOL ("--crc on|off, --no-crc"). */
    const char *help;
};

enum wsg_options_result {
    WSG_OPTIONS_RUN = 0, /* start the emulator */
    WSG_OPTIONS_EXIT,    /* done (--help printed): exit status 0 */
    WSG_OPTIONS_ERROR    /* message printed on stderr: exit status 2 */
};

/* The settings table, in --help's order; its length goes to count. */
const struct wsg_setting *wsg_options_settings(size_t *count);
/* Every setting's default: the table's, or zero (none, the model's). */
void wsg_options_defaults(struct wsg_options *o);
/* The options of gripper i of a fleet: o with its interfaces counted up
 * (TCP and UDP ports, the pty path, the CAN ID pair, the serial number).
 * The pty path is written to path. With one gripper: o itself. */
void wsg_options_gripper(const struct wsg_options *o, unsigned i,
                         struct wsg_options *out, char *path, size_t pathlen);
/* Read a config file's "key = value" lines from f (named path in
 * messages) over the current contents of o. Prints a one-line
 * "wsgemu: PATH:LINE: ..." error itself. Values are kept in o: f's lines
 * must not be needed afterwards. */
enum wsg_options_result wsg_options_read_config(struct wsg_options *o, FILE *f,
                                                const char *path);
/* After all settings are read: the defaults of what was not given, the
 * model's config with every setting checked against the model's ranges,
 * the fleet's counting checked. Prints its error itself. */
enum wsg_options_result wsg_options_finish(struct wsg_options *o);
/* One config-file key given to finished options (the model known), as
 * the web page's settings give it: val read as the file's value is, and a
 * value whose range is the model's checked against it and written into
 * o->axis at once. A text value points at val: the caller keeps it. On
 * error, "KEY: reason" (as the command line words it) goes to err, and
 * -EINVAL is returned; o may then be half changed (give it a copy). */
int wsg_options_set(struct wsg_options *o, const char *key, const char *val,
                    char *err, size_t errcap);
/* Parse argv over the current contents of o (call wsg_options_defaults
 * first). Prints usage or a one-line "wsgemu: ..." error itself. */
enum wsg_options_result wsg_options_parse(struct wsg_options *o, int argc,
                                          char **argv);

#endif
