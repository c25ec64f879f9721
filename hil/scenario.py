# SPDX-License-Identifier: Apache-2.0
"""HIL scenarios: data files (TOML) that say what the rig is, how the firmware is
configured over CAN, which controllers run side by side, what happens during the
run, and what the run must end in.

A scenario file (hil/scenarios/*.toml, docs/hil.md has the full reference):

    name = "case3"
    title = "..."
    duration_s = 180.0           # control time after START
    quick_duration_s = 30.0      # --quick
    windows = [[5, 30], [30, 60]]  # RMSTE windows [s]
    paper = "table2"             # optional: the paper's figures to print beside ours
    seed = 1                     # the rig's sensor noise

    [rig]                        # RigParams overrides (hil/rig_params.py), nested
    p0_kpa = 60.0

    [params]                     # firmware parameters for every controller, set over CAN
    "act.polarity" = -1

    [reference]                  # ref.kind and its ref.* parameters
    kind = "CASE3"

    [[controllers]]              # one firmware node each, on its own identical rig
    label = "ppc"
    mode = "PPC"
    params = { "ppc.w1_cm" = 0.2 }

    [[controllers]]              # a lane whose set comes from `pmactl commission` on its rig
    label = "mfac"               # (hil run/offline --commission); only the task's own
    mode = "MFAC"                # parameters here (COMMISSION_TASK_PARAMS)
    commission = true

    [[events]]                   # rig or host actions at a control time
    t_s = 20.0
    action = "disturbance"
    value = 40.0                 # N

    [expect]                     # how the run must end (checked and written to summary.json)
    state = "RUNNING"
    fault_code = "NONE"

Everything is validated when loaded: an unknown key, a parameter the table does
not have, a value outside its range or a bad event is a ScenarioError naming the
file and the key, before anything starts.
"""
from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from pmactl.protocol import Protocol, load_protocol
from pmactl.rules import broken_rule

from .rig_params import RigParams

# the parameters the rules a SET enforces involve (docs/parameters.md, rules 1-5)
RULE_PARAMS = ("adc.gain_cm_per_count", "adc.raw_min_counts", "adc.raw_max_counts",
               "adc.wire_break_below_counts", "dac.counts_per_kpa", "dac.min_counts", "dac.max_counts")

# What a commissioned lane's file may give: the task's own parameters (accuracy, tuning time, the
# band check); everything else comes from commissioning, the node-wide input set-up included
COMMISSION_TASK_PARAMS = ("ppc.w1_cm", "ppc.t_u_s", "ppc.band_check")
COMMISSIONED_NODE_WIDE = ("act.polarity", "act.p0_kpa", "ctrl.u_min", "ctrl.u_max")
COMMISSION_MODES = ("PPC", "MFAC")

SCENARIO_DIR = Path(__file__).resolve().parent / "scenarios"

# Rig and host actions an event can take (value: its unit).
EVENT_ACTIONS: dict[str, str] = {
    "load_mass": "kg: the moving load mass from now on",
    "bias_force": "N: a constant pull on the free end from now on",
    "disturbance": "N: the disturbance cylinder's force, switched on now (0: off)",
    "wire_break": "1: the sensor's wire breaks (0: repaired)",
    "sensor_block": "1: the laser loses its target (0: back)",
    "host_heartbeat": "0: the host stops sending HOST_HEARTBEAT (1: resumes)",
}
REFERENCE_KINDS = ("HOLD", "STEP", "SINE", "CASE1", "CASE3")
_TOP_KEYS = {"base", "name", "title", "description", "duration_s", "quick_duration_s", "windows", "paper", "seed",
             "rig", "params", "reference", "controllers", "events", "expect", "settle_s", "armed_s"}


class ScenarioError(ValueError):
    """A scenario file that cannot be run as written."""


@dataclass(frozen=True)
class Controller:
    label: str                      # the name in reports (e.g. "ppc", "ppc-paper", "mfac")
    mode: str                       # ctrl.mode: PPC, MFAC, PID, OPEN_LOOP, OFF
    params: dict[str, float | int]  # firmware parameters of this controller only
    description: str = ""
    # commission = true in the file: the lane's set comes from `pmactl commission` on its own rig
    # (hil run/offline --commission); the file gives only the task's own parameters
    commission: bool = False
    derived: bool = False           # params hold a commissioning's derivation (hil/commissioned.py)


@dataclass(frozen=True)
class Event:
    t_s: float
    action: str
    value: float


@dataclass(frozen=True)
class Expect:
    state: str = "RUNNING"
    fault_code: str = "NONE"
    start_result: str = "OK"        # the START command's result (e.g. "BAND": refused)


@dataclass
class Scenario:
    name: str
    title: str
    description: str
    path: Path | None
    duration_s: float
    quick_duration_s: float
    windows: list[tuple[float, float]]
    paper: str | None
    seed: int
    rig: dict[str, Any]
    params: dict[str, float | int]
    reference: dict[str, Any]
    controllers: list[Controller]
    events: list[Event]
    expect: Expect
    settle_s: float = 0.5           # idle ticks before ARM (rig vented, samples flowing)
    armed_s: float = 1.0            # ARMED at the preset pressure before START

    # ---------------------------------------------------------------- derived --
    def rig_params(self) -> RigParams:
        return RigParams.from_dict(self.rig)

    def node_params(self, ctrl: Controller) -> dict[str, float | int]:
        """Every firmware parameter for one controller's node, in the order they
        are set: the rig's wiring (adc.*, dac.*), the scenario's, the reference's,
        the controller's."""
        proto = protocol()
        wiring = self.rig_params().firmware_scaling()
        wiring.pop("act.p0_kpa", None)  # the preset pressure is the scenario's choice (see docs/hil.md)
        out: dict[str, float | int] = {}
        for name, value in wiring.items():
            p = proto.param(name)
            out[name] = float(value) if p.type == "f32" else int(round(value))
        out.update({k: v for k, v in self.params.items() if not (ctrl.commission and k in COMMISSIONED_NODE_WIDE)})
        out.update({f"ref.{k}": v for k, v in self.reference.items() if k != "kind"})
        out["ref.kind"] = proto.param("ref.kind").check(self.reference_kind())
        out["ctrl.mode"] = proto.param("ctrl.mode").check(ctrl.mode)
        out.update(ctrl.params)
        return {k: proto.param(k).check(v) for k, v in out.items()}

    def needs_commissioning(self) -> list[str]:
        """The lanes whose set comes from commissioning and has not been derived yet."""
        return [c.label for c in self.controllers if c.commission and not c.derived]

    def reference_kind(self) -> str:
        return str(self.reference.get("kind", "HOLD")).upper()

    def t_u_s(self, ctrl: Controller) -> float | None:
        """The tuning time of a PPC node (None for others)."""
        if ctrl.mode != "PPC":
            return None
        merged = {**self.params, **ctrl.params}
        return float(merged.get("ppc.t_u_s", _PROTO_DEFAULT("ppc.t_u_s")))

    def w1_cm(self, ctrl: Controller) -> float:
        merged = {**self.params, **ctrl.params}
        return float(merged.get("ppc.w1_cm", _PROTO_DEFAULT("ppc.w1_cm")))

    def band_cm(self) -> tuple[float, float]:
        """The output constraint k_low < x < k_high (safety.x_min_cm, safety.x_max_cm)."""
        lo = float(self.params.get("safety.x_min_cm", _PROTO_DEFAULT("safety.x_min_cm")))
        hi = float(self.params.get("safety.x_max_cm", _PROTO_DEFAULT("safety.x_max_cm")))
        return lo, hi

    def duration(self, quick: bool) -> float:
        return self.quick_duration_s if quick else self.duration_s

    def windows_for(self, duration_s: float) -> list[tuple[float, float]]:
        """The RMSTE windows that fit in a run of this length (a quick run keeps
        the first ones, the last one cut at the end)."""
        out = []
        for t0, t1 in self.windows:
            if t0 < duration_s:
                out.append((t0, min(t1, duration_s)))
        return out


_PROTO: Protocol | None = None


def protocol() -> Protocol:
    global _PROTO
    if _PROTO is None:
        _PROTO = load_protocol()
    return _PROTO


def _PROTO_DEFAULT(name: str) -> float:
    return float(protocol().param(name).default)


# ------------------------------------------------------------------- loading --
def find(name_or_path: str) -> Path:
    """A scenario by name (hil/scenarios/NAME.toml) or by path."""
    p = Path(name_or_path)
    if p.suffix == ".toml" and p.exists():
        return p
    q = SCENARIO_DIR / f"{name_or_path}.toml"
    if q.exists():
        return q
    names = ", ".join(available())
    raise ScenarioError(f"no scenario {name_or_path!r} (a .toml path or one of: {names})")


def available() -> list[str]:
    """Scenario names (files starting with _ are bases that scenarios build on)."""
    return sorted(p.stem for p in SCENARIO_DIR.glob("*.toml") if not p.name.startswith("_"))


def _merge(base: dict[str, Any], over: dict[str, Any]) -> dict[str, Any]:
    """over on top of base; tables (rig, params, ...) merged key by key, lists replaced."""
    out = dict(base)
    for k, v in over.items():
        out[k] = _merge(out[k], v) if isinstance(v, dict) and isinstance(out.get(k), dict) else v
    return out


def _read(path: Path, seen: tuple[Path, ...] = ()) -> dict[str, Any]:
    """A scenario file's table, on top of its `base` file (a path relative to it) if any."""
    if path in seen:
        raise ScenarioError(f"{path}: base files include each other")
    try:
        data = tomllib.loads(path.read_text())
    except tomllib.TOMLDecodeError as e:
        raise ScenarioError(f"{path}: not valid TOML: {e}") from e
    except OSError as e:
        raise ScenarioError(f"{path}: {e.strerror}") from e
    base = data.pop("base", None)
    if base is None:
        return data
    return _merge(_read(path.parent / str(base), (*seen, path)), data)


def load(name_or_path: str) -> Scenario:
    path = find(name_or_path)
    data = _read(path)
    data["name"] = path.stem          # a scenario is named by its file
    return parse(data, path)


def _num(where: str, v: Any, lo: float = -math.inf, hi: float = math.inf) -> float:
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
        raise ScenarioError(f"{where}: expected a finite number, got {v!r}")
    if not lo <= v <= hi:
        raise ScenarioError(f"{where}: {v} outside [{lo:g}, {hi:g}]")
    return float(v)


def _check_params(where: str, params: Any) -> dict[str, float | int]:
    """Firmware parameters by name, each checked against the table (range, type,
    enum names such as ctrl.mode = "PPC" turned into their numbers)."""
    if not isinstance(params, dict):
        raise ScenarioError(f"{where}: expected a table of parameter = value")
    proto = protocol()
    out: dict[str, float | int] = {}
    for key, value in params.items():
        try:
            p = proto.param(key)
        except (KeyError, ValueError) as e:
            raise ScenarioError(f"{where}: unknown firmware parameter {key!r}") from e
        try:
            out[p.name] = p.check(value)
        except (ValueError, TypeError) as e:
            raise ScenarioError(f"{where}.{key}: {e}") from e
    return out


def parse(data: dict[str, Any], path: Path | None = None) -> Scenario:
    where = str(path) if path else "scenario"
    unknown = set(data) - _TOP_KEYS
    if unknown:
        raise ScenarioError(f"{where}: unknown key(s) {', '.join(sorted(unknown))}")
    for key in ("name", "duration_s", "controllers"):
        if key not in data:
            raise ScenarioError(f"{where}: missing {key!r}")
    duration = _num(f"{where}: duration_s", data["duration_s"], 0.01, 3600.0)
    quick = _num(f"{where}: quick_duration_s", data.get("quick_duration_s", min(duration, 10.0)), 0.01, duration)
    windows: list[tuple[float, float]] = []
    for i, w in enumerate(data.get("windows", [[0.0, duration]])):
        if not (isinstance(w, list) and len(w) == 2):
            raise ScenarioError(f"{where}: windows[{i}] must be [t0, t1]")
        t0 = _num(f"{where}: windows[{i}][0]", w[0], 0.0, duration)
        t1 = _num(f"{where}: windows[{i}][1]", w[1], t0, duration)
        if t1 <= t0:
            raise ScenarioError(f"{where}: windows[{i}] is empty")
        windows.append((t0, t1))

    rig = data.get("rig", {})
    try:
        RigParams.from_dict(rig)
    except (ValueError, TypeError) as e:
        raise ScenarioError(f"{where}: [rig]: {e}") from e

    params = _check_params(f"{where}: [params]", data.get("params", {}))
    reference = dict(data.get("reference", {"kind": "HOLD"}))
    kind = str(reference.get("kind", "HOLD")).upper()
    if kind not in REFERENCE_KINDS:
        raise ScenarioError(f"{where}: [reference] kind {kind!r} not one of {', '.join(REFERENCE_KINDS)}")
    reference["kind"] = kind
    _check_params(f"{where}: [reference]", {f"ref.{k}": v for k, v in reference.items() if k != "kind"})

    controllers: list[Controller] = []
    labels: set[str] = set()
    raw_ctrls = data["controllers"]
    if not isinstance(raw_ctrls, list) or not raw_ctrls:
        raise ScenarioError(f"{where}: [[controllers]]: at least one")
    if len(raw_ctrls) > 15:
        raise ScenarioError(f"{where}: at most 15 controllers (one CAN node id each)")
    for i, c in enumerate(raw_ctrls):
        cw = f"{where}: controllers[{i}]"
        extra = set(c) - {"label", "mode", "params", "description", "commission"}
        if extra:
            raise ScenarioError(f"{cw}: unknown key(s) {', '.join(sorted(extra))}")
        label = str(c.get("label", ""))
        if not label or not label.replace("-", "").replace("_", "").isalnum() or label in labels:
            raise ScenarioError(f"{cw}: label must be a unique name of letters, digits, - and _")
        labels.add(label)
        mode = str(c.get("mode", "")).upper()
        if mode not in protocol().param("ctrl.mode").values.values():
            raise ScenarioError(f"{cw}: mode {mode!r} is not a ctrl.mode value")
        cparams = _check_params(f"{cw}.params", c.get("params", {}))
        commission = c.get("commission", False)
        if not isinstance(commission, bool):
            raise ScenarioError(f"{cw}: commission must be true or false")
        if commission:
            if mode not in COMMISSION_MODES:
                raise ScenarioError(f"{cw}: commission = true needs mode {' or '.join(COMMISSION_MODES)}")
            beyond = sorted(set(cparams) - set(COMMISSION_TASK_PARAMS))
            if beyond:
                raise ScenarioError(f"{cw}: a commissioned lane gives only the task's own parameters "
                                    f"({', '.join(COMMISSION_TASK_PARAMS)}); not {', '.join(beyond)}")
        controllers.append(Controller(label, mode, cparams, str(c.get("description", "")), commission))

    events: list[Event] = []
    for i, ev in enumerate(data.get("events", [])):
        ew = f"{where}: events[{i}]"
        if set(ev) - {"t_s", "action", "value"}:
            raise ScenarioError(f"{ew}: unknown key(s) {', '.join(sorted(set(ev) - {'t_s', 'action', 'value'}))}")
        action = str(ev.get("action", ""))
        if action not in EVENT_ACTIONS:
            raise ScenarioError(f"{ew}: action {action!r} not one of {', '.join(EVENT_ACTIONS)}")
        events.append(Event(_num(f"{ew}.t_s", ev.get("t_s"), 0.0, duration),
                            action, _num(f"{ew}.value", ev.get("value"), -1e4, 1e4)))
    events.sort(key=lambda e: e.t_s)

    ex = data.get("expect", {})
    if set(ex) - {"state", "fault_code", "start_result"}:
        raise ScenarioError(f"{where}: [expect]: unknown key(s)")
    proto = protocol()
    expect = Expect(str(ex.get("state", "RUNNING")).upper(), str(ex.get("fault_code", "NONE")).upper(),
                    str(ex.get("start_result", "OK")).upper())
    if expect.state not in proto.state_names.values():
        raise ScenarioError(f"{where}: [expect] state {expect.state!r} unknown")
    if expect.fault_code not in proto.enum_names("HEARTBEAT", "FaultCode").values():
        raise ScenarioError(f"{where}: [expect] fault_code {expect.fault_code!r} unknown")

    scenario = Scenario(
        name=str(data["name"]), title=str(data.get("title", data["name"])),
        description=str(data.get("description", "")), path=path, duration_s=duration,
        quick_duration_s=quick, windows=windows, paper=data.get("paper"),
        seed=int(data.get("seed", 1)), rig=rig, params=params, reference=reference,
        controllers=controllers, events=events, expect=expect,
        settle_s=_num(f"{where}: settle_s", data.get("settle_s", 0.5), 0.05, 60.0),
        armed_s=_num(f"{where}: armed_s", data.get("armed_s", 1.0), 0.05, 60.0),
    )
    _check_rules(where, scenario)
    return scenario


def _check_rules(where: str, scenario: "Scenario") -> None:
    """What the node would refuse: every controller's whole set (the defaults, the rig's
    wiring, the scenario's and the controller's parameters) must keep every rule between
    parameters (docs/parameters.md), the ones SET enforces and the ones ARM checks."""
    proto = protocol()
    defaults = {p.name: p.default for p in proto.params}
    for ctrl in scenario.controllers:
        values = {**defaults, **scenario.node_params(ctrl)}
        rule = broken_rule(values)
        if rule in (6, 8, 11, 12) and ctrl.commission and not ctrl.derived:
            rule = 0        # the input set-up is commissioning's (polarity, p0, u range)
        if rule:
            names = {1: "adc.gain_cm_per_count != 0",
                     2: "adc.raw_min_counts <= adc.raw_max_counts",
                     3: "adc.wire_break_below_counts <= adc.raw_min_counts",
                     4: "dac.counts_per_kpa != 0", 5: "dac.min_counts <= dac.max_counts",
                     6: "act.polarity is -1 or +1", 7: "0 <= act.p_min_kpa < act.p_max_kpa",
                     8: "act.p_min_kpa <= act.p0_kpa <= act.p_max_kpa",
                     9: "safety.safe_kpa <= act.p_max_kpa (FIXED)",
                     10: "safety.x_min_cm < safety.x_max_cm", 11: "ctrl.u_min < ctrl.u_max",
                     12: "p0 + polarity * kpa_per_u * u within act.p_min_kpa..p_max_kpa "
                         "for u = ctrl.u_min, ctrl.u_max"}
            raise ScenarioError(f"{where}: controller {ctrl.label}: the parameter set breaks rule "
                                f"{rule} ({names[rule]}; docs/parameters.md), which the node refuses")
