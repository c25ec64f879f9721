# SPDX-License-Identifier: Apache-2.0
"""Commands on several nodes (--node 1,2,5, --all) with a report per node, bad node lists, and
moving a node to another id (pmactl node-id): its refusals, which change nothing."""
from __future__ import annotations

import json
from pathlib import Path

import pytest
from fakenode import PROTO, STATE

from pmactl.cli import EXIT_NO_REPLY, EXIT_OK, EXIT_REFUSED, EXIT_USAGE


def test_status_of_a_list_of_nodes_reports_each(pmactl, fake) -> None:
    fake(node=1, uid=bytes([1]) * 12)
    fake(node=2, uid=bytes([2]) * 12)
    r = pmactl("--node", "1,2", "status")
    assert r.code == EXIT_OK, r.err
    assert "node 1: node 1 on virtual" in r.out and "node 2: node 2 on virtual" in r.out
    assert f"node 2:   unique id    {'02' * 12}" in r.out
    assert "2 node(s): all OK" in r.out


@pytest.mark.parametrize("nodes, message", [
    ("1,1", "node 1 listed twice"), ("2,0-3", "node 2 listed twice"), ("1,16", "outside 0..15"),
    ("3-1", "runs backwards"), ("x", "is not a node id"), ("", "empty node list")])
def test_bad_node_lists_are_usage_errors(pmactl, fake, nodes: str, message: str) -> None:
    n = fake(node=1)
    r = pmactl("--node", nodes, "arm")
    assert r.code == EXIT_USAGE and message in r.err
    assert n.state == STATE["IDLE"]                      # nothing sent


def test_single_node_commands_refuse_a_list(pmactl, fake, tmp_path: Path) -> None:
    fake(node=1)
    fake(node=2)
    r = pmactl("--node", "1,2", "record", str(tmp_path / "r.csv"))
    assert r.code == EXIT_USAGE and "record works on one node" in r.err
    r = pmactl("--all", "node-id", "5")
    assert r.code == EXIT_USAGE and "node-id works on one node" in r.err
    r = pmactl("--node", "1,2", "params", "dump", str(tmp_path / "p.json"))
    assert r.code == EXIT_USAGE and "{node}" in r.err


def test_all_arms_every_node_and_a_missing_one_is_reported(pmactl, fake) -> None:
    a, b, c = fake(node=1), fake(node=4), fake(node=9)
    r = pmactl("--all", "arm")
    assert r.code == EXIT_OK, r.err
    assert all(n.state == STATE["ARMED"] for n in (a, b, c))
    assert "node 4: node 4: ARM OK" in r.out and "3 node(s): all OK" in r.out
    r = pmactl("--node", "1,7", "disarm")                # 7 does not exist
    assert r.code == EXIT_NO_REPLY
    assert a.state == STATE["IDLE"] and "node 1: node 1: DISARM OK" in r.out
    assert "no COMMAND_ACK from node 7" in r.err and "2 node(s): exit status 4" in r.out


def test_dump_of_several_nodes_writes_one_file_each(pmactl, fake, tmp_path: Path) -> None:
    fake(node=1)
    fake(node=2)
    r = pmactl("--node", "1,2", "params", "dump", str(tmp_path / "n{node}.json"))
    assert r.code == EXIT_OK, r.err
    assert json.loads((tmp_path / "n1.json").read_text())["node"] == 1
    assert json.loads((tmp_path / "n2.json").read_text())["node"] == 2


def test_node_id_move_refuses_a_taken_id_and_an_active_node(pmactl, fake) -> None:
    a = fake(node=1, uid=bytes([1]) * 12)
    fake(node=2, uid=bytes([2]) * 12)
    r = pmactl("--node", "1", "node-id", "2")
    assert r.code == EXIT_REFUSED and f"node id 2 is already used by the device(s) {'02' * 12}" in r.err
    a.set_state("ARMED")
    r = pmactl("--node", "1", "node-id", "3")
    assert r.code == EXIT_REFUSED and "node 1 is ARMED: disarm it first" in r.err
    r = pmactl("--node", "1", "node-id", "1")
    assert r.code == EXIT_USAGE
    assert a.sets() == []                                # nothing changed
    assert a.value("sys.node_id") == 0


def test_node_id_move_sets_saves_restarts_and_verifies(pmactl, fake) -> None:
    a = fake(node=1, uid=bytes([1]) * 12, storage=True)
    r = pmactl("--node", "1", "node-id", "6", "--wait", "5")
    assert r.code == EXIT_OK, r.err
    assert "sys.node_id = 6 set and saved; restarting it" in r.out
    assert f"verified: the device {'01' * 12} answers on node id 6" in r.out
    assert a.node == 6 and a.reset_cause == 3 and a.saved is not None
    assert a.saved[PROTO.param("sys.node_id").id] == 6


def test_node_id_move_without_restart_asks_for_one(pmactl, fake) -> None:
    """A node that refuses RESTART (older firmware): the move is set and saved, the user is told
    to restart it, and the wait ends without the device on its new id."""
    a = fake(node=1, uid=bytes([1]) * 12, storage=True, restarts=False)
    r = pmactl("--node", "1", "node-id", "6", "--wait", "0.5")
    assert r.code == EXIT_NO_REPLY
    assert "sys.node_id = 6 set and saved" in r.out and "refused RESTART (UNKNOWN_COMMAND)" in r.out
    assert "did not answer on node id 6" in r.err
    assert a.value("sys.node_id") == 6 and a.saved is not None
    assert a.saved[PROTO.param("sys.node_id").id] == 6
