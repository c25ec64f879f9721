# SPDX-License-Identifier: Apache-2.0
"""tools/hil_matrix.py: its table rows from run summaries, the tasks' files, its rigs' values
(each a real rig parameter), its options; one real run, offline, where the library is built."""
from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

from hil import acceptance, offline
from hil import scenario as scn
from pma_tools import hil_matrix as hm

TOOL = Path(hm.__file__)


def lane(rmste: list[float], lost: float | None = None, fallback: float | None = None,
         state: str = "RUNNING", fault: str = "NONE", viol: int = 0) -> dict[str, Any]:
    return {"rmste_cm": rmste, "guarantee_lost_at_s": lost, "fallback_at_s": fallback,
            "final_state": state, "final_fault_code": fault, "constraint_violations": viol}


def test_row_states_the_worst_window_and_what_happened():
    s = {"controllers": {"ppc": lane([0.002, 0.003], lost=1.5), "mfac": lane([0.004, 0.0025], viol=7)}}
    line, worst = hm.row("R: a rig", "case1", s)
    assert worst == pytest.approx(1.2)
    assert line == ("| R: a rig | case1 | 0.0020 0.0030 | 0.0040 0.0025 | 1.20 | 1.50 s / - | 0 / 7 |")
    s["controllers"]["ppc"] = lane([0.002, 0.002], state="FAULT", fault="BARRIER")
    line, _ = hm.row("R", "case3", s)
    assert "(FAULT / BARRIER)" in line and "| - |" in line


def test_tasks_on_each_profile_are_the_shipped_files():
    assert hm.task_file("nominal", "case1") == "case1"
    for profile in ("dmsp10", "mas10-itv2050"):
        for task in hm.TASKS:
            assert Path(hm.task_file(profile, task)).is_file()


@pytest.mark.parametrize("matrix", sorted(hm.MATRICES))
def test_every_rig_value_is_a_rig_parameter(matrix):
    rigs, _ = hm.MATRICES[matrix]
    base = scn.load("case1").rig_params()
    for rig in rigs:
        assert rig.profile in ("nominal", "dmsp10", "mas10-itv2050")
        for value in rig.values.split():
            path, _, number = value.partition("=")
            base.replace(**{path: float(number)}).validate()   # ValueError for an unknown path


@pytest.mark.parametrize("ranges", [hm.RANDOM_RANGES, hm.WIDE_RANGES], ids=["random", "wide"])
def test_random_rigs_are_repeatable_valid_and_within_their_spans(ranges):
    rigs = hm.random_rigs(5, 12, ranges)
    assert rigs == hm.random_rigs(5, 12, ranges) and rigs != hm.random_rigs(6, 12, ranges)
    assert hm.random_rigs(5, 3, ranges) == rigs[:3]            # the first n of a longer draw
    spans = {path: (how, lo, hi, where) for path, how, lo, hi, where in ranges}
    for rig in rigs:
        base = scn.load(hm.task_file(rig.profile, "case3")).rig_params()
        params = base
        for value in rig.values.split():
            path, _, number = value.partition("=")
            how, lo, hi, where = spans[path]
            assert rig.profile in where
            section, name = path.split(".")
            v, x = float(getattr(getattr(base, section), name)), float(number)
            if how == "bits":
                assert x in (10, 11, 12)
            elif how == "shift":
                assert v + lo - 1e-3 <= x <= v + hi + 1e-3
            else:
                assert v * lo * (1 - 1e-3) <= x <= v * hi * (1 + 1e-3)
            params = params.replace(**{path: x})
        params.validate()


def test_bad_options_exit_2(tmp_path):
    a_file = tmp_path / "a_file"
    a_file.write_text("")
    for args in (["--matrix", "eleven"], ["--matrix", "ten", "--jobs", "0"], [],
                 ["--matrix", "random", "--count", "0"], ["--matrix", "random", "--seed", "-1"],
                 ["--matrix", "ten", "--seed", "3"], ["--matrix", "seven", "--count=2"],
                 ["--matrix", "variants", "--wide"],
                 ["--matrix", "random", "--out", str(a_file)], ["--matrix", "random", "--seed", "1", "1"],
                 ["--matrix", "random", "--reuse"], ["--matrix", "random", "--plot", str(tmp_path / "f.svg")],
                 ["--matrix", "random", "--plot", str(tmp_path / "no" / "f.png")],
                 ["--matrix", "random", "--plot", str(tmp_path)]):
        r = subprocess.run([sys.executable, str(TOOL), *args], capture_output=True, text=True)
        assert r.returncode == 2, (args, r.stderr)
        assert "Traceback" not in r.stderr


@pytest.mark.skipif(not offline.LIB_PATH.exists(), reason="libpma_offline.so not built")
def test_one_run_gives_its_row(tmp_path):
    s = hm.run(["constraint_approach", "--quick", "--rig", "load.mass_kg=2.0"], tmp_path / "one.json")
    line, worst = hm.row("X", "constraint_approach", s)
    assert line.startswith("| X | constraint_approach | ") and worst > 0.0
    assert s["controllers"]["ppc"]["final_state"] == "RUNNING"


def summary(task: str, time_to_band_s: float, t_u_s: float) -> dict[str, Any]:
    """A run that meets every criterion of hil/acceptance.py but the band entry it is given."""
    ppc = {"w1_cm": 0.2, "t_u_s": t_u_s, "guarantee_lost_at_s": None, "fallback_at_s": None,
           "funnel_wide_at_s": None, "samples_outside_w1_after_tu": 0, "barrier_breaches_after_tu": 0,
           "constraint_violations": 0, "constraint_violations_true_x": 0, "chatter_ratio": 1.5,
           "time_to_band_s": time_to_band_s}
    return {"file": str(scn.find(task)), "duration_s": 10.0, "period_s": 0.001, "windows": [[5.0, 10.0]],
            "state": {"ppc": "RUNNING"}, "fault_code": {"ppc": "NONE"},
            "rmste": {"ppc": [0.01], "mfac": [0.02]}, "controllers": {"ppc": ppc, "mfac": {}},
            "commissioning": {"derivation": {"figures": {"stroke_min_cm": -2.9, "stroke_max_cm": -0.1}}}}


def test_acceptance_pairs_each_rigs_case_2b_with_its_case_2a():
    jobs = [(rig, task, []) for rig in ("R1: x", "R2: y") for task in ("case2a", "case2b")]
    runs = [summary("case2a", 4.0, 6.0), summary("case2b", 1.0, 2.0),      # R1: 2b first
            summary("case2a", 1.0, 6.0), summary("case2b", 1.5, 2.0)]      # R2: 2b later
    failures = hm.acceptance_failures(jobs, runs)
    assert [f for f in failures[:3] if any(f.values())] == []
    assert acceptance.BAND_ENTRY not in failures[0] and acceptance.BAND_ENTRY in failures[1]
    missed = {name: f for name, f in failures[3].items() if f}
    assert list(missed) == [acceptance.BAND_ENTRY]
    assert len(missed[acceptance.BAND_ENTRY]) == 1 and "band entered at 1.5 s (2b" in missed[acceptance.BAND_ENTRY][0]


def test_reuse_makes_the_table_and_figure_again_from_the_summaries(tmp_path):
    """--reuse with every run's summary already in --out: no run is made (these summaries are
    made up: a run would overwrite them), and the table, the criteria and the figure come from them."""
    for i, task in enumerate(hm.TASKS):
        s = summary(task, 1.0, 6.0 if task == "case2a" else 2.0)
        s["rmste"]["ppc"] = [0.03] if task == "load_change" else [0.01]          # one run behind MFAC
        for lane_name in ("ppc", "mfac"):
            s["controllers"][lane_name].update(lane(s["rmste"][lane_name]))
        (tmp_path / f"run_{i:03d}.json").write_text(json.dumps([s]))
    png = tmp_path / "f.png"
    r = subprocess.run([sys.executable, str(TOOL), "--matrix", "random", "--count", "1", "--out", str(tmp_path),
                        "--reuse", "--plot", str(png)], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    assert r.stdout.count("| R1: ") == len(hm.TASKS)
    assert "5 of 6 runs with the paper's controller ahead" in r.stdout
    assert "5 of 6 runs meet every acceptance criterion" in r.stdout and "load_change: 5-10 s: 1.500 x" in r.stdout
    assert "runs missing each criterion: at most MFAC's RMSTE in every window 1\n" in r.stdout
    assert png.stat().st_size > 10_000 and png.read_bytes()[:4] == b"\x89PNG"
