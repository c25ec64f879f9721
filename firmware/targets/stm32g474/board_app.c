/* SPDX-License-Identifier: Apache-2.0 */
/* The board's main-loop glue: see board_app.h. */
#include "board_app.h"

#include <stddef.h>
#include <string.h>

pma_app_platform_t board_platform(const uint8_t *device_uid)
{
    pma_app_platform_t p = {
        .plant_bridge = 0,   /* the ADC and DAC; sys.plant_bridge switches to CAN frames */
        .lockstep = 0,       /* a hardware timer ticks the loop */
        .node_id = -1,       /* the stored sys.node_id */
        .store_first_block = BOARD_STORE_FIRST_BLOCK,
        .store_blocks_per_slot = BOARD_STORE_BLOCKS_PER_SLOT,
        .watchdog_ms = BOARD_WATCHDOG_MS,
    };
    if (device_uid != NULL) memcpy(p.device_uid, device_uid, sizeof p.device_uid);
    return p;
}

static int blink(uint64_t time_ms, uint32_t period_ms, uint32_t on_ms)
{
    return (time_ms % period_ms) < on_ms;
}

int board_led_on(uint8_t state, uint64_t time_ms)
{
    switch (state) {
    case PMA_STATE_IDLE: return blink(time_ms, BOARD_LED_IDLE_PERIOD_MS, BOARD_LED_IDLE_ON_MS);
    case PMA_STATE_ARMED: return blink(time_ms, BOARD_LED_ARMED_PERIOD_MS, BOARD_LED_ARMED_ON_MS);
    case PMA_STATE_FAULT: return blink(time_ms, BOARD_LED_FAULT_PERIOD_MS, BOARD_LED_FAULT_ON_MS);
    case PMA_STATE_RUNNING: return 1;
    default: return 1; /* BOOT */
    }
}

static void led_update(board_t *b, const pma_app_t *app)
{
    const int on = board_led_on(app->state, pma_hal_time_us() / 1000u);
    if (on != b->led) {
        board_led_write(on);
        if (b->led >= 0) ++b->led_changes;
        b->led = (int8_t)on;
    }
}

int board_start(board_t *b, pma_app_t *app, const pma_hal_config_t *hc,
                const uint8_t *device_uid)
{
    if (b == NULL || app == NULL) return PMA_ERR_NULL;
    memset(b, 0, sizeof *b);
    b->led = -1;
    /* the watchdog first: a start-up that hangs (a peripheral that never
     * answers) ends in a reset instead of a dead board */
    (void)pma_hal_watchdog_start(BOARD_WATCHDOG_MS);
    const pma_hal_config_t defaults = {.can_bitrate_bps = PMA_HAL_CAN_DEFAULT_BITRATE_BPS,
                                       .port = NULL};
    int rc = pma_hal_init(hc != NULL ? hc : &defaults);
    if (rc != PMA_OK) {
        b->last_rc = rc;
        return rc;
    }
    const pma_app_platform_t plat = board_platform(device_uid);
    rc = pma_app_init(app, &plat);
    led_update(b, app);
    b->last_rc = rc;
    return rc;
}

int board_step(board_t *b, pma_app_t *app)
{
    if (b == NULL || app == NULL) return PMA_ERR_NULL;
    const int rc = pma_app_step(app);
    led_update(b, app);
    b->last_rc = rc;
    return rc;
}
