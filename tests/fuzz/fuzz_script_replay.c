/* Harness 5 under its replay name (see replay.c). */
#define FUZZ_ENTRY fuzz_script_one
#include "fuzz_script.c"
