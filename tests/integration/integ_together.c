/*
 * integ_together: every interface of one daemon at once (TCP, UDP and the
 * serial port; CAN joins where this host has a vcan, the CAN runner covers
 * it otherwise). They share one gripper: a motion started on one is seen
 * moving from the others and refused there with E_ALREADY_RUNNING, and its
 * final result goes to the interface and peer that sent it, nowhere else.
 * The ready line names them all, in a fixed order.
 *
 * Each homing is started with simulated time paused (the control channel),
 * so that it is still running when the other interfaces ask, however slow
 * the machine; then time goes on and the homing ends.
 */
#include "check.h"
#include "emu.h"
#include "emu_ctl.h"
#include "wsg/axis.h"

#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#define N 3

int main(int argc, char **argv)
{
    const char *exe = emu_exe(argc, argv);
    const struct emu_transport *tps[N] = {&emu_tcp, &emu_udp, &emu_pty};
    struct emu e;
    struct emu_client c[N];
    struct wsg_client_frame f;
    struct ctl k;
    char v[128];
    int i, j;
    static const char *const extra[] = {"--control", "127.0.0.1:0", NULL};

    REQUIRE(emu_start_multi(&e, exe, tps, N, extra) == 0);
    printf("%s\n", e.line);
    /* tcp=, udp=, pty= in this order, each once. */
    {
        const char *t = strstr(e.line, " tcp="), *u = strstr(e.line, " udp="),
                   *p = strstr(e.line, " pty=");
        CHECK(strncmp(e.line, "ready ", 6) == 0);
        CHECK(t && u && p && t < u && u < p);
    }
    REQUIRE(ctl_open(&k, &e) == 0);
    for (i = 0; i < N; i++) {
        REQUIRE(emu_field(&e, tps[i]->field, v, sizeof v));
        REQUIRE(emu_open(&c[i], &e, tps[i]) == 0);
    }

    /* A homing from each interface in turn: moving for all, refused on the
     * others, its result only where it was sent. */
    for (i = 0; i < N; i++) {
        uint8_t dir = (uint8_t)(i % 2 ? WSG_HOME_NEGATIVE : WSG_HOME_POSITIVE);
        unsigned before[N];
        uint32_t fl;

        for (j = 0; j < N; j++)
            before[j] = c[j].link.seen[WSG_CMD_HOMING];
        /* Each homing starts away from its end stop (55 mm, then at the
         * other end), so it moves. */
        CMD_OK(&k, "time pause");
        CHECK_EQ(
            emu_request(&c[i], WSG_CMD_HOMING, &dir, 1, NULL, EMU_REPLY_MS),
            WSG_E_CMD_PENDING);
        for (j = 0; j < N; j++) {
            if (j == i)
                continue;
            CHECK(emu_get_flags(&c[j], &fl) == 0);
            CHECK(fl & WSG_SF_MOVING);
            CHECK_EQ(emu_request(&c[j], WSG_CMD_HOMING, &dir, 1, NULL,
                                 EMU_REPLY_MS),
                     WSG_E_ALREADY_RUNNING);
        }
        CMD_OK(&k, "time resume");
        CHECK_EQ(emu_recv_id(&c[i], WSG_CMD_HOMING, &f, EMU_HOMING_MS), 1);
        CHECK_EQ(f.status, WSG_E_SUCCESS);
        for (j = 0; j < N; j++) {
            REQUIRE(emu_sync(&c[j], EMU_REPLY_MS) == 0);
            if (j == i)
                CHECK_EQ(c[j].link.seen[WSG_CMD_HOMING] - before[j], 2);
            else /* its own E_ALREADY_RUNNING, nothing of the result */
                CHECK_EQ(c[j].link.seen[WSG_CMD_HOMING] - before[j], 1);
        }
    }
    /* One gripper: the width the last homing left is everybody's. */
    {
        float w[N];
        for (i = 0; i < N; i++)
            CHECK(emu_get_float(&c[i], WSG_CMD_GET_WIDTH, &w[i]) == 0);
        CHECK_NEAR(w[0], 110.0, 0.01); /* the last, from the pty: positive */
        CHECK_NEAR(w[1], w[0], 1e-6);
        CHECK_NEAR(w[2], w[0], 1e-6);
    }
    for (i = 0; i < N; i++) {
        CHECK_EQ(c[i].link.bad, 0);
        if (tps[i]->connection)
            CHECK_EQ(emu_request(&c[i], WSG_CMD_DISCONNECT, NULL, 0, NULL,
                                 EMU_REPLY_MS),
                     WSG_E_SUCCESS);
        emu_close(&c[i]);
    }
    ctl_close(&k);
    CHECK_EQ(emu_stop(&e), 0);
    TEST_EXIT();
}
