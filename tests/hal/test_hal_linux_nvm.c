/* SPDX-License-Identifier: Apache-2.0 */
/* Linux port, NVM in a file: created erased at the configured size, the raw
 * image format, contents kept across re-initialisation, flash semantics
 * (program only over erased bytes, program-size alignment, block ranges),
 * erase, and the refusal of a file of the wrong size. The power-cut hook is
 * tested in test_hal_linux_reset.c (it ends the process). */
#define _GNU_SOURCE

#include "test_hal_linux.h"

#include <fcntl.h>
#include <sys/stat.h>

static char dir[256];
static char path[300];

static int init_nvm(uint32_t block_size, uint32_t block_count)
{
    pma_hal_linux_config_t c = PMA_HAL_LINUX_CONFIG_INIT;
    c.no_can = 1;
    c.storage_path = path;
    c.nvm_block_size = block_size;
    c.nvm_block_count = block_count;
    const pma_hal_config_t cfg = {.can_bitrate_bps = 0, .port = &c};
    return pma_hal_init(&cfg);
}

/* Every test: a fresh directory, the storage file's path in it (not created). */
void setUp(void)
{
    dir[0] = '\0';
    linux_test_mkdtemp(dir, sizeof dir);
    (void)snprintf(path, sizeof path, "%s/nvm.bin", dir);
}

/* After every test, also one that failed: the port down, the directory removed. */
void tearDown(void)
{
    pma_hal_deinit();
    if (dir[0] != '\0') linux_test_rmdir(dir);
}

/* The whole file, read without the HAL. */
static size_t read_file(uint8_t *buf, size_t capacity)
{
    const int fd = open(path, O_RDONLY | O_CLOEXEC);
    TEST_ASSERT_TRUE(fd >= 0);
    const ssize_t n = read(fd, buf, capacity);
    (void)close(fd);
    TEST_ASSERT_TRUE(n >= 0);
    return (size_t)n;
}

static bool all_equal(const uint8_t *p, size_t n, uint8_t v)
{
    for (size_t i = 0; i < n; ++i) {
        if (p[i] != v) return false;
    }
    return true;
}

static void test_created_erased_with_defaults(void)
{
    TEST_ASSERT_EQUAL_INT(-1, access(path, F_OK));
    assert_status(init_nvm(0, 0), PMA_OK);
    pma_nvm_geometry_t g;
    assert_status(pma_hal_nvm_geometry(&g), PMA_OK);
    TEST_ASSERT_EQUAL_INT(2048, g.block_size);
    TEST_ASSERT_EQUAL_INT(4, g.block_count);
    TEST_ASSERT_EQUAL_INT(8, g.program_size);
    static uint8_t file[2048 * 4 + 1];
    TEST_ASSERT_EQUAL_INT(2048 * 4, read_file(file, sizeof file));
    TEST_ASSERT_TRUE(all_equal(file, 2048 * 4, 0xFF));
    struct stat st;
    TEST_ASSERT_EQUAL_INT(0, stat(path, &st));
    TEST_ASSERT_EQUAL_INT(0644, st.st_mode & 0777);
    assert_status(pma_hal_nvm_geometry(NULL), PMA_ERR_NULL);
}

static void test_program_read_and_file_format(void)
{
    assert_status(init_nvm(64, 3), PMA_OK);
    uint8_t data[16], back[16];
    for (unsigned i = 0; i < sizeof data; ++i) data[i] = (uint8_t)(0x10u + i);
    assert_status(pma_hal_nvm_program(1, 8, data, 16), PMA_OK);
    assert_status(pma_hal_nvm_read(1, 8, back, 16), PMA_OK);
    TEST_ASSERT_EQUAL_MEMORY(data, back, 16);
    assert_status(pma_hal_nvm_read(1, 9, back, 3), PMA_OK); /* any offset and length */
    TEST_ASSERT_EQUAL_MEMORY(data + 1, back, 3);
    assert_status(pma_hal_nvm_read(1, 0, back, 0), PMA_OK);
    /* the raw image: block b at b x block_size, nothing else in the file */
    uint8_t file[64 * 3 + 1];
    TEST_ASSERT_EQUAL_INT(64 * 3, read_file(file, sizeof file));
    TEST_ASSERT_EQUAL_MEMORY(data, file + 64 + 8, 16);
    TEST_ASSERT_TRUE(all_equal(file, 64 + 8, 0xFF));
    TEST_ASSERT_TRUE(all_equal(file + 64 + 24, 64 * 3 - 64 - 24, 0xFF));
    /* a zero-length program is a no-op */
    assert_status(pma_hal_nvm_program(1, 8, data, 0), PMA_OK);
    assert_status(pma_hal_nvm_read(1, 0, NULL, 1), PMA_ERR_NULL);
    assert_status(pma_hal_nvm_program(1, 0, NULL, 8), PMA_ERR_NULL);
}

static void test_reopen_keeps_data(void)
{
    assert_status(init_nvm(64, 3), PMA_OK);
    const uint8_t data[8] = {1, 2, 3, 4, 5, 6, 7, 8};
    assert_status(pma_hal_nvm_program(2, 56, data, 8), PMA_OK);
    pma_hal_deinit();
    assert_status(init_nvm(64, 3), PMA_OK);
    uint8_t back[8];
    assert_status(pma_hal_nvm_read(2, 56, back, 8), PMA_OK);
    TEST_ASSERT_EQUAL_MEMORY(data, back, 8);
    assert_status(init_nvm(64, 3), PMA_OK); /* re-init without deinit */
    assert_status(pma_hal_nvm_read(2, 56, back, 8), PMA_OK);
    TEST_ASSERT_EQUAL_MEMORY(data, back, 8);
}

static void test_not_erased(void)
{
    assert_status(init_nvm(64, 2), PMA_OK);
    const uint8_t a[16] = {0xF0, 0xF1, 0xF2, 0xF3, 0xF4, 0xF5, 0xF6, 0xF7,
                           0xF8, 0xF9, 0xFA, 0xFB, 0xFC, 0xFD, 0xFE, 0xFF};
    const uint8_t b[16] = {0};
    assert_status(pma_hal_nvm_program(0, 8, a, 8), PMA_OK);
    /* over programmed bytes, or partly over them: refused, nothing changed */
    assert_status(pma_hal_nvm_program(0, 8, b, 8), PMA_ERR_NOT_ERASED);
    assert_status(pma_hal_nvm_program(0, 0, b, 16), PMA_ERR_NOT_ERASED);
    assert_status(pma_hal_nvm_program(0, 8, b, 16), PMA_ERR_NOT_ERASED);
    uint8_t back[24];
    assert_status(pma_hal_nvm_read(0, 0, back, 24), PMA_OK);
    TEST_ASSERT_TRUE(all_equal(back, 8, 0xFF));
    TEST_ASSERT_EQUAL_MEMORY(a, back + 8, 8);
    TEST_ASSERT_TRUE(all_equal(back + 16, 8, 0xFF));
    /* a unit that reads 0xFF after a program of 0xFF is erased as far as anyone can tell */
    const uint8_t ff[8] = {0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF};
    assert_status(pma_hal_nvm_program(1, 0, ff, 8), PMA_OK);
    assert_status(pma_hal_nvm_program(1, 0, b, 8), PMA_OK);
}

static void test_alignment_and_ranges(void)
{
    assert_status(init_nvm(64, 2), PMA_OK);
    const uint8_t d[16] = {0};
    uint8_t back[16];
    assert_status(pma_hal_nvm_program(0, 4, d, 8), PMA_ERR_RANGE);   /* offset */
    assert_status(pma_hal_nvm_program(0, 8, d, 4), PMA_ERR_RANGE);   /* length */
    assert_status(pma_hal_nvm_program(0, 56, d, 16), PMA_ERR_RANGE); /* past the block */
    assert_status(pma_hal_nvm_program(0, 64, d, 8), PMA_ERR_RANGE);
    assert_status(pma_hal_nvm_program(2, 0, d, 8), PMA_ERR_RANGE);   /* no block 2 */
    assert_status(pma_hal_nvm_read(0, 60, back, 8), PMA_ERR_RANGE);
    assert_status(pma_hal_nvm_read(0, 65, back, 0), PMA_ERR_RANGE);
    assert_status(pma_hal_nvm_read(2, 0, back, 1), PMA_ERR_RANGE);
    assert_status(pma_hal_nvm_read(0, UINT32_MAX, back, 2), PMA_ERR_RANGE);
    assert_status(pma_hal_nvm_erase(2), PMA_ERR_RANGE);
    assert_status(pma_hal_nvm_read(0, 0, back, 16), PMA_OK);
    TEST_ASSERT_TRUE(all_equal(back, 16, 0xFF)); /* none of the refused programs wrote */
}

static void test_erase(void)
{
    assert_status(init_nvm(64, 3), PMA_OK);
    uint8_t d[64];
    memset(d, 0x00, sizeof d);
    for (uint32_t b = 0; b < 3; ++b) assert_status(pma_hal_nvm_program(b, 0, d, 64), PMA_OK);
    assert_status(pma_hal_nvm_erase(1), PMA_OK);
    uint8_t file[64 * 3];
    TEST_ASSERT_EQUAL_INT(sizeof file, read_file(file, sizeof file));
    TEST_ASSERT_TRUE(all_equal(file, 64, 0x00));
    TEST_ASSERT_TRUE(all_equal(file + 64, 64, 0xFF)); /* only block 1 */
    TEST_ASSERT_TRUE(all_equal(file + 128, 64, 0x00));
    assert_status(pma_hal_nvm_program(1, 0, d, 64), PMA_OK); /* programmable again */
}

/* A block larger than the port's internal chunk (4 KiB): checked and erased whole. */
static void test_large_block(void)
{
    enum { BS = 3 * 4096 + 8 };
    assert_status(init_nvm(BS, 2), PMA_OK);
    static uint8_t d[BS], back[BS];
    memset(d, 0x3C, sizeof d);
    assert_status(pma_hal_nvm_program(1, 0, d, BS), PMA_OK);
    assert_status(pma_hal_nvm_read(1, 0, back, BS), PMA_OK);
    TEST_ASSERT_EQUAL_MEMORY(d, back, BS);
    const uint8_t z[8] = {0};
    assert_status(pma_hal_nvm_program(1, BS - 8, z, 8), PMA_ERR_NOT_ERASED);
    assert_status(pma_hal_nvm_erase(1), PMA_OK);
    assert_status(pma_hal_nvm_read(1, 0, back, BS), PMA_OK);
    TEST_ASSERT_TRUE(all_equal(back, BS, 0xFF));
}

static void test_wrong_size_file(void)
{
    /* made with another geometry */
    assert_status(init_nvm(64, 3), PMA_OK);
    pma_hal_deinit();
    assert_status(init_nvm(64, 4), PMA_ERR_RANGE);
    const char *msg = pma_hal_linux_last_error();
    assert_contains(msg, path);
    assert_contains(msg, "192 bytes");
    assert_contains(msg, "needs 256");
    /* the file was left alone */
    struct stat st;
    TEST_ASSERT_EQUAL_INT(0, stat(path, &st));
    TEST_ASSERT_EQUAL_INT(192, st.st_size);
    /* an empty file is not silently erased either */
    const int fd = open(path, O_WRONLY | O_TRUNC | O_CLOEXEC);
    TEST_ASSERT_TRUE(fd >= 0);
    (void)close(fd);
    assert_status(init_nvm(64, 3), PMA_ERR_RANGE);
    assert_contains(pma_hal_linux_last_error(), "0 bytes");
    pma_nvm_geometry_t g;
    assert_status(pma_hal_nvm_geometry(&g), PMA_ERR_NOT_READY);
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_created_erased_with_defaults);
    RUN_TEST(test_program_read_and_file_format);
    RUN_TEST(test_reopen_keeps_data);
    RUN_TEST(test_not_erased);
    RUN_TEST(test_alignment_and_ranges);
    RUN_TEST(test_erase);
    RUN_TEST(test_large_block);
    RUN_TEST(test_wrong_size_file);
    return UNITY_END();
}
