/* SPDX-License-Identifier: Apache-2.0 */
/* Parameter storage (firmware/storage/pstore.h) on the fake NVM: the A/B
 * rotation, the record layout, corruption of every part of a record,
 * sequence wrap-around, oversized blobs, read-back verification, device
 * failures. The power-cut sweep is in test_pstore_powercut.c. */
#include "pstore_test.h"

static pma_pstore_t ps;

/* Every test: fresh devices and an empty store. */
void setUp(void)
{
    fresh(&ps);
}

static void expect_load(uint32_t seed, uint32_t len, uint32_t seq, uint8_t slot, uint8_t valid)
{
    pma_pstore_info_t info;
    memset(blob, 0, sizeof blob);
    assert_status(pma_pstore_load(&ps, blob, sizeof blob, &info), PMA_OK);
    TEST_ASSERT_EQUAL_INT(len, info.len);
    TEST_ASSERT_TRUE(blob_is(seed, len));
    TEST_ASSERT_EQUAL_INT((uint16_t)seed, info.blob_version);
    TEST_ASSERT_EQUAL_INT(seq, info.sequence);
    TEST_ASSERT_EQUAL_INT(slot, info.slot);
    TEST_ASSERT_EQUAL_INT(valid, info.valid_slots);
}

static void test_init_checks(void)
{
    pma_pstore_t p;
    assert_status(pma_pstore_init(NULL, 0, 1), PMA_ERR_NULL);
    assert_status(pma_pstore_init(&p, T_FIRST, 0), PMA_ERR_RANGE);
    assert_status(pma_pstore_init(&p, 3, T_BPS), PMA_ERR_RANGE);      /* slot B past the end */
    assert_status(pma_pstore_init(&p, T_BLOCKS + 1u, 1), PMA_ERR_RANGE);
    assert_status(pma_pstore_init(&p, 0, T_BLOCKS / 2u), PMA_OK);
    TEST_ASSERT_EQUAL_INT(PMA_PSTORE_MAX_BLOB_BYTES, p.capacity);
    assert_status(pma_pstore_init(&p, 0, 1), PMA_OK);                /* a 64-byte slot */
    TEST_ASSERT_EQUAL_INT(T_BLOCK - 20u, p.capacity);
    /* a program size above the chunk buffer */
    const pma_nvm_geometry_t big = {.block_size = 256, .block_count = 4, .program_size = 64};
    assert_status(pma_fake_nvm_attach(nvm_mem, sizeof nvm_mem, &big), PMA_OK);
    assert_status(pma_pstore_init(&p, 0, 1), PMA_ERR_RANGE);
    /* not ready: neither the HAL nor the store */
    pma_hal_deinit();
    assert_status(pma_pstore_init(&p, 0, 1), PMA_ERR_NOT_READY);
    TEST_ASSERT_FALSE(p.ready);
    assert_status(pma_pstore_load(&p, blob, sizeof blob, NULL), PMA_ERR_NOT_READY);
    assert_status(pma_pstore_save(&p, blob, 1, 0), PMA_ERR_NOT_READY);
}

static void test_empty_store_gives_defaults_code(void)
{
    pma_pstore_info_t info;
    assert_status(pma_pstore_load(&ps, blob, sizeof blob, &info), PMA_ERR_NO_RECORD);
    assert_status(pma_pstore_load(&ps, NULL, sizeof blob, &info), PMA_ERR_NULL);
    assert_status(pma_pstore_load(NULL, blob, sizeof blob, &info), PMA_ERR_NULL);
    assert_status(pma_pstore_save(&ps, NULL, 4, 0), PMA_ERR_NULL);
}

static void test_saves_alternate_slots(void)
{
    save_seed(&ps, 11, 100);
    expect_load(11, 100, 1, 0, 0x1);
    save_seed(&ps, 12, 512);
    expect_load(12, 512, 2, 1, 0x3);
    save_seed(&ps, 13, 7);
    expect_load(13, 7, 3, 0, 0x3);
    /* the older record is still there, intact, in the other slot */
    save_seed(&ps, 14, 0);
    expect_load(14, 0, 4, 1, 0x3);
    /* nothing outside the two slots was touched */
    for (size_t i = 0; i < T_BLOCK; ++i) TEST_ASSERT_EQUAL_HEX8(0xFF, nvm_mem[i]);
    for (size_t i = (T_FIRST + 2 * T_BPS) * T_BLOCK; i < sizeof nvm_mem; ++i) {
        TEST_ASSERT_EQUAL_HEX8(0xFF, nvm_mem[i]);
    }
}

/* The bytes in NVM are exactly the layout documented in pstore.h. */
static void test_record_layout(void)
{
    save_seed(&ps, 0x1234, 37);
    const uint8_t *p = slot_mem(0);
    const uint8_t head[16] = {0x50, 0x4D, 0x53, 0x50, 1, 0, 0x34, 0x12, 1, 0, 0, 0, 37, 0, 0, 0};
    TEST_ASSERT_EQUAL_MEMORY(head, p, 16);
    for (size_t i = 0; i < 37; ++i) TEST_ASSERT_EQUAL_HEX8(pattern_byte(0x1234, i), p[16 + i]);
    const uint32_t crc = pma_crc32(p, 16 + 37);
    TEST_ASSERT_EQUAL_HEX32(crc, p[53] | p[54] << 8 | p[55] << 16 | (uint32_t)p[56] << 24);
    for (size_t i = 57; i < T_BPS * T_BLOCK; ++i) TEST_ASSERT_EQUAL_HEX8(0xFF, p[i]);
    /* and the encoder of the tests agrees with it */
    craft_record(1, 2, 0x4321, 37);
    expect_load(0x4321, 37, 2, 1, 0x3);
}

static void test_zero_length_and_small_buffer(void)
{
    assert_status(pma_pstore_save(&ps, NULL, 0, 5), PMA_OK);
    pma_pstore_info_t info;
    assert_status(pma_pstore_load(&ps, blob, 0, &info), PMA_OK);
    TEST_ASSERT_EQUAL_INT(0, info.len);
    TEST_ASSERT_EQUAL_INT(5, info.blob_version);
    save_seed(&ps, 3, 200);
    assert_status(pma_pstore_load(&ps, blob, 199, &info), PMA_ERR_RANGE);
    assert_status(pma_pstore_load(&ps, blob, 200, NULL), PMA_OK);
    TEST_ASSERT_TRUE(blob_is(3, 200));
}

static void test_oversized_rejected_changes_nothing(void)
{
    save_seed(&ps, 21, 300);
    const uint32_t crc_before = pma_crc32(nvm_mem, sizeof nvm_mem);
    const uint32_t ops_before = pma_fake_nvm_op_count();
    /* (blob holds only the maximum: an oversized save must not even read it) */
    assert_status(pma_pstore_save(&ps, blob, PMA_PSTORE_MAX_BLOB_BYTES + 1u, 1), PMA_ERR_RANGE);
    TEST_ASSERT_EQUAL_INT(ops_before, pma_fake_nvm_op_count());
    TEST_ASSERT_EQUAL_HEX32(crc_before, pma_crc32(nvm_mem, sizeof nvm_mem));
    expect_load(21, 300, 1, 0, 0x1);
    /* a smaller layout has a smaller capacity */
    pma_pstore_t small;
    assert_status(pma_pstore_init(&small, T_FIRST, 2), PMA_OK); /* 128-byte slots */
    TEST_ASSERT_EQUAL_INT(108, small.capacity);
    assert_status(pma_pstore_save(&small, blob, 109, 1), PMA_ERR_RANGE);
    TEST_ASSERT_EQUAL_HEX32(crc_before, pma_crc32(nvm_mem, sizeof nvm_mem));
}

/* Corrupting the newest record anywhere makes load fall back to the other. */
static void test_corruption_falls_back(void)
{
    /* byte offsets in the newest record (len 40): magic, format, blob version,
     * sequence, length, payload start/end, CRC */
    const size_t where[] = {0, 3, 4, 6, 8, 11, 12, 15, 16, 55, 56, 59};
    for (size_t w = 0; w < sizeof where / sizeof where[0]; ++w) {
        for (unsigned bit = 0; bit < 8; bit += 3) {
            fresh(&ps);
            save_seed(&ps, 31, 64);
            save_seed(&ps, 32, 40);
            slot_mem(1)[where[w]] ^= (uint8_t)(1u << bit);
            expect_load(31, 64, 1, 0, 0x1);
        }
    }
}

static void test_both_corrupt_gives_defaults_code(void)
{
    save_seed(&ps, 41, 64);
    save_seed(&ps, 42, 64);
    slot_mem(0)[20] ^= 0x01;            /* payload of A */
    slot_mem(1)[16 + 64 + 2] ^= 0x80;   /* CRC of B */
    assert_status(pma_pstore_load(&ps, blob, sizeof blob, NULL), PMA_ERR_NO_RECORD);
    /* a single record, corrupt: nothing valid either */
    fresh(&ps);
    save_seed(&ps, 43, 10);
    slot_mem(0)[9] ^= 0x10;             /* sequence */
    assert_status(pma_pstore_load(&ps, blob, sizeof blob, NULL), PMA_ERR_NO_RECORD);
    /* a record of another format version or length beyond the maximum is invalid */
    fresh(&ps);
    craft_record(0, 1, 44, 10);
    slot_mem(0)[4] = 2;
    put32(slot_mem(0) + 26, pma_crc32(slot_mem(0), 26));
    assert_status(pma_pstore_load(&ps, blob, sizeof blob, NULL), PMA_ERR_NO_RECORD);
    craft_record(0, 1, 44, 10);
    put32(slot_mem(0) + 12, PMA_PSTORE_MAX_BLOB_BYTES + 1u);
    assert_status(pma_pstore_load(&ps, blob, sizeof blob, NULL), PMA_ERR_NO_RECORD);
}

/* Save goes to the slot without the newest valid record: a corrupt newer
 * slot is overwritten, the valid older one kept. */
static void test_save_replaces_corrupt_slot(void)
{
    save_seed(&ps, 51, 64);
    save_seed(&ps, 52, 64);
    slot_mem(1)[30] ^= 0x04;
    save_seed(&ps, 53, 64);
    expect_load(53, 64, 2, 1, 0x3); /* sequence continues from the valid record */
    slot_mem(1)[30] ^= 0x04;        /* now corrupt the new one: 51 again */
    expect_load(51, 64, 1, 0, 0x1);
}

/* Sequence numbers wrap: serial-number arithmetic picks the newer. */
static void test_sequence_wraparound(void)
{
    craft_record(0, 0xFFFFFFFFu, 61, 20);
    craft_record(1, 0x00000000u, 62, 20);
    expect_load(62, 20, 0, 1, 0x3);
    save_seed(&ps, 63, 20);
    expect_load(63, 20, 1, 0, 0x3);

    craft_record(0, 0xFFFFFFFEu, 64, 20);
    craft_record(1, 0xFFFFFFFFu, 65, 20);
    expect_load(65, 20, 0xFFFFFFFFu, 1, 0x3);
    save_seed(&ps, 66, 20);
    expect_load(66, 20, 0, 0, 0x3);

    craft_record(0, 5, 67, 20);
    craft_record(1, 0x80000006u, 68, 20); /* more than half the circle ahead: behind */
    expect_load(67, 20, 5, 0, 0x3);
}

/* A worn NVM byte: the read-back differs, the save reports it, the
 * previous record stays the newest and the half-good slot is erased. */
static void test_verify_failure(void)
{
    save_seed(&ps, 71, 64);
    pma_fake_nvm_stuck_byte(T_FIRST + T_BPS, 40, true); /* slot B, payload */
    fill_blob(72, 64);
    assert_status(pma_pstore_save(&ps, blob, 64, 72), PMA_ERR_VERIFY);
    expect_load(71, 64, 1, 0, 0x1);
    for (size_t i = 0; i < T_BLOCK; ++i) TEST_ASSERT_EQUAL_HEX8(0xFF, slot_mem(1)[i]);
    pma_fake_nvm_stuck_byte(0, 0, false);
    save_seed(&ps, 73, 64);
    expect_load(73, 64, 2, 1, 0x3);
}

/* A failing device: save changes nothing, load reports the failure rather
 * than "no record" when it could not read. */
static void test_device_failure(void)
{
    pma_fake_nvm_cut_power(0, 0);
    assert_status(pma_hal_nvm_erase(T_BLOCKS - 1u), PMA_ERR_IO); /* power is gone */
    assert_status(pma_pstore_load(&ps, blob, sizeof blob, NULL), PMA_ERR_IO);
    assert_status(pma_pstore_save(&ps, blob, 8, 1), PMA_ERR_IO);
    power_on(&ps);
    assert_status(pma_pstore_load(&ps, blob, sizeof blob, NULL), PMA_ERR_NO_RECORD);
    save_seed(&ps, 81, 8);
    pma_fake_nvm_cut_power(0, 0);
    assert_status(pma_hal_nvm_erase(T_BLOCKS - 1u), PMA_ERR_IO);
    const uint32_t ops = pma_fake_nvm_op_count();
    assert_status(pma_pstore_save(&ps, blob, 8, 1), PMA_ERR_IO);
    TEST_ASSERT_EQUAL_INT(ops, pma_fake_nvm_op_count());
    power_on(&ps);
    expect_load(81, 8, 1, 0, 0x1);
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_init_checks);
    RUN_TEST(test_empty_store_gives_defaults_code);
    RUN_TEST(test_saves_alternate_slots);
    RUN_TEST(test_record_layout);
    RUN_TEST(test_zero_length_and_small_buffer);
    RUN_TEST(test_oversized_rejected_changes_nothing);
    RUN_TEST(test_corruption_falls_back);
    RUN_TEST(test_both_corrupt_gives_defaults_code);
    RUN_TEST(test_save_replaces_corrupt_slot);
    RUN_TEST(test_sequence_wraparound);
    RUN_TEST(test_verify_failure);
    RUN_TEST(test_device_failure);
    return UNITY_END();
}
