/* SPDX-License-Identifier: Apache-2.0 */
/* Internal to the Linux port: how its modules (linux_*.c) call one another,
 * and the pure parts (RX ring, error-frame decoding) that the host tests
 * exercise directly. Each module keeps its device state in static storage:
 * one device set per process, like the hardware of an MCU. */
#ifndef PMA_LINUX_INTERNAL_H
#define PMA_LINUX_INTERNAL_H

#include <stdbool.h>
#include <stdint.h>

#include "pma_hal_linux.h"

/* ------------------------------------------------------------ the port -- */

bool pma_linux_initialised(void);

#if defined(__GNUC__)
#define PMA_LINUX_PRINTF(f, a) __attribute__((format(printf, f, a)))
#else
#define PMA_LINUX_PRINTF(f, a)
#endif

/* Sets the message pma_hal_linux_last_error() returns (truncated to fit). */
void pma_linux_set_error(const char *fmt, ...) PMA_LINUX_PRINTF(1, 2);
void pma_linux_clear_error(void);

/* ----------------------------------------------------------------- CAN -- */

/* Opens, configures and binds the raw socket (accept-all filter, error
 * frames, drop counting); resets the ring and the error state. PMA_OK or
 * PMA_ERR_IO / PMA_ERR_RANGE with the reason set by pma_linux_set_error(). */
int pma_linux_can_open(const char *ifname, uint16_t tick_id, uint16_t tick_mask, int tick_dlc);
/* Closes the socket (nothing open: does nothing). */
void pma_linux_can_close(void);
/* Lockstep: from now on every tick frame read from the socket counts as one
 * tick. Frames that arrived before stay queued for pma_hal_can_recv() but
 * are no ticks. */
void pma_linux_can_tick_arm(void);
void pma_linux_can_tick_disarm(void);
/* Lockstep tick wait: PMA_OK for a tick, PMA_ERR_EMPTY when woken without one
 * (another frame, idle_ms without any, a signal, or a full ring), PMA_ERR_IO
 * when the socket fails. */
int pma_linux_can_tick_wait(uint32_t idle_ms);

/* Fixed-capacity FIFO of received frames, filled from the socket. */
typedef struct pma_linux_ring {
    pma_can_frame_t slot[PMA_HAL_LINUX_CAN_RX_DEPTH];
    uint32_t head;                 /* index of the oldest frame */
    uint32_t count;
} pma_linux_ring_t;

void pma_linux_ring_clear(pma_linux_ring_t *r);
bool pma_linux_ring_push(pma_linux_ring_t *r, const pma_can_frame_t *frame); /* false: full */
bool pma_linux_ring_pop(pma_linux_ring_t *r, pma_can_frame_t *frame);        /* false: empty */

/* Fault confinement as far as SocketCAN error frames tell it (linux/can/error.h).
 * Counters come from CAN_ERR_CNT (data[6] TEC, data[7] REC) when the driver
 * sends them; otherwise a state report moves them to the nearest value of
 * that state (warning: 96, passive: 128, active: at most 95), so that
 * pma_hal_can_status() stays consistent with ISO 11898-1's thresholds. */
typedef struct pma_linux_can_err {
    uint16_t tec, rec;
    bool bus_off;                  /* latched until recovered (a port never leaves it on its own) */
    bool kernel_restarted;         /* the driver reported CAN_ERR_RESTARTED while latched */
    bool recovery_requested;       /* pma_hal_can_recover() asked, waiting for the restart */
    uint32_t controller_rx_overflows; /* CAN_ERR_CRTL_RX_OVERFLOW: frames the controller lost */
} pma_linux_can_err_t;

#define PMA_LINUX_CAN_BUS_OFF_TEC 256u

void pma_linux_can_err_reset(pma_linux_can_err_t *e);
/* Applies one received error frame (can_id with CAN_ERR_FLAG, 8 data bytes);
 * other ids are ignored. */
void pma_linux_can_err_apply(pma_linux_can_err_t *e, uint32_t can_id, const uint8_t data[8]);
/* Leaves bus-off: error-active, TEC = REC = 0. */
void pma_linux_can_err_recovered(pma_linux_can_err_t *e);
pma_can_state_t pma_linux_can_err_state(const pma_linux_can_err_t *e);

/* Waits until the socket's send queue is empty, at most max_us. */
void pma_linux_can_flush(uint32_t max_us);

/* ---------------------------------------------------------------- time -- */

/* Stops the tick and selects its source for the next pma_hal_tick_start(). */
void pma_linux_tick_configure(bool lockstep, uint32_t idle_wake_ms);
void pma_linux_tick_stop(void);

/* ----------------------------------------------------------------- NVM -- */

/* Opens (or creates, erased) and locks the storage file. */
int pma_linux_nvm_open(const char *path, uint32_t block_size, uint32_t block_count,
                       int32_t cut_after_ops, uint32_t cut_permille);
void pma_linux_nvm_close(void);

/* ------------------------------------------------------------ watchdog -- */

/* Reads (once per process) and removes PMA_HAL_LINUX_RESET_CAUSE_ENV. */
void pma_linux_reset_cause_latch(void);
/* What the watchdog re-executes (NULL: it exits instead). */
void pma_linux_watchdog_set_argv(char *const *argv);
/* Name -> cause, as in the environment variable; NULL: POWER_ON. */
pma_reset_cause_t pma_linux_reset_cause_parse(const char *value);

#endif /* PMA_LINUX_INTERNAL_H */
