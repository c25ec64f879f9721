# SPDX-License-Identifier: Apache-2.0
"""A fake PMA node for the unit tests: a thread on python-can's virtual bus that
answers the protocol (docs/protocol.md) for a few parameters, closely enough to test
every pmactl command, its output and its errors without CAN hardware or firmware.

It is a test double, not a model of the firmware: the state machine follows the
command table of docs/protocol.md, parameter SETs are checked in the firmware's order
(UNKNOWN_ID, TYPE, NOT_FINITE, RANGE, STATE), and while RUNNING it sends TELEM_A..E
with a synthetic exponential approach of x to the reference.
"""
from __future__ import annotations

import math
import threading
import time
from dataclasses import dataclass, field
from typing import Any, Callable

import can

from pmactl.identity import device_tag
from pmactl.protocol import Param, load_protocol, param_table_hash, protocol_version, to_f32

PROTO = load_protocol()
STATE = {v: k for k, v in PROTO.state_names.items()}
FAULT = {v: k for k, v in PROTO.fault_names.items()}
RESULT = {v: k for k, v in PROTO.status_names.items()}
CMD = dict(PROTO.commands)
OPS = dict(PROTO.param_ops)
TYPE = {"f32": 0, "u32": 1, "i32": 2}
VALUE_SIG = {0: "ValueF32", 1: "ValueU32", 2: "ValueI32"}

DEFAULT_PARAMS = ("sys.node_id", "sys.tick_hz", "sys.heartbeat_ms", "telem.decimation", "telem.mask",
                  "ctrl.mode", "ctrl.u_min", "ctrl.u_max", "ppc.w1_cm", "ppc.t_u_s", "ref.kind",
                  "act.p0_kpa", "act.polarity", "safety.x_min_cm", "safety.x_max_cm",
                  "safety.host_timeout_ms")
UNKNOWN_ID = 250          # a parameter this package's table does not know (a "newer firmware")
OUTPUT_ACTIVE, PLANT_BRIDGE, PARAMS_CHANGED, PARAMS_DEFAULT, SENSOR_VALID, REF_ACTIVE = \
    0x01, 0x02, 0x08, 0x10, 0x40, 0x80


def wait_until(cond: Callable[[], bool], timeout_s: float = 10.0) -> bool:
    """Polls cond until it holds or timeout_s passes; its last value. The fake node's
    thread handles frames when the machine lets it, so a test waits for an effect
    rather than sleeping a fixed time."""
    deadline = time.monotonic() + timeout_s
    while not cond():
        if time.monotonic() > deadline:
            return cond()
        time.sleep(0.005)
    return True


@dataclass
class Row:
    param: Param | None
    type: int
    value: float | int
    min: float | int
    max: float | int
    default: float | int
    access: str


@dataclass
class FakeNode:
    channel: str
    node: int = 0
    heartbeat_s: float = 0.05
    telem_s: float = 0.01            # one telemetry tick every telem_s while RUNNING
    storage: bool = False            # SAVE/LOAD work (else NOT_IMPLEMENTED)
    sensor: bool = True              # ARM needs a sensor sample (else NOT_READY)
    answer: bool = True              # False: heartbeats only, no replies
    heartbeats: bool = True
    wire_break_at_tick: int | None = None   # RUNNING: fault SENSOR_WIRE_BREAK after this many ticks
    overrides: dict[str, dict[str, Any]] = field(default_factory=dict)  # name -> {"max": ...}
    params: tuple[str, ...] = DEFAULT_PARAMS
    uid: bytes = bytes(range(1, 13))  # the 12-byte unique id DEVICE_INFO reports
    info_protocol_version: int | None = None  # DEVICE_INFO's ProtocolVersion (None: the DBC's)
    info_length: int = 8                      # DLC of the DEVICE_INFO frames it sends
    motion: str = "approach"         # telemetry: "approach" (x settles on x_r) or "sine" (x_r a 2 s sine)
    restarts: bool = True            # RESTART works (False: UNKNOWN_COMMAND, as protocol < 4)
    # GET_STATUS's values by name (the DBC's StatusId); None: GET_STATUS unknown (an old node)
    status_values: dict[str, int] | None = field(default_factory=lambda: {
        "LAST_RULE": 0, "RX_OVERRUNS": 0, "RX_DEFERRED": 0, "RX_DROPPED": 0, "FRAMES_BAD": 0,
        "TICKS": 1234, "FRAMES_RX": 56, "GUARANTEE_LOST_TICKS": 0, "GUARANTEE_LOST_AT_MS": 0xFFFFFFFF,
        "BARRIER_BREACHES": 0})

    def __post_init__(self) -> None:
        self.rows: dict[int, Row] = {}
        for name in self.params:
            p = PROTO.param(name)
            row = Row(p, TYPE[p.type], p.default, p.min, p.max, p.default, p.access)
            for k, v in self.overrides.get(name, {}).items():
                setattr(row, k, v)
            row.value = self._norm(row.type, row.default)
            self.rows[p.id] = row
        self.rows[UNKNOWN_ID] = Row(None, 1, 7, 0, 10, 7, "live")
        self.saved: dict[int, float | int] | None = None
        self.state = STATE["IDLE"]
        self.fault = 0
        self.changed = False
        self.counter = 0
        self.reset_cause = 1                # POWER_ON
        self.restart_due = False
        self.received: list[tuple[str, dict[str, Any]]] = []   # every frame handled, in order
        self.setpoints: list[float] = []
        self.host_heartbeats = 0
        self.telem_ticks = 0
        # The host-heartbeat timeout counts telemetry ticks (as the firmware counts control
        # ticks), not wall time, so a slow test machine does not make it expire early.
        # After set_state("RUNNING") it starts with the first frame from the host (the test
        # stands for "a host started this node a moment ago"); after START, at once.
        self.ticks_since_host_hb = 0
        self.host_timer_armed = False
        self.lock = threading.Lock()
        self.bus = can.Bus(interface="virtual", channel=self.channel)
        self._stop = threading.Event()
        self.thread = threading.Thread(target=self._loop, daemon=True)

    # ------------------------------------------------------------ control --
    def __enter__(self) -> "FakeNode":
        self.thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def close(self) -> None:
        self._stop.set()
        self.thread.join(2)
        self.bus.shutdown()

    def set_state(self, state: str, fault: str = "NONE") -> None:
        with self.lock:
            self.state = STATE[state]
            self.fault = FAULT[fault]
            if state == "RUNNING":
                self.telem_ticks = 0
                self.ticks_since_host_hb = 0
                self.host_timer_armed = False

    def value(self, name: str) -> float | int:
        return self.rows[PROTO.param(name).id].value

    def sets(self) -> list[dict[str, Any]]:
        """PARAM_REQ SETs received."""
        return [sig for name, sig in self.received if name == "PARAM_REQ" and sig["Op"] == OPS["SET"]]

    # --------------------------------------------------------------- loop --
    @staticmethod
    def _norm(t: int, v: float | int) -> float | int:
        return to_f32(float(v)) if t == 0 else int(v)

    def _send(self, message: str, data: dict[str, Any] | None = None) -> None:
        fid = PROTO.frame_id(message, self.node)
        payload = PROTO.encode(message, data)
        self.bus.send(can.Message(arbitration_id=fid, data=payload, is_extended_id=False))

    def _flags(self) -> int:
        f = PLANT_BRIDGE
        if self.state in (STATE["ARMED"], STATE["RUNNING"]):
            f |= OUTPUT_ACTIVE
        if self.state == STATE["RUNNING"]:
            f |= REF_ACTIVE
        if self.sensor:
            f |= SENSOR_VALID
        if self.changed:
            f |= PARAMS_CHANGED
        if self.saved is None:
            f |= PARAMS_DEFAULT
        return f

    def _heartbeat(self) -> None:
        self._send("HEARTBEAT", {
            "State": self.state, "FaultCode": self.fault, "Flags": self._flags(),
            "Controller": int(self.value("ctrl.mode")), "Reference": int(self.value("ref.kind")),
            "ResetCause": self.reset_cause, "Counter": self.counter})
        self.counter = (self.counter + 1) & 0xFF

    def _telemetry(self) -> None:
        self.telem_ticks += 1
        t = self.telem_ticks * self.telem_s
        if self.motion == "sine":
            xr = -1.5 + 0.5 * math.sin(2 * math.pi * t / 2.0)
            x = xr + 0.1 * math.cos(2 * math.pi * t / 2.0)
        else:
            xr = -1.5
            x = xr + 0.5 * math.exp(-t / 0.2)
        e = x - xr
        u = -40.0 * e
        mask = int(self.value("telem.mask"))
        frames = {
            "TELEM_A": {"TimeMs": int(round(t * 1000)), "XCm": x},
            "TELEM_B": {"XrCm": xr, "ECm": e},
            "TELEM_C": {"U": u, "VCmS": -e / 0.2},
            "TELEM_D": {"Internal1": e, "Internal2": 0.1},
            "TELEM_E": {"PressureKpa": 300.0 + u, "CtrlFlags": 0, "Breaches": 0},
        }
        for bit, (name, data) in enumerate(frames.items()):
            if mask >> bit & 1:
                self._send(name, data)

    def _loop(self) -> None:
        next_hb = time.monotonic()
        next_telem = time.monotonic()
        while not self._stop.is_set():
            msg = self.bus.recv(0.002)
            with self.lock:
                if msg is not None:
                    self._handle(msg)
                now = time.monotonic()
                if self.heartbeats and now >= next_hb:
                    self._heartbeat()
                    next_hb = now + self.heartbeat_s
                if self.state == STATE["RUNNING"] and now >= next_telem:
                    timeout_ms = int(self.value("safety.host_timeout_ms"))
                    if (timeout_ms and self.host_timer_armed
                            and self.ticks_since_host_hb * self.telem_s * 1000.0 >= timeout_ms):
                        self.state, self.fault = STATE["FAULT"], FAULT["HOST_HEARTBEAT_LOST"]
                    elif self.wire_break_at_tick is not None and self.telem_ticks >= self.wire_break_at_tick:
                        self.state, self.fault = STATE["FAULT"], FAULT["SENSOR_WIRE_BREAK"]
                    else:
                        self._telemetry()
                        if self.host_timer_armed:
                            self.ticks_since_host_hb += 1
                        next_telem = now + self.telem_s

    # ------------------------------------------------------------- frames --
    def _handle(self, msg: can.Message) -> None:
        found = PROTO.message_of(msg.arbitration_id)
        if found is None:
            return
        name, node = found
        if name == "ESTOP_ALL" or (name == "ESTOP" and node == self.node):
            self.received.append((name, {}))
            self._fault("ESTOP")
            return
        if self.answer and not msg.data and (
                name == "DEVICE_INFO_REQ_ALL" or (name == "DEVICE_INFO_REQ" and node == self.node)):
            self.received.append((name, {}))
            self._device_info()
            return
        if node != self.node:
            return
        try:
            sig = PROTO.decode(name, bytes(msg.data)) if PROTO.messages[name].signals else {}
        except Exception:
            return
        self.received.append((name, sig))
        self.host_timer_armed = True
        if name == "HOST_HEARTBEAT":
            self.host_heartbeats += 1
            self.ticks_since_host_hb = 0
        elif name == "SETPOINT":
            self.setpoints.append(float(sig["XrCm"]))
        elif name == "COMMAND" and self.answer:
            res = self._command(int(sig["Command"]), int(sig["Arg"]))
            self._send("COMMAND_ACK", {"Command": sig["Command"], "Arg": sig["Arg"], "Result": res,
                                       "State": self.state})
            if self.restart_due:
                self._reboot()
        elif name == "PARAM_REQ" and self.answer:
            self._param(sig)

    def _device_info(self) -> None:
        version = (protocol_version(PROTO.db) if self.info_protocol_version is None
                   else self.info_protocol_version)
        table = param_table_hash({"id": p.id, "name": p.name, "type": p.type, "min": p.min,
                                  "max": p.max, "default": p.default} for p in PROTO.params)
        tag = device_tag(self.uid)
        pages: list[dict[str, Any]] = [
            {"Page": 0, "ProtocolVersion": version, "FwMajor": 0, "FwMinor": 2, "FwPatch": 0,
             "BuildTarget": 1, "BuildFlags": 0, "DeviceTag": tag},
            {"Page": 1, "FwCommit": 0x1234ABCD, "ParamCount": len(PROTO.params), "DeviceTag": tag},
            {"Page": 2, "ParamTableHash": table, "DeviceTag": tag},
            {"Page": 3, "UidLow": int.from_bytes(self.uid[:6], "little"), "DeviceTag": tag},
            {"Page": 4, "UidHigh": int.from_bytes(self.uid[6:], "little"), "DeviceTag": tag},
        ]
        fid = PROTO.frame_id("DEVICE_INFO", self.node)
        for page in pages:
            data = PROTO.encode("DEVICE_INFO", page)
            data = (data + bytes(8))[: self.info_length]
            self.bus.send(can.Message(arbitration_id=fid, data=data, is_extended_id=False))

    def _reboot(self) -> None:
        """A software reset: RAM back to the saved set (or the defaults), the stored
        sys.node_id in force, a BOOT heartbeat with ResetCause SOFTWARE, then IDLE."""
        self.restart_due = False
        for i, r in self.rows.items():
            r.value = self.saved[i] if self.saved is not None else self._norm(r.type, r.default)
        self.node = int(self.value("sys.node_id")) if self.saved is not None else self.node
        self.changed = False
        self.reset_cause = 3
        self.counter = 0
        self.state, self.fault = STATE["BOOT"], 0
        self._heartbeat()
        self.state = STATE["IDLE"]

    def _fault(self, fault: str) -> None:
        if self.state != STATE["FAULT"]:
            self.state, self.fault = STATE["FAULT"], FAULT[fault]

    def _command(self, cmd: int, arg: int) -> int:
        s = self.state
        ok = RESULT["OK"]
        if cmd == CMD["ESTOP"]:
            self._fault("ESTOP")
            return ok
        if cmd == CMD["CLEAR_FAULTS"]:
            if s == STATE["FAULT"]:
                self.state, self.fault = STATE["IDLE"], 0
            return ok
        if cmd in (CMD["SELECT_CONTROLLER"], CMD["SELECT_REFERENCE"]):
            p = PROTO.param("ctrl.mode" if cmd == CMD["SELECT_CONTROLLER"] else "ref.kind")
            return self._set(p.id, TYPE[p.type], arg)[0]
        if cmd == CMD["RESTART"] and self.restarts:
            if s in (STATE["ARMED"], STATE["RUNNING"]):
                return RESULT["STATE"]
            self.restart_due = True
            return ok
        if s == STATE["FAULT"] and cmd in (CMD["ARM"], CMD["DISARM"], CMD["START"], CMD["STOP"]):
            return RESULT["FAULT"]
        if cmd == CMD["ARM"]:
            if s == STATE["RUNNING"]:
                return RESULT["STATE"]
            if not self.sensor:
                return RESULT["NOT_READY"]
            self.state = STATE["ARMED"]
            return ok
        if cmd == CMD["DISARM"]:
            self.state = STATE["IDLE"]
            return ok
        if cmd == CMD["START"]:
            if s != STATE["ARMED"]:
                return RESULT["STATE"]
            self.state = STATE["RUNNING"]
            self.telem_ticks = 0
            self.ticks_since_host_hb = 0
            return ok
        if cmd == CMD["STOP"]:
            if s == STATE["IDLE"]:
                return RESULT["STATE"]
            self.state = STATE["ARMED"]
            return ok
        return RESULT["UNKNOWN_COMMAND"]

    def _set(self, pid: int, t: int, value: float | int) -> tuple[int, float | int]:
        row = self.rows.get(pid)
        if row is None:
            return RESULT["UNKNOWN_ID"], 0
        if t != row.type:
            return RESULT["TYPE"], row.value
        if isinstance(value, float) and not math.isfinite(value):
            return RESULT["NOT_FINITE"], row.value
        if not row.min <= value <= row.max:
            return RESULT["RANGE"], row.value
        active = self.state in (STATE["ARMED"], STATE["RUNNING"])
        if (row.access == "stopped" and self.state == STATE["RUNNING"]) or (row.access == "idle" and active):
            return RESULT["STATE"], row.value
        row.value = self._norm(row.type, value)
        self.changed = True
        return RESULT["OK"], row.value

    def _param(self, sig: dict[str, Any]) -> None:
        op, pid, t = int(sig["Op"]), int(sig["Id"]), int(sig["Type"])
        res, rtype, value = RESULT["OK"], t, 0
        row = self.rows.get(pid)
        active = self.state in (STATE["ARMED"], STATE["RUNNING"])
        if op in (OPS["GET"], OPS["GET_MIN"], OPS["GET_MAX"], OPS["GET_DEFAULT"]):
            if row is None:
                res = RESULT["UNKNOWN_ID"]
            else:
                rtype = row.type
                value = {OPS["GET"]: row.value, OPS["GET_MIN"]: row.min, OPS["GET_MAX"]: row.max,
                         OPS["GET_DEFAULT"]: row.default}[op]
        elif op == OPS["SET"]:
            res, value = self._set(pid, t, sig.get(VALUE_SIG.get(t, ""), 0))
            if row is not None:
                rtype = row.type
        elif op == OPS["GET_STATUS"] and self.status_values is not None:
            rtype = 1
            names = {v: k for k, v in PROTO.status_ids.items()}
            if pid in names and names[pid] in self.status_values:
                value = self.status_values[names[pid]]
            else:
                res = RESULT["UNKNOWN_ID"]
        elif op == OPS["NEXT_ID"]:
            rtype = 1
            later = sorted(i for i in self.rows if i > pid)
            if later:
                value = later[0]
            else:
                res = RESULT["EMPTY"]
        elif op in (OPS["SAVE"], OPS["LOAD"], OPS["RESTORE_DEFAULTS"]):
            if active:
                res = RESULT["STATE"]
            elif op == OPS["RESTORE_DEFAULTS"]:
                for r in self.rows.values():
                    r.value = self._norm(r.type, r.default)
                self.changed = True
            elif not self.storage:
                res = RESULT["NOT_IMPLEMENTED"]
            elif op == OPS["SAVE"]:
                self.saved = {i: r.value for i, r in self.rows.items()}
                self.changed = False
            elif self.saved is None:
                res = RESULT["NO_RECORD"]
            else:
                for i, v in self.saved.items():
                    self.rows[i].value = v
                self.changed = False
        else:
            res = RESULT["UNKNOWN_COMMAND"]
        value = self._norm(rtype, value) if rtype in (0, 1, 2) else 0
        self._send("PARAM_RESP", {"Op": op, "Type": rtype, "Id": pid, "Result": res,
                                  VALUE_SIG.get(rtype, "ValueU32"): value})
