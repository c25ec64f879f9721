/* SPDX-License-Identifier: Apache-2.0 */
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
    ADC_TypeDef *const adc = g4_io.adc1;
    adc_ready = 0;
    SET_BIT(g4_io.rcc->AHB2ENR, RCC_AHB2ENR_ADC12EN | RCC_AHB2ENR_GPIOAEN);
    (void)READ_REG(g4_io.rcc->AHB2ENR);
    g4_gpio_mode(g4_io.gpioa, G4_ADC_PIN, G4_GPIO_MODE_ANALOG);
    MODIFY_REG(g4_io.adc12_common->CCR, ADC_CCR_CKMODE,
               _VAL2FLD(ADC_CCR_CKMODE, G4_ADC_CKMODE_HCLK_DIV4));
    /* out of deep power-down, then the regulator on, then wait for it */
    WRITE_REG(adc->CR, 0u);
    WRITE_REG(adc->CR, ADC_CR_ADVREGEN);
    g4_cpu_delay_cycles(ADC_VREG_STARTUP_CYCLES);
    /* single-ended calibration (ADEN = 0) */
    WRITE_REG(adc->CR, ADC_CR_ADVREGEN | ADC_CR_ADCAL);
    if (g4_wait(&adc->CR, ADC_CR_ADCAL, 0u, G4_POLLS_SHORT) != 0) return PMA_ERR_IO;
    WRITE_REG(adc->CFGR, ADC_CFGR_CONT | ADC_CFGR_OVRMOD); /* 12 bits, right-aligned */
    WRITE_REG(adc->CFGR2, ADC_CFGR2_ROVSE | _VAL2FLD(ADC_CFGR2_OVSR, G4_ADC_OVSR_16X) |
                              _VAL2FLD(ADC_CFGR2_OVSS, G4_ADC_OVSS_SHIFT4));
    MODIFY_REG(adc->SMPR1, ADC_SMPR1_SMP1, _VAL2FLD(ADC_SMPR1_SMP1, G4_ADC_SMP_92CYC5));
    WRITE_REG(adc->SQR1, _VAL2FLD(ADC_SQR1_L, 0u) | _VAL2FLD(ADC_SQR1_SQ1, G4_ADC_CHANNEL));
    g4_w1c(&adc->ISR, ADC_ISR_ADRDY);
    WRITE_REG(adc->CR, ADC_CR_ADVREGEN | ADC_CR_ADEN);
    if (g4_wait(&adc->ISR, ADC_ISR_ADRDY, ADC_ISR_ADRDY, G4_POLLS_SHORT) != 0) return PMA_ERR_IO;
    WRITE_REG(adc->CR, ADC_CR_ADVREGEN | ADC_CR_ADEN | ADC_CR_ADSTART);
    /* the first oversampled result, so that a read never returns the reset 0 */
    if (g4_wait(&adc->ISR, ADC_ISR_EOC, ADC_ISR_EOC, G4_POLLS_SHORT) != 0) return PMA_ERR_IO;
    adc_ready = 1;
    return PMA_OK;
}

int g4_adc_read(uint16_t *raw_counts)
{
    if (raw_counts == NULL) return PMA_ERR_NULL;
    const uint32_t cr = READ_REG(g4_io.adc1->CR);
    if (!adc_ready || !(cr & ADC_CR_ADSTART) || !(cr & ADC_CR_ADEN)) {
        return PMA_ERR_IO; /* the conversions stopped */
    }
    /* reading DR clears EOC; DR keeps the newest result */
    *raw_counts = (uint16_t)(_FLD2VAL(ADC_DR_RDATA, READ_REG(g4_io.adc1->DR)) & 0xFFFu);
    return PMA_OK;
}

void g4_adc_stop(void)
{
    ADC_TypeDef *const adc = g4_io.adc1;
    adc_ready = 0;
    const uint32_t cr = READ_REG(adc->CR);
    if (cr & ADC_CR_ADSTART) {
        WRITE_REG(adc->CR, ADC_CR_ADVREGEN | ADC_CR_ADEN | ADC_CR_ADSTP);
        (void)g4_wait(&adc->CR, ADC_CR_ADSTART, 0u, G4_POLLS_SHORT);
    }
}

int g4_dac_init(void)
{
    DAC_TypeDef *const dac = g4_io.dac1;
    SET_BIT(g4_io.rcc->AHB2ENR, RCC_AHB2ENR_DAC1EN | RCC_AHB2ENR_GPIOAEN);
    (void)READ_REG(g4_io.rcc->AHB2ENR);
    g4_gpio_mode(g4_io.gpioa, G4_DAC_PIN, G4_GPIO_MODE_ANALOG);
    /* before EN1: HFSEL for an AHB clock above 160 MHz, normal mode with
     * the buffer off, to the pin */
    CLEAR_BIT(dac->CR, DAC_CR_EN1);
    WRITE_REG(dac->MCR, _VAL2FLD(DAC_MCR_HFSEL, G4_DAC_HFSEL_ABOVE_160MHZ) |
                            _VAL2FLD(DAC_MCR_MODE1, G4_DAC_MODE_PIN_UNBUFFERED));
    WRITE_REG(dac->DHR12R1, 0u); /* 0 V: the regulator's minimum pressure */
    SET_BIT(dac->CR, DAC_CR_EN1);
    if (g4_wait(&dac->SR, DAC_SR_DAC1RDY, DAC_SR_DAC1RDY, G4_POLLS_SHORT) != 0) return PMA_ERR_IO;
    return PMA_OK;
}

int g4_dac_write(uint16_t counts)
{
    if (counts > G4_DAC_MAX_COUNTS) return PMA_ERR_RANGE;
    if (!READ_BIT(g4_io.dac1->CR, DAC_CR_EN1)) return PMA_ERR_IO;
    WRITE_REG(g4_io.dac1->DHR12R1, _VAL2FLD(DAC_DHR12R1_DACC1DHR, counts));
    return PMA_OK;
}
