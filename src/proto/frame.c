/*
 * Frame encoding and the incremental frame parser.
 *
 * The parser is a byte-driven state machine over caller-owned state, in the
 * manner of MAVLink's frame_char_buffer: input may arrive in any split, a
 * read may hold several frames or half of one. It hunts for three preamble
 * bytes, reads ID and SIZE, refuses a SIZE above its maximum before
 * buffering anything, then collects payload and checksum. The CRC runs over
 * every byte of the frame including the received checksum and must end at 0
 * (chapter 1.1), so no byte is looked at twice.
 */
#include <string.h>

#include "wsg/proto.h"

enum {
    WSG_PS_HUNT = 0, /* counting preamble bytes in size_lo */
    WSG_PS_ID,
    WSG_PS_SIZE_LO,
    WSG_PS_SIZE_HI,
    WSG_PS_BODY
};

static const uint8_t wsg_preamble[WSG_PREAMBLE_LEN] = {
    WSG_PREAMBLE_BYTE, WSG_PREAMBLE_BYTE, WSG_PREAMBLE_BYTE};

uint16_t wsg_get_u16(const uint8_t *p)
{
    return (uint16_t)(p[0] | (p[1] << 8));
}

uint32_t wsg_get_u32(const uint8_t *p)
{
    return (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) |
           ((uint32_t)p[3] << 24);
}

float wsg_get_f32(const uint8_t *p)
{
    uint32_t u = wsg_get_u32(p);
    float f;
    memcpy(&f, &u, sizeof f);
    return f;
}

void wsg_put_u16(uint8_t *p, uint16_t v)
{
    p[0] = (uint8_t)v;
    p[1] = (uint8_t)(v >> 8);
}

void wsg_put_u32(uint8_t *p, uint32_t v)
{
    p[0] = (uint8_t)v;
    p[1] = (uint8_t)(v >> 8);
    p[2] = (uint8_t)(v >> 16);
    p[3] = (uint8_t)(v >> 24);
}

void wsg_put_f32(uint8_t *p, float v)
{
    uint32_t u;
    memcpy(&u, &v, sizeof u);
    wsg_put_u32(p, u);
}

size_t wsg_frame_encode(uint8_t *out, size_t cap, uint8_t id,
                        const uint8_t *payload, size_t len)
{
    size_t total = WSG_HEADER_LEN + len + WSG_CRC_LEN;
    uint16_t crc;

    if (len > 0xFFFFu || total > cap)
        return 0;
    memcpy(out, wsg_preamble, WSG_PREAMBLE_LEN);
    out[3] = id;
    wsg_put_u16(out + 4, (uint16_t)len);
    if (len)
        memcpy(out + WSG_HEADER_LEN, payload, len);
    crc = wsg_crc_update(WSG_CRC_INIT, out, WSG_HEADER_LEN + len);
    wsg_put_u16(out + WSG_HEADER_LEN + len, crc);
    return total;
}

size_t wsg_frame_encode_reply(uint8_t *out, size_t cap, uint8_t id,
                              uint16_t status, const uint8_t *params,
                              size_t len)
{
    size_t total = WSG_HEADER_LEN + 2 + len + WSG_CRC_LEN;
    uint16_t crc;

    if (len > 0xFFFFu - 2 || total > cap)
        return 0;
    memcpy(out, wsg_preamble, WSG_PREAMBLE_LEN);
    out[3] = id;
    wsg_put_u16(out + 4, (uint16_t)(len + 2));
    wsg_put_u16(out + WSG_HEADER_LEN, status);
    if (len)
        memcpy(out + WSG_HEADER_LEN + 2, params, len);
    crc = wsg_crc_update(WSG_CRC_INIT, out, total - WSG_CRC_LEN);
    wsg_put_u16(out + total - WSG_CRC_LEN, crc);
    return total;
}

void wsg_parser_init(struct wsg_parser *p, int check_crc)
{
    memset(p, 0, sizeof *p);
    p->state = WSG_PS_HUNT;
    p->check_crc = check_crc ? 1 : 0;
    p->max = WSG_PAYLOAD_MAX;
}

void wsg_parser_set_max(struct wsg_parser *p, uint16_t max)
{
    p->max = max > WSG_REPLY_PAYLOAD_MAX ? WSG_REPLY_PAYLOAD_MAX : max;
}

int wsg_parser_partial(const struct wsg_parser *p, uint8_t *id)
{
    if (p->state == WSG_PS_HUNT || p->state == WSG_PS_ID)
        return p->state == WSG_PS_ID ? 2 : 0;
    *id = p->id;
    return 1;
}

static void wsg_parser_hunt(struct wsg_parser *p)
{
    p->state = WSG_PS_HUNT;
    p->size_lo = 0;
}

size_t wsg_parser_feed(struct wsg_parser *p, const uint8_t *data, size_t len,
                       enum wsg_parse_event *ev, struct wsg_frame *frame)
{
    size_t i = 0;

    *ev = WSG_PARSE_NONE;
    while (i < len) {
        uint8_t b = data[i];

        switch (p->state) {
        case WSG_PS_HUNT:
            i++;
            if (b != WSG_PREAMBLE_BYTE) {
                p->size_lo = 0;
                break;
            }
            if (++p->size_lo == WSG_PREAMBLE_LEN) {
                p->crc = wsg_crc_update(WSG_CRC_INIT, wsg_preamble,
                                        WSG_PREAMBLE_LEN);
                p->state = WSG_PS_ID;
            }
            break;
        case WSG_PS_ID:
            i++;
            /* A fourth AAh extends the preamble: garbage ending in AAh
             * before a real packet must not shift its header. No command
             * has the ID AAh. */
            if (b == WSG_PREAMBLE_BYTE)
                break;
            p->id = b;
            p->crc = wsg_crc_update(p->crc, &b, 1);
            p->state = WSG_PS_SIZE_LO;
            break;
        case WSG_PS_SIZE_LO:
            i++;
            p->size_lo = b;
            p->crc = wsg_crc_update(p->crc, &b, 1);
            p->state = WSG_PS_SIZE_HI;
            break;
        case WSG_PS_SIZE_HI:
            i++;
            p->size = (uint16_t)(p->size_lo | (b << 8));
            p->crc = wsg_crc_update(p->crc, &b, 1);
            if (p->size > p->max) {
                /* Refuse before buffering: nothing depends on SIZE. */
                frame->id = p->id;
                frame->len = 0;
                frame->payload = p->buf;
                wsg_parser_hunt(p);
                *ev = WSG_PARSE_OVERSIZE;
                return i;
            }
            p->got = 0;
            p->state = WSG_PS_BODY;
            break;
        case WSG_PS_BODY: {
            size_t need = (size_t)p->size + WSG_CRC_LEN - p->got;
            size_t n = len - i < need ? len - i : need;

            memcpy(p->buf + p->got, data + i, n);
            p->crc = wsg_crc_update(p->crc, data + i, n);
            p->got = (uint16_t)(p->got + n);
            i += n;
            if (n < need)
                break;
            frame->id = p->id;
            frame->len = p->size;
            frame->payload = p->buf;
            *ev = (p->crc == 0 || !p->check_crc) ? WSG_PARSE_FRAME
                                                 : WSG_PARSE_BAD_CRC;
            wsg_parser_hunt(p);
            return i;
        }
        default:
            wsg_parser_hunt(p);
            break;
        }
    }
    return i;
}
