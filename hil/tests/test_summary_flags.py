# SPDX-License-Identifier: Apache-2.0
"""The harness's copy of the application's CtrlFlags bits is the firmware's (controller.h), and
first_flag_time finds the first sample with a bit."""
from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from hil import summary

ROOT = Path(__file__).resolve().parents[2]
HEADER = ROOT / "firmware/app/controller.h"
PPC_HEADER = ROOT / "firmware/control/include/pma/ppc.h"


def test_flag_bits_are_the_firmwares():
    text = HEADER.read_text()
    found = {m.group(1): int(m.group(2), 16)
             for m in re.finditer(r"#define PMA_CTRL_FLAG_(\w+)\s+0x([0-9A-Fa-f]+)u", text)}
    assert found == {"GUARANTEE_LOST": summary.CTRL_FLAG_GUARANTEE_LOST,
                     "FALLBACK": summary.CTRL_FLAG_FALLBACK}


def test_the_laws_flags_are_the_laws():
    text = PPC_HEADER.read_text()
    for name, value in (("WIDE", summary.PPC_FLAG_WIDE), ("SAT_HIGH", summary.PPC_FLAG_SAT_HIGH),
                        ("SAT_LOW", summary.PPC_FLAG_SAT_LOW)):
        m = re.search(rf"#define PMA_PPC_FLAG_{name}\s+0x([0-9A-Fa-f]+)u", text)
        assert m is not None and int(m.group(1), 16) == value, name


def test_first_flag_time():
    telem = {"t_s": np.array([0.0, 0.01, 0.02, 0.03]),
             "ctrl_flags": np.array([0x01, 0x4001, 0xC000, 0x4000], dtype=float)}
    assert summary.first_flag_time(telem, summary.CTRL_FLAG_GUARANTEE_LOST) == 0.01
    assert summary.first_flag_time(telem, summary.CTRL_FLAG_FALLBACK) == 0.02
    assert summary.first_flag_time(telem, 0x0100) is None
    assert summary.first_flag_time({"t_s": np.array([])}, summary.CTRL_FLAG_FALLBACK) is None


def test_held_at_limit_before_the_loss():
    """The time the output had been at one limit at the first lost sample: from the last sample
    at another limit or none; 0 off the limits or where they alternate on that sample."""
    lost, hi, lo = summary.CTRL_FLAG_GUARANTEE_LOST, summary.PPC_FLAG_SAT_HIGH, summary.PPC_FLAG_SAT_LOW
    t = np.arange(6) * 0.01

    def held(*flags: int) -> float | None:
        return summary.held_at_limit_before({"t_s": t[:len(flags)], "ctrl_flags": np.array(flags, dtype=float)}, lost)
    assert held(0, lo, lo, lo, lost | lo, lost | lo) == pytest.approx(0.03)
    assert held(lo, lo, hi, hi, lost | hi) == pytest.approx(0.02)       # from the swing to the other one
    assert held(lo, lo, lo, 0x01, lost | lo) == pytest.approx(0.0)      # off the limit the sample before
    assert held(lo, lo, lost, lost) == 0.0                               # off the limits at the loss
    assert held(lo, lo, lo) is None                                      # never lost
    assert held(lost | hi | lo) == 0.0
