/* SPDX-License-Identifier: Apache-2.0 */
/* The application's input and output: which source the position comes from (the
 * ADC or the plant bridge), this tick's sample, and the pressure command to the
 * DAC or the bridge, safe whenever the output is inactive or a conversion fails. */
#include <string.h>

#include "actuator.h"
#include "app_core.h"
#include "generated/pma_proto.h"

void pma_app_bridge_switched(pma_app_t *app, uint8_t on)
{
    app->bridge.active = on;
    app->bridge.have = app->bridge.fresh = app->bridge.gap = 0;
    app->sensor.ticks_since_sample = 0;
    app->sensor.sample_status = PMA_SAMPLE_NONE;
    app->sensor.status = PMA_ERR_NOT_READY;
}

#if PMA_CTRL_Q16
/* ARM: the fixed-point stages are built again at the first active tick; from then on, while
 * the output is active, they are used as built (their parameters, adc.*, act.*, dac.*,
 * safety.safe_* and sys.tick_hz, are idle-only: SET refuses them then). */
void pma_app_io_q16_arm(pma_app_t *app)
{
    app->sensor.q16.built = 0;
    app->output.q16.built = 0;
}

/* The fixed-point input stage of the parameters as they are, rebuilt while the output is
 * inactive when one of the values it is built from changed (their bits compared: a few
 * instructions a tick, and no path that changes a parameter can miss it); NULL where it cannot
 * represent them (the float function then runs, and reports an invalid scaling). */
static const pma_input_q16_t *input_q16(pma_app_t *app)
{
    pma_app_input_q16_t *c = &app->sensor.q16;
    if (c->built && pma_app_output_active(app)) return c->ok ? &c->stage : NULL;
    const pma_params_t *p = &app->params;
    const float f[] = {p->adc_offset_cm, p->adc_gain_cm_per_count};
    enum { NF = sizeof f / sizeof f[0] };   /* then three integer parameters */
    _Static_assert(NF + 3u == PMA_APP_INPUT_KEY_WORDS, "the key holds exactly the values the stage is built from");
    uint32_t key[PMA_APP_INPUT_KEY_WORDS];
    memcpy(key, f, sizeof f);
    key[NF] = p->adc_raw_min_counts;
    key[NF + 1] = p->adc_raw_max_counts;
    key[NF + 2] = p->adc_wire_break_below_counts;
    if (!c->built || memcmp(key, c->key, sizeof key) != 0) {
        pma_adc_scaling_t s;
        pma_app_adc_scaling(p, &s);
        c->ok = (uint8_t)(pma_input_q16_build(&c->stage, &s) == PMA_OK);
        memcpy(c->key, key, sizeof key);
        c->built = 1;
    }
    return c->ok ? &c->stage : NULL;
}
#endif

/* The position of this tick's sample in cm: in Q16.16 builds the fixed-point stage where it
 * takes the scaling (and x_cm from it), else the float function, which defines it. */
static int scale_sample(pma_app_t *app)
{
#if PMA_CTRL_Q16
    const pma_input_q16_t *in = input_q16(app);
    if (in != NULL) {
        pma_q16_t x = 0;
        const int rc = pma_input_q16_cm(in, app->sensor.raw_counts, &x);
        if (rc == PMA_OK) {
            app->sensor.x_q16 = x;
            app->sensor.x_in_q16 = 1;   /* its float only when read: pma_app_position_cm */
        }
        return rc;
    }
#endif
    pma_adc_scaling_t s;
    pma_app_adc_scaling(&app->params, &s);
    float x = 0.0f;
    const int rc = pma_adc_counts_to_cm(&s, app->sensor.raw_counts, &x);
    if (rc == PMA_OK) {
        app->sensor.x_cm = x;
#if PMA_CTRL_Q16
        app->sensor.x_q16 = pma_q16_from_f32(x);   /* saturated: the slot's range */
        app->sensor.x_in_q16 = 0;
#endif
    }
    return rc;
}

/* The position of this tick: from the ADC, or the plant bridge's last sample. */
void pma_app_acquire(pma_app_t *app)
{
    int rc;
    if (pma_app_bridge_on(app)) {
        if (!app->bridge.have) {
            app->sensor.sample_status = PMA_SAMPLE_NONE;
            if (app->sensor.ticks_since_sample != UINT32_MAX) ++app->sensor.ticks_since_sample;
            app->sensor.status = PMA_ERR_NOT_READY;
            return;
        }
        if (app->bridge.fresh) {
            app->sensor.sample_status = app->bridge.gap ? PMA_SAMPLE_GAP : PMA_SAMPLE_NEW;
            app->sensor.ticks_since_sample = 0;
        } else {
            app->sensor.sample_status = PMA_SAMPLE_REPEATED;
            if (app->sensor.ticks_since_sample != UINT32_MAX) ++app->sensor.ticks_since_sample;
        }
        app->bridge.fresh = 0;
        app->bridge.gap = 0;
        app->sensor.raw_counts = app->bridge.raw_counts;
        rc = PMA_OK;
    } else {
        app->sensor.ticks_since_sample = 0;
        rc = pma_hal_adc_read(&app->sensor.raw_counts);
    }
    if (rc == PMA_OK) rc = scale_sample(app);
    app->sensor.status = rc;
}

#if PMA_CTRL_Q16
/* The fixed-point output stage, built at the first active tick after ARM; NULL where it
 * cannot represent the parameters. */
static const pma_output_q16_t *output_q16(pma_app_t *app)
{
    pma_app_output_q16_t *c = &app->output.q16;
    if (!c->built) {
        pma_actuator_config_t ac;
        pma_dac_scaling_t ds;
        pma_app_actuator_config(&app->params, &ac);
        pma_app_dac_scaling(&app->params, &ds);
        c->ok = (uint8_t)(pma_output_q16_build(&c->stage, &ac, &ds, app->timing.period_s) == PMA_OK);
        c->built = 1;
    }
    return c->ok ? &c->stage : NULL;
}

/* The float functions take over p (the output went inactive, or the stage cannot represent
 * the parameters, or the DAC failed): the stage's last p as the float they start from. */
static void sync_pressure_f32(pma_app_t *app)
{
    pma_app_output_q16_t *c = &app->output.q16;
    if (c->p_valid) app->output.p_kpa = pma_q16_to_f32(c->p_kpa);
    c->p_valid = 0;
}
#endif

float pma_app_position_cm(const pma_app_t *app)
{
#if PMA_CTRL_Q16
    if (app->sensor.x_in_q16) return pma_q16_to_f32(app->sensor.x_q16);
#endif
    return app->sensor.x_cm;
}

float pma_app_output_u(const pma_app_t *app)
{
#if PMA_CTRL_Q16
    if (app->output.u_in_q16) return pma_q16_to_f32(app->output.u_q16);
#endif
    return app->output.u;
}

float pma_app_pressure_kpa(const pma_app_t *app)
{
#if PMA_CTRL_Q16
    if (app->output.q16.p_valid) return pma_q16_to_f32(app->output.q16.p_kpa);
#endif
    return app->output.p_kpa;
}

void pma_app_write_output(pma_app_t *app)
{
    int written = 0;   /* p and its DAC code set by the fixed-point stage */
#if PMA_CTRL_Q16
    /* an active output in fixed point where the stage takes the values; the float functions,
     * which define it, otherwise (and always in float builds) */
    pma_app_output_q16_t *c = &app->output.q16;
    if (pma_app_output_active(app)) {
        const pma_output_q16_t *q = output_q16(app);
        /* p(k-1): as the stage wrote it, else the float value where the stage takes it */
        const int p_ok = c->p_valid || pma_output_q16_takes(app->output.p_kpa);
        if (q != NULL && p_ok) {
            const pma_q16_t p_prev = c->p_valid ? c->p_kpa : pma_q16_from_f32(app->output.p_kpa);
            const pma_q16_t p = pma_output_q16_kpa(q, app->output.u_q16, p_prev);
            c->p_kpa = p;
            c->p_valid = 1;   /* output.p_kpa's float only when read: pma_app_pressure_kpa */
            app->output.dac_counts = pma_output_q16_counts(q, p);
            written = 1;
        }
    }
    if (!written) sync_pressure_f32(app);   /* the float functions take p(k-1) and write p below */
#endif
    pma_actuator_config_t ac;
    pma_dac_scaling_t ds;
    if (!written) {
        pma_app_actuator_config(&app->params, &ac);
        pma_app_dac_scaling(&app->params, &ds);
        if (pma_app_output_active(app)) {
            app->output.p_kpa = pma_actuator_active_kpa(&ac, pma_app_output_u(app), app->output.p_kpa,
                                                        app->timing.period_s);
        } else {
            app->output.p_kpa = pma_actuator_safe_kpa(&ac, app->output.p_kpa);
        }
        uint16_t counts = app->output.dac_counts;
        if (pma_dac_kpa_to_counts(&ds, app->output.p_kpa, &counts) == PMA_OK) {
            app->output.dac_counts = counts;
        } else {
            /* unreachable while the scaling is enforced at SET (and p is finite):
             * never keep an active pressure on the output */
            pma_app_raise_fault(app, PMA_FAULT_OUTPUT);
            app->output.dac_counts = 0;
        }
    }
    if (pma_app_bridge_on(app)) {
        app->tx_due |= PMA_APP_TX_ACTUATOR; /* the plant bridge's output: a frame */
        return;
    }
    if (pma_hal_dac_write(app->output.dac_counts) != PMA_OK) {
        /* the DAC refused the value (or failed): never leave an earlier,
         * perhaps active, command on the output. Try the safe value, and if
         * the DAC refuses that too, 0 counts (0 V / 0 mA: a regulator's
         * minimum pressure). */
        pma_app_raise_fault(app, PMA_FAULT_OUTPUT);
        pma_app_actuator_config(&app->params, &ac);
        pma_app_dac_scaling(&app->params, &ds);
#if PMA_CTRL_Q16
        sync_pressure_f32(app);
#endif
        app->output.p_kpa = pma_actuator_safe_kpa(&ac, app->output.p_kpa);
        uint16_t counts = 0;
        if (pma_dac_kpa_to_counts(&ds, app->output.p_kpa, &counts) != PMA_OK ||
            pma_hal_dac_write(counts) != PMA_OK) {
            counts = 0;
            (void)pma_hal_dac_write(counts);
        }
        app->output.dac_counts = counts;
    }
}
