# SPDX-License-Identifier: Apache-2.0
"""Grouping telemetry into rows and recording it (TelemetryGrouper, TelemetryRecorder).
"""
from __future__ import annotations

import copy
import csv
import json
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable

import can

from pmactl.bus import NODE_REPLIES
from pmactl.errors import NodeStateError, NoReply, PmaError
from pmactl.node import HOST_HEARTBEAT_PERIOD_S, PmaNode, Status
from pmactl.protocol import TELEM_FRAMES, to_f32
from pmactl.recording import COLUMNS, header_row, row_cells

# --------------------------------------------------------------- telemetry --
# The signals of TELEM_A..E and the recording's columns (pmactl.recording.COLUMNS).
_TELEM_SIGNALS = {
    "TELEM_A": (("TimeMs", "t"), ("XCm", "x")),
    "TELEM_B": (("XrCm", "xr"), ("ECm", "e")),
    "TELEM_C": (("U", "u"), ("VCmS", "v")),
    "TELEM_D": (("Internal1", "internal1"), ("Internal2", "internal2")),
    "TELEM_E": (("PressureKpa", "p"), ("CtrlFlags", "ctrl_flags"), ("Breaches", "breaches")),
}


@dataclass
class TelemetryRow:
    """One telemetry tick: TELEM_A and the TELEM_B..E frames that followed it. Values
    are by column key (pmactl.recording.COLUMNS); frames not received are absent."""
    values: dict[str, float | int]
    frames: set[str]
    rx_time: float              # receive time of TELEM_A (s, the message's timestamp)

    @property
    def t_s(self) -> float:
        return float(self.values["t"])


class TelemetryGrouper:
    """Groups TELEM_A..E frames into rows: each TELEM_A starts a row, and the TELEM_B..E
    frames that follow it, until the next TELEM_A, belong to it. A row is complete when
    every frame of `mask` (telem.mask: bit 0 TELEM_A .. bit 4 TELEM_E) has arrived, and
    is returned then; an incomplete row is returned when the next TELEM_A comes or at
    flush(). Frames before the first TELEM_A, and repeats within a row, are counted as
    orphans."""

    def __init__(self, mask: int = 0x1F, period_ms: float | None = None) -> None:
        self.expected = {name for bit, name in enumerate(TELEM_FRAMES) if mask >> bit & 1}
        self.period_ms = period_ms      # nominal TimeMs step between rows, for counting gaps
        self.current: TelemetryRow | None = None
        self.rows = 0
        self.incomplete = 0
        self.orphans = 0
        self.lost = 0                   # rows missing by TimeMs (with period_ms)
        self._last_t: float | None = None

    def feed(self, name: str, sig: dict[str, Any], rx_time: float) -> list[TelemetryRow]:
        out: list[TelemetryRow] = []
        if name not in _TELEM_SIGNALS:
            return out
        if name == "TELEM_A":
            if self.current is not None:
                out.append(self._emit())
            self.current = TelemetryRow({}, set(), rx_time)
        elif self.current is None or name in self.current.frames:
            self.orphans += 1
            return out
        row = self.current
        assert row is not None
        row.frames.add(name)
        for signal, key in _TELEM_SIGNALS[name]:
            v = sig[signal]
            row.values[key] = v / 1000.0 if key == "t" else v
        if self.expected <= row.frames:
            out.append(self._emit())
        return out

    def flush(self) -> list[TelemetryRow]:
        return [self._emit()] if self.current is not None else []

    def _emit(self) -> TelemetryRow:
        row = self.current
        assert row is not None
        self.current = None
        self.rows += 1
        if not self.expected <= row.frames:
            self.incomplete += 1
        t_ms = row.t_s * 1000.0
        if self.period_ms and self._last_t is not None:
            steps = round((t_ms - self._last_t) / self.period_ms)
            if steps > 1:
                self.lost += steps - 1
        self._last_t = t_ms
        return row


@dataclass
class RecordProgress:
    elapsed_s: float            # wall clock since the recording began
    seconds: float | None       # the requested duration
    rows: int
    last: TelemetryRow | None


@dataclass
class RecordSummary:
    rows: int
    incomplete: int
    orphans: int
    lost: int
    frames_logged: int
    elapsed_s: float
    t_first_s: float | None
    t_last_s: float | None
    max_abs_e_cm: float | None
    breaches: int | None
    stop_reason: str
    final_status: Status | None
    csv_path: str
    log_path: str | None
    meta_path: str | None

    def as_dict(self) -> dict[str, Any]:
        d = {k: v for k, v in self.__dict__.items() if k != "final_status"}
        d["final_state"] = self.final_status.state_name if self.final_status else None
        d["final_fault"] = self.final_status.fault_name if self.final_status else None
        return d


def internal_labels(controller: str | None) -> tuple[tuple[str, str], tuple[str, str]]:
    """(name, unit) of TELEM_D's Internal1 and Internal2 for a controller (ctrl.mode name)."""
    return {
        "PPC": (("lambda1", "cm"), ("lambda2", "cm/s")),
        "MFAC": (("phi", "cm/input unit"), ("u_prev", "input unit")),
        "PID": (("i_term", "input unit"), ("d_term", "input unit")),
    }.get(controller or "", (("internal1", "-"), ("internal2", "-")))


class TelemetryRecorder:
    """Records a node's telemetry to a CSV file (one row per telemetry tick, units in the
    header: pmactl.recording), the frames it receives and sends to a python-can log (.blf,
    .asc or .log, chosen by the file name), and the run's parameters and summary to a JSON
    file next to the CSV. Sends HOST_HEARTBEAT while it runs. It receives only the node's
    replies, heartbeats and telemetry (filters: a 1 kHz plant bridge would otherwise flood
    it), unless all_frames."""

    def __init__(self, node: PmaNode, csv_path: str | Path, log_path: str | Path | None = None,
                 meta_path: str | Path | None = None, host_heartbeat: bool = True,
                 all_frames: bool = False) -> None:
        self.client = node
        self.csv_path = Path(csv_path)
        self.log_path = Path(log_path) if log_path else None
        self.meta_path = Path(meta_path) if meta_path else None
        self.host_heartbeat = host_heartbeat
        self.all_frames = all_frames     # receive (and log) every frame, not only the node's replies
        self.params: dict[str, float | int] = {}

    def run(self, seconds: float | None = None, samples: int | None = None, start: bool = False,
            progress: Callable[[RecordProgress], None] | None = None,
            progress_every_s: float = 0.2, first_timeout_s: float | None = None) -> RecordSummary:
        """Records until `seconds` (wall clock) have passed, `samples` rows were written,
        the node leaves RUNNING, or KeyboardInterrupt (which ends the recording normally:
        stop_reason says so). With start, sends START first and STOP at the end.

        NodeStateError when the node is not RUNNING (without start) or its telemetry is
        off; NoReply when no telemetry arrives within first_timeout_s (default: the
        client's timeout, at least 1 s)."""
        node = self.client
        saved_hb = node.host_heartbeat_s
        saved_filters = node.bus.filters
        if self.host_heartbeat:
            node.host_heartbeat_s = HOST_HEARTBEAT_PERIOD_S
        if not self.all_frames:
            node.listen_to(NODE_REPLIES + TELEM_FRAMES)
        try:
            return self._run(seconds, samples, start, progress, progress_every_s, first_timeout_s)
        finally:
            node.host_heartbeat_s = saved_hb
            node.bus.set_filters(saved_filters)

    def _run(self, seconds: float | None, samples: int | None, start: bool,
             progress: Callable[[RecordProgress], None] | None, progress_every_s: float,
             first_timeout_s: float | None) -> RecordSummary:
        node = self.client
        st = node.status()
        if st.state_name == "FAULT":
            raise NodeStateError(f"node {node.node} is in FAULT ({st.fault_name}): clear-faults first")
        if start and st.state_name != "ARMED":
            raise NodeStateError(f"node {node.node} is {st.state_name}, not ARMED: arm it before record --start")
        if not start and st.state_name != "RUNNING":
            raise NodeStateError(f"node {node.node} is {st.state_name}, not RUNNING: "
                                 f"use record --start (or start it first)")
        self.params = node.snapshot()
        mask = int(self.params.get("telem.mask", 0x1F))
        decimation = int(self.params.get("telem.decimation", 10))
        tick_hz = float(self.params.get("sys.tick_hz", 1000))
        if decimation == 0 or not mask & 1:
            raise NodeStateError(f"node {node.node} sends no telemetry to group: telem.decimation = "
                                 f"{decimation}, telem.mask = {mask} (needs bit 0, TELEM_A)")
        controller = node.proto.param("ctrl.mode").values.get(int(self.params.get("ctrl.mode", -1)))
        grouper = TelemetryGrouper(mask, period_ms=decimation * 1000.0 / tick_hz)
        labels = internal_labels(controller)

        pending: list[TelemetryRow] = []
        stats = {"written": 0, "frames_logged": 0}
        extremes: dict[str, Any] = {"max_e": None, "breaches": None, "first": None, "last": None,
                                    "t0_rx": None}
        # The node's state: from the heartbeats that arrive after the recording began
        # (after START with start=True); the recording ends when one shows another state.
        seen: dict[str, Status | None] = {"status": None if start else st}

        def on_frame(name: str, nid: int, sig: dict[str, Any], msg: can.Message) -> None:
            if nid != node.node:
                return
            if name == "HEARTBEAT" and nid in node.statuses:
                seen["status"] = node.statuses[nid]
            pending.extend(grouper.feed(name, sig, msg.timestamp))

        logger: can.Listener | None = None
        if self.log_path:
            self.log_path.parent.mkdir(parents=True, exist_ok=True)
            logger = can.Logger(str(self.log_path))

        def log_raw(msg: can.Message) -> None:
            if logger is not None:
                # The BLF writer takes a channel number from the digits of the channel name;
                # names without a small one (virtual buses) are logged on its default channel.
                ch = can.util.channel2int(msg.channel)
                if msg.channel is not None and (ch is None or not 0 <= ch < 255):
                    msg = copy.copy(msg)
                    msg.channel = None
                logger.on_message_received(msg)
                stats["frames_logged"] += 1

        def write_pending(w: Any) -> None:
            for row in pending:
                if extremes["t0_rx"] is None:
                    extremes["t0_rx"] = row.rx_time
                self._write(w, row, row.rx_time - extremes["t0_rx"])
                stats["written"] += 1
                if extremes["first"] is None:
                    extremes["first"] = row.t_s
                extremes["last"] = row
                if "e" in row.values:
                    e = abs(float(row.values["e"]))
                    extremes["max_e"] = e if extremes["max_e"] is None else max(extremes["max_e"], e)
                if "breaches" in row.values:
                    extremes["breaches"] = int(row.values["breaches"])
            pending.clear()

        self.csv_path.parent.mkdir(parents=True, exist_ok=True)
        stop_reason = ""
        started = False
        t_begin = time.monotonic()
        with self.csv_path.open("w", newline="") as f:
            w = csv.writer(f)
            w.writerow(header_row(labels))
            node.frame_listeners.append(on_frame)
            node.raw_listeners.append(log_raw)
            try:
                try:
                    if start:
                        node.start()
                        started = True
                        # a heartbeat sent before START was handled may have come in while
                        # waiting for its acknowledgement: only later ones tell the state
                        seen["status"] = None
                    t_begin = time.monotonic()
                    next_progress = t_begin
                    first_wait = first_timeout_s if first_timeout_s is not None else max(1.0, node.timeout_s)
                    while True:
                        now = time.monotonic()
                        if seconds is not None and now - t_begin >= seconds:
                            stop_reason = f"{seconds:g} s recorded"
                            break
                        if samples is not None and stats["written"] >= samples:
                            stop_reason = f"{samples} samples recorded"
                            grouper.current = None          # a row begun after the last one
                            break
                        if stats["written"] == 0 and now - t_begin > first_wait:
                            raise NoReply(f"no telemetry from node {node.node} within {first_wait:g} s")
                        cur = seen["status"]
                        if cur is not None and cur.state_name != "RUNNING":
                            fault = f" ({cur.fault_name})" if cur.fault else ""
                            stop_reason = f"node {node.node} left RUNNING: {cur.state_name}{fault}"
                            break
                        wait = 0.05
                        if seconds is not None:
                            wait = min(wait, max(0.0, t_begin + seconds - now))
                        node.receive(wait)
                        write_pending(w)
                        if progress and time.monotonic() >= next_progress:
                            progress(RecordProgress(time.monotonic() - t_begin, seconds, stats["written"],
                                                    extremes["last"]))
                            next_progress = time.monotonic() + progress_every_s
                    # the frames of the last telemetry tick are on their way: complete its row
                    grace = time.monotonic() + 0.1
                    while grouper.current is not None and time.monotonic() < grace:
                        node.receive(0.02)
                except KeyboardInterrupt:
                    stop_reason = "interrupted (Ctrl-C)"
                except NoReply:
                    if started:                  # do not leave a started node without a host
                        try:
                            node.stop()
                        except (PmaError, NoReply):
                            pass
                    raise
                write_pending(w)
                pending.extend(grouper.flush())
                write_pending(w)
                cur = seen["status"]
                if started and (cur is None or cur.state_name == "RUNNING"):
                    try:
                        node.stop()
                    except (PmaError, NoReply) as e:
                        stop_reason += f"; STOP failed: {e}"
            finally:
                node.frame_listeners.remove(on_frame)
                node.raw_listeners.remove(log_raw)
                if logger is not None:
                    logger.stop()
        elapsed = time.monotonic() - t_begin
        last_row: TelemetryRow | None = extremes["last"]
        if progress:
            progress(RecordProgress(elapsed, seconds, stats["written"], last_row))
        summary = RecordSummary(
            rows=stats["written"], incomplete=grouper.incomplete, orphans=grouper.orphans,
            lost=grouper.lost, frames_logged=stats["frames_logged"], elapsed_s=elapsed,
            t_first_s=extremes["first"], t_last_s=last_row.t_s if last_row else None,
            max_abs_e_cm=extremes["max_e"], breaches=extremes["breaches"], stop_reason=stop_reason,
            final_status=node.statuses.get(node.node), csv_path=str(self.csv_path),
            log_path=str(self.log_path) if self.log_path else None,
            meta_path=str(self.meta_path) if self.meta_path else None)
        if self.meta_path:
            self._write_meta(summary, controller, labels)
        return summary

    @staticmethod
    def _write(w: Any, row: TelemetryRow, rx_rel: float) -> None:
        w.writerow(row_cells(row.values, rx_rel))

    def _write_meta(self, summary: RecordSummary, controller: str | None,
                    labels: tuple[tuple[str, str], tuple[str, str]]) -> None:
        assert self.meta_path is not None
        proto = self.client.proto
        params = {}
        for name, value in self.params.items():
            p = proto.param(name)
            params[name] = p.values.get(int(value), value) if p.values else \
                (to_f32(float(value)) if p.type == "f32" else int(value))
        meta = {
            "format": "pmactl-recording 1",
            "node": self.client.node,
            "controller": controller,
            "internal1": {"name": labels[0][0], "unit": labels[0][1]},
            "internal2": {"name": labels[1][0], "unit": labels[1][1]},
            "columns": [{"key": c.key, "unit": c.unit} for c in COLUMNS],
            "summary": summary.as_dict(),
            "params": params,
            "units": {name: proto.param(name).unit for name in params},
        }
        self.meta_path.write_text(json.dumps(meta, indent=2) + "\n")
