/* Harness 2 under its replay name (see replay.c). */
#define FUZZ_ENTRY fuzz_commands_one
#include "fuzz_commands.c"
