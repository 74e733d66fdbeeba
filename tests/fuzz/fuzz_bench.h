/*
 * The test bench the fuzz harnesses share: one emulated gripper, two
 * sessions that check every packet the emulator sends, and the invariants
 * of the protocol and the model, checked after every input chunk and every
 * model step.
 *
 * Both harnesses decode their input into chunks: bytes for one session,
 * then a world event (a part, an obstacle, a fault, a session closed), then
 * a few model steps. At the end the bench steps until every motion has
 * ended and checks that every E_CMD_PENDING got exactly one final result.
 * A violated invariant calls abort(), which libFuzzer reports as a crash
 * and the replay test as a failure.
 */
#ifndef WSG_FUZZ_BENCH_H
#define WSG_FUZZ_BENCH_H

#include <stddef.h>
#include <stdint.h>

struct wsg_device;

/* The chunk's control byte. Bit 0: session 0 (a TCP-like connection) or
 * 1 (a UDP-like peer). Bits 1-3: how many model steps follow the chunk:
 * 0, 1, 2, 5, 10, 50, 200 or 1000. Bits 4-7: the world event applied after
 * the bytes: 0-8 none, 9 feed the bytes as one datagram instead of a
 * stream, 10 place a part (width from the first data byte, within the
 * opening; stiffness from the second), 11 remove it, 12 set or clear faults
 * (first data byte: bits 0-4 select, bit 7 sets), 13 place an obstacle
 * (first data byte), 14 remove it, 15 close the session (its peer comes
 * back under a fresh tag).
 *
 * Set FUZZ_TRACE in the environment to print every event and packet of a
 * replayed input, which is how a crash is read. */
#define FUZZ_CTL_SESSION 0x01u

/* Start a run. cfg selects the model (bits 0-1), the force sensor (bit 2)
 * and the parser's checksum check (bit 3 set: --no-crc). */
void fuzz_bench_begin(uint8_t cfg);
/* Feed data to a session as a stream (or, event 9, as one datagram), apply
 * the control byte's world event, then step the model. */
void fuzz_bench_chunk(uint8_t ctl, const uint8_t *data, size_t len);
/* Step until no motion is left (bounded) and check the final results. */
void fuzz_bench_end(void);
/* The bench's gripper, for a harness that changes what the commands do not
 * reach (the fingers fitted, their power, their wires) between chunks; it
 * settles the device after such a change, as the control channel does. */
struct wsg_device *fuzz_bench_device(void);

#endif
