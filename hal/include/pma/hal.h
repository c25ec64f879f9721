/* SPDX-License-Identifier: Apache-2.0 */
/* The port interface: the one header every HAL port implements (in the manner
 * of CANopenNode's CO_driver.h). Exactly one port is linked into a program,
 * chosen at link time (CMake: link `pma_hal` plus one of `pma_hal_fake`,
 * `pma_hal_template`, `pma_hal_linux` (the host), `pma_hal_stm32g474` (the
 * board)); there are
 * no function pointers and no run-time registration.
 *
 * Rules every port follows (docs/hal.md):
 * - Every function returns PMA_OK (0) or a negative pma_status_t code and never
 *   blocks, except pma_hal_tick_wait(). Functions that cannot fail return void.
 * - A port keeps its device state in static storage (the hardware is global
 *   anyway) and documents it; everything here is called from one thread (the
 *   application's main loop), never from an interrupt. A port's own interrupt
 *   handlers (CAN RX, timer) hand data to these functions through lock-free
 *   single-producer / single-consumer queues.
 * - Before pma_hal_init() and after pma_hal_deinit() every device function
 *   returns PMA_ERR_NOT_READY, except the clock (pma_hal_time_us), the
 *   watchdog (start, kick: it may guard start-up) and pma_hal_reset_cause().
 * - A port without some device returns PMA_ERR_NOT_IMPLEMENTED from it (the
 *   template port does so everywhere).
 * - Units are in the names: _us, _ms, _bps, _counts. */
#ifndef PMA_HAL_H
#define PMA_HAL_H

#include <stddef.h>
#include <stdint.h>

#include "pma/status.h"

/* ---------------------------------------------------------------- port -- */

typedef struct pma_hal_config {
    uint32_t can_bitrate_bps; /* classic CAN bit rate; 0: PMA_HAL_CAN_DEFAULT_BITRATE_BPS.
                                 Ports that cannot set it (SocketCAN) ignore it. */
    const void *port;         /* port-specific settings (declared in the port's own
                                 header, e.g. the Linux interface name) or NULL */
} pma_hal_config_t;

/* Brings up every device of the port: CAN controller (error-active, counters 0,
 * accept-all filter, queues empty), ADC, DAC, NVM, timers. cfg NULL: defaults.
 * Calling it again re-initialises (and stops the tick). It neither starts the
 * tick nor the watchdog (nor can it stop a running watchdog). */
int pma_hal_init(const pma_hal_config_t *cfg);

/* Shuts the devices down (CAN offline, tick stopped). The watchdog, once
 * started, keeps running: hardware watchdogs cannot be stopped. */
void pma_hal_deinit(void);

/* Short constant name of the port, e.g. "fake", "template" (never NULL). */
const char *pma_hal_port_name(void);

/* ----------------------------------------------------------------- ADC -- */

/* Latest raw sample of the position sensor (a laser displacement sensor), in
 * counts: the application scales it and checks its range and wire break
 * (pma_adc_counts_to_cm(), firmware/app/scaling.h). Returns PMA_ERR_IO when
 * the converter fails. */
int pma_hal_adc_read(uint16_t *raw_counts);

/* ----------------------------------------------------------------- DAC -- */

/* Sets the pressure command output (to the electro-pneumatic regulator) to
 * `counts` (the application's pma_dac_kpa_to_counts() gives them from kPa,
 * firmware/app/scaling.h). Counts beyond the port's
 * converter (documented by the port) return PMA_ERR_RANGE and change nothing. */
int pma_hal_dac_write(uint16_t counts);

/* ----------------------------------------------------------------- CAN -- */
/* Classic CAN 2.0A: 11-bit identifiers, 0..8 data bytes, no remote frames. */

#define PMA_HAL_CAN_DEFAULT_BITRATE_BPS 1000000u
#define PMA_CAN_ID_MAX 0x7FFu
#define PMA_CAN_DLC_MAX 8u
/* Every port accepts at least (and the fake exactly) this many filters. */
#define PMA_CAN_FILTERS_MAX 8u

/* 12 bytes, aligned to 4 so that a frame is copied as three words: at the 2 bytes its
 * members need, GCC copies it with a library memcpy call, byte by byte on ARMv6-M. */
typedef struct pma_can_frame {
    _Alignas(4) uint16_t id;         /* 0..PMA_CAN_ID_MAX */
    uint8_t dlc;                     /* number of data bytes, 0..8 */
    uint8_t data[PMA_CAN_DLC_MAX];
} pma_can_frame_t;

/* A frame is received when (frame.id & mask) == (id & mask) for any filter. */
typedef struct pma_can_filter {
    uint16_t id;
    uint16_t mask;                   /* 1 bits must match; mask 0 accepts every id */
} pma_can_filter_t;

/* Fault confinement state (ISO 11898-1): error-active while TEC and REC are
 * <= 127, error-passive when either is above, bus-off when TEC exceeds 255. */
typedef enum pma_can_state {
    PMA_CAN_ERROR_ACTIVE = 0,
    PMA_CAN_ERROR_PASSIVE = 1,
    PMA_CAN_BUS_OFF = 2,
} pma_can_state_t;

typedef struct pma_can_status {
    uint16_t tec;                    /* transmit error counter (256 in bus-off) */
    uint16_t rec;                    /* receive error counter */
    pma_can_state_t state;
    uint32_t rx_overruns;            /* frames lost because the RX queue was full, since init */
} pma_can_status_t;

/* Queues one frame for transmission; never blocks. PMA_ERR_FULL: the TX queue
 * is full (nothing queued, try again next tick); PMA_ERR_BUS_OFF: controller
 * is bus-off; PMA_ERR_RANGE: id > 0x7FF or dlc > 8. PMA_OK means queued, not
 * yet acknowledged on the bus. */
int pma_hal_can_send(const pma_can_frame_t *frame);

/* Takes the oldest received frame that passed the filters; never blocks.
 * PMA_ERR_EMPTY when there is none. */
int pma_hal_can_recv(pma_can_frame_t *frame);

/* Replaces the receive filters. count 0 (filters may then be NULL) accepts
 * every id, which is also the state after pma_hal_init(). count above
 * PMA_CAN_FILTERS_MAX or an id/mask above 0x7FF: PMA_ERR_RANGE, nothing
 * changed. Frames already queued stay queued. */
int pma_hal_can_set_filters(const pma_can_filter_t *filters, size_t count);

/* Error counters and fault confinement state. */
int pma_hal_can_status(pma_can_status_t *status);

/* Asks a bus-off controller to rejoin the bus. A port never leaves bus-off
 * on its own. Recovery completes after the bus has been idle for 128 x 11
 * recessive bits (1.4 ms at 1 Mbit/s), or never while the bus stays broken:
 * poll pma_hal_can_status() for PMA_CAN_ERROR_ACTIVE (TEC = REC = 0). Returns
 * PMA_OK when recovery was requested or the controller was not bus-off. */
int pma_hal_can_recover(void);

/* ---------------------------------------------------------------- time -- */

/* Monotonic microseconds since an arbitrary origin (power-on on hardware);
 * never decreases, never wraps in practice (2^64 us). */
uint64_t pma_hal_time_us(void);

/* Starts (or restarts with a new period) the periodic control tick. The first
 * tick falls period_us after the call. period_us 0: PMA_ERR_RANGE. */
int pma_hal_tick_start(uint32_t period_us);

/* Blocks until the next tick, then returns PMA_OK. The application polls this
 * from its main loop; there is no tick callback, so control code never runs
 * in interrupt context, and a port defines what a tick is: a hardware timer
 * (board), a POSIX timer (host real-time mode) or the arrival of the next
 * sensor sample (host lockstep mode).
 * late_ticks (may be NULL) receives how many ticks had already passed when
 * the call was made: 0 when the loop keeps up (the call slept); 1 when the
 * previous cycle overran into this period (returns at once, this tick is
 * served late); n > 1 when n - 1 ticks were skipped entirely (returns at once
 * for the latest one; ticks are never queued up). PMA_ERR_NOT_READY: tick
 * not started.
 * PMA_ERR_EMPTY: woken without a tick. Only a port whose ticks are driven by
 * received frames (host lockstep mode: a tick is the arrival of a sensor
 * sample frame) returns it: when any other frame arrives, and at least every
 * few milliseconds while none does, so that the main loop still serves
 * commands while the plant is paused. The loop then handles received frames
 * and calls pma_hal_tick_wait() again without running the control step. */
int pma_hal_tick_wait(uint32_t *late_ticks);

/* ----------------------------------------------------------------- NVM -- */
/* Non-volatile storage with flash semantics: an erase sets a whole block to
 * 0xFF; a program can only clear bits and only over erased bytes (programming
 * an area that is not erased is PMA_ERR_NOT_ERASED on the fake, undefined on
 * hardware); offsets and lengths of program are multiples of program_size.
 * A power loss during program or erase leaves the affected bytes undefined
 * (partly old, partly new). Reading them must not fault the MCU: a port whose
 * flash checks ECC (STM32G4: 8 ECC bits per 64-bit double word, a double
 * error raises an NMI) catches that and returns PMA_ERR_CORRUPT for a read
 * touching such a unit, until its block is erased. PMA_ERR_IO means the
 * device itself failed. */

typedef struct pma_nvm_geometry {
    uint32_t block_size;             /* bytes per erase block, a multiple of program_size */
    uint32_t block_count;            /* blocks available to the application, numbered from 0 */
    uint32_t program_size;           /* program granularity in bytes (e.g. 8 on STM32G4) */
} pma_nvm_geometry_t;

int pma_hal_nvm_geometry(pma_nvm_geometry_t *geometry);

/* Reads len bytes at offset within block; any offset and length inside the
 * block. PMA_ERR_RANGE: outside the block or block >= block_count;
 * PMA_ERR_CORRUPT: the range holds data the device flags as corrupt. */
int pma_hal_nvm_read(uint32_t block, uint32_t offset, void *buf, uint32_t len);

/* Programs len bytes at offset within block. PMA_ERR_RANGE: outside the block
 * or not aligned to program_size. PMA_ERR_IO: the device failed (power loss). */
int pma_hal_nvm_program(uint32_t block, uint32_t offset, const void *data, uint32_t len);

/* Erases one whole block to 0xFF (may take tens of ms on flash). */
int pma_hal_nvm_erase(uint32_t block);

/* ------------------------------------------------------------ watchdog -- */

typedef enum pma_reset_cause {
    PMA_RESET_UNKNOWN = 0,
    PMA_RESET_POWER_ON = 1,
    PMA_RESET_WATCHDOG = 2,
    PMA_RESET_SOFTWARE = 3,          /* software-requested reset */
    PMA_RESET_PIN = 4,               /* external reset pin */
    PMA_RESET_BROWNOUT = 5,
} pma_reset_cause_t;

/* Starts the watchdog: the program is reset when more than timeout_ms pass
 * without pma_hal_watchdog_kick(). Once started it cannot be stopped; calling
 * again changes the timeout (and kicks). PMA_ERR_RANGE: 0 or beyond what the
 * hardware can count (documented by the port). */
int pma_hal_watchdog_start(uint32_t timeout_ms);

/* Restarts the watchdog timeout; does nothing when it was not started. */
void pma_hal_watchdog_kick(void);

/* Why the program last started (latched at start-up). */
pma_reset_cause_t pma_hal_reset_cause(void);

/* --------------------------------------------------------------- reset -- */

/* Longest wait of pma_hal_system_reset() for queued CAN frames to leave. */
#define PMA_HAL_RESET_TX_FLUSH_US 20000u

/* A software reset of the program: waits until the CAN frames already queued
 * by pma_hal_can_send() have left (at most PMA_HAL_RESET_TX_FLUSH_US: a
 * bus-off controller sends nothing), then restarts the program from the
 * beginning, as a reset would; pma_hal_reset_cause() then reads
 * PMA_RESET_SOFTWARE. A port that can reset does not return (the board: the
 * Cortex-M system reset; the Linux port: it re-executes the program with the
 * argv given at pma_hal_init(), or exits with PMA_HAL_LINUX_EXIT_RESET
 * without one). The fake records the request and returns (the test then
 * calls pma_fake_reboot()); the template returns. The caller must have put
 * the output in its safe state first. */
void pma_hal_system_reset(void);

#endif /* PMA_HAL_H */
