/* SPDX-License-Identifier: Apache-2.0 */
/* The blank template port: every function of pma/hal.h exists (this links)
 * and answers as documented (PMA_ERR_NOT_IMPLEMENTED, or a neutral value). */
#include "hal_test.h"

#include <string.h>

#include "pma/hal.h"

static void test_every_function_is_present(void)
{
    TEST_ASSERT_EQUAL_STRING("template", pma_hal_port_name());
    assert_status(pma_hal_init(NULL), PMA_ERR_NOT_IMPLEMENTED);
    const pma_hal_config_t cfg = {.can_bitrate_bps = 500000u, .port = NULL};
    assert_status(pma_hal_init(&cfg), PMA_ERR_NOT_IMPLEMENTED);

    uint16_t raw;
    assert_status(pma_hal_adc_read(&raw), PMA_ERR_NOT_IMPLEMENTED);
    assert_status(pma_hal_adc_read(NULL), PMA_ERR_NULL);
    assert_status(pma_hal_dac_write(0), PMA_ERR_NOT_IMPLEMENTED);

    pma_can_frame_t f = {.id = 0x123, .dlc = 2, .data = {1, 2}};
    const pma_can_filter_t filt = {.id = 0x100, .mask = 0x700};
    pma_can_status_t st;
    assert_status(pma_hal_can_send(&f), PMA_ERR_NOT_IMPLEMENTED);
    assert_status(pma_hal_can_recv(&f), PMA_ERR_NOT_IMPLEMENTED);
    assert_status(pma_hal_can_set_filters(&filt, 1), PMA_ERR_NOT_IMPLEMENTED);
    assert_status(pma_hal_can_status(&st), PMA_ERR_NOT_IMPLEMENTED);
    assert_status(pma_hal_can_recover(), PMA_ERR_NOT_IMPLEMENTED);

    TEST_ASSERT_EQUAL_UINT64(0, pma_hal_time_us());
    uint32_t late;
    assert_status(pma_hal_tick_start(1000), PMA_ERR_NOT_IMPLEMENTED);
    assert_status(pma_hal_tick_wait(&late), PMA_ERR_NOT_IMPLEMENTED);

    pma_nvm_geometry_t g;
    uint8_t buf[8];
    memset(buf, 0xFF, sizeof buf);
    assert_status(pma_hal_nvm_geometry(&g), PMA_ERR_NOT_IMPLEMENTED);
    assert_status(pma_hal_nvm_read(0, 0, buf, sizeof buf), PMA_ERR_NOT_IMPLEMENTED);
    assert_status(pma_hal_nvm_program(0, 0, buf, sizeof buf), PMA_ERR_NOT_IMPLEMENTED);
    assert_status(pma_hal_nvm_erase(0), PMA_ERR_NOT_IMPLEMENTED);

    assert_status(pma_hal_watchdog_start(100), PMA_ERR_NOT_IMPLEMENTED);
    pma_hal_watchdog_kick();
    TEST_ASSERT_EQUAL_INT(PMA_RESET_UNKNOWN, pma_hal_reset_cause());
    pma_hal_deinit();
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_every_function_is_present);
    return UNITY_END();
}
