# SPDX-License-Identifier: Apache-2.0
"""Acceptance of the firmware against the paper's experiments, over vcan: every
scenario runs pma-fw-host in lockstep through the HIL runner, and the tests
assert on the simulated results (never on timing).

    hil/with-vcan .venv/bin/python -m pytest -q hil/tests/test_hil_acceptance.py

Each scenario runs once per session (full length); the runs take several minutes. The
exception is Case 3's PID lane (a comparison, no claim of the paper's): it runs on the quick
Case 3 (30 s) instead of beside the three 180 s lanes, which keeps a quarter of that run's
time out of CI.
"""
from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import can
import numpy as np
import pytest

from hil import scenario as scn
from hil.fw_process import FW_HOST, BUILD_HINT
from hil.runner import STOP_FILE, RunOptions, Runner

REPO = Path(__file__).resolve().parents[2]
CHATTER_MAX = 3.0   # pressure command's total variation at most 3x what the reference needs

pytestmark = pytest.mark.skipif(not Path("/sys/class/net/vcan0").exists(),
                                reason="needs vcan0: run under hil/with-vcan")


@pytest.fixture(scope="session")
def runs(tmp_path_factory: pytest.TempPathFactory) -> Any:
    assert FW_HOST.exists(), f"{FW_HOST} missing: {BUILD_HINT}"
    cache: dict[str, tuple[dict[str, Any], Path]] = {}

    def run(name: str) -> tuple[dict[str, Any], Path]:
        """name: a scenario, or "case3-pid" (Case 3's PID lane alone, quick)."""
        if name not in cache:
            out = tmp_path_factory.mktemp(name)
            quick = name == "case3-pid"
            sc = scn.load("case3" if quick else name)
            if sc.name == "case3":
                sc.controllers = [c for c in sc.controllers if (c.label == "pid") == quick]
            summary = Runner(sc, RunOptions(out=out, quick=quick, progress=False)).run()
            assert not summary["errors"], summary["errors"]
            cache[name] = (summary, out)
        return cache[name]
    return run


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
    """With the scenario's set (docs/hil.md: Cases 1 and 2 w2 = 2 cm/s and c = 32, Case 3 its
    own) lambda2 never meets its barrier after t_u, and the supervisor's BARRIER fault
    (safety.barrier_ticks, left at its default) is on for this node."""
    s, _ = runs(case)
    c = s["controllers"]["ppc"]
    assert "safety.barrier_ticks" not in c["params_set"]
    assert c["barrier_breaches_after_tu"] == 0


@pytest.mark.parametrize("case", ["case1", "case2a", "case2b", "case3"])
def test_paper_controller_does_not_chatter(runs, case):
    c = runs(case)[0]["controllers"]["ppc"]
    assert c["chatter_ratio"] is not None and c["chatter_ratio"] < CHATTER_MAX, c["chatter_ratio"]


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
    """Windows 60-180 s, by a wide margin (at least 2x)."""
    s, _ = runs("case3")
    ppc, mfac = s["rmste"]["ppc"], s["rmste"]["mfac"]
    assert len(ppc) == 6
    for w, a, b in list(zip(s["windows"], ppc, mfac))[2:]:
        assert 2.0 * a < b, f"window {w}: PPC {a:.4f} cm vs MFAC {b:.4f} cm"


# In 5-30 s and 30-60 s both controllers are near the sensor's quantisation floor (a perfect loop
# measures about 0.0014 cm): the margin there is small (5-30 s: 2.4 %, and 1.3-3.1 % on the rig's
# noise seeds 1-4) and comes from the Case 3 set's options ppc.ref_vel and ppc.obs_pos
# (docs/hil.md "Case 3: a set of its own", "Limits"). The lockstep run is deterministic (seeded
# rig, tick by tick), so the result does not change from run to run.
def test_case3_paper_controller_beats_mfac_in_every_window(runs):
    s, _ = runs("case3")
    for w, a, b in zip(s["windows"], s["rmste"]["ppc"], s["rmste"]["mfac"]):
        assert a < b, f"window {w}: PPC {a:.6f} cm vs MFAC {b:.6f} cm"


def test_case3_mfac_error_grows_as_the_chirp_speeds_up(runs):
    s, _ = runs("case3")
    mfac = s["rmste"]["mfac"]
    assert all(b > a for a, b in zip(mfac[1:], mfac[2:])), mfac    # from 30 s on, every window worse
    assert mfac[-1] > 5.0 * mfac[0]


def test_case3_pid_runs_for_comparison(runs):
    s, _ = runs("case3-pid")
    assert list(s["controllers"]) == ["pid"] and s["duration_s"] == 30.0
    assert s["state"]["pid"] == "RUNNING" and len(s["rmste"]["pid"]) == 1     # window 5-30 s
    assert s["rmste"]["pid"][0] < 0.2


def test_smaller_tu_enters_the_band_sooner(runs):
    a, _ = runs("case2a")
    b, _ = runs("case2b")
    ta, tb = a["controllers"]["ppc"]["time_to_band_s"], b["controllers"]["ppc"]["time_to_band_s"]
    assert tb < ta
    assert tb <= 2.0 and ta <= 6.0     # by t_u


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


# ------------------------------------------------------------- the recordings --
def test_bus_log_holds_every_bridge_frame(runs):
    s, out = runs("wire_break")
    from pmactl.protocol import load_protocol
    proto = load_protocol()
    sensor_id = proto.frame_id("PLANT_SENSOR", 1)
    act_id = proto.frame_id("PLANT_ACTUATOR", 1)
    n_sensor = n_act = 0
    with can.BLFReader(str(out / "bus.blf")) as reader:
        for msg in reader:
            if msg.arbitration_id == sensor_id:
                proto.decode("PLANT_SENSOR", bytes(msg.data))
                n_sensor += 1
            elif msg.arbitration_id == act_id:
                n_act += 1
    ticks = len(np.load(out / "signals.npz")["pid__counts"])
    assert n_sensor == ticks and n_act == ticks


def test_bus_log_decodes_completely_with_the_dbc_beside_it(runs, tmp_path):
    """bus.dbc (pmactl dbc of the run's nodes) decodes every frame of bus.blf in cantools'
    own command line, after python-can's converter turned the BLF into a candump log."""
    s, out = runs("wire_break")
    assert s["bus_dbc"] == "bus.dbc" and (out / "bus.dbc").exists()
    log = tmp_path / "bus.log"
    subprocess.run([sys.executable, "-m", "can.logconvert", str(out / "bus.blf"), str(log)],
                   check=True, capture_output=True)
    with can.BLFReader(str(out / "bus.blf")) as reader:
        frames = sum(1 for _ in reader)
    r = subprocess.run([sys.executable, "-m", "cantools", "decode", "--single-line", str(out / "bus.dbc")],
                       stdin=log.open(), capture_output=True, text=True, check=True)
    lines = [line for line in r.stdout.splitlines() if line.strip()]
    assert frames > 1000 and len(lines) == frames
    unknown = [line for line in lines if "Unknown frame id" in line]
    assert not unknown, unknown[:5]
    assert any(":: PLANT_SENSOR_N1(" in line for line in lines)
    assert any(":: HEARTBEAT_N1(" in line for line in lines)


def test_summary_records_every_nodes_identity(runs):
    """summary.json's identity: each lane's DEVICE_INFO (firmware, protocol, table, unique id)."""
    s, _ = runs("wire_break")
    from pmactl.protocol import load_protocol, protocol_version
    version = (REPO / "VERSION").read_text().strip()
    assert set(s["identity"]) == set(s["controllers"])
    uids = set()
    for label, ident in s["identity"].items():
        assert "error" not in ident, (label, ident)
        assert ident["protocol_version"] == protocol_version(load_protocol().db)
        assert ident["firmware"].startswith(version) and ident["build_target"] == "HOST"
        assert ident["problems"] == [] and len(ident["uid"]) == 24
        uids.add(ident["uid"])
    assert len(uids) == len(s["identity"])           # each lane its own device


# ---------------------------------------------------------------- clean stops --
def _start_cli(out: Path, extra_env: dict[str, str] | None = None) -> subprocess.Popen[bytes]:
    env = dict(os.environ, PMA_HIL_INSIDE="1", **(extra_env or {}))
    return subprocess.Popen([sys.executable, "-m", "hil", "run", "case1", "--out", str(out), "--no-figures"],
                            cwd=REPO, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT)


def _wait_running(out: Path, proc: subprocess.Popen[bytes]) -> None:
    deadline = time.monotonic() + 60
    while not (out / "bus.blf").exists() or (out / "bus.blf").stat().st_size == 0:
        assert proc.poll() is None, proc.stdout.read().decode() if proc.stdout else ""
        assert time.monotonic() < deadline
        time.sleep(0.2)
    time.sleep(3.0)


@pytest.mark.parametrize("how", ["sigint", "stop_file"])
def test_interrupted_run_stops_the_firmware_cleanly(tmp_path, how):
    out = tmp_path / "run"
    proc = _start_cli(out)
    _wait_running(out, proc)
    if how == "sigint":
        proc.send_signal(signal.SIGINT)          # Ctrl-C in a terminal
    else:
        (out / STOP_FILE).touch()                # what Ctrl-C outside the vcan guest does
    text = proc.communicate(timeout=60)[0].decode()
    assert proc.returncode == 130, text
    summary = json.loads((out / "summary.json").read_text())
    assert summary["interrupted"] and summary["errors"] == []   # firmware exited with status 0
    assert "INTERRUPTED" in text
    left = subprocess.run(["pgrep", "-f", str(out / "firmware")], capture_output=True, text=True)
    assert left.stdout.strip() == "", "pma-fw-host left running"


# ------------------------------------------------------------------ --board --
def test_board_mode_drives_a_real_time_node(tmp_path):
    """--board (docs/hil.md "Real board"): no pma-fw-host of its own, the node bridged by
    sys.plant_bridge and ticking on its own timer, the harness paced by its answers.
    pma-fw-host without --lockstep stands in for the board (its tick is a real-time timer,
    and it takes whatever sample came last).

    Neither Python nor pma-fw-host in the vcan guest is a real-time loop, so this tests the
    board path, not the machine: what it asserts holds however late the harness is (the
    configuration, the time axis matched to the board's telemetry tick for tick, every tick
    the board made lived through by the rig, the node still RUNNING). How well the loop
    tracks on this path depends on how many ticks went without a new sample, i.e. on the
    machine's speed, so it is printed, not asserted (the lockstep tests assert the paper's
    guarantee). Hence the node's timing limits are set wide: 50 Hz (the lowest tick rate),
    a tick may be served up to 20 s late, 200 s without a sample, 60 s without a host
    heartbeat, and no BARRIER fault (stale samples push the law onto its barrier; a CI
    run on a loaded machine faulted here at 200 Hz)."""
    from hil.fw_process import FirmwareProcess
    sc = scn.load("case1")
    sc.controllers = [c for c in sc.controllers if c.label == "ppc"]
    sc.params.update({"sys.tick_hz": 50, "safety.sensor_timeout_ticks": 10000, "safety.host_timeout_ms": 60000,
                      "safety.max_late_ticks": 1000, "safety.barrier_ticks": 0})
    node = 5
    fw = FirmwareProcess(tmp_path, ["--node", str(node), "--watchdog-ms", "10000"]).start()
    try:
        out = tmp_path / "board"
        opts = RunOptions(out=out, quick=True, board=True, board_node=node, progress=False, reply_timeout_s=10.0)
        summary = Runner(sc, opts).run()
    finally:
        fw.stop()
    assert not summary["errors"], summary["errors"]
    assert not (out / "firmware").exists()                  # the harness started no firmware
    c = summary["controllers"]["ppc"]
    print(f"board path at 50 Hz: {c['board_repeated_ticks']} ticks without a new sample, "
          f"max |e| after t_u {c['max_abs_error_after_tu_cm']:.4f} cm (w1 {c['w1_cm']} cm), "
          f"{c['constraint_violations_true_x']} samples outside the constraint")
    assert c["params_set"]["sys.plant_bridge"] == 1 and c["params_read_back"]["sys.plant_bridge"] == 1
    assert c["params_read_back"]["sys.tick_hz"] == 50
    # the harness's time axis is the board's: its x and x_r match TELEM_A/B tick for tick,
    # also across ticks without a new sample (board_repeated_ticks of them, however many)
    assert c["reference_check_max_abs_cm"] < 1e-4 and c["board_repeated_ticks"] >= 0
    assert (summary["state"]["ppc"], summary["fault_code"]["ppc"]) == ("RUNNING", "NONE"), \
        f"{summary['state']} {summary['fault_code']}, {c['board_repeated_ticks']} repeated ticks"
    d = np.load(out / "signals.npz")
    run = d["ppc__run_step"] >= 0
    assert np.all(d["ppc__output_active"][run] == 1)
    assert np.count_nonzero(d["ppc__sample_status"][run] == 3) == 0     # every tick had a sample
    # the run's time axis counts the board's ticks: strictly increasing, to the run's end
    steps = d["ppc__run_step"][run]
    assert np.all(np.diff(steps) >= 1) and steps[-1] >= round(summary["duration_s"] / summary["period_s"]) - 1
