# SPDX-License-Identifier: Apache-2.0
"""pmactl scope: a live view of running nodes' telemetry.

Four panels over a rolling window of host time (0 = now, in s): (a) the position x and
the reference x_r, (b) the tracking error e with the accuracy band +-w1 (PPC's ppc.w1_cm,
read from each node, or --w1), (c) the controller output u, (d) the pressure command p.
One colour per node. The data are the TELEM_A..E frames, grouped per tick as
``pmactl record`` groups them (client.TelemetryGrouper).

In a window (any interactive matplotlib backend; TkAgg by default, which needs tkinter:
Debian's python3-tk) it redraws every 1/--fps s by blitting: the axes are drawn once,
each frame only the lines move, so 25 frames per second cost little. Keys: space or p
pauses (the view freezes; the telemetry is still received, and still recorded), r starts
and stops recording, s saves the view as PNG, q quits. Without a window (--headless) it
renders --frames frames with Agg and writes each as a PNG (for tests and reports).

A recording is the CSV of ``pmactl record`` (pmactl.recording: one row per tick, units in
the header), one file per node: CSV for one node, CSV's stem + ``_n<node>`` for several.
"""
from __future__ import annotations

import csv
import json
import math
import threading
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO, Any

import can

from pmactl.client import (
    NoReply,
    PmaError,
    PmaNode,
    TelemetryGrouper,
    TelemetryRow,
    frame_filters,
    internal_labels,
)
from pmactl.paramfile import ParamFileError
from pmactl.protocol import TELEM_FRAMES
from pmactl.recording import COLUMNS, header_row, row_cells

# Called after each frame drawn with (scope, frames drawn so far): for tests and embedding.
frame_hooks: list[Callable[[Scope, int], None]] = []

PANELS = (("x", "position x, reference x_r [cm]"), ("e", "error e [cm]"),
          ("u", "controller output u [input unit]"), ("p", "pressure command p [kPa]"))
HOST_HEARTBEAT_PERIOD_S = 0.1


class ScopeError(Exception):
    """The scope cannot run as asked (no interactive backend, a file it cannot write)."""


@dataclass
class ScopeOptions:
    nodes: list[int]
    window_s: float = 10.0             # the rolling window, s of host time
    fps: float = 30.0                  # target redraws per second
    w1_cm: float | None = None         # None: each node's ppc.w1_cm
    host_heartbeat: bool = False       # send HOST_HEARTBEAT to every node (keeps them RUNNING)
    csv: Path | None = None            # where recordings go (None: scope-<date>-<time>.csv)
    record: bool = False               # record from the start
    seconds: float | None = None       # stop after this long (None: until q / closed / Ctrl-C)
    frames: int | None = None          # stop after this many frames drawn
    headless: bool = False             # Agg, no window: PNGs
    png_prefix: Path | None = None     # headless: PREFIX_0001.png, ...
    dpi: int = 80


@dataclass
class Trace:
    """One node's rows inside the window, and its recording."""
    node: int
    grouper: TelemetryGrouper
    w1_cm: float | None = None
    controller: str | None = None      # ctrl.mode's name: the internals' columns
    params: dict[str, float | int] = field(default_factory=dict)   # read at the start
    rx: deque[float] = field(default_factory=deque)
    cols: dict[str, deque[float]] = field(default_factory=lambda: {k: deque() for k in ("x", "xr", "e", "u", "p")})
    rows: int = 0
    last: TelemetryRow | None = None
    file: IO[str] | None = None
    writer: Any = None
    path: Path | None = None
    recorded: int = 0                  # rows in the current recording
    recorded_total: int = 0
    rx0: float | None = None

    def add(self, row: TelemetryRow) -> None:
        self.rx.append(row.rx_time)
        for k, col in self.cols.items():
            v = row.values.get(k)
            col.append(float(v) if v is not None else math.nan)
        self.rows += 1
        self.last = row

    def trim(self, oldest: float) -> None:
        while self.rx and self.rx[0] < oldest:
            self.rx.popleft()
            for col in self.cols.values():
                col.popleft()


@dataclass
class ScopeSummary:
    frames: int
    elapsed_s: float
    rows: dict[int, int]
    recorded: dict[int, int]
    files: list[str]
    stop_reason: str
    recent_fps: float = 0.0            # over the last 50 frames (the first, full draws excluded)
    full_draws: int = 0

    drawing_s: float = 0.0             # from the first frame drawn to the last

    @property
    def fps(self) -> float:
        """Frames per second while drawing (the start-up, window and first draw excluded)."""
        return (self.frames - 1) / self.drawing_s if self.frames > 1 and self.drawing_s > 0 else 0.0


class Scope:
    def __init__(self, client: PmaNode, opts: ScopeOptions, out: Callable[[str], None] = print) -> None:
        self.client = client
        self.opts = opts
        self.out = out
        self.traces: dict[int, Trace] = {}
        self.paused = False
        self.paused_at: float | None = None
        self.quit_reason: str | None = None
        self.frames = 0
        self.full_draws = 0
        self._first_frame_t: float | None = None
        self._last_frame_t = 0.0
        self.files: list[str] = []
        self._hb_stop = threading.Event()
        self._fig: Any = None
        self._artists: list[Any] = []
        self._lines: dict[tuple[int, str], Any] = {}
        self._axes: dict[str, Any] = {}
        self._status: Any = None
        self._bg: Any = None
        self._ylim_checked = 0.0
        self._title_at = 0.0
        self._t_begin = time.monotonic()
        self._rate_frames: deque[float] = deque(maxlen=50)
        self._recording = False

    # ----------------------------------------------------------- set-up --
    def setup(self) -> None:
        node = self.client
        filters: list[dict[str, Any]] = []
        for n in self.opts.nodes:
            filters += frame_filters(node.proto, ("PARAM_RESP", "HEARTBEAT") + TELEM_FRAMES, n)
        node.bus.set_filters(filters)  # type: ignore[arg-type]
        saved = node.node
        for n in self.opts.nodes:
            mask, w1, controller = 0x1F, self.opts.w1_cm, None
            params: dict[str, float | int] = {}
            node.node = n                     # the client's requests go to node n
            try:
                mask = int(node.get("telem.mask"))
                controller = node.proto.param("ctrl.mode").values.get(int(node.get("ctrl.mode")))
                # what `pmactl plot` takes from a recording's .meta.json: w1, t_u, the band
                for name in ("ppc.w1_cm", "ppc.t_u_s", "safety.x_min_cm", "safety.x_max_cm"):
                    params[name] = node.get(name)
                if w1 is None and controller == "PPC":
                    w1 = float(params["ppc.w1_cm"])
            except (NoReply, PmaError, KeyError):
                pass            # a node that does not answer: shown with what it told
            finally:
                node.node = saved
            self.traces[n] = Trace(n, TelemetryGrouper(mask), w1, controller=controller, params=params)
        if self.opts.record:
            self.start_recording()

    # ---------------------------------------------------------- the bus --
    def poll(self, max_frames: int = 5000) -> int:
        """Receives what has arrived (without waiting); returns the number of rows."""
        node = self.client
        rows = 0
        for _ in range(max_frames):
            msg = node.bus.recv(0.0)
            if msg is None:
                break
            found = node.proto.message_of(msg.arbitration_id)
            if found is None or msg.is_extended_id or msg.is_error_frame:
                continue
            name, nid = found
            tr = self.traces.get(nid)
            if tr is None or name not in TELEM_FRAMES:
                continue
            sig = _decode(node, name, msg)
            if sig is None:             # a frame of the wrong length: not ours to show
                continue
            for row in tr.grouper.feed(name, sig, msg.timestamp):
                self._row(tr, row)
                rows += 1
        return rows

    def _row(self, tr: Trace, row: TelemetryRow) -> None:
        if tr.writer is not None:
            if tr.rx0 is None:
                tr.rx0 = row.rx_time
            tr.writer.writerow(row_cells(row.values, row.rx_time - tr.rx0))
            tr.recorded += 1
            tr.recorded_total += 1
        if not self.paused:
            tr.add(row)

    def _host_heartbeats(self) -> None:
        """HOST_HEARTBEAT to every node every 0.1 s, in a thread of its own: a slow redraw
        (a full one, or a busy machine) must not let a RUNNING node fault."""
        counter = 0
        while not self._hb_stop.wait(0 if counter == 0 else HOST_HEARTBEAT_PERIOD_S):
            for n in self.opts.nodes:
                try:
                    self.client.send("HOST_HEARTBEAT", {"Counter": counter & 0xFF}, node=n)
                except can.CanError:
                    pass        # the bus failed: the receiving side reports it
            counter += 1

    # -------------------------------------------------------- recording --
    def _csv_path(self, node: int) -> Path:
        base = self.opts.csv or Path(time.strftime("scope-%Y%m%d-%H%M%S.csv"))
        if len(self.opts.nodes) > 1:
            base = base.with_name(f"{base.stem}_n{node}{base.suffix or '.csv'}")
        path, k = base, 2
        while str(path) in self.files:          # a second recording of this run
            path = base.with_name(f"{base.stem}_{k}{base.suffix}")
            k += 1
        return path

    def start_recording(self) -> None:
        for tr in self.traces.values():
            path = self._csv_path(tr.node)
            try:
                tr.file = path.open("w", newline="")
            except OSError as e:
                raise ParamFileError(str(path), [f"cannot write: {e.strerror or e}"]) from None
            tr.writer = csv.writer(tr.file)
            tr.writer.writerow(header_row(internal_labels(tr.controller)))
            tr.path, tr.rx0 = path, None
            self.files.append(str(path))
            self.out(f"recording node {tr.node} to {path}")
        self._recording = True

    def stop_recording(self) -> None:
        for tr in self.traces.values():
            if tr.file is not None:
                tr.file.close()
                if tr.recorded == 0 and tr.path is not None:
                    # no telemetry came: no header-only file (and no metadata) left behind
                    tr.path.unlink(missing_ok=True)
                    if str(tr.path) in self.files:
                        self.files.remove(str(tr.path))
                    self.out(f"no rows of node {tr.node} recorded: {tr.path} not kept")
                else:
                    self.out(f"recorded {tr.recorded} rows of node {tr.node} to {tr.path}")
                    if tr.path is not None:
                        self._write_meta(tr, tr.path)
            tr.file = tr.writer = None
            tr.recorded = 0
        self._recording = False

    def _write_meta(self, tr: Trace, path: Path) -> None:
        """PATH's .meta.json, as `pmactl record` writes it (fewer parameters: those `plot`
        uses), so `pmactl plot` draws w1, t_u and the band of the run."""
        proto = self.client.proto
        labels = internal_labels(tr.controller)
        meta = {
            "format": "pmactl-recording 1", "source": "pmactl scope", "node": tr.node,
            "controller": tr.controller,
            "internal1": {"name": labels[0][0], "unit": labels[0][1]},
            "internal2": {"name": labels[1][0], "unit": labels[1][1]},
            "columns": [{"key": c.key, "unit": c.unit} for c in COLUMNS],
            "summary": {"rows": tr.recorded},
            "params": {k: float(v) for k, v in tr.params.items()},
            "units": {k: proto.param(k).unit for k in tr.params},
        }
        try:
            path.with_name(path.stem + ".meta.json").write_text(json.dumps(meta, indent=2) + "\n")
        except OSError as e:
            raise ParamFileError(str(path), [f"cannot write its metadata: {e.strerror or e}"]) from None

    # ----------------------------------------------------------- figure --
    def build_figure(self) -> Any:
        import matplotlib.pyplot as plt

        fig, axes = plt.subplots(len(PANELS), 1, sharex=True, figsize=(10, 8), dpi=self.opts.dpi)
        fig.subplots_adjust(left=0.09, right=0.98, top=0.93, bottom=0.07, hspace=0.12)
        who = ", ".join(str(n) for n in self.opts.nodes)
        fig.suptitle(f"pmactl scope: node{'s' if len(self.opts.nodes) > 1 else ''} {who}", fontsize=11)
        animated = not self.opts.headless
        for ax, (key, label) in zip(axes, PANELS):
            self._axes[key] = ax
            ax.set_ylabel(label, fontsize=8)
            ax.grid(True, alpha=0.3)
            ax.set_xlim(-self.opts.window_s, 0.0)
        for i, n in enumerate(self.opts.nodes):
            color = f"C{i % 10}"
            for key, ax, style in (("x", self._axes["x"], "-"), ("xr", self._axes["x"], "--"),
                                   ("e", self._axes["e"], "-"), ("u", self._axes["u"], "-"),
                                   ("p", self._axes["p"], "-")):
                (line,) = ax.plot([], [], style, color=color, lw=1.5, animated=animated,
                                  label=f"node {n} {'x' if key == 'x' else 'x_r'}" if key in ("x", "xr") else None)
                self._lines[(n, key)] = line
                self._artists.append(line)
        for w1 in sorted({tr.w1_cm for tr in self.traces.values() if tr.w1_cm is not None}):
            ax = self._axes["e"]
            ax.axhspan(-w1, w1, color="0.85", zorder=0, label=f"+-w1 = {w1:g} cm")
            ax.axhline(w1, color="0.5", lw=0.8, ls=":")
            ax.axhline(-w1, color="0.5", lw=0.8, ls=":")
        self._axes["x"].legend(loc="upper left", fontsize=7, ncol=max(1, len(self.opts.nodes)))
        if any(tr.w1_cm is not None for tr in self.traces.values()):
            self._axes["e"].legend(loc="upper left", fontsize=7)
        self._axes["p"].set_xlabel("host time [s] (0 = now)")
        # the live status (values, rate, PAUSED, REC): in the window's title, where it costs
        # nothing; drawing a changing text into the figure costs more than all the lines
        if self.opts.headless:
            self._status = fig.text(0.09, 0.955, "", fontsize=8, family="monospace")
        else:
            fig.text(0.09, 0.955, "keys: space pause, r record, s save PNG, q quit", fontsize=8)
        for key in ("x", "e", "u", "p"):
            self._axes[key].set_ylim(-1.0, 1.0)
        self._fig = fig
        return fig

    def _update_artists(self, now: float) -> bool:
        """Sets the lines' data; True when an axis' limits changed (a full redraw)."""
        t_now = self.paused_at if self.paused and self.paused_at is not None else now
        import numpy as np

        for tr in self.traces.values():
            if not self.paused:
                tr.trim(t_now - self.opts.window_s - 1.0)
            t = np.fromiter(tr.rx, float, len(tr.rx)) - t_now
            for key in ("x", "xr", "e", "u", "p"):
                self._lines[(tr.node, key)].set_data(t, np.fromiter(tr.cols[key], float, len(t)))
        rescale = False
        if now - self._ylim_checked >= 0.5:
            self._ylim_checked = now
            for key, ax in self._axes.items():
                vals = [np.fromiter(self.traces[n].cols[k], float) for n in self.opts.nodes
                        for k in (("x", "xr") if key == "x" else (key,))]
                if key == "e":
                    vals += [np.array([tr.w1_cm, -tr.w1_cm]) for tr in self.traces.values()
                             if tr.w1_cm is not None]
                allv = np.concatenate(vals) if vals else np.empty(0)
                allv = allv[np.isfinite(allv)]
                if not len(allv):
                    continue
                lo, hi = float(allv.min()), float(allv.max())
                span = max(hi - lo, 1e-3)
                cur_lo, cur_hi = ax.get_ylim()
                cur_span = cur_hi - cur_lo
                if lo < cur_lo or hi > cur_hi or span < 0.25 * cur_span:
                    ax.set_ylim(lo - 0.15 * span, hi + 0.15 * span)
                    rescale = True
        if self._status is not None:
            self._status.set_text(self.status_text(now))
        elif now - self._title_at >= 0.25:
            self._title_at = now
            manager = self._fig.canvas.manager
            if manager is not None:
                manager.set_window_title(f"pmactl scope | {self.status_text(now)}")
        return rescale

    def status_text(self, now: float) -> str:
        parts = []
        for tr in self.traces.values():
            if tr.last is None:
                parts.append(f"node {tr.node}: no telemetry")
                continue
            v = tr.last.values
            x, e = v.get("x"), v.get("e")
            parts.append(f"node {tr.node}: t {tr.last.t_s:7.2f} s"
                         + (f" x {float(x):+.3f} cm" if x is not None else "")
                         + (f" e {float(e):+.4f} cm" if e is not None else ""))
        rate = self.rate()
        parts.append(f"{rate:4.1f} frames/s")
        if self.paused:
            parts.append("PAUSED (space)")
        if self._recording:
            parts.append("REC (r)")
        return " | ".join(parts)

    def rate(self) -> float:
        """Frames drawn per second over the last 50 frames."""
        if len(self._rate_frames) < 2:
            return 0.0
        span = self._rate_frames[-1] - self._rate_frames[0]
        return (len(self._rate_frames) - 1) / span if span > 0 else 0.0

    def draw_frame(self) -> None:
        """One frame: receive, update the lines, blit them (a full draw when the axes change)."""
        self.poll()
        now = time.time()
        canvas = self._fig.canvas
        full = self._update_artists(now)
        if self.opts.headless:
            pass                                    # savefig draws everything
        elif full or self._bg is None:
            canvas.draw()                           # on_draw captures the background
            self.full_draws += 1
        else:
            canvas.restore_region(self._bg)
            self._draw_animated()
            canvas.blit(self._fig.bbox)
        self.frames += 1
        t = time.monotonic()
        self._rate_frames.append(t)
        if self._first_frame_t is None:
            self._first_frame_t = t
        self._last_frame_t = t
        for hook in frame_hooks:
            hook(self, self.frames)

    def _on_draw(self, _event: Any) -> None:
        canvas = self._fig.canvas
        self._bg = canvas.copy_from_bbox(self._fig.bbox)
        self._draw_animated()

    def _draw_animated(self) -> None:
        for a in self._artists:
            self._fig.draw_artist(a)

    def on_key(self, event: Any) -> None:
        key = (event.key or "").lower()
        if key in (" ", "p"):
            self.paused = not self.paused
            self.paused_at = time.time() if self.paused else None
        elif key == "r":
            if self._recording:
                self.stop_recording()
            else:
                self.start_recording()
        elif key == "s":
            path = Path(time.strftime("scope-%Y%m%d-%H%M%S.png"))
            self.save_png(path)
            self.out(f"view saved to {path}")
        elif key in ("q", "escape"):
            self.stop("quit (q)")

    def save_png(self, path: Path) -> None:
        for a in self._artists:
            a.set_animated(False)
        try:
            self._fig.savefig(path, dpi=self.opts.dpi)
        finally:
            for a in self._artists:
                a.set_animated(not self.opts.headless)
        self._bg = None

    def stop(self, reason: str) -> None:
        if self.quit_reason is None:
            self.quit_reason = reason
        if self._fig is not None and not self.opts.headless:
            import matplotlib.pyplot as plt
            plt.close(self._fig)

    def _done(self) -> str | None:
        if self.quit_reason:
            return self.quit_reason
        if self.opts.frames is not None and self.frames >= self.opts.frames:
            return f"{self.opts.frames} frames drawn"
        if self.opts.seconds is not None and time.monotonic() - self._t_begin >= self.opts.seconds:
            return f"{self.opts.seconds:g} s shown"
        return None

    # -------------------------------------------------------------- run --
    def run(self) -> ScopeSummary:
        import matplotlib
        if self.opts.headless:
            matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        if not self.opts.headless and not _interactive(matplotlib.get_backend()):
            raise ScopeError(f"no interactive matplotlib backend (got {matplotlib.get_backend()!r}): "
                             f"no display (DISPLAY unset), or tkinter missing (Debian: apt-get "
                             f"install python3-tk); or use --headless --frames N")
        self.setup()
        self._t_begin = time.monotonic()
        hb = threading.Thread(target=self._host_heartbeats, daemon=True, name="pmactl-scope-hb")
        if self.opts.host_heartbeat:
            hb.start()
        try:
            fig = self.build_figure()
            period_s = 1.0 / self.opts.fps
            if self.opts.headless:
                self._run_headless(fig, period_s)
            else:
                fig.canvas.mpl_connect("draw_event", self._on_draw)
                # matplotlib's own keys (s: a save dialog, p: pan, r: home view, ...) would
                # fight the scope's: the scope's keys only
                manager = fig.canvas.manager
                if manager is not None and getattr(manager, "key_press_handler_id", None) is not None:
                    fig.canvas.mpl_disconnect(manager.key_press_handler_id)
                fig.canvas.mpl_connect("key_press_event", self.on_key)
                fig.canvas.mpl_connect("close_event", lambda _e: self.stop("window closed"))
                timer = fig.canvas.new_timer(interval=max(1, int(period_s * 1000)))
                state = {"last": time.monotonic()}

                def step() -> None:
                    t0 = time.monotonic()
                    try:
                        self.draw_frame()
                    except KeyboardInterrupt:
                        self.stop("interrupted (Ctrl-C)")
                        return
                    reason = self._done()
                    if reason:
                        self.stop(reason)
                        timer.stop()
                        return
                    # the timer re-arms after the callback: aim at the period from start to start
                    work_ms = (time.monotonic() - t0) * 1000.0
                    timer.interval = max(1, int(period_s * 1000 - work_ms))
                    state["last"] = t0

                timer.add_callback(step)
                timer.start()
                try:
                    plt.show()
                except KeyboardInterrupt:
                    self.stop("interrupted (Ctrl-C)")
                timer.stop()
        finally:
            self._hb_stop.set()
            if hb.is_alive():
                hb.join(1.0)
            if self._recording:
                self.stop_recording()
            plt.close("all")
        elapsed = time.monotonic() - self._t_begin
        return ScopeSummary(frames=self.frames, elapsed_s=elapsed,
                            rows={n: tr.rows for n, tr in self.traces.items()},
                            recorded={n: tr.recorded_total for n, tr in self.traces.items()}, files=self.files,
                            stop_reason=self.quit_reason or self._done() or "window closed",
                            recent_fps=self.rate(), full_draws=self.full_draws,
                            drawing_s=(self._last_frame_t - self._first_frame_t)
                            if self._first_frame_t is not None else 0.0)

    def _run_headless(self, fig: Any, period_s: float) -> None:
        prefix = self.opts.png_prefix or Path("scope")
        next_t = time.monotonic()
        try:
            while not self._done():
                wait = next_t - time.monotonic()
                if wait > 0:
                    time.sleep(wait)
                next_t += period_s
                self.draw_frame()
                fig.savefig(f"{prefix}_{self.frames:04d}.png", dpi=self.opts.dpi)
        except KeyboardInterrupt:
            self.stop("interrupted (Ctrl-C)")


def _decode(node: PmaNode, name: str, msg: can.Message) -> dict[str, Any] | None:
    try:
        return node.proto.decode(name, bytes(msg.data))
    except Exception:           # noqa: BLE001 - cantools raises several kinds on bad data
        return None


def _interactive(backend: str) -> bool:
    b = backend.lower()
    return not (b in ("agg", "pdf", "ps", "svg", "pgf", "cairo", "template")
                or b.startswith("module://matplotlib_inline"))

