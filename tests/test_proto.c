/*
 * The protocol layer: the CRC of Appendix C against the manual's example
 * packets, frame encoding, and the incremental parser under every split of
 * its input, garbage, bad checksums and oversized SIZE fields; numbers as
 * the documentation writes them.
 */
#include <errno.h>
#include <string.h>

#include "check.h"
#include "manual_packets.h"
#include "wsg/proto.h"

/* All seven example packets of chapter 1, byte for byte. */
static void test_crc_examples(void)
{
    int i;

    for (i = 0; i < MP_COUNT; i++) {
        uint16_t crc = wsg_crc_update(WSG_CRC_INIT, MP(i), MP_LEN(i) - 2);
        CHECK_EQ(crc, wsg_get_u16(MP(i) + MP_LEN(i) - 2));
        /* Over the whole packet including its checksum: 0 (ch. 1.1). */
        CHECK_EQ(wsg_crc_update(WSG_CRC_INIT, MP(i), MP_LEN(i)), 0);
    }
    CHECK_EQ(wsg_crc_update(WSG_CRC_INIT, MP(MP_LOOP_1234), 8), 0x666D);
}

/* The table against the bitwise definition of the polynomial. */
static void test_crc_table(void)
{
    unsigned i, b;

    for (i = 0; i < 256; i++) {
        uint8_t byte = (uint8_t)i;
        uint16_t t = (uint16_t)(i << 8);
        for (b = 0; b < 8; b++)
            t = (uint16_t)((t & 0x8000u) ? ((unsigned)t << 1) ^ 0x1021u
                                         : (unsigned)t << 1);
        /* crc 0: T[byte] is all that remains of the update */
        CHECK_EQ(wsg_crc_update(0, &byte, 1), t);
    }
}

static void test_encode(void)
{
    uint8_t out[64], payload[2] = {0x12, 0x34};
    uint8_t acc[4];

    CHECK_EQ(wsg_frame_encode(out, sizeof out, 0x01, NULL, 0),
             MP_LEN(MP_LOOP_EMPTY));
    CHECK(memcmp(out, MP(MP_LOOP_EMPTY), MP_LEN(MP_LOOP_EMPTY)) == 0);
    CHECK_EQ(wsg_frame_encode(out, sizeof out, 0x01, payload, 2),
             MP_LEN(MP_LOOP_1234));
    CHECK(memcmp(out, MP(MP_LOOP_1234), MP_LEN(MP_LOOP_1234)) == 0);
    CHECK_EQ(wsg_frame_encode_reply(out, sizeof out, 0x20, 0, NULL, 0),
             MP_LEN(MP_HOMING_OK));
    CHECK(memcmp(out, MP(MP_HOMING_OK), MP_LEN(MP_HOMING_OK)) == 0);
    wsg_put_f32(acc, 150.0f);
    CHECK_EQ(wsg_frame_encode_reply(out, sizeof out, 0x30, 0, acc, 4),
             MP_LEN(MP_GET_ACC));
    CHECK(memcmp(out, MP(MP_GET_ACC), MP_LEN(MP_GET_ACC)) == 0);
    /* Too small a buffer: nothing written, 0 returned. */
    CHECK_EQ(wsg_frame_encode(out, 9, 0x01, payload, 2), 0);
    CHECK_EQ(wsg_get_f32(acc), 150.0f);
}

/* Everything the parser reports for an input fed in chunks of `chunk`. */
struct events {
    int n;
    enum wsg_parse_event ev[16];
    uint8_t id[16];
    uint16_t len[16];
    uint8_t payload[16][WSG_REPLY_PAYLOAD_MAX];
};

static void feed_chunked(struct wsg_parser *p, const uint8_t *in, size_t len,
                         size_t chunk, struct events *e)
{
    size_t off = 0;

    memset(e, 0, sizeof *e);
    while (off < len) {
        size_t n = len - off < chunk ? len - off : chunk;
        const uint8_t *c = in + off;
        off += n;
        while (n) {
            enum wsg_parse_event ev;
            struct wsg_frame f;
            size_t used = wsg_parser_feed(p, c, n, &ev, &f);
            REQUIRE(used > 0 && used <= n);
            c += used;
            n -= used;
            if (ev == WSG_PARSE_NONE) {
                CHECK_EQ(n, 0);
                continue;
            }
            REQUIRE(e->n < 16);
            e->ev[e->n] = ev;
            e->id[e->n] = f.id;
            e->len[e->n] = f.len;
            memcpy(e->payload[e->n], f.payload, f.len);
            e->n++;
        }
    }
}

static void test_parser_splits(void)
{
    uint8_t stream[256];
    size_t len = 0, chunk;
    struct events ref, e;
    struct wsg_parser p;
    int i;

    /* garbage, two frames back to back, garbage ending in AAh, a frame */
    memcpy(stream + len, "\x01\x02\xAA\x55", 4);
    len += 4;
    memcpy(stream + len, MP(MP_LOOP_1234), MP_LEN(MP_LOOP_1234));
    len += MP_LEN(MP_LOOP_1234);
    memcpy(stream + len, MP(MP_LOOP_EMPTY), MP_LEN(MP_LOOP_EMPTY));
    len += MP_LEN(MP_LOOP_EMPTY);
    memcpy(stream + len, "\xAA\xAA\x00\xAA", 4);
    len += 4;
    memcpy(stream + len, MP(MP_GET_ACC), MP_LEN(MP_GET_ACC));
    len += MP_LEN(MP_GET_ACC);

    wsg_parser_init(&p, 1);
    feed_chunked(&p, stream, len, len, &ref);
    REQUIRE(ref.n == 3);
    for (i = 0; i < 3; i++)
        CHECK_EQ(ref.ev[i], WSG_PARSE_FRAME);
    CHECK_EQ(ref.id[0], 0x01);
    CHECK_EQ(ref.len[0], 2);
    CHECK(memcmp(ref.payload[0], "\x12\x34", 2) == 0);
    CHECK_EQ(ref.id[1], 0x01);
    CHECK_EQ(ref.len[1], 0);
    CHECK_EQ(ref.id[2], 0x30);
    CHECK_EQ(ref.len[2], 6);

    /* Any split of the input gives the same frames. */
    for (chunk = 1; chunk < len; chunk++) {
        wsg_parser_init(&p, 1);
        feed_chunked(&p, stream, len, chunk, &e);
        CHECK_EQ(e.n, ref.n);
        CHECK(memcmp(&e, &ref, sizeof e) == 0);
    }
}

static void test_parser_bad_crc(void)
{
    uint8_t stream[64];
    struct events e;
    struct wsg_parser p;

    memcpy(stream, MP(MP_LOOP_1234), MP_LEN(MP_LOOP_1234));
    stream[MP_LEN(MP_LOOP_1234) - 1] ^= 0xFF; /* break the checksum */
    memcpy(stream + MP_LEN(MP_LOOP_1234), MP(MP_LOOP_EMPTY),
           MP_LEN(MP_LOOP_EMPTY));

    wsg_parser_init(&p, 1);
    feed_chunked(&p, stream, MP_LEN(MP_LOOP_1234) + MP_LEN(MP_LOOP_EMPTY), 3,
                 &e);
    REQUIRE(e.n == 2);
    CHECK_EQ(e.ev[0], WSG_PARSE_BAD_CRC);
    CHECK_EQ(e.id[0], 0x01);            /* answered under the received ID */
    CHECK_EQ(e.ev[1], WSG_PARSE_FRAME); /* and back in step */

    /* Checksum evaluation off: the same bytes are a frame. */
    wsg_parser_init(&p, 0);
    feed_chunked(&p, stream, MP_LEN(MP_LOOP_1234), 1, &e);
    REQUIRE(e.n == 1);
    CHECK_EQ(e.ev[0], WSG_PARSE_FRAME);
}

static void test_parser_oversize(void)
{
    /* SIZE FFFFh: refused at once, without waiting for 65535 bytes */
    uint8_t stream[64] = {0xAA, 0xAA, 0xAA, 0x06, 0xFF, 0xFF, 0x00, 0x00};
    size_t len = 8;
    struct events e;
    struct wsg_parser p;
    uint8_t big[3 + 3] = {0xAA,
                          0xAA,
                          0xAA,
                          0x06,
                          (WSG_PAYLOAD_MAX + 1) & 0xFF,
                          (WSG_PAYLOAD_MAX + 1) >> 8};

    memcpy(stream + len, MP(MP_LOOP_EMPTY), MP_LEN(MP_LOOP_EMPTY));
    len += MP_LEN(MP_LOOP_EMPTY);
    wsg_parser_init(&p, 1);
    feed_chunked(&p, stream, len, 1, &e);
    REQUIRE(e.n == 2);
    CHECK_EQ(e.ev[0], WSG_PARSE_OVERSIZE);
    CHECK_EQ(e.id[0], 0x06);
    CHECK_EQ(e.ev[1], WSG_PARSE_FRAME);
    CHECK_EQ(e.id[1], 0x01);

    /* One above the maximum is refused; the maximum itself is accepted. */
    wsg_parser_init(&p, 1);
    feed_chunked(&p, big, sizeof big, 1, &e);
    REQUIRE(e.n == 1);
    CHECK_EQ(e.ev[0], WSG_PARSE_OVERSIZE);
    {
        uint8_t loop[WSG_PAYLOAD_MAX], frame[WSG_PAYLOAD_MAX + 8];
        size_t n;
        memset(loop, 0x5A, sizeof loop);
        n = wsg_frame_encode(frame, sizeof frame, 0x06, loop, sizeof loop);
        REQUIRE(n == sizeof frame);
        wsg_parser_init(&p, 1);
        feed_chunked(&p, frame, n, 7, &e);
        REQUIRE(e.n == 1);
        CHECK_EQ(e.ev[0], WSG_PARSE_FRAME);
        CHECK_EQ(e.len[0], WSG_PAYLOAD_MAX);
    }
}

/* A host reading replies: the 256-byte Loop echo is a 258-byte payload. */
static void test_parser_reply_max(void)
{
    uint8_t echo[WSG_PAYLOAD_MAX], frame[WSG_FRAME_MAX];
    struct events e;
    struct wsg_parser p;
    size_t n;

    memset(echo, 0xAA, sizeof echo); /* preamble bytes inside a payload */
    n = wsg_frame_encode_reply(frame, sizeof frame, 0x06, 0, echo,
                               sizeof echo);
    REQUIRE(n == WSG_FRAME_MAX);
    wsg_parser_init(&p, 1);
    feed_chunked(&p, frame, n, 5, &e);
    REQUIRE(e.n >= 1);
    CHECK_EQ(e.ev[0], WSG_PARSE_OVERSIZE); /* too big for a request */
    wsg_parser_init(&p, 1);
    wsg_parser_set_max(&p, 0xFFFF); /* capped to the buffer */
    CHECK_EQ(p.max, WSG_REPLY_PAYLOAD_MAX);
    feed_chunked(&p, frame, n, 5, &e);
    REQUIRE(e.n == 1);
    CHECK_EQ(e.ev[0], WSG_PARSE_FRAME);
    CHECK_EQ(e.len[0], WSG_REPLY_PAYLOAD_MAX);
}

static void test_status_names(void)
{
    CHECK(strcmp(wsg_status_name(WSG_E_SUCCESS), "E_SUCCESS") == 0);
    CHECK(strcmp(wsg_status_name(WSG_E_CMD_PENDING), "E_CMD_PENDING") == 0);
    CHECK(strcmp(wsg_status_name(WSG_E_FILE_EXISTS), "E_FILE_EXISTS") == 0);
    CHECK(strcmp(wsg_status_name(31), "E_UNKNOWN") == 0);
}

/* Numbers as the documentation writes them: decimal or 0x hex, never
 * octal, nothing else around them. */
static void test_numbers(void)
{
    unsigned long v = 0;

    CHECK_EQ(wsg_parse_ulong("010", 0x7FF, &v), 0);
    CHECK_EQ(v, 10);
    CHECK_EQ(wsg_parse_ulong("08", 0x7FF, &v), 0);
    CHECK_EQ(v, 8);
    CHECK_EQ(wsg_parse_ulong("0x7fE", 0x7FF, &v), 0);
    CHECK_EQ(v, 0x7FE);
    CHECK_EQ(wsg_parse_ulong("0X10", 0x7FF, &v), 0);
    CHECK_EQ(v, 16);
    CHECK_EQ(wsg_parse_ulong("0", 0, &v), 0);
    CHECK_EQ(v, 0);
    CHECK_EQ(wsg_parse_ulong("", 10, &v), -EINVAL);
    CHECK_EQ(wsg_parse_ulong("0x", 10, &v), -EINVAL);
    CHECK_EQ(wsg_parse_ulong(" 1", 10, &v), -EINVAL);
    CHECK_EQ(wsg_parse_ulong("-1", 10, &v), -EINVAL);
    CHECK_EQ(wsg_parse_ulong("+1", 10, &v), -EINVAL);
    CHECK_EQ(wsg_parse_ulong("1a", 100, &v), -EINVAL);
    CHECK_EQ(wsg_parse_ulong("256", 255, &v), -ERANGE);
    CHECK_EQ(wsg_parse_ulong("0x800", 0x7FF, &v), -ERANGE);
    CHECK_EQ(wsg_parse_ulong("99999999999999999999999", 0xFFFFFFFFul, &v),
             -ERANGE);
}

int main(void)
{
    test_crc_examples();
    test_crc_table();
    test_encode();
    test_parser_splits();
    test_parser_bad_crc();
    test_parser_oversize();
    test_parser_reply_max();
    test_status_names();
    test_numbers();
    TEST_EXIT();
}
