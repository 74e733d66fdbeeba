/*
 * integ_latency: --latency MS[:JITTER], the gripper answering late.
 *
 * With time paused (the control channel) everything is exact, and the
 * control channel's "delayed" (packets waiting to leave) tells when a
 * request has been read, since its answer cannot:
 * - --latency 5: a request over TCP, and one over UDP, gets nothing after
 *   "time step 4" and its answer after one more step; the log shows the
 *   packet going out 5 ms after it came in;
 * - several requests in one write are answered in order, together, 5 ms
 *   later;
 * - --latency 3:4: each answer leaves after 3..7 ms (more than one value
 *   occurs), pipelined answers keep their order, and a second run meets
 *   the same delays (a fixed seed);
 * - a stream at 10 ms under --latency 3: its first packet 3 ms after the
 *   request, then exactly one per 10 ms;
 * - 64 KiB of packets wait per interface; what does not fit is dropped
 *   whole and counted (delay_dropped), the rest leaves intact;
 * - a fleet (--grippers 2): each gripper's answers wait on its own;
 * - running (not paused) with --latency 20: a round trip takes 20 ms;
 * - --latency 0 (and 0:0) answers at once, as without the option;
 * - the config key "latency" works like the option; bad values end the
 *   start with status 2 and a message naming the option.
 */
/* mkstemp, fdopen */
#define _POSIX_C_SOURCE 200809L

#include "check.h"
#include "emu.h"
#include "emu_ctl.h"

#include <stdlib.h>
#include <string.h>
#include <unistd.h>

/* How long a daemon (under valgrind too) may take to read a request. */
#define READ_MS 10000

static const char *exe;

/* Packets waiting to leave, as the control channel's state says. */
static int delayed(struct ctl *k)
{
    return (int)ctl_json_num(ctl_cmd(k, "state"), "delayed");
}

/* Until n packets wait: the daemon has read what was sent. */
static void wait_delayed(struct ctl *k, int n)
{
    double end = emu_now_ms() + READ_MS;
    int d;

    while ((d = delayed(k)) != n && emu_now_ms() < end)
        emu_sleep_ms(2);
    if (d != n)
        fprintf(stderr, "delayed: %d, want %d\n", d, n);
    REQUIRE(d == n);
}

static void step(struct ctl *k, int ms)
{
    char cmd[32];

    snprintf(cmd, sizeof cmd, "time step %d", ms);
    CMD_OK(k, cmd);
}

static long long now_us(struct ctl *k)
{
    return ctl_time_us(ctl_cmd(k, "time"));
}

/* Nothing arrives (the steps ran before "ok": a packet they released
 * would be on its way already). */
static void quiet(struct emu_client *c)
{
    struct wsg_client_frame f;

    CHECK_EQ(emu_recv(c, &f, 100), 0);
}

/* Start with --control and args (NULL-terminated), TCP and UDP. */
static void start(struct emu *e, const char *const *args)
{
    const struct emu_transport *tps[] = {&emu_tcp, &emu_udp};
    const char *all[16];
    size_t n = 0;

    all[n++] = "--control";
    all[n++] = "127.0.0.1:0";
    while (*args && n < sizeof all / sizeof all[0] - 1)
        all[n++] = *args++;
    all[n] = NULL;
    REQUIRE(emu_start_multi(e, exe, tps, 2, all) == 0);
}

/* One request on c: nothing after MS - 1 steps, the answer after MS. */
static void check_exact(struct emu_client *c, struct ctl *k, int ms)
{
    struct wsg_client_frame f;
    long long t0 = now_us(k);

    REQUIRE(emu_send(c, WSG_CMD_GET_SYSTEM_STATE, NULL, 0) == 0);
    wait_delayed(k, 1);
    step(k, ms - 1);
    quiet(c);
    CHECK_EQ(delayed(k), 1);
    step(k, 1);
    CHECK_EQ(emu_recv(c, &f, EMU_REPLY_MS), 1);
    CHECK_EQ(f.id, WSG_CMD_GET_SYSTEM_STATE);
    CHECK_EQ(f.status, WSG_E_SUCCESS);
    CHECK_EQ(delayed(k), 0);
    CHECK_EQ(now_us(k), t0 + ms * 1000LL);
    quiet(c);
}

/* n Loop requests (payload: their number) in one write. */
static void send_loops(struct emu_client *c, int n)
{
    uint8_t buf[64 * 16];
    size_t len = 0;
    int i;

    REQUIRE(n <= 64);
    for (i = 0; i < n; i++) {
        uint8_t b = (uint8_t)i;

        len +=
            wsg_frame_encode(buf + len, sizeof buf - len, WSG_CMD_LOOP, &b, 1);
    }
    REQUIRE(emu_send_raw(c, buf, len) == 0);
}

/* n Loop answers, in order. */
static void recv_loops(struct emu_client *c, int n)
{
    struct wsg_client_frame f;
    int i;

    for (i = 0; i < n; i++) {
        REQUIRE(emu_recv(c, &f, EMU_REPLY_MS) == 1);
        CHECK_EQ(f.id, WSG_CMD_LOOP);
        CHECK_EQ(EMU_NPARAMS(&f), 1);
        CHECK_EQ(EMU_PARAMS(&f)[0], i);
    }
}

static void test_exact(const char *logdir)
{
    char path[512], text[65536];
    const char *args[] = {"--latency", "5", "--log", path, NULL};
    struct emu e;
    struct emu_client tcp, udp;
    struct ctl k;
    const uint8_t get[] = {WSG_CMD_GET_SYSTEM_STATE, WSG_CMD_GET_GRASP_STATE,
                           WSG_CMD_GET_WIDTH, WSG_CMD_GET_SPEED,
                           WSG_CMD_GET_FORCE};
    struct wsg_client_frame f;
    uint8_t buf[128];
    size_t i, len = 0;

    snprintf(path, sizeof path, "%s/latency.log", logdir);
    start(&e, args);
    REQUIRE(ctl_open(&k, &e) == 0);
    REQUIRE(emu_open(&tcp, &e, &emu_tcp) == 0);
    REQUIRE(emu_open(&udp, &e, &emu_udp) == 0);
    CMD_OK(&k, "time pause");

    check_exact(&tcp, &k, 5);
    check_exact(&udp, &k, 5);

    /* Pipelined: answered in order, all 5 ms later. */
    for (i = 0; i < sizeof get; i++)
        len += wsg_frame_encode(buf + len, sizeof buf - len, get[i], NULL, 0);
    REQUIRE(emu_send_raw(&tcp, buf, len) == 0);
    wait_delayed(&k, (int)sizeof get);
    step(&k, 4);
    quiet(&tcp);
    step(&k, 1);
    for (i = 0; i < sizeof get; i++) {
        REQUIRE(emu_recv(&tcp, &f, EMU_REPLY_MS) == 1);
        CHECK_EQ(f.id, get[i]);
        CHECK_EQ(f.status, WSG_E_SUCCESS);
    }
    send_loops(&udp, 20);
    wait_delayed(&k, 20);
    step(&k, 5);
    recv_loops(&udp, 20);
    CHECK_EQ(delayed(&k), 0);
    CHECK_EQ(ctl_json_num(ctl_cmd(&k, "state"), "delay_dropped"), 0);

    emu_close(&tcp);
    emu_close(&udp);
    ctl_close(&k);
    CHECK_EQ(emu_stop(&e), 0);

    /* The log shows a packet when it leaves: 5 ms after it came. */
    {
        FILE *fp = fopen(path, "r");
        char *in, *out;
        double tin, tout;

        REQUIRE(fp != NULL);
        len = fread(text, 1, sizeof text - 1, fp);
        text[len] = '\0';
        fclose(fp);
        in = strstr(text, " in 40h");
        out = strstr(text, " out 40h");
        REQUIRE(in && out && in < out);
        /* "t=S.FFFFFF" stands before the peer on each line. */
        while (in > text && in[-1] != '\n')
            in--;
        while (out > text && out[-1] != '\n')
            out--;
        in = strstr(in, " t=");
        out = strstr(out, " t=");
        REQUIRE(in && out);
        tin = atof(in + 3);
        tout = atof(out + 3);
        CHECK_NEAR(tout - tin, 0.005, 1e-6);
        unlink(path);
    }
}

/* 30 requests one at a time: the steps each answer took, into ms[]. */
static void jitter_run(int *ms)
{
    const char *args[] = {"--latency", "3:4", NULL};
    struct emu e;
    struct emu_client c;
    struct ctl k;
    struct wsg_client_frame f;
    int i;

    start(&e, args);
    REQUIRE(ctl_open(&k, &e) == 0);
    REQUIRE(emu_open(&c, &e, &emu_tcp) == 0);
    CMD_OK(&k, "time pause");
    for (i = 0; i < 30; i++) {
        uint8_t b = (uint8_t)i;

        REQUIRE(emu_send(&c, WSG_CMD_LOOP, &b, 1) == 0);
        wait_delayed(&k, 1);
        for (ms[i] = 0; ms[i] < 20 && delayed(&k) > 0; ms[i]++)
            step(&k, 1);
        REQUIRE(emu_recv(&c, &f, EMU_REPLY_MS) == 1);
        CHECK_EQ(f.id, WSG_CMD_LOOP);
        CHECK_EQ(EMU_PARAMS(&f)[0], i);
        CHECK(ms[i] >= 3 && ms[i] <= 7);
    }
    /* Pipelined with jitter: drawn delays vary, the order does not. */
    send_loops(&c, 40);
    wait_delayed(&k, 40);
    for (i = 0; i < 60 && delayed(&k) > 0; i++)
        step(&k, 1);
    CHECK(i >= 3 && i <= 7);
    recv_loops(&c, 40);
    emu_close(&c);
    ctl_close(&k);
    CHECK_EQ(emu_stop(&e), 0);
}

static void test_jitter(void)
{
    int a[30], b[30], i, distinct = 0;
    int seen[8] = {0};

    jitter_run(a);
    jitter_run(b);
    for (i = 0; i < 30; i++) {
        CHECK_EQ(a[i], b[i]);
        if (a[i] >= 3 && a[i] <= 7 && !seen[a[i]]++)
            distinct++;
    }
    printf("jitter: %d distinct delays of 3..7 ms in 30\n", distinct);
    CHECK(distinct >= 3);
}

static void test_stream(void)
{
    const char *args[] = {"--latency", "3", NULL};
    struct emu e;
    struct emu_client c;
    struct ctl k;
    struct wsg_client_frame f;
    uint8_t p[3];
    int i;

    start(&e, args);
    REQUIRE(ctl_open(&k, &e) == 0);
    REQUIRE(emu_open(&c, &e, &emu_tcp) == 0);
    CMD_OK(&k, "time pause");
    /* 43h every 10 ms */
    p[0] = 1;
    wsg_put_u16(p + 1, 10);
    REQUIRE(emu_send(&c, WSG_CMD_GET_WIDTH, p, sizeof p) == 0);
    wait_delayed(&k, 1);
    step(&k, 2);
    quiet(&c);
    step(&k, 1);
    CHECK_EQ(emu_recv(&c, &f, EMU_REPLY_MS), 1);
    CHECK_EQ(f.id, WSG_CMD_GET_WIDTH);
    for (i = 0; i < 10; i++) {
        step(&k, 10);
        CHECK_EQ(emu_recv(&c, &f, EMU_REPLY_MS), 1);
        CHECK_EQ(f.id, WSG_CMD_GET_WIDTH);
        CHECK_EQ(delayed(&k), 0);
        quiet(&c);
    }
    /* Ended: the answer to that, and nothing after it. */
    p[0] = 0;
    REQUIRE(emu_send(&c, WSG_CMD_GET_WIDTH, p, sizeof p) == 0);
    wait_delayed(&k, 1);
    step(&k, 100);
    CHECK_EQ(emu_recv(&c, &f, EMU_REPLY_MS), 1);
    quiet(&c);
    emu_close(&c);
    ctl_close(&k);
    CHECK_EQ(emu_stop(&e), 0);
}

/* A full line drops whole packets, counts them, and sends the rest. */
static void test_bound(void)
{
    const char *args[] = {"--latency", "10000", NULL};
    struct emu e;
    struct emu_client c;
    struct ctl k;
    struct wsg_client_frame f;
    uint8_t p[3];
    /* 43h answers are 14 bytes; 64 KiB of them wait. */
    const int fit = 65536 / 14;
    double dropped, end;
    int i;

    start(&e, args);
    REQUIRE(ctl_open(&k, &e) == 0);
    REQUIRE(emu_open(&c, &e, &emu_tcp) == 0);
    CMD_OK(&k, "time pause");
    /* 43h on every step: 5001 packets in 5 s, none due before 10 s. */
    p[0] = 1;
    wsg_put_u16(p + 1, 0);
    REQUIRE(emu_send(&c, WSG_CMD_GET_WIDTH, p, sizeof p) == 0);
    wait_delayed(&k, 1);
    step(&k, 5000);
    CHECK_EQ(delayed(&k), fit);
    dropped = ctl_json_num(ctl_cmd(&k, "state"), "delay_dropped");
    CHECK_EQ(dropped, 5001 - fit);
    /* The stream's end: its answer finds the line full too. */
    p[0] = 0;
    REQUIRE(emu_send(&c, WSG_CMD_GET_WIDTH, p, sizeof p) == 0);
    end = emu_now_ms() + READ_MS;
    while (ctl_json_num(ctl_cmd(&k, "state"), "delay_dropped") == dropped &&
           emu_now_ms() < end)
        emu_sleep_ms(2);
    CHECK_EQ(ctl_json_num(ctl_cmd(&k, "state"), "delay_dropped"), dropped + 1);
    /* What waited leaves, whole and in time order. */
    step(&k, 10000);
    for (i = 0; i < fit; i++) {
        REQUIRE(emu_recv(&c, &f, EMU_REPLY_MS) == 1);
        CHECK_EQ(f.id, WSG_CMD_GET_WIDTH);
    }
    quiet(&c);
    CHECK_EQ(c.link.bad, 0);
    CHECK_EQ(delayed(&k), 0);
    emu_close(&c);
    ctl_close(&k);
    CHECK_EQ(emu_stop(&e), 0);
}

/* In a fleet each gripper delays its own packets. */
static void test_fleet(void)
{
    const char *args[] = {"--grippers", "2", "--latency", "5", NULL};
    struct emu e;
    struct emu_client c0, c1;
    struct ctl k;

    start(&e, args);
    REQUIRE(ctl_open(&k, &e) == 0);
    REQUIRE(emu_open_nth(&c0, &e, &emu_tcp, 0) == 0);
    REQUIRE(emu_open_nth(&c1, &e, &emu_tcp, 1) == 0);
    CMD_OK(&k, "time pause");
    CMD_OK(&k, "gripper 1");
    check_exact(&c1, &k, 5);
    CMD_OK(&k, "gripper 0");
    check_exact(&c0, &k, 5);
    quiet(&c1);
    emu_close(&c0);
    emu_close(&c1);
    ctl_close(&k);
    CHECK_EQ(emu_stop(&e), 0);
}

/* Running in real time: the answer takes the latency. */
static void test_running(void)
{
    const char *args[] = {"--latency", "20", NULL};
    struct emu e;
    struct emu_client c;
    struct ctl k;
    double t0, best = 1e9;
    int i;

    start(&e, args);
    REQUIRE(ctl_open(&k, &e) == 0);
    REQUIRE(emu_open(&c, &e, &emu_tcp) == 0);
    for (i = 0; i < 5; i++) {
        t0 = emu_now_ms();
        CHECK_EQ(
            emu_request(&c, WSG_CMD_GET_WIDTH, NULL, 0, NULL, EMU_REPLY_MS),
            WSG_E_SUCCESS);
        if (emu_now_ms() - t0 < best)
            best = emu_now_ms() - t0;
    }
    /* Up to a step less: the request is stamped at the last grid point
     * passed. */
    printf("running: fastest round trip %.1f ms\n", best);
    CHECK(best >= 18.5);
    emu_close(&c);
    ctl_close(&k);
    CHECK_EQ(emu_stop(&e), 0);
}

/* MS 0 is today's emulator: the answer with time paused, no step. */
static void test_zero(const char *value)
{
    const char *args[] = {"--latency", value, NULL};
    struct emu e;
    struct emu_client c;
    struct ctl k;

    start(&e, args);
    REQUIRE(ctl_open(&k, &e) == 0);
    REQUIRE(emu_open(&c, &e, &emu_tcp) == 0);
    CMD_OK(&k, "time pause");
    CHECK_EQ(emu_request(&c, WSG_CMD_GET_WIDTH, NULL, 0, NULL, EMU_REPLY_MS),
             WSG_E_SUCCESS);
    CHECK_EQ(delayed(&k), 0);
    emu_close(&c);
    ctl_close(&k);
    CHECK_EQ(emu_stop(&e), 0);
}

static void test_config(void)
{
    char path[512];
    const char *args[] = {"--config", path, NULL};
    struct emu e;
    struct emu_client c;
    struct ctl k;
    struct wsg_client_frame f;

    emu_temp_file(path, sizeof path, "latency",
                  "# answer late\nlatency = 2\n");
    start(&e, args);
    REQUIRE(ctl_open(&k, &e) == 0);
    REQUIRE(emu_open(&c, &e, &emu_tcp) == 0);
    CMD_OK(&k, "time pause");
    REQUIRE(emu_send(&c, WSG_CMD_GET_WIDTH, NULL, 0) == 0);
    wait_delayed(&k, 1);
    step(&k, 1);
    quiet(&c);
    step(&k, 1);
    CHECK_EQ(emu_recv(&c, &f, EMU_REPLY_MS), 1);
    emu_close(&c);
    ctl_close(&k);
    CHECK_EQ(emu_stop(&e), 0);
    unlink(path);
}

/* Exit status 2, nothing on stdout, and stderr containing want. */
static void bad(const char *const *args, const char *want)
{
    char out[512], err[1024];
    int st = emu_run(exe, args, 5000, out, sizeof out, err, sizeof err);

    printf("%s %s: status %d, stderr \"%s\"\n", args[0],
           args[1] ? args[1] : "", st, err);
    CHECK_EQ(st, 2);
    CHECK(strstr(out, "ready") == NULL);
    CHECK(strstr(err, want) != NULL);
    if (!strstr(err, want))
        fprintf(stderr, "  expected \"%s\" in it\n", want);
}

static void test_bad_values(void)
{
    static const char *const values[] = {"",
                                         "x",
                                         "-1",
                                         "10001",
                                         "5:10001",
                                         "5:",
                                         ":5",
                                         "5:3:1",
                                         "2.5",
                                         "0x5",
                                         " 5",
                                         "5:-1",
                                         "99999999999999999999"};
    char path[512];
    const char *args[] = {"--config", path, NULL};
    size_t i;

    for (i = 0; i < sizeof values / sizeof values[0]; i++) {
        const char *a[] = {"--latency", values[i], NULL};

        bad(a, "--latency");
    }
    {
        const char *a[] = {"--latency", "5:x", NULL};

        bad(a, "MS[:JITTER]");
    }
    emu_temp_file(path, sizeof path, "latency", "latency = 5:x\n");
    bad(args, ":1: latency:");
    unlink(path);
}

int main(int argc, char **argv)
{
    const char *tmp = getenv("TMPDIR");
    char dir[256];

    exe = emu_exe(argc, argv);
    snprintf(dir, sizeof dir, "%s/wsgemu-latency-XXXXXX", tmp ? tmp : "/tmp");
    REQUIRE(mkdtemp(dir) != NULL);
    test_exact(dir);
    rmdir(dir);
    test_jitter();
    test_stream();
    test_bound();
    test_fleet();
    test_running();
    test_zero("0");
    test_zero("0:0");
    test_config();
    test_bad_values();
    TEST_EXIT();
}
