/* SPDX-License-Identifier: Apache-2.0 */
/* Cost of one whole tick of the application (pma_app_step on the fake HAL: the
 * ADC sample and its scaling, the velocity estimate, the controller, the
 * supervisor, the actuator and the DAC, the heartbeat and the telemetry frames
 * at their decimation), in the arithmetic this build's controller slot uses
 * (PMA_CTRL_ARITH, firmware/app). Under `cmake --build --preset <arm> --target
 * bench` QEMU runs with -icount shift=0, so the figures are instruction counts;
 * on the host, wall-clock ns. Prints figures, never asserts.
 *
 * The node RUNS a HOLD at -1.5 cm with the sensor at -1.52 cm (within w1), its
 * counts dithering by one count from tick to tick as a real sensor's do: the
 * controller works in its linear region and takes its general path on every
 * tick (a sample that never changes would let the law's input settle, and
 * MFAC's estimator, which PPC runs beside its law, skip its divisions);
 * nothing faults; the host heartbeat check is off (no host here). With t >= t_u the paper's
 * law on its default gains sits at its velocity barrier with its output at ctrl.u_max
 * (CtrlFlags 0x4006): every tick there is a lost tick of the guarantee monitor, which it
 * only counts (pma_ctrl_lost_again). Each figure is (N ticks - N passes of
 * the same loop without the tick) / N. The frames a tick queued are popped after it,
 * so the fake CAN's pops (about 40 instructions a tick on the M0) are in the figure;
 * `tools/profile_tick.py` shows the tick per function and per library. */
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "app.h"
#include "app_core.h"
#include "generated/pma_param_table.h"
#include "pma/hal.h"
#include "pma_board.h"
#include "pma_hal_fake.h"
#include "scaling.h"

#define N 2048u

static pma_app_t app;
static uint16_t sensor_counts;   /* the sample at -1.52 cm; the ticks alternate it with one more */
static volatile uint32_t sink;

#if PMA_CTRL_Q16
#define ARITH "q16"
#else
#define ARITH "f32"
#endif

static int set_f32(uint16_t id, float v)
{
    pma_param_value_t x;
    x.f32 = v;
    return pma_app_param_set(&app, id, PMA_PARAM_F32, x);
}

static int set_u32(uint16_t id, uint32_t v)
{
    pma_param_value_t x;
    x.u32 = v;
    return pma_app_param_set(&app, id, PMA_PARAM_U32, x);
}

static uint32_t drain(void)
{
    pma_can_frame_t f;
    uint32_t n = 0;
    while (pma_fake_can_tx_pop(&f) == PMA_OK) ++n;
    return n;
}

/* The node started, configured for mode and t_u, ARMED and RUNNING; 0 or an error text. */
static const char *start(uint32_t mode, float t_u_s)
{
    pma_fake_reset();
    if (pma_hal_init(NULL) != PMA_OK) return "hal init";
    const pma_app_platform_t plat = {.plant_bridge = 0, .lockstep = 0, .node_id = 3,
                                     .store_first_block = 0, .store_blocks_per_slot = 0,
                                     .watchdog_ms = 0};
    pma_params_defaults(&app.params);
    pma_adc_scaling_t s;
    pma_app_adc_scaling(&app.params, &s);   /* the application's own builder */
    if (pma_adc_cm_to_counts(&s, -1.52f, &sensor_counts) != PMA_OK) return "sensor counts";
    pma_fake_adc_set(sensor_counts);
    if (pma_app_init(&app, &plat) != PMA_OK) return "app init";
    int rc = set_u32(PMA_PARAM_CTRL_MODE, mode);
    if (rc == PMA_OK) rc = set_u32(PMA_PARAM_REF_KIND, PMA_REF_KIND_HOLD);
    if (rc == PMA_OK) rc = set_f32(PMA_PARAM_REF_OFFSET_CM, -1.5f);
    if (rc == PMA_OK) rc = set_f32(PMA_PARAM_PPC_T_U_S, t_u_s);
    if (rc == PMA_OK) rc = set_u32(PMA_PARAM_SAFETY_HOST_TIMEOUT_MS, 0u);
    if (rc != PMA_OK) return "parameters";
    for (int i = 0; i < 5; ++i) (void)pma_app_step(&app);
    if (pma_app_command(&app, PMA_CMD_ARM, 0) != PMA_OK) return "ARM";
    for (int i = 0; i < 5; ++i) (void)pma_app_step(&app);
    if (pma_app_command(&app, PMA_CMD_START, 0) != PMA_OK) return "START";
    for (int i = 0; i < 50; ++i) (void)pma_app_step(&app);   /* past that t_u */
    drain();
    return app.state == PMA_STATE_RUNNING ? NULL : "not RUNNING";
}

static void bench(const char *what, uint32_t mode, float t_u_s)
{
    const char *err = start(mode, t_u_s);
    if (err != NULL) {
        printf("BENCH setup failed: %s (%s)\n", what, err);
        return;
    }
    uint32_t frames = 0;
    pma_board_timer_start();
    for (uint32_t k = 0; k < N; ++k) {
        pma_fake_adc_set((uint16_t)(sensor_counts + (k & 1u)));
        frames += drain();
    }
    const uint32_t empty = pma_board_timer_elapsed_ns();
    pma_board_timer_start();
    for (uint32_t k = 0; k < N; ++k) {
        pma_fake_adc_set((uint16_t)(sensor_counts + (k & 1u)));
        (void)pma_app_step(&app);
        frames += drain();
    }
    const uint32_t total = pma_board_timer_elapsed_ns();
    if (app.state != PMA_STATE_RUNNING) {
        printf("BENCH setup failed: %s left RUNNING (fault %u)\n", what, (unsigned)app.fault);
        return;
    }
    sink = frames;
    printf("BENCH %s app_tick_%s(%s) %.1f %s/tick (%.2f frames/tick)\n", pma_board_name(), ARITH, what,
           ((double)total - (double)empty) / (double)N, pma_board_time_unit(), (double)frames / (double)N);
}

int main(void)
{
    /* the application's RAM: it has no globals, all of it is this struct (the program's) */
    printf("SIZE %s pma_app_t %u bytes\n", pma_board_name(), (unsigned)sizeof(pma_app_t));
    bench("ppc,t<t_u", PMA_CTRL_MODE_PPC, 1000.0f);
    bench("ppc,t>=t_u", PMA_CTRL_MODE_PPC, 0.03125f);  /* t_u >= 1/64 s in Q16.16 */
    bench("mfac", PMA_CTRL_MODE_MFAC, 2.0f);
    bench("pid", PMA_CTRL_MODE_PID, 2.0f);
    return 0;
}
