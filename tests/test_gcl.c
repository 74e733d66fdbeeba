/*
 * GCL's line codec and parser on their own (no I/O), and the interpreter
 * on a device with a fake clock: the edges the integration tests reach
 * only by luck. A line of exactly the limit ending in CR LF is a line; one
 * byte more is too long; a query index is read within the line's length;
 * a GRIP whose width lies beyond the stroke is judged against the stroke
 * the model takes, so no part is no part (18), not a collision (29).
 */
#include <string.h>

#include "check.h"
#include "tdev.h"
#include "wsg/gcl.h"

/* Feed text, return the event of the first line that ends. */
static enum wsg_gcl_event feed_one(struct wsg_gcl_line *l, const char *text,
                                   size_t len, const char **line, size_t *n)
{
    enum wsg_gcl_event ev = WSG_GCL_NONE;
    size_t used = 0;

    while (used < len && ev == WSG_GCL_NONE)
        used += wsg_gcl_line_feed(l, (const uint8_t *)text + used, len - used,
                                  &ev, line, n);
    return ev;
}

static void test_line_limits(void)
{
    static char text[WSG_GCL_LINE_MAX + 8];
    struct wsg_gcl_line l;
    const char *line;
    size_t n;

    /* POS? and blanks up to exactly the limit, then CR LF: a line. */
    memset(text, ' ', sizeof text);
    memcpy(text, "POS?", 4);
    text[WSG_GCL_LINE_MAX] = '\r';
    text[WSG_GCL_LINE_MAX + 1] = '\n';
    wsg_gcl_line_init(&l);
    CHECK_EQ(feed_one(&l, text, WSG_GCL_LINE_MAX + 2, &line, &n),
             WSG_GCL_LINE);
    CHECK_EQ(n, WSG_GCL_LINE_MAX);
    /* The same with LF alone. */
    text[WSG_GCL_LINE_MAX] = '\n';
    CHECK_EQ(feed_one(&l, text, WSG_GCL_LINE_MAX + 1, &line, &n),
             WSG_GCL_LINE);
    /* One byte more is too long, with CR LF or without. */
    text[WSG_GCL_LINE_MAX] = ' ';
    text[WSG_GCL_LINE_MAX + 1] = '\r';
    text[WSG_GCL_LINE_MAX + 2] = '\n';
    CHECK_EQ(feed_one(&l, text, WSG_GCL_LINE_MAX + 3, &line, &n),
             WSG_GCL_TOO_LONG);
    text[WSG_GCL_LINE_MAX + 1] = '\n';
    CHECK_EQ(feed_one(&l, text, WSG_GCL_LINE_MAX + 2, &line, &n),
             WSG_GCL_TOO_LONG);
    /* The next line starts afresh; binary bytes are their own event. */
    CHECK_EQ(feed_one(&l, "POS?\n", 5, &line, &n), WSG_GCL_LINE);
    CHECK_EQ(feed_one(&l, "PO\001S?\n", 6, &line, &n), WSG_GCL_BINARY);
    CHECK_EQ(feed_one(&l, "\r\n\nPOS?\n", 8, &line, &n), WSG_GCL_LINE);
    CHECK(n == 4 && memcmp(line, "POS?", 4) == 0);
}

static void test_parse(void)
{
    struct wsg_gcl_cmd c;
    /* No NUL after the line: the parser must keep within n. */
    static const char open_index[3] = {'A', '[', '1'};

    CHECK_EQ(wsg_gcl_parse(open_index, sizeof open_index, &c), -1);
    CHECK_EQ(wsg_gcl_parse("FDATA[1]?", 9, &c), 0);
    CHECK(c.form == WSG_GCL_QUERY && c.index == 1);
    CHECK_EQ(wsg_gcl_parse("FDATA[256]?", 11, &c), -1);
    CHECK_EQ(wsg_gcl_parse(" move ( 50.5 , 100 ) ", 21, &c), 0);
    CHECK(strcmp(c.name, "MOVE") == 0 && c.form == WSG_GCL_CALL);
    CHECK(c.nargs == 2 && c.arg[0].num == 50.5 && c.arg[1].num == 100);
    CHECK_EQ(wsg_gcl_parse("AUTOSEND(\"POS\", 50)", 19, &c), 0);
    CHECK(c.arg[0].is_str && strcmp(c.arg[0].str, "POS") == 0);
    CHECK_EQ(wsg_gcl_parse("VERBOSE=1", 9, &c), 0);
    CHECK(c.form == WSG_GCL_SET && c.arg[0].num == 1);
    CHECK_EQ(wsg_gcl_parse("MOVE(nan)", 9, &c), -1);
    CHECK_EQ(wsg_gcl_parse("MOVE(1e999)", 11, &c), -1);
    CHECK_EQ(wsg_gcl_parse("MOVE(50", 7, &c), -1);
    CHECK(strcmp(c.name, "MOVE") == 0); /* the name for the ERR line */
}

/* What the interpreter wrote to session 0, as one string. */
struct out {
    char text[4096];
    size_t len;
    unsigned writes;
};

static struct out out;

static void out_send(struct wsg_session *s, const uint8_t *pkt, size_t len)
{
    (void)s;
    REQUIRE(out.len + len < sizeof out.text);
    memcpy(out.text + out.len, pkt, len);
    out.len += len;
    out.text[out.len] = '\0';
    out.writes++;
}

static void say(struct wsg_gcl *g, const char *line)
{
    wsg_gcl_input(g, (const uint8_t *)line, strlen(line));
}

/* A device whose session 0 speaks GCL into out. */
static void gcl_open(struct tdev *t, struct wsg_gcl *g)
{
    static const struct wsg_gcl_config cfg = {10.0, 100.0};

    tdev_init(t);
    t->sess[0].s.send = out_send;
    wsg_gcl_init(g, &t->dev, &t->sess[0].s, &cfg);
}

static void run_until_quiet(struct tdev *t)
{
    int i;

    for (i = 0; i < 20000 && !wsg_device_idle(&t->dev); i++)
        wsg_device_step(&t->dev);
}

static void test_grip_beyond_stroke(void)
{
    struct tdev t;
    struct wsg_gcl g;

    gcl_open(&t, &g);
    say(&g, "HOME()\n");
    run_until_quiet(&t);
    memset(&out, 0, sizeof out);
    /* Homed open, nothing between the fingers and a width past the
     * stroke: the model grasps at the stroke, closing through the
     * clamping travel, and finds no part. */
    say(&g, "GRIP(10, 500)\n");
    run_until_quiet(&t);
    CHECK(strcmp(out.text, "ACK GRIP\nERR GRIP 18\n") == 0);
    CHECK_EQ(out.writes, 2); /* a line per write */
    CHECK_EQ(wsg_axis_grasp_state(tdev_axis(&t)), WSG_GS_NO_PART);
    /* A part wider than width + tolerance, closing: a collision. */
    say(&g, "MOVE(100)\n");
    run_until_quiet(&t);
    wsg_axis_set_part(tdev_axis(&t), 80.0, 50.0);
    memset(&out, 0, sizeof out);
    say(&g, "GRIP(10, 40)\n");
    run_until_quiet(&t);
    CHECK(strcmp(out.text, "ACK GRIP\nERR GRIP 29\n") == 0);
}

/* After BYE() every line is refused, the interpreter's own too, as the
 * binary side refuses everything after 07h. */
static void test_after_bye(void)
{
    struct tdev t;
    struct wsg_gcl g;

    gcl_open(&t, &g);
    memset(&out, 0, sizeof out);
    say(&g, "BYE()\nVERBOSE=1\nPWT=5\nPOS?\nFOO()\n");
    CHECK(strcmp(out.text, "ACK BYE\nERR VERBOSE 16\nERR PWT 16\n"
                           "ERR POS 16\nERR FOO 16\n") == 0);
}

int main(void)
{
    test_line_limits();
    test_parse();
    test_grip_beyond_stroke();
    test_after_bye();
    TEST_EXIT();
}
