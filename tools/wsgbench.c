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
 * memory; and a fleet of grippers in one process (--grippers). Figures
 * with a target get "ok" or "MISSED"; a missed target is not an error: this
 * is a measuring tool. It fails (status 1) only when something could not be
 * measured: a server that does not start, a reply that is missing or
 * malformed. Every wait has a timeout. See usage() for the options.
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
 * own wsgemu --grippers N.
 */
#define _GNU_SOURCE /* sched_setaffinity, pipe2, cfmakeraw, prctl */

#include "ctljson.h"
#include "wsg/proto.h"
#include "wsgclient.h"

#include <arpa/inet.h>
#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <getopt.h>
#include <limits.h>
#include <math.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sched.h>
#include <signal.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/epoll.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <termios.h>
#include <time.h>
#include <unistd.h>

#ifndef WSG_VERSION
#define WSG_VERSION "?"
#endif

#define REPLY_MS    2000  /* an immediate reply */
#define READY_MS    10000 /* a server's ready line */
#define FLEET_MS    60000 /* a fleet's ready line, all its homings */
#define MOTION_MS   30000 /* a motion's final result */
#define STALL_MS    1000  /* a 10 ms stream silent this long is broken */
#define STREAM_MS   10    /* the jitter stream's period */
#define ROUNDS      10    /* latency: alternating rounds */
#define STROKE_MM   110.0 /* WSG 50 */
#define NS_PER_S    1000000000ull
#define NS_PER_MS   1000000ull
#define ROWS_MAX    64
#define NOT_APPLIED (-INFINITY) /* a row's reference: not applicable */
#define EMU         0
#define REF         1

enum link_kind { L_TCP, L_UDP, L_PTY };
static const char *const kind_name[] = {"TCP", "UDP", "pty"};

struct opts {
    const char *emu, *ref;
    const char *attach; /* a running emulator's ready line, or NULL */
    long pid;           /* its process, or -1 */
    long samples;
    long inflight;
    double tput_s, jitter_s, idle_s, move_s;
    long fleet;
    int quick;
};

struct server {
    const char *name;
    pid_t pid;
    int out_fd;
    char *line; /* the ready line, without its newline */
};

/* One client connection, named for messages. */
struct link {
    struct wsg_client c;
    char who[32]; /* "wsgemu TCP" */
};

enum target { T_NONE, T_LT, T_LE, T_GE, T_EQ, T_NEAR };

struct row {
    char label[48];
    double emu, ref; /* NAN: not measured; ref NOT_APPLIED */
    int decimals;
    enum target tk;
    double tv, tol; /* T_NEAR: within tv +- tol */
    int on_ratio;   /* the target applies to emu/ref */
    char ttext[20];
};

struct proc_sample {
    uint64_t t_ns;
    unsigned long long ctxt, cpu_ns;
};

struct bench {
    struct opts o;
    int cpu_bench, cpu_server; /* -1: not pinned */
    int ncpu;
    char emu_exe[PATH_MAX], ref_exe[PATH_MAX];
    char tmpdir[64], pty_path[2][PATH_MAX];
    int udp_rfd[2];
    uint16_t udp_remote[2];
    struct server srv[2]; /* attached: srv[EMU] has only its line */
    pid_t pid[2];         /* whose /proc the rows read; -1: none */
    int attach;
    struct row rows[ROWS_MAX];
    int nrows;
    int failures;
};

/* ---- small helpers ---- */

static void msg(const char *fmt, ...)
{
    va_list ap;

    fputs("wsgbench: ", stderr);
    va_start(ap, fmt);
    vfprintf(stderr, fmt, ap);
    va_end(ap);
    fputc('\n', stderr);
}

static uint64_t now_ns(void)
{
    struct timespec ts;

    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (uint64_t)ts.tv_sec * NS_PER_S + (uint64_t)ts.tv_nsec;
}

static void sleep_s(double s)
{
    struct timespec ts;

    ts.tv_sec = (time_t)s;
    ts.tv_nsec = (long)((s - (double)ts.tv_sec) * 1e9);
    while (nanosleep(&ts, &ts) < 0 && errno == EINTR)
        ;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;

    return (x > y) - (x < y);
}

struct dist {
    double p50, p99, max;
};

/* Nearest-rank percentiles; sorts v. */
static struct dist dist_of(double *v, size_t n)
{
    struct dist d = {NAN, NAN, NAN};

    if (n == 0)
        return d;
    qsort(v, n, sizeof *v, cmp_double);
    d.p50 = v[(size_t)ceil(0.50 * (double)n) - 1];
    d.p99 = v[(size_t)ceil(0.99 * (double)n) - 1];
    d.max = v[n - 1];
    return d;
}

static struct row *add_row(struct bench *b, const char *label, double emu,
                           double ref, int decimals)
{
    struct row *r = &b->rows[b->nrows < ROWS_MAX ? b->nrows++ : ROWS_MAX - 1];

    memset(r, 0, sizeof *r);
    snprintf(r->label, sizeof r->label, "%s", label);
    r->emu = emu;
    r->ref = ref;
    r->decimals = decimals;
    return r;
}

static void set_target(struct row *r, enum target tk, double tv, int on_ratio,
                       const char *text)
{
    r->tk = tk;
    r->tv = tv;
    r->on_ratio = on_ratio;
    snprintf(r->ttext, sizeof r->ttext, "%s", text);
}

/* ---- servers ---- */

/* The servers running now and the bench's temporary directory, for the
 * SIGINT/SIGTERM handler: globals, since a handler gets nothing else. */
#define LIVE_MAX 4
static volatile pid_t live[LIVE_MAX];
static char live_dir[64];
/* While an attached emulator runs at x100: its control channel and the
 * command that puts its time scale back. */
static volatile int live_ctl = -1;
static char live_restore[48];
static volatile size_t live_restore_len;

static void live_set(pid_t old, pid_t pid)
{
    for (int i = 0; i < LIVE_MAX; i++)
        if (live[i] == old) {
            live[i] = pid;
            return;
        }
}

/* Interrupted: put an attached emulator's time scale back, stop the
 * servers the way they like to be stopped, so they remove their pty links,
 * then the directory; only async-signal-safe calls. (Were the bench killed
 * outright, PR_SET_PDEATHSIG still ends them.) */
static void on_signal(int sig)
{
    if (live_ctl >= 0) {
        ssize_t w = write(live_ctl, live_restore, live_restore_len);

        (void)w;
    }
    for (int i = 0; i < LIVE_MAX; i++)
        if (live[i] > 0)
            kill(live[i], SIGTERM);
    for (int i = 0; i < LIVE_MAX; i++)
        if (live[i] > 0)
            waitpid(live[i], NULL, 0);
    if (live_dir[0])
        rmdir(live_dir);
    _exit(128 + sig);
}

static void pin(int cpu)
{
    cpu_set_t set;

    if (cpu < 0)
        return;
    CPU_ZERO(&set);
    CPU_SET(cpu, &set);
    sched_setaffinity(0, sizeof set, &set);
}

/* Start exe (argv[0] is exe) with stdout on a pipe and wait for its ready
 * line. 0, or -1 with a message; on failure everything taken here is given
 * back (the child reaped, the pipe closed, the line freed), so a caller
 * that gives up on the server has nothing to clean up. */
static int server_start(struct bench *b, struct server *s, const char *name,
                        char *const *argv, int timeout_ms)
{
    int po[2];
    size_t cap = 4096, len = 0;
    uint64_t deadline = now_ns() + (uint64_t)timeout_ms * NS_PER_MS;
    int st;

    s->name = name;
    s->pid = -1;
    s->out_fd = -1;
    s->line = malloc(cap);
    if (!s->line) {
        msg("%s: out of memory", name);
        goto fail;
    }
    if (pipe2(po, O_CLOEXEC) < 0) {
        msg("%s: pipe: %s", name, strerror(errno));
        goto fail_line;
    }
    fflush(NULL);
    s->pid = fork();
    if (s->pid == 0) {
        int null = open("/dev/null", O_RDONLY);

        /* Never outlive the bench, even if it is killed. */
        prctl(PR_SET_PDEATHSIG, SIGKILL);
        pin(b->cpu_server);
        signal(SIGPIPE, SIG_DFL);
        if (null > 0)
            dup2(null, 0);
        dup2(po[1], 1);
        execv(argv[0], argv);
        fprintf(stderr, "wsgbench: exec %s: %s\n", argv[0], strerror(errno));
        _exit(127);
    }
    close(po[1]);
    s->out_fd = po[0];
    if (s->pid < 0) {
        msg("%s: fork: %s", name, strerror(errno));
        goto fail_pipe;
    }
    live_set(0, s->pid);
    for (;;) {
        struct pollfd p = {s->out_fd, POLLIN, 0};
        uint64_t now = now_ns();
        ssize_t n;
        char *nl;

        if (now >= deadline) {
            msg("%s: no ready line within %d ms", name, timeout_ms);
            goto fail_child;
        }
        if (poll(&p, 1, (int)((deadline - now) / NS_PER_MS) + 1) <= 0)
            continue;
        if (len + 1024 > cap) {
            char *bigger = realloc(s->line, cap * 2);
            if (!bigger) {
                msg("%s: out of memory", name);
                goto fail_child;
            }
            s->line = bigger;
            cap *= 2;
        }
        n = read(s->out_fd, s->line + len, cap - len - 1);
        if (n < 0 && errno == EINTR)
            continue;
        if (n <= 0) {
            msg("%s (%s) exited before it was ready", name, argv[0]);
            goto fail_child;
        }
        len += (size_t)n;
        s->line[len] = '\0';
        nl = strchr(s->line, '\n');
        if (nl) {
            *nl = '\0';
            break;
        }
    }
    if (strncmp(s->line, "ready", 5) != 0) {
        msg("%s: unexpected first line \"%.80s\"", name, s->line);
        goto fail_child;
    }
    return 0;
fail_child:
    kill(s->pid, SIGKILL);
    waitpid(s->pid, &st, 0);
    live_set(s->pid, 0);
    s->pid = -1;
fail_pipe:
    close(s->out_fd);
    s->out_fd = -1;
fail_line:
    free(s->line);
    s->line = NULL;
fail:
    return -1;
}

/* SIGTERM, 3 s to exit with status 0, else SIGKILL. 0 or -1. */
static int server_stop(struct server *s)
{
    uint64_t deadline = now_ns() + 3 * NS_PER_S;
    int st = 0, rc = -1;

    if (s->pid > 0) {
        kill(s->pid, SIGTERM);
        while (waitpid(s->pid, &st, WNOHANG) == 0) {
            if (now_ns() > deadline) {
                msg("%s did not exit within 3 s of SIGTERM", s->name);
                kill(s->pid, SIGKILL);
                waitpid(s->pid, &st, 0);
                st = -1;
                break;
            }
            sleep_s(0.005);
        }
        if (st != -1 && WIFEXITED(st) && WEXITSTATUS(st) == 0)
            rc = 0;
        else if (st != -1)
            msg("%s ended with %s %d", s->name,
                WIFEXITED(st) ? "status" : "signal",
                WIFEXITED(st) ? WEXITSTATUS(st) : WTERMSIG(st));
    } else {
        rc = 0;
    }
    if (s->pid > 0)
        live_set(s->pid, 0);
    if (s->out_fd >= 0)
        close(s->out_fd);
    free(s->line);
    s->line = NULL;
    s->out_fd = -1;
    s->pid = -1;
    return rc;
}

/* The value of field name= of a ready line, malloc'd (fleet lists are
 * long); NULL if absent. */
static char *field(const char *line, const char *name)
{
    size_t nl = strlen(name);
    const char *p = line;

    while ((p = strstr(p, name)) != NULL) {
        if ((p == line || p[-1] == ' ') && p[nl] == '=') {
            const char *v = p + nl + 1;
            return strndup(v, strcspn(v, " "));
        }
        p += nl;
    }
    return NULL;
}

/* "A.B.C.D:PORT" (anything after the port is ignored: ">REMOTE"). */
static int parse_ipport(const char *s, struct sockaddr_in *sa)
{
    char host[32];
    const char *c = strchr(s, ':');
    unsigned long port;

    if (!c || (size_t)(c - s) >= sizeof host)
        return -EINVAL;
    memcpy(host, s, (size_t)(c - s));
    host[c - s] = '\0';
    memset(sa, 0, sizeof *sa);
    sa->sin_family = AF_INET;
    port = strtoul(c + 1, NULL, 10);
    if (inet_pton(AF_INET, host, &sa->sin_addr) != 1 || port == 0 ||
        port > 65535)
        return -EINVAL;
    sa->sin_port = htons((uint16_t)port);
    return 0;
}

/* Attached: rows that need interface key= of READY when it is not there
 * get a note, and are n/a without failing. 1 then, else 0. */
static int attach_lacks(const struct bench *b, const char *key,
                        const char *rows)
{
    char *v;
    int have;

    if (!b->attach)
        return 0;
    v = field(b->srv[EMU].line, key);
    have = v != NULL;
    free(v);
    if (!have)
        msg("no %s= in --attach: %s rows not measured", key, rows);
    return !have;
}

/* Attached without --pid: the same for the emulator's /proc figures. */
static int attach_nopid(const struct bench *b, const char *what)
{
    if (b->pid[EMU] > 0)
        return 0;
    msg("no --pid with --attach: %s not measured", what);
    return 1;
}

/* ---- /proc ---- */

/* Context switches of every thread (status) and CPU time: nanoseconds
 * from each thread's schedstat where the kernel keeps it, else the
 * process's utime+stime in clock ticks from stat (10 ms steps: coarse for
 * short windows). */
static int proc_read(pid_t pid, struct proc_sample *s)
{
    char path[320], buf[2048], *p;
    unsigned long long v, ut, st;
    struct dirent *de;
    int i, have_ns = 1;
    DIR *d;
    FILE *f;

    s->t_ns = now_ns();
    s->ctxt = 0;
    s->cpu_ns = 0;
    snprintf(path, sizeof path, "/proc/%d/task", (int)pid);
    d = opendir(path);
    if (!d)
        return -errno;
    while ((de = readdir(d)) != NULL) {
        if (de->d_name[0] == '.')
            continue;
        snprintf(path, sizeof path, "/proc/%d/task/%s/status", (int)pid,
                 de->d_name);
        f = fopen(path, "r");
        if (!f)
            continue; /* a thread that just ended */
        while (fgets(buf, sizeof buf, f))
            if (sscanf(buf, "voluntary_ctxt_switches: %llu", &v) == 1 ||
                sscanf(buf, "nonvoluntary_ctxt_switches: %llu", &v) == 1)
                s->ctxt += v;
        fclose(f);
        snprintf(path, sizeof path, "/proc/%d/task/%s/schedstat", (int)pid,
                 de->d_name);
        f = fopen(path, "r");
        if (!f || fscanf(f, "%llu", &v) != 1)
            have_ns = 0;
        else
            s->cpu_ns += v;
        if (f)
            fclose(f);
    }
    closedir(d);
    if (have_ns && s->cpu_ns > 0)
        return 0;
    snprintf(path, sizeof path, "/proc/%d/stat", (int)pid);
    f = fopen(path, "r");
    if (!f)
        return -errno;
    p = fgets(buf, sizeof buf, f);
    fclose(f);
    /* utime and stime are fields 14 and 15; the name (2) may hold
     * blanks, so count from its closing parenthesis. */
    p = p ? strrchr(buf, ')') : NULL;
    if (!p)
        return -EINVAL;
    p++;
    for (i = 0; i < 11 && p; i++)
        p = strchr(p + 1, ' ');
    if (!p || sscanf(p, " %llu %llu", &ut, &st) != 2)
        return -EINVAL;
    s->cpu_ns =
        (ut + st) * (NS_PER_S / (unsigned long long)sysconf(_SC_CLK_TCK));
    return 0;
}

static double wakes_per_s(const struct proc_sample *a,
                          const struct proc_sample *b)
{
    return (double)(b->ctxt - a->ctxt) / ((double)(b->t_ns - a->t_ns) / 1e9);
}

static double cpu_percent(const struct proc_sample *a,
                          const struct proc_sample *b)
{
    return 100.0 * (double)(b->cpu_ns - a->cpu_ns) /
           (double)(b->t_ns - a->t_ns);
}

/* A "Key:  N kB" line of /proc/PID/status, in MiB; NAN if absent. */
static double proc_mib(pid_t pid, const char *key)
{
    char path[64], buf[256];
    size_t kl = strlen(key);
    double v = NAN;
    FILE *f;

    snprintf(path, sizeof path, "/proc/%d/status", (int)pid);
    f = fopen(path, "r");
    if (!f)
        return NAN;
    while (fgets(buf, sizeof buf, f))
        if (strncmp(buf, key, kl) == 0 && buf[kl] == ':')
            v = strtod(buf + kl + 1, NULL) / 1024.0;
    fclose(f);
    return v;
}

/* ---- links ---- */

/* Malformed packets end the measurement: a server must not send them. */
static int bad_is_fatal(struct wsg_client *c, enum wsg_parse_event ev,
                        uint8_t id)
{
    const struct link *l = c->user;

    msg("%s: malformed packet with ID %02Xh (%s)", l->who, id,
        ev == WSG_PARSE_BAD_CRC ? "bad checksum" : "oversize");
    return 1;
}

static void link_init(struct link *l, enum link_kind kind, const char *name)
{
    static const enum wsg_link_kind kinds[] = {[L_TCP] = WSG_LINK_TCP,
                                               [L_UDP] = WSG_LINK_UDP,
                                               [L_PTY] = WSG_LINK_SERIAL};

    wsg_client_init(&l->c, kinds[kind]);
    l->c.on_bad = bad_is_fatal;
    l->c.user = l;
    snprintf(l->who, sizeof l->who, "%s %s", name, kind_name[kind]);
}

/* A receive that failed (not a timeout), reported. */
static void link_error(const struct link *l, int r)
{
    if (r != -EBADMSG) /* already said by bad_is_fatal */
        msg("%s: %s", l->who,
            r == -EPIPE ? "connection closed" : strerror(-r));
}

static int link_tcp(struct link *l, const struct sockaddr_in *sa)
{
    int r = wsg_client_open_tcp(&l->c, sa, REPLY_MS);

    if (r < 0)
        msg("%s: connect to port %u: %s", l->who,
            (unsigned)ntohs(sa->sin_port), strerror(-r));
    return r < 0 ? -1 : 0;
}

/* Replies on rfd, which the bench owns (the server was started answering
 * to its port). */
static int link_udp(struct link *l, const struct sockaddr_in *sa, int rfd)
{
    int r = wsg_client_open_udp(&l->c, sa, rfd, 0);

    if (r < 0)
        msg("%s: %s", l->who, strerror(-r));
    return r < 0 ? -1 : 0;
}

static int link_pty(struct link *l, const char *path)
{
    int r = wsg_client_open_serial(&l->c, path);

    if (r < 0)
        msg("%s: %s: %s", l->who, path, strerror(-r));
    return r < 0 ? -1 : 0;
}

static int link_sent(const struct link *l, int r)
{
    if (r < 0)
        msg("%s: send: %s", l->who, r == -EIO ? "short write" : strerror(-r));
    return r < 0 ? -1 : 0;
}

static int link_send(struct link *l, const uint8_t *buf, size_t n)
{
    return link_sent(l, wsg_client_send(&l->c, buf, n));
}

static int link_sendf(struct link *l, uint8_t id, const uint8_t *payload,
                      size_t len)
{
    return link_sent(l, wsg_client_send_frame(&l->c, id, payload, len));
}

/* One read of what epoll said is there: 1, 0 when nothing was after all,
 * -1 at the end of the stream or on an error (reported). */
static int link_read(struct link *l)
{
    long n = wsg_client_read(&l->c);

    if (n == -EAGAIN)
        return 0;
    if (n < 0)
        link_error(l, (int)n);
    return n < 0 ? -1 : 1;
}

/* Wait for input until deadline and read it: 1, 0 on timeout, -1 at the
 * end of the stream or on an error (reported). */
static int link_wait(struct link *l, uint64_t deadline)
{
    int r = wsg_client_fill(&l->c, deadline);

    if (r < 0)
        link_error(l, r);
    return r < 0 ? -1 : r;
}

/* Next frame: 1; 0 when none came by deadline (deadline 0: only what is
 * buffered is looked at); -1 on a broken frame, the end of the stream or
 * an error (reported). */
static int link_recv(struct link *l, struct wsg_client_frame *f,
                     uint64_t deadline)
{
    int r = wsg_client_recv(&l->c, f, deadline);

    if (r < 0)
        link_error(l, r);
    return r < 0 ? -1 : r;
}

/* Wait for a frame with this ID (others are skipped): 0, or -1 with a
 * message. */
static int link_recv_id(struct link *l, uint8_t id, struct wsg_client_frame *f,
                        int timeout_ms)
{
    int r = wsg_client_recv_id(&l->c, id, f, wsg_client_deadline(timeout_ms));

    if (r == 0)
        msg("%s: no answer to %02Xh within %d ms", l->who, id, timeout_ms);
    else if (r < 0)
        link_error(l, r);
    return r == 1 ? 0 : -1;
}

/* A motion command through E_CMD_PENDING to its final result. The final
 * status, or -1 (reported). */
static int link_motion(struct link *l, uint8_t id, const uint8_t *payload,
                       size_t len)
{
    struct wsg_client_frame f;

    if (link_sendf(l, id, payload, len) < 0 ||
        link_recv_id(l, id, &f, REPLY_MS) < 0)
        return -1;
    if (f.status == WSG_E_CMD_PENDING &&
        link_recv_id(l, id, &f, MOTION_MS) < 0)
        return -1;
    return (int)f.status;
}

/* Over TCP, Disconnect Announcement first: a plain close would put the
 * emulator into FAST STOP. */
static void link_close(struct link *l)
{
    struct wsg_client_frame f;

    if (l->c.kind == WSG_LINK_TCP && l->c.fd >= 0 &&
        link_sendf(l, WSG_CMD_DISCONNECT, NULL, 0) == 0)
        link_recv_id(l, WSG_CMD_DISCONNECT, &f, REPLY_MS);
    wsg_client_close(&l->c);
}

/* A control-channel command and its one-line answer (without newline).
 * 0, or -1 (reported). */
static int ctl_cmd(struct link *l, const char *cmd, char *out, size_t cap)
{
    int r =
        wsg_client_line(&l->c, cmd, out, cap, wsg_client_deadline(REPLY_MS));

    if (r == 0)
        msg("control: no answer to \"%s\" within %d ms", cmd, REPLY_MS);
    else if (r < 0)
        link_error(l, r);
    return r == 1 ? 0 : -1;
}

/* The control channel's stats: model steps and overruns since start. */
static int ctl_stats(struct link *ctl, double *steps, double *overruns)
{
    char line[1024];

    if (ctl_cmd(ctl, "stats", line, sizeof line) < 0)
        return -1;
    if (strncmp(line, "ok {", 4) != 0 ||
        wsg_json_num(line, "steps", steps) < 0 ||
        wsg_json_num(line, "overruns", overruns) < 0) {
        msg("control: \"stats\" answered \"%.120s\" (want ok {...\"steps\":"
            "S,\"overruns\":O...})",
            line);
        return -1;
    }
    return 0;
}

/* Simulated seconds from the control channel ("time" -> "ok SECONDS"),
 * with the wall time at which it was read (between sending and answer). */
static int ctl_time(struct link *ctl, double *sim, uint64_t *wall)
{
    char line[128];
    uint64_t t0 = now_ns();

    if (ctl_cmd(ctl, "time", line, sizeof line) < 0)
        return -1;
    *wall = t0 + (now_ns() - t0) / 2;
    if (sscanf(line, "ok %lf", sim) != 1) {
        msg("control: \"time\" answered \"%.80s\"", line);
        return -1;
    }
    return 0;
}

/* ---- the requests ---- */

static uint8_t req_width[WSG_HEADER_LEN + WSG_CRC_LEN];

static int check_width(const struct link *l, const struct wsg_client_frame *f)
{
    if (f->id == WSG_CMD_GET_WIDTH && f->len == 6 &&
        f->status == WSG_E_SUCCESS)
        return 0;
    msg("%s: malformed answer to 43h: ID %02Xh, %u bytes, status %s", l->who,
        f->id, f->len, f->len >= 2 ? wsg_status_name(f->status) : "none");
    return -1;
}

static int open_link(struct bench *b, struct link *l, int which,
                     enum link_kind kind)
{
    struct sockaddr_in sa;
    char *v;
    int rc = -1;

    link_init(l, kind, b->srv[which].name);
    if (kind == L_PTY)
        return link_pty(l, b->pty_path[which]);
    v = field(b->srv[which].line, kind == L_TCP ? "tcp" : "udp");
    if (!v || parse_ipport(v, &sa) < 0)
        msg("%s: no usable address in \"%s\"", l->who, b->srv[which].line);
    else if (kind == L_TCP)
        rc = link_tcp(l, &sa);
    else
        rc = link_udp(l, &sa, b->udp_rfd[which]);
    free(v);
    return rc;
}

/* One request in flight: send 43h, wait for its answer. */
static int sample(struct link *l, double *us)
{
    uint64_t t0 = now_ns();
    struct wsg_client_frame f;
    int r;

    if (link_send(l, req_width, sizeof req_width) < 0)
        return -1;
    r = link_recv(l, &f, t0 + REPLY_MS * NS_PER_MS);
    if (r == 0)
        msg("%s: no answer to 43h within %d ms", l->who, REPLY_MS);
    if (r <= 0 || check_width(l, &f) < 0)
        return -1;
    *us = (double)(now_ns() - t0) / 1e3;
    return 0;
}

/* ---- 1. latency ---- */

static int bench_latency(struct bench *b, enum link_kind kind)
{
    struct link l[2];
    double *lat[2] = {NULL, NULL}, dummy;
    size_t per = (size_t)(b->o.samples / ROUNDS), n[2] = {0, 0};
    size_t warm = per < 200 ? 200 : per > 2000 ? 2000 : per, i;
    struct dist d[2] = {{NAN, NAN, NAN}, {NAN, NAN, NAN}};
    char label[48];
    int s, round, rc = -1;
    struct row *r;

    l[EMU].c.fd = l[REF].c.fd = -1;
    l[EMU].c.own_rfd = l[REF].c.own_rfd = 0;
    if (per == 0)
        per = 1;
    if (attach_lacks(b,
                     kind == L_TCP   ? "tcp"
                     : kind == L_UDP ? "udp"
                                     : "pty",
                     kind_name[kind])) {
        rc = 0;
        goto cleanup;
    }
    /* Attached, with no socket on the UDP answers' port: said at start. */
    if (kind == L_UDP && b->udp_rfd[EMU] < 0)
        goto cleanup;
    for (s = 0; s < 2; s++) {
        lat[s] = malloc(per * ROUNDS * sizeof(double));
        if (!lat[s] || open_link(b, &l[s], s, kind) < 0)
            goto cleanup;
        for (i = 0; i < warm; i++)
            if (sample(&l[s], &dummy) < 0)
                goto cleanup;
    }
    /* Alternating rounds, each server first every other round. */
    for (round = 0; round < ROUNDS; round++) {
        for (int k = 0; k < 2; k++) {
            s = (round + k) % 2;
            for (i = 0; i < per; i++)
                if (sample(&l[s], &lat[s][n[s]++]) < 0)
                    goto cleanup;
        }
    }
    d[EMU] = dist_of(lat[EMU], n[EMU]);
    d[REF] = dist_of(lat[REF], n[REF]);
    rc = 0;
cleanup:
    snprintf(label, sizeof label, "%s latency median (us)", kind_name[kind]);
    /* The targets are on TCP; UDP and the pty are shown beside. */
    r = add_row(b, label, d[EMU].p50, d[REF].p50, 1);
    if (kind == L_TCP)
        set_target(r, T_LE, 1.25, 1, "ratio <= 1.25");
    snprintf(label, sizeof label, "%s latency p99 (us)", kind_name[kind]);
    r = add_row(b, label, d[EMU].p99, d[REF].p99, 1);
    if (kind == L_TCP)
        set_target(r, T_LE, 2, 1, "ratio <= 2");
    snprintf(label, sizeof label, "%s latency max (us)", kind_name[kind]);
    add_row(b, label, d[EMU].max, d[REF].max, 1);
    for (s = 0; s < 2; s++) {
        if (l[s].c.fd >= 0)
            link_close(&l[s]);
        free(lat[s]);
    }
    return rc;
}

/* ---- 2. pipelined throughput ---- */

/* Keep k requests in flight for dur_ns: the replies counted in that
 * window; afterwards the ones still owed are collected. */
static int pipelined(struct link *l, long k, uint64_t dur_ns, double *count,
                     double *secs)
{
    uint8_t *batch = malloc((size_t)k * sizeof req_width);
    uint64_t t0, end, now;
    long inflight = k, got, i;
    struct wsg_client_frame f;
    int r, rc = -1;

    if (!batch)
        return -1;
    for (i = 0; i < k; i++)
        memcpy(batch + i * (long)sizeof req_width, req_width,
               sizeof req_width);
    *count = 0;
    t0 = now_ns();
    end = t0 + dur_ns;
    if (link_send(l, batch, (size_t)k * sizeof req_width) < 0)
        goto cleanup;
    while ((now = now_ns()) < end) {
        r = link_wait(l, end);
        if (r < 0)
            goto cleanup;
        got = 0;
        while ((r = link_recv(l, &f, 0)) == 1) {
            if (check_width(l, &f) < 0)
                goto cleanup;
            got++;
        }
        if (r < 0)
            goto cleanup;
        *count += (double)got;
        /* Refill in one write: what a pipelining client does. */
        if (got && link_send(l, batch, (size_t)got * sizeof req_width) < 0)
            goto cleanup;
    }
    *secs = (double)(now - t0) / 1e9;
    /* inflight is still k: every reply received was replaced. */
    for (; inflight > 0; inflight--) {
        r = link_recv(l, &f, now_ns() + REPLY_MS * NS_PER_MS);
        if (r == 0)
            msg("%s: %ld pipelined answers missing", l->who, inflight);
        if (r <= 0 || check_width(l, &f) < 0)
            goto cleanup;
    }
    rc = 0;
cleanup:
    free(batch);
    return rc;
}

static int bench_throughput(struct bench *b)
{
    struct link l[2];
    struct row *r;
    int rounds = b->o.quick ? 2 : 6, round, s, rc = -1;
    uint64_t dur = (uint64_t)(b->o.tput_s / rounds * 1e9);
    double count[2] = {0, 0}, secs[2] = {0, 0}, c, t;
    char label[48];
    int done = 0;

    l[EMU].c.fd = l[REF].c.fd = -1;
    l[EMU].c.own_rfd = l[REF].c.own_rfd = 0;
    if (attach_lacks(b, "tcp", "pipelined TCP")) {
        rc = 0;
        goto cleanup;
    }
    for (s = 0; s < 2; s++)
        if (open_link(b, &l[s], s, L_TCP) < 0 ||
            pipelined(&l[s], b->o.inflight, dur / 4, &c, &t) < 0)
            goto cleanup; /* the first quarter round warms up */
    for (round = 0; round < rounds; round++) {
        for (int k = 0; k < 2; k++) {
            s = (round + k) % 2;
            if (pipelined(&l[s], b->o.inflight, dur, &c, &t) < 0)
                goto cleanup;
            count[s] += c;
            secs[s] += t;
        }
    }
    rc = 0;
    done = 1;
cleanup:
    snprintf(label, sizeof label, "TCP pipelined, %ld in flight (1/s)",
             b->o.inflight);
    r = add_row(b, label, done ? count[EMU] / secs[EMU] : NAN,
                done ? count[REF] / secs[REF] : NAN, 0);
    set_target(r, T_GE, 0.8, 1, "ratio >= 0.8");
    for (s = 0; s < 2; s++)
        if (l[s].c.fd >= 0)
            link_close(&l[s]);
    return rc;
}

/* ---- 3. stream jitter ---- */

static int bench_jitter(struct bench *b)
{
    static const uint8_t sub[3] = {0x01, STREAM_MS, 0x00};
    struct link l[2];
    size_t cap = (size_t)(b->o.jitter_s * 1000 / STREAM_MS * 2) + 64;
    double *iv[2] = {NULL, NULL};
    size_t n[2] = {0, 0};
    uint64_t last[2] = {0, 0}, end;
    int seen[2] = {0, 0};
    struct dist d[2] = {{NAN, NAN, NAN}, {NAN, NAN, NAN}};
    int epfd = -1, s, rc = -1, done = 0;
    struct row *r;

    l[EMU].c.fd = l[REF].c.fd = -1;
    l[EMU].c.own_rfd = l[REF].c.own_rfd = 0;
    if (attach_lacks(b, "tcp", "43h stream")) {
        rc = 0;
        goto cleanup;
    }
    epfd = epoll_create1(EPOLL_CLOEXEC);
    if (epfd < 0)
        goto cleanup;
    for (s = 0; s < 2; s++) {
        struct epoll_event ev = {.events = EPOLLIN, .data.u32 = (uint32_t)s};

        iv[s] = malloc(cap * sizeof(double));
        if (!iv[s] || open_link(b, &l[s], s, L_TCP) < 0 ||
            epoll_ctl(epfd, EPOLL_CTL_ADD, l[s].c.rfd, &ev) < 0)
            goto cleanup;
    }
    /* Both streams at once, in one epoll: half the wall time, and the
     * same machine noise for both. */
    for (s = 0; s < 2; s++)
        if (link_sendf(&l[s], WSG_CMD_GET_WIDTH, sub, sizeof sub) < 0)
            goto cleanup;
    end = now_ns() + (uint64_t)(b->o.jitter_s * 1e9);
    last[EMU] = last[REF] = now_ns();
    for (;;) {
        struct epoll_event ev[2];
        uint64_t now = now_ns();
        int ne, i;

        if (now >= end)
            break;
        for (s = 0; s < 2; s++)
            if (now - last[s] > STALL_MS * NS_PER_MS) {
                msg("%s: the 43h stream stopped (nothing for %d ms)", l[s].who,
                    STALL_MS);
                goto cleanup;
            }
        ne = epoll_wait(epfd, ev, 2, 100);
        for (i = 0; i < ne; i++) {
            struct wsg_client_frame f;
            long got;
            int k;

            s = (int)ev[i].data.u32;
            got = link_read(&l[s]);
            if (got == 0)
                continue;
            if (got < 0)
                goto cleanup;
            now = now_ns();
            while ((k = link_recv(&l[s], &f, 0)) == 1) {
                if (check_width(&l[s], &f) < 0)
                    goto cleanup;
                /* The first is the answer to the request itself; the
                 * intervals start at the first periodic packet. */
                if (seen[s]++ >= 2 && n[s] < cap)
                    iv[s][n[s]++] =
                        fabs((double)(now - last[s]) / 1e3 - STREAM_MS * 1e3);
                last[s] = now;
            }
            if (k < 0)
                goto cleanup;
        }
    }
    d[EMU] = dist_of(iv[EMU], n[EMU]);
    d[REF] = dist_of(iv[REF], n[REF]);
    rc = 0;
    done = 1;
cleanup:
    add_row(b, "43h stream 10 ms jitter p50 (us)", d[EMU].p50, d[REF].p50, 1);
    r = add_row(b, "43h stream 10 ms jitter p99 (us)", d[EMU].p99, d[REF].p99,
                1);
    set_target(r, T_LT, 1000, 0, "< 1000");
    add_row(b, "43h stream 10 ms jitter max (us)", d[EMU].max, d[REF].max, 1);
    add_row(b, "43h stream intervals (count)", done ? (double)n[EMU] : NAN,
            done ? (double)n[REF] : NAN, 0);
    for (s = 0; s < 2; s++) {
        if (l[s].c.fd >= 0)
            link_close(&l[s]); /* ends the stream with the connection */
        free(iv[s]);
    }
    if (epfd >= 0)
        close(epfd);
    return rc;
}

/* ---- 4. idle ---- */

static int bench_idle(struct bench *b)
{
    struct proc_sample a[2], z[2];
    double w[2] = {NAN, NAN}, c[2] = {NAN, NAN};
    int s, rc = 0;
    struct row *r;

    attach_nopid(b, "the emulator's idle wakes and CPU");
    sleep_s(0.3); /* let the last close settle */
    for (s = 0; s < 2; s++)
        if (b->pid[s] > 0)
            rc |= proc_read(b->pid[s], &a[s]);
    sleep_s(b->o.idle_s);
    for (s = 0; s < 2; s++)
        if (b->pid[s] > 0)
            rc |= proc_read(b->pid[s], &z[s]);
    if (rc < 0) {
        msg("idle: cannot read /proc of the servers");
    } else {
        for (s = 0; s < 2; s++) {
            if (b->pid[s] <= 0)
                continue;
            w[s] = wakes_per_s(&a[s], &z[s]);
            c[s] = cpu_percent(&a[s], &z[s]);
        }
    }
    r = add_row(b, "idle wakes/s", w[EMU], w[REF], 2);
    set_target(r, T_LT, 1, 0, "< 1");
    r = add_row(b, "idle CPU % of one core", c[EMU], c[REF], 1);
    set_target(r, T_LT, 0.05, 0, "0.0");
    return rc < 0 ? -1 : 0;
}

/* A 43h stream of 1 s and nothing moving: the emulator runs the gripper
 * from the stream's deadline, so it wakes about once a second (one wake
 * per packet), not once per model step. */
static int bench_slow_stream(struct bench *b)
{
    static const uint8_t sub[3] = {0x01, 0xE8, 0x03}; /* every 1000 ms */
    struct proc_sample a[2], z[2];
    double w[2] = {NAN, NAN};
    struct link l[2];
    int s, rc = -1;
    struct row *r;

    l[EMU].c.fd = l[REF].c.fd = -1;
    l[EMU].c.own_rfd = l[REF].c.own_rfd = 0;
    if (attach_lacks(b, "tcp", "1 s stream") ||
        attach_nopid(b, "the emulator's wakes with a 1 s stream")) {
        rc = 0;
        goto cleanup;
    }
    for (s = 0; s < 2; s++)
        if (open_link(b, &l[s], s, L_TCP) < 0 ||
            link_sendf(&l[s], WSG_CMD_GET_WIDTH, sub, sizeof sub) < 0)
            goto cleanup;
    sleep_s(0.5); /* past the answer to the request itself */
    for (s = 0; s < 2; s++)
        if (b->pid[s] > 0 && proc_read(b->pid[s], &a[s]) < 0)
            goto cleanup;
    sleep_s(b->o.idle_s);
    for (s = 0; s < 2; s++) {
        if (b->pid[s] <= 0)
            continue;
        if (proc_read(b->pid[s], &z[s]) < 0)
            goto cleanup;
        w[s] = wakes_per_s(&a[s], &z[s]);
    }
    rc = 0;
cleanup:
    if (rc < 0)
        msg("1 s stream: cannot subscribe or read /proc of the servers");
    r = add_row(b, "1 s stream, idle: wakes/s", w[EMU], w[REF], 2);
    set_target(r, T_LT, 2, 0, "~1");
    for (s = 0; s < 2; s++)
        if (l[s].c.fd >= 0)
            link_close(&l[s]);
    return rc;
}

/* ---- 5. the model's step rate while moving ---- */

/* Measure for secs: steps/s and overruns from the control channel's stats,
 * CPU % of pid (none when pid is not > 0). */
static int measure_moving(struct link *ctl, pid_t pid, double secs,
                          double *rate, double *overruns, double *cpu)
{
    double s0, o0, s1, o1;
    struct proc_sample a, z;
    uint64_t t0, t1;

    if ((pid > 0 && proc_read(pid, &a) < 0) || ctl_stats(ctl, &s0, &o0) < 0)
        return -1;
    t0 = now_ns();
    sleep_s(secs);
    if ((pid > 0 && proc_read(pid, &z) < 0) || ctl_stats(ctl, &s1, &o1) < 0)
        return -1;
    t1 = now_ns();
    *rate = (s1 - s0) / ((double)(t1 - t0) / 1e9);
    *overruns = o1 - o0;
    *cpu = pid > 0 ? cpu_percent(&a, &z) : NAN;
    return 0;
}

static void put_move(uint8_t *pl, double width, double speed)
{
    pl[0] = 0; /* absolute, clamp on block */
    wsg_put_f32(pl + 1, (float)width);
    wsg_put_f32(pl + 5, (float)speed);
}

/* A speed that keeps the fingers moving across the stroke for longer than
 * the window (plus time to set it up), at least the model's 5 mm/s. */
static double slow_speed(double window_s)
{
    double v = STROKE_MM / (window_s + 2.0);

    return v < 5.0 ? 5.0 : v;
}

static int bench_moving(struct bench *b)
{
    struct link l, ctl;
    uint8_t dir = 0, pl[9];
    double rate = NAN, ovr = NAN, cpu = NAN;
    struct wsg_client_frame f;
    int st, rc = -1;
    char *c = field(b->srv[EMU].line, "control");
    struct sockaddr_in sa;
    struct row *r;

    link_init(&l, L_TCP, "wsgemu");
    link_init(&ctl, L_TCP, "wsgemu control");
    if (attach_lacks(b, "tcp", "moving") ||
        attach_lacks(b, "control", "moving")) {
        rc = 0;
        goto cleanup;
    }
    attach_nopid(b, "the emulator's CPU while moving");
    if (!c || parse_ipport(c, &sa) < 0) {
        msg("wsgemu: no control= in its ready line");
        goto cleanup;
    }
    if (link_tcp(&ctl, &sa) < 0 || open_link(b, &l, EMU, L_TCP) < 0)
        goto cleanup;
    st = link_motion(&l, WSG_CMD_HOMING, &dir, 1);
    if (st != WSG_E_SUCCESS) {
        if (st >= 0)
            msg("wsgemu: Homing ended with %s", wsg_status_name((unsigned)st));
        goto cleanup;
    }
    put_move(pl, 0.0, slow_speed(b->o.move_s));
    if (link_sendf(&l, WSG_CMD_PREPOSITION, pl, sizeof pl) < 0 ||
        link_recv_id(&l, WSG_CMD_PREPOSITION, &f, REPLY_MS) < 0)
        goto cleanup;
    if (f.status != WSG_E_CMD_PENDING) {
        msg("wsgemu: Preposition answered %s", wsg_status_name(f.status));
        goto cleanup;
    }
    sleep_s(0.1);
    rc = measure_moving(&ctl, b->pid[EMU], b->o.move_s, &rate, &ovr, &cpu);
    /* Stop rather than wait out the motion: E_SUCCESS for 22h, the
     * motion's final result (E_CMD_ABORTED) for 21h. */
    if (link_sendf(&l, WSG_CMD_STOP, NULL, 0) < 0 ||
        link_recv_id(&l, WSG_CMD_PREPOSITION, &f, MOTION_MS) < 0)
        rc = -1;
cleanup:
    r = add_row(b, "moving: model steps/s", rate, NOT_APPLIED, 0);
    set_target(r, T_NEAR, 1000, 0, "1000 +- 2%");
    r->tol = 20;
    r = add_row(b, "moving: step overruns", ovr, NOT_APPLIED, 0);
    set_target(r, T_EQ, 0, 0, "0");
    add_row(b, "moving: CPU % of one core", cpu, NOT_APPLIED, 1);
    link_close(&l);
    wsg_client_close(&ctl.c);
    free(c);
    return rc;
}

/* ---- 6. time scale ---- */

/* Attached: the emulator's scale now (control "stats"), then x100. 0, or
 * -1 (reported); *scaled is set once "time scale 100" has been sent. */
static int scale_up(struct link *ctl, char *prior, size_t cap, int *scaled)
{
    char line[1024];
    double v;

    if (ctl_cmd(ctl, "stats", line, sizeof line) < 0)
        return -1;
    if (strncmp(line, "ok {", 4) != 0 || wsg_json_num(line, "scale", &v) < 0) {
        msg("control: \"stats\" answered \"%.120s\" (want ok {...\"scale\":"
            "X...})",
            line);
        return -1;
    }
    snprintf(prior, cap, "%.17g", v);
    snprintf(live_restore, sizeof live_restore, "time scale %s\n", prior);
    live_restore_len = strlen(live_restore);
    live_ctl = ctl->c.fd;
    *scaled = 1;
    if (ctl_cmd(ctl, "time scale 100", line, sizeof line) < 0)
        return -1;
    if (strcmp(line, "ok scale 100") != 0) {
        msg("control: \"time scale 100\" answered \"%.80s\" (want ok scale "
            "100; is its time paused?)",
            line);
        return -1;
    }
    return 0;
}

/* Attached: the scale it had before. 0, or -1 (reported). */
static int scale_back(struct link *ctl, const char *prior)
{
    char cmd[48], line[128];

    live_ctl = -1;
    snprintf(cmd, sizeof cmd, "time scale %s", prior);
    if (ctl_cmd(ctl, cmd, line, sizeof line) < 0) {
        msg("the attached emulator may still run at x100");
        return -1;
    }
    if (strncmp(line, "ok scale", 8) != 0) {
        msg("control: \"%s\" answered \"%.80s\": the attached emulator may "
            "still run at x100",
            cmd, line);
        return -1;
    }
    return 0;
}

/* Homing, Grasp and Release of a 40 mm part at x100: an emulator started
 * with --time-scale 100, or the attached one set to it for the cycle. */
static int bench_timescale(struct bench *b)
{
    char *argv[] = {b->emu_exe,    "--tcp",        "127.0.0.1:0", "--control",
                    "127.0.0.1:0", "--time-scale", "100",         NULL};
    struct server s;
    struct link l, ctl;
    struct sockaddr_in sa;
    char line[128], prior[32] = "1", *c = NULL;
    const char *ready;
    uint8_t dir = 0, pl[8];
    double sim0, sim1, wall = NAN, sim = NAN;
    uint64_t w0, w1;
    int st, i, rc = -1, started = 0, scaled = 0;
    struct row *r;
    static const struct {
        uint8_t id;
        float width, speed;
    } cycle[] = {{WSG_CMD_HOMING, 0, 0},
                 {WSG_CMD_GRASP, 40, 100},
                 {WSG_CMD_RELEASE, 100, 100}};

    link_init(&l, L_TCP, "wsgemu x100");
    link_init(&ctl, L_TCP, "wsgemu x100 control");
    if (b->attach) {
        if (attach_lacks(b, "tcp", "x100") ||
            attach_lacks(b, "control", "x100")) {
            rc = 0;
            goto row;
        }
        ready = b->srv[EMU].line;
    } else {
        if (server_start(b, &s, "wsgemu --time-scale 100", argv, READY_MS) < 0)
            goto row;
        started = 1;
        ready = s.line;
    }
    c = field(ready, "control");
    if (!c || parse_ipport(c, &sa) < 0) {
        msg("wsgemu x100: no control= in its ready line");
        goto cleanup;
    }
    if (link_tcp(&ctl, &sa) < 0)
        goto cleanup;
    free(c);
    c = field(ready, "tcp");
    if (!c || parse_ipport(c, &sa) < 0 || link_tcp(&l, &sa) < 0)
        goto cleanup;
    if (b->attach && scale_up(&ctl, prior, sizeof prior, &scaled) < 0)
        goto cleanup;
    if (ctl_cmd(&ctl, "part 40", line, sizeof line) < 0)
        goto cleanup;
    if (strncmp(line, "ok", 2) != 0) {
        msg("control: \"part 40\" answered \"%.80s\"", line);
        goto cleanup;
    }
    if (ctl_time(&ctl, &sim0, &w0) < 0)
        goto cleanup;
    for (i = 0; i < 3; i++) {
        if (cycle[i].id == WSG_CMD_HOMING) {
            st = link_motion(&l, cycle[i].id, &dir, 1);
        } else {
            wsg_put_f32(pl, cycle[i].width);
            wsg_put_f32(pl + 4, cycle[i].speed);
            st = link_motion(&l, cycle[i].id, pl, sizeof pl);
        }
        if (st != WSG_E_SUCCESS) {
            if (st >= 0)
                msg("wsgemu x100: %02Xh ended with %s", cycle[i].id,
                    wsg_status_name((unsigned)st));
            goto cleanup;
        }
    }
    if (ctl_time(&ctl, &sim1, &w1) < 0)
        goto cleanup;
    wall = (double)(w1 - w0) / 1e6;
    sim = sim1 - sim0;
    rc = 0;
cleanup:
    link_close(&l);
    if (scaled && scale_back(&ctl, prior) < 0)
        rc = -1;
    wsg_client_close(&ctl.c);
    if (started && server_stop(&s) < 0)
        rc = -1;
row:
    free(c);
    add_row(b, "x100: home+grasp+release wall (ms)", wall, NOT_APPLIED, 1);
    add_row(b, "x100: same, simulated (s)", sim, NOT_APPLIED, 3);
    r = add_row(b, "x100: speed-up (simulated/wall)",
                rc == 0 ? sim / (wall / 1e3) : NAN, NOT_APPLIED, 1);
    set_target(r, T_GE, 50, 0, ">= 50");
    return rc;
}

/* ---- 7. memory ---- */

static int bench_memory(struct bench *b)
{
    double rss[2], hwm[2];
    int s;
    struct row *r;

    attach_nopid(b, "the emulator's RSS");
    for (s = 0; s < 2; s++) {
        rss[s] = b->pid[s] > 0 ? proc_mib(b->pid[s], "VmRSS") : NAN;
        hwm[s] = b->pid[s] > 0 ? proc_mib(b->pid[s], "VmHWM") : NAN;
    }
    r = add_row(b, "RSS (MiB)", rss[EMU], rss[REF], 2);
    set_target(r, T_LT, 4, 0, "< 4");
    add_row(b, "peak RSS, VmHWM (MiB)", hwm[EMU], hwm[REF], 2);
    if ((b->pid[EMU] > 0 && isnan(rss[EMU])) || isnan(rss[REF])) {
        msg("memory: cannot read /proc/PID/status of the servers");
        return -1;
    }
    return 0;
}

/* ---- 8. fleet ---- */

struct fleet {
    struct bench *b;
    struct server s;
    long n;
    struct link *l;
    struct link ctl;
    int epfd;
    uint8_t *got; /* per gripper: which awaited answers came */
};

/* Send one request to grippers lo..hi-1. */
static int fleet_send(struct fleet *f, long lo, long hi, uint8_t id,
                      const uint8_t *payload, size_t len)
{
    for (long i = lo; i < hi; i++)
        if (link_sendf(&f->l[i], id, payload, len) < 0)
            return -1;
    return 0;
}

/* Up to two awaited answers per gripper in lo..hi-1: an ID, and whether
 * the final result is awaited (else the immediate E_CMD_PENDING); a final
 * result must be E_SUCCESS when need_ok. Waiting for both at once keeps
 * an answer from being skipped while the other is awaited. */
struct await {
    uint8_t id;
    int final, need_ok;
};

static int fleet_wait(struct fleet *f, long lo, long hi, const struct await *w,
                      int nw, int timeout_ms)
{
    uint64_t deadline = now_ns() + (uint64_t)timeout_ms * NS_PER_MS;
    uint8_t all = (uint8_t)((1u << nw) - 1u);
    long left = hi - lo, i;

    memset(f->got + lo, 0, (size_t)(hi - lo));
    while (left > 0) {
        struct epoll_event ev[64];
        uint64_t now = now_ns();
        int ne, e;

        if (now >= deadline) {
            msg("fleet: %ld of %ld grippers did not answer %02Xh within %d "
                "ms",
                left, hi - lo, w[0].id, timeout_ms);
            return -1;
        }
        ne = epoll_wait(f->epfd, ev, 64, 100);
        for (e = 0; e < ne; e++) {
            struct link *l;
            struct wsg_client_frame fr;
            long got;
            int k, j;

            i = (long)ev[e].data.u64;
            l = &f->l[i];
            got = link_read(l);
            if (got == 0)
                continue;
            if (got < 0)
                return -1;
            while ((k = link_recv(l, &fr, 0)) == 1) {
                if (i < lo || i >= hi)
                    continue;
                for (j = 0; j < nw; j++) {
                    int pending = fr.status == WSG_E_CMD_PENDING;

                    if (fr.id != w[j].id || (f->got[i] & (1u << j)))
                        continue;
                    if (w[j].final && pending)
                        continue;
                    if ((!w[j].final && !pending) ||
                        (w[j].final && w[j].need_ok &&
                         fr.status != WSG_E_SUCCESS)) {
                        msg("%s: %02Xh answered %s", l->who, fr.id,
                            wsg_status_name(fr.status));
                        return -1;
                    }
                    f->got[i] |= (uint8_t)(1u << j);
                    if (f->got[i] == all)
                        left--;
                }
            }
            if (k < 0)
                return -1;
        }
    }
    return 0;
}

/* Grippers lo..hi-1 move slowly across the stroke; measured for the
 * window; then stopped. */
static int fleet_moving(struct fleet *f, long lo, long hi, double *rate,
                        double *ovr, double *cpu)
{
    static const struct await pending = {WSG_CMD_PREPOSITION, 0, 0};
    static const struct await stopped[2] = {{WSG_CMD_STOP, 1, 1},
                                            {WSG_CMD_PREPOSITION, 1, 0}};
    uint8_t pl[9];

    put_move(pl, 0.0, slow_speed(f->b->o.move_s));
    if (fleet_send(f, lo, hi, WSG_CMD_PREPOSITION, pl, sizeof pl) < 0 ||
        fleet_wait(f, lo, hi, &pending, 1, MOTION_MS) < 0)
        return -1;
    sleep_s(0.1);
    if (measure_moving(&f->ctl, f->s.pid, f->b->o.move_s, rate, ovr, cpu) < 0)
        return -1;
    if (fleet_send(f, lo, hi, WSG_CMD_STOP, NULL, 0) < 0 ||
        fleet_wait(f, lo, hi, stopped, 2, MOTION_MS) < 0)
        return -1;
    return 0;
}

static int bench_fleet(struct bench *b)
{
    static const struct await homed = {WSG_CMD_HOMING, 1, 1};
    static const struct await moved = {WSG_CMD_PREPOSITION, 1, 1};
    struct fleet f;
    char nbuf[24], label[48];
    char *argv[] = {b->emu_exe,    "--grippers", nbuf,          "--tcp",
                    "127.0.0.1:0", "--control",  "127.0.0.1:0", NULL};
    double iw = NAN, ic = NAN, rss = NAN, home_s = NAN;
    double r10 = NAN, o10 = NAN, c10 = NAN, ra = NAN, oa = NAN, ca = NAN;
    struct proc_sample a, z;
    struct sockaddr_in sa;
    struct rlimit rl;
    char *tcp = NULL, *c = NULL, *p;
    long i, tenth;
    uint8_t pl[9], dir = 0;
    uint64_t t0;
    int rc = -1, started = 0;
    struct row *r;

    memset(&f, 0, sizeof f);
    f.b = b;
    f.n = b->o.fleet;
    f.epfd = -1;
    tenth = f.n / 10 > 0 ? f.n / 10 : 1;
    link_init(&f.ctl, L_TCP, "fleet control");
    snprintf(nbuf, sizeof nbuf, "%ld", f.n);

    /* One connection per gripper, plus a few. */
    if (getrlimit(RLIMIT_NOFILE, &rl) == 0 && rl.rlim_cur < rl.rlim_max) {
        rl.rlim_cur = rl.rlim_max;
        setrlimit(RLIMIT_NOFILE, &rl);
    }
    if (getrlimit(RLIMIT_NOFILE, &rl) == 0 && rl.rlim_cur != RLIM_INFINITY &&
        rl.rlim_cur < (rlim_t)f.n + 32) {
        msg("fleet: %ld connections need more descriptors than the limit "
            "(%lu)",
            f.n, (unsigned long)rl.rlim_cur);
        goto rows;
    }
    if (server_start(b, &f.s, "wsgemu --grippers", argv, FLEET_MS) < 0) {
        msg("fleet: wsgemu --grippers %ld did not start (does it have "
            "--grippers?)",
            f.n);
        goto rows;
    }
    started = 1;
    f.l = calloc((size_t)f.n, sizeof *f.l);
    f.got = calloc((size_t)f.n, 1);
    for (i = 0; f.l && i < f.n; i++)
        f.l[i].c.fd = f.l[i].c.rfd = -1;
    tcp = field(f.s.line, "tcp");
    c = field(f.s.line, "control");
    f.epfd = epoll_create1(EPOLL_CLOEXEC);
    if (!f.l || !f.got || !tcp || !c || f.epfd < 0 ||
        parse_ipport(c, &sa) < 0 || link_tcp(&f.ctl, &sa) < 0) {
        msg("fleet: no tcp= and control= in the ready line, or no memory");
        goto cleanup;
    }
    /* Idle first: nothing connected but the control channel. */
    sleep_s(0.5);
    if (proc_read(f.s.pid, &a) < 0)
        goto cleanup;
    sleep_s(b->o.idle_s);
    if (proc_read(f.s.pid, &z) < 0)
        goto cleanup;
    iw = wakes_per_s(&a, &z);
    ic = cpu_percent(&a, &z);
    rss = proc_mib(f.s.pid, "VmRSS");

    for (i = 0, p = tcp; i < f.n; i++) {
        struct epoll_event ev = {.events = EPOLLIN, .data.u64 = (uint64_t)i};
        char name[32];

        snprintf(name, sizeof name, "gripper %ld", i);
        link_init(&f.l[i], L_TCP, name);
        if (!p || parse_ipport(p, &sa) < 0) {
            msg("fleet: tcp= lists fewer than %ld addresses", f.n);
            goto cleanup;
        }
        if (link_tcp(&f.l[i], &sa) < 0 ||
            epoll_ctl(f.epfd, EPOLL_CTL_ADD, f.l[i].c.rfd, &ev) < 0)
            goto cleanup;
        p = strchr(p, ',');
        p = p ? p + 1 : NULL;
    }
    t0 = now_ns();
    if (fleet_send(&f, 0, f.n, WSG_CMD_HOMING, &dir, 1) < 0 ||
        fleet_wait(&f, 0, f.n, &homed, 1, FLEET_MS) < 0)
        goto cleanup;
    home_s = (double)(now_ns() - t0) / 1e9;

    /* A tenth moving, stopped, sent back to the end stop quickly; then all
     * of them moving: the cost should follow what moves, not N. */
    if (fleet_moving(&f, 0, tenth, &r10, &o10, &c10) < 0)
        goto cleanup;
    put_move(pl, STROKE_MM, 420.0);
    if (fleet_send(&f, 0, tenth, WSG_CMD_PREPOSITION, pl, sizeof pl) < 0 ||
        fleet_wait(&f, 0, tenth, &moved, 1, MOTION_MS) < 0)
        goto cleanup;
    if (fleet_moving(&f, 0, f.n, &ra, &oa, &ca) < 0)
        goto cleanup;
    rc = 0;
cleanup:
    /* No 07h to a thousand connections: the emulator is stopped first, so
     * FAST STOP on close does not matter. */
    if (started && server_stop(&f.s) < 0)
        rc = -1;
    for (i = 0; f.l && i < f.n; i++)
        if (f.l[i].c.fd >= 0)
            close(f.l[i].c.fd);
    wsg_client_close(&f.ctl.c);
    if (f.epfd >= 0)
        close(f.epfd);
rows:
    snprintf(label, sizeof label, "fleet %ld: idle wakes/s", f.n);
    r = add_row(b, label, iw, NOT_APPLIED, 2);
    set_target(r, T_LT, 1, 0, "< 1");
    snprintf(label, sizeof label, "fleet %ld: idle CPU %% of one core", f.n);
    r = add_row(b, label, ic, NOT_APPLIED, 1);
    set_target(r, T_LT, 1, 0, "< 1");
    snprintf(label, sizeof label, "fleet %ld: RSS (MiB)", f.n);
    r = add_row(b, label, rss, NOT_APPLIED, 2);
    set_target(r, T_LT, 64, 0, "< 64");
    snprintf(label, sizeof label, "fleet %ld: homing all (s)", f.n);
    add_row(b, label, home_s, NOT_APPLIED, 2);
    snprintf(label, sizeof label, "fleet %ld/%ld moving: CPU %%", tenth, f.n);
    add_row(b, label, c10, NOT_APPLIED, 1);
    snprintf(label, sizeof label, "fleet %ld/%ld moving: steps/s", tenth, f.n);
    r = add_row(b, label, r10, NOT_APPLIED, 0);
    set_target(r, T_NEAR, 1000, 0, "1000 +- 2%");
    r->tol = 20;
    snprintf(label, sizeof label, "fleet %ld/%ld moving: overruns", tenth,
             f.n);
    r = add_row(b, label, o10, NOT_APPLIED, 0);
    set_target(r, T_EQ, 0, 0, "0");
    snprintf(label, sizeof label, "fleet %ld/%ld moving: CPU %%", f.n, f.n);
    add_row(b, label, ca, NOT_APPLIED, 1);
    snprintf(label, sizeof label, "fleet %ld/%ld moving: steps/s", f.n, f.n);
    r = add_row(b, label, ra, NOT_APPLIED, 0);
    set_target(r, T_NEAR, 1000, 0, "1000 +- 2%");
    r->tol = 20;
    snprintf(label, sizeof label, "fleet %ld/%ld moving: overruns", f.n, f.n);
    r = add_row(b, label, oa, NOT_APPLIED, 0);
    set_target(r, T_EQ, 0, 0, "0");
    snprintf(label, sizeof label, "fleet CPU all / CPU %ld moving", tenth);
    add_row(b, label, c10 > 0 ? ca / c10 : NAN, NOT_APPLIED, 1);
    free(tcp);
    free(c);
    free(f.l);
    free(f.got);
    return rc;
}

/* ---- the table ---- */

static void fmt_value(char *buf, size_t cap, double v, int decimals)
{
    if (v == NOT_APPLIED)
        snprintf(buf, cap, "-");
    else if (isnan(v))
        snprintf(buf, cap, "n/a");
    else
        snprintf(buf, cap, "%.*f", decimals, v);
}

static void print_table(const struct bench *b)
{
    if (b->attach && b->pid[EMU] > 0)
        printf("wsgbench %s: attached wsgemu (pid %d) vs wsgref", WSG_VERSION,
               (int)b->pid[EMU]);
    else if (b->attach)
        printf("wsgbench %s: attached wsgemu vs wsgref", WSG_VERSION);
    else
        printf("wsgbench: wsgemu %s vs wsgref", WSG_VERSION);
    printf(", %ld samples, %d CPU%s", b->o.samples, b->ncpu,
           b->ncpu == 1 ? "" : "s");
    if (b->cpu_bench >= 0 && b->attach)
        printf(" (reference%s on CPU %d, bench on CPU %d; the attached "
               "emulator is not pinned)",
               b->o.fleet > 0 ? " and fleet" : "", b->cpu_server,
               b->cpu_bench);
    else if (b->cpu_bench >= 0)
        printf(" (servers on CPU %d, bench on CPU %d)", b->cpu_server,
               b->cpu_bench);
    else if (b->attach)
        printf(" (nothing pinned)");
    printf("\n%-36s %10s %10s %7s  %s\n", "figure", "emulator", "reference",
           "ratio", "target");
    for (int i = 0; i < b->nrows; i++) {
        const struct row *r = &b->rows[i];
        char e[24], f[24], q[24];
        double ratio = NAN, v;
        const char *mark = "";

        fmt_value(e, sizeof e, r->emu, r->decimals);
        fmt_value(f, sizeof f, r->ref, r->decimals);
        if (r->ref == NOT_APPLIED) {
            snprintf(q, sizeof q, "-");
        } else {
            if (!isnan(r->emu) && !isnan(r->ref) && r->ref > 0)
                ratio = r->emu / r->ref;
            /* 0 against 0 (idle) has no ratio, but is no failure. */
            fmt_value(q, sizeof q, r->ref == 0 ? NOT_APPLIED : ratio, 2);
        }
        v = r->on_ratio ? ratio : r->emu;
        if (r->tk != T_NONE) {
            int ok = r->tk == T_LT   ? v < r->tv
                     : r->tk == T_LE ? v <= r->tv
                     : r->tk == T_GE ? v >= r->tv
                     : r->tk == T_EQ ? v == r->tv
                                     : fabs(v - r->tv) <= r->tol;
            mark = isnan(v) ? "n/a" : ok ? "ok" : "MISSED";
        }
        if (*mark)
            printf("%-36s %10s %10s %7s  %-13s %s\n", r->label, e, f, q,
                   r->ttext, mark);
        else
            printf("%-36s %10s %10s %7s\n", r->label, e, f, q);
    }
    fflush(stdout);
}

/* ---- setup ---- */

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
        "  --quick                1000 samples, 0.5 s throughput, 2 s "
        "jitter,\n"
        "                         1 s idle, 1 s moving, fleet of 20 (options\n"
        "                         given explicitly still win)\n"
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
        "\n"
        "Both servers run on one CPU and the bench on another when there\n"
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
        "their own wsgemu --grippers N (--emu), skipped when there is none.\n",
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
        {"quick", no_argument, NULL, 'q'},
        {"help", no_argument, NULL, 'h'},
        {NULL, 0, NULL, 0}};
    double v;
    int c;

    /* -1: not given; the defaults depend on --quick. */
    o->samples = o->inflight = o->fleet = o->pid = -1;
    o->tput_s = o->jitter_s = o->idle_s = o->move_s = -1;
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
            if (parse_num(optarg, c == 'm' ? 0.2 : 0.1, 3600, &v) < 0) {
                msg("not a number of seconds in range: \"%s\"", optarg);
                return -1;
            }
            *(c == 't'   ? &o->tput_s
              : c == 'j' ? &o->jitter_s
              : c == 'i' ? &o->idle_s
                         : &o->move_s) = v;
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
        /* Attached, only the fleet rows start one. */
        if (b->attach && !b->o.emu) {
            if (b->o.fleet > 0)
                msg("cannot run %s: %s: fleet rows skipped (give --emu "
                    "PATH)",
                    b->emu_exe, strerror(errno));
            b->o.fleet = 0;
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
    if (b.o.fleet > 0 && bench_fleet(&b) < 0)
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
