# SPDX-License-Identifier: Apache-2.0
"""tools/stack_report.py on a synthetic build tree: GCC call-graph files (.ci) of the objects
a map file says are in the image, and one of another port that is not."""
from __future__ import annotations

import subprocess
import sys
from pathlib import Path

TOOL = Path(__file__).resolve().parents[2] / "tools" / "stack_report.py"


def node(name: str, frame: int | None, where: str = "x.c:1:1") -> str:
    label = f"{name.rsplit(':', 1)[-1]}\\n{where}" + (f"\\n{frame} bytes (static)" if frame is not None else "")
    return f'node: {{ title: "{name}" label: "{label}" }}\n'


def edge(a: str, b: str) -> str:
    return f'edge: {{ sourcename: "{a}" targetname: "{b}" label: "x.c:2:3" }}\n'


def tree(tmp: Path) -> tuple[Path, Path]:
    app = tmp / "app/CMakeFiles/pma_app.dir"
    port = tmp / "hal/CMakeFiles/pma_hal_board.dir"
    fake = tmp / "hal/CMakeFiles/pma_hal_fake.dir"
    for d in (app, port, fake, tmp / "img"):
        d.mkdir(parents=True)
    (tmp / "img/start.c.ci").write_text(
        "graph: {\n" + node("Reset_Handler", 8) + edge("Reset_Handler", "main") + node("main", None)
        + node("start.c:TIM_IRQHandler", 0) + edge("start.c:TIM_IRQHandler", "tick_isr") + "}\n")
    (app / "app.c.ci").write_text(
        "graph: {\n" + node("main", 32) + edge("main", "step") + edge("main", "small")
        + node("step", 100) + edge("step", "nvm_read") + edge("step", "memcpy")
        + node("small", 50) + "}\n")
    (port / "port.c.ci").write_text(
        "graph: {\n" + node("nvm_read", 200) + node("tick_isr", 16) + "}\n")
    (fake / "fake.c.ci").write_text("graph: {\n" + node("nvm_read", 3000) + "}\n")   # not linked
    for ci in tmp.rglob("*.ci"):                 # the objects beside their call graphs
        ci.with_name(ci.name[: -len(".ci")] + ".obj").write_bytes(b"")
    mp = tmp / "img/image.map"
    mp.write_text("Archive member included to satisfy reference by file (symbol)\n\n"
                  "app/libpma_app.a(app.c.obj)\n                              img/start.c.obj (main)\n"
                  "hal/libpma_hal_board.a(port.c.obj)\n                              app/libpma_app.a(app.c.obj)\n\n"
                  "LOAD img/start.c.obj\nLOAD app/libpma_app.a\nLOAD hal/libpma_hal_board.a\n")
    return tmp, mp


def run(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, str(TOOL), *args], capture_output=True, text=True, check=False)


def test_worst_case_is_the_deepest_linked_path_with_the_interrupts_on_top(tmp_path: Path) -> None:
    build, mp = tree(tmp_path)
    r = run(str(build), "--map", str(mp), "--isr", "TIM_IRQHandler", "--stack-bytes", "1024")
    assert r.returncode == 0, r.stderr
    # loop: Reset 8 + main 32 + step 100 + nvm_read 200 (the board's, not the fake's 3000);
    # the interrupt: 0 + tick_isr 16 + the 104 B exception frame
    assert "worst case 460 of 1024 bytes" in r.stdout, r.stdout
    assert "from Reset_Handler: 340 B" in r.stdout and "TIM_IRQHandler: 16 B + 104 B" in r.stdout
    assert "not counted (1): memcpy" in r.stdout


def test_over_the_stack_fails_and_a_missing_handler_is_an_error(tmp_path: Path) -> None:
    build, mp = tree(tmp_path)
    r = run(str(build), "--map", str(mp), "--isr", "TIM_IRQHandler", "--stack-bytes", "400")
    assert r.returncode == 1 and "exceeds the 400 B stack" in r.stderr
    r = run(str(build), "--map", str(mp), "--isr", "NOPE_IRQHandler")
    assert r.returncode == 2 and "NOPE_IRQHandler not found" in r.stderr
    (tmp_path / "app/CMakeFiles/pma_app.dir/app.c.ci").unlink()
    r = run(str(build), "--map", str(mp), "--isr", "TIM_IRQHandler")
    assert r.returncode == 2 and "call-graph files missing" in r.stderr
