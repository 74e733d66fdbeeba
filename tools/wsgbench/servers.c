/*
 * wsgbench's servers: wsgemu and wsgref started as children (pinned to
 * the servers' CPU, never outliving the bench) up to their ready lines,
 * stopped with SIGTERM, stopped from the signal handler when the bench is
 * interrupted; the fields of a ready line; what --attach lacks; and the
 * servers' figures from /proc (context switches, CPU time, memory).
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

/* ---- servers ---- */

/* The servers running now and the bench's temporary directory, for the
 * SIGINT/SIGTERM handler: globals, since a handler gets nothing else. */
volatile pid_t live[LIVE_MAX];
char live_dir[64];
/* While an attached emulator runs at x100: its control channel and the
 * command that puts its time scale back. */
volatile int live_ctl = -1;
char live_restore[48];
volatile size_t live_restore_len;

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
void on_signal(int sig)
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

void pin(int cpu)
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
int server_start(struct bench *b, struct server *s, const char *name,
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
int server_stop(struct server *s)
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
char *field(const char *line, const char *name)
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

/* Connect l over TCP to the address of field key= ("tcp", "control") of
 * ready line line. 0, or -1 (reported). */
int link_ready(struct link *l, const char *line, const char *key)
{
    struct sockaddr_in sa;
    char *v = field(line, key);
    int rc = -1;

    if (!v)
        msg("no %s= in the ready line \"%.80s\"", key, line);
    else if (parse_ipport(v, &sa) == 0 && link_tcp(l, &sa) == 0)
        rc = 0;
    free(v);
    return rc;
}

/* d with nothing started yet (emud_stop() does nothing). */
void emud_init(struct emud *d, const char *name)
{
    link_init(&d->l, L_TCP, name);
    link_init(&d->ctl, L_TCP, name);
    d->started = 0;
}

/* Start d from argv (named name) and connect to its control channel and
 * TCP. 0, or -1 (reported); emud_stop() in either case. */

int emud_start(struct bench *b, struct emud *d, const char *name, char **argv)
{
    emud_init(d, name);
    if (server_start(b, &d->s, name, argv, READY_MS) < 0)
        return -1;
    d->started = 1;
    if (link_ready(&d->ctl, d->s.line, "control") < 0 ||
        link_ready(&d->l, d->s.line, "tcp") < 0)
        return -1;
    return 0;
}

/* Its connection closed (07h first), its control channel, the server. 0,
 * or -1 when it did not end as it should (reported). */
int emud_stop(struct emud *d)
{
    link_close(&d->l);
    wsg_client_close(&d->ctl.c);
    if (!d->started)
        return 0;
    d->started = 0;
    return server_stop(&d->s);
}

/* "A.B.C.D:PORT" (anything after the port is ignored: ">REMOTE"). */
int parse_ipport(const char *s, struct sockaddr_in *sa)
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
int attach_lacks(const struct bench *b, const char *key, const char *rows)
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
int attach_nopid(const struct bench *b, const char *what)
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
int proc_read(pid_t pid, struct proc_sample *s)
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

double wakes_per_s(const struct proc_sample *a, const struct proc_sample *b)
{
    return (double)(b->ctxt - a->ctxt) / ((double)(b->t_ns - a->t_ns) / 1e9);
}

double cpu_percent(const struct proc_sample *a, const struct proc_sample *b)
{
    return 100.0 * (double)(b->cpu_ns - a->cpu_ns) /
           (double)(b->t_ns - a->t_ns);
}

/* A "Key:  N kB" line of /proc/PID/status, in MiB; NAN if absent. */
double proc_mib(pid_t pid, const char *key)
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
