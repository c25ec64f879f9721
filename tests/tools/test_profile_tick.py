# SPDX-License-Identifier: Apache-2.0
"""tools/profile_tick.py on a synthetic QEMU trace and link map: the timed windows, the
instructions of each translated block counted each time it runs, and the owner of an address."""
from __future__ import annotations

import subprocess
import sys
from pathlib import Path

from pma_tools import profile_tick

TOOL = Path(__file__).resolve().parents[2] / "tools" / "profile_tick.py"


def block(pc: int, func: str, n: int, host: int) -> str:
    """A block's translation (n instructions) and its first run."""
    insns = "".join(f"0x{pc + 2 * k:08x}:  46c0      nop\n" for k in range(n))
    return f"----------------\nIN: {func}\n{insns}\n" + run(pc, func, host)


def run(pc: int, func: str, host: int) -> str:
    return f"Trace 0: 0x{host:x} [00800400/{pc:08x}/00000510/ff020200] {func}\n"


def test_windows_count_blocks_per_run_between_the_timer_calls(tmp_path: Path) -> None:
    log = tmp_path / "exec.log"
    text = block(0x100, "setup", 9, 0x7000)                         # before any window: ignored
    text += block(0x200, "pma_board_timer_start", 3, 0x7100)
    text += block(0x210, "pma_board_timer_start", 2, 0x7200)        # its second block: same window
    text += block(0x300, "loop", 4, 0x7300) + run(0x300, "loop", 0x7300)
    text += block(0x400, "pma_board_timer_elapsed_ns", 5, 0x7400)
    text += run(0x200, "pma_board_timer_start", 0x7100)
    text += run(0x300, "loop", 0x7300) + block(0x500, "tick", 7, 0x7500) + run(0x500, "tick", 0x7500)
    text += run(0x400, "pma_board_timer_elapsed_ns", 0x7400)
    text += run(0x300, "loop", 0x7300)                              # after the windows: ignored
    log.write_text(text)
    wins = profile_tick.windows(log)
    assert [dict(w) for w in wins] == [{"loop": 8}, {"loop": 4, "tick": 14}]


def test_owners_from_a_gnu_ld_map(tmp_path: Path) -> None:
    m = tmp_path / "x.map"
    m.write_text(
        "Memory Configuration\n\n"
        ".text           0x00000000     0x9000\n"
        " .text.law\n"
        "                0x00001000      0x200 firmware/control/libpma_control.a(ppc_q16.c.obj)\n"
        " .text.step     0x00001200       0x80 firmware/app/libpma_app.a(app.c.obj)\n"
        " .text          0x00002000       0x90 /usr/lib/arm-none-eabi/lib/libg.a(lib_a-memcpy-stub.o)\n"
        " .text.empty    0x00003000        0x0 firmware/app/libpma_app.a(x.c.obj)\n"
        " .text.main     0x00004000       0x40 tests/bench/CMakeFiles/b.dir/bench_app_tick.c.obj\n"
        ".data           0x20000000       0x10\n"
        " .data.x        0x20000000       0x10 firmware/app/libpma_app.a(app.c.obj)\n")
    owners = profile_tick.code_owners(m)
    assert profile_tick.owner_of(owners, 0x1000) == "libpma_control.a"
    assert profile_tick.owner_of(owners, 0x11FF) == "libpma_control.a"
    assert profile_tick.owner_of(owners, 0x1200) == "libpma_app.a"
    assert profile_tick.owner_of(owners, 0x2010) == "libg.a"
    assert profile_tick.owner_of(owners, 0x4002) == "bench_app_tick.c.obj"
    assert profile_tick.owner_of(owners, 0x3000) == "?"          # an empty section owns nothing
    assert profile_tick.owner_of(owners, 0x0FFF) == "?"
    assert profile_tick.owner_of(owners, 0x20000000) == "?"      # data is not code


def test_bad_options_exit_2(tmp_path: Path) -> None:
    for args in (["--ticks", "0"], ["--by", "file"], ["--elf", str(tmp_path / "none.elf")]):
        r = subprocess.run([sys.executable, str(TOOL), *args], capture_output=True, text=True, check=False)
        assert r.returncode == 2, args
        assert "error" in r.stderr
