/* ADC1 for the position sensor and DAC1 for the pressure command (RM0440
 * sections 21 and 22). Front ends: docs/hardware.md.
 *
 * ADC: PA0 (ADC1_IN1) converted continuously, 92.5 cycles of sampling at
 * 42.5 MHz (HCLK / 4), 16x hardware oversampling shifted right by 4: a mean
 * of 16 conversions as a 12-bit number every 39.5 us, overwriting the
 * previous (OVRMOD), so a read takes the newest without waiting.
 * DAC: PA4 (DAC1_OUT1), 12 bits right-aligned, 0..4095, output buffer OFF: the
 * buffer cannot go below about 0.2 V (nor above VDDA - 0.2 V), which the x3
 * stage would turn into a pressure at "0 kPa"; unbuffered the pin reaches 0 V.
 * Its source impedance (about 15 kOhm) needs a high-impedance load: the
 * op-amp's non-inverting input (docs/hardware.md). */
#include "g4_drivers.h"

#define ADC_VREG_STARTUP_CYCLES (20u * 170u) /* t_ADCVREG_STUP 20 us at 170 MHz */

static uint8_t adc_ready;

int g4_adc_init(void)
{
    adc_ready = 0;
    g4_rmw(g4_io.rcc, G4_RCC_AHB2ENR_OFFSET, 0u,
           G4_RCC_AHB2ENR_ADC12EN_Msk | G4_RCC_AHB2ENR_GPIOAEN_Msk);
    (void)g4_rd(g4_io.rcc, G4_RCC_AHB2ENR_OFFSET);
    g4_gpio_mode(g4_io.gpioa, G4_ADC_PIN, G4_GPIO_MODE_ANALOG);
    g4_rmw(g4_io.adc12_common, G4_ADC12_COMMON_CCR_OFFSET, G4_ADC12_COMMON_CCR_CKMODE_Msk,
           G4_FIELD(G4_ADC_CKMODE_HCLK_DIV4, G4_ADC12_COMMON_CCR_CKMODE));
    /* out of deep power-down, then the regulator on, then wait for it */
    g4_wr(g4_io.adc1, G4_ADC1_CR_OFFSET, 0u);
    g4_wr(g4_io.adc1, G4_ADC1_CR_OFFSET, G4_ADC1_CR_ADVREGEN_Msk);
    g4_cpu_delay_cycles(ADC_VREG_STARTUP_CYCLES);
    /* single-ended calibration (ADEN = 0) */
    g4_wr(g4_io.adc1, G4_ADC1_CR_OFFSET, G4_ADC1_CR_ADVREGEN_Msk | G4_ADC1_CR_ADCAL_Msk);
    if (g4_wait(g4_io.adc1, G4_ADC1_CR_OFFSET, G4_ADC1_CR_ADCAL_Msk, 0u, G4_POLLS_SHORT) != 0) {
        return PMA_ERR_IO;
    }
    g4_wr(g4_io.adc1, G4_ADC1_CFGR_OFFSET,
          G4_ADC1_CFGR_CONT_Msk | G4_ADC1_CFGR_OVRMOD_Msk); /* 12 bits, right-aligned */
    g4_wr(g4_io.adc1, G4_ADC1_CFGR2_OFFSET,
          G4_ADC1_CFGR2_ROVSE_Msk | G4_FIELD(G4_ADC_OVSR_16X, G4_ADC1_CFGR2_OVSR) |
              G4_FIELD(G4_ADC_OVSS_SHIFT4, G4_ADC1_CFGR2_OVSS));
    g4_rmw(g4_io.adc1, G4_ADC1_SMPR1_OFFSET, G4_ADC1_SMPR1_SMP1_Msk,
           G4_FIELD(G4_ADC_SMP_92CYC5, G4_ADC1_SMPR1_SMP1));
    g4_wr(g4_io.adc1, G4_ADC1_SQR1_OFFSET,
          G4_FIELD(0u, G4_ADC1_SQR1_L) | G4_FIELD(G4_ADC_CHANNEL, G4_ADC1_SQR1_SQ1));
    g4_w1c(g4_io.adc1, G4_ADC1_ISR_OFFSET, G4_ADC1_ISR_ADRDY_Msk);
    g4_wr(g4_io.adc1, G4_ADC1_CR_OFFSET, G4_ADC1_CR_ADVREGEN_Msk | G4_ADC1_CR_ADEN_Msk);
    if (g4_wait(g4_io.adc1, G4_ADC1_ISR_OFFSET, G4_ADC1_ISR_ADRDY_Msk, G4_ADC1_ISR_ADRDY_Msk,
                G4_POLLS_SHORT) != 0) {
        return PMA_ERR_IO;
    }
    g4_wr(g4_io.adc1, G4_ADC1_CR_OFFSET,
          G4_ADC1_CR_ADVREGEN_Msk | G4_ADC1_CR_ADEN_Msk | G4_ADC1_CR_ADSTART_Msk);
    /* the first oversampled result, so that a read never returns the reset 0 */
    if (g4_wait(g4_io.adc1, G4_ADC1_ISR_OFFSET, G4_ADC1_ISR_EOC_Msk, G4_ADC1_ISR_EOC_Msk,
                G4_POLLS_SHORT) != 0) {
        return PMA_ERR_IO;
    }
    adc_ready = 1;
    return PMA_OK;
}

int g4_adc_read(uint16_t *raw_counts)
{
    if (raw_counts == NULL) return PMA_ERR_NULL;
    const uint32_t cr = g4_rd(g4_io.adc1, G4_ADC1_CR_OFFSET);
    if (!adc_ready || !(cr & G4_ADC1_CR_ADSTART_Msk) || !(cr & G4_ADC1_CR_ADEN_Msk)) {
        return PMA_ERR_IO; /* the conversions stopped */
    }
    /* reading DR clears EOC; DR keeps the newest result */
    *raw_counts = (uint16_t)(G4_GET(g4_rd(g4_io.adc1, G4_ADC1_DR_OFFSET), G4_ADC1_DR_RDATA) & 0xFFFu);
    return PMA_OK;
}

void g4_adc_stop(void)
{
    adc_ready = 0;
    const uint32_t cr = g4_rd(g4_io.adc1, G4_ADC1_CR_OFFSET);
    if (cr & G4_ADC1_CR_ADSTART_Msk) {
        g4_wr(g4_io.adc1, G4_ADC1_CR_OFFSET,
              G4_ADC1_CR_ADVREGEN_Msk | G4_ADC1_CR_ADEN_Msk | G4_ADC1_CR_ADSTP_Msk);
        (void)g4_wait(g4_io.adc1, G4_ADC1_CR_OFFSET, G4_ADC1_CR_ADSTART_Msk, 0u, G4_POLLS_SHORT);
    }
}

int g4_dac_init(void)
{
    g4_rmw(g4_io.rcc, G4_RCC_AHB2ENR_OFFSET, 0u,
           G4_RCC_AHB2ENR_DAC1EN_Msk | G4_RCC_AHB2ENR_GPIOAEN_Msk);
    (void)g4_rd(g4_io.rcc, G4_RCC_AHB2ENR_OFFSET);
    g4_gpio_mode(g4_io.gpioa, G4_DAC_PIN, G4_GPIO_MODE_ANALOG);
    /* before EN1: HFSEL for an AHB clock above 160 MHz, normal mode with
     * the buffer on, to the pin */
    g4_rmw(g4_io.dac1, G4_DAC1_CR_OFFSET, G4_DAC1_CR_EN1_Msk, 0u);
    g4_wr(g4_io.dac1, G4_DAC1_MCR_OFFSET,
          G4_FIELD(G4_DAC_HFSEL_ABOVE_160MHZ, G4_DAC1_MCR_HFSEL) | G4_FIELD(G4_DAC_MODE_PIN_UNBUFFERED, G4_DAC1_MCR_MODE1));
    g4_wr(g4_io.dac1, G4_DAC1_DHR12R1_OFFSET, 0u); /* 0 V: the regulator's minimum pressure */
    g4_rmw(g4_io.dac1, G4_DAC1_CR_OFFSET, 0u, G4_DAC1_CR_EN1_Msk);
    if (g4_wait(g4_io.dac1, G4_DAC1_SR_OFFSET, G4_DAC1_SR_DAC1RDY_Msk, G4_DAC1_SR_DAC1RDY_Msk,
                G4_POLLS_SHORT) != 0) {
        return PMA_ERR_IO;
    }
    return PMA_OK;
}

int g4_dac_write(uint16_t counts)
{
    if (counts > G4_DAC_MAX_COUNTS) return PMA_ERR_RANGE;
    if (!(g4_rd(g4_io.dac1, G4_DAC1_CR_OFFSET) & G4_DAC1_CR_EN1_Msk)) return PMA_ERR_IO;
    g4_wr(g4_io.dac1, G4_DAC1_DHR12R1_OFFSET, G4_FIELD(counts, G4_DAC1_DHR12R1_DACC1DHR));
    return PMA_OK;
}
