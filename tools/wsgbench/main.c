/*
 * wsgbench: measures wsgemu against wsgref, the minimal reference server (a
 * frame parser and fixed replies), in one run on one machine, and prints
 * one table with both figures and their ratio, so the table says what the
 * emulator costs beyond the physical limit of the machine rather than what
 * the machine happens to do today.
 *
 * It starts both servers itself (pinned to one CPU, itself to another when
 * there are two), reads their ready lines, and measures: request latency
 * over TCP, UDP and the pty in alternating rounds (machine noise hits both
 * alike); pipelined TCP throughput; the jitter of a 10 ms auto-update
 * stream (both streams at once); idle wakes and CPU; the model's step rate
 * while moving (control channel "stats"); a time-scaled grasp cycle;
 * memory; scripts on the gripper (a registered ID's round trip beside
 * 43h's, the daemon's wakes while its script waits, a PD script driven at
 * rising rates); POS? over GCL, the text interface, beside 43h; and a
 * fleet of grippers in one process (--grippers).
 * Figures with a target get "ok" or "MISSED"; a missed target is not an
 * error: this is a measuring tool. It fails (status 1) only when something
 * could not be measured: a server that does not start, a reply that is
 * missing or malformed. Every wait has a timeout. See usage() for the
 * options.
 *
 * With --attach READY it measures a wsgemu that is already running instead
 * of starting one: READY is the ready line that emulator printed, and the
 * emulator rows use its addresses (tcp=, udp=, pty=, control=); the
 * reference is still started here, and nothing is pinned (the emulator
 * cannot be, and both servers must be scheduled alike).
 * The /proc rows (idle, CPU, RSS) need its process (--pid); the moving and
 * x100 rows need control= (x100 sets "time scale 100" there and puts the
 * old scale back after). A row whose interface or process was not given
 * is n/a with a note on stderr, and that is no failure. The motion rows
 * home and move the attached gripper. The fleet rows always start their
 * own wsgemu --grippers N, the script rows their own wsgemu --script, and
 * the GCL rows their own two wsgemu, one with --text-interface on.
 *
 * This file: the options, finding the programs, choosing the CPUs, --attach,
 * starting the servers, the order of the measurements, and the messages
 * and clock every file uses. The others: servers.c, links.c, table.c, and
 * one file per group of figures (traffic.c, idle.c, motion.c, fleet.c,
 * script.c, gcl.c); wsgbench.h, what they share.
 */
#define _GNU_SOURCE /* sched_setaffinity, pipe2, prctl, strndup */

#include "wsgbench.h"

#include <arpa/inet.h>
#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <getopt.h>
#include <math.h>
#include <netinet/in.h>
#include <poll.h>
#include <sched.h>
#include <signal.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/epoll.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

/* The bench's scripts: the source tree's, as CMake says where it is. */
#ifndef WSG_BENCH_SCRIPTS
#define WSG_BENCH_SCRIPTS "tests/scripts"
#endif

void msg(const char *fmt, ...)
{
    va_list ap;

    fputs("wsgbench: ", stderr);
    va_start(ap, fmt);
    vfprintf(stderr, fmt, ap);
    va_end(ap);
    fputc('\n', stderr);
}

uint64_t now_ns(void)
{
    struct timespec ts;

    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (uint64_t)ts.tv_sec * NS_PER_S + (uint64_t)ts.tv_nsec;
}

void sleep_s(double s)
{
    struct timespec ts;

    ts.tv_sec = (time_t)s;
    ts.tv_nsec = (long)((s - (double)ts.tv_sec) * 1e9);
    while (nanosleep(&ts, &ts) < 0 && errno == EINTR)
        ;
}

static void usage(FILE *out)
{
    fputs(
        "Usage: wsgbench [OPTION]...\n"
        "Measure wsgemu against wsgref (a parser with fixed replies: the\n"
        "machine's limit) in one run and print one table: each figure for\n"
        "both, their ratio emulator/reference, and the target, marked ok or\n"
        "MISSED (a missed target is not an error).\n"
        "\n"
        "  --emu PATH             wsgemu to measure (default: ../wsgemu\n"
        "                         beside this program's directory)\n"
        "  --attach READY         measure a running wsgemu instead of\n"
        "                         starting one: READY is the ready line it\n"
        "                         printed (\"ready tcp=A:P udp=A:P>R "
        "pty=PATH\n"
        "                         control=A:P\", \"ready\" optional)\n"
        "  --pid PID              with --attach: its process, for the\n"
        "                         /proc rows (idle, CPU, RSS)\n"
        "  --ref PATH             wsgref (default: wsgref beside this "
        "program)\n"
        "  --samples N            latency samples per transport and server\n"
        "                         (default 20000), in 10 alternating rounds\n"
        "  --inflight K           pipelined requests in flight (default 32)\n"
        "  --throughput-seconds S pipelined run per server (default 3)\n"
        "  --jitter-seconds S     length of the 10 ms streams, both at once\n"
        "                         (default 60)\n"
        "  --idle-seconds S       idle window (default 10)\n"
        "  --move-seconds S       window while the fingers move (default 4)\n"
        "  --fleet N              grippers in the fleet rows (default 1000)\n"
        "  --no-fleet             skip the fleet rows\n"
        "  --scripts DIR          where bench_echo.lua and bench_pd.lua are\n"
        "                         (default: the source tree's tests/scripts)\n"
        "  --script-seconds S     each rate of the PD script (default 3)\n"
        "  --no-script            skip the script rows\n"
        "  --no-gcl               skip the GCL rows\n"
        "  --no-web               skip the web page rows\n"
        "  --quick                1000 samples, 0.5 s throughput, 2 s "
        "jitter,\n"
        "                         1 s idle, 1 s moving, 0.5 s per PD rate,\n"
        "                         fleet of 20 (explicit options still win)\n"
        "  -h, --help             this text\n"
        "\n"
        "Rows: 43h latency (median, p99, max) over TCP, UDP and the pty;\n"
        "pipelined TCP answers per second; jitter of a 43h stream with a\n"
        "10 ms period, |interval - 10 ms|; idle wakes/s (context switches)\n"
        "and CPU % (utime+stime) from /proc; while a Preposition moves the\n"
        "fingers, the model's steps/s and overruns (control \"stats\") and\n"
        "CPU %; Homing, Grasp and Release at --time-scale 100 (control\n"
        "\"part 40\" and \"time\"): simulated/wall time; VmRSS and VmHWM;\n"
        "with --grippers N: idle wakes and CPU, RSS, homing all, then a\n"
        "tenth and then all of them moving (CPU %, steps/s, overruns).\n"
        "Scripts, each on a wsgemu --script of its own: B0h answered by\n"
        "bench_echo.lua against 43h on the same connection (the reference\n"
        "column of these rows is the 43h), median and p99; the timer\n"
        "wakes (control \"stats\") while the script waits in cmd.read;\n"
        "bench_pd.lua, a PD step on mc.speed per B1h as UMI's script,\n"
        "driven at 250, 500, 1000 and 2000 Hz: answers/s, % answered,\n"
        "overruns, and the highest rate with 99% answered at 99% of the\n"
        "rate and no overrun. GCL: POS? on a wsgemu --text-interface on\n"
        "against 43h on another wsgemu, both started here, in alternating\n"
        "rounds (the reference column of these rows is the 43h), median\n"
        "and p99. Web: 43h on a wsgemu --web with a process reading the\n"
        "page's event stream against the same without it, in alternating\n"
        "rounds, median and p99.\n"
        "\n",
        out);
    /* Two pieces: C99 promises string literals of 4095 bytes only. */
    fputs("Both servers run on one CPU and the bench on another when there\n"
          "are two. Exit status: 0 when every figure was measured; 1 when a\n"
          "server did not start or an answer was missing or malformed (the\n"
          "table shows n/a there, stderr says why); 2 on a usage error.\n"
          "\n"
          "With --attach the reference is still started here and nothing is\n"
          "pinned, so both servers are scheduled alike. Its rows use the\n"
          "addresses of READY: udp= says where its answers go (port R on the\n"
          "bench's address), so the bench binds R, which must be free. Rows\n"
          "whose interface is not in READY (tcp=, udp=, pty=; control= for\n"
          "the moving and x100 rows) and, without --pid, its /proc figures\n"
          "are n/a with a note on stderr, and that is no failure. For the\n"
          "x100 rows its time scale is set to 100 (control \"time scale\")\n"
          "and put back after. The moving and x100 rows home, move and grasp\n"
          "the attached gripper and leave a 40 mm part in it (control \"part\n"
          "40\"): attach only to a test gripper. The fleet rows still start\n"
          "their own wsgemu --grippers N (--emu), the script rows their\n"
          "own wsgemu --script and the GCL rows two wsgemu, skipped when\n"
          "there is none.\n",
          out);
}

static int parse_num(const char *s, double min, double max, double *v)
{
    char *end;

    errno = 0;
    *v = strtod(s, &end);
    return end != s && *end == '\0' && errno == 0 && *v >= min && *v <= max
               ? 0
               : -1;
}

static int parse_opts(struct opts *o, int argc, char **argv)
{
    static const struct option lo[] = {
        {"emu", required_argument, NULL, 'e'},
        {"attach", required_argument, NULL, 'a'},
        {"pid", required_argument, NULL, 'p'},
        {"ref", required_argument, NULL, 'r'},
        {"samples", required_argument, NULL, 'n'},
        {"inflight", required_argument, NULL, 'k'},
        {"throughput-seconds", required_argument, NULL, 't'},
        {"jitter-seconds", required_argument, NULL, 'j'},
        {"idle-seconds", required_argument, NULL, 'i'},
        {"move-seconds", required_argument, NULL, 'm'},
        {"fleet", required_argument, NULL, 'f'},
        {"no-fleet", no_argument, NULL, 'F'},
        {"scripts", required_argument, NULL, 'S'},
        {"script-seconds", required_argument, NULL, 's'},
        {"no-script", no_argument, NULL, 'N'},
        {"no-gcl", no_argument, NULL, 'G'},
        {"no-web", no_argument, NULL, 'W'},
        {"quick", no_argument, NULL, 'q'},
        {"help", no_argument, NULL, 'h'},
        {NULL, 0, NULL, 0}};
    double v;
    int c;

    /* -1: not given; the defaults depend on --quick. */
    o->samples = o->inflight = o->fleet = o->pid = -1;
    o->tput_s = o->jitter_s = o->idle_s = o->move_s = o->script_s = -1;
    o->scripts = WSG_BENCH_SCRIPTS;
    while ((c = getopt_long(argc, argv, "h", lo, NULL)) != -1) {
        switch (c) {
        case 'e':
            o->emu = optarg;
            break;
        case 'r':
            o->ref = optarg;
            break;
        case 'a':
            o->attach = optarg;
            break;
        case 'p':
            if (parse_num(optarg, 1, INT_MAX, &v) < 0 || v != floor(v)) {
                msg("--pid: not a process ID: \"%s\"", optarg);
                return -1;
            }
            o->pid = (long)v;
            break;
        case 'n':
        case 'k':
        case 'f':
            if (parse_num(optarg, c == 'f' ? 0 : 1, c == 'k' ? 1024 : 1e7,
                          &v) < 0 ||
                v != floor(v)) {
                msg("--%s: not a whole number in range: \"%s\"",
                    c == 'n'   ? "samples"
                    : c == 'k' ? "inflight"
                               : "fleet",
                    optarg);
                return -1;
            }
            *(c == 'n'   ? &o->samples
              : c == 'k' ? &o->inflight
                         : &o->fleet) = (long)v;
            break;
        case 't':
        case 'j':
        case 'i':
        case 'm':
        case 's':
            if (parse_num(optarg, c == 'm' ? 0.2 : 0.1, 3600, &v) < 0) {
                msg("not a number of seconds in range: \"%s\"", optarg);
                return -1;
            }
            *(c == 't'   ? &o->tput_s
              : c == 'j' ? &o->jitter_s
              : c == 'i' ? &o->idle_s
              : c == 's' ? &o->script_s
                         : &o->move_s) = v;
            break;
        case 'S':
            o->scripts = optarg;
            break;
        case 'N':
            o->no_script = 1;
            break;
        case 'G':
            o->no_gcl = 1;
            break;
        case 'W':
            o->no_web = 1;
            break;
        case 'F':
            o->fleet = 0;
            break;
        case 'q':
            o->quick = 1;
            break;
        case 'h':
            usage(stdout);
            exit(0);
        default:
            usage(stderr);
            return -1;
        }
    }
    if (optind < argc) {
        msg("unexpected argument \"%s\"", argv[optind]);
        return -1;
    }
    if (o->pid > 0 && !o->attach) {
        msg("--pid goes with --attach");
        return -1;
    }
#define DEF(field, normal, fast)                                              \
    if (o->field < 0)                                                         \
    o->field = o->quick ? (fast) : (normal)
    DEF(samples, 20000, 1000);
    DEF(inflight, 32, 32);
    DEF(tput_s, 3.0, 0.5);
    DEF(jitter_s, 60.0, 2.0);
    DEF(idle_s, 10.0, 1.0);
    DEF(move_s, 4.0, 1.0);
    DEF(fleet, 1000, 20);
    DEF(script_s, 3.0, 0.5);
#undef DEF
    return 0;
}

/* wsgemu and wsgref relative to this program (build/tools/wsgbench). */
static int find_exes(struct bench *b)
{
    char self[PATH_MAX], *slash;
    ssize_t n = readlink("/proc/self/exe", self, sizeof self - 1);

    if (n < 0) {
        msg("/proc/self/exe: %s", strerror(errno));
        return -1;
    }
    self[n] = '\0';
    slash = strrchr(self, '/');
    if (slash)
        *slash = '\0';
    snprintf(b->emu_exe, sizeof b->emu_exe, "%s", b->o.emu ? b->o.emu : "");
    if (!b->o.emu && snprintf(b->emu_exe, sizeof b->emu_exe, "%s/../wsgemu",
                              self) >= (int)sizeof b->emu_exe)
        return -1;
    snprintf(b->ref_exe, sizeof b->ref_exe, "%s", b->o.ref ? b->o.ref : "");
    if (!b->o.ref && snprintf(b->ref_exe, sizeof b->ref_exe, "%s/wsgref",
                              self) >= (int)sizeof b->ref_exe)
        return -1;
    if (access(b->emu_exe, X_OK) < 0) {
        /* Attached, only the fleet, script and GCL rows start one. */
        if (b->attach && !b->o.emu) {
            if (b->o.fleet > 0 || !b->o.no_script || !b->o.no_gcl ||
                !b->o.no_web)
                msg("cannot run %s: %s: fleet, script, GCL and web rows "
                    "skipped "
                    "(give --emu PATH)",
                    b->emu_exe, strerror(errno));
            b->o.fleet = 0;
            b->o.no_script = 1;
            b->o.no_gcl = 1;
            b->o.no_web = 1;
        } else {
            msg("cannot run %s: %s (give --emu PATH)", b->emu_exe,
                strerror(errno));
            return -1;
        }
    }
    if (access(b->ref_exe, X_OK) < 0) {
        msg("cannot run %s: %s (give --ref PATH)", b->ref_exe,
            strerror(errno));
        return -1;
    }
    return 0;
}

/* Servers on the second CPU the bench may use, the bench on the first. */
static void choose_cpus(struct bench *b)
{
    cpu_set_t set;
    int i, first = -1, second = -1;

    b->cpu_bench = b->cpu_server = -1;
    b->ncpu = 1;
    if (sched_getaffinity(0, sizeof set, &set) < 0)
        return;
    b->ncpu = CPU_COUNT(&set);
    for (i = 0; i < CPU_SETSIZE && second < 0; i++) {
        if (!CPU_ISSET(i, &set))
            continue;
        if (first < 0)
            first = i;
        else
            second = i;
    }
    /* An attached emulator runs where the scheduler puts it: pinning only
     * the reference would give the two different wakeup paths (one across
     * CPUs, one not), so nothing is pinned and both are scheduled alike. */
    if (second < 0 || b->attach)
        return;
    b->cpu_bench = first;
    b->cpu_server = second;
    pin(first);
}

/* A UDP socket on 127.0.0.1 where a server's answers arrive. */
static int reserve_udp(int *fd, uint16_t *port)
{
    struct sockaddr_in sa;
    socklen_t sl = sizeof sa;

    *fd = socket(AF_INET, SOCK_DGRAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
    if (*fd < 0)
        return -errno;
    memset(&sa, 0, sizeof sa);
    sa.sin_family = AF_INET;
    sa.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    if (bind(*fd, (struct sockaddr *)&sa, sizeof sa) < 0 ||
        getsockname(*fd, (struct sockaddr *)&sa, &sl) < 0)
        return -errno;
    *port = ntohs(sa.sin_port);
    return 0;
}

/* Attached: a socket where the emulator's UDP answers arrive, the remote
 * port on the address the bench's requests to it come from. 0 or -errno. */
static int reply_socket(const struct sockaddr_in *to, uint16_t remote, int *fd)
{
    struct sockaddr_in me;
    socklen_t sl = sizeof me;
    int probe = socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
    int r = 0;

    if (probe < 0 ||
        connect(probe, (const struct sockaddr *)to, sizeof *to) < 0 ||
        getsockname(probe, (struct sockaddr *)&me, &sl) < 0)
        r = -errno;
    if (probe >= 0)
        close(probe);
    if (r < 0)
        return r;
    me.sin_port = htons(remote);
    *fd = socket(AF_INET, SOCK_DGRAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
    if (*fd < 0 || bind(*fd, (struct sockaddr *)&me, sizeof me) < 0) {
        r = -errno;
        if (*fd >= 0)
            close(*fd);
        *fd = -1;
    }
    return r;
}

/* --attach READY: the emulator's ready line (with "ready" in front), its
 * pty, its process. -1 (reported) when they are not usable. */
static int attach_setup(struct bench *b)
{
    const char *r = b->o.attach + strspn(b->o.attach, " ");
    size_t n;
    char *v, *gt, *end;
    unsigned long remote;
    int have = 0;

    b->attach = 1;
    if (strncmp(r, "ready", 5) == 0 && (r[5] == ' ' || r[5] == '\0'))
        r += 5 + strspn(r + 5, " ");
    n = strcspn(r, "\r\n");
    b->srv[EMU].name = "wsgemu";
    b->srv[EMU].line = malloc(n + 7);
    if (!b->srv[EMU].line) {
        msg("out of memory");
        return -1;
    }
    snprintf(b->srv[EMU].line, n + 7, "ready %.*s", (int)n, r);
    for (int i = 0; i < 4; i++) {
        static const char *const keys[] = {"tcp", "udp", "pty", "control"};

        v = field(b->srv[EMU].line, keys[i]);
        have |= v != NULL;
        free(v);
    }
    if (!have) {
        msg("--attach: no tcp=, udp=, pty= or control= in \"%.80s\"",
            b->o.attach);
        return -1;
    }
    /* A fleet lists each gripper's: the first one's is measured. */
    v = field(b->srv[EMU].line, "pty");
    if (v) {
        v[strcspn(v, ",")] = '\0';
        snprintf(b->pty_path[EMU], sizeof b->pty_path[EMU], "%s", v);
    }
    free(v);
    v = field(b->srv[EMU].line, "udp");
    if (v) {
        struct sockaddr_in sa;

        gt = strchr(v, '>');
        remote = gt ? strtoul(gt + 1, &end, 10) : 0;
        if (parse_ipport(v, &sa) < 0 || !gt || remote == 0 || remote > 65535 ||
            (*end != '\0' && *end != ',')) {
            msg("--attach: udp=%s is not ADDR:PORT>REMOTE", v);
            free(v);
            return -1;
        }
        int e = reply_socket(&sa, (uint16_t)remote, &b->udp_rfd[EMU]);
        if (e < 0)
            msg("--attach: cannot receive the UDP answers on port %lu: %s "
                "(another client there?)",
                remote, strerror(-e));
        b->udp_remote[EMU] = (uint16_t)remote;
    }
    free(v);
    if (b->o.pid > 0 && kill((pid_t)b->o.pid, 0) < 0 && errno == ESRCH) {
        msg("--pid %ld: no such process", b->o.pid);
        return -1;
    }
    return 0;
}

static int start_servers(struct bench *b)
{
    char udp[2][32];
    char *eargv[] = {b->emu_exe,    "--tcp", "127.0.0.1:0",    "--udp",
                     udp[EMU],      "--pty", b->pty_path[EMU], "--control",
                     "127.0.0.1:0", NULL};
    char *rargv[] = {b->ref_exe, "--tcp", "127.0.0.1:0",    "--udp",
                     udp[REF],   "--pty", b->pty_path[REF], NULL};

    for (int s = b->attach ? REF : EMU; s < 2; s++) {
        if (reserve_udp(&b->udp_rfd[s], &b->udp_remote[s]) < 0) {
            msg("UDP socket: %s", strerror(errno));
            return -1;
        }
        snprintf(udp[s], sizeof udp[s], "127.0.0.1:0:%u",
                 (unsigned)b->udp_remote[s]);
    }
    if (!b->attach &&
        server_start(b, &b->srv[EMU], "wsgemu", eargv, READY_MS) < 0)
        return -1;
    return server_start(b, &b->srv[REF], "wsgref", rargv, READY_MS);
}

int main(int argc, char **argv)
{
    static struct bench b; /* the rows: a few KiB off the stack */
    int s, rc;

    b.udp_rfd[EMU] = b.udp_rfd[REF] = -1;
    b.srv[EMU].pid = b.srv[REF].pid = -1;
    b.srv[EMU].out_fd = b.srv[REF].out_fd = -1;
    b.pid[EMU] = b.pid[REF] = -1;
    if (parse_opts(&b.o, argc, argv) < 0)
        return 2;
    if (b.o.attach && attach_setup(&b) < 0)
        return 2;
    if (find_exes(&b) < 0)
        return 1;
    signal(SIGPIPE, SIG_IGN);
    wsg_frame_encode(req_width, sizeof req_width, WSG_CMD_GET_WIDTH, NULL, 0);
    choose_cpus(&b);
    snprintf(b.tmpdir, sizeof b.tmpdir, "/tmp/wsgbench-XXXXXX");
    if (!mkdtemp(b.tmpdir)) {
        msg("mkdtemp: %s", strerror(errno));
        return 1;
    }
    memcpy(live_dir, b.tmpdir, sizeof live_dir);
    signal(SIGINT, on_signal);
    signal(SIGTERM, on_signal);
    if (!b.attach)
        snprintf(b.pty_path[EMU], sizeof b.pty_path[EMU], "%s/emu", b.tmpdir);
    snprintf(b.pty_path[REF], sizeof b.pty_path[REF], "%s/ref", b.tmpdir);

    if (start_servers(&b) < 0) {
        msg("a server did not start: nothing measured");
        b.failures++;
        goto cleanup;
    }
    b.pid[EMU] = b.attach ? (pid_t)b.o.pid : b.srv[EMU].pid;
    b.pid[REF] = b.srv[REF].pid;
    for (int k = L_TCP; k <= L_PTY; k++)
        if (bench_latency(&b, (enum link_kind)k) < 0)
            b.failures++;
    if (bench_throughput(&b) < 0)
        b.failures++;
    if (bench_jitter(&b) < 0)
        b.failures++;
    if (bench_idle(&b) < 0)
        b.failures++;
    if (bench_slow_stream(&b) < 0)
        b.failures++;
    if (bench_moving(&b) < 0)
        b.failures++;
    if (bench_timescale(&b) < 0)
        b.failures++;
    if (bench_memory(&b) < 0)
        b.failures++;
    for (s = 0; s < 2; s++)
        if (server_stop(&b.srv[s]) < 0)
            b.failures++;
    if (!b.o.no_script && bench_script(&b) < 0)
        b.failures++;
    if (!b.o.no_gcl && bench_gcl(&b) < 0)
        b.failures++;
    if (!b.o.no_web && bench_web(&b) < 0)
        b.failures++;
    if (b.o.fleet > 0 && bench_fleet(&b) < 0)
        b.failures++;
    if (bench_fingers(&b) < 0)
        b.failures++;
    if (bench_physics(&b) < 0)
        b.failures++;
    print_table(&b);

cleanup:
    for (s = 0; s < 2; s++) {
        server_stop(&b.srv[s]);
        if (b.udp_rfd[s] >= 0)
            close(b.udp_rfd[s]);
        /* The servers' own, if one was killed; never an attached one's. */
        if (!(b.attach && s == EMU))
            unlink(b.pty_path[s]);
    }
    rmdir(b.tmpdir);
    rc = b.failures ? 1 : 0;
    if (rc)
        msg("%d part%s could not be measured (see above)", b.failures,
            b.failures == 1 ? "" : "s");
    return rc;
}
