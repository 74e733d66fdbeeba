/* Harness 7 under its replay name (see replay.c). */
#define FUZZ_ENTRY fuzz_match_one
#include "fuzz_match.c"
