/*
 * The manual's example exchanges of chapters 1.2 and 1.3, replayed against
 * the dispatcher and compared byte for byte: the Homing acknowledge, the
 * unknown command 90h, Get Acceleration's 150.0 mm/s^2, and the pending and
 * final answers of a Preposition.
 */
#include "manual_packets.h"
#include "tdev.h"

static void check_bytes(const struct tdev_pkt *p, const uint8_t *want,
                        size_t n)
{
    CHECK_EQ(p->raw_len, n);
    CHECK(p->raw_len == n && memcmp(p->raw, want, n) == 0);
}

int main(void)
{
    static const uint8_t cmd_unknown[] = {0xAA, 0xAA, 0xAA, 0x90,
                                          0x00, 0x00, 0x00, 0x00};
    struct tdev t;
    uint8_t dir = 0, pkt[WSG_FRAME_MAX], acc[4];
    size_t n;

    tdev_init(&t);

    /* 1.2 example 1: Homing acknowledged, after its E_CMD_PENDING. */
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_HOMING, &dir, 1), WSG_E_CMD_PENDING);
    CHECK(tdev_run_until(&t, 0, WSG_CMD_HOMING, 4000) > 0);
    check_bytes(tdev_last(&t), MP(MP_HOMING_OK), MP_LEN(MP_HOMING_OK));

    /* 1.2 example 2: unknown command 90h; the checksum of the request does
     * not matter here, so send it with a valid one. */
    n = wsg_frame_encode(pkt, sizeof pkt, 0x90, NULL, 0);
    CHECK_EQ(n, sizeof cmd_unknown);
    tdev_clear(&t);
    tdev_feed(&t, 0, pkt, n);
    REQUIRE(t.sess[0].n == 1);
    check_bytes(tdev_last(&t), MP(MP_UNKNOWN), MP_LEN(MP_UNKNOWN));

    /* 1.2 example 3 (with the ID erratum of NOTES.md: 31h): 150.0 mm/s^2
     * is the default acceleration. */
    CHECK_EQ(tdev_cmd(&t, WSG_CMD_GET_ACCELERATION, NULL, 0), WSG_E_SUCCESS);
    wsg_put_f32(acc, 150.0f);
    n = wsg_frame_encode_reply(pkt, sizeof pkt, 0x31, 0, acc, 4);
    check_bytes(tdev_last(&t), pkt, n);
    CHECK(memcmp(tdev_last(&t)->raw + 6, "\x00\x00\x00\x00\x16\x43", 6) == 0);

    /* 1.3: a Preposition answered E_CMD_PENDING, then E_SUCCESS. */
    CHECK_EQ(tdev_move(&t, 0, 50.0f, 100.0f), WSG_E_CMD_PENDING);
    check_bytes(tdev_last(&t), MP(MP_PENDING), MP_LEN(MP_PENDING));
    CHECK(tdev_run_until(&t, 0, WSG_CMD_PREPOSITION, 4000) > 0);
    check_bytes(tdev_last(&t), MP(MP_FINAL), MP_LEN(MP_FINAL));
    TEST_EXIT();
}
