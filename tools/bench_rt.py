#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Real-time benchmark of pma-fw-host over vcan (printed figures, no assertions).

Run where vcan0 exists, e.g.:  hil/with-vcan .venv/bin/python tools/bench_rt.py

1. Tick period jitter in real-time mode at sys.tick_hz (default 1 kHz): the
   firmware sends one PLANT_ACTUATOR frame per tick; the intervals between the
   kernel receive timestamps of consecutive frames, minus the nominal period.
2. Sensor-sample-to-actuator-command latency: a PLANT_SENSOR frame is sent at
   a random phase of the tick; the latency is from its own (looped-back)
   timestamp to the first PLANT_ACTUATOR frame echoing its Seq. In real-time
   mode a sample waits for the next tick (0..1 period) plus the processing; in
   lockstep mode the sample is the tick, so the latency is the processing and
   the CAN path alone.

Inside the User-Mode Linux guest of hil/with-vcan (one CPU, shared by the
firmware and this script, timer resolution of the guest kernel) the figures
are far worse than on a native kernel or a board; they say what this loop
achieves here, not what the firmware can do.
"""
from __future__ import annotations

import argparse
import os
import random
import sys
import tempfile
import time
from pathlib import Path

import can
import numpy as np

from hil.fw_process import FirmwareProcess
from pmactl import PmaNode, load_protocol


def pct(a: np.ndarray) -> str:
    return (f"p50 {np.percentile(a, 50):8.1f}  p99 {np.percentile(a, 99):8.1f}  "
            f"max {a.max():8.1f}  (n = {a.size})")


def jitter(bus: can.BusABC, node: PmaNode, seconds: float, period_us: float) -> np.ndarray:
    act_id = node.proto.frame_id("PLANT_ACTUATOR", 0)
    stamps: list[float] = []
    end = time.monotonic() + seconds
    seq = 0
    next_sample = time.monotonic()
    while time.monotonic() < end:
        now = time.monotonic()
        if now >= next_sample:  # keep the sensor alive (about every 5 ms)
            node.sensor_sample(seq, 2457)
            seq += 1
            next_sample = now + 0.005
        m = bus.recv(0.005)
        if m is not None and m.arbitration_id == act_id:
            stamps.append(m.timestamp)
    t = np.asarray(stamps)
    return np.abs(np.diff(t) * 1e6 - period_us)


def latency(bus: can.BusABC, node: PmaNode, count: int) -> np.ndarray:
    sensor_id = node.proto.frame_id("PLANT_SENSOR", 0)
    act_id = node.proto.frame_id("PLANT_ACTUATOR", 0)
    out: list[float] = []
    rng = random.Random(1)
    for k in range(count):
        seq = (k + 7) & 0xFF
        time.sleep(rng.uniform(0.0, 0.002))
        node.sensor_sample(seq, 2457)
        t_sent = None
        deadline = time.monotonic() + 1.0
        while time.monotonic() < deadline:
            m = bus.recv(0.1)
            if m is None:
                continue
            if m.arbitration_id == sensor_id and m.data[0] == seq:
                t_sent = m.timestamp      # our own frame, looped back: the same clock
            elif m.arbitration_id == act_id and m.data[0] == seq and t_sent is not None:
                out.append((m.timestamp - t_sent) * 1e6)
                break
    return np.asarray(out)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--channel", default="vcan0")
    ap.add_argument("--seconds", type=float, default=5.0, help="jitter capture length (default 5)")
    ap.add_argument("--samples", type=int, default=500, help="latency samples (default 500)")
    args = ap.parse_args()
    if args.seconds <= 0 or args.samples <= 0:
        ap.error("--seconds and --samples must be positive")
    if not Path(f"/sys/class/net/{args.channel}").exists():
        print(f"bench_rt: no interface {args.channel}: run through hil/with-vcan", file=sys.stderr)
        return 2
    proto = load_protocol()
    print(f"pma-fw-host real-time benchmark on {args.channel} ({os.uname().release})")
    logs = tempfile.TemporaryDirectory(prefix="bench_rt-")
    for lockstep in (False, True):
        fw = FirmwareProcess(Path(logs.name), ["--node", "0"] + (["--lockstep"] if lockstep else []),
                             channel=args.channel).start()
        try:
            with can.Bus(interface="socketcan", channel=args.channel, receive_own_messages=True) as bus:
                node = PmaNode(bus, 0, proto, timeout_s=5.0)
                node.heartbeat()
                hz = float(node.get("sys.tick_hz"))
                mode = "lockstep" if lockstep else f"real time at {hz:g} Hz"
                if not lockstep:
                    j = jitter(bus, node, args.seconds, 1e6 / hz)
                    print(f"  tick period jitter |dT - T| [us], {mode}: {pct(j)}")
                lat = latency(bus, node, args.samples)
                print(f"  sample-to-command latency [us], {mode}: {pct(lat)}")
        finally:
            fw.stop()
    logs.cleanup()
    return 0


if __name__ == "__main__":
    sys.exit(main())
