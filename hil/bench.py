# SPDX-License-Identifier: Apache-2.0
"""Lockstep throughput of the HIL loop, next to a raw python-can round trip with
the same firmware node in the same run, and where the time in between goes.

    python -m hil bench [--seconds 5]

Each variant drives one pma-fw-host node in lockstep mode (one PLANT_SENSOR =
one control tick) and counts completed steps, in 5 rounds of every variant in turn, each round
starting one variant further on (--seconds of wall time per variant in all): the rates are
each variant's median, the ratios the median of the rounds' ratios:

  raw        python-can send of a prebuilt frame + recv of the node's PLANT_ACTUATOR:
             the limit of this loop (the node's tick is in it)
  +codec     the frames encoded and decoded as the runner does (the DBC's layouts compiled
             once, pmactl.frame_layout)
  +log       and every frame written to the python-can BLF log
  +rig       and the simulated rig stepped by one control period (RK4)
  raw+telem  the raw loop again with the node RUNNING the runner's scenario: every frame
             the node sends in a tick is received (PLANT_ACTUATOR, its telemetry and
             heartbeats), the host heartbeat sent every 100 ticks, as in the runner: the
             limit of the runner's own traffic
  runner     the HIL runner's own step (hil/runner.py, one lane: also its
             bookkeeping and telemetry), from the same HOLD scenario

The cost of each addition is the difference of the reciprocal rates (us per step).
"""
from __future__ import annotations

import json
import statistics
import tempfile
import time
from pathlib import Path
from typing import Any, Callable

import can

from pmactl import PmaNode

from .fw_process import BUILD_HINT, FW_HOST, FirmwareProcess
from .rig import Rig
from .rig_params import RigParams
from .runner import LOCKSTEP_WATCHDOG_MS, REPLY_TIMEOUT_S, TIMED_EVERY
from .scenario import parse, protocol

NODE = 9          # the benchmark's own node; the runner's lanes are nodes 1, 2, ...
ROUNDS = 5
HOST_HEARTBEAT_EVERY = 100     # ticks: the runner's HOST_HEARTBEAT every 100 ms at 1 kHz
# the runner variant's scenario; raw+telem runs the node with the same parameters
RUN_PARAMS: dict[str, float] = {"act.p0_kpa": 100.0, "act.polarity": -1, "act.p_max_kpa": 900.0,
                                "ctrl.u_min": -800.0, "ctrl.u_max": 100.0}
RUN_REFERENCE: dict[str, Any] = {"kind": "HOLD", "offset_cm": -1.0}
RUN_RIG: dict[str, float] = {"p0_kpa": 60.0, "substep_s": 2.5e-4}
# each variant's cost is counted against the one it adds to
ADDED_TO = {"+codec": "raw", "+log": "+codec", "+rig": "+log", "raw+telem": "raw", "runner": "raw+telem"}


def _loop(seconds: float, step: Callable[[int], None]) -> float:
    """Steps per second of `step` over `seconds` of wall time (after 50 warm-up steps)."""
    for k in range(50):
        step(k)
    n = 0
    t0 = time.perf_counter()
    end = t0 + seconds
    while True:
        step(n)
        n += 1
        if n % 100 == 0 and time.perf_counter() >= end:
            break
    return n / (time.perf_counter() - t0)


def measure(cfg: dict[str, Any], seconds: float, work: Path) -> dict[str, Any]:
    proto = protocol()
    sensor_id = proto.frame_id("PLANT_SENSOR", NODE)
    act_id = proto.frame_id("PLANT_ACTUATOR", NODE)
    rig = Rig(RigParams.from_dict({"p0_kpa": 300.0, "substep_s": 2.5e-4}), seed=1)
    fw = FirmwareProcess(work, ["--node", str(NODE), "--storage", str(work / "bench.nvm"), "--lockstep",
                                "--watchdog-ms", str(LOCKSTEP_WATCHDOG_MS)],
                         channel=str(cfg.get("channel", "vcan0"))).start()
    bus = can.Bus(**cfg)
    bus.set_filters([{"can_id": act_id, "can_mask": 0x7FF, "extended": False}])
    logger = can.Logger(str(work / "bench.blf"))
    state = {"seq": 0}
    try:
        deadline = time.monotonic() + 10
        while time.monotonic() < deadline:      # the node is up when it answers a sample
            bus.send(can.Message(arbitration_id=sensor_id, data=bytes([0, 0x10, 0x08]), is_extended_id=False))
            if bus.recv(0.2) is not None:
                break
        else:
            raise RuntimeError(f"pma-fw-host did not answer:\n{fw.output()}")

        def exchange(data: bytes, log: bool) -> can.Message:
            msg = can.Message(arbitration_id=sensor_id, data=data, is_extended_id=False)
            bus.send(msg)
            if log:
                logger.on_message_received(msg)
            while True:
                r = bus.recv(REPLY_TIMEOUT_S)
                if r is None:
                    raise RuntimeError(f"no PLANT_ACTUATOR within {REPLY_TIMEOUT_S:g} s:\n{fw.output()[-2000:]}")
                if log:
                    logger.on_message_received(r)
                if r.arbitration_id == act_id and r.data[0] == data[0]:
                    return r

        def raw(_: int) -> None:
            state["seq"] = (state["seq"] + 1) & 0xFF
            exchange(bytes([state["seq"], 0x10, 0x08]), False)

        def variant(use_rig: bool, log: bool) -> Callable[[int], None]:
            def step(_: int) -> None:
                state["seq"] = (state["seq"] + 1) & 0xFF
                counts = rig.sensor_counts() if use_rig else 2064
                data = proto.encode_raw("PLANT_SENSOR", {"Seq": state["seq"], "RawCounts": counts})
                r = exchange(data, log)
                sig = proto.decode("PLANT_ACTUATOR", bytes(r.data))
                if use_rig:
                    rig.apply_dac(int(sig["DacCounts"]))
                    rig.step(1e-3)
            return step

        variants = {"raw": raw, "+codec": variant(False, False), "+log": variant(False, True),
                    "+rig": variant(True, True)}
        running = _RunningNode(bus, fw, sensor_id, act_id)
        # rounds of every variant in turn, the runner's too, and the median of each: the guest's
        # one CPU is shared with whatever else the machine does, and how fast it runs drifts over
        # a minute (the bare round trip 590-840 us on one day), so one block per variant would
        # compare different machines; the ratios are the medians of each round's ratio. Each
        # round starts one variant further on, so that no variant always follows the same one
        # (the first of a fixed order ran up to 20 % faster than the second, the same loop)
        slot = seconds / ROUNDS
        runs: list[dict[str, float]] = []

        def own_node(fn: Callable[[int], None]) -> Callable[[int], float]:
            def rate(_: int) -> float:
                bus.set_filters([{"can_id": act_id, "can_mask": 0x7FF, "extended": False}])
                _drain(bus)
                return _loop(slot, fn)
            return rate

        def runner(k: int) -> float:
            runs.append(_runner_rate(cfg, slot, work / f"r{k}"))
            return runs[-1]["ticks_per_s"]

        rates_of: dict[str, Callable[[int], float]] = {
            **{name: own_node(fn) for name, fn in variants.items()},
            "raw+telem": lambda _k: running.rate(slot), "runner": runner}
        names = list(rates_of)
        samples: dict[str, list[float]] = {k: [] for k in names}
        for k in range(ROUNDS):
            for name in names[k % len(names):] + names[:k % len(names)]:
                samples[name].append(rates_of[name](k))
        rates = {k: statistics.median(v) for k, v in samples.items()}
        # the rig alone, outside the bus loop
        t0 = time.perf_counter()
        for _ in range(2000):
            rig.step(1e-3)
        rig_us = (time.perf_counter() - t0) / 2000 * 1e6
    finally:
        logger.stop()
        bus.shutdown()
        fw.stop(expect_status=0)
    mid = sorted(runs, key=lambda r: r["ticks_per_s"])[len(runs) // 2]
    split = {k: mid[k] / mid["run_ticks"] * 1e6 for k in ("recv_wait_s", "rig_s", "other_s")}
    us = {k: 1e6 / v for k, v in rates.items()}

    def ratio(a: str, b: str) -> float:
        return statistics.median(x / y for x, y in zip(samples[a], samples[b]))
    return {"seconds": seconds, "rounds": ROUNDS, "steps_per_s": rates, "us_per_step": us,
            "steps_per_s_per_round": samples,
            "added_us_per_step": {k: us[k] - us[base] for k, base in ADDED_TO.items()},
            "rig_step_us_alone": rig_us, "runner_us_per_step": split,
            "runner_vs_raw": ratio("runner", "raw"),
            "runner_vs_raw_telem": ratio("runner", "raw+telem")}


def _drain(bus: can.BusABC) -> None:
    """Frames left in the socket's queue (the node's answers to another variant)."""
    while bus.recv(0) is not None:
        pass


class _RunningNode:
    """raw+telem: the node RUNNING the runner's scenario (PID holding a position), a prebuilt
    sample out and every frame of the tick in, python-can only; configured once, then ARMed,
    STARTed, measured, STOPped and DISARMed in each round."""

    def __init__(self, bus: can.BusABC, fw: FirmwareProcess, sensor_id: int, act_id: int) -> None:
        self.bus, self.fw, self.sensor_id, self.act_id = bus, fw, sensor_id, act_id
        bus.set_filters(None)
        self.node = PmaNode(bus, NODE, protocol())
        for key, value in {**RUN_PARAMS, "ref.offset_cm": RUN_REFERENCE["offset_cm"]}.items():
            self.node.set(key, value)
        self.node.select_controller("PID")
        self.node.select_reference(str(RUN_REFERENCE["kind"]))
        # a sample at the held position: the node measures x = offset, inside its limits
        self.counts = Rig(RigParams.from_dict(RUN_RIG), seed=1).sensor_counts()
        self.seq = self.hb = 0

    def step(self, k: int) -> None:
        self.seq = seq = (self.seq + 1) & 0xFF
        if k % HOST_HEARTBEAT_EVERY == 0:
            self.node.host_heartbeat(self.hb)
            self.hb = (self.hb + 1) & 0xFF
        self.bus.send(can.Message(arbitration_id=self.sensor_id,
                                  data=bytes([seq, self.counts & 0xFF, self.counts >> 8]), is_extended_id=False))
        while True:
            r = self.bus.recv(REPLY_TIMEOUT_S)
            if r is None:
                raise RuntimeError(f"no PLANT_ACTUATOR within {REPLY_TIMEOUT_S:g} s:\n{self.fw.output()[-2000:]}")
            if r.arbitration_id == self.act_id and r.data[0] == seq:
                return

    def rate(self, seconds: float) -> float:
        self.bus.set_filters(None)
        _drain(self.bus)
        for k in range(20):              # the node's sample is this one before ARM
            self.step(k)
        self.node.arm()
        self.step(0)
        self.node.start()
        rate = _loop(seconds, self.step)
        status = self.node.status()
        if status.state_name != "RUNNING":
            raise RuntimeError(f"raw+telem: the node left RUNNING ({status.summary()})")
        self.node.stop()
        self.node.disarm()
        return rate


def _runner_rate(cfg: dict[str, Any], seconds: float, work: Path) -> dict[str, float]:
    from .runner import Runner, RunOptions
    # a 1-lane HOLD run; its length in control time is set so that it lasts about `seconds`
    sc = parse({"name": "bench", "duration_s": max(1.0, seconds * 0.6), "rig": dict(RUN_RIG),
                "params": dict(RUN_PARAMS), "reference": dict(RUN_REFERENCE),
                "controllers": [{"label": "pid", "mode": "PID"}]})
    summary = Runner(sc, RunOptions(out=work / "runner", bus_config=cfg, progress=False)).run()
    if summary["errors"]:
        raise RuntimeError("; ".join(summary["errors"]))
    return dict(summary["benchmark"])


def run_bench(cfg: dict[str, Any], seconds: float, out: Path) -> int:
    if not FW_HOST.exists():
        print(f"hil bench: {FW_HOST} not found: {BUILD_HINT}")
        return 1
    out.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(dir=out) as tmp:
        r = measure(cfg, seconds, Path(tmp))
    print(f"lockstep HIL loop over {cfg.get('interface')} {cfg.get('channel')}, one pma-fw-host node, "
          f"{seconds:g} s per variant")
    per = r["steps_per_s_per_round"]
    print(f"{'variant':9s} {'steps/s':>9s} {'rounds':>11s} {'us/step':>9s} {'added us':>9s}  to")
    for k, v in r["steps_per_s"].items():
        base = ADDED_TO.get(k)
        added = "" if base is None else f"{r['added_us_per_step'][k]:9.0f}  {base}"
        rounds = f"{min(per[k]):.0f}-{max(per[k]):.0f}"
        print(f"{k:9s} {v:9.0f} {rounds:>11s} {r['us_per_step'][k]:9.0f} {added}")
    print(f"rig.step(1 ms) alone: {r['rig_step_us_alone']:.0f} us")
    sp = r["runner_us_per_step"]
    print(f"runner step: {sp['recv_wait_s']:.0f} us in bus.recv (the node's tick, its telemetry and heartbeat "
          f"frames, the guest's scheduling), {sp['rig_s']:.0f} us rig + recording, {sp['other_s']:.0f} us the rest "
          f"(encode, send, decode, log, events); timed on every {TIMED_EVERY}th tick, each part with a clock read "
          f"of its own (a system call: about 70 us in the vcan guest)")

    def spread(a: str, b: str) -> str:
        rs = sorted(100 * x / y for x, y in zip(per[a], per[b]))
        return f"rounds {rs[0]:.0f}-{rs[-1]:.0f} %"
    print(f"runner / raw round trip: {100 * r['runner_vs_raw']:.0f} % ({spread('runner', 'raw')}; "
          "the node IDLE: its PLANT_ACTUATOR only)")
    ratio = r["runner_vs_raw_telem"]
    print(f"runner / raw+telem: {100 * ratio:.0f} % ({spread('runner', 'raw+telem')}; the same frames as the "
          "runner's: the runner's own cost)")
    if ratio < 0.8:
        print(f"the runner's own step costs more than 20 % of its traffic's raw round trip: "
              f"{r['us_per_step']['runner'] - r['us_per_step']['raw+telem']:.0f} us per step")
    (out / "bench.json").write_text(json.dumps(r, indent=2) + "\n")
    print(f"written: {out / 'bench.json'}")
    return 0
