# SPDX-License-Identifier: Apache-2.0
"""pmactl.frame_layout against cantools on the project's DBC: the same raw values from every
message it compiles, for random frames and the edges of each signal; the same bytes encoded;
errors for short frames and values beyond a signal's bits; None where cantools is needed."""
from __future__ import annotations

import math
import random

import cantools.database
import pytest

from pmactl.frame_layout import FrameLayout
from pmactl.protocol import load_protocol

PROTO = load_protocol()
COMPILED = sorted(n for n, lay in PROTO.layouts.items() if lay is not None)


def cantools_decode(name: str, data: bytes) -> dict:
    out = PROTO.messages[name].decode(data, decode_choices=False, scaling=False)
    assert isinstance(out, dict)
    return dict(out)


def same(a: dict, b: dict) -> bool:
    if a.keys() != b.keys():
        return False
    return all(x == y or (isinstance(x, float) and math.isnan(x) and math.isnan(y)) for x, y in
               ((a[k], b[k]) for k in a))


def test_the_loop_s_messages_are_compiled_and_the_multiplexed_ones_are_not():
    for name in ("PLANT_SENSOR", "PLANT_ACTUATOR", "HEARTBEAT", "TELEM_A", "TELEM_B", "TELEM_C",
                 "TELEM_D", "TELEM_E", "COMMAND_ACK"):
        assert name in COMPILED
    for name in ("PARAM_REQ", "PARAM_RESP", "DEVICE_INFO"):   # multiplexed: cantools
        assert PROTO.layouts[name] is None


@pytest.mark.parametrize("name", COMPILED)
def test_decode_equals_cantools(name):
    rng = random.Random(name)
    n = PROTO.messages[name].length
    frames = [bytes(n), b"\xff" * n] + [bytes(rng.getrandbits(8) for _ in range(n)) for _ in range(300)]
    layout = PROTO.layouts[name]
    assert layout is not None
    for data in frames:
        assert same(layout.decode(data), cantools_decode(name, data)), data.hex()
        assert same(layout.decode(data + b"\x00"), cantools_decode(name, data + b"\x00"))   # excess ignored


@pytest.mark.parametrize("name", COMPILED)
def test_encode_equals_cantools(name):
    rng = random.Random(name + "e")
    m = PROTO.messages[name]
    layout = PROTO.layouts[name]
    assert layout is not None
    for _ in range(200):
        values = cantools_decode(name, bytes(rng.getrandbits(8) for _ in range(m.length)))
        if any(isinstance(v, float) and not math.isfinite(v) for v in values.values()):
            continue
        want = bytes(m.encode(values, scaling=False, strict=False))
        assert layout.encode(values) == want


def test_errors():
    sensor = PROTO.layouts["PLANT_SENSOR"]
    assert sensor is not None
    with pytest.raises(cantools.database.DecodeError):
        sensor.decode(b"\x01\x02")              # 2 of 3 bytes
    with pytest.raises(ValueError):
        sensor.encode({"Seq": 256, "RawCounts": 0})
    with pytest.raises(ValueError):
        sensor.encode({"Seq": 1, "RawCounts": -1})
    with pytest.raises(ValueError):
        sensor.encode({"Seq": 1.5, "RawCounts": 0})
    with pytest.raises(KeyError):
        sensor.encode({"Seq": 1})
    assert PROTO.encode_raw("PLANT_SENSOR", {"Seq": 7, "RawCounts": 0x1234}) == \
        PROTO.encode("PLANT_SENSOR", {"Seq": 7, "RawCounts": 0x1234})


def test_a_big_endian_signal_keeps_cantools():
    db = cantools.database.load_string(
        'VERSION ""\nBU_: N\nBO_ 16 M: 2 N\n SG_ S : 7|16@0+ (1,0) [0|65535] "" N\n', "dbc")
    assert FrameLayout.of(db.messages[0]) is None
