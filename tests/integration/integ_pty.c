/*
 * integ_pty: what is particular to the serial interface (--pty PATH).
 *
 * - the ready line reads pty=PATH, the path as given, and PATH is a
 *   symlink to a /dev/pts/N; a stale symlink is replaced, anything else at
 *   PATH is refused with exit status 1 and a message (and left alone);
 * - requests and replies over the port (Loop, Get Opening Width), homing
 *   answered E_CMD_PENDING then E_SUCCESS, 07h E_NOT_AVAILABLE (a serial
 *   line has no connection to announce the end of);
 * - a driver that closes the port and opens it again keeps working, every
 *   time; a close is no disconnect: no FAST STOP, not even in a motion;
 * - nobody having the port open (never opened, or closed) costs no CPU
 *   and no wake-ups, nor does a driver that has it open and is quiet;
 * - a driver with 8N2 and VMIN=0/VTIME=5 that reads byte by byte works;
 * - an auto-update stream runs on across a close; after reopening, the
 *   first bytes are a packet's preamble, never the rest of a packet cut at
 *   the close;
 * - a driver that does not read costs whole packets beyond the output
 *   bound, never a broken one, and the port works on;
 * - SIGTERM exits 0 and removes the link;
 * - --pty-mode sets the slave's permissions, --pty-group its group (as
 *   root, to dialout where it exists); a bad mode or an unknown group is
 *   refused with status 2 and a message.
 */
#define _GNU_SOURCE /* cfmakeraw, cfsetspeed */

#include "check.h"
#include "emu.h"
#include "wsg/axis.h"

#include <errno.h>
#include <fcntl.h>
#include <grp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <termios.h>
#include <unistd.h>

/* The link path from the ready line. */
static const char *pty_path(const struct emu *e, char *buf, size_t cap)
{
    const char *p = emu_field(e, "pty", buf, cap);

    REQUIRE(p != NULL);
    return p;
}

/* Nobody has the port open: over a second the daemon is scheduled a
 * handful of times at most (a master polling HUP in the epoll set would
 * make it spin) and uses no CPU time worth a tick. */
static void check_idle(const struct emu *e, const char *when)
{
    long sw0, sw1, t0, t1;

    emu_sleep_ms(100);
    REQUIRE(emu_proc_activity(e->pid, &sw0, &t0) == 0);
    emu_sleep_ms(1000);
    REQUIRE(emu_proc_activity(e->pid, &sw1, &t1) == 0);
    printf("idle (%s): %ld switches, %ld ticks in 1 s\n", when, sw1 - sw0,
           t1 - t0);
    CHECK(sw1 - sw0 <= 5);
    CHECK(t1 - t0 <= 2);
}

/* The length of the packet at buf (n bytes there): 0 if the preamble or
 * the checksum is wrong, -1 if it is not complete. */
static long packet_at(const uint8_t *buf, size_t n)
{
    size_t len;

    if (n < WSG_HEADER_LEN)
        return -1;
    if (buf[0] != 0xAA || buf[1] != 0xAA || buf[2] != 0xAA)
        return 0;
    len = WSG_HEADER_LEN + wsg_get_u16(buf + 4) + WSG_CRC_LEN;
    if (n < len)
        return -1;
    return wsg_crc_update(WSG_CRC_INIT, buf, len) == 0 ? (long)len : 0;
}

/* buf holds whole packets back to back (a last one may be incomplete):
 * their number, or -1 at the first byte that does not start a good one. */
static long count_packets(const uint8_t *buf, size_t n, uint8_t id)
{
    size_t off = 0;
    long count = 0;

    while (off < n) {
        long len = packet_at(buf + off, n - off);

        if (len < 0)
            break;
        if (len == 0 || buf[off + 3] != id) {
            fprintf(stderr, "  not a %02Xh packet at byte %zu:", id, off);
            for (size_t i = off; i < n && i < off + 16; i++)
                fprintf(stderr, " %02X", buf[i]);
            fprintf(stderr, "\n");
            return -1;
        }
        off += (size_t)len;
        count++;
    }
    return count;
}

/* Everything that arrives within ms (raw reads). */
static size_t read_for(struct emu_client *c, uint8_t *buf, size_t cap, int ms)
{
    double deadline = emu_now_ms() + ms;
    size_t got = 0;

    while (got < cap) {
        int left = (int)(deadline - emu_now_ms());
        long n;

        if (left <= 0)
            break;
        n = emu_recv_raw(c, buf + got, cap - got, left);
        if (n <= 0)
            break;
        got += (size_t)n;
    }
    return got;
}

/* Everything until the line has been quiet for quiet_ms. */
static size_t read_until_quiet(struct emu_client *c, uint8_t *buf, size_t cap,
                               int quiet_ms)
{
    size_t got = 0;

    while (got < cap) {
        /* The first bytes may be long in coming on a loaded machine (or
         * under valgrind): that wait is a bound like any reply's. Once
         * they flow, a quiet spell means the end. */
        long n = emu_recv_raw(c, buf + got, cap - got,
                              got ? quiet_ms : EMU_REPLY_MS);

        if (n <= 0)
            break;
        got += (size_t)n;
    }
    return got;
}

static void test_ready_line(struct emu *e)
{
    char v[256], target[256];
    struct stat st;
    ssize_t n;

    printf("ready line: \"%s\"\n", e->line);
    /* Only the interface asked for, and the path exactly as given. */
    CHECK(strncmp(e->line, "ready pty=", 10) == 0);
    CHECK(strchr(e->line + 6, ' ') == NULL);
    pty_path(e, v, sizeof v);
    CHECK(strcmp(v, e->tp_arg[0]) == 0);
    REQUIRE(lstat(v, &st) == 0);
    CHECK(S_ISLNK(st.st_mode));
    n = readlink(v, target, sizeof target - 1);
    REQUIRE(n > 0);
    target[n] = '\0';
    printf("%s -> %s\n", v, target);
    CHECK(strncmp(target, "/dev/pts/", 9) == 0);
    REQUIRE(stat(v, &st) == 0);
    CHECK(S_ISCHR(st.st_mode));
}

static void test_round_trip(struct emu *e)
{
    struct emu_client c;
    struct wsg_client_frame f;
    float w = -1;

    REQUIRE(emu_open(&c, e, &emu_pty) == 0);
    CHECK_EQ(emu_request(&c, WSG_CMD_LOOP, "serial", 6, &f, EMU_REPLY_MS),
             WSG_E_SUCCESS);
    CHECK(f.len == 8 && memcmp(EMU_PARAMS(&f), "serial", 6) == 0);
    /* Power-up: the fingers at half the stroke. */
    CHECK_EQ(emu_get_float(&c, WSG_CMD_GET_WIDTH, &w), 0);
    CHECK_NEAR(w, 55.0, 0.01);
    CHECK_EQ(c.link.bad, 0);
    emu_close(&c);
}

/* Open and quiet: the master sits in the epoll set and wakes nobody. */
static void test_idle_open(struct emu *e)
{
    struct emu_client c;

    REQUIRE(emu_open(&c, e, &emu_pty) == 0);
    CHECK_EQ(emu_request(&c, WSG_CMD_LOOP, "q", 1, NULL, EMU_REPLY_MS),
             WSG_E_SUCCESS);
    check_idle(e, "open, quiet");
    emu_close(&c);
}

static void test_homing(struct emu *e)
{
    struct emu_client c;
    uint8_t dir = 0;
    int immediate = -1;

    REQUIRE(emu_open(&c, e, &emu_pty) == 0);
    CHECK_EQ(
        emu_motion(&c, WSG_CMD_HOMING, &dir, 1, EMU_HOMING_MS, &immediate),
        WSG_E_SUCCESS);
    CHECK_EQ(immediate, WSG_E_CMD_PENDING);
    /* No connection to announce the end of. */
    CHECK_EQ(emu_request(&c, WSG_CMD_DISCONNECT, NULL, 0, NULL, EMU_REPLY_MS),
             WSG_E_NOT_AVAILABLE);
    /* And it changed nothing: commands are still served. */
    CHECK_EQ(emu_request(&c, WSG_CMD_LOOP, "on", 2, NULL, EMU_REPLY_MS),
             WSG_E_SUCCESS);
    emu_close(&c);
}

/* Close and reopen, several times: each opener is served, and a close (even
 * in a motion) is no disconnect. Expects the gripper referenced. */
static void test_reopen(struct emu *e)
{
    struct emu_client c;
    struct wsg_client_frame f;
    uint8_t p[16];
    uint32_t flags = 0;
    float w = 0;
    char tok[8];

    for (int i = 0; i < 5; i++) {
        REQUIRE(emu_open(&c, e, &emu_pty) == 0);
        snprintf(tok, sizeof tok, "open%d", i);
        CHECK_EQ(
            emu_request(&c, WSG_CMD_LOOP, tok, strlen(tok), &f, EMU_REPLY_MS),
            WSG_E_SUCCESS);
        CHECK(f.len == 2 + strlen(tok) &&
              memcmp(EMU_PARAMS(&f), tok, strlen(tok)) == 0);
        CHECK_EQ(emu_get_flags(&c, &flags), 0);
        CHECK_EQ(flags & WSG_SF_FAST_STOP, 0);
        CHECK_EQ(c.link.bad, 0);
        emu_close(&c);
    }

    /* Closed in the middle of a motion: the motion goes on to its end. */
    REQUIRE(emu_open(&c, e, &emu_pty) == 0);
    size_t n = emu_move_payload(p, 0, 20.0f, 100.0f);
    CHECK_EQ(emu_request(&c, WSG_CMD_PREPOSITION, p, n, NULL, EMU_REPLY_MS),
             WSG_E_CMD_PENDING);
    emu_close(&c);
    emu_sleep_ms(50);
    REQUIRE(emu_open(&c, e, &emu_pty) == 0);
    CHECK_EQ(emu_get_flags(&c, &flags), 0);
    CHECK_EQ(flags & WSG_SF_FAST_STOP, 0);
    CHECK_EQ(
        emu_wait_float(&c, WSG_CMD_GET_WIDTH, 19.99f, 20.01f, EMU_MOVE_MS, &w),
        0);
    CHECK_EQ(emu_wait_flags(&c, WSG_SF_MOVING | WSG_SF_FAST_STOP, 0,
                            EMU_MOVE_MS, &flags),
             0);
    emu_close(&c);
}

/* A driver that sets 8N2 and a read timeout (VMIN 0, VTIME 5: a read
 * returns what is there, or 0 bytes after 0.5 s) and reads byte by byte. */
static void test_8n2_byte_reads(struct emu *e)
{
    char path[256];
    struct termios tio;
    struct wsg_client_frame f;
    uint8_t req[64], buf[64];
    double t0, dt;
    size_t n, got;
    int fd, zeros;
    ssize_t r;

    pty_path(e, path, sizeof path);
    fd = open(path, O_RDWR | O_NOCTTY | O_CLOEXEC);
    REQUIRE(fd >= 0);
    REQUIRE(tcgetattr(fd, &tio) == 0);
    cfmakeraw(&tio);
    tio.c_cflag &= ~(tcflag_t)(CSIZE | PARENB);
    tio.c_cflag |= CS8 | CSTOPB | CLOCAL | CREAD;
    tio.c_cc[VMIN] = 0;
    tio.c_cc[VTIME] = 5;
    cfsetspeed(&tio, B115200);
    REQUIRE(tcsetattr(fd, TCSANOW, &tio) == 0);

    /* Nothing to read: the read times out with 0 bytes. */
    t0 = emu_now_ms();
    r = read(fd, buf, 1);
    dt = emu_now_ms() - t0;
    CHECK_EQ(r, 0);
    /* The terminal's 0.5 s, give or take the scheduler: the upper bound
     * only stops a read that does not time out at all. */
    CHECK(dt >= 300 && dt <= emu_ms(2000));

    static const struct {
        uint8_t id;
        const char *payload;
        size_t params; /* after the status */
    } reqs[] = {{WSG_CMD_LOOP, "8N2", 3},
                {WSG_CMD_GET_SYSTEM_STATE, NULL, 4},
                {WSG_CMD_GET_WIDTH, NULL, 4}};
    for (size_t i = 0; i < sizeof reqs / sizeof reqs[0]; i++) {
        size_t plen = reqs[i].payload ? strlen(reqs[i].payload) : 0;
        size_t want = WSG_HEADER_LEN + 2 + reqs[i].params + WSG_CRC_LEN;

        n = wsg_frame_encode(req, sizeof req, reqs[i].id,
                             (const uint8_t *)reqs[i].payload, plen);
        REQUIRE(n > 0);
        REQUIRE(write(fd, req, n) == (ssize_t)n);
        /* One byte per read; timeouts (0.5 s each) are allowed for 2 s, a
         * bound on the reply's delay, not a hang. */
        got = 0;
        zeros = 0;
        while (got < want && zeros < emu_ms(2000) / 500) {
            r = read(fd, buf + got, 1);
            if (r == 1)
                got++;
            else if (r == 0)
                zeros++;
            else if (errno != EINTR)
                break;
        }
        CHECK_EQ(got, want);
        CHECK(got == want && emu_packet_decode(buf, got, &f) == 0);
        CHECK_EQ(f.id, reqs[i].id);
        CHECK_EQ(f.status, WSG_E_SUCCESS);
        if (reqs[i].payload)
            CHECK(memcmp(EMU_PARAMS(&f), reqs[i].payload, plen) == 0);
    }
    /* Nothing more came. */
    CHECK_EQ(read(fd, buf, 1), 0);
    close(fd);
}

/* Subscribe 43h every 20 ms, read part of a packet, close; the stream goes
 * on while the port is closed; after reopening, the first bytes start a
 * packet and the stream is still there. */
static void test_stream_reopen(struct emu *e)
{
    struct emu_client c;
    struct wsg_client_frame f;
    uint8_t sub[3] = {0x01, 20, 0}; /* auto update, 20 ms */
    uint8_t buf[4096];
    unsigned before;
    size_t got;
    long count;

    REQUIRE(emu_open(&c, e, &emu_pty) == 0);
    CHECK_EQ(
        emu_request(&c, WSG_CMD_GET_WIDTH, sub, sizeof sub, &f, EMU_REPLY_MS),
        WSG_E_SUCCESS);
    before = c.link.seen[WSG_CMD_GET_WIDTH];
    got = 0;
    while (emu_recv_id(&c, WSG_CMD_GET_WIDTH, &f, emu_ms(600)) == 1 &&
           c.link.seen[WSG_CMD_GET_WIDTH] - before < 20)
        got++;
    printf("stream: %zu packets\n", got);
    CHECK(got >= 15);

    for (int round = 0; round < 3; round++) {
        /* Let packets pile up unread, take 5 bytes (a packet cut in two),
         * close. */
        emu_sleep_ms(100);
        CHECK_EQ(read(c.fd, buf, 5), 5);
        emu_close(&c);
        emu_sleep_ms(150);

        REQUIRE(emu_open(&c, e, &emu_pty) == 0);
        /* At a large scale the window may fill buf (292 packets of 43h):
         * read_for stops there, with more than enough to count. */
        got = read_for(&c, buf, sizeof buf, emu_ms(400));
        printf("after reopen %d: %zu bytes, first %02X %02X %02X\n", round,
               got, got > 0 ? buf[0] : 0, got > 1 ? buf[1] : 0,
               got > 2 ? buf[2] : 0);
        REQUIRE(got >= 3);
        CHECK(buf[0] == 0xAA && buf[1] == 0xAA && buf[2] == 0xAA);
        count = count_packets(buf, got, WSG_CMD_GET_WIDTH);
        /* About 20 in 400 ms (and more in a scaled window): the stream
         * runs on. */
        CHECK(count >= 10);
    }

    /* End it: after the barrier, silence. */
    sub[0] = 0;
    REQUIRE(emu_send(&c, WSG_CMD_GET_WIDTH, sub, sizeof sub) == 0);
    REQUIRE(emu_sync(&c, EMU_REPLY_MS) == 0);
    emu_drop_kept(&c);
    CHECK_EQ(emu_recv(&c, &f, EMU_QUIET_MS), 0);
    emu_close(&c);
}

/* A driver that keeps the port open and does not read: its requests are
 * still served; what the terminal and the emulator's queue cannot hold is
 * lost in whole packets; once it reads, it gets whole packets in order,
 * and the port works on. */
static void test_not_reading(struct emu *e)
{
    enum { NREQ = 600, PLEN = 250 };
    struct emu_client c;
    static uint8_t in[NREQ * (WSG_HEADER_LEN + 2 + PLEN + WSG_CRC_LEN)];
    uint8_t p[PLEN];
    size_t got, off = 0;
    long count = 0, last = -1, order_ok = 1;

    REQUIRE(emu_open(&c, e, &emu_pty) == 0);
    memset(p, 0x5A, sizeof p);
    for (int i = 0; i < NREQ; i++) {
        wsg_put_u16(p, (uint16_t)i);
        REQUIRE(emu_send(&c, WSG_CMD_LOOP, p, sizeof p) == 0);
    }
    /* Time for the daemon to read every request (and to drop what it
     * cannot queue), before this end reads and makes room. */
    emu_sleep_ms(emu_ms(300));
    got = read_until_quiet(&c, in, sizeof in, EMU_QUIET_MS);
    while (off < got) {
        long len = packet_at(in + off, got - off);
        long seq;

        if (len <= 0)
            break;
        seq = wsg_get_u16(in + off + WSG_HEADER_LEN + 2);
        if (in[off + 3] != WSG_CMD_LOOP || seq <= last)
            order_ok = 0;
        last = seq;
        off += (size_t)len;
        count++;
    }
    printf("not reading: %d requests, %zu bytes, %ld whole replies\n", NREQ,
           got, count);
    CHECK_EQ(off, got);
    CHECK(order_ok);
    CHECK(count > 200 && count < NREQ);
    CHECK_EQ(emu_request(&c, WSG_CMD_LOOP, "after", 5, NULL, EMU_REPLY_MS),
             WSG_E_SUCCESS);
    emu_close(&c);
}

static void test_sigterm(const char *exe)
{
    struct emu e;
    struct emu_client c;
    struct wsg_client_frame f;
    char path[256];
    struct stat st;

    REQUIRE(emu_start_tp(&e, exe, &emu_pty, NULL) == 0);
    pty_path(&e, path, sizeof path);
    REQUIRE(emu_open(&c, &e, &emu_pty) == 0);
    CHECK_EQ(emu_request(&c, WSG_CMD_LOOP, "t", 1, NULL, EMU_REPLY_MS),
             WSG_E_SUCCESS);
    /* With the port open. */
    CHECK_EQ(emu_stop(&e), 0);
    CHECK(lstat(path, &st) < 0 && errno == ENOENT);
    /* The line is gone. */
    CHECK_EQ(emu_recv(&c, &f, EMU_REPLY_MS), -1);
    emu_close(&c);
}

/* What is at PATH already: a symlink (a previous run's) is replaced, a
 * regular file is not touched. */
static void test_path_taken(const char *exe)
{
    struct emu scratch, e;
    const char *path;
    const char *args[3];
    char out[512], err[512], target[64];
    struct stat st;
    ssize_t n;
    int fd, status;

    memset(&scratch, 0, sizeof scratch);
    REQUIRE(emu_pty.daemon_args(&scratch) == 0);
    path = scratch.tp_arg[0];

    /* A dangling symlink, as a killed emulator leaves behind. */
    REQUIRE(symlink("/nonexistent/pts/99", path) == 0);
    REQUIRE(emu_start(&e, exe, scratch.tp_argv) == 0);
    n = readlink(path, target, sizeof target - 1);
    REQUIRE(n > 0);
    target[n] = '\0';
    CHECK(strncmp(target, "/dev/pts/", 9) == 0);
    CHECK_EQ(emu_stop(&e), 0);
    CHECK(lstat(path, &st) < 0 && errno == ENOENT);

    /* A regular file. */
    fd = open(path, O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0600);
    REQUIRE(fd >= 0);
    REQUIRE(write(fd, "mine", 4) == 4);
    close(fd);
    status = emu_run(exe, scratch.tp_argv, emu_ms(5000), out, sizeof out, err,
                     sizeof err);
    printf("regular file at PATH: status %d, stderr \"%s\"\n", status, err);
    CHECK_EQ(status, 1);
    CHECK(strstr(err, path) != NULL);
    CHECK(strstr(err, "not a symlink") != NULL);
    CHECK(strstr(out, "ready") == NULL);
    CHECK(lstat(path, &st) == 0 && S_ISREG(st.st_mode) && st.st_size == 4);
    unlink(path);

    /* A directory that does not exist. */
    args[0] = "--pty";
    args[1] = "/nonexistent-wsgemu-dir/ttyWSG0";
    args[2] = NULL;
    status =
        emu_run(exe, args, emu_ms(5000), out, sizeof out, err, sizeof err);
    printf("missing directory: status %d, stderr \"%s\"\n", status, err);
    CHECK_EQ(status, 1);
    CHECK(strstr(err, args[1]) != NULL);
}

static void test_mode_group(const char *exe)
{
    const char *tmp = getenv("TMPDIR");
    char path[256], out[512], err[512], gid[32];
    const char *args[] = {"--pty", path, "--pty-mode", "0660",
                          NULL,    NULL, NULL};
    struct group *dialout = geteuid() == 0 ? getgrnam("dialout") : NULL;
    struct stat st;
    struct emu e;
    int status;

    snprintf(path, sizeof path, "%s/wsgemu-pty-mode-%ld", tmp ? tmp : "/tmp",
             (long)getpid());
    if (dialout) {
        args[4] = "--pty-group";
        args[5] = "dialout";
    } else {
        printf("not root or no group dialout: --pty-group not checked\n");
    }
    REQUIRE(emu_start(&e, exe, args) == 0);
    CHECK_EQ(stat(path, &st), 0); /* the slave, through the link */
    CHECK_EQ(st.st_mode & 07777, 0660);
    if (dialout)
        CHECK_EQ(st.st_gid, dialout->gr_gid);
    CHECK_EQ(emu_stop(&e), 0);

    /* Refused before anything opens: status 2, the value named. */
    args[3] = "0999";
    args[4] = NULL;
    status =
        emu_run(exe, args, emu_ms(5000), out, sizeof out, err, sizeof err);
    printf("--pty-mode 0999: status %d, stderr \"%s\"\n", status, err);
    CHECK_EQ(status, 2);
    CHECK(strstr(err, "0999") != NULL);
    args[2] = "--pty-group";
    args[3] = "no-such-group-wsgemu";
    status =
        emu_run(exe, args, emu_ms(5000), out, sizeof out, err, sizeof err);
    printf("--pty-group unknown: status %d, stderr \"%s\"\n", status, err);
    CHECK_EQ(status, 2);
    CHECK(strstr(err, "no-such-group-wsgemu") != NULL);
    /* A GID in decimal is taken as it is. */
    snprintf(gid, sizeof gid, "%ld", (long)getegid());
    args[3] = gid;
    REQUIRE(emu_start(&e, exe, args) == 0);
    CHECK(stat(path, &st) == 0 && st.st_gid == getegid());
    CHECK_EQ(emu_stop(&e), 0);
}

int main(int argc, char **argv)
{
    const char *exe = emu_exe(argc, argv);
    struct emu e;

    REQUIRE(emu_start_tp(&e, exe, &emu_pty, NULL) == 0);
    test_ready_line(&e);
    check_idle(&e, "never opened");
    test_round_trip(&e);
    test_idle_open(&e);
    test_homing(&e);
    test_reopen(&e);
    check_idle(&e, "closed");
    test_8n2_byte_reads(&e);
    test_stream_reopen(&e);
    test_not_reading(&e);
    CHECK_EQ(emu_stop(&e), 0);

    test_sigterm(exe);
    test_path_taken(exe);
    test_mode_group(exe);
    TEST_EXIT();
}
