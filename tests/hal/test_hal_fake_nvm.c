/* SPDX-License-Identifier: Apache-2.0 */
/* Fake port, NVM: geometry, flash semantics (erase to 0xFF, program only
 * erased and aligned areas), the power-cut injector with partial application,
 * power-on keeping the contents, a worn byte. */
#include "hal_test.h"

#include <string.h>

#include "pma/hal.h"
#include "pma_hal_fake.h"

#define BLOCK 64u
#define BLOCKS 4u
#define PROG 8u

static uint8_t mem[BLOCK * BLOCKS];
static const pma_nvm_geometry_t geo = {.block_size = BLOCK, .block_count = BLOCKS,
                                       .program_size = PROG};

/* Every test: fresh devices, HAL up, `mem` attached as the NVM. */
void setUp(void)
{
    pma_fake_reset();
    assert_status(pma_hal_init(NULL), PMA_OK);
    memset(mem, 0x5A, sizeof mem); /* attach must erase this */
    assert_status(pma_fake_nvm_attach(mem, sizeof mem, &geo), PMA_OK);
}

static bool all_equal(const uint8_t *p, size_t n, uint8_t v)
{
    for (size_t i = 0; i < n; ++i) {
        if (p[i] != v) return false;
    }
    return true;
}

static void test_attach_and_geometry(void)
{
    pma_nvm_geometry_t g;
    assert_status(pma_hal_nvm_geometry(&g), PMA_OK);
    TEST_ASSERT_EQUAL_MEMORY(&geo, &g, sizeof g);
    TEST_ASSERT_TRUE(all_equal(mem, sizeof mem, 0xFF));

    pma_fake_reset();
    assert_status(pma_hal_init(NULL), PMA_OK);
    assert_status(pma_hal_nvm_geometry(&g), PMA_ERR_NOT_READY); /* nothing attached */
    assert_status(pma_hal_nvm_erase(0), PMA_ERR_NOT_READY);
    pma_nvm_geometry_t bad = geo;
    bad.program_size = 24; /* 64 is no multiple of 24 */
    assert_status(pma_fake_nvm_attach(mem, sizeof mem, &bad), PMA_ERR_RANGE);
    bad = geo;
    bad.block_count = 0;
    assert_status(pma_fake_nvm_attach(mem, sizeof mem, &bad), PMA_ERR_RANGE);
    assert_status(pma_fake_nvm_attach(mem, sizeof mem - 1u, &geo), PMA_ERR_RANGE);
    assert_status(pma_fake_nvm_attach(NULL, sizeof mem, &geo), PMA_ERR_NULL);
    assert_status(pma_fake_nvm_attach(mem, sizeof mem, &geo), PMA_OK);
    assert_status(pma_hal_nvm_geometry(NULL), PMA_ERR_NULL);
}

static void test_flash_semantics(void)
{
    uint8_t data[16], back[16];
    for (unsigned i = 0; i < sizeof data; ++i) data[i] = (uint8_t)(0x10u + i);
    assert_status(pma_hal_nvm_program(1, 8, data, 16), PMA_OK);
    assert_status(pma_hal_nvm_read(1, 8, back, 16), PMA_OK);
    TEST_ASSERT_EQUAL_MEMORY(data, back, 16);
    TEST_ASSERT_TRUE(all_equal(mem + BLOCK, 8, 0xFF) &&
                     all_equal(mem + BLOCK + 24, BLOCK - 24, 0xFF));
    /* unaligned reads are fine; unaligned programs are not */
    assert_status(pma_hal_nvm_read(1, 9, back, 3), PMA_OK);
    TEST_ASSERT_EQUAL_MEMORY(data + 1, back, 3);
    assert_status(pma_hal_nvm_program(1, 40, data, 4), PMA_ERR_RANGE);
    assert_status(pma_hal_nvm_program(1, 44, data, 8), PMA_ERR_RANGE);
    /* outside a block or the device */
    assert_status(pma_hal_nvm_read(1, 60, back, 8), PMA_ERR_RANGE);
    assert_status(pma_hal_nvm_read(BLOCKS, 0, back, 1), PMA_ERR_RANGE);
    assert_status(pma_hal_nvm_program(1, BLOCK, data, 8), PMA_ERR_RANGE);
    assert_status(pma_hal_nvm_erase(BLOCKS), PMA_ERR_RANGE);
    assert_status(pma_hal_nvm_read(1, 0, NULL, 1), PMA_ERR_NULL);
    /* programming over programmed bytes fails and changes nothing,
     * even for bits a program could clear */
    uint8_t zeros[8] = {0};
    assert_status(pma_hal_nvm_program(1, 16, zeros, 8), PMA_ERR_NOT_ERASED);
    assert_status(pma_hal_nvm_read(1, 8, back, 16), PMA_OK);
    TEST_ASSERT_EQUAL_MEMORY(data, back, 16);
    /* partly erased units count too */
    assert_status(pma_hal_nvm_program(1, 0, zeros, 16), PMA_ERR_NOT_ERASED);
    TEST_ASSERT_TRUE(all_equal(mem + BLOCK, 8, 0xFF));
    /* erase: the whole block to 0xFF, others untouched */
    assert_status(pma_hal_nvm_program(2, 0, data, 16), PMA_OK);
    assert_status(pma_hal_nvm_erase(1), PMA_OK);
    TEST_ASSERT_TRUE(all_equal(mem + BLOCK, BLOCK, 0xFF));
    TEST_ASSERT_EQUAL_MEMORY(data, mem + 2 * BLOCK, 16);
    assert_status(pma_hal_nvm_program(1, 16, zeros, 8), PMA_OK);
    TEST_ASSERT_EQUAL_INT(4, pma_fake_nvm_op_count()); /* 3 programs + 1 erase succeeded */
}

static void test_power_cut_during_program(void)
{
    uint8_t data[32], back[32];
    for (unsigned i = 0; i < sizeof data; ++i) data[i] = (uint8_t)i;
    pma_fake_nvm_cut_power(2, 500);
    assert_status(pma_hal_nvm_program(0, 0, data, 8), PMA_OK);
    assert_status(pma_hal_nvm_program(0, 8, data, 8), PMA_OK);
    TEST_ASSERT_FALSE(pma_fake_nvm_power_lost());
    assert_status(pma_hal_nvm_program(0, 16, data, 32), PMA_ERR_IO); /* the cut one */
    TEST_ASSERT_TRUE(pma_fake_nvm_power_lost());
    /* dead until power-on */
    assert_status(pma_hal_nvm_read(0, 0, back, 8), PMA_ERR_IO);
    assert_status(pma_hal_nvm_erase(3), PMA_ERR_IO);
    assert_status(pma_hal_nvm_program(3, 0, data, 8), PMA_ERR_IO);
    /* a prefix of 16 of the 32 bytes went in */
    TEST_ASSERT_EQUAL_MEMORY(data, mem + 16, 16);
    TEST_ASSERT_TRUE(all_equal(mem + 32, 16, 0xFF));

    pma_fake_power_on();
    TEST_ASSERT_EQUAL_INT(PMA_RESET_POWER_ON, pma_hal_reset_cause());
    assert_status(pma_hal_nvm_read(0, 0, back, 8), PMA_ERR_NOT_READY); /* MCU restarted */
    assert_status(pma_hal_init(NULL), PMA_OK);
    TEST_ASSERT_FALSE(pma_fake_nvm_power_lost());
    assert_status(pma_hal_nvm_read(0, 16, back, 32), PMA_OK); /* contents kept */
    TEST_ASSERT_EQUAL_MEMORY(data, back, 16);
    assert_status(pma_hal_nvm_program(0, 32, data, 16), PMA_OK); /* erased rest: usable */
    TEST_ASSERT_EQUAL_INT(4, pma_fake_nvm_op_count());
}

static void test_power_cut_during_erase(void)
{
    uint8_t zeros[BLOCK];
    memset(zeros, 0, sizeof zeros);
    assert_status(pma_hal_nvm_program(2, 0, zeros, BLOCK), PMA_OK);
    pma_fake_nvm_cut_power(0, 250);
    assert_status(pma_hal_nvm_erase(2), PMA_ERR_IO);
    TEST_ASSERT_TRUE(all_equal(mem + 2 * BLOCK, BLOCK / 4, 0xFF));                /* erased part */
    TEST_ASSERT_TRUE(all_equal(mem + 2 * BLOCK + BLOCK / 4, BLOCK * 3 / 4, 0x00)); /* old data */
    pma_fake_power_on();
    assert_status(pma_hal_init(NULL), PMA_OK);
    assert_status(pma_hal_nvm_erase(2), PMA_OK);
    TEST_ASSERT_TRUE(all_equal(mem + 2 * BLOCK, BLOCK, 0xFF));
}

/* 0 permille: nothing applied; 1000: all applied, yet the caller sees the
 * failure (power went before the operation returned). */
static void test_cut_extremes(void)
{
    const uint8_t data[8] = {1, 2, 3, 4, 5, 6, 7, 8};
    pma_fake_nvm_cut_power(0, 0);
    assert_status(pma_hal_nvm_program(0, 0, data, 8), PMA_ERR_IO);
    TEST_ASSERT_TRUE(all_equal(mem, 8, 0xFF));
    pma_fake_power_on();
    assert_status(pma_hal_init(NULL), PMA_OK);
    pma_fake_nvm_cut_power(0, 1000);
    assert_status(pma_hal_nvm_program(0, 0, data, 8), PMA_ERR_IO);
    TEST_ASSERT_EQUAL_MEMORY(data, mem, 8);
    pma_fake_power_on();
    assert_status(pma_hal_init(NULL), PMA_OK);
    /* operations refused by their argument checks do not count towards the cut */
    pma_fake_nvm_cut_power(0, 1000);
    assert_status(pma_hal_nvm_program(0, 0, data, 8), PMA_ERR_NOT_ERASED);
    assert_status(pma_hal_nvm_program(0, 3, data, 8), PMA_ERR_RANGE);
    TEST_ASSERT_FALSE(pma_fake_nvm_power_lost());
    assert_status(pma_hal_nvm_erase(0), PMA_ERR_IO);
    TEST_ASSERT_TRUE(all_equal(mem, BLOCK, 0xFF));
    /* a restart disarms a cut that has not happened yet */
    pma_fake_power_on();
    assert_status(pma_hal_init(NULL), PMA_OK);
    pma_fake_nvm_cut_power(5, 0);
    pma_fake_reboot();
    assert_status(pma_hal_init(NULL), PMA_OK);
    for (int i = 0; i < 10; ++i) assert_status(pma_hal_nvm_erase(1), PMA_OK);
}

static void test_worn_byte(void)
{
    const uint8_t data[8] = {1, 2, 3, 4, 5, 6, 7, 8};
    pma_fake_nvm_stuck_byte(3, 5, true);
    assert_status(pma_hal_nvm_program(3, 0, data, 8), PMA_OK); /* reports success */
    uint8_t back[8];
    assert_status(pma_hal_nvm_read(3, 0, back, 8), PMA_OK);
    TEST_ASSERT_EQUAL_HEX8(5, back[4]);
    TEST_ASSERT_EQUAL_HEX8(0xFF, back[5]);
    pma_fake_nvm_stuck_byte(3, 5, false);
    assert_status(pma_hal_nvm_erase(3), PMA_OK);
    assert_status(pma_hal_nvm_program(3, 0, data, 8), PMA_OK);
    assert_status(pma_hal_nvm_read(3, 0, back, 8), PMA_OK);
    TEST_ASSERT_EQUAL_MEMORY(data, back, 8);
}

/* ECC flash: a unit left half-written by a cut reads as corrupt until erased. */
static void test_ecc_torn_unit(void)
{
    uint8_t data[16], back[16];
    memset(data, 0x00, sizeof data);
    pma_fake_nvm_ecc(true);
    pma_fake_nvm_cut_power(0, 500);                           /* 8 of 16 bytes: aligned */
    assert_status(pma_hal_nvm_program(0, 0, data, 16), PMA_ERR_IO);
    pma_fake_power_on();
    assert_status(pma_hal_init(NULL), PMA_OK);
    assert_status(pma_hal_nvm_read(0, 0, back, 16), PMA_OK); /* whole units: no ECC error */

    pma_fake_nvm_cut_power(0, 375);                           /* 6 of 16 bytes: unit 2 torn */
    assert_status(pma_hal_nvm_program(0, 16, data, 16), PMA_ERR_IO);
    pma_fake_power_on();
    assert_status(pma_hal_init(NULL), PMA_OK);
    assert_status(pma_hal_nvm_read(0, 16, back, 1), PMA_ERR_CORRUPT);
    assert_status(pma_hal_nvm_read(0, 20, back, 8), PMA_ERR_CORRUPT);
    assert_status(pma_hal_nvm_read(0, 24, back, 8), PMA_OK);  /* the next unit is fine */
    assert_status(pma_hal_nvm_read(0, 8, back, 8), PMA_OK);
    assert_status(pma_hal_nvm_program(0, 24, data, 8), PMA_OK);
    memset(mem + 22, 0xFF, 2);                                 /* even if its bytes look erased */
    memset(mem + 16, 0xFF, 6);
    assert_status(pma_hal_nvm_program(0, 16, data, 8), PMA_ERR_NOT_ERASED);
    pma_fake_nvm_ecc(false);                                   /* a flash without ECC reads it */
    assert_status(pma_hal_nvm_read(0, 16, back, 8), PMA_OK);
    pma_fake_nvm_ecc(true);

    /* a cut erase leaves a torn unit at its boundary; erasing again clears everything */
    pma_fake_nvm_cut_power(0, 100);                           /* 6 of 64 bytes */
    assert_status(pma_hal_nvm_erase(0), PMA_ERR_IO);
    pma_fake_power_on();
    assert_status(pma_hal_init(NULL), PMA_OK);
    assert_status(pma_hal_nvm_read(0, 0, back, 8), PMA_ERR_CORRUPT);
    assert_status(pma_hal_nvm_read(0, 16, back, 8), PMA_ERR_CORRUPT); /* still the old one */
    assert_status(pma_hal_nvm_erase(0), PMA_OK);
    assert_status(pma_hal_nvm_read(0, 0, back, 16), PMA_OK);
    assert_status(pma_hal_nvm_read(0, 16, back, 16), PMA_OK);
    TEST_ASSERT_TRUE(all_equal(mem, BLOCK, 0xFF));
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_attach_and_geometry);
    RUN_TEST(test_flash_semantics);
    RUN_TEST(test_power_cut_during_program);
    RUN_TEST(test_power_cut_during_erase);
    RUN_TEST(test_cut_extremes);
    RUN_TEST(test_worn_byte);
    RUN_TEST(test_ecc_torn_unit);
    return UNITY_END();
}
