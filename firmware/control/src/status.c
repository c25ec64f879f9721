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
    default: return "PMA_ERR_UNKNOWN";
    }
}
