# SPDX-License-Identifier: Apache-2.0
"""Figures of merit of one controller's run, from the recorded signals.

All times are control time since START [s] (tick n of the run is t = n T). The
error is the one the paper's tables use: the measured position (the sensor's
counts through the firmware's adc.* scaling, what the controller saw) minus the
reference, at every control tick.
"""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np

from pmactl.figures import (
    max_abs_from,
    rmste,
    samples_outside_from,
    time_to_band,
    total_variation_per_s,
)

# the figures themselves, once for the harness and pmactl (their rules: pmactl/figures.py)
__all__ = ["LaneMetrics", "lane_metrics", "rmste", "time_to_band", "total_variation_per_s"]


@dataclass
class LaneMetrics:
    label: str
    mode: str
    samples: int
    duration_s: float
    windows: list[tuple[float, float]]
    rmste_cm: list[float]
    t_u_s: float | None
    w1_cm: float | None
    max_abs_error_cm: float
    max_abs_error_after_tu_cm: float | None     # after t_u (PPC) or after the first window's start
    samples_outside_w1_after_tu: int | None
    time_to_band_s: float | None                # from then on |e| < w1 to the end
    constraint_violations: int                  # samples of the measured x outside k_low < x < k_high (all)
    constraint_violations_true_x: int           # the same with the rig's true position
    # the same split by who commands the pressure: the controller (output active), or the
    # safe state after a fault (output inactive: e.g. a vented muscle under a pull is
    # outside the band by physics, docs/firmware.md "The safe state")
    x_min_cm: float
    x_max_cm: float
    barrier_breaches: int | None                # PPC: clamped steps, whole run (TELEM_E; None: no telemetry)
    barrier_breaches_after_tu: int | None
    peak_velocity_cm_s: float                   # the rig's true |x'|
    peak_velocity_estimate_cm_s: float | None   # the firmware's estimate (telemetry)
    peak_u: float | None                        # the controller's |u| [input unit] (telemetry)
    peak_pressure_cmd_kpa: float
    tv_u_per_s: float | None                    # total variation of u per second (telemetry rate)
    tv_pressure_cmd_kpa_per_s: float            # total variation of the pressure command per second (every tick)
    tv_pressure_needed_kpa_per_s: float | None  # the same for the static pressure the reference needs
    chatter_ratio: float | None                 # tv_pressure_cmd / tv_pressure_needed (1 = no more motion than needed)
    constraint_violations_controlled: int = 0   # samples with the output active
    constraint_violations_safe_state: int = 0   # samples in the safe state (output inactive)
    # the same ratio over what the reference needs on a hysteretic rig: the pressure on the branch
    # its direction puts the muscle on, each reversal crossing the hysteresis without moving x
    # (hil/summary.py hysteretic_pressure_for); equal to the above on a rig without hysteresis
    tv_pressure_needed_hysteretic_kpa_per_s: float | None = None
    chatter_ratio_hysteretic: float | None = None
    final_state: str = ""
    final_fault_code: str = ""
    extra: dict[str, Any] = field(default_factory=dict)

    def to_dict(self) -> dict[str, Any]:
        d = asdict(self)
        d["windows"] = [list(w) for w in self.windows]
        return d


def _chatter(tv_p_kpa_per_s: float, t_needed_s: np.ndarray | None,
             p_needed_kpa: np.ndarray | None) -> tuple[float | None, float | None]:
    """(the needed pressure's total variation [kPa/s], the command's over it); None, None
    without a need of two samples or more, a ratio of None where the need does not move."""
    if p_needed_kpa is None or t_needed_s is None or len(p_needed_kpa) <= 1:
        return None, None
    tv_need = total_variation_per_s(t_needed_s, p_needed_kpa)
    return tv_need, (tv_p_kpa_per_s / tv_need if tv_need > 1e-9 else None)


def lane_metrics(label: str, mode: str, t_s: np.ndarray, e_cm: np.ndarray, x_meas_cm: np.ndarray,
                 x_true_cm: np.ndarray, v_true_cm_s: np.ndarray, p_cmd_kpa: np.ndarray,
                 windows: list[tuple[float, float]], band: tuple[float, float], t_u_s: float | None,
                 w1_cm: float | None, telem: dict[str, np.ndarray] | None,
                 p_needed_kpa: np.ndarray | None = None, t_needed_s: np.ndarray | None = None,
                 output_active: np.ndarray | None = None,
                 p_needed_hysteretic_kpa: np.ndarray | None = None,
                 t_needed_hysteretic_s: np.ndarray | None = None) -> LaneMetrics:
    lo, hi = band
    t_after = t_u_s if t_u_s is not None else (windows[0][0] if windows else 0.0)
    max_after = max_abs_from(t_s, e_cm, t_after)
    outside_after = samples_outside_from(t_s, e_cm, w1_cm, t_after) if w1_cm else None
    viol = int(np.sum((x_meas_cm <= lo) | (x_meas_cm >= hi)))
    viol_true = int(np.sum((x_true_cm <= lo) | (x_true_cm >= hi)))
    outside = (x_meas_cm <= lo) | (x_meas_cm >= hi)
    active = np.ones(len(x_meas_cm), bool) if output_active is None else np.asarray(output_active).astype(bool)
    viol_controlled = int(np.sum(outside & active))
    viol_safe = int(np.sum(outside & ~active))
    breaches = breaches_after = None
    peak_v_est = peak_u = tv_u = None
    if telem is not None and len(telem.get("t_s", [])):
        tt = telem["t_s"]
        if mode == "PPC" and "breaches" in telem:
            b = telem["breaches"].astype(np.int64)
            breaches = int(b[-1])
            at_tu = b[tt <= (t_u_s or 0.0)]
            breaches_after = int(b[-1] - (at_tu[-1] if len(at_tu) else 0))
        peak_v_est = float(np.max(np.abs(telem["v_cm_s"])))
        peak_u = float(np.max(np.abs(telem["u"])))
        tv_u = total_variation_per_s(tt, telem["u"])
    tv_p = total_variation_per_s(t_s, p_cmd_kpa)
    tv_need, chatter = _chatter(tv_p, t_needed_s, p_needed_kpa)
    tv_need_h, chatter_h = _chatter(tv_p, t_needed_hysteretic_s, p_needed_hysteretic_kpa)
    return LaneMetrics(
        label=label, mode=mode, samples=int(len(t_s)),
        duration_s=float(t_s[-1] - t_s[0]) if len(t_s) else 0.0, windows=windows,
        rmste_cm=rmste(t_s, e_cm, windows), t_u_s=t_u_s, w1_cm=w1_cm,
        max_abs_error_cm=float(np.max(np.abs(e_cm))) if len(e_cm) else math.nan,
        max_abs_error_after_tu_cm=max_after, samples_outside_w1_after_tu=outside_after,
        time_to_band_s=time_to_band(t_s, e_cm, w1_cm) if w1_cm else None,
        constraint_violations=viol, constraint_violations_true_x=viol_true,
        x_min_cm=float(np.min(x_meas_cm)), x_max_cm=float(np.max(x_meas_cm)),
        barrier_breaches=breaches, barrier_breaches_after_tu=breaches_after,
        peak_velocity_cm_s=float(np.max(np.abs(v_true_cm_s))), peak_velocity_estimate_cm_s=peak_v_est,
        peak_u=peak_u, peak_pressure_cmd_kpa=float(np.max(p_cmd_kpa)) if len(p_cmd_kpa) else math.nan,
        tv_u_per_s=tv_u, tv_pressure_cmd_kpa_per_s=tv_p, tv_pressure_needed_kpa_per_s=tv_need,
        chatter_ratio=chatter,
        constraint_violations_controlled=viol_controlled, constraint_violations_safe_state=viol_safe,
        tv_pressure_needed_hysteretic_kpa_per_s=tv_need_h, chatter_ratio_hysteretic=chatter_h,
    )
