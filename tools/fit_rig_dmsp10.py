# SPDX-License-Identifier: Apache-2.0
"""Fit the rig's "dmsp10" profile to the public measurements of a Festo DMSP-10-250.

    .venv/bin/python tools/fit_rig_dmsp10.py [--cache DIR] [--offline] [--write] [--quick]

The measurements are T. Bazina's (GitHub tbazina/pam_lqi_pid: a DMSP-10-250 with a
proportional pressure valve, laser displacement and pressure sensor at 100 Hz). That
repository states no licence: this project uses its figures and ships none of its
files. The script reads them from a cache outside the repository (default
~/.cache/pma-rig-data/tbazina-pam_lqi_pid/, or --cache), downloading what is missing
from raw.githubusercontent.com unless --offline. It reads columns by name, so a
cache may hold the public files or only the columns used here:

    analysis_outputs/local_static_map_repeatability_hold_points.csv
        hold_id, branch, u_previous_v, u_cmd_v, s_start_mm, s_terminal_mm, p_start_bar, p_terminal_bar
        (the 4 s holds of experiment/excitation_experiment_100hz_15min_4s_hold.csv)
    analysis_outputs/open_loop_dynamic_pressure_reference_summary.csv
        branch, theta_s, tau_fast_s, tau_slow_s, weight_fast (the pressure's FOPDT fit)
    analysis_outputs/open_loop_creep_summary.csv
        branch, a, tau_s (the displacement's creep after the pressure plateau)

The fit/validation split: holds 2-60 (the first 4 minutes of the record) are the fit
set; holds 61-112 are never used by the fit and validate it. Stages:

1. static (least squares on the fit holds' terminal values): the valve's map
   u [V] -> p [kPa], the spring K(P) = K0 - K1 P, the load W and the hysteresis
   amplitude, with F(P) fixed to Martens & Boblan's force map of the same muscle;
2. the valve (coordinate search): dead times, filling and exhaust rates, the slow
   pilot, against the measured step figures of the DMSP-10-250's table (rise and fall
   times, dead times), starting from the FOPDT summary;
3. creep: its fractions and time constants against the table's creep figures,
   starting from the creep summary;
4. hysteresis shape: the Maxwell-slip element widths against the table's loop
   widths and the small-reversal slope;
5. validation: the whole hold sequence 2-112 driven through the fitted rig with the
   recorded commands; RMS errors of the terminal s and p for the fit and the
   validation holds.

--write stores the result in hil/profiles/dmsp10.json (the shipped parameters).
The record's pressure reads -0.30 bar vented (the first samples, u = 0): the fit
takes the gauge pressure as the recorded p + 30 kPa.
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import time
import urllib.request
from pathlib import Path
from typing import Any, Callable

import numpy as np

from hil.rig import Rig
from hil.rig_figures import DMSP10_POINTS, quiet, table
from hil.rig_params import RigParams

ROOT = Path(__file__).resolve().parents[1]

REPO = "tbazina/pam_lqi_pid"
COMMIT = "6f0ae4db9ec1b855a89ea0b54be39bdf6c1d044d"
FILES = (
    "analysis_outputs/local_static_map_repeatability_hold_points.csv",
    "analysis_outputs/open_loop_dynamic_pressure_reference_summary.csv",
    "analysis_outputs/open_loop_creep_summary.csv",
)
P_OFFSET_KPA = 30.0  # the record's p reads -0.30 bar at atmospheric pressure
FIT_LAST_HOLD = 60
OUT = ROOT / "hil" / "profiles" / "dmsp10.json"

# The table measured on the DMSP-10-250 (the same figures live in
# hil/tests/test_rig_profiles.py): the fit's targets are the ranges' middles.
TARGETS = {
    "dead_time_rise_ms": 35.0, "dead_time_fall_ms": 65.0,
    "rise_small_ms": 70.0, "rise_large_ms": 330.0,
    "fall_small_ms": 1100.0, "fall_large_ms": 1270.0,
    "creep_rise_pct": 18.5, "creep_fall_pct": 34.0,
    "loop_400ms_mid_pct": 19.0, "loop_400ms_max_pct": 21.0,
    "loop_4s_mid_pct": 10.0, "reversal_pct": 68.0,
}


def cache_dir(arg: str | None) -> Path:
    base = Path(arg) if arg else Path(os.path.expanduser("~/.cache/pma-rig-data"))
    return base / REPO.replace("/", "-")


def fetch(cache: Path, rel: str, offline: bool) -> Path:
    path = cache / rel
    if path.exists():
        return path
    if offline:
        raise SystemExit(f"{path} is missing (run without --offline to download it)")
    url = f"https://raw.githubusercontent.com/{REPO}/{COMMIT}/{rel}"
    path.parent.mkdir(parents=True, exist_ok=True)
    print(f"downloading {url}")
    with urllib.request.urlopen(url, timeout=60) as r:  # noqa: S310 (a fixed https URL)
        path.write_bytes(r.read())
    return path


def read_csv(path: Path) -> list[dict[str, str]]:
    with path.open(newline="") as f:
        return list(csv.DictReader(f))


# ------------------------------------------------------------------- the profile
def base_profile() -> dict[str, Any]:
    """What the fit starts from: the DMSP-10-250's geometry and the parts the data
    do not determine (every value documented in docs/rig.md)."""
    return {
        "muscle": {
            "length_mm": 250.0,
            # F(P): Martens & Boblan's map is of this very muscle (the nominal defaults).
            "hyst_ramp_n": 100.0,
            "hyst_delta_mm": [0.5, 1.5, 4.0, 10.0],
            "hyst_weights": [0.25, 0.25, 0.25, 0.25],
        },
        # the load: a constant pull W (fitted) on an assumed 2 kg of moving parts (carriage, sensor target)
        "load": {"incline_deg": 0.0, "mass_kg": 2.0},
        "regulator": {"fs_kpa": 600.0, "p_max_kpa": 600.0, "linearity_frac_fs": 0.0, "hysteresis_frac_fs": 0.0},
        "valve": {
            "model": "flow", "supply_kpa": 700.0, "b_critical": 0.3, "p_band_kpa": 15.0,
            "volume_gain_per_mm": 0.012, "polytropic_n": 1.0,
        },
        "creep": {},
    }


def with_static(prof: dict[str, Any], k0: float, k1: float, w_n: float, a_n: float) -> dict[str, Any]:
    p = json.loads(json.dumps(prof))
    m = p["muscle"]
    m.update({"k0_low_n_per_mm": k0, "k1_low_n_per_mm_kpa": k1, "k0_high_n_per_mm": k0, "k1_high_n_per_mm_kpa": k1,
              "hyst_force_n": a_n})
    # the damper: the MAS-10's viscoelastic time constants B/K (Serres's ratio) at 300 kPa
    nominal = Rig(RigParams())
    k300 = k0 - k1 * 300.0
    m["b_contract_ns_per_mm"] = RigParams().muscle.b_contract_ns_per_mm * k300 / nominal._k_of_p(300.0)
    m["b_relax_ns_per_mm"] = RigParams().muscle.b_relax_ns_per_mm * k300 / nominal._k_of_p(300.0)
    p["load"]["bias_force_n"] = w_n
    return p


def params_of(prof: dict[str, Any]) -> RigParams:
    return RigParams.from_dict(prof)


# ------------------------------------------------------------------- stage 1
def fit_static(holds: list[dict[str, Any]], prof: dict[str, Any]) -> tuple[dict[str, Any], dict[str, float]]:
    """Valve map and K0, K1, W, A by least squares on the fit holds' terminal values."""
    u = np.array([h["u_cmd_v"] for h in holds])
    pg = np.array([h["p_terminal_bar"] for h in holds]) * 100.0 + P_OFFSET_KPA
    s = np.array([h["s_terminal_mm"] for h in holds])
    br = np.array([1.0 if h["branch"] == "up" else -1.0 for h in holds])
    slope, offset = np.polyfit(u, pg, 1)

    def resid(x: np.ndarray) -> np.ndarray:
        rig = Rig(params_of(with_static(prof, *x)))
        s0 = rig.static_xs_mm(0.0)
        return np.array([rig.static_xs_mm(p, friction=b) - s0 for p, b in zip(pg, br)]) - s

    x = np.array([12.0, 0.0, 30.0, 20.0])
    for _ in range(30):
        r = resid(x)
        jac = np.empty((len(r), len(x)))
        for j in range(len(x)):
            dx = np.zeros_like(x)
            dx[j] = 1e-4 * max(abs(x[j]), 1e-2)
            jac[:, j] = (resid(x + dx) - r) / dx[j]
        step, *_ = np.linalg.lstsq(jac, -r, rcond=None)
        x = x + step
        if np.max(np.abs(step)) < 1e-7:
            break
    rms = float(np.sqrt(np.mean(resid(x) ** 2)))
    k0, k1, w_n, a_n = (float(v) for v in x)
    out = with_static(prof, k0, k1, w_n, a_n)
    info = {"valve_kpa_per_v": float(slope), "valve_offset_kpa": float(offset), "k0_n_per_mm": k0,
            "k1_n_per_mm_kpa": k1, "load_n": w_n, "hyst_force_n": a_n, "static_rms_s_mm": rms}
    return out, info


# ------------------------------------------------------------------ stages 2-4
def cost(figs: dict[str, float], keys: tuple[str, ...]) -> float:
    return float(sum(((figs[k] - TARGETS[k]) / TARGETS[k]) ** 2 for k in keys))


def coordinate_search(prof: dict[str, Any], names: list[tuple[str, str, float, float]],
                      figures: Callable[[Any], dict[str, float]], keys: tuple[str, ...],
                      rounds: int, raw: bool = False) -> dict[str, Any]:
    """Multiplicative coordinate search: each (group, name, lo, hi) scaled by 1/f, f
    while the cost falls; f shrinks each round. figures takes RigParams (or, raw,
    the profile's dict)."""
    def evaluate(pr: dict[str, Any]) -> float:
        return cost(figures(pr if raw else params_of(pr)), keys)

    best = json.loads(json.dumps(prof))
    best_cost = evaluate(best)
    factor = 1.5
    for rnd in range(rounds):
        for group, name, lo, hi in names:
            for f in (factor, 1.0 / factor):
                trial = json.loads(json.dumps(best))
                v = min(max(trial[group][name] * f, lo), hi)
                if v == trial[group][name]:
                    continue
                trial[group][name] = v
                c = evaluate(trial)
                if c < best_cost:
                    best, best_cost = trial, c
                    break
        print(f"  round {rnd + 1}: cost {best_cost:.4f}", flush=True)
        factor = 1.0 + 0.5 * (factor - 1.0)
    return best


def step_table(params: RigParams) -> dict[str, float]:
    return table(params, DMSP10_POINTS, loops=False)


def full_table(params: RigParams) -> dict[str, float]:
    return table(params, DMSP10_POINTS, loops=True)


# ------------------------------------------------------------------- stage 5
def simulate_holds(params: RigParams, holds: list[dict[str, Any]], info: dict[str, float]) -> dict[str, np.ndarray]:
    """The recorded command sequence (4 s holds from vented) through the rig;
    terminal s (from the vented length) and p (as the record reads it) per hold."""
    q = quiet(params)
    q.initial_p_kpa = 0.0
    rig = Rig(q, seed=0)
    s0 = rig.contraction_mm
    s_end, p_end = [], []
    for h in holds:
        cmd = max(0.0, info["valve_kpa_per_v"] * h["u_cmd_v"] + info["valve_offset_kpa"])
        c = rig.kpa_to_dac(cmd)
        for _ in range(400):
            rig.apply_dac(c)
            rig.step(0.01)
        s_end.append(rig.contraction_mm - s0)
        p_end.append((rig.p_kpa - P_OFFSET_KPA) / 100.0)
    return {"s_mm": np.array(s_end), "p_bar": np.array(p_end)}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--cache", help="cache directory (default ~/.cache/pma-rig-data)")
    ap.add_argument("--offline", action="store_true", help="never download")
    ap.add_argument("--write", action="store_true", help=f"write {OUT.relative_to(ROOT)}")
    ap.add_argument("--quick", action="store_true", help="fewer search rounds")
    args = ap.parse_args(argv)
    t0 = time.time()
    cache = cache_dir(args.cache)
    paths = {rel: fetch(cache, rel, args.offline) for rel in FILES}
    holds_all: list[dict[str, Any]] = [{k: (v if k == "branch" else float(v)) for k, v in row.items()
                  if k in ("hold_id", "branch", "u_cmd_v", "s_terminal_mm", "p_terminal_bar")}
                 for row in read_csv(paths[FILES[0]]) if row["branch"] in ("up", "down")]
    holds_all.sort(key=lambda h: h["hold_id"])
    fit = [h for h in holds_all if h["hold_id"] <= FIT_LAST_HOLD]
    val = [h for h in holds_all if h["hold_id"] > FIT_LAST_HOLD]
    fopdt = {r["branch"]: r for r in read_csv(paths[FILES[1]])}
    creep = {r["branch"]: r for r in read_csv(paths[FILES[2]])}
    print(f"{len(fit)} fit holds, {len(val)} validation holds")

    prof, info = fit_static(fit, base_profile())
    print("static:", json.dumps({k: round(v, 4) for k, v in info.items()}))

    # valve: start from the FOPDT summary (its dead time theta includes the first
    # curvature; the slow share 1 - weight_fast, tau_slow)
    v = prof["valve"]
    v.update({
        "dead_time_rise_s": 0.8 * float(fopdt["up"]["theta_s"]),
        "dead_time_fall_s": 0.7 * float(fopdt["down"]["theta_s"]),
        "slow_weight_rise": 1.0 - float(fopdt["up"]["weight_fast"]),
        "slow_weight_fall": 1.0 - float(fopdt["down"]["weight_fast"]),
        "slow_tau_rise_s": float(fopdt["up"]["tau_slow_s"]),
        "slow_tau_fall_s": float(fopdt["down"]["tau_slow_s"]),
        # the record's slopes: about 7 bar/s filling, 4 bar/s exhausting (hold 2, 3)
        "fill_rate_kpa_s": 900.0, "exhaust_rate_kpa_s": 700.0,
    })
    c = prof["creep"]
    # creep: the summary's exponential (a, tau) describes 0-4 s after the pressure's
    # plateau; the 400 ms loop (half of it rate-dependent) needs a longer memory, so the
    # search starts from 1.5 a and 3 tau
    c.update({"frac_contract": min(0.9, 1.5 * float(creep["up"]["a"])),
              "frac_relax": min(0.9, 3.0 * float(creep["down"]["a"])),
              "tau_contract_s": 3.0 * float(creep["up"]["tau_s"]), "tau_relax_s": 3.0 * float(creep["down"]["tau_s"])})
    rounds = 2 if args.quick else 3
    print("valve (the pressure's figures):")
    prof = coordinate_search(prof, [
        ("valve", "dead_time_rise_s", 0.0, 0.2), ("valve", "dead_time_fall_s", 0.0, 0.2),
        ("valve", "fill_rate_kpa_s", 100.0, 1e5), ("valve", "exhaust_rate_kpa_s", 100.0, 1e5),
        ("valve", "p_band_kpa", 2.0, 100.0),
        ("valve", "slow_weight_fall", 0.0, 0.9), ("valve", "slow_tau_fall_s", 0.05, 5.0),
    ], step_table, ("dead_time_rise_ms", "dead_time_fall_ms", "rise_small_ms", "rise_large_ms",
                    "fall_small_ms", "fall_large_ms"), rounds)
    print("creep and hysteresis (the displacement's figures):")
    prof["muscle"]["hyst_delta_scale"] = 1.0  # searched, then folded into hyst_delta_mm

    def with_scale(pr: dict[str, Any]) -> dict[str, Any]:
        q = json.loads(json.dumps(pr))
        sc = q["muscle"].pop("hyst_delta_scale")
        q["muscle"]["hyst_delta_mm"] = [d * sc for d in q["muscle"]["hyst_delta_mm"]]
        return q

    def scaled_table(pr: dict[str, Any]) -> dict[str, float]:
        return full_table(params_of(with_scale(pr)))

    prof = coordinate_search(prof, [
        ("creep", "frac_contract", 0.0, 0.9), ("creep", "frac_relax", 0.0, 0.9),
        ("creep", "tau_contract_s", 0.05, 20.0), ("creep", "tau_relax_s", 0.05, 20.0),
        ("muscle", "hyst_force_n", 0.0, 200.0), ("muscle", "hyst_delta_scale", 0.05, 20.0),
    ], scaled_table, ("creep_rise_pct", "creep_fall_pct", "loop_400ms_mid_pct", "loop_400ms_max_pct",
                      "loop_4s_mid_pct", "reversal_pct"), rounds, raw=True)
    prof = with_scale(prof)
    print("profile:", json.dumps(prof, sort_keys=True))
    params = params_of(prof)
    figs = full_table(params)

    sim_fit = simulate_holds(params, holds_all, info)
    ids = np.array([h["hold_id"] for h in holds_all])
    s_meas = np.array([h["s_terminal_mm"] for h in holds_all])
    p_meas = np.array([h["p_terminal_bar"] for h in holds_all])
    rms: dict[str, float] = {}
    for name, mask in (("fit", ids <= FIT_LAST_HOLD), ("validation", ids > FIT_LAST_HOLD)):
        rms[f"{name}_rms_s_mm"] = float(np.sqrt(np.mean((sim_fit["s_mm"][mask] - s_meas[mask]) ** 2)))
        rms[f"{name}_rms_p_bar"] = float(np.sqrt(np.mean((sim_fit["p_bar"][mask] - p_meas[mask]) ** 2)))
        rms[f"{name}_holds"] = int(mask.sum())
    stroke = float(s_meas.max() - s_meas.min())
    rms["stroke_mm"] = stroke
    print("figures:", json.dumps({k: round(val, 1) for k, val in figs.items()}))
    print("targets:", json.dumps(TARGETS))
    print("hold RMS:", json.dumps({k: round(val, 4) for k, val in rms.items()}))
    print(f"done in {time.time() - t0:.0f} s")
    if args.write:
        OUT.parent.mkdir(parents=True, exist_ok=True)
        doc = {
            "_comment": "Written by tools/fit_rig_dmsp10.py from the public DMSP-10-250 measurements in "
                        f"github.com/{REPO} (commit {COMMIT[:10]}); docs/rig.md, 'Against a real muscle'.",
            "rig": prof,
            "fit": {"static": info, "figures": figs, "targets": TARGETS, "holds": rms,
                    "fit_holds": f"2-{FIT_LAST_HOLD}", "validation_holds": f"{FIT_LAST_HOLD + 1}-{int(ids.max())}"},
        }
        OUT.write_text(json.dumps(doc, indent=1, sort_keys=True) + "\n")
        print(f"wrote {OUT.relative_to(ROOT)}")
        plot_holds(ids, s_meas, p_meas, sim_fit, rms)
    return 0


def plot_holds(ids: np.ndarray, s_meas: np.ndarray, p_meas: np.ndarray, sim: dict[str, np.ndarray],
               rms: dict[str, float]) -> None:
    """docs/img/rig_dmsp10_holds.png: the terminal s and p of every 4 s hold, measured and
    simulated, the fit and validation holds marked (figures only, no data shipped)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(2, 1, figsize=(10, 6), sharex=True)
    for ax, meas, model, unit, key in ((axes[0], s_meas, sim["s_mm"], "s [mm]", "s_mm"),
                                       (axes[1], p_meas, sim["p_bar"], "p [bar, as recorded]", "p_bar")):
        ax.plot(ids, meas, "o", ms=3, label="measured (4 s hold, terminal)")
        ax.plot(ids, model, "x", ms=4, label="dmsp10 profile")
        ax.axvspan(ids.min() - 0.5, FIT_LAST_HOLD + 0.5, color="0.9", zorder=0)
        ax.set_ylabel(unit)
        ax.grid(True, alpha=0.3)
        ax.set_title(f"{unit}: RMS error fit {rms['fit_rms_' + key]:.3g}, "
                     f"validation {rms['validation_rms_' + key]:.3g}",
                     fontsize=9)
    axes[0].legend(fontsize=8)
    axes[1].set_xlabel(f"hold (shaded: fit holds 2-{FIT_LAST_HOLD}; the rest: validation)")
    fig.tight_layout()
    out = ROOT / "docs" / "img" / "rig_dmsp10_holds.png"
    fig.savefig(out, dpi=110)
    plt.close(fig)
    print(f"wrote {out.relative_to(ROOT)}")


if __name__ == "__main__":
    raise SystemExit(main())
