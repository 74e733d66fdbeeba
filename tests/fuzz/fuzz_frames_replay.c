/* Harness 1 under its replay name (see replay.c). */
#define FUZZ_ENTRY fuzz_frames_one
#include "fuzz_frames.c"
