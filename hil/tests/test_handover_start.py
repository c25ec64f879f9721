# SPDX-License-Identifier: Apache-2.0
"""The hand-over to MFAC during the start, where the law cannot keep its funnel: Case 3's first
30 s on a `dmsp10` whose valve is flow-limited (fills at 537 and exhausts at 412 kPa/s) with
84-130 ms dead times, a 20 % softer spring and a 153 N pull (the rig R5 of
`tools/hil_matrix.py --matrix random --seed 6`), with t_u = 0.5 s instead of the case's 2 s,
shorter than the travel to the reference's start (commissioning warns of it; at 2 s the law
keeps its funnel there since the start's holding input is taken on the rising branch,
docs/commissioning.md). Lanes `ppc` with `ppc.fallback` 1 (MFAC at
the first lost tick, here during the start transient, the law's input at its limit) and `mfac`,
both commissioned on that rig, offline (the real firmware, libpma_offline.so).

MFAC takes over from the static map's holding input at that point of the reference and from
phi(1), as it starts on its own (docs/controllers.md, "When the guarantee is lost"): the node
keeps tracking, no fault, about as well as the MFAC lane that ran from the start. (From the
law's last input it hit the position limit: POSITION_LIMIT.)

    .venv/bin/python -m pytest -q hil/tests/test_handover_start.py
"""
from __future__ import annotations

from dataclasses import replace
from typing import Any

import pytest

from hil import offline
from hil import scenario as scn
from hil.commissioned import commission_offline

RIG = {   # the drawn rig's values over the dmsp10 profile (hil/rig_params.py paths)
    "muscle.stiffness_scale": 0.8041, "load.bias_force_n": -153.4,
    "valve.fill_rate_kpa_s": 537.4, "valve.exhaust_rate_kpa_s": 411.9,
    "valve.dead_time_rise_s": 0.08388, "valve.dead_time_fall_s": 0.1304,
    "sensor.noise_cm": 0.001695, "creep.frac_contract": 0.1955, "drift.temp_rate_k_per_s": 0.1711,
}
WINDOW = 0   # 5-30 s, the quick run's first window
T_U_S = 0.5   # the task's t_u: shorter than the travel to the reference's start allows

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def run() -> dict[str, Any]:
    assert offline.LIB_PATH.exists(), f"{offline.LIB_PATH} missing: {offline.BUILD_HINT}"
    sc = scn.load("realistic/dmsp10/case3")
    sc = offline.with_overrides(sc, [], [offline.Override(k, v, f"--rig {k}") for k, v in RIG.items()])
    sc = replace(sc, controllers=[replace(c, params={**c.params, "ppc.t_u_s": T_U_S})
                                  for c in sc.controllers if c.label in ("ppc", "mfac")])
    sc, result = commission_offline(sc)
    assert result is not None
    sc = replace(sc, controllers=[replace(c, params={**c.params, "ppc.fallback": 1}) if c.label == "ppc"
                                  else c for c in sc.controllers])
    (summary,) = offline.run_scenarios([sc], quick=True)
    assert not summary["errors"], summary["errors"]
    return {"summary": summary, "commissioning": result}


def test_the_task_is_beyond_the_rig_at_its_start(run):
    # the case this test is for: commissioning says t_u is short of the travel, and the law
    # loses its guarantee and hands over before t_u
    s = run["summary"]
    t_u = s["controllers"]["ppc"]["params_set"]["ppc.t_u_s"]
    assert run["commissioning"].derivation.figures["t_u_travel_s"] > t_u
    info = s["controllers"]["ppc"]
    assert info["fallback_at_s"] is not None and info["fallback_at_s"] < t_u


def test_the_node_keeps_tracking_after_the_hand_over(run):
    s = run["summary"]
    assert (s["state"]["ppc"], s["fault_code"]["ppc"]) == ("RUNNING", "NONE")
    assert s["constraint_violations"]["ppc"] == 0


def test_about_as_well_as_mfac_from_the_start(run):
    s = run["summary"]
    ppc, mfac = s["rmste"]["ppc"][WINDOW], s["rmste"]["mfac"][WINDOW]
    assert ppc <= 1.25 * mfac, (ppc, mfac)
    # and well inside the task's accuracy there, as the MFAC lane (the first window's RMSTE
    # against w1: after the 0.5 s t_u the start's transient is still there, in both lanes)
    w1 = s["controllers"]["ppc"]["params_set"]["ppc.w1_cm"]
    assert mfac < 0.25 * w1 and ppc < 0.25 * w1, (ppc, mfac)
