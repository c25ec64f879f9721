# SPDX-License-Identifier: Apache-2.0
"""The harness's copy of the application's CtrlFlags bits is the firmware's (controller.h), and
first_flag_time finds the first sample with a bit."""
from __future__ import annotations

import re
from pathlib import Path

import numpy as np

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


def test_wide_flag_is_the_laws():
    m = re.search(r"#define PMA_PPC_FLAG_WIDE\s+0x([0-9A-Fa-f]+)u", PPC_HEADER.read_text())
    assert m is not None and int(m.group(1), 16) == summary.PPC_FLAG_WIDE


def test_first_flag_time():
    telem = {"t_s": np.array([0.0, 0.01, 0.02, 0.03]),
             "ctrl_flags": np.array([0x01, 0x4001, 0xC000, 0x4000], dtype=float)}
    assert summary.first_flag_time(telem, summary.CTRL_FLAG_GUARANTEE_LOST) == 0.01
    assert summary.first_flag_time(telem, summary.CTRL_FLAG_FALLBACK) == 0.02
    assert summary.first_flag_time(telem, 0x0100) is None
    assert summary.first_flag_time({"t_s": np.array([])}, summary.CTRL_FLAG_FALLBACK) is None
