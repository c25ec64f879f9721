# SPDX-License-Identifier: Apache-2.0
"""Figures and the table of docs/rig.md, "Against a real muscle".

    .venv/bin/python hil/plot_rig_real.py [--out docs/img] [--no-plots]

Prints the measured muscle's table (the DMSP-10-250's figures) for the three rig profiles (nominal, dmsp10, mas10-itv2050)
and writes docs/img/rig_real_steps.png (pressure steps, in % of the step),
rig_real_creep.png (s after a pressure step, in % of its change) and
rig_real_loop.png (the 400 ms staircase loops, in % of the stroke). Only the rig
model runs here; the measured record's comparison is tools/fit_rig_dmsp10.py's
figure (docs/img/rig_dmsp10_holds.png). Takes a few minutes.
"""

from __future__ import annotations

import argparse
import os
from typing import Any

import numpy as np

from hil.rig_figures import (
    DMSP10_POINTS,
    MAS10_POINTS,
    TablePoints,
    loop_width_pct,
    quiet,
    run_commands,
    staircase_loop,
    table,
)
from hil.rig_params import RigParams

PROFILES: list[tuple[str, TablePoints]] = [("nominal", MAS10_POINTS), ("dmsp10", DMSP10_POINTS),
                                           ("mas10-itv2050", MAS10_POINTS)]
MEASURED = {  # the measured DMSP-10-250's table (hil/tests/test_rig_profiles.py has the source)
    "dead_time_rise_ms": "30-40", "dead_time_fall_ms": "50-80", "rise_small_ms": "70", "rise_large_ms": "330",
    "fall_small_ms": "1,100", "fall_large_ms": "1,270", "creep_rise_pct": "13-24", "creep_fall_pct": "24-44",
    "loop_400ms_mid_pct": "19", "loop_400ms_max_pct": "21", "loop_4s_mid_pct": "about 10", "reversal_pct": "about 68",
}
LABELS = {
    "dead_time_rise_ms": "pressure dead time, rising [ms]", "dead_time_fall_ms": "pressure dead time, falling [ms]",
    "rise_small_ms": "pressure rise 10-90 %, small step [ms]", "rise_large_ms": "pressure rise 10-90 %, large step [ms]",
    "fall_small_ms": "pressure fall 10-90 %, 0.5 bar [ms]", "fall_large_ms": "pressure fall 10-90 %, 1.2 bar [ms]",
    "creep_rise_pct": "creep 0.5-4 s, rising [% of step]", "creep_fall_pct": "creep 0.5-4 s, falling [% of step]",
    "loop_400ms_mid_pct": "loop 400 ms, mid [% of stroke]", "loop_400ms_max_pct": "loop 400 ms, max [% of stroke]",
    "loop_4s_mid_pct": "loop at 4 s holds, mid [% of stroke]", "reversal_pct": "0.45 bar reversal [% of large-step slope]",
}


def print_table(tables: dict[str, dict[str, Any]]) -> None:
    names = [n for n, _ in PROFILES]
    print("| quantity | DMSP-10 measured | " + " | ".join(names) + " |")
    print("|---|---|" + "---|" * len(names))
    for key, label in LABELS.items():
        cells = [f"{tables[n][key]:.0f}" for n in names]
        print(f"| {label} | {MEASURED[key]} | " + " | ".join(cells) + " |")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", default="docs/img")
    ap.add_argument("--no-plots", action="store_true")
    args = ap.parse_args(argv)
    params = {n: quiet(RigParams.from_dict({"profile": n})) for n, _ in PROFILES}
    tables = {n: table(params[n], pts) for n, pts in PROFILES}
    print_table(tables)
    if args.no_plots:
        return 0
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    os.makedirs(args.out, exist_ok=True)
    # pressure steps in % of the step
    fig, axes = plt.subplots(1, 2, figsize=(11, 4))
    for ax, which, title in ((axes[0], "rise_large", "rise (large step)"), (axes[1], "fall_large", "fall (large step)")):
        for n, pts in PROFILES:
            a, b = getattr(pts, which)
            r = run_commands(params[n], [(b, 4.0)], a)
            ax.plot(r.t_s, 100 * (r.p_kpa - r.p_kpa[0]) / (r.p_kpa[-1] - r.p_kpa[0]), label=f"{n} ({a:.0f}->{b:.0f} kPa)")
        ax.set_xlabel("time after the command step [s]")
        ax.set_ylabel("pressure [% of its change over 4 s]")
        ax.set_title(f"Pressure {title}")
        ax.grid(True, alpha=0.3)
        ax.set_xlim(0, 4)
        ax.legend(fontsize=8)
    axes[0].set_xlim(0, 1.0)
    fig.tight_layout()
    fig.savefig(os.path.join(args.out, "rig_real_steps.png"), dpi=110)
    plt.close(fig)
    # creep: s after the large steps
    fig, axes = plt.subplots(1, 2, figsize=(11, 4))
    for ax, which, title in ((axes[0], "rise_large", "contraction after a rise"), (axes[1], "fall_large", "relaxation after a fall")):
        for n, pts in PROFILES:
            a, b = getattr(pts, which)
            r = run_commands(params[n], [(b, 4.0)], a)
            ax.plot(r.t_s, 100 * (r.s_mm - r.s_mm[0]) / (r.s_mm[-1] - r.s_mm[0]), label=n)
        ax.axvline(0.5, color="k", lw=0.6, ls=":")
        ax.set_xlabel("time after the command step [s]")
        ax.set_ylabel("s [% of its change over 4 s]")
        ax.set_title(f"Creep: {title}")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(os.path.join(args.out, "rig_real_creep.png"), dpi=110)
    plt.close(fig)
    # staircase loops in % of stroke
    fig, ax = plt.subplots(figsize=(6.5, 5))
    for n, pts in PROFILES:
        lp = staircase_loop(params[n], pts.loop_max_kpa, pts.loop_step_400ms_kpa, 0.4)
        w = loop_width_pct(lp)
        s_min = min(lp["s_up"].min(), lp["s_down"].min())
        ax.plot(100 * np.concatenate([lp["p_up"], lp["p_down"]]) / pts.loop_max_kpa,
                100 * (np.concatenate([lp["s_up"], lp["s_down"]]) - s_min) / w["stroke_mm"],
                label=f"{n}: width {w['mid_pct']:.0f} % mid, {w['max_pct']:.0f} % max")
    ax.set_xlabel("pressure [% of the staircase's top]")
    ax.set_ylabel("contraction [% of stroke]")
    ax.set_title("400 ms staircase (measured DMSP-10: 19 % mid, 21 % max)")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(os.path.join(args.out, "rig_real_loop.png"), dpi=110)
    plt.close(fig)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
