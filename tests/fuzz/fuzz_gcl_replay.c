/* Harness 6 under its replay name (see replay.c). */
#define FUZZ_ENTRY fuzz_gcl_one
#include "fuzz_gcl.c"
