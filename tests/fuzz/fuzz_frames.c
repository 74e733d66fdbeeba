/*
 * Harness 1: arbitrary bytes through the frame parser, the dispatcher and
 * the model, with the checksums as they come (so mostly checksum errors,
 * unless the first byte turns the check off as --no-crc does).
 *
 * Input: one configuration byte (fuzz_bench_begin), then chunks of
 * [length][control][length bytes of wire data] (fuzz_bench_chunk); a chunk
 * cut off by the end of the input takes what is left. The chunking lets
 * the fuzzer split frames across reads and interleave model steps.
 */
#include <stddef.h>
#include <stdint.h>

#include "fuzz_bench.h"

/* The replay build renames the entry point so one program holds both
 * harnesses. */
#ifndef FUZZ_ENTRY
#define FUZZ_ENTRY LLVMFuzzerTestOneInput
#endif

int FUZZ_ENTRY(const uint8_t *data, size_t size);

int FUZZ_ENTRY(const uint8_t *data, size_t size)
{
    size_t i = 1;

    if (size < 1)
        return 0;
    fuzz_bench_begin(data[0]);
    while (i < size) {
        size_t len = data[i];
        uint8_t ctl = i + 1 < size ? data[i + 1] : 0;

        i += 2;
        if (i > size)
            i = size;
        if (len > size - i)
            len = size - i;
        fuzz_bench_chunk(ctl, data + i, len);
        i += len;
    }
    fuzz_bench_end();
    return 0;
}
