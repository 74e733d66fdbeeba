/*
 * integ_lost: nothing is lost, nothing is doubled, nothing overtakes. One
 * daemon serves three TCP clients, one UDP client and the serial port (the
 * pty) at once; CAN is covered by the CAN runner (tests/can), which runs
 * the protocol suite over a vcan bus.
 *
 * Each client sends REQUESTS mixed requests without waiting for each
 * answer (pipelined, at most WINDOW outstanding, paced over some seconds):
 * Loop (06h) with a sequence number, state queries (31h, 40h, 41h, 43h..45h)
 * and now and then a Preposition (21h), which is answered E_CMD_PENDING and
 * later by its final result, or E_ALREADY_RUNNING while the one gripper moves
 * for anybody. Streams are off, so every packet received is an answer.
 *
 * Checked per client: the immediate answers arrive in the order of the
 * requests, one each (matched by ID, and for Loop by its sequence number);
 * every E_CMD_PENDING is followed by exactly one final result; nothing
 * arrives after the last one. The run is bounded by RUN_MS.
 */
#define _GNU_SOURCE

#include "check.h"
#include "emu.h"
#include "wsg/axis.h"

#include <poll.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#define NCLIENTS 5
#define REQUESTS 3000
#define WINDOW   8
#define RUN_MS   emu_ms(20000)
/* Paced, so the run lasts long enough for several motions (at most one
 * request per client per PACE_MS; the window still bounds what is out). */
#define PACE_MS 2.0

struct expect {
    uint8_t id;
    uint32_t seq; /* Loop only */
};

struct client {
    struct emu_client c;
    const char *name;
    unsigned idx;
    struct expect fifo[WINDOW];
    unsigned head, n;  /* outstanding immediate answers */
    unsigned sent;     /* requests sent */
    unsigned answered; /* immediate answers matched */
    unsigned pending;  /* E_CMD_PENDING without a final result yet */
    unsigned finals, already, misorder;
};

static uint8_t next_request(struct client *k, uint8_t *p, size_t *len)
{
    static const uint8_t queries[] = {
        WSG_CMD_GET_SYSTEM_STATE, WSG_CMD_GET_GRASP_STATE,
        WSG_CMD_GET_WIDTH,        WSG_CMD_GET_SPEED,
        WSG_CMD_GET_FORCE,        WSG_CMD_GET_ACCELERATION};
    unsigned i = k->sent;

    /* Staggered per client, so the motions that get through come from
     * all of them. */
    if ((i + 8 * k->idx) % 40 == 20) {
        /* Alternate between two widths: a real move each time it is
         * accepted. */
        *len = emu_move_payload(p, 0, (i / 40) % 2 ? 30.0f : 70.0f, 400.0f);
        return WSG_CMD_PREPOSITION;
    }
    if (i % 2 == 0) {
        wsg_put_u32(p, i);
        *len = 4;
        return WSG_CMD_LOOP;
    }
    *len = 0;
    return queries[(i / 2) % sizeof queries];
}

static double t0;

static void send_more(struct client *k)
{
    while (k->n < WINDOW && k->sent < REQUESTS &&
           k->sent <= (emu_now_ms() - t0) / PACE_MS) {
        uint8_t p[16];
        size_t len;
        uint8_t id = next_request(k, p, &len);
        struct expect *x = &k->fifo[(k->head + k->n) % WINDOW];

        x->id = id;
        x->seq = k->sent;
        if (emu_send(&k->c, id, p, len) != 0) {
            CHECK(!"send failed");
            k->sent = REQUESTS; /* give up on this client */
            return;
        }
        k->n++;
        k->sent++;
    }
}

static void take(struct client *k, const struct wsg_client_frame *f)
{
    struct expect *x;

    /* A motion's final result: its ID, a final status, and one of this
     * client's motions outstanding. An immediate answer to a later motion
     * is E_CMD_PENDING or E_ALREADY_RUNNING, so the two are told apart;
     * and the final result leaves before any later answer, in order. */
    if (f->id == WSG_CMD_PREPOSITION && k->pending > 0 &&
        f->status != WSG_E_CMD_PENDING && f->status != WSG_E_ALREADY_RUNNING) {
        k->pending--;
        k->finals++;
        return;
    }
    if (k->n == 0) {
        if (k->misorder++ < 5)
            fprintf(stderr, "%s: unexpected %02Xh status %u\n", k->name,
                    (unsigned)f->id, f->status);
        return;
    }
    x = &k->fifo[k->head];
    if (f->id != x->id ||
        (f->id == WSG_CMD_LOOP &&
         (f->len != 6 || wsg_get_u32(EMU_PARAMS(f)) != x->seq)) ||
        (f->id != WSG_CMD_PREPOSITION && f->status != WSG_E_SUCCESS)) {
        if (k->misorder++ < 5)
            fprintf(stderr,
                    "%s: request %u: expected %02Xh, got %02Xh status %u\n",
                    k->name, (unsigned)x->seq, (unsigned)x->id,
                    (unsigned)f->id, f->status);
    }
    if (f->id == WSG_CMD_PREPOSITION) {
        if (f->status == WSG_E_CMD_PENDING)
            k->pending++;
        else if (f->status == WSG_E_ALREADY_RUNNING)
            k->already++;
        else if (k->misorder++ < 5)
            fprintf(stderr, "%s: Preposition answered %u\n", k->name,
                    f->status);
    }
    k->head = (k->head + 1) % WINDOW;
    k->n--;
    k->answered++;
}

static int done(const struct client *k)
{
    return k->sent == REQUESTS && k->n == 0 && k->pending == 0;
}

int main(int argc, char **argv)
{
    const char *exe = emu_exe(argc, argv);
    const struct emu_transport *tps[3] = {&emu_tcp, &emu_udp, &emu_pty};
    static struct client ks[NCLIENTS];
    static const char *const extra[] = {"--acceleration", "5000", NULL};
    struct emu e;
    struct wsg_client_frame f;
    int imm = 0;
    /* "can" (the CAN runner's argument): the same run over the one peer a
     * bus has; otherwise TCP, UDP and the pty at once. */
    int over_can = argc > 2 && strcmp(argv[2], "can") == 0;
    int nclients = over_can ? 1 : NCLIENTS;

    setvbuf(stdout, NULL, _IOLBF, 0);
    /* Short moves: more of them succeed in the run, and more finals
     * interleave with the answers. */
    if (over_can) {
        REQUIRE(emu_start_tp(&e, exe, &emu_can, extra) == 0);
        ks[0].name = "can";
        REQUIRE(emu_open(&ks[0].c, &e, &emu_can) == 0);
    } else {
        static const char *const names[NCLIENTS] = {"tcp 1", "tcp 2", "tcp 3",
                                                    "udp", "pty"};
        REQUIRE(emu_start_multi(&e, exe, tps, 3, extra) == 0);
        for (int i = 0; i < NCLIENTS; i++) {
            ks[i].name = names[i];
            ks[i].idx = (unsigned)i;
            REQUIRE(emu_open(&ks[i].c, &e, i < 3 ? &emu_tcp : tps[i - 2]) ==
                    0);
        }
    }
    printf("%s\n", e.line);
    /* Prepositions need a referenced gripper. */
    CHECK_EQ(
        emu_motion(&ks[0].c, WSG_CMD_HOMING, "\0", 1, EMU_HOMING_MS, &imm),
        WSG_E_SUCCESS);
    CHECK_EQ(imm, WSG_E_CMD_PENDING);

    t0 = emu_now_ms();
    for (;;) {
        struct pollfd pfd[NCLIENTS];
        int all = 1;

        for (int i = 0; i < nclients; i++) {
            send_more(&ks[i]);
            while (emu_recv(&ks[i].c, &f, 0) == 1)
                take(&ks[i], &f);
            send_more(&ks[i]);
            all &= done(&ks[i]);
            pfd[i].fd = ks[i].c.fd;
            pfd[i].events = POLLIN;
        }
        if (all || emu_now_ms() - t0 > RUN_MS)
            break;
        poll(pfd, (nfds_t)nclients, 1);
    }
    printf("run: %.0f ms\n", emu_now_ms() - t0);
    unsigned finals = 0;
    for (int i = 0; i < nclients; i++) {
        struct client *k = &ks[i];

        /* Nothing after the last answer: no duplicate, no stray final. */
        CHECK_EQ(emu_recv(&k->c, &f, EMU_QUIET_MS), 0);
        printf("%-6s %u sent, %u answered in order, %u out of order, "
               "%u finals, %u E_ALREADY_RUNNING, %u still pending\n",
               k->name, k->sent, k->answered, k->misorder, k->finals,
               k->already, k->pending);
        CHECK_EQ(k->sent, REQUESTS);
        CHECK_EQ(k->answered, REQUESTS);
        CHECK_EQ(k->misorder, 0);
        CHECK_EQ(k->pending, 0);
        CHECK_EQ(k->c.link.bad, 0);
        finals += k->finals;
        if (k->c.tp->connection)
            CHECK_EQ(emu_request(&k->c, WSG_CMD_DISCONNECT, NULL, 0, NULL,
                                 EMU_REPLY_MS),
                     WSG_E_SUCCESS);
        emu_close(&k->c);
    }
    /* Motions did run during the test, not only refusals. */
    CHECK(finals > 1);
    CHECK_EQ(emu_stop(&e), 0);
    TEST_EXIT();
}
