# SPDX-License-Identifier: Apache-2.0
"""`pmactl commission`: the guided set-up of one node on a freshly wired rig, over CAN only
(docs/commissioning.md). The node runs OPEN_LOOP (u = ctrl.openloop_u, set live) while this
module steps the pressure and reads the position from the node's own telemetry; every time is
the node's control time (TELEM_A TimeMs), so the same procedure runs on a board in real time
and on a simulated rig in lockstep. The rules that turn the measurements into parameters are
in pmactl/commission_rules.py.

Steps: wiring check (sensor valid, noise at rest, a small pressure step moves x, its sign gives
act.polarity); static map (a pressure staircase up and down inside act.p_min..p_max, stopped
before x comes within a margin of the constraints); step responses at three operating points;
derivation. Whatever happens (done, refused, Ctrl-C, a fault, a lost node) the node is left
in its safe state (STOP, DISARM) with every parameter the procedure changed set back, unless
apply=True, which then SETs the derived parameters (save=True also SAVEs them).
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np

from .client import CommandError, NodeStateError, NoReply, PmaNode
from .commission_rules import (
    CommissionError,
    Derivation,
    Measured,
    StaticMap,
    StepFit,
    Task,
    band_problem,
    derive,
    fit_step,
)

# what the procedure changes on the node (set back at the end unless applied)
TOUCHED = ("ctrl.mode", "ctrl.openloop_u", "ctrl.u_min", "ctrl.u_max", "act.p0_kpa", "act.polarity",
           "telem.decimation", "telem.mask", "ref.kind", "ref.offset_cm")
OPEN_LOOP = 4               # ctrl.mode
TELEM_MASK = 0x11           # TELEM_A (time, x) and TELEM_E (pressure, flags)
SETTLE_S = 1.5              # after START at the preset pressure (ARM slews there)
REST_S = 0.5                # noise at rest
MOVE_S = 1.0                # the direction step's hold
LEVELS = 10                 # static map: levels per direction
LEVEL_S = 0.6               # hold per level; x is the mean of its last third
STEP_S = 1.0                # each step response
STEP_FRAC = 0.05            # step size, of act.p_min..p_max
NOISE_MAX_CM = 0.05         # a noisier sensor at rest is refused
MOVE_MIN_CM = 0.005         # the direction step must move x at least this much (and 6 sigma)


# what to check when the node faults while commissioning runs (FaultCode names, the DBC)
FAULT_HINTS = {
    "POSITION_LIMIT": "x left safety.x_min_cm..x_max_cm (less safety.x_margin_cm): a noisy sensor or a wrong "
                      "adc.* scaling (compare x above with where the muscle is), or a band that leaves the muscle "
                      "too little room",
    "SENSOR_RANGE": "the sensor read outside adc.raw_min_counts..raw_max_counts: check its wiring, its supply and "
                    "those limits",
    "SENSOR_WIRE_BREAK": "the sensor's signal fell below adc.wire_break_below_counts: check its wiring and supply",
    "SENSOR_READ": "the ADC did not read: check the sensor's input",
    "SENSOR_TIMEOUT": "no sample for safety.sensor_timeout_ticks: check the sensor, or the plant bridge's samples",
    "HOST_HEARTBEAT_LOST": "the node heard no host heartbeat for safety.host_timeout_ms: check the bus",
    "ESTOP": "the emergency stop was pressed",
}


class CommissionAborted(RuntimeError):
    """The procedure stopped before it ended (the reason is the message); the node is safe."""


@dataclass
class Recording:
    t_s: list[float] = field(default_factory=list)
    x_cm: list[float] = field(default_factory=list)
    p_kpa: list[float] = field(default_factory=list)


@dataclass
class Result:
    measured: Measured
    derivation: Derivation
    recordings: dict[str, Recording]
    rig_time_s: float
    wall_s: float
    applied: bool = False
    saved: bool = False

    def report(self) -> dict[str, Any]:
        m = self.measured
        return {"derivation": self.derivation.as_dict(),
                "measured": {"polarity_measured": m.polarity_measured, "noise_cm": m.noise_cm,
                             "static_map": vars(m.static_map),
                             "steps": [vars(s) for s in m.steps]},
                "rig_time_s": self.rig_time_s, "wall_s": self.wall_s,
                "applied": self.applied, "saved": self.saved}


class Commissioning:
    """One run of the procedure on `node` (a PmaNode with host heartbeats on)."""

    def __init__(self, node: PmaNode, task: Task, progress: Callable[[str, float], None] | None = None,
                 timeout_s: float = 2.0) -> None:
        self.node = node
        self.task = task
        user_progress = progress or (lambda what, frac: None)
        self.phase = "start"         # what the procedure was doing (the last progress), for an abort's message

        def progress_and_phase(what: str, frac: float) -> None:
            self.phase = what
            user_progress(what, frac)
        self.progress = progress_and_phase
        self.timeout_s = timeout_s
        self.saved: dict[str, float | int] = {}
        self.recordings: dict[str, Recording] = {}
        self._row: dict[str, float] = {}
        self.t_now = 0.0
        self.x_now = math.nan
        self.p_now = math.nan
        if node.host_heartbeat_s is None:
            node.host_heartbeat_s = 0.1

    # ------------------------------------------------------------ running --
    def run(self, apply: bool = False, save: bool = False) -> Result:
        wall0 = time.monotonic()
        node = self.node
        t = self.task
        # before anything moves (pmactl checks the same as options, x_start too). The reference's
        # start is not checked here: where it lies outside the reachable band, the derivation
        # takes the start's holding input at the band's edge and says so
        problem = band_problem(t.x_min_cm, t.x_max_cm, t.w1_cm)
        if problem is not None:
            raise CommissionError(f"the task: {problem}")
        st = node.status(self.timeout_s)
        if st.state_name != "IDLE":
            raise NodeStateError(f"node {node.node} is {st.state_name}"
                                 + (f" ({st.fault_name})" if st.fault_name != "NONE" else "")
                                 + ": commissioning starts from IDLE (pmactl stop / disarm / clear-faults)")
        if "SENSOR_VALID" not in st.flag_names:
            raise CommissionError("the position sensor reads invalid (wire break, out of range or no sample): "
                                  "check its wiring, supply and the adc.* scaling")
        for name in TOUCHED:
            self.saved[name] = node.get(name)
        self.p_min = float(node.get("act.p_min_kpa"))
        self.p_max = float(node.get("act.p_max_kpa"))
        self.kpa_per_u = float(node.get("act.kpa_per_u"))
        self.period_s = 1.0 / float(node.get("sys.tick_hz"))
        # one ADC count in cm: the finest position step the loop can see
        self.resolution_cm = abs(float(node.get("adc.gain_cm_per_count")))
        # the node's band [cm]: the HOLD reference START checks, and what a RANGE refusal names
        self.band_cm = (float(node.get("safety.x_min_cm")), float(node.get("safety.x_max_cm")))
        self.margin_cm = max(0.1, 0.5 * self.task.w1_cm)
        ok = False
        try:
            measured, t_rig = self._measure()
            derivation = derive(measured, self.task)
            self._clamp_to_ranges(derivation)
            ok = True
        finally:
            self._safe(quiet=not ok)
        applied = saved = False
        if apply:
            for name, value in _apply_order(derivation.params):
                node.set(name, value)
            applied = True
            if save:
                node.save()
                saved = True
        return Result(measured, derivation, self.recordings, t_rig, time.monotonic() - wall0, applied, saved)

    def _clamp_to_ranges(self, d: Derivation) -> None:
        """Every derived value inside its parameter's range as the node reports it (GET_MIN,
        GET_MAX); a value that had to be clamped is reported."""
        for name, value in list(d.params.items()):
            lo, hi, _ = self.node.info(name)
            if not lo <= value <= hi:
                clamped = min(max(value, lo), hi)
                d.warnings.append(f"{name} = {value:g} is outside its range {lo:g}..{hi:g}: set to {clamped:g}")
                d.params[name] = type(value)(clamped)

    def _measure(self) -> tuple[Measured, float]:
        node = self.node
        # u is the pressure change from p0 in kPa while measuring: polarity +1, 1 kPa per unit
        p0 = min(max(float(self.saved["act.p0_kpa"]), self.p_min), self.p_max)
        node.set("act.polarity", 1)
        node.set("act.p0_kpa", p0)
        self.p0 = p0
        self.p_cmd = p0
        self.dxdp_sign = 0          # unknown until the direction step
        node.set("ctrl.u_min", (self.p_min - p0) / self.kpa_per_u)
        node.set("ctrl.u_max", (self.p_max - p0) / self.kpa_per_u)
        node.set("ctrl.mode", OPEN_LOOP)
        node.set("ctrl.openloop_u", 0.0)
        node.set("ref.kind", 0)
        # OPEN_LOOP does not follow the reference, but START checks it against the band in every
        # mode: HOLD at the band's middle, whatever the task's reference was left at
        node.set("ref.offset_cm", 0.5 * (self.band_cm[0] + self.band_cm[1]))
        node.set("telem.decimation", 1)
        node.set("telem.mask", TELEM_MASK)
        self._command("ARM", node.arm)
        self._command("START", node.start)
        t_start = self._wait_s(0.05)
        # --- wiring: the noise at rest, then which way a small step moves x
        self.progress("wiring check", 0.0)
        self._hold(p0, SETTLE_S, "settle")
        rest = self._hold(p0, REST_S, "rest")
        x_rest = float(np.mean(rest.x_cm))
        # the noise: what a straight line through the samples leaves (a slow creep is no noise)
        t_rest = np.asarray(rest.t_s) - rest.t_s[0]
        still = len(set(rest.x_cm)) == 1    # one value on every sample (a line's residue is then ~1e-16, not 0)
        noise_rest = 0.0 if still else float(
            np.std(np.asarray(rest.x_cm) - np.polyval(np.polyfit(t_rest, rest.x_cm, 1), t_rest)))
        if noise_rest > NOISE_MAX_CM:
            raise CommissionError(f"the position noise at rest is {noise_rest:.4f} cm (over {NOISE_MAX_CM} cm): check "
                                  "the sensor's shielding, ground and target")
        # what the loop sees is never quieter than the ADC's quantisation (one count, uniform: its
        # standard deviation is a count over sqrt(12)); a still muscle on a quiet sensor reads less
        # at rest, down to one value on every sample, which is not yet a stuck sensor
        noise = max(noise_rest, self.resolution_cm / math.sqrt(12.0))
        dp = max(0.1 * (self.p_max - self.p_min), 20.0)
        p_move = p0 + dp if p0 + dp <= self.p_max else p0 - dp
        moved = self._hold(p_move, MOVE_S, "direction")
        dx = float(np.mean(moved.x_cm[-len(moved.x_cm) // 5:])) - x_rest
        if still and set(moved.x_cm) == set(rest.x_cm):
            raise CommissionError(f"the position reads the same value on every sample, at rest and after a pressure "
                                  f"step of {p_move - p0:+.0f} kPa: a stuck or saturated sensor (check its output "
                                  "and the ADC input), or nothing moves (check the air supply and the regulator)")
        if abs(dx) < max(MOVE_MIN_CM, 6.0 * noise):
            raise CommissionError(f"a pressure step of {p_move - p0:+.0f} kPa moved x by {dx:+.4f} cm: nothing moves. "
                                  "Check the air supply, the regulator's command wiring and the dac.* scaling")
        polarity = 1 if dx * (p_move - p0) > 0 else -1
        self.dxdp_sign = polarity
        # --- static map: a staircase from the bottom of the range to the top and back
        self.progress("static map", 0.15)
        static = self._static_map()
        # --- step responses at three operating points inside the reachable range
        self.progress("step responses", 0.6)
        steps = self._steps(static, noise)
        self.progress("derivation", 0.95)
        t_rig = self.t_now - t_start
        return Measured(polarity_measured=polarity, noise_cm=noise, static_map=static, steps=steps,
                        period_s=self.period_s, kpa_per_u=self.kpa_per_u, p_min_kpa=self.p_min,
                        p_max_kpa=self.p_max, noise_rest_cm=noise_rest, resolution_cm=self.resolution_cm), t_rig

    def _static_map(self) -> StaticMap:
        """A staircase on LEVELS pressures over act.p_min..p_max: up from p0 to the top (or to
        the last level before x comes within the margin of a constraint), down from there to
        the bottom (the same stop), up again to the top: the descending and the ascending
        branch over the same reachable range. A level where x came near a constraint is left
        at once and not kept."""
        grid = list(np.linspace(self.p_min, self.p_max, LEVELS))
        above = [p for p in grid if p > self.p0]
        top = self.p0
        for p in above:
            if not self._level(p, "map")[0]:
                break
            top = p
        self._level(top, "map")
        down_p: list[float] = []
        down_x: list[float] = []
        for p in [q for q in reversed(grid) if q <= top]:
            heading = self._heading(p)
            ok, x = self._level(p, "map")
            if not ok:
                if self._heading_into(x, heading):
                    break
                continue        # still near the constraint it moves away from (hysteresis, creep)
            down_p.append(p)
            down_x.append(x)
            self.progress("static map", 0.15 + 0.22 * len(down_p) / LEVELS)
        if len(down_p) < 3:
            raise CommissionError(f"the position comes within {self.margin_cm:g} cm of a constraint at all but "
                                  f"{len(down_p)} of {LEVELS} pressure levels: the constraints leave no stroke to map "
                                  "(check safety.x_min_cm / x_max_cm and the sensor's zero), or the pressure range "
                                  f"act.p_min_kpa..p_max_kpa = {self.p_min:g}..{self.p_max:g} kPa does not move the "
                                  "muscle clear of them")
        up_p: list[float] = []
        up_x: list[float] = []
        for p in reversed(down_p):
            ok, x = self._level(p, "map")
            if not ok:          # near a constraint on this branch (hysteresis): not kept
                continue
            up_p.append(p)
            up_x.append(x)
            self.progress("static map", 0.37 + 0.22 * len(up_p) / len(down_p))
        if len(up_p) < 3:
            raise CommissionError("the ascending branch stays near a constraint: the hysteresis leaves no stroke "
                                  "to map inside the constraints")
        return StaticMap(up_p, up_x, list(reversed(down_p)), list(reversed(down_x)))

    def _level(self, p_kpa: float, label: str) -> tuple[bool, float]:
        """Hold one level: (False, its last x) when x came near a constraint, else (True, x at its
        end)."""
        rec = self._hold(p_kpa, LEVEL_S, label, stop_near_limits=True)
        if self._beyond(rec.x_cm[-1]) or len(rec.x_cm) < 3:
            return False, rec.x_cm[-1]
        return True, float(np.mean(rec.x_cm[-len(rec.x_cm) // 3:]))

    def _steps(self, static: StaticMap, noise_cm: float) -> list[StepFit]:
        lo, hi = static.stroke_cm()
        fits: list[StepFit] = []
        dp = STEP_FRAC * (self.p_max - self.p_min)
        for k, frac in enumerate((0.3, 0.5, 0.7)):
            x_op = lo + frac * (hi - lo)
            p_op = static.hold_kpa(x_op)
            p_op = min(max(p_op, self.p_min + dp), self.p_max - dp)
            self._hold(p_op, STEP_S, "settle")
            for sign in (1.0, -1.0):
                rec = self._hold(p_op + sign * dp, STEP_S, f"step{k}{'+' if sign > 0 else '-'}",
                                 stop_near_limits=True)
                t = np.asarray(rec.t_s) - rec.t_s[0]
                fits.append(fit_step(t, np.asarray(rec.x_cm), p_op, sign * dp, noise_cm=noise_cm))
                self._hold(p_op, 0.3 * STEP_S, "settle")
            self.progress("step responses", 0.6 + 0.35 * (k + 1) / 3)
        return fits

    # -------------------------------------------------------------- helpers --
    def _command(self, what: str, send: Callable[[], object]) -> None:
        """ARM or START for the open-loop measurements; a refusal is a CommissionError that says
        what to check (the node is left as the procedure found it)."""
        try:
            send()
        except CommandError as e:
            if e.name == "RANGE":
                lo, hi = self.band_cm
                raise CommissionError(
                    f"the node refused {what} (RANGE): the muscle must rest inside the band safety.x_min_cm.."
                    f"x_max_cm = {lo:g}..{hi:g} cm before anything moves (check the band against where the "
                    "vented muscle rests, and the sensor's zero adc.offset_cm), or a rule between parameters is "
                    "broken (pmactl counters LAST_RULE)") from e
            raise CommissionError(f"the node refused {what} ({e.name}): check pmactl status, the sensor's "
                                  "wiring and the rig's samples") from e

    def _hold(self, p_kpa: float, seconds: float, label: str, stop_near_limits: bool = False) -> Recording:
        """Command p_kpa and record x for `seconds` of control time (from the next sample)."""
        p = min(max(p_kpa, self.p_min), self.p_max)
        heading = self._heading(p)
        self.p_cmd = p
        self.node.set("ctrl.openloop_u", (p - self.p0) / self.kpa_per_u)
        rec = Recording()
        t_end: float | None = None
        while True:
            self._next_row()
            if t_end is None:
                t_end = self.t_now + seconds
            rec.t_s.append(self.t_now)
            rec.x_cm.append(self.x_now)
            rec.p_kpa.append(self.p_now)
            # near a constraint while this level moves x towards it: leave at once (a level
            # that moves x away from one it starts near is held, and judged at its end)
            if stop_near_limits and self._heading_into(self.x_now, heading):
                break
            if self.t_now >= t_end:
                break
        self.recordings.setdefault(label, Recording())
        r = self.recordings[label]
        r.t_s += rec.t_s
        r.x_cm += rec.x_cm
        r.p_kpa += rec.p_kpa
        return rec

    def _heading(self, p_kpa: float) -> int:
        """Which way commanding p_kpa moves x (+1 up, -1 down, 0 unknown or no change): the sign
        of the pressure change times dx/dp's."""
        p = min(max(p_kpa, self.p_min), self.p_max)
        return self.dxdp_sign * (1 if p > self.p_cmd else -1 if p < self.p_cmd else 0)

    def _depth(self, x: float) -> float:
        """How far x is inside the margin of the nearer constraint [cm] (<= 0: clear of both)."""
        return max(self.task.x_min_cm + self.margin_cm - x, x - (self.task.x_max_cm - self.margin_cm))

    def _beyond(self, x: float) -> bool:
        return self._depth(x) > 0.0

    def _heading_into(self, x: float, heading: int) -> bool:
        """x is within the margin of the constraint that `heading` (+1: x rising) moves it to."""
        if heading > 0:
            return x >= self.task.x_max_cm - self.margin_cm
        if heading < 0:
            return x <= self.task.x_min_cm + self.margin_cm
        return False

    def _wait_s(self, seconds: float) -> float:
        self._next_row()
        t_end = self.t_now + seconds
        while self.t_now < t_end:
            self._next_row()
        return self.t_now

    def _next_row(self) -> None:
        """The next telemetry group (TELEM_A, then TELEM_E of the same tick)."""
        deadline = time.monotonic() + self.timeout_s
        while time.monotonic() < deadline:
            r = self.node.receive(self.timeout_s)
            if r is None:
                continue
            name, nid, sig, _ = r
            if nid != self.node.node:
                continue
            if name == "HEARTBEAT":
                state = self.node.proto.state_names.get(int(sig["State"]), str(sig["State"]))
                if state != "RUNNING":
                    fault = self.node.statuses[nid].fault_name
                    where = f" during the {self.phase}" + (f" at x = {self.x_now:.3f} cm" if math.isfinite(self.x_now)
                                                           else "")
                    hint = f": {FAULT_HINTS[fault]}" if fault in FAULT_HINTS else ""
                    raise CommissionAborted(f"the node left RUNNING{where}: {state}"
                                            + (f" (fault {fault}){hint}" if fault != "NONE" else ""))
            elif name == "TELEM_A":
                self._row = {"t": float(sig["TimeMs"]) / 1000.0, "x": float(sig["XCm"])}
            elif name == "TELEM_E" and "t" in self._row:
                self.t_now, self.x_now, self.p_now = self._row["t"], self._row["x"], float(sig["PressureKpa"])
                self._row = {}
                return
        raise CommissionAborted(f"no telemetry from node {self.node.node} for {self.timeout_s:g} s: the node or the "
                                "bus is lost")

    def _safe(self, quiet: bool) -> None:
        """STOP and DISARM (the node vents or holds as safety.safe_mode says), then the touched
        parameters back. On the way out after an error nothing here may hide that error."""
        node = self.node
        for command in ("STOP", "DISARM"):
            try:
                node.command(command, check=False)
            except (NoReply, OSError):
                if not quiet:
                    raise
        for name, value in self.saved.items():
            try:
                node.set(name, value)
            except Exception:
                if not quiet:
                    raise


def _apply_order(params: dict[str, float | int]) -> list[tuple[str, float | int]]:
    """The derived parameters in an order every rule between parameters accepts (the actuator
    first, then the output range, then the rest)."""
    first = ["act.polarity", "act.p0_kpa", "safety.x_min_cm", "safety.x_max_cm", "ctrl.u_min", "ctrl.u_max"]
    return [(n, params[n]) for n in first if n in params] + [(n, v) for n, v in params.items() if n not in first]
