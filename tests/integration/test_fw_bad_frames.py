# SPDX-License-Identifier: Apache-2.0
"""Malformed and foreign frames (docs/protocol.md "Bad input"): answered with
an error (COMMAND, PARAM_REQ) or dropped, never obeyed; after each one the
state and every parameter are unchanged and the node still answers."""
from __future__ import annotations

import struct
import time

import pytest
from test_fw_lib import (
    CAN_EFF_FLAG,
    CAN_RTR_FLAG,
    FAULT,
    PROTO,
    RESULT,
    SAMPLE,
    STATE,
    RawCan,
    Rig,
    arm,
    arm_and_start,
    base_id,
    default_of,
    f32,
    f32_bits,
    fresh_heartbeat,
    param_raw,
    param_resp,
    query_state,
    replies_of,
    sentinel_get,
    snapshot,
    start,
)

NODE = 3
OTHER_NODES = [n for n in range(16) if n != NODE]

COMMAND = base_id("COMMAND")
PARAM_REQ = base_id("PARAM_REQ")
PLANT_SENSOR = base_id("PLANT_SENSOR")
SETPOINT = base_id("SETPOINT")
HOST_HEARTBEAT = base_id("HOST_HEARTBEAT")

TYPES = {"f32": 0, "u32": 1, "i32": 2}


def value_bytes(p, v) -> bytes:
    return f32_bits(v) if p.type == "f32" else struct.pack("<i" if p.type == "i32" else "<I", int(v))


def set_raw(pname: str, value, reserved: int = 0, type_code: int | None = None, op: int = 1) -> bytes:
    p = PROTO.param(pname)
    t = TYPES[p.type] if type_code is None else type_code
    vb = value if isinstance(value, bytes) else value_bytes(p, value)
    return param_raw(op, t, p.id, reserved, vb)


def resp_value(sig: dict):
    return {0: sig.get("ValueF32"), 1: sig.get("ValueU32"), 2: sig.get("ValueI32")}.get(sig["Type"], None)


@pytest.fixture
def idle_node(firmware, bus):
    """A node in IDLE with a valid position (so that a wrongly obeyed ARM would succeed)."""
    fw, node = start(firmware, bus, node=NODE)
    rig = Rig(node)
    rig.tick()
    before = snapshot(node)
    yield fw, node, rig, before
    assert snapshot(node) == before, "a bad frame changed a parameter"
    fw.stop()


def test_command_wrong_length_is_answered_length(idle_node) -> None:
    fw, node, rig, _ = idle_node
    for data in (b"", b"\x01", b"\x01\x00\x00", b"\x01\x00\x00\x00", b"\x01\x00" + bytes(6), b"\x05\x00" + bytes(6)):
        node.send_raw(COMMAND | NODE, data)
        ack = node.wait_for("COMMAND_ACK")
        echo = (data[0] if len(data) > 0 else 0, data[1] if len(data) > 1 else 0)
        assert (ack["Command"], ack["Arg"]) == echo, (data, ack)
        assert ack["Result"] == RESULT["LENGTH"] and ack["State"] == STATE["IDLE"], (data, ack)
        assert query_state(node) == STATE["IDLE"]
    # in ARMED a DISARM / ESTOP command of the wrong length changes nothing either
    assert node.arm().state == STATE["ARMED"]
    for data in (b"\x02", b"\x02\x00\x00", b"\x05\x00\x00\x00\x00\x00\x00\x00"):
        node.send_raw(COMMAND | NODE, data)
        ack = node.wait_for("COMMAND_ACK")
        assert ack["Result"] == RESULT["LENGTH"] and ack["State"] == STATE["ARMED"], ack
    assert rig.tick()["OutputActive"] == 1
    assert node.disarm().state == STATE["IDLE"]


def test_param_req_wrong_length_is_answered_length(idle_node) -> None:
    fw, node, rig, before = idle_node
    full = set_raw("telem.mask", 3)                           # a valid SET, 8 bytes
    for n in (0, 1, 2, 3, 4, 7):
        node.send_raw(PARAM_REQ | NODE, full[:n])
        want_id = PROTO.param("telem.mask").id if n >= 3 else 0
        r = node.wait_for("PARAM_RESP", lambda s: s["Result"] != 0)
        assert r["Result"] == RESULT["LENGTH"], (n, r)
        assert r["Id"] == want_id, (n, r)
        if n >= 1:
            assert (r["Op"], r["Type"]) == (1, 1), (n, r)
        assert resp_value(r) in (0, None), r
        assert node.get("telem.mask") == 31
    # SAVE / RESTORE_DEFAULTS / LOAD of the wrong length do nothing either
    node.set("telem.mask", 30)
    for op in (2, 3, 8):
        node.send_raw(PARAM_REQ | NODE, bytes([op, 0, 0, 0]))
        assert node.wait_for("PARAM_RESP", lambda s, op=op: s["Op"] == op)["Result"] == RESULT["LENGTH"]
    assert node.get("telem.mask") == 30
    node.set("telem.mask", 31)


def test_param_req_malformed_fields(idle_node) -> None:
    fw, node, rig, before = idle_node
    p = PROTO.param("ppc.c")
    # Reserved != 0: UNKNOWN_COMMAND, for any Op
    for reserved in (1, 0x80, 0xFF):
        for op in (0, 1, 2, 3, 8):
            node.send_raw(PARAM_REQ | NODE, set_raw("ppc.c", 9.0, reserved=reserved, op=op))
            r = param_resp(node, op, p.id)
            assert r["Result"] == RESULT["UNKNOWN_COMMAND"], (reserved, op, r)
    assert node.get("ppc.c") == before["ppc.c"]
    # unknown Op 10..15 (9 is GET_STATUS)
    for op in range(10, 16):
        node.send_raw(PARAM_REQ | NODE, param_raw(op, 0, p.id, 0, f32_bits(9.0)))
        r = param_resp(node, op, p.id)
        assert r["Result"] == RESULT["UNKNOWN_COMMAND"], (op, r)
    # SET with Type 3..15 (and the other valid types): TYPE, the reply carries the value
    for t in list(range(3, 16)) + [1, 2]:
        node.send_raw(PARAM_REQ | NODE, param_raw(1, t, p.id, 0, f32_bits(9.0)))
        r = param_resp(node, 1, p.id)
        assert r["Result"] == RESULT["TYPE"], (t, r)
        assert r["Type"] == 0 and r["ValueF32"] == before["ppc.c"], (t, r)
    for name, t in (("telem.mask", 0), ("telem.mask", 2), ("act.polarity", 1), ("act.polarity", 0)):
        pp = PROTO.param(name)
        node.send_raw(PARAM_REQ | NODE, param_raw(1, t, pp.id, 0, b"\x01\x00\x00\x00"))
        assert param_resp(node, 1, pp.id)["Result"] == RESULT["TYPE"], name
    # GET with Type 3..15: the request's Type does not matter
    for t in (3, 9, 15):
        node.send_raw(PARAM_REQ | NODE, param_raw(0, t, p.id))
        r = param_resp(node, 0, p.id)
        assert r["Result"] == 0 and r["Type"] == 0 and r["ValueF32"] == before["ppc.c"], r


NAN_BITS = [0x7FC00000, 0xFFC00000, 0x7F800001, 0x7FFFFFFF, 0x7F800000, 0xFF800000]


def test_param_set_not_finite_and_out_of_range(idle_node) -> None:
    fw, node, rig, before = idle_node
    for p in PROTO.params:
        cases: list[tuple[bytes, str]] = []
        if p.type == "f32":
            cases += [(struct.pack("<I", bits), "NOT_FINITE") for bits in NAN_BITS]
            lo, hi = f32(p.min), f32(p.max)
            # the nearest representable values outside the range
            below = struct.unpack("<f", struct.pack("<i", struct.unpack("<i", struct.pack("<f", lo))[0]
                                                    + (1 if lo < 0 else -1)))[0] if lo != 0 else -1e-30
            above = struct.unpack("<f", struct.pack("<i", struct.unpack("<i", struct.pack("<f", hi))[0]
                                                    + (1 if hi > 0 else -1)))[0] if hi != 0 else 1e-30
            cases += [(f32_bits(below), "RANGE"), (f32_bits(above), "RANGE"),
                      (f32_bits(3.0e38), "RANGE"), (f32_bits(-3.0e38), "RANGE")]
        elif p.type == "u32":
            if p.min > 0:
                cases.append((struct.pack("<I", int(p.min) - 1), "RANGE"))
            cases += [(struct.pack("<I", int(p.max) + 1), "RANGE"), (struct.pack("<I", 0xFFFFFFFF), "RANGE")]
        else:
            cases += [(struct.pack("<i", int(p.min) - 1), "RANGE"), (struct.pack("<i", int(p.max) + 1), "RANGE"),
                      (struct.pack("<i", -2**31), "RANGE"), (struct.pack("<i", 2**31 - 1), "RANGE")]
        for vb, want in cases:
            node.send_raw(PARAM_REQ | NODE, param_raw(1, TYPES[p.type], p.id, 0, vb))
            r = param_resp(node, 1, p.id)
            assert PROTO.status_name(r["Result"]) == want, (p.name, vb.hex(), r)
            assert resp_value(r) == before[p.name], (p.name, vb.hex(), r)
    # unknown ids
    for pid in (0, 6, 999, 0xFFFF):
        for op in (0, 1, 4, 5, 6):
            node.send_raw(PARAM_REQ | NODE, param_raw(op, 1, pid, 0, b"\x01\x00\x00\x00"))
            assert param_resp(node, op, pid)["Result"] == RESULT["UNKNOWN_ID"], (pid, op)
    # an unknown id with an undefined Type: UNKNOWN_ID (the id is checked first), Type echoed
    for t in (3, 7, 15):
        for op in (0, 1, 4, 5, 6):
            node.send_raw(PARAM_REQ | NODE, param_raw(op, t, 999))
            r = param_resp(node, op, 999)
            assert r["Result"] == RESULT["UNKNOWN_ID"] and r["Type"] == t, (t, op, r)
    for pid in (max(q.id for q in PROTO.params), 0xFFFF):
        node.send_raw(PARAM_REQ | NODE, param_raw(7, 1, pid))
        assert param_resp(node, 7, pid)["Result"] == RESULT["EMPTY"]
    assert query_state(node) == STATE["IDLE"]


def test_frames_for_other_nodes_and_unknown_ids(idle_node) -> None:
    """No reply, no effect: other node ids, base ids from 0x100 up, the
    reserved ids 0x001..0x00F, and the ids nodes only send."""
    fw, node, rig, before = idle_node
    arm_cmd = b"\x01\x00"
    set_req = set_raw("telem.mask", 1)
    sent = []
    for other in OTHER_NODES:
        sent += [(COMMAND | other, arm_cmd), (PARAM_REQ | other, set_req), (base_id("ESTOP") | other, b""),
                 (PARAM_REQ | other, param_raw(2, 0, 0))]
    for base in range(0x100, 0x800, 0x10):
        sent += [(base | NODE, arm_cmd), (base | NODE, set_req)]
    for reserved in range(1, 16):
        sent.append((reserved, b""))
    for message in ("PLANT_ACTUATOR", "COMMAND_ACK", "PARAM_RESP", "HEARTBEAT",
                    "TELEM_A", "TELEM_B", "TELEM_C", "TELEM_D", "TELEM_E"):
        m = PROTO.messages[message]
        sent += [(base_id(message) | NODE, bytes([1] + [0] * (m.length - 1))), (base_id(message) | NODE, set_req)]
    for i in range(0, len(sent), 32):
        for fid, data in sent[i:i + 32]:
            node.send_raw(fid, data)
        got = sentinel_get(node)
        assert not replies_of(got), got
        assert query_state(node) == STATE["IDLE"]
    hb = fresh_heartbeat(node)
    assert hb["State"] == STATE["IDLE"] and hb["FaultCode"] == FAULT["NONE"]


def test_extended_remote_and_fd_frames_are_not_received(idle_node) -> None:
    fw, node, rig, before = idle_node
    with RawCan() as raw, RawCan(fd=True) as rawfd:
        frames = [
            (CAN_EFF_FLAG | COMMAND | NODE, b"\x01\x00"),             # ARM, 29-bit id
            (CAN_EFF_FLAG | PARAM_REQ | NODE, set_raw("telem.mask", 1)),
            (CAN_EFF_FLAG | base_id("ESTOP") | NODE, b""),
            (CAN_EFF_FLAG | 0, b""),                                  # "ESTOP_ALL" with a 29-bit id
            (CAN_EFF_FLAG | (0x1234 << 11) | COMMAND | NODE, b"\x01\x00"),
            (CAN_RTR_FLAG | COMMAND | NODE, None),                    # remote frames, DLC 2
            (CAN_RTR_FLAG | PARAM_REQ | NODE, None),
            (CAN_RTR_FLAG | base_id("ESTOP") | NODE, None),
            (CAN_RTR_FLAG, None),
        ]
        for fid, data in frames:
            if data is None:
                raw.send(fid, b"", dlc=2)
            else:
                raw.send(fid, data)
            got = sentinel_get(node)
            assert not replies_of(got), (hex(fid), got)
            assert query_state(node) == STATE["IDLE"], hex(fid)
        # CAN FD (vcan0 has MTU 72): never delivered to the node's classic socket
        mtu = int(open("/sys/class/net/vcan0/mtu").read())
        if mtu >= 72:
            for fid, data, flags in [
                (COMMAND | NODE, b"\x01\x00", 0),
                (COMMAND | NODE, b"\x01\x00", 0x01),                  # CANFD_BRS
                (PARAM_REQ | NODE, set_raw("telem.mask", 1), 0),
                (PARAM_REQ | NODE, set_raw("telem.mask", 1) + bytes(4), 0),   # 12 bytes
                (COMMAND | NODE, b"\x01\x00" + bytes(62), 0),
                (base_id("ESTOP") | NODE, b"", 0),
                (0, bytes(8), 0),
            ]:
                rawfd.send_fd(fid, data, flags)
                got = sentinel_get(node)
                assert not replies_of(got), (hex(fid), got)
                assert query_state(node) == STATE["IDLE"]
    # lockstep: none of these made a tick (the next sample is the next Seq, NEW)
    act = rig.tick()
    assert act["Sample"] == SAMPLE["NEW"] and act["OutputActive"] == 0
    hb = fresh_heartbeat(node)
    assert hb["State"] == STATE["IDLE"] and hb["FaultCode"] == FAULT["NONE"]


def test_extended_and_fd_plant_sensor_make_no_tick(firmware, bus) -> None:
    fw, node = start(firmware, bus, node=NODE)
    rig = Rig(node)
    rig.tick()
    with RawCan() as raw, RawCan(fd=True) as rawfd:
        raw.send(CAN_EFF_FLAG | PLANT_SENSOR | NODE, bytes([1]) + struct.pack("<H", 100))
        raw.send(CAN_RTR_FLAG | PLANT_SENSOR | NODE, b"", dlc=3)
        rawfd.send_fd(PLANT_SENSOR | NODE, bytes([1]) + struct.pack("<H", 100))
        got = sentinel_get(node)
    assert not [f for f in got if f[0] == "PLANT_ACTUATOR"], got
    assert rig.tick()["Sample"] == SAMPLE["NEW"]
    fw.stop()


def test_plant_sensor_wrong_length_is_dropped(firmware, bus) -> None:
    """ARMED: a PLANT_SENSOR of the wrong length carrying a wire-break value is
    dropped as if never received: no fault, and in lockstep no tick either
    (no PLANT_ACTUATOR answers it; docs/protocol.md "Bad input")."""
    fw, node = start(firmware, bus, node=NODE)
    before = snapshot(node)
    node.set("safety.sensor_timeout_ticks", 3)       # had they been ticks, they would time out
    rig = arm(node, settle_ticks=3)
    for data in (b"", bytes([rig.seq]), bytes([rig.seq, 10]), bytes([rig.seq, 10, 0, 0]),
                 bytes([rig.seq, 10, 0, 0, 0, 0, 0, 0]), bytes([rig.seq + 1, 10, 0, 0, 0])):
        node.send_raw(PLANT_SENSOR | NODE, data)
        got = sentinel_get(node)
        assert not [f for f in got if f[0] == "PLANT_ACTUATOR"], (data, got)
    assert query_state(node) == STATE["ARMED"]
    act = rig.tick()                                   # the next Seq follows the last good one
    assert act["Sample"] == SAMPLE["NEW"] and act["OutputActive"] == 1, act
    assert fresh_heartbeat(node)["FaultCode"] == FAULT["NONE"]
    assert node.disarm().result == 0
    node.set("safety.sensor_timeout_ticks", before["safety.sensor_timeout_ticks"])
    assert snapshot(node) == before
    fw.stop()


def test_setpoint_and_host_heartbeat_wrong_length_are_dropped(firmware, bus) -> None:
    fw, node = start(firmware, bus, node=NODE)
    node.set("ctrl.mode", 0)
    node.set("ref.kind", 6)                           # STREAM
    node.set("ref.rate_cm_s", 0.0)
    node.set("telem.decimation", 1)
    node.set("telem.mask", 0x02)                      # TELEM_B
    timeout = 10
    node.set("safety.host_timeout_ms", timeout)      # 10 ticks at 1 kHz
    rig = arm_and_start(node, settle_ticks=1)
    offset = default_of("ref.offset_cm")
    rig.tick(host_heartbeat=True)
    assert node.wait_for("TELEM_B")["XrCm"] == offset
    good = f32_bits(-1.0)
    for data in (good[:3], good + b"\0", good + bytes(4), b"", good[:1]):
        node.send_raw(SETPOINT | NODE, data)
        rig.tick(host_heartbeat=True)
        assert node.wait_for("TELEM_B")["XrCm"] == offset, data
    # HOST_HEARTBEAT of the wrong length: not a heartbeat, the timeout runs on
    node.host_heartbeat()
    for i in range(1, timeout):
        node.send_raw(HOST_HEARTBEAT | NODE, [b"", b"\0\0", bytes(8)][i % 3])
        assert rig.tick()["OutputActive"] == 1, i
    node.send_raw(HOST_HEARTBEAT | NODE, b"\0\0")
    act = rig.tick()
    assert act["OutputActive"] == 0 and act["DacCounts"] == 0
    hb = fresh_heartbeat(node)
    assert hb["FaultCode"] == FAULT["HOST_HEARTBEAT_LOST"]
    fw.stop()


def test_flood_of_bad_frames_node_still_answers(firmware, bus) -> None:
    """Hundreds of malformed frames back to back: the node drops or answers
    each and keeps answering (the RX path bounds the frames per loop; a request
    that finds the node's request queue full is dropped and counted,
    docs/protocol.md "Bad input")."""
    fw, node = start(firmware, bus, node=NODE)
    before = snapshot(node)
    answered = 0
    for i in range(300):
        node.send_raw(PARAM_REQ | NODE, param_raw(1, 0, PROTO.param("ppc.c").id, 1 + i % 255, f32_bits(9.0)))
        node.send_raw(SETPOINT | NODE, b"\x00")
        if i % 50 == 49:
            # the burst's replies, until the node is quiet; then it answers again
            deadline = time.monotonic() + 1.0
            while time.monotonic() < deadline:
                r = node.receive(0.2)
                if r is not None and r[0] == "PARAM_RESP":
                    assert r[2]["Result"] == RESULT["UNKNOWN_COMMAND"], r
                    answered += 1
                    deadline = time.monotonic() + 1.0
            sentinel_get(node)
    node.send_raw(PARAM_REQ | NODE, param_raw(9, 1, 4))       # GET_STATUS RX_DROPPED
    dropped = param_resp(node, 9, 4)["ValueU32"]
    assert answered + dropped == 300, (answered, dropped)
    assert node.get("ppc.c") == before["ppc.c"]
    assert query_state(node) == STATE["IDLE"]
    assert snapshot(node) == before
    fw.stop()
