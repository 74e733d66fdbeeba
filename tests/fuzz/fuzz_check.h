/*
 * The fuzz harnesses' invariant check: abort() rather than assert(), so the
 * check stays in every build type; the message names the invariant and
 * libFuzzer's stack trace the path that broke it.
 */
#ifndef WSG_FUZZ_CHECK_H
#define WSG_FUZZ_CHECK_H

#include <stdio.h>
#include <stdlib.h>

#define FUZZ_CHECK(cond)                                                      \
    do {                                                                      \
        if (!(cond)) {                                                        \
            fprintf(stderr, "%s:%d: invariant failed: %s\n", __FILE__,        \
                    __LINE__, #cond);                                         \
            abort();                                                          \
        }                                                                     \
    } while (0)

#endif
