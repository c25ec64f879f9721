/* SPDX-License-Identifier: Apache-2.0 */
/* Shared set-up of the parameter storage tests: a small fake NVM (64-byte
 * blocks, 8-byte program size, like a scaled-down STM32G4 page), slots of 9
 * blocks from block 1 (room for a 512-byte blob), one blob buffer, blob
 * contents derived from a seed so no second buffer is needed (16 KB of RAM on
 * the Cortex-M0), and a record encoder written from the documented format. */
#ifndef PMA_PSTORE_TEST_H
#define PMA_PSTORE_TEST_H

#include "pma/status.h"
#include "pma_test.h"

#include <stdbool.h>
#include <string.h>

#include "crc32.h"
#include "pma/hal.h"
#include "pma_hal_fake.h"
#include "pstore.h"

#define T_BLOCK 64u
#define T_PROG 8u
#define T_FIRST 1u                   /* block 0 belongs to someone else */
#define T_BPS 9u                     /* blocks per slot: 576 bytes >= 16 + 512 + 4 */
#define T_BLOCKS (T_FIRST + 2u * T_BPS + 1u) /* and one more after slot B */

static uint8_t nvm_mem[T_BLOCK * T_BLOCKS];
static uint8_t blob[PMA_PSTORE_MAX_BLOB_BYTES];

static inline uint8_t *slot_mem(unsigned slot)
{
    return nvm_mem + (T_FIRST + slot * T_BPS) * T_BLOCK;
}

static inline uint8_t pattern_byte(uint32_t seed, size_t i)
{
    const uint32_t x = (seed * 2654435761u) ^ (uint32_t)(i * 40503u);
    return (uint8_t)(x ^ (x >> 11) ^ (x >> 23));
}

static inline void fill_blob(uint32_t seed, size_t len)
{
    for (size_t i = 0; i < len; ++i) blob[i] = pattern_byte(seed, i);
}

static inline bool blob_is(uint32_t seed, size_t len)
{
    for (size_t i = 0; i < len; ++i) {
        if (blob[i] != pattern_byte(seed, i)) return false;
    }
    return true;
}

/* Fresh devices: fake reset, HAL up, NVM erased; then the store. */
static inline void fresh(pma_pstore_t *ps)
{
    pma_fake_reset();
    assert_status(pma_hal_init(NULL), PMA_OK);
    const pma_nvm_geometry_t g = {.block_size = T_BLOCK, .block_count = T_BLOCKS,
                                  .program_size = T_PROG};
    assert_status(pma_fake_nvm_attach(nvm_mem, sizeof nvm_mem, &g), PMA_OK);
    assert_status(pma_pstore_init(ps, T_FIRST, T_BPS), PMA_OK);
}

/* After a power cut: power on, the firmware starts again. */
static inline void power_on(pma_pstore_t *ps)
{
    pma_fake_power_on();
    assert_status(pma_hal_init(NULL), PMA_OK);
    assert_status(pma_pstore_init(ps, T_FIRST, T_BPS), PMA_OK);
}

static inline void save_seed(const pma_pstore_t *ps, uint32_t seed, size_t len)
{
    fill_blob(seed, len);
    assert_status(pma_pstore_save(ps, blob, len, (uint16_t)seed), PMA_OK);
}

static inline void put32(uint8_t *p, uint32_t v)
{
    for (int i = 0; i < 4; ++i) p[i] = (uint8_t)(v >> (8 * i));
}

/* Writes a record straight into the fake's memory (slot erased first), as
 * the documented layout says; the tests then break fields of it on purpose. */
static inline void craft_record(unsigned slot, uint32_t seq, uint32_t seed, uint32_t len)
{
    uint8_t *p = slot_mem(slot);
    memset(p, 0xFF, T_BPS * T_BLOCK);
    put32(p, PMA_PSTORE_MAGIC);
    p[4] = (uint8_t)PMA_PSTORE_FORMAT_VERSION;
    p[5] = 0;
    p[6] = (uint8_t)seed;
    p[7] = (uint8_t)(seed >> 8);
    put32(p + 8, seq);
    put32(p + 12, len);
    for (uint32_t i = 0; i < len; ++i) p[16 + i] = pattern_byte(seed, i);
    put32(p + 16 + len, pma_crc32(p, 16 + len));
}

#endif /* PMA_PSTORE_TEST_H */
