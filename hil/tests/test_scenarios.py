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
    (["run", "case1", "--out", "x", "--controller", "ppc-paper", "--interface", "no_such_interface"], 3),
    (["run", "case1", "--out", "x"], 2),                  # its ppc and mfac lanes need --commission
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
