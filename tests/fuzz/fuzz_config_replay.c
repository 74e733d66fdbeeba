/* Harness 3 under its replay name (see replay.c). */
#define FUZZ_ENTRY fuzz_config_one
#include "fuzz_config.c"
