/*
 * WSG wire protocol: the CRC of Appendix C, frame encoding and an
 * incremental frame parser. What the packets mean (status codes, command
 * IDs, payload layouts) is the schema's, wsg/schema.h, included here.
 *
 * This layer does no I/O, reads no clock and allocates nothing. The parser
 * keeps its whole state in a caller-owned struct and consumes any split of
 * the byte stream, so every transport (TCP stream, UDP datagram, serial
 * bytes, CAN frames) feeds it the same way.
 */
#ifndef WSG_PROTO_H
#define WSG_PROTO_H

#include <stddef.h>
#include <stdint.h>

#include "wsg/schema.h"

#define WSG_PREAMBLE_BYTE 0xAAu
#define WSG_PREAMBLE_LEN  3u
#define WSG_HEADER_LEN    6u /* preamble, ID, SIZE (u16) */
#define WSG_CRC_LEN       2u
#define WSG_CRC_INIT      0xFFFFu

/* A reply carries a 2-byte status before its parameters (Loop echoes 256). */
#define WSG_REPLY_PARAMS_MAX  WSG_PAYLOAD_MAX
#define WSG_REPLY_PAYLOAD_MAX (WSG_REPLY_PARAMS_MAX + 2u)
#define WSG_FRAME_MAX         (WSG_HEADER_LEN + WSG_REPLY_PAYLOAD_MAX + WSG_CRC_LEN)

/* Appendix C: table-driven CRC. Start with WSG_CRC_INIT; running it over a
 * whole packet including its checksum gives 0. */
uint16_t wsg_crc_update(uint16_t crc, const uint8_t *data, size_t len);

/* Little-endian field access, as every multi-byte value on the wire. */
uint16_t wsg_get_u16(const uint8_t *p);
uint32_t wsg_get_u32(const uint8_t *p);
float wsg_get_f32(const uint8_t *p);
void wsg_put_u16(uint8_t *p, uint16_t v);
void wsg_put_u32(uint8_t *p, uint32_t v);
void wsg_put_f32(uint8_t *p, float v);

/* Build a packet with a valid checksum. Returns its length, or 0 if it does
 * not fit in cap or the payload exceeds what SIZE can express. */
size_t wsg_frame_encode(uint8_t *out, size_t cap, uint8_t id,
                        const uint8_t *payload, size_t len);
/* Build a reply: status, then params (the manual sends params only with
 * E_SUCCESS, and Loop's echo; the caller decides). */
size_t wsg_frame_encode_reply(uint8_t *out, size_t cap, uint8_t id,
                              uint16_t status, const uint8_t *params,
                              size_t len);

/* A received frame. payload points into the parser's buffer and is valid
 * until the next call to wsg_parser_feed. */
struct wsg_frame {
    uint8_t id;
    uint16_t len;
    const uint8_t *payload;
};

enum wsg_parse_event {
    WSG_PARSE_NONE = 0, /* all input consumed, no event */
    WSG_PARSE_FRAME,    /* a complete frame with a good (or ignored) CRC */
    WSG_PARSE_BAD_CRC,  /* complete frame, wrong CRC: frame.id is valid */
    WSG_PARSE_OVERSIZE  /* SIZE above the parser's max: frame.id is valid */
};

struct wsg_parser {
    uint8_t state;     /* private: enum in proto/frame.c */
    uint8_t check_crc; /* 0: received checksums are ignored (--no-crc) */
    uint8_t id;
    uint8_t size_lo;
    uint16_t max; /* largest SIZE accepted */
    uint16_t size;
    uint16_t got; /* payload + CRC bytes received */
    uint16_t crc; /* running CRC over everything received */
    uint8_t buf[WSG_REPLY_PAYLOAD_MAX + WSG_CRC_LEN];
};

/* Accepts SIZE up to WSG_PAYLOAD_MAX, what any command takes. */
void wsg_parser_init(struct wsg_parser *p, int check_crc);
/* A host reading replies accepts up to WSG_REPLY_PAYLOAD_MAX (a 256-byte
 * Loop echo plus its status); larger values are capped to that. */
void wsg_parser_set_max(struct wsg_parser *p, uint16_t max);
/* Inside a frame (its preamble seen, its end not yet): 1, with the ID in
 * *id once it has arrived (else *id is left alone and 2 is returned). */
int wsg_parser_partial(const struct wsg_parser *p, uint8_t *id);
/* Consume bytes until an event or the end of the input. Returns the number
 * of bytes consumed; call again with the rest while it is less than len.
 * Bytes before a preamble are skipped. After BAD_CRC or OVERSIZE the parser
 * is already hunting for the next preamble. */
size_t wsg_parser_feed(struct wsg_parser *p, const uint8_t *data, size_t len,
                       enum wsg_parse_event *ev, struct wsg_frame *frame);

/* A number as the documentation writes one: decimal digits, or 0x (0X)
 * and hex digits (010 is ten), at most max. Returns 0, -EINVAL for other
 * text, -ERANGE above max. */
int wsg_parse_ulong(const char *s, unsigned long max, unsigned long *out);

#endif
