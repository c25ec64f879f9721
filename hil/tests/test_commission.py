# SPDX-License-Identifier: Apache-2.0
"""`pmactl commission` (docs/commissioning.md): the derivation on synthetic data with known
answers, and the procedure over CAN frames against the real firmware on the simulated rig
(hil/offline_bus.py: python-can's bus API, libpma_offline.so behind it, no vcan): what it
derives, what it refuses, and that it leaves the node as it found it.

    .venv/bin/python -m pytest -q hil/tests/test_commission.py
"""
from __future__ import annotations

import math
import tomllib
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import pmactl.commission_rules as rules
from hil import offline
from hil import scenario as scn
from hil.commissioned import before_commissioning
from hil.offline_bus import OfflineBus
from pmactl import cli, commission_report
from pmactl.client import NodeStateError, PmaNode
from pmactl.commission import TOUCHED, CommissionAborted, Commissioning, Result
from pmactl.commission_rules import (
    CommissionError,
    Measured,
    StaticMap,
    StepFit,
    Task,
    derive,
    fit_step,
    law_margins,
    law_noise_rate,
    loop_margins,
    mfac_phi1,
)

TASK = Task(w1_cm=0.2, t_u_s=2.0, x_min_cm=-3.0, x_max_cm=0.0, x_start_cm=-2.0)
NOISY_CM = 0.005   # a sensor whose noise through the law moves the input more than 3.5x the need


# ------------------------------------------------------------------ the rules --
def test_fit_step_finds_a_known_fopdt():
    rng = np.random.default_rng(1)
    t = np.arange(0.0, 1.0, 1e-3)
    gain, tau, theta, dp = -0.004, 0.05, 0.012, 40.0
    x = -1.0 + gain * dp * np.where(t > theta, 1 - np.exp(-(t - theta) / tau), 0.0) + rng.normal(0, 2e-4, t.size)
    f = fit_step(t, x, 300.0, dp)
    assert f.gain_cm_per_kpa == pytest.approx(gain, rel=0.03)
    assert f.tau_s == pytest.approx(tau, rel=0.1)
    assert f.theta_s == pytest.approx(theta, abs=0.004)


def test_first_movement_shows_the_dead_time_a_slow_tail_hides():
    """A response with a dead time, a fast part and a slow tail (creep, a slow valve stage):
    the two-point fit, dominated by the tail, puts its dead time near zero; the first movement
    finds the dead time, and the rules take that."""
    rng = np.random.default_rng(2)
    t = np.arange(0.0, 1.0, 1e-3)
    theta, dp, noise = 0.035, -45.0, 1.4e-3
    moving = np.where(t > theta, 1.0, 0.0)
    shape = moving * (0.3 * (1 - np.exp(-(t - theta) / 0.02)) + 0.7 * (1 - np.exp(-(t - theta) / 0.35)))
    x = -1.0 + 0.19 * shape + rng.normal(0, noise, t.size)
    f = fit_step(t, x, 300.0, dp, noise_cm=noise)
    assert f.theta_s < 0.01                                 # what the fit alone would give
    assert f.first_move_s == pytest.approx(theta, abs=0.006)
    assert math.isnan(fit_step(t, x, 300.0, dp).first_move_s)      # no noise given: not measured
    small = -1.0 + 5 * noise * shape + rng.normal(0, noise, t.size)
    assert math.isnan(fit_step(t, small, 300.0, dp, noise_cm=noise).first_move_s)   # too small to tell
    m = _measured(theta=0.0, tau=0.2)
    for s in m.steps:
        s.first_move_s = f.first_move_s
    d = derive(m, TASK)
    assert d.figures["theta_s"] == pytest.approx(f.first_move_s) and d.figures["theta_fit_s"] == 0.0
    assert d.figures["kc_u_per_cm"] < derive(_measured(theta=0.0, tau=0.2), TASK).figures["kc_u_per_cm"]


def test_early_lag_shows_the_fast_part_a_slow_tail_hides():
    """A response whose fast part is followed by a slow tail fits as a long lag; the early lag
    (10 % to 35 % of the step) is that of the fast part, and the rules design on it: a lower gain
    Kc, the loop's crossover where the fast part is. On a plain FOPDT the early lag is the lag,
    and the design does not change."""
    rng = np.random.default_rng(3)
    t = np.arange(0.0, 1.0, 1e-3)
    theta, dp, noise = 0.035, -45.0, 1.4e-3
    moving = np.where(t > theta, 1.0, 0.0)
    fast_tau, slow_tau = 0.04, 0.5
    shape = moving * (0.6 * (1 - np.exp(-(t - theta) / fast_tau)) + 0.4 * (1 - np.exp(-(t - theta) / slow_tau)))
    f = fit_step(t, -1.0 + 0.19 * shape + rng.normal(0, noise, t.size), 300.0, dp, noise_cm=noise)
    # the fit's lag is the tail's; the early lag is within 2.5x the fast part's (0.6 of the step
    # in it: from 10 % to 35 % a single lag 0.6 / 0.35 slower than the fast part alone)
    assert f.tau_s > 4 * fast_tau
    assert fast_tau <= f.tau_early_s <= 2.5 * fast_tau
    fopdt = moving * (1 - np.exp(-(t - theta) / 0.05))
    g = fit_step(t, -1.0 + 0.19 * fopdt + rng.normal(0, noise, t.size), 300.0, dp, noise_cm=noise)
    assert g.tau_early_s == pytest.approx(g.tau_s, rel=0.25)
    assert math.isnan(fit_step(t, -1.0 + 0.19 * shape, 300.0, dp).tau_early_s)   # no noise given: not measured
    small = -1.0 + 5 * noise * shape + rng.normal(0, noise, t.size)
    assert math.isnan(fit_step(t, small, 300.0, dp, noise_cm=noise).tau_early_s)   # too small to tell

    tail, plain = _measured(tau=f.tau_s), _measured(tau=f.tau_s)
    for s in tail.steps:
        s.tau_early_s = f.tau_early_s
    for s in plain.steps:
        s.tau_early_s = 2 * f.tau_s          # an early part slower than the fit: the fit's lag stands
    d_tail, d_plain, d_fit = derive(tail, TASK), derive(plain, TASK), derive(_measured(tau=f.tau_s), TASK)
    assert d_tail.figures["tau_s"] == pytest.approx(f.tau_early_s)
    assert d_plain.figures == d_fit.figures
    assert d_tail.figures["kc_u_per_cm"] < d_fit.figures["kc_u_per_cm"]


def test_loop_gain_is_the_median_of_the_steps_slopes():
    """Three steps into the hysteresis' dead band (next to no movement, their lags noise) and
    three that move on a long lag: the loop's gain at its crossover is each step's g / tau, their
    median, times the median lag; the ratio of the median gain to the median lag would pair a
    dead-band step's gain with a moving step's lag and design a loop 5/3 times too fast. MFAC's
    reset threshold keeps the median gain (MFAC estimates the step's dx/du)."""
    gains, lags = [-0.0002, -0.0002, -0.0002, -0.004, -0.004, -0.004], [0.02, 0.5, 0.03, 0.3, 0.3, 0.3]
    m = _measured()
    m.steps = [StepFit(300.0 + 100 * i, 40.0, g, tau, 0.01, 0.0) for i, (g, tau) in enumerate(zip(gains, lags))]
    d = derive(m, TASK)
    f = d.figures
    per_s = float(np.median([abs(g) / tau for g, tau in zip(gains, lags)]))
    assert f["tau_s"] == pytest.approx(0.3)
    assert f["loop_gain_cm_per_u"] == pytest.approx(per_s * 0.3)
    assert f["gain_cm_per_u"] == pytest.approx(0.0021)
    assert f["loop_gain_cm_per_u"] / f["gain_cm_per_u"] == pytest.approx(5.0 / 3.0)
    assert f["kc_u_per_cm"] == pytest.approx(0.3 / (f["loop_gain_cm_per_u"] * (f["tau_c_s"] + f["theta_eff_s"])))
    assert d.params["mfac.eps"] == pytest.approx(rules.MFAC_EPS_PER_GAIN * 0.0021)


def test_a_step_that_did_not_move_takes_the_lag_of_those_that_did():
    """On a coarse, noisy sensor the steps into the dead band move less than MOVED_SIGMAS noise
    deviations (no first movement measured) and fit the noise: lags of a sample or two, whose
    slopes g / tau would be the largest of all and design a loop several times too slow. They
    take the median lag of the steps that moved; their gains stay. Where no step's movement was
    measured (no noise given), every fit's lag stands."""
    dead = [StepFit(300.0 + 200 * i, 45.0, -0.0002, tau, 0.0, 0.0) for i, tau in enumerate((2e-4, 1.4e-3, 2e-3))]
    moving = [StepFit(300.0 + 200 * i, -45.0, g, tau, 0.06, 0.0, first_move_s=0.07)
              for i, (g, tau) in enumerate(((-0.004, 0.1), (-0.003, 0.12), (-0.005, 0.09)))]
    m = _measured()
    m.steps = dead + moving
    f = derive(m, TASK).figures
    lag = 0.1                                  # the median of the moving steps' lags
    slopes = [0.0002 / lag] * 3 + [0.004 / 0.1, 0.003 / 0.12, 0.005 / 0.09]
    assert f["tau_s"] == pytest.approx(lag)
    # the median of all six, but at least 1 / GM_MIN of the moving steps' (the next test)
    assert f["loop_gain_cm_per_u"] == pytest.approx(
        max(float(np.median(slopes)), float(np.median(slopes[3:])) / rules.GM_MIN) * lag)
    assert f["gain_cm_per_u"] == pytest.approx(0.0016)          # MFAC's median gain: all six steps
    for s in m.steps:
        s.first_move_s = math.nan                                # nothing measured: the fits stand
    unmeasured = derive(m, TASK).figures
    fitted = [2e-4, 1.4e-3, 2e-3, 0.1, 0.12, 0.09]
    assert unmeasured["loop_gain_cm_per_u"] == pytest.approx(
        float(np.median([abs(s.gain_cm_per_kpa) / t for s, t in zip(m.steps, fitted)])) * float(np.median(fitted)))
    assert f["kc_u_per_cm"] > 1.5 * unmeasured["kc_u_per_cm"]   # the noise fits' loop: that much too slow


def test_loop_gain_keeps_the_moving_steps_within_its_gain_margin():
    """Half the steps into the dead band (next to no gain, no movement measured: the median of all
    six lands between them and the moving ones) and three moving at three times that median: a
    loop shaped on the median would meet three times its gain wherever the muscle moves along a
    branch, beyond the gain margin GM_MIN it keeps. The loop is shaped on 1 / GM_MIN of the
    moving steps' median slope instead, and as built it stays stable at their gain (gain margin
    above 1 there). Where every step moves alike, the median of all stands."""
    lag = 0.15
    dead = [StepFit(300.0 + 200 * i, 45.0, g, lag, 0.05, 0.0) for i, g in enumerate((-0.0001, -0.0001, -0.001))]
    moving = [StepFit(300.0 + 200 * i, -45.0, g, lag, 0.05, 0.0, first_move_s=0.06)
              for i, g in enumerate((-0.0023, -0.0051, -0.0054))]
    m = _measured()
    m.steps = dead + moving
    m.static_map = StaticMap([0.0, 900.0], [-0.3, -2.7], [0.0, 900.0], [-0.4, -2.8])   # 0.0027 cm/kPa
    d = derive(m, TASK)
    f = d.figures
    median_all = float(np.median([0.0001, 0.0001, 0.001, 0.0023, 0.0051, 0.0054]))       # 0.00165
    assert median_all < 0.0051 / rules.GM_MIN
    assert median_all > rules.LOOP_GAIN_PER_MAP_MIN / abs(d.params["ppc.ref_ff"])       # not the map's floor
    assert f["loop_gain_cm_per_u"] == pytest.approx(0.0051 / rules.GM_MIN)
    assert f["loop_gain_moving_cm_per_u"] == pytest.approx(0.0051)
    assert f["loop_gain_median_cm_per_u"] == pytest.approx(median_all)
    assert f["gain_cm_per_u"] == pytest.approx(median_all)        # MFAC's median gain: all six steps
    line = next(x for x in commission_report.text(Result(m, d, {}, 1.0, 1.0)) if x.startswith("step responses"))
    assert "the moving steps' 0.00510 over the gain margin 2" in line
    p = d.params
    as_built = law_margins(f["k_v_u_per_cm_s"], f["k_p_per_s"], p["ppc.ff_gain_per_s"], p["vel.fc_hz"],
                           0.0051, f["tau_s"], f["theta_eff_s"], p["ppc.u_lpf_hz"])
    assert as_built["gain_margin"] > 1.0
    alike = _measured()
    for s in alike.steps:
        s.first_move_s = 0.02
    d_alike = derive(alike, TASK)
    assert d_alike.figures["loop_gain_cm_per_u"] == pytest.approx(0.003)
    line = next(x for x in commission_report.text(Result(alike, d_alike, {}, 1.0, 1.0))
                if x.startswith("step responses"))
    assert "moving steps" not in line


def test_fit_step_refuses_a_flat_or_short_record():
    t = np.arange(0.0, 1.0, 1e-3)
    with pytest.raises(CommissionError):
        fit_step(t[:10], np.zeros(10), 300.0, 40.0)
    with pytest.raises(CommissionError):
        fit_step(t, np.zeros(t.size), 300.0, 40.0)


def _map() -> StaticMap:
    p = [100.0, 300.0, 500.0, 700.0, 900.0]
    return StaticMap(p, [-0.2, -1.0, -1.6, -2.0, -2.4], p, [-0.3, -1.3, -1.9, -2.3, -2.4])


def test_static_map_hold_pressure_is_between_the_branches():
    m = _map()
    assert m.hold_kpa(-1.3) == pytest.approx(0.5 * (400.0 + 300.0))
    assert m.hysteresis_kpa(-1.3) == pytest.approx(100.0)
    with pytest.raises(CommissionError, match="outside the measured stroke"):
        m.hold_kpa(-2.9)


def _measured(theta: float = 0.01, tau: float = 0.05) -> Measured:
    steps = [StepFit(p, s * 40.0, -0.003, tau, theta, 0.0) for p in (300.0, 500.0, 700.0) for s in (1, -1)]
    return Measured(polarity_measured=-1, noise_cm=0.001, static_map=_map(), steps=steps, period_s=1e-3,
                    kpa_per_u=1.0, p_min_kpa=0.0, p_max_kpa=900.0)


def test_derive_follows_the_rules():
    d = derive(_measured(), TASK)
    p = d.params
    assert p["act.polarity"] == -1                     # x falls as the pressure rises
    assert 0.0 < p["act.p0_kpa"] < 900.0
    assert p["ctrl.u_min"] < 0.0 < p["ctrl.u_max"]
    # u = polarity (p - p0): the range maps onto 0..900 kPa exactly
    assert p["act.p0_kpa"] - p["ctrl.u_max"] == pytest.approx(0.0, abs=0.02)
    assert p["act.p0_kpa"] - p["ctrl.u_min"] == pytest.approx(900.0, abs=0.02)
    # SIMC with the tightest tau_c that keeps the margins of the loop as built (theta_eff = theta +
    # one period = 0.011 s), not below tau / 5 = 0.01 s
    f = d.figures
    tau_c = f["tau_c_s"]
    assert tau_c >= max(rules.TAU_C_PER_THETA_MIN * 0.011, 0.05 / rules.SPEEDUP_MAX) - 1e-12
    assert f["kc_u_per_cm"] == pytest.approx(0.05 / (0.003 * (tau_c + 0.011)), rel=1e-6)
    assert p["ppc.w2_cm_s"] == pytest.approx(5.0 * p["ppc.a_cm_s"], rel=1e-3)
    assert f["with_observer_phase_margin_deg"] >= 45.0 and f["with_observer_gain_margin"] >= 2.0
    assert d.margins["phase_margin_deg"] > 45.0 and d.margins["gain_margin"] > 2.0   # the PID's: more
    # the steady-state input at the start position, for the feedforward and MFAC
    assert p["ppc.ff_init"] == p["mfac.u_init"]
    # the integrator waits above the speed from which the loop stops within w1 / 2: the speed the
    # report promises w1 for
    v_max = TASK.w1_cm / (2.0 * (tau_c + f["theta_eff_s"]))
    assert p["ppc.ff_hold_speed_cm_s"] == pytest.approx(v_max, abs=1e-4)
    assert f["v_max_cm_s"] == pytest.approx(v_max, rel=1e-9)
    # the synthetic map reaches -2.4 cm: the band's bottom is out of reach, and said so
    assert len(d.warnings) == 1 and "measured stroke" in d.warnings[0]


def test_loop_gain_is_at_least_a_part_of_the_static_maps():
    """Steps that stay in the hysteresis' dead band read a gain far below the static map's slope:
    the loop is shaped on LOOP_GAIN_PER_MAP_MIN of the map's gain instead (1 / |ppc.ref_ff|), and
    the report says why; steps at the map's gain keep their own."""
    d = derive(_measured(), TASK)
    assert d.figures["loop_gain_cm_per_u"] == pytest.approx(0.003)
    assert not any("dead band" in w for w in d.warnings)
    m = _measured()
    for s in m.steps:
        s.gain_cm_per_kpa = -0.0003                  # a tenth of the steps above
    d = derive(m, TASK)
    map_gain = 1.0 / abs(d.params["ppc.ref_ff"])
    assert 0.0003 < rules.LOOP_GAIN_PER_MAP_MIN * map_gain
    assert d.figures["loop_gain_cm_per_u"] == pytest.approx(rules.LOOP_GAIN_PER_MAP_MIN * map_gain, rel=1e-5)
    assert d.figures["gain_cm_per_u"] == pytest.approx(0.0003)     # MFAC's gain stays the steps'
    assert any("dead band" in w for w in d.warnings)


def test_the_start_is_held_on_the_path_from_the_armed_muscle():
    # ARM raises the pressure to p0 = the middle of the branches at the band's middle (-1.3 cm:
    # 350 kPa), so the armed muscle rests on the rising branch there, at -1.15 cm
    up = _map()
    d = derive(_measured(), TASK)
    p0 = d.params["act.p0_kpa"]
    assert p0 == pytest.approx(350.0)
    assert d.figures["x_armed_cm"] == pytest.approx(-1.15)
    # x falls as the pressure rises (polarity -1): a start at -2 cm lies further along the rising
    # branch, reached by raising the pressure still: held at the rising branch's 700 kPa, not at the
    # middle of the branches (625 kPa); u = polarity (p - p0)
    assert d.figures["p_start_kpa"] == pytest.approx(700.0) and d.figures["start_on_rising_branch"] == 1.0
    assert up.hold_kpa(-2.0) == pytest.approx(625.0)
    assert d.params["ppc.ff_init"] == pytest.approx(-(700.0 - p0))
    assert d.params["mfac.u_init"] == d.params["ppc.ff_init"]
    # a start back from the armed muscle (-0.5 cm) is reached by lowering the pressure, onto a minor
    # loop between the branches: the middle of the branches (175 and 140 kPa)
    back = derive(_measured(), Task(w1_cm=0.2, t_u_s=2.0, x_min_cm=-3.0, x_max_cm=0.0, x_start_cm=-0.5))
    assert back.figures["p_start_kpa"] == pytest.approx(0.5 * (175.0 + 140.0))
    assert back.figures["start_on_rising_branch"] == 0.0
    assert back.params["ppc.ff_init"] == pytest.approx(-(157.5 - p0))
    # the armed position itself: no way to go, the middle
    here = derive(_measured(), Task(w1_cm=0.2, t_u_s=2.0, x_min_cm=-3.0, x_max_cm=0.0, x_start_cm=-1.15))
    assert here.figures["p_start_kpa"] == pytest.approx(up.hold_kpa(-1.15))


def test_derive_gains_fall_with_the_dead_time():
    fast, slow = derive(_measured(theta=0.005), TASK), derive(_measured(theta=0.04), TASK)
    assert slow.params["ppc.a_cm_s"] <= fast.params["ppc.a_cm_s"]   # K_p = 1 / tau_I: the lag's, or slower
    assert slow.figures["kc_u_per_cm"] < fast.figures["kc_u_per_cm"]
    # the margins are the rule's, whatever the lag
    for d in (fast, slow):
        assert _as_built_keeps_margins(d.figures)


def _as_built_keeps_margins(f: dict[str, float], slack: float = 0.0) -> bool:
    return (f["with_observer_phase_margin_deg"] >= rules.PM_MIN_DEG - slack
            and f["with_observer_gain_margin"] >= rules.GM_MIN - slack / 100.0)


def test_derive_relaxes_the_loop_until_its_margins_hold():
    """A lag-free response (theta 0): the tightest tau_c is bounded by tau / SPEEDUP_MAX, and the
    margins the report prints are those of the loop the rule chose."""
    d = derive(_measured(theta=0.0, tau=0.2), TASK)
    assert d.figures["tau_c_s"] >= 0.2 / rules.SPEEDUP_MAX - 1e-12
    assert _as_built_keeps_margins(d.figures)


@pytest.mark.parametrize("theta,tau", [(0.005, 0.05), (0.02, 0.05), (0.063, 0.087), (0.1, 0.18), (0.04, 0.3)])
def test_the_margins_that_decide_are_the_loop_as_built(theta, tau):
    """The rule keeps PM_MIN_DEG and GM_MIN on the loop with the velocity observer in it (the loop
    the node runs), and takes the tightest tau_c that does: 3 % tighter, they fail (unless tau_c
    is at its floor). Shaped on the PID's margins alone, theta 63 ms and tau 87 ms (a
    flow-limited valve with a long dead time) gave tau_c = 0.35 theta_eff and, with the
    observer, 35 deg and a gain margin of 1.5: the loop hunted where the muscle's gain was
    higher than the measured median."""
    d = derive(_measured(theta=theta, tau=tau), TASK)
    f = d.figures
    assert _as_built_keeps_margins(f)
    k = f["tau_c_s"] / f["theta_eff_s"]
    floor = max(rules.TAU_C_PER_THETA_MIN, tau / rules.SPEEDUP_MAX / f["theta_eff_s"])
    if k > floor * 1.03:
        gain = f["loop_gain_cm_per_u"]
        _, tighter = rules._shaped(gain, f["tau_s"], f["theta_eff_s"], d.params["vel.fc_hz"], k / 1.03)
        assert not rules._keeps_margins(tighter)


def test_reference_feedforward_is_the_static_maps_slope_taken_tau_plus_theta_ahead():
    # a linear map with no hysteresis: x = -p / 400 cm, so 400 kPa hold one cm more (u per cm with
    # polarity -1 and 1 kPa per unit: +400, u rising as x rises)
    p = [0.0, 200.0, 400.0, 600.0, 800.0]
    x = [-q / 400.0 for q in p]
    m = _measured(theta=0.02, tau=0.06)
    m.static_map = StaticMap(p, x, p, x)
    task = Task(w1_cm=0.2, t_u_s=2.0, x_min_cm=-3.0, x_max_cm=0.0, x_ref_min_cm=-1.5, x_ref_max_cm=-0.5)
    d = derive(m, task)
    assert d.params["ppc.ref_ff"] == pytest.approx(400.0, rel=1e-4)
    assert d.params["ppc.ref_ff_lead_s"] == pytest.approx(0.06 + 0.02 + 1e-3, abs=1e-4)
    # a steeper map where the reference lives: the slope is taken over the reference's range
    x2 = [0.0, -0.5, -1.0, -1.25, -1.5]         # 400 kPa per cm to -1 cm, 800 beyond
    m.static_map = StaticMap(p, x2, p, x2)
    low = derive(m, Task(w1_cm=0.1, t_u_s=2.0, x_min_cm=-3.0, x_max_cm=0.5, x_ref_min_cm=-1.5, x_ref_max_cm=-1.0))
    assert low.params["ppc.ref_ff"] == pytest.approx(800.0, rel=1e-3)


def test_hysteresis_feedforward_is_a_part_of_the_maps_loop_over_the_dead_bands_width():
    """ppc.ref_ff_hyst: HYST_FF_PART of the half-width of the static map's loop (its median over the
    reference's range); ppc.ref_ff_hyst_cm: the smallest step gain times half that width (how far
    the muscle moves while the pressure crosses the loop), at least what keeps the play within
    HYST_SLOPE_MAX times the map's slope, and at least HYST_PLAY_MIN_CM; its adaptation
    (ppc.ref_ff_hyst_gain_per_s, ppc.ref_ff_hyst_max): HYST_ADAPT_PER_FF of the feedforward
    integrator's gain, within the loop's whole half-width."""
    p = [0.0, 200.0, 400.0, 600.0, 800.0]
    x_up = [-q / 400.0 for q in p]                   # the rising branch 120 kPa above the falling one
    x_down = [-(q + 120.0) / 400.0 for q in p]
    m = _measured()
    m.kpa_per_u = 2.0
    m.static_map = StaticMap(p, x_up, p, x_down)
    m.steps[0].gain_cm_per_kpa = -0.0002            # the step into the dead band
    task = Task(w1_cm=0.2, t_u_s=2.0, x_min_cm=-3.0, x_max_cm=0.0, x_ref_min_cm=-1.5, x_ref_max_cm=-0.7)
    d = derive(m, task)
    assert d.params["ppc.ref_ff_hyst"] == pytest.approx(rules.HYST_FF_PART * 60.0 / 2.0, abs=1e-3)
    assert d.params["ppc.ref_ff_hyst_cm"] == pytest.approx(0.0002 * 60.0, abs=1e-4)
    # adapted on the node within the loop's whole half-width, at a part of the integrator's gain
    assert d.params["ppc.ref_ff_hyst_max"] == pytest.approx(60.0 / 2.0, abs=1e-3)
    assert d.params["ppc.ref_ff_hyst_gain_per_s"] == pytest.approx(
        rules.HYST_ADAPT_PER_FF * d.params["ppc.ff_gain_per_s"], rel=1e-2)
    # no hysteresis: no term and nothing to adapt; an ideal backlash (a dead-band step that does
    # not move): the floor
    m.static_map = StaticMap(p, x_up, p, x_up)
    d0 = derive(m, task)
    assert d0.params["ppc.ref_ff_hyst"] == 0.0
    assert d0.params["ppc.ref_ff_hyst_gain_per_s"] == 0.0 and d0.params["ppc.ref_ff_hyst_max"] == 0.0
    m.static_map = StaticMap(p, x_up, p, x_down)
    m.steps[0].gain_cm_per_kpa = 0.0
    # the map's slope: 400 kPa per cm, 200 input units per cm at 2 kPa per unit
    gentle = rules.HYST_FF_PART * 60.0 / 2.0 / (rules.HYST_SLOPE_MAX * 200.0)
    assert derive(m, task).params["ppc.ref_ff_hyst_cm"] == pytest.approx(gentle, abs=1e-4)
    # a muscle the pressure hardly moves (a steep map): down to the floor
    steep = [-q / 40000.0 for q in p]
    m.static_map = StaticMap(p, steep, p, [-(q + 120.0) / 40000.0 for q in p])
    task_steep = Task(w1_cm=0.002, t_u_s=2.0, x_min_cm=-0.1, x_max_cm=0.0, x_ref_min_cm=-0.015,
                      x_ref_max_cm=-0.007)
    assert derive(m, task_steep).params["ppc.ref_ff_hyst_cm"] == pytest.approx(rules.HYST_PLAY_MIN_CM)


def test_mfac_reset_threshold_is_a_tenth_of_the_measured_gain():
    m = _measured()
    m.kpa_per_u = 2.0                                # gain 0.003 cm/kPa = 0.006 cm per input unit
    d = derive(m, TASK)
    assert d.figures["gain_cm_per_u"] == pytest.approx(0.006)
    assert d.params["mfac.eps"] == pytest.approx(rules.MFAC_EPS_PER_GAIN * 0.006)
    assert d.params["mfac.eps"] < d.params["mfac.phi1"]      # START's rule |phi1| > eps


def test_derive_says_what_the_task_cannot_have():
    noisy = _measured()
    noisy.noise_cm = 0.05
    d = derive(noisy, Task(w1_cm=0.1, t_u_s=0.01, x_min_cm=-3.0, x_max_cm=0.0, speed_cm_s=100.0))
    text = " ".join(d.warnings)
    assert "noise" in text and "speed" in text and "t_u" in text
    with pytest.raises(CommissionError, match="outside the measured stroke"):
        derive(_measured(), Task(w1_cm=0.2, t_u_s=2.0, x_min_cm=-9.0, x_max_cm=-6.0))


def test_a_reference_beyond_the_band_less_w1_is_said():
    """eq. 14: START refuses a reference that does not keep w1 inside the constraints; the report
    says so before the user meets the refusal, and only then."""
    base = dict(w1_cm=0.2, t_u_s=2.0, x_min_cm=-3.0, x_max_cm=0.0)
    inside = derive(_measured(), Task(**base, x_ref_min_cm=-2.5, x_ref_max_cm=-0.5))
    assert not any("BAND" in w for w in inside.warnings)
    for lo, hi in ((-2.9, -0.5), (-2.5, -0.1)):
        beyond = derive(_measured(), Task(**base, x_ref_min_cm=lo, x_ref_max_cm=hi))
        assert any("refuses START (BAND" in w and f"{lo:.3f}..{hi:.3f} cm" in w for w in beyond.warnings)


def test_a_t_u_shorter_than_the_armed_distance_over_the_loops_speed_is_said():
    d = derive(_measured(), TASK)
    f = d.figures
    # ARM raises the pressure to p0: the armed muscle rests on the rising branch there
    p0 = d.params["act.p0_kpa"]
    up = _map()
    assert f["x_armed_cm"] == pytest.approx(float(np.interp(p0, up.p_up_kpa, up.x_up_cm)), abs=1e-9)
    travel = abs(-2.0 - f["x_armed_cm"]) / f["v_max_cm_s"]
    assert f["t_u_travel_s"] == pytest.approx(travel, rel=1e-9)
    assert not any("armed muscle" in w for w in d.warnings)          # TASK's t_u = 2 s is enough here
    short = Task(w1_cm=0.2, t_u_s=0.5 * travel, x_min_cm=-3.0, x_max_cm=0.0, x_start_cm=-2.0)
    said = [w for w in derive(_measured(), short).warnings if "armed muscle" in w]
    assert len(said) == 1 and f"t_u >= {travel:.1f} s" in said[0]
    # no start given: nothing to say about it
    free = Task(w1_cm=0.2, t_u_s=0.001, x_min_cm=-3.0, x_max_cm=0.0)
    assert not any("armed muscle" in w for w in derive(_measured(), free).warnings)


def test_loop_margins_of_a_known_loop():
    # an integrator 10/s with a 0.05 s delay: crossover 10 rad/s, phase margin 90 - 28.6 deg
    m = loop_margins(0.0, 10.0, 0.0, 1.0, 1e-9, 0.05)
    assert m["crossover_rad_s"] == pytest.approx(10.0, rel=0.01)
    assert m["phase_margin_deg"] == pytest.approx(90.0 - math.degrees(0.5), abs=0.5)


def test_law_margins_are_the_pid_without_the_observer_and_less_with_it():
    """The law's small-signal loop through the tracking observer: with an observer far faster
    than the loop it is loop_margins' PID K_v (K_p + k_ff) + K_v s + K_v K_p k_ff / s; at 4x the
    crossover its lag costs gain margin."""
    f = derive(_measured(theta=0.03), TASK).figures
    k_v, k_p, g, tau, theta = f["k_v_u_per_cm_s"], f["k_p_per_s"], f["gain_cm_per_u"], f["tau_s"], f["theta_eff_s"]
    k_ff = rules.FF_PER_KP * k_p
    pid = loop_margins(k_v * (k_p + k_ff), k_v * k_p * k_ff, k_v, g, tau, theta)
    far = law_margins(k_v, k_p, k_ff, 1e5, g, tau, theta)
    for key in ("phase_margin_deg", "gain_margin", "crossover_rad_s"):
        assert far[key] == pytest.approx(pid[key], rel=2e-3)
    near = law_margins(k_v, k_p, k_ff, 4.0 * pid["crossover_rad_s"] / (2.0 * math.pi), g, tau, theta)
    assert near["gain_margin"] < 0.9 * pid["gain_margin"]


@pytest.mark.parametrize("theta", [0.005, 0.02, 0.04, 0.065])
def test_derive_places_the_observer_and_reports_the_loop_with_it(theta):
    """The observer sits at FC_PER_CROSSOVER x the crossover of the tightest loop the rule allows
    (tau_c = TAU_C_PER_THETA_MIN theta_eff), and the report's second margins line is the loop as
    built, with that observer in it: less margin than the PID's, more than with an observer at
    half that bandwidth."""
    d = derive(_measured(theta=theta), TASK)
    f, p = d.figures, d.params
    tightest = rules._shape(f["loop_gain_cm_per_u"], f["tau_s"], f["theta_eff_s"], rules.TAU_C_PER_THETA_MIN)
    fc = rules.FC_PER_CROSSOVER * tightest.margins["crossover_rad_s"] / (2.0 * math.pi)
    assert p["vel.fc_hz"] == pytest.approx(min(max(fc, rules.FC_MIN_HZ), rules.FC_MAX_HZ), abs=0.006)
    args = (f["k_v_u_per_cm_s"], f["k_p_per_s"], rules.FF_PER_KP * f["k_p_per_s"])
    plant = (f["gain_cm_per_u"], f["tau_s"], f["theta_eff_s"])
    # the command's low-pass (none, or between FU_PER_FC_MIN and _MAX x the observer's bandwidth) in
    # the loop as built
    fu = p["ppc.u_lpf_hz"] / p["vel.fc_hz"]
    assert fu == 0.0 or rules.FU_PER_FC_MIN - 1e-3 <= fu <= rules.FU_PER_FC_MAX + 1e-3
    again = law_margins(*args, p["vel.fc_hz"], *plant, p["ppc.u_lpf_hz"])
    assert f["with_observer_gain_margin"] == pytest.approx(again["gain_margin"], rel=1e-3)
    assert f["with_observer_phase_margin_deg"] == pytest.approx(again["phase_margin_deg"], abs=0.1)
    slower = law_margins(*args, p["vel.fc_hz"] / 2.0, *plant, p["ppc.u_lpf_hz"])
    assert slower["gain_margin"] < f["with_observer_gain_margin"] < d.margins["gain_margin"]
    assert slower["phase_margin_deg"] < f["with_observer_phase_margin_deg"] < d.margins["phase_margin_deg"]


@pytest.mark.parametrize("noise_cm", [0.0002, 0.0015, NOISY_CM])
def test_the_commands_low_pass_only_where_the_noise_would_chatter(noise_cm):
    """The command's low-pass (ppc.u_lpf_hz) where, through the tightest loop without it, the
    sensor's noise would move the input more than CHATTER_WARN_PER_NEED x what the reference needs:
    then the highest corner from FU_PER_FC_MAX x the observer's bandwidth down in steps of FU_STEP
    (to FU_PER_FC_MIN x) whose loop, shaped with its lag in the margins, brings the noise within
    that; the loop looser than without it, still keeping the margins. Below that, none: the loop
    is the unfiltered tightest, with nothing lost. MFAC's set is the same either way (it has no
    low-pass)."""
    d = derive(_noisy(noise_cm), _task(0.05, None))
    f, p = d.figures, d.params
    bound = rules.CHATTER_WARN_PER_NEED * f["need_input_rate_u_per_s"]
    quiet = derive(_noisy(0.0), _task(0.05, None))          # no noise: never filtered
    assert quiet.params["ppc.u_lpf_hz"] == 0.0
    assert {k: v for k, v in p.items() if k.startswith("mfac.")} == \
        {k: v for k, v in quiet.params.items() if k.startswith("mfac.")}
    if f["noise_input_rate_unfiltered_u_per_s"] <= bound:
        assert noise_cm == 0.0002                            # the quiet sensor
        assert p["ppc.u_lpf_hz"] == 0.0
        assert f["tau_c_s"] == quiet.figures["tau_c_s"] and p["ppc.a_cm_s"] == quiet.params["ppc.a_cm_s"]
        assert f["noise_input_rate_u_per_s"] == f["noise_input_rate_unfiltered_u_per_s"]
        return
    assert noise_cm > 0.0002
    fu = p["ppc.u_lpf_hz"] / p["vel.fc_hz"]
    assert rules.FU_PER_FC_MIN - 1e-3 <= fu <= rules.FU_PER_FC_MAX + 1e-3
    assert f["tau_c_s"] > quiet.figures["tau_c_s"] and _as_built_keeps_margins(f)
    assert f["noise_input_rate_u_per_s"] < f["noise_input_rate_unfiltered_u_per_s"]
    without = law_margins(f["k_v_u_per_cm_s"], f["k_p_per_s"], rules.FF_PER_KP * f["k_p_per_s"],
                          p["vel.fc_hz"], f["gain_cm_per_u"], f["tau_s"], f["theta_eff_s"])
    assert without["phase_margin_deg"] > f["with_observer_phase_margin_deg"]
    if f["noise_input_rate_u_per_s"] <= bound:
        # the highest corner that does: one step higher (where there is one) does not
        if fu < rules.FU_PER_FC_MAX - 1e-3:
            higher = min(fu / rules.FU_STEP, rules.FU_PER_FC_MAX)
            shape, _, fc = rules._tightest_shape(f["loop_gain_cm_per_u"], f["tau_s"], f["theta_eff_s"], 1e-3, higher)
            assert rules._noise_rate(shape, fc, 1e-3, noise_cm, higher) > bound
    else:
        assert fu == pytest.approx(rules.FU_PER_FC_MIN, abs=1e-3)   # the lowest corner, still above


@pytest.mark.parametrize("fu", [0.0, 15.0])
def test_law_noise_rate_is_the_mean_input_change_that_white_noise_makes(fu):
    """law_noise_rate against white Gaussian noise through the law's recursion, tick by tick (with
    the command's low-pass ppc.u_lpf_hz at fu as pma/lpf.h runs it, or none): the mean
    |u_k - u_(k-1)| per period, within the sample mean's spread; linear in the noise, and about the
    square of the observer's bandwidth (its velocity's change per tick) without the low-pass."""
    k_v, k_p, k_ff, fc, period, sigma = 2.5, 8.0, 240.0, 15.0, 1e-3, 0.002
    rng = np.random.default_rng(3)
    x = rng.normal(0.0, sigma, 200_000)
    p = math.exp(-2.0 * math.pi * fc * period)
    k_u = 1.0 - math.exp(-2.0 * math.pi * fu * period) if fu > 0.0 else 1.0
    x_hat = v_hat = u_ff = u_last = y = 0.0
    changes = np.empty(x.size)
    for k, xk in enumerate(x):
        r = xk - (x_hat + period * v_hat)
        x_hat += period * v_hat + (1.0 - p * p) * r
        v_hat += (1.0 - p) ** 2 / period * r
        u_law = k_v * (k_p * x_hat + v_hat)
        u_ff += k_ff * period * u_law
        y += k_u * (u_law + u_ff - y)
        changes[k] = abs(y - u_last)
        u_last = y
    simulated = float(np.mean(changes[2000:])) / period      # after the start's transient
    assert law_noise_rate(k_v, k_p, k_ff, fc, period, sigma, fu) == pytest.approx(simulated, rel=0.02)
    assert law_noise_rate(k_v, k_p, k_ff, fc, period, 2 * sigma, fu) == pytest.approx(
        2 * law_noise_rate(k_v, k_p, k_ff, fc, period, sigma, fu), rel=1e-9)
    if fu == 0.0:
        ratio = (law_noise_rate(k_v, k_p, k_ff, 2 * fc, period, sigma)
                 / law_noise_rate(k_v, k_p, k_ff, fc, period, sigma))
        assert 3.0 < ratio < 4.5
    else:   # the low-pass at the observer's bandwidth: the noise's roll-off second-order
        assert law_noise_rate(k_v, k_p, k_ff, fc, period, sigma, fu) < 0.3 * law_noise_rate(
            k_v, k_p, k_ff, fc, period, sigma)


def _noisy(noise_cm: float) -> Measured:
    m = _measured(theta=0.02, tau=0.06)
    m.noise_cm = noise_cm
    return m


def _task(mean_speed: float | None, noise_limit: float | None = 2.0) -> Task:
    return Task(w1_cm=0.2, t_u_s=2.0, x_min_cm=-3.0, x_max_cm=0.0, x_start_cm=-2.0, speed_cm_s=0.4,
                mean_speed_cm_s=mean_speed, noise_limit=noise_limit)


@pytest.mark.parametrize("limit", [1.5, 2.5])
def test_a_noise_limit_slows_the_observer_until_its_noise_moves_the_input_no_more_than_asked(limit):
    """With a noise limit K (pmactl commission --noise-limit), where the sensor's noise through the
    law would move the input more than K times what the reference needs, the observer comes down in
    steps of FC_NOISE_STEP, the loop loosening with it to keep the margins, until it does not: the
    first step down that meets the bound. Without one, the observer stays where the margins put
    it and the report warns."""
    free = derive(_noisy(NOISY_CM), _task(0.05, None))      # no bound: the margins' observer
    assert free.params["vel.fc_hz"] == derive(_noisy(NOISY_CM), _task(0.0)).params["vel.fc_hz"]
    assert free.figures["noise_limit"] == 0.0
    assert any("chatter" in w and "--noise-limit" in w for w in free.warnings)
    d = derive(_noisy(NOISY_CM), _task(0.05, limit))
    f, p = d.figures, d.params
    need = abs(p["ppc.ref_ff"]) * 0.05
    assert f["need_input_rate_u_per_s"] == pytest.approx(need, rel=1e-3)
    assert f["noise_limit"] == limit
    assert {k: v for k, v in d.params.items() if k.startswith("mfac.")} == \
        {k: v for k, v in free.params.items() if k.startswith("mfac.")}       # MFAC has no observer
    assert free.figures["noise_input_rate_u_per_s"] > limit * need   # the case is real
    assert f["noise_input_rate_u_per_s"] <= limit * need
    assert p["vel.fc_hz"] < free.params["vel.fc_hz"]
    assert f["tau_c_s"] >= free.figures["tau_c_s"] and _as_built_keeps_margins(f)
    # one step faster, the loop the margins allow there is too noisy
    fc_up = p["vel.fc_hz"] / rules.FC_NOISE_STEP
    if fc_up < free.params["vel.fc_hz"]:
        gain, tau, theta = f["loop_gain_cm_per_u"], f["tau_s"], f["theta_eff_s"]
        fu = p["ppc.u_lpf_hz"] / p["vel.fc_hz"]      # with the command's low-pass it chose
        shape, _ = rules._tightest_at(gain, tau, theta, fc_up, fu)
        assert rules._noise_rate(shape, fc_up, 1e-3, NOISY_CM, fu) > limit * need
    # the noise the report states is the loop's as derived
    assert f["noise_input_rate_u_per_s"] == pytest.approx(law_noise_rate(
        f["k_v_u_per_cm_s"], f["k_p_per_s"], p["ppc.ff_gain_per_s"], p["vel.fc_hz"], 1e-3, NOISY_CM,
        p["ppc.u_lpf_hz"]), rel=2e-3)
    assert not any("chatter" in w for w in d.warnings)


def test_a_noise_limit_that_is_not_a_positive_number_is_refused():
    for bad in (0.0, -1.0, math.nan, math.inf):
        with pytest.raises(CommissionError, match="noise limit"):
            derive(_noisy(0.003), _task(0.05, bad))


def test_a_quiet_sensor_or_no_speed_leaves_the_observer_where_the_margins_put_it():
    quiet = derive(_noisy(1e-5), _task(0.05))
    assert quiet.params["vel.fc_hz"] == derive(_noisy(1e-5), _task(0.0)).params["vel.fc_hz"]
    # no mean speed given: a sine's, 2 / pi of the largest
    sine = derive(_noisy(0.003), _task(None))
    assert sine.figures["need_input_rate_u_per_s"] == pytest.approx(
        abs(sine.params["ppc.ref_ff"]) * 2.0 / math.pi * 0.4, rel=1e-3)


def test_a_sensor_too_noisy_for_any_observer_is_said_and_the_margins_stay():
    """The observer comes down only as far as a loop keeps the margins: below that, the noise
    stays and the report says what to expect."""
    d = derive(_noisy(0.05), _task(0.01))
    f, p = d.figures, d.params
    assert any("chatter" in w and "slowest observer" in w for w in d.warnings)
    assert _as_built_keeps_margins(f)
    fc_down = max(rules.FC_NOISE_STEP * p["vel.fc_hz"], rules.FC_MIN_HZ)
    fu = p["ppc.u_lpf_hz"] / p["vel.fc_hz"]     # the command's low-pass: at its lowest corner here
    assert fu == pytest.approx(rules.FU_PER_FC_MIN, abs=1e-3)
    if fc_down < p["vel.fc_hz"]:
        _, below = rules._tightest_at(f["loop_gain_cm_per_u"], f["tau_s"], f["theta_eff_s"], fc_down, fu)
        assert not rules._keeps_margins(below)


def test_integral_loop_gain_max_of_a_pure_delay():
    # K e^{-theta s} / s: PM = 90 deg - K theta and GM = pi / (2 K theta): both limits (45 deg, 2)
    # meet at K = pi / (4 theta)
    assert rules.integral_loop_gain_max(1e-9, 0.05) == pytest.approx(math.pi / 0.2, rel=0.01)


@pytest.mark.parametrize("gain, tau, theta", [(0.00148, 0.061, 0.034), (0.0051, 0.16, 0.065),
                                              (0.02, 0.3, 0.1), (0.0005, 0.02, 0.005)])
def test_mfac_gains_keep_the_margins_at_the_measured_gain(gain, tau, theta):
    m = rules.mfac_gains(gain, tau, theta, 1e-3, ki_per_tick=5.0)
    assert m.margins["phase_margin_deg"] >= rules.PM_MIN_DEG - 0.5
    assert m.margins["gain_margin"] >= rules.GM_MIN - 0.01
    assert m.lam >= rules.MFAC_LAMBDA
    k_paper = rules.MFAC_RHO * gain**2 / ((rules.MFAC_LAMBDA + gain**2) * 1e-3)
    k_max = rules.integral_loop_gain_max(tau, theta)
    if k_paper <= k_max:        # the paper's lambda keeps them: unchanged
        assert m.lam == rules.MFAC_LAMBDA and m.k_loop_per_s == pytest.approx(k_paper)
    else:                       # raised just as far as the margins need
        assert m.k_loop_per_s == pytest.approx(k_max, rel=1e-6)
    # phi(1): MFAC's first steps at the PI's integral gain, with that lambda
    assert rules.MFAC_RHO * m.phi1 / (m.lam + m.phi1**2) == pytest.approx(5.0, rel=1e-6)


def test_mfac_gains_on_a_loop_too_slow_for_any_margin_say_so():
    """A dead time of 20 s: no integral loop above the bisection's floor keeps the margins; the
    gains are still derived and the derivation warns instead of refusing the rig."""
    m = rules.mfac_gains(0.005, 1.0, 20.0, 1e-3, ki_per_tick=0.01)
    assert m.margins["phase_margin_deg"] < rules.PM_MIN_DEG or m.margins["gain_margin"] < rules.GM_MIN
    meas = _measured(theta=20.0, tau=1.0)
    d = derive(meas, TASK)
    assert any("MFAC's integral loop" in w for w in d.warnings)


def test_mfac_gains_raise_lambda_on_a_stiff_slow_loop():
    """A high gain with a long lag (the slow valve of dmsp10): the paper's lambda would make the
    integral loop unstable there, so it is raised."""
    m = rules.mfac_gains(0.0051, 0.16, 0.065, 1e-3, ki_per_tick=2.0)
    assert m.lam > 3 * rules.MFAC_LAMBDA


def test_mfac_phi1_gives_the_integral_gain():
    for ki in (1.0, 20.0, 100.0):
        phi = mfac_phi1(ki)
        gain = 31.7 * phi / (0.03 + phi * phi)
        assert gain == pytest.approx(ki, rel=1e-6) or phi == pytest.approx(math.sqrt(0.03))


# -------------------------------------------------------- over CAN, offline --
@pytest.fixture
def rig_node(request: pytest.FixtureRequest) -> Any:
    """A freshly wired node on the paper's rig: its sensor and DAC scalings, the actuator's
    pressure range and the constraints set, nothing else. A parameter is the scenario's name, or
    (name, {sensor property: value}) for another sensor on its rig."""
    assert offline.LIB_PATH.exists(), f"{offline.LIB_PATH} missing: {offline.BUILD_HINT}"
    name, sensor = getattr(request, "param", "case3"), {}
    if isinstance(name, tuple):
        name, sensor = name
    sc = scn.load(name)
    sc.rig.setdefault("sensor", {}).update(sensor)
    bus = OfflineBus(sc.rig_params(), node_id=1)
    node = PmaNode(bus, node=1, host_heartbeat_s=0.1)
    for k, v in before_commissioning(sc).items():
        node.set(k, v)
    bus.run_for(0.5)
    yield bus, node
    bus.shutdown()


def _snapshot(node: PmaNode) -> dict[str, float | int]:
    return {name: node.get(name) for name in TOUCHED}


def test_commission_on_the_paper_rig(rig_node):
    bus, node = rig_node
    before = _snapshot(node)
    r = Commissioning(node, TASK).run()
    d = r.derivation
    assert d.params["act.polarity"] == -1
    lo, hi = r.measured.static_map.stroke_cm()
    assert -3.0 + 0.1 <= lo < hi <= 0.0 - 0.1          # the sweep kept its margin from the constraints
    assert r.rig_time_s < 60.0
    assert d.margins["phase_margin_deg"] > 45.0
    # without apply nothing changed, and the node is back in IDLE
    assert _snapshot(node) == before
    assert node.status().state_name == "IDLE"


def test_commission_starts_whatever_reference_the_node_was_left_with(rig_node):
    """START checks the reference against the band in every mode, OPEN_LOOP too: a HOLD left
    outside the band (a node's earlier task) must not stop commissioning, and is set back."""
    bus, node = rig_node
    node.set("ref.offset_cm", -5.0)             # outside safety.x_min_cm..x_max_cm = -3..0 cm
    before = _snapshot(node)
    r = Commissioning(node, TASK).run()
    assert r.derivation.params["act.polarity"] == -1
    assert _snapshot(node) == before and node.get("ref.offset_cm") == -5.0
    assert node.status().state_name == "IDLE"


def test_commission_apply_sets_the_parameters(rig_node):
    bus, node = rig_node
    r = Commissioning(node, TASK).run(apply=True)
    for name, value in r.derivation.params.items():
        assert node.get(name) == pytest.approx(value, rel=1e-6, abs=1e-6)
    assert r.applied and not r.saved


def test_commission_refuses_a_node_that_is_not_idle(rig_node):
    bus, node = rig_node
    node.set("act.p0_kpa", 100.0)
    node.set("ctrl.u_min", -100.0)
    node.set("ctrl.u_max", 800.0)
    node.arm()
    with pytest.raises(NodeStateError, match="ARMED"):
        Commissioning(node, TASK).run()
    assert node.status().state_name == "ARMED"           # refused before anything was sent


def test_commission_refuses_a_disconnected_sensor(rig_node):
    bus, node = rig_node
    bus.rig.break_wire(True)
    bus.run_for(0.3)
    before = _snapshot(node)
    with pytest.raises(CommissionError, match="sensor"):
        Commissioning(node, TASK).run()
    assert _snapshot(node) == before


@pytest.mark.parametrize("rig_node", [("case3", {"noise_cm": 1.0})], indirect=True)
def test_a_fault_while_it_runs_says_when_where_and_what_to_check(rig_node):
    """A sensor so noisy that x crosses the band at rest faults the node (POSITION_LIMIT) before
    the wiring check can weigh its noise: the abort names the fault, when it came, where x was
    and what to check, and the node is left as it was (safe, every parameter set back)."""
    bus, node = rig_node
    before = _snapshot(node)
    with pytest.raises(CommissionAborted, match=r"during the start at x = -?\d+\.\d+ cm: FAULT \(fault "
                                                r"POSITION_LIMIT\): .*noisy sensor"):
        Commissioning(node, TASK).run()
    assert _snapshot(node) == before
    assert node.status().state_name != "RUNNING"


QUIET_SENSOR = {"noise_cm": 0.0, "adc_noise_counts": 0.0}      # a still muscle reads one value at rest


@pytest.mark.parametrize("rig_node", [("case3", QUIET_SENSOR)], indirect=True)
def test_a_sensor_quieter_than_its_adc_takes_the_quantisations_noise(rig_node):
    """A noise-free sensor on a still muscle reads the same count on every sample at rest: that
    is not a stuck sensor (the direction step moves it), and the noise the rules take is the ADC's
    quantisation, one count over sqrt(12), never less."""
    bus, node = rig_node
    r = Commissioning(node, TASK).run()
    m = r.measured
    count_cm = abs(float(node.get("adc.gain_cm_per_count")))
    assert m.noise_rest_cm == 0.0 and m.resolution_cm == pytest.approx(count_cm)
    assert m.noise_cm == pytest.approx(count_cm / math.sqrt(12.0))
    assert r.derivation.figures["noise_cm"] == m.noise_cm
    assert "quantisation" in commission_report.text(r)[1]
    assert node.status().state_name == "IDLE"


def test_commission_refuses_a_stuck_sensor(rig_node, monkeypatch):
    """A sensor that reads the same valid count whatever the pressure (stuck, or a muscle that
    does not move under a noise-free sensor) is refused, the node left as it was."""
    bus, node = rig_node
    count = bus.rig.sensor_counts()
    monkeypatch.setattr(bus.rig, "sensor_counts", lambda: count)
    bus.run_for(0.3)
    before = _snapshot(node)
    with pytest.raises(CommissionError, match="same value on every sample, at rest and after a pressure step"):
        Commissioning(node, TASK).run()
    assert _snapshot(node) == before
    assert node.status().state_name == "IDLE"


def test_commission_refuses_an_actuator_that_does_not_move_the_muscle(rig_node):
    bus, node = rig_node
    bus.actuator_connected = False
    before = _snapshot(node)
    with pytest.raises(CommissionError, match="nothing moves"):
        Commissioning(node, TASK).run()
    assert _snapshot(node) == before
    assert node.status().state_name == "IDLE"


def test_commission_refuses_a_band_the_resting_muscle_is_outside_of(rig_node):
    """A band that leaves out where the vented muscle rests: the node refuses ARM (RANGE), and
    commissioning says so and what to check, the node left as it was."""
    bus, node = rig_node
    node.set("safety.x_max_cm", -0.8)
    before = _snapshot(node)
    with pytest.raises(CommissionError, match=r"refused ARM \(RANGE\).*-3\.\.-0\.8 cm"):
        Commissioning(node, Task(w1_cm=0.2, t_u_s=2.0, x_min_cm=-3.0, x_max_cm=-0.8)).run()
    assert _snapshot(node) == before
    assert node.status().state_name == "IDLE"


def test_commission_refuses_a_pressure_range_that_does_not_move_the_muscle_clear_of_the_band(rig_node):
    """act.p_max_kpa 50: every level leaves the vented muscle within the margin of x_max; the
    refusal names the pressure range as well as the band."""
    bus, node = rig_node
    node.set("act.p_max_kpa", 50.0)
    before = _snapshot(node)
    with pytest.raises(CommissionError, match=r"no stroke to map.*p_max_kpa = 0\.\.50 kPa"):
        Commissioning(node, TASK).run()
    assert _snapshot(node) == before
    assert node.status().state_name == "IDLE"


def test_commission_refuses_a_band_not_wider_than_two_w1_before_anything_moves(rig_node):
    bus, node = rig_node
    before = _snapshot(node)
    with pytest.raises(CommissionError, match=r"the task: the band -3\.\.0 cm is not wider than 2 w1 = 4 cm"):
        Commissioning(node, Task(w1_cm=2.0, t_u_s=2.0, x_min_cm=-3.0, x_max_cm=0.0)).run()
    assert _snapshot(node) == before
    assert node.status().state_name == "IDLE"


def test_commission_refuses_a_band_outside_the_stroke(rig_node):
    bus, node = rig_node
    with pytest.raises(CommissionError, match="constraint"):
        Commissioning(node, Task(w1_cm=0.2, t_u_s=2.0, x_min_cm=-9.0, x_max_cm=-6.0)).run()
    assert node.status().state_name == "IDLE"


# ------------------------------------------------------------------ the CLI --
@pytest.mark.parametrize("argv", [
    ["commission", "--w1", "0.2", "--t-u", "2", "--save"],                         # --save without --apply
    ["commission", "--w1", "-0.2", "--t-u", "2"],                                  # w1 not positive
    ["commission", "--w1", "0.2", "--t-u", "nan"],
    ["commission", "--w1", "2", "--t-u", "2", "--x-min", "-3", "--x-max", "0"],   # band narrower than 2 w1
    ["commission", "--w1", "0.2", "--t-u", "2", "--x-min", "0", "--x-max", "-3"],
    ["commission", "--t-u", "2"],
    ["commission", "--w1", "0.2", "--t-u", "2", "--speed", "0.5", "--mean-speed", "0.6"],   # mean above largest
    ["commission", "--w1", "0.2", "--t-u", "2", "--speed", "0.5", "--mean-speed", "-0.1"],
    ["commission", "--w1", "0.2", "--t-u", "2", "--noise-limit", "0"],
    ["commission", "--w1", "0.2", "--t-u", "2", "--noise-limit", "inf"],
    ["commission", "--w1", "0.2", "--t-u", "2", "--noise-limit", "two"],
])
def test_cli_refuses_bad_options_before_sending(rig_node, monkeypatch, argv):
    bus, node = rig_node
    monkeypatch.setattr(cli, "open_bus", lambda cfg: bus)
    sent: list[Any] = []
    monkeypatch.setattr(bus, "send", lambda msg, timeout=None: sent.append(msg))
    assert cli.main(["--node", "1", *argv]) == cli.EXIT_USAGE
    assert not [m for m in sent if (m.arbitration_id & 0x7F0) in (0x040, 0x070)]   # no COMMAND, no SET


def test_cli_commission_writes_its_report(rig_node, monkeypatch, tmp_path: Path, capsys):
    bus, node = rig_node
    monkeypatch.setattr(cli, "open_bus", lambda cfg: bus)
    monkeypatch.setattr(bus, "shutdown", lambda: None)
    code = cli.main(["--node", "1", "commission", "--w1", "0.2", "--t-u", "2", "--x-start", "-2",
                     "--out", str(tmp_path), "--quiet"])
    out = capsys.readouterr().out
    assert code == cli.EXIT_OK, out
    assert "phase margin" in out and "nothing changed on the node" in out
    assert "the sensor's noise through the law moves the input" in out and "a set-point task" in out
    for f in ("report.json", "params.json", "commissioning.png"):
        assert (tmp_path / f).exists()
    # the parameter file loads with pmactl's own reader
    from pmactl import paramfile
    entries = paramfile.load(str(tmp_path / "params.json"), scn.protocol())
    assert {p.name for p, _ in entries} >= {"act.polarity", "act.p0_kpa", "ppc.a_cm_s", "mfac.phi1"}
    # a tracking task with a noise limit: the report weighs the noise against the need, and says the bound
    code = cli.main(["--node", "1", "commission", "--w1", "0.2", "--t-u", "2", "--x-start", "-2", "--speed", "0.4",
                     "--noise-limit", "1.5", "--quiet"])
    out = capsys.readouterr().out
    assert code == cli.EXIT_OK, out
    assert "--noise-limit 1.5" in out


def test_hil_offline_runs_the_ppc_lane_on_the_commissioned_set(tmp_path: Path, capsys):
    from hil.__main__ import main as hil_main
    code = hil_main(["offline", "case3", "--controller", "ppc", "--duration", "8", "--commission", "--brief",
                     "--out", str(tmp_path)])
    out = capsys.readouterr().out
    assert code == 0, out
    import json
    rep = json.loads((tmp_path / "commissioning.json").read_text())
    assert rep["derivation"]["params"]["act.polarity"] == -1
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert summary["controllers"]["ppc"]["params_set"]["ppc.a_cm_s"] == pytest.approx(
        rep["derivation"]["params"]["ppc.a_cm_s"])


def test_scenario_lanes_take_their_set_from_commissioning(tmp_path: Path, capsys):
    """The paper's cases give their ppc and mfac lanes no gains: running them needs --commission
    (exit 2 without it, with the lanes named), a commissioned lane that carries a gain is refused
    when the file is loaded, and --commission on a scenario without such a lane is refused."""
    from hil.__main__ import main as hil_main
    for case in ("case1", "case2a", "case2b", "case3", "load_change", "constraint_approach"):
        sc = scn.load(case)
        assert set(sc.needs_commissioning()) == {"ppc", "mfac"}, case
    assert hil_main(["offline", "case3", "--controller", "mfac", "--duration", "1"]) == 2
    assert "take their set from commissioning" in capsys.readouterr().err
    assert hil_main(["offline", "wire_break", "--commission"]) == 2
    assert hil_main(["run", "case3", "--out", str(tmp_path / "r"), "--controller", "ppc-paper", "--commission"]) == 2
    assert hil_main(["run", "case3", "--out", str(tmp_path / "r")]) == 2
    assert "--commission" in capsys.readouterr().err
    bad = dict(tomllib.loads((scn.SCENARIO_DIR / "case3.toml").read_text()))
    bad["name"] = "bad"
    bad.pop("base")
    bad.update(tomllib.loads((scn.SCENARIO_DIR / "_rig_paper.toml").read_text()))
    bad["controllers"] = [{"label": "ppc", "mode": "PPC", "commission": True, "params": {"ppc.a_cm_s": 10.0}}]
    with pytest.raises(scn.ScenarioError, match="only the task's own parameters"):
        scn.parse(bad)
    bad["controllers"] = [{"label": "pid", "mode": "PID", "commission": True}]
    with pytest.raises(scn.ScenarioError, match="commission = true needs mode"):
        scn.parse(bad)


def test_an_explicit_set_wins_over_the_commissioned_value(tmp_path: Path):
    """`hil offline --commission --set NAME=V`: the lane runs on the derivation with the user's
    value on top (what the user asks for is what runs)."""
    import json

    from hil.__main__ import main as hil_main
    code = hil_main(["offline", "case2b", "--controller", "ppc", "--duration", "2", "--commission", "--brief",
                     "--set", "ppc.a_cm_s=1.5", "--out", str(tmp_path)])
    assert code == 0
    summary = json.loads((tmp_path / "summary.json").read_text())
    got = summary["controllers"]["ppc"]["params_set"]
    assert got["ppc.a_cm_s"] == 1.5
    assert got["ppc.ref_ff"] == json.loads((tmp_path / "commissioning.json").read_text())["derivation"]["params"][
        "ppc.ref_ff"]


def test_a_user_limit_set_for_every_lane_is_the_commissionings_too(tmp_path: Path):
    """`hil offline --commission --set act.p_max_kpa=600`: the user's pressure range is what the
    node knows before commissioning, so the static map stays inside it and the derived input
    range with it (the lanes then ARM and run; before, commissioning swept to the file's 900 kPa
    and START refused the input range that came out of it)."""
    import json

    from hil.__main__ import main as hil_main
    code = hil_main(["offline", "case2b", "--controller", "ppc", "--duration", "2", "--commission", "--brief",
                     "--set", "act.p_max_kpa=600", "--out", str(tmp_path)])
    assert code == 0
    c = json.loads((tmp_path / "commissioning.json").read_text())
    assert max(c["measured"]["static_map"]["p_up_kpa"] + c["measured"]["static_map"]["p_down_kpa"]) <= 600.0
    d = c["derivation"]["params"]
    assert d["act.p0_kpa"] + d["ctrl.u_max"] <= 600.0 + 1e-3
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert summary["controllers"]["ppc"]["params_set"]["act.p_max_kpa"] == 600.0
    assert summary["state"]["ppc"] == "RUNNING"


def test_the_harness_commissions_with_the_scenarios_noise_limit():
    """hil run/offline --commission --noise-limit K: the scenario's noise_limit reaches the
    commissioning's task, and on a 4x coarser sensor it slows the observer the margins chose."""
    from hil.commissioned import commission, task_of
    sc = scn.load("variants/case3_coarse_sensor")
    assert task_of(sc).noise_limit is None
    free = commission(sc).derivation
    sc.noise_limit = 1.5
    assert task_of(sc).noise_limit == 1.5
    quiet = commission(sc).derivation
    assert quiet.figures["noise_limit"] == 1.5 and free.figures["noise_limit"] == 0.0
    assert free.figures["noise_input_rate_u_per_s"] > 1.5 * free.figures["need_input_rate_u_per_s"]
    assert quiet.figures["noise_input_rate_u_per_s"] <= 1.5 * quiet.figures["need_input_rate_u_per_s"]
    assert quiet.params["vel.fc_hz"] < free.params["vel.fc_hz"]
