# SPDX-License-Identifier: Apache-2.0
"""The streamed set-point (ref.kind STREAM, SETPOINT frames) and telemetry
(TELEM_A..E every telem.decimation ticks while RUNNING, only the frames of
telem.mask), in lockstep mode."""
from __future__ import annotations

import struct

import pytest
from test_fw_lib import (
    COUNTS_MID,
    PROTO,
    STATE,
    Rig,
    arm,
    arm_and_start,
    base_id,
    counts_to_cm,
    default_of,
    f32,
    f32_bits,
    query_state,
    replies_until,
    sentinel_get,
    start,
)

NODE = 6
SETPOINT = base_id("SETPOINT")
TELEM = ["TELEM_A", "TELEM_B", "TELEM_C", "TELEM_D", "TELEM_E"]


def stream_node(firmware, bus, rate: float = 0.0, mode: int = 0):
    fw, node = start(firmware, bus, node=NODE)
    node.set("ctrl.mode", mode)
    node.set("ref.kind", 6)                      # STREAM
    node.set("ref.rate_cm_s", rate)
    node.set("telem.decimation", 1)
    node.set("telem.mask", 0x02)                 # TELEM_B: XrCm, ECm
    return fw, node


def xr_after_tick(node, rig: Rig) -> dict:
    rig.tick(host_heartbeat=True)
    return node.wait_for("TELEM_B")


def test_stream_moves_the_reference(firmware, bus) -> None:
    fw, node = stream_node(firmware, bus)
    x = counts_to_cm(COUNTS_MID)
    offset = default_of("ref.offset_cm")
    rig = arm(node, settle_ticks=2)
    node.setpoint(-1.0)                          # while ARMED: dropped
    assert node.start().result == 0
    b = xr_after_tick(node, rig)
    assert b["XrCm"] == offset, b                # STREAM starts at ref.offset_cm
    assert b["ECm"] == f32(x - offset)
    for target in (-1.0, -2.5, -0.01, -2.99, -1.75):
        node.setpoint(target)
        b = xr_after_tick(node, rig)
        assert b["XrCm"] == f32(target), (target, b)
        assert b["ECm"] == pytest.approx(x - target, abs=1e-5)
        b = xr_after_tick(node, rig)             # it stays there
        assert b["XrCm"] == f32(target)
    current = f32(-1.75)
    # outside the band (strictly inside (x_min, x_max) is required) or not finite: ignored
    x_min, x_max = default_of("safety.x_min_cm"), default_of("safety.x_max_cm")
    rejected = [x_min, x_max, x_min - 0.001, x_max + 0.001, 0.5, -3.5, 1000.0, -1000.0, 3.0e38]
    for target in rejected:
        node.send_raw(SETPOINT | NODE, f32_bits(target))
        assert xr_after_tick(node, rig)["XrCm"] == current, target
    for bits in (0x7FC00000, 0xFFC00000, 0x7F800001, 0x7F800000, 0xFF800000):
        node.send_raw(SETPOINT | NODE, struct.pack("<I", bits))
        assert xr_after_tick(node, rig)["XrCm"] == current, hex(bits)
    # several set-points between two ticks: the last one counts
    node.setpoint(-2.0)
    node.setpoint(-0.5)
    assert xr_after_tick(node, rig)["XrCm"] == -0.5
    # after STOP and START, the stream begins again at the offset
    assert node.stop().result == 0
    node.setpoint(-2.0)                          # ARMED: dropped
    rig.tick()
    assert node.start().result == 0
    assert xr_after_tick(node, rig)["XrCm"] == offset
    assert query_state(node) == STATE["RUNNING"]
    fw.stop()


def test_stream_rate_limit(firmware, bus) -> None:
    """ref.rate_cm_s > 0: the reference moves towards the set-point at that
    rate (per tick: rate / sys.tick_hz)."""
    rate = 2.0
    fw, node = stream_node(firmware, bus, rate=rate)
    rig = arm_and_start(node, settle_ticks=2)
    offset = default_of("ref.offset_cm")
    assert xr_after_tick(node, rig)["XrCm"] == offset
    node.setpoint(-1.0)
    step = rate / default_of("sys.tick_hz")
    xs = [xr_after_tick(node, rig)["XrCm"] for _ in range(300)]
    # monotonic, at most one step per tick, reaches the target and stays
    prev = offset
    for v in xs:
        assert prev - 1e-6 <= v <= prev + step + 1e-5, (prev, v)
        prev = v
    assert xs[-1] == -1.0
    n_moving = sum(1 for v in xs if v != -1.0)
    assert abs(n_moving - 0.5 / step) <= 2, n_moving
    fw.stop()


def test_stream_with_ppc_keeps_w1_from_the_band(firmware, bus) -> None:
    """PPC with ppc.band_check: targets must lie inside (x_min + w1, x_max - w1);
    without the band check (or another controller) the whole open band."""
    fw, node = stream_node(firmware, bus, mode=1)
    w1 = default_of("ppc.w1_cm")
    rig = arm_and_start(node, settle_ticks=1)
    assert xr_after_tick(node, rig)["XrCm"] == default_of("ref.offset_cm")
    for target, ok in ((-0.1, False), (-2.9, False), (-0.25, True), (-2.75, True), (-w1 + 0.01, False)):
        before = xr_after_tick(node, rig)["XrCm"]
        node.setpoint(target)
        got = xr_after_tick(node, rig)["XrCm"]
        assert got == (f32(target) if ok else before), (target, got)
    assert node.disarm().result == 0
    node.set("ppc.band_check", 0)
    rig = arm_and_start(node, rig, settle_ticks=1)
    node.setpoint(-0.1)
    assert xr_after_tick(node, rig)["XrCm"] == f32(-0.1)
    fw.stop()


def test_stream_negative_rate_refused_at_start(firmware, bus) -> None:
    """ref.rate_cm_s is the STREAM rate limit, >= 0: a negative one makes
    START fail (RANGE) and the node stays ARMED."""
    fw, node = stream_node(firmware, bus, rate=-1.0)
    arm(node, settle_ticks=1)
    ack = node.command("START", check=False)
    assert PROTO.status_name(ack.result) == "RANGE" and ack.state == STATE["ARMED"], ack
    fw.stop()


def test_setpoint_ignored_for_other_references(firmware, bus) -> None:
    fw, node = start(firmware, bus, node=NODE)
    node.set("ctrl.mode", 0)
    node.set("ref.kind", 0)                     # HOLD
    node.set("telem.decimation", 1)
    node.set("telem.mask", 0x02)
    rig = arm_and_start(node, settle_ticks=1)
    for target in (-1.0, -2.0):
        node.setpoint(target)
        assert xr_after_tick(node, rig)["XrCm"] == default_of("ref.offset_cm")
    fw.stop()


# ---------------------------------------------------------------- telemetry --

def run_ticks(node, rig: Rig, n: int) -> list[tuple[str, dict]]:
    """n ticks; every frame of the node in bus order (name, signals)."""
    out = []
    for _ in range(n):
        node.host_heartbeat()
        seq = rig.seq
        node.sensor_sample(seq, rig.counts)
        rig.seq = (rig.seq + 1) & 0xFF
        got = replies_until(node, lambda name, nid, s, seq=seq: name == "PLANT_ACTUATOR" and nid == NODE
                            and s["Seq"] == seq)
        out += [(name, s) for name, nid, s in got if nid == NODE and name != "HEARTBEAT"]
    out += [(name, s) for name, nid, s in sentinel_get(node) if nid == NODE and name != "HEARTBEAT"]
    return out


@pytest.mark.parametrize("tick_hz,decimation,mask", [(1000, 7, 31), (200, 3, 0b10101), (1000, 1, 0b01010),
                                                     (500, 10, 0b00001)])
def test_telemetry_every_decimation_ticks(firmware, bus, tick_hz, decimation, mask) -> None:
    fw, node = start(firmware, bus, node=NODE)
    node.set("sys.tick_hz", tick_hz)
    node.set("vel.fc_hz", 10.0)
    node.set("ctrl.mode", 0)
    node.set("telem.decimation", decimation)
    node.set("telem.mask", mask)
    rig = Rig(node)
    rig.tick()
    assert node.arm().result == 0
    armed = run_ticks(node, rig, 3 * decimation + 2)
    assert not [f for f in armed if f[0].startswith("TELEM")], "telemetry while ARMED"
    assert node.start().result == 0
    n = 10 * decimation + decimation - 1
    frames = run_ticks(node, rig, n)
    wanted = [t for i, t in enumerate(TELEM) if mask & (1 << i)]
    # per tick: PLANT_ACTUATOR, then the selected TELEM_* in order A..E, every decimation-th tick
    tick = 0
    groups = []
    for name, s in frames:
        if name == "PLANT_ACTUATOR":
            tick += 1
            continue
        assert name in wanted, name
        if not groups or groups[-1][0] != tick:
            groups.append((tick, []))
        groups[-1][1].append((name, s))
    assert [g[0] for g in groups] == [decimation * k for k in range(1, n // decimation + 1)], groups
    for t, g in groups:
        assert [name for name, _ in g] == wanted, (t, g)
    # TimeMs: the control time of the step, (tick - 1) x the period
    period_us = round(1e6 / tick_hz)
    if "TELEM_A" in wanted:
        times = [dict(g)["TELEM_A"]["TimeMs"] for _, g in groups]
        assert times == [((t - 1) * period_us) // 1000 for t, _ in groups], times
        assert {b - a for a, b in zip(times, times[1:])} == {decimation * period_us // 1000}
        assert all(dict(g)["TELEM_A"]["XCm"] == counts_to_cm(COUNTS_MID) for _, g in groups)
    if "TELEM_B" in wanted:
        assert all(dict(g)["TELEM_B"]["XrCm"] == default_of("ref.offset_cm") for _, g in groups)
    if "TELEM_E" in wanted:
        assert all(dict(g)["TELEM_E"]["PressureKpa"] == default_of("act.p0_kpa") for _, g in groups[1:])
    # STOP: no more telemetry
    assert node.stop().result == 0
    assert not [f for f in run_ticks(node, rig, 2 * decimation) if f[0].startswith("TELEM")]
    fw.stop()


def test_telemetry_off(firmware, bus) -> None:
    """telem.decimation 0 or telem.mask 0: no telemetry; both are live."""
    fw, node = start(firmware, bus, node=NODE)
    node.set("ctrl.mode", 0)
    rig = arm_and_start(node, settle_ticks=1)
    node.set("telem.decimation", 0)
    assert not [f for f in run_ticks(node, rig, 25) if f[0].startswith("TELEM")]
    node.set("telem.decimation", 2)
    node.set("telem.mask", 0)
    assert not [f for f in run_ticks(node, rig, 25) if f[0].startswith("TELEM")]
    node.set("telem.mask", 31)
    frames = run_ticks(node, rig, 4)
    assert sum(1 for f in frames if f[0] == "TELEM_A") == 2
    fw.stop()
