# SPDX-License-Identifier: Apache-2.0
"""pmactl scope: headless (Agg, PNG per frame) against fake nodes on the virtual bus, and
in a real window under Xvfb with screenshots. Frames are counted, never seconds."""
from __future__ import annotations

import importlib.util
import json
import os
import shutil
import subprocess
import sys
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from fakenode import wait_until
from PIL import Image

from pmactl import scope
from pmactl.cli import EXIT_NO_REPLY, EXIT_OK, EXIT_USAGE
from pmactl.recording import header_row, read_recording

HERE = Path(__file__).resolve().parent
LINE_RGB = (0x1F, 0x77, 0xB4)        # matplotlib's C0: node 0's x and x_r


@pytest.fixture
def hooks() -> Iterator[list[Callable[[scope.Scope, int], None]]]:
    yield scope.frame_hooks
    scope.frame_hooks.clear()


def _line_mask(path: Path) -> np.ndarray:
    """Pixels of node 0's colour (anti-aliased: within a small distance of it)."""
    img = np.asarray(Image.open(path).convert("RGB")).astype(int)
    return np.asarray(np.abs(img - np.array(LINE_RGB)).sum(axis=2) < 60, dtype=bool)


def _moved_columns(a: np.ndarray, b: np.ndarray) -> tuple[int, int]:
    """(columns with the line in either image, columns where its rows differ)."""
    cols = np.flatnonzero(a.any(axis=0) | b.any(axis=0))
    moved = sum(1 for c in cols if not np.array_equal(a[:, c], b[:, c]))
    return len(cols), moved


def test_headless_frames_show_moving_telemetry(fake, pmactl, tmp_path: Path, hooks: list[Any]) -> None:
    node = fake(motion="sine")
    node.set_state("RUNNING")

    def hook(sc: scope.Scope, frames: int) -> None:
        # each frame draws at least 10 more telemetry rows (0.1 s of the node's data time),
        # however slowly the fake node's thread runs on a loaded machine: frames count data
        tr = sc.traces[0]
        rows = tr.rows
        wait_until(lambda: (sc.poll(), tr.rows)[1] >= rows + 10)

    hooks.append(hook)
    r = pmactl("scope", "--headless", "--frames", "6", "--out", str(tmp_path / "f"),
               "--host-heartbeat", "--window", "3")
    assert r.code == EXIT_OK, r.err
    pngs = sorted(tmp_path.glob("f_*.png"))
    assert [p.name for p in pngs] == [f"f_{i:04d}.png" for i in range(1, 7)]
    assert "; 6 frames drawn" in r.out and "telemetry rows shown" in r.out
    first, last = _line_mask(pngs[0]), _line_mask(pngs[-1])
    assert last.sum() > 200                      # the lines are drawn
    cols, moved = _moved_columns(first, last)
    assert moved > 0.2 * cols, (cols, moved)


def test_record_and_pause_keys(fake, pmactl, tmp_path: Path, hooks: list[Any]) -> None:
    """r starts a recording (record's CSV format), space pauses the view: rows keep being
    recorded while the view stays still; r again ends the file."""
    node = fake(motion="sine")
    node.set_state("RUNNING")
    seen: dict[str, int] = {}

    class Key:
        def __init__(self, key: str) -> None:
            self.key = key

    def hook(sc: scope.Scope, frames: int) -> None:
        tr = sc.traces[0]
        if frames == 1:
            sc.on_key(Key("r"))
        elif frames == 2:
            wait_until(lambda: sc.poll() > 0 or tr.recorded > 0)
        elif frames == 3:
            sc.on_key(Key(" "))
            seen["paused_rows"] = tr.rows
            seen["paused_recorded"] = tr.recorded
        elif frames == 4:
            wait_until(lambda: (sc.poll(), tr.recorded)[1] > seen["paused_recorded"] + 5)
            seen["rows_after"] = tr.rows
            seen["recorded_after"] = tr.recorded
            sc.on_key(Key("r"))

    hooks.append(hook)
    csv_path = tmp_path / "run.csv"
    r = pmactl("scope", "--headless", "--frames", "5", "--out", str(tmp_path / "f"), "--host-heartbeat",
               "--csv", str(csv_path))
    assert r.code == EXIT_OK, r.err
    assert seen["rows_after"] == seen["paused_rows"]            # paused: the view keeps its rows
    assert seen["recorded_after"] > seen["paused_recorded"]     # ... the recording goes on
    assert f"recording node 0 to {csv_path}" in r.out
    assert f"recorded {seen['recorded_after']} rows of node 0 to {csv_path}" in r.out
    rec = read_recording(csv_path)                              # pmactl record's format
    assert len(rec) == seen["recorded_after"]
    assert csv_path.read_text().splitlines()[0].split(",")[:6] == header_row()[:6]
    assert np.all(np.diff(rec["t"]) > 0) and not np.isnan(rec["x"]).any()
    # `pmactl plot` draws it, with w1 and the band from the .meta.json beside it
    meta = json.loads((tmp_path / "run.meta.json").read_text())
    assert meta["node"] == 0 and meta["params"]["ppc.w1_cm"] == pytest.approx(node.value("ppc.w1_cm"))
    r = pmactl("plot", str(csv_path), "--no-panels", bus=False)
    assert r.code == EXIT_OK, r.err
    assert (tmp_path / "run.png").exists() and "rows, t " in r.out
    assert meta["controller"] == "PPC" and "|e| < w1 = " in r.out


def test_two_nodes_record_one_file_each(fake, pmactl, tmp_path: Path) -> None:
    for n in (1, 2):
        fake(node=n, motion="sine").set_state("RUNNING")
    csv_path = tmp_path / "two.csv"
    r = pmactl("scope", "--nodes", "1,2", "--headless", "--frames", "4", "--out", str(tmp_path / "f"),
               "--host-heartbeat", "--record", "--csv", str(csv_path))
    assert r.code == EXIT_OK, r.err
    for n in (1, 2):
        assert f"node {n}: " in r.out
        assert len(read_recording(tmp_path / f"two_n{n}.csv")) > 0


def test_scope_errors(fake, pmactl, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    node = fake()                                # IDLE: no telemetry
    r = pmactl("scope", "--headless", "--frames", "3", "--out", str(tmp_path / "f"))
    assert r.code == EXIT_NO_REPLY and "no telemetry from node(s) 0" in r.err
    r = pmactl("scope", "--headless", "--out", str(tmp_path / "f"))
    assert r.code == EXIT_USAGE and "--frames" in r.err
    r = pmactl("scope", "--nodes", "1,1", "--headless", "--frames", "1")
    assert r.code == EXIT_USAGE and "node 1 listed twice" in r.err
    r = pmactl("scope", "--headless", "--frames", "1", "--out", str(tmp_path / "no" / "f"))
    assert r.code == EXIT_USAGE and "does not exist" in r.err
    # no display: a message that says what to do, not a traceback
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    import matplotlib
    monkeypatch.setattr(matplotlib, "get_backend", lambda: "agg")
    r = pmactl("scope", "--frames", "1")
    assert r.code == EXIT_USAGE
    assert "no interactive matplotlib backend" in r.err and "--headless" in r.err
    assert "Traceback" not in r.err
    assert node.state == 1                      # nothing was sent that changes it (IDLE)


def _xvfb_missing() -> str | None:
    if shutil.which("Xvfb") is None:
        return "Xvfb is not installed (Debian: apt-get install xvfb; tools/setup.sh installs it)"
    if importlib.util.find_spec("tkinter") is None:
        return "tkinter is missing (Debian: apt-get install python3-tk; tools/setup.sh installs it)"
    return None


def _in_a_window(cwd: Path, *args: str) -> subprocess.CompletedProcess[str]:
    """scope_window.py ARGS on a fresh virtual X server (TkAgg); it must exit 0."""
    xvfb = subprocess.Popen(["Xvfb", "-displayfd", "1", "-screen", "0", "1024x768x24", "-nolisten", "tcp"],
                            stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    try:
        assert xvfb.stdout is not None
        display = f":{xvfb.stdout.readline().strip()}"
        env = dict(os.environ, DISPLAY=display, MPLBACKEND="TkAgg")   # the script's folder: its imports
        r = subprocess.run([sys.executable, str(HERE / "scope_window.py"), *args],
                           env=env, capture_output=True, text=True, timeout=300, check=False, cwd=cwd)
        assert r.returncode == EXIT_OK, r.stdout + r.stderr
        return r
    finally:
        xvfb.terminate()
        xvfb.wait(10)


@pytest.mark.skipif(_xvfb_missing() is not None, reason=str(_xvfb_missing()))
def test_scope_in_a_window_under_xvfb(tmp_path: Path) -> None:
    """The TkAgg window on a virtual X server: the plotted line is on the screen, and it
    moves between a screenshot after frame 30 and one after frame 45; the keys work."""
    r = _in_a_window(tmp_path, str(tmp_path), "30", "15")
    stats = json.loads((tmp_path / "stats.json").read_text())
    assert stats["frames"] == 47
    assert stats["paused_after_space"] is True and stats["paused_after_second_space"] is False
    assert len(list(tmp_path.glob("scope-*.png"))) == 1 and "view saved to scope-" in r.stdout
    a, b = _line_mask(tmp_path / "shot1.png"), _line_mask(tmp_path / "shot2.png")
    assert a.shape == (768, 1024)
    assert a.sum() > 300 and b.sum() > 300, (a.sum(), b.sum())      # the line is in the window
    cols, moved = _moved_columns(a, b)
    assert cols > 100 and moved > 0.2 * cols, (cols, moved)          # and it moved
    print(f"scope under Xvfb: {stats}")          # the measured rate, for the record (-s)


@pytest.mark.skipif(_xvfb_missing() is not None, reason=str(_xvfb_missing()))
@pytest.mark.parametrize("nodes", [1, 3])
def test_scope_rate_in_a_window_under_xvfb(tmp_path: Path, nodes: int) -> None:
    """A benchmark, printed (-s), never asserted on: the rate the scope reaches in a TkAgg
    window drawing NODES running fake nodes for 5 s (the figure docs quote). The test asserts
    only that it drew and saw every node's telemetry."""
    r = _in_a_window(tmp_path, "rate", str(tmp_path), "5", str(nodes))
    stats = json.loads((tmp_path / "stats.json").read_text())
    assert stats["frames"] > 1
    assert all(f"node {n}" in r.stdout for n in range(1, nodes + 1)), r.stdout
    print(f"scope rate, {nodes} node(s), TkAgg under Xvfb, --fps 30: mean {stats['mean_fps']:.1f} "
          f"frames/s, last 50 frames {stats['recent_fps']:.1f} frames/s ({stats['frames']} frames)")
