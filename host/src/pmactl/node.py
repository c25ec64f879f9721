# SPDX-License-Identifier: Apache-2.0
"""PmaNode: the synchronous client of one node (commands, parameters, status), and its
replies.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any, Callable, Iterable

import can

from pmactl.bus import frame_filters
from pmactl.errors import CommandError, NoReply, PmaError, SetRejected
from pmactl.protocol import Param, Protocol, load_protocol

# PARAM_REQ's Type and Op values, by name
TYPE_CODES = {"f32": 0, "u32": 1, "i32": 2}
TYPE_SIGNALS = {0: "ValueF32", 1: "ValueU32", 2: "ValueI32"}
TYPE_NAMES = {v: k for k, v in TYPE_CODES.items()}
OPS: dict[str, int] = load_protocol().param_ops   # PARAM_REQ's Op names, from the packaged DBC

HOST_HEARTBEAT_PERIOD_S = 0.1       # 10 Hz, well inside the default safety.host_timeout_ms (500 ms)


def wire_value(proto: Protocol, p: Param, value: object) -> float | int:
    """value as a SET of p carries it (PARAM_REQ's ValueF32 / ValueU32 / ValueI32): a float for
    an f32 parameter, an int otherwise; text as Param.parse reads it. ValueError naming the
    parameter for what no frame can carry: not a number, a fraction for an integer parameter,
    beyond the value signal's range (the DBC's: an infinity, a float beyond float32, an integer
    outside its type). The table's range is not checked (Param.check does that; the node
    checks it anyway), and a NaN goes out: the node refuses it (NOT_FINITE)."""
    if isinstance(value, str):
        value = p.parse(value)
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ValueError(f"{p.name}: {value!r} is not a number")
    if p.type == "f32":
        value = float(value)
    elif isinstance(value, float):
        if not value.is_integer():
            raise ValueError(f"{p.name} is an integer parameter: {value!r} is not an integer")
        value = int(value)
    return proto.check_signal("PARAM_REQ", TYPE_SIGNALS[TYPE_CODES[p.type]], value, what=f"{p.name} ({p.type})",
                              finite=False)


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
        if isinstance(command, str):
            if command not in self.proto.commands:
                raise KeyError(f"no command {command!r}; known: {', '.join(self.proto.commands)}")
            code = self.proto.commands[command]
        else:
            code = int(command)
        # both are bytes in the DBC (COMMAND's Command and Arg): out of that, nothing can be sent
        arg_lo, arg_hi = (int(v or 0) for v in self.proto.signal_range("COMMAND", "Arg")[:2])
        code_lo, code_hi = (int(v or 0) for v in self.proto.signal_range("COMMAND", "Command")[:2])
        if not (code_lo <= code <= code_hi and arg_lo <= arg <= arg_hi):
            raise ValueError(f"command {command}: the command and its argument are bytes ({arg_lo}..{arg_hi}), got "
                             f"{code} and {arg}")
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
        boot = self.wait_state("BOOT", timeout_s=timeout_s).state
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
        opc = self.proto.param_ops[op] if isinstance(op, str) else int(op)
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

    def status_value(self, key: str | int) -> int:
        """One of the node's counters or status values (GET_STATUS) by name (the DBC's value
        table StatusId, e.g. "GUARANTEE_LOST_TICKS") or Id; PmaError UNKNOWN_ID from a node
        that does not have it."""
        if isinstance(key, str) and not key.isdigit():
            name = key.upper()
            if name not in self.proto.status_ids:
                raise KeyError(f"no status value {key!r}; known: {', '.join(self.proto.status_ids)}")
            sid = self.proto.status_ids[name]
        else:
            sid = int(key)
        r = self._checked(f"status {key}", self.param_request("GET_STATUS", sid, TYPE_CODES["u32"]))
        return int(r.value)

    def status_values(self) -> dict[str, int]:
        """Every status value the DBC names, read from the node (in Id order)."""
        return {name: self.status_value(sid)
                for name, sid in sorted(self.proto.status_ids.items(), key=lambda kv: kv[1])}

    def set(self, key: str | int, value: float | int) -> float | int:
        """Sets a parameter in the node's RAM; returns the value it now has.

        Not checked against the table here (the node checks): use Param.check first.
        SetRejected (a PmaError) when the node refuses, with the value it kept."""
        p = self.proto.param(key)
        value = wire_value(self.proto, p, value)
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
        codes = {v: k for k, v in self.proto.state_names.items()}
        if state not in codes:
            raise KeyError(f"no state {state!r}; known: {', '.join(codes)}")
        code = codes[state]
        sig = self.wait_for("HEARTBEAT", lambda s: s["State"] == code, timeout_s=timeout_s)
        return Status.from_signals(self.proto, self.node, sig)

    def host_heartbeat(self, counter: int = 0) -> None:
        self.send("HOST_HEARTBEAT", {"Counter": counter & 0xFF})

    def setpoint(self, xr_cm: float) -> None:
        """Sends a SETPOINT; ValueError (nothing sent) for a value the frame cannot carry
        (not finite, or outside the DBC's range of XrCm)."""
        self.proto.check_signal("SETPOINT", "XrCm", xr_cm, what="set-point")
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


