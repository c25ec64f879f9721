# SPDX-License-Identifier: Apache-2.0
"""Where the application's tick spends its instructions, per function, on an emulated core.

Runs a benchmark ELF (default: the Cortex-M0 build's ``bench_app_tick``) under QEMU with
``-icount shift=0 -d in_asm,exec,nochain`` and counts the guest instructions of every translated
block each time it runs. ``bench_app_tick`` times each case as two windows opened by
``pma_board_timer_start``: the loop without the tick, then the loop with it. This tool
subtracts the first from the second, function by function, and divides by the number of
ticks. The result is the tick's instructions per function. Its total matches the benchmark's
printed figure to within the timer calls.

    python tools/profile_tick.py [--elf build/cortex-m0/tests/bench/bench_app_tick.elf]
                                 [--machine microbit] [--ticks 2048] [--top 30]
                                 [--by function|library]

``--by library`` sums the functions by the library (archive) their code was linked from, read
from the link map beside the ELF (``<name>.map``): the control library, the application, the
fake HAL, the C and compiler runtime (memcpy, the division routines) and the benchmark itself.

Prints figures; asserts nothing. The trace of a whole run is about 400 MB, written to a
temporary file and deleted afterwards.
"""

from __future__ import annotations

import argparse
import collections
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
WINDOW_START = "pma_board_timer_start"
WINDOW_END = "pma_board_timer_elapsed_ns"

_TRACE = re.compile(r"^Trace \d+: (0x[0-9a-f]+) \[[0-9a-f]+/([0-9a-f]+)/[0-9a-f]+/[0-9a-f]+\] (\S*)")
_INSN = re.compile(r"^0x[0-9a-f]+:\s")
# a section placed by the linker: "<name> 0xADDR 0xSIZE path[(member)]", the name perhaps on the
# line before
_PLACED = re.compile(r"^\s*(?:\.\S+)?\s+0x([0-9a-f]+)\s+0x([0-9a-f]+)\s+(\S+)$")


def code_owners(map_file: Path) -> list[tuple[int, int, str]]:
    """(start, end, library) of every code section in a GNU ld map, sorted by start."""
    out: list[tuple[int, int, str]] = []
    in_text = False
    for line in map_file.read_text(errors="replace").splitlines():
        if line.startswith(".text"):
            in_text = True
        elif line.startswith(".") and not line.startswith(".text"):
            in_text = False
        if not in_text:
            continue
        m = _PLACED.match(line)
        if m is None or int(m.group(2), 16) == 0:
            continue
        start = int(m.group(1), 16)
        path = m.group(3)
        lib = path.split("(")[0].rsplit("/", 1)[-1] if "(" in path else path.rsplit("/", 1)[-1]
        out.append((start, start + int(m.group(2), 16), lib))
    return sorted(out)


def owner_of(owners: list[tuple[int, int, str]], pc: int) -> str:
    lo, hi = 0, len(owners)
    while lo < hi:   # the last section starting at or before pc
        mid = (lo + hi) // 2
        if owners[mid][0] <= pc:
            lo = mid + 1
        else:
            hi = mid
    if lo and pc < owners[lo - 1][1]:
        return owners[lo - 1][2]
    return "?"


def windows(log: Path, owners: list[tuple[int, int, str]] | None = None) -> list[collections.Counter[str]]:
    """Instructions per function (per library with owners) in each timed window of the run."""
    sizes: dict[tuple[str, str], int] = {}
    pending = 0
    out: list[collections.Counter[str]] = []
    current: collections.Counter[str] | None = None
    with log.open(errors="replace") as f:
        for line in f:
            if line.startswith("IN:"):
                pending = 0
                continue
            if _INSN.match(line):
                pending += 1
                continue
            m = _TRACE.match(line)
            if m is None:
                continue
            key = (m.group(1), m.group(2))
            if pending:
                sizes[key] = pending
                pending = 0
            func = m.group(3) or "?"
            if func == WINDOW_START:
                if current is None:   # the function's first block opens the window
                    current = collections.Counter()
                    out.append(current)
            elif func == WINDOW_END:
                current = None
            elif current is not None:
                what = func if owners is None else owner_of(owners, int(m.group(2), 16))
                current[what] += sizes.get(key, 0)
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--elf", type=Path,
                    default=ROOT / "build/cortex-m0/tests/bench/bench_app_tick.elf")
    ap.add_argument("--machine", default="microbit", help="QEMU machine (microbit: M0, mps2-an385: M3)")
    ap.add_argument("--ticks", type=int, default=2048, help="ticks per window (bench_app_tick's N)")
    ap.add_argument("--top", type=int, default=30, help="functions to list per case")
    ap.add_argument("--by", choices=["function", "library"], default="function",
                    help="sum per function or per library (from the link map beside the ELF)")
    args = ap.parse_args(argv)
    if not args.elf.is_file():
        ap.error(f"{args.elf}: no such ELF (build it: cmake --build --preset cortex-m0)")
    if args.ticks <= 0 or args.top <= 0:
        ap.error("--ticks and --top must be positive")
    owners = None
    if args.by == "library":
        map_file = args.elf.with_suffix(".map")
        if not map_file.is_file():
            ap.error(f"{map_file}: no link map beside the ELF")
        owners = code_owners(map_file)
    qemu = shutil.which("qemu-system-arm")
    if qemu is None:
        ap.error("qemu-system-arm not found (Debian: apt-get install qemu-system-arm)")
    with tempfile.TemporaryDirectory() as tmp:
        log = Path(tmp) / "exec.log"
        run = subprocess.run(
            [qemu, "-M", args.machine, "-nographic", "-monitor", "none", "-serial", "none",
             "-semihosting-config", "enable=on,target=native", "-icount", "shift=0",
             "-d", "in_asm,exec,nochain", "-D", str(log), "-kernel", str(args.elf)],
            capture_output=True, text=True, check=False, timeout=600)
        if run.returncode != 0:
            print(run.stdout + run.stderr, file=sys.stderr)
            return run.returncode
        names = [ln.split(" ")[2] for ln in run.stdout.splitlines() if ln.startswith("BENCH ")]
        wins = windows(log, owners)
    if len(wins) % 2 or not wins:
        print(f"expected pairs of timed windows, found {len(wins)}", file=sys.stderr)
        return 1
    for i in range(0, len(wins), 2):
        empty, full = wins[i], wins[i + 1]
        diff = {fn: (full[fn] - empty.get(fn, 0)) / args.ticks for fn in full}
        total = sum(diff.values())
        name = names[i // 2] if i // 2 < len(names) else f"case {i // 2}"
        print(f"\n{name}: {total:,.0f} instructions/tick")
        for fn, n in sorted(diff.items(), key=lambda kv: -kv[1])[: args.top]:
            if abs(n) >= 0.5:
                print(f"  {n:8.1f}  {fn}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
