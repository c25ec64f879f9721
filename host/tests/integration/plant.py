# SPDX-License-Identifier: Apache-2.0
"""A simulated plant behind the plant bridge, in a thread: the rig side of
PLANT_SENSOR / PLANT_ACTUATOR for pma-fw-host in lockstep mode (one sample is one
control tick).

The plant is the paper's eq. 7 with constant coefficients, the plant of the firmware's
closed-loop unit test (docs/controllers.md, "Measured: barrier steps vs velocity
estimator"): x'' = H u - D x' - G x with H = 2 (cm/s^2)/kPa, D = 30 1/s, G = 20 1/s^2,
u = p - p0 in kPa (p the pressure command, p0 = act.p0_kpa). While the node's output is
inactive (safe state: vent) the rig holds the load at a rest position (a mechanical
stop), so a vented muscle never leaves the sensor's range.

Counts and pressures use the default scaling parameters (adc.*, dac.*) of the table.

Time. The rig is the node's clock: in lockstep the node advances one control tick per
sample, and nothing else. The rig paces its samples at rate_hz of wall time, but what a
test checks is counted in control ticks: wait with wait_ticks, or pause() the rig to
freeze control time while the test does something slow (run_ticks, resume,
resume_on), never with sleeps. Two things on the node still count wall time, and the
rig keeps both from depending on how fast the machine runs:

- A RUNNING node faults HOST_HEARTBEAT_LOST after safety.host_timeout_ms of *control*
  time without HOST_HEARTBEAT, while hosts (pmactl record, pmactl monitor
  --host-heartbeat) send one every 100 ms of *wall* time. On a loaded machine the rig's
  thread can get ahead of a host's process. So the rig holds its next sample while the
  node is RUNNING (as its last HEARTBEAT or COMMAND_ACK says), a host heartbeat to the
  node has been seen within host_gate_s of wall time, and host_gate_ticks ticks have
  passed since that heartbeat; it goes on at the next host heartbeat. A host that sends
  none, or stopped sending (more than host_gate_s ago), is not waited for: the node
  faults as it should (host_gate_ticks=None turns the hold off).
- The node's software watchdog counts wall time: the fixtures start pma-fw-host with a
  long one (conftest.py).
"""
from __future__ import annotations

import math
import threading
import time
from typing import Callable

import can
import numpy as np

from pmactl.protocol import load_protocol

PROTO = load_protocol()
STATE = {name: code for code, name in PROTO.state_names.items()}


def _default(name: str) -> float:
    return float(PROTO.param(name).default)


ADC_OFFSET, ADC_GAIN = _default("adc.offset_cm"), _default("adc.gain_cm_per_count")
DAC_ZERO, DAC_PER_KPA = _default("dac.counts_at_zero_kpa"), _default("dac.counts_per_kpa")


def cm_to_counts(x_cm: float) -> int:
    return int(round((x_cm - ADC_OFFSET) / ADC_GAIN))


def counts_to_kpa(counts: int) -> float:
    return (counts - DAC_ZERO) / DAC_PER_KPA


class PlantRig:
    def __init__(self, channel: str, node: int = 0, x_rest_cm: float = -1.0, p0_kpa: float = 300.0,
                 h: float = 2.0, d: float = 30.0, g: float = 20.0, tick_s: float = 0.001,
                 rate_hz: float = 1000.0, noise_cm: float = 0.0, seed: int = 1,
                 host_gate_ticks: int | None = 250, host_gate_s: float = 10.0) -> None:
        self.channel, self.node = channel, node
        self.x_rest, self.p0 = x_rest_cm, p0_kpa
        self.h, self.d, self.g = h, d, g
        self.tick_s, self.rate_hz = tick_s, rate_hz
        self.noise = noise_cm
        self.seed = seed
        self.rng = np.random.default_rng(seed)
        self.x, self.v = x_rest_cm, 0.0
        self.seq = 0
        self.ticks = 0
        self.misses = 0
        self.active = False
        # the node's state, from its last HEARTBEAT or COMMAND_ACK (None: none seen yet)
        self.state: int | None = None
        # HOST_HEARTBEAT frames to the node, and when (rig ticks, wall time) the last one came
        self.host_gate_ticks, self.host_gate_s = host_gate_ticks, host_gate_s
        self.host_heartbeats = 0
        self.host_holds = 0                  # polls spent holding a sample for a host heartbeat
        self._host_tick = 0
        self._host_wall = -math.inf
        # pausing: the rig sends no sample once ticks >= _run_until (until the node reaches
        # _resume_state, if set); _idle is set while it does so
        self._lock = threading.Lock()
        self._run_until: float = math.inf
        self._resume_state: int | None = None
        self._idle = threading.Event()
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)

    def start(self) -> "PlantRig":
        self._thread.start()
        return self

    def stop(self) -> None:
        self._stop.set()
        self._thread.join(5)

    def __enter__(self) -> "PlantRig":
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.stop()

    # ------------------------------------------------------------ waiting --
    # (timeouts: hang guards only, far beyond what a loaded machine needs)
    def wait_ticks(self, n: int, timeout_s: float = 120.0) -> None:
        """Returns once the rig has run n more ticks."""
        target = self.ticks + n
        self._wait(lambda: self.ticks >= target, timeout_s,
                   lambda: f"{self.ticks} of {target} ticks (misses {self.misses})")

    def wait_state(self, name: str, timeout_s: float = 120.0) -> None:
        """Returns once the node's HEARTBEAT or COMMAND_ACK showed state `name` (e.g. "RUNNING")."""
        self._wait(lambda: self.state == STATE[name], timeout_s,
                   lambda: f"node state {self.state}, not {name}")

    def wait_host_heartbeat(self, timeout_s: float = 120.0) -> None:
        """Returns once a HOST_HEARTBEAT to the node has been seen (after this call)."""
        target = self.host_heartbeats + 1
        self._wait(lambda: self.host_heartbeats >= target, timeout_s, lambda: "no HOST_HEARTBEAT")

    # ------------------------------------------------------------ pausing --
    def pause(self, timeout_s: float = 120.0) -> None:
        """Stops sending samples (after the exchange in progress): the node's control time
        stands still until run_ticks, resume or resume_on. Returns once the rig is idle."""
        with self._lock:
            self._run_until = min(self._run_until, self.ticks)
            self._resume_state = None
        self._wait(self._idle.is_set, timeout_s, lambda: "did not pause")

    def run_ticks(self, n: int, timeout_s: float = 120.0) -> None:
        """Paused: runs exactly n ticks, then pauses again. Returns once paused."""
        with self._lock:
            self._run_until = self.ticks + n
            self._resume_state = None
            self._idle.clear()
        self._wait(self._idle.is_set, timeout_s, lambda: f"{self.ticks} of {self._run_until} ticks")

    def resume(self) -> None:
        with self._lock:
            self._run_until, self._resume_state = math.inf, None

    def resume_on(self, state: str) -> None:
        """Paused: resumes as soon as the node reports `state` (e.g. "RUNNING": on the
        COMMAND_ACK of a START a recorder sends, so that no tick passes in between)."""
        with self._lock:
            self._resume_state = STATE[state]

    def reseed(self, seed: int | None = None) -> None:
        """Paused: restarts the sensor noise (default: the rig's seed), so that what follows
        sees the same noise every time."""
        self.rng = np.random.default_rng(self.seed if seed is None else seed)

    def _wait(self, done: Callable[[], bool], timeout_s: float, what: Callable[[], str]) -> None:
        deadline = time.monotonic() + timeout_s
        while not done():
            if not self._thread.is_alive():
                raise RuntimeError(f"plant rig: the thread ended ({what()})")
            if time.monotonic() > deadline:
                raise TimeoutError(f"plant rig: {what()} after {timeout_s:g} s")
            time.sleep(0.005)

    # ------------------------------------------------------------- thread --
    def _step(self, p_kpa: float, active: bool) -> None:
        if not active:
            self.x, self.v = self.x_rest, 0.0
            return
        u = p_kpa - self.p0
        n = 4
        h = self.tick_s / n
        for _ in range(n):                  # semi-implicit Euler, 4 substeps per tick
            a = self.h * u - self.d * self.v - self.g * self.x
            self.v += a * h
            self.x += self.v * h

    def _note(self, msg: can.Message) -> None:
        """Bookkeeping of the node's HEARTBEAT and COMMAND_ACK, and of HOST_HEARTBEAT to it."""
        i, n = msg.arbitration_id, len(msg.data)
        if (i, n) in self._state_frames:
            self.state = int(PROTO.decode(self._state_frames[(i, n)], bytes(msg.data))["State"])
        elif (i, n) == self._host_frame:
            self._host_tick, self._host_wall = self.ticks, time.monotonic()
            self.host_heartbeats += 1

    def _paused(self) -> bool:
        with self._lock:
            paused = self.ticks >= self._run_until
            if paused and self._resume_state is not None and self.state == self._resume_state:
                self._run_until, self._resume_state = math.inf, None
                paused = False
            if paused:
                self._idle.set()
            else:
                self._idle.clear()
            return paused

    def _host_hold(self) -> bool:
        """True while the next sample must wait for a host heartbeat (see the module's doc)."""
        return (self.host_gate_ticks is not None and self.state == STATE["RUNNING"]
                and self.ticks - self._host_tick >= self.host_gate_ticks
                and time.monotonic() - self._host_wall < self.host_gate_s)

    def _run(self) -> None:
        sensor_id = PROTO.frame_id("PLANT_SENSOR", self.node)
        act_id = PROTO.frame_id("PLANT_ACTUATOR", self.node)
        act_msg = PROTO.messages["PLANT_ACTUATOR"]

        def frame(name: str) -> tuple[int, int]:
            return PROTO.frame_id(name, self.node), PROTO.messages[name].length

        self._state_frames = {frame(name): name for name in ("HEARTBEAT", "COMMAND_ACK")}
        self._host_frame = frame("HOST_HEARTBEAT")
        ids = [act_id, self._host_frame[0], *(i for i, _ in self._state_frames)]
        bus = can.Bus(interface="socketcan", channel=self.channel,
                      can_filters=[{"can_id": i, "can_mask": 0x7FF} for i in ids])
        period = 1.0 / self.rate_hz
        next_t = time.monotonic()
        try:
            while not self._stop.is_set():
                if self._paused() or self._host_hold():
                    if not self._idle.is_set():
                        self.host_holds += 1
                    msg = bus.recv(0.005)
                    if msg is not None:
                        self._note(msg)
                    next_t = time.monotonic()        # no catch-up burst afterwards
                    continue
                x_meas = self.x + (self.rng.normal(0.0, self.noise) if self.noise else 0.0)
                counts = min(max(cm_to_counts(x_meas), 0), 65535)
                data = PROTO.encode("PLANT_SENSOR", {"Seq": self.seq, "RawCounts": counts})
                bus.send(can.Message(arbitration_id=sensor_id, data=data, is_extended_id=False))
                # A reply that does not come is asked for again with the same sample (the node
                # treats it as a repeat, one tick without a new sample: safety.sensor_timeout_ticks
                # of them in a row fault). Generous: a node that only waits for the CPU must not
                # get a row of repeats (the watchdog, conftest.py, catches a hung one first).
                deadline = time.monotonic() + 2.0
                reply = None
                while reply is None and (left := deadline - time.monotonic()) > 0:
                    msg = bus.recv(left)
                    if msg is None:
                        continue
                    if msg.arbitration_id == act_id and len(msg.data) == 4:
                        sig = act_msg.decode(bytes(msg.data), decode_choices=False)
                        if sig["Seq"] == self.seq:
                            reply = sig
                    else:
                        self._note(msg)
                if reply is None:
                    self.misses += 1                 # node restarting, or very busy: try again
                else:
                    self.active = bool(reply["OutputActive"])
                    self._step(counts_to_kpa(int(reply["DacCounts"])), self.active)
                    self.seq = (self.seq + 1) & 0xFF
                    self.ticks += 1
                next_t += period
                delay = next_t - time.monotonic()
                if delay > 0:
                    time.sleep(delay)
                else:
                    next_t = time.monotonic()        # behind: no catch-up burst
        finally:
            bus.shutdown()
