"""Issue 16: what a client written from the docs alone relies on, checked on the
wire (raw frames, so that no client library hides a difference).

PARAM_RESP's Type (docs/protocol.md, signal table of PARAM_RESP): SAVE, LOAD and
RESTORE_DEFAULTS echo the request's Type, a LENGTH reply takes it from byte 0, and a
reply for an unknown id echoes it, also for the undefined Types 3..15 (the value
bytes are then 0). SET checks the id before the Type (UNKNOWN_ID before TYPE)."""
from __future__ import annotations

import can

from test_fw_lib import RESULT, STATE, base_id, drain, param_raw, query_state, start

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
