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
} pma_status_t;

/* Short constant name of a status code, e.g. "PMA_ERR_RANGE" (never NULL). */
const char *pma_status_name(int status);

#endif /* PMA_STATUS_H */
