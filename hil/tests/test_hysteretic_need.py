# SPDX-License-Identifier: Apache-2.0
"""What the reference needs of the valve on a hysteretic rig (hil/summary.py
hysteretic_pressure_for, the denominator of chatter_ratio_hysteretic): on a rig without
hysteresis it is the frictionless need; with hysteresis every reversal adds the width of the
muscle's and the regulator's loops, and between reversals it follows one branch. No CAN."""
from __future__ import annotations

import copy

import numpy as np

from hil import scenario as scn
from hil.metrics import total_variation_per_s
from hil.rig import Rig
from hil.summary import hysteretic_pressure_for, static_pressure_for


def case3_on(muscle_hyst_n: float, regulator_hyst_frac: float) -> scn.Scenario:
    sc = scn.load("case3")
    rig = copy.deepcopy(sc.rig)
    rig.setdefault("muscle", {})["hyst_force_n"] = muscle_hyst_n
    rig.setdefault("regulator", {})["hysteresis_frac_fs"] = regulator_hyst_frac
    sc.rig = rig
    return sc


def triangle(reversals: int, lo_cm: float, hi_cm: float, n_per_leg: int = 200) -> np.ndarray:
    legs = [np.linspace(lo_cm, hi_cm, n_per_leg) if i % 2 == 0 else np.linspace(hi_cm, lo_cm, n_per_leg)
            for i in range(reversals + 1)]
    return np.concatenate([leg if i == 0 else leg[1:] for i, leg in enumerate(legs)])


def test_without_hysteresis_it_is_the_frictionless_need() -> None:
    sc = case3_on(0.0, 0.0)
    x = triangle(4, -2.0, -0.5)
    np.testing.assert_allclose(hysteretic_pressure_for(sc)(x), static_pressure_for(sc)(x), rtol=0, atol=0.5)


def test_each_reversal_crosses_both_loops() -> None:
    sc = case3_on(60.0, 0.01)
    rig = Rig(sc.rig_params())
    backlash_kpa = rig.params.regulator.hysteresis_frac_fs * rig.params.regulator.fs_kpa
    f = hysteretic_pressure_for(sc)
    lo, hi = -2.0, -0.5
    x = triangle(6, lo, hi)                  # 7 legs, 6 turns: 3 at each end
    t = np.arange(len(x)) * 0.01
    need = f(x)
    assert np.all(np.isfinite(need))

    def branches(xe: float) -> tuple[float, float]:
        """(rising-pressure branch, falling-pressure branch) at xe, approached from both sides."""
        a, b = f(np.array([xe - 0.01, xe]))[1], f(np.array([xe + 0.01, xe]))[1]
        return max(a, b), min(a, b)
    (r_lo, f_lo), (r_hi, f_hi) = branches(lo), branches(hi)
    first_up = static_pressure_for(sc)(np.array([hi]))[0] > static_pressure_for(sc)(np.array([lo]))[0]
    first, second = (r_hi - r_lo, f_hi - f_lo) if first_up else (f_hi - f_lo, r_hi - r_lo)
    expected = 4 * abs(first) + 3 * abs(second) + 3 * (r_lo - f_lo) + 3 * (r_hi - f_hi)
    total = total_variation_per_s(t, need) * (t[-1] - t[0])
    np.testing.assert_allclose(total, expected, rtol=0.01)
    # each loop's width is at least the regulator's backlash (the muscle's friction on top)
    assert r_lo - f_lo > backlash_kpa and r_hi - f_hi > backlash_kpa
    assert total > total_variation_per_s(t, static_pressure_for(sc)(x)) * (t[-1] - t[0]) + 6 * backlash_kpa


def test_between_reversals_it_follows_one_branch_and_a_pause_keeps_it() -> None:
    sc = case3_on(60.0, 0.01)
    f = hysteretic_pressure_for(sc)
    rising = np.linspace(-2.0, -0.5, 50)   # x's direction is the pressure's through the polarity
    still = np.full(20, -0.5)
    up_then_pause = f(np.concatenate([rising, still]))
    assert len(set(np.round(up_then_pause[-21:], 6))) == 1           # the pause stays on its branch
    down_then_pause = f(np.concatenate([rising[::-1], np.full(20, -2.0)]))
    assert len(set(np.round(down_then_pause[-21:], 6))) == 1
    # the two branches at the same x differ by the loops' width
    assert abs(f(np.array([-1.0, -1.1]))[1] - f(np.array([-1.2, -1.1]))[1]) > 10.0


def test_out_of_reach_is_nan() -> None:
    sc = case3_on(60.0, 0.01)
    need = hysteretic_pressure_for(sc)(np.array([-1.0, -50.0, 50.0]))
    assert np.isfinite(need[0]) and np.isnan(need[1]) and np.isnan(need[2])


def test_the_regulators_backlash_alone_is_its_width() -> None:
    sc = case3_on(0.0, 0.01)
    reg = Rig(sc.rig_params()).params.regulator
    f = hysteretic_pressure_for(sc)
    for xe in (-2.0, -1.0, -0.5):
        a, b = f(np.array([xe - 0.01, xe]))[1], f(np.array([xe + 0.01, xe]))[1]
        np.testing.assert_allclose(abs(a - b), reg.hysteresis_frac_fs * reg.fs_kpa, rtol=1e-6)
