# SPDX-License-Identifier: Apache-2.0
"""The offline runs without CAN: the ctypes layer over libpma_offline.so (the real firmware on
the fake port) and `python -m hil offline`'s refusals. Needs the library
(cmake --preset host-offline && cmake --build --preset host-offline); the comparison with the
same scenario over CAN is test_offline_vs_hil.py (vcan)."""
from __future__ import annotations

import json
import math

import pytest

from hil import offline
from hil import scenario as scn
from hil.__main__ import main
from hil.commissioned import commission_offline

ARM, START, STOP = (scn.protocol().commands[c] for c in ("ARM", "START", "STOP"))
COUNTS_AT_MINUS_1_5_CM = 2948     # the default adc.* scaling: x = 7.5 - 0.0030525 counts


@pytest.fixture()
def node() -> offline.Node:
    assert offline.LIB_PATH.exists(), f"{offline.LIB_PATH} missing: {offline.BUILD_HINT}"
    n = offline.Node()
    n.start(node_id=3)
    return n


def test_a_fresh_node_is_idle_with_the_defaults(node):
    assert node.state_name() == "IDLE" and node.fault_name() == "NONE"
    proto = scn.protocol()
    assert set(node.ids) == {p.name for p in proto.params}      # the same table as the DBC side
    assert node.get("ppc.c") == pytest.approx(float(proto.param("ppc.c").default))
    assert node.get("sys.tick_hz") == 1000 and isinstance(node.get("sys.tick_hz"), int)


def test_set_goes_through_the_firmware_and_returns_what_it_holds(node):
    assert node.set("ppc.c", 80.0) == 80.0
    assert node.set("ppc.w1_cm", 0.1) == pytest.approx(0.1, rel=1e-7)   # float32
    assert node.get("ppc.w1_cm") == node.set("ppc.w1_cm", 0.1)
    assert node.set("vel.kind", 1) == 1


def test_an_unknown_parameter_name_is_a_clear_error(node):
    with pytest.raises(offline.UnknownParameter, match="no parameter 'ppc.nope'"):
        node.set("ppc.nope", 1.0)
    with pytest.raises(offline.UnknownParameter):
        node.param_id(9999)


def test_nan_is_refused_by_the_firmware(node):
    before = node.get("ppc.c")
    with pytest.raises(offline.ParamRejected) as e:
        node.set("ppc.c", math.nan)
    assert e.value.status == "PMA_ERR_NOT_FINITE" and scn.protocol().status_name(e.value.code) == "NOT_FINITE"
    assert node.get("ppc.c") == before


def test_a_value_out_of_range_is_refused_with_the_firmwares_code(node):
    before = node.get("ppc.w1_cm")
    with pytest.raises(offline.ParamRejected, match="PMA_ERR_RANGE") as e:
        node.set("ppc.w1_cm", 1e9)
    assert e.value.code == -3 and scn.protocol().status_name(e.value.code) == "RANGE"
    assert node.get("ppc.w1_cm") == before
    with pytest.raises(offline.ParamRejected, match="PMA_ERR_TYPE"):
        node.set("vel.kind", 0.5)                  # an integer parameter


def test_commands_take_the_real_path(node):
    rc, state = node.command(START)
    assert scn.protocol().status_name(rc) == "STATE" and scn.protocol().state_names[state] == "IDLE"
    rc, _ = node.command(ARM)                       # no sample yet: never without a position
    assert scn.protocol().status_name(rc) == "NOT_READY"
    for _ in range(3):
        o = node.tick(COUNTS_AT_MINUS_1_5_CM)
        assert o.seq > 0 and o.sample_status == 0 and o.output_active == 0
    rc, state = node.command(ARM)
    assert rc == 0 and scn.protocol().state_names[state] == "ARMED"
    o = node.tick(COUNTS_AT_MINUS_1_5_CM)
    assert o.output_active == 1 and o.state == state
    with pytest.raises(offline.ParamRejected, match="PMA_ERR_STATE"):
        node.set("sys.tick_hz", 500)                # only while the output is inactive


def test_a_tick_runs_the_controller_and_sends_telemetry(node):
    node.set("ref.kind", 0)                          # HOLD
    node.set("ref.offset_cm", -1.5)
    counts = COUNTS_AT_MINUS_1_5_CM
    for _ in range(5):
        node.tick(counts)
    assert node.command(ARM)[0] == 0
    for _ in range(20):
        node.tick(counts)
    assert node.command(START)[0] == 0
    frames = 0
    for _ in range(10):
        o = node.tick(counts)
        frames |= o.telem_frames
    assert frames == 0x1F and o.state == 3                 # every 10 ticks: TELEM_A..E
    assert o.telem_time_ms == 9 and o.telem_x_cm == o.x_cm
    assert o.telem_xr_cm == pytest.approx(-1.5) and o.telem_u == o.u
    assert node.command(STOP)[0] == 0


@pytest.mark.parametrize("argv, message", [
    (["case2b", "--set", "ppc.nope=1"], "no such parameter"),
    (["case2b", "--set", "ppc.w1_cm=1e9"], "outside"),
    (["case2b", "--set", "ppc.w1_cm=nan"], "not finite"),
    (["case2b", "--set", "ppc.w1_cm"], "NAME=VALUE"),
    (["case2b", "--rig", "regulator.tau_s=-1"], "--rig"),
    (["case2b", "--rig", "nonsense=1"], "--rig"),
    (["case2b", "--grid", "ppc.c"], "--grid"),
    (["case2b", "--grid", "ppc.c=1,1e9"], "outside"),
    (["case2b", "--controller", "nope"], "no controller nope"),
    (["case2b", "--jobs", "0"], "--jobs"),
    (["case2b", "--noise-limit", "2"], "add --commission"),
    (["case2b", "--commission", "--noise-limit", "0"], "--noise-limit"),
    (["case2b", "--commission", "--noise-limit", "nan"], "--noise-limit"),
    (["case2b", "--set", "ctrl.mode=2"], "ctrl.mode"),
    (["no_such_scenario"], "no scenario"),
])
def test_bad_offline_options_exit_2_with_the_reason(argv, message, capsys):
    assert main(["offline", *argv]) == 2
    assert message in capsys.readouterr().err


def test_an_offline_run_is_deterministic_and_jobs_do_not_change_it(tmp_path):
    sc = scn.load("case2b")
    sc.duration_s = sc.quick_duration_s = 3.0
    sc.windows = [(1.0, 3.0)]
    sc, _ = commission_offline(sc)          # its ppc and mfac lanes take their set from commissioning
    one = offline.run_scenarios([sc], quick=False, jobs=1)[0]
    two = offline.run_scenarios([sc], quick=False, jobs=2)[0]
    assert one["expect_met"] and not one["errors"]
    assert one["controllers"] == two["controllers"]
    assert one["controllers"]["ppc"]["rmste_cm"][0] < 0.3
    assert one["ctrl_arith"] == offline.ctrl_arith()     # the summary names the slot's arithmetic


def test_the_library_names_its_arithmetic_and_a_stated_one_is_checked(monkeypatch):
    """PMA_OFFLINE_ARITH: a run (a CI stage) that means one build refuses the other."""
    have = offline.ctrl_arith()
    assert have in offline.ARITHS
    other = next(a for a in offline.ARITHS if a != have)
    monkeypatch.setenv(offline.ARITH_ENV, have)
    offline._load(offline.LIB_PATH)
    monkeypatch.setenv(offline.ARITH_ENV, other)
    with pytest.raises(offline.OfflineError, match=f"controller slot is {have}, {offline.ARITH_ENV} asks for {other}"):
        offline._load(offline.LIB_PATH)
    monkeypatch.setenv(offline.ARITH_ENV, "double")
    with pytest.raises(offline.OfflineError, match="one of f32, q16"):
        offline._load(offline.LIB_PATH)


def test_a_grid_sweeps_firmware_and_rig_values(tmp_path, capsys):
    out = tmp_path / "sweep.json"
    rc = main(["offline", "case2b", "--controller", "ppc-paper", "--duration", "3", "--grid", "ppc.c=16,32",
               "--grid", "rig:load.bias_force_n=0,5", "--json", str(out), "--brief"])
    assert rc == 0
    runs = json.loads(out.read_text())
    assert [r["variant"] for r in runs] == [{"ppc.c": c, "rig:load.bias_force_n": f} for c in (16, 32) for f in (0, 5)]
    assert [r["controllers"]["ppc-paper"]["params_read_back"]["ppc.c"] for r in runs] == [16.0, 16.0, 32.0, 32.0]
    assert len({r["controllers"]["ppc-paper"]["rmste_cm"][0] for r in runs}) == 4
    assert "ppc.c=16 rig:load.bias_force_n=5" in capsys.readouterr().out


def test_the_report_names_the_controller_slots_arithmetic(capsys):
    assert main(["offline", "case2b", "--controller", "ppc-paper", "--duration", "0.5"]) == 0
    assert f"the controller slot in {offline.ctrl_arith()} (offline)" in capsys.readouterr().out


# --------------------------------- options checked as a whole before anything runs (exit 2) --
@pytest.mark.parametrize("argv, message", [
    (["--seed", "-1"], "--seed: expected an integer >= 0"),
    (["--grid", "seed=-1"], "--grid seed: expected an integer >= 0"),
    (["--grid", "seed=1.5"], "--grid seed: expected an integer >= 0"),
    (["--set", "safety.x_min_cm=1"], "--set safety.x_min_cm=1: controller ppc-paper: the parameter set breaks rule 10"),
    (["--set", "act.polarity=0"], "breaks rule 6"),
    (["--grid", "ctrl.u_max=100,-900"], "--grid ctrl.u_max=-900: controller ppc-paper: the parameter set breaks rule"),
    (["--grid", "ctrl.u_max=1,nan"], "--grid ctrl.u_max: nan is not finite"),
    (["--set", "ctrl.u_max=nan"], "--set ctrl.u_max: nan is not finite"),
    (["--rig", "contraction_is_negative_x=yes"], "--rig contraction_is_negative_x: expected true or false"),
    (["--rig", "load.bias_force_n=nan"], "--rig load.bias_force_n: must be finite"),
    (["--grid", "rig:load.bias_force_n=0,nan"], "--grid rig:load.bias_force_n: must be finite"),
    (["--rig", "load.mass_kg=heavy"], "--rig load.mass_kg: expected a number"),
    (["--rig", "load=5"], "--rig load: a group"),
    (["--rig", "sensor.span_cm=1e9"], "adc.offset_cm"),
    (["--out", "f"], "--out: f exists and is not a directory"),
    (["--out", "f/sub"], "--out: f/sub: cannot be made"),
    (["--json", "no_such_dir/x.json"], "--json: no_such_dir/x.json: no directory"),
    (["--json", "d"], "--json: d is a directory"),
])
def test_bad_offline_options_are_refused_before_the_run(argv, message, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "f").write_text("a file")
    (tmp_path / "d").mkdir()
    ran: list[object] = []

    def run_scenarios(*a, **k):
        ran.append(a)
        return []
    monkeypatch.setattr(offline, "run_scenarios", run_scenarios)
    assert main(["offline", "case2b", "--controller", "ppc-paper", "--duration", "0.5", "--brief", *argv]) == 2
    err = capsys.readouterr().err
    assert message in err and len(err.strip().splitlines()) == 1 and "Traceback" not in err
    assert not ran and (tmp_path / "f").read_text() == "a file"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["d", "f"]          # nothing written


def test_a_bool_rig_value_from_the_command_line_is_parsed_strictly():
    sc = scn.load("case2b")
    for text, value in (("false", False), ("0", False), ("true", True), ("1", True), ("FALSE", False)):
        v = offline.build_variants(sc, [], [("contraction_is_negative_x", text)], None)[0]
        assert v.scenario.rig_params().contraction_is_negative_x is value
    grid = offline.build_variants(sc, [], [], ["rig:sensor.inverted=false,true"])
    assert [x.scenario.rig_params().sensor.inverted for x in grid] == [False, True]
