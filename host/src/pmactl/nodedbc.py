# SPDX-License-Identifier: Apache-2.0
"""A DBC for a bus of several nodes, generated from the protocol's one DBC.

firmware/protocol/pma_proto.dbc lists each message once, at its base id (node 0): a frame
of node 3 (base id + 3) is not in it, so generic tools (``python -m cantools decode`` and
``monitor``, SavvyCAN, python-can viewers) decode node 0 only. ``node_database`` makes
one message per node and message, at the node's real frame id, named with the node
(``HEARTBEAT_N3``, ``TELEM_A_N12``); the broadcasts (ESTOP_ALL, DEVICE_INFO_REQ_ALL) stay once, at their ids. Signals,
value tables, comments, float types and the multiplexing are those of the one DBC, so
there is nothing here to keep in step with it. ``pmactl dbc`` writes the file; the HIL
harness writes one beside its bus log.
"""
from __future__ import annotations

import copy
from collections.abc import Iterable
from pathlib import Path

import cantools.database
from cantools.database.can import Database

from pmactl.protocol import BROADCASTS, NODE_COUNT, Protocol, load_protocol


class NodeListError(ValueError):
    """A node list that is not one: not a number, out of range, or a node twice."""


def parse_nodes(text: str) -> list[int]:
    """Node ids from text such as ``0-15``, ``1,2,5`` or ``0-3,8``, in the order given.

    NodeListError naming the bad entry: not a number, outside 0..15, a range that runs
    backwards, or a node id listed twice."""
    nodes: list[int] = []
    if not text.strip():
        raise NodeListError("empty node list (give ids 0..15, e.g. 1,2,5 or 0-15)")
    for part in text.split(","):
        item = part.strip()
        lo_text, dash, hi_text = item.partition("-")
        try:
            lo = int(lo_text, 0)
            hi = int(hi_text, 0) if dash else lo
        except ValueError:
            raise NodeListError(f"node list {text!r}: {item!r} is not a node id or a range "
                                f"(e.g. 3 or 0-15)") from None
        for v in (lo, hi):
            if not 0 <= v < NODE_COUNT:
                raise NodeListError(f"node list {text!r}: node id {v} outside 0..{NODE_COUNT - 1}")
        if hi < lo:
            raise NodeListError(f"node list {text!r}: range {item!r} runs backwards")
        for v in range(lo, hi + 1):
            if v in nodes:
                raise NodeListError(f"node list {text!r}: node {v} listed twice")
            nodes.append(v)
    return nodes


def check_nodes(nodes: Iterable[int]) -> list[int]:
    """The node ids as a list; NodeListError for one outside 0..15 or one given twice."""
    out: list[int] = []
    for v in nodes:
        if isinstance(v, bool) or not isinstance(v, int) or not 0 <= v < NODE_COUNT:
            raise NodeListError(f"node id {v!r} outside 0..{NODE_COUNT - 1}")
        if v in out:
            raise NodeListError(f"node {v} listed twice")
        out.append(v)
    if not out:
        raise NodeListError("no node ids")
    return out


def message_name(message: str, node: int) -> str:
    """The name of a node's message in a node DBC: ``HEARTBEAT_N3`` (a broadcast as is)."""
    return message if message in BROADCASTS else f"{message}_N{node}"


def node_database(nodes: Iterable[int], protocol: Protocol | None = None) -> Database:
    """A cantools database with every message of the protocol for each node, at its frame id
    (base id + node id) and named ``NAME_N<node>``; the broadcasts once, at their ids."""
    proto = protocol or load_protocol()
    ids = check_nodes(nodes)
    db = proto.db
    messages = []
    for m in db.messages:
        if m.name in BROADCASTS:
            messages.append(copy.deepcopy(m))
            continue
        for n in ids:
            c = copy.deepcopy(m)
            c.frame_id = m.frame_id | n
            c.name = message_name(m.name, n)
            messages.append(c)
    messages.sort(key=lambda m: m.frame_id)
    return Database(messages=messages, nodes=copy.deepcopy(db.nodes), buses=copy.deepcopy(db.buses),
                    version=db.version, dbc_specifics=copy.deepcopy(db.dbc))


def node_dbc_text(nodes: Iterable[int], protocol: Protocol | None = None) -> str:
    """The node DBC as text (cantools' DBC writer)."""
    ids = check_nodes(nodes)
    text = node_database(ids, protocol).as_dbc_string()
    head = (f"pmactl node DBC for nodes {','.join(map(str, ids))}, generated from "
            f"pma_proto.dbc (frame id = base id + node id)")
    # the generated text starts with VERSION; a comment line is not part of the DBC
    # grammar, so the provenance goes into the database comment instead (CM_ "...")
    return text.replace('CM_ "', f'CM_ "{head}. ', 1) if 'CM_ "' in text else text


def write_node_dbc(path: str | Path, nodes: Iterable[int], protocol: Protocol | None = None) -> Path:
    """Writes the node DBC of `nodes` to path (the HIL harness's and ``pmactl dbc``'s
    function); returns the path. NodeListError for a bad node list, OSError for the file."""
    p = Path(path)
    text = node_dbc_text(nodes, protocol)
    # a DBC that cantools cannot read back is a bug here, not a file to hand to a user
    cantools.database.load_string(text, database_format="dbc")
    p.write_text(text)
    return p
