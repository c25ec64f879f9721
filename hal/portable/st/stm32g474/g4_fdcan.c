/* SPDX-License-Identifier: Apache-2.0 */
/* FDCAN1 in classic CAN mode (RM0440 section 44).
 *
 * Pins: PA11 = FDCAN1_RX, PA12 = FDCAN1_TX (AF9), to a 3.3 V transceiver
 * such as the SN65HVD230; build with -DG4_CAN_PINS_PB8_PB9=1 for PB8/PB9
 * (the NUCLEO's Arduino D15/D14). Kernel clock: PCLK1 (170 MHz).
 *
 * Message RAM: the G4's fixed layout (g4_port_defs.h, G4_MRAM_*); the node's
 * filters are classic id + mask standard filters storing into Rx FIFO 0,
 * frames that match none are rejected (no filter: every standard frame is
 * accepted into FIFO 0); extended and remote frames are rejected.
 *
 * Queues: the interrupt (line 0) moves received frames from the 3-element
 * Rx FIFO 0 into a 32-frame ring that pma_hal_can_recv() empties, and frames
 * queued by pma_hal_can_send() from a 16-frame ring into the 3-element Tx
 * FIFO; send pends the interrupt itself, so the interrupt is the only
 * consumer of the TX ring and the only producer of the RX ring.
 *
 * Bus-off: the controller sets CCCR.INIT itself and stays off the bus;
 * g4_can_recover() clears INIT, and the controller rejoins after 129
 * occurrences of 11 recessive bits (PSR.BO then clears, TEC = REC = 0). */
#include "g4_drivers.h"

#include <string.h>

#ifndef G4_CAN_PINS_PB8_PB9
#define G4_CAN_PINS_PB8_PB9 0
#endif

#define CAN_PRIO 2u

typedef struct ring {
    pma_can_frame_t f[G4_CAN_RX_RING];
    volatile uint32_t head, tail;  /* head: producer writes; tail: consumer writes */
} rx_ring_t;

typedef struct tx_ring {
    pma_can_frame_t f[G4_CAN_TX_RING];
    volatile uint32_t head, tail;
} tx_ring_t;

static rx_ring_t rx;
static tx_ring_t tx;
static volatile uint32_t rx_overruns;
static uint8_t can_up;

_Static_assert((G4_CAN_RX_RING & (G4_CAN_RX_RING - 1u)) == 0, "ring sizes: powers of two");
_Static_assert((G4_CAN_TX_RING & (G4_CAN_TX_RING - 1u)) == 0, "ring sizes: powers of two");

/* ------------------------------------------------------------ bit timing -- */

int g4_can_timing_for(uint32_t kernel_hz, uint32_t bitrate_bps, g4_can_timing_t *t)
{
    if (t == NULL) return PMA_ERR_NULL;
    if (bitrate_bps == 0u || kernel_hz == 0u) return PMA_ERR_RANGE;
    /* sample point in tenths of a percent */
    const uint32_t sp_permille = bitrate_bps >= 800000u ? 800u : 875u;
    for (uint32_t presc = 1u; presc <= 512u; ++presc) {
        const uint64_t div = (uint64_t)presc * bitrate_bps;
        if (kernel_hz % div != 0u) continue;
        const uint32_t tq = (uint32_t)(kernel_hz / div);
        if (tq < 8u || tq > 25u) continue;
        /* sync (1 tq) + tseg1 = the time quanta before the sample point */
        uint32_t before = (tq * sp_permille + 500u) / 1000u;
        if (before > tq - 2u) before = tq - 2u; /* tseg2 >= 2 */
        const uint32_t tseg1 = before - 1u;
        const uint32_t tseg2 = tq - before;
        *t = (g4_can_timing_t){.prescaler = presc, .tseg1_tq = tseg1, .tseg2_tq = tseg2,
                               .sjw_tq = tseg2 < 4u ? tseg2 : 4u};
        return PMA_OK;
    }
    return PMA_ERR_RANGE;
}

uint32_t g4_nbtp_value(const g4_can_timing_t *t)
{
    /* every field holds its value minus one */
    return _VAL2FLD(FDCAN_NBTP_NSJW, t->sjw_tq - 1u) | _VAL2FLD(FDCAN_NBTP_NBRP, t->prescaler - 1u) |
           _VAL2FLD(FDCAN_NBTP_NTSEG1, t->tseg1_tq - 1u) |
           _VAL2FLD(FDCAN_NBTP_NTSEG2, t->tseg2_tq - 1u);
}

/* ------------------------------------------------------------ init mode -- */

static int enter_init(void)
{
    FDCAN_GlobalTypeDef *const can = g4_io.fdcan1;
    SET_BIT(can->CCCR, FDCAN_CCCR_INIT);
    if (g4_wait(&can->CCCR, FDCAN_CCCR_INIT, FDCAN_CCCR_INIT, G4_POLLS_SHORT) != 0) {
        return PMA_ERR_IO;
    }
    SET_BIT(can->CCCR, FDCAN_CCCR_CCE);
    return PMA_OK;
}

static int leave_init(void)
{
    FDCAN_GlobalTypeDef *const can = g4_io.fdcan1;
    CLEAR_BIT(can->CCCR, FDCAN_CCCR_CCE | FDCAN_CCCR_INIT);
    return g4_wait(&can->CCCR, FDCAN_CCCR_INIT, 0u, G4_POLLS_SHORT) == 0 ? PMA_OK : PMA_ERR_IO;
}

static void mram_wr(uint32_t offset, uint32_t value)
{
    g4_io.mram[offset / 4u] = value;
}

/* Filters and RXGFC; the controller must be in INIT with CCE. */
static void program_filters(const pma_can_filter_t *filters, size_t count)
{
    for (uint32_t i = 0; i < G4_MRAM_STD_FILTERS; ++i) {
        uint32_t s0 = 0u; /* SFT 0 with SFEC 0: disabled */
        if (i < count) {
            s0 = (G4_MRAM_SFT_CLASSIC << G4_MRAM_SFT_SHIFT) |
                 (G4_MRAM_SFEC_FIFO0 << G4_MRAM_SFEC_SHIFT) |
                 ((uint32_t)(filters[i].id & PMA_CAN_ID_MAX) << G4_MRAM_SFID1_SHIFT) |
                 ((uint32_t)(filters[i].mask & PMA_CAN_ID_MAX) << G4_MRAM_SFID2_SHIFT);
        }
        mram_wr(G4_MRAM_FLSSA + 4u * i, s0);
    }
    const uint32_t anfs = count == 0u ? G4_FDCAN_ANF_FIFO0 : G4_FDCAN_ANF_REJECT;
    WRITE_REG(g4_io.fdcan1->RXGFC,
              _VAL2FLD(FDCAN_RXGFC_LSS, count) | _VAL2FLD(FDCAN_RXGFC_LSE, 0u) |
                  _VAL2FLD(FDCAN_RXGFC_ANFS, anfs) |
                  _VAL2FLD(FDCAN_RXGFC_ANFE, G4_FDCAN_ANF_REJECT) | FDCAN_RXGFC_RRFS |
                  FDCAN_RXGFC_RRFE);
}

int g4_can_init(uint32_t kernel_hz, uint32_t bitrate_bps)
{
    can_up = 0;
    g4_can_timing_t t;
    int rc = g4_can_timing_for(kernel_hz, bitrate_bps, &t);
    if (rc != PMA_OK) return rc;
    g4_nvic_disable(FDCAN1_IT0_IRQn);

    RCC_TypeDef *const rcc = g4_io.rcc;
    FDCAN_GlobalTypeDef *const can = g4_io.fdcan1;
    SET_BIT(rcc->APB1ENR1, RCC_APB1ENR1_FDCANEN);
    MODIFY_REG(rcc->CCIPR, RCC_CCIPR_FDCANSEL,
               _VAL2FLD(RCC_CCIPR_FDCANSEL, G4_RCC_CCIPR_FDCANSEL_PCLK1));
    if (G4_CAN_PINS_PB8_PB9) {
        SET_BIT(rcc->AHB2ENR, RCC_AHB2ENR_GPIOBEN);
        (void)READ_REG(rcc->AHB2ENR);
        g4_gpio_af(g4_io.gpiob, 8u, G4_GPIO_AF9_FDCAN1);
        g4_gpio_af(g4_io.gpiob, 9u, G4_GPIO_AF9_FDCAN1);
    } else {
        SET_BIT(rcc->AHB2ENR, RCC_AHB2ENR_GPIOAEN);
        (void)READ_REG(rcc->AHB2ENR);
        g4_gpio_af(g4_io.gpioa, 11u, G4_GPIO_AF9_FDCAN1);
        g4_gpio_af(g4_io.gpioa, 12u, G4_GPIO_AF9_FDCAN1);
    }

    rc = enter_init();
    if (rc != PMA_OK) return rc;
    /* classic CAN: no FD frames, no bit rate switch, automatic retransmission */
    CLEAR_BIT(can->CCCR, FDCAN_CCCR_FDOE | FDCAN_CCCR_BRSE | FDCAN_CCCR_DAR);
    WRITE_REG(g4_io.fdcan_config->CKDIV, _VAL2FLD(FDCAN_CKDIV_PDIV, 0u)); /* kernel clock /1 */
    WRITE_REG(can->NBTP, g4_nbtp_value(&t));
    for (uint32_t off = 0; off < G4_MRAM_SIZE; off += 4u) mram_wr(off, 0u);
    program_filters(NULL, 0u);
    WRITE_REG(can->TXBC, 0u); /* TFQM 0: FIFO, frames leave in order */
    /* interrupts: new frame in FIFO 0, FIFO 0 frame lost, Tx FIFO empty; all on line 0 */
    g4_w1c(&can->IR, 0xFFFFFFu);
    WRITE_REG(can->ILS, 0u);
    WRITE_REG(can->IE, FDCAN_IE_RF0NE | FDCAN_IE_RF0LE | FDCAN_IE_TFEE);
    WRITE_REG(can->ILE, FDCAN_ILE_EINT0);

    rx.head = rx.tail = 0u;
    tx.head = tx.tail = 0u;
    rx_overruns = 0u;
    rc = leave_init();
    if (rc != PMA_OK) return rc;
    can_up = 1;
    g4_nvic_enable(FDCAN1_IT0_IRQn, CAN_PRIO);
    return PMA_OK;
}

void g4_can_stop(void)
{
    can_up = 0;
    g4_nvic_disable(FDCAN1_IT0_IRQn);
    SET_BIT(g4_io.fdcan1->CCCR, FDCAN_CCCR_INIT);
}

int g4_can_set_filters(const pma_can_filter_t *filters, size_t count)
{
    if (!can_up) return PMA_ERR_NOT_READY;
    if (count > PMA_CAN_FILTERS_MAX) return PMA_ERR_RANGE;
    if (count > 0u && filters == NULL) return PMA_ERR_NULL;
    for (size_t i = 0; i < count; ++i) {
        if (filters[i].id > PMA_CAN_ID_MAX || filters[i].mask > PMA_CAN_ID_MAX) return PMA_ERR_RANGE;
    }
    /* RXGFC is writable only in INIT with CCE: a frame on the bus right now
     * may be missed; frames already in the ring stay */
    int rc = enter_init();
    if (rc == PMA_OK) {
        program_filters(filters, count);
        rc = leave_init();
    }
    return rc;
}

/* ---------------------------------------------------------------- queues -- */

int g4_can_send(const pma_can_frame_t *frame)
{
    if (frame == NULL) return PMA_ERR_NULL;
    if (!can_up) return PMA_ERR_NOT_READY;
    if (frame->id > PMA_CAN_ID_MAX || frame->dlc > PMA_CAN_DLC_MAX) return PMA_ERR_RANGE;
    if (READ_BIT(g4_io.fdcan1->PSR, FDCAN_PSR_BO)) return PMA_ERR_BUS_OFF;
    const uint32_t head = tx.head;
    if (head - tx.tail >= G4_CAN_TX_RING) return PMA_ERR_FULL;
    tx.f[head % G4_CAN_TX_RING] = *frame;
    tx.head = head + 1u;
    g4_nvic_set_pending(FDCAN1_IT0_IRQn); /* the interrupt hands it to the controller */
    return PMA_OK;
}

int g4_can_tx_idle(void)
{
    if (!can_up || READ_BIT(g4_io.fdcan1->CCCR, FDCAN_CCCR_INIT)) return 1; /* off the bus: sends nothing */
    return tx.tail == tx.head && READ_REG(g4_io.fdcan1->TXBRP) == 0u;
}

int g4_can_recv(pma_can_frame_t *frame)
{
    if (frame == NULL) return PMA_ERR_NULL;
    if (!can_up) return PMA_ERR_NOT_READY;
    const uint32_t tail = rx.tail;
    if (tail == rx.head) return PMA_ERR_EMPTY;
    *frame = rx.f[tail % G4_CAN_RX_RING];
    rx.tail = tail + 1u;
    return PMA_OK;
}

static void rx_take(void)
{
    FDCAN_GlobalTypeDef *const can = g4_io.fdcan1;
    const uint32_t fill = _FLD2VAL(FDCAN_RXF0S_F0FL, READ_REG(can->RXF0S));
    /* at most the fill level seen once: each acknowledge frees one element */
    for (uint32_t k = 0; k < fill && k < G4_MRAM_RX_FIFO_ELEMENTS; ++k) {
        const uint32_t gi = _FLD2VAL(FDCAN_RXF0S_F0GI, READ_REG(can->RXF0S));
        const volatile uint32_t *el = &g4_io.mram[(G4_MRAM_F0SA + gi * G4_MRAM_ELEMENT_BYTES) / 4u];
        const uint32_t r0 = el[0], r1 = el[1], d0 = el[2], d1 = el[3];
        WRITE_REG(can->RXF0A, _VAL2FLD(FDCAN_RXF0A_F0AI, gi));
        if (r0 & (G4_MRAM_W0_XTD | G4_MRAM_W0_RTR)) continue; /* filtered out already */
        if (r1 & G4_MRAM_W1_FDF) continue;                     /* never with FDOE = 0 */
        const uint32_t head = rx.head;
        if (head - rx.tail >= G4_CAN_RX_RING) {
            rx_overruns = rx_overruns + 1u;
            continue;
        }
        pma_can_frame_t *f = &rx.f[head % G4_CAN_RX_RING];
        f->id = (uint16_t)((r0 >> G4_MRAM_W0_STDID_SHIFT) & PMA_CAN_ID_MAX);
        const uint32_t dlc = (r1 >> G4_MRAM_W1_DLC_SHIFT) & 0xFu;
        f->dlc = (uint8_t)(dlc > 8u ? 8u : dlc); /* classic: DLC 9..15 still mean 8 bytes */
        for (uint32_t b = 0; b < 4u; ++b) {
            f->data[b] = (uint8_t)(d0 >> (8u * b));
            f->data[4u + b] = (uint8_t)(d1 >> (8u * b));
        }
        rx.head = head + 1u;
    }
}

static void tx_give(void)
{
    const uint32_t txfqs = READ_REG(g4_io.fdcan1->TXFQS);
    if (txfqs & FDCAN_TXFQS_TFQF) return;
    const uint32_t free_slots = _FLD2VAL(FDCAN_TXFQS_TFFL, txfqs);
    const uint32_t put = _FLD2VAL(FDCAN_TXFQS_TFQPI, txfqs);
    uint32_t added = 0u;
    /* the put index advances by one per add request (FIFO mode) */
    for (uint32_t k = 0; k < free_slots && tx.tail != tx.head; ++k) {
        const pma_can_frame_t *f = &tx.f[tx.tail % G4_CAN_TX_RING];
        const uint32_t idx = (put + k) % G4_MRAM_TX_ELEMENTS;
        const uint32_t el = G4_MRAM_TBSA + idx * G4_MRAM_ELEMENT_BYTES;
        uint32_t d0 = 0u, d1 = 0u;
        for (uint32_t b = 0; b < 4u; ++b) {
            d0 |= (uint32_t)f->data[b] << (8u * b);
            d1 |= (uint32_t)f->data[4u + b] << (8u * b);
        }
        mram_wr(el, (uint32_t)f->id << G4_MRAM_W0_STDID_SHIFT);
        mram_wr(el + 4u, (uint32_t)f->dlc << G4_MRAM_W1_DLC_SHIFT);
        mram_wr(el + 8u, d0);
        mram_wr(el + 12u, d1);
        added |= 1u << idx;
        tx.tail = tx.tail + 1u;
    }
    if (added != 0u) WRITE_REG(g4_io.fdcan1->TXBAR, added);
}

void g4_can_isr(void)
{
    const uint32_t ir = READ_REG(g4_io.fdcan1->IR);
    g4_w1c(&g4_io.fdcan1->IR, ir); /* what is handled now */
    if (ir & FDCAN_IR_RF0L) rx_overruns = rx_overruns + 1u; /* the 3-frame FIFO overflowed */
    rx_take();
    if (!READ_BIT(g4_io.fdcan1->CCCR, FDCAN_CCCR_INIT)) tx_give();
}

/* --------------------------------------------------------------- status -- */

int g4_can_status(pma_can_status_t *st)
{
    if (st == NULL) return PMA_ERR_NULL;
    if (!can_up) return PMA_ERR_NOT_READY;
    const uint32_t ecr = READ_REG(g4_io.fdcan1->ECR);
    const uint32_t psr = READ_REG(g4_io.fdcan1->PSR);
    st->tec = (uint16_t)_FLD2VAL(FDCAN_ECR_TEC, ecr);
    /* REC is 7 bits; RP says it has reached the error-passive level 128 */
    st->rec = (uint16_t)(_FLD2VAL(FDCAN_ECR_REC, ecr) | ((ecr & FDCAN_ECR_RP) ? 128u : 0u));
    st->rx_overruns = rx_overruns;
    if (psr & FDCAN_PSR_BO) {
        st->state = PMA_CAN_BUS_OFF;
        st->tec = 256u;
    } else if (psr & FDCAN_PSR_EP) {
        st->state = PMA_CAN_ERROR_PASSIVE;
    } else {
        st->state = PMA_CAN_ERROR_ACTIVE;
    }
    return PMA_OK;
}

int g4_can_recover(void)
{
    if (!can_up) return PMA_ERR_NOT_READY;
    if (!READ_BIT(g4_io.fdcan1->PSR, FDCAN_PSR_BO)) return PMA_OK;
    /* the controller set INIT when it went bus-off; clearing it starts the
     * recovery sequence. Frames still in the TX ring are kept. */
    CLEAR_BIT(g4_io.fdcan1->CCCR, FDCAN_CCCR_CCE | FDCAN_CCCR_INIT);
    return PMA_OK;
}
