/* SPDX-License-Identifier: Apache-2.0 */
#include "pma/status.h"

#include <stddef.h>

const char *pma_status_name(int status)
{
    switch (status) {
    case PMA_OK: return "PMA_OK";
    case PMA_ERR_NULL: return "PMA_ERR_NULL";
    case PMA_ERR_NOT_FINITE: return "PMA_ERR_NOT_FINITE";
    case PMA_ERR_RANGE: return "PMA_ERR_RANGE";
    case PMA_ERR_BAND: return "PMA_ERR_BAND";
    case PMA_ERR_NOT_READY: return "PMA_ERR_NOT_READY";
    case PMA_ERR_UNSUPPORTED: return "PMA_ERR_UNSUPPORTED";
    case PMA_ERR_FIXED_RANGE: return "PMA_ERR_FIXED_RANGE";
    case PMA_ERR_NOT_IMPLEMENTED: return "PMA_ERR_NOT_IMPLEMENTED";
    case PMA_ERR_EMPTY: return "PMA_ERR_EMPTY";
    case PMA_ERR_FULL: return "PMA_ERR_FULL";
    case PMA_ERR_BUS_OFF: return "PMA_ERR_BUS_OFF";
    case PMA_ERR_IO: return "PMA_ERR_IO";
    case PMA_ERR_NOT_ERASED: return "PMA_ERR_NOT_ERASED";
    case PMA_ERR_WIRE_BREAK: return "PMA_ERR_WIRE_BREAK";
    case PMA_ERR_NO_RECORD: return "PMA_ERR_NO_RECORD";
    case PMA_ERR_VERIFY: return "PMA_ERR_VERIFY";
    case PMA_ERR_CORRUPT: return "PMA_ERR_CORRUPT";
    case PMA_ERR_UNKNOWN_ID: return "PMA_ERR_UNKNOWN_ID";
    case PMA_ERR_TYPE: return "PMA_ERR_TYPE";
    case PMA_ERR_STATE: return "PMA_ERR_STATE";
    case PMA_ERR_UNKNOWN_COMMAND: return "PMA_ERR_UNKNOWN_COMMAND";
    case PMA_ERR_LENGTH: return "PMA_ERR_LENGTH";
    case PMA_ERR_FAULT: return "PMA_ERR_FAULT";
    default: return "PMA_ERR_UNKNOWN";
    }
}
