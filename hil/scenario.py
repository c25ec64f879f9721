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

from .report import PAPER
from .rig_params import RigParams

# the parameters the rules a SET enforces involve (docs/parameters.md, rules 1-5)
RULE_PARAMS = ("adc.gain_cm_per_count", "adc.raw_min_counts", "adc.raw_max_counts",
               "adc.wire_break_below_counts", "dac.counts_per_kpa", "dac.min_counts", "dac.max_counts")

# What a commissioned lane's file may give: the task's own parameters (accuracy, tuning time, the
# band check); everything else comes from commissioning, the node-wide input set-up included
COMMISSION_TASK_PARAMS = ("ppc.w1_cm", "ppc.t_u_s", "ppc.band_check")
COMMISSIONED_NODE_WIDE = ("act.polarity", "act.p0_kpa", "ctrl.u_min", "ctrl.u_max")
# the user's limits: with the rig's wiring, what a freshly wired node knows before commissioning,
# and what commissioning keeps within (the pressure range it sweeps, the band it stays clear of)
USER_LIMITS = ("act.p_min_kpa", "act.p_max_kpa", "safety.x_min_cm", "safety.x_max_cm")
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
    # hil run/offline --commission --noise-limit K: the commissioning's bound on the input's
    # motion from the sensor's noise (pmactl commission --noise-limit; None: none)
    noise_limit: float | None = None

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
    """A scenario file's table, on top of its `base` file if any: a path relative to it, or a
    shipped scenario's name (hil/scenarios/NAME.toml, e.g. "case3" or "realistic/dmsp10/case3")."""
    if path in seen:
        raise ScenarioError(f"{path}: base files include each other")
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except tomllib.TOMLDecodeError as e:
        raise ScenarioError(f"{path}: not valid TOML: {e}") from e
    except UnicodeDecodeError as e:
        raise ScenarioError(f"{path}: not UTF-8 text (TOML is UTF-8): at byte {e.start}") from e
    except OSError as e:
        raise ScenarioError(f"{path}: {e.strerror or e}") from e
    base = data.pop("base", None)
    if base is None:
        return data
    base_text = _text(f"{path}: base", base)
    base_path = path.parent / base_text
    if not base_path.is_file():
        # a user's own file outside hil/scenarios builds on a shipped one by its name
        shipped = SCENARIO_DIR / f"{base_text}.toml"
        if Path(base_text).suffix or not shipped.is_file():
            raise ScenarioError(f"{path}: base: no file {base_path}, and {base_text!r} is not a shipped scenario's "
                                f"name (hil/scenarios: {', '.join(available())}, or realistic/PROFILE/NAME)")
        base_path = shipped
    return _merge(_read(base_path, (*seen, path)), data)


def load(name_or_path: str) -> Scenario:
    path = find(name_or_path)
    data = _read(path)
    data["name"] = path.stem          # a scenario is named by its file
    return parse(data, path)


# ------------------------------------------------------- the file's schema --
# Every value of a scenario file goes through one of these typed checks: a wrong type or a
# value outside its range is a ScenarioError naming the key and what it expects.
SEED_MAX = 2**63 - 1                # numpy's generator takes any non-negative integer; JSON keeps 63 bits
# events whose value is a switch: 1 on, 0 off (EVENT_ACTIONS)
SWITCH_EVENTS = ("wire_break", "sensor_block", "host_heartbeat")


def _type_name(v: Any) -> str:
    return {dict: "a table", list: "an array", str: "text", bool: "true/false"}.get(type(v), type(v).__name__)


def _num(where: str, v: Any, lo: float = -math.inf, hi: float = math.inf) -> float:
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
        raise ScenarioError(f"{where}: expected a finite number, got {v!r}")
    if not lo <= v <= hi:
        raise ScenarioError(f"{where}: {v} outside [{lo:g}, {hi:g}]")
    return float(v)


def _text(where: str, v: Any, choices: tuple[str, ...] | None = None, upper: bool = False) -> str:
    """Text (upper: case-insensitive, returned in upper case), one of `choices` if given."""
    if not isinstance(v, str):
        raise ScenarioError(f"{where}: expected text{_one_of(choices)}, got {_type_name(v)} {v!r}")
    t = v.upper() if upper else v
    if choices is not None and t not in choices:
        raise ScenarioError(f"{where}: {v!r} is not{_one_of(choices)[1:]}")
    return t


def _one_of(choices: tuple[str, ...] | None) -> str:
    return "" if choices is None else f", one of {', '.join(choices)}"


def _flag(where: str, v: Any) -> bool:
    if not isinstance(v, bool):
        raise ScenarioError(f"{where}: expected true or false, got {v!r}")
    return v


def _table(where: str, v: Any) -> dict[str, Any]:
    if not isinstance(v, dict):
        raise ScenarioError(f"{where}: expected a table, got {_type_name(v)} {v!r}")
    return v


def _array(where: str, v: Any, of_tables: bool = False) -> list[Any]:
    if not isinstance(v, list):
        raise ScenarioError(f"{where}: expected an array{' of tables' if of_tables else ''}, "
                            f"got {_type_name(v)} {v!r}")
    if of_tables:
        for i, item in enumerate(v):
            _table(f"{where}[{i}]", item)
    return v


def _keys(where: str, table: dict[str, Any], allowed: set[str]) -> None:
    unknown = set(table) - allowed
    if unknown:
        raise ScenarioError(f"{where}: unknown key(s) {', '.join(sorted(unknown))} "
                            f"(known: {', '.join(sorted(allowed))})")


def check_seed(where: str, v: Any) -> int:
    """The rig's sensor-noise seed: an integer 0..SEED_MAX (ScenarioError otherwise)."""
    if isinstance(v, bool) or not isinstance(v, int) or not 0 <= v <= SEED_MAX:
        raise ScenarioError(f"{where}: expected an integer >= 0 (at most 2**63 - 1), got {v!r}")
    return v


def result_names() -> tuple[str, ...]:
    """The names a command's result can have (COMMAND_ACK Result: OK, BAND, ...)."""
    return tuple(protocol().status_names.values())


def check_rig(where: str, rig: Any) -> dict[str, Any]:
    """A [rig] table: every value typed and in range (RigParams.from_dict)."""
    table = _table(where, rig)
    try:
        RigParams.from_dict(table)
    except (ValueError, TypeError) as e:
        raise ScenarioError(f"{where}: {e}") from e
    return table


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


def _event(ew: str, ev: dict[str, Any], duration: float) -> Event:
    _keys(ew, ev, {"t_s", "action", "value"})
    for key in ("t_s", "action", "value"):
        if key not in ev:
            raise ScenarioError(f"{ew}: missing {key!r}")
    action = _text(f"{ew}.action", ev["action"], tuple(EVENT_ACTIONS))
    t_s = _num(f"{ew}.t_s", ev["t_s"], 0.0, duration)
    if action in SWITCH_EVENTS:
        value = ev["value"]
        if isinstance(value, bool) or value not in (0, 1):
            raise ScenarioError(f"{ew}.value: expected 1 or 0 for {action} ({EVENT_ACTIONS[action]}), "
                                f"got {value!r}")
        return Event(t_s, action, float(value))
    value_f = _num(f"{ew}.value", ev["value"], -1e4, 1e4)
    if action == "load_mass" and not value_f > 0:
        raise ScenarioError(f"{ew}.value: load_mass must be > 0 kg, got {value_f:g}")
    return Event(t_s, action, value_f)


def parse(data: dict[str, Any], path: Path | None = None) -> Scenario:
    where = str(path) if path else "scenario"
    data = _table(where, data)
    _keys(where, data, _TOP_KEYS)
    for key in ("name", "duration_s", "controllers"):
        if key not in data:
            raise ScenarioError(f"{where}: missing {key!r}")
    name = _text(f"{where}: name", data["name"])
    title = _text(f"{where}: title", data.get("title", name))
    description = _text(f"{where}: description", data.get("description", ""))
    paper = data.get("paper")
    if paper is not None:
        paper = _text(f"{where}: paper", paper, tuple(PAPER))
    seed = check_seed(f"{where}: seed", data.get("seed", 1))
    duration = _num(f"{where}: duration_s", data["duration_s"], 0.01, 3600.0)
    quick = _num(f"{where}: quick_duration_s", data.get("quick_duration_s", min(duration, 10.0)), 0.01, duration)
    windows: list[tuple[float, float]] = []
    for i, w in enumerate(_array(f"{where}: windows", data.get("windows", [[0.0, duration]]))):
        if not (isinstance(w, list) and len(w) == 2):
            raise ScenarioError(f"{where}: windows[{i}] must be [t0, t1], got {w!r}")
        t0 = _num(f"{where}: windows[{i}][0]", w[0], 0.0, duration)
        t1 = _num(f"{where}: windows[{i}][1]", w[1], t0, duration)
        if t1 <= t0:
            raise ScenarioError(f"{where}: windows[{i}] is empty")
        windows.append((t0, t1))

    rig = check_rig(f"{where}: [rig]", data.get("rig", {}))

    params = _check_params(f"{where}: [params]", data.get("params", {}))
    reference = dict(_table(f"{where}: [reference]", data.get("reference", {"kind": "HOLD"})))
    reference["kind"] = _text(f"{where}: [reference] kind", reference.get("kind", "HOLD"), REFERENCE_KINDS,
                              upper=True)
    _check_params(f"{where}: [reference]", {f"ref.{k}": v for k, v in reference.items() if k != "kind"})

    controllers: list[Controller] = []
    labels: set[str] = set()
    raw_ctrls = _array(f"{where}: controllers", data["controllers"], of_tables=True)
    if not raw_ctrls:
        raise ScenarioError(f"{where}: [[controllers]]: at least one")
    if len(raw_ctrls) > 15:
        raise ScenarioError(f"{where}: at most 15 controllers (one CAN node id each)")
    modes = tuple(protocol().param("ctrl.mode").values.values())
    for i, c in enumerate(raw_ctrls):
        cw = f"{where}: controllers[{i}]"
        _keys(cw, c, {"label", "mode", "params", "description", "commission"})
        label = _text(f"{cw}.label", c.get("label", ""))
        if not label or not label.replace("-", "").replace("_", "").isalnum() or label in labels:
            raise ScenarioError(f"{cw}: label must be a unique name of letters, digits, - and _")
        labels.add(label)
        mode = _text(f"{cw}.mode", c.get("mode", ""), modes, upper=True)
        cparams = _check_params(f"{cw}.params", c.get("params", {}))
        commission = _flag(f"{cw}.commission", c.get("commission", False))
        if commission:
            if mode not in COMMISSION_MODES:
                raise ScenarioError(f"{cw}: commission = true needs mode {' or '.join(COMMISSION_MODES)}")
            beyond = sorted(set(cparams) - set(COMMISSION_TASK_PARAMS))
            if beyond:
                raise ScenarioError(f"{cw}: a commissioned lane gives only the task's own parameters "
                                    f"({', '.join(COMMISSION_TASK_PARAMS)}); not {', '.join(beyond)}")
        controllers.append(Controller(label, mode, cparams, _text(f"{cw}.description", c.get("description", "")),
                                      commission))

    events = [_event(f"{where}: events[{i}]", ev, duration)
              for i, ev in enumerate(_array(f"{where}: events", data.get("events", []), of_tables=True))]
    events.sort(key=lambda e: e.t_s)

    ex = _table(f"{where}: [expect]", data.get("expect", {}))
    _keys(f"{where}: [expect]", ex, {"state", "fault_code", "start_result"})
    proto = protocol()
    expect = Expect(
        _text(f"{where}: [expect] state", ex.get("state", "RUNNING"), tuple(proto.state_names.values()), upper=True),
        _text(f"{where}: [expect] fault_code", ex.get("fault_code", "NONE"),
              tuple(proto.enum_names("HEARTBEAT", "FaultCode").values()), upper=True),
        _text(f"{where}: [expect] start_result", ex.get("start_result", "OK"), result_names(), upper=True))

    scenario = Scenario(
        name=name, title=title, description=description, path=path, duration_s=duration,
        quick_duration_s=quick, windows=windows, paper=paper, seed=seed, rig=rig, params=params,
        reference=reference, controllers=controllers, events=events, expect=expect,
        settle_s=_num(f"{where}: settle_s", data.get("settle_s", 0.5), 0.05, 60.0),
        armed_s=_num(f"{where}: armed_s", data.get("armed_s", 1.0), 0.05, 60.0),
    )
    check_rules(where, scenario)
    return scenario


def check_rules(where: str, scenario: "Scenario") -> None:
    """What the node would refuse: every controller's whole set (the defaults, the rig's
    wiring, the scenario's and the controller's parameters) must keep every rule between
    parameters (docs/parameters.md), the ones SET enforces and the ones ARM checks.
    Run on a file's scenario and again on one changed by options (hil/offline.py)."""
    proto = protocol()
    defaults = {p.name: p.default for p in proto.params}
    for ctrl in scenario.controllers:
        try:
            node = scenario.node_params(ctrl)
        except (ValueError, TypeError) as e:     # e.g. the rig's wiring outside a parameter's range
            raise ScenarioError(f"{where}: controller {ctrl.label}: {e}") from e
        values = {**defaults, **node}
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
