"""The protocol client: one class, used by pmactl, the HIL harness and the tests.

PmaNode talks to one node over any python-can bus (socketcan, pcan, kvaser,
slcan, virtual, ...). It is synchronous: each request waits for its reply and
drops unrelated frames, except heartbeats, which it keeps (the last one per
node) for status queries.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import Any, Callable

import can

from pmactl.protocol import Param, Protocol, load_protocol

TYPE_CODES = {"f32": 0, "u32": 1, "i32": 2}
TYPE_SIGNALS = {0: "ValueF32", 1: "ValueU32", 2: "ValueI32"}
OPS = {"GET": 0, "SET": 1, "SAVE": 2, "RESTORE_DEFAULTS": 3, "GET_MIN": 4, "GET_MAX": 5,
       "GET_DEFAULT": 6, "NEXT_ID": 7, "LOAD": 8}


class PmaError(Exception):
    """A request the node answered with an error code (negative pma_status_t)."""

    def __init__(self, what: str, code: int, name: str) -> None:
        super().__init__(f"{what}: {name} ({code})")
        self.code = code
        self.name = name


class CommandError(PmaError):
    pass


class NoReply(TimeoutError):
    """No reply within the timeout."""


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


class PmaNode:
    def __init__(self, bus: can.BusABC, node: int = 0, protocol: Protocol | None = None,
                 timeout_s: float = 1.0) -> None:
        self.bus = bus
        self.node = node
        self.proto = protocol or load_protocol()
        self.timeout_s = timeout_s
        self.heartbeats: dict[int, dict[str, Any]] = {}

    # ------------------------------------------------------------ frames --
    def send(self, message: str, data: dict[str, Any] | None = None, node: int | None = None) -> None:
        payload = self.proto.encode(message, data)
        self.send_raw(self.proto.frame_id(message, self.node if node is None else node), payload)

    def send_raw(self, frame_id: int, payload: bytes) -> None:
        self.bus.send(can.Message(arbitration_id=frame_id, data=payload, is_extended_id=False))

    def receive(self, timeout_s: float | None = None) -> tuple[str, int, dict[str, Any], can.Message] | None:
        """The next frame of the protocol (any node) as (message, node, signals, raw)."""
        msg = self.bus.recv(self.timeout_s if timeout_s is None else timeout_s)
        if msg is None or msg.is_extended_id or msg.is_error_frame or msg.is_remote_frame:
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

    def estop(self, all_nodes: bool = False) -> None:
        """Emergency stop (no reply: watch the heartbeat)."""
        self.send("ESTOP_ALL" if all_nodes else "ESTOP")

    def select_controller(self, name: str) -> Ack:
        return self.command("SELECT_CONTROLLER", self._enum("ctrl.mode", name))

    def select_reference(self, name: str) -> Ack:
        return self.command("SELECT_REFERENCE", self._enum("ref.kind", name))

    def _enum(self, param: str, name: str) -> int:
        p = self.proto.param(param)
        for k, v in p.values.items():
            if v == name.upper():
                return k
        raise ValueError(f"{param}: no value {name!r} (one of {', '.join(p.values.values())})")

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
        """Sets a parameter in the node's RAM; returns the value it now has."""
        p = self.proto.param(key)
        if p.type == "f32":
            value = float(value)
        elif isinstance(value, float):
            if not value.is_integer():
                raise ValueError(f"{p.name} is an integer parameter")
            value = int(value)
        r = self.param_request("SET", p.id, TYPE_CODES[p.type], value)
        return self._checked(f"set {p.name} = {value}", r).value

    def info(self, key: str | int) -> tuple[float | int, float | int, float | int]:
        """(min, max, default) as the node reports them."""
        p = self.proto.param(key)
        t = TYPE_CODES[p.type]
        return tuple(self._checked(f"{op} {p.name}", self.param_request(op, p.id, t)).value
                     for op in ("GET_MIN", "GET_MAX", "GET_DEFAULT"))  # type: ignore[return-value]

    def ids(self) -> list[int]:
        """Every parameter id the node has (NEXT_ID enumeration)."""
        out: list[int] = []
        last = 0
        while True:
            r = self.param_request("NEXT_ID", last, 1)
            if r.result < 0:
                return out
            last = int(r.value)
            out.append(last)

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
