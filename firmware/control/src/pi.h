/* SPDX-License-Identifier: Apache-2.0 */
/* pi, once, for the control library's sources, and the forms of it they use.
 * The digits are those every source used before (the golden vectors hold them
 * to the last bit); the float forms round the double ones, and the fixed-point
 * ones round them to their Q format, both at compile time. */
#ifndef PMA_PI_H
#define PMA_PI_H

#include <stdint.h>

#define PMA_PI 3.14159265358979                        /* double */
#define PMA_HALF_PI_F ((float)(PMA_PI / 2.0))
#define PMA_TWO_PI_F ((float)(2.0 * PMA_PI))
/* pi/2 in Q2.30 (1686629713) */
#define PMA_HALF_PI_Q30 ((int32_t)(PMA_PI / 2.0 * 1073741824.0 + 0.5))
/* 2 pi / 55 in Q16.16 (7487): Case 3's chirp */
#define PMA_TWO_PI_55_Q16 ((int64_t)(2.0 * PMA_PI / 55.0 * 65536.0 + 0.5))

#endif /* PMA_PI_H */
