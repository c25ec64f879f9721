/* SPDX-License-Identifier: Apache-2.0 */
/* The safety supervisor (supervisor.h) and the actuator limits and safe
 * states (actuator.h): pure functions, no HAL.
 *
 * Supervisor: each fault condition on its own, its threshold (one below does
 * not trip, at/above does), the documented priority order, nothing while the
 * output is inactive except CAN bus-off, the RUNNING-only checks ignored while
 * ARMED, a NaN or infinite position trips; its position check from the floats' bits
 * (pma/finite.h, on cores without an FPU) answers as the float comparisons for every float.
 * Actuator: validation rules, p = p0 + polarity * kpa_per_u * u with the
 * clamp to [p_min, p_max] and the slew limit, the safe modes VENT / HOLD /
 * FIXED (at once, no slew limit), non-finite inputs. */
#include "app_test.h"
#include "pma/finite.h"
#include "pma/fixed.h"

/* ------------------------------------------------------------ supervisor -- */

static pma_supervisor_limits_t lim;
static pma_supervisor_input_t in;

/* Defaults of params.toml at 1 kHz; a RUNNING tick with nothing wrong. The fixture of the
 * supervisor tests: each calls it first. */
static void setup_supervisor(void)
{
    lim = (pma_supervisor_limits_t){
        .x_lo_cm = -3.5f, .x_hi_cm = 0.5f, .sensor_timeout_ticks = 10,
        .max_late_ticks = 2, .host_timeout_ticks = 500, .barrier_ticks = 100,
    };
    in = (pma_supervisor_input_t){
        .output_active = 1, .running = 1, .bus_off = 0, .sensor_status = PMA_OK,
        .x_cm = -1.5f, .ticks_since_sample = 0, .late_ticks = 0,
        .ticks_since_host_heartbeat = 0, .controller_error = 0, .u = 12.5f, .barrier_run = 0,
    };
}

#define check(want) assert_fault(pma_supervisor_check(&lim, &in), (want))

static void test_supervisor_nothing_wrong(void)
{
    setup_supervisor();
    check(PMA_FAULT_NONE);
    in.running = 0;
    check(PMA_FAULT_NONE);
    assert_fault(pma_supervisor_check(NULL, &in), PMA_FAULT_CONTROLLER);
    assert_fault(pma_supervisor_check(&lim, NULL), PMA_FAULT_CONTROLLER);
}

static void test_supervisor_each_condition(void)
{
    setup_supervisor();
    pma_supervisor_input_t good = in;

    in.bus_off = 1;
    check(PMA_FAULT_CAN_BUS_OFF);
    in = good;
    in.sensor_status = PMA_ERR_WIRE_BREAK;
    check(PMA_FAULT_SENSOR_WIRE_BREAK);
    in.sensor_status = PMA_ERR_RANGE;
    check(PMA_FAULT_SENSOR_RANGE);
    in.sensor_status = PMA_ERR_IO;
    check(PMA_FAULT_SENSOR_READ);
    in.sensor_status = PMA_ERR_NOT_READY;  /* no sample at all: not a valid reading */
    check(PMA_FAULT_SENSOR_READ);
    in = good;

    /* sensor timeout: at sensor_timeout_ticks, not one below */
    in.ticks_since_sample = 9;
    check(PMA_FAULT_NONE);
    in.ticks_since_sample = 10;
    check(PMA_FAULT_SENSOR_TIMEOUT);
    in.ticks_since_sample = UINT32_MAX;
    check(PMA_FAULT_SENSOR_TIMEOUT);
    in = good;

    /* position: [x_min - margin, x_max + margin] is allowed, inclusive */
    in.x_cm = 0.5f;
    check(PMA_FAULT_NONE);
    in.x_cm = -3.5f;
    check(PMA_FAULT_NONE);
    in.x_cm = nextafterf(0.5f, 1.0f);
    check(PMA_FAULT_POSITION_LIMIT);
    in.x_cm = nextafterf(-3.5f, -4.0f);
    check(PMA_FAULT_POSITION_LIMIT);
    in.x_cm = 40.0f;
    check(PMA_FAULT_POSITION_LIMIT);
    in = good;

    /* tick overrun: more than max_late_ticks */
    in.late_ticks = 2;
    check(PMA_FAULT_NONE);
    in.late_ticks = 3;
    check(PMA_FAULT_TICK_OVERRUN);
    in = good;

    /* host heartbeat: at host_timeout_ticks; 0 disables */
    in.ticks_since_host_heartbeat = 499;
    check(PMA_FAULT_NONE);
    in.ticks_since_host_heartbeat = 500;
    check(PMA_FAULT_HOST_HEARTBEAT_LOST);
    lim.host_timeout_ticks = 0;
    in.ticks_since_host_heartbeat = UINT32_MAX;
    check(PMA_FAULT_NONE);
    lim.host_timeout_ticks = 500;
    in = good;

    in.controller_error = 1;
    check(PMA_FAULT_CONTROLLER);
    in = good;

    in.u = NAN;
    check(PMA_FAULT_NOT_FINITE);
    in.u = INFINITY;
    check(PMA_FAULT_NOT_FINITE);
    in.u = -INFINITY;
    check(PMA_FAULT_NOT_FINITE);
    in.u = 10000.0f;
    check(PMA_FAULT_NONE);
    in = good;

    /* barrier: barrier_ticks consecutive clamps; 0 disables */
    in.barrier_run = 99;
    check(PMA_FAULT_NONE);
    in.barrier_run = 100;
    check(PMA_FAULT_BARRIER);
    lim.barrier_ticks = 0;
    in.barrier_run = UINT32_MAX;
    check(PMA_FAULT_NONE);
}

static void test_supervisor_nan_position_trips(void)
{
    setup_supervisor();
    in.x_cm = NAN;
    check(PMA_FAULT_POSITION_LIMIT);
    in.x_cm = -NAN;
    check(PMA_FAULT_POSITION_LIMIT);
    in.x_cm = INFINITY;
    check(PMA_FAULT_POSITION_LIMIT);
    in.x_cm = -INFINITY;
    check(PMA_FAULT_POSITION_LIMIT);
    in.running = 0; /* ARMED too */
    in.x_cm = NAN;
    check(PMA_FAULT_POSITION_LIMIT);
}

/* Inactive output (IDLE, FAULT, BOOT): only bus-off. */
static float from_bits(uint32_t b)
{
    float f;
    memcpy(&f, &b, sizeof f);
    return f;
}

static uint32_t xorshift(uint32_t *s)
{
    *s ^= *s << 13;
    *s ^= *s >> 17;
    *s ^= *s << 5;
    return *s;
}

/* pma_f32_within and pma_f32_order_key against the float comparisons (the C library's on
 * cores without an FPU): every pair and triple of special values (zeros of both signs,
 * the smallest subnormal, the limits, infinities, NaNs of both signs), then random bits
 * and random floats near each other. */
static void test_within_is_the_float_comparison(void)
{
    const uint32_t special[] = {0x00000000u, 0x80000000u, 0x00000001u, 0x80000001u, 0x007FFFFFu,
                                0x00800000u, 0x3F800000u, 0xBF800000u, 0x7F7FFFFFu, 0xFF7FFFFFu,
                                0x7F800000u, 0xFF800000u, 0x7FC00000u, 0xFFC00000u, 0x7F800001u};
    enum { NS = sizeof special / sizeof special[0] };
    unsigned checked = 0;
    for (unsigned a = 0; a < NS; ++a) {
        for (unsigned b = 0; b < NS; ++b) {
            const float x = from_bits(special[a]), y = from_bits(special[b]);
            if (x == x && y == y) {
                TEST_ASSERT_EQUAL_INT(x <= y, pma_f32_order_key(x) <= pma_f32_order_key(y));
            }
            for (unsigned c = 0; c < NS; ++c) {
                const float z = from_bits(special[c]);
                TEST_ASSERT_EQUAL_INT(y <= x && x <= z, pma_f32_within(x, y, z));
                ++checked;
            }
        }
    }
    uint32_t seed = 0x9E3779B9u;
    for (unsigned i = 0; i < 20000u; ++i) {
        const uint32_t bx = xorshift(&seed);
        /* half of the bounds near x (the same exponent), half anywhere */
        const uint32_t bl = (i & 1u) ? (bx ^ (xorshift(&seed) & 0x800000FFu)) : xorshift(&seed);
        const uint32_t bh = (i & 2u) ? (bx ^ (xorshift(&seed) & 0x800000FFu)) : xorshift(&seed);
        const float x = from_bits(bx), lo = from_bits(bl), hi = from_bits(bh);
        TEST_ASSERT_EQUAL_INT(lo <= x && x <= hi, pma_f32_within(x, lo, hi));
        if (x == x && lo == lo) {
            TEST_ASSERT_EQUAL_INT(lo <= x, pma_f32_order_key(lo) <= pma_f32_order_key(x));
        }
        ++checked;
    }
    TEST_ASSERT_EQUAL_UINT(NS * NS * NS + 20000u, checked);
}

/* The Q16.16 envelope answers as the float check of the position's float, for every q: around
 * both of its ends and at random, on envelopes of every kind (the defaults, a point, one where
 * the conversion rounds (|x| >= 256 cm), beyond the Q16.16 range, infinite, empty, NaN); and
 * the supervisor checks a Q16.16 position with it. */
static void test_supervisor_q16_envelope_is_the_float_check(void)
{
    const float nan = from_bits(0x7FC00000u);
    const float env[][2] = {
        {-3.5f, 0.5f}, {-1.0f, -1.0f}, {-0.0f, 0.0f}, {0.0f, -0.0f}, {1e-9f, 2e-9f},
        {-300.0f, 300.25f}, {-256.0f, 256.0f}, {255.999f, 1000.0001f}, {-40000.0f, 40000.0f},
        {-INFINITY, INFINITY}, {-INFINITY, -1.25f}, {1.25f, INFINITY}, {40000.0f, 50000.0f},
        {-50000.0f, -40000.0f}, {1.0f, -1.0f}, {nan, 1.0f}, {-1.0f, nan}, {INFINITY, INFINITY},
    };
    enum { NE = sizeof env / sizeof env[0] };
    uint32_t seed = 0x2545F491u;
    unsigned checked = 0;
    for (unsigned e = 0; e < NE; ++e) {
        pma_supervisor_limits_t l = {.x_lo_cm = env[e][0], .x_hi_cm = env[e][1]};
        pma_supervisor_limits_q16(&l);
        const int64_t ends[] = {l.x_lo_q16, l.x_hi_q16, 0, INT32_MIN, INT32_MAX};
        for (unsigned k = 0; k < sizeof ends / sizeof ends[0]; ++k) {
            for (int64_t d = -300; d <= 300; ++d) {
                const int64_t q64 = ends[k] + d;
                if (q64 < INT32_MIN || q64 > INT32_MAX) continue;
                const int32_t q = (int32_t)q64;
                TEST_ASSERT_EQUAL_INT(pma_f32_within(pma_q16_to_f32(q), l.x_lo_cm, l.x_hi_cm),
                                      q >= l.x_lo_q16 && q <= l.x_hi_q16);
                ++checked;
            }
        }
        for (unsigned i = 0; i < 2000u; ++i) {
            const int32_t q = (int32_t)test_rand_u32(&seed);
            TEST_ASSERT_EQUAL_INT(pma_f32_within(pma_q16_to_f32(q), l.x_lo_cm, l.x_hi_cm),
                                  q >= l.x_lo_q16 && q <= l.x_hi_q16);
            ++checked;
        }
    }
    TEST_ASSERT_TRUE(checked > NE * 2000u);

    /* the supervisor on a Q16.16 position: the inclusive ends, one LSB beyond trips */
    setup_supervisor();
    pma_supervisor_limits_q16(&lim);
    TEST_ASSERT_EQUAL_INT32(-7 * 32768, lim.x_lo_q16);   /* -3.5 cm */
    TEST_ASSERT_EQUAL_INT32(32768, lim.x_hi_q16);        /* 0.5 cm */
    in.x_cm = nan;   /* not read where the position is x_q16 */
    in.x_in_q16 = 1;
    in.x_q16 = 32768;
    check(PMA_FAULT_NONE);
    in.x_q16 = -7 * 32768;
    check(PMA_FAULT_NONE);
    in.x_q16 = 32769;
    check(PMA_FAULT_POSITION_LIMIT);
    in.x_q16 = -7 * 32768 - 1;
    check(PMA_FAULT_POSITION_LIMIT);
    in.x_q16 = INT32_MIN;
    check(PMA_FAULT_POSITION_LIMIT);
    pma_supervisor_limits_q16(NULL);   /* no crash */
}

static void test_supervisor_inactive_only_bus_off(void)
{
    setup_supervisor();
    in.output_active = 0;
    in.running = 0;
    in.sensor_status = PMA_ERR_WIRE_BREAK;
    in.x_cm = NAN;
    in.ticks_since_sample = UINT32_MAX;
    in.late_ticks = 1000;
    in.ticks_since_host_heartbeat = UINT32_MAX;
    in.controller_error = 1;
    in.u = NAN;
    in.barrier_run = UINT32_MAX;
    check(PMA_FAULT_NONE);
    in.bus_off = 1;
    check(PMA_FAULT_CAN_BUS_OFF);
}

/* ARMED: sensor, position and overrun checks, but not the RUNNING ones. */
static void test_supervisor_armed_skips_running_checks(void)
{
    setup_supervisor();
    in.running = 0;
    in.ticks_since_host_heartbeat = UINT32_MAX;
    in.controller_error = 1;
    in.u = NAN;
    in.barrier_run = UINT32_MAX;
    check(PMA_FAULT_NONE);
    in.late_ticks = 3;
    check(PMA_FAULT_TICK_OVERRUN);
    in.x_cm = 1.0f;
    check(PMA_FAULT_POSITION_LIMIT);
    in.sensor_status = PMA_ERR_RANGE;
    check(PMA_FAULT_SENSOR_RANGE);
}

/* The order of supervisor.h: bus-off (every state); then while active: no
 * new sample (plant bridge), sensor wire break, out of range, read error,
 * position, tick overrun; then while RUNNING: host heartbeat, controller
 * error, non-finite output, barrier. Everything wrong at once, then the
 * winner removed one by one. */
static void test_supervisor_priority(void)
{
    setup_supervisor();
    in.bus_off = 1;
    in.ticks_since_sample = 10;
    in.sensor_status = PMA_ERR_WIRE_BREAK;
    in.x_cm = 5.0f;
    in.late_ticks = 10;
    in.ticks_since_host_heartbeat = 1000;
    in.controller_error = 1;
    in.u = NAN;
    in.barrier_run = 1000;
    check(PMA_FAULT_CAN_BUS_OFF);
    in.bus_off = 0;
    check(PMA_FAULT_SENSOR_TIMEOUT);
    in.sensor_status = PMA_ERR_RANGE;
    check(PMA_FAULT_SENSOR_TIMEOUT);
    in.ticks_since_sample = 9;
    check(PMA_FAULT_SENSOR_RANGE);
    in.sensor_status = PMA_ERR_WIRE_BREAK;
    check(PMA_FAULT_SENSOR_WIRE_BREAK);
    in.sensor_status = PMA_ERR_IO;
    check(PMA_FAULT_SENSOR_READ);
    in.sensor_status = PMA_OK;
    check(PMA_FAULT_POSITION_LIMIT);
    in.x_cm = NAN; /* a NaN position is a position fault, before the rest */
    check(PMA_FAULT_POSITION_LIMIT);
    in.x_cm = -1.0f;
    check(PMA_FAULT_TICK_OVERRUN);
    in.late_ticks = 0;
    check(PMA_FAULT_HOST_HEARTBEAT_LOST);
    in.ticks_since_host_heartbeat = 0;
    check(PMA_FAULT_CONTROLLER);
    in.controller_error = 0;
    check(PMA_FAULT_NOT_FINITE);
    in.u = 0.0f;
    check(PMA_FAULT_BARRIER);
    in.barrier_run = 0;
    check(PMA_FAULT_NONE);
}

static void test_fault_names(void)
{
    TEST_ASSERT_EQUAL_STRING("NONE", pma_fault_name(PMA_FAULT_NONE));
    TEST_ASSERT_EQUAL_STRING("SENSOR_WIRE_BREAK", pma_fault_name(PMA_FAULT_SENSOR_WIRE_BREAK));
    TEST_ASSERT_EQUAL_STRING("OUTPUT", pma_fault_name(PMA_FAULT_OUTPUT));
    TEST_ASSERT_EQUAL_STRING("INIT", pma_fault_name(PMA_FAULT_INIT));
    TEST_ASSERT_EQUAL_STRING("UNKNOWN", pma_fault_name(PMA_FAULT_INIT + 1));
    TEST_ASSERT_EQUAL_STRING("UNKNOWN", pma_fault_name(-1));
    /* the names are the DBC's FaultCode values */
    TEST_ASSERT_EQUAL_INT(PMA_PROTO_HEARTBEAT_FAULT_CODE_WATCHDOG_RESET_CHOICE,
                          PMA_FAULT_WATCHDOG_RESET);
    TEST_ASSERT_EQUAL_INT(PMA_PROTO_HEARTBEAT_FAULT_CODE_OUTPUT_CHOICE, PMA_FAULT_OUTPUT);
    TEST_ASSERT_EQUAL_INT(PMA_PROTO_HEARTBEAT_FAULT_CODE_INIT_CHOICE, PMA_FAULT_INIT);
    TEST_ASSERT_EQUAL_INT(PMA_PROTO_HEARTBEAT_FAULT_CODE_BARRIER_CHOICE, PMA_FAULT_BARRIER);
}

/* -------------------------------------------------------------- actuator -- */

static pma_actuator_config_t ac;

/* The fixture of the actuator tests: each calls it first. */
static void setup_actuator(void)
{
    ac = (pma_actuator_config_t){
        .p0_kpa = 300.0f, .kpa_per_u = 1.0f, .polarity = 1, .p_min_kpa = 0.0f,
        .p_max_kpa = 600.0f, .slew_kpa_s = 0.0f, .safe_mode = PMA_SAFE_VENT, .safe_kpa = 0.0f,
    };
}

static void test_actuator_validate(void)
{
    setup_actuator();
    const pma_actuator_config_t good = ac;
    assert_status(pma_actuator_validate(&ac), PMA_OK);
    assert_status(pma_actuator_validate(NULL), PMA_ERR_NULL);

    ac.polarity = -1;
    assert_status(pma_actuator_validate(&ac), PMA_OK);
    ac.polarity = 0;
    assert_status(pma_actuator_validate(&ac), PMA_ERR_RANGE);
    ac.polarity = 2;
    assert_status(pma_actuator_validate(&ac), PMA_ERR_RANGE);
    ac = good;
    ac.p_min_kpa = 600.0f; /* p_min >= p_max */
    assert_status(pma_actuator_validate(&ac), PMA_ERR_RANGE);
    ac = good;
    ac.p_min_kpa = -1.0f;
    assert_status(pma_actuator_validate(&ac), PMA_ERR_RANGE);
    ac = good;
    ac.p0_kpa = 601.0f;   /* p0 outside [p_min, p_max] */
    assert_status(pma_actuator_validate(&ac), PMA_ERR_RANGE);
    ac.p0_kpa = 600.0f;   /* the edge is inside */
    assert_status(pma_actuator_validate(&ac), PMA_OK);
    ac = good;
    ac.p_min_kpa = 100.0f;
    ac.p0_kpa = 99.0f;
    assert_status(pma_actuator_validate(&ac), PMA_ERR_RANGE);
    ac = good;
    ac.kpa_per_u = 0.0f;
    assert_status(pma_actuator_validate(&ac), PMA_ERR_RANGE);
    ac = good;
    ac.slew_kpa_s = -1.0f;
    assert_status(pma_actuator_validate(&ac), PMA_ERR_RANGE);
    ac = good;
    ac.safe_mode = 3;
    assert_status(pma_actuator_validate(&ac), PMA_ERR_RANGE);
    ac = good;
    ac.safe_mode = PMA_SAFE_FIXED;
    ac.safe_kpa = 600.0f;
    assert_status(pma_actuator_validate(&ac), PMA_OK);
    ac.safe_kpa = 600.5f;  /* FIXED above p_max */
    assert_status(pma_actuator_validate(&ac), PMA_ERR_RANGE);
    ac.safe_mode = PMA_SAFE_VENT; /* safe_kpa only matters for FIXED */
    assert_status(pma_actuator_validate(&ac), PMA_OK);
    /* non-finite fields */
    float *fields[] = {&ac.p0_kpa, &ac.kpa_per_u, &ac.p_min_kpa, &ac.p_max_kpa, &ac.slew_kpa_s,
                       &ac.safe_kpa};
    for (size_t i = 0; i < sizeof fields / sizeof fields[0]; ++i) {
        ac = good;
        *fields[i] = NAN;
        assert_status(pma_actuator_validate(&ac), PMA_ERR_NOT_FINITE);
        *fields[i] = INFINITY;
        assert_status(pma_actuator_validate(&ac), PMA_ERR_NOT_FINITE);
    }
}

static void test_actuator_law_clamp_polarity(void)
{
    setup_actuator();
    /* no slew limit: p = p0 + polarity * kpa_per_u * u, clamped */
    assert_near(pma_actuator_active_kpa(&ac, 0.0f, 0.0f, 1e-3f), 300.0f, 0.0f);
    assert_near(pma_actuator_active_kpa(&ac, 25.0f, 0.0f, 1e-3f), 325.0f, 1e-4);
    assert_near(pma_actuator_active_kpa(&ac, -100.0f, 0.0f, 1e-3f), 200.0f, 1e-4);
    assert_near(pma_actuator_active_kpa(&ac, 400.0f, 0.0f, 1e-3f), 600.0f, 0.0f); /* p_max */
    assert_near(pma_actuator_active_kpa(&ac, -400.0f, 0.0f, 1e-3f), 0.0f, 0.0f);  /* p_min */
    assert_near(pma_actuator_active_kpa(&ac, 1e30f, 0.0f, 1e-3f), 600.0f, 0.0f);
    ac.kpa_per_u = 2.0f;
    assert_near(pma_actuator_active_kpa(&ac, 25.0f, 0.0f, 1e-3f), 350.0f, 1e-4);
    ac.polarity = -1;
    assert_near(pma_actuator_active_kpa(&ac, 25.0f, 0.0f, 1e-3f), 250.0f, 1e-4);
    assert_near(pma_actuator_active_kpa(&ac, -25.0f, 0.0f, 1e-3f), 350.0f, 1e-4);
    assert_near(pma_actuator_active_kpa(&ac, 400.0f, 0.0f, 1e-3f), 0.0f, 0.0f);
    ac.p_min_kpa = 50.0f;
    ac.p_max_kpa = 500.0f;
    assert_near(pma_actuator_active_kpa(&ac, 400.0f, 0.0f, 1e-3f), 50.0f, 0.0f);
    assert_near(pma_actuator_active_kpa(&ac, -400.0f, 0.0f, 1e-3f), 500.0f, 0.0f);
}

static void test_actuator_slew_limit(void)
{
    setup_actuator();
    ac.slew_kpa_s = 20000.0f; /* 20 kPa per 1 ms tick */
    float p = 0.0f;
    /* from the vented state up to p0: 15 ticks of 20 kPa */
    for (int k = 1; k <= 15; ++k) {
        p = pma_actuator_active_kpa(&ac, 0.0f, p, 1e-3f);
        assert_near(p, 20.0f * (float)k, 1e-3);
    }
    p = pma_actuator_active_kpa(&ac, 0.0f, p, 1e-3f);
    assert_near(p, 300.0f, 1e-3);
    /* down by at most 20 per tick, a small step at once */
    assert_near(pma_actuator_active_kpa(&ac, -300.0f, 300.0f, 1e-3f), 280.0f, 1e-3);
    assert_near(pma_actuator_active_kpa(&ac, 5.0f, 300.0f, 1e-3f), 305.0f, 1e-3);
    /* the period scales it */
    assert_near(pma_actuator_active_kpa(&ac, 300.0f, 300.0f, 2e-3f), 340.0f, 1e-3);
    /* 0: no limit */
    ac.slew_kpa_s = 0.0f;
    assert_near(pma_actuator_active_kpa(&ac, 300.0f, 0.0f, 1e-3f), 600.0f, 0.0f);
}

static void test_actuator_safe_modes(void)
{
    setup_actuator();
    ac.slew_kpa_s = 10.0f; /* the safe state ignores the slew limit */
    ac.safe_mode = PMA_SAFE_VENT;
    TEST_ASSERT_TRUE(pma_actuator_safe_kpa(&ac, 450.0f) == 0.0f);
    ac.safe_mode = PMA_SAFE_HOLD;
    TEST_ASSERT_TRUE(pma_actuator_safe_kpa(&ac, 450.0f) == 450.0f);
    TEST_ASSERT_TRUE(pma_actuator_safe_kpa(&ac, 0.0f) == 0.0f);
    TEST_ASSERT_TRUE(pma_actuator_safe_kpa(&ac, NAN) == 0.0f);
    TEST_ASSERT_TRUE(pma_actuator_safe_kpa(&ac, INFINITY) == 0.0f);
    TEST_ASSERT_TRUE(pma_actuator_safe_kpa(&ac, -5.0f) == 0.0f);
    ac.safe_mode = PMA_SAFE_FIXED;
    ac.safe_kpa = 120.0f;
    TEST_ASSERT_TRUE(pma_actuator_safe_kpa(&ac, 450.0f) == 120.0f);
    TEST_ASSERT_TRUE(pma_actuator_safe_kpa(&ac, NAN) == 120.0f);
}

/* Non-finite u or previous pressure: the safe pressure, never NaN. */
static void test_actuator_non_finite(void)
{
    setup_actuator();
    ac.slew_kpa_s = 20000.0f;
    const float bad[] = {NAN, INFINITY, -INFINITY};
    for (size_t i = 0; i < 3; ++i) {
        ac.safe_mode = PMA_SAFE_VENT;
        TEST_ASSERT_TRUE(pma_actuator_active_kpa(&ac, bad[i], 300.0f, 1e-3f) == 0.0f);
        TEST_ASSERT_TRUE(pma_actuator_active_kpa(&ac, 0.0f, bad[i], 1e-3f) == 0.0f);
        ac.safe_mode = PMA_SAFE_FIXED;
        ac.safe_kpa = 80.0f;
        TEST_ASSERT_TRUE(pma_actuator_active_kpa(&ac, bad[i], 300.0f, 1e-3f) == 80.0f);
        TEST_ASSERT_TRUE(pma_actuator_active_kpa(&ac, 0.0f, bad[i], 1e-3f) == 80.0f);
        ac.safe_mode = PMA_SAFE_HOLD;  /* no previous value to hold: vent */
        TEST_ASSERT_TRUE(pma_actuator_active_kpa(&ac, 0.0f, bad[i], 1e-3f) == 0.0f);
        /* (HOLD with a non-finite u and a finite previous value: test_app_bugs.c) */
    }
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_supervisor_nothing_wrong);
    RUN_TEST(test_supervisor_each_condition);
    RUN_TEST(test_supervisor_nan_position_trips);
    RUN_TEST(test_within_is_the_float_comparison);
    RUN_TEST(test_supervisor_q16_envelope_is_the_float_check);
    RUN_TEST(test_supervisor_inactive_only_bus_off);
    RUN_TEST(test_supervisor_armed_skips_running_checks);
    RUN_TEST(test_supervisor_priority);
    RUN_TEST(test_fault_names);
    RUN_TEST(test_actuator_validate);
    RUN_TEST(test_actuator_law_clamp_polarity);
    RUN_TEST(test_actuator_slew_limit);
    RUN_TEST(test_actuator_safe_modes);
    RUN_TEST(test_actuator_non_finite);
    return UNITY_END();
}
