/* Harness 7 under its replay name (see replay.c). */
#define FUZZ_ENTRY fuzz_sse_one
#include "fuzz_sse.c"
