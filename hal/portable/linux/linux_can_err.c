/* SPDX-License-Identifier: Apache-2.0 */
/* Linux port, pure parts of CAN: the RX ring and the decoding of SocketCAN
 * error frames into ISO 11898-1 fault confinement. No system calls here, so
 * the host tests check them directly (under ASan, which the vcan tests
 * cannot use: see tests/hal/CMakeLists.txt). */
#include "linux_internal.h"

#include <linux/can.h>
#include <linux/can/error.h>
#include <string.h>

void pma_linux_ring_clear(pma_linux_ring_t *r)
{
    r->head = 0;
    r->count = 0;
}

bool pma_linux_ring_push(pma_linux_ring_t *r, const pma_can_frame_t *frame)
{
    if (r->count == PMA_HAL_LINUX_CAN_RX_DEPTH) return false;
    r->slot[(r->head + r->count) % PMA_HAL_LINUX_CAN_RX_DEPTH] = *frame;
    r->count++;
    return true;
}

bool pma_linux_ring_pop(pma_linux_ring_t *r, pma_can_frame_t *frame)
{
    if (r->count == 0) return false;
    *frame = r->slot[r->head];
    r->head = (r->head + 1u) % PMA_HAL_LINUX_CAN_RX_DEPTH;
    r->count--;
    return true;
}

/* ------------------------------------------------------- error frames -- */

/* ISO 11898-1 thresholds: warning at 96 (still error-active), error-passive
 * above 127. */
#define WARNING_LEVEL 96u
#define PASSIVE_LEVEL 128u

void pma_linux_can_err_reset(pma_linux_can_err_t *e)
{
    memset(e, 0, sizeof *e);
}

void pma_linux_can_err_recovered(pma_linux_can_err_t *e)
{
    e->bus_off = false;
    e->kernel_restarted = false;
    e->recovery_requested = false;
    e->tec = 0;
    e->rec = 0;
}

static uint16_t clamp_u16(uint16_t v, uint16_t lo, uint16_t hi)
{
    return v < lo ? lo : (v > hi ? hi : v);
}

/* A state report without counters: move a counter to its state's range. */
static void counter_to_state(uint16_t *counter, uint8_t bits, uint8_t warning_bit,
                             uint8_t passive_bit)
{
    if (bits & passive_bit) {
        *counter = clamp_u16(*counter, PASSIVE_LEVEL, 255u);
    } else if (bits & warning_bit) {
        *counter = clamp_u16(*counter, WARNING_LEVEL, PASSIVE_LEVEL - 1u);
    }
}

void pma_linux_can_err_apply(pma_linux_can_err_t *e, uint32_t can_id, const uint8_t data[8])
{
    if ((can_id & CAN_ERR_FLAG) == 0) return;
    const uint8_t ctrl = (can_id & CAN_ERR_CRTL) ? data[1] : 0u;
    if (ctrl & CAN_ERR_CRTL_RX_OVERFLOW) e->controller_rx_overflows++;

    if (can_id & CAN_ERR_BUSOFF) {
        e->bus_off = true;
        e->kernel_restarted = false;
        e->recovery_requested = false;
        e->tec = PMA_LINUX_CAN_BUS_OFF_TEC;
        return;
    }
    if (can_id & CAN_ERR_RESTARTED) {
        /* The driver put the controller back on the bus (restart-ms, or our
         * netlink request): counters start from 0. While bus-off is latched,
         * the application has not necessarily asked yet: the HAL contract
         * says a port never leaves bus-off on its own, so only remember it. */
        if (!e->bus_off || e->recovery_requested) {
            pma_linux_can_err_recovered(e);
        } else {
            e->kernel_restarted = true;
        }
        return;
    }
    if (e->bus_off) return; /* the counters of a latched bus-off stay at 256 */

    if (ctrl & CAN_ERR_CRTL_ACTIVE) {
        /* back below the warning level on both counters */
        if (e->tec >= WARNING_LEVEL) e->tec = WARNING_LEVEL - 1u;
        if (e->rec >= WARNING_LEVEL) e->rec = WARNING_LEVEL - 1u;
    }
    counter_to_state(&e->tec, ctrl, CAN_ERR_CRTL_TX_WARNING, CAN_ERR_CRTL_TX_PASSIVE);
    counter_to_state(&e->rec, ctrl, CAN_ERR_CRTL_RX_WARNING, CAN_ERR_CRTL_RX_PASSIVE);
    if (can_id & CAN_ERR_CNT) {
        e->tec = data[6];
        e->rec = data[7];
    }
}

pma_can_state_t pma_linux_can_err_state(const pma_linux_can_err_t *e)
{
    if (e->bus_off) return PMA_CAN_BUS_OFF;
    if (e->tec >= PASSIVE_LEVEL || e->rec >= PASSIVE_LEVEL) return PMA_CAN_ERROR_PASSIVE;
    return PMA_CAN_ERROR_ACTIVE;
}
