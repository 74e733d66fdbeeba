/*
 * Harness 6: arbitrary bytes as what a GCL client sends (wsg/gcl.h), cut
 * into chunks of random sizes, through two things at once:
 *
 *   (a) the line codec and the parser alone: every byte is consumed, an
 *       event comes only at a newline and is the one a reference model of
 *       the codec expects there (a line, too long, binary bytes, or none
 *       for an empty line), a line is at most WSG_GCL_LINE_MAX bytes, and
 *       the parser, given each line (and each chunk) in a buffer of exactly
 *       its length, reads nothing past it and returns a name in upper case
 *       no longer than WSG_GCL_NAME_MAX, at most WSG_GCL_ARGS_MAX
 *       arguments and only finite numbers;
 *   (b) the interpreter on a gripper (one text session, as the TCP
 *       transport has with --text-interface): every line the codec reports
 *       gets exactly one immediate answer (ACK NAME, ERR NAME code, or
 *       NAME=value, with the name the line's), before the next line; what
 *       else is sent is a motion's final result (FIN or ERR with the
 *       motion's name), exactly one for each motion acknowledged, or a
 *       stream line (@KEY=value) while streams are polled; each send
 *       carries one line of printable ASCII and its newline; and the model
 *       stays within its stroke.
 *
 * Input: four header bytes, then text. Header byte 0 selects the model
 * (bits 0-1) and the force sensor (bit 2); bytes 1-3 seed the generator
 * that cuts the chunks and sometimes steps the model between them, so the
 * fuzzer varies the cuts without touching the text. A line of the text
 * that starts with '#' is the harness's, for (b) only: "#s N" steps the
 * model N times (the streams polled after each), "#p W [K]" places a part
 * of width W mm (within the opening) and stiffness K, "#p" removes it,
 * "#o W" places an obstacle, "#o" removes it, "#f B" sets or clears
 * faults (B's bits 0-4 select, bit 7 sets, as in fuzz_bench.h), "#c"
 * closes the connection (FAST STOP unless BYE() came first) and opens a
 * new one. The seeds (corpus/gcl) are text files in this form.
 *
 * At the end the model is stepped until no motion is left, and every
 * motion acknowledged must have had its final result. Set FUZZ_TRACE in
 * the environment to print every line in and out of a replayed input.
 */
#include <ctype.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "axis_impl.h"
#include "fuzz_axis.h"
#include "fuzz_check.h"
#include "wsg/device.h"
#include "wsg/gcl.h"

#ifndef FUZZ_ENTRY
#define FUZZ_ENTRY LLVMFuzzerTestOneInput
#endif

int FUZZ_ENTRY(const uint8_t *data, size_t size);

#define FUZZ_HEADER 4u
/* Steps one "#s" may ask for, and at the end at most (as fuzz_bench: a
 * full stroke of the longest model at the lowest speed fits). */
#define FUZZ_STEPS_MAX 10000L
#define FUZZ_END_STEPS 100000L
/* Motions acknowledged and not finished: one at a time on one axis; the
 * room is for a violation to show as one rather than as an overflow. */
#define FUZZ_OWED 8

/* ---- the chunk generator ---- */

static uint32_t fuzz_rand(uint32_t *x)
{
    /* xorshift32: deterministic per input, never 0 from a nonzero seed. */
    *x ^= *x << 13;
    *x ^= *x >> 17;
    *x ^= *x << 5;
    return *x;
}

/* Mostly short chunks (a line in pieces, several lines at once), now and
 * then a long one. */
static size_t fuzz_chunk(uint32_t *x, size_t left)
{
    uint32_t r = fuzz_rand(x);
    size_t n = (r & 7u) == 0 ? 1u + (r >> 8) % 512u : 1u + (r >> 8) % 24u;

    return n < left ? n : left;
}

/* ---- (a) the codec against a reference ---- */

/* What the codec should report at a newline, from the bytes of the line. */
struct fuzz_ref {
    size_t raw; /* bytes since the last newline */
    size_t crs; /* of them, CRs at the end */
    int binary; /* a byte no text line has */
    char buf[WSG_GCL_LINE_MAX + 1];
};

static int fuzz_text_byte(uint8_t b)
{
    return (b >= 0x20 && b < 0x7F) || b == '\t' || b == '\r';
}

static void fuzz_ref_byte(struct fuzz_ref *r, uint8_t b)
{
    if (r->raw < sizeof r->buf)
        r->buf[r->raw] = (char)b;
    r->raw++;
    r->crs = b == '\r' ? r->crs + 1 : 0;
    if (!fuzz_text_byte(b))
        r->binary = 1;
}

/* At a newline: the event expected, and the line's length without its CRs.
 * A line of WSG_GCL_LINE_MAX bytes or less whose CR LF takes it past the
 * limit is reported too long by the codec (it counts the CRs), where
 * gcl.h measures a line without them: *alt is the event gcl.h's reading
 * gives, accepted too (the README's fuzzing notes); else it is the one
 * returned. */
static enum wsg_gcl_event fuzz_ref_end(struct fuzz_ref *r, size_t *content,
                                       enum wsg_gcl_event *alt)
{
    enum wsg_gcl_event ev;

    *content = r->raw - r->crs;
    if (r->raw > WSG_GCL_LINE_MAX)
        ev = WSG_GCL_TOO_LONG;
    else if (r->binary)
        ev = WSG_GCL_BINARY;
    else if (*content > 0)
        ev = WSG_GCL_LINE;
    else
        ev = WSG_GCL_NONE;
    *alt = ev;
    if (r->raw > WSG_GCL_LINE_MAX && *content <= WSG_GCL_LINE_MAX)
        *alt = r->binary      ? WSG_GCL_BINARY
               : *content > 0 ? WSG_GCL_LINE
                              : WSG_GCL_NONE;
    r->raw = r->crs = 0;
    r->binary = 0;
    return ev;
}

/* Length of a string in a buffer of max bytes, NUL or not (C99 has no
 * strnlen). */
static size_t fuzz_strlen(const char *s, size_t max)
{
    const char *z = memchr(s, '\0', max);

    return z ? (size_t)(z - s) : max;
}

/* The parser on exactly n bytes of a heap copy, so that ASan sees a read
 * past them; the command it fills is sane whatever the outcome. */
static void fuzz_parse(const char *text, size_t n)
{
    struct wsg_gcl_cmd c;
    char *copy = malloc(n ? n : 1);
    size_t k;
    unsigned i;
    int rc;

    FUZZ_CHECK(copy != NULL);
    memcpy(copy, text, n);
    rc = wsg_gcl_parse(copy, n, &c);
    free(copy);
    FUZZ_CHECK(rc == 0 || rc == -1);
    k = fuzz_strlen(c.name, sizeof c.name);
    FUZZ_CHECK(k <= WSG_GCL_NAME_MAX);
    FUZZ_CHECK(k == 0 || isupper((unsigned char)c.name[0]));
    for (i = 0; i < k; i++)
        FUZZ_CHECK(isupper((unsigned char)c.name[i]) ||
                   isdigit((unsigned char)c.name[i]) || c.name[i] == '_');
    if (rc < 0)
        return;
    FUZZ_CHECK(k > 0);
    FUZZ_CHECK(c.form == WSG_GCL_CALL || c.form == WSG_GCL_QUERY ||
               c.form == WSG_GCL_SET);
    FUZZ_CHECK(c.nargs <= WSG_GCL_ARGS_MAX);
    FUZZ_CHECK(c.index >= -1 && c.index <= 255);
    FUZZ_CHECK(c.index < 0 || c.form == WSG_GCL_QUERY);
    FUZZ_CHECK(c.form != WSG_GCL_SET || c.nargs == 1);
    FUZZ_CHECK(c.form != WSG_GCL_QUERY || c.nargs == 0);
    for (i = 0; i < c.nargs; i++) {
        if (c.arg[i].is_str)
            FUZZ_CHECK(fuzz_strlen(c.arg[i].str, sizeof c.arg[i].str) <=
                       WSG_GCL_STR_MAX);
        else
            FUZZ_CHECK(isfinite(c.arg[i].num));
    }
}

static void fuzz_codec(const uint8_t *data, size_t size, uint32_t seed)
{
    static struct wsg_gcl_line l;
    static struct fuzz_ref r;
    size_t i = 0;

    wsg_gcl_line_init(&l);
    memset(&r, 0, sizeof r);
    while (i < size) {
        size_t len = fuzz_chunk(&seed, size - i);
        const uint8_t *p = data + i;

        fuzz_parse((const char *)p, len);
        i += len;
        while (len > 0) {
            enum wsg_gcl_event ev, want = WSG_GCL_NONE, alt = WSG_GCL_NONE;
            const char *line = NULL;
            size_t n = 0, used, k, content = 0;

            used = wsg_gcl_line_feed(&l, p, len, &ev, &line, &n);
            FUZZ_CHECK(used >= 1 && used <= len);
            FUZZ_CHECK(ev == WSG_GCL_NONE || ev == WSG_GCL_LINE ||
                       ev == WSG_GCL_TOO_LONG || ev == WSG_GCL_BINARY);
            /* An event ends the call at its newline; without one, all of
             * the chunk is taken. */
            FUZZ_CHECK(ev == WSG_GCL_NONE ? used == len : p[used - 1] == '\n');
            for (k = 0; k < used; k++) {
                if (p[k] != '\n') {
                    fuzz_ref_byte(&r, p[k]);
                    continue;
                }
                want = fuzz_ref_end(&r, &content, &alt);
                /* Only the call's last byte may end a line with an event. */
                if (k + 1 < used)
                    FUZZ_CHECK(want == WSG_GCL_NONE && alt == WSG_GCL_NONE);
            }
            if (p[used - 1] == '\n')
                FUZZ_CHECK(ev == want || ev == alt);
            else
                FUZZ_CHECK(ev == WSG_GCL_NONE);
            if (ev == WSG_GCL_LINE) {
                FUZZ_CHECK(line != NULL && n >= 1 && n <= WSG_GCL_LINE_MAX);
                /* The line's bytes, still in r.buf (reset, not cleared). */
                FUZZ_CHECK(n == content && line[n] == '\0');
                FUZZ_CHECK(memcmp(line, r.buf, n) == 0);
                FUZZ_CHECK(memchr(line, '\n', n) == NULL);
                FUZZ_CHECK(line[n - 1] != '\r');
                for (k = 0; k < n; k++)
                    FUZZ_CHECK(fuzz_text_byte((uint8_t)line[k]));
                fuzz_parse(line, n);
            }
            p += used;
            len -= used;
        }
    }
}

/* ---- (b) the interpreter on a gripper ---- */

enum fuzz_phase {
    FUZZ_PH_IDLE,  /* nothing may be sent */
    FUZZ_PH_INPUT, /* answers to lines, final results a command caused */
    FUZZ_PH_STEP,  /* final results (steps, world events, a close) */
    FUZZ_PH_STREAM /* @ lines */
};

static struct {
    struct wsg_device dev;
    struct wsg_session s;
    struct wsg_gcl g;
    int closing; /* its tag resolves no more, as in a transport */
    uint32_t next_tag;
    enum fuzz_phase phase;
    /* The line being answered: its name as the answer must carry it. */
    int line_open;
    char name[WSG_GCL_NAME_MAX + 1];
    unsigned answers;
    unsigned long lines; /* lines the interpreter reported */
    /* A final result the device just looked up: the next send is it. */
    const char *final_name;
    /* Motions acknowledged, in order, with the session's tag. */
    struct {
        uint32_t tag;
        const char *name;
    } owed[FUZZ_OWED];
    unsigned nowed;
    int trace;
} G;

static const char *const fuzz_motions[] = {"HOME", "MOVE", "GRIP", "RELEASE"};

static const char *fuzz_motion(const char *name, size_t n)
{
    size_t i;

    for (i = 0; i < sizeof fuzz_motions / sizeof fuzz_motions[0]; i++)
        if (strlen(fuzz_motions[i]) == n &&
            memcmp(fuzz_motions[i], name, n) == 0)
            return fuzz_motions[i];
    return NULL;
}

static void fuzz_fail(const char *what, const char *line, size_t len)
{
    fprintf(stderr, "fuzz_gcl: %s: %.*s\n", what, (int)len, line);
    abort();
}

/* "ERR NAME code" or "ERR NAME code E_NAME" after its "ERR NAME ": the
 * code a status, and the text, when there, that status's name. */
static int fuzz_err_tail(const char *p, const char *end)
{
    const char *e;
    unsigned long code = 0;
    size_t n;

    if (p == end || !isdigit((unsigned char)*p))
        return 0;
    while (p < end && isdigit((unsigned char)*p) && code < 100000)
        code = code * 10 + (unsigned long)(*p++ - '0');
    if (code > WSG_E_FILE_EXISTS)
        return 0;
    if (p == end)
        return 1;
    if (*p++ != ' ')
        return 0;
    e = wsg_status_name((uint16_t)code);
    n = (size_t)(end - p);
    return e && strlen(e) == n && memcmp(e, p, n) == 0;
}

/* The line (without its newline) starts with the word w and a space. */
static int fuzz_word(const char *p, const char *end, const char *w)
{
    size_t n = strlen(w);

    return (size_t)(end - p) > n && memcmp(p, w, n) == 0 && p[n] == ' ';
}

static void fuzz_final(const char *line, size_t len)
{
    const char *end = line + len - 1, *name = G.final_name;
    size_t n = strlen(name);

    G.final_name = NULL;
    if (len - 1 == 4 + n && memcmp(line, "FIN ", 4) == 0 &&
        memcmp(line + 4, name, n) == 0)
        return;
    if (fuzz_word(line, end, "ERR") && fuzz_word(line + 4, end, name) &&
        fuzz_err_tail(line + 5 + n, end))
        return;
    fuzz_fail("not the final result of the motion acknowledged", line, len);
}

static void fuzz_immediate(const char *line, size_t len)
{
    const char *end = line + len - 1, *m;
    size_t n = strlen(G.name);

    if (!G.line_open)
        fuzz_fail("a line sent for no input line", line, len);
    if (++G.answers > 1)
        fuzz_fail("a second answer to one input line", line, len);
    if (fuzz_word(line, end, "ERR") && fuzz_word(line + 4, end, G.name) &&
        fuzz_err_tail(line + 5 + n, end))
        return;
    if (len - 1 == 4 + n && memcmp(line, "ACK ", 4) == 0 &&
        memcmp(line + 4, G.name, n) == 0) {
        m = fuzz_motion(G.name, n);
        if (m) {
            FUZZ_CHECK(G.nowed < FUZZ_OWED);
            G.owed[G.nowed].tag = G.s.tag;
            G.owed[G.nowed++].name = m;
        }
        return;
    }
    /* A value: NAME=..., or FDATA[i]=... */
    if ((size_t)(end - line) > n && memcmp(line, G.name, n) == 0 &&
        (line[n] == '=' || line[n] == '['))
        return;
    fuzz_fail("not an answer to the line", line, len);
}

static void fuzz_stream(const char *line, size_t len)
{
    static const char *const keys[] = {"POS", "SPEED", "FORCE", "GRIPSTATE",
                                       "SYSFLAGS"};
    size_t i, n;

    for (i = 0; i < sizeof keys / sizeof keys[0]; i++) {
        n = strlen(keys[i]);
        if (len > n + 3 && line[0] == '@' &&
            memcmp(line + 1, keys[i], n) == 0 && line[n + 1] == '=')
            return;
    }
    fuzz_fail("not a stream line", line, len);
}

static void fuzz_send(struct wsg_session *s, const uint8_t *pkt, size_t len)
{
    const char *line = (const char *)pkt;
    size_t i;

    if (G.trace)
        fprintf(stderr, "t=%lu out s%u ph%d %.*s",
                (unsigned long)wsg_device_axis(&G.dev)->time_us,
                (unsigned)s->tag, (int)G.phase, (int)len, line);
    FUZZ_CHECK(s == &G.s && !G.closing);
    /* One line per write, newline included (minWSG compares each recv()
     * with one whole line), of printable ASCII. */
    if (len < 2 || line[len - 1] != '\n')
        fuzz_fail("not one line", line, len);
    for (i = 0; i + 1 < len; i++)
        if (!(pkt[i] >= 0x20 && pkt[i] < 0x7F))
            fuzz_fail("not printable ASCII", line, len);
    if (G.final_name) {
        FUZZ_CHECK(G.phase == FUZZ_PH_INPUT || G.phase == FUZZ_PH_STEP);
        fuzz_final(line, len);
        return;
    }
    switch (G.phase) {
    case FUZZ_PH_INPUT:
        fuzz_immediate(line, len);
        break;
    case FUZZ_PH_STREAM:
        fuzz_stream(line, len);
        break;
    default:
        fuzz_fail("sent outside input, steps and stream polls", line, len);
    }
}

/* A final result leaves the model: the first motion owed under this tag,
 * sent if the session is still there. */
static struct wsg_session *fuzz_lookup(void *ctx, uint32_t tag)
{
    unsigned i;

    (void)ctx;
    FUZZ_CHECK(G.phase == FUZZ_PH_INPUT || G.phase == FUZZ_PH_STEP);
    FUZZ_CHECK(!G.final_name);
    for (i = 0; i < G.nowed && G.owed[i].tag != tag; i++)
        ;
    if (i == G.nowed) {
        fprintf(stderr,
                "fuzz_gcl: a final result for tag %u, which owes "
                "none\n",
                (unsigned)tag);
        abort();
    }
    if (G.trace)
        fprintf(stderr, "final for tag %u: %s\n", (unsigned)tag,
                G.owed[i].name);
    if (tag == G.s.tag && !G.closing)
        G.final_name = G.owed[i].name;
    memmove(&G.owed[i], &G.owed[i + 1], (G.nowed - i - 1) * sizeof G.owed[0]);
    G.nowed--;
    return G.final_name ? &G.s : NULL;
}

/* Each line the interpreter takes comes through the communication log's
 * hook before it runs: the previous one has had its answer by then. */
static void fuzz_trace_line(void *ctx, const struct wsg_session *s,
                            const char *line, size_t n)
{
    struct wsg_gcl_cmd c;

    (void)ctx;
    FUZZ_CHECK(G.phase == FUZZ_PH_INPUT && s == &G.s);
    FUZZ_CHECK(!G.line_open || G.answers == 1);
    if (G.trace)
        fprintf(stderr, "t=%lu in  %.*s\n",
                (unsigned long)wsg_device_axis(&G.dev)->time_us, (int)n, line);
    G.line_open = 1;
    G.answers = 0;
    G.lines++;
    /* The name the answer carries: the line's, as far as the parser read
     * it; "?" without one. "(line too long)" and "(binary bytes)", the
     * log's words for lines refused whole, have none either. */
    wsg_gcl_parse(line, n, &c);
    snprintf(G.name, sizeof G.name, "%s", c.name[0] ? c.name : "?");
}

/* The model within its limits (fuzz_axis.h), and the force limit GCL's
 * GRIP sets. */
static void fuzz_check_model(void)
{
    const struct wsg_axis *ax = wsg_device_axis(&G.dev);

    fuzz_check_axis(ax);
    FUZZ_CHECK(ax->force_limit >= 0 &&
               ax->force_limit <= ax->cfg.ovr_force + FUZZ_AXIS_EPS);
}

static void fuzz_open(void)
{
    /* The daemon's GCL settings: its default pull-back and speed. */
    static const struct wsg_gcl_config cfg = {10.0, 100.0};

    wsg_session_init(&G.s, G.next_tag++, WSG_SESSION_CONNECTION, fuzz_send,
                     NULL);
    wsg_gcl_init(&G.g, &G.dev, &G.s, &cfg);
    G.closing = 0;
}

static void fuzz_step(void)
{
    G.phase = FUZZ_PH_STEP;
    wsg_device_step(&G.dev);
    FUZZ_CHECK(!G.final_name);
    G.phase = FUZZ_PH_STREAM;
    wsg_device_poll_streams(&G.dev, &G.s);
    G.phase = FUZZ_PH_IDLE;
    fuzz_check_model();
}

static void fuzz_steps(long n)
{
    if (n > FUZZ_STEPS_MAX)
        n = FUZZ_STEPS_MAX;
    while (n-- > 0)
        fuzz_step();
}

/* The interpreter takes a chunk; every line in it was answered. */
static void fuzz_input(const uint8_t *p, size_t len)
{
    G.phase = FUZZ_PH_INPUT;
    wsg_gcl_input(&G.g, p, len);
    FUZZ_CHECK(!G.line_open || G.answers == 1);
    FUZZ_CHECK(!G.final_name);
    G.line_open = 0;
    G.phase = FUZZ_PH_IDLE;
    fuzz_check_model();
}

/* A directive line ("#s 100"): its letter and up to two numbers. */
static void fuzz_directive(const uint8_t *p, size_t n)
{
    static const uint32_t faults[] = {WSG_SF_TEMP_WARNING, WSG_SF_TEMP_FAULT,
                                      WSG_SF_POWER_FAULT, WSG_SF_CURR_FAULT,
                                      WSG_SF_FINGER_FAULT};
    struct wsg_axis *ax = wsg_device_axis(&G.dev);
    char buf[64], *q, *stop;
    double v[2] = {-1.0, 0.0};
    int nv = 0;
    unsigned i, bits;

    if (n < 2)
        return;
    if (n > sizeof buf - 1)
        n = sizeof buf - 1;
    memcpy(buf, p, n);
    buf[n] = '\0';
    for (q = buf + 2; nv < 2; q = stop) {
        double x = strtod(q, &stop);

        if (stop == q || !isfinite(x))
            break;
        v[nv++] = x;
    }
    if (G.trace)
        fprintf(stderr, "t=%lu world %s\n", (unsigned long)ax->time_us, buf);
    G.phase = FUZZ_PH_STEP;
    switch (buf[1]) {
    case 's':
        G.phase = FUZZ_PH_IDLE;
        fuzz_steps(nv > 0 && v[0] > 0 ? (long)fmin(v[0], 1e6) : 1);
        return;
    case 'p': {
        /* Within the opening: the model takes a wider part as one already
         * squeezed past any force limit (the README's fuzzing notes). */
        double open = ax->width - ax->ref_offset;

        wsg_axis_set_part(ax, nv ? fmin(fmax(v[0], 0.0), open) : -1.0,
                          nv > 1 ? fmin(fmax(v[1], 0.0), 1000.0) : 0.0);
        break;
    }
    case 'o':
        wsg_axis_set_obstacle(ax, nv ? fmin(fmax(v[0], 0.0), ax->cfg.stroke)
                                     : -1.0);
        break;
    case 'f':
        /* A byte, whatever number the fuzzer wrote. */
        bits = nv ? (unsigned)fmin(fmax(v[0], 0.0), 255.0) : 0u;
        for (i = 0; i < 5; i++)
            if ((bits >> i) & 1u)
                wsg_axis_set_fault(ax, faults[i], (bits >> 7) & 1u);
        break;
    case 'c':
        G.closing = 1;
        wsg_device_session_closed(&G.dev, &G.s); /* settles itself */
        fuzz_open();
        G.phase = FUZZ_PH_IDLE;
        return;
    default:
        G.phase = FUZZ_PH_IDLE;
        return;
    }
    wsg_axis_settle(ax);
    FUZZ_CHECK(!G.final_name);
    G.phase = FUZZ_PH_IDLE;
}

/* No motion running, requested or owing its abort. */
static int fuzz_quiet(void)
{
    const struct wsg_axis *ax = wsg_device_axis(&G.dev);

    return ax->motion.kind == WSG_MOTION_NONE &&
           ax->req_motion.kind == WSG_MOTION_NONE &&
           ax->req_cancelled.kind == WSG_MOTION_NONE && !ax->req_stop &&
           !ax->req_fast_stop;
}

static void fuzz_device(uint8_t cfgbyte, const uint8_t *data, size_t size,
                        uint32_t seed)
{
    static const char *const models[] = {"wsg50", "wsg50-210", "wsg32",
                                         "wsg25"};
    struct wsg_axis_config c;
    size_t i = 0;
    long n;

    memset(&G, 0, sizeof G);
    G.trace = getenv("FUZZ_TRACE") != NULL;
    FUZZ_CHECK(wsg_axis_config_init(&c, models[cfgbyte & 3u]) == 0);
    c.force_sensor = (cfgbyte >> 2) & 1u;
    wsg_device_init(&G.dev, &c);
    G.dev.lookup = fuzz_lookup;
    G.dev.trace_line = fuzz_trace_line;
    G.next_tag = 1;
    fuzz_open();
    /* i is at the start of a line at the top of every round. */
    while (i < size) {
        const uint8_t *nl;
        size_t end;

        if (data[i] == '#') {
            nl = memchr(data + i, '\n', size - i);
            end = nl ? (size_t)(nl - data) : size;
            fuzz_directive(data + i, end - i);
            i = nl ? end + 1 : size;
            continue;
        }
        /* The text up to the next directive line, in chunks. */
        for (end = i; end < size; end++)
            if (data[end] == '\n' && end + 1 < size && data[end + 1] == '#')
                break;
        end = end < size ? end + 1 : size;
        while (i < end) {
            size_t len = fuzz_chunk(&seed, end - i);
            uint32_t r;

            fuzz_input(data + i, len);
            i += len;
            /* Now and then the model runs between two reads. */
            r = fuzz_rand(&seed) & 31u;
            fuzz_steps(r < 24 ? 0 : r < 28 ? 1 : r < 31 ? 20 : 500);
        }
    }
    for (n = 0; n < FUZZ_END_STEPS && !fuzz_quiet(); n++)
        fuzz_step();
    FUZZ_CHECK(fuzz_quiet());
    /* Every motion acknowledged had its final result (sent, or dropped
     * with a closed connection). */
    if (G.nowed) {
        fprintf(stderr, "fuzz_gcl: %s acknowledged, no final result\n",
                G.owed[0].name);
        abort();
    }
}

int FUZZ_ENTRY(const uint8_t *data, size_t size)
{
    uint32_t seed;

    if (size < FUZZ_HEADER)
        return 0;
    seed = ((uint32_t)data[1] | (uint32_t)data[2] << 8 |
            (uint32_t)data[3] << 16) ^
           0x9E3779B9u;
    fuzz_codec(data + FUZZ_HEADER, size - FUZZ_HEADER, seed ^ 0x5bd1e995u);
    fuzz_device(data[0], data + FUZZ_HEADER, size - FUZZ_HEADER, seed);
    return 0;
}
