/*
 * wsgctl: command-line client of a WSG gripper (or of wsgemu) for people and
 * shell scripts. It names every command of the 2.2.0 command set, takes
 * values in human units and prints them by the protocol schema's reply
 * layouts (wsg/schema.h), waits through E_CMD_PENDING for a motion's
 * final result, follows auto-update streams (watch), sends packets written in
 * WSG Commander's command-editor syntax (raw) and decodes hex dumps of
 * packets (decode). It talks TCP, UDP or a serial line; over TCP it always
 * sends Disconnect Announcement (07h) before closing, so using it never puts
 * the gripper into FAST STOP. With --text it speaks GCL, the text interface
 * of later firmware, instead (text.c), and closes with BYE() for the same
 * reason. Through an emulator's control channel it reads without touching
 * the gripper and runs Lua scripts on it (script). Exit statuses are
 * documented in usage().
 *
 * This file: the options and their arguments, the command table, usage()
 * and main. The link is link.c, the commands commands.c, watch.c,
 * decode.c, control.c, script.c and text.c; what they share, wsgctl.h.
 */
#define _GNU_SOURCE /* getaddrinfo, sigaction, localtime_r */

#include "wsgctl.h"

#include <errno.h>
#include <math.h>
#include <netdb.h>
#include <netinet/in.h>
#include <signal.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

/* Set by SIGINT/SIGTERM: see wsgctl.h. */
volatile sig_atomic_t interrupted;

/* The last thing err() said, for --json's "error": like errno, the one
 * piece of state of the process's error channel. */
static char last_error[512];

void err(const char *fmt, ...)
{
    va_list ap;

    va_start(ap, fmt);
    vsnprintf(last_error, sizeof last_error, fmt, ap);
    va_end(ap);
    fprintf(stderr, "wsgctl: %s\n", last_error);
}

const char *err_last(void)
{
    return last_error;
}

static void on_signal(int sig)
{
    (void)sig;
    interrupted = 1;
}

/* ---- parsing arguments ---- */

static int parse_double(const char *s, double *v)
{
    char *end;

    errno = 0;
    *v = strtod(s, &end);
    return end != s && *end == '\0' && errno == 0 && isfinite(*v) ? 0 : -1;
}

int parse_float(const char *s, float *v)
{
    double d;

    if (parse_double(s, &d) < 0)
        return -1;
    *v = (float)d;
    return 0;
}

/* Decimal digits, or 0x (0X) and hex digits, as WSG Commander and the
 * documentation write numbers (wsg_parse_ulong): 0 or -1. */
int parse_ulong(const char *s, unsigned long max, unsigned long *v)
{
    return wsg_parse_ulong(s, max, v) < 0 ? -1 : 0;
}

/* "HOST:PORT" (and ":LOCAL" for UDP) into its parts; host is copied. */
int split_addr(const char *addr, char *host, size_t cap, unsigned long *port,
               unsigned long *local)
{
    const char *c1 = strchr(addr, ':');
    char rest[64], *c2;

    if (!c1 || (size_t)(c1 - addr) >= cap || c1 == addr ||
        strlen(c1 + 1) >= sizeof rest)
        return -1;
    memcpy(host, addr, (size_t)(c1 - addr));
    host[c1 - addr] = '\0';
    strcpy(rest, c1 + 1);
    c2 = strchr(rest, ':');
    if (c2) {
        if (!local)
            return -1;
        *c2++ = '\0';
        if (parse_ulong(c2, 65535, local) < 0)
            return -1;
    }
    return parse_ulong(rest, 65535, port) < 0 || *port == 0 ? -1 : 0;
}
static const struct command commands[] = {
    {"home", c_home, 0, 1, 1, "[pos|neg]",
     "Homing (20h); default direction from the gripper's configuration",
     "wsgctl home pos", VIA_GRIPPER},
    {"move", c_move, 2, 2, 1, "WIDTH SPEED [--relative] [--stop-on-block]",
     "Preposition (21h): width in mm, speed in mm/s", "wsgctl move 40 100",
     VIA_GRIPPER},
    {"grasp", c_grasp, 2, 2, 1, "WIDTH SPEED",
     "Grasp Part (25h); no part found: E_CMD_FAILED, exit 1",
     "wsgctl grasp 30 50", VIA_GRIPPER},
    {"release", c_release, 2, 2, 1, "WIDTH SPEED",
     "Release Part (26h): open to WIDTH", "wsgctl release 60 50", VIA_GRIPPER},
    {"stop", c_stop, 0, 0, 1, "", "Stop (22h)", "wsgctl stop", VIA_GRIPPER},
    {"fast-stop", c_fast_stop, 0, 0, 1, "", "Issue FAST STOP (23h)",
     "wsgctl fast-stop", VIA_GRIPPER},
    {"ack", c_ack, 0, 0, 1, "", "Acknowledge FAST STOP or fault (24h)",
     "wsgctl ack", VIA_GRIPPER},
    {"info", c_info, 0, 0, 1, "", "Get System Information (50h)",
     "wsgctl info", VIA_GRIPPER},
    {"limits", c_limits, 0, 0, 1, "", "Get System Limits (53h)",
     "wsgctl limits", VIA_GRIPPER},
    {"state", c_state, 0, 0, 1, "",
     "system state flags by name (40h), then grasping state (41h)",
     "wsgctl state", VIA_BOTH},
    {"width", c_width, 0, 0, 1, "", "Get Opening Width (43h), mm",
     "wsgctl -q width", VIA_BOTH},
    {"speed", c_speed, 0, 0, 1, "", "Get Speed (44h), mm/s", "wsgctl speed",
     VIA_BOTH},
    {"force", c_force, 0, 0, 1, "", "Get Force (45h), N", "wsgctl force",
     VIA_BOTH},
    {"temperature", c_temperature, 0, 0, 1, "", "Get Temperature (46h), degC",
     "wsgctl temperature", VIA_BOTH},
    {"tag", c_tag, 0, 1, 1, "[TEXT]",
     "Get Device Tag (52h; \"none\" if unset), or set it (51h; \"\" "
     "removes it)",
     "wsgctl tag lab-2", VIA_GRIPPER},
    {"acc", c_acc, 0, 1, 1, "[VALUE]",
     "Get (31h) or set (30h) the acceleration, mm/s2", "wsgctl acc 500",
     VIA_GRIPPER},
    {"force-limit", c_force_limit, 0, 1, 1, "[VALUE]",
     "Get (33h) or set (32h) the force limit, N", "wsgctl force-limit 20",
     VIA_GRIPPER},
    {"soft-limits", c_soft_limits, 0, 2, 1, "[MINUS PLUS | clear]",
     "Get (35h; \"none\" if unset), set (34h) or clear (36h), mm",
     "wsgctl soft-limits 5 100", VIA_GRIPPER},
    {"overdrive", c_overdrive, 1, 1, 1, "on|off", "Overdrive Mode (37h)",
     "wsgctl overdrive on", VIA_GRIPPER},
    {"stats", c_stats, 0, 0, 1, "[--reset]",
     "Get Grasping Statistics (42h): total, no part, lost part",
     "wsgctl stats --reset", VIA_BOTH},
    {"loop", c_loop, 1, 1, 1, "TEXT", "Loop (06h): prints the echo",
     "wsgctl loop hello", VIA_GRIPPER},
    {"tare", c_tare, 0, 0, 1, "", "Tare Force Sensor (38h)", "wsgctl tare",
     VIA_GRIPPER},
    {"bye", c_bye, 0, 0, 1, "",
     "Disconnect Announcement (07h); over UDP/serial E_NOT_AVAILABLE",
     "wsgctl bye", VIA_GRIPPER},
    {"watch", c_watch, 1, 2, 1,
     "width|speed|force|state|grasp [PERIOD_MS] [--count N]",
     "auto-update (FLAGS 1, default 100 ms): one timestamped value per "
     "line until SIGINT or N values, then unsubscribes (FLAGS 0)",
     "wsgctl watch width 50 --count 10", VIA_GRIPPER},
    {"raw", c_raw, 1, 1 + WSG_PAYLOAD_MAX, 1, "ID [ITEMS...]",
     "send a packet; items as in WSG Commander's command editor: bytes "
     "(32, 0x20), floats (150.0f), strings in double quotes inside one "
     "argument ('\"text\"'; a bare word is refused); prints the answer",
     "wsgctl raw 0x21 0x00 40.0f 100.0f", VIA_GRIPPER},
    {"script", c_script, 1, 2, 1, "run FILE|stop|status|output",
     "with --control only: run the Lua script FILE on the gripper (a "
     "relative path is made absolute from here), stop it, show its state "
     "(-q: the channel's JSON) or print what it printed",
     "wsgctl --control 127.0.0.1:2000 script run pd.lua", VIA_CONTROL},
    {"wait-ready", c_wait_ready, 0, 0, 0, "[--timeout S]",
     "connect and ask 40h (--control: the channel's time) again and again "
     "until the gripper answers or --timeout passes (default 10 s); exit "
     "3 with the reason then",
     "wsgctl --timeout 30 wait-ready", VIA_BOTH},
    {"part", c_channel, 1, 2, 1, "WIDTH [STIFFNESS] | none",
     "control channel: a part of WIDTH mm (STIFFNESS N/mm) between the "
     "fingers, or none (a held part is lost)",
     "wsgctl --control 127.0.0.1:2000 part 40", VIA_CONTROL},
    {"obstacle", c_channel, 1, 1, 1, "WIDTH | none",
     "control channel: something rigid that blocks the fingers at WIDTH mm, "
     "or none",
     "wsgctl --control 127.0.0.1:2000 obstacle 30", VIA_CONTROL},
    {"object", c_channel, 1, 6, 1,
     "box W D H | cylinder D L | sphere D [MASS [FRICTION]] | none",
     "control channel, --physics mujoco: an object between the fingers "
     "(sizes in mm, mass in kg, friction), or none",
     "wsgctl --control 127.0.0.1:2000 object box 40 20 30 0.2", VIA_CONTROL},
    {"pull", c_channel, 1, 1, 1, "N",
     "control channel, --physics mujoco: pull the object out of the "
     "fingers with N newtons (0: stop)",
     "wsgctl --control 127.0.0.1:2000 pull 20", VIA_CONTROL},
    {"fault", c_channel, 2, 2, 1, "NAME on|off",
     "control channel: temp-warning, temp-fault, power, current or finger, "
     "the flag and its consequence",
     "wsgctl --control 127.0.0.1:2000 fault power on", VIA_CONTROL},
    {"time", c_channel, 0, 2, 1, "[scale X | pause | resume | step MS]",
     "control channel: simulated time (seconds), its scale, pause and "
     "resume, a step of MS ms while paused",
     "wsgctl --control 127.0.0.1:2000 time pause", VIA_CONTROL},
    {"capture", c_capture, 0, 2, 1, "[start FILE | stop]",
     "control channel: write what every interface receives and sends to "
     "FILE as pcapng (a relative path from here), stop, or show whether "
     "it runs",
     "wsgctl --control 127.0.0.1:2000 capture start run.pcapng", VIA_CONTROL},
    {"drop", c_channel, 0, 0, 1, "",
     "control channel: close every TCP connection without 07h (FAST STOP), "
     "to test a driver's reconnect",
     "wsgctl --control 127.0.0.1:2000 drop", VIA_CONTROL},
    {"reset", c_channel, 0, 0, 1, "",
     "control channel: a power cycle (defaults, not referenced, motion "
     "aborted, streams ended)",
     "wsgctl --control 127.0.0.1:2000 reset", VIA_CONTROL},
    {"finger", c_finger, 0, 3, 1,
     "[0|1 info|flags|data|power on|off | 0|1 KIND|device FILE|cells]",
     "a finger: 60h..63h (finger 0) or 70h..73h (finger 1), decoded; with "
     "--control the channel's finger: both as JSON, fit none, generic, "
     "fmf, dsa or a device model, power, a DSA pad's cells",
     "wsgctl finger 1 data", VIA_BOTH},
    {"decode", c_decode, 0, 0, 0, "",
     "decode hex packets from stdin (spaces, commas, 0x, h suffix; "
     "any line split); exit 1 if a checksum is bad or a packet incomplete",
     "echo 'AA AA AA 20 02 00 00 00 B3 FD' | wsgctl decode", VIA_GRIPPER},
};
#define NCOMMANDS (sizeof commands / sizeof commands[0])

/* A description, indented 6, in lines of at most 78 columns. */
static void print_wrapped(FILE *f, const char *s)
{
    while (*s) {
        size_t n = strlen(s), cut = n;
        if (n > 72) {
            cut = 72;
            while (cut > 0 && s[cut] != ' ')
                cut--;
            if (cut == 0)
                cut = 72;
        }
        fprintf(f, "      %.*s\n", (int)cut, s);
        s += cut;
        while (*s == ' ')
            s++;
    }
}

static void usage(FILE *f)
{
    fprintf(f,
            "usage: wsgctl [--tcp HOST:PORT | --udp HOST:PORT[:LOCAL] | "
            "--serial PATH |\n"
            "               --control HOST:PORT]\n"
            "              [--text] [--timeout S] [-q|--quiet] [--json] "
            "COMMAND [ARGS]\n"
            "\n"
            "Client of a WSG 50 gripper (or wsgemu), command set 2.2.0.\n"
            "\n"
            "Interfaces (default --tcp $WSG_HOST:$WSG_PORT, each unset "
            "or empty\n"
            "the default's: " DEFAULT_HOST ":%u):\n"
            "  --tcp HOST:PORT        every close is announced with 07h, so "
            "wsgctl never\n"
            "                         puts the gripper into FAST STOP; but "
            "07h aborts a\n"
            "                         running motion (manual 3.1.2), "
            "another client's too\n"
            "  --udp HOST:PORT[:LOCAL]\n"
            "                         requests to PORT, answers received "
            "on LOCAL\n"
            "                         (default %u, the gripper's remote "
            "port)\n"
            "  --serial PATH          raw 115200 8N1\n"
            "  --text                 speak GCL, the text interface of "
            "later firmware\n"
            "                         (wsgemu --text-interface on), over "
            "TCP: the commands\n"
            "                         listed under \"With --text\"; "
            "BYE() before the close\n"
            "  --control HOST:PORT    wsgemu's control channel: state, "
            "width, speed,\n"
            "                         force, temperature and stats read "
            "without touching\n"
            "                         the gripper (no 07h, no session): "
            "safe while another\n"
            "                         client moves it; script, part, "
            "obstacle, fault,\n"
            "                         time, capture, drop and reset go "
            "only here\n"
            "                         (without it: $WSG_CONTROL)\n"
            "Options (anywhere; \"--\" ends them; --opt=value as "
            "--opt value):\n"
            "  --timeout S            wait for an answer (through "
            "E_CMD_PENDING) up to S\n"
            "                         seconds, default 10\n"
            "  --step MS              lockstep with the emulator's time "
            "paused: once the\n"
            "                         gripper accepts a motion "
            "(E_CMD_PENDING), advance\n"
            "                         simulated time by exactly MS ms "
            "through the control\n"
            "                         channel ($WSG_CONTROL), then wait "
            "for the result\n"
            "  --force N              with --text, grasp's force: "
            "GRIP(N, ...)\n"
            "  -q, --quiet            bare values for scripts, one answer "
            "a line: \"55.00\"\n"
            "                         instead of \"width 55.00 mm\"; flags "
            "in hex, enums as\n"
            "                         numbers\n"
            "  --json                 one JSON object per command on "
            "stdout (watch: one\n"
            "                         a value): \"command\", \"status\" "
            "(the gripper's),\n"
            "                         the values by the control "
            "channel's names; on\n"
            "                         failure \"error\" and \"exit\"\n"
            "  -h, --help             this text\n"
            "  -V, --version          wsgctl's version\n"
            "\nCommands:\n",
            DEFAULT_PORT, DEFAULT_UDP_PORT);
    for (size_t i = 0; i < NCOMMANDS; i++) {
        fprintf(f, "  %s%s%s\n", commands[i].name,
                commands[i].args[0] ? " " : "", commands[i].args);
        print_wrapped(f, commands[i].what);
        fprintf(f, "      e.g. %s\n", commands[i].example);
    }
    fprintf(f, "\nWith --text (GCL; readings print as above, an ERR line "
               "goes to stderr):\n");
    for (size_t i = 0; i < text_ncommands; i++) {
        fprintf(f, "  %s%s%s\n", text_commands[i].name,
                text_commands[i].args[0] ? " " : "", text_commands[i].args);
        print_wrapped(f, text_commands[i].what);
        fprintf(f, "      e.g. %s\n", text_commands[i].example);
    }
    fprintf(f, "\nOutput: values with the manual's field names and their "
               "units, one per\n"
               "line (\"width 55.00 mm\", \"grasp-state 4 (HOLDING)\"); "
               "commands that only act\n"
               "print nothing on success. watch prefixes each value with "
               "the local time\n"
               "(HH:MM:SS.mmm; with -q, Unix seconds.mmm). raw prints "
               "\"ID Name: STATUS\" and\n"
               "\"params (N): hex bytes\" for each answer (E_CMD_PENDING "
               "too), then the\n"
               "decoded values of known IDs. script status prints named "
               "values (-q: the\n"
               "channel's JSON line), script output the script's text as "
               "it printed it.\n"
               "part, obstacle, object, pull, fault, time, capture, drop "
               "and reset print\n"
               "the channel's answer without its \"ok\" (\"part 40 50\", "
               "\"paused\"). Errors go\n"
               "to stderr with the manual's names (\"wsgctl: 25h Grasp: "
               "E_CMD_FAILED\").\n"
               "\nExit status: 0 E_SUCCESS; 1 the gripper answered another "
               "status (--text: an\n"
               "ERR line; decode: a bad checksum or incomplete packet; "
               "the control channel's\n"
               "commands: the emulator refused, its reason on stderr); 2 "
               "usage error (also\n"
               "the channel's \"error usage: ...\"); 3 cannot connect, "
               "I/O error or no\n"
               "answer within --timeout (wait-ready: none within it); 130 "
               "interrupted\n"
               "(watch: 0).\n");
}

/* ---- options ---- */

enum opt_id {
    O_HELP,
    O_VERSION,
    O_QUIET,
    O_JSON,
    O_RELATIVE,
    O_STOP_ON_BLOCK,
    O_RESET,
    O_TEXT,
    O_TCP,
    O_UDP,
    O_SERIAL,
    O_CONTROL,
    O_TIMEOUT,
    O_COUNT,
    O_FORCE,
    O_STEP
};

/* Every option, and whether it takes a value ("--timeout 5" or
 * "--timeout=5"). */
static const struct {
    const char *name;
    char letter; /* -q, -h, -V; 0: none */
    int value;
    enum opt_id id;
} options[] = {
    {"help", 'h', 0, O_HELP},       {"version", 'V', 0, O_VERSION},
    {"quiet", 'q', 0, O_QUIET},     {"json", 0, 0, O_JSON},
    {"relative", 0, 0, O_RELATIVE}, {"stop-on-block", 0, 0, O_STOP_ON_BLOCK},
    {"reset", 0, 0, O_RESET},       {"text", 0, 0, O_TEXT},
    {"tcp", 0, 1, O_TCP},           {"udp", 0, 1, O_UDP},
    {"serial", 0, 1, O_SERIAL},     {"control", 0, 1, O_CONTROL},
    {"timeout", 0, 1, O_TIMEOUT},   {"count", 0, 1, O_COUNT},
    {"force", 0, 1, O_FORCE},       {"step", 0, 1, O_STEP},
};
#define NOPTIONS (sizeof options / sizeof options[0])

/* An option's effect; 0 or an exit status (said). */
static int set_option(struct opts *o, enum opt_id id, const char *val)
{
    static const enum link_kind kinds[] = {[O_TCP] = LINK_TCP,
                                           [O_UDP] = LINK_UDP,
                                           [O_SERIAL] = LINK_SERIAL,
                                           [O_CONTROL] = LINK_CONTROL};
    unsigned long n;
    double d;

    switch (id) {
    case O_QUIET:
        o->quiet = 1;
        break;
    case O_JSON:
        break; /* seen before the others: main */
    case O_RELATIVE:
        o->relative = 1;
        break;
    case O_STOP_ON_BLOCK:
        o->stop_on_block = 1;
        break;
    case O_RESET:
        o->reset = 1;
        break;
    case O_TEXT:
        o->text = 1;
        break;
    case O_TCP:
    case O_UDP:
    case O_SERIAL:
    case O_CONTROL:
        o->kind = kinds[id];
        o->addr = val;
        o->addr_given = 1;
        break;
    case O_TIMEOUT:
        if (parse_double(val, &d) < 0 || d <= 0 || d > 86400) {
            err("--timeout: seconds, not \"%s\"", val);
            return EXIT_USAGE;
        }
        o->timeout_s = d;
        break;
    case O_COUNT:
        if (parse_ulong(val, 1000000000ul, &n) < 0 || n == 0) {
            err("--count: a positive number, not \"%s\"", val);
            return EXIT_USAGE;
        }
        o->count = (long)n;
        break;
    case O_FORCE:
        if (parse_double(val, &d) < 0 || d < 0) {
            err("--force: newtons, not \"%s\"", val);
            return EXIT_USAGE;
        }
        o->force = d;
        o->has_force = 1;
        break;
    case O_STEP:
        /* The channel's own bound on one "time step" (an hour). */
        if (parse_ulong(val, 3600000ul, &n) < 0 || n == 0) {
            err("--step: milliseconds of simulated time (1..3600000), not "
                "\"%s\"",
                val);
            return EXIT_USAGE;
        }
        o->step_ms = n;
        break;
    case O_HELP:
    case O_VERSION:
        break; /* main */
    }
    return 0;
}

/* The options into x->o, the rest into pos. 0; an exit status (said);
 * or -1 when --help or --version has been answered. */
static int parse_args(int argc, char **argv, struct ctx *x, char **pos,
                      int *npos)
{
    int opts_done = 0;

    for (int i = 1; i < argc; i++) {
        const char *a = argv[i], *val = NULL, *eq = NULL;
        size_t len;
        int k = -1, rc;

        if (opts_done || a[0] != '-' || a[1] == '\0' ||
            (a[1] != '-' && a[1] != 'q' && a[1] != 'h' && a[1] != 'V')) {
            /* Negative numbers ("-5") are arguments, not options. */
            if (*npos >= (int)(2 + WSG_PAYLOAD_MAX)) {
                err("too many arguments");
                return EXIT_USAGE;
            }
            pos[(*npos)++] = argv[i];
            continue;
        }
        if (!strcmp(a, "--")) {
            opts_done = 1;
            continue;
        }
        if (a[1] == '-') {
            eq = strchr(a + 2, '=');
            len = eq ? (size_t)(eq - a - 2) : strlen(a + 2);
            for (size_t j = 0; j < NOPTIONS; j++)
                if (strlen(options[j].name) == len &&
                    !strncmp(options[j].name, a + 2, len))
                    k = (int)j;
        } else if (a[2] == '\0') {
            for (size_t j = 0; j < NOPTIONS; j++)
                if (options[j].letter == a[1])
                    k = (int)j;
        }
        if (k < 0) {
            err("unknown option %.*s (see --help)",
                eq ? (int)(eq - a) : (int)strlen(a), a);
            return EXIT_USAGE;
        }
        if (options[k].value) {
            val = eq ? eq + 1 : i + 1 < argc ? argv[++i] : NULL;
            if (!val) {
                err("%s needs a value (see --help)", a);
                return EXIT_USAGE;
            }
        } else if (eq) {
            err("--%s takes no value", options[k].name);
            return EXIT_USAGE;
        }
        if (options[k].id == O_HELP) {
            usage(stdout);
            return -1;
        }
        if (options[k].id == O_VERSION) {
            printf("wsgctl %s\n", WSG_VERSION);
            return -1;
        }
        rc = set_option(&x->o, options[k].id, val);
        if (rc)
            return rc;
    }
    return 0;
}

/* --json stands anywhere, and applies to the errors of the line before
 * it too: looked for first. */
static int wants_json(int argc, char **argv)
{
    for (int i = 1; i < argc && strcmp(argv[i], "--"); i++)
        if (!strcmp(argv[i], "--json"))
            return 1;
    return 0;
}

/* Where the command goes when the line names no interface: the gripper's
 * TCP address from WSG_HOST and WSG_PORT (each defaulting on its own),
 * the control channel's from WSG_CONTROL. The line wins over both. 0 or
 * an exit status (said). */
static int env_defaults(struct ctx *x, const struct command *cmd, char *buf,
                        size_t cap)
{
    const char *host = getenv("WSG_HOST"), *port = getenv("WSG_PORT");
    const char *control = getenv("WSG_CONTROL");
    unsigned long p = DEFAULT_PORT;

    if (cmd->via == VIA_CONTROL) {
        if (x->o.addr_given && x->o.kind != LINK_CONTROL) {
            err("%s needs --control HOST:PORT: it goes through the "
                "emulator's control channel",
                cmd->name);
            return EXIT_USAGE;
        }
        if (!x->o.addr_given) {
            if (!control || !control[0]) {
                err("%s needs --control HOST:PORT (or WSG_CONTROL): it goes "
                    "through the emulator's control channel",
                    cmd->name);
                return EXIT_USAGE;
            }
            x->o.kind = LINK_CONTROL;
            x->o.addr = control;
        }
        return 0;
    }
    if (x->o.addr_given)
        return 0;
    if (port && port[0] && (parse_ulong(port, 65535, &p) < 0 || p == 0)) {
        err("WSG_PORT: a port 1..65535, not \"%s\"", port);
        return EXIT_USAGE;
    }
    if ((size_t)snprintf(buf, cap, "%s:%lu",
                         host && host[0] ? host : DEFAULT_HOST, p) >= cap) {
        err("WSG_HOST: too long");
        return EXIT_USAGE;
    }
    x->o.kind = LINK_TCP;
    x->o.addr = buf;
    return 0;
}

/* The command by name in the table that applies (GCL's with --text);
 * NULL (said) when there is none. */
static const struct command *find_command(const struct opts *o,
                                          const char *name)
{
    const struct command *cmd = NULL;

    if (o->text) {
        for (size_t i = 0; i < text_ncommands; i++)
            if (!strcmp(name, text_commands[i].name))
                cmd = &text_commands[i];
    } else {
        for (size_t i = 0; i < NCOMMANDS; i++)
            if (!strcmp(name, commands[i].name))
                cmd = &commands[i];
    }
    if (cmd)
        return cmd;
    for (size_t i = 0; o->text && i < NCOMMANDS; i++)
        if (!strcmp(name, commands[i].name)) {
            err("%s has no GCL form (without --text it speaks the binary "
                "protocol)",
                name);
            return NULL;
        }
    err("unknown command \"%s\" (see --help)", name);
    return NULL;
}

/* What the options and the command say together; 0 or EXIT_USAGE
 * (said). */
static int check_command(const struct ctx *x, const struct command *cmd,
                         int nargs)
{
    if (x->o.text && x->o.kind != LINK_TCP) {
        err("--text (and raw-text) speak GCL, which only TCP carries");
        return EXIT_USAGE;
    }
    if (x->o.text && (x->o.relative || x->o.stop_on_block || x->o.reset)) {
        err("--relative, --stop-on-block and --reset have no GCL form");
        return EXIT_USAGE;
    }
    if (x->o.has_force && (!x->o.text || strcmp(cmd->name, "grasp"))) {
        err("--force is for grasp with --text (GRIP's force)");
        return EXIT_USAGE;
    }
    if (nargs < cmd->min || nargs > cmd->max) {
        err("usage: wsgctl %s %s", cmd->name, cmd->args);
        return EXIT_USAGE;
    }
    if (x->o.kind == LINK_CONTROL && cmd->via == VIA_GRIPPER &&
        cmd->run != c_decode) {
        err("%s needs the gripper's interface: --control reads only (state, "
            "width, speed, force, temperature, stats) and sends the "
            "channel's own commands (part, obstacle, object, pull, fault, "
            "time, capture, "
            "drop, "
            "reset, script; wait-ready)",
            cmd->name);
        return EXIT_USAGE;
    }
    if (x->o.step_ms && (x->o.text || x->o.kind == LINK_CONTROL)) {
        err("--step steps time for a command of the binary protocol sent "
            "to the gripper (not --text, not --control)");
        return EXIT_USAGE;
    }
    if (x->o.jo && (cmd->run == c_decode || x->o.text)) {
        err("--json: decode and the commands of --text print the "
            "protocol's own text");
        return EXIT_USAGE;
    }
    return 0;
}

int main(int argc, char **argv)
{
    struct ctx x;
    char *pos[2 + WSG_PAYLOAD_MAX], tcp_addr[300];
    struct jout *jo = NULL;
    int npos = 0, rc;
    const struct command *cmd = NULL;

    memset(&x, 0, sizeof x);
    x.o.timeout_s = 10.0;
    x.o.kind = LINK_TCP;
    if (wants_json(argc, argv)) {
        jo = calloc(1, sizeof *jo);
        if (!jo) {
            err("out of memory");
            return EXIT_CONN;
        }
    }
    rc = parse_args(argc, argv, &x, pos, &npos);
    if (rc < 0) {
        /* --help, --version: answered, as text. */
        if (jo) {
            free(jo);
            jo = NULL;
        }
        rc = EXIT_OK;
        goto out;
    }
    x.o.jo = jo;
    if (rc)
        goto out;
    if (npos == 0) {
        /* Not the whole of --help (some 230 lines): the form, where it
         * connects, the commands a first try wants and where the rest is. */
        fprintf(stderr,
                "usage: wsgctl [--tcp HOST:PORT | --udp HOST:PORT[:LOCAL] | "
                "--serial PATH |\n"
                "               --control HOST:PORT] [OPTIONS] COMMAND "
                "[ARGS]\n"
                "Without an interface option: --tcp $WSG_HOST:$WSG_PORT "
                "(default %s:%d).\n"
                "To start with: wait-ready, home, width, state, move WIDTH "
                "SPEED, info.\n"
                "wsgctl --help lists every command and option.\n",
                DEFAULT_HOST, DEFAULT_PORT);
        rc = EXIT_USAGE;
        goto out;
    }
    /* raw-text is GCL's alone: it implies --text. */
    if (!strcmp(pos[0], "raw-text"))
        x.o.text = 1;
    cmd = find_command(&x.o, pos[0]);
    rc = cmd ? env_defaults(&x, cmd, tcp_addr, sizeof tcp_addr) : EXIT_USAGE;
    if (!rc)
        rc = check_command(&x, cmd, npos - 1);
    if (!rc && x.o.step_ms) {
        x.o.step_control = getenv("WSG_CONTROL");
        if (!x.o.step_control || !x.o.step_control[0]) {
            err("--step needs the emulator's control channel in "
                "WSG_CONTROL (HOST:PORT)");
            rc = EXIT_USAGE;
        }
    }
    if (rc)
        goto out;

    /* A signal ends a wait, so the close can still be announced; without
     * SA_RESTART, so poll() returns at once. */
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGINT, &sa, NULL);
    sigaction(SIGTERM, &sa, NULL);
    signal(SIGPIPE, SIG_IGN);

    x.command = cmd->name;
    if (jo && x.o.kind != LINK_CONTROL && cmd->conn)
        jo->gripper = 1;
    if (cmd->conn) {
        rc = conn_open(&x.c, &x.o);
        x.c.text = x.o.text;
        if (rc < 0) {
            conn_close(&x.c);
            rc = -rc;
            goto out;
        }
        x.have_conn = 1;
    }
    rc = cmd->run(&x, npos - 1, pos + 1);
    fflush(stdout);
    if (x.have_conn)
        conn_close(&x.c);
    if (cmd->run == c_watch && rc == EXIT_INTERRUPTED)
        rc = EXIT_OK;
out:
    if (jo) {
        if (rc != EXIT_OK || !jo->streamed)
            jout_print(jo,
                       cmd    ? cmd->name
                       : npos ? pos[0]
                              : "",
                       rc, err_last()[0] ? err_last() : "failed");
        free(jo);
    }
    return rc;
}
