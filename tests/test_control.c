/*
 * The control channel's line interpreter on a bench (ctlbench.h), without
 * a socket: one answer per line, in order; lines split anywhere, several
 * in one read, empty, too long, with a NUL; each command's forms and
 * errors; its effects there when the answer is; the gripper a session has
 * selected; time paused and stepped.
 */
#include <stdio.h>

#include "check.h"
#include "ctlbench.h"

static int starts(const char *s, const char *prefix)
{
    return strncmp(s, prefix, strlen(prefix)) == 0;
}

static int has_part(const struct wsg_axis *ax)
{
    double w, k;

    return wsg_axis_part(ax, &w, &k);
}

static void test_lines(void)
{
    struct ctlbench b;
    char longline[WSG_CTL_LINE_MAX + 10];

    REQUIRE(ctlbench_open(&b, 1) == 0);
    /* Split anywhere, several at once: one answer per line, in order. */
    ctlbench_feed(&b, "he", 2);
    CHECK_EQ(b.answers, 0);
    ctlbench_feed(&b, "lp\ngripper\n\nbogus arg\n", 22);
    CHECK_EQ(b.answers, 4);
    CHECK(strstr(b.out, "ok commands: part WIDTH [STIFFNESS]|none, ") ==
          b.out);
    CHECK(strstr(b.out, "\nok gripper 0 of 1\n"
                        "error empty line (try help)\n"
                        "error unknown command 'bogus' (try help)\n") != NULL);
    /* Too long, or with a NUL: one error, and the next line is fine. */
    memset(longline, 'x', sizeof longline);
    ctlbench_feed(&b, longline, sizeof longline);
    CHECK(strcmp(ctlbench_cmd(&b, ""), "error line longer than 256 bytes") ==
          0);
    ctlbench_feed(&b, "sta\0te\n", 7);
    CHECK(strstr(b.out, "error line longer than 256 bytes\n") != NULL);
    CHECK(starts(ctlbench_cmd(&b, "state"), "ok {\"width\":"));
    CHECK(strcmp(ctlbench_cmd(&b, "state now"),
                 "error state takes no arguments") == 0);
    CHECK(strcmp(ctlbench_cmd(&b, "a b c d e"), "error too many arguments") ==
          0);
    /* Blanks around words do not matter; \r\n endings are fine. */
    CHECK(strcmp(ctlbench_cmd(&b, "  gripper\t 0 \r"), "ok gripper 0 of 1") ==
          0);
    ctlbench_close(&b);
}

static void test_world(void)
{
    struct ctlbench b;
    struct wsg_axis *ax;

    REQUIRE(ctlbench_open(&b, 2) == 0);
    ax = wsg_device_axis(&b.grippers[0].dev);
    CHECK(strcmp(ctlbench_cmd(&b, "part 40"), "ok part 40 50") == 0);
    CHECK(has_part(ax));
    CHECK(starts(ctlbench_cmd(&b, "part 400"), "error part: WIDTH"));
    CHECK(starts(ctlbench_cmd(&b, "part 40 -1"), "error part: STIFFNESS"));
    CHECK(strcmp(ctlbench_cmd(&b, "part none"), "ok part none") == 0);
    CHECK(!has_part(ax));
    CHECK(strcmp(ctlbench_cmd(&b, "obstacle 30"), "ok obstacle 30") == 0);
    CHECK(starts(ctlbench_cmd(&b, "obstacle"), "error usage: obstacle"));
    /* A fault: its flag and its consequence when "ok" is there. */
    CHECK(strcmp(ctlbench_cmd(&b, "fault power on"), "ok fault power on") ==
          0);
    CHECK(wsg_axis_flags(ax) & WSG_SF_FAST_STOP);
    CHECK(starts(ctlbench_cmd(&b, "fault power maybe"), "error fault: say"));
    CHECK(starts(ctlbench_cmd(&b, "fault heat on"),
                 "error fault: unknown fault 'heat'"));
    /* The selected gripper: world commands act on it alone. */
    CHECK(strcmp(ctlbench_cmd(&b, "gripper 1"), "ok gripper 1 of 2") == 0);
    CHECK(strcmp(ctlbench_cmd(&b, "part 20"), "ok part 20 50") == 0);
    CHECK(has_part(wsg_device_axis(&b.grippers[1].dev)));
    CHECK(!has_part(ax));
    CHECK(starts(ctlbench_cmd(&b, "gripper 2"), "error gripper: N must be"));
    CHECK(starts(ctlbench_cmd(&b, "reset"), "ok reset"));
    CHECK(starts(ctlbench_cmd(&b, "drop"), "ok dropped 0"));
    ctlbench_close(&b);
}

static void test_time(void)
{
    struct ctlbench b;
    struct wsg_axis *ax;

    REQUIRE(ctlbench_open(&b, 1) == 0);
    ax = wsg_device_axis(&b.grippers[0].dev);
    CHECK(starts(ctlbench_cmd(&b, "time step 5"),
                 "error time step: not paused"));
    CHECK(strcmp(ctlbench_cmd(&b, "time pause"), "ok paused") == 0);
    CHECK(strcmp(ctlbench_cmd(&b, "time step 5"), "ok 0.005") == 0);
    CHECK(starts(ctlbench_cmd(&b, "time step 0.5"),
                 "error time step: 0.5 ms is not a whole number"));
    CHECK(starts(ctlbench_cmd(&b, "time step -1"), "error time step: MS"));
    /* Time runs for the model: a power fault's FAST STOP survives it, a
     * step count is exact. */
    CHECK(strcmp(ctlbench_cmd(&b, "time step 1000"), "ok 1.005") == 0);
    CHECK_EQ(wsg_axis_time(ax), 1005000u);
    CHECK(starts(ctlbench_cmd(&b, "time scale 0"), "error time scale"));
    CHECK(starts(ctlbench_cmd(&b, "time scale 2"), "ok scale 2 paused"));
    CHECK(starts(ctlbench_cmd(&b, "time resume"), "ok running at scale 2"));
    CHECK(starts(ctlbench_cmd(&b, "time"), "ok "));
    CHECK(starts(ctlbench_cmd(&b, "time travel"), "error usage: time"));
    CHECK(starts(ctlbench_cmd(&b, "stats"), "ok {\"grippers\":1,"));
    ctlbench_close(&b);
}

int main(void)
{
    test_lines();
    test_world();
    test_time();
    TEST_EXIT();
}
