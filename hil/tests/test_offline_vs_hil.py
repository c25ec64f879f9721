# SPDX-License-Identifier: Apache-2.0
"""The offline runs are the real firmware: Case 3 (quick, 30 s, all four controllers) and the
wire-break fault, offline (libpma_offline.so, hil/offline.py) and in lockstep over vcan
(pma-fw-host, hil/runner.py), give the same figures to the last digit, and the same signals
tick for tick. This is what lets hil/tests/test_acceptance.py assert the paper's experiments
on offline runs.

    hil/with-vcan .venv/bin/python -m pytest -q hil/tests/test_offline_vs_hil.py

With PMA_OFFLINE_COMPARE_RUN=DIR it takes the over-CAN side from a lockstep run already made
of Case 3 quick (DIR/summary.json and DIR/signals.npz; the CI passes the README main job's
quick run, `tools/run-demo.sh --quick`, its lanes ppc and mfac) and runs only the offline side,
on the same lanes; the wire break still runs over vcan (skipped without it).

Both run the same application code, compiled by the same compiler with the same flags (-O2;
the library is position-independent, which changes no arithmetic), fed the same frames in the
same order: the parameters, ARM, START, a HOST_HEARTBEAT every 100 ms of control time, one
PLANT_SENSOR per tick. The lanes commissioned over CAN (hil run --commission) run offline on the
set that commissioning derived; the run itself starts on a fresh rig in both. What differs and
cannot change a figure: the transport (vcan and
SocketCAN vs the fake CAN controller), the clock (the heartbeat follows the wall clock on the
host, control time offline; no control rule reads it in lockstep) and the storage (a file vs
none: SAVE is never sent).
"""
from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from hil import offline
from hil import scenario as scn
from hil.commissioned import with_derivation
from hil.fw_process import BUILD_HINT, FW_HOST
from hil.runner import Runner, RunOptions
from hil.summary import jsonable

GIVEN_RUN = os.environ.get("PMA_OFFLINE_COMPARE_RUN")
HAVE_VCAN = Path("/sys/class/net/vcan0").exists()
pytestmark = [pytest.mark.vcan, pytest.mark.skipif(not GIVEN_RUN and not HAVE_VCAN,
                                reason="needs vcan0 (run under hil/with-vcan) or "
                                       "PMA_OFFLINE_COMPARE_RUN")]

# Case 3 quick: the paper's experiment, every controller (or the given run's lanes); the wire
# break: a fault, the safe state and the run's last ticks (run over vcan here, 5 s)
SCENARIOS = ["case3", "wire_break"]
# run-specific, not figures of the controllers: where, how fast and on which build it ran (the node
# does not report its controller slot's arithmetic over CAN; the offline library does)
NOT_COMPARED = {"benchmark", "wall_s", "bus_log", "bus_dbc", "offline", "ctrl_arith", "errors", "identity",
                "commissioning"}


@pytest.fixture(scope="module", params=SCENARIOS)
def both(request: pytest.FixtureRequest,
         tmp_path_factory: pytest.TempPathFactory) -> tuple[dict[str, Any], dict[str, Any], Path, Path]:
    assert offline.LIB_PATH.exists(), f"{offline.LIB_PATH} missing: {offline.BUILD_HINT}"
    name = request.param
    off_out = tmp_path_factory.mktemp(f"offline-{name}")
    sc = scn.load(name)
    quick = name == "case3"
    if GIVEN_RUN and name == "case3":
        hil_out = Path(GIVEN_RUN)
        over_can = json.loads((hil_out / "summary.json").read_text())
        assert over_can["quick"] is True and over_can["scenario"] == sc.name, \
            f"{hil_out} is not a quick run of {name}"
        sc.controllers = [c for c in sc.controllers if c.label in over_can["controllers"]]
    else:
        if not HAVE_VCAN:
            pytest.skip(f"{name} over CAN needs vcan0 (run under hil/with-vcan)")
        assert FW_HOST.exists(), f"{FW_HOST} missing: {BUILD_HINT}"
        hil_out = tmp_path_factory.mktemp(f"hil-{name}")
        over_can = Runner(sc, RunOptions(out=hil_out, quick=quick, progress=False,
                                         commission=bool(sc.needs_commissioning()))).run()
    assert not over_can["errors"], over_can["errors"]
    # the commissioned lanes offline on the set their commissioning over CAN derived (the run
    # itself starts on a fresh rig, as offline)
    derived = over_can.get("commissioning", {})
    sc.controllers = [with_derivation(c, derived[c.label]["derivation"]["params"]) if c.commission else c
                      for c in sc.controllers]
    off = offline.run_scenarios([sc], quick=quick, jobs=1, out=off_out)[0]
    assert not off["errors"], off["errors"]
    return over_can, off, hil_out, off_out


def test_every_figure_is_the_same_to_the_last_digit(both):
    over_can, off, _, _ = both
    if over_can["scenario"] == "case3":
        expected = {"ppc", "mfac"} if GIVEN_RUN else {"ppc", "ppc-paper", "mfac", "pid"}
        assert set(over_can["controllers"]) == expected
    for key in set(over_can) | set(off):
        if key in NOT_COMPARED:
            continue
        assert jsonable(off.get(key)) == jsonable(over_can.get(key)), key   # NaN as None
    for label, c in over_can["controllers"].items():
        print(over_can["scenario"], label, "RMSTE", c["rmste_cm"], "chatter", c["chatter_ratio"],
              "state", over_can["state"][label], over_can["fault_code"][label])


def test_every_signal_is_the_same_tick_for_tick(both):
    _, _, hil_out, off_out = both
    a, b = np.load(hil_out / "signals.npz"), np.load(off_out / "signals.npz")
    assert set(a.files) == set(b.files)
    for name in a.files:
        assert a[name].shape == b[name].shape, name
        assert np.array_equal(a[name], b[name], equal_nan=True), name
