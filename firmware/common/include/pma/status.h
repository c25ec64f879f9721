/* SPDX-License-Identifier: Apache-2.0 */
/* Error codes shared by every firmware module: one enum of negative codes
 * (0 is success), in the manner of littlefs' enum lfs_error. New modules
 * append codes; existing values never change (they travel in CAN replies). */
#ifndef PMA_STATUS_H
#define PMA_STATUS_H

typedef enum pma_status {
    PMA_OK = 0,
    PMA_ERR_NULL = -1,         /* a required pointer argument was NULL */
    PMA_ERR_NOT_FINITE = -2,   /* NaN or infinity where a finite number is needed */
    PMA_ERR_RANGE = -3,        /* value outside its documented range (e.g. <= 0 where > 0 is needed) */
    PMA_ERR_BAND = -4,         /* accuracy bounds do not fit the constraint band (eq. 14) */
    PMA_ERR_NOT_READY = -5,    /* instance not (successfully) initialised */
    PMA_ERR_UNSUPPORTED = -6,  /* valid value of a feature this variant does not provide */
    PMA_ERR_FIXED_RANGE = -7,  /* value not representable in the fixed-point format used */
    /* HAL (hal/include/pma/hal.h) and parameter storage (firmware/storage/pstore.h) */
    PMA_ERR_NOT_IMPLEMENTED = -8, /* the HAL port does not implement this function (template) */
    PMA_ERR_EMPTY = -9,        /* nothing to receive / read: queue or log empty */
    PMA_ERR_FULL = -10,        /* queue full (e.g. CAN TX): nothing was queued */
    PMA_ERR_BUS_OFF = -11,     /* CAN controller is bus-off: nothing sent until recovered */
    PMA_ERR_IO = -12,          /* device I/O failure (hardware error, device unpowered) */
    PMA_ERR_NOT_ERASED = -13,  /* NVM program over an area that is not erased */
    PMA_ERR_WIRE_BREAK = -14,  /* sensor output at its wire-break level (broken wire, no power) */
    PMA_ERR_NO_RECORD = -15,   /* storage holds no valid record: use defaults */
    PMA_ERR_VERIFY = -16,      /* read-back after a write differs from what was written */
    PMA_ERR_CORRUPT = -17,     /* stored data failed the device's integrity check (flash ECC) */
    /* Application and CAN protocol (firmware/app) */
    PMA_ERR_UNKNOWN_ID = -18,  /* no parameter with this id */
    PMA_ERR_TYPE = -19,        /* value of the wrong type for this parameter */
    PMA_ERR_STATE = -20,       /* not allowed in the current state (e.g. safety limits while RUNNING) */
    PMA_ERR_UNKNOWN_COMMAND = -21, /* command, operation or selector value not defined */
    PMA_ERR_LENGTH = -22,      /* CAN frame with the wrong data length for its message */
    PMA_ERR_FAULT = -23,       /* refused because a fault is latched (clear faults first) */
} pma_status_t;

/* Short constant name of a status code, e.g. "PMA_ERR_RANGE" (never NULL). */
const char *pma_status_name(int status);

#endif /* PMA_STATUS_H */
