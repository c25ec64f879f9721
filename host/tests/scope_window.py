# SPDX-License-Identifier: Apache-2.0
"""Runs `pmactl scope` in a real window against a fake node, for test_scope.py: the fake
node (fakenode.py, x_r a 2 s sine) RUNNING on a virtual bus in this process, the scope
through pmactl's command line, and two screenshots of the X display (PIL.ImageGrab)
taken after frames FIRST and FIRST + GAP, counted in frames drawn, not in seconds.

    python scope_window.py OUT_DIR FIRST GAP        (DISPLAY names the X server)

With `rate OUT_DIR SECONDS NODES` it measures instead: NODES fake nodes RUNNING, the scope
drawing all of them for SECONDS s without screenshots; stats.json then holds the rate the
scope reached (frames/s, its own count from the first frame drawn).
"""
from __future__ import annotations

import json
import os
import sys
import time
import uuid
from pathlib import Path

from fakenode import FakeNode
from matplotlib.backend_bases import KeyEvent
from PIL import ImageGrab

from pmactl import scope
from pmactl.cli import main


def run(out: Path, first: int, gap: int) -> int:
    shots = {first + 1: out / "shot1.png", first + gap + 1: out / "shot2.png"}
    stats: dict[str, object] = {}

    def press(sc: scope.Scope, key: str) -> None:
        canvas = sc._fig.canvas
        canvas.callbacks.process("key_press_event", KeyEvent("key_press_event", canvas, key))

    def hook(sc: scope.Scope, frames: int) -> None:
        # keys through the window's own event dispatch: space pauses and resumes, s saves
        # the view (and does not open matplotlib's save dialog, which would block here)
        if frames == 5:
            press(sc, " ")
            stats["paused_after_space"] = sc.paused
        elif frames == 8:
            press(sc, " ")
            stats["paused_after_second_space"] = sc.paused
        elif frames == 10:
            press(sc, "s")
        # the frame before this one has gone through Tk's event loop to the X server
        if frames in shots:
            ImageGrab.grab(xdisplay=os.environ["DISPLAY"]).save(shots[frames])
        stats.update(frames=frames, recent_fps=sc.rate(), full_draws=sc.full_draws)

    scope.frame_hooks.append(hook)
    channel = f"scope-window-{uuid.uuid4().hex[:8]}"
    with FakeNode(channel=channel, motion="sine") as node:
        node.set_state("RUNNING")
        code = main(["--interface", "virtual", "--channel", channel, "scope", "--host-heartbeat",
                     "--window", "4", "--frames", str(first + gap + 2)])
    (out / "stats.json").write_text(json.dumps(stats))
    return code


def rate(out: Path, seconds: float, nodes: int) -> int:
    stats: dict[str, object] = {}

    times: list[float] = []

    def hook(sc: scope.Scope, frames: int) -> None:
        times.append(time.monotonic())
        stats.update(frames=frames, recent_fps=sc.rate(),
                     mean_fps=(len(times) - 1) / (times[-1] - times[0]) if times[-1] > times[0] else 0.0)

    scope.frame_hooks.append(hook)
    channel = f"scope-rate-{uuid.uuid4().hex[:8]}"
    fakes = [FakeNode(channel=channel, node=n + 1, motion="sine").__enter__() for n in range(nodes)]
    try:
        for f in fakes:
            f.set_state("RUNNING")
        code = main(["--interface", "virtual", "--channel", channel, "scope", "--host-heartbeat",
                     "--nodes", ",".join(str(f.node) for f in fakes), "--window", "10",
                     "--seconds", f"{seconds:g}"])
    finally:
        for f in fakes:
            f.close()
    (out / "stats.json").write_text(json.dumps(stats))
    return code


if __name__ == "__main__":
    if sys.argv[1] == "rate":
        sys.exit(rate(Path(sys.argv[2]), float(sys.argv[3]), int(sys.argv[4])))
    sys.exit(run(Path(sys.argv[1]), int(sys.argv[2]), int(sys.argv[3])))
