/* SPDX-License-Identifier: Apache-2.0 */
/* Scaling between converter counts and physical units: pure functions, the
 * same for every port. They are the application's policy (the HAL deals in
 * counts only: pma_hal_adc_read(), pma_hal_dac_write()). The scaling values
 * come from the sensor's and regulator's data sheets and the board's
 * analogue front end; they are parameters of the application.
 *
 * Position sensor (ADC): a laser displacement sensor with a 4-20 mA or 0-10 V
 * output. Its output falls to the bottom of the scale (0 mA / 0 V, below the
 * 4 mA live zero) when a wire breaks or it loses power, so samples below a
 * wire-break level are reported as such, separately from "out of range".
 *
 *   x_cm = offset_cm + gain_cm_per_count * raw_counts
 *
 * Example: 4-20 mA over 165 ohm into a 12-bit 3.3 V ADC (4 mA = 819 counts,
 * 20 mA = 4095), sensor range 0-10 cm: gain = 10/3276 cm/count,
 * offset = -819 gain = -2.5 cm. By NAMUR NE 43 a current below 3.6 mA
 * (737 counts) is a sensor failure and from 3.8 mA (778 counts) it is usable;
 * 4095 means the ADC clipped (over range): wire_break_below_counts = 737,
 * raw_min_counts = 778, raw_max_counts = 4094.
 *
 * Pressure command (DAC): an electro-pneumatic regulator with a 0-10 V or
 * 4-20 mA set-point input.
 *
 *   counts = clamp(round(counts_at_zero_kpa + counts_per_kpa * p_kpa),
 *                  min_counts, max_counts)
 *
 * It saturates: a pressure beyond the range gives the nearest end of
 * [min_counts, max_counts]; the application limits pressure in kPa before
 * (actuator limits), this clamp is the last line of defence. Example:
 * 0-600 kPa regulator on a 12-bit DAC scaled to 0-10 V: counts_at_zero_kpa = 0,
 * counts_per_kpa = 4095/600, min_counts = 0, max_counts = 4095. */
#ifndef PMA_SCALING_H
#define PMA_SCALING_H

#include <stdint.h>

typedef struct pma_adc_scaling {
    float offset_cm;                  /* position at 0 counts (finite) */
    float gain_cm_per_count;          /* finite, != 0 (negative: sensor mounted inverted) */
    uint16_t raw_min_counts;          /* smallest valid sample */
    uint16_t raw_max_counts;          /* largest valid sample, >= raw_min_counts */
    uint16_t wire_break_below_counts; /* samples below this: wire break; <= raw_min_counts;
                                         0 disables the check (0-10 V sensors without live zero) */
} pma_adc_scaling_t;

/* PMA_OK, PMA_ERR_NULL, PMA_ERR_NOT_FINITE or PMA_ERR_RANGE (rules above). */
int pma_adc_validate_scaling(const pma_adc_scaling_t *s);

/* Converts one raw sample. PMA_ERR_WIRE_BREAK: raw < wire_break_below_counts;
 * PMA_ERR_RANGE: otherwise outside [raw_min_counts, raw_max_counts]; in both
 * cases *x_cm is left unchanged. Also PMA_ERR_NULL and, for an invalid
 * scaling, its validation code. */
int pma_adc_counts_to_cm(const pma_adc_scaling_t *s, uint16_t raw_counts, float *x_cm);

/* Inverse, for tests and simulators: the nearest count of x_cm, saturated to
 * [raw_min_counts, raw_max_counts]. PMA_ERR_NOT_FINITE for NaN or infinity. */
int pma_adc_cm_to_counts(const pma_adc_scaling_t *s, float x_cm, uint16_t *raw_counts);

typedef struct pma_dac_scaling {
    float counts_at_zero_kpa;         /* output for 0 kPa (gauge), finite */
    float counts_per_kpa;             /* finite, != 0 */
    uint16_t min_counts;              /* saturation limits of the output, min <= max */
    uint16_t max_counts;
} pma_dac_scaling_t;

/* PMA_OK, PMA_ERR_NULL, PMA_ERR_NOT_FINITE or PMA_ERR_RANGE. */
int pma_dac_validate_scaling(const pma_dac_scaling_t *s);

/* Pressure command in kPa to DAC counts, rounded to nearest and saturated
 * (PMA_OK also when saturated). PMA_ERR_NOT_FINITE for NaN or infinity,
 * *counts then unchanged. */
int pma_dac_kpa_to_counts(const pma_dac_scaling_t *s, float p_kpa, uint16_t *counts);

#endif /* PMA_SCALING_H */
