/* SPDX-License-Identifier: Apache-2.0 */
/* CRC-32 (firmware/storage/crc32.h): the standard check value, chaining, and
 * agreement with a plain bit-at-a-time implementation written here. */
#include "pma/status.h"
#include "pma_test.h"

#include <string.h>

#include "crc32.h"

/* Reference: one bit per step, reflected polynomial 0xEDB88320. */
static uint32_t crc32_bitwise(const uint8_t *p, size_t n)
{
    uint32_t c = 0xFFFFFFFFu;
    for (size_t i = 0; i < n; ++i) {
        c ^= p[i];
        for (int b = 0; b < 8; ++b) c = (c & 1u) ? (c >> 1) ^ 0xEDB88320u : c >> 1;
    }
    return ~c;
}

static void test_check_value(void)
{
    TEST_ASSERT_EQUAL_HEX32(0xCBF43926u, pma_crc32("123456789", 9));
    TEST_ASSERT_EQUAL_HEX32(0xCBF43926u, PMA_CRC32_CHECK);
    TEST_ASSERT_EQUAL_HEX32(0u, pma_crc32("", 0));
    const char *fox = "The quick brown fox jumps over the lazy dog";
    TEST_ASSERT_EQUAL_HEX32(0x414FA339u, pma_crc32(fox, strlen(fox)));
}

static void test_chaining(void)
{
    const char *s = "123456789";
    for (size_t cut = 0; cut <= 9; ++cut) {
        const uint32_t c = pma_crc32_update(pma_crc32_update(0u, s, cut), s + cut, 9 - cut);
        TEST_ASSERT_EQUAL_HEX32(0xCBF43926u, c);
    }
}

static void test_matches_bitwise(void)
{
    static uint8_t buf[300];
    uint32_t x = 0x12345678u;
    for (size_t i = 0; i < sizeof buf; ++i) {
        x = x * 1664525u + 1013904223u;
        buf[i] = (uint8_t)(x >> 24);
    }
    for (size_t n = 0; n <= sizeof buf; n += 13) {
        TEST_ASSERT_EQUAL_HEX32(crc32_bitwise(buf, n), pma_crc32(buf, n));
    }
    /* every single-bit flip changes the CRC */
    const uint32_t ref = pma_crc32(buf, 64);
    for (size_t bit = 0; bit < 64 * 8; ++bit) {
        buf[bit / 8] ^= (uint8_t)(1u << (bit % 8));
        TEST_ASSERT_NOT_EQUAL_HEX32(ref, pma_crc32(buf, 64));
        buf[bit / 8] ^= (uint8_t)(1u << (bit % 8));
    }
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_check_value);
    RUN_TEST(test_chaining);
    RUN_TEST(test_matches_bitwise);
    return UNITY_END();
}
