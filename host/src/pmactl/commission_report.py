# SPDX-License-Identifier: Apache-2.0
"""What `pmactl commission` prints and writes: the report (text and report.json), the derived
parameters in the `params dump` format (params.json, for `pmactl params load`), and figures
(static map with both branches, the step responses with their fits, the noise at rest)."""
from __future__ import annotations

import json
import math
from pathlib import Path
from typing import IO, TYPE_CHECKING, Any

import numpy as np

from . import paramfile
from .commission_rules import CHATTER_WARN_PER_NEED, GM_MIN, PM_MIN_DEG
from .protocol import Protocol

if TYPE_CHECKING:
    from .commission import Result


class ProgressBar:
    """One line on a terminal: the step and a bar."""

    def __init__(self, stream: IO[str], width: int = 30) -> None:
        self.stream = stream
        self.width = width

    def update(self, what: str, fraction: float) -> None:
        n = int(round(max(0.0, min(1.0, fraction)) * self.width))
        self.stream.write(f"\r[{'#' * n}{'.' * (self.width - n)}] {100 * fraction:3.0f}% {what:<16}")
        self.stream.flush()

    def close(self) -> None:
        self.stream.write("\n")
        self.stream.flush()


def text(r: Result) -> list[str]:
    d = r.derivation
    f = d.figures
    m = r.measured
    mg = d.margins
    lines = [
        f"commissioning done in {r.rig_time_s:.1f} s of rig time ({r.wall_s:.1f} s wall)",
        f"wiring: x moves {'with' if m.polarity_measured > 0 else 'against'} the pressure: "
        f"act.polarity {d.params['act.polarity']:+d}; noise at rest {1e4 * m.noise_cm:.1f} um (1 sigma)"
        + (f", the quantisation's: one count of {1e4 * m.resolution_cm:.1f} um over sqrt(12) (measured "
           f"{1e4 * m.noise_rest_cm:.1f} um)" if m.noise_rest_cm is not None and m.noise_rest_cm < m.noise_cm else ""),
        f"static map: stroke {f['stroke_min_cm']:.3f}..{f['stroke_max_cm']:.3f} cm over "
        f"{min(m.static_map.p_down_kpa):.0f}..{max(m.static_map.p_down_kpa):.0f} kPa; hysteresis "
        f"{f['hysteresis_kpa_at_p0']:.0f} kPa at the preset pressure",
        f"step responses (median of {len(m.steps)}): gain {f['gain_cm_per_u']:.5f} cm per input unit "
        f"({f['loop_gain_cm_per_u']:.5f} at the loop's crossover{_moving_gain(f)}), "
        f"lag {1000 * f['tau_s']:.1f} ms{_early_lag(f)}, dead time {1000 * f['theta_s']:.1f} ms",
        f"loop: SIMC PI Kc {f['kc_u_per_cm']:.1f} per cm, tau_I {1000 * f['tau_i_s']:.1f} ms "
        f"(tau_c {f['tau_c_s'] / f['theta_eff_s']:.2f} theta_eff); as a PID alone "
        f"phase margin {mg['phase_margin_deg']:.0f} deg, gain margin {mg['gain_margin']:.1f}, "
        f"delay margin {1000 * mg['delay_margin_s']:.0f} ms at {mg['crossover_rad_s']:.1f} rad/s",
        f"loop as built, with the velocity observer at {d.params['vel.fc_hz']:g} Hz{_lpf(d.params)}: phase margin "
        f"{f['with_observer_phase_margin_deg']:.0f} deg, gain margin {f['with_observer_gain_margin']:.1f}, "
        f"delay margin {1000 * f['with_observer_delay_margin_s']:.0f} ms (the rule keeps "
        f"{PM_MIN_DEG:g} deg and {GM_MIN:g})",
        f"the sensor's noise through the law moves the input {f['noise_input_rate_u_per_s']:.1f} units/s "
        f"(mean |du/dt|), the reference needs {f['need_input_rate_u_per_s']:.1f}"
        + _noise_bound(f),
        f"MFAC: lambda {d.params['mfac.lambda']:g}, integral loop gain {f['mfac_k_loop_per_s']:.2f} 1/s at phi = g; "
        f"phase margin {f['mfac_phase_margin_deg']:.0f} deg, gain margin {f['mfac_gain_margin']:.1f}, "
        f"delay margin {1000 * f['mfac_delay_margin_s']:.0f} ms",
        f"hysteresis: {f['hysteresis_kpa_over_ref']:.0f} kPa over the reference's range; the reference "
        f"feedforward's term +-{d.params['ppc.ref_ff_hyst']:g} input units across a play of "
        f"{d.params['ppc.ref_ff_hyst_cm']:g} cm, adapted on the node at {d.params['ppc.ref_ff_hyst_gain_per_s']:g} "
        f"1/s within 0..{d.params['ppc.ref_ff_hyst_max']:g}; MFAC's reset threshold {d.params['mfac.eps']:g}",
        f"start: the armed muscle rests at {f['x_armed_cm']:.3f} cm (the rising branch at act.p0_kpa "
        f"{d.params['act.p0_kpa']:g} kPa); the start held at {f['p_start_kpa']:.0f} kPa ("
        + ("the rising branch: further along it" if f["start_on_rising_branch"] else "the middle of the branches")
        + f"): ppc.ff_init {d.params['ppc.ff_init']:g}",
        "derived parameters:",
    ]
    for name, value in d.params.items():
        lines.append(f"  {name} = {value}")
    lines += [f"promise: {p}" for p in d.promises]
    lines += [f"warning: {w}" for w in d.warnings]
    if r.applied:
        lines.append("applied to the node's RAM" + (" and saved" if r.saved else " (pmactl params save keeps them)"))
    else:
        lines.append("nothing changed on the node (--apply sets them)")
    return lines


def _early_lag(f: dict[str, float]) -> str:
    """Where the steps' early parts set the lag (a slow tail stretched the fits'), the fits' median."""
    if f["tau_s"] >= f["tau_fit_s"]:
        return ""
    return f" (the early parts' lag; the fits, stretched by a slow tail, say {1000 * f['tau_fit_s']:.1f} ms)"


def _moving_gain(f: dict[str, float]) -> str:
    """Where the loop's gain is the moving steps' over GM_MIN (the steps into the dead band pulled
    the median of all below it), says so."""
    if not f.get("loop_gain_on_moving_steps"):
        return ""
    return (f": the moving steps' {f['loop_gain_moving_cm_per_u']:.5f} over the gain margin {GM_MIN:g}, "
            f"above the median of all {f['loop_gain_median_cm_per_u']:.5f}, which the steps into the dead band "
            "pulled down")


def _lpf(params: dict[str, Any]) -> str:
    """The command's low-pass in the loop as built, where commissioning set one."""
    fu = float(params.get("ppc.u_lpf_hz", 0.0))
    return f" and the command's low-pass at {fu:g} Hz" if fu > 0 else ""


def _noise_bound(f: dict[str, float]) -> str:
    """What the sensor's noise does to the input against the need, and the bound the user set
    (figures' noise_limit; 0: none)."""
    noise, need, limit = f["noise_input_rate_u_per_s"], f["need_input_rate_u_per_s"], f["noise_limit"]
    if need <= 0:
        return " (a set-point task: nothing to weigh it against)"
    unfiltered = f.get("noise_input_rate_unfiltered_u_per_s", noise)
    lpf = f"; {unfiltered / need:.2f}x without the command's low-pass" if unfiltered > noise else ""
    if limit > 0:
        held = "within" if noise <= limit * need else "above even at the slowest observer the margins allow:"
        return f" ({noise / need:.2f}x{lpf}; --noise-limit {limit:g}: {held} it)"
    loud = " (expect the valve to chatter: see the warning)" if noise > CHATTER_WARN_PER_NEED * need else ""
    return f" ({noise / need:.2f}x{lpf}; no --noise-limit){loud}"


# the files write() puts into its directory (the figure only where matplotlib is installed)
FILES = ("report.json", "params.json", "commissioning.png")


def write(r: Result, out: Path, proto: Protocol, node: int) -> list[Path]:
    out.mkdir(parents=True, exist_ok=True)
    written = []
    rep = out / FILES[0]
    rep.write_text(json.dumps(_jsonable(r.report()), indent=2) + "\n")
    written.append(rep)
    values = {proto.param(name).id: value for name, value in r.derivation.params.items()}
    par = out / FILES[1]
    par.write_text(paramfile.dumps(proto, values, node))
    written.append(par)
    written += figures(r, out)
    return written


def figures(r: Result, out: Path) -> list[Path]:
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        return []
    m = r.measured
    fig, ax = plt.subplots(1, 3, figsize=(15, 4.2))
    sm = m.static_map
    ax[0].plot(sm.p_up_kpa, sm.x_up_cm, "o-", label="pressure rising")
    ax[0].plot(sm.p_down_kpa, sm.x_down_cm, "s-", label="pressure falling")
    ax[0].axvline(float(r.derivation.params["act.p0_kpa"]), color="gray", ls="--", label="preset p0")
    ax[0].set_xlabel("pressure [kPa]")
    ax[0].set_ylabel("x [cm]")
    ax[0].set_title("static map (both branches)")
    ax[0].legend(fontsize=8)
    for label, rec in sorted(r.recordings.items()):
        if not label.startswith("step"):
            continue
        t = np.asarray(rec.t_s)
        x = np.asarray(rec.x_cm)
        # each step's recording: from its first sample, relative to where it started
        ax[1].plot(t - t[0], x - x[0], lw=0.8, label=label)
    ax[1].set_xlabel("time after the step [s]")
    ax[1].set_ylabel("x - x(step) [cm]")
    ax[1].set_title("step responses (+-5 % of the pressure range)")
    ax[1].legend(fontsize=7, ncol=2)
    rest = r.recordings.get("rest")
    if rest is not None and rest.x_cm:
        x = 1e4 * (np.asarray(rest.x_cm) - float(np.mean(rest.x_cm)))
        ax[2].hist(x, bins=30)
        ax[2].set_xlabel("x - mean [um]")
        ax[2].set_title(f"noise at rest: {1e4 * m.noise_cm:.1f} um (1 sigma)")
    fig.tight_layout()
    path = out / FILES[2]
    fig.savefig(path, dpi=90)
    plt.close(fig)
    return [path]


def _jsonable(v: object) -> object:
    if isinstance(v, dict):
        return {str(k): _jsonable(x) for k, x in v.items()}
    if isinstance(v, (list, tuple)):
        return [_jsonable(x) for x in v]
    if isinstance(v, (np.floating, float)):
        f = float(v)
        return f if math.isfinite(f) else None
    if isinstance(v, np.integer):
        return int(v)
    return v
