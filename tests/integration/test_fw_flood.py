# SPDX-License-Identifier: Apache-2.0
"""A flood of valid requests (PARAM_REQ GETs to the node's own id at a high rate) must
leave the control tick and the tracking unchanged (docs/protocol.md "Bad input": the node
reads at most 128 frames per loop iteration, handles the control-relevant ones at once,
answers at most 8 requests per iteration and drops, counted, what does not fit its request queue).

The node runs in lockstep, so the closed loop is deterministic: the same samples give
the same commands. The test runs the same closed loop (a plant after the paper's eq. 7,
PPC on the CASE1 reference) twice, once quiet and once under the flood, and asserts on
ticks and commands, never on time: every sample is answered by exactly one
PLANT_ACTUATOR for that sample (Seq, Sample NEW), the node counted exactly one tick per
sample, and the pressure commands, hence the tracking, are the same bit for bit. The
flood is bounded in count (cangen -n) and the test stops it when the run is over.

The rate: by default a frame every 0.125 ms, 8,000 frames/s, the most a 1 Mbit/s bus carries
of such frames (docs/protocol.md "Bus load"). PMA_FLOOD_GAP_MS sets another gap; 0 is the full
rate of vcan (about 68,000 frames/s in the guest), where the guest kernel itself drops frames
from the node's socket buffer when the node is off its one CPU (RX_OVERRUNS): a plant sample
can then be lost before the firmware sees it, which no firmware can prevent on one socket, so
that rate is for a look by hand, not for CI."""
from __future__ import annotations

import math
import os
import socket
import struct
import subprocess
import time

from test_fw_lib import CHANNEL, STATE, base_id, default_of, param_raw, start

NODE = 3
SENSOR_ID = base_id("PLANT_SENSOR") | NODE
ACTUATOR_ID = base_id("PLANT_ACTUATOR") | NODE
PARAM_REQ_ID = base_id("PARAM_REQ") | NODE
PARAM_RESP_ID = base_id("PARAM_RESP") | NODE
COMMAND_ID = base_id("COMMAND") | NODE
COMMAND_ACK_ID = base_id("COMMAND_ACK") | NODE
FLOOD_FRAMES = 2_000_000            # an upper bound: the test stops cangen at the end of the run
FLOOD_GAP_MS = os.environ.get("PMA_FLOOD_GAP_MS", "0.125")   # 8,000 frames/s: a 1 Mbit/s bus full
RUN_TICKS = 3000                    # 3 s of control time at 1 kHz
GET_STATUS = 9
STATUS = {"RX_OVERRUNS": 2, "RX_DEFERRED": 3, "RX_DROPPED": 4, "TICKS": 6, "FRAMES_RX": 7}

CAN_RAW = 1
SOL_CAN_RAW = 101
CAN_RAW_FILTER = 1
CAN_FRAME = struct.Struct("=IB3x8s")

ADC_OFFSET, ADC_GAIN = default_of("adc.offset_cm"), default_of("adc.gain_cm_per_count")
DAC_ZERO, DAC_PER_KPA = default_of("dac.counts_at_zero_kpa"), default_of("dac.counts_per_kpa")
P0 = default_of("act.p0_kpa")


def raw_socket(filters: list[tuple[int, int]]) -> socket.socket:
    """A raw CAN socket that receives only the (id, mask) pairs given (none: nothing)."""
    s = socket.socket(socket.PF_CAN, socket.SOCK_RAW, CAN_RAW)
    s.setsockopt(SOL_CAN_RAW, CAN_RAW_FILTER, b"".join(struct.pack("=II", i, m) for i, m in filters))
    s.bind((CHANNEL,))
    return s


class LockstepPlant:
    """x'' = H u - D x' - G x (H = 2 (cm/s^2)/kPa, D = 30 1/s, G = 20 1/s^2, u = p - p0; the
    closed-loop plant of host/tests/integration/plant.py), one sample per tick, waiting for
    the node's command to each before the next."""

    def __init__(self) -> None:
        self.tx = raw_socket([])
        self.rx = raw_socket([(ACTUATOR_ID, 0x7FF)])
        self.rx.settimeout(10.0)
        self.x, self.v, self.seq = -1.0, 0.0, 0
        self.commands: list[int] = []
        self.positions: list[float] = []

    def close(self) -> None:
        self.tx.close()
        self.rx.close()

    def tick(self) -> tuple[int, int]:
        counts = int(round((self.x - ADC_OFFSET) / ADC_GAIN))
        self.tx.send(CAN_FRAME.pack(SENSOR_ID, 3, bytes([self.seq, counts & 0xFF, counts >> 8]) + bytes(5)))
        while True:
            can_id, dlc, data = CAN_FRAME.unpack(self.rx.recv(16))
            if can_id == ACTUATOR_ID and dlc == 4:
                break
        seq, dac = data[0], data[1] | data[2] << 8
        sample, active = data[3] & 0x3, data[3] >> 2 & 1
        assert seq == self.seq and sample == 0, (self.seq, data[:4].hex())   # this sample, NEW
        self.seq = (self.seq + 1) & 0xFF
        if active:                          # the node's output drives the muscle
            u = (dac - DAC_ZERO) / DAC_PER_KPA - P0
            for _ in range(4):              # RK-free: 4 explicit sub-steps of 0.25 ms
                a = 2.0 * u - 30.0 * self.v - 20.0 * self.x
                self.v += a * 2.5e-4
                self.x += self.v * 2.5e-4
        self.commands.append(dac)
        self.positions.append(self.x)
        return dac, active


def command(code: int, arg: int = 0) -> tuple[int, int]:
    """A COMMAND and its (Result, State), over a socket of its own (see status)."""
    s = raw_socket([(COMMAND_ACK_ID, 0x7FF)])
    s.settimeout(10.0)
    try:
        s.send(CAN_FRAME.pack(COMMAND_ID, 2, bytes([code, arg]) + bytes(6)))
        while True:
            can_id, dlc, data = CAN_FRAME.unpack(s.recv(16))
            if data[0] == code and data[1] == arg:
                return struct.unpack("<b", data[2:3])[0], data[3]
    finally:
        s.close()


def status(name: str) -> int:
    """GET_STATUS over a socket of its own that receives only the node's PARAM_RESP (the
    test's bus socket holds the flood's backlog)."""
    s = raw_socket([(PARAM_RESP_ID, 0x7FF)])
    s.settimeout(10.0)
    try:
        s.send(CAN_FRAME.pack(PARAM_REQ_ID, 8, param_raw(GET_STATUS, 1, STATUS[name])))
        while True:
            can_id, dlc, data = CAN_FRAME.unpack(s.recv(16))
            if data[0] & 0xF == GET_STATUS and data[1] | data[2] << 8 == STATUS[name]:
                assert data[3] == 0, data.hex()
                return int.from_bytes(data[4:8], "little")
    finally:
        s.close()


def closed_loop_run(firmware, bus, flood: bool) -> tuple[list[int], list[float], dict[str, int]]:
    # A full-rate flood inside the one-CPU guest can hold the node off the CPU for seconds on a
    # loaded machine; the wall-clock watchdog (what a stall test checks elsewhere) is not what
    # this test is about, so it is set long.
    fw, node = start(firmware, bus, node=NODE, extra=["--watchdog-ms", "60000"])
    node.timeout_s = 10.0                   # a hang guard (the guest's one CPU is shared)
    for name, v in (("ppc.w1_cm", 0.3), ("ppc.ff_gain_per_s", 2.0), ("safety.host_timeout_ms", 0),
                    ("telem.decimation", 0)):
        node.set(name, v)
    node.command("SELECT_REFERENCE", 4)   # CASE1
    plant = LockstepPlant()
    cangen = None
    try:
        for _ in range(20):
            plant.tick()
        assert command(1) == (0, STATE["ARMED"])                           # ARM
        for _ in range(300):
            plant.tick()
        ticks_before = status("TICKS")
        if flood:
            # the flood: GETs of id 3 to node 3, back to back (gap 0), bounded in count
            # (in the guest's one CPU cangen fills the node's socket buffer in its time
            # slices: the kernel drops frames there, counted as RX_OVERRUNS)
            cangen = subprocess.Popen(["cangen", CHANNEL, "-g", FLOOD_GAP_MS, "-I", f"{PARAM_REQ_ID:03X}", "-L", "8",
                                       "-D", "0003000000000000", "-n", str(FLOOD_FRAMES)],
                                      stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
            time.sleep(0.5)                 # (only to let the flood get going; nothing is timed)
        assert command(3) == (0, STATE["RUNNING"])                         # START
        plant.commands.clear()
        plant.positions.clear()
        for _ in range(RUN_TICKS):
            plant.tick()
        if cangen is not None:
            assert cangen.poll() is None, "the flood ended before the run: raise FLOOD_FRAMES"
            cangen.terminate()
            cangen.wait(10)
            cangen = None
        time.sleep(0.5)                     # let the node answer what it queued
        counts = {name: status(name) for name in STATUS}
        counts["TICKS"] -= ticks_before
        return plant.commands, plant.positions, counts
    finally:
        if cangen is not None:
            cangen.kill()
            cangen.wait(10)
        plant.close()
        fw.stop()


def test_request_flood_leaves_ticks_and_tracking_unchanged(firmware, bus) -> None:
    quiet_cmd, quiet_x, quiet = closed_loop_run(firmware, bus, flood=False)
    flood_cmd, flood_x, flooded = closed_loop_run(firmware, bus, flood=True)
    # one tick per sample, none lost or added: the node's own count over the run
    assert quiet["TICKS"] == flooded["TICKS"] == RUN_TICKS, (quiet, flooded)
    assert len(flood_cmd) == len(quiet_cmd) == RUN_TICKS
    assert flood_cmd == quiet_cmd, "the flood changed the pressure commands"
    # the tracking (CASE1: x_r = -0.5 sin(t) - 2 cm), the same in both runs, and inside w1 after t_u
    xr = [-0.5 * math.sin(k * 0.001) - 2.0 for k in range(RUN_TICKS)]
    e_after_tu = [abs(x - r) for x, r in zip(flood_x, xr)][2000:]
    assert flood_x == quiet_x and max(e_after_tu) < 0.3, max(e_after_tu)
    # what the node deferred and dropped is counted (printed above); none when quiet
    assert quiet["RX_DROPPED"] == 0
    print(f"quiet {quiet}, flooded {flooded}")
    # the flood reached the firmware: thousands more frames handled than in the quiet run
    assert flooded["FRAMES_RX"] > quiet["FRAMES_RX"] + 1000, (quiet, flooded)
