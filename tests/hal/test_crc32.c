/* CRC-32 (firmware/app/crc32.h): the standard check value, chaining, and
 * agreement with a plain bit-at-a-time implementation written here. */
#include "hal_test.h"

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

static void test_check_value(void **state)
{
    (void)state;
    assert_int_equal(pma_crc32("123456789", 9), 0xCBF43926u);
    assert_int_equal(PMA_CRC32_CHECK, 0xCBF43926u);
    assert_int_equal(pma_crc32("", 0), 0u);
    const char *fox = "The quick brown fox jumps over the lazy dog";
    assert_int_equal(pma_crc32(fox, strlen(fox)), 0x414FA339u);
}

static void test_chaining(void **state)
{
    (void)state;
    const char *s = "123456789";
    for (size_t cut = 0; cut <= 9; ++cut) {
        const uint32_t c = pma_crc32_update(pma_crc32_update(0u, s, cut), s + cut, 9 - cut);
        assert_int_equal(c, 0xCBF43926u);
    }
}

static void test_matches_bitwise(void **state)
{
    (void)state;
    static uint8_t buf[300];
    uint32_t x = 0x12345678u;
    for (size_t i = 0; i < sizeof buf; ++i) {
        x = x * 1664525u + 1013904223u;
        buf[i] = (uint8_t)(x >> 24);
    }
    for (size_t n = 0; n <= sizeof buf; n += 13) {
        assert_int_equal(pma_crc32(buf, n), crc32_bitwise(buf, n));
    }
    /* every single-bit flip changes the CRC */
    const uint32_t ref = pma_crc32(buf, 64);
    for (size_t bit = 0; bit < 64 * 8; ++bit) {
        buf[bit / 8] ^= (uint8_t)(1u << (bit % 8));
        assert_true(pma_crc32(buf, 64) != ref);
        buf[bit / 8] ^= (uint8_t)(1u << (bit % 8));
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_check_value),
        cmocka_unit_test(test_chaining),
        cmocka_unit_test(test_matches_bitwise),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
