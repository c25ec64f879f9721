/* SPDX-License-Identifier: Apache-2.0 */
/* The board's main-loop glue: everything of the STM32G474 firmware that is
 * not register access, in portable C over pma/hal.h, so the same object
 * code runs on the board and, against the fake HAL, in the emulated
 * Cortex-M4F closed-loop test (tests/app/test_app_closed_loop.c).
 *
 * The board: the application with its ADC and DAC (the plant bridge off
 * unless sys.plant_bridge = 1), parameters in two flash pages (one page
 * per slot), the watchdog started before anything else, and the status LED
 * showing the state (board_led_on). */
#ifndef BOARD_APP_H
#define BOARD_APP_H

#include <stdint.h>

#include "app.h"
#include "pma/hal.h"

#define BOARD_WATCHDOG_MS 500u      /* > the longest stall: a flash page erase (22 ms max) */
#define BOARD_STORE_FIRST_BLOCK 0u
#define BOARD_STORE_BLOCKS_PER_SLOT 1u

/* LED patterns: period and on-time in ms (0 period: steady). */
#define BOARD_LED_IDLE_PERIOD_MS 1000u   /* a short flash each second: alive, output safe */
#define BOARD_LED_IDLE_ON_MS 100u
#define BOARD_LED_ARMED_PERIOD_MS 250u   /* 4 Hz: output active at the preset pressure */
#define BOARD_LED_ARMED_ON_MS 125u
#define BOARD_LED_FAULT_PERIOD_MS 100u   /* 10 Hz: fault latched */
#define BOARD_LED_FAULT_ON_MS 50u
                                         /* RUNNING: steady on; BOOT: steady on */

typedef struct board {
    int8_t led;                          /* last level written, -1: none yet */
    uint32_t led_changes;                /* LED writes that changed the level */
    int last_rc;                         /* last pma_app_step result */
} board_t;

/* The application platform of the board, with its unique device id (NULL: unknown, zeros). */
pma_app_platform_t board_platform(const uint8_t *device_uid);

/* 1 when the LED is on for this state at time_ms. */
int board_led_on(uint8_t state, uint64_t time_ms);

/* Starts watchdog, HAL and application; the HAL configuration hc may be
 * NULL (defaults: 1 Mbit/s), device_uid the board's unique id
 * (PMA_DEVICE_UID_BYTES bytes; NULL: unknown). Returns PMA_OK or the first
 * error (the application is then in FAULT INIT, or the HAL is not up). */
int board_start(board_t *b, pma_app_t *app, const pma_hal_config_t *hc,
                const uint8_t *device_uid);

/* One main-loop iteration: pma_app_step(), then the LED. Returns the step's
 * result (PMA_OK, or the tick's error: the loop cannot go on). */
int board_step(board_t *b, pma_app_t *app);

/* The LED output, defined by the program that links this file (the board's
 * main.c: LD2; the test: a recorder). */
void board_led_write(int on);

#endif /* BOARD_APP_H */
