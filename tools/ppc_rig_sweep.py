#!/usr/bin/env python3
"""Offline closed-loop runs of the firmware's control pipeline on the simulated rig.

Pure Python, no CAN. Each control tick (1 ms at sys.tick_hz = 1000) does what the firmware
application does (firmware/app/app.c, controller.c, actuator.c, hal/src/*_scaling.c):

    counts = rig.sensor_counts()                      # 12-bit ADC sample
    x      = adc.offset_cm + adc.gain_cm_per_count * counts
    (RUNNING only) v = velest(x); xr = ref(t); u = ctrl(t, x, v, xr)
                   (PPC with ppc.obs_pos / ppc.ref_vel: x_hat for x, v - xr' for v)
    p      = p0 + polarity * kpa_per_u * u, clamped to [p_min, p_max], slew-limited
    rig.apply_dac(round(dac.counts_at_zero_kpa + dac.counts_per_kpa * p)); rig.step(T)

The controllers are the numpy/python mirror of the firmware's control library
(tests/golden/pma_reference.py), MFAC in float32 arithmetic as the firmware runs it (its
near-steady-state behaviour depends on it: see pma_reference.Mfac). The run starts with the rig vented and at rest (IDLE output
VENT = 0 kPa), ARMs (output p0, u = 0) for --arm-s, then STARTs the tracking task (t = 0).

Cases (the paper's Section 5, /work/shared/spec/controller.md): 1, 2a, 2b, 3.
Metrics (after START): RMSTE per window, max |e| after t_u, time to enter the w1 band for good,
band violations (-3 < x < 0), barrier breaches (after t_u and in total), the longest run of
consecutive barrier ticks (safety.barrier_ticks faults the drive), peak |v|, peak |u|, the total
variation of u and of the pressure command per second, compared with the total variation of
the static pressure the reference itself needs.

Scenario defaults (override with --rig / --set / --dist): rig p0_kpa 40 (x = 0 at the relaxed
muscle), initial_p_kpa 0 (vented, at rest), 2.55 kg hanging load; Case 1 load.bias_force_n +20 N
(cylinder at port B pulling, in the sensor zero); Case 3 disturbance -20 N (port A: a push) from
t = 20 s. Firmware: act.polarity -1, act.p0_kpa 100 (ARMED muscle at x ~ -0.14 cm), act.p_max_kpa
900, ctrl.u_min/u_max derived from act.* unless given. Each case sets the paper's ppc.* values.
The paper's law exactly: no --set at all (ff off, soft barrier off, vel.fc_hz 30).

Examples:
    .venv/bin/python tools/ppc_rig_sweep.py --case 1
    .venv/bin/python tools/ppc_rig_sweep.py --case 3 --quick --set ppc.ff_gain_per_s=2
    .venv/bin/python tools/ppc_rig_sweep.py --case 3 --set ctrl.mode=2 --set act.kpa_per_u=90
    .venv/bin/python tools/ppc_rig_sweep.py --case 2a --grid ppc.ff_gain_per_s=0,1,2 --jobs 2
"""
from __future__ import annotations

import argparse
import importlib.util
import itertools
import json
import math
import multiprocessing
import sys
import time
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

REPO = Path(__file__).resolve().parents[1]
if str(REPO) not in sys.path:
    sys.path.insert(0, str(REPO))

from hil.rig import Rig  # noqa: E402
from hil.rig_params import RigParams  # noqa: E402


def _load_reference() -> Any:
    path = REPO / "tests" / "golden" / "pma_reference.py"
    spec = importlib.util.spec_from_file_location("pma_reference", path)
    assert spec is not None and spec.loader is not None
    mod = importlib.util.module_from_spec(spec)
    sys.modules["pma_reference"] = mod
    spec.loader.exec_module(mod)
    return mod


ref_mod = _load_reference()

PARAMS_TOML = REPO / "firmware" / "app" / "params.toml"
MODE_PPC, MODE_MFAC, MODE_PID = 1, 2, 3


def firmware_table() -> dict[str, dict[str, Any]]:
    """name -> the parameter's entry in firmware/app/params.toml (range, unit, default)."""
    with open(PARAMS_TOML, "rb") as f:
        return {p["name"]: p for p in tomllib.load(f)["param"]}


def firmware_defaults() -> dict[str, float]:
    """name -> default of every parameter in firmware/app/params.toml."""
    return {name: p["default"] for name, p in firmware_table().items()}


def check_firmware_values(values: dict[str, Any], table: dict[str, dict[str, Any]]) -> None:
    """SystemExit for a name the firmware does not have or a value outside its range
    (params.toml): a result the firmware would refuse to run is no result."""
    for name, v in values.items():
        p = table.get(name)
        if p is None:
            raise SystemExit(f"ppc_rig_sweep: {name}: no such firmware parameter (firmware/app/params.toml)")
        if isinstance(v, (int, float)) and not p["min"] <= v <= p["max"]:
            raise SystemExit(f"ppc_rig_sweep: {name} = {v:g} is outside {p['min']:g}..{p['max']:g} "
                             f"{p.get('unit', '')}: the firmware would refuse it")


# ------------------------------------------------------------------------------------ cases --
@dataclass
class Case:
    name: str
    ref_kind: int
    duration_s: float
    windows: list[tuple[float, float]]
    fw: dict[str, float]
    # rig scenario: RigParams overrides and the time-dependent disturbance
    rig: dict[str, Any] = field(default_factory=dict)
    dist_n: float = 0.0
    dist_t_on_s: float = 20.0


W12 = [(10.0, 20.0), (20.0, 30.0), (30.0, 40.0), (40.0, 50.0), (50.0, 60.0)]
W3 = [(5.0, 30.0), (30.0, 60.0), (60.0, 90.0), (90.0, 120.0), (120.0, 150.0), (150.0, 180.0)]

# Paper's values per case (controller.md table). ref.horizon_s covers the run (band check).
CASES: dict[str, Case] = {
    "1": Case("1", ref_mod.REF_CASE1, 60.0, W12,
              {"ppc.t_u_s": 6, "ppc.a_cm_s": 2, "ppc.c": 2, "ppc.w1_cm": 0.5, "ppc.w2_cm_s": 0.5,
               "ref.kind": 4, "ref.horizon_s": 60,
               # x_r - w1 touches k_low = -3 exactly: the START band check (eq. 14, strict)
               # refuses Case 1, so the paper's own Case 1 needs the check off.
               "ppc.band_check": 0},
              rig={"load.bias_force_n": 20.0}),
    "2a": Case("2a", ref_mod.REF_CASE1, 60.0, W12,
               {"ppc.t_u_s": 6, "ppc.a_cm_s": 2, "ppc.c": 2, "ppc.w1_cm": 0.3, "ppc.w2_cm_s": 0.5,
                "ref.kind": 4, "ref.horizon_s": 60}),
    "2b": Case("2b", ref_mod.REF_CASE1, 60.0, W12,
               {"ppc.t_u_s": 2, "ppc.a_cm_s": 2, "ppc.c": 2, "ppc.w1_cm": 0.3, "ppc.w2_cm_s": 0.5,
                "ref.kind": 4, "ref.horizon_s": 60}),
    "3": Case("3", ref_mod.REF_CASE3, 180.0, W3,
              {"ppc.t_u_s": 2, "ppc.a_cm_s": 2, "ppc.c": 2, "ppc.w1_cm": 0.2, "ppc.w2_cm_s": 0.5,
               "ref.kind": 5, "ref.horizon_s": 180},
              # port A: opposite to Case 1's port B pull, i.e. a push (negative)
              dist_n=-20.0, dist_t_on_s=20.0),
}

# Scenario defaults common to all cases (see the report for the reasons):
#  - rig p0 40 kPa: x = 0 (the sensor zero) at the relaxed muscle (F(P) = 0 below 42 kPa), so that -2.5 cm is inside
#    the regulator's range; the rig starts vented (initial_p_kpa 0).
#  - firmware: polarity -1 (this rig's H < 0), p0 100 kPa (ARMED muscle at x = -0.14 cm), p_max 900.
COMMON_RIG: dict[str, Any] = {"p0_kpa": 40.0, "initial_p_kpa": 0.0}
COMMON_FW: dict[str, float] = {"act.polarity": -1, "act.p0_kpa": 100.0, "act.p_min_kpa": 0.0,
                               "act.p_max_kpa": 900.0, "vel.fc_hz": 30.0}


def parse_value(text: str) -> Any:
    low = text.strip().lower()
    if low in ("true", "false"):
        return low == "true"
    if low in ("none", "null"):
        return None
    try:
        v = float(text)
        return int(v) if v.is_integer() and "." not in text and "e" not in low else v
    except ValueError:
        return text


def parse_assignments(items: list[str] | None) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for item in items or []:
        if "=" not in item:
            raise SystemExit(f"expected name=value, got {item!r}")
        k, v = item.split("=", 1)
        out[k.strip()] = parse_value(v)
    return out


# ------------------------------------------------------------------------------- simulation --
@dataclass
class RunConfig:
    case: str
    fw: dict[str, Any]
    rig: dict[str, Any]
    duration_s: float
    dist_n: float
    dist_t_on_s: float
    seed: int = 1
    idle_s: float = 0.2
    arm_s: float = 1.0
    label: str = ""
    trace: str = ""


def build_config(case_name: str, fw_over: dict[str, Any], rig_over: dict[str, Any],
                 duration_s: float | None = None, dist_n: float | None = None,
                 seed: int = 1, arm_s: float = 1.0, label: str = "") -> RunConfig:
    case = CASES[case_name]
    defaults = firmware_defaults()
    fw = dict(defaults)
    fw.update(COMMON_FW)
    fw.update(case.fw)
    fw.update(fw_over)
    unknown = set(fw) - set(defaults)
    if unknown:
        raise SystemExit(f"unknown firmware parameter(s) {sorted(unknown)}")
    # ctrl.u_min/u_max consistent with the actuator limits unless given explicitly
    k = float(fw["act.kpa_per_u"]) * float(fw["act.polarity"])
    lims = sorted(((fw["act.p_min_kpa"] - fw["act.p0_kpa"]) / k, (fw["act.p_max_kpa"] - fw["act.p0_kpa"]) / k))
    if "ctrl.u_min" not in fw_over:
        fw["ctrl.u_min"] = lims[0]
    if "ctrl.u_max" not in fw_over:
        fw["ctrl.u_max"] = lims[1]
    rig = dict(COMMON_RIG)
    rig.update(case.rig)
    rig.update(rig_over)
    return RunConfig(case=case_name, fw=fw, rig=rig,
                     duration_s=case.duration_s if duration_s is None else duration_s,
                     dist_n=case.dist_n if dist_n is None else dist_n,
                     dist_t_on_s=case.dist_t_on_s, seed=seed, arm_s=arm_s, label=label)


def ref_bounds(kind: int, horizon_s: float) -> tuple[float, float]:
    if kind == ref_mod.REF_CASE1:
        return -2.5, -1.5
    if kind == ref_mod.REF_CASE3:
        return -2.0 - horizon_s / 360.0, -2.0 + horizon_s / 360.0
    raise ValueError("only CASE1 and CASE3 references here")


def static_u_need(rig: Rig, fw: dict[str, Any], kind: int, duration_s: float) -> float:
    """Total variation per second of the static pressure command that holds x_r(t) (kPa/s):
    the smallest input activity any controller needs (10 ms grid)."""
    ref = ref_mod.Ref(ref_mod.RefConfig(kind=kind))
    prev = None
    tv = 0.0
    n = int(duration_s / 0.01)
    for i in range(n + 1):
        xr, _ = ref.eval(i * 0.01)
        p = rig.p_cmd_for_x_cm(xr)
        if p is None:
            p = fw["act.p_max_kpa"] if xr < 0 else fw["act.p_min_kpa"]
        if prev is not None:
            tv += abs(p - prev)
        prev = p
    return tv / duration_s


def simulate(cfg: RunConfig) -> dict[str, Any]:
    fw = cfg.fw
    rp = RigParams().replace(**cfg.rig) if cfg.rig else RigParams()
    rig = Rig(rp, seed=cfg.seed)
    period = 1.0 / float(fw["sys.tick_hz"])
    mode = int(fw["ctrl.mode"])
    kind = int(fw["ref.kind"])
    u_min, u_max = float(fw["ctrl.u_min"]), float(fw["ctrl.u_max"])
    # START checks of controller.c: the band check (eq. 14)
    start_refused = ""
    margin = float(fw["ppc.w1_cm"]) if (mode == MODE_PPC and fw["ppc.band_check"]) else 0.0
    lo, hi = ref_bounds(kind, float(fw["ref.horizon_s"]))
    if not (lo - margin > fw["safety.x_min_cm"] and hi + margin < fw["safety.x_max_cm"]):
        start_refused = "PMA_ERR_BAND (set ppc.band_check = 0 to run anyway)"

    ref = ref_mod.Ref(ref_mod.RefConfig(kind=kind))
    vel = ref_mod.Velest(ref_mod.VelestConfig(kind=int(fw["vel.kind"]), fc_hz=float(fw["vel.fc_hz"]),
                                              period_s=period))
    ppc = mfac = pid = None
    if mode == MODE_PPC:
        ppc = ref_mod.Ppc(ref_mod.PpcConfig(
            a_cm_s=fw["ppc.a_cm_s"], c=fw["ppc.c"], w1_cm=fw["ppc.w1_cm"], w2_cm_s=fw["ppc.w2_cm_s"],
            t_u_s=fw["ppc.t_u_s"], u_min=u_min, u_max=u_max, barrier_margin=fw["ppc.barrier_margin"],
            soft_barrier_r=fw["ppc.soft_barrier_r"], ff_gain_per_s=fw["ppc.ff_gain_per_s"],
            ff_init=fw["ppc.ff_init"], period_s=period))
        t_u = float(fw["ppc.t_u_s"])
        w1 = float(fw["ppc.w1_cm"])
        if fw["ppc.obs_pos"] and int(fw["vel.kind"]) != 1:
            start_refused = start_refused or "PMA_ERR_RANGE (ppc.obs_pos needs vel.kind = 1)"
    elif mode == MODE_MFAC:
        mfac = ref_mod.Mfac(ref_mod.MfacConfig(
            eta=fw["mfac.eta"], mu=fw["mfac.mu"], rho=fw["mfac.rho"], lam=fw["mfac.lambda"],
            eps=fw["mfac.eps"], phi1=fw["mfac.phi1"], u_min=u_min, u_max=u_max, u_init=fw["mfac.u_init"]),
            float32=True)        # as pma_mfac_step_f32: in double, Case 3 30-60 s reads 15 % higher
        t_u = float(fw["ppc.t_u_s"])  # evaluation uses the case's t_u and w1 for comparison
        w1 = float(fw["ppc.w1_cm"])
    elif mode == MODE_PID:
        pid = ref_mod.Pid(ref_mod.PidConfig(
            kp=fw["pid.kp"], ki=fw["pid.ki"], kd=fw["pid.kd"], tf_s=fw["pid.tf_s"],
            k_aw_per_s=fw["pid.k_aw_per_s"], period_s=period, u_min=u_min, u_max=u_max))
        t_u = float(fw["ppc.t_u_s"])
        w1 = float(fw["ppc.w1_cm"])
    else:
        raise SystemExit("ctrl.mode must be 1 (PPC), 2 (MFAC) or 3 (PID)")

    off, gain = float(fw["adc.offset_cm"]), float(fw["adc.gain_cm_per_count"])
    raw_min, raw_max = int(fw["adc.raw_min_counts"]), int(fw["adc.raw_max_counts"])
    c0, cpk = float(fw["dac.counts_at_zero_kpa"]), float(fw["dac.counts_per_kpa"])
    cmin, cmax = int(fw["dac.min_counts"]), int(fw["dac.max_counts"])
    p0, pol, kpu = float(fw["act.p0_kpa"]), float(fw["act.polarity"]), float(fw["act.kpa_per_u"])
    p_lo, p_hi = float(fw["act.p_min_kpa"]), float(fw["act.p_max_kpa"])
    slew = float(fw["act.slew_kpa_s"]) * period
    xmin, xmax, xmarg = float(fw["safety.x_min_cm"]), float(fw["safety.x_max_cm"]), float(fw["safety.x_margin_cm"])
    barrier_ticks = int(fw["safety.barrier_ticks"])

    n_idle = int(round(cfg.idle_s / period))
    n_arm = int(round(cfg.arm_s / period))
    n_run = int(round(cfg.duration_s / period))
    if cfg.dist_n != 0.0:
        rig.set_disturbance(cfg.dist_n, t_on_s=(n_idle + n_arm) * period + cfg.dist_t_on_s)

    p_cmd = 0.0
    faults: list[str] = []
    arm_x: list[float] = []
    # per-run-sample logs
    ts: list[float] = []
    es: list[float] = []
    es_true: list[float] = []  # true position (at the sample instant) minus x_r
    xs_meas: list[float] = []
    xs_true: list[float] = []
    us: list[float] = []
    ps: list[float] = []
    vs: list[float] = []
    flags: list[int] = []
    barrier_run = 0
    max_barrier_run = 0
    max_barrier_run_after_tu = 0
    fault_time = None
    trace_rows: list[tuple[float, ...]] = []
    for k in range(n_idle + n_arm + n_run):
        counts = rig.sensor_counts()
        x = off + gain * counts
        sensor_ok = raw_min <= counts <= raw_max
        if k < n_idle:  # IDLE: VENT
            p_cmd = 0.0
        elif k < n_idle + n_arm:  # ARMED: u = 0 -> p0
            if k == n_idle and not (xmin - xmarg <= x <= xmax + xmarg):
                faults.append(f"ARM refused: x = {x:.3f} cm")
            arm_x.append(rig.x_cm)
            p = min(max(p0, p_lo), p_hi)
            p_cmd = min(max(p, p_cmd - slew), p_cmd + slew) if slew > 0 else p
        else:  # RUNNING
            j = k - n_idle - n_arm
            t = j * period
            if not sensor_ok:
                faults.append(f"sensor fault at t = {t:.3f}")
            v = vel.step(x)
            xr, xr_dot = ref.eval(t)
            fl = 0
            if ppc is not None:  # the options choose the law's inputs, as firmware/app/controller.c
                o = ppc.step(t, vel.xh if fw["ppc.obs_pos"] else x,
                             v - xr_dot if fw["ppc.ref_vel"] else v, xr)
                u = o.u
                fl = o.flags
            elif mfac is not None:
                xr_next, _ = ref.eval(t + period)
                u = mfac.step(x, xr_next).u
            else:
                u = pid.step(xr, x).u
            barrier = bool(fl & (ref_mod.PPC_FLAG_BARRIER1 | ref_mod.PPC_FLAG_BARRIER2))
            barrier_run = barrier_run + 1 if barrier else 0
            max_barrier_run = max(max_barrier_run, barrier_run)
            if t >= t_u:
                max_barrier_run_after_tu = max(max_barrier_run_after_tu, barrier_run)
            if fault_time is None:
                if not (xmin - xmarg <= x <= xmax + xmarg):
                    fault_time = (t, "POSITION_LIMIT")
                elif barrier_ticks and barrier_run >= barrier_ticks:
                    fault_time = (t, "BARRIER")
            p = p0 + pol * kpu * u
            p = min(max(p, p_lo), p_hi)
            if slew > 0:
                p = min(max(p, p_cmd - slew), p_cmd + slew)
            p_cmd = p
            ts.append(t)
            es.append(x - xr)
            es_true.append(rig.x_cm - xr)
            xs_meas.append(x)
            us.append(u)
            ps.append(p)
            flags.append(fl)
            if cfg.trace:
                extra = (o.u_ff, o.u_law, o.lambda1_cm, o.lambda2_cm_s, v) if ppc is not None else (0, 0, 0, 0, v)
                trace_rows.append((t, x, xr, u, p) + extra)
        v_counts = c0 + cpk * p_cmd
        dac = cmin if not v_counts > cmin else (cmax if not v_counts < cmax else int(v_counts + 0.5))
        rig.apply_dac(dac)
        rig.step(period)
        if k >= n_idle + n_arm:
            xs_true.append(rig.x_cm)
            vs.append(rig.v_cm_s)

    if cfg.trace:
        with open(cfg.trace, "w") as f:
            f.write("t,x_meas,xr,u,p_cmd,u_ff,u_law,lambda1,lambda2,v_est,x_true,v_true\n")
            for row, xt, vt in zip(trace_rows, xs_true, vs):
                f.write(",".join(f"{c:.6g}" for c in row + (xt, vt)) + "\n")
    # ------------------------------------------------------------------------- metrics --
    res: dict[str, Any] = {"case": cfg.case, "label": cfg.label, "mode": mode}
    n = len(ts)
    windows = [w for w in CASES[cfg.case].windows if w[1] <= cfg.duration_s + 1e-9]
    if not windows:
        windows = [(min(t_u, cfg.duration_s / 2), cfg.duration_s)]
    rms = []
    for a, b in windows:
        sel = [es[i] for i in range(int(round(a / period)), min(n, int(round(b / period))))]
        rms.append(math.sqrt(sum(e * e for e in sel) / len(sel)) if sel else float("nan"))
    res["windows"] = windows
    res["rmste"] = rms
    rms_t = []
    for a, b in windows:
        sel = es_true[int(round(a / period)):min(n, int(round(b / period)))]
        rms_t.append(math.sqrt(sum(e * e for e in sel) / len(sel)) if sel else float("nan"))
    res["rmste_true"] = rms_t
    i_tu = min(n, int(round(t_u / period)))
    after = range(i_tu, n)
    res["max_abs_e_after_tu"] = max((abs(es[i]) for i in after), default=float("nan"))
    res["samples_outside_w1_after_tu"] = sum(1 for i in after if abs(es[i]) >= w1)
    last_out = max((i for i in range(n) if abs(es[i]) >= w1), default=-1)
    res["t_enter_band_s"] = (last_out + 1) * period if last_out + 1 < n else float("inf")
    first_in = next((i for i in range(n) if abs(es[i]) < w1), None)
    res["t_first_in_band_s"] = first_in * period if first_in is not None else float("inf")
    res["band_violations_true"] = sum(1 for xv in xs_true if not (xmin < xv < xmax))
    res["band_violations_meas"] = sum(1 for xv in xs_meas if not (xmin < xv < xmax))
    res["x_true_range"] = (min(xs_true), max(xs_true))
    res["arm_x_true_range"] = (min(arm_x), max(arm_x)) if arm_x else (float("nan"), float("nan"))
    if ppc is not None:
        b1 = [bool(f & ref_mod.PPC_FLAG_BARRIER1) for f in flags]
        b2 = [bool(f & ref_mod.PPC_FLAG_BARRIER2) for f in flags]
        res["breaches1_total"], res["breaches2_total"] = sum(b1), sum(b2)
        res["breaches_after_tu"] = sum(1 for i in after if b1[i] or b2[i])
        res["soft_steps_after_tu"] = sum(1 for i in after if flags[i] & (ref_mod.PPC_FLAG_SOFT1 | ref_mod.PPC_FLAG_SOFT2))
        res["sat_steps_after_tu"] = sum(1 for i in after if flags[i] & (ref_mod.PPC_FLAG_SAT_HIGH | ref_mod.PPC_FLAG_SAT_LOW))
        res["max_barrier_run"] = max_barrier_run
        res["max_barrier_run_after_tu"] = max_barrier_run_after_tu
    res["supervisor_fault"] = fault_time
    res["faults"] = faults[:5]
    res["start_refused"] = start_refused
    res["peak_abs_v_cm_s"] = max(abs(v) for v in vs)
    res["peak_abs_v_after_tu"] = max((abs(vs[i]) for i in after), default=float("nan"))
    res["peak_abs_u"] = max(abs(u) for u in us)
    dur_after = max((n - i_tu) * period, period)
    tvu = sum(abs(us[i] - us[i - 1]) for i in range(max(i_tu, 1), n))
    tvp = sum(abs(ps[i] - ps[i - 1]) for i in range(max(i_tu, 1), n))
    res["tv_u_per_s_after_tu"] = tvu / dur_after
    res["tv_p_kpa_per_s_after_tu"] = tvp / dur_after
    res["tv_p_need_kpa_per_s"] = static_u_need(rig, fw, kind, cfg.duration_s)
    # jitter: RMS of the pressure command minus its 50 ms centred moving average (after t_u)
    half = int(round(0.025 / period))
    csum = [0.0]
    for pv in ps:
        csum.append(csum[-1] + pv)
    jit = [ps[i] - (csum[i + half + 1] - csum[i - half]) / (2 * half + 1)
           for i in range(max(i_tu, half), n - half)]
    res["p_jitter_rms_kpa"] = math.sqrt(sum(j * j for j in jit) / len(jit)) if jit else float("nan")
    res["fw"] = {k: cfg.fw[k] for k in sorted(cfg.fw) if k.split(".")[0] in
                 ("ppc", "mfac", "pid", "vel", "act", "ctrl", "safety")}
    res["rig"] = cfg.rig
    res["dist_n"] = cfg.dist_n
    res["duration_s"] = cfg.duration_s
    return res


def format_result(r: dict[str, Any], verbose_params: bool = False) -> str:
    mode = {1: "PPC", 2: "MFAC", 3: "PID"}[r["mode"]]
    lines = [f"== case {r['case']} {mode} {r['label']}"]
    lines.append("  RMSTE " + "  ".join(f"{a:g}-{b:g}: {v:.4f}" for (a, b), v in zip(r["windows"], r["rmste"]))
                 + "  (measured x)")
    lines.append("  RMSTE " + "  ".join(f"{a:g}-{b:g}: {v:.4f}" for (a, b), v in zip(r["windows"], r["rmste_true"]))
                 + "  (true x)")
    s = (f"  max|e| after t_u {r['max_abs_e_after_tu']:.4f} cm, samples |e|>=w1 after t_u "
         f"{r['samples_outside_w1_after_tu']}, enters band for good at {r['t_enter_band_s']:.3f} s "
         f"(first {r['t_first_in_band_s']:.3f} s)")
    lines.append(s)
    lines.append(f"  band violations true/meas {r['band_violations_true']}/{r['band_violations_meas']}, "
                 f"x true in [{r['x_true_range'][0]:.3f}, {r['x_true_range'][1]:.3f}], "
                 f"ARMED x in [{r['arm_x_true_range'][0]:.3f}, {r['arm_x_true_range'][1]:.3f}]")
    if r["mode"] == 1:
        lines.append(f"  breaches after t_u {r['breaches_after_tu']} (total l1 {r['breaches1_total']}, "
                     f"l2 {r['breaches2_total']}), longest barrier run {r['max_barrier_run']} "
                     f"(after t_u {r['max_barrier_run_after_tu']}), soft steps {r['soft_steps_after_tu']}, "
                     f"saturated steps {r['sat_steps_after_tu']}")
    lines.append(f"  peak |v| {r['peak_abs_v_cm_s']:.3f} cm/s (after t_u {r['peak_abs_v_after_tu']:.3f}), "
                 f"peak |u| {r['peak_abs_u']:.1f}, TV(u)/s {r['tv_u_per_s_after_tu']:.1f} u/s, "
                 f"TV(p)/s {r['tv_p_kpa_per_s_after_tu']:.1f} kPa/s (reference needs "
                 f"{r['tv_p_need_kpa_per_s']:.1f} kPa/s), p jitter {r['p_jitter_rms_kpa']:.2f} kPa rms")
    if r["supervisor_fault"] or r["faults"] or r["start_refused"]:
        lines.append(f"  supervisor fault {r['supervisor_fault']}, faults {r['faults']}, "
                     f"START {r['start_refused'] or 'ok'}")
    if verbose_params:
        lines.append("  fw " + " ".join(f"{k}={v:g}" if isinstance(v, (int, float)) else f"{k}={v}"
                                        for k, v in r["fw"].items()))
        lines.append(f"  rig {r['rig']} disturbance {r['dist_n']} N")
    return "\n".join(lines)


def _run(cfg: RunConfig) -> dict[str, Any]:
    t0 = time.time()
    r = simulate(cfg)
    r["cpu_s"] = time.time() - t0
    return r


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--case", choices=sorted(CASES), default="1")
    ap.add_argument("--quick", action="store_true", help="short run (20 s, Case 3: 60 s)")
    ap.add_argument("--duration", type=float, default=None, help="run length after START [s]")
    ap.add_argument("--set", action="append", metavar="NAME=VALUE",
                    help="firmware parameter override (params.toml names), repeatable")
    ap.add_argument("--rig", action="append", metavar="PATH=VALUE",
                    help="RigParams override (e.g. load.incline_deg=0), repeatable")
    ap.add_argument("--dist", type=float, default=None, help="Case 3 disturbance force [N] (from t = 20 s)")
    ap.add_argument("--grid", action="append", metavar="NAME=V1,V2,...",
                    help="sweep a firmware (or rig:PATH) parameter; cartesian product, repeatable")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--arm-s", type=float, default=1.0, help="ARMED time before START [s]")
    ap.add_argument("--jobs", type=int, default=max(1, multiprocessing.cpu_count()))
    ap.add_argument("--json", type=Path, default=None, help="append results as JSON lines")
    ap.add_argument("--params", action="store_true", help="print the full parameter set")
    ap.add_argument("--trace", type=str, default="", help="write a per-tick CSV trace (single run only)")
    args = ap.parse_args(argv)

    duration = args.duration
    if duration is None and args.quick:
        duration = 60.0 if args.case == "3" else 20.0
    fw_over = parse_assignments(args.set)
    rig_over = parse_assignments(args.rig)
    grid: list[tuple[str, list[Any]]] = []
    for g in args.grid or []:
        k, vals = g.split("=", 1)
        grid.append((k.strip(), [parse_value(v) for v in vals.split(",")]))
    cfgs = []
    table = firmware_table()
    for combo in itertools.product(*[vals for _, vals in grid]) if grid else [()]:
        fo, ro = dict(fw_over), dict(rig_over)
        label = []
        for (k, _), v in zip(grid, combo):
            if k.startswith("rig:"):
                ro[k[4:]] = v
            else:
                fo[k] = v
            label.append(f"{k}={v}")
        check_firmware_values(fo, table)
        cfgs.append(build_config(args.case, fo, ro, duration, args.dist, args.seed, args.arm_s,
                                 " ".join(label)))
    if args.trace and len(cfgs) == 1:
        cfgs[0].trace = args.trace
    if len(cfgs) == 1:
        results = [_run(cfgs[0])]
    else:
        with multiprocessing.Pool(min(args.jobs, len(cfgs))) as pool:
            results = pool.map(_run, cfgs)
    for r in results:
        print(format_result(r, args.params), flush=True)
        if args.json:
            with open(args.json, "a") as f:
                f.write(json.dumps(r) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
