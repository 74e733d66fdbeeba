/*
 * integ_wsgctl: the command-line client against the real daemon, run as a
 * child process the way a person or a shell script runs it; only its
 * stdout, stderr and exit status are checked.
 *
 * The daemon serves TCP, UDP and (where there are pseudo-terminals) a pty
 * at once, so one gripper sees every interface:
 * - --help, usage errors (exit 2), no command (a short usage pointing
 *   to --help), no emulator listening (exit 3, saying what to check:
 *   wsgemu running, the address, WSG_HOST/WSG_PORT without --tcp);
 * - over TCP: home then width, move, grasp with no part (exit 1,
 *   E_CMD_FAILED on stderr), release, state, info, raw with bytes, a float
 *   and a string, raw with an unknown ID, watch --count, watch ended by
 *   SIGINT (exit 0);
 * - decode of the manual's example packets in its own notation, split
 *   across lines and with commas, and with a flipped checksum (exit 1);
 * - one command each over UDP and over the serial pty;
 * - --version; an unknown option is named as unknown, a known one without
 *   its value as needing one; -q info prints bare values; decode tells a
 *   request from a reply;
 * - numbers are decimal (010 is ten, 08 eight) or 0x hex, nothing else;
 * - the 07h of wsgctl's close aborts another client's running motion
 *   (manual 3.1.2), while --control reads width and state through the
 *   control channel without touching it;
 * - script through --control: run (an absolute path, and a relative one
 *   made absolute from wsgctl's directory), the script answering its own
 *   ID over TCP, status readable and as JSON (-q), output as printed
 *   (escapes undone), stop; a missing file, a second run and a script
 *   that fails are exit 1 with the emulator's reason, script without
 *   --control or with a bad subcommand exit 2;
 * - --text against a second daemon whose TCP port speaks GCL
 *   (--text-interface on): home, width, move, state, grasp with and
 *   without a part and with the force --force gives, release, stats,
 *   fast-stop refusing a move (ERR on stderr, exit 1) and ack, the
 *   readings printed as the binary commands print them; raw-text with a
 *   query, a motion (ACK then FIN) and an unknown command; what GCL has no
 *   form for refused (exit 2); wsgctl in the wrong language with either
 *   daemon gets no answer (exit 3) and still leaves it out of FAST STOP;
 *   the text daemon, too, is not in FAST STOP at the end (every close
 *   announced with BYE());
 * - the control channel's part, obstacle, fault, time, capture, drop and
 *   reset
 *   through --control, each seen in the channel's state; the channel's
 *   refusals (exit 1) and usage errors (exit 2), and none without
 *   --control or WSG_CONTROL;
 * - --step MS in lockstep: with time paused, a motion accepted and its
 *   result after exactly MS ms of simulated time (from WSG_CONTROL), a
 *   refusal at once with nothing stepped; without --step a paused motion
 *   is said to be accepted with no result (exit 3); --step without
 *   WSG_CONTROL, with a bad value or with --control is exit 2;
 * - --opt=value, WSG_HOST, WSG_PORT and WSG_CONTROL set for the child,
 *   the command line winning over them;
 * - --json objects of readings, actions, failures (the gripper's status,
 *   the reason, the exit status), watch, raw, usage errors and the
 *   control channel's answers;
 * - wait-ready: at once against the daemon, a failure within --timeout
 *   against a closed port, and a wait through a daemon started 0.5 s
 *   later on a fixed free port;
 * - at the end the gripper is not in FAST STOP: every wsgctl close over
 *   TCP was announced with 07h.
 *
 * argv[1] is the daemon; the client's path comes from $WSGCTL (set by
 * CMake) or argv[2].
 */
#define _GNU_SOURCE /* mkdtemp, posix_openpt */

#include "check.h"
#include "emu.h"
#include "emu_ctl.h"
#include "wsg/axis.h"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <signal.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

/* A bound on one run of wsgctl (its own --timeout is 10 s by default). */
#define RUN_MS emu_ms(15000)

struct env {
    const char *ctl;
    char tcp[160];   /* HOST:PORT of the daemon */
    char udp[160];   /* HOST:PORT:LOCAL for wsgctl */
    char pty[160];   /* "" without pseudo-terminals */
    char out[16384]; /* last run's stdout (--help is long) */
    char err[4096];  /* last run's stderr */
};

/* A port nobody uses right now (bound, then released). */
static unsigned free_port(int type)
{
    struct sockaddr_in sa;
    socklen_t len = sizeof sa;
    int fd = socket(AF_INET, type, 0);
    unsigned port = 0;

    REQUIRE(fd >= 0);
    memset(&sa, 0, sizeof sa);
    sa.sin_family = AF_INET;
    sa.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    if (bind(fd, (struct sockaddr *)&sa, sizeof sa) == 0 &&
        getsockname(fd, (struct sockaddr *)&sa, &len) == 0)
        port = ntohs(sa.sin_port);
    close(fd);
    REQUIRE(port != 0);
    return port;
}

/* Run wsgctl with the interface options (iface, addr; iface NULL: none)
 * and the rest; stdout and stderr into v. Returns the exit status. */
static int ctl(struct env *v, const char *iface, const char *addr, ...)
{
    const char *args[32];
    char timeout[32];
    int n = 0, rc;
    va_list ap;

    if (iface) {
        args[n++] = iface;
        args[n++] = addr;
        /* wsgctl's wait for an answer is a bound like the tests' own: as
         * long again on a machine the time scale declares slower. A later
         * --timeout of the test's overrides it. */
        if (emu_time_scale() > 1.0) {
            snprintf(timeout, sizeof timeout, "%.1f", 10.0 * emu_time_scale());
            args[n++] = "--timeout";
            args[n++] = timeout;
        }
    }
    va_start(ap, addr);
    for (const char *a; (a = va_arg(ap, const char *)) != NULL && n < 31;)
        args[n++] = a;
    va_end(ap);
    args[n] = NULL;
    rc = emu_run(v->ctl, args, RUN_MS, v->out, sizeof v->out, v->err,
                 sizeof v->err);
    printf("$ wsgctl");
    for (int i = 0; i < n; i++)
        printf(" %s", args[i]);
    printf("  -> %d\n%s", rc, v->out);
    if (v->err[0])
        printf("[stderr] %s", v->err);
    return rc;
}

#define TCP(v, ...) ctl((v), "--tcp", (v)->tcp, __VA_ARGS__, (char *)NULL)

/* A shell pipeline (for stdin): sh -c CMD, with $WSGCTL set. */
static int shell(struct env *v, const char *cmd)
{
    const char *args[] = {"-c", cmd, NULL};
    int rc;

    setenv("WSGCTL", v->ctl, 1);
    rc = emu_run("/bin/sh", args, RUN_MS, v->out, sizeof v->out, v->err,
                 sizeof v->err);
    printf("$ %s  -> %d\n%s", cmd, rc, v->out);
    if (v->err[0])
        printf("[stderr] %s", v->err);
    return rc;
}

static int has(const char *hay, const char *needle)
{
    return strstr(hay, needle) != NULL;
}

static int count_lines(const char *s)
{
    int n = 0;

    for (; *s; s++)
        n += *s == '\n';
    return n;
}

static void test_usage(struct env *v)
{
    CHECK_EQ(ctl(v, NULL, NULL, "--help", (char *)NULL), 0);
    CHECK(has(v->out, "watch") && has(v->out, "raw") &&
          has(v->out, "decode") && has(v->out, "Exit status"));
    /* No command: a short usage that points to --help, not all of it. */
    CHECK_EQ(ctl(v, NULL, NULL, (char *)NULL), 2);
    CHECK(has(v->err, "usage: wsgctl") && has(v->err, "wsgctl --help"));
    CHECK(count_lines(v->err) <= 8);
    CHECK_EQ(TCP(v, "frobnicate"), 2);
    CHECK(has(v->err, "unknown command"));
    CHECK_EQ(TCP(v, "move", "10"), 2);
    CHECK_EQ(TCP(v, "move", "ten", "20"), 2);
    CHECK_EQ(TCP(v, "home", "sideways"), 2);
    CHECK_EQ(TCP(v, "raw", "0x06", "bareword"), 2);
    CHECK_EQ(TCP(v, "raw", "300"), 2);
    CHECK_EQ(TCP(v, "--timeout", "soon", "width"), 2);
    CHECK_EQ(ctl(v, NULL, NULL, "--version", (char *)NULL), 0);
    CHECK(!strncmp(v->out, "wsgctl ", 7) && count_lines(v->out) == 1);
    CHECK_EQ(TCP(v, "--frobnicate", "width"), 2);
    CHECK(has(v->err, "unknown option --frobnicate"));
    CHECK_EQ(TCP(v, "width", "--timeout"), 2);
    CHECK(has(v->err, "--timeout needs a value"));
    CHECK_EQ(ctl(v, "--udp", "nohostport", "width", (char *)NULL), 2);
}

static void test_no_emulator(struct env *v)
{
    char addr[64];

    snprintf(addr, sizeof addr, "127.0.0.1:%u", free_port(SOCK_STREAM));
    CHECK_EQ(ctl(v, "--tcp", addr, "width", (char *)NULL), 3);
    CHECK(has(v->err, "connect"));
    /* What to check is said, not only the reason: is wsgemu running, and
     * where wsgctl looked. Without --tcp the address came from WSG_HOST
     * and WSG_PORT (or their defaults), and that is said too. */
    CHECK(has(v->err, "is wsgemu") && has(v->err, "ready line"));
    setenv("WSG_PORT", addr + strlen("127.0.0.1:"), 1);
    CHECK_EQ(ctl(v, NULL, NULL, "width", (char *)NULL), 3);
    unsetenv("WSG_PORT");
    CHECK(has(v->err, addr) && has(v->err, "is wsgemu") &&
          has(v->err, "WSG_HOST") && has(v->err, "WSG_PORT"));
    /* UDP has no connection: the missing answer is the error. */
    snprintf(addr, sizeof addr, "127.0.0.1:%u:%u", free_port(SOCK_DGRAM),
             free_port(SOCK_DGRAM));
    CHECK_EQ(ctl(v, "--udp", addr, "--timeout", "0.5", "width", (char *)NULL),
             3);
    CHECK(has(v->err, "no answer"));
}

static void test_tcp(struct env *v)
{
    CHECK_EQ(TCP(v, "home"), 0);
    CHECK_EQ(v->out[0], '\0'); /* acting commands print nothing */
    CHECK_EQ(TCP(v, "width"), 0);
    CHECK(!strcmp(v->out, "width 110.00 mm\n"));
    CHECK_EQ(TCP(v, "-q", "width"), 0);
    CHECK(!strcmp(v->out, "110.00\n"));

    CHECK_EQ(TCP(v, "move", "40", "100"), 0);
    CHECK_EQ(TCP(v, "-q", "width"), 0);
    CHECK(!strcmp(v->out, "40.00\n"));
    CHECK_EQ(TCP(v, "move", "--relative", "10", "100"), 0);
    CHECK_EQ(TCP(v, "-q", "width"), 0);
    CHECK(!strcmp(v->out, "50.00\n"));

    /* No part between the fingers. */
    CHECK_EQ(TCP(v, "grasp", "20", "50"), 1);
    CHECK(has(v->err, "E_CMD_FAILED"));
    CHECK_EQ(TCP(v, "state"), 0);
    /* SF_CMD_FAILURE is gone: the 07h of the grasp's close succeeded. */
    CHECK(has(v->out, "flags 0x00000001 (SF_REFERENCED)\n"));
    CHECK(has(v->out, "grasp-state 2 (NO_PART)\n"));
    /* Bare values: the flags in hex, the grasping state's number. */
    CHECK_EQ(TCP(v, "-q", "state"), 0);
    CHECK(!strcmp(v->out, "0x00000001\n2\n"));
    CHECK_EQ(TCP(v, "-q", "stats"), 0);
    CHECK(!strcmp(v->out, "1 1 0\n"));

    CHECK_EQ(TCP(v, "release", "60", "50"), 0);
    CHECK_EQ(TCP(v, "width"), 0);
    CHECK(!strcmp(v->out, "width 60.00 mm\n"));
    CHECK_EQ(TCP(v, "state"), 0);
    CHECK(has(v->out,
              "flags 0x00000081 (SF_REFERENCED SF_TARGET_POS_REACHED)\n"));
    CHECK(has(v->out, "grasp-state 0 (IDLE)\n"));
    CHECK(!has(v->out, "SF_FAST_STOP"));

    CHECK_EQ(TCP(v, "info"), 0);
    CHECK(
        !strcmp(v->out, "type 1 (WSG 50)\nhwrev 1\nswrev 2.2.0\nserial 1\n"));
    CHECK_EQ(TCP(v, "-q", "info"), 0); /* TYPE HWREV FIRMWARE SN */
    CHECK(!strcmp(v->out, "1 1 2.2.0 1\n"));
    CHECK_EQ(TCP(v, "limits"), 0);
    CHECK(has(v->out, "stroke 110.00 mm\nmin-speed 5.00 mm/s\n"));
    CHECK(has(v->out, "\novr-force 120.00 N\n"));

    CHECK_EQ(TCP(v, "tag"), 0);
    CHECK(!strcmp(v->out, "tag none\n"));
    CHECK_EQ(TCP(v, "tag", "bench-1"), 0);
    CHECK_EQ(TCP(v, "-q", "tag"), 0);
    CHECK(!strcmp(v->out, "bench-1\n"));
    CHECK_EQ(TCP(v, "force-limit", "30"), 0);
    CHECK_EQ(TCP(v, "force-limit"), 0);
    CHECK(!strcmp(v->out, "force-limit 30.00 N\n"));
    CHECK_EQ(TCP(v, "soft-limits", "5", "100"), 0);
    CHECK_EQ(TCP(v, "soft-limits"), 0);
    CHECK(!strcmp(v->out, "limit-minus 5.00 mm\nlimit-plus 100.00 mm\n"));
    CHECK_EQ(TCP(v, "soft-limits", "clear"), 0);
    CHECK_EQ(TCP(v, "-q", "soft-limits"), 0);
    CHECK(!strcmp(v->out, "none\n"));
    CHECK_EQ(TCP(v, "temperature"), 0);
    CHECK(!strcmp(v->out, "temperature 25.0 degC\n"));
    CHECK_EQ(TCP(v, "loop", "hello"), 0);
    CHECK(!strcmp(v->out, "hello\n"));
    CHECK_EQ(TCP(v, "tare"), 1); /* no force measurement fingers */
    CHECK(has(v->err, "E_NOT_AVAILABLE"));
}

static void test_raw(struct env *v)
{
    /* The command editor's example: a byte and the float 150.0f. */
    CHECK_EQ(TCP(v, "raw", "0x06", "0x01", "150.0f"), 0);
    CHECK(has(v->out, "06h Loop: E_SUCCESS\n"));
    CHECK(has(v->out, "params (5): 01 00 00 16 43\n"));
    CHECK_EQ(TCP(v, "raw", "6", "\"abc\"", "32"), 0);
    CHECK(has(v->out, "params (4): 61 62 63 20\n"));
    /* Known IDs come with their values. */
    CHECK_EQ(TCP(v, "raw", "0x43"), 0);
    CHECK(has(v->out, "params (4): 00 00 70 42\n"));
    CHECK(has(v->out, "width 60.00 mm\n"));
    /* A motion: pending, then the final result. */
    CHECK_EQ(TCP(v, "raw", "0x21", "0", "55.0f", "100.0f"), 0);
    CHECK(has(v->out, "E_CMD_PENDING") && has(v->out, ": E_SUCCESS"));
    CHECK_EQ(TCP(v, "raw", "0x90"), 1);
    CHECK(has(v->out, "E_CMD_UNKNOWN") && has(v->err, "E_CMD_UNKNOWN"));
    /* Numbers are decimal or 0x hex: a leading 0 makes no octal. */
    CHECK_EQ(TCP(v, "raw", "06", "010", "08", "0x0A", "0X0b", "255"), 0);
    CHECK(has(v->out, "06h Loop: E_SUCCESS\n"));
    CHECK(has(v->out, "params (5): 0A 08 0A 0B FF\n"));
    CHECK_EQ(TCP(v, "raw", "010"), 1); /* 0Ah: no command */
    CHECK(has(v->out, "0Ah") && has(v->err, "E_CMD_UNKNOWN"));
    /* Nothing else is a number: signs, blanks, a bare 0x, other prefixes,
     * more than a byte. */
    static const char *const no[] = {"+1",  " 1",  "1 ",  "0x",   "0x1G",
                                     "0b1", "0o7", "256", "0x100"};
    for (size_t i = 0; i < sizeof no / sizeof no[0]; i++) {
        CHECK_EQ(TCP(v, "raw", "6", no[i]), 2);
        CHECK(has(v->err, "bad item"));
    }
}

static void test_decode(struct env *v)
{
    /* Chapter 1's examples as the manual prints them, split over lines. */
    CHECK_EQ(shell(v, "printf 'AAh AAh AAh 01h 00h 00h E8h 10h\\n"
                      "AAh AAh AAh 01h 02h 00h 12h 34h 6Dh 66h "
                      "AAh AAh AAh 20h\\n02h 00h 00h 00h B3h FDh\\n"
                      "AAh AAh AAh 90h 02h 00h 0Eh 00h FDh 02h\\n"
                      "AAh AAh AAh 21h 02h 00h 1Ah 00h 67h CBh\\n' | "
                      "\"$WSGCTL\" decode"),
             0);
    CHECK_EQ(count_lines(v->out), 5);
    CHECK(has(v->out, "request (refused by its length or ID) 01h (unknown "
                      "ID) SIZE 0 payload checksum E8 10 ok"));
    CHECK(has(v->out, "reply 20h Homing SIZE 2 status E_SUCCESS payload "
                      "00 00 checksum B3 FD ok"));
    CHECK(has(v->out, "reply 90h (unknown ID) SIZE 2 status E_CMD_UNKNOWN"));
    CHECK(has(v->out, "reply 21h Preposition SIZE 2 status E_CMD_PENDING"));
    /* Requests: Homing with its direction byte, Get Opening Width with no
     * payload; a Loop fits both. */
    CHECK_EQ(shell(v, "echo 'AA AA AA 20 01 00 00 8F 83 "
                      "AA AA AA 43 00 00 BD 54' | \"$WSGCTL\" decode"),
             0);
    CHECK(has(v->out, "request 20h Homing SIZE 1 payload 00 checksum"));
    CHECK(has(v->out, "request 43h GetOpeningWidth SIZE 0 payload "
                      "checksum BD 54 ok"));
    CHECK(!has(v->out, "status"));
    /* The Get Acceleration reply as it really is (see NOTES), with commas
     * and 0x: the values are decoded. */
    CHECK_EQ(shell(v, "echo '0xAA,0xAA,0xAA,0x31,0x06,0x00,0x00,0x00,"
                      "0x00,0x00,0x16,0x43,0x1C,0xAF' | \"$WSGCTL\" decode"),
             0);
    CHECK(has(v->out, "acceleration 150.00 mm/s2"));
    /* A flipped checksum. */
    CHECK_EQ(shell(v, "echo 'AA AA AA 20 02 00 00 00 FD B3' | "
                      "\"$WSGCTL\" decode"),
             1);
    CHECK(has(v->out, "20h Homing") && has(v->out, "checksum FD B3 bad"));
    CHECK_EQ(shell(v, "echo 'AA AA AA 20 02 00 00' | \"$WSGCTL\" decode"), 1);
    CHECK(has(v->out, "incomplete"));
    CHECK_EQ(shell(v, "echo 'AA AA zz' | \"$WSGCTL\" decode"), 2);
}

static void test_watch(struct env *v)
{
    char line[64], cmd[256];

    CHECK_EQ(TCP(v, "watch", "width", "20", "--count", "3"), 0);
    CHECK_EQ(count_lines(v->out), 3);
    /* "HH:MM:SS.mmm width 55.00 mm" */
    for (const char *p = v->out; *p; p = strchr(p, '\n') + 1) {
        unsigned h, m, s, ms;
        CHECK(sscanf(p, "%2u:%2u:%2u.%3u width 55.00 m%63s", &h, &m, &s, &ms,
                     line) == 5);
    }
    CHECK_EQ(TCP(v, "-q", "watch", "grasp", "--count", "2"), 0);
    CHECK_EQ(count_lines(v->out), 2);
    CHECK(has(v->out, " 0\n"));
    /* --count 010 is ten, not octal eight. */
    CHECK_EQ(TCP(v, "-q", "watch", "width", "10", "--count", "010"), 0);
    CHECK_EQ(count_lines(v->out), 10);
    /* Until interrupted: SIGINT ends it with status 0. The lines it
     * printed before (some 12 in 0.6 s, fewer while wsgctl starts on a
     * slow machine, hence the scaled wait). */
    snprintf(cmd, sizeof cmd,
             "\"$WSGCTL\" --tcp $TCP watch state 50 & p=$!; "
             "sleep %.1f; kill -INT $p; wait $p",
             emu_ms(600) / 1000.0);
    CHECK_EQ(shell(v, cmd), 0);
    CHECK(count_lines(v->out) >= 2);
    CHECK(has(v->out, "SF_REFERENCED"));
}

static void test_udp_pty(struct env *v)
{
    CHECK_EQ(ctl(v, "--udp", v->udp, "-q", "width", (char *)NULL), 0);
    CHECK(!strcmp(v->out, "55.00\n"));
    CHECK_EQ(ctl(v, "--udp", v->udp, "move", "70", "200", (char *)NULL), 0);
    CHECK_EQ(ctl(v, "--udp", v->udp, "watch", "speed", "--count", "2",
                 (char *)NULL),
             0);
    CHECK_EQ(count_lines(v->out), 2);
    /* No connection to announce the end of. */
    CHECK_EQ(ctl(v, "--udp", v->udp, "bye", (char *)NULL), 1);
    CHECK(has(v->err, "E_NOT_AVAILABLE"));
    if (!v->pty[0]) {
        printf("no pseudo-terminals here: serial part skipped\n");
        return;
    }
    CHECK_EQ(ctl(v, "--serial", v->pty, "-q", "width", (char *)NULL), 0);
    CHECK(!strcmp(v->out, "70.00\n"));
    CHECK_EQ(ctl(v, "--serial", v->pty, "move", "30", "200", (char *)NULL), 0);
    CHECK_EQ(ctl(v, "--serial", v->pty, "info", (char *)NULL), 0);
    CHECK(has(v->out, "swrev 2.2.0"));
    CHECK_EQ(TCP(v, "-q", "width"), 0);
    CHECK(!strcmp(v->out, "30.00\n"));
}

/* Every wsgctl close over TCP was announced: no FAST STOP. */
/* A slow motion by another client: wsgctl's 07h at its close aborts it
 * (3.1.2: any movement running when the announcement arrives), --control
 * reads beside it without a trace. */
static void test_control_read(struct env *v, struct emu *e)
{
    struct emu_client c;
    struct wsg_client_frame f;
    uint8_t p[16];
    size_t n = emu_move_payload(p, 0, 5.0f, 5.0f);
    char addr[64];
    struct ctl k;

    REQUIRE(emu_field(e, "control", addr, sizeof addr) != NULL);
    /* Time paused: the motion runs until something ends it, however slow
     * this machine (or valgrind) makes the wsgctl runs between. */
    REQUIRE(ctl_open(&k, e) == 0);
    REQUIRE(ctl_is_ok(ctl_cmd(&k, "time pause")));
    REQUIRE(emu_open(&c, e, &emu_tcp) == 0);
    REQUIRE(emu_request(&c, WSG_CMD_PREPOSITION, p, n, NULL, EMU_REPLY_MS) ==
            WSG_E_CMD_PENDING);
    CHECK_EQ(ctl(v, "--control", addr, "state", (char *)NULL), 0);
    CHECK(has(v->out, "SF_MOVING") &&
          has(v->out, "grasp-state 6 (POSITIONING)"));
    CHECK_EQ(ctl(v, "--control", addr, "-q", "width", (char *)NULL), 0);
    CHECK(atof(v->out) > 5.0 && atof(v->out) <= 60.0);
    CHECK_EQ(ctl(v, "--control", addr, "-q", "stats", (char *)NULL), 0);
    CHECK(!strcmp(v->out, "1 1 0\n"));
    CHECK_EQ(ctl(v, "--control", addr, "temperature", (char *)NULL), 0);
    CHECK(!strcmp(v->out, "temperature 25.0 degC\n"));
    /* Nothing but readings: no motion, no reset of the statistics. */
    CHECK_EQ(ctl(v, "--control", addr, "home", (char *)NULL), 2);
    CHECK(has(v->err, "reads only"));
    CHECK_EQ(ctl(v, "--control", addr, "stats", "--reset", (char *)NULL), 2);
    /* Still moving: nothing was sent to the gripper. */
    CHECK_EQ(emu_recv_id(&c, WSG_CMD_PREPOSITION, &f, EMU_QUIET_MS), 0);
    /* A reading over TCP: its close's 07h ends the motion. */
    CHECK_EQ(TCP(v, "width"), 0);
    CHECK_EQ(emu_recv_id(&c, WSG_CMD_PREPOSITION, &f, EMU_REPLY_MS), 1);
    CHECK_EQ(f.status, WSG_E_CMD_ABORTED);
    CHECK_EQ(emu_request(&c, WSG_CMD_DISCONNECT, NULL, 0, NULL, EMU_REPLY_MS),
             WSG_E_SUCCESS);
    emu_close(&c);
    CHECK(ctl_is_ok(ctl_cmd(&k, "time resume")));
    ctl_close(&k);
}

/* A file with this text; 0 or -1. */
static int write_file(const char *path, const char *text)
{
    FILE *f = fopen(path, "w");
    int ok;

    if (!f)
        return -1;
    ok = fputs(text, f) >= 0;
    return fclose(f) == 0 && ok ? 0 : -1;
}

#define CONTROL(v, addr, ...)                                                 \
    ctl((v), "--control", (addr), __VA_ARGS__, (char *)NULL)

/* A script that answers B0h with what it got, through wsgctl --control;
 * the packets go over TCP. */
static void test_script(struct env *v, struct emu *e)
{
    static const char echo[] = "cmd.register(0xB0)\n"
                               "print(\"echo\\tready\")\n"
                               "while true do\n"
                               "  local id, payload = cmd.read()\n"
                               "  printf(\"got %d bytes\\n\", #payload)\n"
                               "  cmd.send(id, etob(E_SUCCESS), payload)\n"
                               "end\n";
    char dir[64] = "/tmp/wsgctl-script-XXXXXX", addr[64], path[128], bad[128],
         missing[128], want[160], cmd[512];

    REQUIRE(emu_field(e, "control", addr, sizeof addr) != NULL);
    REQUIRE(mkdtemp(dir) != NULL);
    snprintf(path, sizeof path, "%s/echo.lua", dir);
    snprintf(bad, sizeof bad, "%s/bad.lua", dir);
    snprintf(missing, sizeof missing, "%s/missing.lua", dir);
    REQUIRE(write_file(path, echo) == 0);
    REQUIRE(write_file(bad, "x = = 1\n") == 0);

    /* Only the control channel runs scripts. */
    CHECK_EQ(TCP(v, "script", "status"), 2);
    CHECK(has(v->err, "script needs --control"));
    CHECK_EQ(CONTROL(v, addr, "script", "start"), 2);
    CHECK_EQ(CONTROL(v, addr, "script", "run"), 2);

    CHECK_EQ(CONTROL(v, addr, "script", "status"), 0);
    CHECK(has(v->out, "script not running\n") &&
          has(v->out, "registered none\n"));
    CHECK_EQ(CONTROL(v, addr, "script", "run", missing), 1);
    CHECK(has(v->err, "missing.lua: No such file or directory"));
    CHECK_EQ(CONTROL(v, addr, "script", "run", path), 0);
    CHECK(!strcmp(v->out, ""));
    CHECK_EQ(CONTROL(v, addr, "script", "run", path), 1);
    CHECK(has(v->err, "stop it first"));
    CHECK_EQ(CONTROL(v, addr, "script", "status"), 0);
    snprintf(want, sizeof want, "file %s\n", path);
    CHECK(!strncmp(v->out, "script running (reading)\n", 25) &&
          has(v->out, want) && has(v->out, "registered B0h\n"));
    CHECK_EQ(CONTROL(v, addr, "-q", "script", "status"), 0);
    CHECK(!strncmp(v->out, "{\"running\":true,", 16) &&
          has(v->out, "\"registered\":[176]") && count_lines(v->out) == 1);
    /* The gripper answers B0h through the script. */
    CHECK_EQ(TCP(v, "raw", "0xB0", "7", "8"), 0);
    CHECK(has(v->out, "E_SUCCESS") && has(v->out, "07 08"));
    CHECK_EQ(CONTROL(v, addr, "script", "output"), 0);
    CHECK(!strcmp(v->out, "echo\tready\ngot 2 bytes\n"));
    CHECK_EQ(CONTROL(v, addr, "script", "stop"), 0);
    CHECK_EQ(CONTROL(v, addr, "script", "stop"), 0); /* none: no error */
    CHECK_EQ(CONTROL(v, addr, "script", "status"), 0);
    CHECK(has(v->out, "script not running\n"));

    /* A relative path is wsgctl's, not the daemon's. */
    snprintf(cmd, sizeof cmd,
             "cd %s && \"$WSGCTL\" --control %s script run echo.lua && "
             "\"$WSGCTL\" --control %s script status",
             dir, addr, addr);
    CHECK_EQ(shell(v, cmd), 0);
    CHECK(has(v->out, want));
    CHECK_EQ(CONTROL(v, addr, "script", "stop"), 0);

    /* A script that fails as it starts: its error, and the state says
     * so. Outside a script directory, the error names the line and Lua's
     * words, not the file's text. */
    CHECK_EQ(CONTROL(v, addr, "script", "run", bad), 1);
    CHECK(has(v->err, "bad.lua:1: unexpected symbol ("));
    CHECK(!has(v->err, "near"));
    CHECK_EQ(CONTROL(v, addr, "script", "status"), 0);
    CHECK(!strncmp(v->out, "script failed\n", 14) && has(v->out, "error ") &&
          has(v->out, "unexpected symbol"));

    unlink(path);
    unlink(bad);
    rmdir(dir);
}

/* The control channel's scenario commands through wsgctl --control: each
 * changes the world as the channel's own "state" shows; the channel's
 * refusals are exit 1 with its reason, its usage errors and a missing
 * --control exit 2. */
static void test_channel(struct env *v, struct emu *e)
{
    struct emu_client c;
    char addr[64];
    struct ctl k;
    const char *st;

    REQUIRE(emu_field(e, "control", addr, sizeof addr) != NULL);
    REQUIRE(ctl_open(&k, e) == 0);

    CHECK_EQ(CONTROL(v, addr, "part", "40"), 0);
    CHECK(!strncmp(v->out, "part 40 ", 8) && count_lines(v->out) == 1);
    CHECK(has(ctl_cmd(&k, "state"), "\"part\":{\"width\":40.000,"));
    CHECK_EQ(CONTROL(v, addr, "part", "30", "80"), 0);
    CHECK(!strcmp(v->out, "part 30 80\n"));
    CHECK(has(ctl_cmd(&k, "state"),
              "\"part\":{\"width\":30.000,\"stiffness\":80}"));
    CHECK_EQ(CONTROL(v, addr, "part", "none"), 0);
    CHECK(has(ctl_cmd(&k, "state"), "\"part\":null"));
    CHECK_EQ(CONTROL(v, addr, "obstacle", "25"), 0);
    CHECK(!strcmp(v->out, "obstacle 25\n"));
    CHECK(has(ctl_cmd(&k, "state"), "\"obstacle\":25.000}"));
    CHECK_EQ(CONTROL(v, addr, "obstacle", "none"), 0);
    CHECK(has(ctl_cmd(&k, "state"), "\"obstacle\":null}"));
    CHECK_EQ(CONTROL(v, addr, "fault", "temp-warning", "on"), 0);
    CHECK(!strcmp(v->out, "fault temp-warning on\n"));
    CHECK(has(ctl_cmd(&k, "state"), "\"temp_warning\""));
    CHECK_EQ(CONTROL(v, addr, "fault", "temp-warning", "off"), 0);
    CHECK(!has(ctl_cmd(&k, "state"), "\"temp_warning\""));

    /* Time: paused, stepped exactly, resumed. */
    CHECK_EQ(CONTROL(v, addr, "time", "pause"), 0);
    CHECK(!strcmp(v->out, "paused\n"));
    CHECK(has(ctl_cmd(&k, "state"), "\"paused\":true"));
    st = ctl_cmd(&k, "time");
    {
        long long before = ctl_time_us(st), after;

        CHECK_EQ(CONTROL(v, addr, "time", "step", "10"), 0);
        after = ctl_time_us(ctl_cmd(&k, "time"));
        CHECK(before >= 0 && after == before + 10000);
    }
    CHECK_EQ(CONTROL(v, addr, "time"), 0);
    CHECK(atof(v->out) > 0.0 && count_lines(v->out) == 1);
    CHECK_EQ(CONTROL(v, addr, "time", "resume"), 0);
    CHECK(!strncmp(v->out, "running at scale ", 17));
    CHECK(has(ctl_cmd(&k, "state"), "\"paused\":false"));

    /* The channel refuses: its reason, exit 1. */
    CHECK_EQ(CONTROL(v, addr, "part", "500"), 1);
    CHECK(has(v->err, "part: WIDTH must be a number of mm"));
    CHECK_EQ(CONTROL(v, addr, "fault", "bogus", "on"), 1);
    CHECK(has(v->err, "unknown fault 'bogus'"));
    CHECK_EQ(CONTROL(v, addr, "time", "step", "10"), 1);
    CHECK(has(v->err, "not paused"));
    /* Malformed: exit 2, by wsgctl's count or the channel's "usage". */
    CHECK_EQ(CONTROL(v, addr, "part"), 2);
    CHECK_EQ(CONTROL(v, addr, "fault", "power"), 2);
    CHECK_EQ(CONTROL(v, addr, "time", "step"), 2);
    CHECK(has(v->err, "usage: time"));
    CHECK_EQ(CONTROL(v, addr, "part", "4 0"), 2);
    CHECK(has(v->err, "blank"));
    CHECK_EQ(TCP(v, "part", "40"), 2);
    CHECK(has(v->err, "part needs --control"));
    CHECK_EQ(ctl(v, NULL, NULL, "drop", (char *)NULL), 2);
    CHECK(has(v->err, "WSG_CONTROL"));
    CHECK(has(ctl_cmd(&k, "state"), "\"part\":null"));

    /* drop: a connection closed without 07h, so FAST STOP, as a real
     * link loss; acknowledged again afterwards. */
    REQUIRE(emu_open(&c, e, &emu_tcp) == 0);
    CHECK_EQ(CONTROL(v, addr, "drop"), 0);
    CHECK(has(v->out, "dropped ") && atoi(v->out + 8) >= 1);
    emu_close(&c);
    CHECK(has(ctl_cmd(&k, "state"), "\"fast_stop\""));
    CHECK_EQ(TCP(v, "ack"), 0);
    CHECK(!has(ctl_cmd(&k, "state"), "\"fast_stop\""));

    /* capture: started with a path relative to wsgctl's directory (made
     * absolute, so the file lands there, not in the daemon's), a request
     * captured, its state, stopped; the file is pcapng. */
    {
        char dir[64] = "/tmp/wsgctl-capture-XXXXXX", here[4096];
        char file[128], magic[4] = {0};
        FILE *f;

        REQUIRE(mkdtemp(dir) != NULL);
        REQUIRE(getcwd(here, sizeof here) != NULL);
        REQUIRE(chdir(dir) == 0);
        CHECK_EQ(CONTROL(v, addr, "capture", "start", "run.pcapng"), 0);
        REQUIRE(chdir(here) == 0);
        snprintf(file, sizeof file, "%s/run.pcapng", dir);
        CHECK(has(v->out, file));
        CHECK_EQ(TCP(v, "width"), 0);
        CHECK_EQ(CONTROL(v, addr, "capture"), 0);
        CHECK(has(v->out, file) && has(v->out, " records "));
        CHECK_EQ(CONTROL(v, addr, "capture", "stop"), 0);
        CHECK(has(v->out, "capture stopped ") && atoi(v->out + 16) >= 2);
        CHECK_EQ(CONTROL(v, addr, "capture"), 0);
        CHECK(!strcmp(v->out, "capture off\n"));
        f = fopen(file, "rb");
        CHECK(f != NULL);
        if (f) {
            CHECK_EQ(fread(magic, 1, 4, f), 4);
            CHECK(!memcmp(magic, "\x0a\x0d\x0d\x0a", 4));
            fclose(f);
        }
        unlink(file);
        rmdir(dir);
        CHECK_EQ(CONTROL(v, addr, "capture", "start"), 2);
        CHECK_EQ(CONTROL(v, addr, "capture", "begin", "x"), 2);
        CHECK_EQ(CONTROL(v, addr, "capture", "start", "a b"), 2);
        CHECK(has(v->err, "blank"));
    }

    /* reset: a power cycle, not referenced afterwards. */
    CHECK(has(ctl_cmd(&k, "state"), "\"referenced\""));
    CHECK_EQ(CONTROL(v, addr, "reset"), 0);
    CHECK(!strcmp(v->out, "reset\n"));
    CHECK(!has(ctl_cmd(&k, "state"), "\"referenced\""));
    CHECK_EQ(TCP(v, "home"), 0);
    ctl_close(&k);
}

/* --step: a motion in lockstep, time advanced by exactly what was asked
 * from the moment the gripper accepted it, whatever wsgctl's own speed. */
static void test_step(struct env *v, struct emu *e)
{
    char addr[64];
    struct ctl k;
    long long t0;

    REQUIRE(emu_field(e, "control", addr, sizeof addr) != NULL);
    REQUIRE(ctl_open(&k, e) == 0);
    CMD_OK(&k, "time pause");
    t0 = ctl_time_us(ctl_cmd(&k, "time"));
    REQUIRE(t0 >= 0);

    /* No control channel to step with: a usage error, nothing sent. */
    unsetenv("WSG_CONTROL");
    CHECK_EQ(TCP(v, "--step", "2000", "move", "70", "100"), 2);
    CHECK(has(v->err, "--step needs") && has(v->err, "WSG_CONTROL"));
    setenv("WSG_CONTROL", addr, 1);
    CHECK_EQ(TCP(v, "--step", "0", "move", "70", "100"), 2);
    CHECK(has(v->err, "--step: milliseconds"));
    CHECK_EQ(ctl(v, "--control", addr, "--step", "10", "time", (char *)NULL),
             2);
    CHECK_EQ(ctl_time_us(ctl_cmd(&k, "time")), t0);

    /* 110 to 70 mm at 100 mm/s ends well within 2 s: its result, 2 s of
     * simulated time later, to the microsecond. */
    CHECK_EQ(TCP(v, "--step", "2000", "move", "70", "100"), 0);
    CHECK_EQ(ctl_time_us(ctl_cmd(&k, "time")), t0 + 2000000LL);
    CHECK_EQ(TCP(v, "-q", "width"), 0);
    CHECK(!strcmp(v->out, "70.00\n"));
    /* A grasp with no part: its failure, after the same exact step. */
    CHECK_EQ(TCP(v, "--step", "3000", "grasp", "20", "50"), 1);
    CHECK(has(v->err, "E_CMD_FAILED"));
    CHECK_EQ(ctl_time_us(ctl_cmd(&k, "time")), t0 + 5000000LL);
    /* Refused at once (FAST STOP): no step at all. */
    CHECK_EQ(TCP(v, "fast-stop"), 0);
    CHECK_EQ(TCP(v, "--step", "2000", "move", "60", "100"), 1);
    CHECK(has(v->err, "E_ACCESS_DENIED"));
    CHECK_EQ(ctl_time_us(ctl_cmd(&k, "time")), t0 + 5000000LL);
    CHECK_EQ(TCP(v, "ack"), 0);
    unsetenv("WSG_CONTROL");

    /* Without --step, a paused motion is accepted and its result never
     * comes: said as such, not as a gripper that did not answer. */
    CHECK_EQ(TCP(v, "--timeout", "0.5", "move", "60", "100"), 3);
    CHECK(has(v->err, "accepted (E_CMD_PENDING), but no final result"));
    CHECK(has(v->err, "--step"));
    CHECK_EQ(ctl_time_us(ctl_cmd(&k, "time")), t0 + 5000000LL);
    CMD_OK(&k, "time resume");
    CHECK_EQ(TCP(v, "home"), 0); /* back at 110 mm for what follows */
    ctl_close(&k);
}

/* --opt=value for options with a value, none for those without; the
 * gripper's address from WSG_HOST and WSG_PORT, the channel's from
 * WSG_CONTROL, each only when the line names no interface. */
static void test_options_env(struct env *v, struct emu *e)
{
    char addr[64], tcp[200], port[16], closed[64];
    const char *colon = strrchr(v->tcp, ':');

    REQUIRE(emu_field(e, "control", addr, sizeof addr) != NULL);
    REQUIRE(colon != NULL);
    snprintf(port, sizeof port, "%s", colon + 1);
    snprintf(tcp, sizeof tcp, "--tcp=%s", v->tcp);
    snprintf(closed, sizeof closed, "127.0.0.1:%u", free_port(SOCK_STREAM));

    CHECK_EQ(
        ctl(v, NULL, NULL, tcp, "--timeout=5", "-q", "width", (char *)NULL),
        0);
    CHECK(!strcmp(v->out, "110.00\n"));
    CHECK_EQ(ctl(v, NULL, NULL, tcp, "--timeout=soon", "width", (char *)NULL),
             2);
    CHECK(has(v->err, "--timeout: seconds"));
    CHECK_EQ(ctl(v, NULL, NULL, tcp, "--quiet=1", "width", (char *)NULL), 2);
    CHECK(has(v->err, "--quiet takes no value"));
    CHECK_EQ(
        ctl(v, NULL, NULL, tcp, "watch", "width", "--count=2", (char *)NULL),
        0);
    CHECK_EQ(count_lines(v->out), 2);
    CHECK_EQ(ctl(v, "--control", addr, "part", "none", (char *)NULL), 0);

    setenv("WSG_HOST", "127.0.0.1", 1);
    setenv("WSG_PORT", port, 1);
    CHECK_EQ(ctl(v, NULL, NULL, "-q", "width", (char *)NULL), 0);
    CHECK(!strcmp(v->out, "110.00\n"));
    /* WSG_HOST alone: the default port (1000), where nothing listens
     * here, or something else: not this gripper's answer anyway. */
    setenv("WSG_PORT", "0x10000", 1);
    CHECK_EQ(ctl(v, NULL, NULL, "width", (char *)NULL), 2);
    CHECK(has(v->err, "WSG_PORT"));
    /* The line wins: --tcp over a WSG_PORT where nothing listens. */
    setenv("WSG_PORT", strrchr(closed, ':') + 1, 1);
    CHECK_EQ(ctl(v, NULL, NULL, "--timeout", "2", "width", (char *)NULL), 3);
    CHECK_EQ(ctl(v, NULL, NULL, tcp, "-q", "width", (char *)NULL), 0);
    CHECK(!strcmp(v->out, "110.00\n"));
    unsetenv("WSG_HOST");
    unsetenv("WSG_PORT");

    setenv("WSG_CONTROL", addr, 1);
    CHECK_EQ(ctl(v, NULL, NULL, "obstacle", "70", (char *)NULL), 0);
    CHECK(!strcmp(v->out, "obstacle 70\n"));
    CHECK_EQ(ctl(v, NULL, NULL, "-q", "script", "status", (char *)NULL), 0);
    CHECK(has(v->out, "\"running\":false"));
    /* The line wins here too: a --control where nothing listens. */
    CHECK_EQ(ctl(v, "--control", closed, "obstacle", "none", (char *)NULL), 3);
    /* WSG_CONTROL is not the gripper's interface: readings go to TCP. */
    CHECK_EQ(ctl(v, NULL, NULL, "--tcp", v->tcp, "-q", "width", (char *)NULL),
             0);
    CHECK_EQ(ctl(v, NULL, NULL, "obstacle", "none", (char *)NULL), 0);
    unsetenv("WSG_CONTROL");
}

/* --json: one object per command, its fields by the control channel's
 * names, failures with "error" and "exit". */
static void test_json(struct env *v, struct emu *e)
{
    char addr[64];

    REQUIRE(emu_field(e, "control", addr, sizeof addr) != NULL);
    CHECK_EQ(TCP(v, "--json", "width"), 0);
    CHECK(!strcmp(v->out, "{\"command\":\"width\",\"status\":\"E_SUCCESS\","
                          "\"width\":110}\n"));
    CHECK_EQ(TCP(v, "--json", "move", "40.5", "100"), 0);
    CHECK(
        !strcmp(v->out, "{\"command\":\"move\",\"status\":\"E_SUCCESS\"}\n"));
    CHECK_EQ(TCP(v, "--json", "state"), 0);
    /* The flags by number and by name (the failed script of
     * test_script left SF_SCRIPT_FAILURE set). */
    CHECK(!strncmp(v->out,
                   "{\"command\":\"state\",\"status\":\"E_SUCCESS\","
                   "\"flags\":",
                   45) &&
          has(v->out, ",\"flags_names\":[\"SF_REFERENCED\","
                      "\"SF_TARGET_POS_REACHED\"") &&
          has(v->out, "],\"grasp_state\":0,\"grasp_state_name\":\"IDLE\"}"
                      "\n"));
    CHECK_EQ(TCP(v, "--json", "info"), 0);
    CHECK(has(v->out, "\"swrev\":\"2.2.0\"") && has(v->out, "\"serial\":1"));
    CHECK_EQ(TCP(v, "--json", "tag"), 0);
    CHECK(has(v->out, "\"tag\":\"bench-1\"}")); /* set in test_tcp */
    CHECK_EQ(TCP(v, "--json", "soft-limits"), 0);
    CHECK(has(v->out, "\"soft_limits\":null}"));
    CHECK_EQ(TCP(v, "--json", "loop", "say \"hi\"\\"), 0);
    CHECK(has(v->out, "\"echo\":\"say \\\"hi\\\"\\\\\""));
    CHECK_EQ(TCP(v, "--json", "grasp", "20", "50"), 1);
    CHECK(!strcmp(v->out, "{\"command\":\"grasp\",\"status\":"
                          "\"E_CMD_FAILED\",\"error\":\"25h Grasp: "
                          "E_CMD_FAILED\",\"exit\":1}\n"));
    CHECK(has(v->err, "E_CMD_FAILED")); /* said on stderr too */
    CHECK_EQ(TCP(v, "--json", "release", "60", "50"), 0);
    CHECK_EQ(TCP(v, "--json", "watch", "width", "--count", "2"), 0);
    CHECK_EQ(count_lines(v->out), 2);
    CHECK(!strncmp(v->out, "{\"command\":\"watch\",", 19) &&
          has(v->out, ",\"time\":") && has(v->out, ",\"width\":60}\n"));
    CHECK_EQ(TCP(v, "--json", "raw", "0x43"), 0);
    CHECK(has(v->out, "\"id\":67,\"params\":\"00 00 70 42\",\"width\":60}"));
    /* Usage errors too, wherever --json stands. */
    CHECK_EQ(TCP(v, "move", "ten", "20", "--json"), 2);
    CHECK(!strncmp(v->out,
                   "{\"command\":\"move\",\"error\":\"width: not a "
                   "number",
                   45) &&
          has(v->out, "\"exit\":2}\n"));
    CHECK_EQ(TCP(v, "--json", "decode"), 2);
    /* The control channel: readings, its commands' answers, refusals. */
    CHECK_EQ(CONTROL(v, addr, "--json", "width"), 0);
    CHECK(!strcmp(v->out, "{\"command\":\"width\",\"width\":60}\n"));
    CHECK_EQ(CONTROL(v, addr, "--json", "part", "40"), 0);
    CHECK(
        !strcmp(v->out, "{\"command\":\"part\",\"answer\":\"part 40 50\"}\n"));
    CHECK_EQ(CONTROL(v, addr, "--json", "part", "500"), 1);
    CHECK(has(v->out, "\"error\":\"part: WIDTH must be") &&
          has(v->out, "\"exit\":1}\n") && !has(v->out, "\"status\""));
    CHECK_EQ(CONTROL(v, addr, "--json", "script", "status"), 0);
    CHECK(!strncmp(
        v->out, "{\"command\":\"script\",\"answer\":{\"running\":false,", 46));
    CHECK_EQ(CONTROL(v, addr, "part", "none"), 0);
}

/* wait-ready: at once against a running gripper, a failure within its
 * --timeout against a closed port, and a wait through a gripper that is
 * started only after half a second. */
static void test_wait_ready(struct env *v, const char *exe, struct emu *e)
{
    char addr[64], closed[64], late[64];
    const char *args[] = {"--tcp", late, (char *)NULL};
    const char *wargs[] = {v->ctl, "--tcp",      late,        "--timeout",
                           "",     "wait-ready", (char *)NULL};
    char timeout[32];
    double t0, took;
    struct emu d;
    pid_t pid;
    int status = -1, waited = 0;

    REQUIRE(emu_field(e, "control", addr, sizeof addr) != NULL);
    CHECK_EQ(TCP(v, "wait-ready"), 0);
    CHECK(!strcmp(v->out, ""));
    CHECK_EQ(TCP(v, "--json", "wait-ready"), 0);
    CHECK(has(v->out, "{\"command\":\"wait-ready\",\"waited\":"));
    CHECK_EQ(CONTROL(v, addr, "wait-ready"), 0);

    snprintf(closed, sizeof closed, "127.0.0.1:%u", free_port(SOCK_STREAM));
    t0 = emu_now_ms();
    CHECK_EQ(
        ctl(v, "--tcp", closed, "--timeout", "1", "wait-ready", (char *)NULL),
        3);
    took = emu_now_ms() - t0;
    printf("wait-ready on a closed port: %.0f ms\n", took);
    CHECK(took >= 900.0 && took < 1000.0 + emu_ms(3000));
    CHECK(has(v->err, "not ready within 1.0 s: cannot connect"));

    /* Started late: wsgctl is already waiting when the daemon comes. */
    snprintf(late, sizeof late, "127.0.0.1:%u", free_port(SOCK_STREAM));
    snprintf(timeout, sizeof timeout, "%.1f", 10.0 * emu_time_scale());
    wargs[4] = timeout;
    pid = fork();
    REQUIRE(pid >= 0);
    if (pid == 0) {
        int null = open("/dev/null", O_WRONLY);

        if (null >= 0)
            dup2(null, STDOUT_FILENO);
        execv(v->ctl, (char *const *)wargs);
        _exit(127);
    }
    usleep(500 * 1000);
    CHECK_EQ(waitpid(pid, &status, WNOHANG), 0); /* still waiting */
    REQUIRE(emu_start(&d, exe, args) == 0);
    t0 = emu_now_ms();
    while (emu_now_ms() - t0 < emu_ms(10000)) {
        if (waitpid(pid, &status, WNOHANG) == pid) {
            waited = 1;
            break;
        }
        usleep(20 * 1000);
    }
    if (!waited) {
        kill(pid, SIGKILL);
        waitpid(pid, &status, 0);
    }
    printf("wait-ready for a late gripper: %s, status 0x%x, %.0f ms after "
           "it started\n",
           waited ? "ended" : "killed", status, emu_now_ms() - t0);
    CHECK(waited && WIFEXITED(status) && WEXITSTATUS(status) == 0);
    CHECK_EQ(emu_stop(&d), 0);
}

/* wsgctl --text: e is a daemon started with --text-interface on. */
#define TXT(v, tcp, ...)                                                      \
    ctl((v), "--tcp", (tcp), "--text", __VA_ARGS__, (char *)NULL)

static void test_text(struct env *v, const char *exe)
{
    const char *args[] = {"--tcp",     "127.0.0.1:0", "--text-interface", "on",
                          "--control", "127.0.0.1:0", (char *)NULL};
    char tcp[160], control[160];
    struct emu e;
    struct ctl k;
    size_t n;

    REQUIRE(emu_start(&e, exe, args) == 0);
    REQUIRE(emu_field(&e, "tcp", tcp, sizeof tcp) != NULL);
    REQUIRE(emu_field(&e, "control", control, sizeof control) != NULL);
    REQUIRE(ctl_open(&k, &e) == 0);

    CHECK_EQ(TXT(v, tcp, "home"), 0);
    CHECK_EQ(v->out[0], '\0'); /* acting commands print nothing */
    CHECK_EQ(TXT(v, tcp, "width"), 0);
    CHECK(!strcmp(v->out, "width 110.00 mm\n"));
    CHECK_EQ(TXT(v, tcp, "move", "40", "100"), 0);
    CHECK_EQ(TXT(v, tcp, "-q", "width"), 0);
    CHECK(!strcmp(v->out, "40.00\n"));
    CHECK_EQ(TXT(v, tcp, "state"), 0);
    CHECK(!strcmp(v->out,
                  "flags 0x00000081 (SF_REFERENCED SF_TARGET_POS_REACHED)\n"
                  "grasp-state 0 (IDLE)\n"));
    CHECK_EQ(TXT(v, tcp, "-q", "state"), 0);
    CHECK(!strcmp(v->out, "0x00000081\n0\n"));

    /* GRIP(force, width, speed) sets the force limit: not guessed. */
    CHECK_EQ(TXT(v, tcp, "grasp", "30", "50"), 2);
    CHECK(has(v->err, "--force"));
    /* No part: through the clamping travel, NO PART. */
    CHECK_EQ(TXT(v, tcp, "--force", "20", "grasp", "30", "50"), 1);
    CHECK(has(v->err, "ERR GRIP 18 (E_CMD_FAILED)"));
    CHECK_EQ(TXT(v, tcp, "-q", "state"), 0);
    n = strlen(v->out);
    CHECK(n >= 3 && !strcmp(v->out + n - 3, "\n2\n"));
    CHECK_EQ(TXT(v, tcp, "release"), 0);
    /* A part where the grip expects it: held. */
    CMD_OK(&k, "part 20");
    CHECK_EQ(TXT(v, tcp, "--force", "20", "grasp", "20", "50"), 0);
    CHECK_EQ(TXT(v, tcp, "state"), 0);
    CHECK(has(v->out, "grasp-state 4 (HOLDING)\n"));
    CHECK_EQ(TXT(v, tcp, "-q", "stats"), 0);
    CHECK(!strcmp(v->out, "2 1 0\n"));
    CHECK_EQ(TXT(v, tcp, "release", "10", "50"), 0);
    CMD_OK(&k, "part none");
    /* GRIP(): close until contact; with nothing there the fingers meet,
     * and RELEASE() opens by the default pull-back, 10 mm. */
    CHECK_EQ(TXT(v, tcp, "grasp"), 0);
    CHECK_EQ(TXT(v, tcp, "release"), 0);
    CHECK_EQ(TXT(v, tcp, "width"), 0);
    CHECK(!strcmp(v->out, "width 10.00 mm\n"));

    /* raw-text: every line of the answer, as it came. */
    CHECK_EQ(ctl(v, "--tcp", tcp, "raw-text", "POS?", (char *)NULL), 0);
    CHECK(!strcmp(v->out, "POS=10.0\n"));
    CHECK_EQ(ctl(v, "--tcp", tcp, "raw-text", "MOVE(30, 100)", (char *)NULL),
             0);
    CHECK(!strcmp(v->out, "ACK MOVE\nFIN MOVE\n"));
    CHECK_EQ(ctl(v, "--tcp", tcp, "raw-text", "FOO()", (char *)NULL), 1);
    CHECK(!strcmp(v->out, "ERR FOO 14\n"));
    CHECK(has(v->err, "E_CMD_UNKNOWN"));

    /* FAST STOP refuses a motion until acknowledged. */
    CHECK_EQ(TXT(v, tcp, "fast-stop"), 0);
    CHECK_EQ(TXT(v, tcp, "move", "40", "100"), 1);
    CHECK(has(v->err, "ERR MOVE 16 (E_ACCESS_DENIED)"));
    CHECK_EQ(TXT(v, tcp, "state"), 0);
    CHECK(has(v->out, "SF_FAST_STOP"));
    CHECK_EQ(TXT(v, tcp, "ack"), 0);
    CHECK_EQ(TXT(v, tcp, "move", "40", "100"), 0);

    CHECK_EQ(TXT(v, tcp, "temperature"), 0);
    CHECK(!strcmp(v->out, "temperature 25.0 degC\n"));
    CHECK_EQ(TXT(v, tcp, "-q", "info"), 0);
    CHECK(!strcmp(v->out, "WSG50 2.2.0 1\n"));
    CHECK_EQ(TXT(v, tcp, "tag"), 0);
    CHECK(!strcmp(v->out, "tag none\n"));
    CHECK_EQ(TXT(v, tcp, "tare"), 1); /* no force measurement fingers */
    CHECK(has(v->err, "E_NOT_AVAILABLE"));

    /* What GCL has no form for. */
    CHECK_EQ(TXT(v, tcp, "limits"), 2);
    CHECK(has(v->err, "no GCL form"));
    CHECK_EQ(TXT(v, tcp, "move", "--relative", "10", "100"), 2);
    CHECK_EQ(ctl(v, "--udp", v->udp, "raw-text", "POS?", (char *)NULL), 2);
    CHECK_EQ(ctl(v, "--tcp", tcp, "raw-text", "", (char *)NULL), 2);
    CHECK_EQ(ctl(v, "--tcp", tcp, "--force", "20", "width", (char *)NULL), 2);

    /* The wrong language gets no answer either way; the close is then
     * announced both ways, so neither gripper is left in FAST STOP (the
     * binary one is checked at the end of the test). */
    CHECK_EQ(TXT(v, v->tcp, "--timeout", "0.5", "width"), 3);
    CHECK(has(v->err, "no answer"));
    CHECK_EQ(ctl(v, "--tcp", tcp, "--timeout", "0.5", "width", (char *)NULL),
             3);

    CHECK_EQ(ctl(v, "--control", control, "state", (char *)NULL), 0);
    CHECK(!has(v->out, "SF_FAST_STOP"));
    ctl_close(&k);
    CHECK_EQ(emu_stop(&e), 0);
}

static void check_no_fast_stop(struct emu *e)
{
    struct emu_client c;
    uint32_t flags = 0;

    REQUIRE(emu_open(&c, e, &emu_tcp) == 0);
    CHECK(emu_get_flags(&c, &flags) == 0);
    printf("final flags 0x%08lX\n", (unsigned long)flags);
    CHECK(!(flags & WSG_SF_FAST_STOP));
    CHECK_EQ(emu_request(&c, WSG_CMD_DISCONNECT, NULL, 0, NULL, EMU_REPLY_MS),
             WSG_E_SUCCESS);
    emu_close(&c);
}

int main(int argc, char **argv)
{
    const char *exe = emu_exe(argc, argv);
    static struct env v; /* big buffers: not on the stack */
    struct emu e;
    char udp_daemon[64], dir[64] = "/tmp/wsgctl-pty-XXXXXX", field[128];
    const char *args[10];
    unsigned rport = free_port(SOCK_DGRAM);
    int n = 0, m;

    v.ctl = getenv("WSGCTL");
    if (!v.ctl || !v.ctl[0])
        v.ctl = argc > 2 ? argv[2] : NULL;
    if (!v.ctl || access(v.ctl, X_OK) != 0) {
        printf("SKIP: no wsgctl ($WSGCTL or argv[2])\n");
        return 77;
    }
    snprintf(udp_daemon, sizeof udp_daemon, "127.0.0.1:0:%u", rport);
    args[n++] = "--tcp";
    args[n++] = "127.0.0.1:0";
    args[n++] = "--udp";
    args[n++] = udp_daemon;
    args[n++] = "--control";
    args[n++] = "127.0.0.1:0";
    m = posix_openpt(O_RDWR | O_NOCTTY);
    if (m >= 0 && mkdtemp(dir)) {
        close(m);
        snprintf(v.pty, sizeof v.pty, "%s/ttyWSG0", dir);
        args[n++] = "--pty";
        args[n++] = v.pty;
    }
    args[n] = NULL;
    REQUIRE(emu_start(&e, exe, args) == 0);
    REQUIRE(emu_field(&e, "tcp", field, sizeof field) != NULL);
    snprintf(v.tcp, sizeof v.tcp, "%s", field);
    setenv("TCP", v.tcp, 1);
    REQUIRE(emu_field(&e, "udp", field, sizeof field) != NULL);
    /* "127.0.0.1:PORT>REMOTE" -> "127.0.0.1:PORT:REMOTE" */
    REQUIRE(strchr(field, '>') != NULL);
    *strchr(field, '>') = ':';
    snprintf(v.udp, sizeof v.udp, "%s", field);

    test_usage(&v);
    test_no_emulator(&v);
    test_tcp(&v);
    test_raw(&v);
    test_decode(&v);
    /* raw moved to 55 mm */
    test_watch(&v);
    test_udp_pty(&v);
    test_control_read(&v, &e);
    test_script(&v, &e);
    test_channel(&v, &e);
    test_step(&v, &e);
    test_options_env(&v, &e);
    test_json(&v, &e);
    test_wait_ready(&v, exe, &e);
    test_text(&v, exe);
    check_no_fast_stop(&e);

    CHECK_EQ(emu_stop(&e), 0);
    if (v.pty[0])
        rmdir(dir);
    TEST_EXIT();
}
