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

void err(const char *fmt, ...)
{
    va_list ap;

    fputs("wsgctl: ", stderr);
    va_start(ap, fmt);
    vfprintf(stderr, fmt, ap);
    va_end(ap);
    fputc('\n', stderr);
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
     "wsgctl home pos"},
    {"move", c_move, 2, 2, 1, "WIDTH SPEED [--relative] [--stop-on-block]",
     "Preposition (21h): width in mm, speed in mm/s", "wsgctl move 40 100"},
    {"grasp", c_grasp, 2, 2, 1, "WIDTH SPEED",
     "Grasp Part (25h); no part found: E_CMD_FAILED, exit 1",
     "wsgctl grasp 30 50"},
    {"release", c_release, 2, 2, 1, "WIDTH SPEED",
     "Release Part (26h): open to WIDTH", "wsgctl release 60 50"},
    {"stop", c_stop, 0, 0, 1, "", "Stop (22h)", "wsgctl stop"},
    {"fast-stop", c_fast_stop, 0, 0, 1, "", "Issue FAST STOP (23h)",
     "wsgctl fast-stop"},
    {"ack", c_ack, 0, 0, 1, "", "Acknowledge FAST STOP or fault (24h)",
     "wsgctl ack"},
    {"info", c_info, 0, 0, 1, "", "Get System Information (50h)",
     "wsgctl info"},
    {"limits", c_limits, 0, 0, 1, "", "Get System Limits (53h)",
     "wsgctl limits"},
    {"state", c_state, 0, 0, 1, "",
     "system state flags by name (40h), then grasping state (41h)",
     "wsgctl state"},
    {"width", c_width, 0, 0, 1, "", "Get Opening Width (43h), mm",
     "wsgctl -q width"},
    {"speed", c_speed, 0, 0, 1, "", "Get Speed (44h), mm/s", "wsgctl speed"},
    {"force", c_force, 0, 0, 1, "", "Get Force (45h), N", "wsgctl force"},
    {"temperature", c_temperature, 0, 0, 1, "", "Get Temperature (46h), degC",
     "wsgctl temperature"},
    {"tag", c_tag, 0, 1, 1, "[TEXT]",
     "Get Device Tag (52h; \"none\" if unset), or set it (51h; \"\" "
     "removes it)",
     "wsgctl tag lab-2"},
    {"acc", c_acc, 0, 1, 1, "[VALUE]",
     "Get (31h) or set (30h) the acceleration, mm/s2", "wsgctl acc 500"},
    {"force-limit", c_force_limit, 0, 1, 1, "[VALUE]",
     "Get (33h) or set (32h) the force limit, N", "wsgctl force-limit 20"},
    {"soft-limits", c_soft_limits, 0, 2, 1, "[MINUS PLUS | clear]",
     "Get (35h; \"none\" if unset), set (34h) or clear (36h), mm",
     "wsgctl soft-limits 5 100"},
    {"overdrive", c_overdrive, 1, 1, 1, "on|off", "Overdrive Mode (37h)",
     "wsgctl overdrive on"},
    {"stats", c_stats, 0, 0, 1, "[--reset]",
     "Get Grasping Statistics (42h): total, no part, lost part",
     "wsgctl stats --reset"},
    {"loop", c_loop, 1, 1, 1, "TEXT", "Loop (06h): prints the echo",
     "wsgctl loop hello"},
    {"tare", c_tare, 0, 0, 1, "", "Tare Force Sensor (38h)", "wsgctl tare"},
    {"bye", c_bye, 0, 0, 1, "",
     "Disconnect Announcement (07h); over UDP/serial E_NOT_AVAILABLE",
     "wsgctl bye"},
    {"watch", c_watch, 1, 2, 1,
     "width|speed|force|state|grasp [PERIOD_MS] [--count N]",
     "auto-update (FLAGS 1, default 100 ms): one timestamped value per "
     "line until SIGINT or N values, then unsubscribes (FLAGS 0)",
     "wsgctl watch width 50 --count 10"},
    {"raw", c_raw, 1, 1 + WSG_PAYLOAD_MAX, 1, "ID [ITEMS...]",
     "send a packet; items as in WSG Commander's command editor: bytes "
     "(32, 0x20), floats (150.0f), strings in double quotes inside one "
     "argument ('\"text\"'; a bare word is refused); prints the answer",
     "wsgctl raw 0x21 0x00 40.0f 100.0f"},
    {"script", c_script, 1, 2, 1, "run FILE|stop|status|output",
     "with --control only: run the Lua script FILE on the gripper (a "
     "relative path is made absolute from here), stop it, show its state "
     "(-q: the channel's JSON) or print what it printed",
     "wsgctl --control 127.0.0.1:2000 script run pd.lua"},
    {"decode", c_decode, 0, 0, 0, "",
     "decode hex packets from stdin (spaces, commas, 0x, h suffix; "
     "any line split); exit 1 if a checksum is bad or a packet incomplete",
     "echo 'AA AA AA 20 02 00 00 00 B3 FD' | wsgctl decode"},
};
#define NCOMMANDS (sizeof commands / sizeof commands[0])

/* What --control can answer: readings the control channel's "state"
 * holds, and the scripts, which only the channel reaches. */
static int control_readable(const struct command *cmd)
{
    return cmd->run == c_state || cmd->run == c_width || cmd->run == c_speed ||
           cmd->run == c_force || cmd->run == c_temperature ||
           cmd->run == c_stats || cmd->run == c_script;
}

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
            "              [--text] [--timeout S] [-q|--quiet] "
            "COMMAND [ARGS]\n"
            "\n"
            "Client of a WSG 50 gripper (or wsgemu), command set 2.2.0.\n"
            "\n"
            "Interfaces (default --tcp " DEFAULT_TCP "):\n"
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
            "                         client moves it; script runs "
            "only here\n"
            "Options (anywhere; \"--\" ends them):\n"
            "  --timeout S            wait for an answer (through "
            "E_CMD_PENDING) up to S\n"
            "                         seconds, default 10\n"
            "  --force N              with --text, grasp's force: "
            "GRIP(N, ...)\n"
            "  -q, --quiet            bare values for scripts, one answer "
            "a line: \"55.00\"\n"
            "                         instead of \"width 55.00 mm\"; flags "
            "in hex, enums as\n"
            "                         numbers\n"
            "  -h, --help             this text\n"
            "  -V, --version          wsgctl's version\n"
            "\nCommands:\n",
            DEFAULT_UDP_PORT);
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
               "Errors go to stderr with the manual's names (\"wsgctl: 25h "
               "Grasp:\n"
               "E_CMD_FAILED\").\n"
               "\nExit status: 0 E_SUCCESS; 1 the gripper answered another "
               "status (--text: an\n"
               "ERR line; decode: a bad checksum or incomplete packet; "
               "script: the emulator\n"
               "refused, its reason on stderr); 2 usage error; 3 cannot "
               "connect, I/O error or\n"
               "no answer within --timeout; 130 interrupted (watch: 0).\n");
}

int main(int argc, char **argv)
{
    struct ctx x;
    char *pos[2 + WSG_PAYLOAD_MAX];
    int npos = 0, opts_done = 0, rc;
    const struct command *cmd = NULL;

    memset(&x, 0, sizeof x);
    x.o.kind = LINK_TCP;
    x.o.addr = DEFAULT_TCP;
    x.o.timeout_s = 10.0;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        const char *val = i + 1 < argc ? argv[i + 1] : NULL;
        double d;

        if (opts_done || a[0] != '-' || a[1] == '\0' ||
            (a[1] != '-' && a[1] != 'q' && a[1] != 'h' && a[1] != 'V')) {
            /* Negative numbers ("-5") are arguments, not options. */
            if (npos >= (int)(sizeof pos / sizeof pos[0])) {
                err("too many arguments");
                return EXIT_USAGE;
            }
            pos[npos++] = argv[i];
            continue;
        }
        if (!strcmp(a, "--")) {
            opts_done = 1;
        } else if (!strcmp(a, "-h") || !strcmp(a, "--help")) {
            usage(stdout);
            return EXIT_OK;
        } else if (!strcmp(a, "-V") || !strcmp(a, "--version")) {
            printf("wsgctl %s\n", WSG_VERSION);
            return EXIT_OK;
        } else if (!strcmp(a, "-q") || !strcmp(a, "--quiet")) {
            x.o.quiet = 1;
        } else if (!strcmp(a, "--relative")) {
            x.o.relative = 1;
        } else if (!strcmp(a, "--stop-on-block")) {
            x.o.stop_on_block = 1;
        } else if (!strcmp(a, "--reset")) {
            x.o.reset = 1;
        } else if (!strcmp(a, "--text")) {
            x.o.text = 1;
        } else if (strcmp(a, "--tcp") && strcmp(a, "--udp") &&
                   strcmp(a, "--serial") && strcmp(a, "--control") &&
                   strcmp(a, "--timeout") && strcmp(a, "--count") &&
                   strcmp(a, "--force")) {
            err("unknown option %s (see --help)", a);
            return EXIT_USAGE;
        } else if (!val) {
            err("%s needs a value (see --help)", a);
            return EXIT_USAGE;
        } else if (!strcmp(a, "--tcp") || !strcmp(a, "--udp") ||
                   !strcmp(a, "--serial") || !strcmp(a, "--control")) {
            x.o.kind = a[2] == 't'   ? LINK_TCP
                       : a[2] == 'u' ? LINK_UDP
                       : a[2] == 's' ? LINK_SERIAL
                                     : LINK_CONTROL;
            x.o.addr = val;
            i++;
        } else if (!strcmp(a, "--timeout")) {
            if (parse_double(val, &d) < 0 || d <= 0 || d > 86400) {
                err("--timeout: seconds, not \"%s\"", val);
                return EXIT_USAGE;
            }
            x.o.timeout_s = d;
            i++;
        } else if (!strcmp(a, "--count")) {
            unsigned long n;
            if (parse_ulong(val, 1000000000ul, &n) < 0 || n == 0) {
                err("--count: a positive number, not \"%s\"", val);
                return EXIT_USAGE;
            }
            x.o.count = (long)n;
            i++;
        } else if (!strcmp(a, "--force")) {
            if (parse_double(val, &d) < 0 || d < 0) {
                err("--force: newtons, not \"%s\"", val);
                return EXIT_USAGE;
            }
            x.o.force = d;
            x.o.has_force = 1;
            i++;
        } else {
            err("unknown option %s (see --help)", a);
            return EXIT_USAGE;
        }
    }
    if (npos == 0) {
        usage(stderr);
        return EXIT_USAGE;
    }
    /* raw-text is GCL's alone: it implies --text. */
    if (!strcmp(pos[0], "raw-text"))
        x.o.text = 1;
    if (x.o.text) {
        for (size_t i = 0; i < text_ncommands; i++)
            if (!strcmp(pos[0], text_commands[i].name))
                cmd = &text_commands[i];
    } else {
        for (size_t i = 0; i < NCOMMANDS; i++)
            if (!strcmp(pos[0], commands[i].name))
                cmd = &commands[i];
    }
    if (!cmd && x.o.text) {
        for (size_t i = 0; i < NCOMMANDS; i++)
            if (!strcmp(pos[0], commands[i].name))
                cmd = &commands[i];
        if (cmd) {
            err("%s has no GCL form (without --text it speaks the binary "
                "protocol)",
                pos[0]);
            return EXIT_USAGE;
        }
    }
    if (!cmd) {
        err("unknown command \"%s\" (see --help)", pos[0]);
        return EXIT_USAGE;
    }
    if (x.o.text && x.o.kind != LINK_TCP) {
        err("--text (and raw-text) speak GCL, which only TCP carries");
        return EXIT_USAGE;
    }
    if (x.o.text && (x.o.relative || x.o.stop_on_block || x.o.reset)) {
        err("--relative, --stop-on-block and --reset have no GCL form");
        return EXIT_USAGE;
    }
    if (x.o.has_force && (!x.o.text || strcmp(cmd->name, "grasp"))) {
        err("--force is for grasp with --text (GRIP's force)");
        return EXIT_USAGE;
    }
    if (npos - 1 < cmd->min || npos - 1 > cmd->max) {
        err("usage: wsgctl %s %s", cmd->name, cmd->args);
        return EXIT_USAGE;
    }
    if (x.o.kind == LINK_CONTROL && cmd->conn && !control_readable(cmd)) {
        err("--control reads only (state, width, speed, force, temperature, "
            "stats) and runs scripts (script); %s needs the gripper's "
            "interface",
            cmd->name);
        return EXIT_USAGE;
    }
    if (x.o.kind != LINK_CONTROL && cmd->run == c_script) {
        err("script needs --control HOST:PORT: scripts are run through "
            "the emulator's control channel");
        return EXIT_USAGE;
    }

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
    if (cmd->conn) {
        rc = conn_open(&x.c, &x.o);
        x.c.text = x.o.text;
        if (rc < 0) {
            conn_close(&x.c);
            return -rc;
        }
        x.have_conn = 1;
    }
    rc = cmd->run(&x, npos - 1, pos + 1);
    fflush(stdout);
    if (x.have_conn)
        conn_close(&x.c);
    if (cmd->run == c_watch && rc == EXIT_INTERRUPTED)
        rc = EXIT_OK;
    return rc;
}
