# SPDX-License-Identifier: Apache-2.0
"""What a client written from the docs alone relies on, checked on the
wire (raw frames, so that no client library hides a difference).

PARAM_RESP's Type (docs/protocol.md, signal table of PARAM_RESP): SAVE, LOAD and
RESTORE_DEFAULTS echo the request's Type, a LENGTH reply takes it from byte 0, and a
reply for an unknown id echoes it, also for the undefined Types 3..15 (the value
bytes are then 0). SET checks the id before the Type (UNKNOWN_ID before TYPE)."""
from __future__ import annotations

import can
from test_fw_lib import STATE, base_id, drain, param_raw, query_state, start

NODE = 3
PARAM_REQ = base_id("PARAM_REQ") | NODE
PARAM_RESP = base_id("PARAM_RESP") | NODE


def raw_reply(bus: can.BusABC, data: bytes, timeout_s: float = 3.0) -> bytes:
    """Sends one PARAM_REQ and returns the data of the node's PARAM_RESP."""
    drain(bus)
    bus.send(can.Message(arbitration_id=PARAM_REQ, data=data, is_extended_id=False))
    while True:
        m = bus.recv(timeout_s)
        assert m is not None, f"no PARAM_RESP to {data.hex()}"
        if m.arbitration_id == PARAM_RESP and not m.is_extended_id:
            return bytes(m.data)


def test_param_resp_type_is_echoed_as_documented(firmware, bus) -> None:
    fw, node = start(firmware, bus, node=NODE)
    assert query_state(node) == STATE["IDLE"]
    # the frames: SAVE with Type 3, a 1-byte request with Type 3, GET of id 999 with Type 5
    assert raw_reply(bus, bytes.fromhex("3200000000000000")) == bytes.fromhex("3200000000000000")
    assert raw_reply(bus, bytes.fromhex("31")) == bytes.fromhex("310000EA00000000")
    assert raw_reply(bus, bytes.fromhex("50E7030000000000")) == bytes.fromhex("50E703EE00000000")
    # every whole-set Op echoes every Type; LOAD after the SAVE above finds the record
    for t in (0, 1, 2, 3, 9, 15):
        for op in (2, 8, 3):
            r = raw_reply(bus, param_raw(op, t, 0))
            assert r[0] == (t << 4 | op) and r[3] == 0 and r[4:] == bytes(4), (op, t, r.hex())
    # LENGTH: Op and Type from byte 0, whatever the Type
    for t in range(16):
        r = raw_reply(bus, bytes([t << 4 | 1, 0x05]))
        assert r == bytes([t << 4 | 1, 0, 0, 0xEA, 0, 0, 0, 0]), (t, r.hex())
    # unknown id, every read Op and every Type: UNKNOWN_ID with the request's Type
    for t in range(16):
        for op in (0, 4, 5, 6):
            r = raw_reply(bus, param_raw(op, t, 999))
            assert r == bytes([t << 4 | op, 0xE7, 0x03, 0xEE, 0, 0, 0, 0]), (op, t, r.hex())


def test_set_checks_the_id_before_the_type(firmware, bus) -> None:
    fw, node = start(firmware, bus, node=NODE)
    # the frame: SET Type 5 of id 0 (no such parameter): UNKNOWN_ID, not TYPE
    assert raw_reply(bus, bytes.fromhex("5100000001000000")) == bytes.fromhex("510000EE00000000")
    for t in range(16):
        for pid in (0, 6, 999, 0xFFFF):
            r = raw_reply(bus, param_raw(1, t, pid, 0, b"\x01\x00\x00\x00"))
            assert r[3] == 0xEE and r[0] == (t << 4 | 1), (t, pid, r.hex())
    # a known id with Type 3..15 is still TYPE, with the parameter's Type and value
    telem_mask = 5
    for t in range(3, 16):
        r = raw_reply(bus, param_raw(1, t, telem_mask, 0, b"\x03\x00\x00\x00"))
        assert r == bytes([0x11, telem_mask, 0, 0xED, 31, 0, 0, 0]), (t, r.hex())
    assert node.get("telem.mask") == 31


# ------------------------------------------------ rules between parameters --

PARAM_ID = {p.name: p.id for p in __import__("test_fw_lib").PROTO.params}
GET_STATUS = 9
STATUS_LAST_RULE = 1


def last_rule(bus: can.BusABC) -> int:
    r = raw_reply(bus, param_raw(GET_STATUS, 1, STATUS_LAST_RULE))
    assert r[0] == (1 << 4 | GET_STATUS) and r[3] == 0, r.hex()
    return int.from_bytes(r[4:], "little")


def set_u32(bus: can.BusABC, name: str, v: int) -> bytes:
    return raw_reply(bus, param_raw(1, 1, PARAM_ID[name], 0, v.to_bytes(4, "little")))


def test_rule_wire_break_needs_the_documented_order(firmware, bus) -> None:
    """docs/parameters.md rule 3: lowering adc.raw_min_counts below the wire-break level
    is refused with RANGE (LAST_RULE 3) until the wire-break level is lowered first."""
    fw, node = start(firmware, bus, node=NODE)
    assert last_rule(bus) == 0
    # the frame: raw_min = 700 (0x2BC) while the wire-break level is 737
    r = raw_reply(bus, bytes.fromhex("11820000BC020000"))
    assert r[3] == 0xFD and int.from_bytes(r[4:], "little") == 778, r.hex()   # RANGE, the value stays
    assert last_rule(bus) == 3
    # the documented order: the wire-break level first, then raw_min
    assert set_u32(bus, "adc.wire_break_below_counts", 600)[3] == 0
    assert set_u32(bus, "adc.raw_min_counts", 700)[3] == 0
    # rule 2: raw_min above raw_max
    r = set_u32(bus, "adc.raw_min_counts", 4095)
    assert r[3] == 0xFD and last_rule(bus) == 2
    assert node.get("adc.raw_min_counts") == 700


def test_defaults_keep_u_inside_the_pressure_range(firmware, bus, proto) -> None:
    """docs/tuning.md: ctrl.u_min = p_min - p0, ctrl.u_max = p_max - p0 (rule 12); the
    defaults agree, and ARM refuses a set whose u range commands pressures the actuator
    limits cut (RANGE, LAST_RULE 12), nothing changes."""
    from test_fw_lib import Rig, default_of
    d = {n: default_of(n) for n in ("ctrl.u_min", "ctrl.u_max", "act.p0_kpa", "act.p_min_kpa",
                                      "act.p_max_kpa", "act.kpa_per_u", "act.polarity")}
    assert d["act.polarity"] == 1 and d["act.kpa_per_u"] == 1
    assert d["ctrl.u_min"] == d["act.p_min_kpa"] - d["act.p0_kpa"]
    assert d["ctrl.u_max"] == d["act.p_max_kpa"] - d["act.p0_kpa"]
    fw, node = start(firmware, bus, node=NODE)
    rig = Rig(node)
    rig.tick()
    for name, v in d.items():
        assert node.get(name) == v, name
    for name, v in (("ctrl.u_min", -400.0), ("ctrl.u_max", 400.0)):
        node.set(name, v)
        rig.tick()
        ack = node.command("ARM", check=False)
        assert proto.status_name(ack.result) == "RANGE" and ack.state == STATE["IDLE"], ack
        assert last_rule(bus) == 12
        node.set(name, d[name])
    # the same with polarity -1 and p0 100: the harness's rig set (u = -800..100 on 0..900 kPa)
    node.set("act.polarity", -1)
    node.set("act.p0_kpa", 100.0)
    node.set("act.p_max_kpa", 900.0)
    node.set("ctrl.u_min", -800.0)
    node.set("ctrl.u_max", 100.0)
    rig.tick()
    assert node.command("ARM", check=False).result == 0


# ------------------------------------- behaviour docs/firmware.md now states --

def test_storage_file_must_be_8192_bytes(tmp_path, firmware, bus) -> None:
    """docs/firmware.md --storage: created with 8,192 bytes; an existing file of another
    size (an empty one made by touch) is refused with exit status 1 and left alone."""
    import subprocess

    from conftest import CHANNEL, FW_HOST
    empty = tmp_path / "node.nvm"
    empty.touch()
    r = subprocess.run([str(FW_HOST), "--can", CHANNEL, "--storage", str(empty)],
                       capture_output=True, text=True, timeout=20)
    assert r.returncode == 1 and "0 bytes" in r.stderr and "8192" in r.stderr, r
    assert empty.read_bytes() == b""
    made = tmp_path / "made.nvm"
    fw, node = start(firmware, bus, node=NODE, storage=made)
    assert made.stat().st_size == 8192
    fw.stop()


def test_node_option_does_not_change_the_parameter(firmware, bus) -> None:
    """docs/firmware.md --node: the node answers on the given id while GET sys.node_id
    returns the stored (here the default) value."""
    from test_fw_lib import default_of
    fw, node = start(firmware, bus, node=NODE)
    assert node.get("sys.node_id") == default_of("sys.node_id") != NODE


def test_non_zero_arg_is_accepted_and_echoed(firmware, bus) -> None:
    """docs/protocol.md COMMAND Arg: commands other than SELECT_* ignore Arg; a non-zero
    one is carried out and echoed."""
    from test_fw_lib import Rig
    fw, node = start(firmware, bus, node=NODE)
    rig = Rig(node)
    rig.tick()
    for cmd, arg, state in (("ARM", 7, "ARMED"), ("STOP", 200, "ARMED"), ("DISARM", 1, "IDLE"),
                            ("ESTOP", 0, "FAULT"), ("CLEAR_FAULTS", 255, "IDLE")):
        ack = node.command(cmd, arg, check=False)
        assert (ack.arg, ack.result, ack.state) == (arg, 0, STATE[state]), (cmd, ack)
        rig.tick()


def test_status_values_are_readable(firmware, bus) -> None:
    """docs/protocol.md "Status values": every Id 1..10 answers U32 with Result 0 (any request
    Type); another Id UNKNOWN_ID; FRAMES_BAD counts a frame of the wrong length; before any
    START the guarantee monitor's values say "held" (0 lost ticks, time 0xFFFFFFFF)."""
    fw, node = start(firmware, bus, node=NODE)
    for sid in range(1, 11):
        for t in (0, 1, 2, 7):
            r = raw_reply(bus, param_raw(GET_STATUS, t, sid))
            assert r[0] == (1 << 4 | GET_STATUS) and r[3] == 0, (sid, t, r.hex())
    for sid in (0, 11, 999):
        assert raw_reply(bus, param_raw(GET_STATUS, 1, sid))[3] == 0xEE
    assert int.from_bytes(raw_reply(bus, param_raw(GET_STATUS, 1, 8))[4:], "little") == 0
    assert int.from_bytes(raw_reply(bus, param_raw(GET_STATUS, 1, 9))[4:], "little") == 0xFFFFFFFF
    assert int.from_bytes(raw_reply(bus, param_raw(GET_STATUS, 1, 10))[4:], "little") == 0
    bad = int.from_bytes(raw_reply(bus, param_raw(GET_STATUS, 1, 5))[4:], "little")
    raw_reply(bus, bytes([0x00, 0x05]))                    # a 2-byte PARAM_REQ: LENGTH
    assert int.from_bytes(raw_reply(bus, param_raw(GET_STATUS, 1, 5))[4:], "little") == bad + 1
    assert int.from_bytes(raw_reply(bus, param_raw(GET_STATUS, 1, 2))[4:], "little") == 0   # RX_OVERRUNS
