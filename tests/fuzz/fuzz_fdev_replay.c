/* Harness fdev under its replay name (see replay.c). */
#define FUZZ_ENTRY fuzz_fdev_one
#include "fuzz_fdev.c"
