# SPDX-License-Identifier: Apache-2.0
"""The Q16.16 build over vcan: pma-fw-host of the preset host-q16 (the controller slot in
Q16.16, docs/fixed-point.md) runs the paper's Case 3, quick variant, commissioned, in the HIL
harness, and keeps the paper's guarantee as the float build does; its RMSTE is within a factor
of two of the float build's quick run of the same scenario (the README main job's, when
PMA_FLOAT_QUICK_RUN names its output), and its commissioning derived a set that fits Q16.16.

    hil/with-vcan .venv/bin/python -m pytest -q hil/tests/test_hil_fixed_point.py

Assertions are on the simulated results, never on timing.
"""
from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
FW_Q16 = REPO / "build/host-q16/firmware/targets/host/pma-fw-host"
W1_CM = 0.2      # the scenario's accuracy

pytestmark = [pytest.mark.vcan, pytest.mark.skipif(not Path("/sys/class/net/vcan0").exists(),
                                reason="needs vcan0: run under hil/with-vcan")]


def test_case3_on_the_q16_build_keeps_the_guarantee(tmp_path: Path) -> None:
    assert FW_Q16.exists(), f"{FW_Q16} missing: cmake --preset host-q16 && cmake --build --preset host-q16"
    out = tmp_path / "case3-q16"
    env = dict(os.environ, PMA_FW_HOST=str(FW_Q16))
    r = subprocess.run([sys.executable, "-m", "hil", "run", "case3", "--quick", "--commission",
                        "--controller", "ppc", "--no-progress", "--no-figures", "--out", str(out)],
                       cwd=REPO, env=env, capture_output=True, text=True, timeout=1800, check=False)
    assert r.returncode == 0, r.stdout[-4000:] + r.stderr[-4000:]
    s = json.loads((out / "summary.json").read_text())
    assert s["state"]["ppc"] == "RUNNING" and s["fault_code"]["ppc"] == "NONE", (s["state"], s["fault_code"])
    assert s["max_abs_error_after_tu"]["ppc"] < W1_CM
    assert s["barrier_breaches"]["ppc"] == 0
    rmste = [v for v in s["rmste"]["ppc"] if v is not None]
    assert rmste and all(v < W1_CM for v in rmste)
    print(f"Q16.16 build, Case 3 quick, ppc: RMSTE {rmste} cm, max |e| after t_u "
          f"{s['max_abs_error_after_tu']['ppc']:.4f} cm")
    float_run = os.environ.get("PMA_FLOAT_QUICK_RUN")
    if float_run:
        f = json.loads((Path(float_run) / "summary.json").read_text())
        ref = [v for v in f["rmste"]["ppc"] if v is not None]
        print(f"float build, same scenario: RMSTE {ref} cm")
        assert len(ref) == len(rmste)
        for q, fl in zip(rmste, ref):
            assert 0.5 * fl <= q <= 2.0 * fl, (rmste, ref)
