#!/usr/bin/env python3
"""Checks the STM32G474 port's own register definitions against ST's SVD.

Every macro of hal/portable/st/stm32g474/g4_regs.h that follows the naming
scheme documented at its top is compared with the SVD (xml.etree, nothing
else): peripheral base addresses, register offsets, bit field positions and
widths, interrupt numbers, and G4_<P>_SAME_LAYOUT_AS_<Q> claims.

Usage: check_svd_regs.py [--svd PATH] [--header PATH]
  default SVD: ../shared/data/svd/STM32G474xx.svd beside the repository.
Exit status: 0 all checked and equal; 1 a mismatch (each printed);
             2 the SVD file is absent (nothing checked; the message says so).
"""
from __future__ import annotations

import argparse
import re
import sys
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DEFAULT_SVD = ROOT.parent / "shared/data/svd/STM32G474xx.svd"
DEFAULT_HEADER = ROOT / "hal/portable/st/stm32g474/g4_regs.h"
PREFIX = "G4_"
EXIT_NO_SVD = 2

# Blocks with a base address in the header whose contents the SVD does not
# describe; only the base is checked, against the SVD block named here.
NOT_DESCRIBED = {
    "MRAM": ("FDCAN", "FDCAN message RAM: the SVD puts a copy of the FDCAN "
                      "controller registers at this address, not the RAM layout (RM0440 44.3.3)"),
}

DEFINE_RE = re.compile(r"^\s*#define\s+(G4_\w+)\s+(.*?)\s*(?:/\*.*)?$")
NUM_RE = re.compile(r"^\(?\s*(0x[0-9A-Fa-f]+|\d+)u?\s*\)?$")
MSK_RE = re.compile(r"^\(\s*(0x[0-9A-Fa-f]+|\d+)u?\s*<<\s*(G4_\w+_Pos)\s*\)$")


@dataclass
class SvdPeripheral:
    name: str
    base: int
    registers: dict[str, tuple[int, dict[str, tuple[int, int]]]] = field(default_factory=dict)


def _int(text: str) -> int:
    return int(text.strip(), 0)


def load_svd(path: Path) -> tuple[dict[str, SvdPeripheral], dict[str, int]]:
    """Peripherals by upper-case name (derivedFrom resolved) and interrupts."""
    root = ET.parse(path).getroot()
    raw = {p.findtext("name"): p for p in root.iter("peripheral")}
    out: dict[str, SvdPeripheral] = {}
    irqs: dict[str, int] = {}
    for name, p in raw.items():
        src = p
        seen = set()
        while src.get("derivedFrom") and src.find("registers") is None:
            parent = src.get("derivedFrom")
            if parent in seen:
                break
            seen.add(parent)
            src = raw[parent]
        per = SvdPeripheral(name, _int(p.findtext("baseAddress")))
        prefixes = {src.findtext("name").upper() + "_", name.upper() + "_",
                    re.sub(r"\d+$", "", name.upper()) + "_"}
        for r in src.iter("register"):
            rname = r.findtext("name").upper()
            fields = {f.findtext("name").upper(): (_int(f.findtext("bitOffset")),
                                                   _int(f.findtext("bitWidth")))
                      for f in r.iter("field")}
            entry = (_int(r.findtext("addressOffset")), fields)
            per.registers[rname] = entry
            for pre in prefixes:  # RCC_CR is CR; DAC1's DAC_MCR is MCR
                if rname.startswith(pre) and len(rname) > len(pre):
                    per.registers.setdefault(rname[len(pre):], entry)
        out[name.upper()] = per
        for i in p.findall("interrupt"):
            irqs[i.findtext("name").upper()] = _int(i.findtext("value"))
    return out, irqs


def parse_header(path: Path) -> dict[str, str]:
    defs: dict[str, str] = {}
    for line in path.read_text().splitlines():
        m = DEFINE_RE.match(line)
        if m:
            defs[m.group(1)] = m.group(2).strip()
    return defs


def check(svd_path: Path, header: Path) -> tuple[list[str], dict[str, int]]:
    """Returns (errors, counts of what was checked)."""
    svd, irqs = load_svd(svd_path)
    defs = parse_header(header)
    errors: list[str] = []
    n = {"bases": 0, "offsets": 0, "fields": 0, "irqs": 0, "layouts": 0}

    def value(name: str) -> int | None:
        m = NUM_RE.match(defs[name])
        return _int(m.group(1)) if m else None

    # peripherals: G4_<P>_BASE
    periphs: dict[str, int] = {}
    for name in defs:
        if name.endswith("_BASE"):
            p = name[len(PREFIX):-len("_BASE")]
            v = value(name)
            if v is None:
                errors.append(f"{name}: not a number: {defs[name]}")
                continue
            periphs[p] = v
    by_len = sorted(periphs, key=len, reverse=True)

    def split_periph(rest: str) -> tuple[str, str] | None:
        for p in by_len:
            if rest.startswith(p + "_"):
                return p, rest[len(p) + 1:]
        return None

    for p, v in periphs.items():
        target = NOT_DESCRIBED[p][0] if p in NOT_DESCRIBED else p
        if target not in svd:
            errors.append(f"G4_{p}_BASE: no peripheral {target} in the SVD")
            continue
        n["bases"] += 1
        if svd[target].base != v:
            errors.append(f"G4_{p}_BASE = {v:#010x}, SVD {target} at {svd[target].base:#010x}")

    # registers: G4_<P>_<R>_OFFSET
    regs: dict[str, list[str]] = {p: [] for p in periphs}
    for name in defs:
        if not name.endswith("_OFFSET"):
            continue
        sp = split_periph(name[len(PREFIX):-len("_OFFSET")])
        if sp is None:
            errors.append(f"{name}: no G4_<PERIPH>_BASE for it")
            continue
        p, r = sp
        regs[p].append(r)
        if p in NOT_DESCRIBED:
            errors.append(f"{name}: {p} has no registers in the SVD")
            continue
        per = svd.get(p)
        if per is None:
            continue
        if r not in per.registers:
            errors.append(f"{name}: SVD {p} has no register {r}")
            continue
        n["offsets"] += 1
        if per.registers[r][0] != value(name):
            errors.append(f"{name} = {defs[name]}, SVD {p}.{r} at {per.registers[r][0]:#x}")

    # fields: G4_<P>_<R>_<F>_Pos / _Msk
    for name in defs:
        if not (name.endswith("_Pos") or name.endswith("_Msk")):
            continue
        stem = name[len(PREFIX):-4]
        sp = split_periph(stem)
        if sp is None:
            errors.append(f"{name}: no G4_<PERIPH>_BASE for it")
            continue
        p, rest = sp
        reg = next((r for r in sorted(regs.get(p, []), key=len, reverse=True)
                    if rest.startswith(r + "_")), None)
        if reg is None:
            errors.append(f"{name}: no G4_{p}_<REG>_OFFSET for it")
            continue
        fld = rest[len(reg) + 1:]
        per = svd.get(p)
        if per is None or reg not in per.registers:
            continue  # reported with the offset
        fields = per.registers[reg][1]
        if fld not in fields:
            errors.append(f"{name}: SVD {p}.{reg} has no field {fld}")
            continue
        off, width = fields[fld]
        if name.endswith("_Pos"):
            n["fields"] += 1
            if value(name) != off:
                errors.append(f"{name} = {defs[name]}, SVD {p}.{reg}.{fld} at bit {off}")
        else:
            m = MSK_RE.match(defs[name])
            if m is None or m.group(2) != name[:-4] + "_Pos":
                errors.append(f"{name}: must be (0x<ones>u << {name[:-4]}_Pos), is {defs[name]}")
                continue
            ones = _int(m.group(1))
            if ones & (ones + 1) != 0 or ones.bit_length() != width:
                errors.append(f"{name}: width {ones.bit_length()} ({m.group(1)}), "
                              f"SVD {p}.{reg}.{fld} is {width} bits wide")

    # interrupts
    for name in defs:
        if name.startswith(PREFIX + "IRQ_") and name != PREFIX + "IRQ_COUNT":
            irq = name[len(PREFIX + "IRQ_"):]
            n["irqs"] += 1
            if irq not in irqs:
                errors.append(f"{name}: no interrupt {irq} in the SVD")
            elif irqs[irq] != value(name):
                errors.append(f"{name} = {defs[name]}, SVD says {irqs[irq]}")
    if PREFIX + "IRQ_COUNT" in defs and irqs:
        if value(PREFIX + "IRQ_COUNT") != max(irqs.values()) + 1:
            errors.append(f"G4_IRQ_COUNT = {defs[PREFIX + 'IRQ_COUNT']}, SVD's highest is "
                          f"{max(irqs.values())}")

    # same layout: every register and field declared for Q exists alike in P
    for name in defs:
        m = re.match(r"^G4_(\w+?)_SAME_LAYOUT_AS_(\w+)$", name)
        if not m:
            continue
        p, q = m.group(1), m.group(2)
        n["layouts"] += 1
        if p not in svd or q not in svd:
            errors.append(f"{name}: {p} or {q} not in the SVD")
            continue
        for r in regs.get(q, []):
            a, b = svd[q].registers.get(r), svd[p].registers.get(r)
            if a is None or b is None or a[0] != b[0]:
                errors.append(f"{name}: register {r} differs")
                continue
            for fname, fv in a[1].items():
                if b[1].get(fname) != fv:
                    errors.append(f"{name}: field {r}.{fname} differs")
    return errors, n


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--svd", type=Path, default=DEFAULT_SVD)
    ap.add_argument("--header", type=Path, default=DEFAULT_HEADER)
    a = ap.parse_args(argv)
    if not a.svd.is_file():
        print(f"check_svd_regs: SKIPPED: SVD file {a.svd} not found (clone the shared data "
              f"beside the repository to check the register definitions)")
        return EXIT_NO_SVD
    errors, n = check(a.svd, a.header)
    for e in errors:
        print(f"check_svd_regs: MISMATCH: {e}")
    for p, (target, why) in NOT_DESCRIBED.items():
        print(f"check_svd_regs: note: G4_{p}_* checked by base only ({why})")
    print(f"check_svd_regs: {a.header.name} against {a.svd.name}: {n['bases']} base addresses, "
          f"{n['offsets']} register offsets, {n['fields']} bit fields (position and width), "
          f"{n['irqs']} interrupts, {n['layouts']} layout claims; {len(errors)} mismatches")
    return 1 if errors else 0


if __name__ == "__main__":
    sys.exit(main())
