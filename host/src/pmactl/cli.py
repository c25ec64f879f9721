# SPDX-License-Identifier: Apache-2.0
"""pmactl: tune, command and watch PMA nodes over CAN (the command line; the protocol
logic is in pmactl.client)."""
from __future__ import annotations

import argparse
import difflib
import fnmatch
import importlib.metadata
import json
import logging
import math
import os
import struct
import sys
import time
from pathlib import Path
from typing import Any, Callable, Sequence

import can
import cantools

from pmactl import adapters, identity, paramfile
from pmactl.client import (
    NODE_REPLIES,
    BadBusConfig,
    BusMonitor,
    CommandError,
    InterfaceError,
    MonitorEvent,
    NodeStateError,
    NoReply,
    ParamInfo,
    PmaError,
    PmaNode,
    RecordProgress,
    SetRejected,
    Status,
    TelemetryRecorder,
    bus_config,
    describe_bus,
    open_bus,
    scan,
    wire_value,
)
from pmactl.nodedbc import NodeListError, node_dbc_text, parse_nodes, write_node_dbc
from pmactl.protocol import BROADCASTS, Param, Protocol, load_protocol
from pmactl.recording import RecordingError, metrics, read_recording

EXIT_OK = 0
EXIT_REFUSED = 1        # the node refused (a command, a parameter set) or cannot do it now
EXIT_USAGE = 2          # bad command line or bad value: nothing was sent
EXIT_INTERFACE = 3      # the CAN interface could not be opened or failed
EXIT_NO_REPLY = 4       # no reply (or no node, no telemetry) within the timeout
EXIT_FILE = 5           # a file that cannot be read, parsed or validated: nothing was sent
EXIT_INTERRUPTED = 130  # Ctrl-C (monitor and record end normally on Ctrl-C instead)

EXIT_CODES_HELP = """\
exit status:
  0    success
  1    the node refused: a command or parameter set answered with an error code
       (printed with its name and meaning), or the node is not in a state to do it
  2    bad command line or bad value (unknown parameter, out of range): nothing sent
  3    the CAN interface could not be opened, or failed
  4    no reply within --timeout (no such node, node not answering, no telemetry)
  5    bad file (unreadable, not JSON/YAML/CSV, or an entry failing validation):
       nothing sent
  130  interrupted (Ctrl-C); monitor and record end normally on Ctrl-C

The bus: --interface/--channel/--bitrate, else python-can's configuration (CAN_INTERFACE,
CAN_CHANNEL, CAN_BITRATE, CAN_CONFIG, ~/.canrc, ...), else socketcan on vcan0.
"""


class UsageError(Exception):
    """A bad value on the command line (exit 2)."""


# ------------------------------------------------------------------ parser --
def _common(p: argparse.ArgumentParser, suppress: bool) -> None:
    d = argparse.SUPPRESS if suppress else None
    g = p.add_argument_group("bus and node")
    g.add_argument("--interface", "-i", default=d,
                   help="python-can interface (socketcan, pcan, kvaser, slcan, virtual, ...); "
                        "default: python-can's configuration, else socketcan")
    g.add_argument("--channel", "-c", default=d,
                   help="channel (vcan0, can0, PCAN_USBBUS1, ...); default: python-can's "
                        "configuration, else vcan0 for socketcan")
    g.add_argument("--bitrate", "-b", type=int, default=d,
                   help="bit rate in bit/s for interfaces that set it (the protocol's is 1000000); "
                        "default: python-can's configuration")
    g.add_argument("--node", "-n", type=_node_list, default=argparse.SUPPRESS if suppress else [0],
                   metavar="ID[,ID...]",
                   help="node id 0..15 (default 0), or a list (1,2,5; ranges: 1-3): the command "
                        "runs on each, with a report per node")
    g.add_argument("--all", "-a", action="store_true", default=argparse.SUPPRESS if suppress else False,
                   help="every node on the bus (the ones whose heartbeat arrives within "
                        "--timeout); estop: ESTOP_ALL")
    g.add_argument("--timeout", "-t", type=_positive, default=argparse.SUPPRESS if suppress else 1.0,
                   help="seconds to wait for a reply (default 1.0)")
    g.add_argument("--verbose", "-v", action="store_true", default=argparse.SUPPRESS if suppress else False,
                   help="show python-can's own log messages (warnings from the interface driver)")


def _node_id(text: str) -> int:
    try:
        v = int(text, 0)
    except ValueError:
        raise argparse.ArgumentTypeError(f"node id {text!r} is not a number") from None
    if not 0 <= v <= 15:
        raise argparse.ArgumentTypeError(f"node id {v} outside 0..15")
    return v


def _node_list(text: str) -> list[int]:
    try:
        return parse_nodes(text)
    except NodeListError as e:
        raise argparse.ArgumentTypeError(str(e)) from None


def _at_least(text: str, low: float, strict: bool, what: str) -> float:
    """A finite number above low (strict) or at least low; argparse's error names `what`."""
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
    if not (math.isfinite(v) and (v > low if strict else v >= low)):
        raise argparse.ArgumentTypeError(f"{text} is not {what}")
    return v


def _positive_value(unit: str) -> Callable[[str], float]:
    """argparse type: a finite number above 0, its error naming the unit ("cm", "seconds")."""
    def parse(text: str) -> float:
        return _at_least(text, 0.0, True, f"a positive number of {unit}")
    parse.__name__ = f"positive number of {unit}"
    return parse


_positive = _positive_value("seconds")
_positive_cm = _positive_value("cm")
_positive_ratio = _positive_value("times what the reference needs")


def _text(what: str) -> Callable[[str], str]:
    """argparse type: a string that is not empty (or blank); what names it in the error."""
    def parse(text: str) -> str:
        if not text.strip():
            raise argparse.ArgumentTypeError(f"the {what} is empty")
        return text
    parse.__name__ = what
    return parse


_file_name = _text("file name")

# the largest --dpi of plot and scope: 1200 dots per inch is print quality; plot's figure of
# every panel (7 x 11 in) is then 8400 x 13200 pixels (about 440 MB while it is drawn)
DPI_MAX = 1200


def _dpi(text: str) -> int:
    try:
        v = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a whole number of dots per inch") from None
    if not 1 <= v <= DPI_MAX:
        raise argparse.ArgumentTypeError(f"{v} dots per inch is outside 1..{DPI_MAX}")
    return v


def _nonnegative(text: str) -> float:
    return _at_least(text, 0.0, False, "a number >= 0")


def _count(text: str) -> int:
    try:
        v = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a whole number") from None
    if v <= 0:
        raise argparse.ArgumentTypeError(f"{v} is not positive")
    return v


def _finite(text: str) -> float:
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
    if not math.isfinite(v):
        raise argparse.ArgumentTypeError(f"{text} is not finite")
    return v


def version_text() -> str:
    """'pmactl X (protocol N, DBC "VERSION")': the tool's version and the protocol's."""
    try:
        tool = importlib.metadata.version("pmactl")
    except importlib.metadata.PackageNotFoundError:
        tool = "(not installed)"
    proto = load_protocol()
    return f'pmactl {tool} (protocol {proto.version}, DBC VERSION "{proto.db.version}")'


def build_parser() -> argparse.ArgumentParser:
    fmt = argparse.RawDescriptionHelpFormatter
    parser = argparse.ArgumentParser(
        prog="pmactl", formatter_class=fmt,
        description="Tune, command and watch PMA controller nodes over CAN "
                    "(protocol: firmware/protocol/pma_proto.dbc, parameters: docs/parameters.md).",
        epilog=EXIT_CODES_HELP)
    parser.add_argument("--version", action="version", version=version_text(),
                        help="the tool's version and the protocol version it speaks, and exit")
    _common(parser, suppress=False)
    common = argparse.ArgumentParser(add_help=False)
    _common(common, suppress=True)
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)

    def add(name: str, help_text: str, **kw: Any) -> argparse.ArgumentParser:
        return sub.add_parser(name, help=help_text, description=help_text, parents=[common],
                              formatter_class=fmt, epilog=EXIT_CODES_HELP, **kw)

    p = add("scan", "list the nodes on the bus (heartbeats) and the devices behind them "
                    "(DEVICE_INFO): firmware, unique id; two devices on one node id are reported")
    p.add_argument("--seconds", type=_positive, default=1.0, help="how long to listen (default 1.0 s)")

    add("status", "the node's state, fault, flags, controller, reference and reset cause, and "
                  "its identity")
    add("info", "the node's identity (DEVICE_INFO): firmware version and commit, build target, "
                "protocol version, parameter table, unique device id")
    p = add("counters", "the node's counters and status values (GET_STATUS) by name: the last rule "
                        "that refused, frames lost, dropped or bad, ticks, and the PPC's lost "
                        "guarantee (lost ticks, when it was first lost) and barrier clamps")
    p.add_argument("names", nargs="*", metavar="NAME",
                   help="only these (e.g. GUARANTEE_LOST_TICKS; case does not matter)")

    p = add("params", "read, write, save and restore parameters")
    psub = p.add_subparsers(dest="params_command", metavar="ACTION", required=True)

    def padd(name: str, help_text: str) -> argparse.ArgumentParser:
        return psub.add_parser(name, help=help_text, description=help_text, parents=[common],
                               formatter_class=fmt, epilog=EXIT_CODES_HELP)

    q = padd("list", "every parameter with its value, unit, range, default and access, as the "
                     "node reports them (* marks a value that differs from the default)")
    q.add_argument("patterns", nargs="*", metavar="PATTERN",
                   help="only names matching: a group (ppc), a glob (ppc.w*) or a name")
    q = padd("get", "the value of parameters")
    q.add_argument("names", nargs="+", metavar="NAME", help="parameter name (or id)")
    q = padd("set", "set a parameter in the node's RAM (save to keep it)")
    q.add_argument("name", metavar="NAME")
    q.add_argument("value", metavar="VALUE", help="a number in the parameter's unit, or an "
                                                  "enumeration value's name")
    q.add_argument("--no-check", action="store_true",
                   help="send without checking the value against the table (the node checks)")
    padd("save", "write every parameter to the node's storage (output inactive only)")
    padd("restore-defaults", "set every parameter to its default in RAM (save to keep them)")
    padd("revert", "replace the parameters in RAM by the set saved in storage (LOAD)")
    q = padd("dump", "write every parameter to a file (JSON; YAML with PyYAML; '-': stdout)")
    q.add_argument("file", metavar="FILE", type=_file_name)
    q = padd("load", "set the parameters of a file; every entry is checked before any is sent")
    q.add_argument("file", metavar="FILE", type=_file_name)
    q.add_argument("--dry-run", action="store_true", help="check the file and show what would change")
    q.add_argument("--send-all", action="store_true",
                   help="send every entry, also those the node already has")
    q.add_argument("--with-node-id", action="store_true",
                   help="also load sys.node_id (by default never: a file copied to another node "
                        "must not give both one id)")

    for name, text in (("arm", "IDLE -> ARMED: the output holds the preset pressure"),
                       ("disarm", "ARMED or RUNNING -> IDLE: the safe output"),
                       ("start", "ARMED -> RUNNING: the selected controller tracks the reference"),
                       ("stop", "RUNNING -> ARMED"),
                       ("clear-faults", "FAULT -> IDLE: clear the latched fault")):
        add(name, text)
    add("estop", "emergency stop: the node (or with --all every node, ESTOP_ALL) enters FAULT")
    p = add("restart", "software reset of the node (output inactive only: IDLE or FAULT); "
                       "unsaved parameter changes are lost; waits until it is back")
    p.add_argument("--wait", type=_positive, default=10.0, metavar="S",
                   help="how long to wait for the node to come back (default 10 s)")
    p = add("node-id", "move the node to another node id safely: checks that no device answers "
                       "on NEW, sets and saves sys.node_id, restarts the node (RESTART) and "
                       "verifies that the same device (unique id) answers on NEW")
    p.add_argument("new_id", type=_node_id, metavar="NEW", help="the new node id, 0..15")
    p.add_argument("--wait", type=_positive, default=60.0, metavar="S",
                   help="how long to wait for the restarted node on NEW (default 60 s)")
    p = add("controller", "select the controller run by the next START (no NAME: show it)")
    p.add_argument("name", nargs="?", metavar="NAME", help="OFF, PPC, MFAC, PID or OPEN_LOOP")
    p = add("reference", "select the reference of the next START (no NAME: show it)")
    p.add_argument("name", nargs="?", metavar="NAME",
                   help="HOLD, STEP, RAMP, SINE, CASE1, CASE3 or STREAM")
    p = add("setpoint", "send a set-point to a node RUNNING the STREAM reference")
    p.add_argument("x_cm", type=_finite, metavar="X_CM", help="target position in cm")
    p.add_argument("--no-check", action="store_true",
                   help="send even when the node would drop it (not RUNNING STREAM, outside the band)")

    p = add("record", "record telemetry (TELEM_A..E) to CSV, every frame to a .blf/.asc log")
    p.add_argument("csv", metavar="CSV", type=_file_name,
                   help="output file (one row per telemetry tick, units in the header)")
    p.add_argument("--seconds", type=_positive, default=10.0, help="how long to record (default 10 s)")
    p.add_argument("--samples", type=_count, help="stop after this many rows")
    p.add_argument("--log", metavar="FILE", type=_file_name,
                   help="python-can log of every frame: .blf, .asc or .log (default: the CSV's name with .blf)")
    p.add_argument("--no-log", action="store_true", help="no frame log")
    p.add_argument("--start", action="store_true",
                   help="send START when the recording begins (node ARMED) and STOP at its end")
    p.add_argument("--no-host-heartbeat", action="store_true",
                   help="do not send HOST_HEARTBEAT (another program keeps the node alive)")
    p.add_argument("--all-frames", action="store_true",
                   help="receive and log every frame on the bus (default: the node's replies, "
                        "heartbeats and telemetry; a busy bus can then overrun pmactl)")
    p.add_argument("--quiet", "-q", action="store_true", help="no progress display")

    p = add("commission", "measure a freshly wired rig over CAN and derive the controllers' parameters "
                          "(docs/commissioning.md): wiring check, static map, step responses, rules; the node "
                          "must be IDLE with its sensor and DAC scalings set. Without --apply nothing changes "
                          "on the node")
    p.add_argument("--w1", type=_positive_cm, required=True, metavar="CM",
                   help="the task's accuracy w1 [cm] (within ppc.w1_cm's range)")
    p.add_argument("--t-u", type=_positive, required=True, metavar="S",
                   help="the task's tuning time t_u [s] (within ppc.t_u_s's range)")
    p.add_argument("--x-min", type=_finite, metavar="CM",
                   help="the lower output constraint [cm] (default: the node's safety.x_min_cm)")
    p.add_argument("--x-max", type=_finite, metavar="CM",
                   help="the upper output constraint [cm] (default: the node's safety.x_max_cm)")
    p.add_argument("--x-start", type=_finite, metavar="CM",
                   help="where the task's reference starts [cm], within x-min + w1 .. x-max - w1 "
                        "(default: the band's middle)")
    p.add_argument("--speed", type=_nonnegative, default=0.0, metavar="CM_S",
                   help="the reference's largest speed [cm/s] (default 0: set-points)")
    p.add_argument("--mean-speed", type=_nonnegative, metavar="CM_S",
                   help="the reference's mean speed |dx_r/dt| [cm/s], at most --speed: what the sensor's "
                        "noise through the law is weighed against (default: a sine's, 2/pi of "
                        "--speed)")
    p.add_argument("--noise-limit", type=_positive_ratio, metavar="K",
                   help="a quieter valve: the velocity observer slower (and the loop the margins then allow) "
                        "until the sensor's noise moves the input at most K times what the reference needs, "
                        "at some accuracy (docs/commissioning.md, 'A quieter valve'; default: no bound, the "
                        "observer as fast as the margins want)")
    p.add_argument("--out", metavar="DIR", type=_file_name,
                   help="write report.json, params.json (the params dump format) and figures (static map, "
                        "step responses, noise) into DIR")
    p.add_argument("--apply", action="store_true", help="SET the derived parameters on the node (RAM)")
    p.add_argument("--save", action="store_true", help="with --apply: also SAVE them (persist)")
    p.add_argument("--quiet", "-q", action="store_true", help="no progress display")

    p = add("plot", "PNG figures of a recording, in the style of the paper's, and its numbers "
                    "(entry into the w1 band, max |e| and RMSTE after t_u, peak velocity and input)")
    p.add_argument("csv", metavar="CSV", type=_file_name)
    p.add_argument("--out", metavar="PREFIX", type=_file_name,
                   help="writes PREFIX.png and PREFIX_<panel>.png (default: the CSV without .csv)")
    p.add_argument("--w1", type=_positive_cm, metavar="CM", help="draw the accuracy band +-w1 on the error")
    p.add_argument("--band", type=_finite, nargs=2, metavar=("LOW_CM", "HIGH_CM"),
                   help="draw the constraints on the position (LOW_CM < HIGH_CM)")
    p.add_argument("--t-u", type=_positive, metavar="S", help="mark the tuning time t_u")
    p.add_argument("--title")
    p.add_argument("--no-meta", action="store_true",
                   help="ignore the recording's .meta.json (by default w1, t_u and the band come from it)")
    p.add_argument("--dpi", type=_dpi, default=150, help=f"resolution (default 150, at most {DPI_MAX})")
    p.add_argument("--no-panels", action="store_true",
                   help="only PREFIX.png (all panels), not one PNG per panel")

    p = add("scope", "live view of running nodes' telemetry: x and x_r, e with +-w1, u, pressure, over "
                     "a rolling window; keys: space pause, r record (CSV as record's), s save PNG, q quit")
    p.add_argument("--nodes", type=_node_list, metavar="LIST",
                   help="the nodes to show: 1,2,5 or 0-3 (default: --node)")
    p.add_argument("--window", type=_positive, default=10.0, metavar="S",
                   help="rolling window in s (default 10)")
    p.add_argument("--fps", type=_positive_value("frames per second"), default=30.0,
                   help="redraws per second (default 30)")
    p.add_argument("--w1", type=_positive_cm, metavar="CM",
                   help="the +-w1 band on e (default: each PPC node's ppc.w1_cm)")
    p.add_argument("--host-heartbeat", action="store_true",
                   help="send HOST_HEARTBEAT to the nodes (keeps them RUNNING without record/monitor)")
    p.add_argument("--csv", metavar="CSV", type=_file_name,
                   help="recording file (several nodes: CSV's stem + _n<node>); default "
                        "scope-<date>-<time>.csv when r is pressed")
    p.add_argument("--record", action="store_true", help="record from the start")
    p.add_argument("--seconds", type=_positive, help="stop after this long")
    p.add_argument("--frames", type=_count, help="stop after this many frames drawn")
    p.add_argument("--headless", action="store_true",
                   help="no window: render with Agg and write each frame as PNG (--out, --frames)")
    p.add_argument("--out", metavar="PREFIX", default="scope", type=_file_name,
                   help="headless: writes PREFIX_0001.png, ... (default scope)")
    p.add_argument("--dpi", type=_dpi, default=80, help=f"resolution (default 80, at most {DPI_MAX})")

    p = add("dbc", "write a DBC of the protocol for every node given: each node's messages at "
                   "their frame ids (NAME_N<node>), for cantools, SavvyCAN and other viewers")
    p.add_argument("--nodes", type=_node_list, default=list(range(16)), metavar="LIST",
                   help="node ids: 0-15 (the default), 1,2,5 or 0-3,8")
    p.add_argument("-o", "--output", metavar="FILE", default="-", type=_file_name,
                   help="the DBC file to write (default '-': stdout)")

    p = add("monitor", "heartbeats and faults of every node, live, until Ctrl-C")
    p.add_argument("--seconds", type=_positive, help="stop after this long")
    p.add_argument("--every", action="store_true", help="print every heartbeat, not only changes")
    p.add_argument("--silent-after", type=_positive, default=1.0, metavar="S",
                   help="report a node silent after this long without a heartbeat (default 1.0 s)")
    p.add_argument("--host-heartbeat", action="store_true",
                   help="send HOST_HEARTBEAT to --node while monitoring (keeps it RUNNING)")
    return parser


# ----------------------------------------------------------------- helpers --
class Session:
    """The parsed arguments, the protocol, and the bus (opened on first use)."""

    def __init__(self, args: argparse.Namespace, out: Callable[[str], None]) -> None:
        self.args = args
        self.out = out
        self.proto: Protocol = load_protocol()
        self._bus: can.BusABC | None = None
        self._node: PmaNode | None = None
        self.cfg: dict[str, Any] | None = None
        # the node id the command works on now (one of --node's, or of --all's)
        self.node_id: int = args.node[0]

    @property
    def bus(self) -> can.BusABC:
        if self._bus is None:
            self.cfg = bus_config(self.args.interface, self.args.channel, self.args.bitrate)
            self._bus = open_bus(self.cfg)
        return self._bus

    def use_node(self, node_id: int) -> None:
        """The next commands go to node_id (same bus)."""
        if node_id != self.node_id:
            self.node_id = node_id
            self._node = None

    @property
    def node(self) -> PmaNode:
        if self._node is None:
            self._node = PmaNode(self.bus, self.node_id, self.proto, timeout_s=self.args.timeout)
            # Only the frames the command needs: on a bus with a 1 kHz plant bridge a
            # client that takes every frame falls behind (record sets its own).
            cmd = self.args.command
            if cmd == "scan" or (cmd == "estop" and self.args.all):
                self._node.listen_to(["HEARTBEAT", "DEVICE_INFO"], node=None)
            elif cmd == "node-id":   # this node's replies, and every node's identity
                self._node.listen_to(NODE_REPLIES, node=None)
            elif cmd == "monitor":
                self._node.listen_to(["HEARTBEAT", "ESTOP", "ESTOP_ALL", "COMMAND", "COMMAND_ACK",
                                      "PARAM_RESP"], node=None)
            elif cmd == "commission":  # the replies, and the telemetry it steps the rig by
                self._node.listen_to(list(NODE_REPLIES) + ["TELEM_A", "TELEM_E"])
            elif cmd not in ("record", "scope"):
                self._node.listen_to(NODE_REPLIES)
        return self._node

    @property
    def bus_text(self) -> str:
        return describe_bus(self.cfg) if self.cfg else "?"

    def close(self) -> None:
        if self._bus is not None:
            try:
                self._bus.shutdown()
            except Exception:       # noqa: BLE001 - closing must not hide the command's result
                pass

    def param(self, name: str) -> Param:
        try:
            return self.proto.param(name)
        except KeyError:
            close = difflib.get_close_matches(name, list(self.proto.by_name), n=3)
            hint = f" (did you mean {', '.join(close)}?)" if close else \
                " (pmactl params list shows them all)"
            raise UsageError(f"unknown parameter {name!r}{hint}") from None


def _value_unit(p: Param | None, text: str) -> str:
    unit = p.unit if p else ""
    if p and p.values:
        return text
    return f"{text} {unit}" if unit else text


def _enum_text(p: Param, value: float | int) -> str:
    return f"{p.text(value)} ({int(value)})" if p.values else _value_unit(p, p.text(value))


def _table(rows: list[list[str]], right: set[int]) -> list[str]:
    widths = [max(len(r[i]) for r in rows) for i in range(len(rows[0]))]
    lines = []
    for r in rows:
        cells = [c.rjust(w) if i in right else c.ljust(w) for i, (c, w) in enumerate(zip(r, widths))]
        lines.append("  ".join(cells).rstrip())
    return lines


def _check_output(path: Path, what: str, create_dir: bool = False) -> None:
    """An output file that can be written: a file name (not a directory, not '.'), in a
    directory that exists (create_dir: or that will be made) and is writable. UsageError
    (exit 2, nothing sent) otherwise: every output is checked before the bus is touched."""
    label = f"{what} {path}" if what else str(path)
    if path.name in ("", ".", "..") or path.is_dir():
        raise UsageError(f"{label}: is a directory (give a file name)")
    parent = path.parent
    if not parent.exists() and not create_dir:
        raise UsageError(f"{label}: directory {parent} does not exist")
    while not parent.exists():       # create_dir: the directory made is in the first that exists
        parent = parent.parent
    if not parent.is_dir():
        raise UsageError(f"{label}: {parent} is not a directory")
    if not os.access(parent, os.W_OK | os.X_OK) or (path.exists() and not os.access(path, os.W_OK)):
        raise UsageError(f"{label}: not writable")


def _check_outputs(outputs: Sequence[tuple[str, Path | None]], inputs: Sequence[tuple[str, Path]] = (),
                   create_dir: bool = False) -> None:
    """Each output checked (_check_output), and no two of the files, outputs and inputs,
    the same file (one would overwrite the other)."""
    seen: dict[Path, str] = {}
    for what, path in inputs:
        seen[path.resolve()] = f"{what} {path}"
    for what, out in outputs:
        if out is None:
            continue
        _check_output(out, what, create_dir)
        key = out.resolve()
        if key in seen:
            raise UsageError(f"{what} {out} is the same file as {seen[key]}: give them different names")
        seen[key] = f"{what} {out}"


def _status_lines(st: Status, bus_text: str) -> list[str]:
    flags = " ".join(st.flag_names) or "-"
    return [f"node {st.node} on {bus_text}",
            f"  state        {st.state_name}",
            f"  fault        {st.fault_name} ({st.fault})",
            f"  flags        0x{st.flags:04X} {flags}",
            f"  controller   {st.controller_name} ({st.controller})",
            f"  reference    {st.reference_name} ({st.reference})",
            f"  reset cause  {st.reset_cause_name} ({st.reset_cause})"]


# ---------------------------------------------------------------- commands --
def _identity_lines(dev: identity.DeviceInfo) -> list[str]:
    return [f"  firmware     {dev.fw_text} ({dev.build_target or '?'})",
            f"  protocol     {dev.protocol_version if dev.protocol_version is not None else '?'}",
            f"  parameters   {dev.param_count if dev.param_count is not None else '?'}, table hash "
            f"{'?' if dev.param_table_hash is None else f'{dev.param_table_hash:08x}'}",
            f"  unique id    {dev.uid_hex}"] + [f"  warning      {p}" for p in dev.problems]


def cmd_scan(s: Session) -> int:
    node = s.node
    found, devices = identity.scan_with_identity(node, s.args.seconds)
    if not found and not devices:
        raise NoReply(f"no node heartbeat on {s.bus_text} within {s.args.seconds:g} s")
    rows = [["node", "state", "fault", "controller", "reference", "firmware", "unique id", "flags"]]
    for nid in sorted(set(found) | set(devices)):
        st = found.get(nid)
        known: list[identity.DeviceInfo | None] = list(devices.get(nid, []))
        for dev in known or [None]:
            fw = dev.fw_text if dev is not None else "(no DEVICE_INFO)"
            uid = dev.uid_hex if dev is not None else "?"
            if st is None:
                rows.append([str(nid), "?", "?", "?", "?", fw, uid, "(no heartbeat)"])
            else:
                rows.append([str(nid), st.state_name, st.fault_name, st.controller_name,
                             st.reference_name, fw, uid, " ".join(st.flag_names) or "-"])
    for line in _table(rows, {0}):
        s.out(line)
    s.out(f"{len(found)} node(s) on {s.bus_text}")
    status = EXIT_OK
    for nid, devs in devices.items():
        for dev in devs:
            for problem in dev.problems:
                s.out(f"warning: node {nid} (unique id {dev.uid_hex}): {problem}")
                status = EXIT_REFUSED
        if len(devs) > 1:
            _err(f"node id {nid} is used by {len(devs)} devices (unique ids "
                 f"{', '.join(d.uid_hex for d in devs)}): their frames mix; give all but one "
                 f"another id (pmactl --node {nid} params set sys.node_id N, then save and "
                 f"restart them one at a time)")
            status = EXIT_REFUSED
    return status


def cmd_info(s: Session) -> int:
    dev = identity.device_info(s.node)
    s.out(f"node {dev.node} on {s.bus_text}")
    for line in _identity_lines(dev):
        s.out(line)
    return EXIT_REFUSED if dev.problems else EXIT_OK


def cmd_status(s: Session) -> int:
    st = s.node.status()
    for line in _status_lines(st, s.bus_text):
        s.out(line)
    try:
        dev = identity.device_info(s.node)
    except NoReply as e:
        s.out(f"  identity     none: {e}")
        return EXIT_OK
    for line in _identity_lines(dev):
        s.out(line)
    return EXIT_REFUSED if dev.problems else EXIT_OK


# how a status value reads (docs/protocol.md, "Status values"): the others are plain counts
NO_VALUE = 0xFFFFFFFF


def _status_text(name: str, value: int) -> str:
    if name == "GUARANTEE_LOST_AT_MS":
        return "never (the guarantee holds)" if value == NO_VALUE else f"{value} ms after START"
    if name == "LAST_RULE":
        return "none" if value == 0 else f"rule {value} (docs/parameters.md, rules between parameters)"
    return str(value)


def cmd_counters(s: Session) -> int:
    known = s.proto.status_ids
    names = [n.upper() for n in s.args.names] or sorted(known, key=lambda n: known[n])
    unknown = [n for n in names if n not in known]
    if unknown:
        raise UsageError(f"no status value {', '.join(unknown)} (known: {', '.join(known)})")
    width = max(len(n) for n in names)
    for name in names:
        s.out(f"  {name:<{width}}  {_status_text(name, s.node.status_value(name))}")
    return EXIT_OK


def _matches(name: str, patterns: list[str]) -> bool:
    if not patterns:
        return True
    return any(name == p or name.startswith(p + ".") or fnmatch.fnmatchcase(name, p) for p in patterns)


def cmd_params_list(s: Session) -> int:
    for pat in s.args.patterns:
        if not any(_matches(n, [pat]) for n in s.proto.by_name):
            raise UsageError(f"no parameter matches {pat!r} (groups: "
                             f"{', '.join(sorted({n.split('.')[0] for n in s.proto.by_name}))})")
    node = s.node
    ids = node.ids()
    if not ids:
        raise NoReply(f"node {node.node} lists no parameters")
    rows = [["id", "name", "value", "unit", "min", "max", "default", "access"]]
    unknown = 0
    for pid in ids:
        p = s.proto.by_id.get(pid)
        if p is not None and not _matches(p.name, s.args.patterns):
            continue
        if p is None and s.args.patterns:
            continue
        info: ParamInfo = node.param_info(pid)
        changed = " " if (p.same(info.value, info.default) if p else info.value == info.default) else "*"
        unknown += p is None
        rows.append([str(pid), info.name, info.text(info.value) + changed,
                     (info.unit or "-") if p else "?", info.text(info.min), info.text(info.max),
                     info.text(info.default), p.access if p else "?"])
    for line in _table(rows, {0}):
        s.out(line)
    if unknown:
        s.out(f"({unknown} id(s) unknown to this pmactl: a newer firmware? names and units come "
              f"from the package's params.toml)")
    return EXIT_OK


def cmd_params_get(s: Session) -> int:
    params = [s.param(n) for n in s.args.names]
    node = s.node
    for p in params:
        s.out(f"{p.name} = {_enum_text(p, node.get(p.id))}")
    return EXIT_OK


def cmd_params_set(s: Session) -> int:
    p = s.param(s.args.name)
    try:
        # --no-check leaves the table's range to the node, but the frame's value signal
        # (PARAM_REQ ValueF32/U32/I32) has its own: out of it, nothing can be sent
        value = wire_value(s.proto, p, s.args.value if s.args.no_check else p.check(s.args.value))
    except ValueError as e:
        raise UsageError(str(e)) from None
    node = s.node
    old = node.get(p.id)
    try:
        new = node.set(p.id, value)
    except (cantools.database.EncodeError, OverflowError, struct.error) as e:
        raise UsageError(f"{p.name}: {s.args.value!r} cannot be sent as {p.type}: {e}") from None
    s.out(f"{p.name} = {_value_unit(p, p.text(new))} (was {p.text(old)})")
    return EXIT_OK


def cmd_params_simple(s: Session) -> int:
    node = s.node
    action = s.args.params_command
    if action == "save":
        node.save()
        s.out(f"node {node.node}: parameters saved to storage")
    elif action == "restore-defaults":
        node.restore_defaults()
        s.out(f"node {node.node}: every parameter at its default in RAM (params save to keep them)")
    elif action == "revert":
        node.load()
        s.out(f"node {node.node}: parameters loaded from storage")
    return EXIT_OK


def cmd_params_dump(s: Session) -> int:
    path = s.args.file.replace("{node}", str(s.node_id))
    paramfile._kind(path)            # a bad file name fails before the bus is touched
    if path != "-":                  # and so does a file that cannot be written
        _check_output(Path(path), "params dump")
    node = s.node
    values = node.values()
    try:
        dev = identity.device_info(node)
        firmware: dict[str, Any] | None = {
            "version": dev.fw_text, "protocol_version": dev.protocol_version,
            "param_table_hash": None if dev.param_table_hash is None
            else f"{dev.param_table_hash:08x}", "unique_id": dev.uid_hex}
    except NoReply:
        firmware = None              # a firmware without DEVICE_INFO: values only
    paramfile.write(path, s.proto, values, node.node, firmware)
    known = sum(1 for pid in values if pid in s.proto.by_id)
    if path != "-":
        s.out(f"{known} parameters of node {node.node} written to {path}"
              + ("" if firmware else " (the node sent no DEVICE_INFO: firmware not recorded)"))
    return EXIT_OK


def _plan_lines(s: Session, plan: paramfile.LoadPlan) -> None:
    if not plan.same_table:
        s.out(f"the file is of another firmware ({plan.file_firmware or 'version not recorded'}"
              f"; pmactl's table {paramfile.table_hash(s.proto):08x}): mapped by name")
    for old, new in plan.renamed:
        s.out(f"renamed {old} -> {new}")
    for p, was, now in plan.clamped:
        s.out(f"clamped {p.name} = {was} to {_value_unit(p, p.text(now))} (range {p.text(p.min)}.."
              f"{p.text(p.max)})")
    for why in plan.dropped:
        s.out(f"dropped {why}")
    if plan.lacking and not plan.same_table:
        s.out(f"not in the file ({len(plan.lacking)}, they keep the node's values): "
              + ", ".join(p.name for p in plan.lacking))
    if plan.node_id_skipped:
        s.out(f"{paramfile.NODE_ID_PARAM} not loaded (--with-node-id loads it)")


def cmd_params_load(s: Session) -> int:
    plan = paramfile.plan(s.args.file, paramfile.read(s.args.file), s.proto,
                          with_node_id=s.args.with_node_id)
    entries = plan.entries
    if not entries:                  # nothing to send: a bad file, not a success without a node
        why = ["no parameter to load (\"params\" lists none)"] if not plan.dropped and not plan.node_id_skipped \
            else ["no parameter to load: every entry was left out"] + [f"dropped {d}" for d in plan.dropped] \
            + ([f"{paramfile.NODE_ID_PARAM} is loaded only with --with-node-id"] if plan.node_id_skipped else [])
        raise paramfile.ParamFileError(s.args.file, why)
    node = s.node
    _plan_lines(s, plan)
    if s.args.dry_run:
        current = node.values([p.id for p, _ in entries])
        n = 0
        for p, value in entries:
            if not p.same(current[p.id], value):
                n += 1
                s.out(f"would set {p.name} = {_value_unit(p, p.text(value))} (now {p.text(current[p.id])})")
        s.out(f"{len(entries)} entries valid, {n} would change (dry run: nothing sent)")
        return EXIT_OK
    report = node.load_values(entries, skip_unchanged=not s.args.send_all)
    for p, old, new in report.changed:
        s.out(f"set {p.name} = {_value_unit(p, p.text(new))} (was {p.text(old)})")
    for e in report.rejected:
        param = e.param
        assert param is not None
        _err(f"node {node.node} rejected set {param.name} = {param.text(e.requested or 0)}: "
             f"{s.proto.status_text(e.code)}; it stays {param.text(e.current or 0)}")
    s.out(f"{len(report.changed)} set, {len(report.unchanged)} unchanged, "
          f"{len(report.rejected)} rejected (from {s.args.file})")
    return EXIT_REFUSED if report.rejected else EXIT_OK


def cmd_command(s: Session) -> int:
    node = s.node
    name = s.args.command.upper().replace("-", "_")
    ack = node.command(name)
    s.out(f"node {node.node}: {name} OK, state {node.state_name(ack.state)}")
    if name == "START":
        try:
            timeout_ms = int(node.get("safety.host_timeout_ms"))
        except (PmaError, NoReply):
            timeout_ms = -1
        if timeout_ms != 0:
            when = f"{timeout_ms} ms" if timeout_ms > 0 else "safety.host_timeout_ms"
            s.out(f"note: a RUNNING node faults (HOST_HEARTBEAT_LOST) without HOST_HEARTBEAT for "
                  f"{when}: keep `pmactl monitor --host-heartbeat` or `pmactl record` running, "
                  f"or start with `pmactl record --start`")
    return EXIT_OK


def cmd_estop(s: Session) -> int:
    node = s.node
    if not s.args.all:
        node.estop()
        st = node.wait_state("FAULT")
        s.out(f"node {node.node}: ESTOP sent, state {st.state_name} ({st.fault_name})")
        return EXIT_OK
    node.estop(all_nodes=True)
    seen = scan(node, s.args.timeout)
    if not seen:
        raise NoReply(f"ESTOP_ALL sent; no node heartbeat on {s.bus_text} within {s.args.timeout:g} s")
    not_stopped = []
    for nid, st in seen.items():
        s.out(f"node {nid}: {st.state_name} ({st.fault_name})")
        if st.state_name != "FAULT":
            not_stopped.append(nid)
    if not_stopped:
        raise NoReply(f"ESTOP_ALL sent; node(s) {', '.join(map(str, not_stopped))} not in FAULT "
                      f"within {s.args.timeout:g} s")
    s.out(f"ESTOP_ALL sent: {len(seen)} node(s) in FAULT")
    return EXIT_OK


def cmd_restart(s: Session) -> int:
    node = s.node
    st = node.status()
    if st.state_name not in ("IDLE", "FAULT", "BOOT"):
        raise NodeStateError(f"node {node.node} is {st.state_name}: disarm it first (a restart "
                             f"needs the output inactive); nothing sent")
    t0 = time.monotonic()
    back = node.restart(timeout_s=s.args.wait)
    s.out(f"node {node.node}: restarted in {time.monotonic() - t0:.2f} s: {back.state_name}, "
          f"reset cause {back.reset_cause_name}"
          + (", unsaved parameter changes discarded" if "PARAMS_CHANGED" in st.flag_names else ""))
    return EXIT_OK


def cmd_node_id(s: Session) -> int:
    node = s.node
    old, new = node.node, s.args.new_id
    if new == old:
        raise UsageError(f"node {old} already has id {new}")
    dev = identity.device_info(node)
    if dev.uid is None:
        raise NodeStateError(f"node {old} reports no unique id: it could not be told from "
                             f"another device on id {new} after the move")
    others = identity.discover(node, seconds=min(1.0, s.args.timeout)).get(new, [])
    if others:
        raise NodeStateError(f"node id {new} is already used by the device(s) "
                             f"{', '.join(d.uid_hex for d in others)}: nothing changed")
    st = node.status()
    if st.state_name not in ("IDLE", "FAULT"):
        raise NodeStateError(f"node {old} is {st.state_name}: disarm it first (sys.node_id can "
                             f"change only with the output inactive); nothing changed")
    node.set("sys.node_id", new)
    node.save()
    ack = node.command("RESTART", check=False)
    if ack.result == 0:
        s.out(f"node {old} (unique id {dev.uid_hex}): sys.node_id = {new} set and saved; "
              f"restarting it")
    else:                                   # firmware without RESTART (protocol < 4)
        s.out(f"node {old} (unique id {dev.uid_hex}): sys.node_id = {new} set and saved; it "
              f"refused RESTART ({s.proto.status_name(ack.result)}): restart the node now "
              f"(power cycle or reset) to apply it")
    deadline = time.monotonic() + s.args.wait
    moved = PmaNode(node.bus, new, s.proto, timeout_s=s.args.timeout)
    while time.monotonic() < deadline:
        try:
            found = identity.device_info(moved, timeout_s=min(1.0, s.args.timeout))
        except NoReply:
            continue
        if found.uid == dev.uid:
            s.out(f"verified: the device {dev.uid_hex} answers on node id {new}")
            return EXIT_OK
        raise NodeStateError(f"another device ({found.uid_hex}) answers on node id {new}")
    raise NoReply(f"the device {dev.uid_hex} did not answer on node id {new} within "
                  f"{s.args.wait:g} s (sys.node_id {new} is saved: it applies at its next start; "
                  f"a pma-fw-host started with --node keeps that id)")


def cmd_select(s: Session) -> int:
    which = s.args.command
    pname = "ctrl.mode" if which == "controller" else "ref.kind"
    p = s.proto.param(pname)
    if s.args.name is None:
        v = s.node.get(pname)
        s.out(f"{which} {p.text(v)} ({pname}; one of {', '.join(p.values.values())})")
        return EXIT_OK
    try:
        value = p.check(s.args.name)
    except ValueError:
        raise UsageError(f"{which} {s.args.name!r}: not one of {', '.join(p.values.values())}") from None
    node = s.node
    cmd = "SELECT_CONTROLLER" if which == "controller" else "SELECT_REFERENCE"
    ack = node.command(cmd, int(value))
    s.out(f"node {node.node}: {which} {p.text(value)} (at the next START), state {node.state_name(ack.state)}")
    return EXIT_OK


def cmd_setpoint(s: Session) -> int:
    x = float(s.args.x_cm)
    try:                             # what SETPOINT can carry (the DBC's range), --no-check or not
        s.proto.check_signal("SETPOINT", "XrCm", x, what="set-point")
    except ValueError as e:
        raise UsageError(str(e)) from None
    node = s.node
    if not s.args.no_check:
        st = node.status()
        if st.state_name != "RUNNING" or st.reference_name != "STREAM":
            raise NodeStateError(f"node {node.node} is {st.state_name} with reference "
                                 f"{st.reference_name}: it uses set-points only while RUNNING STREAM "
                                 f"(nothing sent; --no-check sends anyway)")
        lo, hi = float(node.get("safety.x_min_cm")), float(node.get("safety.x_max_cm"))
        if not lo < x < hi:
            raise UsageError(f"set-point {x:g} cm is outside the constraint band ({lo:g}, {hi:g}) cm: "
                             f"the node would drop it (nothing sent)")
    node.setpoint(x)
    s.out(f"node {node.node}: set-point {x:g} cm sent")
    return EXIT_OK


def _progress_printer(quiet: bool) -> Callable[[RecordProgress], None] | None:
    if quiet:
        return None
    tty = sys.stderr.isatty()
    state = {"last_line": -1.0}

    def show(p: RecordProgress) -> None:
        total = f"/{p.seconds:g}" if p.seconds else ""
        text = f"recording {p.elapsed_s:5.1f}{total} s  {p.rows} rows"
        if p.last is not None:
            v = p.last.values
            text += f"  t {p.last.t_s:8.3f} s"
            if "x" in v:
                text += f"  x {float(v['x']):+.3f} cm"
            if "e" in v:
                text += f"  e {float(v['e']):+.4f} cm"
            if "breaches" in v:
                text += f"  breaches {int(v['breaches'])}"
        if tty:
            sys.stderr.write("\r" + text.ljust(90)[:110])
            sys.stderr.flush()
        elif p.elapsed_s - state["last_line"] >= 1.0:
            state["last_line"] = p.elapsed_s
            sys.stderr.write(text + "\n")
    return show


def cmd_record(s: Session) -> int:
    csv_path = Path(s.args.csv)
    _check_output(csv_path, "")      # before deriving the other names from it
    log = None
    if not s.args.no_log:
        log = Path(s.args.log) if s.args.log is not None else csv_path.with_suffix(".blf")
        if log.suffix.lower() not in (".blf", ".asc", ".log"):
            raise UsageError(f"--log {log}: use a .blf, .asc or .log file")
    meta = csv_path.with_name(csv_path.stem + ".meta.json")
    _check_outputs([("CSV", csv_path), ("--log" if s.args.log is not None else "frame log", log),
                    ("metadata", meta)])
    node = s.node
    rec = TelemetryRecorder(node, csv_path, log, meta, host_heartbeat=not s.args.no_host_heartbeat,
                            all_frames=s.args.all_frames)
    show = _progress_printer(s.args.quiet)
    try:
        summary = rec.run(seconds=s.args.seconds, samples=s.args.samples, start=s.args.start,
                          progress=show)
    finally:
        if show is not None and sys.stderr.isatty():
            sys.stderr.write("\n")
    span = (f" (t {summary.t_first_s:.3f}..{summary.t_last_s:.3f} s)"
            if summary.t_first_s is not None and summary.t_last_s is not None else "")
    s.out(f"recorded {summary.rows} rows{span} from node {node.node} in {summary.elapsed_s:.1f} s: "
          f"{summary.stop_reason}")
    s.out(f"  csv   {summary.csv_path}")
    if summary.log_path:
        s.out(f"  log   {summary.log_path} ({summary.frames_logged} frames)")
    s.out(f"  meta  {summary.meta_path}")
    e = f"{summary.max_abs_e_cm:.4f} cm" if summary.max_abs_e_cm is not None else "-"
    b = str(summary.breaches) if summary.breaches is not None else "-"
    s.out(f"  max |e| {e}, breaches {b}, incomplete rows {summary.incomplete}, "
          f"lost rows {summary.lost}")
    if summary.stop_reason.startswith(f"node {node.node} left RUNNING"):
        return EXIT_REFUSED
    if summary.rows == 0:
        raise NoReply(f"no telemetry from node {node.node}")
    return EXIT_OK


def _meta_options(meta_path: Path, w1: float | None, t_u: float | None, band: Any,
                  title: str | None) -> tuple[float | None, float | None, Any, str | None]:
    """w1, t_u, band and title, those the command line left open taken from a recording's
    .meta.json (w1 and t_u of a PPC run, the band safety.x_min_cm..x_max_cm). A value plot
    would take that is not a finite number (w1, t_u: positive; the band: low < high) makes
    the file a bad one, ParamFileError listing each (exit 5): --no-meta, or the option, sets
    the value instead."""
    def bad(problems: list[str]) -> paramfile.ParamFileError:
        return paramfile.ParamFileError(str(meta_path), problems + [
            "(--no-meta ignores the file; --w1, --t-u, --band give the values instead)"])
    try:
        meta = json.loads(meta_path.read_text())
    except (OSError, UnicodeDecodeError, ValueError) as e:
        raise bad([f"not a recording's metadata: {getattr(e, 'strerror', None) or e}"]) from None
    if not isinstance(meta, dict) or not isinstance(meta.get("params", {}), dict):
        raise bad(["not a recording's metadata: not a JSON object with a \"params\" object"])
    params: dict[str, Any] = meta.get("params", {})
    problems: list[str] = []

    def number(key: str, positive: bool, unit: str) -> float | None:
        v = params[key]
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) \
                or (positive and v <= 0):
            problems.append(f"params.{key} = {json.dumps(v)} is not a {'positive ' if positive else ''}"
                            f"finite number ({unit})")
            return None
        return float(v)

    if meta.get("controller") == "PPC":
        if w1 is None and "ppc.w1_cm" in params:
            w1 = number("ppc.w1_cm", True, "cm")
        if t_u is None and "ppc.t_u_s" in params:
            t_u = number("ppc.t_u_s", True, "s")
    if band is None and "safety.x_min_cm" in params and "safety.x_max_cm" in params:
        lo, hi = number("safety.x_min_cm", False, "cm"), number("safety.x_max_cm", False, "cm")
        if lo is not None and hi is not None:
            if lo < hi:
                band = (lo, hi)
            else:
                problems.append(f"params.safety.x_min_cm = {lo:g} cm is not below "
                                f"params.safety.x_max_cm = {hi:g} cm")
    if problems:
        raise bad(problems)
    if title is None:
        title = (f"node {meta.get('node')}, {meta.get('controller')}, "
                 f"reference {params.get('ref.kind', '?')}")
    return w1, t_u, band, title


def cmd_plot(s: Session) -> int:
    from pmactl.plot import PlotOptions, output_paths, plot_recording
    csv_path = Path(s.args.csv)
    if s.args.band and not s.args.band[0] < s.args.band[1]:
        raise UsageError(f"--band {s.args.band[0]:g} {s.args.band[1]:g}: LOW_CM must be below HIGH_CM")
    if csv_path.name in ("", ".", "..") or csv_path.is_dir():
        raise paramfile.ParamFileError(str(csv_path), ["cannot read: is a directory"])
    prefix = Path(s.args.out) if s.args.out else csv_path.with_suffix("")
    if prefix.name in ("", ".", "..") or (s.args.out is not None and prefix.is_dir()):
        raise UsageError(f"--out {s.args.out}: is a directory; give a file name prefix "
                         f"(e.g. {prefix / csv_path.with_suffix('').name})")
    _check_outputs([("figure", path) for path in output_paths(prefix, not s.args.no_panels)],
                   inputs=[("the recording", csv_path)], create_dir=True)
    try:
        rec = read_recording(csv_path)
    except RecordingError as e:
        raise paramfile.ParamFileError(str(csv_path), [str(e).split(": ", 1)[-1]]) from None
    if len(rec) == 0:
        raise paramfile.ParamFileError(str(csv_path), ["no rows to plot"])
    w1, band, t_u, title = s.args.w1, tuple(s.args.band) if s.args.band else None, s.args.t_u, s.args.title
    meta_path = csv_path.with_name(csv_path.stem + ".meta.json")
    if not s.args.no_meta and meta_path.exists():
        w1, t_u, band, title = _meta_options(meta_path, w1, t_u, band, title)
    written = plot_recording(rec, prefix, PlotOptions(w1_cm=w1, band_cm=band, t_u_s=t_u,
                                                      title=title, dpi=s.args.dpi,
                                                      panels=not s.args.no_panels))
    for path in written:
        s.out(str(path))
    s.out(f"{csv_path}:")
    for line in metrics(rec, w1, t_u).lines(w1, t_u, rec.units.get("u", "input unit")):
        s.out(f"  {line}")
    return EXIT_OK


def cmd_dbc(s: Session) -> int:
    nodes: list[int] = s.args.nodes
    if s.args.output == "-":
        sys.stdout.write(node_dbc_text(nodes, s.proto))
        sys.stdout.flush()
        return EXIT_OK
    path = Path(s.args.output)
    _check_output(path, "")
    try:
        write_node_dbc(path, nodes, s.proto)
    except OSError as e:
        raise paramfile.ParamFileError(str(path), [f"cannot write: {e.strerror or e}"]) from None
    s.out(f"{path}: protocol {s.proto.version} for node(s) {','.join(map(str, nodes))} "
          f"({len(s.proto.db.messages) - len(BROADCASTS)} messages per node, the broadcasts "
          f"{', '.join(BROADCASTS)} once)")
    return EXIT_OK


def cmd_scope(s: Session) -> int:
    from pmactl.scope import Scope, ScopeError, ScopeOptions
    a = s.args
    nodes: list[int] = a.nodes or list(a.node)
    if a.headless and a.frames is None and a.seconds is None:
        raise UsageError("--headless needs --frames N or --seconds S (it writes a PNG per frame)")
    csv_path = Path(a.csv) if a.csv is not None else None
    out = Path(a.out)
    if csv_path is not None:
        _check_output(csv_path, "--csv")       # and each node's file, as the scope names them
        csvs = [csv_path] if len(nodes) == 1 else \
            [csv_path.with_name(f"{csv_path.stem}_n{n}{csv_path.suffix or '.csv'}") for n in nodes]
        _check_outputs([("--csv", path) for path in csvs]
                       + [("metadata", path.with_name(path.stem + ".meta.json")) for path in csvs])
    if a.headless:
        if out.name in ("", ".", "..") or out.is_dir():
            raise UsageError(f"--out {a.out}: is a directory; give a file name prefix (e.g. {out / 'scope'})")
        _check_output(out.with_name(f"{out.name}_0001.png"), "--out")
    opts = ScopeOptions(nodes=nodes, window_s=a.window, fps=a.fps, w1_cm=a.w1,
                        host_heartbeat=a.host_heartbeat, csv=csv_path, record=a.record,
                        seconds=a.seconds, frames=a.frames, headless=a.headless, png_prefix=out,
                        dpi=a.dpi)
    scope = Scope(s.node, opts, out=s.out)
    try:
        summary = scope.run()
    except ScopeError as e:
        raise UsageError(str(e)) from None
    s.out(f"scope: {summary.frames} frames in {summary.elapsed_s:.1f} s: {summary.fps:.1f} frames/s "
          f"from the first frame on, {summary.recent_fps:.1f} over the last 50, "
          f"{summary.full_draws} full redraws; {summary.stop_reason}")
    for n, rows in summary.rows.items():
        rec = f", {summary.recorded[n]} recorded" if summary.recorded.get(n) else ""
        s.out(f"  node {n}: {rows} telemetry rows shown{rec}")
    if not any(summary.rows.values()) and not any(summary.recorded.values()):
        raise NoReply(f"no telemetry from node(s) {','.join(map(str, nodes))} (are they RUNNING?)")
    return EXIT_OK


def cmd_monitor(s: Session) -> int:
    node = s.node
    if s.args.host_heartbeat:
        node.host_heartbeat_s = 0.1
    mon = BusMonitor(node, silent_s=s.args.silent_after, every=s.args.every)
    until = f" for {s.args.seconds:g} s" if s.args.seconds else " (Ctrl-C to stop)"
    s.out(f"watching {s.bus_text}{until}")
    end = time.monotonic() + s.args.seconds if s.args.seconds else math.inf
    try:
        while (left := end - time.monotonic()) > 0:
            for ev in mon.poll(min(left, 0.2)):
                s.out(_event_line(ev))
    except KeyboardInterrupt:
        pass
    s.out(f"{len(mon.last)} node(s) seen" + (": " if mon.last else "") +
          ", ".join(f"{n} {st.state_name}" + (f" ({st.fault_name})" if st.fault else "")
                    for n, st in sorted(mon.last.items())))
    return EXIT_OK


def _event_line(ev: MonitorEvent) -> str:
    who = "bus    " if ev.node < 0 else f"node {ev.node:<2d}"
    return f"{ev.time:8.3f}  {who}  {ev.text}"


PARAMS_COMMANDS: dict[str, Callable[[Session], int]] = {
    "list": cmd_params_list, "get": cmd_params_get, "set": cmd_params_set,
    "save": cmd_params_simple, "restore-defaults": cmd_params_simple, "revert": cmd_params_simple,
    "dump": cmd_params_dump, "load": cmd_params_load,
}
COMMANDS: dict[str, Callable[[Session], int]] = {
    "scan": cmd_scan, "status": cmd_status, "info": cmd_info, "counters": cmd_counters,
    "params": lambda s: PARAMS_COMMANDS[s.args.params_command](s),
    "arm": cmd_command, "disarm": cmd_command, "start": cmd_command, "stop": cmd_command,
    "clear-faults": cmd_command, "estop": cmd_estop, "restart": cmd_restart, "controller": cmd_select,
    "reference": cmd_select, "setpoint": cmd_setpoint, "record": cmd_record, "plot": cmd_plot,
    "monitor": cmd_monitor, "node-id": cmd_node_id, "dbc": cmd_dbc, "scope": cmd_scope,
    "commission": lambda s: cmd_commission(s),
}
# Commands that work on one node (or on the whole bus) and so take no list of nodes.
SINGLE_NODE = ("scan", "record", "plot", "monitor", "node-id", "commission")


def _check_band(x_min: float, x_max: float, w1: float, x_start: float | None, source: str) -> None:
    """The task's band as commissioning checks it (commission_rules.band_problem), named by the
    options; `source` says where a value not given as an option came from."""
    from .commission_rules import band_problem
    problem = band_problem(x_min, x_max, w1, x_start, names=("--x-min", "--x-max", "--x-start"))
    if problem is not None:
        raise UsageError(problem + source)


def cmd_commission(s: Session) -> int:
    from . import commission, commission_report
    from .commission_rules import CommissionError, Task
    args = s.args
    if args.save and not args.apply:
        raise UsageError("--save needs --apply (nothing is set without it)")
    if args.mean_speed is not None and args.mean_speed > args.speed:
        raise UsageError(f"--mean-speed {args.mean_speed:g} cm/s exceeds --speed {args.speed:g} cm/s "
                         "(the reference's largest speed)")
    out_dir = Path(args.out) if args.out is not None else None
    if out_dir is not None:
        if out_dir.exists() and not out_dir.is_dir():
            raise UsageError(f"--out {args.out}: not a directory")
        # every file it will write, before anything is sent: a minute of measurement is not lost
        # to a directory that cannot be made or written after it
        _check_outputs([("--out", out_dir / name) for name in commission_report.FILES], create_dir=True)
    # the task, against the parameter table's ranges of the parameters it becomes (the node
    # would refuse them after the whole measurement), before anything is sent
    for option, pname, value in (("--w1", "ppc.w1_cm", args.w1), ("--t-u", "ppc.t_u_s", args.t_u),
                                 ("--x-min", "safety.x_min_cm", args.x_min),
                                 ("--x-max", "safety.x_max_cm", args.x_max)):
        if value is not None:
            try:
                s.proto.param(pname).check(value)
            except ValueError as e:
                raise UsageError(f"{option}: {e}") from None
    if args.x_min is not None and args.x_max is not None:
        _check_band(args.x_min, args.x_max, args.w1, args.x_start, "")
    node = s.node
    x_min = args.x_min if args.x_min is not None else float(node.get("safety.x_min_cm"))
    x_max = args.x_max if args.x_max is not None else float(node.get("safety.x_max_cm"))
    _check_band(x_min, x_max, args.w1, args.x_start,
                "" if args.x_min is not None and args.x_max is not None
                else f" (node {node.node}'s safety.x_min_cm..x_max_cm where not given)")
    task = Task(w1_cm=args.w1, t_u_s=args.t_u, x_min_cm=x_min, x_max_cm=x_max, x_start_cm=args.x_start,
                speed_cm_s=args.speed, mean_speed_cm_s=args.mean_speed, noise_limit=args.noise_limit)
    bar = commission_report.ProgressBar(sys.stderr) if not args.quiet and sys.stderr.isatty() else None
    run = commission.Commissioning(node, task, progress=bar.update if bar else None, timeout_s=max(args.timeout, 1.0))
    try:
        result = run.run(apply=args.apply, save=args.save)
    except (CommissionError, commission.CommissionAborted) as e:
        if bar:
            bar.close()
        _err(f"error: commissioning of node {s.node_id} stopped: {e}; the node was left stopped and disarmed, "
             "its parameters as they were")
        return EXIT_REFUSED
    except KeyboardInterrupt:
        if bar:
            bar.close()
        _err(f"interrupted: node {s.node_id} was left stopped and disarmed, its parameters as they were")
        return EXIT_INTERRUPTED
    if bar:
        bar.close()
    for line in commission_report.text(result):
        s.out(line)
    if out_dir is not None:
        for path in commission_report.write(result, out_dir, s.proto, node.node):
            s.out(f"written: {path}")
    return EXIT_OK


def _err(text: str) -> None:
    sys.stderr.write(f"pmactl: {text}\n")
    sys.stderr.flush()


def main(argv: Sequence[str] | None = None) -> int:
    """Runs pmactl with argv (default: sys.argv[1:]); returns the exit status."""
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as e:          # argparse: --help (0) or a usage error (2)
        return int(e.code) if isinstance(e.code, int) else EXIT_USAGE

    def out(line: str) -> None:
        print(line, flush=True)

    # python-can logs an interface's errors before it raises them; pmactl reports them itself
    logging.getLogger("can").setLevel(logging.DEBUG if args.verbose else logging.CRITICAL)
    if args.verbose:
        logging.basicConfig(level=logging.WARNING, format="pmactl: %(name)s: %(message)s")

    s = Session(args, out)
    try:
        nodes = _nodes_of(s)
    except (UsageError, BadBusConfig) as e:
        _err(f"error: {e}")
        s.close()
        return EXIT_USAGE
    except InterfaceError as e:
        _err(f"error: {e}")
        s.close()
        return EXIT_INTERFACE
    except NoReply as e:
        _err(f"error: {e}")
        s.close()
        return EXIT_NO_REPLY
    try:
        if len(nodes) == 1:
            s.use_node(nodes[0])
            return _run_one(s)
        worst = EXIT_OK
        for n in nodes:
            s.use_node(n)
            s.out = (lambda line, n=n: out(f"node {n}: {line}"))  # type: ignore[misc]
            code = _run_one(s)
            if code == EXIT_INTERRUPTED:
                return code
            worst = max(worst, code)
        s.out = out
        out(f"{len(nodes)} node(s): " + ("all OK" if worst == EXIT_OK else f"exit status {worst}"))
        return worst
    finally:
        s.close()


def _nodes_of(s: Session) -> list[int]:
    """The node ids of the command: --node's list, or with --all the nodes whose heartbeat
    arrives within --timeout. A command of one node (or of the bus) takes one."""
    args = s.args
    if args.command == "estop" and args.all:
        return [args.node[0]]                # ESTOP_ALL: one broadcast
    if args.command in ("scan", "monitor", "plot") :
        return [args.node[0]]
    if args.all:
        if args.command in SINGLE_NODE:
            raise UsageError(f"{args.command} works on one node: --all does not apply")
        probe = PmaNode(s.bus, 0, s.proto, timeout_s=args.timeout)
        probe.listen_to(["HEARTBEAT"], node=None)
        found = scan(probe, args.timeout)
        if not found:
            raise NoReply(f"--all: no node heartbeat on {s.bus_text} within {args.timeout:g} s")
        return sorted(found)
    if len(args.node) > 1 and args.command in SINGLE_NODE:
        raise UsageError(f"{args.command} works on one node: give one --node")
    if len(args.node) > 1 and args.command == "params" and args.params_command == "dump" \
            and args.file != "-" and "{node}" not in args.file:
        raise UsageError("params dump to several nodes needs a file name with {node} in it "
                         "(e.g. node{node}.json)")
    return list(args.node)


def _run_one(s: Session) -> int:
    """The command on s's current node, its exceptions turned into exit statuses."""
    args = s.args
    try:
        return COMMANDS[args.command](s)
    except (UsageError, BadBusConfig) as e:
        _err(f"error: {e}")
        return EXIT_USAGE
    except paramfile.ParamFileError as e:
        _err(f"error: {e.path}: bad file (nothing sent):")
        for problem in e.problems:
            sys.stderr.write(f"  {problem}\n")
        return EXIT_FILE
    except InterfaceError as e:
        _err(f"error: {e}")
        return EXIT_INTERFACE
    except SetRejected as e:
        p = e.param
        name = p.name if p else "?"
        kept = f"; {name} stays {p.text(e.current)}" if p is not None and e.current is not None else ""
        _err(f"error: node {s.node_id} rejected set {name} = "
             f"{p.text(e.requested) if p and e.requested is not None else '?'}: "
             f"{s.proto.status_text(e.code)}{kept}")
        return EXIT_REFUSED
    except CommandError as e:
        cmd = e.what.replace("command ", "")
        _err(f"error: node {s.node_id} refused {cmd}: {s.proto.status_text(e.code)}")
        return EXIT_REFUSED
    except PmaError as e:
        _err(f"error: node {s.node_id}: {e.what}: {s.proto.status_text(e.code)}")
        return EXIT_REFUSED
    except NodeStateError as e:
        _err(f"error: {e}")
        return EXIT_REFUSED
    except NoReply as e:
        _err(f"error: {e} (is the node on {s.bus_text}? --node, --channel, --timeout)")
        return EXIT_NO_REPLY
    except can.CanError as e:
        hint = adapters.explain(s.cfg or {}, e)
        _err(f"error: CAN interface {s.bus_text} failed: {e}" + (f"\n  {hint}" if hint else ""))
        return EXIT_INTERFACE
    except KeyboardInterrupt:
        _err("interrupted")
        return EXIT_INTERRUPTED




if __name__ == "__main__":
    sys.exit(main())
