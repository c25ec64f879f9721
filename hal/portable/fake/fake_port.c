/* SPDX-License-Identifier: Apache-2.0 */
/* Fake port: initialisation and the three depths of reset (pma_hal_fake.h). */
#include "fake_internal.h"

#include <stddef.h>

static bool initialised; /* pma_hal_init() done; static: one fake device set per program */

int pma_hal_init(const pma_hal_config_t *cfg)
{
    uint32_t bitrate_bps = PMA_HAL_CAN_DEFAULT_BITRATE_BPS;
    if (cfg != NULL && cfg->can_bitrate_bps != 0) bitrate_bps = cfg->can_bitrate_bps;
    pma_fake_adc_dac_reset_(PMA_FAKE_RESET_INIT);
    pma_fake_can_reset_(PMA_FAKE_RESET_INIT, bitrate_bps);
    pma_fake_time_reset_(PMA_FAKE_RESET_INIT);
    pma_fake_nvm_reset_(PMA_FAKE_RESET_INIT);
    initialised = true;
    return PMA_OK;
}

void pma_hal_deinit(void)
{
    pma_fake_can_reset_(PMA_FAKE_RESET_INIT, PMA_HAL_CAN_DEFAULT_BITRATE_BPS);
    pma_fake_time_reset_(PMA_FAKE_RESET_INIT);
    initialised = false;
}

const char *pma_hal_port_name(void)
{
    return "fake";
}

bool pma_fake_initialised(void)
{
    return initialised;
}

static void restart(pma_fake_reset_depth_t depth)
{
    pma_fake_adc_dac_reset_(depth);
    pma_fake_can_reset_(depth, PMA_HAL_CAN_DEFAULT_BITRATE_BPS);
    pma_fake_time_reset_(depth);
    pma_fake_nvm_reset_(depth);
    initialised = false;
}

void pma_fake_reset(void)
{
    pma_fake_set_reset_cause_(PMA_RESET_POWER_ON);
    restart(PMA_FAKE_RESET_ALL);
}

void pma_fake_power_on(void)
{
    pma_fake_set_reset_cause_(PMA_RESET_POWER_ON);
    restart(PMA_FAKE_RESET_RESTART);
}

void pma_fake_reboot(void)
{
    pma_fake_set_reset_cause_(pma_fake_watchdog_expired() ? PMA_RESET_WATCHDOG
                                                          : PMA_RESET_SOFTWARE);
    restart(PMA_FAKE_RESET_RESTART);
}
