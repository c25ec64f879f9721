# SPDX-License-Identifier: Apache-2.0
"""The HIL harness without CAN: scenario files, their validation, the metrics and
the command line's refusals (the runs themselves: test_hil_acceptance.py, over vcan)."""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from hil import scenario as scn
from hil.__main__ import main
from hil.metrics import rmste, time_to_band, total_variation_per_s
from hil.reference import reference_function

BASE = {"name": "t", "duration_s": 10.0, "controllers": [{"label": "ppc", "mode": "PPC"}]}


def test_every_shipped_scenario_loads_and_names_its_file():
    names = scn.available()
    for required in ("case1", "case2a", "case2b", "case3", "wire_break", "host_heartbeat_lost",
                     "load_change", "constraint_approach"):
        assert required in names
    for name in names:
        s = scn.load(name)
        assert s.name == name and s.controllers and s.duration_s > 0
        for c in s.controllers:
            params = s.node_params(c)        # every value checked against the table
            assert params["ctrl.mode"] == scn.protocol().param("ctrl.mode").check(c.mode)


@pytest.mark.parametrize("change, message", [
    ({"bogus": 1}, "unknown key"),
    ({"duration_s": -1}, "duration_s"),
    ({"duration_s": float("nan")}, "finite"),
    ({"params": {"ppc.nope": 1}}, "unknown firmware parameter"),
    ({"params": {"ppc.w1_cm": -1.0}}, "outside"),
    ({"params": {"ctrl.mode": "FUZZY"}}, "ctrl.mode"),
    ({"reference": {"kind": "TRIANGLE"}}, "kind"),
    ({"reference": {"kind": "SINE", "amplitude_cm": 1e9}}, "outside"),
    ({"rig": {"regulator": {"tau_s": -1}}}, "rig"),
    ({"rig": {"nonsense": 1}}, "rig"),
    ({"events": [{"t_s": 1, "action": "explode", "value": 1}]}, "action"),
    ({"events": [{"t_s": 99, "action": "wire_break", "value": 1}]}, "outside"),
    ({"windows": [[5, 2]]}, "windows"),
    ({"controllers": []}, "at least one"),
    ({"controllers": [{"label": "a", "mode": "PPC"}, {"label": "a", "mode": "MFAC"}]}, "unique"),
    ({"controllers": [{"label": "a", "mode": "PPC", "gain": 3}]}, "unknown key"),
    ({"expect": {"fault_code": "ON_FIRE"}}, "fault_code"),
])
def test_a_bad_scenario_is_refused_with_the_key_named(change, message):
    with pytest.raises(scn.ScenarioError, match=message):
        scn.parse({**BASE, **change})


def test_node_params_order_and_wiring():
    s = scn.parse({**BASE, "params": {"act.polarity": -1, "ppc.w1_cm": 0.3},
                   "controllers": [{"label": "ppc", "mode": "PPC", "params": {"ppc.w1_cm": 0.2}}],
                   "reference": {"kind": "SINE", "offset_cm": -1.0}})
    p = s.node_params(s.controllers[0])
    scale = s.rig_params().firmware_scaling()
    assert p["adc.gain_cm_per_count"] == pytest.approx(scale["adc.gain_cm_per_count"])
    assert p["ppc.w1_cm"] == 0.2                      # the controller's value wins
    assert p["act.polarity"] == -1 and p["ref.offset_cm"] == -1.0
    assert "act.p0_kpa" not in p                      # the preset pressure is the scenario's choice
    assert s.w1_cm(s.controllers[0]) == 0.2 and s.t_u_s(s.controllers[0]) == pytest.approx(
        float(scn.protocol().param("ppc.t_u_s").default))


def test_quick_windows_are_cut_to_the_run():
    s = scn.parse({**BASE, "duration_s": 60, "quick_duration_s": 25, "windows": [[10, 20], [20, 30], [30, 40]]})
    assert s.windows_for(25) == [(10, 20), (20, 25)]
    assert s.windows_for(60) == [(10, 20), (20, 30), (30, 40)]


def test_reference_formulas_match_the_paper():
    t = np.array([0.0, 1.0, 30.0, 180.0])
    case1 = reference_function({"kind": "CASE1"})(t)
    assert case1 == pytest.approx(-0.5 * np.sin(t) - 2.0)
    case3 = reference_function({"kind": "CASE3"})(t)
    assert case3[0] == pytest.approx(-2.0)
    assert case3[3] == pytest.approx(180 * math.sin(2 * math.pi * 180 * (1 + 180 / 55) / 55 - math.pi / 2) / 360 - 2)
    step = reference_function({"kind": "STEP", "offset_cm": -1.0, "amplitude_cm": -0.5, "t0_s": 1.0})(t)
    assert list(step) == [-1.0, -1.5, -1.5, -1.5]


def test_metrics_on_known_signals():
    t = np.arange(0, 10, 0.001)
    e = np.where(t < 2, 1.0, 0.1 * np.sin(2 * np.pi * t))
    r = rmste(t, e, [(0, 2), (2, 10)])
    assert r[0] == pytest.approx(1.0) and r[1] == pytest.approx(0.1 / math.sqrt(2), rel=1e-3)
    assert time_to_band(t, e, 0.5) == pytest.approx(2.0)
    assert time_to_band(t, np.ones_like(t), 0.5) is None
    y = np.tile([0.0, 1.0], 500)
    assert total_variation_per_s(np.linspace(0, 1, 1000), y) == pytest.approx(999.0)
    # the harness's figures are pmactl's (one module, one rule: pmactl/figures.py)
    from pmactl import figures
    assert (rmste, time_to_band, total_variation_per_s) == (figures.rmste, figures.time_to_band,
                                                            figures.total_variation_per_s)


@pytest.mark.parametrize("argv, code", [
    (["run"], 2),                                         # no scenario
    (["run", "case1"], 2),                                # no --out
    (["run", "no_such_scenario", "--out", "x"], 2),
    (["run", "case1", "--out", "x", "--controller", "nobody"], 2),
    (["run", "case1", "--out", "x", "--node", "99"], 2),
    (["run", "case3", "--out", "x", "--board"], 2),       # a board runs one controller at a time
    (["run", "case1", "--out", "x", "--controller", "ppc-paper", "--interface", "no_such_interface"], 2),
    (["run", "case1", "--out", "x"], 2),                  # its ppc and mfac lanes need --commission
    (["run", "case1", "--out", "x", "--noise-limit", "2"], 2),                   # a commissioning option
    (["run", "case1", "--out", "x", "--commission", "--noise-limit", "-1"], 2),
    (["frobnicate"], 2),
])
def test_bad_command_lines_are_refused(argv, code, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main(argv) == code
    assert not (tmp_path / "x").exists()                  # nothing was started or written


def test_list_prints_every_scenario(capsys):
    assert main(["list"]) == 0
    out = capsys.readouterr().out
    for name in scn.available():
        assert name in out


def test_report_of_a_missing_run(tmp_path: Path):
    assert main(["report", str(tmp_path)]) == 2


# ----------------------------------------- every value of a file typed: exit 2, never a traceback --
@pytest.mark.parametrize("change, message", [
    ({"controllers": [1, 2]}, r"controllers\[0\]: expected a table"),
    ({"controllers": {"label": "a"}}, "controllers: expected an array"),
    ({"events": [5]}, r"events\[0\]: expected a table"),
    ({"events": 5}, "events: expected an array"),
    ({"expect": 5}, r"\[expect\]: expected a table"),
    ({"windows": 5}, "windows: expected an array"),
    ({"windows": [5]}, r"windows\[0\] must be"),
    ({"reference": 5}, r"\[reference\]: expected a table"),
    ({"reference": "CASE1"}, r"\[reference\]: expected a table"),
    ({"reference": {"kind": 3}}, "kind: expected text"),
    ({"rig": 5}, r"\[rig\]: expected a table"),
    ({"rig": {"load": {"bias_force_n": math.nan}}}, "load.bias_force_n must be finite"),
    ({"rig": {"contraction_is_negative_x": "false"}}, "expected true or false"),
    ({"seed": "abc"}, "seed: expected an integer"),
    ({"seed": -1}, "seed: expected an integer"),
    ({"seed": 1.7}, "seed: expected an integer"),
    ({"seed": True}, "seed: expected an integer"),
    ({"paper": 42}, "paper: expected text"),
    ({"paper": "nosuch"}, "paper: 'nosuch' is not one of"),
    ({"title": [1, 2]}, "title: expected text"),
    ({"description": 5}, "description: expected text"),
    ({"controllers": [{"label": 5, "mode": "PPC"}]}, r"label: expected text"),
    ({"controllers": [{"label": "a", "mode": 2}]}, r"mode: expected text"),
    ({"controllers": [{"label": "a", "mode": "PPC", "description": 1}]}, "description: expected text"),
    ({"controllers": [{"label": "a", "mode": "PPC", "commission": "yes"}]}, "commission: expected true or false"),
    ({"events": [{"t_s": 1, "action": "wire_break", "value": 5}]}, "expected 1 or 0 for wire_break"),
    ({"events": [{"t_s": 1, "action": "sensor_block", "value": 0.5}]}, "expected 1 or 0 for sensor_block"),
    ({"events": [{"t_s": 1, "action": "host_heartbeat", "value": True}]}, "expected 1 or 0 for host_heartbeat"),
    ({"events": [{"t_s": 1, "action": "load_mass", "value": 0}]}, "load_mass must be > 0"),
    ({"events": [{"t_s": 1, "action": 3, "value": 1}]}, "action: expected text"),
    ({"events": [{"t_s": 1, "action": "disturbance"}]}, "missing 'value'"),
    ({"expect": {"start_result": "BOGUS"}}, "start_result: 'BOGUS' is not one of"),
    ({"expect": {"state": 3}}, "state: expected text"),
    ({"rig": {"sensor": {"span_cm": 1e9}}}, "adc.offset_cm"),   # the wiring it gives is out of range
])
def test_a_mistyped_scenario_value_is_refused_with_the_key_named(change, message):
    with pytest.raises(scn.ScenarioError, match=message):
        scn.parse({**BASE, **change})


def test_the_valid_values_of_the_typed_keys_still_load():
    s = scn.parse({**BASE, "seed": 7, "paper": "table2", "title": "T",
                   "events": [{"t_s": 1, "action": "wire_break", "value": 1},
                              {"t_s": 2, "action": "wire_break", "value": 0.0},
                              {"t_s": 3, "action": "load_mass", "value": 3}],
                   "expect": {"state": "fault", "fault_code": "SENSOR_WIRE_BREAK", "start_result": "band"}})
    assert s.seed == 7 and s.paper == "table2" and s.title == "T"
    assert [e.value for e in s.events] == [1.0, 0.0, 3.0]
    assert (s.expect.state, s.expect.start_result) == ("FAULT", "BAND")


def test_every_shipped_scenario_file_loads_with_its_values_typed():
    paths = sorted(p for p in scn.SCENARIO_DIR.rglob("*.toml") if not p.name.startswith("_"))
    assert len(paths) > 30                                  # hil/scenarios, realistic/*, variants
    for p in paths:
        s = scn.load(str(p))
        assert isinstance(s.seed, int) and isinstance(s.title, str)


@pytest.mark.parametrize("text, message", [
    (b'title = "caf\xe9"\n', "not UTF-8"),
    (b'base = 5\n', "base: expected text"),
    (b'base = "no_such_base.toml"\n', "base: no file"),
    (b'base = "no_such_case"\n', "'no_such_case' is not a shipped scenario's name"),
    (b'seed = -1\n', "seed"),
])
def test_a_bad_scenario_file_exits_2_with_one_line(tmp_path, capsys, text, message):
    f = tmp_path / "bad.toml"
    f.write_bytes(text + b'duration_s = 1.0\n[[controllers]]\nlabel = "pid"\nmode = "PID"\n')
    with pytest.raises(scn.ScenarioError, match=message):
        scn.load(str(f))
    assert main(["offline", str(f), "--brief"]) == 2
    err = capsys.readouterr().err
    assert message in err and len(err.strip().splitlines()) == 1 and "Traceback" not in err


def test_a_users_file_builds_on_a_shipped_scenario_by_its_name(tmp_path):
    """A file outside hil/scenarios names the shipped scenario it builds on ("case3",
    "realistic/dmsp10/case3"); a file beside it of that name would win (a path comes first)."""
    f = tmp_path / "my_case3.toml"
    f.write_text('base = "realistic/dmsp10/case3"\ntitle = "mine"\n[rig.load]\nmass_kg = 2.5\n')
    mine, shipped = scn.load(str(f)), scn.load("realistic/dmsp10/case3")
    assert mine.name == "my_case3" and mine.title == "mine" and mine.duration_s == shipped.duration_s
    assert mine.rig["load"]["mass_kg"] == 2.5 and mine.controllers == shipped.controllers
    assert mine.rig_params().valve == shipped.rig_params().valve      # the profile's, through the base
    (tmp_path / "case3").write_text('duration_s = 7.0\n[[controllers]]\nlabel = "pid"\nmode = "PID"\n')
    f.write_text('base = "case3"\n')
    assert scn.load(str(f)).duration_s == 7.0


# ---------------------------------------------- run, bench, report: options checked up front --
@pytest.mark.parametrize("argv, message", [
    (["run", "case2b", "--controller", "ppc-paper", "--out", "f"], "--out: f exists and is not a directory"),
    (["run", "case2b", "--controller", "ppc-paper", "--out", "x", "--bitrate", "-5"], "bit rate -5"),
    (["run", "case2b", "--controller", "ppc-paper", "--out", "x", "--bitrate", "0"], "bit rate 0"),
    (["run", "case2b", "--controller", "ppc-paper", "--out", "x", "--interface", "nosuch"], "socketcan"),
    (["bench", "--seconds", "-1", "--out", "x"], "--seconds"),
    (["bench", "--seconds", "nan", "--out", "x"], "--seconds"),
    (["bench", "--seconds", "0", "--out", "x"], "--seconds"),
    (["bench", "--out", "f"], "--out"),
    (["bench", "--out", "x", "--bitrate", "0"], "bit rate 0"),
    (["bench", "--out", "x", "--interface", "nosuch"], "nosuch"),
])
def test_run_and_bench_options_are_checked_before_anything_starts(argv, message, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "f").write_text("a file")
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert message in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "x").exists() and (tmp_path / "f").read_text() == "a file"


def test_a_bench_failure_is_one_line_and_a_nonzero_status(tmp_path, monkeypatch, capsys):
    import hil.bench

    def fail(cfg, seconds, out):
        out.mkdir(parents=True, exist_ok=True)
        raise RuntimeError("pma-fw-host did not answer:\nits output\nmore of it")
    monkeypatch.setattr(hil.bench, "run_bench", fail)
    rc = main(["bench", "--seconds", "0.1", "--out", str(tmp_path / "b"), "--interface", "virtual",
               "--channel", "bench-test"])
    assert rc == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "pma-fw-host did not answer" in err[0]
    assert "its output" in (tmp_path / "b" / "bench-error.txt").read_text()


@pytest.mark.parametrize("content, message", [
    ("{bad", "not a readable JSON file"),
    ("{}", "no 'scenario'"),
    ("[]", "expected a JSON object"),
    ('{"scenario": "s", "title": "t", "duration_s": 1, "period_s": 0.001, "windows": [], "rmste": {}, '
     '"controllers": {"a": 5}, "state": {}, "fault_code": {}, "expect": {"state": "RUNNING", '
     '"fault_code": "NONE", "start_result": "OK"}}', "controllers.a"),
])
def test_report_of_a_bad_summary_is_a_clear_error(tmp_path, capsys, content, message):
    (tmp_path / "summary.json").write_text(content)
    assert main(["report", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert message in err and len(err.strip().splitlines()) == 1


def test_report_figures_need_the_runs_signals(tmp_path, capsys):
    summary = {"scenario": "s", "title": "t", "duration_s": 1.0, "period_s": 0.001, "windows": [[0, 1]],
               "rmste": {}, "controllers": {}, "state": {}, "fault_code": {},
               "expect": {"state": "RUNNING", "fault_code": "NONE", "start_result": "OK"}}
    import json
    (tmp_path / "summary.json").write_text(json.dumps(summary))
    assert main(["report", str(tmp_path)]) == 0                      # the summary alone reads
    capsys.readouterr()
    assert main(["report", str(tmp_path), "--figures"]) == 2
    assert "signals.npz not found" in capsys.readouterr().err
    (tmp_path / "signals.npz").write_bytes(b"not a zip")
    assert main(["report", str(tmp_path), "--figures"]) == 2
    assert "signals.npz" in capsys.readouterr().err
