/* SPDX-License-Identifier: Apache-2.0 */
/* The fake port: pma/hal.h for tests, with a control API to feed it and to
 * inject faults. Link `pma_hal_fake` instead of a hardware port.
 *
 * All state is static (one fake device set per program), single-threaded,
 * without dynamic allocation. Nothing happens on its own: time passes only in
 * pma_fake_time_advance_us() and pma_hal_tick_wait(); frames arrive only via
 * pma_fake_can_inject(). Queue and log depths are compile-time constants
 * (small: the Cortex-M0 test board has 16 KB of RAM); the NVM memory is
 * supplied by the test (pma_fake_nvm_attach()).
 *
 * Three depths of reset:
 *   pma_hal_init()      CAN controller reset (error-active, counters 0, accept-all
 *                       filter, RX queue and TX queue empty), tick stopped.
 *   pma_fake_power_on() the MCU restarts after a power cut (reset cause
 *   pma_fake_reboot()   POWER_ON) or a watchdog/software reset (WATCHDOG if the
 *                       watchdog expired, else SOFTWARE): as above, plus not
 *                       initialised, watchdog stopped, NVM powered again with its
 *                       contents kept. What lies outside the MCU stays: the clock
 *                       (the test's world time), the sensor value and its faults,
 *                       the DAC and CAN TX logs, CAN bus faults.
 *   pma_fake_reset()    everything to its start state (call it in test set-up):
 *                       time 0, no faults, logs empty, NVM detached, reset cause
 *                       POWER_ON, not initialised. */
#ifndef PMA_HAL_FAKE_H
#define PMA_HAL_FAKE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "pma/hal.h"

#ifndef PMA_FAKE_CAN_RX_DEPTH
#define PMA_FAKE_CAN_RX_DEPTH 8u      /* frames waiting for pma_hal_can_recv() */
#endif
#ifndef PMA_FAKE_CAN_TX_QUEUE_DEPTH
#define PMA_FAKE_CAN_TX_QUEUE_DEPTH 4u /* frames held while TX is blocked */
#endif
#ifndef PMA_FAKE_CAN_TX_LOG_DEPTH
#define PMA_FAKE_CAN_TX_LOG_DEPTH 16u /* frames on the bus not yet popped by the test */
#endif
#ifndef PMA_FAKE_DAC_LOG_DEPTH
#define PMA_FAKE_DAC_LOG_DEPTH 8u     /* most recent DAC writes kept */
#endif
#ifndef PMA_FAKE_NVM_TORN_MAX
#define PMA_FAKE_NVM_TORN_MAX 8u      /* half-written units the ECC model remembers */
#endif
#define PMA_FAKE_DAC_MAX_COUNTS 4095u /* a 12-bit DAC: larger counts are PMA_ERR_RANGE */
#define PMA_FAKE_ADC_WIRE_BREAK_COUNTS 0u /* what a broken wire reads: the bottom of the scale */
/* pma_hal_watchdog_start() accepts 1..this (an STM32 IWDG counts up to ~32 s) */
#define PMA_FAKE_WATCHDOG_MAX_MS 32000u

/* ------------------------------------------------------------ whole fake -- */

void pma_fake_reset(void);
void pma_fake_power_on(void);
void pma_fake_reboot(void);
bool pma_fake_initialised(void);

/* ------------------------------------------------------------------ time -- */

/* Moves the clock forward; the watchdog expires on the way if it is due. */
void pma_fake_time_advance_us(uint64_t dt_us);
/* pma_hal_tick_wait() sleeps by advancing the clock to the next tick. */

/* Lockstep, as a port that ticks on received sensor frames (the Linux port's
 * --lockstep): while on, pma_hal_tick_wait() ticks only once per
 * pma_fake_tick_grant() (the clock advanced to the next tick boundary as
 * above, never late); without a grant it returns PMA_ERR_EMPTY at once and no
 * time passes (a loop iteration that only handles frames). Off after
 * pma_fake_reset(); a grant not yet used is dropped by pma_hal_init(). */
void pma_fake_tick_lockstep(bool on);
void pma_fake_tick_grant(void);

/* -------------------------------------------------------------- watchdog -- */

/* True once the clock went more than the timeout past the last kick (or the
 * start). It stays true (kicks no longer help: the MCU "was reset") until
 * pma_fake_reboot() / pma_fake_power_on() / pma_fake_reset(). */
bool pma_fake_watchdog_expired(void);
bool pma_fake_watchdog_running(void);

/* ----------------------------------------------------------------- reset -- */

/* pma_hal_system_reset() calls since the last restart: the fake's system
 * reset only counts; the test restarts the MCU with pma_fake_reboot(), whose
 * reset cause is then SOFTWARE. */
uint32_t pma_fake_system_reset_requests(void);

/* ------------------------------------------------------------------- ADC -- */

/* The sensor's true output, read by pma_hal_adc_read() unless a fault is set. */
void pma_fake_adc_set(uint16_t raw_counts);
/* Faults, each until pma_fake_adc_clear_fault() (a new fault replaces the old):
 * stuck: reads the current value forever, later pma_fake_adc_set() ignored; */
void pma_fake_adc_stuck(void);
/* out of range: reads raw_counts (meant outside the scaling's valid range); */
void pma_fake_adc_out_of_range(uint16_t raw_counts);
/* wire break: reads PMA_FAKE_ADC_WIRE_BREAK_COUNTS (0 mA / 0 V); */
void pma_fake_adc_wire_break(void);
/* read error: pma_hal_adc_read() fails with PMA_ERR_IO. */
void pma_fake_adc_read_error(void);
void pma_fake_adc_clear_fault(void);
uint32_t pma_fake_adc_read_count(void); /* successful and failed reads since reset */

/* ------------------------------------------------------------------- DAC -- */

typedef struct pma_fake_dac_write {
    uint64_t time_us;
    uint16_t counts;
} pma_fake_dac_write_t;

uint32_t pma_fake_dac_write_count(void); /* accepted writes since reset */
/* Fault: while true every pma_hal_dac_write() fails with PMA_ERR_IO and
 * changes nothing (a broken converter); cleared by pma_fake_reset(). */
void pma_fake_dac_fail(bool fail);
/* Write number `age` back from the newest (0: the newest). PMA_ERR_EMPTY when
 * nothing was written, PMA_ERR_RANGE when older than kept or than written. */
int pma_fake_dac_log(uint32_t age, pma_fake_dac_write_t *w);

/* ------------------------------------------------------------------- CAN -- */

#define PMA_FAKE_CAN_FILTERED 1       /* pma_fake_can_inject(): rejected by the filters */
#define PMA_FAKE_CAN_DROPPED 2        /* pma_fake_can_inject(): lost by a drop fault */

typedef enum pma_fake_can_dir {
    PMA_FAKE_CAN_RX = 0,              /* frames from the bus to the firmware */
    PMA_FAKE_CAN_TX = 1,              /* frames from the firmware to the bus */
} pma_fake_can_dir_t;

/* A frame arrives from the bus. PMA_OK: queued for pma_hal_can_recv() (twice
 * under a duplicate fault); PMA_FAKE_CAN_FILTERED; PMA_FAKE_CAN_DROPPED;
 * PMA_ERR_FULL: RX queue full, the frame is lost and rx_overruns counts it;
 * PMA_ERR_BUS_OFF: the controller is off the bus; PMA_ERR_NOT_READY before
 * pma_hal_init(); PMA_ERR_RANGE: invalid frame. A received frame (filtered
 * or not) lowers REC by one as on a real controller. */
int pma_fake_can_inject(const pma_can_frame_t *frame);
uint32_t pma_fake_can_rx_pending(void);  /* frames waiting for pma_hal_can_recv() */

/* The frames the firmware put on the bus, oldest first. pma_fake_can_tx_pop()
 * returns PMA_ERR_EMPTY when none. When more than PMA_FAKE_CAN_TX_LOG_DEPTH
 * are waiting the oldest is overwritten (and counted). */
int pma_fake_can_tx_pop(pma_can_frame_t *frame);
uint32_t pma_fake_can_tx_pending(void);
uint32_t pma_fake_can_tx_overwritten(void);

/* Blocked: sent frames wait in the TX queue (nobody acknowledges them) and
 * pma_hal_can_send() returns PMA_ERR_FULL once PMA_FAKE_CAN_TX_QUEUE_DEPTH
 * are waiting. Unblocking puts the waiting frames on the bus in order. */
void pma_fake_can_block_tx(bool blocked);
/* The next n frames in that direction are lost / delivered twice. */
void pma_fake_can_drop(pma_fake_can_dir_t dir, uint32_t n);
void pma_fake_can_duplicate(pma_fake_can_dir_t dir, uint32_t n);

/* Forces the error counters; the state follows (TEC > 255: bus-off, TEC set to
 * 256, the TX queue is discarded, a pending recovery is cancelled). */
void pma_fake_can_set_error_counters(uint16_t tec, uint16_t rec);
/* A broken bus: every pma_hal_can_send() is one failed transmission attempt
 * (TEC += 8, the frame is lost, the call still returns PMA_OK as a real
 * controller's queueing does): error-passive after 16 sends, bus-off after
 * 32. A successful transmission lowers TEC by one. */
void pma_fake_can_bus_errors(bool on);
/* What pma_hal_can_recover() does from bus-off: the controller rejoins
 * (TEC = REC = 0, error-active) delay_us after the request, or never while
 * `blocked` (the bus is still broken; unblocking completes a pending
 * request). Default: delay 0, not blocked. */
void pma_fake_can_set_recovery(uint32_t delay_us, bool blocked);
uint32_t pma_fake_can_bitrate_bps(void); /* as given to pma_hal_init() */

/* ------------------------------------------------------------------- NVM -- */

/* Gives the fake its storage: mem (at least block_size * block_count bytes,
 * owned by the test) becomes a freshly erased device (all 0xFF) of geometry g.
 * PMA_ERR_RANGE for a zero or inconsistent geometry (block_size not a multiple
 * of program_size) or too small mem. Until attached the NVM functions return
 * PMA_ERR_NOT_READY. Also clears the faults below and the operation count. */
int pma_fake_nvm_attach(uint8_t *mem, size_t mem_size, const pma_nvm_geometry_t *g);

/* Power-cut injector: the next ops_before_cut program/erase operations
 * succeed; the one after is cut: it applies only the first
 * applied_permille/1000 of its bytes (a program writes a prefix of its data,
 * an erase sets a prefix of the block to 0xFF and leaves the rest as it was;
 * 1000: fully done, but power failed before it returned), returns PMA_ERR_IO,
 * and from then on every NVM read, program and erase returns PMA_ERR_IO until
 * pma_fake_power_on(), which keeps the contents. Operations that fail their
 * argument checks (PMA_ERR_RANGE, PMA_ERR_NOT_ERASED) do not count. */
void pma_fake_nvm_cut_power(uint32_t ops_before_cut, uint32_t applied_permille);
bool pma_fake_nvm_power_lost(void);
/* Program and erase operations performed (including a cut one) since attach. */
uint32_t pma_fake_nvm_op_count(void);
/* A worn cell: programming the byte at (block, offset) leaves it unchanged
 * (the program still reports success); erasing works. One byte at a time;
 * stuck false clears it. */
void pma_fake_nvm_stuck_byte(uint32_t block, uint32_t offset, bool stuck);
/* ECC flash (like the STM32G4's): when a cut leaves a program unit partly
 * old and partly new (applied bytes not a multiple of program_size), reads
 * touching that unit return PMA_ERR_CORRUPT and programs over it
 * PMA_ERR_NOT_ERASED until its block is erased. Off after attach. Up to
 * PMA_FAKE_NVM_TORN_MAX such units are remembered. */
void pma_fake_nvm_ecc(bool on);
uint32_t pma_fake_nvm_corrupt_reads(void); /* reads refused so, since attach */

#endif /* PMA_HAL_FAKE_H */
