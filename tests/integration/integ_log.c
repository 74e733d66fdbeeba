/*
 * integ_log: the communication log (--log FILE) as a user reads it.
 *
 * A client sends a Homing (pending, then its final result), a Loop, an
 * unknown ID, a Loop with a bad checksum, a Get Opening Width, a Get System
 * Information, a Get System State and a Get Grasping Statistics with its
 * reset flag. The log must show one line per packet in each direction with
 * the peer, the command names, the status names of the replies and the
 * parameters decoded by the schema (the width as a float, flags and enums
 * with the manual's names); lines appear in the file while the daemon runs
 * (it flushes after each batch of events), and all of them after it
 * stopped. Without --log no file is written, and a log that cannot be
 * opened is an error at start.
 *
 * Events: connections opened and closed with and without 07h, a FAST STOP
 * by each of its causes (disconnect, 23h, a fault, a soft limit), the
 * acknowledges, and the control commands that changed the world each show
 * as an "event" line. On SIGHUP the daemon opens the file again at its
 * path: after a rename (logrotate), new lines go to a new file there.
 *
 * A size bound (--log-max): the file never passes it; at the bound it
 * moves to FILE.old and the newest lines go on in FILE, whole lines in
 * both; 0 is no bound.
 *
 * Signals from the very start: a SIGHUP sent while the daemon still reads
 * its options does not kill it (it reaches its ready line and serves), a
 * SIGTERM then ends it with status 0 rather than by the signal.
 */
/* mkdtemp, fdopen, kill */
#define _POSIX_C_SOURCE 200809L

#include "check.h"
#include "emu.h"
#include "emu_ctl.h"

#include <fcntl.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

static const char *exe;

/* The first line that contains every one of the (NULL-terminated) parts;
 * NULL if none does. The line is copied into out. */
static const char *find_line(const char *text, const char *const *parts,
                             char *out, size_t cap)
{
    const char *p = text;

    while (*p) {
        const char *end = strchr(p, '\n');
        size_t n = end ? (size_t)(end - p) : strlen(p);
        size_t i;
        int ok = 1;

        if (n < cap) {
            memcpy(out, p, n);
            out[n] = '\0';
            for (i = 0; parts[i] && ok; i++)
                ok = strstr(out, parts[i]) != NULL;
            if (ok)
                return out;
        }
        if (!end)
            break;
        p = end + 1;
    }
    return NULL;
}

static void expect(const char *text, const char *const *parts)
{
    char line[1024];

    if (find_line(text, parts, line, sizeof line)) {
        CHECK(1);
        return;
    }
    CHECK(!"a log line with these parts");
    for (size_t i = 0; parts[i]; i++)
        fprintf(stderr, "  part: \"%s\"\n", parts[i]);
}

static void test_log(const char *dir)
{
    char path[512], port[64], peer[80], text[65536];
    const char *args[] = {"--tcp", "127.0.0.1:0", "--log", path, NULL};
    struct emu e;
    struct emu_client c;
    struct wsg_client_frame f;
    uint8_t pkt[32], home = 0;
    size_t n;
    int imm = -1;

    snprintf(path, sizeof path, "%s/comm.log", dir);
    REQUIRE(emu_start(&e, exe, args) == 0);
    REQUIRE(emu_open(&c, &e, &emu_tcp) == 0);
    CHECK_EQ(emu_motion(&c, WSG_CMD_HOMING, &home, 1, emu_ms(10000), &imm),
             WSG_E_SUCCESS);
    CHECK_EQ(imm, WSG_E_CMD_PENDING);
    CHECK_EQ(emu_request(&c, WSG_CMD_LOOP, "abc", 3, NULL, EMU_REPLY_MS),
             WSG_E_SUCCESS);
    CHECK_EQ(emu_request(&c, 0x7F, NULL, 0, NULL, EMU_REPLY_MS),
             WSG_E_CMD_UNKNOWN);
    n = wsg_frame_encode(pkt, sizeof pkt, WSG_CMD_LOOP, (const uint8_t *)"xy",
                         2);
    pkt[n - 1] ^= 0x5A;
    REQUIRE(emu_send_raw(&c, pkt, n) == 0);
    CHECK_EQ(emu_recv_id(&c, WSG_CMD_LOOP, &f, EMU_REPLY_MS), 1);
    CHECK_EQ(f.status, WSG_E_CHECKSUM_ERROR);
    CHECK_EQ(emu_request(&c, WSG_CMD_GET_WIDTH, NULL, 0, NULL, EMU_REPLY_MS),
             WSG_E_SUCCESS);
    CHECK_EQ(
        emu_request(&c, WSG_CMD_GET_SYSTEM_INFO, NULL, 0, NULL, EMU_REPLY_MS),
        WSG_E_SUCCESS);
    CHECK_EQ(
        emu_request(&c, WSG_CMD_GET_SYSTEM_STATE, NULL, 0, NULL, EMU_REPLY_MS),
        WSG_E_SUCCESS);
    CHECK_EQ(emu_request(&c, WSG_CMD_GET_GRASP_STATS, "\x01", 1, NULL,
                         EMU_REPLY_MS),
             WSG_E_SUCCESS);

    /* Flushed after the batch that sent the reply: there while running.
     * The daemon may be descheduled between its send and the flush, so the
     * file is read again until the line is there, within a bound. */
    {
        const char *const p[] = {" out 43h GetOpeningWidth E_SUCCESS width=",
                                 NULL};
        char line[1024];
        double deadline = emu_now_ms() + EMU_REPLY_MS;

        for (;;) {
            REQUIRE(emu_slurp(path, text, sizeof text) >= 0);
            if (find_line(text, p, line, sizeof line) ||
                emu_now_ms() >= deadline)
                break;
            emu_sleep_ms(10);
        }
        expect(text, p);
    }
    emu_close(&c);
    CHECK_EQ(emu_stop(&e), 0);
    REQUIRE(emu_slurp(path, text, sizeof text) > 0);
    printf("log:\n%s", text);

    /* The peer as the transport names it: "tcp 127.0.0.1:PORT". */
    REQUIRE(emu_field(&e, "tcp", port, sizeof port) != NULL);
    snprintf(peer, sizeof peer, " tcp 127.0.0.1:");
    {
        const char *const p1[] = {peer, " in 20h Homing direction=0(default)",
                                  NULL};
        const char *const p2[] = {peer, " out 20h Homing E_CMD_PENDING", NULL};
        const char *const p3[] = {" out 20h Homing E_SUCCESS", NULL};
        const char *const p4[] = {" in 06h Loop data=61 62 63", NULL};
        const char *const p5[] = {" out 06h Loop E_SUCCESS data=61 62 63",
                                  NULL};
        const char *const p6[] = {" in 7Fh unknown", NULL};
        const char *const p7[] = {" out 7Fh unknown E_CMD_UNKNOWN", NULL};
        const char *const p8[] = {" in 06h Loop checksum-error", NULL};
        const char *const p9[] = {" out 06h Loop E_CHECKSUM_ERROR", NULL};
        /* Homing went to the positive end: the WSG 50's 110 mm. */
        const char *const p10[] = {
            " out 43h GetOpeningWidth E_SUCCESS width=110.000", NULL};
        const char *const p11[] = {" in 43h GetOpeningWidth", NULL};
        /* The firmware emulated, and the emulator's own version. */
        const char *const p12[] = {" out 50h GetSystemInformation E_SUCCESS "
                                   "type=1(WSG 50) hwrev=1 swrev=2.2.0 "
                                   "serial=1 "
                                   "emulator=wsgemu-" WSG_VERSION,
                                   NULL};
        /* Flags and enums by the manual's names, bits of a request too. */
        const char *const p13[] = {" out 40h GetSystemState E_SUCCESS "
                                   "flags=0x00000001(SF_REFERENCED)",
                                   NULL};
        const char *const p14[] = {" in 42h GetGraspingStatistics "
                                   "flags=0x01(reset)",
                                   NULL};
        const char *const p15[] = {" out 42h GetGraspingStatistics E_SUCCESS "
                                   "total=0 no-part=0 lost-part=0",
                                   NULL};
        const char *const *all[] = {p1, p2,  p3,  p4,  p5,  p6,  p7, p8,
                                    p9, p10, p11, p12, p13, p14, p15};

        for (size_t i = 0; i < sizeof all / sizeof all[0]; i++)
            expect(text, all[i]);
    }
    /* Every line: wall clock, simulated time, peer. */
    {
        const char *p = text;
        int lines = 0;

        while (*p) {
            const char *end = strchr(p, '\n');

            REQUIRE(end != NULL); /* whole lines only */
            CHECK(end - p > 20 && p[2] == ':' && p[5] == ':' && p[8] == '.');
            CHECK(strncmp(p + 12, " t=", 3) == 0);
            lines++;
            p = end + 1;
        }
        /* 4 requests + 1 bad packet in, 5 replies + 1 final result out;
         * the emu helpers may add requests of their own, not fewer. */
        CHECK(lines >= 11);
    }
    unlink(path);
}

/* Read path until it has a line with every one of parts, within bound. */
static int wait_line(const char *path, const char *const *parts, char *text,
                     size_t cap)
{
    char line[1024];
    double deadline = emu_now_ms() + EMU_REPLY_MS;

    for (;;) {
        if (emu_slurp(path, text, cap) >= 0 &&
            find_line(text, parts, line, sizeof line))
            return 1;
        if (emu_now_ms() >= deadline)
            return 0;
        emu_sleep_ms(10);
    }
}

static void test_events(const char *dir)
{
    char path[512], text[65536];
    const char *args[] = {"--tcp", "127.0.0.1:0", "--control", "127.0.0.1:0",
                          "--log", path,          NULL};
    struct emu e;
    struct emu_client c;
    struct ctl k;
    uint8_t p[16], home = 0;
    size_t n;

    snprintf(path, sizeof path, "%s/events.log", dir);
    REQUIRE(emu_start(&e, exe, args) == 0);
    REQUIRE(ctl_open(&k, &e) == 0);

    /* A connection that announces its close, one that does not. */
    REQUIRE(emu_open(&c, &e, &emu_tcp) == 0);
    CHECK_EQ(emu_request(&c, WSG_CMD_DISCONNECT, NULL, 0, NULL, EMU_REPLY_MS),
             WSG_E_SUCCESS);
    emu_close(&c);
    {
        const char *const w[] = {" event closed (07h)", NULL};
        CHECK(wait_line(path, w, text, sizeof text));
    }
    REQUIRE(emu_open(&c, &e, &emu_tcp) == 0);
    CHECK_EQ(emu_request(&c, WSG_CMD_LOOP, "x", 1, NULL, EMU_REPLY_MS),
             WSG_E_SUCCESS);
    emu_abort(&c);
    {
        const char *const w[] = {" event fast-stop cause=disconnect", NULL};
        CHECK(wait_line(path, w, text, sizeof text));
    }

    REQUIRE(emu_open(&c, &e, &emu_tcp) == 0);
    CHECK_EQ(
        emu_request(&c, WSG_CMD_ACK_FAST_STOP, "ack", 3, NULL, EMU_REPLY_MS),
        WSG_E_SUCCESS);
    CHECK_EQ(
        emu_request(&c, WSG_CMD_ACK_FAST_STOP, "ack", 3, NULL, EMU_REPLY_MS),
        WSG_E_SUCCESS);
    CHECK_EQ(emu_request(&c, WSG_CMD_FAST_STOP, NULL, 0, NULL, EMU_REPLY_MS),
             WSG_E_SUCCESS);
    CHECK_EQ(
        emu_request(&c, WSG_CMD_ACK_FAST_STOP, "ack", 3, NULL, EMU_REPLY_MS),
        WSG_E_SUCCESS);

    /* A fault that stops: the control command, then its consequence. */
    CMD_OK(&k, "fault power on");
    CMD_OK(&k, "fault power off");
    CHECK_EQ(
        emu_request(&c, WSG_CMD_ACK_FAST_STOP, "ack", 3, NULL, EMU_REPLY_MS),
        WSG_E_SUCCESS);
    CMD_OK(&k, "part 40");
    CMD_OK(&k, "part none");

    /* A grasp with no part whose clamping travel runs past a soft limit:
     * FAST STOP at the limit (as in test_axis). */
    CHECK_EQ(emu_motion(&c, WSG_CMD_HOMING, &home, 1, EMU_HOMING_MS, NULL),
             WSG_E_SUCCESS);
    n = emu_move_payload(p, 0, 60.0f, 100.0f);
    CHECK_EQ(emu_motion(&c, WSG_CMD_PREPOSITION, p, n, EMU_MOVE_MS, NULL),
             WSG_E_SUCCESS);
    wsg_put_f32(p, 20.0f);
    wsg_put_f32(p + 4, 100.0f);
    CHECK_EQ(
        emu_request(&c, WSG_CMD_SET_SOFT_LIMITS, p, 8, NULL, EMU_REPLY_MS),
        WSG_E_SUCCESS);
    n = emu_grasp_payload(p, 25.0f, 100.0f);
    CHECK_EQ(emu_motion(&c, WSG_CMD_GRASP, p, n, EMU_MOVE_MS, NULL),
             WSG_E_RANGE_ERROR);
    CMD_OK(&k, "reset");
    emu_close(&c);
    ctl_close(&k);
    CHECK_EQ(emu_stop(&e), 0);
    REQUIRE(emu_slurp(path, text, sizeof text) > 0);
    printf("events:\n%s", text);
    {
        const char *const p1[] = {" tcp 127.0.0.1:", " event connected", NULL};
        const char *const p2[] = {" tcp 127.0.0.1:", " event closed (07h)",
                                  NULL};
        const char *const p3[] = {
            " tcp 127.0.0.1:", " event closed without 07h", NULL};
        const char *const p4[] = {
            " tcp 127.0.0.1:", " event fast-stop cause=disconnect", NULL};
        const char *const p5[] = {" event ack fast-stop cleared", NULL};
        const char *const p6[] = {" event ack nothing to clear", NULL};
        const char *const p7[] = {
            " tcp 127.0.0.1:", " event fast-stop cause=23h", NULL};
        const char *const p8[] = {" control event fault power on", NULL};
        const char *const p9[] = {" gripper event fast-stop cause=fault",
                                  NULL};
        const char *const p10[] = {" control event fault power off", NULL};
        const char *const p11[] = {" control event part 40 ", NULL};
        const char *const p12[] = {" control event part none", NULL};
        const char *const p13[] = {" gripper event fast-stop cause=soft-limit",
                                   NULL};
        const char *const p14[] = {" control event reset", NULL};
        const char *const *all[] = {p1, p2, p3,  p4,  p5,  p6,  p7,
                                    p8, p9, p10, p11, p12, p13, p14};
        char l1[1024], l2[1024];

        for (size_t i = 0; i < sizeof all / sizeof all[0]; i++)
            expect(text, all[i]);
        /* The command first, then what it caused. */
        if (find_line(text, p8, l1, sizeof l1) &&
            find_line(text, p9, l2, sizeof l2))
            CHECK(strstr(text, l1) < strstr(text, l2));
    }
    unlink(path);
}

/* logrotate renames the file and sends SIGHUP: the lines before it stay in
 * the renamed file, those after it go to a new file at the path. */
static void test_reopen(const char *dir)
{
    char path[512], old[600], text[65536];
    const char *args[] = {"--tcp", "127.0.0.1:0", "--log", path, NULL};
    const char *const one[] = {" in 06h Loop data=6F 6E 65", NULL};
    const char *const two[] = {" in 06h Loop data=74 77 6F", NULL};
    char line[1024];
    struct emu e;
    struct emu_client c;
    struct stat st;
    double deadline;

    snprintf(path, sizeof path, "%s/rot.log", dir);
    snprintf(old, sizeof old, "%s.1", path);
    REQUIRE(emu_start(&e, exe, args) == 0);
    REQUIRE(emu_open(&c, &e, &emu_tcp) == 0);
    CHECK_EQ(emu_request(&c, WSG_CMD_LOOP, "one", 3, NULL, EMU_REPLY_MS),
             WSG_E_SUCCESS);
    CHECK(wait_line(path, one, text, sizeof text));
    REQUIRE(rename(path, old) == 0);
    REQUIRE(kill(e.pid, SIGHUP) == 0);
    /* The new file appears when the signal was handled. */
    deadline = emu_now_ms() + EMU_REPLY_MS;
    while (stat(path, &st) != 0 && emu_now_ms() < deadline)
        emu_sleep_ms(10);
    CHECK_EQ(stat(path, &st), 0);
    CHECK_EQ(emu_request(&c, WSG_CMD_LOOP, "two", 3, NULL, EMU_REPLY_MS),
             WSG_E_SUCCESS);
    CHECK(wait_line(path, two, text, sizeof text));
    CHECK(find_line(text, one, line, sizeof line) == NULL);
    emu_close(&c);
    CHECK_EQ(emu_stop(&e), 0); /* SIGHUP did not end it */
    REQUIRE(emu_slurp(old, text, sizeof text) > 0);
    expect(text, one);
    CHECK(find_line(text, two, line, sizeof line) == NULL);
    unlink(path);
    unlink(old);
}

/* Whole lines, each starting with the wall clock: 1, or 0. */
static int whole_lines(const char *text)
{
    const char *p = text;

    while (*p) {
        const char *end = strchr(p, '\n');

        if (!end || end - p < 20 || p[2] != ':' || p[5] != ':')
            return 0;
        p = end + 1;
    }
    return 1;
}

/* --log-max BYTES: the file never passes BYTES; at the bound it becomes
 * FILE.old (whole lines in both) and the newest lines are in FILE. With
 * 0 there is no bound. */
static void test_bound(const char *dir)
{
    char path[512], old[600], text[65536], payload[8];
    const char *args[] = {"--tcp",     "127.0.0.1:0", "--log", path,
                          "--log-max", "2000",        NULL};
    const char *const last[] = {" in 06h Loop data=6C 61 73 74", NULL};
    struct emu e;
    struct emu_client c;
    struct stat st;
    char line[1024];
    long n, total = 0;
    int i;

    snprintf(path, sizeof path, "%s/bound.log", dir);
    snprintf(old, sizeof old, "%s.old", path);
    REQUIRE(emu_start(&e, exe, args) == 0);
    REQUIRE(emu_open(&c, &e, &emu_tcp) == 0);
    /* Some 200 lines of about 90 bytes: the bound is passed many times. */
    for (i = 0; i < 100; i++) {
        snprintf(payload, sizeof payload, "%04d", i);
        CHECK_EQ(emu_request(&c, WSG_CMD_LOOP, payload, 4, NULL, EMU_REPLY_MS),
                 WSG_E_SUCCESS);
    }
    CHECK_EQ(emu_request(&c, WSG_CMD_LOOP, "last", 4, NULL, EMU_REPLY_MS),
             WSG_E_SUCCESS);
    emu_close(&c);
    CHECK_EQ(emu_stop(&e), 0);
    REQUIRE(stat(path, &st) == 0);
    CHECK(st.st_size > 0 && st.st_size <= 2000);
    n = emu_slurp(path, text, sizeof text);
    CHECK(n > 0 && whole_lines(text));
    total += n;
    /* The newest lines are in the file, the last request among them. */
    CHECK(find_line(text, last, line, sizeof line) != NULL);
    REQUIRE(stat(old, &st) == 0);
    CHECK(st.st_size > 0 && st.st_size <= 2000);
    n = emu_slurp(old, text, sizeof text);
    CHECK(n > 0 && whole_lines(text));
    total += n;
    /* Between the bound and twice it kept, no more. */
    CHECK(total > 2000 && total <= 4000);
    unlink(path);
    unlink(old);

    /* 0: no bound, nothing moved aside. */
    args[5] = "0";
    REQUIRE(emu_start(&e, exe, args) == 0);
    REQUIRE(emu_open(&c, &e, &emu_tcp) == 0);
    for (i = 0; i < 100; i++)
        CHECK_EQ(emu_request(&c, WSG_CMD_LOOP, "abcd", 4, NULL, EMU_REPLY_MS),
                 WSG_E_SUCCESS);
    emu_close(&c);
    CHECK_EQ(emu_stop(&e), 0);
    REQUIRE(stat(path, &st) == 0);
    CHECK(st.st_size > 4000);
    CHECK(stat(old, &st) != 0);
    unlink(path);
}

/* A signal that comes while the daemon is still reading its options: it
 * waits for the event loop instead of taking its default action (death).
 * The config file is a FIFO, so the daemon is held inside its option
 * parsing, past the dynamic loader, until the test has sent the signal:
 * no race with the daemon's start. SIGHUP (logrotate's) must leave it
 * running to its ready line and serving; SIGTERM must end it cleanly
 * (status 0), not kill it. */
static void early_signal(const char *dir, int sig)
{
    char fifo[512];
    const char *args[] = {"--config", fifo, NULL};
    static const char text[] = "tcp = 127.0.0.1:0\n";
    struct emu e;
    struct emu_client c;
    int fd, st;

    snprintf(fifo, sizeof fifo, "%s/early.conf", dir);
    REQUIRE(mkfifo(fifo, 0600) == 0);
    REQUIRE(emu_spawn(&e, exe, args) == 0);
    /* Opened for writing once the daemon opened it for reading: it is in
     * main() then, reading its options. */
    fd = open(fifo, O_WRONLY);
    unlink(fifo);
    REQUIRE(fd >= 0);
    REQUIRE(kill(e.pid, sig) == 0);
    CHECK_EQ(write(fd, text, sizeof text - 1), (ssize_t)(sizeof text - 1));
    close(fd);
    if (sig == SIGHUP) {
        REQUIRE(emu_ready(&e) == 0);
        REQUIRE(emu_open(&c, &e, &emu_tcp) == 0);
        CHECK_EQ(emu_request(&c, WSG_CMD_LOOP, "hup", 3, NULL, EMU_REPLY_MS),
                 WSG_E_SUCCESS);
        emu_close(&c);
        CHECK_EQ(emu_stop(&e), 0);
    } else {
        /* The ready line, then the stop the signal asked for. */
        st = emu_ready(&e);
        CHECK_EQ(st, 0);
        if (st == 0)
            CHECK_EQ(emu_stop_sig(&e, 0), 0);
    }
}

static void test_early_signals(const char *dir)
{
    early_signal(dir, SIGTERM);
    early_signal(dir, SIGHUP);
}

static void test_bad_log(void)
{
    static const char *const args[] = {"--tcp", "127.0.0.1:0", "--log",
                                       "/nonexistent/dir/comm.log", NULL};
    char out[512], err[512];
    int st =
        emu_run(exe, args, emu_ms(5000), out, sizeof out, err, sizeof err);

    printf("bad log: status %d, stderr \"%s\"\n", st, err);
    CHECK(st != 0);
    CHECK(strstr(err, "/nonexistent/dir/comm.log") != NULL);
    CHECK(strstr(out, "ready") == NULL);
}

int main(int argc, char **argv)
{
    const char *tmp = getenv("TMPDIR");
    char dir[256];

    exe = emu_exe(argc, argv);
    snprintf(dir, sizeof dir, "%s/wsgemu-log-XXXXXX", tmp ? tmp : "/tmp");
    REQUIRE(mkdtemp(dir) != NULL);
    test_log(dir);
    test_events(dir);
    test_reopen(dir);
    test_bound(dir);
    test_early_signals(dir);
    test_bad_log();
    rmdir(dir);
    TEST_EXIT();
}
