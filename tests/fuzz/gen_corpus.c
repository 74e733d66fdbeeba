/*
 * Writes the seed corpus (corpus/frames and corpus/commands): the manual's
 * example packets of chapter 1, a valid packet for every command of the
 * table with sensible parameters (after a homing, so the motion commands
 * get past E_NOT_INITIALIZED), and homing, grasp, FAST STOP and stream
 * sequences. Each scenario is written in both harnesses' input formats.
 * The output is committed; rebuild it only to change the seeds (every
 * build compiles this program, so it stays in step with the harnesses):
 *
 *   ./build/tests/fuzz/fuzz_gen_corpus tests/fuzz/corpus
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fuzz_ids.h"
#include "manual_packets.h"
#include "wsg/axis.h"
#include "wsg/proto.h"

#define GEN_MAX 8192

/* Control bytes (fuzz_bench.h): session 0, steps from the table index. */
#define CTL_STEPS(i)   ((uint8_t)((i) << 1))
#define CTL_WORLD(ev)  ((uint8_t)((ev) << 4))
#define STEPS_NONE     0
#define STEPS_10       4
#define STEPS_200      6
#define STEPS_1000     7
#define WORLD_DATAGRAM 9
#define WORLD_PART     10
#define WORLD_FAULT    12
#define WORLD_CLOSE    15

struct gen {
    uint8_t frames[GEN_MAX], cmds[GEN_MAX];
    size_t nf, nc;
};

static void gen_begin(struct gen *g, uint8_t cfg)
{
    g->frames[0] = g->cmds[0] = cfg;
    g->nf = g->nc = 1;
}

/* One command in both formats: a chunk holding its frame, a record. */
static void gen_cmd(struct gen *g, uint8_t id, uint8_t ctl, const void *p,
                    size_t len)
{
    uint8_t pkt[WSG_FRAME_MAX];
    size_t n = wsg_frame_encode(pkt, sizeof pkt, id, p, len);
    size_t k;

    if (!n || len > 255 || g->nf + n + 2 > GEN_MAX ||
        g->nc + len + 3 > GEN_MAX)
        abort();
    g->frames[g->nf++] = (uint8_t)n;
    g->frames[g->nf++] = ctl;
    memcpy(g->frames + g->nf, pkt, n);
    g->nf += n;
    for (k = 0; k < FUZZ_NIDS && fuzz_ids[k] != id; k++)
        ;
    g->cmds[g->nc++] = k < FUZZ_NIDS ? (uint8_t)k : id;
    g->cmds[g->nc++] = ctl;
    g->cmds[g->nc++] = (uint8_t)len;
    memcpy(g->cmds + g->nc, p, len);
    g->nc += len;
}

static void gen_f2(struct gen *g, uint8_t id, uint8_t ctl, float a, float b)
{
    uint8_t p[8];

    wsg_put_f32(p, a);
    wsg_put_f32(p + 4, b);
    gen_cmd(g, id, ctl, p, sizeof p);
}

static void gen_f1(struct gen *g, uint8_t id, float a)
{
    uint8_t p[4];

    wsg_put_f32(p, a);
    gen_cmd(g, id, CTL_STEPS(STEPS_10), p, sizeof p);
}

static void gen_move(struct gen *g, uint8_t flags, float w, float v)
{
    uint8_t p[9];

    p[0] = flags;
    wsg_put_f32(p + 1, w);
    wsg_put_f32(p + 5, v);
    gen_cmd(g, WSG_CMD_PREPOSITION, CTL_STEPS(STEPS_1000), p, sizeof p);
}

static void gen_home(struct gen *g)
{
    uint8_t dir = 0;

    gen_cmd(g, WSG_CMD_HOMING, CTL_STEPS(STEPS_1000), &dir, 1);
    gen_cmd(g, WSG_CMD_GET_WIDTH, CTL_STEPS(STEPS_1000), NULL, 0);
}

static void gen_write(const char *dir, const char *sub, const char *name,
                      const uint8_t *data, size_t len)
{
    char path[1024];
    FILE *f;

    snprintf(path, sizeof path, "%s/%s/%s", dir, sub, name);
    f = fopen(path, "wb");
    if (!f || fwrite(data, 1, len, f) != len || fclose(f) != 0) {
        perror(path);
        exit(1);
    }
}

static void gen_save(const struct gen *g, const char *dir, const char *name)
{
    gen_write(dir, "frames", name, g->frames, g->nf);
    gen_write(dir, "commands", name, g->cmds, g->nc);
}

/* A raw packet as one chunk of the frames harness. */
static void gen_raw(const char *dir, const char *name, uint8_t cfg,
                    uint8_t ctl, const uint8_t *pkt, size_t n)
{
    uint8_t buf[64];

    buf[0] = cfg;
    buf[1] = (uint8_t)n;
    buf[2] = ctl;
    memcpy(buf + 3, pkt, n);
    gen_write(dir, "frames", name, buf, n + 3);
}

/* A valid packet for each command, with sensible parameters, after a
 * homing. */
static void gen_each_command(const char *dir)
{
    static const uint8_t stream_on[3] = {0x01, 0x0A, 0x00}; /* every 10 ms */
    static const uint8_t stream_chg[3] = {0x03, 0x00, 0x00};
    static const uint8_t zero = 0, one = 1;
    struct gen g;
    size_t k;
    char name[64];

    for (k = 0; k < FUZZ_NIDS; k++) {
        uint8_t id = fuzz_ids[k];
        uint8_t ctl = CTL_STEPS(STEPS_1000);

        gen_begin(&g, 0);
        gen_home(&g);
        switch (id) {
        case WSG_CMD_LOOP:
            gen_cmd(&g, id, ctl, "hello gripper", 13);
            break;
        case WSG_CMD_HOMING:
            gen_cmd(&g, id, ctl, &one, 1);
            break;
        case WSG_CMD_PREPOSITION:
            gen_move(&g, 0, 50.0f, 100.0f);
            break;
        case WSG_CMD_ACK_FAST_STOP:
            gen_cmd(&g, WSG_CMD_FAST_STOP, ctl, NULL, 0);
            gen_cmd(&g, id, ctl, "ack", 3);
            break;
        case WSG_CMD_GRASP:
            gen_f2(&g, id, ctl, 40.0f, 50.0f);
            break;
        case WSG_CMD_RELEASE:
            gen_f2(&g, id, ctl, 60.0f, 50.0f);
            break;
        case WSG_CMD_SET_ACCELERATION:
            gen_f1(&g, id, 1000.0f);
            break;
        case WSG_CMD_SET_FORCE_LIMIT:
            gen_f1(&g, id, 40.0f);
            break;
        case WSG_CMD_SET_SOFT_LIMITS:
            gen_f2(&g, id, ctl, 10.0f, 100.0f);
            break;
        case WSG_CMD_OVERDRIVE:
            gen_cmd(&g, id, ctl, &one, 1);
            break;
        case WSG_CMD_GET_SYSTEM_STATE:
        case WSG_CMD_GET_WIDTH:
            gen_cmd(&g, id, ctl, stream_on, 3);
            gen_move(&g, 0, 20.0f, 50.0f);
            break;
        case WSG_CMD_GET_SPEED:
        case WSG_CMD_GET_FORCE:
            gen_cmd(&g, id, ctl, stream_chg, 3);
            gen_move(&g, 0, 20.0f, 50.0f);
            break;
        case WSG_CMD_GET_GRASP_STATS:
            gen_cmd(&g, id, ctl, &zero, 1);
            break;
        case WSG_CMD_SET_DEVICE_TAG:
            gen_cmd(&g, id, ctl, "wsgemu", 6);
            gen_cmd(&g, WSG_CMD_GET_DEVICE_TAG, ctl, NULL, 0);
            break;
        default: /* no parameters */
            gen_cmd(&g, id, ctl, NULL, 0);
            break;
        }
        snprintf(name, sizeof name, "cmd-%02x", id);
        gen_save(&g, dir, name);
    }
}

int main(int argc, char **argv)
{
    /* README's Homing request, and one with a SIZE above any command. */
    static const uint8_t req_homing[] = {0xAA, 0xAA, 0xAA, 0x20, 0x01,
                                         0x00, 0x00, 0x8F, 0x83};
    static const uint8_t oversize[] = {0xAA, 0xAA, 0xAA, 0x06, 0xFF, 0xFF};
    static const uint8_t fault = 0x84; /* TEMP_FAULT on */
    static const uint8_t zero = 0;
    const char *dir = argc > 1 ? argv[1] : "corpus";
    struct gen g;
    int i;

    for (i = 0; i < MP_COUNT; i++) {
        char name[64];

        snprintf(name, sizeof name, "manual-%s", manual_packets[i].name);
        gen_raw(dir, name, 0, CTL_STEPS(STEPS_10), MP(i), MP_LEN(i));
    }
    gen_raw(dir, "homing-request", 0, CTL_STEPS(STEPS_10), req_homing,
            sizeof req_homing);
    gen_raw(dir, "homing-request-nocrc", 0x08, CTL_STEPS(STEPS_10), req_homing,
            sizeof req_homing);
    gen_raw(dir, "oversize", 0, CTL_STEPS(STEPS_10), oversize,
            sizeof oversize);
    gen_raw(dir, "datagram-cut", 0, CTL_WORLD(WORLD_DATAGRAM), req_homing, 5);
    gen_each_command(dir);

    /* Homing both ways on each model. */
    gen_begin(&g, 0x06); /* wsg32 with a force sensor */
    gen_home(&g);
    gen_cmd(&g, WSG_CMD_HOMING, CTL_STEPS(STEPS_1000), "\x02", 1);
    gen_save(&g, dir, "seq-homing");

    /* Grasp a 30 mm part, hold, release; then lose it. */
    gen_begin(&g, 0x04); /* wsg50 with a force sensor */
    gen_home(&g);
    gen_cmd(&g, WSG_CMD_GET_GRASP_STATE,
            CTL_STEPS(STEPS_NONE) | CTL_WORLD(WORLD_PART), "\x46", 1);
    gen_f2(&g, WSG_CMD_GRASP, CTL_STEPS(STEPS_1000), 30.0f, 50.0f);
    gen_cmd(&g, WSG_CMD_GET_FORCE, CTL_STEPS(STEPS_200), NULL, 0);
    gen_cmd(&g, WSG_CMD_GET_GRASP_STATS, CTL_STEPS(STEPS_10), &zero, 1);
    gen_f2(&g, WSG_CMD_RELEASE, CTL_STEPS(STEPS_1000), 60.0f, 50.0f);
    gen_f2(&g, WSG_CMD_GRASP, CTL_STEPS(STEPS_1000), 30.0f, 50.0f);
    gen_cmd(&g, WSG_CMD_GET_SYSTEM_STATE, CTL_STEPS(STEPS_200) | 0xB0, NULL,
            0); /* world 11: the part goes */
    gen_save(&g, dir, "seq-grasp");

    /* FAST STOP in a move, refused commands, acknowledge, move again. */
    gen_begin(&g, 0);
    gen_home(&g);
    gen_move(&g, 0, 10.0f, 20.0f);
    gen_cmd(&g, WSG_CMD_FAST_STOP, CTL_STEPS(STEPS_10), NULL, 0);
    gen_move(&g, 0, 50.0f, 20.0f);
    gen_cmd(&g, WSG_CMD_ACK_FAST_STOP, CTL_STEPS(STEPS_10), "ack", 3);
    gen_move(&g, WSG_MOVE_RELATIVE | WSG_MOVE_STOP_ON_BLOCK, -5.0f, 20.0f);
    gen_save(&g, dir, "seq-fast-stop");

    /* A move cut by a fault, then a session closed mid-move. */
    gen_begin(&g, 0);
    gen_home(&g);
    gen_move(&g, 0, 0.0f, 5.0f);
    gen_cmd(&g, WSG_CMD_GET_SYSTEM_STATE,
            CTL_STEPS(STEPS_10) | CTL_WORLD(WORLD_FAULT), &fault, 1);
    gen_cmd(&g, WSG_CMD_GET_TEMPERATURE, CTL_STEPS(STEPS_10), NULL, 0);
    gen_move(&g, 0, 5.0f, 5.0f);
    gen_cmd(&g, WSG_CMD_GET_WIDTH,
            CTL_STEPS(STEPS_10) | CTL_WORLD(WORLD_CLOSE), NULL, 0);
    gen_save(&g, dir, "seq-fault-close");
    return 0;
}
