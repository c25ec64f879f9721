# SPDX-License-Identifier: Apache-2.0
"""Acceptance of the firmware against the paper's experiments: every scenario runs the real
firmware (the application, its control library and the fake HAL port built as
libpma_offline.so, hil/offline.py) against the simulated rig, stepped tick by tick exactly as
the HIL runner steps pma-fw-host in lockstep over vcan, and the tests assert on the simulated
results (never on timing).

    .venv/bin/python -m pytest -q hil/tests/test_acceptance.py

The runs need no CAN: the same lockstep runs over vcan give the same figures to the last digit
and the same signals tick for tick (hil/tests/test_offline_vs_hil.py, run in CI on the README
main job's quick run and on a fault scenario), and what only the CAN path has (the bus log,
the nodes' identity, a clean stop, --board) is tested over vcan in
hil/tests/test_hil_acceptance.py.

Every claim is asserted on three rigs (PROFILES): the realistic `dmsp10` profile, the default,
the realistic `mas10-itv2050` profile and the idealised rig. Each scenario runs once per session
and rig, full length, its lanes in
two worker processes. Case 3's PID lane (a comparison, no claim of the paper's; its gains are
the idealised rig's) runs on the quick Case 3 (30 s) of the idealised rig.
"""
from __future__ import annotations

import functools
from typing import Any

import numpy as np
import pytest

from hil import acceptance, offline
from hil import scenario as scn
from hil.commissioned import commission_offline

JOBS = 2            # worker processes per scenario (the machines have 2 cores)
# The rigs every claim is asserted on: the realistic profile fitted to a measured DMSP-10-250
# (creep, its slow flow-limited valve, smooth hysteresis: docs/rig.md) first, the default; the
# paper's MAS-10 with the ITV2050 of its datasheet (creep, a flow-limited regulator, smooth
# hysteresis); and the idealised rig (the nominal profile) of the paper scenarios as they are.
PROFILES = ("dmsp10", "mas10-itv2050", "nominal")

pytestmark = pytest.mark.slow


@pytest.fixture(scope="session")
def _run(tmp_path_factory: pytest.TempPathFactory) -> Any:
    assert offline.LIB_PATH.exists(), f"{offline.LIB_PATH} missing: {offline.BUILD_HINT}"
    cache: dict[tuple[str, str], tuple[dict[str, Any], Any]] = {}

    def run(profile: str, name: str) -> tuple[dict[str, Any], Any]:
        """name: a scenario, or "case3-pid" (Case 3's PID lane alone, quick), on the rig profile."""
        if (profile, name) not in cache:
            out = tmp_path_factory.mktemp(f"{profile}-{name}")
            quick = name == "case3-pid"
            base = "case3" if quick else name
            sc = scn.load(base if profile == "nominal" else f"realistic/{profile}/{base}")
            if sc.name == "case3":
                sc.controllers = [c for c in sc.controllers if (c.label == "pid") == quick]
            sc, _ = commission_offline(sc)     # the ppc and mfac lanes: commissioned on the rig
            summary = offline.run_scenarios([sc], quick=quick, jobs=JOBS, out=out)[0]
            assert not summary["errors"], summary["errors"]
            cache[(profile, name)] = (summary, out)
        return cache[(profile, name)]
    return run


@pytest.fixture(scope="session", params=PROFILES)
def runs(request: pytest.FixtureRequest, _run: Any) -> Any:
    """The scenario runner on each rig profile of PROFILES in turn: every test that takes it
    asserts the same on the realistic profile and on the idealised rig."""
    return functools.partial(_run, request.param)


@pytest.fixture(scope="session")
def nominal_runs(_run: Any) -> Any:
    return functools.partial(_run, "nominal")


# ------------------------------------------------------ the paper's controller --
@pytest.mark.parametrize("case", ["case1", "case2a", "case2b", "case3"])
def test_paper_controller_meets_its_guarantees(runs, case):
    s, _ = runs(case)
    c = s["controllers"]["ppc"]
    assert s["state"]["ppc"] == "RUNNING" and s["fault_code"]["ppc"] == "NONE"
    assert c["samples_outside_w1_after_tu"] == 0, f"|e| >= w1 after t_u: max {c['max_abs_error_after_tu_cm']}"
    assert c["max_abs_error_after_tu_cm"] < c["w1_cm"]
    assert c["constraint_violations"] == 0 and c["constraint_violations_true_x"] == 0
    assert -3.0 < c["x_min_cm"] and c["x_max_cm"] < 0.0
    # the harness's reference is the firmware's (TELEM_B), sample for sample
    assert c["reference_check_max_abs_cm"] < 1e-4


@pytest.mark.parametrize("case", ["case1", "case2a", "case2b", "case3"])
def test_paper_controller_has_no_barrier_breach_after_tu(runs, case):
    """With the commissioned set lambda2 never meets its barrier after t_u, and the supervisor's
    BARRIER fault (safety.barrier_ticks, left at its default) is on for this node."""
    s, _ = runs(case)
    c = s["controllers"]["ppc"]
    assert "safety.barrier_ticks" not in c["params_set"]
    assert c["barrier_breaches_after_tu"] == 0


@pytest.mark.parametrize("case", ["case1", "case2a", "case2b", "case3"])
def test_paper_controller_does_not_chatter(runs, case):
    assert not acceptance.chatter_failures(runs(case)[0], case)


@pytest.mark.parametrize("case", ["case1", "case2a", "case2b", "case3"])
def test_the_paper_law_exactly_is_reported(runs, case):
    """The paper's law with the options off runs beside it, and its figures are in the summary:
    RMSTE per window, barrier breaches and the chattering of u."""
    s, _ = runs(case)
    c = s["controllers"]["ppc-paper"]
    p = c["params_set"]
    assert p.get("ppc.ff_gain_per_s", 0.0) == 0.0 and p.get("ppc.soft_barrier_r", 1.0) == 1.0
    assert len(s["rmste"]["ppc-paper"]) == len(s["windows"])
    assert c["barrier_breaches"] is not None and c["tv_u_per_s"] is not None
    assert c["tv_pressure_cmd_kpa_per_s"] > 0.0


def test_case3_paper_controller_beats_mfac_once_the_chirp_speeds_up(runs):
    """Windows 60-180 s, by a wide margin (at least 2x), with the guarantee held; and MFAC's
    error growing with the chirp (hil/acceptance.py)."""
    s, _ = runs("case3")
    assert len(s["rmste"]["ppc"]) == 6 and s["windows"][2][0] == acceptance.CASE3_FROM_S
    assert s["controllers"]["ppc"]["guarantee_lost_at_s"] is None
    assert not acceptance.case3_failures(s)
    assert all(measurable for *_, measurable in acceptance.case3_factor_windows(s))   # every window, here


# In 5-30 s and 30-60 s both controllers are near the sensor's quantisation floor (a perfect loop
# measures about 0.0014 cm): the margin there is small (5-30 s: 2.4 %, and 1.3-3.1 % on the rig's
# noise seeds 1-4) and comes from the Case 3 set's options ppc.ref_vel and ppc.obs_pos
# (docs/hil.md "Case 3: a set of its own", "Limits"). The lockstep run is deterministic (seeded
# rig, tick by tick), so the result does not change from run to run.
def test_case3_paper_controller_beats_mfac_in_every_window(runs):
    s, _ = runs("case3")
    for w, a, b in zip(s["windows"], s["rmste"]["ppc"], s["rmste"]["mfac"]):
        assert a < b, f"window {w}: PPC {a:.6f} cm vs MFAC {b:.6f} cm"


def test_case3_pid_runs_for_comparison(nominal_runs):
    """The PID lane's gains are hand-tuned on the idealised rig: a comparison there only."""
    s, _ = nominal_runs("case3-pid")
    assert list(s["controllers"]) == ["pid"] and s["duration_s"] == 30.0
    assert s["state"]["pid"] == "RUNNING" and len(s["rmste"]["pid"]) == 1     # window 5-30 s
    assert s["rmste"]["pid"][0] < 0.2


def test_smaller_tu_enters_the_band_sooner(runs):
    """2b (t_u 2 s) enters the band no later than 2a (t_u 6 s), into w1 and into w1 / 10. Both
    come within w1 in 0.4 s or less, before either funnel has narrowed much: the start's holding
    input (ppc.ff_init) and the reference feedforward carry the muscle in, closing faster than
    ppc.ff_hold_speed_cm_s, so the feedforward integrator waits in both. Into w1 / 10, 2b is 0 to
    36 ms ahead on these rigs (on the idealised one the same tick, 0.327 s: before the hold, 2b's
    integrator wound up faster on the way in and got there 3 ms sooner, the windup the hold
    prevents, docs/controllers.md option 8)."""
    a, out_a = runs("case2a")
    b, out_b = runs("case2b")
    assert (a["controllers"]["ppc"]["t_u_s"], b["controllers"]["ppc"]["t_u_s"]) == (6.0, 2.0)
    assert not acceptance.band_entry_failures(a, b, feasible=True)      # the shipped tasks are

    def first_within_tenth(summary: dict[str, Any], out: Any) -> float:
        sig = np.load(out / "signals.npz")
        inside = np.flatnonzero(np.abs(sig["ppc__e_cm"]) < summary["controllers"]["ppc"]["w1_cm"] / 10.0)
        assert len(inside), "never within w1 / 10"
        return float(sig["ppc__t_s"][inside[0]])
    ta, tb = first_within_tenth(a, out_a), first_within_tenth(b, out_b)
    assert tb <= ta, (tb, ta)


@pytest.mark.parametrize("case", ["case1", "case2a", "case2b", "case3", "load_change", "constraint_approach"])
def test_one_commissioned_set_for_every_task(runs, case):
    """The ppc and mfac lanes run on what commissioning derived on the rig plus only the task's
    own parameters: no gain and no rig-model number comes from the scenario file, and both
    lanes run to the end without a fault; the PPC's guarantee holds (no hand-over to MFAC)."""
    s, _ = runs(case)
    sc = scn.load(case)
    for label in ("ppc", "mfac"):
        ctrl = next(c for c in sc.controllers if c.label == label)
        assert ctrl.commission and set(ctrl.params) <= set(scn.COMMISSION_TASK_PARAMS)
        assert s["state"][label] == "RUNNING" and s["fault_code"][label] == "NONE", (label, s["fault_code"])
    derived = s["controllers"]["ppc"]["params_set"]
    for name in ("act.p0_kpa", "ppc.a_cm_s", "ppc.c", "ppc.w2_cm_s", "ppc.ff_init", "ppc.ref_ff", "mfac.phi1"):
        assert name in derived
    assert derived["act.p0_kpa"] != sc.params["act.p0_kpa"]      # the preset pressure is measured
    assert s["controllers"]["ppc"]["samples_outside_w1_after_tu"] == 0


# ------------------------------------------------------------- other scenarios --
def test_load_change_is_absorbed(runs):
    s, _ = runs("load_change")
    c = s["controllers"]["ppc"]
    assert s["state"]["ppc"] == "RUNNING" and s["fault_code"]["ppc"] == "NONE"
    assert c["samples_outside_w1_after_tu"] == 0
    assert c["constraint_violations"] == 0


def test_reference_near_the_constraint_stays_inside(runs):
    s, _ = runs("constraint_approach")
    c = s["controllers"]["ppc"]
    assert s["state"]["ppc"] == "RUNNING"
    assert c["x_max_cm"] < 0.0 and c["constraint_violations"] == 0
    assert c["samples_outside_w1_after_tu"] == 0


def test_reference_across_the_constraint_is_refused(runs):
    s, _ = runs("constraint_refused")
    assert s["start_result"]["ppc"] == "BAND" and s["state"]["ppc"] == "ARMED" and s["expect_met"]


@pytest.mark.parametrize("name, fault", [("wire_break", "SENSOR_WIRE_BREAK"),
                                         ("host_heartbeat_lost", "HOST_HEARTBEAT_LOST"),
                                         ("sensor_lost_target", "POSITION_LIMIT")])
def test_fault_ends_in_the_safe_state(runs, name, fault):
    s, out = runs(name)
    label = next(iter(s["controllers"]))
    c = s["controllers"][label]
    assert s["state"][label] == "FAULT" and s["fault_code"][label] == fault and s["expect_met"]
    # the documented safe state (safety.safe_mode VENT): output inactive, DAC at 0 kPa
    assert c["final_output_active"] == 0
    assert c["final_dac_counts"] == round(c["params_set"]["dac.counts_at_zero_kpa"])
    d = np.load(out / "signals.npz")
    active = d[f"{label}__output_active"]
    run = d[f"{label}__run_step"] >= 0
    first_off = int(np.flatnonzero(run & (active == 0))[0])
    event_t = scn.load(name).events[0].t_s
    t_off = d[f"{label}__run_step"][first_off] * s["period_s"]
    assert event_t <= t_off
    if name == "wire_break":
        # applied in the tick that saw the broken wire
        counts = d[f"{label}__counts"]
        first_broken = int(np.flatnonzero(run & (counts < c["params_set"]["adc.wire_break_below_counts"]))[0])
        assert first_off == first_broken
    if name == "host_heartbeat_lost":
        timeout_s = 0.5
        assert event_t + timeout_s - 0.11 <= t_off <= event_t + timeout_s + 0.01
