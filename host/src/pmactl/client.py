# SPDX-License-Identifier: Apache-2.0
"""The protocol client: one class, used by pmactl, the HIL harness and the tests.

PmaNode talks to one node over any python-can bus (socketcan, pcan, kvaser,
slcan, virtual, ...). It is synchronous: each request waits for its reply and
drops unrelated frames, except heartbeats, which it keeps (the last one per
node) for status queries. Every frame it receives or sends is also passed to
its listeners (``frame_listeners``: decoded protocol frames; ``raw_listeners``:
every can.Message, e.g. a can.Logger), so a recorder sees the frames that
arrive while a request waits for its reply.

Besides PmaNode: opening a bus from python-can's configuration (open_bus),
finding nodes (scan), watching a bus (BusMonitor) and recording telemetry
(TelemetryGrouper, TelemetryRecorder).
"""
from __future__ import annotations

import copy
import csv
import json
import math
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Iterable

import can

from pmactl import adapters
from pmactl.protocol import BASE_ID_MASK, BROADCASTS, TELEM_FRAMES, Param, Protocol, load_protocol, to_f32
from pmactl.recording import COLUMNS, header_row, row_cells

TYPE_CODES = {"f32": 0, "u32": 1, "i32": 2}
TYPE_SIGNALS = {0: "ValueF32", 1: "ValueU32", 2: "ValueI32"}
TYPE_NAMES = {v: k for k, v in TYPE_CODES.items()}
OPS = {"GET": 0, "SET": 1, "SAVE": 2, "RESTORE_DEFAULTS": 3, "GET_MIN": 4, "GET_MAX": 5,
       "GET_DEFAULT": 6, "NEXT_ID": 7, "LOAD": 8}

DEFAULT_INTERFACE = "socketcan"
DEFAULT_CHANNEL = "vcan0"           # only when the interface is socketcan
HOST_HEARTBEAT_PERIOD_S = 0.1       # 10 Hz, well inside the default safety.host_timeout_ms (500 ms)


# ------------------------------------------------------------------ errors --
class PmaError(Exception):
    """A request the node answered with an error code (negative pma_status_t)."""

    def __init__(self, what: str, code: int, name: str) -> None:
        super().__init__(f"{what}: {name} ({code})")
        self.what = what
        self.code = code
        self.name = name


class CommandError(PmaError):
    """A COMMAND answered with an error code."""


class SetRejected(PmaError):
    """A parameter SET the node refused; `current` is the value it kept."""

    def __init__(self, what: str, code: int, name: str, param: Param | None = None,
                 requested: float | int | None = None, current: float | int | None = None) -> None:
        super().__init__(what, code, name)
        self.param = param
        self.requested = requested
        self.current = current


class NoReply(TimeoutError):
    """No reply within the timeout."""


class InterfaceError(Exception):
    """The CAN interface could not be opened (or failed)."""


class NodeStateError(Exception):
    """The node is not in a state (or configuration) that allows the request."""


# ---------------------------------------------------------------- the bus --
def bus_config(interface: str | None = None, channel: str | None = None,
               bitrate: int | None = None, context: str | None = None,
               config_file: str | None = None) -> dict[str, Any]:
    """The bus configuration: the given values, then python-can's own configuration
    (can.rc, CAN_INTERFACE / CAN_CHANNEL / CAN_BITRATE / CAN_CONFIG, ~/.canrc and the
    other files of can.util.load_config), and only what is still unset defaults:
    interface socketcan, and channel vcan0 when the interface is socketcan.

    InterfaceError for an unknown interface name."""
    given: dict[str, Any] = {k: v for k, v in (("interface", interface), ("channel", channel),
                                                 ("bitrate", bitrate)) if v is not None}
    if "interface" not in given:
        sources: list[dict[str, Any]] = [dict(can.rc), can.util.load_environment_config(context),
                                         can.util.load_environment_config(),
                                         can.util.load_file_config(config_file, context or "default"),
                                         can.util.load_file_config(config_file)]
        if not any(src.get("interface") or src.get("bustype") for src in sources):
            given["interface"] = DEFAULT_INTERFACE
    try:
        cfg = dict(can.util.load_config(path=config_file, config=given, context=context))
    except can.CanInterfaceNotImplementedError as e:
        known = ", ".join(sorted(can.interfaces.VALID_INTERFACES))
        name = str(given.get("interface") or "")
        hint = adapters.unknown_interface_hint(name) if name else ""
        raise InterfaceError(f"bad CAN configuration: {e} (python-can knows: {known})"
                             + (f"\n  {hint}" if hint else "")) from e
    except (ValueError, TypeError) as e:
        raise InterfaceError(f"bad CAN configuration: {e}") from e
    if cfg.get("channel") is None and cfg.get("interface") == DEFAULT_INTERFACE:
        cfg["channel"] = DEFAULT_CHANNEL
    return {k: v for k, v in cfg.items() if v is not None}


def describe_bus(cfg: dict[str, Any]) -> str:
    text = f"{cfg.get('interface')} {cfg.get('channel', '(default channel)')}"
    if cfg.get("bitrate"):
        text += f" at {int(cfg['bitrate'])} bit/s"
    return text


def open_bus(cfg: dict[str, Any]) -> can.BusABC:
    """can.Bus(**cfg); InterfaceError with python-can's reason when it cannot be opened
    (python-can raises CanError or OSError on open, ImportError for a missing driver) and
    the step that fixes it (pmactl.adapters.explain)."""
    try:
        return can.Bus(**cfg)
    except KeyboardInterrupt:
        raise
    except Exception as e:      # a driver without its library raises about anything
        hint = adapters.explain(cfg, e)
        reason = str(e) or type(e).__name__
        raise InterfaceError(f"cannot open CAN interface {describe_bus(cfg)}: {reason}"
                             + (f"\n  {hint}" if hint else "")) from e


# Messages a node sends: what a client listens to.
NODE_REPLIES = ("COMMAND_ACK", "PARAM_RESP", "HEARTBEAT", "DEVICE_INFO")


def frame_filters(proto: Protocol, messages: Iterable[str], node: int | None = None) -> list[dict[str, Any]]:
    """python-can receive filters for the given messages, of one node (None: every node).
    On a busy bus (a plant bridge at 1 kHz) a client that receives every frame can fall
    behind and lose frames in its socket; filters (in the kernel for socketcan) avoid it."""
    out: list[dict[str, Any]] = []
    for m in messages:
        base = proto.messages[m].frame_id
        if m in BROADCASTS:
            out.append({"can_id": base, "can_mask": 0x7FF, "extended": False})
        elif node is None:
            out.append({"can_id": base, "can_mask": BASE_ID_MASK, "extended": False})
        else:
            out.append({"can_id": base | node, "can_mask": 0x7FF, "extended": False})
    return out


# ----------------------------------------------------------------- replies --
@dataclass(frozen=True)
class Ack:
    command: int
    arg: int
    result: int
    state: int


@dataclass(frozen=True)
class ParamReply:
    op: int
    id: int
    type: int
    result: int
    value: float | int


@dataclass(frozen=True)
class Status:
    """One HEARTBEAT, decoded (numbers and their names from the DBC)."""
    node: int
    state: int
    fault: int
    flags: int
    controller: int
    reference: int
    reset_cause: int
    counter: int
    state_name: str
    fault_name: str
    flag_names: tuple[str, ...]
    controller_name: str
    reference_name: str
    reset_cause_name: str
    time: float = 0.0                  # time.monotonic() when received

    @classmethod
    def from_signals(cls, proto: Protocol, node: int, sig: dict[str, Any],
                     t: float | None = None) -> "Status":
        def name(sig_name: str, value: int) -> str:
            return proto.enum_names("HEARTBEAT", sig_name).get(value, str(value))
        vals = {k: int(sig[k]) for k in ("State", "FaultCode", "Flags", "Controller", "Reference",
                                         "ResetCause", "Counter")}
        return cls(node=node, state=vals["State"], fault=vals["FaultCode"], flags=vals["Flags"],
                   controller=vals["Controller"], reference=vals["Reference"],
                   reset_cause=vals["ResetCause"], counter=vals["Counter"],
                   state_name=name("State", vals["State"]),
                   fault_name=name("FaultCode", vals["FaultCode"]),
                   flag_names=tuple(proto.flag_names(vals["Flags"])),
                   controller_name=name("Controller", vals["Controller"]),
                   reference_name=name("Reference", vals["Reference"]),
                   reset_cause_name=name("ResetCause", vals["ResetCause"]),
                   time=time.monotonic() if t is None else t)

    def summary(self) -> str:
        fault = f", fault {self.fault_name}" if self.fault else ""
        return (f"{self.state_name}{fault}, controller {self.controller_name}, "
                f"reference {self.reference_name}")


@dataclass(frozen=True)
class ParamInfo:
    """A parameter as the node reports it (GET, GET_MIN, GET_MAX, GET_DEFAULT), with its
    table row (name, unit) when this package knows the id."""
    id: int
    type: int
    value: float | int
    min: float | int
    max: float | int
    default: float | int
    param: Param | None = None

    @property
    def name(self) -> str:
        return self.param.name if self.param else f"#{self.id}"

    @property
    def unit(self) -> str:
        return self.param.unit if self.param else "?"

    def text(self, value: float | int) -> str:
        if self.param:
            return self.param.text(value)
        return f"{value:.7g}" if isinstance(value, float) else str(value)


@dataclass
class LoadReport:
    """What PmaNode.load_values did, per parameter."""
    changed: list[tuple[Param, float | int, float | int]] = field(default_factory=list)  # old, new
    unchanged: list[Param] = field(default_factory=list)
    rejected: list[SetRejected] = field(default_factory=list)


# ------------------------------------------------------------------ client --
FrameListener = Callable[[str, int, dict[str, Any], can.Message], None]
RawListener = Callable[[can.Message], None]


class PmaNode:
    def __init__(self, bus: can.BusABC, node: int = 0, protocol: Protocol | None = None,
                 timeout_s: float = 1.0, host_heartbeat_s: float | None = None) -> None:
        self.bus = bus
        self.node = node
        self.proto = protocol or load_protocol()
        self.timeout_s = timeout_s
        self.heartbeats: dict[int, dict[str, Any]] = {}
        self.statuses: dict[int, Status] = {}
        self.frame_listeners: list[FrameListener] = []
        self.raw_listeners: list[RawListener] = []
        # While set, every wait sends HOST_HEARTBEAT to the node this often (keeps a
        # RUNNING node from faulting with HOST_HEARTBEAT_LOST); None: never.
        self.host_heartbeat_s = host_heartbeat_s
        # The time base of those heartbeats: the bus's own clock when it has one (a simulated
        # bus in control time, hil/offline_bus.py), else the wall clock.
        self.clock: Callable[[], float] = getattr(bus, "clock", time.monotonic)
        self._next_host_heartbeat = 0.0
        self._host_heartbeat_counter = 0

    # ------------------------------------------------------------ frames --
    def listen_to(self, messages: Iterable[str] | None, node: int | None = -1) -> None:
        """Receive only these messages (of this client's node by default; None: of every
        node); messages=None receives everything again."""
        if messages is None:
            self.bus.set_filters(None)
        else:
            self.bus.set_filters(frame_filters(self.proto, messages, self.node if node == -1 else node))  # type: ignore[arg-type]

    def send(self, message: str, data: dict[str, Any] | None = None, node: int | None = None) -> None:
        payload = self.proto.encode(message, data)
        self.send_raw(self.proto.frame_id(message, self.node if node is None else node), payload)

    def send_raw(self, frame_id: int, payload: bytes) -> None:
        msg = can.Message(arbitration_id=frame_id, data=payload, is_extended_id=False,
                          timestamp=time.time(), is_rx=False)
        self.bus.send(msg)
        for listener in self.raw_listeners:
            listener(msg)

    def _keep_alive(self) -> float | None:
        """Sends HOST_HEARTBEAT when due; the time to the next one (None: off)."""
        if self.host_heartbeat_s is None:
            return None
        now = self.clock()
        if now >= self._next_host_heartbeat:
            self.host_heartbeat(self._host_heartbeat_counter)
            self._host_heartbeat_counter = (self._host_heartbeat_counter + 1) & 0xFF
            self._next_host_heartbeat = now + self.host_heartbeat_s
        return max(0.0, self._next_host_heartbeat - self.clock())

    def receive(self, timeout_s: float | None = None) -> tuple[str, int, dict[str, Any], can.Message] | None:
        """The next frame of the protocol (any node) as (message, node, signals, raw).

        None when nothing came within the timeout (or earlier, when a host heartbeat
        is due), or the frame is not a protocol frame."""
        wait = self.timeout_s if timeout_s is None else timeout_s
        due = self._keep_alive()
        if due is not None:
            wait = min(wait, due)
        msg = self.bus.recv(max(0.0, wait))
        if msg is None:
            return None
        for raw in self.raw_listeners:
            raw(msg)
        if msg.is_extended_id or msg.is_error_frame or msg.is_remote_frame:
            return None
        found = self.proto.message_of(msg.arbitration_id)
        if found is None:
            return None
        name, node = found
        try:
            sig = self.proto.decode(name, bytes(msg.data)) if len(msg.data) else {}
        except Exception:  # wrong length or undecodable: not for us to interpret
            return None
        if name == "HEARTBEAT":
            self.heartbeats[node] = sig
            try:
                self.statuses[node] = Status.from_signals(self.proto, node, sig)
            except (KeyError, TypeError, ValueError):
                pass
        for listener in self.frame_listeners:
            listener(name, node, sig, msg)
        return name, node, sig, msg

    def wait_for(self, message: str, pred: Callable[[dict[str, Any]], bool] | None = None,
                 timeout_s: float | None = None, node: int | None = None) -> dict[str, Any]:
        """Signals of the next `message` from the node that satisfies pred."""
        want_node = self.node if node is None else node
        deadline = time.monotonic() + (self.timeout_s if timeout_s is None else timeout_s)
        while True:
            left = deadline - time.monotonic()
            if left <= 0:
                raise NoReply(f"no {message} from node {want_node} within "
                              f"{self.timeout_s if timeout_s is None else timeout_s:g} s")
            got = self.receive(left)
            if got is None:
                continue
            name, node_id, sig, _ = got
            if name == message and node_id == want_node and (pred is None or pred(sig)):
                return sig

    # ---------------------------------------------------------- commands --
    def command(self, command: str | int, arg: int = 0, check: bool = True) -> Ack:
        code = self.proto.commands[command] if isinstance(command, str) else int(command)
        self.send("COMMAND", {"Command": code, "Arg": arg})
        sig = self.wait_for("COMMAND_ACK", lambda s: s["Command"] == code and s["Arg"] == arg)
        ack = Ack(sig["Command"], sig["Arg"], sig["Result"], sig["State"])
        if check and ack.result < 0:
            raise CommandError(f"command {command}", ack.result, self.proto.status_name(ack.result))
        return ack

    def arm(self) -> Ack: return self.command("ARM")
    def disarm(self) -> Ack: return self.command("DISARM")
    def start(self) -> Ack: return self.command("START")
    def stop(self) -> Ack: return self.command("STOP")
    def clear_faults(self) -> Ack: return self.command("CLEAR_FAULTS")

    def restart(self, timeout_s: float = 10.0) -> Status:
        """RESTART: a software reset of the node (only with its output inactive; unsaved
        parameter changes are lost). Returns the first heartbeat after its start-up (BOOT),
        once it is out of BOOT; NoReply if it does not come back within timeout_s."""
        self.command("RESTART")
        boot = {v: k for k, v in self.proto.state_names.items()}["BOOT"]
        self.wait_for("HEARTBEAT", lambda s: s["State"] == boot, timeout_s=timeout_s)
        sig = self.wait_for("HEARTBEAT", lambda s: s["State"] != boot, timeout_s=timeout_s)
        return Status.from_signals(self.proto, self.node, sig)

    def estop(self, all_nodes: bool = False) -> None:
        """Emergency stop (no reply: watch the heartbeat)."""
        self.send("ESTOP_ALL" if all_nodes else "ESTOP")

    def select_controller(self, name: str | int) -> Ack:
        return self.command("SELECT_CONTROLLER", self._enum("ctrl.mode", name))

    def select_reference(self, name: str | int) -> Ack:
        return self.command("SELECT_REFERENCE", self._enum("ref.kind", name))

    def _enum(self, param: str, name: str | int) -> int:
        p = self.proto.param(param)
        if isinstance(name, int):
            if name not in p.values:
                raise ValueError(f"{param}: no value {name} (one of {', '.join(p.values.values())})")
            return name
        for k, v in p.values.items():
            if v == name.strip().upper():
                return k
        if name.strip().isdigit() and int(name) in p.values:
            return int(name)
        raise ValueError(f"{param}: no value {name!r} (one of {', '.join(p.values.values())})")

    def state_name(self, state: int) -> str:
        return self.proto.state_names.get(state, str(state))

    # -------------------------------------------------------- parameters --
    def param_request(self, op: str | int, pid: int = 0, type_code: int = 0,
                      value: float | int = 0) -> ParamReply:
        opc = OPS[op] if isinstance(op, str) else int(op)
        data = {"Op": opc, "Type": type_code, "Id": pid, "Reserved": 0, TYPE_SIGNALS[type_code]: value}
        self.send("PARAM_REQ", data)
        sig = self.wait_for("PARAM_RESP", lambda s: s["Op"] == opc and s["Id"] == pid)
        t = int(sig["Type"])
        return ParamReply(opc, pid, t, int(sig["Result"]), sig.get(TYPE_SIGNALS.get(t, ""), 0))

    def _checked(self, what: str, r: ParamReply) -> ParamReply:
        if r.result < 0:
            raise PmaError(what, r.result, self.proto.status_name(r.result))
        return r

    def get(self, key: str | int) -> float | int:
        p = self.proto.param(key)
        return self._checked(f"get {p.name}", self.param_request("GET", p.id, TYPE_CODES[p.type])).value

    def set(self, key: str | int, value: float | int) -> float | int:
        """Sets a parameter in the node's RAM; returns the value it now has.

        Not checked against the table here (the node checks): use Param.check first.
        SetRejected (a PmaError) when the node refuses, with the value it kept."""
        p = self.proto.param(key)
        if p.type == "f32":
            value = float(value)
        elif isinstance(value, float):
            if not value.is_integer():
                raise ValueError(f"{p.name} is an integer parameter")
            value = int(value)
        r = self.param_request("SET", p.id, TYPE_CODES[p.type], value)
        if r.result < 0:
            raise SetRejected(f"set {p.name} = {p.text(value)}", r.result,
                              self.proto.status_name(r.result), p, value, r.value)
        return r.value

    def info(self, key: str | int) -> tuple[float | int, float | int, float | int]:
        """(min, max, default) as the node reports them."""
        p = self.proto.param(key)
        t = TYPE_CODES[p.type]
        return tuple(self._checked(f"{op} {p.name}", self.param_request(op, p.id, t)).value
                     for op in ("GET_MIN", "GET_MAX", "GET_DEFAULT"))  # type: ignore[return-value]

    def param_info(self, pid: int) -> ParamInfo:
        """Value, min, max and default of one parameter id, as the node reports them."""
        p = self.proto.by_id.get(pid)
        t = TYPE_CODES[p.type] if p else 0
        what = p.name if p else f"parameter #{pid}"
        replies = [self._checked(f"{op.lower()} {what}", self.param_request(op, pid, t))
                   for op in ("GET", "GET_MIN", "GET_MAX", "GET_DEFAULT")]
        return ParamInfo(id=pid, type=replies[0].type, value=replies[0].value, min=replies[1].value,
                         max=replies[2].value, default=replies[3].value, param=p)

    def param_table(self, progress: Callable[[int, int], None] | None = None) -> list[ParamInfo]:
        """Every parameter the node has (NEXT_ID enumeration) with its value and range."""
        ids = self.ids()
        out = []
        for i, pid in enumerate(ids):
            out.append(self.param_info(pid))
            if progress:
                progress(i + 1, len(ids))
        return out

    def ids(self) -> list[int]:
        """Every parameter id the node has (NEXT_ID enumeration, until EMPTY)."""
        out: list[int] = []
        last = 0
        while True:
            r = self.param_request("NEXT_ID", last, 1)
            if r.result < 0:
                if self.proto.status_name(r.result) == "EMPTY" or not out:
                    return out
                raise PmaError(f"next id after {last}", r.result, self.proto.status_name(r.result))
            nxt = int(r.value)
            if nxt <= last:          # a node that does not advance would loop forever
                return out
            last = nxt
            out.append(last)

    def values(self, ids: Iterable[int] | None = None) -> dict[int, float | int]:
        """Current values by id: of `ids`, else of every id the node has."""
        out: dict[int, float | int] = {}
        for pid in (self.ids() if ids is None else ids):
            p = self.proto.by_id.get(pid)
            t = TYPE_CODES[p.type] if p else 0
            out[pid] = self._checked(f"get #{pid}", self.param_request("GET", pid, t)).value
        return out

    def snapshot(self) -> dict[str, float | int]:
        """Values of the table's parameters by name (those the node does not have are left
        out): what a recording notes about its run."""
        out: dict[str, float | int] = {}
        for p in self.proto.params:
            r = self.param_request("GET", p.id, TYPE_CODES[p.type])
            if r.result == 0:
                out[p.name] = r.value
        return out

    def load_values(self, entries: Iterable[tuple[Param, float | int]],
                    skip_unchanged: bool = True) -> LoadReport:
        """Sets each (parameter, value), in order; a refusal is recorded, not raised, and
        the rest are still sent. With skip_unchanged, a value the node already has is not
        sent (so a full parameter file loads into an ARMED node as long as only its
        stopped-class parameters differ)."""
        report = LoadReport()
        for p, value in entries:
            old = self.get(p.id) if skip_unchanged else None
            if old is not None and p.same(old, value):
                report.unchanged.append(p)
                continue
            try:
                new = self.set(p.id, value)
            except SetRejected as e:
                report.rejected.append(e)
                continue
            report.changed.append((p, old if old is not None else new, new))
        return report

    def save(self) -> None:
        self._checked("save", self.param_request("SAVE"))

    def restore_defaults(self) -> None:
        self._checked("restore defaults", self.param_request("RESTORE_DEFAULTS"))

    def load(self) -> None:
        self._checked("load", self.param_request("LOAD"))

    # ------------------------------------------------------------ status --
    def heartbeat(self, timeout_s: float | None = None) -> dict[str, Any]:
        """The node's next heartbeat."""
        return self.wait_for("HEARTBEAT", timeout_s=timeout_s)

    def status(self, timeout_s: float | None = None) -> Status:
        """The node's next heartbeat, decoded."""
        sig = self.heartbeat(timeout_s)
        return Status.from_signals(self.proto, self.node, sig)

    def wait_state(self, state: str, timeout_s: float | None = None) -> Status:
        """The first heartbeat that shows `state` (e.g. "FAULT")."""
        code = {v: k for k, v in self.proto.state_names.items()}[state]
        sig = self.wait_for("HEARTBEAT", lambda s: s["State"] == code, timeout_s=timeout_s)
        return Status.from_signals(self.proto, self.node, sig)

    def host_heartbeat(self, counter: int = 0) -> None:
        self.send("HOST_HEARTBEAT", {"Counter": counter & 0xFF})

    def setpoint(self, xr_cm: float) -> None:
        if not math.isfinite(xr_cm):
            raise ValueError("set-point must be finite")
        self.send("SETPOINT", {"XrCm": xr_cm})

    # ------------------------------------------------------ plant bridge --
    def sensor_sample(self, seq: int, raw_counts: int) -> None:
        self.send("PLANT_SENSOR", {"Seq": seq & 0xFF, "RawCounts": raw_counts})

    def exchange_sample(self, seq: int, raw_counts: int, timeout_s: float | None = None) -> dict[str, Any]:
        """Sends a sensor sample and returns the PLANT_ACTUATOR frame computed from it."""
        self.sensor_sample(seq, raw_counts)
        return self.wait_for("PLANT_ACTUATOR", lambda s: s["Seq"] == seq & 0xFF, timeout_s=timeout_s)


def param_value_text(p: Param, value: float | int) -> str:
    if p.values and int(value) in p.values:
        return f"{int(value)} ({p.values[int(value)]})"
    return f"{value:.7g}" if p.type == "f32" else str(int(value))


# -------------------------------------------------------------------- scan --
def scan(node: PmaNode, seconds: float = 1.0) -> dict[int, Status]:
    """The nodes whose heartbeats arrive within `seconds`: the last Status of each."""
    seen: dict[int, Status] = {}
    deadline = time.monotonic() + seconds
    while (left := deadline - time.monotonic()) > 0:
        got = node.receive(left)
        if got and got[0] == "HEARTBEAT" and got[1] in node.statuses:
            seen[got[1]] = node.statuses[got[1]]
    return dict(sorted(seen.items()))


# ----------------------------------------------------------------- monitor --
@dataclass(frozen=True)
class MonitorEvent:
    time: float                 # s since the monitor started
    node: int                   # -1: the bus (ESTOP_ALL)
    kind: str                   # seen, state, fault, flags, controller, reference, restart,
    #                             silent, back, estop, estop_all, refused, heartbeat
    text: str
    status: Status | None = None


class BusMonitor:
    """Heartbeats and faults of every node on a bus, as events: a node seen for the
    first time, a change of state, fault, flags, controller or reference, a restart
    (Counter back to 0 in BOOT), a node silent for `silent_s` (and back), ESTOP and
    ESTOP_ALL frames, and refused commands and parameter sets. `every` adds one event
    per heartbeat."""

    def __init__(self, node: PmaNode, silent_s: float = 1.0, every: bool = False) -> None:
        self.client = node
        self.proto = node.proto
        self.silent_s = silent_s
        self.every = every
        self.t0 = time.monotonic()
        self.last: dict[int, Status] = {}
        self.silent: set[int] = set()
        self._last_cmd: dict[int, tuple[int, int]] = {}

    def poll(self, timeout_s: float) -> list[MonitorEvent]:
        """Events from the frames that arrive within timeout_s (returns after one frame)."""
        got = self.client.receive(timeout_s)
        events = self._silence()
        if got is None:
            return events
        name, node, sig, _ = got
        now = time.monotonic() - self.t0
        if name == "HEARTBEAT" and node in self.client.statuses:
            events += self._heartbeat(now, self.client.statuses[node])
        elif name == "ESTOP_ALL":
            events.append(MonitorEvent(now, -1, "estop_all", "ESTOP_ALL on the bus (every node)"))
        elif name == "ESTOP":
            events.append(MonitorEvent(now, node, "estop", "ESTOP frame"))
        elif name == "COMMAND":
            self._last_cmd[node] = (int(sig["Command"]), int(sig["Arg"]))
        elif name == "COMMAND_ACK" and int(sig["Result"]) < 0:
            cmd = self.proto.enum_names("COMMAND", "Command").get(int(sig["Command"]), str(sig["Command"]))
            events.append(MonitorEvent(now, node, "refused", f"refused {cmd}: "
                                       f"{self.proto.status_text(int(sig['Result']))}"))
        elif name == "PARAM_RESP" and int(sig["Result"]) < 0 and int(sig["Op"]) == OPS["SET"]:
            p = self.proto.by_id.get(int(sig["Id"]))
            events.append(MonitorEvent(now, node, "refused",
                                       f"refused set {p.name if p else '#' + str(sig['Id'])}: "
                                       f"{self.proto.status_text(int(sig['Result']))}"))
        return events

    def _silence(self) -> list[MonitorEvent]:
        now = time.monotonic()
        out = []
        for node, st in self.last.items():
            if node not in self.silent and now - st.time > self.silent_s:
                self.silent.add(node)
                out.append(MonitorEvent(now - self.t0, node, "silent",
                                        f"silent: no heartbeat for {now - st.time:.1f} s"))
        return out

    def _heartbeat(self, now: float, st: Status) -> list[MonitorEvent]:
        out: list[MonitorEvent] = []
        prev = self.last.get(st.node)
        self.last[st.node] = st
        flags = " ".join(st.flag_names) or "-"
        if prev is None:
            out.append(MonitorEvent(now, st.node, "seen",
                                    f"{st.summary()}, flags {flags}, reset {st.reset_cause_name}", st))
            return out
        if st.node in self.silent:
            self.silent.discard(st.node)
            out.append(MonitorEvent(now, st.node, "back", f"back: {st.summary()}", st))
        if st.state_name == "BOOT" or (st.counter == 0 and prev.counter != 255):
            out.append(MonitorEvent(now, st.node, "restart",
                                    f"restarted ({st.state_name}, reset cause {st.reset_cause_name})", st))
        if st.fault != prev.fault and st.fault:
            out.append(MonitorEvent(now, st.node, "fault", f"FAULT {st.fault_name} ({st.fault})", st))
        if st.state != prev.state:
            out.append(MonitorEvent(now, st.node, "state", f"state {prev.state_name} -> {st.state_name}", st))
        if st.controller != prev.controller:
            out.append(MonitorEvent(now, st.node, "controller",
                                    f"controller {prev.controller_name} -> {st.controller_name}", st))
        if st.reference != prev.reference:
            out.append(MonitorEvent(now, st.node, "reference",
                                    f"reference {prev.reference_name} -> {st.reference_name}", st))
        if st.flags != prev.flags:
            gone = [f for f in prev.flag_names if f not in st.flag_names]
            new = [f for f in st.flag_names if f not in prev.flag_names]
            out.append(MonitorEvent(now, st.node, "flags",
                                    "flags " + " ".join([f"+{f}" for f in new] + [f"-{f}" for f in gone]), st))
        if self.every:
            out.append(MonitorEvent(now, st.node, "heartbeat",
                                    f"heartbeat {st.counter}: {st.summary()}, flags {flags}", st))
        return out


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
