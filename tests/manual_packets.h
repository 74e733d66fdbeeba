/*
 * The example packets of the manual's chapter 1, byte for byte, for every
 * test that replays them (the CRC and codec tests, the exchanges of 1.2
 * and 1.3, the fuzz corpus). The Get Acceleration example lost one 00h in
 * the manual's text (SIZE says 6, five bytes are printed); its checksum
 * DCCBh is right for the packet with it (docs/behaviour.md).
 */
#ifndef WSG_TEST_MANUAL_PACKETS_H
#define WSG_TEST_MANUAL_PACKETS_H

#include <stdint.h>

enum manual_packet_id {
    MP_LOOP_EMPTY, /* 1.1: command 01h, no payload */
    MP_LOOP_1234,  /* 1.1: command 01h, payload 12h 34h */
    MP_HOMING_OK,  /* 1.2: Homing answered E_SUCCESS */
    MP_UNKNOWN,    /* 1.2: 90h answered E_CMD_UNKNOWN */
    MP_GET_ACC,    /* 1.2: Get Acceleration answered 150.0 mm/s^2 */
    MP_PENDING,    /* 1.3: Preposition answered E_CMD_PENDING */
    MP_FINAL,      /* 1.3: Preposition's final E_SUCCESS */
    MP_COUNT
};

struct manual_packet {
    const char *name; /* for messages and corpus file names */
    unsigned len;
    uint8_t b[14];
};

static const struct manual_packet manual_packets[MP_COUNT] = {
    [MP_LOOP_EMPTY] = {"ex1",
                       8,
                       {0xAA, 0xAA, 0xAA, 0x01, 0x00, 0x00, 0xE8, 0x10}},
    [MP_LOOP_1234] = {"ex2",
                      10,
                      {0xAA, 0xAA, 0xAA, 0x01, 0x02, 0x00, 0x12, 0x34, 0x6D,
                       0x66}},
    [MP_HOMING_OK] = {"homing-reply",
                      10,
                      {0xAA, 0xAA, 0xAA, 0x20, 0x02, 0x00, 0x00, 0x00, 0xB3,
                       0xFD}},
    [MP_UNKNOWN] = {"unknown",
                    10,
                    {0xAA, 0xAA, 0xAA, 0x90, 0x02, 0x00, 0x0E, 0x00, 0xFD,
                     0x02}},
    [MP_GET_ACC] = {"getacc",
                    14,
                    {0xAA, 0xAA, 0xAA, 0x30, 0x06, 0x00, 0x00, 0x00, 0x00,
                     0x00, 0x16, 0x43, 0xDC, 0xCB}},
    [MP_PENDING] = {"pending",
                    10,
                    {0xAA, 0xAA, 0xAA, 0x21, 0x02, 0x00, 0x1A, 0x00, 0x67,
                     0xCB}},
    [MP_FINAL] = {"final",
                  10,
                  {0xAA, 0xAA, 0xAA, 0x21, 0x02, 0x00, 0x00, 0x00, 0x28,
                   0x04}},
};

/* Bytes and length of one of them. */
#define MP(i)     (manual_packets[(i)].b)
#define MP_LEN(i) ((size_t)manual_packets[(i)].len)

#endif
