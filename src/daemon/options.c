/*
 * Command line and config file parsing for wsgemu, driven by one table of
 * settings (settings[], below): getopt_long's table, the config file's
 * keys, the defaults and --help are all made from it, so an option is
 * added in one row. Every option is validated here, before anything is
 * opened, so a typo ends the program with status 2 and one clear line
 * instead of a half-started emulator. Values land in struct wsg_options;
 * the model's configuration is resolved here too, because an unknown model
 * name is a usage error like any other, and the settings whose range
 * depends on the model are checked against the model's own ranges
 * (wsg_axis_config_set) once it is known.
 */
#define _GNU_SOURCE

#include "options.h"

#include "delay.h"    /* the latencies it takes */
#include "sched.h"    /* the time scales it runs */
#include "web_host.h" /* the names --web-host takes */
#include "wsg/device.h"

#include <arpa/inet.h>
#include <ctype.h>
#include <errno.h>
#include <getopt.h>
#include <grp.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

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
 * pair and "127.0.0.1:1500" an address and a port. REMOTE "source" is
 * remote port 0: answers to each datagram's source port. */
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
        if (strcmp(last, "source") == 0)
            v = 0;
        else if (parse_uint(last, 65535, &v) < 0 || v == 0)
            return -EINVAL;
        *remote = (uint16_t)v;
    }
    return parse_endpoint(buf, ep);
}

/* IFACE[:ID], ID decimal or 0x-prefixed hex, 0..max. */
static int parse_can(char *arg, unsigned long max, const char **iface,
                     uint16_t *id)
{
    char *colon = strrchr(arg, ':');
    unsigned long v;

    if (colon) {
        *colon = '\0';
        if (wsg_parse_ulong(colon + 1, max, &v) < 0)
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

/* The field of o that WSG_AT(field) names. */
static void *field(struct wsg_options *o, size_t at)
{
    return (char *)o + at - 1;
}

static int too_much_text(char *err, size_t errcap)
{
    snprintf(err, errcap,
             "too much text in the config file (%u bytes "
             "of values at most)",
             WSG_OPTIONS_STRBUF);
    return -EINVAL;
}

/* "min..max" as --help and the messages show it: whole numbers in full
 * (4294967295, where %g would write 4.29497e+09), others as %g does. */
static const char *range_text(const struct wsg_setting *s, char *buf,
                              size_t cap)
{
    const double ends[2] = {s->min, s->max};
    char end[2][24];
    int i;

    for (i = 0; i < 2; i++)
        snprintf(end[i], sizeof end[i],
                 ends[i] == floor(ends[i]) && fabs(ends[i]) < 1e15 ? "%.0f"
                                                                   : "%g",
                 ends[i]);
    snprintf(buf, cap, "%s..%s", end[0], end[1]);
    return buf;
}

static void model_value_set(struct wsg_model_value *m, double v, unsigned line)
{
    m->given = 1;
    m->value = v;
    m->line = line;
}

/* The parsers of composite values (wsg_setting_parse_fn). */

/* --tcp, --control, --web [ADDR:]PORT: without ADDR, the address before it
 * stays (the default's, or the config file's). */
static int set_endpoint(struct wsg_options *o, const struct wsg_setting *s,
                        const char *val, unsigned line, char *err,
                        size_t errcap)
{
    (void)line;
    if (parse_endpoint(val, field(o, s->at)) == 0)
        return 0;
    snprintf(err, errcap,
             "'%s' is not [ADDR:]PORT with an IPv4 ADDR and a PORT "
             "of 0..65535",
             val);
    return -EINVAL;
}

static int set_udp(struct wsg_options *o, const struct wsg_setting *s,
                   const char *val, unsigned line, char *err, size_t errcap)
{
    (void)line;
    if (parse_udp(val, field(o, s->at), &o->udp_remote_port) == 0)
        return 0;
    snprintf(err, errcap,
             "'%s' is not [ADDR:]PORT[:REMOTE] with an IPv4 ADDR, a "
             "PORT of 0..65535 and a REMOTE port of 1..65535 or 'source'",
             val);
    return -EINVAL;
}

static int set_can(struct wsg_options *o, const struct wsg_setting *s,
                   const char *val, unsigned line, char *err, size_t errcap)
{
    /* parse_can cuts its argument at the ID: keep it (a file's value)
     * first, and report the whole text. */
    char *k = (char *)keep(o, val, line > 0);
    char shown[64];

    if (!k)
        return too_much_text(err, errcap);
    snprintf(shown, sizeof shown, "%s", val);
    if (parse_can(k, (unsigned long)s->max, &o->can_iface, &o->can_id) == 0)
        return 0;
    snprintf(err, errcap,
             "'%s' is not IFACE[:ID] with an interface name and an "
             "11-bit ID of %lu..0x%lX",
             shown, (unsigned long)s->min, (unsigned long)s->max);
    return -EINVAL;
}

/* Permission bits in octal ("0660", "660"), nothing beyond 0777: the
 * set-ID and sticky bits mean nothing on a terminal. */
static int set_pty_mode(struct wsg_options *o, const struct wsg_setting *s,
                        const char *val, unsigned line, char *err,
                        size_t errcap)
{
    unsigned long v = 0;
    const char *p = val;

    (void)line;
    for (; *p >= '0' && *p <= '7' && v <= 0777; p++)
        v = v * 8 + (unsigned long)(*p - '0');
    if (p == val || *p || v > 0777) {
        snprintf(err, errcap,
                 "'%s' is not a mode in octal of 0..0777 (e.g. 0660)", val);
        return -EINVAL;
    }
    *(uint32_t *)field(o, s->at) = (uint32_t)v;
    return 0;
}

/* --finger0, --finger1: none, generic, fmf, dsa or device:FILE (a device
 * model, docs/fingers.md). */
static int set_finger(struct wsg_options *o, const struct wsg_setting *s,
                      const char *val, unsigned line, char *err, size_t errcap)
{
    int i = s->name[6] == '1', k;

    if (strncmp(val, "device:", 7) == 0 && val[7]) {
        const char *p = keep(o, val + 7, line > 0);

        if (!p) {
            snprintf(err, errcap, "too many long values");
            return -E2BIG;
        }
        o->finger_kind[i] = WSG_FINGER_DEVICE + 1;
        o->finger_model[i] = p;
        return 0;
    }
    k = wsg_finger_kind_parse(val);
    if (k < 0 || k == WSG_FINGER_DEVICE) {
        snprintf(err, errcap,
                 "'%s' is not a finger: none, generic, fmf, dsa or "
                 "device:FILE",
                 val);
        return -EINVAL;
    }
    o->finger_kind[i] = k + 1;
    o->finger_model[i] = NULL;
    return 0;
}

/* A group name, or a GID in decimal, looked up now: a group the system
 * does not know is a mistake in the setup, reported before anything
 * opens. */
static int set_pty_group(struct wsg_options *o, const struct wsg_setting *s,
                         const char *val, unsigned line, char *err,
                         size_t errcap)
{
    struct group gr, *found = NULL;
    char buf[4096];
    unsigned long v;
    int r;

    (void)line;
    if (parse_uint(val, 0xFFFFFFFEul, &v) == 0) {
        *(uint32_t *)field(o, s->at) = (uint32_t)v;
        return 0;
    }
    r = getgrnam_r(val, &gr, buf, sizeof buf, &found);
    if (r == 0 && found) {
        *(uint32_t *)field(o, s->at) = (uint32_t)found->gr_gid;
        return 0;
    }
    snprintf(err, errcap,
             "'%s' is not a group of this system (a name or a GID)", val);
    return -EINVAL;
}

static int set_homing(struct wsg_options *o, const struct wsg_setting *s,
                      const char *val, unsigned line, char *err, size_t errcap)
{
    int *dir = field(o, s->at);

    (void)line;
    if (strcmp(val, "positive") == 0)
        *dir = WSG_HOME_POSITIVE;
    else if (strcmp(val, "negative") == 0)
        *dir = WSG_HOME_NEGATIVE;
    else {
        snprintf(err, errcap, "'%s' is not positive or negative", val);
        return -EINVAL;
    }
    return 0;
}

/* NAME[,NAME...]: host names the web page answers to, added to those
 * given before (--web-host again, the config file's). Each is checked as
 * a browser would send it in Host (web_host.h): a mistyped one would
 * only lock the page out, so it is an error now, not a refusal later. */
static int set_web_host(struct wsg_options *o, const struct wsg_setting *s,
                        const char *val, unsigned line, char *err,
                        size_t errcap)
{
    char *list = field(o, s->at);
    size_t used = strlen(list);
    const char *p = val, *end;

    (void)line;
    for (;;) {
        size_t n, i;

        while (*p == ' ')
            p++;
        end = strchr(p, ',');
        n = end ? (size_t)(end - p) : strlen(p);
        while (n > 0 && p[n - 1] == ' ')
            n--;
        if (wsg_web_host_name_valid(p, n) < 0) {
            snprintf(err, errcap,
                     "'%.*s' is not a host name (letters, digits, '-' and "
                     "'.'), an IPv4 address or an [IPv6] address, without "
                     "a port",
                     (int)(n < 80 ? n : 80), p);
            return -EINVAL;
        }
        if (used + (used > 0) + n + 1 > WSG_WEB_HOSTS_MAX) {
            snprintf(err, errcap, "too many names (%u characters at most)",
                     WSG_WEB_HOSTS_MAX - 1);
            return -EINVAL;
        }
        if (used > 0)
            list[used++] = ',';
        for (i = 0; i < n; i++)
            list[used++] = (char)tolower((unsigned char)p[i]);
        list[used] = '\0';
        if (!end)
            return 0;
        p = end + 1;
    }
}

/* What Set Device Tag (51h) would accept: min..max printable characters. */
static int set_tag(struct wsg_options *o, const struct wsg_setting *s,
                   const char *val, unsigned line, char *err, size_t errcap)
{
    size_t n = strlen(val), i;
    const char *k;
    char r[64];

    for (i = 0; i < n; i++)
        if (val[i] < 0x20 || val[i] > 0x7E)
            break;
    if (n < s->min || n > s->max || i < n) {
        snprintf(err, errcap, "'%s' is not %s printable ASCII characters", val,
                 range_text(s, r, sizeof r));
        return -EINVAL;
    }
    k = keep(o, val, line > 0);
    if (!k)
        return too_much_text(err, errcap);
    *(const char **)field(o, s->at) = k;
    return 0;
}

/* WIDTH[:STIFFNESS]: WIDTH is checked against the model later, like any
 * WSG_SETTING_MODEL value. */
static int set_part(struct wsg_options *o, const struct wsg_setting *s,
                    const char *val, unsigned line, char *err, size_t errcap)
{
    char buf[64];
    char *colon;
    double w, st = 0.0;

    if (strlen(val) >= sizeof buf)
        goto bad;
    strcpy(buf, val);
    colon = strchr(buf, ':');
    if (colon) {
        *colon = '\0';
        if (parse_double(colon + 1, &st) < 0 || !(st > 0))
            goto bad;
    }
    if (parse_double(buf, &w) < 0 || w < 0)
        goto bad;
    model_value_set(field(o, s->at), w, line);
    o->initial_part_stiffness = st;
    return 0;
bad:
    snprintf(err, errcap,
             "'%s' is not WIDTH[:STIFFNESS] with a WIDTH in mm >= 0 and "
             "a STIFFNESS in N/mm > 0",
             val);
    return -EINVAL;
}

/* MS[:JITTER], each in min..max. Whole milliseconds, decimal digits only:
 * the delay runs on the model's step grid, and a fraction would only look
 * precise. */
static int set_latency(struct wsg_options *o, const struct wsg_setting *s,
                       const char *val, unsigned line, char *err,
                       size_t errcap)
{
    const char *colon = strchr(val, ':');
    unsigned long ms, jitter = 0, max = (unsigned long)s->max;
    char buf[16], r[64];
    size_t n = colon ? (size_t)(colon - val) : strlen(val);

    (void)line;
    if (n < sizeof buf) {
        memcpy(buf, val, n);
        buf[n] = '\0';
        if (parse_uint(buf, max, &ms) == 0 &&
            (!colon || parse_uint(colon + 1, max, &jitter) == 0) &&
            ms >= s->min && jitter >= s->min) {
            o->latency_ms = (uint32_t)ms;
            o->latency_jitter_ms = (uint32_t)jitter;
            return 0;
        }
    }
    snprintf(err, errcap,
             "'%s' is not MS[:JITTER] with MS and JITTER whole "
             "milliseconds in %s",
             val, range_text(s, r, sizeof r));
    return -EINVAL;
}

/* Every setting, in --help's order. Adding an option is adding a row: the
 * command line, the config file (unless cli_only), the defaults and
 * --help follow. The settings checked against the model stand in the order
 * their errors are looked for. */
static const struct wsg_setting settings[] = {
    {.name = "tcp",
     .type = WSG_SETTING_PARSE,
     .parse = set_endpoint,
     .at = WSG_AT(tcp),
     .given = WSG_AT(tcp_enabled),
     .def = "127.0.0.1:1000",
     .section = WSG_SECTION_INTERFACES,
     .arg = "[ADDR:]PORT",
     .help = "listen for TCP clients on an IPv4\n"
             "address (default {default};\n"
             "port 0 picks a free port)"},
    {.name = "udp",
     .type = WSG_SETTING_PARSE,
     .parse = set_udp,
     .at = WSG_AT(udp),
     .given = WSG_AT(udp_enabled),
     .def = "127.0.0.1:1500:1501",
     .section = WSG_SECTION_INTERFACES,
     .arg = "[ADDR:]PORT[:REMOTE]",
     .help = "receive datagrams on PORT, answer\n"
             "to the sender's address at port\n"
             "REMOTE (default {default});\n"
             "REMOTE 'source': at the port it\n"
             "sent from (not what a gripper does)"},
    {.name = "pty",
     .type = WSG_SETTING_TEXT,
     .at = WSG_AT(pty_path),
     .section = WSG_SECTION_INTERFACES,
     .arg = "PATH",
     .help = "serial port: a pseudo-terminal\n"
             "whose slave PATH links to"},
    {.name = "pty-mode",
     .type = WSG_SETTING_PARSE,
     .parse = set_pty_mode,
     .at = WSG_AT(pty_mode),
     .given = WSG_AT(pty_mode_given),
     .section = WSG_SECTION_INTERFACES,
     .arg = "MODE",
     .help = "permissions of the pty's slave, in\n"
             "octal (0660: its group may open it;\n"
             "default: as the system makes it)"},
    {.name = "pty-group",
     .type = WSG_SETTING_PARSE,
     .parse = set_pty_group,
     .at = WSG_AT(pty_group),
     .given = WSG_AT(pty_group_given),
     .section = WSG_SECTION_INTERFACES,
     .arg = "NAME|GID",
     .help = "group of the pty's slave (dialout);\n"
             "the user must be in it, or root"},
    {.name = "can",
     .type = WSG_SETTING_PARSE,
     .parse = set_can,
     .min = 0,
     .max = WSG_CAN_ID_MAX,
     .section = WSG_SECTION_INTERFACES,
     .arg = "IFACE[:ID]",
     .help = "SocketCAN interface; commands on\n"
             "the 11-bit ID (default 0x000),\n"
             "answers on ID+1"},
    /* A real gripper serves a handful; 64 leaves room for test rigs that
     * open one per process while a connection storm or a port scan still
     * finds a limit. */
    {.name = "max-clients",
     .type = WSG_SETTING_UINT,
     .at = WSG_AT(max_clients),
     .min = 1,
     .max = WSG_MAX_CLIENTS_MAX,
     .def = "64",
     .section = WSG_SECTION_INTERFACES,
     .arg = "N",
     .help = "TCP connections served at once\n"
             "({range}, default {default}); a further one\n"
             "is accepted and closed at once"},
    {.name = "control",
     .type = WSG_SETTING_PARSE,
     .parse = set_endpoint,
     .at = WSG_AT(control),
     .given = WSG_AT(control_enabled),
     .def = "127.0.0.1:0",
     .section = WSG_SECTION_INTERFACES,
     .arg = "[ADDR:]PORT",
     .help = "control channel (TCP, default\n"
             "address 127.0.0.1)"},
    /* Like the control channel, it can stop the gripper and will change
     * its settings: loopback unless an address is given. */
    {.name = "web",
     .type = WSG_SETTING_PARSE,
     .parse = set_endpoint,
     .at = WSG_AT(web),
     .given = WSG_AT(web_enabled),
     .def = "127.0.0.1:0",
     .section = WSG_SECTION_INTERFACES,
     .arg = "[ADDR:]PORT",
     .help = "the gripper's web page (HTTP,\n"
             "default address 127.0.0.1)"},
    /* DNS rebinding: a page answers only to the names it was given. */
    {.name = "web-host",
     .type = WSG_SETTING_PARSE,
     .parse = set_web_host,
     .at = WSG_AT(web_hosts),
     .section = WSG_SECTION_INTERFACES,
     .arg = "NAME[,NAME...]",
     .help = "a name the web page answers to\n"
             "(its Host) besides localhost,\n"
             "127.x.x.x, [::1] and its address;\n"
             "given again, adds (default none)"},
    {.name = "model",
     .type = WSG_SETTING_TEXT,
     .at = WSG_AT(model),
     .section = WSG_SECTION_GRIPPER,
     .arg = "NAME",
     .help = "wsg50 (default), wsg50-210, wsg32,\n"
             "wsg25"},
    {.name = "physics",
     .type = WSG_SETTING_TEXT,
     .at = WSG_AT(physics),
     .section = WSG_SECTION_GRIPPER,
     .arg = "PLANT",
     .help = "builtin (default) or mujoco: the\n"
             "world the fingers move in"},
    {.name = "scene",
     .type = WSG_SETTING_TEXT,
     .at = WSG_AT(scene),
     .section = WSG_SECTION_GRIPPER,
     .arg = "FILE",
     .help = "MJCF scene for --physics mujoco\n"
             "(default the model's own)"},
    {.name = "scene-fingers",
     .type = WSG_SETTING_TEXT,
     .at = WSG_AT(scene_fingers),
     .section = WSG_SECTION_GRIPPER,
     .arg = "LEFT,RIGHT",
     .help = "the scene's two finger slide joints\n"
             "(default wsg_left,wsg_right)"},
    {.name = "acceleration",
     .type = WSG_SETTING_MODEL,
     .at = WSG_AT(acceleration),
     .quantity = WSG_AXIS_ACCELERATION,
     .unit = "mm/s^2",
     .section = WSG_SECTION_GRIPPER,
     .arg = "MM_S2",
     .help = "default acceleration (default 150,\n"
             "within the model's limits)"},
    {.name = "force-limit",
     .type = WSG_SETTING_MODEL,
     .at = WSG_AT(force_limit),
     .quantity = WSG_AXIS_FORCE_LIMIT,
     .unit = "N",
     .section = WSG_SECTION_GRIPPER,
     .arg = "N",
     .help = "default grasping force limit\n"
             "(default half the nominal force;\n"
             "minimum..nominal force)"},
    {.name = "homing-direction",
     .type = WSG_SETTING_PARSE,
     .parse = set_homing,
     .at = WSG_AT(homing_dir),
     .section = WSG_SECTION_GRIPPER,
     .arg = "DIR",
     .help = "positive (default) or negative"},
    {.name = "clamping-travel",
     .type = WSG_SETTING_MODEL,
     .at = WSG_AT(clamp_travel),
     .quantity = WSG_AXIS_CLAMP_TRAVEL,
     .unit = "mm",
     .section = WSG_SECTION_GRIPPER,
     .arg = "MM",
     .help = "grasp clamping travel (default 10;\n"
             "0..stroke)"},
    {.name = "width-tolerance",
     .type = WSG_SETTING_MODEL,
     .at = WSG_AT(width_tolerance),
     .quantity = WSG_AXIS_WIDTH_TOLERANCE,
     .unit = "mm",
     .section = WSG_SECTION_GRIPPER,
     .arg = "MM",
     .help = "part width tolerance (default 10;\n"
             "0..stroke)"},
    {.name = "crc",
     .type = WSG_SETTING_BOOL,
     .at = WSG_AT(check_crc),
     .def = "on",
     .section = WSG_SECTION_GRIPPER,
     .arg = "on|off",
     .help = "check the checksums of received\n"
             "packets (default {default})"},
    {.name = "no-crc",
     .type = WSG_SETTING_NOT,
     .at = WSG_AT(check_crc),
     .section = WSG_SECTION_GRIPPER},
    {.name = "disconnect-fast-stop",
     .type = WSG_SETTING_BOOL,
     .at = WSG_AT(disconnect_fast_stop),
     .def = "on",
     .section = WSG_SECTION_GRIPPER,
     .arg = "on|off",
     .help = "FAST STOP when a TCP client closes\n"
             "without a Disconnect Announcement\n"
             "(07h) (default {default})"},
    {.name = "no-disconnect-fast-stop",
     .type = WSG_SETTING_NOT,
     .at = WSG_AT(disconnect_fast_stop),
     .section = WSG_SECTION_GRIPPER},
    {.name = "text-interface",
     .type = WSG_SETTING_BOOL,
     .at = WSG_AT(text_interface),
     .def = "off",
     .section = WSG_SECTION_INTERFACES,
     .arg = "on|off",
     .help = "the TCP port speaks GCL, the text\n"
             "interface of later firmware, instead\n"
             "of the binary protocol (default {default})"},
    {.name = "release-pullback",
     .type = WSG_SETTING_NUMBER,
     .at = WSG_AT(release_pullback),
     .min = 0,
     .max = 100,
     .unit = "mm",
     .def = "10",
     .section = WSG_SECTION_GRIPPER,
     .arg = "MM",
     .help = "GCL's RELEASE() opens this far\n"
             "({range} mm, default {default})"},
    {.name = "force-sensor",
     .type = WSG_SETTING_BOOL,
     .at = WSG_AT(force_sensor),
     .def = "off",
     .section = WSG_SECTION_GRIPPER,
     .arg = "on|off",
     .help = "force measurement fingers fitted:\n"
             "Tare (38h) works, 40h shows\n"
             "SF_FORCECNTL_MODE while grasping\n"
             "and holding (default {default})"},
    {.name = "finger0",
     .type = WSG_SETTING_PARSE,
     .parse = set_finger,
     .section = WSG_SECTION_GRIPPER,
     .arg = "KIND",
     .help = "finger 0 (finger 1 of 60h..63h):\n"
             "none, generic, fmf, dsa or\n"
             "device:FILE, a device model (default\n"
             "fmf with --force-sensor on, else\n"
             "generic)"},
    {.name = "finger1",
     .type = WSG_SETTING_PARSE,
     .parse = set_finger,
     .section = WSG_SECTION_GRIPPER,
     .arg = "KIND",
     .help = "finger 1 (70h..73h), as --finger0"},
    {.name = "serial",
     .type = WSG_SETTING_UINT,
     .at = WSG_AT(serial),
     .min = 0,
     .max = 4294967295.0,
     .def = "1",
     .section = WSG_SECTION_GRIPPER,
     .arg = "N",
     .help = "serial number ({range},\n"
             "default {default})"},
    {.name = "tag",
     .type = WSG_SETTING_PARSE,
     .parse = set_tag,
     .at = WSG_AT(device_tag),
     .min = 1,
     .max = WSG_TAG_MAX,
     .section = WSG_SECTION_GRIPPER,
     .arg = "TEXT",
     .help = "device tag: {range} printable ASCII\n"
             "characters (default none)"},
    {.name = "part",
     .type = WSG_SETTING_MODEL,
     .parse = set_part,
     .at = WSG_AT(initial_part),
     .quantity = WSG_AXIS_WIDTH,
     .unit = "mm",
     .section = WSG_SECTION_GRIPPER,
     .arg = "WIDTH[:STIFFNESS]",
     .help = "a part of WIDTH mm (0..stroke)\n"
             "between the fingers at start,\n"
             "STIFFNESS N/mm (default 50)"},
    {.name = "script",
     .type = WSG_SETTING_TEXT,
     .at = WSG_AT(script_path),
     .section = WSG_SECTION_GRIPPER,
     .arg = "FILE",
     .help = "startup script: run the Lua script\n"
             "FILE on the gripper at start;\n"
             "require finds modules beside it"},
    {.name = "script-dir",
     .type = WSG_SETTING_TEXT,
     .at = WSG_AT(script_dir),
     .section = WSG_SECTION_GRIPPER,
     .arg = "DIR",
     .help = "the gripper's /user: the web page\n"
             "lists, uploads, runs and deletes the\n"
             "scripts in DIR (default none)"},
    /* Uploads alone fill the directory: bounds on what they may fill it
     * with, far above what a gripper's scripts need. */
    {.name = "script-quota",
     .type = WSG_SETTING_UINT,
     .at = WSG_AT(script_quota),
     .min = 0,
     .max = 4294967295.0,
     .unit = "bytes",
     .def = "16777216",
     .section = WSG_SECTION_GRIPPER,
     .arg = "BYTES",
     .help = "the script directory's scripts may\n"
             "take BYTES in all after an upload\n"
             "({range}, default {default})"},
    {.name = "script-files",
     .type = WSG_SETTING_UINT,
     .at = WSG_AT(script_files),
     .min = 0,
     .max = WSG_SCRIPT_FILES_MAX,
     .def = "256",
     .section = WSG_SECTION_GRIPPER,
     .arg = "N",
     .help = "scripts the directory may hold after\n"
             "an upload ({range}, default {default})"},
    {.name = "script-memory",
     .type = WSG_SETTING_UINT,
     .at = WSG_AT(script_memory),
     .min = WSG_SCRIPT_MEMORY_MIN_MIB,
     .max = WSG_SCRIPT_MEMORY_MAX_MIB,
     .unit = "MiB",
     .def = "16",
     .section = WSG_SECTION_GRIPPER,
     .arg = "MIB",
     .help = "memory a script may use, MiB\n"
             "({range}, default {default}); past it\n"
             "the script stops with an error"},
    {.name = "step-us",
     .type = WSG_SETTING_UINT,
     .at = WSG_AT(step_us),
     .min = WSG_STEP_US_MIN,
     .max = WSG_STEP_US_MAX,
     .unit = "microseconds",
     .def = "1000",
     .section = WSG_SECTION_EMULATOR,
     .arg = "US",
     .help = "model step in microseconds\n"
             "({range}, default {default})"},
    {.name = "time-scale",
     .type = WSG_SETTING_NUMBER,
     .at = WSG_AT(time_scale),
     .min = WSG_SCHED_SCALE_MIN,
     .max = WSG_SCHED_SCALE_MAX,
     .def = "1",
     .section = WSG_SECTION_EMULATOR,
     .arg = "X",
     .help = "simulated seconds per real second\n"
             "({range}, default {default})"},
    {.name = "latency",
     .type = WSG_SETTING_PARSE,
     .parse = set_latency,
     .min = 0,
     .max = WSG_DELAY_MS_MAX,
     .def = "0",
     .section = WSG_SECTION_EMULATOR,
     .arg = "MS[:JITTER]",
     .help = "every packet the gripper sends\n"
             "leaves MS ms of simulated time late,\n"
             "plus 0..JITTER ms drawn from a fixed\n"
             "seed, in order ({range} each; default\n"
             "{default}: at once)"},
    {.name = "log",
     .type = WSG_SETTING_TEXT,
     .at = WSG_AT(log_path),
     .section = WSG_SECTION_EMULATOR,
     .arg = "FILE",
     .help = "communication log: one line per\n"
             "packet and per event; '-' for\n"
             "stderr; SIGHUP opens FILE again"},
    /* A log nobody rotates must not fill the disk: a bound by default,
     * generous for a day of a busy test rig. */
    {.name = "log-max",
     .type = WSG_SETTING_UINT,
     .at = WSG_AT(log_max),
     .min = 0,
     .max = 4294967295.0,
     .unit = "bytes",
     .def = "67108864",
     .section = WSG_SECTION_EMULATOR,
     .arg = "BYTES",
     .help = "at BYTES the log FILE is moved to\n"
             "FILE.old (replacing it) and a new\n"
             "one begins ({range}, default\n"
             "{default}; 0: no bound)"},
    {.name = "capture",
     .type = WSG_SETTING_TEXT,
     .at = WSG_AT(capture_path),
     .section = WSG_SECTION_EMULATOR,
     .arg = "FILE",
     .help = "write what every interface receives\n"
             "and sends to FILE as pcapng, for\n"
             "Wireshark (wsg.lua decodes it)"},
    /* A capture left running on a CI machine must not fill its disk. */
    {.name = "capture-max",
     .type = WSG_SETTING_UINT,
     .at = WSG_AT(capture_max),
     .min = 0,
     .max = 4294967295.0,
     .unit = "bytes",
     .def = "268435456",
     .section = WSG_SECTION_EMULATOR,
     .arg = "BYTES",
     .help = "a capture stops at BYTES ({range},\n"
             "default {default}; 0: no bound)"},
    {.name = "config",
     .type = WSG_SETTING_CONFIG,
     .at = WSG_AT(config_path),
     .cli_only = 1,
     .section = WSG_SECTION_EMULATOR,
     .arg = "FILE",
     .help = "read settings from FILE first; the\n"
             "command line overrides them"},
    {.name = "grippers",
     .type = WSG_SETTING_UINT,
     .at = WSG_AT(grippers),
     .min = 1,
     .max = WSG_GRIPPERS_MAX,
     .def = "1",
     .section = WSG_SECTION_EMULATOR,
     .arg = "N",
     .help = "N independent grippers in one\n"
             "process ({range}, default {default}); each\n"
             "gets its own interfaces, counted up\n"
             "from the ones given (see README)"},
    {.name = "help",
     .short_name = 'h',
     .type = WSG_SETTING_HELP,
     .cli_only = 1,
     .section = WSG_SECTION_EMULATOR,
     .help = "show this help and exit"},
    {.name = "version",
     .short_name = 'V',
     .type = WSG_SETTING_VERSION,
     .cli_only = 1,
     .section = WSG_SECTION_EMULATOR,
     .help = "show the version and exit"},
};

#define WSG_SETTINGS_N (sizeof settings / sizeof settings[0])

const struct wsg_setting *wsg_options_settings(size_t *count)
{
    *count = WSG_SETTINGS_N;
    return settings;
}

/* No value of any setting holds a control character (a newline, a
 * carriage return, a tab, ESC, DEL): a path with a newline in it would
 * write a line of its own into the config file that the web page saves,
 * and into every message that shows it. Checked here, so the command
 * line, the config file and the web page all refuse it alike. The value
 * itself is not shown: the message would carry what it refuses. */
static int control_free(const char *val, char *err, size_t errcap)
{
    size_t i;

    for (i = 0; val[i]; i++) {
        unsigned char ch = (unsigned char)val[i];

        if (ch < 0x20 || ch == 0x7F) {
            snprintf(err, errcap,
                     "a control character (byte 0x%02X at %lu) is not "
                     "allowed in a value",
                     ch, (unsigned long)i + 1);
            return -EINVAL;
        }
    }
    return 0;
}

/* Apply one setting. val is its text (an argument, a file's value, the
 * default), or NULL for a flag on the command line (--no-crc). line is 0
 * for the command line and the defaults. On error, err gets the reason
 * (without the setting's name). */
static int apply(struct wsg_options *o, const struct wsg_setting *s,
                 const char *val, unsigned line, char *err, size_t errcap)
{
    unsigned long u;
    double d;
    int b = 1;
    char r[64];
    const char *k;

    if (val && control_free(val, err, errcap) < 0)
        return -EINVAL;
    switch (s->type) {
    case WSG_SETTING_UINT:
        if (parse_uint(val, (unsigned long)s->max, &u) < 0 || u < s->min)
            goto bad_number;
        *(uint32_t *)field(o, s->at) = (uint32_t)u;
        return 0;
    case WSG_SETTING_NUMBER:
        if (parse_double(val, &d) < 0 || d < s->min || d > s->max)
            goto bad_number;
        *(double *)field(o, s->at) = d;
        return 0;
    case WSG_SETTING_MODEL:
        if (s->parse)
            return s->parse(o, s, val, line, err, errcap);
        /* The range depends on the model, which may come later: checked
         * in finish(). */
        if (parse_double(val, &d) < 0 || d < 0) {
            snprintf(err, errcap, "'%s' is not a non-negative number", val);
            return -EINVAL;
        }
        model_value_set(field(o, s->at), d, line);
        return 0;
    case WSG_SETTING_BOOL:
    case WSG_SETTING_NOT:
        /* "no-crc = on" in a file means what --no-crc means. */
        if (val && parse_bool(val, &b) < 0) {
            snprintf(err, errcap, "'%s' is not on or off", val);
            return -EINVAL;
        }
        *(int *)field(o, s->at) = s->type == WSG_SETTING_NOT ? !b : b;
        return 0;
    case WSG_SETTING_TEXT:
        if (val[0] == '\0') {
            snprintf(err, errcap, "an empty value");
            return -EINVAL;
        }
        k = keep(o, val, line > 0);
        if (!k)
            return too_much_text(err, errcap);
        *(const char **)field(o, s->at) = k;
        return 0;
    case WSG_SETTING_PARSE:
        return s->parse(o, s, val, line, err, errcap);
    default:
        snprintf(err, errcap, "not a setting");
        return -EINVAL;
    }
bad_number:
    snprintf(err, errcap, "'%s' is not a number%s%s in %s", val,
             s->unit ? " of " : "", s->unit ? s->unit : "",
             range_text(s, r, sizeof r));
    return -EINVAL;
}

/* A setting given on the command line or in the file: applied, and its
 * flag set (an interface named is served). */
static int give(struct wsg_options *o, const struct wsg_setting *s,
                const char *val, unsigned line, char *err, size_t errcap)
{
    if (apply(o, s, val, line, err, errcap) < 0)
        return -EINVAL;
    if (s->given)
        *(int *)field(o, s->given) = 1;
    return 0;
}

void wsg_options_defaults(struct wsg_options *o)
{
    char err[512];
    size_t i;

    /* Zero is the default of the rest: no such interface, no log, the
     * model's own values (homing direction WSG_HOME_DEFAULT). */
    memset(o, 0, sizeof *o);
    o->can_id = WSG_CAN_ID_DEFAULT; /* --can gives it with an IFACE only */
    for (i = 0; i < WSG_SETTINGS_N; i++) {
        if (!settings[i].def)
            continue;
        /* The table's own defaults parse; the tests start the emulator
         * with them all the time. */
        if (apply(o, &settings[i], settings[i].def, 0, err, sizeof err) < 0) {
            fprintf(stderr, "wsgemu: the default of --%s: %s\n",
                    settings[i].name, err);
            abort();
        }
    }
}

/* --help's text starts in this column. */
#define WSG_HELP_COLUMN 29

static const char *const section_names[] = {
    [WSG_SECTION_INTERFACES] =
        "Interfaces (with none of these: TCP and UDP on their defaults)",
    [WSG_SECTION_GRIPPER] = "Gripper (what its web page sets)",
    [WSG_SECTION_EMULATOR] = "Emulator",
};

/* One setting in --help: its names and value, with its negation if it has
 * one ("--crc on|off, --no-crc"), then its text from WSG_HELP_COLUMN on,
 * {range} and {default} filled in from the table. */
static void usage_setting(FILE *f, const struct wsg_setting *s)
{
    int w = fprintf(f, "  ");
    const char *p;
    char r[64];
    size_t i;

    if (s->short_name)
        w += fprintf(f, "-%c, ", s->short_name);
    w += fprintf(f, "--%s", s->name);
    if (s->arg)
        w += fprintf(f, " %s", s->arg);
    for (i = 0; i < WSG_SETTINGS_N; i++)
        if (settings[i].type == WSG_SETTING_NOT && settings[i].at == s->at)
            w += fprintf(f, ", --%s", settings[i].name);
    if (w < WSG_HELP_COLUMN)
        fprintf(f, "%*s", WSG_HELP_COLUMN - w, "");
    else
        fprintf(f, "\n%*s", WSG_HELP_COLUMN, "");
    for (p = s->help; *p; p++) {
        if (*p == '\n')
            fprintf(f, "\n%*s", WSG_HELP_COLUMN, "");
        else if (strncmp(p, "{range}", 7) == 0) {
            fputs(range_text(s, r, sizeof r), f);
            p += 6;
        } else if (strncmp(p, "{default}", 9) == 0) {
            fputs(s->def ? s->def : "none", f);
            p += 8;
        } else
            fputc(*p, f);
    }
    fputc('\n', f);
}

static void usage(FILE *f)
{
    size_t section, i;

    fputs("Usage: wsgemu [OPTION]...\n"
          "Emulate a Weiss WSG 50 gripper on its host interfaces.\n",
          f);
    /* Section by section: the table keeps a later setting next to its
     * kin (--text-interface after the gripper's), not in its section's
     * run, and each heading is printed once. */
    for (section = 0; section < sizeof section_names / sizeof *section_names;
         section++) {
        fprintf(f, "\n%s:\n", section_names[section]);
        for (i = 0; i < WSG_SETTINGS_N; i++)
            if (settings[i].help && (size_t)settings[i].section == section)
                usage_setting(f, &settings[i]);
    }
    fputs("\n"
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
          "No value, here or on the command line, may hold a control\n"
          "character (newline, tab, ESC, ...). Errors name the file and\n"
          "line; bad settings exit with status 2.\n"
          "\n"
          "When every interface is open, one line is printed on stdout:\n"
          "  ready tcp=ADDR:PORT udp=ADDR:PORT>REMOTE pty=PATH can=IFACE:ID\n"
          "        control=ADDR:PORT web=ADDR:PORT\n"
          "(the fields of the open interfaces only; with --grippers N each\n"
          "gripper field lists N values, comma-separated, in gripper order).\n"
          "SIGINT or SIGTERM stops the emulator with exit status 0.\n",
          f);
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

/* The UDP ports of a fleet go up in pairs: by one when the listening and
 * reply ranges stay apart, else by two when listening and reply ports
 * differ by an odd number (1500:1501 gives 1500:1501, 1502:1503, ...), so
 * no gripper listens on a port another one answers to. 0: no stride
 * keeps them apart. */
static unsigned udp_stride(const struct wsg_options *o)
{
    long d = (long)o->udp_remote_port - (long)o->udp.port;

    if (o->grippers <= 1 || o->udp.port == 0 || o->udp_remote_port == 0 ||
        labs(d) >= (long)o->grippers)
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
    if (out->udp_remote_port != 0) /* 0: source, for each of them */
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
 * its ranges (an error, not a silent clamp: a setting the gripper would
 * not take is a mistake in the setup) and write them into its config. */
enum wsg_options_result wsg_options_finish(struct wsg_options *o)
{
    struct wsg_axis_config *c = &o->axis;
    size_t i;

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
    for (i = 0; i < WSG_SETTINGS_N; i++) {
        const struct wsg_setting *s = &settings[i];
        const struct wsg_model_value *v;
        struct wsg_axis_range r;
        char where[512];

        if (s->type != WSG_SETTING_MODEL)
            continue;
        v = field(o, s->at);
        if (!v->given ||
            wsg_axis_config_set(c, s->quantity, v->value, &r) == 0)
            continue;
        origin(o, v->line, s->name, where, sizeof where);
        fprintf(stderr,
                "wsgemu: %s: %g %s is out of range: %g..%g %s for the %s%s\n",
                where, v->value, s->unit, r.min, r.max, s->unit,
                o->model ? o->model : "wsg50", v->line ? "" : " (try --help)");
        return WSG_OPTIONS_ERROR;
    }
    if (o->homing_dir != WSG_HOME_DEFAULT)
        c->homing_dir = o->homing_dir;
    c->force_sensor = o->force_sensor;
    return check_fleet(o);
}

/* A config file's key: a setting that is no command-line-only one. */
static const struct wsg_setting *find_key(const char *key)
{
    size_t i;

    for (i = 0; i < WSG_SETTINGS_N; i++)
        if (!settings[i].cli_only && strcmp(settings[i].name, key) == 0)
            return &settings[i];
    return NULL;
}

int wsg_options_set(struct wsg_options *o, const char *key, const char *val,
                    char *err, size_t errcap)
{
    const struct wsg_setting *s = find_key(key);
    const struct wsg_model_value *v;
    struct wsg_axis_range r;
    char why[512];

    if (!s) {
        snprintf(err, errcap, "unknown setting '%s'", key);
        return -EINVAL;
    }
    if (give(o, s, val, 0, why, sizeof why) < 0) {
        snprintf(err, errcap, "%s: %s", key, why);
        return -EINVAL;
    }
    if (s->type != WSG_SETTING_MODEL)
        return 0;
    /* As finish() checks it, with the same words. */
    v = field(o, s->at);
    if (wsg_axis_config_set(&o->axis, s->quantity, v->value, &r) == 0)
        return 0;
    snprintf(err, errcap, "%s: %g %s is out of range: %g..%g %s for the %s",
             key, v->value, s->unit, r.min, r.max, s->unit,
             o->model ? o->model : "wsg50");
    return -EINVAL;
}

enum wsg_options_result wsg_options_read_config(struct wsg_options *o, FILE *f,
                                                const char *path)
{
    char line[1024];
    unsigned lineno = 0;

    while (fgets(line, sizeof line, f)) {
        char *key, *val, *eq, *end;
        const struct wsg_setting *s;
        char err[512];
        size_t n = strlen(line);

        lineno++;
        if (n == sizeof line - 1 && line[n - 1] != '\n' && !feof(f)) {
            fprintf(stderr,
                    "wsgemu: %s:%u: line too long (%zu characters "
                    "at most)\n",
                    path, lineno, sizeof line - 2);
            return WSG_OPTIONS_ERROR;
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
            return WSG_OPTIONS_ERROR;
        }
        val = eq + 1;
        while (isspace((unsigned char)*val))
            val++;
        end = eq;
        while (end > key && isspace((unsigned char)end[-1]))
            end--;
        *end = '\0';
        s = find_key(key);
        if (!s) {
            fprintf(stderr, "wsgemu: %s:%u: unknown setting '%s'\n", path,
                    lineno, key);
            return WSG_OPTIONS_ERROR;
        }
        if (give(o, s, val, lineno, err, sizeof err) < 0) {
            fprintf(stderr, "wsgemu: %s:%u: %s: %s\n", path, lineno, key, err);
            return WSG_OPTIONS_ERROR;
        }
    }
    if (ferror(f)) {
        fprintf(stderr, "wsgemu: %s: read error\n", path);
        return WSG_OPTIONS_ERROR;
    }
    return WSG_OPTIONS_RUN;
}

/* Read the config file named by --config. */
static enum wsg_options_result read_config(struct wsg_options *o,
                                           const char *path)
{
    enum wsg_options_result res;
    FILE *f = fopen(path, "r");

    if (!f) {
        fprintf(stderr, "wsgemu: --config: cannot open '%s': %s\n", path,
                strerror(errno));
        return WSG_OPTIONS_ERROR;
    }
    res = wsg_options_read_config(o, f, path);
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

/* getopt_long's table and short options, made from the settings: a
 * setting's getopt value is its short option, else 256 plus its index. */
static void getopt_tables(struct option *longopts, char *shortopts)
{
    size_t i;

    /* ':' first: a missing argument is told apart from an unknown one. */
    *shortopts++ = ':';
    for (i = 0; i < WSG_SETTINGS_N; i++) {
        const struct wsg_setting *s = &settings[i];
        int arg = s->type != WSG_SETTING_NOT && s->type != WSG_SETTING_HELP &&
                  s->type != WSG_SETTING_VERSION;

        longopts[i].name = s->name;
        longopts[i].has_arg = arg ? required_argument : no_argument;
        longopts[i].flag = NULL;
        longopts[i].val = s->short_name ? s->short_name : 256 + (int)i;
        if (s->short_name) {
            *shortopts++ = s->short_name;
            if (arg)
                *shortopts++ = ':';
        }
    }
    memset(&longopts[i], 0, sizeof longopts[i]);
    *shortopts = '\0';
}

/* The setting getopt_long's value c stands for; NULL for '?' and ':'. */
static const struct wsg_setting *from_getopt(int c)
{
    size_t i;

    if (c >= 256 && (size_t)(c - 256) < WSG_SETTINGS_N)
        return &settings[c - 256];
    for (i = 0; i < WSG_SETTINGS_N; i++)
        if (settings[i].short_name && settings[i].short_name == c)
            return &settings[i];
    return NULL;
}

enum wsg_options_result wsg_options_parse(struct wsg_options *o, int argc,
                                          char **argv)
{
    struct option longopts[WSG_SETTINGS_N + 1];
    char shortopts[2 * WSG_SETTINGS_N + 2];
    const struct wsg_setting *s;
    int c;

    getopt_tables(longopts, shortopts);
    /* getopt's own messages would name argv[0], which may be a path; ours
     * always start with "wsgemu:". */
    opterr = 0;

    /* First pass: --help, --version and --config only, so the file is
     * read before the command line is applied over it. Errors wait for
     * the second pass. optind = 0 makes glibc start over completely. */
    optind = 0;
    while ((c = getopt_long(argc, argv, shortopts, longopts, NULL)) != -1) {
        s = from_getopt(c);
        if (!s)
            continue;
        if (s->type == WSG_SETTING_HELP) {
            usage(stdout);
            return WSG_OPTIONS_EXIT;
        }
        if (s->type == WSG_SETTING_VERSION) {
            /* The emulator's version; the firmware it emulates is what
             * Get System Information (50h) reports. */
            printf("wsgemu %s\n", WSG_VERSION);
            return WSG_OPTIONS_EXIT;
        }
        if (s->type == WSG_SETTING_CONFIG)
            *(const char **)field(o, s->at) = optarg;
    }
    if (o->config_path && read_config(o, o->config_path) != WSG_OPTIONS_RUN)
        return WSG_OPTIONS_ERROR;

    optind = 0;
    while ((c = getopt_long(argc, argv, shortopts, longopts, NULL)) != -1) {
        char err[512];

        if (c == ':') {
            fprintf(stderr,
                    "wsgemu: option '%s' needs an argument (try --help)\n",
                    argv[optind - 1]);
            return WSG_OPTIONS_ERROR;
        }
        s = from_getopt(c);
        if (!s) {
            bad_option(argv);
            return WSG_OPTIONS_ERROR;
        }
        if (s->type == WSG_SETTING_CONFIG)
            continue; /* read above */
        if (give(o, s, optarg, 0, err, sizeof err) < 0) {
            fprintf(stderr, "wsgemu: --%s: %s (try --help)\n", s->name, err);
            return WSG_OPTIONS_ERROR;
        }
    }
    if (optind < argc) {
        fprintf(stderr, "wsgemu: unexpected argument '%s' (try --help)\n",
                argv[optind]);
        return WSG_OPTIONS_ERROR;
    }
    return wsg_options_finish(o);
}
