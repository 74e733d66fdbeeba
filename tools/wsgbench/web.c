/*
 * wsgbench's web rows: does a browser watching the web page slow the
 * gripper's interfaces? One wsgemu --web, 43h round trips over TCP in
 * alternating rounds without and with a watcher: a child process that
 * holds the page's event stream (/events) open and reads everything it is
 * sent, as a browser's page does. With it, every packet is also formatted
 * as a log line and pushed (with the state) at up to 20 Hz. The rows'
 * reference column is the same daemon's 43h with no page open; the median
 * may not grow by more than a quarter.
 */
#define _GNU_SOURCE /* sched_setaffinity, pipe2, prctl, strndup */

#include "wsgbench.h"

#include <arpa/inet.h>
#include <errno.h>
#include <netinet/in.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#define WEB_ALONE   0 /* the samples with no page open */
#define WEB_WATCHED 1 /* those with a page watching */

/* A process that reads the event stream until it is killed; its pid, or
 * -1. It reports once that the stream's head came (a byte on ready), so
 * the round starts with the watcher in place. */
static pid_t watcher_start(const struct sockaddr_in *sa, const char *addr)
{
    char req[256], buf[4096];
    int ready[2], fd;
    pid_t pid;
    ssize_t n;

    if (pipe(ready) < 0)
        return -1;
    pid = fork();
    if (pid < 0) {
        close(ready[0]);
        close(ready[1]);
        return -1;
    }
    if (pid == 0) {
        close(ready[0]);
        fd = socket(AF_INET, SOCK_STREAM, 0);
        if (fd < 0 || connect(fd, (const struct sockaddr *)sa, sizeof *sa) < 0)
            _exit(1);
        n = snprintf(req, sizeof req,
                     "GET /events HTTP/1.1\r\nHost: %s\r\n"
                     "Accept: text/event-stream\r\n\r\n",
                     addr);
        if (write(fd, req, (size_t)n) != n)
            _exit(1);
        n = read(fd, buf, sizeof buf);
        if (n <= 0 || write(ready[1], "r", 1) != 1)
            _exit(1);
        close(ready[1]);
        while (read(fd, buf, sizeof buf) > 0)
            ;
        _exit(0);
    }
    close(ready[1]);
    n = read(ready[0], buf, 1);
    close(ready[0]);
    if (n != 1) {
        kill(pid, SIGKILL);
        waitpid(pid, NULL, 0);
        return -1;
    }
    return pid;
}

static void watcher_stop(pid_t pid)
{
    if (pid <= 0)
        return;
    kill(pid, SIGKILL);
    waitpid(pid, NULL, 0);
}

/* The two sides: one connection's 43h, with the watcher running while
 * the watched side's rounds last. */
struct web_bench {
    struct link l;
    struct sockaddr_in web;
    const char *addr;
    pid_t watcher;
};

static int web_take(void *ctx, int side, double *us)
{
    (void)side;
    return sample(&((struct web_bench *)ctx)->l, us);
}

static int web_turn(void *ctx, int side, int on)
{
    struct web_bench *wb = ctx;

    if (side != WEB_WATCHED)
        return 0;
    if (!on) {
        watcher_stop(wb->watcher);
        wb->watcher = -1;
        return 0;
    }
    wb->watcher = watcher_start(&wb->web, wb->addr);
    if (wb->watcher < 0) {
        msg("wsgemu --web: the watcher could not open /events");
        return -1;
    }
    return 0;
}

int bench_web(struct bench *b)
{
    char *argv[] = {b->emu_exe, "--tcp",       "127.0.0.1:0",
                    "--web",    "127.0.0.1:0", NULL};
    struct dist dd[2] = {{NAN, NAN, NAN}, {NAN, NAN, NAN}};
    struct web_bench wb;
    struct sockaddr_in tcp;
    struct server srv;
    char *v = NULL, *w = NULL;
    int started = 0, rc = -1;
    struct row *r;

    link_init(&wb.l, L_TCP, "wsgemu --web");
    wb.watcher = -1;
    if (server_start(b, &srv, "wsgemu --web", argv, READY_MS) < 0)
        goto cleanup;
    started = 1;
    v = field(srv.line, "tcp");
    w = field(srv.line, "web");
    if (!v || !w) {
        msg("wsgemu --web: no tcp= or web= in its ready line");
        goto cleanup;
    }
    wb.addr = w;
    if (parse_ipport(v, &tcp) < 0 || parse_ipport(w, &wb.web) < 0 ||
        link_tcp(&wb.l, &tcp) < 0)
        goto cleanup;
    rc = alternate(b, web_take, web_turn, &wb, dd);
cleanup:
    watcher_stop(wb.watcher);
    link_close(&wb.l);
    if (started && server_stop(&srv) < 0)
        rc = -1;
    r = add_row(b, "43h median, page watching (us)", dd[WEB_WATCHED].p50,
                dd[WEB_ALONE].p50, 1);
    set_target(r, T_LE, 1.25, 1, "ratio <= 1.25");
    add_row(b, "43h p99, page watching (us)", dd[WEB_WATCHED].p99,
            dd[WEB_ALONE].p99, 1);
    free(v);
    free(w);
    return rc;
}
