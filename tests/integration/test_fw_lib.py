# SPDX-License-Identifier: Apache-2.0
"""Shared helpers of the test_fw_*.py integration tests (no tests here).

Everything talks to pma-fw-host over vcan0 with python-can and pmactl.PmaNode;
frames the client has no method for are built as raw bytes (send_raw, or a
raw SocketCAN socket for error, remote, extended-id and CAN FD frames).
"""
from __future__ import annotations

import math
import os
import signal
import socket
import struct
import time
from typing import Any, Callable

import can

from pmactl.client import TYPE_CODES, NoReply, PmaNode
from pmactl.protocol import Param, load_protocol

CHANNEL = os.environ.get("PMA_CAN_CHANNEL", "vcan0")   # as conftest.py

PROTO = load_protocol()

# States, faults, results and commands by name, from the DBC (never hard-coded numbers).
STATE = {v: k for k, v in PROTO.state_names.items()}
FAULT = {v: k for k, v in PROTO.fault_names.items()}
RESULT = {v: k for k, v in PROTO.status_names.items()}
CMD = dict(PROTO.commands)
SAMPLE = {v: k for k, v in PROTO._choices("PLANT_ACTUATOR", "Sample").items()}
RESET = {v: k for k, v in PROTO._choices("HEARTBEAT", "ResetCause").items()}

# HEARTBEAT Flags bits (docs/protocol.md "Heartbeat flags").
HB_OUTPUT_ACTIVE = 0x0001
HB_PLANT_BRIDGE = 0x0002
HB_LOCKSTEP = 0x0004
HB_PARAMS_CHANGED = 0x0008
HB_PARAMS_DEFAULT = 0x0010
HB_CAN_PASSIVE = 0x0020
HB_SENSOR_VALID = 0x0040
HB_REF_ACTIVE = 0x0080
HB_SAVE_FAILED = 0x0100
HB_GUARANTEE_LOST = 0x0200
HB_FALLBACK = 0x0400
# TELEM_E CtrlFlags bits (docs/controllers.md): the paper's law's and the application's
CTRL_BARRIER1 = 0x0001
CTRL_WIDEN1 = 0x0040
CTRL_WIDE = 0x0100
CTRL_GUARANTEE_LOST = 0x4000
CTRL_FALLBACK = 0x8000

EXIT_POWER_CUT = 85           # PMA_HAL_LINUX_EXIT_POWER_CUT (hal/portable/linux/pma_hal_linux.h)

# Linux <linux/can.h>, <linux/can/error.h>
CAN_EFF_FLAG = 0x80000000
CAN_RTR_FLAG = 0x40000000
CAN_ERR_FLAG = 0x20000000
CAN_ERR_BUSOFF = 0x00000040
CAN_ERR_DLC = 8


def base_id(message: str) -> int:
    return PROTO.messages[message].frame_id


def f32(x: float) -> float:
    """x rounded to IEEE single precision, as the node stores it."""
    return struct.unpack("<f", struct.pack("<f", x))[0]


def f32_bits(x: float) -> bytes:
    return struct.pack("<f", x)


def default_of(name: str) -> float | int:
    p = PROTO.param(name)
    return f32(p.default) if p.type == "f32" else int(p.default)


# ----------------------------------------------------------- sensor scaling --
# x = adc.offset_cm + adc.gain_cm_per_count * counts, in single precision
# (firmware/app/adc_scaling.c), with the defaults of params.toml.

def counts_to_cm(counts: int, offset: float | None = None, gain: float | None = None) -> float:
    off = f32(default_of("adc.offset_cm") if offset is None else offset)
    g = f32(default_of("adc.gain_cm_per_count") if gain is None else gain)
    return f32(off + f32(g * f32(float(counts))))


def cm_to_counts(x_cm: float) -> int:
    """The count whose position is nearest to x_cm (default scaling)."""
    off = default_of("adc.offset_cm")
    g = default_of("adc.gain_cm_per_count")
    return int(round((x_cm - off) / g))


COUNTS_MID = 2948                      # x = -1.499 cm: mid-band, the default HOLD reference
assert abs(counts_to_cm(COUNTS_MID) - (-1.5)) < 0.01


def dac_counts(p_kpa: float) -> int:
    """pma_dac_kpa_to_counts with the dac.* defaults (round half away, clamp)."""
    z = f32(default_of("dac.counts_at_zero_kpa"))
    k = f32(default_of("dac.counts_per_kpa"))
    v = f32(z + f32(k * f32(p_kpa)))
    c = math.floor(v + 0.5) if v >= 0 else -math.floor(-v + 0.5)
    return int(min(max(c, default_of("dac.min_counts")), default_of("dac.max_counts")))


# ------------------------------------------------------------------- bus --

def drain(bus: can.BusABC, quiet_s: float = 0.0) -> list[can.Message]:
    """Reads (and returns) everything waiting in the test's socket."""
    out = []
    while True:
        m = bus.recv(quiet_s)
        if m is None:
            return out
        out.append(m)


def start(firmware, bus: can.BusABC, **kw) -> tuple[Any, PmaNode]:
    """Starts pma-fw-host via the conftest factory and waits for its BOOT
    heartbeat (State BOOT; kept as node.boot), so that no buffered frame of
    an earlier process with the same node id is taken for this one's."""
    drain(bus)
    fw, node = firmware(wait_heartbeat=False, **kw)
    node.boot = node.wait_for("HEARTBEAT", lambda s: s["State"] == STATE["BOOT"], timeout_s=10.0)
    query_state(node)          # answered from the main loop: start-up is over
    return fw, node


def query_state(node: PmaNode) -> int:
    """The node's state now, from the COMMAND_ACK of command 0 (unknown:
    changes nothing, always answered with the state)."""
    ack = node.command(0, check=False)
    assert ack.result == RESULT["UNKNOWN_COMMAND"], ack
    return ack.state


def fresh_heartbeat(node: PmaNode, timeout_s: float = 2.0) -> dict[str, Any]:
    """A heartbeat sent after everything the test sent so far was handled:
    the node answers the state query first, the heartbeat comes after it."""
    query_state(node)
    return node.wait_for("HEARTBEAT", timeout_s=timeout_s)


def hb_state(node: PmaNode) -> tuple[str, str]:
    hb = fresh_heartbeat(node)
    return PROTO.state_names[hb["State"]], PROTO.fault_names[hb["FaultCode"]]


def wait_state(node: PmaNode, state: str, timeout_s: float = 3.0) -> dict[str, Any]:
    return node.wait_for("HEARTBEAT", lambda s: s["State"] == STATE[state], timeout_s=timeout_s)


def replies_until(node: PmaNode, pred: Callable[[str, int, dict[str, Any]], bool],
                  timeout_s: float = 3.0) -> list[tuple[str, int, dict[str, Any]]]:
    """Every protocol frame (any node) received until one satisfies pred
    (included, last). Raises NoReply on timeout."""
    got = []
    deadline = time.monotonic() + timeout_s
    while True:
        left = deadline - time.monotonic()
        if left <= 0:
            raise NoReply(f"no matching frame within {timeout_s} s; got {got}")
        r = node.receive(left)
        if r is None:
            continue
        name, nid, sig, _ = r
        got.append((name, nid, sig))
        if pred(name, nid, sig):
            return got


def sentinel_get(node: PmaNode, pname: str = "telem.mask") -> list[tuple[str, int, dict[str, Any]]]:
    """Sends a GET of pname and returns every protocol frame received before
    its PARAM_RESP (the node handles frames in order, so a reply to anything
    sent before the GET would be among them)."""
    p = PROTO.param(pname)
    node.send("PARAM_REQ", {"Op": 0, "Type": TYPE_CODES[p.type], "Id": p.id, "Reserved": 0,
                            {"f32": "ValueF32", "u32": "ValueU32", "i32": "ValueI32"}[p.type]: 0})
    got = replies_until(node, lambda n, nid, s: n == "PARAM_RESP" and nid == node.node and s["Id"] == p.id
                        and s["Op"] == 0)
    return got[:-1]


def replies_of(frames, node_ids=None) -> list[tuple[str, int, dict[str, Any]]]:
    """The answers (COMMAND_ACK, PARAM_RESP) among frames."""
    return [f for f in frames if f[0] in ("COMMAND_ACK", "PARAM_RESP")
            and (node_ids is None or f[1] in node_ids)]


def param_raw(op: int, type_code: int, pid: int, reserved: int = 0, value: bytes = b"\0\0\0\0") -> bytes:
    return bytes([(op & 0xF) | ((type_code & 0xF) << 4), pid & 0xFF, (pid >> 8) & 0xFF, reserved]) + value


def param_resp(node: PmaNode, op: int, pid: int, timeout_s: float | None = None) -> dict[str, Any]:
    return node.wait_for("PARAM_RESP", lambda s: s["Op"] == op and s["Id"] == pid, timeout_s=timeout_s)


def snapshot(node: PmaNode, names: list[str] | None = None) -> dict[str, float | int]:
    """GET of every parameter (or of names)."""
    return {p.name: node.get(p.name) for p in PROTO.params if names is None or p.name in names}


# ------------------------------------------------------------ plant rig --

class Rig:
    """The plant side of the bridge in lockstep mode: one PLANT_SENSOR per
    tick, Seq +1 each, returning the PLANT_ACTUATOR computed from it."""

    def __init__(self, node: PmaNode, seq: int = 0, counts: int = COUNTS_MID) -> None:
        self.node = node
        self.seq = seq & 0xFF
        self.counts = counts

    def tick(self, counts: int | None = None, host_heartbeat: bool = False) -> dict[str, Any]:
        if host_heartbeat:
            self.node.host_heartbeat()
        c = self.counts if counts is None else counts
        act = self.node.exchange_sample(self.seq, c)
        self.seq = (self.seq + 1) & 0xFF
        return act

    def repeat(self) -> dict[str, Any]:
        """The previous sample again (a duplicate: same Seq)."""
        prev = (self.seq - 1) & 0xFF
        return self.node.exchange_sample(prev, self.counts)

    def ticks(self, n: int, **kw) -> list[dict[str, Any]]:
        return [self.tick(**kw) for _ in range(n)]


def arm(node: PmaNode, rig: Rig | None = None, settle_ticks: int = 20) -> Rig:
    """A valid sample, ARM, then settle_ticks ticks (the pressure reaches p0)."""
    rig = rig or Rig(node)
    rig.tick()
    ack = node.arm()
    assert ack.result == 0 and ack.state == STATE["ARMED"], ack
    rig.ticks(settle_ticks)
    return rig


def arm_and_start(node: PmaNode, rig: Rig | None = None, settle_ticks: int = 20) -> Rig:
    rig = arm(node, rig, settle_ticks)
    ack = node.start()
    assert ack.result == 0 and ack.state == STATE["RUNNING"], ack
    return rig


# ------------------------------------------------------- raw SocketCAN --

class RawCan:
    """A raw SocketCAN socket for frames python-can's Message does not make
    simply: error frames, classic frames with any can_id flags, CAN FD."""

    def __init__(self, fd: bool = False) -> None:
        self.s = socket.socket(socket.PF_CAN, socket.SOCK_RAW, socket.CAN_RAW)
        if fd:
            self.s.setsockopt(socket.SOL_CAN_RAW, socket.CAN_RAW_FD_FRAMES, 1)
        self.s.bind((CHANNEL,))

    def send(self, can_id: int, data: bytes = b"", dlc: int | None = None) -> None:
        n = len(data) if dlc is None else dlc
        self.s.send(struct.pack("=IB3x8s", can_id, n, data.ljust(8, b"\0")))

    def send_fd(self, can_id: int, data: bytes, flags: int = 0) -> None:
        self.s.send(struct.pack("=IBB2x64s", can_id, len(data), flags, data.ljust(64, b"\0")))

    def bus_off(self) -> None:
        self.send(CAN_ERR_FLAG | CAN_ERR_BUSOFF, bytes(8), dlc=CAN_ERR_DLC)

    def close(self) -> None:
        self.s.close()

    def __enter__(self) -> "RawCan":
        return self

    def __exit__(self, *exc) -> None:
        self.close()


class frozen:
    """with frozen(pid): ... -- the process is stopped (SIGSTOP, and seen
    stopped in /proc) for the block, so that frames sent meanwhile reach it
    all at once when it continues (SIGCONT)."""

    def __init__(self, pid: int) -> None:
        self.pid = pid

    def _state(self) -> str:
        with open(f"/proc/{self.pid}/stat") as f:
            return f.read().rsplit(")", 1)[1].split()[0]

    def __enter__(self) -> "frozen":
        os.kill(self.pid, signal.SIGSTOP)
        deadline = time.monotonic() + 5.0
        while self._state() not in ("T", "t"):
            if time.monotonic() > deadline:
                raise TimeoutError(f"process {self.pid} did not stop")
            time.sleep(0.001)
        return self

    def __exit__(self, *exc) -> None:
        os.kill(self.pid, signal.SIGCONT)


def params_by_access(access: str) -> list[Param]:
    return [p for p in PROTO.params if p.access == access]


__all__ = [n for n in dir() if not n.startswith("_")]
