/* Harness fingers under its replay name (see replay.c). */
#define FUZZ_ENTRY fuzz_fingers_one
#include "fuzz_fingers.c"
