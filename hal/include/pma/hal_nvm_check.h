/* SPDX-License-Identifier: Apache-2.0 */
/* The NVM access rules of pma/hal.h in one place, for the ports that keep their
 * geometry in a pma_nvm_geometry_t (the fake, the Linux port): a range lies
 * inside one block; a program is also aligned to program_size in offset and
 * length. Each returns PMA_OK or PMA_ERR_RANGE (the ports' NVM functions return
 * that as it is). Pure and overflow-safe: offset + len is never computed. */
#ifndef PMA_HAL_NVM_CHECK_H
#define PMA_HAL_NVM_CHECK_H

#include <stdint.h>

#include "pma/hal.h"

static inline int pma_nvm_check_range(const pma_nvm_geometry_t *g, uint32_t block, uint32_t offset,
                                      uint32_t len)
{
    if (block >= g->block_count) return PMA_ERR_RANGE;
    if (offset > g->block_size || len > g->block_size - offset) return PMA_ERR_RANGE;
    return PMA_OK;
}

static inline int pma_nvm_check_program(const pma_nvm_geometry_t *g, uint32_t block, uint32_t offset,
                                        uint32_t len)
{
    const int rc = pma_nvm_check_range(g, block, offset, len);
    if (rc != PMA_OK) return rc;
    if (g->program_size == 0 || offset % g->program_size != 0 || len % g->program_size != 0) {
        return PMA_ERR_RANGE;
    }
    return PMA_OK;
}

#endif /* PMA_HAL_NVM_CHECK_H */
