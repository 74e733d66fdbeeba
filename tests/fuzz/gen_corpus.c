/*
 * Writes the seed corpus (corpus/frames and corpus/commands): the manual's
 * example packets of chapter 1, a valid packet for every command of the
 * table with sensible parameters (after a homing, so the motion commands
 * get past E_NOT_INITIALIZED), and homing, grasp, FAST STOP and stream
 * sequences. Each scenario is written in both harnesses' input formats.
 * corpus/script has the script harness's seeds (fuzz_script.c): values for
 * cmd.send's flattening, and each of its script's IDs, a full queue, a
 * preempted loop, the script's failure and end, orphaned answers.
 * corpus/match has the pattern harness's (fuzz_match.c): each construct of
 * the pattern language, the errors, and the patterns that held the daemon
 * (%b(), a long set, a long literal, a plain find, a backtracking gsub) on
 * subjects small enough for Lua's own matcher to answer.
 * corpus/fingers has the finger harness's (fuzz_fingers.c): each finger
 * command in both styles, a DSA pad and an FMF finger through a grasp, a
 * device's UART and SPI; corpus/fdev the device model harness's
 * (fuzz_fdev.c): a model as the public scripts use one, and each
 * behaviour of its own model over UART and SPI.
 * The output is committed; rebuild it only to change the seeds (every
 * build compiles this program, so it stays in step with the harnesses):
 *
 *   ./build/tests/fuzz/fuzz_gen_corpus tests/fuzz/corpus
 */
#include <math.h>
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

/* ---- the script harness (fuzz_script.c) ---- */

/* Its record's ID byte: below 80h an index into the script's IDs
 * (fb_pick: B0h..BDh in order), from 80h a firmware ID of fuzz_ids. */
static uint8_t sc_sel(uint8_t id)
{
    size_t k;

    if (id >= 0xB0 && id <= 0xBD)
        return (uint8_t)(id - 0xB0);
    for (k = 0; k < FUZZ_NIDS && fuzz_ids[k] != id; k++)
        ;
    if (k == FUZZ_NIDS)
        abort();
    return (uint8_t)(0x80 + (k + FUZZ_NIDS - 0x80 % FUZZ_NIDS) % FUZZ_NIDS);
}

/* Control byte: the session, the steps after (index as fuzz_bench's),
 * and the event (fuzz_script.c's list). */
#define SC_CTL(sess, steps, ev) ((uint8_t)((sess) | (steps) << 1 | (ev) << 4))
#define SC_DATAGRAM             9
#define SC_BAD_CRC              10
#define SC_SPLIT                11
#define SC_RESTART              12
#define SC_STOP                 13
#define SC_CLOSE                14
#define SC_RESET                15

struct sgen {
    uint8_t b[GEN_MAX];
    size_t n;
};

static void sc_begin(struct sgen *g, uint8_t cfg)
{
    g->b[0] = cfg;
    g->n = 1;
}

static void sc_bytes(struct sgen *g, const void *p, size_t len)
{
    if (g->n + len > GEN_MAX)
        abort();
    memcpy(g->b + g->n, p, len);
    g->n += len;
}

static void sc_rec(struct sgen *g, uint8_t id, uint8_t ctl, const void *p,
                   size_t len)
{
    uint8_t h[3];

    h[0] = sc_sel(id);
    h[1] = ctl;
    h[2] = (uint8_t)len;
    sc_bytes(g, h, 3);
    sc_bytes(g, p, len);
}

static void sc_rec1(struct sgen *g, uint8_t id, uint8_t ctl, uint8_t b)
{
    sc_rec(g, id, ctl, &b, 1);
}

static void sc_recf(struct sgen *g, uint8_t id, uint8_t ctl, float v,
                    uint8_t extra)
{
    uint8_t p[5];

    wsg_put_f32(p, v);
    p[4] = extra;
    sc_rec(g, id, ctl, p, sizeof p);
}

static void sc_save(const struct sgen *g, const char *dir, const char *name)
{
    gen_write(dir, "script", name, g->b, g->n);
}

static void gen_script(const char *dir)
{
    static const uint8_t floats[12] = {0x00, 0x00, 0xC0, 0x3F,  /* 1.5 */
                                       0x01, 0x00, 0xC0, 0x7F,  /* NaN */
                                       0x00, 0x00, 0x00, 0x80}; /* -0 */
    /* cmd.send's values (fa_value's kinds: low nibble kind, high nibble
     * argument). First the mode byte, the argument count, the cap (an
     * index into fa_cap's table, 14: 65535; or bit 4 and 16 bits), the
     * error buffer (an index, 4: 128 bytes), the first argument sent. */
    static const uint8_t fl_basic[] = {
        0x01, 4,    14,  4,    0,                /* 4 arguments */
        0x02, 5,                                 /* 5 */
        0x11,                                    /* true */
        0x08, 3,    'a', 0,    'b',              /* "a\0b" */
        0x3A, 0x02, 1,   0x06, 2,   0x08, 1, 'x' /* {1, 2.0, "x"} */
    };
    static const uint8_t fl_deep5[] = {
        0x01, 1,    14,   3,    0,            /* 1 argument */
        0x1A, 0x1A, 0x1A, 0x1A, 0x1A, 0x02, 9 /* {{{{{9}}}}}: sent */
    };
    static const uint8_t fl_deep6[] = {
        0x01, 1,    14,   3,    0,                  /* 1 argument */
        0x1A, 0x1A, 0x1A, 0x1A, 0x1A, 0x1A, 0x02, 9 /* 6 deep: refused */
    };
    static const uint8_t fl_errors[] = {
        0x01, 3,   14, 4, 1, /* 3 arguments, from the second */
        0x0D,                /* a function, not sent */
        0x02, 200,           /* 200 */
        0x83                 /* 256 */
    };
    static const uint8_t fl_floats[] = {
        0x01, 6,    14,   4,    0, /* 6 arguments */
        0x05, 0x15, 0x45, 0x85,    /* 0.0, -0.0, 255.0, 127.0 */
        0x06, 7,    0x16, 7        /* 7.0, 7.5 */
    };
    static const uint8_t fl_holes[] = {
        0x01, 3,    14,   4,    0,                /* 3 arguments */
        0x3B, 0x00, 0x02, 2,    0x00, 2, 0x02, 7, /* {nil, 2, nil}, t[6] = 7 */
        0x2C, 0x02, 1,    0x02, 2,            /* {1, 2} with __len, __index */
        0x4A, 0x02, 1,    0x00, 0x02, 3, 0x00 /* {1, nil, 3, nil} */
    };
    static const uint8_t fl_cycle[] = {
        0x01, 1,    14,   4, 0, /* 1 argument */
        0x2A, 0x0E, 0x02, 1     /* t = {t, 1} */
    };
    static const uint8_t fl_cap[] = {
        0x01, 2,    0x10 | 14, 0xFF, 0xFF, 4, 0, /* 2 arguments, cap 65535 */
        0x09, 0xFE, 0xFF,                        /* 65534 bytes of 00 */
        0x1A, 0x02, 7                            /* {7}: 65535 in all */
    };
    static const uint8_t fl_over[] = {
        0x01, 2,    14,   4, 0, /* 2 arguments */
        0x19, 0x00, 0x00,       /* 65536 bytes of 11h */
        0x02, 1                 /* 1 */
    };
    static const uint8_t fl_other[] = {
        0x01, 7,    15,   2, 0, /* 7 arguments, cap 65536 */
        0x0F, 0x1F, 0x2F,       /* userdata, light userdata, thread */
        0x05, 0x15,             /* 0.0, -0.0 */
        0x45, 0x65,             /* 255.0, 256.0 */
        0x0D                    /* a C function */
    };
    struct sgen g;
    uint8_t big[255];
    int i;

    gen_write(dir, "script", "flatten-basic", fl_basic, sizeof fl_basic);
    gen_write(dir, "script", "flatten-deep-5", fl_deep5, sizeof fl_deep5);
    gen_write(dir, "script", "flatten-deep-6", fl_deep6, sizeof fl_deep6);
    gen_write(dir, "script", "flatten-errors", fl_errors, sizeof fl_errors);
    gen_write(dir, "script", "flatten-floats", fl_floats, sizeof fl_floats);
    gen_write(dir, "script", "flatten-holes-meta", fl_holes, sizeof fl_holes);
    gen_write(dir, "script", "flatten-cycle", fl_cycle, sizeof fl_cycle);
    gen_write(dir, "script", "flatten-cap", fl_cap, sizeof fl_cap);
    gen_write(dir, "script", "flatten-over-cap", fl_over, sizeof fl_over);
    gen_write(dir, "script", "flatten-other", fl_other, sizeof fl_other);

    /* Each of the script's IDs, homed first (speed mode needs it). */
    for (i = 0; i < (int)sizeof big; i++)
        big[i] = (uint8_t)i;
    sc_begin(&g, 0x02);
    sc_rec(&g, 0xB0, SC_CTL(0, 2, 0), "echo", 4);
    sc_rec(&g, 0xB0, SC_CTL(1, 2, 0), big, sizeof big);
    sc_rec(&g, 0xB1, SC_CTL(0, 2, 0), "\xC8\x01\x02", 3);
    sc_rec(&g, 0xB1, SC_CTL(1, 2, 0), NULL, 0);
    sc_rec(&g, 0xB2, SC_CTL(0, 2, 0), floats, sizeof floats);
    sc_rec1(&g, 0xB3, SC_CTL(0, 2, 0), 5);
    sc_rec1(&g, 0xB3, SC_CTL(1, 2, 0), 200);
    sc_rec1(&g, 0xB4, SC_CTL(0, 4, 0), 8);
    sc_rec1(&g, 0xB5, SC_CTL(0, 2, 0), 3);
    sc_rec1(&g, 0xB6, SC_CTL(0, 2, 0), 2);
    sc_recf(&g, 0xB7, SC_CTL(0, 6, 0), 20.0f, 0);
    sc_recf(&g, 0xB7, SC_CTL(0, 4, 0), -20.0f, 1);
    sc_rec1(&g, 0xB8, SC_CTL(0, 1, 0), 1);
    sc_rec(&g, 0xBA, SC_CTL(1, 1, 0), "hi", 2);
    sc_rec1(&g, 0xB8, SC_CTL(0, 1, 0), 0);
    sc_rec(&g, 0xBA, SC_CTL(0, 1, 0), "hi", 2);
    sc_rec(&g, 0xBB, SC_CTL(1, 1, 0), NULL, 0);
    sc_rec1(&g, 0xB9, SC_CTL(0, 1, 0), 3);
    sc_rec(&g, 0xBC, SC_CTL(0, 1, 0), NULL, 0);
    sc_rec(&g, WSG_CMD_GET_SYSTEM_STATE, SC_CTL(0, 1, 0), NULL, 0);
    sc_save(&g, dir, "script-each-id");

    /* A sleeping script and 70 packets: the queue fills, E_OVERRUN. */
    sc_begin(&g, 0);
    sc_rec1(&g, 0xB4, SC_CTL(0, 0, 0), 200);
    for (i = 0; i < 70; i++) {
        sc_rec1(&g, i % 3 ? 0xB0 : 0xBB, SC_CTL((unsigned)i & 1u, 0, 0),
                (uint8_t)i);
    }
    sc_rec(&g, WSG_CMD_GET_WIDTH, SC_CTL(0, 7, 0), NULL, 0);
    sc_save(&g, dir, "script-queue-full");

    /* A loop preempted with packets behind it. */
    sc_begin(&g, 0);
    sc_rec1(&g, 0xB5, SC_CTL(0, 0, 0), 255);
    sc_rec1(&g, 0xB0, SC_CTL(1, 0, 0), 1);
    sc_rec(&g, 0xBB, SC_CTL(0, 1, 0), NULL, 0);
    sc_rec1(&g, 0xB5, SC_CTL(1, 5, 0), 40);
    sc_rec(&g, 0xBB, SC_CTL(0, 1, 0), NULL, 0);
    sc_save(&g, dir, "script-preempted");

    /* Failure (D20), the IDs unknown, a restart; an end of its own. */
    sc_begin(&g, 0);
    sc_rec1(&g, 0xB9, SC_CTL(0, 1, 0), 0xEE);
    sc_rec1(&g, 0xB0, SC_CTL(0, 1, 0), 1);
    sc_rec(&g, WSG_CMD_GET_SYSTEM_STATE, SC_CTL(1, 1, 0), NULL, 0);
    sc_rec1(&g, 0xB0, SC_CTL(0, 1, SC_RESTART), 2);
    sc_rec1(&g, 0xB9, SC_CTL(1, 1, 0), 0xED);
    sc_rec1(&g, 0xB1, SC_CTL(1, 1, 0), 3);
    sc_rec1(&g, 0xB1, SC_CTL(1, 1, SC_RESTART), 4);
    sc_rec1(&g, 0xB0, SC_CTL(0, 1, SC_STOP), 5);
    sc_save(&g, dir, "script-fail-end-restart");

    /* Answers whose session closed: to the other session, or nowhere. */
    sc_begin(&g, 0);
    sc_rec1(&g, 0xB4, SC_CTL(1, 0, SC_CLOSE), 40);
    sc_rec1(&g, 0xB0, SC_CTL(0, 5, 0), 1);
    sc_rec1(&g, 0xB4, SC_CTL(1, 0, SC_CLOSE), 40);
    sc_rec1(&g, 0xB3, SC_CTL(1, 5, SC_CLOSE), 1);
    sc_rec1(&g, 0xB0, SC_CTL(0, 1, 0), 2);
    sc_save(&g, dir, "script-orphans");

    /* 07h, then the script's IDs refused on that connection only; a
     * datagram, a split frame, a broken checksum, a power cycle. */
    sc_begin(&g, 0);
    sc_rec(&g, WSG_CMD_DISCONNECT, SC_CTL(0, 1, 0), NULL, 0);
    sc_rec1(&g, 0xB0, SC_CTL(0, 1, 0), 1);
    sc_rec1(&g, 0xB0, SC_CTL(1, 1, SC_DATAGRAM), 2);
    sc_rec(&g, 0xB1, SC_CTL(1, 1, SC_SPLIT), "split", 5);
    sc_rec1(&g, 0xB0, SC_CTL(1, 1, SC_BAD_CRC), 3);
    sc_rec1(&g, 0xB0, SC_CTL(1, 1, SC_RESET), 4);
    sc_rec1(&g, 0xB0, SC_CTL(0, 1, SC_CLOSE), 5);
    sc_rec1(&g, 0xB0, SC_CTL(0, 1, 0), 6);
    sc_save(&g, dir, "script-transports");

    /* Speed mode against the host's commands, and memory past the cap. */
    sc_begin(&g, 0x02);
    sc_recf(&g, 0xB7, SC_CTL(0, 6, 0), 30.0f, 0);
    sc_rec(&g, WSG_CMD_STOP, SC_CTL(1, 1, 0), NULL, 0);
    sc_recf(&g, 0xB7, SC_CTL(0, 7, 0), -80.0f, 0);
    sc_rec(&g, WSG_CMD_GET_WIDTH, SC_CTL(1, 1, 0), NULL, 0);
    sc_rec1(&g, 0xB6, SC_CTL(0, 1, 0), 255);
    sc_rec1(&g, 0xB6, SC_CTL(0, 1, 0), 60);
    sc_rec1(&g, 0xB6, SC_CTL(0, 1, 0), 30);
    sc_rec(&g, WSG_CMD_FAST_STOP, SC_CTL(1, 1, 0), NULL, 0);
    sc_recf(&g, 0xB7, SC_CTL(0, 1, 0), 10.0f, 0);
    sc_rec1(&g, 0xB9, SC_CTL(0, 1, 0), 0xEC);
    sc_rec1(&g, 0xB0, SC_CTL(0, 1, SC_RESTART), 1);
    sc_rec1(&g, 0xB9, SC_CTL(0, 1, 0), 0xEB);
    sc_save(&g, dir, "script-speed-memory");

    /* The rest of the library, each function once, homed. */
    sc_begin(&g, 0x02);
    for (i = 0; i < 30; i++) {
        uint8_t p[10] = {(uint8_t)i};

        wsg_put_f32(p + 1, i % 2 ? 40.0f : -1.0f);
        wsg_put_f32(p + 5, i % 3 ? 50.0f : NAN);
        p[9] = (uint8_t)(i * 7);
        sc_rec(&g, 0xBD, SC_CTL((unsigned)i & 1u, 2, 0), p, sizeof p);
    }
    sc_save(&g, dir, "script-library");
}

/* ---- the pattern harness (fuzz_match.c) ---- */

/* Its call byte: the function, and what else is given. */
#define FM_FIND     0x00
#define FM_MATCH    0x01
#define FM_GMATCH   0x02
#define FM_GSUB     0x03
#define FM_PLAIN    0x04
#define FM_TABLE    0x08
#define FM_JOIN     0x10
#define FM_KEEP     0x18
#define FM_ARG      0x20
#define FM_NO_YIELD 0x40
#define FM_TOKENS   0x80

/* A length as the harness reads it: two bytes, little-endian. */
static size_t gen_len(uint8_t *b, size_t len)
{
    b[0] = (uint8_t)(len & 0xFF);
    b[1] = (uint8_t)(len >> 8);
    return 2;
}

/* One input: the call, the slice's steps less one, the init or count,
 * then the subject, the pattern and the replacement, each with its
 * length. The subject is reps copies of s, the pattern preps of p. */
static void gen_match_rep(const char *dir, const char *name, unsigned op,
                          unsigned slice, int arg, const char *s,
                          unsigned reps, const char *p, unsigned preps,
                          const char *r)
{
    uint8_t b[4096];
    size_t n = 0, ls = strlen(s) * reps, lp = strlen(p) * preps;
    size_t lr = strlen(r), i;

    if (ls > 1024 || lp > 1024 || lr > 255)
        abort();
    b[n++] = (uint8_t)op;
    b[n++] = (uint8_t)slice;
    b[n++] = (uint8_t)(int8_t)arg;
    n += gen_len(b + n, ls);
    for (i = 0; i < reps; i++) {
        memcpy(b + n, s, strlen(s));
        n += strlen(s);
    }
    n += gen_len(b + n, lp);
    for (i = 0; i < preps; i++) {
        memcpy(b + n, p, strlen(p));
        n += strlen(p);
    }
    n += gen_len(b + n, lr);
    memcpy(b + n, r, lr);
    n += lr;
    gen_write(dir, "match", name, b, n);
}

static void gen_match(const char *dir, const char *name, unsigned op,
                      unsigned slice, int arg, const char *s, unsigned reps,
                      const char *p, const char *r)
{
    gen_match_rep(dir, name, op, slice, arg, s, reps, p, 1, r);
}

static void gen_patterns(const char *dir)
{
    /* gsub by tokens: a ) . b + c - ? on "ab(abc a", into "<%1>". */
    static const uint8_t tokens[] = {
        0x83, 3, 0, 8, 0, 'a', 'b', '(', 'a', 'b', 'c', ' ', 'a', 8,  0,
        0,    4, 6, 1, 8, 2,   9,   10,  4,   0,   '<', '%', '1', '>'};

    /* What held the daemon, small: a slice of 1 step yields at each. */
    gen_match(dir, "balance", FM_FIND, 0, 0, "(", 200, "%b()", "");
    gen_match(dir, "balance-nested", FM_GMATCH, 2, 0, "x((a)(b))y(()", 1,
              "%b()", "");
    gen_match(dir, "long-set", FM_FIND, 5, 0, "b", 60,
              "[aaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaa]", "");
    gen_match(dir, "long-literal", FM_MATCH, 3, 0, "a", 200,
              "aaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaab", "");
    gen_match(dir, "plain-find", FM_FIND | FM_PLAIN, 0, 0, "a", 250,
              "aaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaa"
              "aaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaab",
              "");
    gen_match(dir, "gsub-backtrack", FM_GSUB, 7, 0, "a", 60, ".-.-b", "x");
    gen_match(dir, "lazy-many", FM_FIND, 9, 0, "a", 200,
              ".-.-.-.-.-.-.-.-.-.-a", "");
    /* The language. */
    gen_match(dir, "set-classes", FM_GMATCH, 4, 0, "  foo_bar9 = 1, _x2 ", 1,
              "[%a_][%w_]*", "");
    gen_match(dir, "captures", FM_MATCH, 1, 0, "key = value", 1,
              "^(%w+)%s*=%s*(%w+)$", "");
    gen_match(dir, "positions", FM_GMATCH, 0, 0, "one two", 1, "()(%a+)()",
              "");
    gen_match(dir, "empty-matches", FM_GMATCH, 1, 0, "baaac", 1, "a*", "");
    gen_match(dir, "backref", FM_MATCH, 2, 0, "xaabaay", 1, "(a+)b%1", "");
    gen_match(dir, "frontier", FM_GSUB, 3, 0, "THE (quick) fox", 1,
              "%f[%a]%a+", "<%0>");
    gen_match(dir, "anchored", FM_MATCH, 0, 0, "xxxxy", 1, "^(x*)$", "");
    gen_match(dir, "optional", FM_FIND | FM_ARG, 1, -4, "color colour", 1,
              "colou?r", "");
    gen_match(dir, "plus-minus", FM_GSUB, 2, 0, "<a><bb><>", 1, "<(.-)>",
              "[%1]");
    gen_match(dir, "empty-items", FM_GMATCH, 0, 0, "cb xb xxb", 1,
              "(x-)(a?)(y*)b", "");
    gen_match(dir, "dollar-mid", FM_FIND, 0, 0, "a$b", 1, "a$b", "");
    gen_match(dir, "gsub-count", FM_GSUB | FM_ARG, 1, 2, "a a a a", 1, "a",
              "b");
    gen_match(dir, "gsub-anchored", FM_GSUB, 0, 0, "aaa", 1, "^a", "b");
    gen_match(dir, "gsub-table", FM_GSUB | FM_TABLE, 1, 0, "a b ab d", 1,
              "%w+", "");
    gen_match(dir, "gsub-function", FM_GSUB | FM_JOIN, 0, 0, "a=1, b=2", 1,
              "(%w+)=(%w+)", "");
    gen_match(dir, "gsub-keep", FM_GSUB | FM_KEEP, 2, 0, "a b x y", 1, "%w",
              "");
    gen_match(dir, "gsub-positions", FM_GSUB, 0, 0, "abc", 1, "()", "%1,");
    gen_match(dir, "no-yield", FM_GSUB | FM_NO_YIELD, 0, 0, "(", 100, "%b()",
              "x");
    gen_match(dir, "z-class", FM_FIND, 1, 0, "a\001b", 1, "%z*[%c]b", "");
    gen_write(dir, "match", "tokens", tokens, sizeof tokens);
    /* The errors, raised when the machine reaches them. */
    gen_match(dir, "err-set", FM_FIND, 0, 0, "abc", 1, "b[a", "");
    gen_match(dir, "err-set-never", FM_FIND, 0, 0, "abc", 1, "x[a", "");
    gen_match(dir, "err-escape", FM_MATCH, 0, 0, "abc", 1, "a%", "");
    gen_match(dir, "err-capture-index", FM_MATCH, 0, 0, "abc", 1, "(a)%2", "");
    gen_match(dir, "err-unfinished", FM_MATCH, 0, 0, "abc", 1, "(a", "");
    gen_match(dir, "err-close", FM_MATCH, 0, 0, "abc", 1, "a)", "");
    gen_match(dir, "err-balance-args", FM_FIND, 0, 0, "abc", 1, "%b(", "");
    gen_match(dir, "err-frontier", FM_FIND, 0, 0, "abc", 1, "%fa", "");
    gen_match(dir, "err-too-many", FM_MATCH, 0, 0, "a", 1,
              "((((((((((((((((((((((((((((((((((a))))))))))))))))))))))))"
              "))))))))",
              "");
    gen_match_rep(dir, "err-too-complex", FM_MATCH, 0, 0, "a", 220, "a?", 220,
                  "");
    gen_match_rep(dir, "depth-199", FM_MATCH, 0, 0, "a", 220, "a?", 199, "");
    gen_match(dir, "err-replacement", FM_GSUB, 0, 0, "abc", 1, "b", "%");
    gen_match(dir, "err-replacement-index", FM_GSUB, 0, 0, "abc", 1, "b",
              "%2");
    gen_match(dir, "err-replacement-value", FM_GSUB | FM_KEEP, 0, 0, "abc", 1,
              "c", "");
}

/* ---- corpus/fingers (fuzz_fingers.c) and corpus/fdev (fuzz_fdev.c) ---- */

struct fgen {
    uint8_t b[GEN_MAX];
    size_t n;
};

static void fg_bytes(struct fgen *g, const void *p, size_t len)
{
    if (g->n + len > GEN_MAX)
        abort();
    memcpy(g->b + g->n, p, len);
    g->n += len;
}

/* A finger command record (op 0..7: 60h..63h, 70h..73h). */
static void fg_rec(struct fgen *g, uint8_t op, uint8_t ctl, const void *p,
                   size_t len)
{
    uint8_t h[3] = {op, ctl, (uint8_t)len};

    fg_bytes(g, h, 3);
    fg_bytes(g, p, len);
}

/* Another command of the schema, by ID. */
static void fg_cmd(struct fgen *g, uint8_t id, uint8_t ctl, const void *p,
                   size_t len)
{
    uint8_t h[4] = {0xC0, ctl, (uint8_t)(len + 1), 0};

    while (h[3] < FUZZ_NIDS && fuzz_ids[h[3]] != id)
        h[3]++;
    fg_bytes(g, h, 4);
    fg_bytes(g, p, len);
}

static void fg_cmdf2(struct fgen *g, uint8_t id, uint8_t ctl, float a, float b)
{
    uint8_t p[8];

    wsg_put_f32(p, a);
    wsg_put_f32(p + 4, b);
    fg_cmd(g, id, ctl, p, sizeof p);
}

/* A change between chunks (fuzz_fingers.c: op 0xE0..0xE7). */
static void fg_event(struct fgen *g, uint8_t ev, const void *p, size_t len)
{
    fg_rec(g, (uint8_t)(0xE0 + ev), CTL_STEPS(STEPS_10), p, len);
}

static const uint8_t fuzz_finger_seed_ids[8] = {0x60, 0x61, 0x62, 0x63,
                                                0x70, 0x71, 0x72, 0x73};

static void gen_fingers(const char *dir)
{
    static const uint8_t i0 = 0, i1 = 1, i9 = 9, on1[2] = {1, 1},
                         off1[2] = {1, 0}, one = 1, zero = 0;
    /* kind k of finger i: byte (k << 1) | i */
    static const uint8_t dsa0 = 3u << 1, fmf1 = (2u << 1) | 1u, none0 = 0,
                         dev1[3] = {(4u << 1) | 1u, 0x10, 25};
    static const uint8_t uart1[4] = {0x00, 0xC2, 0x01, 0x00}; /* 115200 */
    static const uint8_t spi1[6] = {0x40, 0x42, 0x0F, 0x00, 8, 0};
    struct fgen g;
    int op;

    /* Each command alone, in both styles, on the default fingers. */
    for (op = 0; op < 8; op++) {
        char name[32];

        g.n = 0;
        fg_bytes(&g, &zero, 1);
        fg_rec(&g, (uint8_t)op, CTL_STEPS(STEPS_10),
               (op & 3) == 2 ? &one : NULL, (op & 3) == 2 ? 1 : 0);
        if (op < 4) {
            fg_rec(&g, (uint8_t)op, CTL_STEPS(STEPS_10),
                   (op & 3) == 2 ? on1 : &i1, (op & 3) == 2 ? 2 : 1);
            fg_rec(&g, (uint8_t)op, CTL_STEPS(STEPS_10), &i9, 1);
        }
        snprintf(name, sizeof name, "finger-%02x", fuzz_finger_seed_ids[op]);
        gen_write(dir, "fingers", name, g.b, g.n);
    }

    /* A DSA pad and an FMF finger feel a grasp; power off and on. */
    g.n = 0;
    fg_bytes(&g, "\x04", 1); /* force sensor */
    fg_event(&g, 0, &dsa0, 1);
    fg_event(&g, 0, &fmf1, 1);
    fg_cmd(&g, WSG_CMD_HOMING, CTL_STEPS(STEPS_1000), &i0, 1);
    fg_cmd(&g, WSG_CMD_HOMING, CTL_STEPS(STEPS_1000), NULL, 0);
    fg_cmd(&g, WSG_CMD_GET_GRASP_STATE,
           CTL_STEPS(STEPS_NONE) | CTL_WORLD(WORLD_PART), "\x46", 1);
    fg_cmdf2(&g, WSG_CMD_GRASP, CTL_STEPS(STEPS_1000), 30.0f, 50.0f);
    fg_rec(&g, 3, CTL_STEPS(STEPS_10), NULL, 0);
    fg_rec(&g, 7, CTL_STEPS(STEPS_10), NULL, 0);
    fg_rec(&g, 1, CTL_STEPS(STEPS_10), &i0, 1);
    fg_event(&g, 3, "\x19\x32", 2); /* a 5 x 10 mm patch */
    fg_event(&g, 2, NULL, 0);       /* tare */
    fg_rec(&g, 7, CTL_STEPS(STEPS_10), NULL, 0);
    fg_rec(&g, 6, CTL_STEPS(STEPS_10), &zero, 1);
    fg_rec(&g, 7, CTL_STEPS(STEPS_10), NULL, 0);
    fg_rec(&g, 2, CTL_STEPS(STEPS_10), off1, 2);
    fg_rec(&g, 3, CTL_STEPS(STEPS_10), &i1, 1);
    fg_event(&g, 0, &none0, 1);
    fg_rec(&g, 2, CTL_STEPS(STEPS_10), &one, 1);
    fg_rec(&g, 3, CTL_STEPS(STEPS_10), NULL, 0);
    fg_cmd(&g, WSG_CMD_TARE, CTL_STEPS(STEPS_10), NULL, 0);
    gen_write(dir, "fingers", "seq-grasp", g.b, g.n);

    /* Custom electronics on finger 2: UART echo, SPI, a failing link. */
    g.n = 0;
    fg_bytes(&g, &zero, 1);
    fg_event(&g, 0, dev1, sizeof dev1);
    fg_event(&g, 4, uart1, sizeof uart1);
    fg_event(&g, 6, "\x01za", 3);
    fg_rec(&g, 5, CTL_STEPS(STEPS_200), NULL, 0);
    fg_event(&g, 7, &one, 1);
    fg_rec(&g, 7, CTL_STEPS(STEPS_10), NULL, 0);
    fg_event(&g, 5, spi1, sizeof spi1);
    fg_event(&g, 7, "\x03\x01\x02\x03", 4);
    fg_event(&g, 0, "\x09\x01\x10", 3); /* its data() fails */
    fg_rec(&g, 7, CTL_STEPS(STEPS_10), NULL, 0);
    fg_cmd(&g, WSG_CMD_GET_SYSTEM_STATE, CTL_STEPS(STEPS_10), NULL, 0);
    fg_rec(&g, 6, CTL_STEPS(STEPS_10), &zero, 1);
    fg_rec(&g, 6, CTL_STEPS(STEPS_10), &one, 1);
    fg_rec(&g, 5, CTL_STEPS(STEPS_10), NULL, 0);
    gen_write(dir, "fingers", "seq-device", g.b, g.n);
}

/* fuzz_fdev.c's records: [op][length][bytes]. */
static void fd_rec(struct fgen *g, uint8_t op, const void *p, size_t len)
{
    uint8_t h[2] = {op, (uint8_t)len};

    fg_bytes(g, h, 2);
    fg_bytes(g, p, len);
}

static void gen_fdev(const char *dir)
{
    static const char tip[] =
        "DATA_SIZE = 4\n"
        "function on_uart(b)\n"
        "  if b:find('z', 1, true) then dev.send('x') end\n"
        "  if b:find('a', 1, true) then dev.send(string.rep('\\0', 50)) end\n"
        "end\n"
        "function on_spi(tx) return string.char(42) .. tx end\n"
        "function data() return 'abcd' end\n";
    static const uint8_t baud[4] = {0x00, 0xC2, 0x01, 0x00};
    static const uint8_t steps = 10, off = 0, on = 0;
    struct fgen g;
    unsigned k;

    /* The example the public scripts follow: power cycle, z/x, a and 50
     * bytes, an SPI poll, 63h. */
    g.n = 0;
    fg_bytes(&g, "\x01", 1);
    fg_bytes(&g, tip, sizeof tip); /* with its NUL */
    fd_rec(&g, 4, &off, 1);
    fd_rec(&g, 4 | 8, &on, 1);
    fd_rec(&g, 0, baud, sizeof baud);
    fd_rec(&g, 1, "z", 1);
    fd_rec(&g, 3, &steps, 1);
    fd_rec(&g, 6, NULL, 0);
    fd_rec(&g, 1, "a", 1);
    fd_rec(&g, 3, &steps, 1);
    fd_rec(&g, 6, NULL, 0);
    fd_rec(&g, 5, NULL, 0);
    fd_rec(&g, 7, NULL, 0);
    fd_rec(&g, 2, "\x00\x00", 2);
    gen_write(dir, "fdev", "tip", g.b, g.n);

    /* Each of fdev_model's behaviours, over the UART and over SPI. */
    for (k = 0; k < 16; k++) {
        uint8_t b = (uint8_t)(k | 0x10);
        char name[32];

        g.n = 0;
        fg_bytes(&g, "\x00\x08", 2); /* DATA_SIZE 8 */
        fd_rec(&g, 0, baud, sizeof baud);
        fd_rec(&g, 1, &b, 1);
        fd_rec(&g, 3, &steps, 1);
        fd_rec(&g, 6, NULL, 0);
        fd_rec(&g, 5, NULL, 0);
        fd_rec(&g, 4, &off, 1);
        fd_rec(&g, 4 | 8, &on, 1);
        fd_rec(&g, 7, NULL, 0);
        fd_rec(&g, 2, &b, 1);
        fd_rec(&g, 5, NULL, 0);
        snprintf(name, sizeof name, "model-%02u", k);
        gen_write(dir, "fdev", name, g.b, g.n);
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

    gen_script(dir);
    gen_patterns(dir);
    gen_fingers(dir);
    gen_fdev(dir);
    return 0;
}
