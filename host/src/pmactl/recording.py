# SPDX-License-Identifier: Apache-2.0
"""The telemetry recording's CSV format (written by client.TelemetryRecorder, read by plot).

One row per telemetry tick (TELEM_A and the TELEM_B..E frames that followed it), one
header row with each column's name and unit as ``name [unit]``. An empty cell is a
value whose frame did not arrive (or was masked off by telem.mask). Columns, in order:

| column | from | unit |
|---|---|---|
| ``t [s]`` | TELEM_A TimeMs | s, run time since START |
| ``x [cm]`` | TELEM_A XCm | cm |
| ``xr [cm]`` | TELEM_B XrCm | cm |
| ``e [cm]`` | TELEM_B ECm | cm, e = x - xr |
| ``u [input unit]`` | TELEM_C U | input unit (kPa of pressure change with act.kpa_per_u = 1) |
| ``v [cm/s]`` | TELEM_C VCmS | cm/s |
| 7th: ``lambda1 [cm]`` (PPC) | TELEM_D Internal1 | per controller (see internal_labels) |
| 8th: ``lambda2 [cm/s]`` (PPC) | TELEM_D Internal2 | per controller |
| ``p [kPa]`` | TELEM_E PressureKpa | kPa |
| ``ctrl_flags [-]`` | TELEM_E CtrlFlags | bit mask |
| ``breaches [-]`` | TELEM_E Breaches | count |
| ``rx_time [s]`` | host receive time of TELEM_A | s since the first row |
"""
from __future__ import annotations

import csv
import re
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    import numpy as np


@dataclass(frozen=True)
class Column:
    key: str
    name: str
    unit: str


COLUMNS: tuple[Column, ...] = (
    Column("t", "t", "s"),
    Column("x", "x", "cm"),
    Column("xr", "xr", "cm"),
    Column("e", "e", "cm"),
    Column("u", "u", "input unit"),
    Column("v", "v", "cm/s"),
    Column("internal1", "internal1", "-"),
    Column("internal2", "internal2", "-"),
    Column("p", "p", "kPa"),
    Column("ctrl_flags", "ctrl_flags", "-"),
    Column("breaches", "breaches", "-"),
    Column("rx_time", "rx_time", "s"),
)
_INTERNAL = {"internal1": 0, "internal2": 1}
_CELL = re.compile(r"^\s*(?P<name>[^\[\]]+?)\s*\[(?P<unit>[^\[\]]*)\]\s*$")


def header_row(labels: tuple[tuple[str, str], tuple[str, str]] | None = None) -> list[str]:
    """The header: ``name [unit]`` per column; labels give the internals' (name, unit)."""
    out = []
    for c in COLUMNS:
        name, unit = c.name, c.unit
        if labels and c.key in _INTERNAL:
            name, unit = labels[_INTERNAL[c.key]]
        out.append(f"{name} [{unit}]")
    return out


def row_cells(values: dict[str, float | int], rx_rel_s: float) -> list[str]:
    """The CSV cells of one telemetry row (values by column key; a missing key is an empty
    cell), rx_rel_s the host's receive time in s since the first row."""
    cells: list[str] = []
    for col in COLUMNS:
        if col.key == "rx_time":
            cells.append(f"{rx_rel_s:.6f}")
            continue
        v = values.get(col.key)
        if v is None:
            cells.append("")
        elif col.key == "t":
            cells.append(f"{float(v):.3f}")
        elif isinstance(v, float):
            cells.append(f"{v:.9g}")
        else:
            cells.append(str(int(v)))
    return cells


class RecordingError(ValueError):
    """The file is not a pmactl recording."""


@dataclass
class Recording:
    """A recording's columns as float arrays (NaN where a cell is empty), by key."""
    path: Path
    data: dict[str, np.ndarray]
    names: dict[str, str]        # key -> name in the header (internals: e.g. lambda1)
    units: dict[str, str]        # key -> unit

    def __len__(self) -> int:
        return len(self.data["t"])

    def __getitem__(self, key: str) -> np.ndarray:
        return self.data[key]


def read_recording(path: str | Path) -> Recording:
    """Reads a recording CSV; RecordingError with the reason when it is not one."""
    import numpy as np  # here: pmactl's start-up stays fast without it

    path = Path(path)
    try:
        with path.open(newline="") as f:
            header = next(csv.reader(f), None)
    except (OSError, UnicodeDecodeError) as e:
        raise RecordingError(f"{path}: cannot read: {e}") from e
    if not header:
        raise RecordingError(f"{path}: empty file")
    if len(header) != len(COLUMNS):
        raise RecordingError(f"{path}: {len(header)} columns, a recording has {len(COLUMNS)} "
                             f"({', '.join(header_row())})")
    names: dict[str, str] = {}
    units: dict[str, str] = {}
    for c, cell in zip(COLUMNS, header):
        m = _CELL.match(cell)
        if not m or (c.key not in _INTERNAL and (m["name"] != c.name or m["unit"] != c.unit)):
            raise RecordingError(f"{path}: column {cell!r} where a recording has "
                                 f"'{c.name} [{c.unit}]'")
        names[c.key], units[c.key] = m["name"], m["unit"]
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", UserWarning)      # "Empty input file": no rows
            arr = np.genfromtxt(path, delimiter=",", skip_header=1, dtype=float,
                                missing_values="", filling_values=np.nan, invalid_raise=True,
                                ndmin=2)
    except ValueError as e:
        raise RecordingError(f"{path}: not a recording: {e}") from e
    if arr.size == 0:
        arr = np.empty((0, len(COLUMNS)))
    if arr.shape[1] != len(COLUMNS):
        raise RecordingError(f"{path}: rows of {arr.shape[1]} cells, expected {len(COLUMNS)}")
    if len(arr) and np.isnan(arr[:, 0]).any():
        raise RecordingError(f"{path}: rows without a time (t [s] is empty or not a number)")
    return Recording(path, {c.key: arr[:, i] for i, c in enumerate(COLUMNS)}, names, units)


@dataclass
class Metrics:
    """Numbers of a recording that tuning looks at (the paper's trade-offs: entry into the
    band, peak velocity and input while converging, accuracy after t_u, barrier clamps)."""
    rows: int
    t_first_s: float
    t_last_s: float
    time_to_band_s: float | None      # |e| < w1 from this time to the end (None: not at the end)
    converge_peak_v_cm_s: float | None  # peaks while converging: until time_to_band (or t_u)
    converge_peak_u: float | None
    max_abs_e_after_tu_cm: float | None
    rmste_after_tu_cm: float | None   # root-mean-square tracking error for t >= t_u
    peak_abs_v_cm_s: float | None     # over the whole recording
    peak_abs_u: float | None
    breaches: int | None              # barrier clamps since START (the last row's count)

    def lines(self, w1_cm: float | None, t_u_s: float | None, u_unit: str = "input unit") -> list[str]:
        def num(v: float | None, fmt: str) -> str:
            return "-" if v is None else format(v, fmt)
        out = [f"{self.rows} rows, t {self.t_first_s:.3f}..{self.t_last_s:.3f} s"]
        if w1_cm is not None:
            entry = (f"from t = {self.time_to_band_s:.3f} s on" if self.time_to_band_s is not None
                     else "not at the end of the recording")
            tu = f" (t_u = {t_u_s:g} s)" if t_u_s is not None else ""
            out.append(f"|e| < w1 = {w1_cm:g} cm {entry}{tu}")
        if w1_cm is not None or t_u_s is not None:
            until = "until then" if self.time_to_band_s is not None else "until t_u"
            out.append(f"{until}: peak |v| {num(self.converge_peak_v_cm_s, '.3g')} cm/s, "
                       f"peak |u| {num(self.converge_peak_u, '.3g')} {u_unit}")
        since = f"t >= t_u = {t_u_s:g} s" if t_u_s is not None else "the whole run"
        out.append(f"over {since}: max |e| {num(self.max_abs_e_after_tu_cm, '.4f')} cm, "
                   f"RMSTE {num(self.rmste_after_tu_cm, '.4f')} cm")
        out.append(f"whole run: peak |v| {num(self.peak_abs_v_cm_s, '.3g')} cm/s, "
                   f"peak |u| {num(self.peak_abs_u, '.3g')} {u_unit}")
        if self.breaches is not None:
            out.append(f"barrier clamps (breaches) {self.breaches}")
        return out


def metrics(rec: Recording, w1_cm: float | None = None, t_u_s: float | None = None) -> Metrics:
    """The recording's figures (pmactl/figures.py: their rules for NaN and "never")."""
    import numpy as np

    from . import figures  # numpy: imported when needed (pmactl starts without it)

    t, e, v, u = rec["t"], rec["e"], rec["v"], rec["u"]
    entry = figures.time_to_band(t, e, w1_cm) if w1_cm is not None else None

    def peak(a: "np.ndarray", where: "np.ndarray") -> float | None:
        sel = a[where & ~np.isnan(a)]
        return float(np.max(np.abs(sel))) if len(sel) else None

    every = np.ones(len(t), dtype=bool)
    end = entry if entry is not None else t_u_s
    converging = t <= end if end is not None else np.zeros(len(t), dtype=bool)
    b = rec["breaches"]
    bv = b[~np.isnan(b)]
    return Metrics(rows=len(t), t_first_s=float(t[0]) if len(t) else 0.0,
                   t_last_s=float(t[-1]) if len(t) else 0.0, time_to_band_s=entry,
                   converge_peak_v_cm_s=peak(v, converging), converge_peak_u=peak(u, converging),
                   max_abs_e_after_tu_cm=figures.max_abs_from(t, e, t_u_s),
                   rmste_after_tu_cm=figures.rmste_from(t, e, t_u_s),
                   peak_abs_v_cm_s=peak(v, every), peak_abs_u=peak(u, every),
                   breaches=int(bv[-1]) if len(bv) else None)
