# SPDX-License-Identifier: Apache-2.0
"""Reads docs/protocol.md for the tests: its runnable examples, its tables.

Imported as pma_tools.protocol_doc by tests/protocol (no CAN) and
tests/integration/test_protocol_doc.py (runs the examples against pma-fw-host). The
conventions are described in the document itself, section "Examples are tests":

  - every ```console block is a runnable example;
  - `$ cansend IFACE ID#DATA` lines are sent; the lines that follow are the
    frames `candump IFACE` shows from then on (default format), starting
    with the sent frame; node HEARTBEATs in between are left out unless shown;
  - `$ candump -n N IFACE,ID:MASK` lines are run as they stand and must print
    the lines that follow;
  - `XX` in place of a data byte matches any byte.
"""
from __future__ import annotations

import re
import shlex
from dataclasses import dataclass, field
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DOC = ROOT / "docs/protocol.md"
DBC = ROOT / "firmware/protocol/pma_proto.dbc"

BASE_ID_MASK = 0x7F0
NODE_ID_MASK = 0x00F
HEARTBEAT_BASE = 0x0A0
BROADCAST_IDS = (0x000, 0x120)   # ESTOP_ALL, DEVICE_INFO_REQ_ALL: no node id
WILDCARD = "XX"

_FENCE = re.compile(r"^```(\S*)\s*$")
_CANDUMP_LINE = re.compile(r"^\s*(\S+)\s+([0-9A-Fa-f]{3})\s+\[(\d)\]\s*((?:[0-9A-Fa-f]{2}|XX)(?:\s+(?:[0-9A-Fa-f]{2}|XX))*)?\s*$")  # noqa: E501
_CANSEND_FRAME = re.compile(r"^([0-9A-Fa-f]{3})#((?:[0-9A-Fa-f]{2})*)$")


@dataclass(frozen=True)
class Frame:
    """One candump line: interface, 11-bit id, DLC, data bytes (None: XX)."""
    iface: str
    can_id: int
    dlc: int
    data: tuple[int | None, ...]

    @staticmethod
    def parse(line: str) -> "Frame":
        m = _CANDUMP_LINE.match(line)
        if not m:
            raise ValueError(f"not a candump line (default format): {line!r}")
        data = tuple(None if b == WILDCARD else int(b, 16) for b in (m.group(4) or "").split())
        f = Frame(m.group(1), int(m.group(2), 16), int(m.group(3)), data)
        if len(f.data) != f.dlc:
            raise ValueError(f"[{f.dlc}] but {len(f.data)} data bytes: {line!r}")
        return f

    def matches(self, actual: "Frame") -> bool:
        """self (expected, may hold wildcards) against an actual frame."""
        return (self.iface == actual.iface and self.can_id == actual.can_id
                and self.dlc == actual.dlc
                and all(e is None or e == a for e, a in zip(self.data, actual.data)))

    @property
    def is_heartbeat(self) -> bool:
        return self.can_id & BASE_ID_MASK == HEARTBEAT_BASE

    def __str__(self) -> str:
        data = " ".join(WILDCARD if b is None else f"{b:02X}" for b in self.data)
        return f"{self.iface}  {self.can_id:03X}   [{self.dlc}]  {data}"


@dataclass
class Step:
    """One `$ ...` command of an example and the frames it must produce."""
    command: str
    line_no: int
    expected: list[Frame] = field(default_factory=list)

    @property
    def argv(self) -> list[str]:
        return shlex.split(self.command)

    @property
    def tool(self) -> str:
        return self.argv[0]

    def sent_frame(self) -> Frame:
        """The frame of a cansend step."""
        argv = self.argv
        if argv[0] != "cansend" or len(argv) != 3:
            raise ValueError(f"line {self.line_no}: want `cansend IFACE ID#DATA`: {self.command}")
        m = _CANSEND_FRAME.match(argv[2])
        if not m:
            raise ValueError(f"line {self.line_no}: want a classic 11-bit frame ID#DATA "
                             f"(3 hex digits, whole bytes): {argv[2]}")
        data = bytes.fromhex(m.group(2))
        return Frame(argv[1], int(m.group(1), 16), len(data), tuple(data))


@dataclass
class Example:
    line_no: int          # of the opening fence
    heading: str          # the section it is in
    steps: list[Step]


def read_doc(path: Path = DOC) -> str:
    return path.read_text(encoding="utf-8")


def code_blocks(text: str) -> list[tuple[str, int, list[str], str]]:
    """(info string, line number of the fence, lines, heading) of every fenced block."""
    blocks = []
    lines = text.splitlines()
    heading = ""
    i = 0
    while i < len(lines):
        if lines[i].startswith("#") and not lines[i].startswith("#!"):
            heading = lines[i].lstrip("#").strip()
        m = _FENCE.match(lines[i])
        if m:
            start = i
            body = []
            i += 1
            while i < len(lines) and not lines[i].startswith("```"):
                body.append(lines[i])
                i += 1
            if i >= len(lines):
                raise ValueError(f"line {start + 1}: unclosed code block")
            blocks.append((m.group(1), start + 1, body, heading))
        i += 1
    return blocks


def examples(text: str | None = None) -> list[Example]:
    """The runnable examples (```console blocks), in document order."""
    text = read_doc() if text is None else text
    out = []
    for info, line_no, body, heading in code_blocks(text):
        if info != "console":
            continue
        steps: list[Step] = []
        for k, line in enumerate(body):
            n = line_no + 1 + k
            if not line.strip():
                continue
            if line.startswith("$ "):
                steps.append(Step(line[2:].strip(), n))
                continue
            if not steps:
                raise ValueError(f"line {n}: output before the first `$ ` command")
            try:
                steps[-1].expected.append(Frame.parse(line))
            except ValueError as e:
                raise ValueError(f"line {n}: {e}") from None
        if not steps:
            raise ValueError(f"line {line_no}: a console block without a `$ ` command")
        for s in steps:
            if s.tool == "cansend":
                sent = s.sent_frame()
                if not s.expected or not s.expected[0].matches(sent):
                    raise ValueError(f"line {s.line_no}: the first line after a cansend must be "
                                     f"the sent frame: {sent}")
            elif s.tool == "candump":
                if "-n" not in s.argv:
                    raise ValueError(f"line {s.line_no}: a candump example must end by itself "
                                     f"(-n COUNT): {s.command}")
                if not s.expected:
                    raise ValueError(f"line {s.line_no}: a candump example without output")
            else:
                raise ValueError(f"line {s.line_no}: only cansend and candump run in examples: "
                                 f"{s.command}")
        out.append(Example(line_no, heading, steps))
    return out


def example_message_names(exs: list[Example], dbc_messages: dict[int, str]) -> set[str]:
    """Names of the DBC messages that occur (sent or expected) in the examples;
    dbc_messages maps base id -> name."""
    names = set()
    for ex in exs:
        for s in ex.steps:
            frames = list(s.expected)
            if s.tool == "cansend":
                frames.append(s.sent_frame())
            for f in frames:
                name = dbc_messages.get(f.can_id & BASE_ID_MASK)
                # ESTOP_ALL is id 0 itself; 0x001..0x00F are not ESTOP_ALL
                if name is not None and (f.can_id & BASE_ID_MASK != 0 or f.can_id == 0):
                    names.add(name)
    return names


# ---------------------------------------------------------------- tables --

def split_row(line: str) -> list[str]:
    return [c.strip() for c in line.strip().strip("|").split("|")]


def tables_after(text: str, heading_pattern: str) -> list[list[list[str]]]:
    """The tables (rows of cells, header and separator dropped) between the
    first heading matching heading_pattern (regex on the heading text) and the
    next heading of the same or a higher level."""
    lines = text.splitlines()
    start = level = None
    for i, line in enumerate(lines):
        m = re.match(r"^(#+)\s+(.*)$", line)
        if m and re.search(heading_pattern, m.group(2)):
            start, level = i + 1, len(m.group(1))
            break
    if start is None:
        raise KeyError(f"no heading matching {heading_pattern!r}")
    tables: list[list[list[str]]] = []
    current: list[list[str]] | None = None
    in_code = False
    for line in lines[start:]:
        if line.startswith("```"):
            in_code = not in_code
        m = re.match(r"^(#+)\s", line)
        if not in_code and m and len(m.group(1)) <= level:
            break
        if not in_code and line.startswith("|"):
            if current is None:
                current = []
                tables.append(current)
            cells = split_row(line)
            if not all(re.fullmatch(r":?-+:?", c) for c in cells):
                current.append(cells)
        else:
            current = None
    for t in tables:
        del t[0]  # header
    return tables


def unquote(cell: str) -> str:
    return cell.strip().strip("`").strip()


ARROW = "\u2192"  # the arrow of the transition table's cells


def parse_transition_cell(cell: str) -> tuple[str, str]:
    """'OK \u2192 ARMED [1]' -> ('OK', 'ARMED')."""
    m = re.match(rf"^([A-Z_]+) {ARROW} ([A-Z]+)(?: \[\d\])?$", cell.strip())
    if not m:
        raise ValueError(f"transition cell {cell!r}: want 'RESULT {ARROW} STATE' and an optional [n]")
    return m.group(1), m.group(2)


def transition_table(text: str) -> tuple[list[str], list[tuple[str, dict[str, tuple[str, str]]]]]:
    """The state machine's table: (state columns, [(first cell, {state: (result, new state)})])."""
    after = text.split("\n## State machine\n", 1)[1]
    heads = [line for line in after.splitlines() if line.startswith("| command")]
    if not heads:
        raise KeyError("no transition table (header '| command | IDLE | ...')")
    states = split_row(heads[0])[1:]
    rows = tables_after(text, r"^State machine$")[0]
    return states, [(r[0], {s: parse_transition_cell(c) for s, c in zip(states, r[1:], strict=True)})
                    for r in rows]


def section(text: str, begin: str, end: str) -> str:
    """The text between two marker lines (exclusive)."""
    a = text.index(begin) + len(begin)
    b = text.index(end, a)
    return text[a:b].strip("\n") + "\n"
