/*
 * WSG wire protocol: status codes, command IDs, the CRC of Appendix C, frame
 * encoding and an incremental frame parser.
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

#define WSG_PREAMBLE_BYTE 0xAAu
#define WSG_PREAMBLE_LEN  3u
#define WSG_HEADER_LEN    6u /* preamble, ID, SIZE (u16) */
#define WSG_CRC_LEN       2u
#define WSG_CRC_INIT      0xFFFFu

/* Largest request payload any command accepts: Loop (06h) takes 256 bytes.
 * A SIZE above this is refused before a single payload byte is buffered. */
#define WSG_PAYLOAD_MAX 256u
/* A reply carries a 2-byte status before its parameters (Loop echoes 256). */
#define WSG_REPLY_PARAMS_MAX  WSG_PAYLOAD_MAX
#define WSG_REPLY_PAYLOAD_MAX (WSG_REPLY_PARAMS_MAX + 2u)
#define WSG_FRAME_MAX         (WSG_HEADER_LEN + WSG_REPLY_PAYLOAD_MAX + WSG_CRC_LEN)

/* Appendix A: every status a reply can carry. */
enum wsg_status {
    WSG_E_SUCCESS = 0,
    WSG_E_NOT_AVAILABLE = 1,
    WSG_E_NO_SENSOR = 2,
    WSG_E_NOT_INITIALIZED = 3,
    WSG_E_ALREADY_RUNNING = 4,
    WSG_E_FEATURE_NOT_SUPPORTED = 5,
    WSG_E_INCONSISTENT_DATA = 6,
    WSG_E_TIMEOUT = 7,
    WSG_E_READ_ERROR = 8,
    WSG_E_WRITE_ERROR = 9,
    WSG_E_INSUFFICIENT_RESOURCES = 10,
    WSG_E_CHECKSUM_ERROR = 11,
    WSG_E_NO_PARAM_EXPECTED = 12,
    WSG_E_NOT_ENOUGH_PARAMS = 13,
    WSG_E_CMD_UNKNOWN = 14,
    WSG_E_CMD_FORMAT_ERROR = 15,
    WSG_E_ACCESS_DENIED = 16,
    WSG_E_ALREADY_OPEN = 17,
    WSG_E_CMD_FAILED = 18,
    WSG_E_CMD_ABORTED = 19,
    WSG_E_INVALID_HANDLE = 20,
    WSG_E_NOT_FOUND = 21,
    WSG_E_NOT_OPEN = 22,
    WSG_E_IO_ERROR = 23,
    WSG_E_INVALID_PARAMETER = 24,
    WSG_E_INDEX_OUT_OF_BOUNDS = 25,
    WSG_E_CMD_PENDING = 26,
    WSG_E_OVERRUN = 27,
    WSG_E_RANGE_ERROR = 28,
    WSG_E_AXIS_BLOCKED = 29,
    WSG_E_FILE_EXISTS = 30
};

/* Command IDs of the 2.2.0 command set plus Get Temperature (46h). */
enum wsg_cmd_id {
    WSG_CMD_LOOP = 0x06,
    WSG_CMD_DISCONNECT = 0x07,
    WSG_CMD_HOMING = 0x20,
    WSG_CMD_PREPOSITION = 0x21,
    WSG_CMD_STOP = 0x22,
    WSG_CMD_FAST_STOP = 0x23,
    WSG_CMD_ACK_FAST_STOP = 0x24,
    WSG_CMD_GRASP = 0x25,
    WSG_CMD_RELEASE = 0x26,
    WSG_CMD_SET_ACCELERATION = 0x30,
    WSG_CMD_GET_ACCELERATION = 0x31,
    WSG_CMD_SET_FORCE_LIMIT = 0x32,
    WSG_CMD_GET_FORCE_LIMIT = 0x33,
    WSG_CMD_SET_SOFT_LIMITS = 0x34,
    WSG_CMD_GET_SOFT_LIMITS = 0x35,
    WSG_CMD_CLEAR_SOFT_LIMITS = 0x36,
    WSG_CMD_OVERDRIVE = 0x37,
    WSG_CMD_TARE = 0x38,
    WSG_CMD_GET_SYSTEM_STATE = 0x40,
    WSG_CMD_GET_GRASP_STATE = 0x41,
    WSG_CMD_GET_GRASP_STATS = 0x42,
    WSG_CMD_GET_WIDTH = 0x43,
    WSG_CMD_GET_SPEED = 0x44,
    WSG_CMD_GET_FORCE = 0x45,
    WSG_CMD_GET_TEMPERATURE = 0x46,
    WSG_CMD_GET_SYSTEM_INFO = 0x50,
    WSG_CMD_SET_DEVICE_TAG = 0x51,
    WSG_CMD_GET_DEVICE_TAG = 0x52,
    WSG_CMD_GET_SYSTEM_LIMITS = 0x53
};

/* "E_SUCCESS", ...; "E_UNKNOWN" for values outside Appendix A. */
const char *wsg_status_name(unsigned status);

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

#endif
