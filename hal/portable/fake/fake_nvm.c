/* SPDX-License-Identifier: Apache-2.0 */
/* Fake port: RAM-backed NVM with flash semantics (erase to 0xFF, program only
 * over erased bytes, aligned to the program size), a power-cut injector that
 * can leave the interrupted operation partly applied, and optional ECC: a
 * program unit left half-written reads as corrupt until erased. */
#include "fake_internal.h"

#include "pma/hal_nvm_check.h"

#include <string.h>

static struct {
    uint8_t *mem;                /* the test's buffer; NULL: not attached */
    pma_nvm_geometry_t g;
    uint32_t ops;                /* program + erase operations since attach */
    bool cut_armed;
    uint32_t ops_before_cut;
    uint32_t applied_permille;
    bool power_lost;
    bool stuck;
    uint32_t stuck_block, stuck_offset;
    bool ecc;
    uint32_t corrupt_reads;
    uint32_t torn_count;
    struct {
        uint32_t block, unit;    /* unit: offset / program_size */
    } torn[PMA_FAKE_NVM_TORN_MAX];
} nvm;

void pma_fake_nvm_reset_(pma_fake_reset_depth_t depth)
{
    if (depth < PMA_FAKE_RESET_RESTART) return;
    nvm.power_lost = false;
    nvm.cut_armed = false;
    if (depth < PMA_FAKE_RESET_ALL) return;
    memset(&nvm, 0, sizeof nvm);
}

int pma_fake_nvm_attach(uint8_t *mem, size_t mem_size, const pma_nvm_geometry_t *g)
{
    if (mem == NULL || g == NULL) return PMA_ERR_NULL;
    if (g->block_size == 0 || g->block_count == 0 || g->program_size == 0) return PMA_ERR_RANGE;
    if (g->block_size % g->program_size != 0) return PMA_ERR_RANGE;
    if ((uint64_t)g->block_size * g->block_count > mem_size) return PMA_ERR_RANGE;
    memset(&nvm, 0, sizeof nvm);
    nvm.mem = mem;
    nvm.g = *g;
    memset(mem, 0xFF, (size_t)g->block_size * g->block_count);
    return PMA_OK;
}

void pma_fake_nvm_cut_power(uint32_t ops_before_cut, uint32_t applied_permille)
{
    nvm.cut_armed = true;
    nvm.ops_before_cut = ops_before_cut;
    nvm.applied_permille = applied_permille > 1000u ? 1000u : applied_permille;
}

bool pma_fake_nvm_power_lost(void)
{
    return nvm.power_lost;
}

uint32_t pma_fake_nvm_op_count(void)
{
    return nvm.ops;
}

void pma_fake_nvm_stuck_byte(uint32_t block, uint32_t offset, bool stuck)
{
    nvm.stuck = stuck;
    nvm.stuck_block = block;
    nvm.stuck_offset = offset;
}

void pma_fake_nvm_ecc(bool on)
{
    nvm.ecc = on;
}

uint32_t pma_fake_nvm_corrupt_reads(void)
{
    return nvm.corrupt_reads;
}

/* --- ECC: units whose program or erase was cut half-way through a unit --- */

static bool torn_in(uint32_t block, uint32_t offset, uint32_t len)
{
    if (!nvm.ecc || len == 0) return false;
    const uint32_t first = offset / nvm.g.program_size;
    const uint32_t last = (offset + len - 1u) / nvm.g.program_size;
    for (uint32_t i = 0; i < nvm.torn_count; ++i) {
        if (nvm.torn[i].block == block && nvm.torn[i].unit >= first && nvm.torn[i].unit <= last) {
            return true;
        }
    }
    return false;
}

/* Erasing units [0, units) of a block clears their ECC errors. */
static void torn_clear(uint32_t block, uint32_t units)
{
    uint32_t kept = 0;
    for (uint32_t i = 0; i < nvm.torn_count; ++i) {
        if (nvm.torn[i].block != block || nvm.torn[i].unit >= units) nvm.torn[kept++] = nvm.torn[i];
    }
    nvm.torn_count = kept;
}

/* An operation at offset stopped after `applied` bytes: the unit it stopped
 * in holds a mix of old and new bits and an ECC code that fits neither. */
static void torn_mark(uint32_t block, uint32_t offset, uint32_t applied)
{
    if (!nvm.ecc || applied % nvm.g.program_size == 0) return;
    const uint32_t unit = (offset + applied) / nvm.g.program_size;
    if (torn_in(block, unit * nvm.g.program_size, 1)) return;
    if (nvm.torn_count == PMA_FAKE_NVM_TORN_MAX) nvm.torn_count--; /* forget the newest */
    nvm.torn[nvm.torn_count].block = block;
    nvm.torn[nvm.torn_count].unit = unit;
    nvm.torn_count++;
}

/* Common checks of read, program and erase. */
static int usable(void)
{
    if (!pma_fake_initialised() || nvm.mem == NULL) return PMA_ERR_NOT_READY;
    if (nvm.power_lost) return PMA_ERR_IO;
    return PMA_OK;
}

static uint8_t *at(uint32_t block, uint32_t offset)
{
    return nvm.mem + (size_t)block * nvm.g.block_size + offset;
}

/* Counts one program/erase operation; returns how many of its `len` bytes
 * take effect: all of them, or a prefix when power is cut during it. */
static uint32_t operation(uint32_t len)
{
    nvm.ops++;
    if (!nvm.cut_armed) return len;
    if (nvm.ops_before_cut > 0) {
        nvm.ops_before_cut--;
        return len;
    }
    nvm.cut_armed = false;
    nvm.power_lost = true;
    return (uint32_t)((uint64_t)len * nvm.applied_permille / 1000u);
}

int pma_hal_nvm_geometry(pma_nvm_geometry_t *geometry)
{
    if (geometry == NULL) return PMA_ERR_NULL;
    if (!pma_fake_initialised() || nvm.mem == NULL) return PMA_ERR_NOT_READY;
    *geometry = nvm.g;
    return PMA_OK;
}

int pma_hal_nvm_read(uint32_t block, uint32_t offset, void *buf, uint32_t len)
{
    if (buf == NULL) return PMA_ERR_NULL;
    int rc = usable();
    if (rc == PMA_OK) rc = pma_nvm_check_range(&nvm.g, block, offset, len);
    if (rc != PMA_OK) return rc;
    if (torn_in(block, offset, len)) {
        nvm.corrupt_reads++;
        return PMA_ERR_CORRUPT;
    }
    memcpy(buf, at(block, offset), len);
    return PMA_OK;
}

int pma_hal_nvm_program(uint32_t block, uint32_t offset, const void *data, uint32_t len)
{
    if (data == NULL) return PMA_ERR_NULL;
    int rc = usable();
    if (rc == PMA_OK) rc = pma_nvm_check_program(&nvm.g, block, offset, len);
    if (rc != PMA_OK) return rc;
    uint8_t *dst = at(block, offset);
    for (uint32_t i = 0; i < len; ++i) {
        if (dst[i] != 0xFFu) return PMA_ERR_NOT_ERASED;
    }
    if (torn_in(block, offset, len)) return PMA_ERR_NOT_ERASED; /* its bits are undefined */
    if (len == 0) return PMA_OK;
    const uint8_t *src = data;
    const uint32_t applied = operation(len);
    for (uint32_t i = 0; i < applied; ++i) {
        const bool worn = nvm.stuck && block == nvm.stuck_block && offset + i == nvm.stuck_offset;
        if (!worn) dst[i] &= src[i]; /* flash: a program only clears bits */
    }
    if (applied < len) torn_mark(block, offset, applied);
    return nvm.power_lost ? PMA_ERR_IO : PMA_OK;
}

int pma_hal_nvm_erase(uint32_t block)
{
    int rc = usable();
    if (rc == PMA_OK) rc = pma_nvm_check_range(&nvm.g, block, 0, 0);
    if (rc != PMA_OK) return rc;
    const uint32_t applied = operation(nvm.g.block_size);
    memset(at(block, 0), 0xFF, applied);
    torn_clear(block, applied / nvm.g.program_size);
    if (applied < nvm.g.block_size) torn_mark(block, 0, applied);
    return nvm.power_lost ? PMA_ERR_IO : PMA_OK;
}
