/* SPDX-License-Identifier: Apache-2.0 */
/* Linux port: initialisation, the error message, and the converters this
 * port does not have (ADC, DAC: bridged over CAN in the host build). */
#define _GNU_SOURCE

#include "linux_internal.h"

#include <net/if.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

/* Static: one device set per process. */
static bool initialised;
static char last_error[320];

bool pma_linux_initialised(void)
{
    return initialised;
}

void pma_linux_set_error(const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    (void)vsnprintf(last_error, sizeof last_error, fmt, ap);
    va_end(ap);
}

void pma_linux_clear_error(void)
{
    last_error[0] = '\0';
}

const char *pma_hal_linux_last_error(void)
{
    return last_error;
}

/* Checks the settings that need no device; PMA_OK or the code with a message. */
static int validate(const pma_hal_linux_config_t *c, uint32_t block_size, uint32_t block_count)
{
    if (!c->no_can) {
        if (c->can_ifname == NULL) {
            pma_linux_set_error("pma_hal_linux: can_ifname is NULL (name the CAN interface, "
                                "e.g. \"vcan0\", or set no_can)");
            return PMA_ERR_NULL;
        }
        const size_t n = strlen(c->can_ifname);
        if (n == 0 || n >= IFNAMSIZ) {
            pma_linux_set_error("pma_hal_linux: CAN interface name \"%s\" must have 1..%d "
                                "characters", c->can_ifname, IFNAMSIZ - 1);
            return PMA_ERR_RANGE;
        }
    } else if (c->lockstep) {
        pma_linux_set_error("pma_hal_linux: lockstep ticks are CAN frames: it needs CAN "
                            "(no_can is set)");
        return PMA_ERR_RANGE;
    }
    if (c->tick_can_dlc < -1 || c->tick_can_dlc > (int)PMA_CAN_DLC_MAX) {
        pma_linux_set_error("pma_hal_linux: tick_can_dlc %d outside -1..8", c->tick_can_dlc);
        return PMA_ERR_RANGE;
    }
    if (c->tick_can_id > PMA_CAN_ID_MAX || c->tick_can_mask > PMA_CAN_ID_MAX) {
        pma_linux_set_error("pma_hal_linux: tick_can_id 0x%X / tick_can_mask 0x%X above 0x7FF",
                            (unsigned)c->tick_can_id, (unsigned)c->tick_can_mask);
        return PMA_ERR_RANGE;
    }
    if (c->storage_path != NULL) {
        if (block_size % PMA_HAL_LINUX_NVM_PROGRAM_SIZE != 0 ||
            (uint64_t)block_size * block_count > PMA_HAL_LINUX_NVM_MAX_BYTES) {
            pma_linux_set_error("pma_hal_linux: NVM geometry %u x %u bytes: the block size must "
                                "be a multiple of %u and the total at most %u bytes",
                                (unsigned)block_count, (unsigned)block_size,
                                PMA_HAL_LINUX_NVM_PROGRAM_SIZE, PMA_HAL_LINUX_NVM_MAX_BYTES);
            return PMA_ERR_RANGE;
        }
        if (c->nvm_cut_after_ops < -1 || c->nvm_cut_permille > 1000u) {
            pma_linux_set_error("pma_hal_linux: nvm_cut_after_ops %d (-1: off) / "
                                "nvm_cut_permille %u (0..1000) out of range",
                                (int)c->nvm_cut_after_ops, (unsigned)c->nvm_cut_permille);
            return PMA_ERR_RANGE;
        }
    }
    return PMA_OK;
}

int pma_hal_init(const pma_hal_config_t *cfg)
{
    static const pma_hal_linux_config_t defaults = PMA_HAL_LINUX_CONFIG_INIT;
    pma_linux_reset_cause_latch(); /* before anything can fail: the cause is the program's */
    if (initialised) pma_hal_deinit();

    const pma_hal_linux_config_t *c = &defaults;
    if (cfg != NULL && cfg->port != NULL) c = cfg->port;
    /* cfg->can_bitrate_bps is ignored: the bit rate belongs to the interface
     * (`ip link set can0 type can bitrate N`), which needs privileges. */
    const uint32_t block_size =
        c->nvm_block_size != 0 ? c->nvm_block_size : PMA_HAL_LINUX_DEFAULT_NVM_BLOCK_SIZE;
    const uint32_t block_count =
        c->nvm_block_count != 0 ? c->nvm_block_count : PMA_HAL_LINUX_DEFAULT_NVM_BLOCK_COUNT;
    int rc = validate(c, block_size, block_count);
    if (rc != PMA_OK) return rc;

    if (!c->no_can) {
        rc = pma_linux_can_open(c->can_ifname, c->tick_can_id, c->tick_can_mask, c->tick_can_dlc);
        if (rc != PMA_OK) return rc;
    }
    if (c->storage_path != NULL) {
        rc = pma_linux_nvm_open(c->storage_path, block_size, block_count, c->nvm_cut_after_ops,
                                c->nvm_cut_permille);
        if (rc != PMA_OK) {
            pma_linux_can_close();
            return rc;
        }
    }
    pma_linux_tick_configure(c->lockstep != 0, c->lockstep_idle_wake_ms != 0
                                                   ? c->lockstep_idle_wake_ms
                                                   : PMA_HAL_LINUX_DEFAULT_IDLE_WAKE_MS);
    pma_linux_watchdog_set_argv(c->argv);
    pma_linux_clear_error();
    initialised = true;
    return PMA_OK;
}

void pma_hal_deinit(void)
{
    pma_linux_tick_stop();
    pma_linux_can_close();
    pma_linux_nvm_close();
    initialised = false;
}

const char *pma_hal_port_name(void)
{
    return "linux";
}

/* The host has no converters: the host build exchanges the sensor sample and
 * the pressure command with a simulator or the HIL rig over CAN. */
int pma_hal_adc_read(uint16_t *raw_counts)
{
    if (raw_counts == NULL) return PMA_ERR_NULL;
    if (!initialised) return PMA_ERR_NOT_READY;
    return PMA_ERR_NOT_IMPLEMENTED;
}

int pma_hal_dac_write(uint16_t counts)
{
    (void)counts;
    if (!initialised) return PMA_ERR_NOT_READY;
    return PMA_ERR_NOT_IMPLEMENTED;
}
