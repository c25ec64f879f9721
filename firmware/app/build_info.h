/* SPDX-License-Identifier: Apache-2.0 */
/* The firmware's identity, stamped at build time (cmake/PmaBuildInfo.cmake writes the one
 * definition, pma_build_info.c, into the build tree): what DEVICE_INFO reports. */
#ifndef PMA_BUILD_INFO_H
#define PMA_BUILD_INFO_H

#include <stdint.h>

#define PMA_BUILD_FLAG_DIRTY          0x01u /* built from a tree with uncommitted changes */
#define PMA_BUILD_FLAG_COMMIT_UNKNOWN 0x02u /* not built from a git checkout: fw_commit 0 */

typedef struct pma_build_info {
    uint8_t fw_major, fw_minor, fw_patch; /* the VERSION file */
    uint8_t build_target;                 /* DEVICE_INFO BuildTarget (the DBC's VAL_ table) */
    uint8_t build_flags;                  /* PMA_BUILD_FLAG_* */
    uint32_t fw_commit;                   /* first 8 hex digits of the git commit, or 0 */
} pma_build_info_t;

extern const pma_build_info_t pma_build_info;

#endif /* PMA_BUILD_INFO_H */
