/*
 * integ_can: the CAN interface frame by frame, on a real SocketCAN bus
 * ($WSG_TEST_CAN_IFACE, default vcan0; tests/can/run.sh provides one, in a
 * VM where the host kernel has no CAN).
 *
 * - the ready line says can=IFACE:ID (0x%03X); the default ID is 0x000
 *   with answers on 0x001; 0x123 (or decimal 291) answers on 0x124;
 * - an answer of more than 8 bytes arrives as consecutive frames on ID + 1,
 *   all but the last one full, and nothing is sent on any other ID;
 * - packets whose length is a multiple of 8 work both ways: no empty
 *   frame is needed after a request, none follows an answer;
 * - frames on other IDs, RTR frames and extended-ID frames are ignored,
 *   also between the frames of a packet;
 * - a packet cut short and followed by more silence than the reassembly
 *   timeout is discarded: only the next packet is answered; gaps shorter
 *   than the timeout do not cut a packet;
 * - answers to a burst of requests come back whole and in order, never
 *   interleaved, the largest (a 256-byte Loop echo, 34 frames) included;
 * - on a slow bus ($WSG_TEST_CAN_SLOW_IFACE: a vcan whose queue is kept
 *   short, so sends fail with ENOBUFS until it drains) the same answers
 *   still arrive whole and in order, and once they are out the daemon is
 *   idle again (its retry timer stops);
 * - Disconnect Announcement (07h) answers E_NOT_AVAILABLE and changes
 *   nothing (a bus has no connection);
 * - an interface that is missing, or is not a CAN interface, ends the
 *   daemon with status 1 and a message naming it.
 */

#include "check.h"
#include "emu.h"
#include "emu_can.h"
#include "wsg/axis.h"

#include <linux/can.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

/* The daemon's timeout is 100 ms; these stay clear of it on either side,
 * with room for a slow emulated machine. */
#define GAP_SHORT_MS 20
#define GAP_LONG_MS  400

/* CHECK that gives the verdict, to guard the checks that need it. */
#define CHECK_OK(cond) check_ok_((cond) ? 1 : 0, __LINE__, #cond)
static int check_ok_(int ok, int line, const char *what)
{
    check_count++;
    if (!ok) {
        check_failures++;
        fprintf(stderr, "%s:%d: CHECK failed: %s\n", __FILE__, line, what);
    }
    return ok;
}

struct answer {
    uint8_t pkt[WSG_FRAME_MAX];
    size_t len;
    unsigned nframes;
    uint8_t frame_len[64];
    struct wsg_client_frame f;
};

/* One answer packet off rx (filtered to the answer ID), frame by frame,
 * complete by its SIZE field. 0, or -1 on a timeout or a malformed packet. */
static int read_answer(int rx, uint32_t answer_id, struct answer *a,
                       int timeout_ms)
{
    double deadline = emu_now_ms() + timeout_ms;
    size_t want = WSG_HEADER_LEN + WSG_CRC_LEN;

    memset(a, 0, offsetof(struct answer, f));
    while (a->len < want) {
        struct emu_can_frame fr;
        double left = deadline - emu_now_ms();
        int r = emu_can_recv_frame(rx, &fr, left > 0 ? (int)left : 0);

        if (r != 1) {
            fprintf(stderr, "integ_can: answer incomplete: %zu of %zu bytes\n",
                    a->len, want);
            return -1;
        }
        CHECK_EQ(fr.id, answer_id); /* no EFF, RTR or ERR flag either */
        if (a->len + fr.len > sizeof a->pkt ||
            a->nframes == sizeof a->frame_len)
            return -1;
        memcpy(a->pkt + a->len, fr.data, fr.len);
        a->len += fr.len;
        a->frame_len[a->nframes++] = fr.len;
        if (a->len >= WSG_HEADER_LEN)
            want = WSG_HEADER_LEN + wsg_get_u16(a->pkt + 4) + WSG_CRC_LEN;
    }
    if (a->len != want) {
        fprintf(stderr, "integ_can: %zu bytes for a %zu-byte packet\n", a->len,
                want);
        return -1;
    }
    return emu_packet_decode(a->pkt, a->len, &a->f);
}

/* Frames of a packet as the interface prescribes: all full but the last. */
static void check_frames(const struct answer *a)
{
    unsigned i;

    CHECK_EQ(a->nframes, (a->len + 7) / 8);
    for (i = 0; i + 1 < a->nframes; i++)
        CHECK_EQ(a->frame_len[i], 8);
    if (a->nframes > 0)
        CHECK_EQ(a->frame_len[a->nframes - 1], a->len - 8 * (a->nframes - 1));
}

/* Nothing arrives on rx for ms. */
static int quiet(int rx, int ms)
{
    struct emu_can_frame fr;
    int r = emu_can_recv_frame(rx, &fr, ms);

    if (r == 1)
        fprintf(stderr, "integ_can: unexpected frame %03Xh, %u bytes\n",
                (unsigned)fr.id, (unsigned)fr.len);
    return r == 0;
}

static size_t encode(uint8_t *pkt, uint8_t id, const uint8_t *payload,
                     size_t len)
{
    size_t n = wsg_frame_encode(pkt, WSG_FRAME_MAX, id, payload, len);

    REQUIRE(n > 0);
    return n;
}

/* The daemon's ID from its ready line. */
static uint32_t ready_id(const struct emu *e, const char *iface)
{
    char v[64], want[32];
    const char *colon;
    unsigned long id;

    REQUIRE(emu_field(e, "can", v, sizeof v) != NULL);
    colon = strrchr(v, ':');
    REQUIRE(colon != NULL);
    id = strtoul(colon + 1, NULL, 16);
    snprintf(want, sizeof want, "%s:0x%03lX", iface, id);
    CHECK(strcmp(v, want) == 0);
    return (uint32_t)id;
}

/* A daemon started with --can IFACE[:arg_id]: a request on id is answered
 * on id + 1, one on another ID is not. */
static void check_answers_on(const char *exe, const char *iface,
                             const char *arg_id, uint32_t id)
{
    char arg[64];
    const char *args[] = {"--can", arg, NULL};
    uint8_t pkt[WSG_FRAME_MAX];
    struct answer a;
    struct emu e;
    int tx, rx;

    if (arg_id)
        snprintf(arg, sizeof arg, "%s:%s", iface, arg_id);
    else
        snprintf(arg, sizeof arg, "%s", iface);
    REQUIRE(emu_start(&e, exe, args) == 0);
    printf("--can %s: %s\n", arg, e.line);
    CHECK_EQ(ready_id(&e, iface), id);
    tx = emu_can_socket(iface, EMU_CAN_RX_NONE);
    rx = emu_can_socket(iface, (int)id + 1);
    REQUIRE(tx >= 0 && rx >= 0);
    REQUIRE(emu_can_send_packet(
                tx, id, pkt, encode(pkt, WSG_CMD_GET_SYSTEM_INFO, NULL, 0)) ==
            0);
    if (CHECK_OK(read_answer(rx, id + 1, &a, EMU_REPLY_MS) == 0)) {
        CHECK_EQ(a.f.id, WSG_CMD_GET_SYSTEM_INFO);
        CHECK_EQ(a.f.status, WSG_E_SUCCESS);
    }
    /* The IDs next to it are not ours. */
    REQUIRE(emu_can_send_packet(
                tx, (id + 2) & CAN_SFF_MASK, pkt,
                encode(pkt, WSG_CMD_GET_SYSTEM_INFO, NULL, 0)) == 0);
    REQUIRE(emu_can_send_packet(
                tx, (id - 1) & CAN_SFF_MASK, pkt,
                encode(pkt, WSG_CMD_GET_SYSTEM_INFO, NULL, 0)) == 0);
    CHECK(quiet(rx, EMU_QUIET_MS));
    close(tx);
    close(rx);
    CHECK_EQ(emu_stop(&e), 0);
}

static void test_ids(const char *exe, const char *iface)
{
    check_answers_on(exe, iface, NULL, 0x000);
    check_answers_on(exe, iface, "0x123", 0x123);
    check_answers_on(exe, iface, "291", 0x123);
    check_answers_on(exe, iface, "010", 0x00A); /* decimal, not octal */
    check_answers_on(exe, iface, "0x7FE", 0x7FE);
}

static void check_open_fails(const char *exe, const char *iface,
                             const char *why)
{
    const char *args[] = {"--can", iface, NULL};
    char out[512], err[1024];
    int st =
        emu_run(exe, args, emu_ms(5000), out, sizeof out, err, sizeof err);

    printf("--can %s: status %d: %s", iface, st, err);
    CHECK_EQ(st, 1);
    CHECK(strstr(err, iface) != NULL);
    CHECK(strstr(err, why) != NULL);
    CHECK_EQ(out[0], '\0'); /* no ready line */
}

static void test_open_failures(const char *exe)
{
    check_open_fails(exe, "nosuchcan9", "No such device");
    check_open_fails(exe, "lo", "not a CAN interface");
}

/* Get System Information: an 18-byte answer, frames of 8, 8 and 2. Nothing
 * but the answer frames appears on the bus. */
static void test_answer_frames(int tx, int rx, int all, uint32_t id)
{
    uint8_t pkt[WSG_FRAME_MAX];
    struct answer a;
    struct emu_can_frame fr;
    unsigned other = 0, answers = 0;

    REQUIRE(emu_can_send_packet(
                tx, id, pkt, encode(pkt, WSG_CMD_GET_SYSTEM_INFO, NULL, 0)) ==
            0);
    if (CHECK_OK(read_answer(rx, id + 1, &a, EMU_REPLY_MS) == 0)) {
        CHECK_EQ(a.len, 18);
        CHECK_EQ(a.nframes, 3);
        check_frames(&a);
        CHECK_EQ(a.f.status, WSG_E_SUCCESS);
        CHECK_EQ(a.f.len, 10);
    }
    CHECK(quiet(rx, EMU_QUIET_MS));
    /* The monitor saw the request's one frame (8 bytes) and the answer's
     * three, nothing else. */
    while (emu_can_recv_frame(all, &fr, 0) == 1) {
        if (fr.id == id + 1)
            answers++;
        else if (fr.id != id)
            other++;
    }
    CHECK_EQ(answers, 3);
    CHECK_EQ(other, 0);
}

/* Loop with n payload bytes: a request of 8 + n bytes, an answer of
 * 10 + n. */
static void loop_exchange(int tx, int rx, uint32_t id, size_t n,
                          size_t want_req, size_t want_ans)
{
    uint8_t payload[WSG_PAYLOAD_MAX], pkt[WSG_FRAME_MAX];
    struct answer a;
    size_t len, i;

    for (i = 0; i < n; i++)
        payload[i] = (uint8_t)(0xA5 ^ i); /* 0xAA among them, too */
    len = encode(pkt, WSG_CMD_LOOP, payload, n);
    CHECK_EQ(len, want_req);
    REQUIRE(emu_can_send_packet(tx, id, pkt, len) == 0);
    if (CHECK_OK(read_answer(rx, id + 1, &a, EMU_REPLY_MS) == 0)) {
        CHECK_EQ(a.len, want_ans);
        check_frames(&a);
        CHECK_EQ(a.f.id, WSG_CMD_LOOP);
        CHECK_EQ(a.f.status, WSG_E_SUCCESS);
        CHECK_EQ(EMU_NPARAMS(&a.f), n);
        CHECK(memcmp(EMU_PARAMS(&a.f), payload, n) == 0);
    }
}

static void test_multiple_of_8(int tx, int rx, uint32_t id)
{
    /* Requests of 16 and 24 bytes, ended by a full frame: answered at once,
     * with no empty frame after them. */
    loop_exchange(tx, rx, id, 8, 16, 18);
    loop_exchange(tx, rx, id, 16, 24, 26);
    /* Answers of 16 and 24 bytes: two and three full frames, and no empty
     * frame follows. */
    loop_exchange(tx, rx, id, 6, 14, 16);
    loop_exchange(tx, rx, id, 14, 22, 24);
    CHECK(quiet(rx, EMU_QUIET_MS));
    /* The largest: 256 bytes echoed, 266 bytes in 34 frames. */
    loop_exchange(tx, rx, id, 256, 264, 266);
    loop_exchange(tx, rx, id, 0, 8, 10);
    CHECK(quiet(rx, EMU_QUIET_MS));
}

/* A packet with foreign frames between its own: all of it answered, none
 * of the foreign frames. */
static void test_foreign_frames(int tx, int rx, uint32_t id)
{
    uint8_t pkt[WSG_FRAME_MAX], junk[8];
    uint8_t payload[20];
    struct answer a;
    size_t len, off, i;

    for (i = 0; i < sizeof payload; i++)
        payload[i] = (uint8_t)(i + 1);
    len = encode(pkt, WSG_CMD_LOOP, payload, sizeof payload);

    /* Whole packets that are not for us. */
    REQUIRE(emu_can_send_packet(tx, id + 2, pkt, len) == 0);
    REQUIRE(emu_can_send_packet(tx, (id + 0x80) & CAN_SFF_MASK, pkt, len) ==
            0);
    REQUIRE(emu_can_send_packet(tx, id | CAN_EFF_FLAG, pkt, len) == 0);
    REQUIRE(emu_can_send_packet(tx, (id | 0x10000) | CAN_EFF_FLAG, pkt, len) ==
            0);
    for (off = 0; off < len; off += 8)
        REQUIRE(emu_can_send_frame(tx, id | CAN_RTR_FLAG, NULL, 0) == 0);
    CHECK(quiet(rx, EMU_QUIET_MS));

    /* Our packet, with every kind of foreign frame between its frames:
     * each carries bytes that would break the packet if taken as data
     * (RTR frames carry none; one with DLC 8 is sent as well). */
    memset(junk, WSG_PREAMBLE_BYTE, sizeof junk);
    for (off = 0; off < len; off += 8) {
        REQUIRE(emu_can_send_frame(tx, id, pkt + off,
                                   len - off < 8 ? len - off : 8) == 0);
        REQUIRE(emu_can_send_frame(tx, id + 2, junk, 8) == 0);
        REQUIRE(emu_can_send_frame(tx, id | CAN_EFF_FLAG, junk, 8) == 0);
        REQUIRE(emu_can_send_frame(tx, id | CAN_RTR_FLAG, NULL, 0) == 0);
        REQUIRE(emu_can_send_frame(tx, id | CAN_RTR_FLAG, junk, 8) == 0);
    }
    if (CHECK_OK(read_answer(rx, id + 1, &a, EMU_REPLY_MS) == 0)) {
        CHECK_EQ(a.f.id, WSG_CMD_LOOP);
        CHECK_EQ(a.f.status, WSG_E_SUCCESS);
        CHECK_EQ(EMU_NPARAMS(&a.f), sizeof payload);
        CHECK(memcmp(EMU_PARAMS(&a.f), payload, sizeof payload) == 0);
    }
    CHECK(quiet(rx, EMU_QUIET_MS));
}

/* A packet cut short, silence, a new packet: only the new one answered.
 * Then a packet with gaps shorter than the timeout: answered whole. */
static void test_partial_timeout(int tx, int rx, uint32_t id)
{
    uint8_t pkt[WSG_FRAME_MAX], pkt2[WSG_FRAME_MAX], payload[30];
    struct answer a;
    size_t len, len2, off, i;
    double t0;

    for (i = 0; i < sizeof payload; i++)
        payload[i] = (uint8_t)(0x40 + i);
    len = encode(pkt, WSG_CMD_LOOP, payload, sizeof payload);
    len2 = encode(pkt2, WSG_CMD_GET_SYSTEM_INFO, NULL, 0);

    /* The first two of five frames of a Loop, then nothing. */
    REQUIRE(emu_can_send_frame(tx, id, pkt, 8) == 0);
    REQUIRE(emu_can_send_frame(tx, id, pkt + 8, 8) == 0);
    t0 = emu_now_ms();
    CHECK(quiet(rx, GAP_LONG_MS));
    printf("partial packet, then %.0f ms of silence\n", emu_now_ms() - t0);
    /* Were the Loop still being assembled, the new packet would be taken
     * as its payload: no answer to it, and a Loop echo or a checksum error
     * under 06h instead. */
    REQUIRE(emu_can_send_packet(tx, id, pkt2, len2) == 0);
    if (CHECK_OK(read_answer(rx, id + 1, &a, EMU_REPLY_MS) == 0)) {
        CHECK_EQ(a.f.id, WSG_CMD_GET_SYSTEM_INFO);
        CHECK_EQ(a.f.status, WSG_E_SUCCESS);
    }
    CHECK(quiet(rx, EMU_QUIET_MS));

    /* Silence cuts only a packet in progress: a whole packet after a long
     * pause is answered like any other (covered above), and one whose
     * frames come GAP_SHORT_MS apart is assembled whole. */
    for (off = 0; off < len; off += 8) {
        if (off)
            emu_sleep_ms(GAP_SHORT_MS);
        REQUIRE(emu_can_send_frame(tx, id, pkt + off,
                                   len - off < 8 ? len - off : 8) == 0);
    }
    if (CHECK_OK(read_answer(rx, id + 1, &a, EMU_REPLY_MS) == 0)) {
        CHECK_EQ(a.f.id, WSG_CMD_LOOP);
        CHECK_EQ(a.f.status, WSG_E_SUCCESS);
        CHECK_EQ(EMU_NPARAMS(&a.f), sizeof payload);
    }
    CHECK(quiet(rx, EMU_QUIET_MS));
}

/* A burst of requests: every answer whole, in the order asked. */
static void test_burst(int tx, int rx, uint32_t id)
{
    /* Within what a socket's receive buffer holds (some 250 frames): about
     * 130 frames each way. */
    enum { N = 9 };
    uint8_t pkt[WSG_FRAME_MAX], payload[WSG_PAYLOAD_MAX];
    struct answer a;
    int i, good = 0;

    for (i = 0; i < N; i++) {
        /* Sizes vary so that a cut or interleaved answer cannot decode. */
        size_t n = i % 3 == 0 ? WSG_PAYLOAD_MAX : (size_t)(i * 7 % 40);

        memset(payload, i, n);
        REQUIRE(emu_can_send_packet(
                    tx, id, pkt, encode(pkt, WSG_CMD_LOOP, payload, n)) == 0);
    }
    for (i = 0; i < N; i++) {
        size_t n = i % 3 == 0 ? WSG_PAYLOAD_MAX : (size_t)(i * 7 % 40);

        if (read_answer(rx, id + 1, &a, EMU_REPLY_MS) != 0)
            break;
        check_frames(&a);
        if (a.f.id == WSG_CMD_LOOP && a.f.status == WSG_E_SUCCESS &&
            (size_t)EMU_NPARAMS(&a.f) == n &&
            (n == 0 || EMU_PARAMS(&a.f)[n - 1] == (uint8_t)i))
            good++;
    }
    CHECK_EQ(good, N);
    CHECK(quiet(rx, EMU_QUIET_MS));
}

/* A bus slower than the daemon: a 266-byte answer is 34 frames, and the
 * interface's queue holds 10, so the daemon meets ENOBUFS on every big
 * answer and must send the rest from its retry timer, in order. */
static void test_slow_bus(const char *exe, const char *slow)
{
    char arg[64];
    const char *args[] = {"--can", arg, NULL};
    uint32_t id = 0x2A0;
    struct emu e;
    long sw0, sw1, t_0, t_1;
    int tx, rx;
    double t0;

    snprintf(arg, sizeof arg, "%s:0x%03X", slow, (unsigned)id);
    REQUIRE(emu_start(&e, exe, args) == 0);
    printf("slow bus: %s\n", e.line);
    tx = emu_can_socket(slow, EMU_CAN_RX_NONE);
    rx = emu_can_socket(slow, (int)id + 1);
    REQUIRE(tx >= 0 && rx >= 0);
    t0 = emu_now_ms();
    test_multiple_of_8(tx, rx, id);
    test_burst(tx, rx, id);
    printf("slow bus: exchanges done in %.0f ms\n", emu_now_ms() - t0);
    /* Everything is out: the retry timer must have stopped with it. */
    REQUIRE(emu_proc_activity(e.pid, &sw0, &t_0) == 0);
    emu_sleep_ms(1000);
    REQUIRE(emu_proc_activity(e.pid, &sw1, &t_1) == 0);
    printf("slow bus: %ld context switches in 1 s of idleness\n", sw1 - sw0);
    CHECK(sw1 - sw0 <= 5);
    CHECK(t_1 - t_0 <= 2);
    close(tx);
    close(rx);
    CHECK_EQ(emu_stop(&e), 0);
}

/* 07h: not available on a bus, and nothing is refused afterwards. */
static void test_disconnect(struct emu *e)
{
    struct emu_client c;
    uint32_t flags;

    REQUIRE(emu_open(&c, e, &emu_can) == 0);
    CHECK_EQ(emu_request(&c, WSG_CMD_DISCONNECT, NULL, 0, NULL, EMU_REPLY_MS),
             WSG_E_NOT_AVAILABLE);
    CHECK_EQ(
        emu_request(&c, WSG_CMD_GET_SYSTEM_INFO, NULL, 0, NULL, EMU_REPLY_MS),
        WSG_E_SUCCESS);
    CHECK_EQ(emu_get_flags(&c, &flags), 0);
    CHECK_EQ(flags & WSG_SF_FAST_STOP, 0);
    CHECK_EQ(c.link.bad, 0);
    emu_close(&c);
}

/* A script's own command over CAN (issue: IDs a script registers are
 * delivered from every interface): the script, written to TMPDIR here so
 * the test carries it into the VM, answers B0h with E_SUCCESS and the
 * payload doubled; its answer goes out on id + 1 in frames like any. An
 * ID it did not register stays E_CMD_UNKNOWN. */
static void test_script(const char *exe, const char *iface)
{
    static const char lua[] =
        "cmd.register(0xB0)\n"
        "while true do\n"
        "  local id, p = cmd.read()\n"
        "  local out = {}\n"
        "  for i = 1, #p do out[i] = (p[i] * 2) % 256 end\n"
        "  cmd.send(id, etob(E_SUCCESS), cmd.interface(), out)\n"
        "end\n";
    static const uint8_t in[] = {1, 2, 3, 200, 5, 6, 7, 8, 9};
    const char *tmp = getenv("TMPDIR");
    char path[256], arg[64];
    const char *args[] = {"--can", arg, "--script", path, NULL};
    uint8_t pkt[WSG_FRAME_MAX];
    struct answer a;
    struct emu e;
    FILE *f;
    size_t i;
    int tx, rx;

    snprintf(path, sizeof path, "%s/integ_can_%ld.lua",
             tmp && tmp[0] ? tmp : "/tmp", (long)getpid());
    f = fopen(path, "w");
    REQUIRE(f != NULL);
    REQUIRE(fwrite(lua, 1, sizeof lua - 1, f) == sizeof lua - 1);
    REQUIRE(fclose(f) == 0);
    snprintf(arg, sizeof arg, "%s:0x321", iface);
    REQUIRE(emu_start(&e, exe, args) == 0);
    tx = emu_can_socket(iface, EMU_CAN_RX_NONE);
    rx = emu_can_socket(iface, 0x322);
    REQUIRE(tx >= 0 && rx >= 0);
    REQUIRE(emu_can_send_packet(tx, 0x321, pkt,
                                encode(pkt, 0xB0, in, sizeof in)) == 0);
    if (CHECK_OK(read_answer(rx, 0x322, &a, EMU_REPLY_MS) == 0)) {
        check_frames(&a);
        CHECK_EQ(a.f.id, 0xB0);
        CHECK_EQ(a.f.status, WSG_E_SUCCESS);
        /* "CAN", then each byte doubled. */
        CHECK_EQ(EMU_NPARAMS(&a.f), 3 + sizeof in);
        if (EMU_NPARAMS(&a.f) == 3 + sizeof in) {
            CHECK(memcmp(EMU_PARAMS(&a.f), "CAN", 3) == 0);
            for (i = 0; i < sizeof in; i++)
                CHECK_EQ(EMU_PARAMS(&a.f)[3 + i], (uint8_t)(in[i] * 2));
        }
    }
    REQUIRE(emu_can_send_packet(tx, 0x321, pkt, encode(pkt, 0xB1, NULL, 0)) ==
            0);
    if (CHECK_OK(read_answer(rx, 0x322, &a, EMU_REPLY_MS) == 0)) {
        CHECK_EQ(a.f.id, 0xB1);
        CHECK_EQ(a.f.status, WSG_E_CMD_UNKNOWN);
    }
    close(tx);
    close(rx);
    CHECK_EQ(emu_stop(&e), 0);
    unlink(path);
}

int main(int argc, char **argv)
{
    const char *exe = emu_exe(argc, argv);
    const char *iface = emu_can_iface();
    const char *slow;
    struct emu e;
    uint32_t id;
    int tx, rx, all;

    if (emu_can_available(iface) != 0)
        return 77;
    printf("on %s\n", iface);
    test_open_failures(exe);
    test_ids(exe, iface);
    test_script(exe, iface);

    REQUIRE(emu_start_tp(&e, exe, &emu_can, NULL) == 0);
    printf("%s\n", e.line);
    id = ready_id(&e, iface);
    tx = emu_can_socket(iface, EMU_CAN_RX_NONE);
    rx = emu_can_socket(iface, (int)id + 1);
    all = emu_can_socket(iface, EMU_CAN_RX_ALL);
    REQUIRE(tx >= 0 && rx >= 0 && all >= 0);

    test_answer_frames(tx, rx, all, id);
    test_multiple_of_8(tx, rx, id);
    test_foreign_frames(tx, rx, id);
    test_partial_timeout(tx, rx, id);
    test_burst(tx, rx, id);
    test_disconnect(&e);

    close(tx);
    close(rx);
    close(all);
    CHECK_EQ(emu_stop(&e), 0);

    slow = getenv("WSG_TEST_CAN_SLOW_IFACE");
    if (slow && slow[0])
        test_slow_bus(exe, slow);
    else
        printf("no slow bus (WSG_TEST_CAN_SLOW_IFACE): the retry of "
               "refused frames is not tested\n");
    TEST_EXIT();
}
