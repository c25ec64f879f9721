# SPDX-License-Identifier: Apache-2.0
"""Reports of HIL runs: the RMSTE per window next to the paper's Tables 1 and 2,
the other figures of merit, and PNG figures in the style of the paper's Figs. 4-8.
"""
from __future__ import annotations

import contextlib
import io
import json
import math
import zipfile
from pathlib import Path
from typing import Any

import numpy as np

# The paper's measured RMSTE [cm] (controller.md, Tables 1 and 2), by the scenario's `paper` key.
PAPER: dict[str, dict[str, Any]] = {
    "table1_case1": {"windows": [[10, 20], [20, 30], [30, 40], [40, 50], [50, 60]],
                     "rows": {"paper, t_u 6, w1 0.5": [0.0969, 0.0970, 0.0972, 0.0993, 0.1013]}},
    "table1_case2a": {"windows": [[10, 20], [20, 30], [30, 40], [40, 50], [50, 60]],
                      "rows": {"paper, t_u 6, w1 0.3": [0.0891, 0.0852, 0.0866, 0.0878, 0.0875]}},
    "table1_case2b": {"windows": [[10, 20], [20, 30], [30, 40], [40, 50], [50, 60]],
                      "rows": {"paper, t_u 2, w1 0.3": [0.0842, 0.0827, 0.0835, 0.0866, 0.0847]}},
    "table2": {"windows": [[5, 30], [30, 60], [60, 90], [90, 120], [120, 150], [150, 180]],
               "rows": {"paper: its controller": [0.0110, 0.0144, 0.0207, 0.0329, 0.0435, 0.0590],
                        "paper: MFAC": [0.0128, 0.0212, 0.0404, 0.0746, 0.0993, 0.1439]}},
}


def _f(v: Any, fmt: str = ".4f") -> str:
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return "-"
    if isinstance(v, (int, np.integer)) and not isinstance(v, bool):
        return str(int(v))
    return format(float(v), fmt)


def rmste_table(summary: dict[str, Any]) -> str:
    windows = summary["windows"]
    head = ["RMSTE [cm]"] + [f"{a:g}-{b:g} s" for a, b in windows]
    rows = [[label] + [_f(v) for v in vals] for label, vals in summary["rmste"].items()]
    paper = PAPER.get(summary.get("paper") or "")
    if paper:
        pw = [list(map(float, w)) for w in paper["windows"]]
        for label, vals in paper["rows"].items():
            by_w = {tuple(w): v for w, v in zip(pw, vals)}
            rows.append([label] + [_f(by_w.get((float(a), float(b)))) for a, b in windows])
    return _table(head, rows)


def metrics_table(summary: dict[str, Any]) -> str:
    head = ["controller", "t_u s", "w1 cm", "in band s", "max|e| >t_u", "outside w1", "x range cm",
            "violations", "breaches (>t_u)", "peak |v| cm/s", "peak |u|", "peak p kPa", "TV u /s",
            "TV p kPa/s", "chatter", "state / fault"]
    rows = []
    for label, c in summary["controllers"].items():
        if "rmste_cm" not in c:
            rows.append([label] + ["-"] * 14 + [_end(summary, label)])
            continue
        br = "-" if c.get("barrier_breaches") is None else f"{c['barrier_breaches']} ({c['barrier_breaches_after_tu']})"
        rows.append([
            label, _f(c.get("t_u_s"), "g"), _f(c.get("w1_cm"), "g"), _f(c.get("time_to_band_s"), ".3f"),
            _f(c.get("max_abs_error_after_tu_cm")), _f(c.get("samples_outside_w1_after_tu")),
            f"{c['x_min_cm']:.3f}..{c['x_max_cm']:.3f}", str(c["constraint_violations"]), br,
            _f(c.get("peak_velocity_cm_s"), ".2f"), _f(c.get("peak_u"), ".1f"),
            _f(c.get("peak_pressure_cmd_kpa"), ".0f"), _f(c.get("tv_u_per_s"), ".0f"),
            _f(c.get("tv_pressure_cmd_kpa_per_s"), ".0f"), _f(c.get("chatter_ratio"), ".2f"),
            _end(summary, label),
        ])
    return _table(head, rows)


def _end(summary: dict[str, Any], label: str) -> str:
    text = f"{summary['state'].get(label)} / {summary['fault_code'].get(label)}"
    start = summary.get("start_result", {}).get(label)
    return text if start in (None, "OK") else f"{text} (START {start})"


def _table(head: list[str], rows: list[list[str]]) -> str:
    widths = [max(len(str(r[i])) for r in [head, *rows]) for i in range(len(head))]
    def line(r: list[str]) -> str:
        return "| " + " | ".join(str(v).ljust(w) for v, w in zip(r, widths)) + " |"
    sep = "|" + "|".join("-" * (w + 2) for w in widths) + "|"
    return "\n".join([line(head), sep] + [line(r) for r in rows])


class ReportError(ValueError):
    """A run directory without a readable run summary (or signals): what is wrong, in one line."""


# What a run's summary.json must hold for its report: key -> the type(s) it must have
SUMMARY_KEYS: dict[str, tuple[type, ...]] = {
    "scenario": (str,), "title": (str,), "duration_s": (int, float), "period_s": (int, float),
    "windows": (list,), "rmste": (dict,), "controllers": (dict,), "state": (dict,), "fault_code": (dict,),
    "expect": (dict,),
}


def read_summary(run_dir: Path) -> dict[str, Any]:
    """run_dir/summary.json, checked to be a run summary (ReportError otherwise)."""
    p = run_dir / "summary.json"
    if not p.is_file():
        raise ReportError(f"{p} not found" + ("" if run_dir.is_dir() else f" ({run_dir} is not a directory)"))
    try:
        summary: Any = json.loads(p.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as e:
        raise ReportError(f"{p}: not a readable JSON file: {e}") from e
    check_summary(summary, str(p))
    out: dict[str, Any] = summary
    return out


def check_summary(summary: Any, where: str) -> None:
    if not isinstance(summary, dict):
        raise ReportError(f"{where}: not a run summary (expected a JSON object, got {type(summary).__name__})")
    for key, types in SUMMARY_KEYS.items():
        if key not in summary:
            raise ReportError(f"{where}: not a run summary (no {key!r})")
        v = summary[key]
        if isinstance(v, bool) or not isinstance(v, types):
            raise ReportError(f"{where}: not a run summary ({key!r} is {type(v).__name__})")
    if not summary["period_s"] > 0:
        raise ReportError(f"{where}: not a run summary (period_s {summary['period_s']!r})")
    for key in ("state", "fault_code", "start_result"):
        if key not in summary["expect"]:
            raise ReportError(f"{where}: not a run summary (no expect.{key})")
    for label, c in summary["controllers"].items():
        if not isinstance(c, dict):
            raise ReportError(f"{where}: not a run summary (controllers.{label} is {type(c).__name__})")


def render_summary(run_dir: Path) -> str:
    """print_summary's text of a run directory's summary.json (ReportError: nothing printed)."""
    where = str(run_dir / "summary.json")
    summary = read_summary(run_dir)
    buf = io.StringIO()
    try:
        with contextlib.redirect_stdout(buf):
            print_summary(summary)
    except (KeyError, TypeError, ValueError, AttributeError, IndexError) as e:
        raise ReportError(f"{where}: not a run summary as hil writes it ({type(e).__name__}: {e})") from e
    return buf.getvalue().rstrip("\n")


def print_summary(summary: dict[str, Any]) -> None:
    q = " (quick)" if summary.get("quick") else ""
    print(f"\n== {summary['scenario']}{q}: {summary['title']}")
    slot = f", the controller slot in {summary['ctrl_arith']} (offline)" if summary.get("ctrl_arith") else ""
    print(f"   {summary['duration_s']:g} s of control time at {1.0 / summary['period_s']:g} Hz, "
          f"{summary.get('wall_s', 0):.0f} s wall{slot}")
    if summary["rmste"]:
        print()
        print(rmste_table(summary))
    print()
    print(metrics_table(summary))
    b = summary.get("benchmark") or {}
    if b.get("ticks_per_s"):
        print(f"\n   lockstep: {b['ticks_per_s']:.0f} ticks/s x {b['lanes']} nodes = "
              f"{b['node_steps_per_s']:.0f} node steps/s")
    ex = summary["expect"]
    verdict = "met" if summary.get("expect_met") else "NOT met"
    print(f"   expected end: {ex['state']} / {ex['fault_code']} (START {ex['start_result']}): {verdict}")
    if summary.get("interrupted"):
        print("   INTERRUPTED: partial results")
    for e in summary.get("errors", []):
        print(f"   error: {e}")


# ------------------------------------------------------------------ figures --
# the signals of each lane the figure plots (signals.npz: LABEL__KEY)
FIGURE_SIGNALS = ("t_s", "run_step", "x_meas_cm", "e_cm", "v_true_cm_s", "p_kpa", "xr_cm")


def write_figures(out: Path) -> list[Path]:
    """fig_tracking.png (the paper's Figs. 4-8 panels for every controller of the run).
    ReportError for a summary or signals that cannot be read."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    summary = read_summary(out)
    try:
        data = np.load(out / "signals.npz")
    except (OSError, ValueError, zipfile.BadZipFile) as e:
        raise ReportError(f"{out / 'signals.npz'}: not readable signals: {e}") from e
    labels = [k for k in summary["controllers"] if f"{k}__t_s" in data and len(data[f"{k}__t_s"])]
    if not labels:
        return []
    missing = [f"{label}__{key}" for label in labels for key in FIGURE_SIGNALS if f"{label}__{key}" not in data]
    if missing:
        raise ReportError(f"{out / 'signals.npz'}: not a run's signals (no {', '.join(missing[:3])})")
    lo, hi = None, None
    fig, ax = plt.subplots(5, 1, figsize=(10, 12), sharex=True)
    for label in labels:
        c = summary["controllers"][label]
        run = data[f"{label}__run_step"] >= 0
        t = data[f"{label}__t_s"]
        ax[0].plot(t, data[f"{label}__x_meas_cm"][run], lw=0.8, label=f"x ({label})")
        ax[1].plot(t, data[f"{label}__e_cm"], lw=0.8, label=label)
        ax[2].plot(t, data[f"{label}__v_true_cm_s"][run], lw=0.6, label=f"{label} (rig)")
        if f"{label}__telem_t_s" in data:
            tt = data[f"{label}__telem_t_s"]
            ax[3].plot(tt, data[f"{label}__telem_u"], lw=0.8, label=label)
        ax[4].plot(t, data[f"{label}__p_kpa"][run], lw=0.8, label=f"{label}: muscle")
        if c.get("w1_cm") and lo is None:
            lo, hi = -c["w1_cm"], c["w1_cm"]
    first = labels[0]
    ax[0].plot(data[f"{first}__t_s"], data[f"{first}__xr_cm"], "k--", lw=0.8, label="x_r")
    ax[0].axhline(0.0, color="r", lw=0.6)       # the paper's constraint band -3 < x < 0
    ax[0].axhline(-3.0, color="r", lw=0.6)
    if lo is not None:
        ax[1].axhline(lo, color="r", lw=0.6, ls="--", label="+-w1")
        ax[1].axhline(hi, color="r", lw=0.6, ls="--")
    for a, yl in zip(ax, ["x [cm]", "e [cm]", "x' [cm/s]", "u [kPa]", "p [kPa]"]):
        a.set_ylabel(yl)
        a.grid(True, lw=0.3)
        a.legend(loc="upper right", fontsize=7)
    ax[-1].set_xlabel("t [s] since START")
    fig.suptitle(f"{summary['scenario']}: {summary['title']}", fontsize=10)
    fig.tight_layout()
    p = out / "fig_tracking.png"
    fig.savefig(p, dpi=110)
    plt.close(fig)
    return [p]
