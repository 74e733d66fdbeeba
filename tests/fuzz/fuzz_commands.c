/*
 * Harness 2: the input as a sequence of commands, each wrapped into a frame
 * with a valid checksum (wsg_frame_encode), so the fuzzer spends its time in
 * the dispatcher, the handlers and the model rather than in checksum errors.
 *
 * Input: one configuration byte (fuzz_bench_begin), then records of
 * [command][control][length][length bytes of payload]. The command byte
 * picks one of the known IDs for most values (the fuzzer cannot see the
 * dispatch table's index as a comparison, so it would rarely guess one) and
 * is taken as a raw ID from 232 up, which reaches unknown commands.
 */
#include <stddef.h>
#include <stdint.h>

#include "fuzz_bench.h"
#include "fuzz_ids.h"
#include "wsg/proto.h"

#ifndef FUZZ_ENTRY
#define FUZZ_ENTRY LLVMFuzzerTestOneInput
#endif

int FUZZ_ENTRY(const uint8_t *data, size_t size);

int FUZZ_ENTRY(const uint8_t *data, size_t size)
{
    uint8_t pkt[WSG_HEADER_LEN + WSG_PAYLOAD_MAX + WSG_CRC_LEN];
    size_t i = 1;

    if (size < 1)
        return 0;
    fuzz_bench_begin(data[0]);
    while (i + 3 <= size) {
        uint8_t id = data[i] >= FUZZ_RAW_ID_FROM
                         ? data[i]
                         : fuzz_ids[data[i] % FUZZ_NIDS];
        uint8_t ctl = data[i + 1];
        size_t len = data[i + 2], n;

        i += 3;
        if (len > size - i)
            len = size - i;
        n = wsg_frame_encode(pkt, sizeof pkt, id, data + i, len);
        i += len;
        if (n)
            fuzz_bench_chunk(ctl, pkt, n);
    }
    fuzz_bench_end();
    return 0;
}
