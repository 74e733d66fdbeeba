/*
 * Command line parsing for wsgemu. Every option is validated here, before
 * anything is opened, so a typo ends the program with status 2 and one clear
 * line instead of a half-started emulator. Values land in struct
 * wsg_options; the model's configuration is resolved here too, because an
 * unknown model name is a usage error like any other.
 */
#define _GNU_SOURCE

#include "options.h"

#include "delay.h" /* the latencies it takes */
#include "sched.h" /* the time scales it runs */
#include "wsg/device.h"

#include <arpa/inet.h>
#include <ctype.h>
#include <errno.h>
#include <getopt.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

enum {
    OPT_TCP = 256,
    OPT_UDP,
    OPT_PTY,
    OPT_CAN,
    OPT_NO_CRC,
    OPT_CRC,
    OPT_NO_DISCONNECT_FAST_STOP,
    OPT_DISCONNECT_FAST_STOP,
    OPT_STEP_US,
    OPT_MODEL,
    OPT_ACCELERATION,
    OPT_FORCE_LIMIT,
    OPT_HOMING_DIRECTION,
    OPT_CLAMPING_TRAVEL,
    OPT_WIDTH_TOLERANCE,
    OPT_SERIAL,
    OPT_TAG,
    OPT_PART,
    OPT_TIME_SCALE,
    OPT_CONTROL,
    OPT_LOG,
    OPT_CONFIG,
    OPT_MAX_CLIENTS,
    OPT_GRIPPERS,
    OPT_FORCE_SENSOR,
    OPT_LATENCY
};

/* The config file's keys are these names too (without the dashes). */
static const struct option long_options[] = {
    {"tcp", required_argument, NULL, OPT_TCP},
    {"max-clients", required_argument, NULL, OPT_MAX_CLIENTS},
    {"udp", required_argument, NULL, OPT_UDP},
    {"pty", required_argument, NULL, OPT_PTY},
    {"can", required_argument, NULL, OPT_CAN},
    {"no-crc", no_argument, NULL, OPT_NO_CRC},
    {"crc", required_argument, NULL, OPT_CRC},
    {"no-disconnect-fast-stop", no_argument, NULL,
     OPT_NO_DISCONNECT_FAST_STOP},
    {"disconnect-fast-stop", required_argument, NULL,
     OPT_DISCONNECT_FAST_STOP},
    {"step-us", required_argument, NULL, OPT_STEP_US},
    {"model", required_argument, NULL, OPT_MODEL},
    {"acceleration", required_argument, NULL, OPT_ACCELERATION},
    {"force-limit", required_argument, NULL, OPT_FORCE_LIMIT},
    {"homing-direction", required_argument, NULL, OPT_HOMING_DIRECTION},
    {"clamping-travel", required_argument, NULL, OPT_CLAMPING_TRAVEL},
    {"width-tolerance", required_argument, NULL, OPT_WIDTH_TOLERANCE},
    {"serial", required_argument, NULL, OPT_SERIAL},
    {"tag", required_argument, NULL, OPT_TAG},
    {"part", required_argument, NULL, OPT_PART},
    {"time-scale", required_argument, NULL, OPT_TIME_SCALE},
    {"latency", required_argument, NULL, OPT_LATENCY},
    {"control", required_argument, NULL, OPT_CONTROL},
    {"log", required_argument, NULL, OPT_LOG},
    {"config", required_argument, NULL, OPT_CONFIG},
    {"grippers", required_argument, NULL, OPT_GRIPPERS},
    {"force-sensor", required_argument, NULL, OPT_FORCE_SENSOR},
    {"help", no_argument, NULL, 'h'},
    {"version", no_argument, NULL, 'V'},
    {NULL, 0, NULL, 0}};

static void usage(FILE *f)
{
    fprintf(
        f,
        "Usage: wsgemu [OPTION]...\n"
        "Emulate a Weiss WSG 50 gripper on its host interfaces.\n"
        "\n"
        "Interfaces (with none of these: TCP and UDP on their defaults):\n"
        "  --tcp [ADDR:]PORT          listen for TCP clients on an IPv4\n"
        "                             address (default 127.0.0.1:1000;\n"
        "                             port 0 picks a free port)\n"
        "  --udp [ADDR:]PORT[:REMOTE] receive datagrams on PORT, answer\n"
        "                             to the sender's address at port\n"
        "                             REMOTE (default 127.0.0.1:1500:1501)\n"
        "  --pty PATH                 serial port: a pseudo-terminal\n"
        "                             whose slave PATH links to\n"
        "  --can IFACE[:ID]           SocketCAN interface; commands on\n"
        "                             the 11-bit ID (default 0x000),\n"
        "                             answers on ID+1\n"
        "  --max-clients N            TCP connections served at once\n"
        "                             (1..%u, default %u); a further one\n"
        "                             is accepted and closed at once\n"
        "  --control [ADDR:]PORT      control channel (TCP, default\n"
        "                             address 127.0.0.1)\n"
        "\n"
        "Gripper (what its web page sets):\n"
        "  --model NAME               wsg50 (default), wsg50-210, wsg32,\n"
        "                             wsg25\n"
        "  --acceleration MM_S2       default acceleration (default 150,\n"
        "                             within the model's limits)\n"
        "  --force-limit N            default grasping force limit\n"
        "                             (default half the nominal force;\n"
        "                             minimum..nominal force)\n"
        "  --homing-direction DIR     positive (default) or negative\n"
        "  --clamping-travel MM       grasp clamping travel (default 10;\n"
        "                             0..stroke)\n"
        "  --width-tolerance MM       part width tolerance (default 10;\n"
        "                             0..stroke)\n"
        "  --crc on|off, --no-crc     check the checksums of received\n"
        "                             packets (default on)\n"
        "  --disconnect-fast-stop on|off, --no-disconnect-fast-stop\n"
        "                             FAST STOP when a TCP client closes\n"
        "                             without a Disconnect Announcement\n"
        "                             (07h) (default on)\n"
        "  --force-sensor on|off      force measurement fingers fitted:\n"
        "                             Tare (38h) works, 40h shows\n"
        "                             SF_FORCECNTL_MODE while grasping\n"
        "                             and holding (default off)\n"
        "  --serial N                 serial number (0..4294967295,\n"
        "                             default 1)\n"
        "  --tag TEXT                 device tag: 1..64 printable ASCII\n"
        "                             characters (default none)\n"
        "  --part WIDTH[:STIFFNESS]   a part of WIDTH mm (0..stroke)\n"
        "                             between the fingers at start,\n"
        "                             STIFFNESS N/mm (default 50)\n"
        "\n",
        WSG_MAX_CLIENTS_MAX, WSG_MAX_CLIENTS_DEFAULT);
    /* In two parts: C99 guarantees string literals of 4095 bytes only. */
    fprintf(
        f,
        "Emulator:\n"
        "  --step-us US               model step in microseconds\n"
        "                             (%u..%u, default %u)\n"
        "  --time-scale X             simulated seconds per real second\n"
        "                             (0.001..1000, default 1)\n"
        "  --latency MS[:JITTER]      every packet the gripper sends\n"
        "                             leaves MS ms of simulated time late,\n"
        "                             plus 0..JITTER ms drawn from a fixed\n"
        "                             seed, in order (0..%u each; default\n"
        "                             0: at once)\n"
        "  --log FILE                 communication log: one line per\n"
        "                             packet; '-' for stderr\n"
        "  --config FILE              read settings from FILE first; the\n"
        "                             command line overrides them\n"
        "  --grippers N               N independent grippers in one\n"
        "                             process (1..%u, default 1); each\n"
        "                             gets its own interfaces, counted up\n"
        "                             from the ones given (see README)\n"
        "  -h, --help                 show this help and exit\n"
        "  -V, --version              show the version and exit\n"
        "\n"
        "Config file: one 'key = value' per line, the keys the long option\n"
        "names without dashes, the values as on the command line; blank\n"
        "lines and lines starting with '#' are ignored; spaces around key\n"
        "and value are dropped. no-crc and no-disconnect-fast-stop take\n"
        "on|off (also true|false, yes|no, 1|0), like crc,\n"
        "disconnect-fast-stop and force-sensor. Example:\n"
        "  # cell 4\n"
        "  model = wsg50-210\n"
        "  tcp = 127.0.0.1:1000\n"
        "  acceleration = 200\n"
        "  tag = cell 4\n"
        "Errors name the file and line; bad settings exit with status 2.\n"
        "\n"
        "When every interface is open, one line is printed on stdout:\n"
        "  ready tcp=ADDR:PORT udp=ADDR:PORT>REMOTE pty=PATH can=IFACE:ID\n"
        "        control=ADDR:PORT\n"
        "(the fields of the open interfaces only; with --grippers N each\n"
        "gripper field lists N values, comma-separated, in gripper order).\n"
        "SIGINT or SIGTERM stops the emulator with exit status 0.\n",
        WSG_STEP_US_MIN, WSG_STEP_US_MAX, WSG_STEP_US_DEFAULT,
        WSG_DELAY_MS_MAX, WSG_GRIPPERS_MAX);
}

/* Decimal digits only: strtoul would also take signs, spaces and hex. */
static int parse_uint(const char *s, unsigned long max, unsigned long *out)
{
    unsigned long v = 0;

    if (*s == '\0')
        return -EINVAL;
    for (; *s; s++) {
        if (*s < '0' || *s > '9')
            return -EINVAL;
        v = v * 10 + (unsigned long)(*s - '0');
        if (v > max)
            return -ERANGE;
    }
    *out = v;
    return 0;
}

static int parse_endpoint(const char *arg, struct wsg_endpoint *ep)
{
    const char *colon = strrchr(arg, ':');
    const char *port = arg;
    unsigned long v;
    struct in_addr in;

    if (colon) {
        char host[INET_ADDRSTRLEN];
        size_t n = (size_t)(colon - arg);

        if (n == 0 || n >= sizeof host)
            return -EINVAL;
        memcpy(host, arg, n);
        host[n] = '\0';
        if (inet_pton(AF_INET, host, &in) != 1)
            return -EINVAL;
        memcpy(ep->addr, &in.s_addr, 4);
        port = colon + 1;
    }
    if (parse_uint(port, 65535, &v) < 0)
        return -EINVAL;
    ep->port = (uint16_t)v;
    return 0;
}

/* [ADDR:]PORT[:REMOTE]: an IPv4 ADDR has dots, so "1500:1501" is a port
 * pair and "127.0.0.1:1500" an address and a port. */
static int parse_udp(const char *arg, struct wsg_endpoint *ep,
                     uint16_t *remote)
{
    char buf[64];
    char *last = NULL;
    const char *first_colon = strchr(arg, ':');
    unsigned long v;
    int colons = 0;
    const char *p;

    if (strlen(arg) >= sizeof buf)
        return -EINVAL;
    for (p = arg; *p; p++)
        colons += *p == ':';
    strcpy(buf, arg);
    if (colons == 2 || (colons == 1 && first_colon &&
                        !memchr(arg, '.', (size_t)(first_colon - arg)))) {
        last = strrchr(buf, ':');
        *last++ = '\0';
        if (parse_uint(last, 65535, &v) < 0 || v == 0)
            return -EINVAL;
        *remote = (uint16_t)v;
    }
    return parse_endpoint(buf, ep);
}

/* Decimal digits, or 0x (0X) and hex digits, as the documentation gives
 * numbers: strtoul with base 0 would read 010 as octal 8, refuse 08, and
 * take blanks and signs. */
static int parse_dec_hex(const char *s, unsigned long max, unsigned long *out)
{
    unsigned long v = 0, base = 10;

    if (s[0] == '0' && (s[1] == 'x' || s[1] == 'X')) {
        base = 16;
        s += 2;
    }
    if (*s == '\0')
        return -EINVAL;
    for (; *s; s++) {
        unsigned long d;

        if (*s >= '0' && *s <= '9')
            d = (unsigned long)(*s - '0');
        else if (base == 16 && *s >= 'a' && *s <= 'f')
            d = (unsigned long)(*s - 'a' + 10);
        else if (base == 16 && *s >= 'A' && *s <= 'F')
            d = (unsigned long)(*s - 'A' + 10);
        else
            return -EINVAL;
        /* v * base + d > max, asked without overflowing */
        if (d > max || v > (max - d) / base)
            return -ERANGE;
        v = v * base + d;
    }
    *out = v;
    return 0;
}

/* IFACE[:ID], ID decimal or 0x-prefixed hex, 0..0x7FE. */
static int parse_can(char *arg, const char **iface, uint16_t *id)
{
    char *colon = strrchr(arg, ':');
    unsigned long v;

    if (colon) {
        *colon = '\0';
        if (parse_dec_hex(colon + 1, WSG_CAN_ID_MAX, &v) < 0)
            return -EINVAL;
        *id = (uint16_t)v;
    }
    /* IFNAMSIZ is 16 with its NUL */
    if (arg[0] == '\0' || strlen(arg) > 15)
        return -EINVAL;
    *iface = arg;
    return 0;
}

/* A decimal number, as strtod reads it but without its leniencies: no
 * leading blanks, no hex, no inf or nan, nothing after it. */
static int parse_double(const char *s, double *out)
{
    char *end;
    double v;

    if (*s == '\0' ||
        !(*s == '-' || *s == '+' || *s == '.' || (*s >= '0' && *s <= '9')))
        return -EINVAL;
    if (strpbrk(s, "xXiInN"))
        return -EINVAL;
    errno = 0;
    v = strtod(s, &end);
    if (errno || *end || !isfinite(v))
        return -EINVAL;
    *out = v;
    return 0;
}

static int parse_bool(const char *s, int *out)
{
    static const char *const yes[] = {"on", "true", "yes", "1"};
    static const char *const no[] = {"off", "false", "no", "0"};
    size_t i;

    for (i = 0; i < sizeof yes / sizeof yes[0]; i++) {
        if (strcmp(s, yes[i]) == 0) {
            *out = 1;
            return 0;
        }
        if (strcmp(s, no[i]) == 0) {
            *out = 0;
            return 0;
        }
    }
    return -EINVAL;
}

/* A value from a config file lives in a line buffer that is reused: keep a
 * copy in the options. Command-line values stay in argv. */
static const char *keep(struct wsg_options *o, const char *val, int from_file)
{
    size_t n = strlen(val) + 1;
    char *p;

    if (!from_file)
        return val;
    if (n > sizeof o->strbuf - o->strbuf_used)
        return NULL;
    p = o->strbuf + o->strbuf_used;
    memcpy(p, val, n);
    o->strbuf_used += n;
    return p;
}

/* Apply one setting. val is the option's argument, or for a flag option
 * (no-crc) NULL on the command line and an on|off value in a file. On
 * error, err gets the reason (without the option's name) and -1 is
 * returned. line is 0 for the command line. */
static int set_option(struct wsg_options *o, int id, const char *val,
                      unsigned line, char *err, size_t errcap)
{
    int from_file = line > 0;
    unsigned long v;
    double d;
    int b = 1;

    switch (id) {
    case OPT_NO_CRC:
    case OPT_NO_DISCONNECT_FAST_STOP:
        /* "no-crc = on" in a file means what --no-crc means. */
        if (val && parse_bool(val, &b) < 0)
            goto bad_bool;
        if (id == OPT_NO_CRC)
            o->check_crc = !b;
        else
            o->disconnect_fast_stop = !b;
        return 0;
    case OPT_CRC:
    case OPT_DISCONNECT_FAST_STOP:
    case OPT_FORCE_SENSOR:
        if (parse_bool(val, &b) < 0)
            goto bad_bool;
        if (id == OPT_CRC)
            o->check_crc = b;
        else if (id == OPT_FORCE_SENSOR)
            o->force_sensor = b;
        else
            o->disconnect_fast_stop = b;
        return 0;
    default:
        break;
    }
    switch (id) {
    case OPT_TCP:
        if (parse_endpoint(val, &o->tcp) < 0) {
            snprintf(err, errcap,
                     "'%s' is not [ADDR:]PORT with an IPv4 ADDR and a PORT "
                     "of 0..65535",
                     val);
            return -1;
        }
        o->tcp_enabled = 1;
        break;
    case OPT_CONTROL:
        if (parse_endpoint(val, &o->control) < 0) {
            snprintf(err, errcap,
                     "'%s' is not [ADDR:]PORT with an IPv4 ADDR and a PORT "
                     "of 0..65535",
                     val);
            return -1;
        }
        o->control_enabled = 1;
        break;
    case OPT_UDP:
        if (parse_udp(val, &o->udp, &o->udp_remote_port) < 0) {
            snprintf(err, errcap,
                     "'%s' is not [ADDR:]PORT[:REMOTE] with an IPv4 ADDR, a "
                     "PORT of 0..65535 and a REMOTE port of 1..65535",
                     val);
            return -1;
        }
        o->udp_enabled = 1;
        break;
    case OPT_PTY:
    case OPT_LOG:
    case OPT_MODEL: {
        const char *k;

        if (val[0] == '\0') {
            snprintf(err, errcap, "an empty value");
            return -1;
        }
        k = keep(o, val, from_file);
        if (!k)
            goto full;
        if (id == OPT_PTY)
            o->pty_path = k;
        else if (id == OPT_LOG)
            o->log_path = k;
        else
            o->model = k;
        break;
    }
    case OPT_CAN: {
        /* parse_can cuts its argument at the ID: keep it (a file's
         * value) first, and report the whole text. */
        char *k = (char *)keep(o, val, from_file);
        char shown[64];

        if (!k)
            goto full;
        snprintf(shown, sizeof shown, "%s", val);
        if (parse_can(k, &o->can_iface, &o->can_id) < 0) {
            snprintf(err, errcap,
                     "'%s' is not IFACE[:ID] with an interface name and an "
                     "11-bit ID of 0..0x7FE",
                     shown);
            return -1;
        }
        break;
    }
    case OPT_GRIPPERS:
        if (parse_uint(val, WSG_GRIPPERS_MAX, &v) < 0 || v < 1) {
            snprintf(err, errcap, "'%s' is not a number in 1..%u", val,
                     WSG_GRIPPERS_MAX);
            return -1;
        }
        o->grippers = (unsigned)v;
        break;
    case OPT_MAX_CLIENTS:
        if (parse_uint(val, WSG_MAX_CLIENTS_MAX, &v) < 0 || v < 1) {
            snprintf(err, errcap, "'%s' is not a number in 1..%u", val,
                     WSG_MAX_CLIENTS_MAX);
            return -1;
        }
        o->max_clients = (unsigned)v;
        break;
    case OPT_STEP_US:
        if (parse_uint(val, WSG_STEP_US_MAX, &v) < 0 || v < WSG_STEP_US_MIN) {
            snprintf(err, errcap,
                     "'%s' is not a number of microseconds in %u..%u", val,
                     WSG_STEP_US_MIN, WSG_STEP_US_MAX);
            return -1;
        }
        o->step_us = (uint32_t)v;
        break;
    case OPT_ACCELERATION:
    case OPT_FORCE_LIMIT:
    case OPT_CLAMPING_TRAVEL:
    case OPT_WIDTH_TOLERANCE:
        /* The range depends on the model, which may come later: checked
         * in finish(). */
        if (parse_double(val, &d) < 0 || d < 0) {
            snprintf(err, errcap, "'%s' is not a non-negative number", val);
            return -1;
        }
        if (id == OPT_ACCELERATION) {
            o->acceleration = d;
            o->line_acceleration = line;
        } else if (id == OPT_FORCE_LIMIT) {
            o->force_limit = d;
            o->line_force_limit = line;
        } else if (id == OPT_CLAMPING_TRAVEL) {
            o->clamp_travel = d;
            o->line_clamp_travel = line;
        } else {
            o->width_tolerance = d;
            o->line_width_tolerance = line;
        }
        break;
    case OPT_HOMING_DIRECTION:
        if (strcmp(val, "positive") == 0)
            o->homing_dir = WSG_HOME_POSITIVE;
        else if (strcmp(val, "negative") == 0)
            o->homing_dir = WSG_HOME_NEGATIVE;
        else {
            snprintf(err, errcap, "'%s' is not positive or negative", val);
            return -1;
        }
        break;
    case OPT_SERIAL:
        if (parse_uint(val, 0xFFFFFFFFul, &v) < 0) {
            snprintf(err, errcap, "'%s' is not a number in 0..4294967295",
                     val);
            return -1;
        }
        o->serial = (uint32_t)v;
        break;
    case OPT_TAG: {
        size_t n = strlen(val), i;
        const char *k;

        /* What Set Device Tag (51h) would accept. */
        for (i = 0; i < n; i++)
            if (val[i] < 0x20 || val[i] > 0x7E)
                break;
        if (n == 0 || n > WSG_TAG_MAX || i < n) {
            snprintf(err, errcap,
                     "'%s' is not 1..%u printable ASCII characters", val,
                     WSG_TAG_MAX);
            return -1;
        }
        k = keep(o, val, from_file);
        if (!k)
            goto full;
        o->device_tag = k;
        break;
    }
    case OPT_PART: {
        char buf[64];
        char *colon;
        double w, st = 0.0;

        if (strlen(val) >= sizeof buf)
            goto bad_part;
        strcpy(buf, val);
        colon = strchr(buf, ':');
        if (colon) {
            *colon = '\0';
            if (parse_double(colon + 1, &st) < 0 || !(st > 0))
                goto bad_part;
        }
        if (parse_double(buf, &w) < 0 || w < 0)
            goto bad_part;
        o->initial_part = w;
        o->initial_part_stiffness = st;
        o->line_part = line;
        break;
    bad_part:
        snprintf(err, errcap,
                 "'%s' is not WIDTH[:STIFFNESS] with a WIDTH in mm >= 0 and "
                 "a STIFFNESS in N/mm > 0",
                 val);
        return -1;
    }
    case OPT_LATENCY: {
        const char *colon = strchr(val, ':');
        unsigned long ms, jitter = 0;
        char buf[16];
        size_t n = colon ? (size_t)(colon - val) : strlen(val);

        /* Whole milliseconds, decimal digits only: the delay runs on the
         * model's step grid, and a fraction would only look precise. */
        if (n >= sizeof buf)
            goto bad_latency;
        memcpy(buf, val, n);
        buf[n] = '\0';
        if (parse_uint(buf, WSG_DELAY_MS_MAX, &ms) < 0 ||
            (colon && parse_uint(colon + 1, WSG_DELAY_MS_MAX, &jitter) < 0))
            goto bad_latency;
        o->latency_ms = (uint32_t)ms;
        o->latency_jitter_ms = (uint32_t)jitter;
        break;
    bad_latency:
        snprintf(err, errcap,
                 "'%s' is not MS[:JITTER] with MS and JITTER whole "
                 "milliseconds in 0..%u",
                 val, WSG_DELAY_MS_MAX);
        return -1;
    }
    case OPT_TIME_SCALE:
        if (parse_double(val, &d) < 0 || d < WSG_SCHED_SCALE_MIN ||
            d > WSG_SCHED_SCALE_MAX) {
            snprintf(err, errcap, "'%s' is not a number in %g..%g", val,
                     WSG_SCHED_SCALE_MIN, WSG_SCHED_SCALE_MAX);
            return -1;
        }
        o->time_scale = d;
        break;
    default:
        snprintf(err, errcap, "not a setting");
        return -1;
    }
    return 0;
bad_bool:
    snprintf(err, errcap, "'%s' is not on or off", val);
    return -1;
full:
    snprintf(err, errcap,
             "too much text in the config file (%u bytes "
             "of values at most)",
             WSG_OPTIONS_STRBUF);
    return -1;
}

void wsg_options_defaults(struct wsg_options *o)
{
    memset(o, 0, sizeof *o);
    o->tcp.addr[0] = 127;
    o->tcp.addr[3] = 1;
    o->tcp.port = WSG_TCP_PORT_DEFAULT;
    o->max_clients = WSG_MAX_CLIENTS_DEFAULT;
    o->grippers = 1;
    o->udp.addr[0] = 127;
    o->udp.addr[3] = 1;
    o->udp.port = WSG_UDP_PORT_DEFAULT;
    o->udp_remote_port = WSG_UDP_REMOTE_DEFAULT;
    o->can_id = WSG_CAN_ID_DEFAULT;
    o->control.addr[0] = 127;
    o->control.addr[3] = 1;
    o->time_scale = 1.0;
    o->initial_part = -1.0;
    o->initial_part_stiffness = 0.0;
    o->serial = 1;
    o->check_crc = 1;
    o->disconnect_fast_stop = 1;
    o->step_us = WSG_STEP_US_DEFAULT;
    o->model = NULL;
    o->acceleration = -1.0;
    o->force_limit = -1.0;
    o->homing_dir = WSG_HOME_DEFAULT;
    o->clamp_travel = -1.0;
    o->width_tolerance = -1.0;
}

/* "--acceleration" or "FILE:LINE: acceleration", for an error message. */
static void origin(const struct wsg_options *o, unsigned line,
                   const char *name, char *buf, size_t cap)
{
    if (line)
        snprintf(buf, cap, "%s:%u: %s", o->config_path, line, name);
    else
        snprintf(buf, cap, "--%s", name);
}

/* A range check against the model; prints the error itself. */
static int check_range(const struct wsg_options *o, double v, double lo,
                       double hi, unsigned line, const char *name,
                       const char *unit)
{
    char where[512];

    if (v >= lo && v <= hi)
        return 0;
    origin(o, line, name, where, sizeof where);
    fprintf(stderr,
            "wsgemu: %s: %g %s is out of range: %g..%g %s for the %s%s\n",
            where, v, unit, lo, hi, unit, o->model ? o->model : "wsg50",
            line ? "" : " (try --help)");
    return -1;
}

/* The UDP ports of a fleet go up in pairs: by one when the listening and
 * reply ranges stay apart, else by two when listening and reply ports
 * differ by an odd number (1500:1501 gives 1500:1501, 1502:1503, ...), so
 * no gripper listens on a port another one answers to. 0: no stride
 * keeps them apart. */
static unsigned udp_stride(const struct wsg_options *o)
{
    long d = (long)o->udp_remote_port - (long)o->udp.port;

    if (o->grippers <= 1 || o->udp.port == 0 || labs(d) >= (long)o->grippers)
        return 1;
    return (d % 2 != 0) ? 2 : 0;
}

/* Counting up must stay within the ranges of ports and CAN IDs. */
static enum wsg_options_result check_fleet(const struct wsg_options *o)
{
    unsigned long last = o->grippers - 1ul;
    unsigned stride = udp_stride(o);

    if (o->grippers <= 1)
        return WSG_OPTIONS_RUN;
    if (o->tcp_enabled && o->tcp.port != 0 && o->tcp.port + last > 65535ul) {
        fprintf(stderr,
                "wsgemu: --grippers %u: TCP ports %u..%lu go past 65535\n",
                o->grippers, o->tcp.port, o->tcp.port + last);
        return WSG_OPTIONS_ERROR;
    }
    if (o->udp_enabled && stride == 0) {
        fprintf(stderr,
                "wsgemu: --grippers %u: UDP ports from %u and reply ports "
                "from %u would overlap; give --udp PORT:REMOTE with REMOTE "
                "at least %u away from PORT, or an odd distance\n",
                o->grippers, o->udp.port, o->udp_remote_port, o->grippers);
        return WSG_OPTIONS_ERROR;
    }
    if (o->udp_enabled &&
        ((o->udp.port != 0 && o->udp.port + last * stride > 65535ul) ||
         o->udp_remote_port + last * stride > 65535ul)) {
        fprintf(stderr,
                "wsgemu: --grippers %u: UDP ports from %u and reply ports "
                "from %u, %u apart, go past 65535\n",
                o->grippers, o->udp.port, o->udp_remote_port, stride);
        return WSG_OPTIONS_ERROR;
    }
    if (o->can_iface && o->can_id + 2ul * last > WSG_CAN_ID_MAX) {
        fprintf(stderr,
                "wsgemu: --grippers %u: CAN IDs 0x%03X..0x%03lX go past "
                "0x7FF (each gripper takes two)\n",
                o->grippers, o->can_id, o->can_id + 2ul * last + 1ul);
        return WSG_OPTIONS_ERROR;
    }
    return WSG_OPTIONS_RUN;
}

void wsg_options_gripper(const struct wsg_options *o, unsigned i,
                         struct wsg_options *out, char *path, size_t pathlen)
{
    unsigned stride = udp_stride(o);

    *out = *o;
    if (o->grippers <= 1)
        return;
    if (out->tcp.port != 0)
        out->tcp.port = (uint16_t)(out->tcp.port + i);
    if (out->udp.port != 0)
        out->udp.port = (uint16_t)(out->udp.port + i * stride);
    out->udp_remote_port = (uint16_t)(out->udp_remote_port + i * stride);
    out->can_id = (uint16_t)(out->can_id + 2u * i);
    out->serial = o->serial + i;
    if (o->pty_path) {
        /* A number at the end counts up ("/tmp/wsg7": 7, 8, ...), else
         * the gripper's number is appended ("/tmp/wsg": 0, 1, ...). */
        size_t n = strlen(o->pty_path);
        size_t k = n;
        unsigned long base = 0;

        while (k > 0 && isdigit((unsigned char)o->pty_path[k - 1]) &&
               n - k < 9)
            k--;
        if (k < n)
            base = strtoul(o->pty_path + k, NULL, 10);
        snprintf(path, pathlen, "%.*s%lu", (int)k, o->pty_path, base + i);
        out->pty_path = path;
    }
}

/* Everything that needs the model: resolve it, check the settings against
 * its limits (an error, not a silent clamp: a setting the gripper would
 * not take is a mistake in the setup) and write them into its config. */
static enum wsg_options_result finish(struct wsg_options *o)
{
    struct wsg_axis_config *c = &o->axis;

    if (!o->tcp_enabled && !o->udp_enabled && !o->pty_path && !o->can_iface)
        o->tcp_enabled = o->udp_enabled = 1;
    /* Answers sent to the port it listens on would come back to it from
     * its own address as requests, and it would answer itself forever. */
    if (o->udp_enabled && o->udp.port != 0 &&
        o->udp.port == o->udp_remote_port) {
        fprintf(stderr,
                "wsgemu: --udp: REMOTE port %u is the port it listens on, "
                "so it would answer itself; give another REMOTE port "
                "(try --help)\n",
                o->udp_remote_port);
        return WSG_OPTIONS_ERROR;
    }
    if (wsg_axis_config_init(c, o->model ? o->model : "wsg50") < 0) {
        fprintf(stderr,
                "wsgemu: --model: unknown model '%s' (known: wsg50, "
                "wsg50-210, wsg32, wsg25) (try --help)\n",
                o->model);
        return WSG_OPTIONS_ERROR;
    }
    c->step_us = o->step_us;
    if (o->acceleration >= 0) {
        if (check_range(o, o->acceleration, c->min_acc, c->max_acc,
                        o->line_acceleration, "acceleration", "mm/s^2") < 0)
            return WSG_OPTIONS_ERROR;
        c->default_acc = o->acceleration;
    }
    if (o->force_limit >= 0) {
        if (check_range(o, o->force_limit, c->min_force, c->nom_force,
                        o->line_force_limit, "force-limit", "N") < 0)
            return WSG_OPTIONS_ERROR;
        c->default_force = o->force_limit;
    }
    if (o->clamp_travel >= 0) {
        if (check_range(o, o->clamp_travel, 0.0, c->stroke,
                        o->line_clamp_travel, "clamping-travel", "mm") < 0)
            return WSG_OPTIONS_ERROR;
        c->clamp_travel = o->clamp_travel;
    }
    if (o->width_tolerance >= 0) {
        if (check_range(o, o->width_tolerance, 0.0, c->stroke,
                        o->line_width_tolerance, "width-tolerance", "mm") < 0)
            return WSG_OPTIONS_ERROR;
        c->width_tolerance = o->width_tolerance;
    }
    if (o->initial_part >= 0 && check_range(o, o->initial_part, 0.0, c->stroke,
                                            o->line_part, "part", "mm") < 0)
        return WSG_OPTIONS_ERROR;
    if (o->homing_dir != WSG_HOME_DEFAULT)
        c->homing_dir = o->homing_dir;
    c->force_sensor = o->force_sensor;
    return check_fleet(o);
}

/* Read the config file: "key = value" lines over the current options. */
static enum wsg_options_result read_config(struct wsg_options *o,
                                           const char *path)
{
    enum wsg_options_result res = WSG_OPTIONS_ERROR;
    char line[1024];
    unsigned lineno = 0;
    FILE *f = fopen(path, "r");

    if (!f) {
        fprintf(stderr, "wsgemu: --config: cannot open '%s': %s\n", path,
                strerror(errno));
        return WSG_OPTIONS_ERROR;
    }
    while (fgets(line, sizeof line, f)) {
        char *key, *val, *eq, *end;
        const struct option *opt;
        char err[512];
        size_t n = strlen(line);

        lineno++;
        if (n == sizeof line - 1 && line[n - 1] != '\n' && !feof(f)) {
            fprintf(stderr,
                    "wsgemu: %s:%u: line too long (%zu characters "
                    "at most)\n",
                    path, lineno, sizeof line - 2);
            goto cleanup;
        }
        /* Trim the line; blank lines and comments carry nothing. */
        while (n && isspace((unsigned char)line[n - 1]))
            line[--n] = '\0';
        key = line;
        while (isspace((unsigned char)*key))
            key++;
        if (*key == '\0' || *key == '#')
            continue;
        eq = strchr(key, '=');
        if (!eq) {
            fprintf(stderr, "wsgemu: %s:%u: expected 'key = value'\n", path,
                    lineno);
            goto cleanup;
        }
        val = eq + 1;
        while (isspace((unsigned char)*val))
            val++;
        end = eq;
        while (end > key && isspace((unsigned char)end[-1]))
            end--;
        *end = '\0';
        for (opt = long_options; opt->name; opt++)
            if (strcmp(opt->name, key) == 0)
                break;
        if (!opt->name || opt->val == 'h' || opt->val == 'V' ||
            opt->val == OPT_CONFIG) {
            fprintf(stderr, "wsgemu: %s:%u: unknown setting '%s'\n", path,
                    lineno, key);
            goto cleanup;
        }
        if (set_option(o, opt->val, val, lineno, err, sizeof err) < 0) {
            fprintf(stderr, "wsgemu: %s:%u: %s: %s\n", path, lineno, key, err);
            goto cleanup;
        }
    }
    if (ferror(f)) {
        fprintf(stderr, "wsgemu: %s: read error\n", path);
        goto cleanup;
    }
    res = WSG_OPTIONS_RUN;
cleanup:
    fclose(f);
    return res;
}

static void bad_option(char **argv)
{
    const char *bad = argv[optind - 1];
    char opt[3] = {'-', (char)optopt, '\0'};

    /* optopt is 0 for an unknown long option and the option's value for a
     * known one given an argument it does not take. */
    if (strncmp(bad, "--", 2) == 0 && optopt != 0)
        fprintf(stderr, "wsgemu: option '%s' takes no argument", bad);
    else if (strncmp(bad, "--", 2) == 0 || optopt <= 0 || optopt > 255)
        fprintf(stderr, "wsgemu: unknown option '%s'", bad);
    else
        fprintf(stderr, "wsgemu: unknown option '%s'", opt);
    fputs(" (try --help)\n", stderr);
}

enum wsg_options_result wsg_options_parse(struct wsg_options *o, int argc,
                                          char **argv)
{
    int c, idx;

    /* getopt's own messages would name argv[0], which may be a path; ours
     * always start with "wsgemu:". */
    opterr = 0;

    /* First pass: --help and --config only, so the file is read before
     * the command line is applied over it. Errors wait for the second
     * pass. optind = 0 makes glibc start over completely. */
    optind = 0;
    while ((c = getopt_long(argc, argv, ":hV", long_options, NULL)) != -1) {
        if (c == 'h') {
            usage(stdout);
            return WSG_OPTIONS_EXIT;
        }
        if (c == 'V') {
            /* The emulator's version; the firmware it emulates is what
             * Get System Information (50h) reports. */
            printf("wsgemu %s\n", WSG_VERSION);
            return WSG_OPTIONS_EXIT;
        }
        if (c == OPT_CONFIG)
            o->config_path = optarg;
    }
    if (o->config_path && read_config(o, o->config_path) != WSG_OPTIONS_RUN)
        return WSG_OPTIONS_ERROR;

    optind = 0;
    while ((c = getopt_long(argc, argv, ":hV", long_options, &idx)) != -1) {
        char err[512];

        switch (c) {
        case OPT_CONFIG:
            break; /* read above */
        case ':':
            fprintf(stderr,
                    "wsgemu: option '%s' needs an argument (try --help)\n",
                    argv[optind - 1]);
            return WSG_OPTIONS_ERROR;
        case '?':
            bad_option(argv);
            return WSG_OPTIONS_ERROR;
        default:
            if (set_option(o, c, optarg, 0, err, sizeof err) < 0) {
                fprintf(stderr, "wsgemu: --%s: %s (try --help)\n",
                        long_options[idx].name, err);
                return WSG_OPTIONS_ERROR;
            }
            break;
        }
    }
    if (optind < argc) {
        fprintf(stderr, "wsgemu: unexpected argument '%s' (try --help)\n",
                argv[optind]);
        return WSG_OPTIONS_ERROR;
    }
    return finish(o);
}
