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

static int setup(void **state)
{
    (void)state;
    pma_fake_reset();
    if (pma_hal_init(NULL) != PMA_OK) return -1;
    memset(mem, 0x5A, sizeof mem); /* attach must erase this */
    return pma_fake_nvm_attach(mem, sizeof mem, &geo) == PMA_OK ? 0 : -1;
}

static bool all_equal(const uint8_t *p, size_t n, uint8_t v)
{
    for (size_t i = 0; i < n; ++i) {
        if (p[i] != v) return false;
    }
    return true;
}

static void test_attach_and_geometry(void **state)
{
    (void)state;
    pma_nvm_geometry_t g;
    assert_status(pma_hal_nvm_geometry(&g), PMA_OK);
    assert_memory_equal(&g, &geo, sizeof g);
    assert_true(all_equal(mem, sizeof mem, 0xFF));

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

static void test_flash_semantics(void **state)
{
    (void)state;
    uint8_t data[16], back[16];
    for (unsigned i = 0; i < sizeof data; ++i) data[i] = (uint8_t)(0x10u + i);
    assert_status(pma_hal_nvm_program(1, 8, data, 16), PMA_OK);
    assert_status(pma_hal_nvm_read(1, 8, back, 16), PMA_OK);
    assert_memory_equal(back, data, 16);
    assert_true(all_equal(mem + BLOCK, 8, 0xFF) && all_equal(mem + BLOCK + 24, BLOCK - 24, 0xFF));
    /* unaligned reads are fine; unaligned programs are not */
    assert_status(pma_hal_nvm_read(1, 9, back, 3), PMA_OK);
    assert_memory_equal(back, data + 1, 3);
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
    assert_memory_equal(back, data, 16);
    /* partly erased units count too */
    assert_status(pma_hal_nvm_program(1, 0, zeros, 16), PMA_ERR_NOT_ERASED);
    assert_true(all_equal(mem + BLOCK, 8, 0xFF));
    /* erase: the whole block to 0xFF, others untouched */
    assert_status(pma_hal_nvm_program(2, 0, data, 16), PMA_OK);
    assert_status(pma_hal_nvm_erase(1), PMA_OK);
    assert_true(all_equal(mem + BLOCK, BLOCK, 0xFF));
    assert_memory_equal(mem + 2 * BLOCK, data, 16);
    assert_status(pma_hal_nvm_program(1, 16, zeros, 8), PMA_OK);
    assert_int_equal(pma_fake_nvm_op_count(), 4); /* 3 programs + 1 erase succeeded */
}

static void test_power_cut_during_program(void **state)
{
    (void)state;
    uint8_t data[32], back[32];
    for (unsigned i = 0; i < sizeof data; ++i) data[i] = (uint8_t)i;
    pma_fake_nvm_cut_power(2, 500);
    assert_status(pma_hal_nvm_program(0, 0, data, 8), PMA_OK);
    assert_status(pma_hal_nvm_program(0, 8, data, 8), PMA_OK);
    assert_false(pma_fake_nvm_power_lost());
    assert_status(pma_hal_nvm_program(0, 16, data, 32), PMA_ERR_IO); /* the cut one */
    assert_true(pma_fake_nvm_power_lost());
    /* dead until power-on */
    assert_status(pma_hal_nvm_read(0, 0, back, 8), PMA_ERR_IO);
    assert_status(pma_hal_nvm_erase(3), PMA_ERR_IO);
    assert_status(pma_hal_nvm_program(3, 0, data, 8), PMA_ERR_IO);
    /* a prefix of 16 of the 32 bytes went in */
    assert_memory_equal(mem + 16, data, 16);
    assert_true(all_equal(mem + 32, 16, 0xFF));

    pma_fake_power_on();
    assert_int_equal(pma_hal_reset_cause(), PMA_RESET_POWER_ON);
    assert_status(pma_hal_nvm_read(0, 0, back, 8), PMA_ERR_NOT_READY); /* MCU restarted */
    assert_status(pma_hal_init(NULL), PMA_OK);
    assert_false(pma_fake_nvm_power_lost());
    assert_status(pma_hal_nvm_read(0, 16, back, 32), PMA_OK); /* contents kept */
    assert_memory_equal(back, data, 16);
    assert_status(pma_hal_nvm_program(0, 32, data, 16), PMA_OK); /* erased rest: usable */
    assert_int_equal(pma_fake_nvm_op_count(), 4);
}

static void test_power_cut_during_erase(void **state)
{
    (void)state;
    uint8_t zeros[BLOCK];
    memset(zeros, 0, sizeof zeros);
    assert_status(pma_hal_nvm_program(2, 0, zeros, BLOCK), PMA_OK);
    pma_fake_nvm_cut_power(0, 250);
    assert_status(pma_hal_nvm_erase(2), PMA_ERR_IO);
    assert_true(all_equal(mem + 2 * BLOCK, BLOCK / 4, 0xFF));               /* erased part */
    assert_true(all_equal(mem + 2 * BLOCK + BLOCK / 4, BLOCK * 3 / 4, 0x00)); /* old data */
    pma_fake_power_on();
    assert_status(pma_hal_init(NULL), PMA_OK);
    assert_status(pma_hal_nvm_erase(2), PMA_OK);
    assert_true(all_equal(mem + 2 * BLOCK, BLOCK, 0xFF));
}

/* 0 permille: nothing applied; 1000: all applied, yet the caller sees the
 * failure (power went before the operation returned). */
static void test_cut_extremes(void **state)
{
    (void)state;
    const uint8_t data[8] = {1, 2, 3, 4, 5, 6, 7, 8};
    pma_fake_nvm_cut_power(0, 0);
    assert_status(pma_hal_nvm_program(0, 0, data, 8), PMA_ERR_IO);
    assert_true(all_equal(mem, 8, 0xFF));
    pma_fake_power_on();
    assert_status(pma_hal_init(NULL), PMA_OK);
    pma_fake_nvm_cut_power(0, 1000);
    assert_status(pma_hal_nvm_program(0, 0, data, 8), PMA_ERR_IO);
    assert_memory_equal(mem, data, 8);
    pma_fake_power_on();
    assert_status(pma_hal_init(NULL), PMA_OK);
    /* operations refused by their argument checks do not count towards the cut */
    pma_fake_nvm_cut_power(0, 1000);
    assert_status(pma_hal_nvm_program(0, 0, data, 8), PMA_ERR_NOT_ERASED);
    assert_status(pma_hal_nvm_program(0, 3, data, 8), PMA_ERR_RANGE);
    assert_false(pma_fake_nvm_power_lost());
    assert_status(pma_hal_nvm_erase(0), PMA_ERR_IO);
    assert_true(all_equal(mem, BLOCK, 0xFF));
    /* a restart disarms a cut that has not happened yet */
    pma_fake_power_on();
    assert_status(pma_hal_init(NULL), PMA_OK);
    pma_fake_nvm_cut_power(5, 0);
    pma_fake_reboot();
    assert_status(pma_hal_init(NULL), PMA_OK);
    for (int i = 0; i < 10; ++i) assert_status(pma_hal_nvm_erase(1), PMA_OK);
}

static void test_worn_byte(void **state)
{
    (void)state;
    const uint8_t data[8] = {1, 2, 3, 4, 5, 6, 7, 8};
    pma_fake_nvm_stuck_byte(3, 5, true);
    assert_status(pma_hal_nvm_program(3, 0, data, 8), PMA_OK); /* reports success */
    uint8_t back[8];
    assert_status(pma_hal_nvm_read(3, 0, back, 8), PMA_OK);
    assert_int_equal(back[4], 5);
    assert_int_equal(back[5], 0xFF);
    pma_fake_nvm_stuck_byte(3, 5, false);
    assert_status(pma_hal_nvm_erase(3), PMA_OK);
    assert_status(pma_hal_nvm_program(3, 0, data, 8), PMA_OK);
    assert_status(pma_hal_nvm_read(3, 0, back, 8), PMA_OK);
    assert_memory_equal(back, data, 8);
}

/* ECC flash: a unit left half-written by a cut reads as corrupt until erased. */
static void test_ecc_torn_unit(void **state)
{
    (void)state;
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
    assert_true(all_equal(mem, BLOCK, 0xFF));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup(test_attach_and_geometry, setup),
        cmocka_unit_test_setup(test_flash_semantics, setup),
        cmocka_unit_test_setup(test_power_cut_during_program, setup),
        cmocka_unit_test_setup(test_power_cut_during_erase, setup),
        cmocka_unit_test_setup(test_cut_extremes, setup),
        cmocka_unit_test_setup(test_worn_byte, setup),
        cmocka_unit_test_setup(test_ecc_torn_unit, setup),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
