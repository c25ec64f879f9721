# SPDX-License-Identifier: Apache-2.0
"""Tests of the simulated rig's physics (no CAN needed).

    .venv/bin/python -m pytest hil/tests/test_rig.py -q

Published numbers are written out here again (from ../shared/spec/controller.md),
so the calibration is checked against the sources, not against itself.
"""

from __future__ import annotations

import ctypes
import math
import pathlib
import subprocess
import tomllib
from typing import Any

import numpy as np
import pytest

from hil.rig import Rig, RigParams

ROOT = pathlib.Path(__file__).resolve().parents[2]
DT = 0.001  # control period of the firmware's default 1 kHz tick


def quiet(**changes) -> RigParams:
    """Default rig without sensor noise (and with any changes 'group.name')."""
    p = RigParams().replace(**{"sensor.noise_cm": 0.0, "sensor.adc_noise_counts": 0.0})
    return p.replace(**changes) if changes else p


def hold(rig: Rig, p_kpa: float, seconds: float) -> None:
    c = rig.kpa_to_dac(p_kpa)
    for _ in range(int(round(seconds / DT))):
        rig.apply_dac(c)
        rig.step(DT)


def firmware_defaults() -> dict[str, float]:
    data = tomllib.loads((ROOT / "firmware" / "app" / "params.toml").read_text())
    return {p["name"]: p["default"] for p in data["param"]}


# --------------------------------------------------------------- calibration
def test_contractile_element_and_stiffness_match_the_sources():
    rig = Rig(quiet(**{"drift.temp_rate_k_per_s": 0.0}))
    # Martens and Boblan 2017 (DMSP-10): force at nominal length
    assert rig._f_pos(650.0) == pytest.approx(542.5, abs=0.05)
    assert rig._f_pos(360.0) == pytest.approx(283.8, abs=0.05)
    # no force below about 50 kPa
    assert rig._f_pos(40.0) < 2.0
    # zero force at about 21 % contraction at 650 kPa (100 mm muscle): F - K xs = 0
    assert rig._f_pos(650.0) / rig._k_of_p(650.0) == pytest.approx(21.0, rel=0.01)
    # Serres et al. 2009: K's shape (ratios), B contraction/relaxation ratio
    ratio = rig._k_of_p(200.0) / rig._k_of_p(500.0)
    assert ratio == pytest.approx((32.7 - 0.0321 * 200) / (17 + 0.0179 * 500), rel=1e-3)
    m = rig.params.muscle
    assert m.b_contract_ns_per_mm / m.b_relax_ns_per_mm == pytest.approx(2.90 / 1.57)
    # Festo: about 25 % maximum stroke. No load, 0 -> 800 kPa contraction:
    free_800 = rig._f_pos(800.0) / rig._k_of_p(800.0)
    assert 20.0 < free_800 <= 25.0
    # theoretical 630 N at 600 kPa is an upper bound of the measured force
    assert rig._f_pos(600.0) < 630.0


def test_wiring_matches_the_firmware_default_scalings():
    fw = firmware_defaults()
    ours = RigParams().firmware_scaling()
    assert ours["adc.offset_cm"] == pytest.approx(fw["adc.offset_cm"], abs=1e-6)
    assert ours["adc.gain_cm_per_count"] == pytest.approx(fw["adc.gain_cm_per_count"], rel=1e-7)
    assert round(ours["adc.raw_min_counts"]) == fw["adc.raw_min_counts"]
    assert round(ours["adc.wire_break_below_counts"]) == fw["adc.wire_break_below_counts"]
    assert ours["dac.counts_at_zero_kpa"] == fw["dac.counts_at_zero_kpa"]
    assert ours["dac.counts_per_kpa"] == fw["dac.counts_per_kpa"]
    assert ours["dac.max_counts"] == fw["dac.max_counts"]
    assert ours["act.p0_kpa"] == fw["act.p0_kpa"]


# --------------------------------------------------------------- equilibrium
def test_equilibrium_at_p0_is_x_zero():
    rig = Rig(quiet())
    assert rig.x_cm == 0.0 and rig.v_cm_s == 0.0
    assert rig.static_x_cm(rig.params.p0_kpa) == pytest.approx(0.0, abs=1e-12)
    assert rig.p_cmd_for_x_cm(0.0) == pytest.approx(rig.params.p0_kpa, abs=1e-6)
    hold(rig, rig.params.p0_kpa, 3.0)
    assert abs(rig.x_cm) < 1e-3  # only the slow temperature drift moves it
    assert abs(rig.v_cm_s) < 1e-3
    # sensor reads mid-range: 12 mA
    assert rig.sensor_counts() == 2457


def test_x0_follows_p0_and_the_start_pressure_option():
    lo = Rig(quiet(p0_kpa=200.0))
    hi = Rig(quiet(p0_kpa=400.0))
    assert lo.x0_contraction_mm < hi.x0_contraction_mm  # higher preset, more contraction at x = 0
    assert lo.x_cm == 0.0 and hi.x_cm == 0.0
    vented = Rig(quiet(initial_p_kpa=0.0))
    assert vented.x_cm == pytest.approx(vented.static_x_cm(0.0))
    assert vented.x_cm > 1.0  # relaxed muscle: longer, so x > 0 in the paper's sign


# ------------------------------------------------------------ static gain
def test_static_gain_sign_and_magnitude():
    p = quiet(**{"muscle.hyst_force_n": 0.0, "drift.temp_rate_k_per_s": 0.0, "regulator.hysteresis_frac_fs": 0.0})
    rig = Rig(p)
    # independent estimate from the published numbers at the actual p0 pressure:
    # d(xs)/dP = (F1 + K1 xs0) / K, F1 from Martens's two points, K1, K from Serres x scale
    f1 = (542.5 - 283.8) / (650 - 360)
    scale = (542.5 / 21.0) / (17 + 0.0179 * 650)
    pa = rig.regulator_static_kpa(300.0)
    k_lo = (32.7 - 0.0321 * pa) * scale
    expect_mm_per_kpa = (f1 + 0.0321 * scale * rig.x0_contraction_mm) / k_lo
    slope = (rig.static_x_cm(300.1) - rig.static_x_cm(299.9)) / 0.2
    dlin = (rig.regulator_static_kpa(300.1) - rig.regulator_static_kpa(299.9)) / 0.2
    assert slope < 0  # more pressure, more contraction, x more negative (the paper's sign)
    assert -slope / dlin == pytest.approx(expect_mm_per_kpa / 10.0, rel=0.03)
    lin = rig.linearised_eq7()
    assert lin["H_cm_s2_per_kpa"] < 0 and lin["static_gain_cm_per_kpa"] == pytest.approx(slope, rel=1e-3)
    # simulated: a +20 kPa step settles where the static model says
    hold(rig, 320.0, 2.5)
    assert rig.x_cm == pytest.approx(rig.static_x_cm(320.0), abs=3e-4)
    # the whole regulator range moves the muscle over about Festo's 25 % stroke
    span = rig.static_x_cm(0.0) - rig.static_x_cm(900.0)
    assert 2.2 < span < 2.8


def test_sign_convention_switch():
    neg = Rig(quiet())
    pos = Rig(quiet(contraction_is_negative_x=False))
    assert neg.static_x_cm(400.0) == pytest.approx(-pos.static_x_cm(400.0))
    assert pos.linearised_eq7()["H_cm_s2_per_kpa"] > 0


def test_paper_band_reachability_in_cm():
    """Documented finding: with p0 = 300 kPa the paper's references (x down to
    -2.5 cm) are out of reach of a MAS-10-100N; with p0 near 60 kPa they need up
    to about 900 kPa."""
    rig = Rig(quiet())
    assert rig.p_cmd_for_x_cm(-1.0) is not None
    assert rig.p_cmd_for_x_cm(-2.0) is None
    low = Rig(quiet(p0_kpa=60.0))
    maybe = [low.p_cmd_for_x_cm(x) for x in (-1.5, -2.0, -2.5)]
    p_for = [p for p in maybe if p is not None]
    assert len(p_for) == len(maybe)
    assert 400 < p_for[0] < p_for[1] < p_for[2] <= 900


# -------------------------------------------------------- stability, energy
def test_long_random_input_stays_finite_and_bounded():
    rng = np.random.default_rng(42)
    rig = Rig(RigParams(), seed=3)
    t_next = 0.0
    counts = rig.kpa_to_dac(300.0)
    xs, ps_l, cs_l = [], [], []
    for k in range(15000):
        if rig.time_s >= t_next:
            counts = int(rng.choice([0, 4095, int(rng.integers(0, 4096))], p=[0.1, 0.1, 0.8]))
            t_next = rig.time_s + float(rng.uniform(0.001, 0.3))
        if k == 5000:
            rig.set_load_mass(8.0)
        if k == 8000:
            rig.set_disturbance(60.0)
        if k == 11000:
            rig.set_load_mass(0.5)
            rig.set_disturbance(0.0)
        rig.apply_dac(counts)
        rig.step(DT)
        xs.append(rig.x_cm)
        ps_l.append(rig.p_kpa)
        cs_l.append(rig.contraction_mm)
        rig.sensor_counts()
    xs_a, ps, cs = np.array(xs), np.array(ps_l), np.array(cs_l)
    assert np.all(np.isfinite(xs_a)) and np.all(np.isfinite(ps))
    assert ps.min() >= -1e-9 and ps.max() <= 900.0 + 1e-9
    assert np.allclose(cs, rig.x0_contraction_mm - 10.0 * xs_a)  # the paper's sign: contraction -> x < 0
    # physically possible lengths: from stretched by 8 kg + 60 N to about 26 % contraction
    lo_mm = -(8.0 * 9.81 + 60.0) / min(rig._k_of_p(p) for p in (0.0, 300.0, 900.0)) - 0.5
    assert cs.min() > lo_mm
    assert cs.max() < 27.0
    assert np.all(np.isfinite([rig.state()[k] for k in rig.state()]))
    # passive: with the input held, the motion dies out
    hold(rig, 250.0, 3.0)
    assert abs(rig.v_cm_s) < 1e-4


# ------------------------------------------------------------ RK4 order
def _run_sine(substep: float, **changes) -> np.ndarray:
    rig = Rig(quiet(substep_s=substep, **changes))
    for k in range(300):
        if k % 20 == 0:
            rig.apply_pressure_kpa(300.0 + 150.0 * math.sin(2 * math.pi * k / 150.0))
        rig.step(DT)
    return np.array([rig.contraction_mm, rig._s[1]])


def test_rk4_converges_at_fourth_order_on_a_smooth_configuration():
    smooth = {"muscle.hyst_force_n": 0.0, "muscle.b_blend_mm_s": 5.0}
    ref = _run_sine(2.5e-5, **smooth)
    e = [np.abs(_run_sine(h, **smooth) - ref).max() for h in (4e-4, 2e-4, 1e-4)]
    # halving the step divides the error by about 2^4 = 16
    assert 10.0 < e[0] / e[1] < 24.0
    assert 10.0 < e[1] / e[2] < 24.0


def test_rk4_full_model_converges_and_the_default_step_is_accurate():
    ref = _run_sine(1e-5)
    e = {h: np.abs(_run_sine(h) - ref)[0] for h in (4e-4, 1e-4, 2.5e-5)}
    assert e[4e-4] > e[1e-4] > e[2.5e-5]
    assert e[1e-4] < 1e-5  # mm: far below the sensor's 30 um count


# ------------------------------------------------------------ regulator
def test_regulator_dead_time_and_lag_from_a_step():
    p = quiet(**{"regulator.linearity_frac_fs": 0.0, "regulator.hysteresis_frac_fs": 0.0})
    rig = Rig(p)
    r = rig.params.regulator
    rig.apply_pressure_kpa(300.0)
    rig.step(0.05)
    rig.apply_dac(rig.kpa_to_dac(400.0))  # 1820 counts = 400 kPa
    p_i, p_f = rig.p_kpa, rig.p_cmd_kpa
    t0 = rig.time_s
    ts_l, pr_l = [], []
    for _ in range(2000):
        rig.step(1e-4)
        ts_l.append(rig.time_s - t0)
        pr_l.append(rig.p_kpa)
    ts, pr = np.array(ts_l), np.array(pr_l)
    frac = (pr - p_i) / (p_f - p_i)
    # dead time: nothing moves before it
    assert np.all(np.abs(frac[ts < r.dead_time_s - 1e-9]) < 1e-12)
    t_dead = ts[np.argmax(frac > 1e-6)]
    assert t_dead == pytest.approx(r.dead_time_s, abs=1.1e-4)
    # first-order lag: 63.2 % one tau after the dead time, exactly the exponential
    t63 = ts[np.argmax(frac >= 1 - math.exp(-1))]
    assert t63 - r.dead_time_s == pytest.approx(r.tau_s, abs=2e-4)
    after = ts > r.dead_time_s
    model = 1 - np.exp(-(ts[after] - r.dead_time_s) / r.tau_s)
    assert np.max(np.abs(frac[after] - model)) < 1e-6


def test_regulator_hysteresis_and_linearity_are_bounded_by_the_datasheet():
    rig = Rig(quiet())
    r = rig.params.regulator
    errs = [rig.regulator_static_kpa(p) - p for p in np.linspace(0, 900, 91)]
    assert max(abs(e) for e in errs) <= r.linearity_frac_fs * r.fs_kpa + 1e-9
    # backlash: approaching 400 kPa from below and from above differs by 0.5 % FS
    hold(rig, 500.0, 0.01)
    hold(rig, 400.0, 0.5)
    from_above = rig.p_kpa
    hold(rig, 300.0, 0.01)
    hold(rig, 400.0, 0.5)
    from_below = rig.p_kpa
    assert from_above - from_below == pytest.approx(r.hysteresis_frac_fs * r.fs_kpa, rel=0.05)


# ----------------------------------------------------- quantisation, sensor
def test_dac_quantisation_and_range():
    rig = Rig(quiet())
    rig.apply_dac(1365)
    assert rig.p_cmd_kpa == pytest.approx(300.0)
    rig.apply_dac(1366)
    assert rig.p_cmd_kpa == pytest.approx(1366 / 4.55)
    assert rig.kpa_to_dac(300.1) == 1365  # 1 count = 0.22 kPa
    rig.apply_dac(70000)
    assert rig.dac_counts == 4095 and rig.p_cmd_kpa == pytest.approx(900.0)
    rig.apply_dac(-5)
    assert rig.dac_counts == 0 and rig.p_cmd_kpa == 0.0


def test_sensor_quantisation_matches_the_firmware_conversion():
    fw = firmware_defaults()
    rig = Rig(quiet(**{"sensor.tau_s": 0.0}))
    hold(rig, 420.0, 1.5)
    c = rig.sensor_counts()
    assert isinstance(c, int)
    x_fw = fw["adc.offset_cm"] + fw["adc.gain_cm_per_count"] * c
    assert abs(x_fw - rig.x_cm) <= abs(fw["adc.gain_cm_per_count"]) / 2 + 1e-9
    # with noise: samples scatter around the truth by about the set noise
    noisy = Rig(RigParams(), seed=7)
    xs = np.array([fw["adc.offset_cm"] + fw["adc.gain_cm_per_count"] * noisy.sensor_counts() for _ in range(4000)])
    assert abs(xs.mean()) < 3e-4
    assert 0.5e-3 < xs.std() < 2.0e-3  # 5 um noise plus 0.3 counts plus the 30 um step


def test_wire_break_and_laser_out_of_range():
    fw = firmware_defaults()
    rig = Rig(RigParams(), seed=1)
    rig.break_wire(True)
    assert all(rig.sensor_counts() < fw["adc.wire_break_below_counts"] for _ in range(200))
    rig.break_wire(False)
    assert abs(rig.sensor_counts() - 2457) <= 3
    # the laser loses its target: drops to 4 mA = 819 counts, which the firmware's
    # default scaling reads as x = +5 cm (inside 778..4094: not a range fault)
    rig.set_sensor_blocked(True)
    c = [rig.sensor_counts() for _ in range(200)]
    assert all(abs(v - 819) <= 2 for v in c)
    assert fw["adc.offset_cm"] + fw["adc.gain_cm_per_count"] * 819 == pytest.approx(5.0, abs=0.01)
    rig.set_sensor_blocked(False)
    # a narrow sensor: the vented muscle (x about +1.1 cm) leaves its range -> 4 mA
    narrow = Rig(quiet(**{"sensor.span_cm": 1.0}))
    assert narrow.sensor_counts() != 819  # in range at x0
    hold(narrow, 0.0, 2.0)
    assert narrow.x_cm > 0.5
    assert narrow.sensor_counts() == 819
    # a 0-10 V style sensor (bottom of range 0): out of range gives 0 counts
    volt = Rig(quiet(**{"sensor.out_of_range_ma": 0.0}))
    volt.set_sensor_blocked(True)
    assert volt.sensor_counts() == 0


def test_sensor_lag_and_noise_free_reading_follow_the_position():
    rig = Rig(quiet())
    hold(rig, 500.0, 0.2)
    assert rig.x_sensor_cm != rig.x_cm  # first-order response of the laser output
    assert abs(rig.x_sensor_cm - rig.x_cm) < 0.01
    hold(rig, 500.0, 1.5)
    assert rig.x_sensor_cm == pytest.approx(rig.x_cm, abs=1e-6)


# ---------------------------------------------------------- load, disturbance
def test_load_change_and_disturbance_move_the_equilibrium_by_f_over_k():
    p = quiet(**{"muscle.hyst_force_n": 0.0, "drift.temp_rate_k_per_s": 0.0})
    rig = Rig(p)
    hold(rig, 300.0, 0.5)
    k = rig._k_of_p(rig.p_kpa)
    rig.set_load_mass(2.55 + 2.0)
    hold(rig, 300.0, 2.0)
    assert rig.x_cm == pytest.approx(2.0 * 9.80665 / k / 10.0, rel=0.01)  # longer: x > 0
    assert rig.load_mass_kg == 4.55
    x_before = rig.x_cm
    rig.set_disturbance(20.0, t_on_s=rig.time_s + 0.5)
    hold(rig, 300.0, 0.45)
    assert rig.disturbance_force_n == 0.0 and rig.x_cm == pytest.approx(x_before, abs=1e-9)
    hold(rig, 300.0, 0.05 + p.load.disturbance_tau_s)
    assert rig.disturbance_force_n == pytest.approx(20.0 * (1 - math.exp(-1)), rel=0.02)
    hold(rig, 300.0, 2.0)
    assert rig.x_cm - x_before == pytest.approx(20.0 / k / 10.0, rel=0.01)
    rig.set_disturbance(0.0)
    hold(rig, 300.0, 2.0)
    assert rig.x_cm == pytest.approx(x_before, abs=1e-4)


# ----------------------------------------------------- drift and hysteresis
def test_drift_is_visible_and_bounded():
    p = quiet(**{"muscle.hyst_force_n": 0.0, "drift.temp_rate_k_per_s": 1.0, "drift.temp_max_rise_k": 5.0})
    rig = Rig(p)
    hold(rig, 300.0, 6.0)
    x6 = rig.x_cm
    expect = rig.static_x_cm(300.0, temp_rise_k=5.0)
    assert rig.temperature_rise_k == 5.0
    assert abs(x6) > 0.003  # visible: more than one sensor count (0.003 cm)
    assert x6 == pytest.approx(expect, rel=0.02)
    hold(rig, 300.0, 3.0)
    assert rig.x_cm == pytest.approx(x6, abs=1e-5)  # stops at the maximum rise
    # the default rate over a 180 s run moves x0 by less than a tenth of w1 = 0.2 cm
    d = Rig(quiet())
    assert abs(d.static_x_cm(300.0, temp_rise_k=RigParams().drift.temp_rate_k_per_s * 180)) < 0.02


def _staircase(rig: Rig, levels) -> list[float]:
    out = []
    for p in levels:
        hold(rig, p, 1.0)
        out.append(rig.x_cm)
    return out


def test_hysteresis_loop_is_visible_and_bounded():
    rig = Rig(quiet(**{"regulator.hysteresis_frac_fs": 0.0, "drift.temp_rate_k_per_s": 0.0}))
    hold(rig, 100.0, 1.0)
    up = _staircase(rig, [150.0, 200.0, 250.0, 300.0, 350.0, 400.0, 450.0, 500.0])
    down = _staircase(rig, [450.0, 400.0, 350.0, 300.0])
    width = down[-1] - up[3]  # at 300 kPa: falling branch is more contracted (more negative x)
    expect = rig.static_x_cm(300.0, friction=1) - rig.static_x_cm(300.0, friction=-1)
    assert width < 0
    assert abs(width) == pytest.approx(expect, rel=0.1)
    # the published loop: about 16 % of the 0-600 kPa stroke at 300 kPa; bounded well below the band
    light = Rig(quiet(**{"load.mass_kg": 1e-9}))
    stroke = light.static_x_cm(0.0) - light.static_x_cm(600.0)
    assert 0.10 < abs(width) / stroke < 0.25
    assert abs(width) < 0.5
    # without friction no loop
    flat = Rig(quiet(**{"regulator.hysteresis_frac_fs": 0.0, "muscle.hyst_force_n": 0.0,
                        "drift.temp_rate_k_per_s": 0.0}))
    hold(flat, 100.0, 1.0)
    u2 = _staircase(flat, [200.0, 300.0, 400.0])
    d2 = _staircase(flat, [300.0])
    assert abs(d2[0] - u2[1]) < 1e-3


# ---------------------------------------------------------- determinism, API
def _trace(seed: int) -> tuple[list[int], list[float]]:
    rig = Rig(RigParams(), seed=seed)
    rng = np.random.default_rng(0)
    counts, xs = [], []
    for k in range(600):
        if k % 50 == 0:
            c = int(rng.integers(1000, 2500))
        rig.apply_dac(c)
        rig.step(DT)
        counts.append(rig.sensor_counts())
        xs.append(rig.x_cm)
    return counts, xs


def test_determinism_with_a_seed():
    a, b, c = _trace(11), _trace(11), _trace(12)
    assert a == b
    assert a[0] != c[0]  # the seed drives the noise ...
    assert a[1] == c[1]  # ... and nothing else


def test_params_from_dict_round_trip_and_errors():
    muscle: dict[str, Any] = {"hyst_force_n": 0, "hyst_delta_mm": [0.2, 0.4]}
    d = {"p0_kpa": 250, "muscle": muscle, "load": {"mass_kg": 3}}
    with pytest.raises(ValueError):
        RigParams.from_dict(d)  # two deltas but four weights
    muscle["hyst_weights"] = [0.5, 0.5]
    p = RigParams.from_dict(d)
    p.validate()
    assert p.p0_kpa == 250.0 and p.load.mass_kg == 3.0 and p.muscle.hyst_delta_mm == (0.2, 0.4)
    assert p.regulator.tau_s == RigParams().regulator.tau_s  # untouched defaults stay
    assert RigParams.from_dict(p.to_dict()) == p
    with pytest.raises(ValueError):
        RigParams.from_dict({"muscle": {"no_such": 1}})
    with pytest.raises(ValueError):
        RigParams.from_dict({"regulator": {"tau_s": 0}})
    rig = Rig.from_dict({"sensor": {"noise_cm": 0}}, seed=2)
    assert rig.params.sensor.noise_cm == 0.0 and rig.seed == 2
    assert set(rig.state()) >= {"t_s", "x_cm", "v_cm_s", "p_kpa", "p_cmd_kpa"}


def test_time_and_substeps():
    rig = Rig(RigParams())
    for _ in range(1000):
        rig.step(DT)
    assert rig.time_ns == 1_000_000_000 and rig.time_s == 1.0
    assert rig.substep_s == pytest.approx(1e-4)
    heavy = Rig(quiet(**{"load.mass_kg": 0.05}))  # tiny mass: a stiff mode; the sub-step shrinks
    assert heavy.substep_s < 1e-4
    hold(heavy, 500.0, 0.3)
    assert math.isfinite(heavy.x_cm)


def test_substep_250us_matches_100us():
    """The HIL scenarios integrate with 4 RK4 sub-steps per 1 ms tick (substep_s 2.5e-4,
    for speed). Under a fast, switching pressure command the position stays within
    1e-5 cm (0.1 um, 50 times below the sensor noise) of the default 1e-4 s sub-step."""
    def run(h: float) -> np.ndarray:
        rig = Rig(RigParams.from_dict({"p0_kpa": 60.0, "substep_s": h}), seed=1)
        xs = []
        for k in range(3000):
            p = 400.0 + 300.0 * math.sin(2 * math.pi * 2 * k * 1e-3) + (200.0 if (k // 37) % 2 else 0.0)
            rig.apply_dac(int(round(p * 4.55)))
            rig.step(1e-3)
            xs.append(rig.x_cm)
        return np.array(xs)
    fine, coarse = run(1e-4), run(2.5e-4)
    assert np.ptp(fine) > 1.0                      # the command really moves the muscle
    assert np.max(np.abs(fine - coarse)) < 1e-5


# ------------------------------------------------------ every value typed and in range --
@pytest.mark.parametrize("data, message", [
    ({"load": {"bias_force_n": math.nan}}, "load.bias_force_n must be finite"),
    ({"load": {"g_m_s2": math.inf}}, "load.g_m_s2 must be finite"),
    ({"muscle": {"hyst_delta_mm": [0.1, math.nan, 0.5, 1.0]}}, r"muscle.hyst_delta_mm\[1\] must be finite"),
    ({"initial_p_kpa": math.nan}, "initial_p_kpa must be finite"),
    ({"load": {"incline_deg": 120.0}}, "load.incline_deg"),
    ({"sensor": {"shunt_ohm": 0.0}}, "sensor.shunt_ohm"),
    ({"sensor": {"adc_bits": 0}}, "sensor.adc_bits"),
    ({"regulator": {"fs_kpa": -1.0}}, "regulator.fs_kpa"),
    ({"p0_kpa": 2000.0}, "p0_kpa"),
    ({"contraction_is_negative_x": "false"}, "expected true or false"),
    ({"sensor": {"inverted": 0}}, "expected true or false"),
    ({"load": {"mass_kg": "3"}}, "expected a number"),
    ({"load": {"mass_kg": True}}, "expected a number"),
    ({"sensor": {"adc_bits": 11.5}}, "expected an integer"),
    ({"muscle": {"hyst_weights": "abcd"}}, "expected an array of numbers"),
    ({"valve": {"model": 3}}, "expected text"),
    ({"profile": 3}, "profile"),
    ({"load": 5}, "expected a table"),
])
def test_every_rig_value_is_typed_finite_and_in_its_range(data, message):
    with pytest.raises(ValueError, match=message):
        RigParams.from_dict(data)


def test_rig_values_from_the_command_line_are_parsed_by_their_type():
    from hil.rig_params import parse_text
    assert parse_text("contraction_is_negative_x", "false") is False
    assert parse_text("sensor.inverted", "1") is True and parse_text("sensor.inverted", "FALSE") is False
    assert parse_text("sensor.adc_bits", "11") == 11 and parse_text("load.mass_kg", "3") == 3.0
    assert parse_text("valve.model", "flow") == "flow"
    for path, text, message in [("contraction_is_negative_x", "no", "true or false"),
                                ("sensor.adc_bits", "11.5", "integer"), ("load.mass_kg", "heavy", "number"),
                                ("load", "5", "group"), ("load.nope", "1", "no such"),
                                ("muscle.hyst_weights", "1", "array")]:
        with pytest.raises(ValueError, match=message):
            parse_text(path, text)


# ------------------------------------------------------- libpma_rig.so (hil/rig_core)
def test_a_rig_pickled_or_copied_mid_run_goes_on_exactly_as_the_original():
    """A run's result crosses processes with its rig (hil/offline.py --jobs): the state in the C
    library's arrays, the disturbance profile and the queued commands survive the copy."""
    import copy
    import pickle

    from hil.rig_profiles import profile_dict
    for data in ({}, profile_dict("dmsp10")):
        rig = Rig.from_dict(data, seed=4)
        rig.set_disturbance(15.0)
        for k in range(300):
            rig.apply_dac(1500 + 5 * k)
            rig.step(DT)
        copies = [pickle.loads(pickle.dumps(rig)), copy.deepcopy(rig)]
        for r in [rig, *copies]:
            for k in range(300):
                r.apply_dac(3000 - 3 * k)
                r.step(DT)
        assert all(r.state() == rig.state() and r.sensor_counts() == rig.sensor_counts() for r in copies)


def test_more_hysteresis_elements_than_the_c_model_holds_are_refused_by_name():
    from hil.rig_lib import MAX_HYST
    n = MAX_HYST + 1
    with pytest.raises(ValueError, match="muscle.hyst_delta_mm.*at most"):
        RigParams.from_dict({"muscle": {"hyst_delta_mm": [0.1] * n, "hyst_weights": [1.0 / n] * n}})


def test_the_array_sizes_come_from_the_c_header(tmp_path, monkeypatch):
    from hil import rig_lib
    # the shipped header: the state length is its expression of the hysteresis elements
    assert rig_lib.MAX_STATE == 4 + rig_lib.MAX_HYST + 2
    assert rig_lib.library().pma_rig_max_state() == rig_lib.MAX_STATE
    header = tmp_path / "h.h"
    header.write_text("#define A 3\n#define B (A * 2 + 1) /* a comment */\n#define C ((B - A) * 2)\n"
                      "#define D (A / 2)\n#define E foo(1)\n#define F\n")
    monkeypatch.setattr(rig_lib, "HEADER", header)
    assert [rig_lib._header_int(n) for n in "ABC"] == [3, 7, 8]
    for name in "DEFG":   # a division, a call, no value, no such #define
        with pytest.raises(ImportError, match=f"{name}"):
            rig_lib._header_int(name)


def test_the_model_layout_comes_from_the_c_header(tmp_path, monkeypatch):
    from hil import rig_lib
    header = tmp_path / "h.h"
    monkeypatch.setattr(rig_lib, "HEADER", header)
    header.write_text("#define N (2 + 1)\ntypedef struct {\n    double a, b[N]; /* two; b: three */\n"
                      "    const int64_t *t; /* c */ int32_t n;\n    const double *p;\n    int64_t k[4];\n} m_t;\n")
    assert [(name, t) for name, t in rig_lib._struct_fields("m_t")] == [
        ("a", ctypes.c_double), ("b", ctypes.c_double * 3), ("t", ctypes.POINTER(ctypes.c_int64)),
        ("n", ctypes.c_int32), ("p", ctypes.POINTER(ctypes.c_double)), ("k", ctypes.c_int64 * 4)]
    for text, match in (("typedef struct { float f; } m_t;", "does not map"),
                        ("typedef struct { double f[M]; } m_t;", "no integer #define M"),
                        ("typedef struct { double f g; } m_t;", "cannot read the field"),
                        ("typedef struct { double f; } other_t;", "no typedef struct m_t")):
        header.write_text(text + "\n")
        with pytest.raises(ImportError, match=match):
            rig_lib._struct_fields("m_t")


def test_a_missing_or_foreign_rig_library_says_how_to_build_it(tmp_path):
    from hil.rig_lib import API_VERSION, BUILD_HINT, MAX_STATE, Model, RigLibError, _load
    with pytest.raises(RigLibError, match="not found.*" + BUILD_HINT.split()[0]):
        _load(tmp_path / "libpma_rig.so")
    (tmp_path / "bad.so").write_bytes(b"not an ELF file")
    with pytest.raises(RigLibError, match="cannot load"):
        _load(tmp_path / "bad.so")
    # a library of another API version, which lacks this version's functions: its version named,
    # not a missing symbol
    src = tmp_path / "old.c"
    src.write_text("int pma_rig_core_api_version(void) { return API_VERSION - 1; }\n"
                   .replace("API_VERSION", str(API_VERSION)))
    subprocess.run(["cc", "-shared", "-fPIC", "-o", str(tmp_path / "old.so"), str(src)], check=True)
    with pytest.raises(RigLibError, match=f"API version {API_VERSION - 1}, .* needs {API_VERSION}: rebuild"):
        _load(tmp_path / "old.so")
    # this version, built with a longer state than the buffer Python hands it (C would write past it)
    src.write_text("\n".join(f"int {name}(void) {{ return {value}; }}" for name, value in (
        ("pma_rig_core_api_version", API_VERSION), ("pma_rig_model_size", ctypes.sizeof(Model)),
        ("pma_rig_max_state", MAX_STATE + 1))) + "\nint pma_rig_state_len(void) { return 0; }"
                   "\nint pma_rig_advance(void) { return 0; }\ndouble pma_rig_disturbance_n(void) { return 0; }\n")
    subprocess.run(["cc", "-shared", "-fPIC", "-o", str(tmp_path / "long.so"), str(src)], check=True)
    with pytest.raises(RigLibError, match=f"a state of {MAX_STATE + 1} variables, .*'s {MAX_STATE}: rebuild"):
        _load(tmp_path / "long.so")


def test_a_model_the_c_library_cannot_hold_is_an_error_not_a_silent_standstill():
    from hil.rig_lib import MAX_HYST, RigLibError
    rig = Rig(quiet(), seed=1)
    rig._model.n_hyst = MAX_HYST + 1        # what RigParams.validate refuses before it gets there
    with pytest.raises(RigLibError, match="refused the model"):
        rig.step(DT)
