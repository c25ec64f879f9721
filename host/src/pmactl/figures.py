# SPDX-License-Identifier: Apache-2.0
"""The figures of merit of a tracking run, once: what `pmactl record`'s summary, `pmactl plot`
and the HIL harness's summary.json (hil/metrics.py) report, with one name and one rule each.

Inputs are arrays of the same length: time t [s] (increasing), the tracking error e = x - x_r
[cm], or any signal y. The rules:
- a NaN sample of e (a tick without telemetry, a lost frame) is not known to be inside the
  band: it counts as outside w1, and it is left out of RMSTE and max |e|;
- a figure over no (finite) sample is None, and so is "never" (time_to_band when the run
  ends outside the band); in a list of windows such a window's RMSTE is nan (null in JSON).
"""
from __future__ import annotations

import math

import numpy as np


def rmste(t_s: np.ndarray, e_cm: np.ndarray, windows: list[tuple[float, float]]) -> list[float]:
    """Root-mean-square tracking error [cm] over each window t0 <= t < t1 (nan: no sample)."""
    out = []
    finite = ~np.isnan(e_cm)
    for t0, t1 in windows:
        sel = (t_s >= t0) & (t_s < t1) & finite
        out.append(float(np.sqrt(np.mean(e_cm[sel] ** 2))) if sel.any() else math.nan)
    return out


def rmste_from(t_s: np.ndarray, e_cm: np.ndarray, t0_s: float | None) -> float | None:
    """RMSTE [cm] over t >= t0 (the whole run for None); None: no sample."""
    v = rmste(t_s, e_cm, [(-math.inf if t0_s is None else t0_s, math.inf)])[0]
    return None if math.isnan(v) else v


def max_abs_from(t_s: np.ndarray, y: np.ndarray, t0_s: float | None) -> float | None:
    """max |y| over t >= t0 (the whole run for None), NaN samples left out; None: no sample."""
    sel = ~np.isnan(y) if t0_s is None else (t_s >= t0_s) & ~np.isnan(y)
    return float(np.max(np.abs(y[sel]))) if sel.any() else None


def samples_outside_from(t_s: np.ndarray, e_cm: np.ndarray, w1_cm: float, t0_s: float | None) -> int | None:
    """How many samples with t >= t0 have |e| >= w1 (NaN counts as outside); None: no sample."""
    sel = np.ones(len(t_s), bool) if t0_s is None else t_s >= t0_s
    if not sel.any():
        return None
    return int(np.sum(~(np.abs(e_cm[sel]) < w1_cm)))


def time_to_band(t_s: np.ndarray, e_cm: np.ndarray, w1_cm: float) -> float | None:
    """The first time from which |e| < w1 for every later sample (NaN counts as outside);
    None: the run ends outside the band (never), or has no sample."""
    if len(t_s) == 0:
        return None
    outside = np.flatnonzero(~(np.abs(e_cm) < w1_cm))
    if len(outside) == 0:
        return float(t_s[0])
    last = int(outside[-1])
    return None if last + 1 >= len(t_s) else float(t_s[last + 1])


def total_variation_per_s(t_s: np.ndarray, y: np.ndarray) -> float:
    """sum |y[k+1] - y[k]| / duration: how much a signal moves per second (chattering)."""
    if len(y) < 2:
        return 0.0
    return float(np.sum(np.abs(np.diff(y))) / max(t_s[-1] - t_s[0], 1e-12))
