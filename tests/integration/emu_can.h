/*
 * CAN helpers of the integration tests, beside the emu_can client transport
 * (emu_can.c): raw SocketCAN sockets and single frames, for tests that put
 * exactly the frames they mean on the bus (other identifiers, RTR and
 * extended frames, packets cut short) and look at the frames that come
 * back, not only at the packets they carry.
 */
#ifndef WSG_TEST_EMU_CAN_H
#define WSG_TEST_EMU_CAN_H

#include <stddef.h>
#include <stdint.h>

#include "emu.h"

/* The interface the tests use: $WSG_TEST_CAN_IFACE, else "vcan0". */
const char *emu_can_iface(void);
/* 0 when CAN_RAW sockets work and the interface exists; otherwise 77 with
 * the reason printed (the caller skips). */
int emu_can_available(const char *iface);
/* A raw CAN socket on iface that receives only standard data frames with
 * identifier rx_id, or nothing (EMU_CAN_RX_NONE), or every frame but error
 * frames (EMU_CAN_RX_ALL). Returns it, or -1 and a message. */
#define EMU_CAN_RX_NONE (-1)
#define EMU_CAN_RX_ALL  (-2)
int emu_can_socket(const char *iface, int rx_id);

struct emu_can_frame {
    uint32_t id; /* can_id with its EFF/RTR/ERR flag bits */
    uint8_t len;
    uint8_t data[8];
};

/* One frame as given (id may carry CAN_EFF_FLAG or CAN_RTR_FLAG). 0 or -1;
 * a full interface queue is waited out for up to EMU_REPLY_MS. */
int emu_can_send_frame(int fd, uint32_t id, const void *data, size_t len);
/* A packet cut into 8-byte frames on id, the last one shorter. 0 or -1. */
int emu_can_send_packet(int fd, uint32_t id, const uint8_t *pkt, size_t len);
/* The next frame within timeout_ms: 1, 0 on timeout, -1 on an error. */
int emu_can_recv_frame(int fd, struct emu_can_frame *f, int timeout_ms);

#endif
