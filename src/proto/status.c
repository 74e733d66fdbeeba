/*
 * Names of the status codes of Appendix A, for logs, tools and tests.
 */
#include "wsg/proto.h"

static const char *const wsg_status_names[] = {
    [WSG_E_SUCCESS] = "E_SUCCESS",
    [WSG_E_NOT_AVAILABLE] = "E_NOT_AVAILABLE",
    [WSG_E_NO_SENSOR] = "E_NO_SENSOR",
    [WSG_E_NOT_INITIALIZED] = "E_NOT_INITIALIZED",
    [WSG_E_ALREADY_RUNNING] = "E_ALREADY_RUNNING",
    [WSG_E_FEATURE_NOT_SUPPORTED] = "E_FEATURE_NOT_SUPPORTED",
    [WSG_E_INCONSISTENT_DATA] = "E_INCONSISTENT_DATA",
    [WSG_E_TIMEOUT] = "E_TIMEOUT",
    [WSG_E_READ_ERROR] = "E_READ_ERROR",
    [WSG_E_WRITE_ERROR] = "E_WRITE_ERROR",
    [WSG_E_INSUFFICIENT_RESOURCES] = "E_INSUFFICIENT_RESOURCES",
    [WSG_E_CHECKSUM_ERROR] = "E_CHECKSUM_ERROR",
    [WSG_E_NO_PARAM_EXPECTED] = "E_NO_PARAM_EXPECTED",
    [WSG_E_NOT_ENOUGH_PARAMS] = "E_NOT_ENOUGH_PARAMS",
    [WSG_E_CMD_UNKNOWN] = "E_CMD_UNKNOWN",
    [WSG_E_CMD_FORMAT_ERROR] = "E_CMD_FORMAT_ERROR",
    [WSG_E_ACCESS_DENIED] = "E_ACCESS_DENIED",
    [WSG_E_ALREADY_OPEN] = "E_ALREADY_OPEN",
    [WSG_E_CMD_FAILED] = "E_CMD_FAILED",
    [WSG_E_CMD_ABORTED] = "E_CMD_ABORTED",
    [WSG_E_INVALID_HANDLE] = "E_INVALID_HANDLE",
    [WSG_E_NOT_FOUND] = "E_NOT_FOUND",
    [WSG_E_NOT_OPEN] = "E_NOT_OPEN",
    [WSG_E_IO_ERROR] = "E_IO_ERROR",
    [WSG_E_INVALID_PARAMETER] = "E_INVALID_PARAMETER",
    [WSG_E_INDEX_OUT_OF_BOUNDS] = "E_INDEX_OUT_OF_BOUNDS",
    [WSG_E_CMD_PENDING] = "E_CMD_PENDING",
    [WSG_E_OVERRUN] = "E_OVERRUN",
    [WSG_E_RANGE_ERROR] = "E_RANGE_ERROR",
    [WSG_E_AXIS_BLOCKED] = "E_AXIS_BLOCKED",
    [WSG_E_FILE_EXISTS] = "E_FILE_EXISTS",
};

const char *wsg_status_name(unsigned status)
{
    if (status >= sizeof wsg_status_names / sizeof wsg_status_names[0])
        return "E_UNKNOWN";
    return wsg_status_names[status];
}
