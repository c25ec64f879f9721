# SPDX-License-Identifier: Apache-2.0
"""The DBC for every node (pmactl.nodedbc, `pmactl dbc`): generic tools decode logs of
nodes other than 0 with it. The checks go through cantools' own command line
(`python -m cantools decode`), as a user's would, and python-can's log converter."""
from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path
from typing import Any

import can
import cantools
import pytest
from fakenode import PROTO

from pmactl.cli import EXIT_OK, EXIT_USAGE
from pmactl.nodedbc import (
    NodeListError,
    check_nodes,
    node_database,
    parse_nodes,
    write_node_dbc,
)
from pmactl.protocol import BROADCASTS

# One payload per message (valid signal values), encoded with the protocol's DBC.
SAMPLES: dict[str, dict[str, Any]] = {
    "ESTOP": {}, "PLANT_SENSOR": {"Seq": 7, "RawCounts": 30000},
    "PLANT_ACTUATOR": {"Seq": 7, "DacCounts": 2048, "Sample": 0, "OutputActive": 1},
    "COMMAND": {"Command": 3, "Arg": 0}, "COMMAND_ACK": {"Command": 3, "Arg": 0, "Result": 0, "State": 3},
    "SETPOINT": {"XrCm": 1.5},
    "PARAM_REQ": {"Op": 0, "Type": 0, "Id": 34, "Reserved": 0, "ValueF32": 0.0},
    "PARAM_RESP": {"Op": 0, "Type": 0, "Id": 34, "Result": 0, "ValueF32": 0.3},
    "HOST_HEARTBEAT": {"Counter": 1},
    "HEARTBEAT": {"State": 3, "FaultCode": 0, "Flags": 0x47, "Controller": 1, "Reference": 4,
                  "ResetCause": 1, "Counter": 9},
    "TELEM_A": {"TimeMs": 1000, "XCm": -1.25}, "TELEM_B": {"XrCm": -1.5, "ECm": 0.25},
    "TELEM_C": {"U": -10.0, "VCmS": 0.5}, "TELEM_D": {"Internal1": 0.1, "Internal2": 0.2},
    "TELEM_E": {"PressureKpa": 290.0, "CtrlFlags": 0, "Breaches": 0},
}


def frames(nodes: list[int]) -> list[can.Message]:
    """Every message of the protocol from/to each node, then ESTOP_ALL."""
    out = []
    t = 1.0
    for n in nodes:
        for name, sig in SAMPLES.items():
            out.append(can.Message(timestamp=t, arbitration_id=PROTO.frame_id(name, n),
                                   data=PROTO.encode(name, sig), is_extended_id=False, channel=0))
            t += 0.001
    out.append(can.Message(timestamp=t, arbitration_id=0, data=b"", is_extended_id=False, channel=0))
    return out


def cantools_decode(dbc: Path, log_text: str) -> list[str]:
    r = subprocess.run([sys.executable, "-m", "cantools", "decode", "--single-line", str(dbc)],
                       input=log_text, capture_output=True, text=True, check=True)
    return [line for line in r.stdout.splitlines() if line.strip()]


def test_node_list_parsing() -> None:
    assert parse_nodes("0-15") == list(range(16))
    assert parse_nodes("1,2,5") == [1, 2, 5]
    assert parse_nodes("0-3, 8") == [0, 1, 2, 3, 8]
    assert parse_nodes("0x0a") == [10]
    for bad, why in (("1,2,1", "node 1 listed twice"), ("0-3,2", "node 2 listed twice"),
                     ("16", "node id 16 outside 0..15"), ("0-16", "node id 16 outside 0..15"),
                     ("-1", "is not a node id"), ("5-3", "runs backwards"), ("a", "is not a node id"),
                     ("", "empty node list"), ("1,,2", "is not a node id")):
        with pytest.raises(NodeListError, match=re.escape(why)):
            parse_nodes(bad)
    with pytest.raises(NodeListError, match="listed twice"):
        check_nodes([1, 1])
    with pytest.raises(NodeListError, match="outside"):
        node_database([3, 16])


def test_every_node_has_every_message_at_its_frame_id() -> None:
    db = node_database(range(16))
    per_node = [m for m in PROTO.db.messages if m.name not in BROADCASTS]
    assert len(db.messages) == 16 * len(per_node) + len(BROADCASTS)
    for n in range(16):
        for m in per_node:
            c = db.get_message_by_name(f"{m.name}_N{n}")
            assert c.frame_id == m.frame_id + n
            assert [s.name for s in c.signals] == [s.name for s in m.signals]
            assert c.comment == m.comment
    assert db.get_message_by_frame_id(0).name == "ESTOP_ALL"
    assert db.get_message_by_frame_id(0x120).name == "DEVICE_INFO_REQ_ALL"
    assert db.version == PROTO.db.version


def test_cli_writes_a_dbc_that_cantools_loads(pmactl, tmp_path: Path) -> None:
    out = tmp_path / "nodes.dbc"
    r = pmactl("dbc", "--nodes", "0-15", "-o", str(out), bus=False)
    assert r.code == EXIT_OK, r.err
    assert f"protocol {PROTO.version} for node(s) 0,1,2" in r.out
    db = cantools.database.load_file(str(out))
    assert isinstance(db, cantools.database.can.Database)
    assert db.get_message_by_name("HEARTBEAT_N15").frame_id == 0x0AF
    r = pmactl("dbc", "--nodes", "3", bus=False)          # stdout
    assert r.code == EXIT_OK and "BO_ 163 HEARTBEAT_N3: 8 PMA" in r.out


@pytest.mark.parametrize("nodes, why", [("1,2,1", "node 1 listed twice"), ("0-16", "node id 16 outside"),
                                        ("x", "is not a node id")])
def test_cli_bad_node_list_is_exit_2(pmactl, tmp_path: Path, nodes: str, why: str) -> None:
    out = tmp_path / "nodes.dbc"
    r = pmactl("dbc", "--nodes", nodes, "-o", str(out), bus=False)
    assert r.code == EXIT_USAGE
    assert why in r.err and "Traceback" not in r.err
    assert not out.exists()
    r = pmactl("dbc", "-o", str(tmp_path / "no" / "such" / "x.dbc"), bus=False)
    assert r.code == EXIT_USAGE and "does not exist" in r.err


def test_a_bus_log_of_nodes_1_and_2_decodes_completely(tmp_path: Path) -> None:
    """As the HIL writes it: bus.blf of nodes 1 and 2 with bus.dbc beside it. Converted by
    python-can's logconvert to candump's log format, every frame decodes in cantools."""
    blf = tmp_path / "bus.blf"
    sent = frames([1, 2])
    with can.BLFWriter(str(blf)) as w:
        for m in sent:
            w.on_message_received(m)
    dbc = write_node_dbc(tmp_path / "bus.dbc", [1, 2])
    log = tmp_path / "bus.log"
    subprocess.run([sys.executable, "-m", "can.logconvert", str(blf), str(log)], check=True,
                   capture_output=True)
    lines = cantools_decode(dbc, log.read_text())
    assert len(lines) == len(sent)
    assert not [line for line in lines if "Unknown frame id" in line]
    for m, line in zip(sent, lines):
        name, node = PROTO.message_of(m.arbitration_id) or ("?", -1)
        want = "ESTOP_ALL" if name == "ESTOP_ALL" else f"{name}_N{node}"
        assert f":: {want}" in line, line
    # the values, not only the names: node 2's heartbeat and telemetry
    text = "\n".join(lines)
    assert "HEARTBEAT_N2(State: RUNNING, FaultCode: NONE" in text
    assert "TELEM_A_N2(TimeMs: 1000 ms, XCm: -1.25 cm)" in text
    # the protocol's one DBC (node 0's ids) decodes none of these frames but ESTOP_ALL
    base = cantools_decode(_base_dbc(), log.read_text())
    assert sum("Unknown frame id" in line for line in base) == len(sent) - 1


def _base_dbc() -> Path:
    from pmactl.protocol import _data_file
    return _data_file("pma_proto.dbc", "PMA_DBC")


def test_a_candump_log_of_three_nodes_decodes_per_node(tmp_path: Path) -> None:
    """`candump -L` format, `(time) interface id#data`, of nodes 0, 4 and 9."""
    nodes = [0, 4, 9]
    sent = frames(nodes)[:-1]
    text = "".join(f"({m.timestamp:.6f}) vcan0 {m.arbitration_id:03X}#{bytes(m.data).hex().upper()}\n"
                   for m in sent)
    dbc = tmp_path / "three.dbc"
    write_node_dbc(dbc, nodes)
    lines = cantools_decode(dbc, text)
    assert len(lines) == len(sent) and not [line for line in lines if "Unknown" in line]
    for n in nodes:
        mine = [line for line in lines if re.search(rf":: [A-Z_]+_N{n}\(", line)
                or re.search(rf":: [A-Z_]+_N{n}$", line)]
        assert len(mine) == len(SAMPLES), (n, mine)
    assert "PARAM_RESP_N9(Op: GET, Type: F32, Id: 34, Result: OK, ValueF32: 0.3" in "\n".join(lines)
