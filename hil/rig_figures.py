# SPDX-License-Identifier: Apache-2.0
"""The figures of the measured muscle's table (a DMSP-10-250), measured on a simulated rig the way they were
measured on the real DMSP-10-250 (docs/rig.md, "Against a real muscle").

Each function drives a Rig open loop with pressure commands (kPa, through the DAC)
and reads the actual pressure p [kPa] and the contraction s [mm] at the sampling
period of the measurements (10 ms). Shapes are given in percent of the step or of
the stroke, so that muscles of different size compare.

    from hil.rig_figures import table
    figs = table(RigParams.from_dict({"profile": "dmsp10"}))

Used by hil/tests/test_rig_profiles.py, tools/fit_rig_dmsp10.py and
hil/plot_rig_real.py; nothing here changes the rig.
"""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np

from .rig import Rig
from .rig_params import RigParams

SAMPLE_S = 0.01  # the measurements' sampling period (100 Hz)


FIGURE_SUBSTEP_S = 5e-4  # RK4 sub-step of these runs (hil/tests/test_rig_profiles.py checks it against 1e-4 s)


def quiet(params: RigParams, substep_s: float = FIGURE_SUBSTEP_S) -> RigParams:
    """A copy without sensor noise and without the temperature drift, at the given sub-step."""
    p = RigParams.from_dict(params.to_dict())
    p.substep_s = substep_s
    p.sensor.noise_cm = 0.0
    p.sensor.adc_noise_counts = 0.0
    p.drift.temp_rate_k_per_s = 0.0
    return p


@dataclasses.dataclass
class Record:
    t_s: np.ndarray
    p_cmd_kpa: np.ndarray
    p_kpa: np.ndarray
    s_mm: np.ndarray  # contraction [mm], positive: shorter


def run_commands(params: RigParams, commands_kpa: list[tuple[float, float]], p_start_kpa: float,
                 settle_s: float = 6.0, dt_s: float = SAMPLE_S) -> Record:
    """Hold p_start_kpa for settle_s (not recorded), then each (command kPa,
    duration s) in turn; samples every dt_s (the rig steps in dt_s)."""
    p = RigParams.from_dict({**params.to_dict(), "initial_p_kpa": p_start_kpa})
    rig = Rig(p, seed=0)
    for _ in range(int(round(settle_s / dt_s))):
        rig.apply_pressure_kpa(p_start_kpa)
        rig.step(dt_s)
    ts, pc, pr, ss = [], [], [], []
    t = 0.0
    for cmd, dur in commands_kpa:
        c = rig.kpa_to_dac(cmd)
        for _ in range(int(round(dur / dt_s))):
            ts.append(t)
            pc.append(cmd)
            pr.append(rig.p_kpa)
            ss.append(rig.contraction_mm)
            rig.apply_dac(c)
            rig.step(dt_s)
            t += dt_s
    ts.append(t)
    pc.append(commands_kpa[-1][0])
    pr.append(rig.p_kpa)
    ss.append(rig.contraction_mm)
    return Record(np.array(ts), np.array(pc), np.array(pr), np.array(ss))


def _first(t: np.ndarray, cond: np.ndarray) -> float:
    return float(t[np.argmax(cond)]) if np.any(cond) else float("nan")


def step_figures(params: RigParams, p_from_kpa: float, p_to_kpa: float, hold_s: float = 4.0) -> dict[str, float]:
    """One pressure step from rest: the pressure's dead time (first sample past 2 %
    of the change), its 10-90 % time (against the value at the end of the hold: a
    slow final approach lengthens it), and the creep of s: its change between 0.5 s
    and the end of the hold in percent of its whole change over the hold."""
    r = run_commands(params, [(p_to_kpa, hold_s)], p_from_kpa)
    t, pr, s = r.t_s, r.p_kpa, r.s_mm
    dp = pr[-1] - pr[0]
    frac = (pr - pr[0]) / dp
    t10, t90 = _first(t, frac >= 0.1), _first(t, frac >= 0.9)
    ds = s[-1] - s[0]
    i05 = int(round(0.5 / SAMPLE_S))
    return {
        "dead_time_ms": 1000.0 * _first(t, frac > 0.02),
        "rise_10_90_ms": 1000.0 * (t90 - t10),
        "creep_pct": 100.0 * (s[-1] - s[i05]) / ds,
        "dp_kpa": dp,
        "ds_mm": ds,
    }


def staircase_loop(params: RigParams, p_max_kpa: float, step_kpa: float, hold_s: float,
                   p_min_kpa: float = 0.0) -> dict[str, np.ndarray]:
    """A quasi-static staircase p_min -> p_max -> p_min: the terminal p and s of
    every step (after a settle at p_min)."""
    n = int(round((p_max_kpa - p_min_kpa) / step_kpa))
    levels = ([p_min_kpa + step_kpa * i for i in range(1, n + 1)]
              + [p_min_kpa + step_kpa * i for i in range(n - 1, -1, -1)])
    r = run_commands(params, [(lv, hold_s) for lv in levels], p_min_kpa)
    k = int(round(hold_s / SAMPLE_S))
    idx = np.arange(1, len(levels) + 1) * k
    p_end, s_end = r.p_kpa[idx], r.s_mm[idx]
    return {"p_up": np.concatenate([[r.p_kpa[0]], p_end[:n]]), "s_up": np.concatenate([[r.s_mm[0]], s_end[:n]]),
            "p_down": p_end[n - 1:], "s_down": s_end[n - 1:]}


def loop_width_pct(loop: dict[str, np.ndarray]) -> dict[str, float]:
    """The loop's width in s at equal command (falling minus rising branch), in percent
    of the stroke (the range of s): at mid-stroke and its maximum."""
    s_up, s_dn = loop["s_up"], loop["s_down"][::-1]  # both from p_min upwards, level by level
    stroke = max(s_up.max(), s_dn.max()) - min(s_up.min(), s_dn.min())
    width = s_dn - s_up
    mid_level = int(np.argmin(np.abs(s_up - (s_up.min() + 0.5 * stroke))))
    return {"mid_pct": 100.0 * float(width[mid_level]) / stroke, "max_pct": 100.0 * float(width.max()) / stroke,
            "stroke_mm": float(stroke)}


def reversal_ratio_pct(params: RigParams, p_lo_kpa: float, p_hi_kpa: float, rev_kpa: float,
                       hold_s: float = 4.0) -> float:
    """A small reversal after a large step, in percent of the large step's slope
    ds/dp (both from terminal values after hold_s); the mean of a reversal down
    after a large rise and up after a large fall."""
    out = []
    for a, b, c in ((p_lo_kpa, p_hi_kpa, p_hi_kpa - rev_kpa), (p_hi_kpa, p_lo_kpa, p_lo_kpa + rev_kpa)):
        r = run_commands(params, [(b, hold_s), (c, hold_s)], a)
        k = int(round(hold_s / SAMPLE_S))
        s0, s1, s2 = r.s_mm[0], r.s_mm[k], r.s_mm[2 * k]
        p0, p1, p2 = r.p_kpa[0], r.p_kpa[k], r.p_kpa[2 * k]
        out.append(((s2 - s1) / (p2 - p1)) / ((s1 - s0) / (p1 - p0)))
    return 100.0 * float(np.mean(out))


@dataclasses.dataclass(frozen=True)
class TablePoints:
    """Where a profile's table is measured (pressures in kPa)."""

    rise_small: tuple[float, float]
    rise_large: tuple[float, float]
    fall_small: tuple[float, float]
    fall_large: tuple[float, float]
    loop_max_kpa: float
    loop_step_400ms_kpa: float
    loop_step_4s_kpa: float
    reversal: tuple[float, float, float]  # p_lo, p_hi, reversal size


# The measured DMSP-10-250's table at the record's pressures (gauge:
# the record's p + 30 kPa, see tools/fit_rig_dmsp10.py): 0.5 / 2.4 bar rises,
# 0.5 / 1.2 bar falls, the 0.05 V (3 kPa) staircase at 400 ms over the holds'
# range (0 to 7.1 V, 0-420 kPa), 4 s holds, 0.4-0.5 bar reversals.
DMSP10_POINTS = TablePoints(
    rise_small=(150.0, 200.0), rise_large=(0.0, 240.0),
    fall_small=(110.0, 60.0), fall_large=(240.0, 120.0),
    loop_max_kpa=420.0, loop_step_400ms_kpa=6.0, loop_step_4s_kpa=42.0,
    reversal=(120.0, 380.0, 45.0),
)

# The MAS-10 with the ITV2050 (0-900 kPa): the same shapes at its scale (steps of
# the same size in kPa, the loop over 0-600 kPa, its stroke at the rated 600 kPa).
MAS10_POINTS = TablePoints(
    rise_small=(250.0, 300.0), rise_large=(60.0, 300.0),
    fall_small=(110.0, 60.0), fall_large=(240.0, 120.0),
    loop_max_kpa=600.0, loop_step_400ms_kpa=10.0, loop_step_4s_kpa=60.0,
    reversal=(150.0, 450.0, 45.0),
)


def table(params: RigParams, points: TablePoints = DMSP10_POINTS, loops: bool = True) -> dict[str, Any]:
    """Every figure of the measured muscle's table for one rig (noise and drift off). The creep
    figures come from the large rise and fall."""
    q = quiet(params)
    rs = step_figures(q, *points.rise_small)
    rl = step_figures(q, *points.rise_large)
    fs = step_figures(q, *points.fall_small)
    fl = step_figures(q, *points.fall_large)
    out: dict[str, Any] = {
        "dead_time_rise_ms": rs["dead_time_ms"], "dead_time_fall_ms": fs["dead_time_ms"],
        "rise_small_ms": rs["rise_10_90_ms"], "rise_large_ms": rl["rise_10_90_ms"],
        "fall_small_ms": fs["rise_10_90_ms"], "fall_large_ms": fl["rise_10_90_ms"],
        "creep_rise_pct": rl["creep_pct"], "creep_fall_pct": fl["creep_pct"],  # on the large steps
    }
    if loops:
        l400 = loop_width_pct(staircase_loop(q, points.loop_max_kpa, points.loop_step_400ms_kpa, 0.4))
        l4 = loop_width_pct(staircase_loop(q, points.loop_max_kpa, points.loop_step_4s_kpa, 4.0))
        out.update({"loop_400ms_mid_pct": l400["mid_pct"], "loop_400ms_max_pct": l400["max_pct"],
                    "loop_4s_mid_pct": l4["mid_pct"], "stroke_mm": l400["stroke_mm"],
                    "reversal_pct": reversal_ratio_pct(q, *points.reversal)})
    return out
