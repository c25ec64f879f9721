#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Worst-case CAN bus load of PMA nodes with the default parameters.

Reads the data length of every frame from firmware/protocol/pma_proto.dbc
(cantools) and the rates from the defaults in firmware/app/params.toml, and
prints per node:

  bridge  the host build or a HIL set-up: the position sample arrives in
          PLANT_SENSOR and the pressure command leaves in PLANT_ACTUATOR, one
          of each per control tick (sys.tick_hz);
  board   a node with its own ADC and DAC (no plant-bridge frames);

both with the telemetry frames selected by telem.mask every telem.decimation
ticks (the worst case: telemetry is sent only while RUNNING), the node's
HEARTBEAT every sys.heartbeat_ms, and a host heartbeat (HOST_HEARTBEAT) at
10 Hz. Sporadic frames (COMMAND, PARAM_REQ and their replies, SETPOINT,
ESTOP) are left out. A node "fits" while the total of all nodes stays at or
below 50 % of the bit rate (the usual design limit that leaves room for
sporadic traffic, retransmissions after errors and the latency of the lower
priorities); the 16 node ids cap the count.

Usage: busload.py [--bitrate BPS] [--host-heartbeat-hz HZ] [--param NAME=VALUE ...] [--markdown]
  --param overrides a default: sys.tick_hz, telem.decimation, telem.mask or
  sys.heartbeat_ms (repeatable), e.g. --param sys.tick_hz=500.
Exit status: 0, or 1 if one node in bridge mode exceeds 50 % (with the
defaults, or the given settings); 2 on a usage error.
docs/protocol.md holds the --markdown output (tests/protocol checks it).
"""
from __future__ import annotations

import argparse
import sys
import tomllib
from dataclasses import dataclass
from pathlib import Path

import cantools

ROOT = Path(__file__).resolve().parents[1]
DBC = ROOT / "firmware/protocol/pma_proto.dbc"
PARAMS = ROOT / "firmware/app/params.toml"

BITRATE_BPS = 1_000_000      # the protocol's default bit rate (DBC comment)
HOST_HEARTBEAT_HZ = 10.0     # what pmactl and the HIL harness send while a node runs
LOAD_LIMIT = 0.5             # design limit of the total bus load
NODE_IDS = 16                # node ids 0..15
TELEM_MESSAGES = ("TELEM_A", "TELEM_B", "TELEM_C", "TELEM_D", "TELEM_E")  # telem.mask bits 0..4


def frame_bits(n: int) -> int:
    """Worst-case length in bits of a classic CAN 2.0A data frame with n data bytes.

        bits(n) = 47 + 8n + floor((34 + 8n - 1) / 4)

    A data frame with an 11-bit identifier is, in order: start of frame (1 bit),
    identifier (11), RTR (1), IDE (1), r0 (1), DLC (4), data (8n), CRC (15),
    then CRC delimiter (1), ACK slot (1), ACK delimiter (1), end of frame (7),
    and the interframe space (3) before the next frame can start.

    Bit stuffing: after five consecutive bits of the same level the
    transmitter inserts one bit of the opposite level. It applies from the
    start of frame to the end of the CRC: g + 8n bits with g = 1 + 11 + 1 + 1
    + 1 + 4 + 15 = 34. The remaining 13 bits (delimiters, ACK, EOF, IFS) have
    a fixed form and are never stuffed, so the unstuffed length is
    34 + 8n + 13 = 47 + 8n.

    Worst case: the first stuff bit comes after 5 bits, and a stuff bit can
    itself be the first of the next run of five equal bits, so from then on
    a stuff bit can follow every 4 bits (e.g. 11111 0000 1111 0000 ...). The
    number of stuff bits in m stuffed-region bits is thus at most
    floor((m - 1) / 4), here m = 34 + 8n. (Davis, Burns, Bril and Lukkien,
    "Controller Area Network (CAN) schedulability analysis: refuted,
    revisited and revised", Real-Time Systems 35, 2007, eq. 1.)

    Examples: n = 0 -> 55 bits, n = 8 -> 135 bits.
    """
    if not 0 <= n <= 8:
        raise ValueError(f"a classic CAN frame has 0..8 data bytes, not {n}")
    return 47 + 8 * n + (34 + 8 * n - 1) // 4


@dataclass(frozen=True)
class Row:
    traffic: str          # what the frame is for
    message: str          # DBC message name
    direction: str        # "node -> host", ...
    dlc: int
    bits: int             # worst case per frame
    per_s: float          # frames per second per node
    modes: tuple[str, ...]  # "bridge", "board": where the row counts

    @property
    def bps(self) -> float:
        return self.bits * self.per_s


@dataclass(frozen=True)
class Report:
    bitrate: int
    rows: list[Row]
    defaults: dict[str, int]

    def bps(self, mode: str) -> float:
        return sum(r.bps for r in self.rows if mode in r.modes)

    def load(self, mode: str) -> float:
        return self.bps(mode) / self.bitrate

    def nodes(self, mode: str) -> int:
        """How many such nodes keep the total at or below LOAD_LIMIT (at most 16)."""
        per_node = self.bps(mode)
        if per_node <= 0:
            return NODE_IDS
        # integers: no rounding surprise at exactly 50 %
        return min(NODE_IDS, int(LOAD_LIMIT * self.bitrate // per_node))


def param_defaults(path: Path = PARAMS) -> dict[str, int]:
    with path.open("rb") as f:
        return {p["name"]: p["default"] for p in tomllib.load(f)["param"]}


SETTINGS = ("sys.tick_hz", "telem.decimation", "telem.mask", "sys.heartbeat_ms")


def compute(bitrate: int = BITRATE_BPS, host_heartbeat_hz: float = HOST_HEARTBEAT_HZ,
            dbc: Path = DBC, params: Path = PARAMS,
            overrides: dict[str, int] | None = None) -> Report:
    db = cantools.database.load_file(str(dbc))
    dlc = {m.name: m.length for m in db.messages}
    d = param_defaults(params)
    for name, value in (overrides or {}).items():
        if name not in SETTINGS:
            raise ValueError(f"--param: {name} is not one of {', '.join(SETTINGS)}")
        d[name] = value
    tick_hz = int(d["sys.tick_hz"])
    decimation = int(d["telem.decimation"])
    mask = int(d["telem.mask"])
    heartbeat_ms = int(d["sys.heartbeat_ms"])
    telem_hz = tick_hz / decimation if decimation else 0.0

    def row(traffic: str, message: str, direction: str, per_s: float,
            modes: tuple[str, ...] = ("bridge", "board")) -> Row:
        return Row(traffic, message, direction, dlc[message], frame_bits(dlc[message]), per_s, modes)

    rows = [
        row("control tick (bridge)", "PLANT_SENSOR", "rig -> node", float(tick_hz), ("bridge",)),
        row("control tick (bridge)", "PLANT_ACTUATOR", "node -> rig", float(tick_hz), ("bridge",)),
    ]
    for bit, name in enumerate(TELEM_MESSAGES):
        if mask & (1 << bit):
            rows.append(row("telemetry", name, "node -> host", telem_hz))
    rows.append(row("node heartbeat", "HEARTBEAT", "node -> host", 1000.0 / heartbeat_ms))
    rows.append(row("host heartbeat", "HOST_HEARTBEAT", "host -> node", host_heartbeat_hz))
    used = {"sys.tick_hz": tick_hz, "telem.decimation": decimation, "telem.mask": mask,
            "sys.heartbeat_ms": heartbeat_ms}
    return Report(bitrate, rows, used)


def _num(x: float) -> str:
    return f"{x:,.0f}" if float(x).is_integer() else f"{x:,.3g}"


def _pct(x: float) -> str:
    return f"{100.0 * x:.2f} %"


def _limit() -> str:
    return f"{100.0 * LOAD_LIMIT:.0f} %"


def markdown(r: Report) -> str:
    """The table for docs/protocol.md (also what the plain output shows)."""
    d = r.defaults
    out = [
        f"Bit rate {r.bitrate:,} bit/s; defaults: `sys.tick_hz` = {d['sys.tick_hz']}, "
        f"`telem.decimation` = {d['telem.decimation']}, `telem.mask` = {d['telem.mask']}, "
        f"`sys.heartbeat_ms` = {d['sys.heartbeat_ms']}; host heartbeat "
        f"{_num(next(x.per_s for x in r.rows if x.message == 'HOST_HEARTBEAT'))} Hz.\n",
        "\n",
        "| traffic (one node) | message | direction | DLC | bits/frame (worst case) "
        "| frames/s | bit/s | load |\n",
        "|---|---|---|---:|---:|---:|---:|---:|\n",
    ]
    for x in r.rows:
        out.append(f"| {x.traffic} | {x.message} | {x.direction} | {x.dlc} | {x.bits} | "
                   f"{_num(x.per_s)} | {_num(x.bps)} | {_pct(x.bps / r.bitrate)} |\n")
    for mode, what in (("bridge", "**one node, bridge mode** (PLANT_* frames)"),
                       ("board", "**one node, board** (own ADC/DAC, no PLANT_* frames)")):
        out.append(f"| {what} | | | | | | **{_num(r.bps(mode))}** | **{_pct(r.load(mode))}** |\n")
    out.append("\n")
    for mode, what in (("bridge", "bridge mode"), ("board", "boards")):
        n = r.nodes(mode)
        out.append(f"- Nodes that fit within {_limit()} of the bus, {what}: **{n}** "
                   f"({_pct(n * r.load(mode))} together).\n")
    return "".join(out)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--bitrate", type=int, default=BITRATE_BPS, help="bit/s (default 1000000)")
    ap.add_argument("--host-heartbeat-hz", type=float, default=HOST_HEARTBEAT_HZ,
                    help="host heartbeat rate per node (default 10)")
    ap.add_argument("--param", action="append", default=[], metavar="NAME=VALUE",
                    help=f"override a default ({', '.join(SETTINGS)}); repeatable")
    ap.add_argument("--markdown", action="store_true", help="print the table for docs/protocol.md")
    args = ap.parse_args(argv)
    if args.bitrate <= 0 or args.host_heartbeat_hz < 0:
        ap.error("--bitrate must be > 0 and --host-heartbeat-hz >= 0")
    overrides: dict[str, int] = {}
    for item in args.param:
        name, _, value = item.partition("=")
        try:
            overrides[name.strip()] = int(value, 0)
        except ValueError:
            ap.error(f"--param wants NAME=INTEGER, not {item!r}")
    if overrides.get("sys.tick_hz", 1) <= 0 or overrides.get("sys.heartbeat_ms", 1) <= 0 \
            or overrides.get("telem.decimation", 0) < 0 or overrides.get("telem.mask", 0) < 0:
        ap.error("--param: sys.tick_hz and sys.heartbeat_ms must be > 0, the others >= 0")
    try:
        r = compute(args.bitrate, args.host_heartbeat_hz, overrides=overrides)
    except ValueError as e:
        ap.error(str(e))
    if args.markdown:
        sys.stdout.write(markdown(r))
    else:
        w = max(len(x.message) for x in r.rows)
        print(f"CAN bus load per node at {r.bitrate:,} bit/s, defaults from "
              f"{PARAMS.relative_to(ROOT)}" + (f" except {overrides}" if overrides else "") + ":")
        print(f"  {'message':<{w}}  {'DLC':>3}  {'bits':>4}  {'frames/s':>8}  {'bit/s':>9}  {'load':>8}")
        for x in r.rows:
            print(f"  {x.message:<{w}}  {x.dlc:>3}  {x.bits:>4}  {_num(x.per_s):>8}  "
                  f"{_num(x.bps):>9}  {_pct(x.bps / r.bitrate):>8}")
        for mode in ("bridge", "board"):
            print(f"  one node, {mode:<6}: {_num(r.bps(mode)):>9} bit/s  {_pct(r.load(mode)):>8};"
                  f"  nodes within {_limit()}: {r.nodes(mode)}")
    if r.load("bridge") > LOAD_LIMIT:
        print(f"busload: one node in bridge mode needs {_pct(r.load('bridge'))} of the bus, "
              f"more than {_limit()}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
