/*
 * integ_fleet: --grippers N runs N independent grippers in one process.
 * - The ready line lists every gripper's interfaces, comma-separated in
 *   gripper order: TCP ports counted up from the one given, UDP listening
 *   and reply ports counted up in pairs, pty paths counted up from the
 *   number at the end of the path.
 * - Each gripper is its own: its serial number counts up, a homing on one
 *   moves no other, a TCP close without 07h FAST STOPs only its gripper, a
 *   stream of one goes on while the others stay idle.
 * - The control channel selects a gripper ("gripper N") and acts on that
 *   one only; "stats" counts the grippers and the active ones.
 * - Counting past the end of the port or CAN ID ranges, and UDP ranges
 *   that would overlap, are refused with exit status 2.
 * With the transport argument "can" (the CAN runner), the same fleet on a
 * CAN bus instead: an ID pair per gripper, each answering on its own.
 */
#define _GNU_SOURCE /* mkdtemp */

#include "check.h"
#include "emu.h"
#include "emu_ctl.h"
#include "wsg/axis.h"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <unistd.h>

#define N 3

static void test_option_errors(const char *exe)
{
    static const char *const bad[][7] = {
        {"--grippers", "0", NULL},
        {"--grippers", "x", NULL},
        /* 1500..1502 listen, 1502..1504 reply: even distance, overlap. */
        {"--grippers", "3", "--udp", "127.0.0.1:1500:1502", NULL},
        {"--grippers", "2", "--tcp", "127.0.0.1:65535", NULL},
        {"--grippers", "2", "--udp", "127.0.0.1:65534:65535", NULL},
        {"--grippers", "1000", "--can", "vcan0:0x7F0", NULL},
    };
    static const char *const why[] = {"1..",   "1..",   "overlap",
                                      "65535", "65535", "0x7FF"};
    char out[256], err[1024];
    size_t i;

    for (i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        CHECK_EQ(emu_run(exe, bad[i], emu_ms(3000), out, sizeof out, err,
                         sizeof err),
                 2);
        if (!strstr(err, why[i]))
            fprintf(stderr, "case %zu: stderr \"%s\"\n", i, err);
        CHECK(strstr(err, why[i]) != NULL);
    }
}

/* Start with TCP and UDP on counted ports from a base that depends on the
 * pid (ports are shared with everything else on the machine: a taken one
 * makes the start fail, and another base is tried). */
static int start_fleet(struct emu *e, const char *exe, const char *ptydir,
                       unsigned *tcp, unsigned *udp)
{
    int attempt;

    for (attempt = 0; attempt < 8; attempt++) {
        char targ[32], uarg[40], parg[256], n[8];
        const char *args[16];
        int k = 0;

        *tcp = 20000u + (unsigned)((getpid() * 7 + attempt * 997) % 20000);
        *udp = *tcp + 20000u;
        snprintf(targ, sizeof targ, "127.0.0.1:%u", *tcp);
        /* Reply ports one above: counted up in pairs. */
        snprintf(uarg, sizeof uarg, "127.0.0.1:%u:%u", *udp, *udp + 1);
        snprintf(parg, sizeof parg, "%s/wsg7", ptydir);
        snprintf(n, sizeof n, "%d", N);
        args[k++] = "--grippers";
        args[k++] = n;
        args[k++] = "--tcp";
        args[k++] = targ;
        args[k++] = "--udp";
        args[k++] = uarg;
        args[k++] = "--pty";
        args[k++] = parg;
        args[k++] = "--control";
        args[k++] = "127.0.0.1:0";
        args[k++] = "--serial";
        args[k++] = "100";
        args[k] = NULL;
        if (emu_start(e, exe, args) == 0)
            return 0;
    }
    return -1;
}

static uint32_t serial_of(struct emu_client *c)
{
    struct wsg_client_frame f;

    if (emu_request(c, WSG_CMD_GET_SYSTEM_INFO, NULL, 0, &f, EMU_REPLY_MS) !=
            WSG_E_SUCCESS ||
        EMU_NPARAMS(&f) < 8)
        return 0;
    return wsg_get_u32(EMU_PARAMS(&f) + 4);
}

static uint32_t flags_of(struct emu_client *c)
{
    uint32_t fl = 0xFFFFFFFFu;

    emu_get_flags(c, &fl);
    return fl;
}

/* One Get Opening Width over UDP to gripper i: sent to its port, answered
 * at its reply port. */
static int udp_width(unsigned port, unsigned reply)
{
    struct sockaddr_in sa;
    uint8_t pkt[16], in[64];
    int fd = socket(AF_INET, SOCK_DGRAM, 0);
    int ok = 0;
    size_t n;
    struct pollfd p;
    struct wsg_client_frame f;

    if (fd < 0)
        return 0;
    memset(&sa, 0, sizeof sa);
    sa.sin_family = AF_INET;
    sa.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    sa.sin_port = htons((uint16_t)reply);
    if (bind(fd, (struct sockaddr *)&sa, sizeof sa) < 0)
        goto out;
    sa.sin_port = htons((uint16_t)port);
    n = wsg_frame_encode(pkt, sizeof pkt, WSG_CMD_GET_WIDTH, NULL, 0);
    if (sendto(fd, pkt, n, 0, (struct sockaddr *)&sa, sizeof sa) != (ssize_t)n)
        goto out;
    p.fd = fd;
    p.events = POLLIN;
    if (poll(&p, 1, EMU_REPLY_MS) != 1)
        goto out;
    {
        ssize_t r = recv(fd, in, sizeof in, 0);

        ok = r > 0 && emu_packet_decode(in, (size_t)r, &f) == 0 &&
             f.id == WSG_CMD_GET_WIDTH && f.status == WSG_E_SUCCESS;
    }
out:
    close(fd);
    return ok;
}

static int run_local(const char *exe);

/* Three grippers on one bus: commands on ID, ID + 2, ID + 4. */
static void test_can(const char *exe)
{
    static const char *const extra[] = {"--grippers", "3", NULL};
    struct emu e;
    struct emu_client c[N];
    struct wsg_client_frame f;
    char v[256], want[256];
    unsigned long id;
    uint8_t dir = WSG_HOME_POSITIVE;
    unsigned i;

    REQUIRE(emu_start_tp(&e, exe, &emu_can, extra) == 0);
    printf("%s\n", e.line);
    REQUIRE(emu_field(&e, "can", v, sizeof v));
    {
        const char *colon = strchr(v, ':');

        REQUIRE(colon != NULL);
        id = strtoul(colon + 1, NULL, 16);
        snprintf(want, sizeof want, "%.*s:0x%03lX,%.*s:0x%03lX,%.*s:0x%03lX",
                 (int)(colon - v), v, id, (int)(colon - v), v, id + 2,
                 (int)(colon - v), v, id + 4);
        CHECK(strcmp(v, want) == 0);
    }
    for (i = 0; i < N; i++) {
        REQUIRE(emu_open_nth(&c[i], &e, &emu_can, i) == 0);
        CHECK_EQ(serial_of(&c[i]), 1u + i);
    }
    CHECK_EQ(emu_request(&c[1], WSG_CMD_HOMING, &dir, 1, NULL, EMU_REPLY_MS),
             WSG_E_CMD_PENDING);
    CHECK_EQ(emu_recv_id(&c[1], WSG_CMD_HOMING, &f, emu_ms(10000)), 1);
    CHECK_EQ(f.status, WSG_E_SUCCESS);
    CHECK(flags_of(&c[1]) & WSG_SF_REFERENCED);
    CHECK(!(flags_of(&c[0]) & WSG_SF_REFERENCED));
    CHECK(!(flags_of(&c[2]) & WSG_SF_REFERENCED));
    /* Only gripper 1's client saw a homing result. */
    CHECK_EQ(c[0].link.seen[WSG_CMD_HOMING], 0u);
    CHECK_EQ(c[2].link.seen[WSG_CMD_HOMING], 0u);
    for (i = 0; i < N; i++)
        emu_close(&c[i]);
    CHECK_EQ(emu_stop(&e), 0);
}

int main(int argc, char **argv)
{
    const char *exe = emu_exe(argc, argv);

    if (argc > 2 && emu_transport_arg(argc, argv) == &emu_can) {
        test_can(exe);
        TEST_EXIT();
    }
    return run_local(exe);
}

static int run_local(const char *exe)
{
    char ptydir[] = "/tmp/wsgemu-fleet-XXXXXX";
    char want[512], v[1024];
    struct emu e;
    struct emu_client c[N];
    struct wsg_client_frame f;
    struct ctl k;
    unsigned tcp, udp, i;
    uint8_t dir = WSG_HOME_POSITIVE;

    test_option_errors(exe);

    REQUIRE(mkdtemp(ptydir) != NULL);
    REQUIRE(start_fleet(&e, exe, ptydir, &tcp, &udp) == 0);
    printf("%s\n", e.line);

    /* Every gripper on the ready line, counted up in gripper order. */
    snprintf(want, sizeof want, "127.0.0.1:%u,127.0.0.1:%u,127.0.0.1:%u", tcp,
             tcp + 1, tcp + 2);
    REQUIRE(emu_field(&e, "tcp", v, sizeof v));
    CHECK(strcmp(v, want) == 0);
    snprintf(want, sizeof want,
             "127.0.0.1:%u>%u,127.0.0.1:%u>%u,127.0.0.1:%u>%u", udp, udp + 1,
             udp + 2, udp + 3, udp + 4, udp + 5);
    REQUIRE(emu_field(&e, "udp", v, sizeof v));
    CHECK(strcmp(v, want) == 0);
    snprintf(want, sizeof want, "%s/wsg7,%s/wsg8,%s/wsg9", ptydir, ptydir,
             ptydir);
    REQUIRE(emu_field(&e, "pty", v, sizeof v));
    CHECK(strcmp(v, want) == 0);
    REQUIRE(emu_field(&e, "control", v, sizeof v));
    CHECK(strchr(v, ',') == NULL);

    /* Gripper 0 and 2 over TCP, gripper 1 over its serial port. */
    REQUIRE(emu_open_nth(&c[0], &e, &emu_tcp, 0) == 0);
    REQUIRE(emu_open_nth(&c[1], &e, &emu_pty, 1) == 0);
    REQUIRE(emu_open_nth(&c[2], &e, &emu_tcp, 2) == 0);
    REQUIRE(ctl_open(&k, &e) == 0);
    for (i = 0; i < N; i++)
        CHECK_EQ(serial_of(&c[i]), 100u + i);
    /* UDP: each gripper on its own pair of ports. */
    CHECK(udp_width(udp + 2, udp + 3));

    /* A homing on gripper 2 moves gripper 2 only. Simulated time is paused
     * until the checks of the running homing are done, so that it cannot
     * end first on a slow machine. */
    CMD_OK(&k, "time pause");
    CHECK_EQ(emu_request(&c[2], WSG_CMD_HOMING, &dir, 1, NULL, EMU_REPLY_MS),
             WSG_E_CMD_PENDING);
    CMD_OK(&k, "time step 20");
    CHECK(flags_of(&c[2]) & WSG_SF_MOVING);
    CHECK(!(flags_of(&c[0]) & WSG_SF_MOVING));
    CHECK(!(flags_of(&c[1]) & WSG_SF_MOVING));
    {
        const char *s = ctl_cmd(&k, "stats");

        CHECK(ctl_is_ok(s));
        CHECK_EQ(ctl_json_num(s, "grippers"), N);
        CHECK_EQ(ctl_json_num(s, "active"), 1);
    }
    CMD_OK(&k, "time resume");
    CHECK_EQ(emu_recv_id(&c[2], WSG_CMD_HOMING, &f, emu_ms(10000)), 1);
    CHECK_EQ(f.status, WSG_E_SUCCESS);
    CHECK(flags_of(&c[2]) & WSG_SF_REFERENCED);
    CHECK(!(flags_of(&c[0]) & WSG_SF_REFERENCED));
    CHECK(!(flags_of(&c[1]) & WSG_SF_REFERENCED));
    CHECK_EQ(c[0].link.seen[WSG_CMD_HOMING], 0u);
    CHECK_EQ(c[1].link.seen[WSG_CMD_HOMING], 0u);

    /* The control channel acts on the gripper it selected. */
    CHECK(strcmp(ctl_cmd(&k, "gripper"), "ok gripper 0 of 3") == 0);
    CHECK(strncmp(ctl_cmd(&k, "gripper 3"), "error ", 6) == 0);
    CHECK(strcmp(ctl_cmd(&k, "gripper 1"), "ok gripper 1 of 3") == 0);
    CMD_OK(&k, "fault power on");
    /* A power fault is a FAST STOP, with the next step of that gripper. */
    CHECK(emu_wait_flags(&c[1], WSG_SF_FAST_STOP, WSG_SF_FAST_STOP,
                         EMU_REPLY_MS, NULL) == 0);
    CHECK(flags_of(&c[1]) & WSG_SF_POWER_FAULT);
    CHECK(!(flags_of(&c[0]) & (WSG_SF_POWER_FAULT | WSG_SF_FAST_STOP)));
    CHECK(!(flags_of(&c[2]) & (WSG_SF_POWER_FAULT | WSG_SF_FAST_STOP)));
    CMD_OK(&k, "fault power off");
    CHECK_EQ(emu_request(&c[1], WSG_CMD_ACK_FAST_STOP, "ack", 3, NULL,
                         EMU_REPLY_MS),
             WSG_E_SUCCESS);
    CMD_OK(&k, "gripper 2");
    CHECK(ctl_json_num(ctl_cmd(&k, "state"), "width") > 109.0);
    CMD_OK(&k, "gripper 0");
    CHECK(ctl_json_num(ctl_cmd(&k, "state"), "width") < 109.0);

    /* A stream of gripper 2 goes on; the others stay off the active list
     * and silent. */
    {
        uint8_t sub[3] = {0x01, 10, 0};
        unsigned before = c[2].link.seen[WSG_CMD_GET_WIDTH];

        CHECK_EQ(emu_request(&c[2], WSG_CMD_GET_WIDTH, sub, sizeof sub, NULL,
                             EMU_REPLY_MS),
                 WSG_E_SUCCESS);
        emu_sleep_ms(emu_ms(200));
        CHECK(emu_sync(&c[2], EMU_REPLY_MS) == 0);
        CHECK(c[2].link.seen[WSG_CMD_GET_WIDTH] >= before + 10);
        CHECK_EQ(ctl_json_num(ctl_cmd(&k, "stats"), "active"), 1);
        CHECK_EQ(emu_recv_id(&c[0], WSG_CMD_GET_WIDTH, &f, EMU_QUIET_MS), 0);
    }

    /* A close without 07h FAST STOPs its own gripper only. */
    emu_close(&c[0]);
    REQUIRE(emu_open_nth(&c[0], &e, &emu_tcp, 0) == 0);
    CHECK(flags_of(&c[0]) & WSG_SF_FAST_STOP);
    CHECK(!(flags_of(&c[1]) & WSG_SF_FAST_STOP));
    CHECK(!(flags_of(&c[2]) & WSG_SF_FAST_STOP));

    for (i = 0; i < N; i++)
        emu_close(&c[i]);
    ctl_close(&k);
    CHECK_EQ(emu_stop(&e), 0);
    rmdir(ptydir);
    TEST_EXIT();
}
