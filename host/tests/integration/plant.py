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
"""
from __future__ import annotations

import threading
import time

import can
import numpy as np

from pmactl.protocol import load_protocol

PROTO = load_protocol()


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
                 rate_hz: float = 1000.0, noise_cm: float = 0.0, seed: int = 1) -> None:
        self.channel, self.node = channel, node
        self.x_rest, self.p0 = x_rest_cm, p0_kpa
        self.h, self.d, self.g = h, d, g
        self.tick_s, self.rate_hz = tick_s, rate_hz
        self.noise = noise_cm
        self.rng = np.random.default_rng(seed)
        self.x, self.v = x_rest_cm, 0.0
        self.seq = 0
        self.ticks = 0
        self.misses = 0
        self.active = False
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

    def wait_ticks(self, n: int, timeout_s: float = 30.0) -> None:
        """Returns once the rig has run n more ticks."""
        target = self.ticks + n
        deadline = time.monotonic() + timeout_s
        while self.ticks < target:
            if time.monotonic() > deadline:
                raise TimeoutError(f"plant rig: {self.ticks} of {target} ticks (misses {self.misses})")
            time.sleep(0.01)

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

    def _run(self) -> None:
        sensor_id = PROTO.frame_id("PLANT_SENSOR", self.node)
        act_id = PROTO.frame_id("PLANT_ACTUATOR", self.node)
        act_msg = PROTO.messages["PLANT_ACTUATOR"]
        bus = can.Bus(interface="socketcan", channel=self.channel,
                      can_filters=[{"can_id": act_id, "can_mask": 0x7FF}])
        period = 1.0 / self.rate_hz
        next_t = time.monotonic()
        try:
            while not self._stop.is_set():
                x_meas = self.x + (self.rng.normal(0.0, self.noise) if self.noise else 0.0)
                counts = min(max(cm_to_counts(x_meas), 0), 65535)
                data = PROTO.encode("PLANT_SENSOR", {"Seq": self.seq, "RawCounts": counts})
                bus.send(can.Message(arbitration_id=sensor_id, data=data, is_extended_id=False))
                deadline = time.monotonic() + 0.5
                reply = None
                while reply is None and (left := deadline - time.monotonic()) > 0:
                    msg = bus.recv(left)
                    if msg is not None and msg.arbitration_id == act_id and len(msg.data) == 4:
                        sig = act_msg.decode(bytes(msg.data), decode_choices=False)
                        if sig["Seq"] == self.seq:
                            reply = sig
                if reply is None:
                    self.misses += 1                 # node busy or restarting: try again
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
