/*
 * The command IDs the commands harness picks from (fuzz_commands.c), shared
 * with the seed generator so its records name the IDs it means.
 */
#ifndef WSG_FUZZ_IDS_H
#define WSG_FUZZ_IDS_H

#include <stdint.h>

#include "wsg/proto.h"

/* From this value up a command byte is taken as a raw ID. */
#define FUZZ_RAW_ID_FROM 232u

static const uint8_t fuzz_ids[] = {
    WSG_CMD_LOOP,
    WSG_CMD_DISCONNECT,
    WSG_CMD_HOMING,
    WSG_CMD_PREPOSITION,
    WSG_CMD_STOP,
    WSG_CMD_FAST_STOP,
    WSG_CMD_ACK_FAST_STOP,
    WSG_CMD_GRASP,
    WSG_CMD_RELEASE,
    WSG_CMD_SET_ACCELERATION,
    WSG_CMD_GET_ACCELERATION,
    WSG_CMD_SET_FORCE_LIMIT,
    WSG_CMD_GET_FORCE_LIMIT,
    WSG_CMD_SET_SOFT_LIMITS,
    WSG_CMD_GET_SOFT_LIMITS,
    WSG_CMD_CLEAR_SOFT_LIMITS,
    WSG_CMD_OVERDRIVE,
    WSG_CMD_TARE,
    WSG_CMD_GET_SYSTEM_STATE,
    WSG_CMD_GET_GRASP_STATE,
    WSG_CMD_GET_GRASP_STATS,
    WSG_CMD_GET_WIDTH,
    WSG_CMD_GET_SPEED,
    WSG_CMD_GET_FORCE,
    WSG_CMD_GET_TEMPERATURE,
    WSG_CMD_GET_SYSTEM_INFO,
    WSG_CMD_SET_DEVICE_TAG,
    WSG_CMD_GET_DEVICE_TAG,
    WSG_CMD_GET_SYSTEM_LIMITS,
};

#define FUZZ_NIDS (sizeof fuzz_ids / sizeof fuzz_ids[0])

#endif
