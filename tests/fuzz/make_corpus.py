#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Seed corpus and dictionary of the CAN frame fuzzer (tests/fuzz/fuzz_frames.c).

The frames are encoded with cantools from the protocol's one source,
firmware/protocol/pma_proto.dbc, and the parameter ids, types and ranges come
from firmware/app/params.toml, so the seeds follow the protocol as it is.

Each seed is one input of fuzz_frames.c: a platform byte, then 12-byte records
[op][a][b][c][d0..d7] (the op numbers and fields are documented at the top of
fuzz_frames.c; OP_* below must match its enum). The seeds walk the state
machine (ARM, START with every controller and reference, STOP, DISARM, ESTOP,
CLEAR_FAULTS), get, set, save and load parameters, drive the plant bridge with
PLANT_SENSOR sequences, send frames of wrong lengths, other nodes' frames and
invalid DLCs, and inject sensor, CAN and storage faults.

Usage: make_corpus.py OUT_DIR [--dict FILE]   (run with the project's .venv python)
"""
from __future__ import annotations

import argparse
import struct
import sys
import tomllib
from pathlib import Path

import cantools

ROOT = Path(__file__).resolve().parents[2]
DBC = ROOT / "firmware/protocol/pma_proto.dbc"
PARAMS = ROOT / "firmware/app/params.toml"

(OP_FRAME, OP_FRAME_NODE, OP_TICK, OP_STEP, OP_REAL_STEP, OP_INJECT, OP_ADVANCE, OP_POLL,
 OP_ADC, OP_CAN, OP_NVM, OP_REBOOT, OP_COMMAND, OP_PARAM, OP_SENSOR, OP_SETPOINT) = range(16)

NODE_MAP = [0, 1, 7, 15, 3, 10, 12, -1]  # platform byte bits 5-7, as in fuzz_frames.c
START_RAW = 2948                         # x = -1.5 cm with the default sensor scaling
TYPES = {"f32": 0, "u32": 1, "i32": 2}
OPS = {"GET": 0, "SET": 1, "SAVE": 2, "RESTORE_DEFAULTS": 3, "GET_MIN": 4, "GET_MAX": 5,
       "GET_DEFAULT": 6, "NEXT_ID": 7, "LOAD": 8}
CMDS = {"ARM": 1, "DISARM": 2, "START": 3, "STOP": 4, "ESTOP": 5, "CLEAR_FAULTS": 6,
        "SELECT_CONTROLLER": 7, "SELECT_REFERENCE": 8}

db = cantools.database.load_file(str(DBC))
with PARAMS.open("rb") as f:
    PTABLE = sorted(tomllib.load(f)["param"], key=lambda p: p["id"])
PBYID = {p["id"]: p for p in PTABLE}
PBYNAME = {p["name"]: p for p in PTABLE}


def platform(bridge=False, lockstep=False, storage=0, watchdog=False, node_index=0) -> int:
    return (int(bridge) | int(lockstep) << 1 | storage << 2 | int(watchdog) << 4
            | node_index << 5)


def rec(op: int, a: int = 0, b: int = 0, c: int = 0, d: bytes = b"") -> bytes:
    d = bytes(d)[:8].ljust(8, b"\0")
    return bytes([op, a & 0xFF, b & 0xFF, c & 0xFF]) + d


def raw_frame(frame_id: int, data: bytes, dlc: int | None = None, op: int = OP_FRAME) -> bytes:
    """A frame record with an explicit 11-bit id (OP_FRAME) or, for OP_INJECT, b & 0x40 clear."""
    dlc = len(data) if dlc is None else dlc
    return rec(op, frame_id & 0xFF, (frame_id >> 8) & 0x07, dlc & 0x0F, data)


def msg(name: str, node: int = 0, dlc: int | None = None, op: int = OP_FRAME, **signals) -> bytes:
    m = db.get_message_by_name(name)
    data = m.encode(signals, strict=True) if m.signals else b""
    return raw_frame(m.frame_id + node, data, dlc, op)


def cmd(name: str, arg: int = 0, node: int = 0, op: int = OP_FRAME) -> bytes:
    return msg("COMMAND", node, op=op, Command=CMDS[name], Arg=arg)


def param_value_signals(ptype: str, value) -> dict:
    if ptype == "f32":
        return {"Type": 0, "ValueF32": float(value)}
    if ptype == "u32":
        return {"Type": 1, "ValueU32": int(value)}
    return {"Type": 2, "ValueI32": int(value)}


def param(op: str, pid: int, value=0, ptype: str | None = None, node: int = 0) -> bytes:
    ptype = ptype or (PBYID[pid]["type"] if pid in PBYID else "u32")
    return msg("PARAM_REQ", node, Op=OPS[op], Id=pid, Reserved=0,
               **param_value_signals(ptype, value))


def set_param(name: str, value, node: int = 0) -> bytes:
    p = PBYNAME[name]
    return param("SET", p["id"], value, node=node)


def tick(n: int = 1, late: int = 0, sample: int | None = None, slope: int = 0,
         host_hb: bool = False) -> bytes:
    """OP_TICK: n ticks (1..256); optional plant sample raw + i * slope; host heartbeats."""
    a = (0x80 | late) if late else 0
    c = (1 if sample is not None else 0) | (2 if host_hb else 0)
    raw = sample or 0
    return rec(OP_TICK, a, n - 1, c, bytes([raw & 0xFF, raw >> 8, slope & 0xFF]))


def plant_sensor(seq: int, raw: int, node: int = 0) -> bytes:
    return msg("PLANT_SENSOR", node, Seq=seq & 0xFF, RawCounts=raw)


# --------------------------------------------------------------------- seeds --

def seeds() -> dict[str, bytes]:
    s: dict[str, bytes] = {}

    def add(name: str, cfg: int, *records: bytes) -> None:
        s[name] = bytes([cfg]) + b"".join(records)

    add("boot_idle", platform(),
        tick(20), rec(OP_ADVANCE, 0x40, 0x0D, 0x03), rec(OP_POLL), msg("HOST_HEARTBEAT", Counter=1))

    # every controller through ARM, START, run, set-points, STOP, DISARM
    for mode in range(5):
        add(f"run_ctrl{mode}", platform(),
            cmd("SELECT_CONTROLLER", mode), tick(5, sample=START_RAW), cmd("ARM"),
            tick(10, sample=START_RAW), cmd("START"),
            tick(100, sample=START_RAW, slope=1, host_hb=True),
            msg("SETPOINT", XrCm=-1.0), tick(50, sample=START_RAW + 100, host_hb=True),
            set_param("ctrl.openloop_u", 10.0), tick(20, sample=START_RAW, host_hb=True),
            cmd("STOP"), tick(5, sample=START_RAW), cmd("DISARM"), tick(3))

    # every reference kind (STREAM with set-points)
    for kind in range(7):
        add(f"run_ref{kind}", platform(),
            cmd("SELECT_REFERENCE", kind), tick(2, sample=START_RAW), cmd("ARM"),
            tick(2, sample=START_RAW), cmd("START"),
            msg("SETPOINT", XrCm=-2.0), tick(200, sample=START_RAW, slope=-1, host_hb=True),
            msg("SETPOINT", XrCm=-0.5), tick(200, sample=START_RAW - 200, slope=1, host_hb=True),
            cmd("ESTOP"), tick(2), cmd("CLEAR_FAULTS"))

    # parameter access: GET of every id, NEXT_ID walk, limits and defaults
    recs = [param("GET", p["id"]) for p in PTABLE]
    add("param_get_all", platform(), *recs)
    recs = [param("NEXT_ID", 0)] + [param("NEXT_ID", p["id"]) for p in PTABLE]
    add("param_next_id", platform(), *recs)
    recs = []
    for p in PTABLE[::3]:
        recs += [param("GET_MIN", p["id"]), param("GET_MAX", p["id"]), param("GET_DEFAULT", p["id"])]
    add("param_limits", platform(), *recs)
    recs = [param("SET", p["id"], p["default"]) for p in PTABLE]
    add("param_set_defaults", platform(), *recs, tick(3))
    # limits of every parameter in IDLE, then ARMED and RUNNING (access classes)
    for group in sorted({p["name"].split(".")[0] for p in PTABLE}):
        ps = [p for p in PTABLE if p["name"].startswith(group + ".")]
        recs = [tick(2, sample=START_RAW)]
        for p in ps:
            recs += [param("SET", p["id"], p["min"]), param("SET", p["id"], p["max"]),
                     param("SET", p["id"], p["default"])]
        recs += [cmd("ARM")] + [param("SET", p["id"], p["max"]) for p in ps]
        recs += [param("SET", p["id"], p["default"]) for p in ps]
        recs += [cmd("START")] + [param("SET", p["id"], p["default"]) for p in ps]
        recs += [tick(5, sample=START_RAW, host_hb=True), cmd("DISARM"), tick(1)]
        add(f"param_edges_{group}", platform(), *recs)
    # wrong type, reserved byte, unknown id and op
    add("param_bad", platform(),
        param("SET", 2, 100.0, ptype="f32"), param("SET", 17, 5, ptype="u32"),
        param("GET", 999), param("SET", 999, 1), param("GET_MIN", 0), param("NEXT_ID", 168),
        msg("PARAM_REQ", Op=1, Type=1, Id=2, Reserved=7, ValueU32=500),
        # cantools refuses undefined multiplexer values: Type 3 and Op 15 as raw bytes
        raw_frame(db.get_message_by_name("PARAM_REQ").frame_id, bytes([0x3F, 2, 0, 0, 1, 0, 0, 0])),
        msg("PARAM_REQ", Op=9, Type=0, Id=17, Reserved=0, ValueF32=1.0),
        set_param("sys.tick_hz", 50), tick(3), set_param("sys.tick_hz", 5000), tick(3))

    # storage: save, restore defaults, load, power cuts, reboots, a new node id
    for storage in (1, 2, 3):
        add(f"storage{storage}", platform(storage=storage),
            set_param("sys.heartbeat_ms", 20), set_param("act.p0_kpa", 250.0),
            param("SAVE", 0), param("RESTORE_DEFAULTS", 0), param("LOAD", 0),
            set_param("ctrl.mode", 3), param("SAVE", 0), rec(OP_REBOOT, c=0),
            param("GET", 16), rec(OP_NVM, 3, 250, 0), set_param("ctrl.mode", 2), param("SAVE", 0),
            rec(OP_REBOOT, c=1), param("LOAD", 0), rec(OP_NVM, 1, 0, 1),
            rec(OP_NVM, 0, 125, 0), param("SAVE", 0), rec(OP_REBOOT, c=1), param("LOAD", 0),
            tick(3))
    add("node_change", platform(storage=2, node_index=7),
        set_param("sys.node_id", 5), param("SAVE", 0), rec(OP_REBOOT, c=0),
        cmd("ARM", node=5), tick(3, sample=START_RAW), cmd("ARM", node=5), cmd("DISARM", node=5),
        param("GET", 1, node=5), cmd("ARM", node=0), msg("ESTOP", node=5), tick(1))
    for idx, node in enumerate(NODE_MAP[:7]):
        add(f"node{node}", platform(node_index=idx),
            tick(2), cmd("ARM", node=node), cmd("START", node=node),
            tick(5, host_hb=True), msg("ESTOP", node=(node + 1) % 16), tick(1),
            msg("ESTOP", node=node), tick(1), cmd("CLEAR_FAULTS", node=node))

    # plant bridge: sensor frames with gaps and repeats, lockstep flag
    for lockstep in (False, True):
        recs = [plant_sensor(i, START_RAW) for i in range(3)] + [tick(1)]
        recs += [plant_sensor(3, START_RAW), plant_sensor(3, START_RAW), tick(1),
                 plant_sensor(7, START_RAW), tick(1), cmd("ARM"),
                 tick(1, sample=START_RAW), cmd("START"),
                 tick(100, sample=START_RAW, slope=2, host_hb=True),
                 tick(20, host_hb=True),  # no new samples: SENSOR_TIMEOUT
                 cmd("CLEAR_FAULTS"), plant_sensor(0, 100), tick(2)]
        add(f"bridge_ls{int(lockstep)}", platform(bridge=True, lockstep=lockstep), *recs)

    # emergency stops and fault clearing
    add("estop", platform(),
        tick(2), cmd("ARM"), tick(5), msg("ESTOP"), tick(1), cmd("CLEAR_FAULTS"),
        cmd("ARM"), tick(3), msg("ESTOP_ALL"), tick(1), cmd("CLEAR_FAULTS"),
        msg("ESTOP", dlc=8), msg("ESTOP_ALL", dlc=3), tick(1), cmd("ESTOP"), cmd("CLEAR_FAULTS"),
        rec(OP_COMMAND, CMDS["ARM"]), rec(OP_COMMAND, CMDS["ESTOP"]), tick(1),
        rec(OP_COMMAND, CMDS["CLEAR_FAULTS"]))

    # frames of wrong length, invalid DLC, ids of other nodes and beyond 11 bits
    recs = []
    for m in db.messages:
        for dlc in (0, 1, m.length - 1, m.length + 1, 8, 9, 15):
            if 0 <= dlc != m.length:
                recs.append(raw_frame(m.frame_id, bytes(range(1, 9)), dlc))
        recs.append(raw_frame(m.frame_id + 3, bytes(8), m.length))  # node 3
    recs.append(rec(OP_FRAME, 0x40, 0x80, 2, bytes([1, 0])))        # id > 0x7FF
    recs.append(rec(OP_FRAME, 0x40, 0xFF, 2, bytes([1, 0])))
    recs.append(rec(OP_FRAME, 0x40, 0x00, 0x80, bytes([1, 0])))     # dlc 128
    recs.append(rec(OP_FRAME, 0x40, 0x00, 0xFF, bytes([1, 0])))     # dlc 255
    add("bad_frames", platform(), *recs, tick(2))

    # sensor faults while active
    for fault in range(5):
        add(f"adc_fault{fault}", platform(),
            tick(2), cmd("ARM"), tick(2), cmd("START"), tick(5, host_hb=True),
            rec(OP_ADC, 0x10, 0x00, fault), tick(2, host_hb=True), rec(OP_ADC, c=5),
            cmd("CLEAR_FAULTS"), tick(2), cmd("ARM"))
    add("position_limit", platform(),
        tick(2), cmd("ARM"), rec(OP_SENSOR, 0), tick(2), rec(OP_SENSOR, 255), tick(2),
        cmd("CLEAR_FAULTS"), rec(OP_SENSOR, 128), tick(1), cmd("ARM"), cmd("START"),
        rec(OP_SETPOINT, 10), tick(10, host_hb=True), rec(OP_SETPOINT, 240),
        tick(10, host_hb=True), tick(10, late=3))

    # a DAC that fails every write, while active and while in FAULT, then repaired
    add("dac_fail", platform(),
        tick(2), cmd("ARM"), tick(3), rec(OP_ADC, c=6), tick(2), cmd("CLEAR_FAULTS"),
        tick(1), rec(OP_ADC, c=7), tick(1), cmd("CLEAR_FAULTS"), cmd("ARM"), tick(2),
        msg("ESTOP"), rec(OP_ADC, c=6), tick(1), rec(OP_ADC, c=7), tick(1))

    # CAN faults: bus-off, error-passive, blocked TX, drops and duplicates
    add("can_faults", platform(),
        tick(2), cmd("ARM"), rec(OP_CAN, c=0), rec(OP_POLL), tick(1), cmd("CLEAR_FAULTS"),
        rec(OP_CAN, 200, 0, 4, b""), rec(OP_CAN, c=0), rec(OP_POLL), cmd("CLEAR_FAULTS"),
        rec(OP_ADVANCE, 0x00, 0x60, 0), cmd("CLEAR_FAULTS"),
        rec(OP_CAN, 200, 0, 1, bytes([200])), rec(OP_POLL), tick(1),
        rec(OP_CAN, 1, 0, 3), cmd("ARM"), param("GET", 2), tick(3), rec(OP_CAN, 0, 0, 3),
        rec(OP_CAN, 1, 2, 5), cmd("DISARM"), rec(OP_CAN, 0, 3, 6), param("GET", 3),
        rec(OP_CAN, 1, 0, 2), tick(40), rec(OP_CAN, c=7), rec(OP_POLL), cmd("CLEAR_FAULTS"))

    # the loop as the port runs it: frames through the fake bus and filters
    add("loop", platform(watchdog=True),
        cmd("ARM", op=OP_INJECT), msg("COMMAND", op=OP_INJECT, Command=CMDS["START"], Arg=0),
        rec(OP_STEP, b=3), cmd("ARM", op=OP_INJECT), rec(OP_STEP, b=2),
        msg("HOST_HEARTBEAT", op=OP_INJECT, Counter=0), cmd("START", op=OP_INJECT),
        rec(OP_REAL_STEP, b=7), msg("ESTOP_ALL", op=OP_INJECT), rec(OP_REAL_STEP, b=1),
        cmd("CLEAR_FAULTS", node=3, op=OP_INJECT), rec(OP_STEP, b=1),
        rec(OP_ADVANCE, 0x00, 0x00, 0x03), rec(OP_REBOOT, c=0), rec(OP_STEP), cmd("CLEAR_FAULTS"))

    # DAC and actuator settings: slew limits, polarity, safe modes
    for mode in range(3):
        add(f"safe_mode{mode}", platform(),
            set_param("safety.safe_mode", mode), set_param("safety.safe_kpa", 150.0),
            set_param("act.slew_kpa_s", 1000.0), tick(3, sample=START_RAW), cmd("ARM"),
            tick(20, sample=START_RAW), cmd("SELECT_CONTROLLER", 4), cmd("START"),
            set_param("ctrl.openloop_u", 300.0), tick(50, sample=START_RAW, host_hb=True),
            set_param("ctrl.openloop_u", -300.0), tick(50, sample=START_RAW, host_hb=True),
            cmd("ESTOP"), tick(3), cmd("CLEAR_FAULTS"), tick(2),
            set_param("act.polarity", -1), set_param("dac.counts_per_kpa", -2.0),
            set_param("dac.counts_at_zero_kpa", 4000.0), tick(2), cmd("ARM"), tick(5))
    return s


# ---------------------------------------------------------------- dictionary --

def dict_entries() -> dict[str, bytes]:
    e: dict[str, bytes] = {}
    for m in db.messages:
        for node in (0, 1):
            fid = m.frame_id + node
            e[f"frame_{m.name.lower()}_n{node}"] = bytes([OP_FRAME, fid & 0xFF, fid >> 8, m.length])
    for name in CMDS:
        e[f"cmd_{name.lower()}"] = cmd(name)
    e["estop"] = msg("ESTOP")
    e["estop_all"] = msg("ESTOP_ALL")
    e["host_heartbeat"] = msg("HOST_HEARTBEAT", Counter=0)
    e["tick_1"] = tick(1, sample=START_RAW)
    e["tick_50_hb"] = tick(50, sample=START_RAW, host_hb=True)
    e["sensor_mid"] = rec(OP_SENSOR, 128)
    for p in PTABLE:
        e[f"id_{p['name']}"] = struct.pack("<H", p["id"])
    for v in (0.0, 1.0, -1.0, 0.5, 4095.0, 65535.0, 1000.0, -1000.0, 1e6, 1e-6):
        e[f"f32_{v:g}"] = struct.pack("<f", v)
    e["f32_nan"] = struct.pack("<I", 0x7FC00000)
    e["f32_inf"] = struct.pack("<I", 0x7F800000)
    e["f32_ninf"] = struct.pack("<I", 0xFF800000)
    e["f32_denorm"] = struct.pack("<I", 0x00000001)
    for v in (0, 1, 2, 15, 50, 4095, 4096, 65535, 65536, 0xFFFFFFFF, 0x80000000):
        e[f"u32_{v}"] = struct.pack("<I", v)
    return e


def dict_text(entries: dict[str, bytes]) -> str:
    lines = ["# libFuzzer dictionary of tests/fuzz/fuzz_frames.c, generated by "
             "tests/fuzz/make_corpus.py from the DBC and params.toml"]
    for name, value in entries.items():
        key = "".join(c if c.isalnum() else "_" for c in name)
        lines.append(f'{key}="' + "".join(f"\\x{b:02X}" for b in value) + '"')
    return "\n".join(lines) + "\n"


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("out_dir", type=Path, help="corpus directory (created; seeds written by name)")
    ap.add_argument("--dict", type=Path, help="write the libFuzzer dictionary here")
    args = ap.parse_args()
    args.out_dir.mkdir(parents=True, exist_ok=True)
    all_seeds = seeds()
    for name, data in all_seeds.items():
        (args.out_dir / f"seed_{name}").write_bytes(data)
    if args.dict:
        args.dict.parent.mkdir(parents=True, exist_ok=True)
        args.dict.write_text(dict_text(dict_entries()))
    total = sum(len(d) for d in all_seeds.values())
    print(f"make_corpus: {len(all_seeds)} seeds ({total} bytes) in {args.out_dir}"
          + (f", dictionary {args.dict}" if args.dict else ""))
    return 0


if __name__ == "__main__":
    sys.exit(main())
