/*
 * The command IDs the commands harness picks from (fuzz_commands.c): those
 * of the schema (wsg/schema.h), shared with the seed generator so its
 * records name the IDs it means.
 */
#ifndef WSG_FUZZ_IDS_H
#define WSG_FUZZ_IDS_H

#include <stdint.h>

#include "wsg/proto.h"

/* From this value up a command byte is taken as a raw ID. */
#define FUZZ_RAW_ID_FROM 232u

/* Every command of the schema, in its (ID) order: the seed corpus names
 * IDs by their index here. */
#define FUZZ_ID_(id, ...) id,
static const uint8_t fuzz_ids[] = {WSG_SCHEMA_COMMANDS(FUZZ_ID_)};

#define FUZZ_NIDS (sizeof fuzz_ids / sizeof fuzz_ids[0])

#endif
