# SPDX-License-Identifier: Apache-2.0
"""Figures of a recording, in the style of the paper's (Li and Gao, Figs. 4-8): one panel
per quantity over time, lettered (a) position and reference, (b) error with the
assigned accuracy +-w1, (c) velocity, (d) input u, (e) pressure command. Rendered with
matplotlib's Agg backend (no display needed): one figure with every panel, and one
PNG per panel.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from pmactl.recording import Recording

if TYPE_CHECKING:
    from matplotlib.axes import Axes


@dataclass(frozen=True)
class PlotOptions:
    w1_cm: float | None = None               # accuracy band on the error panel
    band_cm: tuple[float, float] | None = None   # constraints k_low, k_high on the position panel
    t_u_s: float | None = None               # tuning time: a dotted vertical line
    title: str | None = None
    dpi: int = 150
    panels: bool = True                      # also one PNG per panel


PANELS = (
    ("a", "position", "Position (cm)"),
    ("b", "error", "Error (cm)"),
    ("c", "velocity", "Velocity (cm/s)"),
    ("d", "input", "Input u ({unit})"),
    ("e", "pressure", "Pressure (kPa)"),
)


def _draw(a: "Axes", key: str, rec: Recording, opt: PlotOptions) -> None:
    t = rec["t"]
    if key == "position":
        a.plot(t, rec["x"], "-", color="tab:blue", lw=1.2, label="$x(t)$")
        a.plot(t, rec["xr"], "--", color="tab:red", lw=1.2, label="$x_r(t)$")
        if opt.band_cm is not None:
            low, high = opt.band_cm
            a.axhline(low, color="k", ls="-.", lw=0.9, label=r"$\underline{k}$, $\overline{k}$")
            a.axhline(high, color="k", ls="-.", lw=0.9)
    elif key == "error":
        a.plot(t, rec["e"], "-", color="tab:blue", lw=1.2, label="$e(t)$")
        if opt.w1_cm is not None:
            a.axhline(opt.w1_cm, color="tab:red", ls="--", lw=1.0, label=r"$\pm w_1$")
            a.axhline(-opt.w1_cm, color="tab:red", ls="--", lw=1.0)
    elif key == "velocity":
        a.plot(t, rec["v"], "-", color="tab:blue", lw=1.0, label=r"$\dot{x}(t)$")
    elif key == "input":
        a.plot(t, rec["u"], "-", color="tab:blue", lw=1.0, label="$u(t)$")
    elif key == "pressure":
        a.plot(t, rec["p"], "-", color="tab:blue", lw=1.0, label="$p(t)$")
    if opt.t_u_s is not None and key in ("error", "velocity", "input"):
        a.axvline(opt.t_u_s, color="0.4", ls=":", lw=1.0, label="$t_u$")
    a.grid(True, lw=0.4, alpha=0.6)
    a.legend(loc="best", fontsize=8, frameon=False)


def output_paths(prefix: str | Path, panels: bool = True) -> list[Path]:
    """The files plot_recording writes: <prefix>.png and, with panels, one per panel."""
    prefix = Path(prefix)
    return [prefix.with_name(prefix.name + ".png")] + [
        prefix.with_name(f"{prefix.name}_{letter}_{name}.png") for letter, name, _ in PANELS if panels]


def plot_recording(rec: Recording, prefix: str | Path, opt: PlotOptions = PlotOptions()) -> list[Path]:
    """Writes <prefix>.png (all panels) and, with opt.panels, <prefix>_<letter>_<name>.png
    (one each); returns the paths."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    prefix = Path(prefix)
    prefix.parent.mkdir(parents=True, exist_ok=True)
    written: list[Path] = []
    ylabels = {name: label.format(unit=rec.units.get("u", "input unit")) for _, name, label in PANELS}
    t = rec["t"]
    xlim = (float(np.nanmin(t)), float(np.nanmax(t))) if len(t) else (0.0, 1.0)

    fig, axes = plt.subplots(len(PANELS), 1, figsize=(7.0, 11.0), sharex=True)
    for ax, (letter, name, _) in zip(axes, PANELS):
        _draw(ax, name, rec, opt)
        ax.set_ylabel(ylabels[name])
        ax.set_title(f"({letter})", loc="left", fontsize=9)
        ax.set_xlim(*xlim)
    axes[-1].set_xlabel("Time (s)")
    if opt.title:
        fig.suptitle(opt.title, fontsize=10)
    fig.tight_layout()
    paths = output_paths(prefix, opt.panels)
    out = paths[0]
    fig.savefig(out, dpi=opt.dpi)
    plt.close(fig)
    written.append(out)

    for (letter, name, _), out in zip(PANELS, paths[1:]):
        fig, ax = plt.subplots(figsize=(6.0, 3.0))
        _draw(ax, name, rec, opt)
        ax.set_xlabel("Time (s)")
        ax.set_ylabel(ylabels[name])
        ax.set_xlim(*xlim)
        ax.set_title(f"({letter})" + (f" {opt.title}" if opt.title else ""), loc="left", fontsize=9)
        fig.tight_layout()
        fig.savefig(out, dpi=opt.dpi)
        plt.close(fig)
        written.append(out)
    return written
