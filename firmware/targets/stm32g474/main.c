/* SPDX-License-Identifier: Apache-2.0 */
/* The STM32G474 (NUCLEO-G474RE) firmware: the application on the board's
 * port. The reset handler (hal/portable/st/stm32g474/startup_stm32g474.c)
 * has already set up the FPU, the 170 MHz clock and the time base. */
#include "board_app.h"
#include "pma_hal_stm32g474.h"

void board_led_write(int on)
{
    pma_hal_stm32g474_led_set(on);
}

/* The loop cannot run (HAL or tick failed): the output to 0 counts (if the
 * DAC is up), the LED flickering, and no watchdog kick, so the watchdog
 * restarts the board, which then reports the restart (FAULT WATCHDOG_RESET). */
static void halt(void)
{
    (void)pma_hal_dac_write(0u);
    for (;;) {
        const uint64_t t_ms = pma_hal_time_us() / 1000u;
        pma_hal_stm32g474_led_set((int)((t_ms / 25u) & 1u)); /* 20 Hz: unlike FAULT (10 Hz) */
    }
}

int main(void)
{
    static pma_app_t app; /* static: no heap, and off the 4 KB stack */
    static board_t board;
    uint8_t uid[PMA_HAL_STM32G474_UID_BYTES];
    pma_hal_stm32g474_device_uid(uid);
    _Static_assert(PMA_HAL_STM32G474_UID_BYTES == PMA_DEVICE_UID_BYTES, "the UID is the device id");
    int rc = board_start(&board, &app, NULL, uid);
    if (rc != PMA_OK && app.state != PMA_STATE_FAULT) halt();
    for (;;) {
        rc = board_step(&board, &app);
        if (rc != PMA_OK) halt();
    }
}
