# SPDX-License-Identifier: Apache-2.0
"""Finding the nodes on a bus (scan) and watching it (BusMonitor).
"""
from __future__ import annotations

import time
from dataclasses import dataclass

from pmactl.node import OPS, PmaNode, Status


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


