#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Golden-vector and cost report of the control library.

Runs, for every preset that has been built (tools/build-all.sh):
  - the golden-vector tests (CTest, label-free: tests named test_golden_*),
    collecting their `GOLDEN ...` summary lines;
  - the benchmarks (`cmake --build --preset P --target bench`; under QEMU with
    -icount shift=0, so Cortex-M figures are exact instruction counts),
    collecting their `BENCH ...` lines;
  - the code size of each control-library object (arm-none-eabi-size).
and prints them as tables, with the issue's cost targets next to the figures.
Figures are printed, never asserted.

Usage: python tools/report.py [--presets host,cortex-m4f,...] [--markdown FILE]
"""
from __future__ import annotations

import argparse
import re
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
PRESETS = ["host", "cortex-m4f", "cortex-m3", "cortex-m0"]
ARM = ["cortex-m4f", "cortex-m3", "cortex-m0"]
# the application's whole tick in both arithmetics of its controller slot (PMA_CTRL_ARITH):
# the presets' defaults (float on host and M4F, Q16.16 on M3 and M0) and the Q16.16 presets
APP_PRESETS = ["cortex-m4f", "cortex-m4f-q16", "cortex-m3", "cortex-m0"]   # instructions (QEMU -icount)
APP_TICK_TARGETS = [("app_tick_q16", "cortex-m0", 3000)]   # instructions per tick (issue)
# the libraries of the application's image (bench_app_tick's link map; the fake HAL,
# Unity-free bench code and libc are not counted)
APP_LIBS = ["pma_app", "pma_control", "pma_proto", "pma_storage", "pma_common"]

# (benchmark name, preset, max instructions per step) from the issue
TARGETS = [
    ("ppc_f32(t>=t_u)", "cortex-m4f", 400),
    ("ppc_f32(t<t_u)", "cortex-m4f", 400),
    ("ppc_q16(t>=t_u)", "cortex-m0", 1500),
    ("ppc_q16(t<t_u)", "cortex-m0", 1500),
    ("mfac_f32", "cortex-m4f", 150),
]

# Control-library objects grouped by module (shared objects listed separately).
MODULES = {
    "ppc_f32": ["ppc_f32", "trig_f32"],
    "ppc_q16": ["ppc_q16"],
    "ppc config (shared)": ["ppc_config"],
    "mfac_f32 + config": ["mfac"],
    "mfac_q16": ["mfac_q16"],
    "pid_f32 + config": ["pid"],
    "pid_q16": ["pid_q16"],
    "velest_f32 + config": ["velest"],
    "velest_q16": ["velest_q16"],
    "ref_f32 + config + band": ["ref"],
    "ref_q16": ["ref_q16"],
    "fixed-point math (shared)": ["fixed"],
    "status names": ["status"],
}


def run(cmd: list[str]) -> str:
    proc = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True)
    if proc.returncode != 0:
        sys.stderr.write(proc.stdout[-3000:] + proc.stderr[-3000:])
        raise SystemExit(f"report: command failed ({proc.returncode}): {' '.join(cmd)}")
    return proc.stdout + proc.stderr


def built(preset: str) -> bool:
    return (ROOT / "build" / preset / "build.ninja").exists()


def golden_lines(preset: str) -> list[str]:
    out = run(["ctest", "--preset", preset, "-R", "^test_golden_", "-V"])
    return [m.group(0) for m in re.finditer(r"GOLDEN [^\r\n]*", out)]


def bench_lines(preset: str) -> tuple[dict[str, float], list[str]]:
    """Cost per step by benchmark name, and the ACCURACY lines."""
    out = run(["cmake", "--build", "--preset", preset, "--target", "bench"])
    figures: dict[str, float] = {}
    for m in re.finditer(r"^BENCH (\S+) (\S+) (-?[0-9.]+) (\S+)/step", out, re.M):
        figures[m.group(2)] = float(m.group(3))
    accuracy = [m.group(1) for m in re.finditer(r"^ACCURACY \S+ (.*)$", out, re.M)]
    return figures, accuracy


def app_tick_lines(preset: str) -> tuple[dict[str, float], int | None]:
    """bench_app_tick's figures: 'app_tick_<arith>(<case>)' -> instructions (ns on host) per
    tick, and sizeof(pma_app_t) [bytes]."""
    out = run(["cmake", "--build", "--preset", preset, "--target", "run-bench_app_tick"])
    size = re.search(r"^SIZE \S+ pma_app_t ([0-9]+) bytes", out, re.M)
    return ({m.group(2): float(m.group(3))
             for m in re.finditer(r"^BENCH (\S+) (app_tick_\S+) (-?[0-9.]+) (\S+)/tick", out, re.M)},
            int(size.group(1)) if size else None)


def app_memory(preset: str) -> dict[str, int] | None:
    """Flash (.text, .rodata, .data) and RAM (.data, .bss) of the application's libraries as
    linked into bench_app_tick (its map: the sections --gc-sections kept), bytes."""
    path = ROOT / "build" / preset / "tests/bench/bench_app_tick.map"
    if not path.exists():
        return None
    text = path.read_text()
    text = text[text.find("Linker script and memory map"):]
    libs = "|".join(APP_LIBS)
    flash = ram = 0
    pat = (r"^ (\.(?:text|rodata|data|bss)\S*)\s+0x[0-9a-f]+\s+0x([0-9a-f]+) "
           rf"\S*lib(?:{libs})\.a\(")
    for m in re.finditer(pat, text.replace("\n                ", " "), re.M):
        section, size = m.group(1), int(m.group(2), 16)
        if section.startswith((".text", ".rodata")):
            flash += size
        elif section.startswith(".data"):
            flash += size
            ram += size
        else:
            ram += size
    return {"flash": flash, "ram": ram}


def code_sizes(preset: str) -> dict[str, int]:
    # the control library and the base library below it (the status names)
    objs = []
    for lib in ("control/CMakeFiles/pma_control.dir", "common/CMakeFiles/pma_common.dir"):
        objdir = ROOT / "build" / preset / "firmware" / lib / "src"
        objs += sorted(objdir.glob("*.obj")) or sorted(objdir.glob("*.o"))
    if not objs:
        return {}
    out = run(["arm-none-eabi-size", *map(str, objs)])
    sizes: dict[str, int] = {}
    for line in out.splitlines()[1:]:
        parts = line.split()
        if len(parts) >= 6:
            text, data = int(parts[0]), int(parts[1])
            sizes[Path(parts[5]).name.split(".")[0]] = text + data
    return sizes


def table(header: list[str], rows: list[list[str]]) -> str:
    widths = [max(len(r[i]) for r in [header, *rows]) for i in range(len(header))]
    fmt = lambda r: "| " + " | ".join(c.ljust(w) for c, w in zip(r, widths)) + " |"
    sep = "|" + "|".join("-" * (w + 2) for w in widths) + "|"
    return "\n".join([fmt(header), sep, *map(fmt, rows)])


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--presets", default=",".join(PRESETS),
                    help="comma-separated presets (default: all four)")
    ap.add_argument("--markdown", type=Path, help="also write the report to this file")
    args = ap.parse_args()
    presets = [p for p in args.presets.split(",") if p]
    if not presets:
        ap.error("--presets names no preset (choose from " + ", ".join(PRESETS) + ")")
    if args.markdown is not None and (str(args.markdown) == "" or args.markdown.is_dir()
                                      or not args.markdown.parent.is_dir()):
        ap.error(f"--markdown {str(args.markdown)!r}: not a file in an existing folder")
    unknown = [p for p in presets if p not in PRESETS]
    if unknown:
        ap.error(f"unknown preset(s): {', '.join(unknown)} (choose from {', '.join(PRESETS)})")
    missing = [p for p in presets if not built(p)]
    if missing:
        ap.error(f"not built: {', '.join(missing)} (run tools/build-all.sh first)")

    parts: list[str] = []
    say = parts.append

    say("## Golden vectors (numpy double reference vs C, per preset)\n")
    golden = {p: golden_lines(p) for p in presets}
    ref = golden[presets[0]]
    for p in presets[1:]:
        same = golden[p] == ref
        say(f"- {p}: {len(golden[p])} summary lines, "
            f"{'identical to' if same else 'DIFFERENT from'} {presets[0]}")
    say("")
    say("```")
    say("\n".join(ref) if ref else "(no GOLDEN lines: golden tests not built)")
    say("```\n")

    say("## Cost per control step (Cortex-M: instructions, QEMU -icount shift=0; host: ns)\n")
    results = {p: bench_lines(p) for p in presets}
    bench = {p: results[p][0] for p in presets}
    names = list(dict.fromkeys(n for p in presets for n in bench[p]))
    cell = lambda v: "-" if v is None or v < 0 else f"{v:.0f}"   # < 0: below timer resolution
    say(table(["step", *presets], [[n, *(cell(bench[p].get(n)) for p in presets)] for n in names]))
    say("")
    say("Targets:\n")
    rows = []
    for name, preset, limit in TARGETS:
        got = bench.get(preset, {}).get(name)
        verdict = "n/a" if got is None else ("met" if got <= limit else "MISSED")
        rows.append([name, preset, str(limit), "-" if got is None else f"{got:.0f}", verdict])
    say(table(["step", "core", "target", "measured", ""], rows))
    say("")

    say("## Accuracy against the double reference (u over all golden sets)\n")
    acc = {p: results[p][1] for p in presets}
    for p in presets[1:]:
        say(f"- {p}: {'identical to' if acc[p] == acc[presets[0]] else 'DIFFERENT from'} {presets[0]}")
    say("")
    say("```")
    say("\n".join(acc[presets[0]]))
    say("```\n")

    arm = [p for p in presets if p in ARM]
    if arm:
        say("## Code size of each module (.text + .data of its objects, bytes)\n")
        sizes = {p: code_sizes(p) for p in arm}
        rows = [[m, *(str(sum(sizes[p].get(o, 0) for o in objs)) for p in arm)]
                for m, objs in MODULES.items()]
        say(table(["module", *arm], rows))
        say("")
    app = [p for p in APP_PRESETS if built(p)]
    if app:
        say("## Cost of a whole tick of the application (bench_app_tick)\n")
        say("pma_app_step on the fake HAL (about 300 instructions a tick of it are the fake's own "
            "bookkeeping: its CAN controller's bus-state update on every call, its frame queues and "
            "the benchmark's pops of the sent frames; `tools/profile_tick.py --by library` shows the "
            "split), RUNNING a HOLD with the sensor's counts alternating by one count "
            "from tick to tick (a still sample would let the law's input settle and skip MFAC's "
            "divisions: the cheapest tick, not the one a budget needs): sample and scaling, "
            "estimator, controller, supervisor, actuator and DAC, heartbeat and telemetry at their "
            "decimation. Instructions per tick (QEMU -icount); the arithmetic is the controller "
            "slot's.\n")
        got_ticks = {p: app_tick_lines(p) for p in app}
        ticks = {p: t for p, (t, _) in got_ticks.items()}
        cases = list(dict.fromkeys(n.split("(", 1)[1] for p in app for n in ticks[p]))
        rows = []
        for p in app:
            arith = next((n.split("(")[0].removeprefix("app_tick_") for n in ticks[p]), "-")
            rows.append([p, arith, *(cell(next((v for n, v in ticks[p].items() if n.endswith(f"({c}")), None))
                                     for c in cases)])
        say(table(["preset", "slot", *(c.rstrip(")") for c in cases)], rows))
        say("")
        rows = []
        for name, preset, limit in APP_TICK_TARGETS:
            got = [v for n, v in ticks.get(preset, {}).items() if n.startswith(name)]
            worst = max(got) if got else None
            verdict = "n/a" if worst is None else ("met" if worst <= limit else "MISSED")
            rows.append([name, preset, str(limit), "-" if worst is None else f"{worst:.0f}", verdict])
        say("Target (the worst case above):\n")
        say(table(["tick", "core", "target", "measured", ""], rows))
        say("")
        mem = {p: app_memory(p) for p in app}
        rows = [[p, str(m["flash"]), str(m["ram"]), str(got_ticks[p][1] or "-")]
                for p, m in mem.items() if m is not None]
        if rows:
            say("Memory of the application: flash of its libraries as linked (" + ", ".join(APP_LIBS) +
                "; bench_app_tick's map, after --gc-sections) and RAM: their static data (none: no "
                "globals) and pma_app_t, which the program holds (the stack comes on top), bytes:\n")
            say(table(["preset", "flash", "static RAM", "pma_app_t"], rows))
            say("")
    text = "\n".join(parts)
    print(text)
    if args.markdown:
        args.markdown.write_text(text + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
