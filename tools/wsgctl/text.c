/*
 * wsgctl --text: wsgctl's commands over GCL, the text interface of later
 * firmware (wsgemu --text-interface on; ../shared/spec/GCL.md). A request
 * is one line ("MOVE(40, 100)"), its answer one line ("POS=54.2",
 * "ACK STOP", "ERR MOVE 16"), and a motion answers "ACK MOVE" at once and
 * "FIN MOVE" or "ERR MOVE 19" when it ends, which wsgctl waits for as it
 * waits through E_CMD_PENDING over the binary protocol. Readings are
 * printed as the binary commands print them: the value is put into the
 * binary reply's layout and printed by print_values, so that a script
 * reads "width 54.20 mm" (or "54.20" with -q) whichever interface the
 * gripper has on. An ERR line is said on stderr and is exit status 1.
 * Before the close wsgctl sends BYE(), as it sends 07h over the binary
 * protocol, so it never puts the gripper into FAST STOP. raw-text sends
 * one line as written and prints every line of its answer.
 */
#define _GNU_SOURCE

#include "wsgctl.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* The gripper's longest line (WSG_GCL_LINE_MAX), and room for an answer
 * line: the emulator's are far shorter; a longer one is cut. */
#define TEXT_LINE_MAX 256u
#define TEXT_ANSWER   512u

typedef void (*line_fn)(const struct opts *o, const char *line);

/* The commands that answer twice: ACK at once, FIN or ERR at the end. */
static const char *const text_motions[] = {"HOME", "MOVE", "GRIP", "RELEASE"};

/* "ACK NAME" of a motion: its name into name (cap 16), 1; else 0. */
static int motion_ack(const char *line, char *name)
{
    size_t i;

    if (strncmp(line, "ACK ", 4) != 0)
        return 0;
    for (i = 0; i < sizeof text_motions / sizeof text_motions[0]; i++)
        if (!strcmp(line + 4, text_motions[i])) {
            strcpy(name, text_motions[i]);
            return 1;
        }
    return 0;
}

/* "FIN NAME" or "ERR NAME ...": the end of the motion name. */
static int motion_end(const char *line, const char *name)
{
    size_t n = strlen(name);

    if (strncmp(line, "FIN ", 4) && strncmp(line, "ERR ", 4))
        return 0;
    return !strncmp(line + 4, name, n) &&
           (line[4 + n] == '\0' || line[4 + n] == ' ');
}

/* Say an ERR line on stderr; the exit status for it. Without VERBOSE=1
 * the gripper sends the code alone: its name from the binary command set
 * (Appendix A, whose codes GCL's are) follows in parentheses. */
static int text_error(const char *line)
{
    const char *code = strrchr(line, ' ');
    char *end;
    unsigned long v;

    if (code && code - line > 4) {
        v = strtoul(code + 1, &end, 10);
        if (end != code + 1 && *end == '\0' && v <= 0xFFFF &&
            strcmp(wsg_status_name((unsigned)v), "E_UNKNOWN") != 0) {
            err("%s (%s)", line, wsg_status_name((unsigned)v));
            return EXIT_GRIPPER;
        }
    }
    err("%s", line);
    return EXIT_GRIPPER;
}

/* The next line from the gripper into out (without CR LF), by deadline.
 * 0, or an exit status (said). what names the request for a timeout. */
static int text_read(struct ctx *x, char *out, size_t cap, uint64_t deadline,
                     const char *what)
{
    int r = wsg_client_line_read(&x->c.l, out, cap, deadline);
    size_t n;

    if (r == 1) {
        x->c.heard = 1;
        n = strlen(out);
        while (n > 0 && out[n - 1] == '\r')
            out[--n] = '\0';
        return 0;
    }
    if (r == 0) {
        /* Binary packets go unanswered by a text interface and the other
         * way round, so a mismatch looks like this. */
        err("no answer to %s within %.1f s (is the gripper's text interface "
            "on?)",
            what, x->o.timeout_s);
        return EXIT_CONN;
    }
    if (r == -EINTR)
        return EXIT_INTERRUPTED;
    if (r == -EPIPE)
        err("the gripper closed the connection");
    else
        err("receive: %s", strerror(-r));
    return EXIT_CONN;
}

/* Send line (without its newline) and read its answer into out: the first
 * line that is not a stream line (@POS=...), and after the ACK of a motion
 * the line that ends it (FIN or ERR with its name), all within --timeout.
 * each, if given, sees every line read. 0 for an answer that is no ERR, or
 * an exit status (said). */
static int text_xact(struct ctx *x, const char *line, char *out, size_t cap,
                     line_fn each)
{
    char buf[TEXT_LINE_MAX + 2], motion[16] = "";
    uint64_t deadline = timeout_deadline(&x->o);
    int rc;

    if (strlen(line) > TEXT_LINE_MAX) {
        err("a GCL line is at most %u characters", TEXT_LINE_MAX);
        return EXIT_USAGE;
    }
    snprintf(buf, sizeof buf, "%s\n", line);
    rc = wsg_client_line_send(&x->c.l, buf);
    if (rc < 0) {
        err("send: %s", rc == -EIO ? "short write" : strerror(-rc));
        return EXIT_CONN;
    }
    for (;;) {
        rc = text_read(x, out, cap, deadline, line);
        if (rc)
            return rc;
        if (each)
            each(&x->o, out);
        if (out[0] == '@')
            continue; /* a stream this connection asked for */
        if (!motion[0]) {
            /* BYE()'s answer, even an ERR: a second one would be too. */
            if (!strcmp(out, "ACK BYE") || !strncmp(out, "ERR BYE ", 8))
                x->c.announced = 1;
            if (motion_ack(out, motion))
                continue;
            break;
        }
        if (motion_end(out, motion))
            break;
    }
    return strncmp(out, "ERR ", 4) ? 0 : text_error(out);
}

/* A command that only acts: its answer is printed by nobody. */
static int text_act(struct ctx *x, const char *line)
{
    char out[TEXT_ANSWER];

    return text_xact(x, line, out, sizeof out, NULL);
}

/* A query's value: the text after "KEY=" of its answer into val. 0, or an
 * exit status (said). */
static int text_query(struct ctx *x, const char *key, char *val, size_t cap)
{
    char line[64], out[TEXT_ANSWER];
    size_t n = strlen(key);
    int rc;

    snprintf(line, sizeof line, "%s?", key);
    rc = text_xact(x, line, out, sizeof out, NULL);
    if (rc)
        return rc;
    if (strncmp(out, key, n) != 0 || out[n] != '=') {
        err("unexpected answer to %s: \"%s\"", line, out);
        return EXIT_CONN;
    }
    snprintf(val, cap, "%s", out + n + 1);
    return 0;
}

static int answer_number(const char *key, const char *val, double *v)
{
    char *end;

    *v = strtod(val, &end);
    if (end == val || *end != '\0' || !isfinite(*v)) {
        err("unexpected answer to %s?: \"%s=%s\"", key, key, val);
        return EXIT_CONN;
    }
    return 0;
}

/* A float reading printed as the binary command id prints it. */
static int text_float(struct ctx *x, const char *key, uint8_t id)
{
    char val[TEXT_ANSWER];
    uint8_t p[4];
    double v;
    int rc = text_query(x, key, val, sizeof val);

    if (rc || (rc = answer_number(key, val, &v)) != 0)
        return rc;
    wsg_put_f32(p, (float)v);
    print_values(&x->o, "", id, p, sizeof p);
    return EXIT_OK;
}

static int need_float(const char *what, const char *s, double *v)
{
    float f;

    if (parse_float(s, &f) < 0) {
        err("%s: not a number: \"%s\"", what, s);
        return EXIT_USAGE;
    }
    *v = f;
    return 0;
}

/* ---- the commands ---- */

static int t_home(struct ctx *x, int argc, char **argv)
{
    const char *line = "HOME()";

    if (argc == 1) {
        if (!strcmp(argv[0], "pos"))
            line = "HOME(1)";
        else if (!strcmp(argv[0], "neg"))
            line = "HOME(0)";
        else {
            err("home: direction is pos or neg, not \"%s\"", argv[0]);
            return EXIT_USAGE;
        }
    }
    return text_act(x, line);
}

/* Numbers as GCL takes them: %g keeps a float's digits and never writes
 * anything the gripper's parser refuses (no inf or nan get here). */
static int t_move(struct ctx *x, int argc, char **argv)
{
    char line[96];
    double w, s;

    (void)argc;
    if (need_float("width", argv[0], &w) || need_float("speed", argv[1], &s))
        return EXIT_USAGE;
    snprintf(line, sizeof line, "MOVE(%.7g, %.7g)", w, s);
    return text_act(x, line);
}

/* grasp: GRIP() closes until contact; with WIDTH SPEED, GRIP(force,
 * width, speed), which sets the force limit as well, so the force is
 * --force's and not guessed. */
static int t_grasp(struct ctx *x, int argc, char **argv)
{
    char line[128];
    double w, s;

    if (argc == 1) {
        err("usage: wsgctl --text grasp [WIDTH SPEED] [--force N]");
        return EXIT_USAGE;
    }
    if (argc == 0) {
        if (x->o.has_force)
            snprintf(line, sizeof line, "GRIP(%.7g)", x->o.force);
        else
            snprintf(line, sizeof line, "GRIP()");
        return text_act(x, line);
    }
    if (!x->o.has_force) {
        err("grasp WIDTH SPEED over GCL needs --force N: GRIP(force, width, "
            "speed) sets the force limit too");
        return EXIT_USAGE;
    }
    if (need_float("width", argv[0], &w) || need_float("speed", argv[1], &s))
        return EXIT_USAGE;
    snprintf(line, sizeof line, "GRIP(%.7g, %.7g, %.7g)", x->o.force, w, s);
    return text_act(x, line);
}

/* release: RELEASE() opens by the gripper's pull-back; PULLBACK [SPEED]
 * are RELEASE's own (relative to the fingers, unlike 26h's width). */
static int t_release(struct ctx *x, int argc, char **argv)
{
    char line[96];
    double p, s;

    if (argc == 0)
        return text_act(x, "RELEASE()");
    if (need_float("pull-back", argv[0], &p))
        return EXIT_USAGE;
    if (argc == 1) {
        snprintf(line, sizeof line, "RELEASE(%.7g)", p);
    } else {
        if (need_float("speed", argv[1], &s))
            return EXIT_USAGE;
        snprintf(line, sizeof line, "RELEASE(%.7g, %.7g)", p, s);
    }
    return text_act(x, line);
}

static int t_stop(struct ctx *x, int argc, char **argv)
{
    (void)argc;
    (void)argv;
    return text_act(x, "STOP()");
}

static int t_fast_stop(struct ctx *x, int argc, char **argv)
{
    (void)argc;
    (void)argv;
    return text_act(x, "FASTSTOP()");
}

static int t_ack(struct ctx *x, int argc, char **argv)
{
    (void)argc;
    (void)argv;
    return text_act(x, "FSACK()");
}

static int t_tare(struct ctx *x, int argc, char **argv)
{
    (void)argc;
    (void)argv;
    return text_act(x, "TARE()");
}

static int t_bye(struct ctx *x, int argc, char **argv)
{
    (void)argc;
    (void)argv;
    return text_act(x, "BYE()");
}

static int t_width(struct ctx *x, int argc, char **argv)
{
    (void)argc;
    (void)argv;
    return text_float(x, "POS", WSG_CMD_GET_WIDTH);
}

static int t_speed(struct ctx *x, int argc, char **argv)
{
    (void)argc;
    (void)argv;
    return text_float(x, "SPEED", WSG_CMD_GET_SPEED);
}

static int t_force(struct ctx *x, int argc, char **argv)
{
    (void)argc;
    (void)argv;
    return text_float(x, "FORCE", WSG_CMD_GET_FORCE);
}

static int t_temperature(struct ctx *x, int argc, char **argv)
{
    char val[TEXT_ANSWER];
    uint8_t p[2];
    double v;
    int rc = text_query(x, "TEMP", val, sizeof val);

    (void)argc;
    (void)argv;
    if (rc || (rc = answer_number("TEMP", val, &v)) != 0)
        return rc;
    /* 46h's layout: tenths of a degree. */
    wsg_put_u16(
        p, (uint16_t)(int16_t)lround(fmax(fmin(v, 3276.7), -3276.8) * 10.0));
    print_values(&x->o, "", WSG_CMD_GET_TEMPERATURE, p, sizeof p);
    return EXIT_OK;
}

/* An unsigned answer ("SYSFLAGS=1") up to max. */
static int text_unsigned(struct ctx *x, const char *key, unsigned long max,
                         unsigned long *v)
{
    char val[TEXT_ANSWER], *end;
    int rc = text_query(x, key, val, sizeof val);

    if (rc)
        return rc;
    errno = 0;
    *v = strtoul(val, &end, 10);
    if (end == val || *end != '\0' || errno != 0 || *v > max ||
        val[0] == '-') {
        err("unexpected answer to %s?: \"%s=%s\"", key, key, val);
        return EXIT_CONN;
    }
    return 0;
}

/* state: SYSFLAGS? and GRIPSTATE?, printed as 40h and 41h print them. */
static int t_state(struct ctx *x, int argc, char **argv)
{
    unsigned long v;
    uint8_t p[4];
    int rc;

    (void)argc;
    (void)argv;
    rc = text_unsigned(x, "SYSFLAGS", 0xFFFFFFFFul, &v);
    if (rc)
        return rc;
    wsg_put_u32(p, (uint32_t)v);
    print_values(&x->o, "", WSG_CMD_GET_SYSTEM_STATE, p, 4);
    rc = text_unsigned(x, "GRIPSTATE", 255, &v);
    if (rc)
        return rc;
    p[0] = (uint8_t)v;
    print_values(&x->o, "", WSG_CMD_GET_GRASP_STATE, p, 1);
    return EXIT_OK;
}

/* stats: GRIPSTATS=total,no-part,lost-part, printed as 42h prints it. */
static int t_stats(struct ctx *x, int argc, char **argv)
{
    char val[TEXT_ANSWER];
    unsigned long t, np, lp;
    uint8_t p[8];
    int rc, k = 0;

    (void)argc;
    (void)argv;
    rc = text_query(x, "GRIPSTATS", val, sizeof val);
    if (rc)
        return rc;
    if (sscanf(val, "%lu,%lu,%lu%n", &t, &np, &lp, &k) != 3 ||
        val[k] != '\0' || t > 0xFFFFFFFFul || np > 0xFFFF || lp > 0xFFFF) {
        err("unexpected answer to GRIPSTATS?: \"GRIPSTATS=%s\"", val);
        return EXIT_CONN;
    }
    wsg_put_u32(p, (uint32_t)t);
    wsg_put_u16(p + 4, (uint16_t)np);
    wsg_put_u16(p + 6, (uint16_t)lp);
    print_values(&x->o, "", WSG_CMD_GET_GRASP_STATS, p, sizeof p);
    return EXIT_OK;
}

/* info: DEVTYPE?, VERSION? and SN?, as GCL words them ("type WSG50";
 * -q: "WSG50 2.2.0 1"); GCL has no hardware revision. */
static int t_info(struct ctx *x, int argc, char **argv)
{
    static const char *const keys[] = {"DEVTYPE", "VERSION", "SN"};
    static const char *const names[] = {"type", "swrev", "serial"};
    char val[TEXT_ANSWER];
    size_t i;
    int rc;

    (void)argc;
    (void)argv;
    for (i = 0; i < 3; i++) {
        rc = text_query(x, keys[i], val, sizeof val);
        if (rc)
            return rc;
        if (x->o.quiet)
            printf("%s%s", i ? " " : "", val);
        else
            printf("%s %s\n", names[i], val);
    }
    if (x->o.quiet)
        putchar('\n');
    return EXIT_OK;
}

/* tag: TAG?; no tag set is "tag none", as over the binary protocol. GCL
 * cannot set it. */
static int t_tag(struct ctx *x, int argc, char **argv)
{
    char line[TEXT_ANSWER];
    unsigned code;
    int rc;

    (void)argv;
    if (argc > 0) {
        err("tag: GCL has no command that sets the device tag");
        return EXIT_USAGE;
    }
    /* The ERR of no tag is no error here: read it before text_xact would
     * say it. */
    rc = wsg_client_line_send(&x->c.l, "TAG?\n");
    if (rc < 0) {
        err("send: %s", strerror(-rc));
        return EXIT_CONN;
    }
    do
        rc = text_read(x, line, sizeof line, timeout_deadline(&x->o), "TAG?");
    while (!rc && line[0] == '@');
    if (rc)
        return rc;
    if (sscanf(line, "ERR TAG %u", &code) == 1 &&
        code == WSG_E_NOT_AVAILABLE) {
        printf(x->o.quiet ? "none\n" : "tag none\n");
        return EXIT_OK;
    }
    if (!strncmp(line, "ERR ", 4))
        return text_error(line);
    if (strncmp(line, "TAG=", 4) != 0) {
        err("unexpected answer to TAG?: \"%s\"", line);
        return EXIT_CONN;
    }
    printf(x->o.quiet ? "%s\n" : "tag %s\n", line + 4);
    return EXIT_OK;
}

static void print_line(const struct opts *o, const char *line)
{
    (void)o;
    printf("%s\n", line);
}

/* raw-text LINE: one line as written; every line of the answer printed as
 * it came, stream lines too. */
static int t_raw(struct ctx *x, int argc, char **argv)
{
    char out[TEXT_ANSWER];
    const char *p;

    (void)argc;
    for (p = argv[0]; *p == ' ' || *p == '\t'; p++)
        ;
    /* A blank line gets no answer, and a newline would make two lines. */
    if (!*p || strpbrk(argv[0], "\r\n")) {
        err("raw-text: one line, not blank, without CR or LF");
        return EXIT_USAGE;
    }
    return text_xact(x, argv[0], out, sizeof out, print_line);
}

const struct command text_commands[] = {
    {"home", t_home, 0, 1, 1, "[pos|neg]",
     "HOME(), HOME(1) or HOME(0); waits for FIN HOME", "wsgctl --text home",
     VIA_GRIPPER},
    {"move", t_move, 2, 2, 1, "WIDTH SPEED", "MOVE(WIDTH, SPEED)",
     "wsgctl --text move 40 100", VIA_GRIPPER},
    {"grasp", t_grasp, 0, 2, 1, "[WIDTH SPEED] [--force N]",
     "GRIP() (or GRIP(N)): close until contact; with WIDTH SPEED, "
     "GRIP(N, WIDTH, SPEED), which needs --force; no part: ERR GRIP 18, "
     "exit 1",
     "wsgctl --text --force 20 grasp 30 50", VIA_GRIPPER},
    {"release", t_release, 0, 2, 1, "[PULLBACK [SPEED]]",
     "RELEASE(): open by PULLBACK mm (default the gripper's) from where "
     "the fingers are",
     "wsgctl --text release 10 50", VIA_GRIPPER},
    {"stop", t_stop, 0, 0, 1, "", "STOP()", "wsgctl --text stop", VIA_GRIPPER},
    {"fast-stop", t_fast_stop, 0, 0, 1, "", "FASTSTOP()",
     "wsgctl --text fast-stop", VIA_GRIPPER},
    {"ack", t_ack, 0, 0, 1, "", "FSACK(): acknowledge FAST STOP",
     "wsgctl --text ack", VIA_GRIPPER},
    {"info", t_info, 0, 0, 1, "", "DEVTYPE?, VERSION?, SN?",
     "wsgctl --text info", VIA_GRIPPER},
    {"state", t_state, 0, 0, 1, "", "SYSFLAGS? then GRIPSTATE?",
     "wsgctl --text state", VIA_GRIPPER},
    {"width", t_width, 0, 0, 1, "", "POS?, mm", "wsgctl --text -q width",
     VIA_GRIPPER},
    {"speed", t_speed, 0, 0, 1, "", "SPEED?, mm/s", "wsgctl --text speed",
     VIA_GRIPPER},
    {"force", t_force, 0, 0, 1, "", "FORCE?, N", "wsgctl --text force",
     VIA_GRIPPER},
    {"temperature", t_temperature, 0, 0, 1, "", "TEMP?, degC",
     "wsgctl --text temperature", VIA_GRIPPER},
    {"tag", t_tag, 0, 0, 1, "", "TAG? (\"none\" if unset)",
     "wsgctl --text tag", VIA_GRIPPER},
    {"stats", t_stats, 0, 0, 1, "", "GRIPSTATS?: total, no part, lost part",
     "wsgctl --text stats", VIA_GRIPPER},
    {"tare", t_tare, 0, 0, 1, "", "TARE()", "wsgctl --text tare", VIA_GRIPPER},
    {"bye", t_bye, 0, 0, 1, "", "BYE()", "wsgctl --text bye", VIA_GRIPPER},
    {"raw-text", t_raw, 1, 1, 1, "LINE",
     "send one GCL line (implies --text) and print every line of the "
     "answer, for a motion through its FIN or ERR",
     "wsgctl raw-text 'POS?'", VIA_GRIPPER},
};
const size_t text_ncommands = sizeof text_commands / sizeof text_commands[0];

/* Over GCL, the close is announced with BYE(), which is what keeps the
 * gripper out of FAST STOP; its answer is awaited briefly (stream lines
 * and a motion's end may come first) so that it is surely read before the
 * FIN. */
void text_close(struct conn *c)
{
    char line[TEXT_ANSWER];
    uint64_t deadline = wsg_client_deadline(1000);
    int saved = interrupted;

    if (c->l.fd < 0 || c->announced)
        return;
    if (!c->heard) {
        close_both_ways(c);
        return;
    }
    interrupted = 0;
    if (wsg_client_line_send(&c->l, "BYE()\n") == 0)
        while (wsg_client_line_read(&c->l, line, sizeof line, deadline) == 1)
            if (!strncmp(line, "ACK BYE", 7) || !strncmp(line, "ERR BYE", 7))
                break;
    interrupted = saved;
    c->announced = 1;
}

/* Nothing came back on the connection: the gripper may speak the other
 * interface (wsgctl --text against a binary gripper, or the other way
 * round), and either would take the close for one without its
 * announcement, FAST STOP. So it is announced both ways: 07h, which a
 * text interface answers with an ERR line, then BYE() on a line of its
 * own, which a binary parser skips as noise. Whichever answer comes (07h's
 * packet or ACK BYE) is awaited up to a second. */
void close_both_ways(struct conn *c)
{
    static const char bye[] = "\nBYE()\n";
    uint8_t pkt[WSG_HEADER_LEN + WSG_CRC_LEN + 2];
    uint64_t deadline = wsg_client_deadline(1000);
    struct wsg_parser p;
    char line[16];
    size_t n, k = 0;
    int saved = interrupted, done = 0;

    if (c->l.fd < 0 || c->announced)
        return;
    n = wsg_frame_encode(pkt, sizeof pkt, WSG_CMD_DISCONNECT, NULL, 0);
    interrupted = 0;
    if (n && wsg_client_send(&c->l, pkt, n) == 0 &&
        wsg_client_send(&c->l, bye, sizeof bye - 1) == 0) {
        wsg_parser_init(&p, 1);
        wsg_parser_set_max(&p, WSG_REPLY_PAYLOAD_MAX);
        while (!done && wsg_client_fill(&c->l, deadline) == 1) {
            const uint8_t *b = c->l.in + c->l.off;
            size_t len = c->l.len - c->l.off, i, used;

            c->l.off = c->l.len;
            for (i = 0; i < len; i++) {
                if (b[i] != '\n') {
                    if (k < sizeof line - 1)
                        line[k++] = (char)b[i];
                    continue;
                }
                line[k] = '\0';
                k = 0;
                if (!strcmp(line, "ACK BYE"))
                    done = 1;
            }
            while (len > 0) {
                enum wsg_parse_event ev;
                struct wsg_frame f;

                used = wsg_parser_feed(&p, b, len, &ev, &f);
                if (ev == WSG_PARSE_FRAME && f.id == WSG_CMD_DISCONNECT)
                    done = 1;
                b += used;
                len -= used;
            }
        }
    }
    interrupted = saved;
    c->announced = 1;
}
