/* SPDX-License-Identifier: Apache-2.0 */
/* Parameter storage in the last two flash pages (RM0440 section 3).
 *
 * Block 0 and 1 of pma/hal.h's NVM are pages 126 and 127: of bank 2 in the
 * default dual-bank mode (OPTR.DBANK = 1, 2 KB pages, 0x0807F000 and
 * 0x0807F800; bank 2 is written while the program runs from bank 1, so the
 * CPU does not stall), or of the single bank (4 KB pages, 0x0807E000 and
 * 0x0807F000). The linker script keeps the last 8 KB free for either.
 *
 * Program: one 64-bit double word at a time (8 ECC bits per double word);
 * a double word must be erased (all 0xFF) first, which is checked for the
 * whole range before anything is written (PMA_ERR_NOT_ERASED).
 * ECC: a read touching a double word with two bit errors (a program or
 * erase cut by a power loss) raises an NMI; the NMI handler calls
 * g4_flash_nmi(), which flags it, and the read returns PMA_ERR_CORRUPT. */
#include "g4_drivers.h"

#include <string.h>

#define SR_ERRORS                                                                          \
    (FLASH_SR_OPERR | FLASH_SR_PROGERR | FLASH_SR_WRPERR | FLASH_SR_PGAERR | FLASH_SR_SIZERR | \
     FLASH_SR_PGSERR | FLASH_SR_MISERR | FLASH_SR_FASTERR | FLASH_SR_RDERR | FLASH_SR_OPTVERR)
#define BLOCKS 2u
#define PROGRAM_BYTES 8u

static volatile uint8_t ecc_double_error; /* set by the NMI handler */

static int dual_bank(void)
{
    return READ_BIT(g4_io.flash->OPTR, FLASH_OPTR_DBANK) != 0u;
}

static uint32_t page_bytes(void)
{
    return dual_bank() ? 2048u : 4096u;
}

static uintptr_t block_addr(uint32_t block)
{
    /* 8 KB area: dual bank uses its last 4 KB (two 2 KB pages) */
    return g4_io.nvm + (dual_bank() ? 4096u : 0u) + block * page_bytes();
}

int g4_flash_geometry(pma_nvm_geometry_t *g)
{
    if (g == NULL) return PMA_ERR_NULL;
    *g = (pma_nvm_geometry_t){.block_size = page_bytes(), .block_count = BLOCKS,
                              .program_size = PROGRAM_BYTES};
    return PMA_OK;
}

static int in_block(uint32_t block, uint32_t offset, uint32_t len)
{
    return block < BLOCKS && offset <= page_bytes() && len <= page_bytes() - offset;
}

int g4_flash_nmi(void)
{
    const uint32_t eccr = READ_REG(g4_io.flash->ECCR);
    if (!(eccr & FLASH_ECCR_ECCD)) return 0;
    ecc_double_error = 1;
    g4_w1c(&g4_io.flash->ECCR, FLASH_ECCR_ECCD);
    return 1;
}

int g4_flash_read(uint32_t block, uint32_t offset, void *buf, uint32_t len)
{
    if (buf == NULL) return PMA_ERR_NULL;
    if (!in_block(block, offset, len)) return PMA_ERR_RANGE;
    ecc_double_error = 0;
    const volatile uint8_t *src = (const volatile uint8_t *)(block_addr(block) + offset);
    uint8_t *dst = buf;
    for (uint32_t i = 0; i < len; ++i) dst[i] = src[i];
    /* the NMI ran during a load above, or ECCD is set without it (NMI
     * taken elsewhere first): either way, this range is not to be trusted */
    if (ecc_double_error || READ_BIT(g4_io.flash->ECCR, FLASH_ECCR_ECCD)) {
        (void)g4_flash_nmi();
        ecc_double_error = 0;
        return PMA_ERR_CORRUPT;
    }
    return PMA_OK;
}

static int unlock(void)
{
    FLASH_TypeDef *const flash = g4_io.flash;
    if (g4_wait(&flash->SR, FLASH_SR_BSY, 0u, G4_POLLS_LONG) != 0) return PMA_ERR_IO;
    if (READ_BIT(flash->CR, FLASH_CR_LOCK)) {
        WRITE_REG(flash->KEYR, G4_FLASH_KEY1);
        WRITE_REG(flash->KEYR, G4_FLASH_KEY2);
        /* a wrong sequence keeps it locked until reset */
        if (g4_wait(&flash->CR, FLASH_CR_LOCK, 0u, 1u) != 0) return PMA_ERR_IO;
    }
    /* errors left by an earlier operation would refuse this one (PGSERR) */
    g4_w1c(&flash->SR, SR_ERRORS | FLASH_SR_EOP);
    return PMA_OK;
}

static void lock(void)
{
    WRITE_REG(g4_io.flash->CR, FLASH_CR_LOCK);
}

/* Flushes the data cache so reads see the new contents. */
static void flush_dcache(void)
{
    FLASH_TypeDef *const flash = g4_io.flash;
    CLEAR_BIT(flash->ACR, FLASH_ACR_DCEN);
    SET_BIT(flash->ACR, FLASH_ACR_DCRST);
    MODIFY_REG(flash->ACR, FLASH_ACR_DCRST, FLASH_ACR_DCEN);
}

/* Waits for the end of an operation; PMA_ERR_IO on a timeout or an error flag. */
static int finish(void)
{
    FLASH_TypeDef *const flash = g4_io.flash;
    if (g4_wait(&flash->SR, FLASH_SR_BSY, 0u, G4_POLLS_LONG) != 0) return PMA_ERR_IO;
    const uint32_t sr = READ_REG(flash->SR);
    g4_w1c(&flash->SR, sr & (SR_ERRORS | FLASH_SR_EOP));
    return (sr & SR_ERRORS) ? PMA_ERR_IO : PMA_OK;
}

int g4_flash_erase(uint32_t block)
{
    if (block >= BLOCKS) return PMA_ERR_RANGE;
    int rc = unlock();
    if (rc != PMA_OK) return rc;
    const uint32_t cr = FLASH_CR_PER | _VAL2FLD(FLASH_CR_PNB, G4_NVM_FIRST_PAGE + block) |
                        (dual_bank() ? FLASH_CR_BKER : 0u); /* bank 2 */
    WRITE_REG(g4_io.flash->CR, cr);
    WRITE_REG(g4_io.flash->CR, cr | FLASH_CR_STRT);
    rc = finish();
    WRITE_REG(g4_io.flash->CR, 0u);
    lock();
    flush_dcache();
    return rc;
}

int g4_flash_program(uint32_t block, uint32_t offset, const void *data, uint32_t len)
{
    if (data == NULL) return PMA_ERR_NULL;
    if (!in_block(block, offset, len) || offset % PROGRAM_BYTES != 0u || len % PROGRAM_BYTES != 0u) {
        return PMA_ERR_RANGE;
    }
    const uintptr_t base = block_addr(block) + offset;
    for (uint32_t i = 0; i < len; i += 4u) {
        if (*(const volatile uint32_t *)(base + i) != 0xFFFFFFFFu) return PMA_ERR_NOT_ERASED;
    }
    int rc = unlock();
    if (rc != PMA_OK) return rc;
    WRITE_REG(g4_io.flash->CR, FLASH_CR_PG);
    const uint8_t *src = data;
    for (uint32_t i = 0; i < len && rc == PMA_OK; i += PROGRAM_BYTES) {
        uint32_t w[2];
        memcpy(w, src + i, sizeof w); /* the caller's buffer may be unaligned */
        /* a double word is programmed by its two words, in address order */
        *(volatile uint32_t *)(base + i) = w[0];
        *(volatile uint32_t *)(base + i + 4u) = w[1];
        rc = finish();
    }
    WRITE_REG(g4_io.flash->CR, 0u);
    lock();
    flush_dcache();
    return rc;
}
