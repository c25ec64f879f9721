# SPDX-License-Identifier: Apache-2.0
"""A run's results: the per-tick recording, and summary.json built from it.

Shared by the two ways of running a scenario, so that they report the same
figures from the same signals: over CAN (hil/runner.py, pma-fw-host or a board)
and offline (hil/offline.py, the same firmware as a shared library). The figures
themselves are hil/metrics.py's.
"""
from __future__ import annotations

import json
import math
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, ClassVar

import numpy as np

from .metrics import lane_metrics, rmste
from .reference import reference_function
from .rig import Rig
from .scenario import Controller, Scenario

PHASE_IDLE, PHASE_ARMED, PHASE_RUNNING = 0, 1, 2
# (message, signal) -> name in the recording of the firmware's telemetry
TELEM_FIELDS = {
    ("TELEM_A", "TimeMs"): "time_ms", ("TELEM_A", "XCm"): "x_cm",
    ("TELEM_B", "XrCm"): "xr_cm", ("TELEM_B", "ECm"): "e_cm",
    ("TELEM_C", "U"): "u", ("TELEM_C", "VCmS"): "v_cm_s",
    ("TELEM_D", "Internal1"): "internal1", ("TELEM_D", "Internal2"): "internal2",
    ("TELEM_E", "PressureKpa"): "pressure_kpa", ("TELEM_E", "CtrlFlags"): "ctrl_flags",
    ("TELEM_E", "Breaches"): "breaches",
}


class Recorder:
    """Per-lane signals at every tick, in preallocated arrays."""

    FIELDS: ClassVar[dict[str, type]] = {
              "phase": np.int8, "run_step": np.int64, "counts": np.int32, "dac_counts": np.int32,
              "output_active": np.int8, "sample_status": np.int8, "x_true_cm": np.float64,
              "v_true_cm_s": np.float64, "x_meas_cm": np.float64, "p_kpa": np.float64,
              "p_cmd_kpa": np.float64, "load_mass_kg": np.float64, "disturbance_n": np.float64}

    # a tick's values as one tuple per lane (Recorder.add), written into the arrays in blocks:
    # the HIL runner's tick then touches one list, not a dozen arrays (in the vcan guest each
    # page a tick touches costs time after the tick's system calls)
    ROW: ClassVar[tuple[str, ...]] = (
        "counts", "dac_counts", "output_active", "sample_status", "phase", "run_step", "x_true_cm",
        "v_true_cm_s", "p_kpa", "p_cmd_kpa", "load_mass_kg", "disturbance_n")
    BLOCK = 1024    # ticks of rows kept before they go into the arrays

    def __init__(self, lanes: int, ticks: int) -> None:
        self.n = 0
        self.data: list[dict[str, np.ndarray]] = [
            {k: np.zeros(ticks, dtype=t) for k, t in self.FIELDS.items()} for _ in range(lanes)]
        self._rows: list[list[tuple[float, ...]]] = [[] for _ in range(lanes)]

    def add(self, lane: int, row: tuple[float, ...]) -> None:
        """Lane's values of tick n, in the order of ROW (then end_tick)."""
        self._rows[lane].append(row)

    def end_tick(self) -> None:
        self.n += 1
        if len(self._rows[0]) >= self.BLOCK:
            self.flush()

    def flush(self) -> None:
        """The rows added so far into the arrays (they are the last ticks before n)."""
        for lane, rows in enumerate(self._rows):
            if rows:
                block = np.array(rows, dtype=np.float64)
                start = self.n - len(rows)
                for j, key in enumerate(self.ROW):
                    self.data[lane][key][start:self.n] = block[:, j]
                rows.clear()

    def trimmed(self, lane: int) -> dict[str, np.ndarray]:
        self.flush()
        return {k: v[:self.n] for k, v in self.data[lane].items()}


@dataclass
class LaneResult:
    """What one lane (controller, node, rig) of a run left: its end and its signals."""
    ctrl: Controller
    node: int
    rig: Rig
    params: dict[str, float | int]                      # the parameters set, in order
    params_read_back: dict[str, float | int]
    state: str
    fault_code: str
    start_result: str
    final_dac: int
    final_active: int
    data: dict[str, np.ndarray] | None                  # Recorder.trimmed(); None: nothing recorded
    telem: dict[str, list[float]] = field(default_factory=dict)
    repeated_ticks: int | None = None                   # --board only


def summarise(sc: Scenario, lanes: list[LaneResult], *, quick: bool, duration_s: float, period_s: float,
              errors: list[str], interrupted: bool, benchmark: dict[str, Any], wall_s: float,
              out: Path | None, extra: dict[str, Any] | None = None) -> dict[str, Any]:
    """summary.json (docs/hil.md) of a run; with out, written there with signals.npz. A telemetry
    check that fails (the firmware's x is not the harness's) is appended to errors."""
    windows = sc.windows_for(duration_s)
    xr_fn = reference_function(sc.reference)
    arrays: dict[str, np.ndarray] = {}
    lanes_out: dict[str, Any] = {}
    summary: dict[str, Any] = {
        "scenario": sc.name, "title": sc.title, "file": str(sc.path) if sc.path else None,
        "quick": quick, "duration_s": duration_s, "period_s": period_s,
        "windows": [list(w) for w in windows], "paper": sc.paper,
        "rmste": {}, "max_abs_error_after_tu": {}, "constraint_violations": {},
        "constraint_violations_controlled": {}, "constraint_violations_safe_state": {}, "barrier_breaches": {},
        "fault_code": {}, "state": {}, "start_result": {}, "controllers": lanes_out,
        "expect": {"state": sc.expect.state, "fault_code": sc.expect.fault_code,
                   "start_result": sc.expect.start_result},
        "interrupted": interrupted, "errors": errors, "benchmark": benchmark,
        "wall_s": wall_s, **(extra or {}),
    }
    band = sc.band_cm()
    needed = static_pressure_for(sc)
    needed_hysteretic = hysteretic_pressure_for(sc, needed)
    for lane in lanes:
        label = lane.ctrl.label
        summary["fault_code"][label] = lane.fault_code
        summary["state"][label] = lane.state
        summary["start_result"][label] = lane.start_result
        info: dict[str, Any] = {"mode": lane.ctrl.mode, "node": lane.node, "description": lane.ctrl.description,
                                "params_set": lane.params, "params_read_back": lane.params_read_back,
                                "final_dac_counts": lane.final_dac, "final_output_active": lane.final_active}
        d = lane.data
        if d is None or len(d["counts"]) == 0:
            lanes_out[label] = info
            continue
        for k, v in d.items():
            arrays[f"{label}__{k}"] = v
        telem = {k: np.asarray(v, dtype=float) for k, v in lane.telem.items()}
        if "time_ms" in telem:
            telem["t_s"] = telem["time_ms"] / 1000.0
        for k, v in telem.items():
            arrays[f"{label}__telem_{k}"] = v
        scale = lane.rig.params.firmware_scaling()
        x_meas = scale["adc.offset_cm"] + scale["adc.gain_cm_per_count"] * d["counts"].astype(float)
        arrays[f"{label}__x_meas_cm"] = x_meas
        run = d["run_step"] >= 0
        t = d["run_step"][run] * period_s
        xr = xr_fn(t)
        e = x_meas[run] - xr
        arrays[f"{label}__t_s"] = t
        arrays[f"{label}__xr_cm"] = xr
        arrays[f"{label}__e_cm"] = e
        info["reference_check_max_abs_cm"] = reference_check(telem, d["run_step"][run], xr_fn, x_meas[run],
                                                             period_s, errors)
        if lane.repeated_ticks is not None:
            info["board_repeated_ticks"] = lane.repeated_ticks
        if len(t) == 0:
            lanes_out[label] = info
            continue
        # the static pressure the reference needs (every 10 ms), for the chattering ratio
        sub = slice(None, None, max(1, round(0.01 / period_s)))
        p_need = needed(xr[sub])
        ok = np.isfinite(p_need)
        p_need_h = needed_hysteretic(xr[sub])
        ok_h = np.isfinite(p_need_h)
        m = lane_metrics(label, lane.ctrl.mode, t, e, x_meas[run], d["x_true_cm"][run], d["v_true_cm_s"][run],
                         d["p_cmd_kpa"][run], windows, band, sc.t_u_s(lane.ctrl),
                         sc.w1_cm(lane.ctrl) if lane.ctrl.mode == "PPC" else None,
                         telem if "t_s" in telem else None,
                         p_need[ok] if ok.sum() > 1 else None, t[sub][ok] if ok.sum() > 1 else None,
                         output_active=d["output_active"][run],
                         p_needed_hysteretic_kpa=p_need_h[ok_h] if ok_h.sum() > 1 else None,
                         t_needed_hysteretic_s=t[sub][ok_h] if ok_h.sum() > 1 else None)
        m.final_state, m.final_fault_code = lane.state, lane.fault_code
        info.update(m.to_dict())
        # the same windows on the rig's true position (the sensor's noise and quantisation left out)
        info["rmste_true_cm"] = rmste(t, d["x_true_cm"][run] - xr, windows)
        # named for what it counts: the reference against the rig's virgin static curve
        # (no hysteresis, no friction, the initial load): a lower bound of what the muscle
        # cannot reach; with strong hysteresis x may bottom out short of it all the same
        info["reference_unreachable_virgin_curve_samples"] = int((~ok).sum())
        # the PPC's guarantee monitor, from TELEM_E's CtrlFlags (docs/controllers.md)
        info["guarantee_lost_at_s"] = first_flag_time(telem, CTRL_FLAG_GUARANTEE_LOST)
        info["fallback_at_s"] = first_flag_time(telem, CTRL_FLAG_FALLBACK)
        info["input_at_limit_before_loss_s"] = held_at_limit_before(telem, CTRL_FLAG_GUARANTEE_LOST)
        # ppc.fallback WIDEN: the first sample with a funnel wider than assigned (the flag lasts
        # t_u, so the telemetry's decimation cannot miss it as it could the one-tick WIDEN1/2)
        info["funnel_wide_at_s"] = (first_flag_time(telem, PPC_FLAG_WIDE)
                                    if lane.ctrl.mode == "PPC" else None)
        summary["rmste"][label] = m.rmste_cm
        summary["max_abs_error_after_tu"][label] = m.max_abs_error_after_tu_cm
        summary["constraint_violations"][label] = m.constraint_violations
        summary["constraint_violations_controlled"][label] = m.constraint_violations_controlled
        summary["constraint_violations_safe_state"][label] = m.constraint_violations_safe_state
        summary["barrier_breaches"][label] = m.barrier_breaches
        lanes_out[label] = info
    ok_all = (not errors and not interrupted and all(
        summary["state"].get(c.label) == sc.expect.state and summary["fault_code"].get(c.label) == sc.expect.fault_code
        and summary["start_result"].get(c.label) == sc.expect.start_result for c in sc.controllers))
    summary["expect_met"] = ok_all
    if out is not None:
        out.mkdir(parents=True, exist_ok=True)
        if arrays:
            np.savez_compressed(out / "signals.npz", **arrays)  # type: ignore[arg-type]
        (out / "summary.json").write_text(json.dumps(jsonable(summary), indent=2) + "\n")
    return summary


# Bits of TELEM_E CtrlFlags set by the application above the control laws' own flags
# (PMA_CTRL_FLAG_* in firmware/app/controller.h; hil/tests/test_summary_flags.py checks them).
CTRL_FLAG_GUARANTEE_LOST = 0x4000
CTRL_FLAG_FALLBACK = 0x8000
# the paper's law's own flag for a widened funnel (PMA_PPC_FLAG_WIDE in pma/ppc.h)
PPC_FLAG_WIDE = 0x0100
# the law's output at ctrl.u_max / ctrl.u_min (PMA_PPC_FLAG_SAT_HIGH / SAT_LOW in pma/ppc.h)
PPC_FLAG_SAT_HIGH = 0x0004
PPC_FLAG_SAT_LOW = 0x0008
PPC_FLAGS_SAT = PPC_FLAG_SAT_HIGH | PPC_FLAG_SAT_LOW


def first_flag_time(telem: dict[str, np.ndarray], bit: int) -> float | None:
    """Control time [s] of the first telemetry sample with `bit` in CtrlFlags; None if none."""
    if "t_s" not in telem or "ctrl_flags" not in telem or not len(telem["ctrl_flags"]):
        return None
    hit = (telem["ctrl_flags"].astype(np.int64) & bit) != 0
    return float(telem["t_s"][np.argmax(hit)]) if hit.any() else None


def held_at_limit_before(telem: dict[str, np.ndarray], bit: int) -> float | None:
    """How long [s] the output had been at one of its limits (PPC_FLAG_SAT_HIGH or _LOW, the same
    one on every telemetry sample) at the first sample with `bit`: 0 where it is not at a limit
    there (or at both), None where no sample has `bit`. From the telemetry, so to its decimation."""
    if "t_s" not in telem or "ctrl_flags" not in telem or not len(telem["ctrl_flags"]):
        return None
    flags = telem["ctrl_flags"].astype(np.int64)
    hit = (flags & bit) != 0
    if not hit.any():
        return None
    i = int(np.argmax(hit))
    sat = int(flags[i]) & PPC_FLAGS_SAT
    if sat not in (PPC_FLAG_SAT_HIGH, PPC_FLAG_SAT_LOW):
        return 0.0
    other = (flags[: i + 1] & PPC_FLAGS_SAT) != sat
    first = int(np.nonzero(other)[0][-1]) + 1 if other.any() else 0
    return float(telem["t_s"][i] - telem["t_s"][first])


def reference_check(telem: dict[str, np.ndarray], steps: np.ndarray, xr_fn: Callable[[np.ndarray], np.ndarray],
                    x_meas: np.ndarray, period_s: float, errors: list[str]) -> float | None:
    """max |x_r(harness) - x_r(firmware, TELEM_B)| over the telemetry samples, and an error
    appended when the firmware's x (TELEM_A) is not the harness's measured x at the same tick
    (the time bases disagree). steps: the run step of each recorded sample (0, 1, 2, ... in
    lockstep; a board's ticks without a new sample are skipped, and they used the sample before)."""
    if "t_s" not in telem or not len(telem["t_s"]) or not len(steps):
        return None
    tick = np.round(telem["t_s"] / period_s).astype(np.int64)
    idx = np.searchsorted(steps, tick, side="right") - 1     # the sample that tick used
    ok = (idx >= 0) & (tick <= steps[-1])
    if not ok.any():
        return None
    idx = idx[ok]
    dx = np.abs(telem["x_cm"][ok] - x_meas[idx])
    if float(np.max(dx)) > 1e-4:
        errors.append(f"telemetry x differs from the harness's measured x by {float(np.max(dx)):.3g} cm: "
                      "the time bases disagree")
    # x_r at the telemetry's own tick (on a repeated tick, later than the sample's)
    return float(np.max(np.abs(telem["xr_cm"][ok] - xr_fn(tick[ok] * period_s))))


def static_pressure_for(sc: Scenario) -> Callable[[np.ndarray], np.ndarray]:
    """x [cm] -> the steady pressure command [kPa] that holds it on the scenario's rig
    (static curve without friction, initial load; NaN where 0..p_max does not reach)."""
    x, p = static_curve(Rig(sc.rig_params(), seed=sc.seed), friction=0.0)

    def f(xq: np.ndarray) -> np.ndarray:
        out: np.ndarray = np.interp(xq, x, p)
        out[(xq < x[0]) | (xq > x[-1])] = math.nan
        return out
    return f


def static_curve(rig: Rig, friction: float) -> tuple[np.ndarray, np.ndarray]:
    """The rig's static curve as (x [cm], pressure command [kPa]) sorted by x, over 45 kPa
    (F(P) > 0: monotone) to p_max; friction as Rig.static_xs_mm's (0: none, +1/-1: a branch)."""
    p = np.linspace(45.0, rig.params.regulator.p_max_kpa, 1000)
    x = np.array([rig.static_x_cm(float(v), friction=friction) for v in p])
    order = np.argsort(x)
    return x[order], p[order]


def hysteretic_pressure_for(sc: Scenario, virgin: Callable[[np.ndarray], np.ndarray] | None = None
                            ) -> Callable[[np.ndarray], np.ndarray]:
    """x_r [cm], samples in time order -> the steady pressure command [kPa] that holds each on
    the branch the reference's direction puts the muscle on: the muscle's friction saturated
    against the motion and the regulator's backlash taken up (the initial load; NaN where the
    branch does not reach). At each reversal the command crosses the width of both loops
    without moving x, motion that static_pressure_for's frictionless curve does not count.
    The direction is that of the frictionless need (x_r's own, through the polarity), held
    where x_r stands still (virgin: static_pressure_for(sc), if the caller has it already)."""
    rig = Rig(sc.rig_params(), seed=sc.seed)
    reg = rig.params.regulator
    backlash_half_kpa = 0.5 * reg.hysteresis_frac_fs * reg.fs_kpa
    rising, falling = static_curve(rig, +1.0), static_curve(rig, -1.0)
    frictionless = virgin if virgin is not None else static_pressure_for(sc)

    def f(xq: np.ndarray) -> np.ndarray:
        step = np.nan_to_num(np.sign(np.diff(frictionless(xq))))
        moving = np.flatnonzero(step)
        direction = np.ones(len(xq))
        if len(moving):
            # each sample takes the last nonzero step's sign up to it (the first one's before it)
            last = np.maximum.accumulate(np.where(step != 0, np.arange(len(step)), -1))
            held = np.where(last >= 0, step[np.maximum(last, 0)], step[moving[0]])
            direction = np.concatenate([[held[0]], held])
        up = np.interp(xq, *rising) + backlash_half_kpa
        down = np.interp(xq, *falling) - backlash_half_kpa
        out: np.ndarray = np.where(direction > 0, up, down)
        outside_up = (xq < rising[0][0]) | (xq > rising[0][-1])
        outside_down = (xq < falling[0][0]) | (xq > falling[0][-1])
        out[np.where(direction > 0, outside_up, outside_down)] = math.nan
        return out
    return f


def jsonable(o: Any) -> Any:
    """o with numpy scalars as Python numbers and non-finite floats as None (JSON null)."""
    if isinstance(o, dict):
        return {str(k): jsonable(v) for k, v in o.items()}
    if isinstance(o, (list, tuple)):
        return [jsonable(v) for v in o]
    if isinstance(o, (np.floating, float)):
        return None if not math.isfinite(float(o)) else float(o)
    if isinstance(o, (np.integer,)):
        return int(o)
    return o
