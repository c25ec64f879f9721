# SPDX-License-Identifier: Apache-2.0
"""docs/protocol.md agrees with the DBC and the firmware headers: message and
signal tables, value tables, heartbeat flags, the transition table's form, and
examples that parse and cover every message. No CAN needed (the examples are
run by tests/integration/test_protocol_doc.py)."""
from __future__ import annotations

import re

import cantools
import pytest

from pma_tools import protocol_doc as dx

ROOT = dx.ROOT
APP_H = ROOT / "firmware/app/app.h"


@pytest.fixture(scope="module")
def db() -> cantools.database.can.Database:
    return cantools.database.load_file(str(dx.DBC))


@pytest.fixture(scope="module")
def doc() -> str:
    return dx.read_doc()


def choices(db, message: str, signal: str) -> dict[int, str]:
    c = db.get_message_by_name(message).get_signal_by_name(signal).choices or {}
    return {int(k): str(v) for k, v in c.items()}


def type_name(sig) -> str:
    if sig.is_float:
        return f"f{sig.length}"
    return f"{'i' if sig.is_signed else 'u'}{sig.length}"


# --------------------------------------------------------------- examples --

def test_examples_parse_and_cover_every_message(db, doc) -> None:
    exs = dx.examples(doc)
    assert len(exs) >= 10
    names = dx.example_message_names(exs, {m.frame_id: m.name for m in db.messages})
    missing = sorted({m.name for m in db.messages} - names)
    assert not missing, f"messages without a runnable example in docs/protocol.md: {missing}"


def test_example_frames_have_the_dbc_lengths(db, doc) -> None:
    """Frames the node sends have their DBC length and decode; frames sent to it
    have their DBC length unless the example is about bad input or ESTOP."""
    by_base = {m.frame_id: m for m in db.messages}
    for ex in dx.examples(doc):
        for step in ex.steps:
            if step.tool != "cansend":
                frames = step.expected
            else:
                sent = step.sent_frame()
                m = by_base.get(sent.can_id & dx.BASE_ID_MASK)
                if m is not None and sent.dlc != m.length:
                    assert "Bad input" in ex.heading or m.name.startswith("ESTOP"), (
                        f"line {step.line_no}: {m.name} with {sent.dlc} bytes outside the bad-input "
                        f"examples")
                frames = step.expected[1:]   # [0] is the sent frame itself
            for f in frames:
                m = by_base.get(f.can_id & dx.BASE_ID_MASK)
                assert m is not None, f"line {step.line_no}: no message with id 0x{f.can_id:03X}"
                assert f.dlc == m.length, f"line {step.line_no}: {m.name} has {m.length} bytes"
                if None not in f.data:
                    if m.name == "PARAM_RESP" and f.data[0] >> 4 > 2:
                        # an undefined Type echoed from the request: no value signal, value bytes 0
                        assert list(f.data[4:]) == [0, 0, 0, 0], f"line {step.line_no}"
                        continue
                    m.decode(bytes(f.data), decode_choices=False)  # raises if it cannot


def test_walk_through_starts_the_node_the_test_starts(doc) -> None:
    assert "pma-fw-host --can vcan0 --node 3 --lockstep --storage" in doc
    for ex in dx.examples(doc):
        for step in ex.steps:
            assert step.argv[1].split(",")[0] == "vcan0" or step.argv[-1].split(",")[0] == "vcan0"
            for f in step.expected:
                assert f.iface == "vcan0"
                assert f.can_id in dx.BROADCAST_IDS or f.can_id & dx.NODE_ID_MASK in (3, 4), (
                    f"line {step.line_no}: the examples talk to node 3")


# ----------------------------------------------------------------- tables --

def test_message_table(db, doc) -> None:
    rows = dx.tables_after(doc, r"^Messages$")[0]
    listed = {}
    for row in rows:
        name = dx.unquote(row[0])
        assert name not in listed, f"{name} twice"
        listed[name] = row
    assert set(listed) == {m.name for m in db.messages}
    for m in db.messages:
        row = listed[m.name]
        assert int(row[1], 16) == m.frame_id, f"{m.name}: base id"
        assert int(row[2]) == m.length, f"{m.name}: DLC"
    order = [dx.unquote(r[0]) for r in rows]
    assert order == [m.name for m in sorted(db.messages, key=lambda m: m.frame_id)], "sorted by id"


@pytest.mark.parametrize("message", [m.name for m in cantools.database.load_file(str(dx.DBC)).messages])
def test_signal_table(db, doc, message: str) -> None:
    m = db.get_message_by_name(message)
    if not m.signals:
        assert re.search(rf"^###.*`{message}`", doc, re.M), f"no section for {message}"
        return
    tables = dx.tables_after(doc, rf"^`{message}`$")
    assert tables, f"no signal table under ### `{message}`"
    rows = {dx.unquote(r[0]): r for r in tables[0]}
    assert set(rows) == {s.name for s in m.signals}, f"{message}: signals"
    for s in m.signals:
        cells = rows[s.name]
        first, _, last = cells[1].partition("..")
        assert (int(first), int(last)) == (s.start, s.start + s.length - 1), f"{message}.{s.name}: bits"
        assert cells[2] == type_name(s), f"{message}.{s.name}: type"
        unit = s.unit or "—"
        assert cells[3] == unit, f"{message}.{s.name}: unit"
        long_lists = {"Command", "Result", "State", "FaultCode"}
        if s.choices and s.name not in long_lists:
            for k, v in s.choices.items():
                assert re.search(rf"\b{int(k)} {v}\b", cells[4]), (
                    f"{message}.{s.name}: value {int(k)} {v} not listed")


@pytest.mark.parametrize("heading,message,signal", [
    (r"^Commands$", "COMMAND", "Command"),
    (r"^States$", "HEARTBEAT", "State"),
    (r"^Result codes$", "PARAM_RESP", "Result"),
    (r"^Faults$", "HEARTBEAT", "FaultCode"),
])
def test_value_tables(db, doc, heading: str, message: str, signal: str) -> None:
    rows = dx.tables_after(doc, heading)[0]
    got = {int(r[0]): dx.unquote(r[1] if signal != "Result" else r[2]) for r in rows}
    assert got == choices(db, message, signal)
    if signal == "Result":
        for r in rows:
            assert int(dx.unquote(r[1]), 16) == int(r[0]) & 0xFF, f"byte of {r[2]}"


def test_status_values_table(db, doc) -> None:
    """The Status values table is the DBC's value table StatusId (which the firmware's
    PMA_STATUS_* are tied to, and pmactl counters reads by name), and every PMA_STATUS_ of
    app.h is in it."""
    rows = dx.tables_after(doc, r"^Status values$")[0]
    got = {int(r[0]): dx.unquote(r[1]) for r in rows}
    table = {int(k): str(v) for k, v in db.dbc.value_tables["StatusId"].items()}
    assert got == table
    src = APP_H.read_text()
    in_c = {m.group(1): int(m.group(2)) for m in re.finditer(r"PMA_STATUS_(\w+)\s*=\s*(\d+)", src)}
    assert in_c == {v: k for k, v in table.items()}


def test_heartbeat_flag_table(doc) -> None:
    src = APP_H.read_text()
    flags = {m.group(1): int(m.group(2), 16)
             for m in re.finditer(r"#define\s+PMA_HB_(\w+)\s+0x([0-9A-Fa-f]+)u", src)}
    rows = dx.tables_after(doc, r"^Heartbeat flags$")[0]
    got = {dx.unquote(r[2]): (int(r[0]), int(r[1], 16)) for r in rows}
    assert got == {n: (v.bit_length() - 1, v) for n, v in flags.items()}


def test_transition_table_form(db, doc) -> None:
    states, rows = dx.transition_table(doc)
    state_names = set(choices(db, "HEARTBEAT", "State").values())
    assert states == ["IDLE", "ARMED", "RUNNING", "FAULT"]
    results = set(choices(db, "COMMAND_ACK", "Result").values())
    commands = choices(db, "COMMAND", "Command")
    seen = []
    for head, cells in rows:
        m = re.match(r"^(\d+) `(\w+)`$", head)
        if m:
            assert commands[int(m.group(1))] == m.group(2)
            seen.append(int(m.group(1)))
        else:
            assert head.startswith("other"), head
        for result, new_state in cells.values():
            assert result in results and new_state in state_names
    assert seen == sorted(commands), "one row per command, in order"
