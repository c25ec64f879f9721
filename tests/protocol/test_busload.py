# SPDX-License-Identifier: Apache-2.0
"""tools/busload.py: the worst-case frame length, the load figures, and the
table in docs/protocol.md being its current output. No CAN needed."""
from __future__ import annotations

import random
import subprocess
import sys
from pathlib import Path

import pytest

from pma_tools import busload
from pma_tools.protocol_doc import DOC, read_doc, section

ROOT = Path(__file__).resolve().parents[2]
BUSLOAD = ROOT / "tools/busload.py"
BEGIN, END = "<!-- busload:begin -->", "<!-- busload:end -->"


# ------------------------------------------------------------ bit formula --

def test_frame_bits_by_hand() -> None:
    # 8 bytes: 47 + 64 + floor((34 + 64 - 1) / 4) = 111 + floor(97 / 4) = 111 + 24
    assert busload.frame_bits(8) == 135
    # 0 bytes: 47 + floor(33 / 4) = 47 + 8
    assert busload.frame_bits(0) == 55
    # 3 bytes (PLANT_SENSOR): 47 + 24 + floor(57 / 4) = 71 + 14
    assert busload.frame_bits(3) == 85
    # 4 bytes (PLANT_ACTUATOR): 47 + 32 + floor(65 / 4) = 79 + 16
    assert busload.frame_bits(4) == 95
    # 1 byte (HOST_HEARTBEAT): 47 + 8 + floor(41 / 4) = 55 + 10
    assert busload.frame_bits(1) == 65


@pytest.mark.parametrize("n", [-1, 9])
def test_frame_bits_rejects_impossible_lengths(n: int) -> None:
    with pytest.raises(ValueError):
        busload.frame_bits(n)


def _crc15(bits: list[int]) -> list[int]:
    """CAN CRC-15 (polynomial 0x4599) of a bit sequence, 15 bits MSB first."""
    crc = 0
    for b in bits:
        nxt = b ^ ((crc >> 14) & 1)
        crc = (crc << 1) & 0x7FFF
        if nxt:
            crc ^= 0x4599
    return [(crc >> (14 - i)) & 1 for i in range(15)]


def _stuffed_length(can_id: int, data: bytes) -> int:
    """Exact length of a real data frame: SOF..CRC stuffed, then 13 fixed bits."""
    bits = [0]                                                # SOF (dominant)
    bits += [(can_id >> (10 - i)) & 1 for i in range(11)]     # identifier
    bits += [0, 0, 0]                                         # RTR, IDE, r0
    bits += [(len(data) >> (3 - i)) & 1 for i in range(4)]    # DLC
    for byte in data:
        bits += [(byte >> (7 - i)) & 1 for i in range(8)]
    bits += _crc15(bits)
    assert len(bits) == 34 + 8 * len(data)
    stuffed, run, last = 0, 0, None
    for b in bits:
        run = run + 1 if b == last else 1
        last = b
        if run == 5:            # a stuff bit of the opposite level, which starts a new run
            stuffed += 1
            last, run = 1 - b, 1
    return len(bits) + stuffed + 13


def test_frame_bits_bounds_real_frames() -> None:
    """The formula bounds every real frame's length from above, and is not far
    off: frames built from runs of equal bits come within half of its stuff bits."""
    rng = random.Random(20240601)
    runs = [0x00, 0xFF, 0x0F, 0xF0, 0x87, 0x78, 0xC3, 0x3C, 0xE1, 0x1E]
    worst_seen = {n: 0 for n in range(9)}
    cases = [(rng.randrange(0x800), bytes(rng.randrange(256) for _ in range(rng.randrange(9))))
             for _ in range(2000)]
    cases += [(rng.randrange(0x800), bytes(rng.choice(runs) for _ in range(n)))
              for n in range(9) for _ in range(500)]
    for can_id, data in cases:
        real = _stuffed_length(can_id, data)
        n = len(data)
        assert 47 + 8 * n <= real <= busload.frame_bits(n), (hex(can_id), data.hex())
        worst_seen[n] = max(worst_seen[n], real)
    for n, seen in worst_seen.items():
        max_stuff = busload.frame_bits(n) - (47 + 8 * n)
        assert seen - (47 + 8 * n) >= max_stuff // 2, (n, seen)


# ---------------------------------------------------------------- figures --

def test_default_load_figures() -> None:
    r = busload.compute()
    assert r.bitrate == 1_000_000
    by_name = {row.message: row for row in r.rows}
    # one PLANT_SENSOR (3 bytes) and one PLANT_ACTUATOR (4 bytes) per 1 kHz tick
    assert by_name["PLANT_SENSOR"].bps == 85 * 1000
    assert by_name["PLANT_ACTUATOR"].bps == 95 * 1000
    # five 8-byte telemetry frames every 10 ticks: 100 Hz each
    assert [n for n in by_name if n.startswith("TELEM_")] == list(busload.TELEM_MESSAGES)
    assert all(by_name[n].per_s == 100 and by_name[n].bits == 135 for n in busload.TELEM_MESSAGES)
    assert by_name["HEARTBEAT"].bps == 135 * 10
    assert by_name["HOST_HEARTBEAT"].bps == 65 * 10
    assert r.bps("bridge") == 85_000 + 95_000 + 5 * 13_500 + 1_350 + 650 == 249_500
    assert r.bps("board") == 249_500 - 180_000
    assert r.nodes("bridge") == 2 and r.nodes("board") == 7


def test_mask_and_decimation_overrides() -> None:
    r = busload.compute(overrides={"telem.mask": 0b00101, "telem.decimation": 0})
    assert [x.message for x in r.rows if x.message.startswith("TELEM_")] == ["TELEM_A", "TELEM_C"]
    assert all(x.per_s == 0 for x in r.rows if x.message.startswith("TELEM_"))
    with pytest.raises(ValueError):
        busload.compute(overrides={"ppc.c": 1})


def test_exit_status() -> None:
    ok = subprocess.run([sys.executable, str(BUSLOAD)], capture_output=True, text=True, timeout=60)
    assert ok.returncode == 0, ok.stderr
    assert "24.95 %" in ok.stdout
    over = subprocess.run([sys.executable, str(BUSLOAD), "--bitrate", "250000"],
                          capture_output=True, text=True, timeout=60)
    assert over.returncode == 1 and "more than 50 %" in over.stderr


def test_doc_table_is_current() -> None:
    """docs/protocol.md holds busload.py --markdown between its markers."""
    text = read_doc()
    assert text.count(BEGIN) == 1 and text.count(END) == 1, f"{DOC.name}: busload markers"
    want = busload.markdown(busload.compute())
    got = section(text, BEGIN, END)
    assert got == want, (f"{DOC.relative_to(ROOT)}: the bus-load table is out of date; replace the "
                         f"lines between the markers with the output of tools/busload.py --markdown")
