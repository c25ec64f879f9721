/* SPDX-License-Identifier: Apache-2.0 */
/* Fake port: a CAN controller (RX queue, TX queue, acceptance filters, ISO
 * 11898-1 fault confinement with bus-off recovery) on a bus the test plays:
 * it injects received frames and pops the transmitted ones from a log. */
#include "fake_internal.h"

#include <string.h>

#define BUS_OFF_TEC 256u

/* Fixed-capacity frame FIFO over caller storage. */
typedef struct frame_fifo {
    pma_can_frame_t *slot;
    uint32_t capacity;
    uint32_t head;               /* oldest */
    uint32_t count;
} frame_fifo_t;

static pma_can_frame_t rx_mem[PMA_FAKE_CAN_RX_DEPTH];
static pma_can_frame_t txq_mem[PMA_FAKE_CAN_TX_QUEUE_DEPTH];
static pma_can_frame_t log_mem[PMA_FAKE_CAN_TX_LOG_DEPTH];

static struct {
    /* the controller (reset by pma_hal_init) */
    frame_fifo_t rx, txq;
    pma_can_filter_t filters[PMA_CAN_FILTERS_MAX];
    uint32_t filter_count;       /* 0: accept all */
    uint16_t tec, rec;
    uint32_t rx_overruns;
    bool recovery_requested;
    uint64_t recovery_due_us;
    uint32_t bitrate_bps;
    /* the bus (the test's side; survives MCU restarts) */
    frame_fifo_t log;
    uint32_t log_overwritten;
    bool tx_blocked, bus_errors, recovery_blocked;
    uint32_t recovery_delay_us;
    uint32_t drop[2], dup[2];    /* indexed by pma_fake_can_dir_t */
} can = {
    .rx = {rx_mem, PMA_FAKE_CAN_RX_DEPTH, 0, 0},
    .txq = {txq_mem, PMA_FAKE_CAN_TX_QUEUE_DEPTH, 0, 0},
    .log = {log_mem, PMA_FAKE_CAN_TX_LOG_DEPTH, 0, 0},
    .bitrate_bps = PMA_HAL_CAN_DEFAULT_BITRATE_BPS,
};

static bool fifo_push(frame_fifo_t *f, const pma_can_frame_t *frame)
{
    if (f->count == f->capacity) return false;
    /* head < capacity and count < capacity: one subtraction wraps it (no division, which the
     * Cortex-M0 does in a library routine: the fake's cost stays out of the tick's benchmark) */
    uint32_t at = f->head + f->count;
    if (at >= f->capacity) at -= f->capacity;
    f->slot[at] = *frame;
    f->count++;
    return true;
}

static bool fifo_pop(frame_fifo_t *f, pma_can_frame_t *frame)
{
    if (f->count == 0) return false;
    *frame = f->slot[f->head];
    f->head = f->head + 1u == f->capacity ? 0u : f->head + 1u;
    f->count--;
    return true;
}

static void fifo_clear(frame_fifo_t *f)
{
    f->head = 0;
    f->count = 0;
}

void pma_fake_can_reset_(pma_fake_reset_depth_t depth, uint32_t bitrate_bps)
{
    fifo_clear(&can.rx);
    fifo_clear(&can.txq);
    can.filter_count = 0;
    can.tec = 0;
    can.rec = 0;
    can.rx_overruns = 0;
    can.recovery_requested = false;
    can.bitrate_bps = bitrate_bps;
    if (depth < PMA_FAKE_RESET_ALL) return;
    fifo_clear(&can.log);
    can.log_overwritten = 0;
    can.tx_blocked = false;
    can.bus_errors = false;
    can.recovery_blocked = false;
    can.recovery_delay_us = 0;
    memset(can.drop, 0, sizeof can.drop);
    memset(can.dup, 0, sizeof can.dup);
}

static bool bus_off(void)
{
    return can.tec >= BUS_OFF_TEC;
}

static void enter_bus_off(void)
{
    can.tec = BUS_OFF_TEC;
    can.recovery_requested = false;
    fifo_clear(&can.txq); /* a bus-off controller abandons its pending frames */
}

/* Completes a requested recovery once it is due (time only moves forward). */
static void update(void)
{
    if (can.recovery_requested && !can.recovery_blocked &&
        pma_hal_time_us() >= can.recovery_due_us) {
        can.recovery_requested = false;
        can.tec = 0;
        can.rec = 0;
    }
}

static bool frame_valid(const pma_can_frame_t *frame)
{
    return frame->id <= PMA_CAN_ID_MAX && frame->dlc <= PMA_CAN_DLC_MAX;
}

static bool filters_accept(uint16_t id)
{
    if (can.filter_count == 0) return true;
    for (uint32_t i = 0; i < can.filter_count; ++i) {
        const pma_can_filter_t *f = &can.filters[i];
        if ((id & f->mask) == (f->id & f->mask)) return true;
    }
    return false;
}

/* True (and one consumed) when the next frame in `dir` is to be lost / doubled. */
static bool take(uint32_t *counter)
{
    if (*counter == 0) return false;
    (*counter)--;
    return true;
}

static void log_push(const pma_can_frame_t *frame)
{
    if (can.log.count == can.log.capacity) {
        pma_can_frame_t oldest;
        (void)fifo_pop(&can.log, &oldest);
        can.log_overwritten++;
    }
    (void)fifo_push(&can.log, frame);
}

/* A frame leaves the controller and is acknowledged on the bus. */
static void transmit(const pma_can_frame_t *frame)
{
    if (can.tec > 0) can.tec--;
    if (take(&can.drop[PMA_FAKE_CAN_TX])) return;
    log_push(frame);
    if (take(&can.dup[PMA_FAKE_CAN_TX])) log_push(frame);
}

int pma_hal_can_send(const pma_can_frame_t *frame)
{
    if (frame == NULL) return PMA_ERR_NULL;
    if (!pma_fake_initialised()) return PMA_ERR_NOT_READY;
    if (!frame_valid(frame)) return PMA_ERR_RANGE;
    update();
    if (bus_off()) return PMA_ERR_BUS_OFF;
    if (can.tx_blocked) return fifo_push(&can.txq, frame) ? PMA_OK : PMA_ERR_FULL;
    if (can.bus_errors) {
        can.tec = (uint16_t)(can.tec + 8u);
        if (can.tec >= BUS_OFF_TEC) enter_bus_off();
        return PMA_OK; /* queued as far as the firmware can tell */
    }
    transmit(frame);
    return PMA_OK;
}

int pma_hal_can_recv(pma_can_frame_t *frame)
{
    if (frame == NULL) return PMA_ERR_NULL;
    if (!pma_fake_initialised()) return PMA_ERR_NOT_READY;
    update();
    return fifo_pop(&can.rx, frame) ? PMA_OK : PMA_ERR_EMPTY;
}

int pma_hal_can_set_filters(const pma_can_filter_t *filters, size_t count)
{
    if (!pma_fake_initialised()) return PMA_ERR_NOT_READY;
    if (count > PMA_CAN_FILTERS_MAX) return PMA_ERR_RANGE;
    if (count > 0 && filters == NULL) return PMA_ERR_NULL;
    for (size_t i = 0; i < count; ++i) {
        if (filters[i].id > PMA_CAN_ID_MAX || filters[i].mask > PMA_CAN_ID_MAX) {
            return PMA_ERR_RANGE;
        }
    }
    for (size_t i = 0; i < count; ++i) can.filters[i] = filters[i];
    can.filter_count = (uint32_t)count;
    return PMA_OK;
}

int pma_hal_can_status(pma_can_status_t *status)
{
    if (status == NULL) return PMA_ERR_NULL;
    if (!pma_fake_initialised()) return PMA_ERR_NOT_READY;
    update();
    status->tec = can.tec;
    status->rec = can.rec;
    status->rx_overruns = can.rx_overruns;
    if (bus_off()) {
        status->state = PMA_CAN_BUS_OFF;
    } else if (can.tec > 127u || can.rec > 127u) {
        status->state = PMA_CAN_ERROR_PASSIVE;
    } else {
        status->state = PMA_CAN_ERROR_ACTIVE;
    }
    return PMA_OK;
}

int pma_hal_can_recover(void)
{
    if (!pma_fake_initialised()) return PMA_ERR_NOT_READY;
    update();
    if (bus_off() && !can.recovery_requested) {
        can.recovery_requested = true;
        can.recovery_due_us = pma_hal_time_us() + can.recovery_delay_us;
        update(); /* delay 0: done at once */
    }
    return PMA_OK;
}

/* ------------------------------------------------------- the test's side -- */

int pma_fake_can_inject(const pma_can_frame_t *frame)
{
    if (frame == NULL) return PMA_ERR_NULL;
    if (!pma_fake_initialised()) return PMA_ERR_NOT_READY;
    if (!frame_valid(frame)) return PMA_ERR_RANGE;
    update();
    if (bus_off()) return PMA_ERR_BUS_OFF;
    if (take(&can.drop[PMA_FAKE_CAN_RX])) return PMA_FAKE_CAN_DROPPED;
    /* a correct reception lowers REC, from error-passive back to 119 (ISO 11898-1) */
    if (can.rec > 127u) {
        can.rec = 119u;
    } else if (can.rec > 0) {
        can.rec--;
    }
    if (!filters_accept(frame->id)) return PMA_FAKE_CAN_FILTERED;
    const int copies = take(&can.dup[PMA_FAKE_CAN_RX]) ? 2 : 1;
    int rc = PMA_OK;
    for (int i = 0; i < copies; ++i) {
        if (!fifo_push(&can.rx, frame)) {
            can.rx_overruns++;
            rc = PMA_ERR_FULL;
        }
    }
    return rc;
}

uint32_t pma_fake_can_rx_pending(void)
{
    return can.rx.count;
}

int pma_fake_can_tx_pop(pma_can_frame_t *frame)
{
    if (frame == NULL) return PMA_ERR_NULL;
    return fifo_pop(&can.log, frame) ? PMA_OK : PMA_ERR_EMPTY;
}

uint32_t pma_fake_can_tx_pending(void)
{
    return can.log.count;
}

uint32_t pma_fake_can_tx_overwritten(void)
{
    return can.log_overwritten;
}

void pma_fake_can_block_tx(bool blocked)
{
    can.tx_blocked = blocked;
    if (blocked) return;
    pma_can_frame_t frame;
    while (fifo_pop(&can.txq, &frame)) transmit(&frame);
}

void pma_fake_can_drop(pma_fake_can_dir_t dir, uint32_t n)
{
    can.drop[dir == PMA_FAKE_CAN_TX ? 1 : 0] = n;
}

void pma_fake_can_duplicate(pma_fake_can_dir_t dir, uint32_t n)
{
    can.dup[dir == PMA_FAKE_CAN_TX ? 1 : 0] = n;
}

void pma_fake_can_set_error_counters(uint16_t tec, uint16_t rec)
{
    can.rec = rec;
    if (tec >= BUS_OFF_TEC) {
        enter_bus_off();
    } else {
        can.tec = tec;
        can.recovery_requested = false;
    }
}

void pma_fake_can_bus_errors(bool on)
{
    can.bus_errors = on;
}

void pma_fake_can_set_recovery(uint32_t delay_us, bool blocked)
{
    can.recovery_delay_us = delay_us;
    can.recovery_blocked = blocked;
}

uint32_t pma_fake_can_bitrate_bps(void)
{
    return can.bitrate_bps;
}
