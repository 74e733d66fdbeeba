/*
 * integ_notify: the daemon as a systemd Type=notify service. With
 * $NOTIFY_SOCKET naming a datagram socket (a path, or an abstract name
 * written with a leading '@'), it sends
 * - "READY=1" with "STATUS=" and the ready line, after that line is on
 *   stdout: whoever waits for either may rely on both;
 * - "STOPPING=1" when SIGTERM ends it, before it exits with status 0.
 * A $NOTIFY_SOCKET it cannot use costs a warning, not the service.
 */
#define _GNU_SOURCE

#include "check.h"
#include "emu.h"

#include <errno.h>
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

/* One datagram from fd within timeout_ms into buf (NUL-terminated);
 * its length, or -1 when none came. */
static ssize_t recv_msg(int fd, char *buf, size_t cap, int timeout_ms)
{
    struct pollfd p = {.fd = fd, .events = POLLIN};
    ssize_t n;

    if (poll(&p, 1, timeout_ms) != 1)
        return -1;
    n = recv(fd, buf, cap - 1, 0);
    if (n >= 0)
        buf[n] = '\0';
    return n;
}

/* Wait up to timeout_ms for pid's exit: its status, 128+N for signal N,
 * -1 (then killed) when it does not end. */
static int wait_exit(pid_t pid, int timeout_ms)
{
    struct timespec ts = {0, 10 * 1000000L};
    int st, i;

    for (i = 0; i < timeout_ms / 10; i++) {
        pid_t r = waitpid(pid, &st, WNOHANG);

        if (r == pid)
            return WIFEXITED(st) ? WEXITSTATUS(st) : 128 + WTERMSIG(st);
        nanosleep(&ts, NULL);
    }
    kill(pid, SIGKILL);
    waitpid(pid, &st, 0);
    return -1;
}

/* The daemon on a free TCP port, told of the socket at name. */
static void run_notified(const char *exe, const char *name,
                         const struct sockaddr_un *sa, socklen_t salen)
{
    char msg[4096], line[2048];
    struct pollfd p;
    size_t n = 0;
    int fd, out[2];
    pid_t pid;

    printf("NOTIFY_SOCKET=%s\n", name);
    fd = socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
    REQUIRE(fd >= 0);
    REQUIRE(bind(fd, (const struct sockaddr *)sa, salen) == 0);
    REQUIRE(pipe2(out, O_CLOEXEC) == 0);
    pid = fork();
    REQUIRE(pid >= 0);
    if (pid == 0) {
        char *argv[] = {(char *)exe, "--tcp", "127.0.0.1:0", NULL};

        dup2(out[1], STDOUT_FILENO);
        setenv("NOTIFY_SOCKET", name, 1);
        execv(exe, argv);
        _exit(127);
    }
    close(out[1]);

    /* READY=1 first, read before the line: when it is here, the line must
     * be already (it is written and flushed before READY=1 is sent). */
    CHECK(recv_msg(fd, msg, sizeof msg, EMU_READY_MS) > 0);
    CHECK(strncmp(msg, "READY=1\n", 8) == 0);
    p.fd = out[0];
    p.events = POLLIN;
    CHECK(poll(&p, 1, 0) == 1);
    while (n < sizeof line - 1 && !memchr(line, '\n', n)) {
        ssize_t r;

        if (poll(&p, 1, EMU_REPLY_MS) != 1)
            break;
        r = read(out[0], line + n, sizeof line - 1 - n);
        if (r <= 0)
            break;
        n += (size_t)r;
    }
    line[n] = '\0';
    REQUIRE(n > 0 && line[n - 1] == '\n');
    line[n - 1] = '\0';
    printf("  %s\n", line);
    CHECK(strncmp(line, "ready tcp=127.0.0.1:", 20) == 0);
    /* The status is the ready line, whole. */
    {
        const char *st = strstr(msg, "\nSTATUS=");

        CHECK(st && strcmp(st + 8, line) == 0);
    }

    /* SIGTERM: STOPPING=1, then status 0. */
    REQUIRE(kill(pid, SIGTERM) == 0);
    CHECK(recv_msg(fd, msg, sizeof msg, EMU_EXIT_MS) > 0);
    CHECK(strcmp(msg, "STOPPING=1") == 0);
    CHECK_EQ(wait_exit(pid, EMU_EXIT_MS), 0);
    close(out[0]);
    close(fd);
}

int main(int argc, char **argv)
{
    const char *exe = emu_exe(argc, argv);
    char dir[] = "/tmp/wsgemu-notify.XXXXXX", name[128];
    struct sockaddr_un sa;
    struct emu e;
    size_t len;

    /* A socket in the file system, as systemd's /run/systemd/notify. */
    REQUIRE(mkdtemp(dir) != NULL);
    memset(&sa, 0, sizeof sa);
    sa.sun_family = AF_UNIX;
    snprintf(name, sizeof name, "%s/notify", dir);
    REQUIRE(strlen(name) < sizeof sa.sun_path);
    strcpy(sa.sun_path, name);
    run_notified(exe, name, &sa,
                 (socklen_t)(offsetof(struct sockaddr_un, sun_path) +
                             strlen(name) + 1));
    unlink(name);
    rmdir(dir);

    /* An abstract name: '@' for the leading NUL, no terminating NUL. */
    snprintf(name, sizeof name, "@wsgemu-notify-%ld", (long)getpid());
    len = strlen(name);
    memset(&sa, 0, sizeof sa);
    sa.sun_family = AF_UNIX;
    memcpy(sa.sun_path + 1, name + 1, len - 1);
    run_notified(exe, name, &sa,
                 (socklen_t)(offsetof(struct sockaddr_un, sun_path) + len));

    /* A name it cannot use (relative), or no one listening: it serves
     * all the same (emu_start waits for the ready line) and ends with 0. */
    printf("NOTIFY_SOCKET=relative, then a path no one listens on\n");
    {
        const char *const args[] = {"--tcp", "127.0.0.1:0", NULL};

        setenv("NOTIFY_SOCKET", "relative", 1);
        REQUIRE(emu_start(&e, exe, args) == 0);
        CHECK_EQ(emu_stop(&e), 0);
        setenv("NOTIFY_SOCKET", "/nonexistent/notify", 1);
        REQUIRE(emu_start(&e, exe, args) == 0);
        CHECK_EQ(emu_stop(&e), 0);
        unsetenv("NOTIFY_SOCKET");
    }
    TEST_EXIT();
}
