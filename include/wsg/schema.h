/*
 * The protocol schema: everything the command set says about its packets,
 * written once. Per command its ID, symbol and name, the length rules the
 * dispatcher enforces, its flags (motion, needs homing, asynchronous, auto
 * update) and the fields of its request and of its reply, typed and named,
 * with units; the status codes of Appendix A, the system state flags of
 * Appendix B and the grasping states of 41h.
 *
 * The lists are X-macros (as MAVLink keeps its message info): whoever needs
 * a table passes a macro that makes one row of it. The dispatcher builds its
 * table indexed by ID from WSG_SCHEMA_COMMANDS, the core library builds
 * wsg_schema[] (below) from it, and the communication log, wsgctl, the
 * fuzzers and the schema dump the Python package is checked against read
 * that, through the field walker declared here. Adding a command is one row
 * here plus its handler in src/cmd/commands.c.
 *
 * The names are the manual's: "SF_REFERENCED", "E_SUCCESS", "HOLDING";
 * field names are the manual's symbols in lower case with hyphens
 * ("no-part", "min-speed", "period-ms"), spelled out where it abbreviates
 * ("acceleration" for ACC, "serial" for SN). The log and wsgctl print
 * them as they are; wsg_schema_key gives the one other spelling, the
 * control channel's JSON keys ("referenced", "no_part").
 */
#ifndef WSG_SCHEMA_H
#define WSG_SCHEMA_H

#include <stddef.h>
#include <stdint.h>

/* Largest request payload any command accepts: Loop (06h) takes 256 bytes.
 * A SIZE above this is refused before a single payload byte is buffered. */
#define WSG_PAYLOAD_MAX 256u
/* The device tag (51h, 52h) holds at most 64 characters. */
#define WSG_TAG_MAX 64u

/* Appendix A: X(VALUE, NAME) for every status a reply can carry. */
#define WSG_SCHEMA_STATUSES(X)                                                \
    X(0, E_SUCCESS)                                                           \
    X(1, E_NOT_AVAILABLE)                                                     \
    X(2, E_NO_SENSOR)                                                         \
    X(3, E_NOT_INITIALIZED)                                                   \
    X(4, E_ALREADY_RUNNING)                                                   \
    X(5, E_FEATURE_NOT_SUPPORTED)                                             \
    X(6, E_INCONSISTENT_DATA)                                                 \
    X(7, E_TIMEOUT)                                                           \
    X(8, E_READ_ERROR)                                                        \
    X(9, E_WRITE_ERROR)                                                       \
    X(10, E_INSUFFICIENT_RESOURCES)                                           \
    X(11, E_CHECKSUM_ERROR)                                                   \
    X(12, E_NO_PARAM_EXPECTED)                                                \
    X(13, E_NOT_ENOUGH_PARAMS)                                                \
    X(14, E_CMD_UNKNOWN)                                                      \
    X(15, E_CMD_FORMAT_ERROR)                                                 \
    X(16, E_ACCESS_DENIED)                                                    \
    X(17, E_ALREADY_OPEN)                                                     \
    X(18, E_CMD_FAILED)                                                       \
    X(19, E_CMD_ABORTED)                                                      \
    X(20, E_INVALID_HANDLE)                                                   \
    X(21, E_NOT_FOUND)                                                        \
    X(22, E_NOT_OPEN)                                                         \
    X(23, E_IO_ERROR)                                                         \
    X(24, E_INVALID_PARAMETER)                                                \
    X(25, E_INDEX_OUT_OF_BOUNDS)                                              \
    X(26, E_CMD_PENDING)                                                      \
    X(27, E_OVERRUN)                                                          \
    X(28, E_RANGE_ERROR)                                                      \
    X(29, E_AXIS_BLOCKED)                                                     \
    X(30, E_FILE_EXISTS)

/* Appendix B: X(BIT, NAME) for each system state flag (D10, D11 and D21
 * up are reserved). */
#define WSG_SCHEMA_SYSTEM_FLAGS(X)                                            \
    X(0, SF_REFERENCED)                                                       \
    X(1, SF_MOVING)                                                           \
    X(2, SF_BLOCKED_MINUS)                                                    \
    X(3, SF_BLOCKED_PLUS)                                                     \
    X(4, SF_SOFT_LIMIT_MINUS)                                                 \
    X(5, SF_SOFT_LIMIT_PLUS)                                                  \
    X(6, SF_AXIS_STOPPED)                                                     \
    X(7, SF_TARGET_POS_REACHED)                                               \
    X(8, SF_OVERDRIVE_MODE)                                                   \
    X(9, SF_FORCECNTL_MODE)                                                   \
    X(12, SF_FAST_STOP)                                                       \
    X(13, SF_TEMP_WARNING)                                                    \
    X(14, SF_TEMP_FAULT)                                                      \
    X(15, SF_POWER_FAULT)                                                     \
    X(16, SF_CURR_FAULT)                                                      \
    X(17, SF_FINGER_FAULT)                                                    \
    X(18, SF_CMD_FAILURE)                                                     \
    X(19, SF_SCRIPT_RUNNING)                                                  \
    X(20, SF_SCRIPT_FAILURE)

/* 41h: X(VALUE, NAME) for each grasping state (8 to 255 are reserved). */
#define WSG_SCHEMA_GRASP_STATES(X)                                            \
    X(0, IDLE)                                                                \
    X(1, GRASPING)                                                            \
    X(2, NO_PART)                                                             \
    X(3, PART_LOST)                                                           \
    X(4, HOLDING)                                                             \
    X(5, RELEASING)                                                           \
    X(6, POSITIONING)                                                         \
    X(7, ERROR)

/* Command flags: the state rules the dispatcher checks, and what kind of
 * command it is. */
#define WSG_CMDF_MOTION 0x01u /* refused in FAST STOP and on faults */
#define WSG_CMDF_HOMED  0x02u /* refused before homing */
/* E_CMD_PENDING, then a final result; refused while moving. */
#define WSG_CMDF_ASYNC    0x04u
#define WSG_CMDF_NO_PARAM 0x08u /* a length error is E_NO_PARAM_EXPECTED */
#define WSG_CMDF_EMPTY_OK 0x10u /* an empty payload is also accepted */
/* Takes FLAGS and PERIOD_MS: a value now, and on request an auto-update
 * stream of it (40h, 41h, 43h to 45h). */
#define WSG_CMDF_STREAM 0x20u
/* A motion command: all of the motion rules. */
#define WSG_CMDF_MOVE (WSG_CMDF_MOTION | WSG_CMDF_ASYNC)

/* What a field is on the wire. Numbers are little-endian. */
enum wsg_field_type {
    WSG_FT_U8,
    WSG_FT_U16,
    WSG_FT_U32,
    WSG_FT_F32,
    WSG_FT_I16_TENTHS, /* int16 in tenths of the unit */
    WSG_FT_VERSION,    /* u16: major << 12 | minor << 8 | patch << 4 */
    WSG_FT_ENUM8,      /* u8, names by value */
    WSG_FT_BITS8,      /* u8 bit vector, names by bit */
    WSG_FT_BITS16,     /* u16 bit vector, names by bit */
    WSG_FT_BITS32,     /* u32 bit vector, names by bit */
    WSG_FT_TEXT,       /* the rest of the payload, up to max: characters */
    WSG_FT_BYTES       /* the rest of the payload, up to max: raw bytes */
};

struct wsg_field {
    const char *name; /* "width", "no-part" */
    const char *unit; /* "mm", "mm/s", "mm/s2", "N", "degC", "ms" or "" */
    /* ENUM8 by value, BITS by bit; NULL entries (and those past nnames)
     * have no name. */
    const char *const *names;
    uint8_t type; /* enum wsg_field_type */
    uint8_t nnames;
    uint16_t max; /* TEXT, BYTES: the most bytes */
};

/* The fields of a request or of a reply's parameters, in wire order. Only
 * the last may be TEXT or BYTES. */
struct wsg_layout {
    const struct wsg_field *fields;
    uint8_t n;
};
/* The most fields a layout has (53h). */
#define WSG_FIELDS_MAX 8u

/* Field constructors for the rows below. */
#define WSG_FIELD_(nm, ty, un, ...)                                           \
    {                                                                         \
        .name = (nm), .unit = (un), .type = (ty), __VA_ARGS__                 \
    }
#define WSG_F_U8(nm)          WSG_FIELD_(nm, WSG_FT_U8, "", .max = 0)
#define WSG_F_U16(nm, un)     WSG_FIELD_(nm, WSG_FT_U16, un, .max = 0)
#define WSG_F_U32(nm)         WSG_FIELD_(nm, WSG_FT_U32, "", .max = 0)
#define WSG_F_F32(nm, un)     WSG_FIELD_(nm, WSG_FT_F32, un, .max = 0)
#define WSG_F_TENTHS(nm, un)  WSG_FIELD_(nm, WSG_FT_I16_TENTHS, un, .max = 0)
#define WSG_F_VERSION(nm)     WSG_FIELD_(nm, WSG_FT_VERSION, "", .max = 0)
#define WSG_F_ENUM8(nm, nms)  WSG_FIELD_(nm, WSG_FT_ENUM8, "", nms)
#define WSG_F_BITS8(nm, nms)  WSG_FIELD_(nm, WSG_FT_BITS8, "", nms)
#define WSG_F_BITS16(nm, nms) WSG_FIELD_(nm, WSG_FT_BITS16, "", nms)
#define WSG_F_BITS32(nm, nms) WSG_FIELD_(nm, WSG_FT_BITS32, "", nms)
#define WSG_F_TEXT(nm, mx)    WSG_FIELD_(nm, WSG_FT_TEXT, "", .max = (mx))
#define WSG_F_BYTES(nm, mx)   WSG_FIELD_(nm, WSG_FT_BYTES, "", .max = (mx))
/* Names of an ENUM8 or BITS field, by value or bit: WSG_NAMES("a", "b"). */
#define WSG_NAMES(...)                                                        \
    .names = (const char *const[]){__VA_ARGS__},                              \
    .nnames = (uint8_t)(sizeof((const char *const[]){__VA_ARGS__}) /          \
                        sizeof(const char *))
/* A layout: WSG_FIELDS(WSG_F_F32("width", "mm"), ...), or WSG_NONE. */
#define WSG_FIELDS(...)                                                       \
    {                                                                         \
        (const struct wsg_field[]){__VA_ARGS__},                              \
            (uint8_t)(sizeof((const struct wsg_field[]){__VA_ARGS__}) /       \
                      sizeof(struct wsg_field))                               \
    }
#define WSG_NONE                                                              \
    {                                                                         \
        NULL, 0                                                               \
    }

/* FLAGS and PERIOD_MS of the commands that stream (3.4.1). */
#define WSG_STREAM_REQUEST                                                    \
    WSG_FIELDS(WSG_F_BITS8("flags", WSG_NAMES("auto-update", "change-only")), \
               WSG_F_U16("period-ms", "ms"))

/* The finger commands (later firmware): a finger index, or nothing for
 * the finger the ID names (60h..63h finger 1, 70h..73h finger 2). */
#define WSG_FINGER_INDEX WSG_FIELDS(WSG_F_U8("finger"))
#define WSG_FINGER_INFO                                                       \
    WSG_FIELDS(                                                               \
        WSG_F_ENUM8("type", WSG_NAMES("none", "generic", "fmf", "dsa")),      \
        WSG_F_U16("size", ""))
/* 61h/71h: include/wsg/finger.h's WSG_FF_* by bit (docs/fingers.md). */
#define WSG_FINGER_FLAGS                                                      \
    WSG_FIELDS(WSG_F_BITS16("flags",                                          \
                            WSG_NAMES("powered", "data", "fault", "contact",  \
                                      "uart", "spi", "overrun")))
#define WSG_FINGER_POWER                                                      \
    WSG_FIELDS(WSG_F_ENUM8("power", WSG_NAMES("off", "on")))

/*
 * The commands of the 2.2.0 command set plus Get Temperature (46h) and the
 * finger commands of later firmware (60h..63h, 70h..73h), in ID
 * order: X(ID, SYMBOL, HANDLER, NAME, MIN_LEN, MAX_LEN, FLAGS, REQUEST,
 * REPLY). SYMBOL makes WSG_CMD_<SYMBOL>; HANDLER names the emulator's
 * handler, wsg_cmd_<HANDLER> in src/cmd/commands.c; NAME is what logs and
 * tools call the command. A request passes the length rules with MIN_LEN
 * to MAX_LEN payload bytes, or none with WSG_CMDF_EMPTY_OK. REPLY is what
 * follows the status of an E_SUCCESS answer.
 */
#define WSG_SCHEMA_COMMANDS(X)                                                \
    X(0x06, LOOP, loop, "Loop", 0, WSG_PAYLOAD_MAX, 0,                        \
      WSG_FIELDS(WSG_F_BYTES("data", WSG_PAYLOAD_MAX)),                       \
      WSG_FIELDS(WSG_F_BYTES("data", WSG_PAYLOAD_MAX)))                       \
    X(0x07, DISCONNECT, disconnect, "Disconnect", 0, 0, WSG_CMDF_NO_PARAM,    \
      WSG_NONE, WSG_NONE)                                                     \
    X(0x20, HOMING, homing, "Homing", 1, 1, WSG_CMDF_MOVE,                    \
      WSG_FIELDS(WSG_F_ENUM8("direction",                                     \
                             WSG_NAMES("default", "positive", "negative"))),  \
      WSG_NONE)                                                               \
    X(0x21, PREPOSITION, preposition, "Preposition", 9, 9,                    \
      WSG_CMDF_MOVE | WSG_CMDF_HOMED,                                         \
      WSG_FIELDS(                                                             \
          WSG_F_BITS8("flags", WSG_NAMES("relative", "stop-on-block")),       \
          WSG_F_F32("width", "mm"), WSG_F_F32("speed", "mm/s")),              \
      WSG_NONE)                                                               \
    X(0x22, STOP, stop, "Stop", 0, 0, WSG_CMDF_NO_PARAM, WSG_NONE, WSG_NONE)  \
    /* An emergency stop is never refused for its payload. */                 \
    X(0x23, FAST_STOP, fast_stop, "FastStop", 0, WSG_PAYLOAD_MAX, 0,          \
      WSG_NONE, WSG_NONE)                                                     \
    X(0x24, ACK_FAST_STOP, ack, "AckFastStop", 3, 3, 0,                       \
      WSG_FIELDS(WSG_F_TEXT("key", 3)), WSG_NONE)                             \
    X(0x25, GRASP, grasp, "Grasp", 8, 8, WSG_CMDF_MOVE | WSG_CMDF_HOMED,      \
      WSG_FIELDS(WSG_F_F32("width", "mm"), WSG_F_F32("speed", "mm/s")),       \
      WSG_NONE)                                                               \
    X(0x26, RELEASE, release, "Release", 8, 8,                                \
      WSG_CMDF_MOVE | WSG_CMDF_HOMED,                                         \
      WSG_FIELDS(WSG_F_F32("width", "mm"), WSG_F_F32("speed", "mm/s")),       \
      WSG_NONE)                                                               \
    X(0x30, SET_ACCELERATION, set_acc, "SetAcceleration", 4, 4, 0,            \
      WSG_FIELDS(WSG_F_F32("acceleration", "mm/s2")), WSG_NONE)               \
    X(0x31, GET_ACCELERATION, get_acc, "GetAcceleration", 0, 0,               \
      WSG_CMDF_NO_PARAM, WSG_NONE,                                            \
      WSG_FIELDS(WSG_F_F32("acceleration", "mm/s2")))                         \
    X(0x32, SET_FORCE_LIMIT, set_force, "SetForceLimit", 4, 4, 0,             \
      WSG_FIELDS(WSG_F_F32("force-limit", "N")), WSG_NONE)                    \
    X(0x33, GET_FORCE_LIMIT, get_force_limit, "GetForceLimit", 0, 0,          \
      WSG_CMDF_NO_PARAM, WSG_NONE, WSG_FIELDS(WSG_F_F32("force-limit", "N"))) \
    X(0x34, SET_SOFT_LIMITS, set_soft_limits, "SetSoftLimits", 8, 8, 0,       \
      WSG_FIELDS(WSG_F_F32("limit-minus", "mm"),                              \
                 WSG_F_F32("limit-plus", "mm")),                              \
      WSG_NONE)                                                               \
    X(0x35, GET_SOFT_LIMITS, get_soft_limits, "GetSoftLimits", 0, 0,          \
      WSG_CMDF_NO_PARAM, WSG_NONE,                                            \
      WSG_FIELDS(WSG_F_F32("limit-minus", "mm"),                              \
                 WSG_F_F32("limit-plus", "mm")))                              \
    X(0x36, CLEAR_SOFT_LIMITS, clear_soft_limits, "ClearSoftLimits", 0, 0,    \
      WSG_CMDF_NO_PARAM, WSG_NONE, WSG_NONE)                                  \
    X(0x37, OVERDRIVE, overdrive, "OverdriveMode", 1, 1, 0,                   \
      WSG_FIELDS(WSG_F_ENUM8("overdrive", WSG_NAMES("off", "on"))), WSG_NONE) \
    X(0x38, TARE, tare, "TareForceSensor", 0, 0, WSG_CMDF_NO_PARAM, WSG_NONE, \
      WSG_NONE)                                                               \
    X(0x40, GET_SYSTEM_STATE, stream, "GetSystemState", 3, 3,                 \
      WSG_CMDF_EMPTY_OK | WSG_CMDF_STREAM, WSG_STREAM_REQUEST,                \
      WSG_FIELDS(WSG_FIELD_("flags", WSG_FT_BITS32, "",                       \
                            .names = wsg_system_flag_names, .nnames = 32)))   \
    X(0x41, GET_GRASP_STATE, stream, "GetGraspingState", 3, 3,                \
      WSG_CMDF_EMPTY_OK | WSG_CMDF_STREAM, WSG_STREAM_REQUEST,                \
      WSG_FIELDS(WSG_FIELD_("grasp-state", WSG_FT_ENUM8, "",                  \
                            .names = wsg_grasp_state_names,                   \
                            .nnames = WSG_GS_COUNT)))                         \
    X(0x42, GET_GRASP_STATS, grasp_stats, "GetGraspingStatistics", 1, 1,      \
      WSG_CMDF_EMPTY_OK,                                                      \
      WSG_FIELDS(WSG_F_BITS8("flags", WSG_NAMES("reset"))),                   \
      WSG_FIELDS(WSG_F_U32("total"), WSG_F_U16("no-part", ""),                \
                 WSG_F_U16("lost-part", "")))                                 \
    X(0x43, GET_WIDTH, stream, "GetOpeningWidth", 3, 3,                       \
      WSG_CMDF_EMPTY_OK | WSG_CMDF_STREAM, WSG_STREAM_REQUEST,                \
      WSG_FIELDS(WSG_F_F32("width", "mm")))                                   \
    X(0x44, GET_SPEED, stream, "GetSpeed", 3, 3,                              \
      WSG_CMDF_EMPTY_OK | WSG_CMDF_STREAM, WSG_STREAM_REQUEST,                \
      WSG_FIELDS(WSG_F_F32("speed", "mm/s")))                                 \
    X(0x45, GET_FORCE, stream, "GetForce", 3, 3,                              \
      WSG_CMDF_EMPTY_OK | WSG_CMDF_STREAM, WSG_STREAM_REQUEST,                \
      WSG_FIELDS(WSG_F_F32("force", "N")))                                    \
    X(0x46, GET_TEMPERATURE, temperature, "GetTemperature", 0, 0,             \
      WSG_CMDF_NO_PARAM, WSG_NONE,                                            \
      WSG_FIELDS(WSG_F_TENTHS("temperature", "degC")))                        \
    X(0x50, GET_SYSTEM_INFO, system_info, "GetSystemInformation", 0, 0,       \
      WSG_CMDF_NO_PARAM, WSG_NONE,                                            \
      WSG_FIELDS(WSG_F_ENUM8("type",                                          \
                             WSG_NAMES("unknown", "WSG 50", "WSG 32",         \
                                       "KMS 40", "WTS", "WSG 25", "WSG 70")), \
                 WSG_F_U8("hwrev"), WSG_F_VERSION("swrev"),                   \
                 WSG_F_U32("serial")))                                        \
    /* Longer than 64 characters is E_OVERRUN, not a format error;            \
     * trailing NULs do not count, so the whole payload range is the          \
     * handler's. */                                                          \
    X(0x51, SET_DEVICE_TAG, set_tag, "SetDeviceTag", 0, WSG_PAYLOAD_MAX, 0,   \
      WSG_FIELDS(WSG_F_TEXT("tag", WSG_PAYLOAD_MAX)), WSG_NONE)               \
    X(0x52, GET_DEVICE_TAG, get_tag, "GetDeviceTag", 0, 0, WSG_CMDF_NO_PARAM, \
      WSG_NONE, WSG_FIELDS(WSG_F_TEXT("tag", WSG_TAG_MAX)))                   \
    X(0x53, GET_SYSTEM_LIMITS, system_limits, "GetSystemLimits", 0, 0,        \
      WSG_CMDF_NO_PARAM, WSG_NONE,                                            \
      WSG_FIELDS(WSG_F_F32("stroke", "mm"), WSG_F_F32("min-speed", "mm/s"),   \
                 WSG_F_F32("max-speed", "mm/s"),                              \
                 WSG_F_F32("min-acc", "mm/s2"),                               \
                 WSG_F_F32("max-acc", "mm/s2"), WSG_F_F32("min-force", "N"),  \
                 WSG_F_F32("nom-force", "N"), WSG_F_F32("ovr-force", "N")))   \
    /* Two addressing styles share 60h..63h: nothing (4.x, finger 1) or       \
     * the finger index first (older clients); 62h takes on/off after         \
     * it, so one byte is 4.x's on/off and two are index and on/off. */       \
    X(0x60, GET_FINGER1_INFO, finger_info, "GetFinger1Info", 1, 1,            \
      WSG_CMDF_EMPTY_OK, WSG_FINGER_INDEX, WSG_FINGER_INFO)                   \
    X(0x61, GET_FINGER1_FLAGS, finger_flags, "GetFinger1Flags", 1, 1,         \
      WSG_CMDF_EMPTY_OK, WSG_FINGER_INDEX, WSG_FINGER_FLAGS)                  \
    X(0x62, FINGER1_POWER, finger_power, "Finger1PowerControl", 1, 2, 0,      \
      WSG_FINGER_POWER, WSG_NONE)                                             \
    X(0x63, GET_FINGER1_DATA, finger_data, "GetFinger1Data", 1, 1,            \
      WSG_CMDF_EMPTY_OK, WSG_FINGER_INDEX,                                    \
      WSG_FIELDS(WSG_F_BYTES("data", WSG_PAYLOAD_MAX)))                       \
    X(0x70, GET_FINGER2_INFO, finger_info, "GetFinger2Info", 0, 0,            \
      WSG_CMDF_NO_PARAM, WSG_NONE, WSG_FINGER_INFO)                           \
    X(0x71, GET_FINGER2_FLAGS, finger_flags, "GetFinger2Flags", 0, 0,         \
      WSG_CMDF_NO_PARAM, WSG_NONE, WSG_FINGER_FLAGS)                          \
    X(0x72, FINGER2_POWER, finger_power, "Finger2PowerControl", 1, 1, 0,      \
      WSG_FINGER_POWER, WSG_NONE)                                             \
    X(0x73, GET_FINGER2_DATA, finger_data, "GetFinger2Data", 0, 0,            \
      WSG_CMDF_NO_PARAM, WSG_NONE,                                            \
      WSG_FIELDS(WSG_F_BYTES("data", WSG_PAYLOAD_MAX)))

/* The C names the lists make: WSG_E_SUCCESS, WSG_SF_REFERENCED (a mask),
 * WSG_GS_HOLDING, WSG_CMD_GET_WIDTH. */
#define WSG_SCHEMA_STATUS_ENUM_(v, name) WSG_##name = (v),
enum wsg_status { WSG_SCHEMA_STATUSES(WSG_SCHEMA_STATUS_ENUM_) };
#define WSG_SCHEMA_SF_ENUM_(bit, name) WSG_##name = 1 << (bit),
enum wsg_system_flag { WSG_SCHEMA_SYSTEM_FLAGS(WSG_SCHEMA_SF_ENUM_) };
#define WSG_SCHEMA_GS_ENUM_(v, name) WSG_GS_##name = (v),
enum wsg_grasp_state { WSG_SCHEMA_GRASP_STATES(WSG_SCHEMA_GS_ENUM_) };
/* How many grasping states have a name: a constant apart from the enum,
 * so a switch over the states need not list it. */
#define WSG_SCHEMA_COUNT_(v, name) +1
enum { WSG_GS_COUNT = 0 WSG_SCHEMA_GRASP_STATES(WSG_SCHEMA_COUNT_) };
#define WSG_SCHEMA_CMD_ENUM_(id, sym, ...) WSG_CMD_##sym = (id),
enum wsg_cmd_id { WSG_SCHEMA_COMMANDS(WSG_SCHEMA_CMD_ENUM_) };

/* Every flag Appendix B defines. */
#define WSG_SCHEMA_SF_OR_(bit, name) | (1u << (bit))
#define WSG_SF_ALL                   (0u WSG_SCHEMA_SYSTEM_FLAGS(WSG_SCHEMA_SF_OR_))

/* One command as wsg_schema[] holds it. */
struct wsg_cmd_schema {
    const char *name;   /* "GetOpeningWidth"; NULL: no command has this ID */
    const char *symbol; /* "GET_WIDTH" */
    uint16_t min_len, max_len;
    uint8_t flags; /* WSG_CMDF_* */
    struct wsg_layout request, reply;
};

/* Indexed by command ID. */
extern const struct wsg_cmd_schema wsg_schema[256];
/* By bit (32 entries, NULL where reserved) and by value (WSG_GS_COUNT). */
extern const char *const wsg_system_flag_names[32];
extern const char *const wsg_grasp_state_names[WSG_GS_COUNT];

/* "E_SUCCESS", ...; "E_UNKNOWN" for values outside Appendix A. */
const char *wsg_status_name(unsigned status);
/* The name of an ID ("GetOpeningWidth"), or NULL for an unknown one. */
const char *wsg_cmd_name(uint8_t id);
/* A request of this ID with len payload bytes passes the length rules
 * (1 or 0); an unknown ID fits nothing. */
int wsg_cmd_request_fits(uint8_t id, size_t len);
/* The length rules themselves, for the dispatcher's own copy of them. */
static inline int wsg_schema_len_ok(uint16_t min_len, uint16_t max_len,
                                    uint8_t flags, size_t len)
{
    return (len >= min_len && len <= max_len) ||
           (len == 0 && (flags & WSG_CMDF_EMPTY_OK));
}

/* The control channel's spelling of a schema name: lower case, '_' for
 * '-', without the "SF_" of a flag ("SF_FORCECNTL_MODE" is
 * "forcecntl_mode", "no-part" is "no_part"). Cut to fit cap. */
void wsg_schema_key(const char *name, char *buf, size_t cap);

/* One field's value, taken off the wire by wsg_layout_decode. */
struct wsg_value {
    const struct wsg_field *field;
    uint32_t raw;        /* the bytes as an integer (F32: its bits) */
    double num;          /* numbers in their unit (F32, I16_TENTHS, ints) */
    const uint8_t *data; /* TEXT, BYTES: into the payload */
    size_t len;
};

/* The type's name as the generated tables spell it ("u8", "bits16",
 * "i16_tenths"), or NULL for a number that is no type. */
const char *wsg_field_type_name(unsigned type);
/* Bytes of the fields before a TEXT or BYTES one: the whole size of a
 * layout without one. */
size_t wsg_layout_size(const struct wsg_layout *l);
/* n bytes are a whole payload of this layout (1 or 0). */
int wsg_layout_fits(const struct wsg_layout *l, size_t n);
/* Take the fields of a payload apart into out[WSG_FIELDS_MAX]: their
 * count, or -1 if n bytes are not a payload of this layout. */
int wsg_layout_decode(const struct wsg_layout *l, const uint8_t *p, size_t n,
                      struct wsg_value *out);
/* Put numbers (in their fields' units, one per field; TEXT and BYTES are
 * left empty) on the wire as this layout; returns the bytes written to
 * out, which holds wsg_layout_size. */
size_t wsg_layout_encode(const struct wsg_layout *l, const double *num,
                         uint8_t *out);

/* How wsg_value_format writes a value. */
struct wsg_value_style {
    int decimals; /* of an F32 */
    /* Around the names of an ENUM8 or BITS value and between them:
     * "(", "|", ")" makes "0x03(relative|stop-on-block)". */
    const char *open, *sep, *close;
    int bare;       /* the value alone: no names, text unquoted */
    size_t max_hex; /* BYTES shown at most (0: all), then "...(N bytes)" */
};
/* The value as text into buf (always terminated); returns its length. A
 * set bit without a name is "D<bit>"; a value without one, the number
 * alone. Text is quoted and anything but printable ASCII other than '"'
 * written as \xNN, unless bare. */
size_t wsg_value_format(const struct wsg_value *v,
                        const struct wsg_value_style *st, char *buf,
                        size_t cap);

#endif
