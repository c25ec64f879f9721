#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Worst-case stack of the board image, from GCC's call-graph files (-fcallgraph-info=su,
one .ci per object of the stm32g474 build): each function's own frame and its direct calls.

The deepest path from the reset handler (through main and the loop) plus, on top of it,
every interrupt handler's deepest path and its exception frame (an interrupt may come at the
deepest point of the loop; the handlers are counted as if all of them nested, which bounds the
port's own priorities), against the stack the linker script reserves. It prints each deepest
path with its frames, and what it could not count: calls through a pointer, recursion,
functions without a frame size (the C library's, the compiler's run-time), and frames of
dynamic size. Exits 1 when the bound exceeds --stack-bytes.

  tools/stack_report.py BUILD_DIR --map IMAGE.map [--stack-bytes 4096] [--root Reset_Handler]
                        [--isr NAME ...] [--frame-bytes 104]

Only the objects the linker put into the image count (from its map file: the objects it loaded
and the archive members it took), so that another port's function of the same name, built in
the same tree, is not mistaken for the board's. A static function is named FILE:NAME in the
call graph; --root and --isr match it by NAME too.
"""
from __future__ import annotations

import argparse
import re
import sys
from dataclasses import dataclass, field
from pathlib import Path

NODE_RE = re.compile(r'node: \{ title: "([^"]+)" label: "([^"]*)"')
EDGE_RE = re.compile(r'edge: \{ sourcename: "([^"]+)" targetname: "([^"]+)"')
BYTES_RE = re.compile(r"(\d+) bytes \((static|dynamic|dynamic,bounded)\)")
LOAD_RE = re.compile(r"^LOAD (\S+\.obj)$", re.M)
MEMBER_RE = re.compile(r"^(\S+)/lib(\w+)\.a\((\S+\.obj)\)$", re.M)
# the handlers of hal/portable/st/stm32g474/startup_stm32g474.c the port enables
DEFAULT_ISRS = ("NMI_Handler", "HardFault_Handler", "TIM2_IRQHandler", "TIM6_DAC_IRQHandler",
                "FDCAN1_IT0_IRQHandler")
# the Cortex-M4F's exception frame with the FPU context (26 words)
FRAME_BYTES = 104


@dataclass
class Graph:
    frame: dict[str, int] = field(default_factory=dict)       # function -> own frame [bytes]
    where: dict[str, str] = field(default_factory=dict)       # function -> file:line
    dynamic: set[str] = field(default_factory=set)
    calls: dict[str, set[str]] = field(default_factory=dict)

    def read(self, path: Path) -> None:
        text = path.read_text(errors="replace")
        for name, label in NODE_RE.findall(text):
            parts = label.split("\\n")
            m = BYTES_RE.search(label)
            if m:
                self.frame[name] = int(m.group(1))
                if m.group(2) != "static":
                    self.dynamic.add(name)
                if len(parts) > 1:
                    self.where[name] = parts[1]
            self.calls.setdefault(name, set())
        for src, dst in EDGE_RE.findall(text):
            self.calls.setdefault(src, set()).add(dst)


@dataclass
class CallPath:
    bytes: int
    chain: list[str]


def deepest(g: Graph, root: str, unknown: set[str], recursive: set[str]) -> CallPath:
    memo: dict[str, CallPath] = {}
    active: set[str] = set()

    def walk(fn: str) -> CallPath:
        if fn in memo:
            return memo[fn]
        if fn in active:
            recursive.add(fn)
            return CallPath(0, [fn])
        active.add(fn)
        own = g.frame.get(fn)
        if own is None:
            unknown.add(fn)
            own = 0
        best = CallPath(0, [])
        for callee in sorted(g.calls.get(fn, ())):
            if callee.startswith("__indirect_call"):
                unknown.add(f"{fn} -> (a call through a pointer)")
                continue
            p = walk(callee)
            if p.bytes > best.bytes:
                best = p
        active.discard(fn)
        memo[fn] = CallPath(own + best.bytes, [fn] + best.chain)
        return memo[fn]

    return walk(root)


def linked_call_graphs(build_dir: Path, map_file: Path) -> list[Path]:
    """The .ci file of every object in the image (the map's LOAD lines and archive members,
    an archive's member found under CMakeFiles/<library>.dir/)."""
    text = map_file.read_text(errors="replace")
    out: set[Path] = set()
    for obj in LOAD_RE.findall(text):
        out.add(build_dir / obj)
    for lib_dir, lib, member in MEMBER_RE.findall(text):
        out.update((build_dir / lib_dir / "CMakeFiles" / f"{lib}.dir").rglob(member))
    return sorted(p.with_name(p.name[: -len(".obj")] + ".ci") for p in out)


def resolve(g: Graph, name: str) -> str | None:
    """A function by its name, also a static one (FILE:NAME)."""
    if name in g.frame:
        return name
    found = [f for f in g.frame if f.endswith(":" + name)]
    return found[0] if len(found) == 1 else None


def show(g: Graph, p: CallPath) -> str:
    return "\n".join(f"    {g.frame.get(f, 0):5d} B  {f.rsplit(':', 1)[-1]}  {_short(g.where.get(f, ''))}".rstrip()
                     for f in p.chain)


def _short(where: str) -> str:
    """file:line:column from the repository's root (the .ci files hold absolute paths)."""
    root = str(Path(__file__).resolve().parents[1]) + "/"
    return where[len(root):] if where.startswith(root) else where


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("build_dir", type=Path)
    ap.add_argument("--map", type=Path, required=True, help="the image's linker map (-Wl,-Map)")
    ap.add_argument("--stack-bytes", type=int, default=4096, help="the stack the linker script reserves")
    ap.add_argument("--root", default="Reset_Handler")
    ap.add_argument("--isr", action="append", help="an interrupt handler (default: the port's)")
    ap.add_argument("--frame-bytes", type=int, default=FRAME_BYTES, help="exception frame per interrupt")
    a = ap.parse_args()
    files = linked_call_graphs(a.build_dir, a.map)
    missing = [f for f in files if not f.exists()]
    if not files or missing:
        print(f"stack_report: {len(missing)} of {len(files)} call-graph files missing (build with "
              f"-fcallgraph-info=su), e.g. {missing[:1]}", file=sys.stderr)
        return 2
    g = Graph()
    for f in files:
        g.read(f)
    root = resolve(g, a.root)
    if root is None:
        print(f"stack_report: {a.root} not found in {len(files)} call-graph files", file=sys.stderr)
        return 2
    unknown: set[str] = set()
    recursive: set[str] = set()
    loop = deepest(g, root, unknown, recursive)
    handlers = [(n, resolve(g, n)) for n in (a.isr or DEFAULT_ISRS)]
    lost = [n for n, fn in handlers if fn is None]
    if lost:
        print(f"stack_report: interrupt handler(s) {', '.join(lost)} not found", file=sys.stderr)
        return 2
    isrs = [(n, deepest(g, fn, unknown, recursive)) for n, fn in handlers if fn is not None]
    isr_total = sum(p.bytes + a.frame_bytes for _, p in isrs)
    total = loop.bytes + isr_total
    print(f"stack report ({len(files)} call-graph files): worst case {total} of {a.stack_bytes} bytes "
          f"({100 * total / a.stack_bytes:.0f} %)")
    print(f"  the loop, from {a.root}: {loop.bytes} B, deepest path:")
    print(show(g, loop))
    for n, p in isrs:
        print(f"  {n}: {p.bytes} B + {a.frame_bytes} B exception frame, deepest path:")
        print(show(g, p))
    not_counted = sorted(unknown | {f"{f} (dynamic frame)" for f in g.dynamic} |
                         {f"{f} (recursion)" for f in recursive})
    if not_counted:
        print(f"  not counted ({len(not_counted)}): " + ", ".join(not_counted))
    if total > a.stack_bytes:
        print(f"stack_report: the worst case {total} B exceeds the {a.stack_bytes} B stack", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
