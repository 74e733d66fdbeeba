/* Harness 4 under its replay name (see replay.c). */
#define FUZZ_ENTRY fuzz_control_one
#include "fuzz_control.c"
