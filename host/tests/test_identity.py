# SPDX-License-Identifier: Apache-2.0
"""Node identity (DEVICE_INFO): pmactl info, status and scan against fake nodes, the two
devices on one node id, a node of another protocol version, a malformed DEVICE_INFO, and the
parameter-table hash tied to the firmware's generated table."""
from __future__ import annotations

import re
from pathlib import Path

from fakenode import PROTO

from pmactl.cli import EXIT_NO_REPLY, EXIT_OK, EXIT_REFUSED
from pmactl.identity import device_tag
from pmactl.protocol import param_table_hash, protocol_version

REPO = Path(__file__).resolve().parents[2]
UID_A = bytes.fromhex("0102030405060708090a0b0c")
UID_B = bytes.fromhex("a1a2a3a4a5a6a7a8a9aaabac")


def test_info_shows_every_field(pmactl, fake) -> None:
    fake(uid=UID_A)
    r = pmactl("info")
    assert r.code == EXIT_OK, r.err
    assert "firmware     0.2.0+1234abcd (HOST)" in r.out
    assert f"protocol     {protocol_version(PROTO.db)}" in r.out
    assert f"parameters   {len(PROTO.params)}, table hash" in r.out
    assert f"unique id    {UID_A.hex()}" in r.out
    assert "warning" not in r.out


def test_status_includes_the_identity(pmactl, fake) -> None:
    fake(node=5, uid=UID_B)
    r = pmactl("--node", "5", "status")
    assert r.code == EXIT_OK, r.err
    assert "state        IDLE" in r.out and f"unique id    {UID_B.hex()}" in r.out


def test_info_without_a_node_is_no_reply(pmactl) -> None:
    r = pmactl("--node", "7", "info")
    assert r.code == EXIT_NO_REPLY
    assert "no DEVICE_INFO from node 7" in r.err


def test_scan_lists_devices_and_finds_two_on_one_id(pmactl, fake) -> None:
    fake(node=1, uid=UID_A)
    fake(node=2, uid=UID_B)
    r = pmactl("scan", "--seconds", "0.5")
    assert r.code == EXIT_OK, r.err
    assert UID_A.hex() in r.out and UID_B.hex() in r.out
    assert "2 node(s)" in r.out
    fake(node=2, uid=bytes(12))                 # a second device answering on id 2
    r = pmactl("scan", "--seconds", "0.5")
    assert r.code == EXIT_REFUSED
    assert "node id 2 is used by 2 devices" in r.err
    assert UID_B.hex() in r.err and bytes(12).hex() in r.err
    assert "node id 1" not in r.err


def test_a_node_of_another_protocol_version_is_reported_not_misread(pmactl, fake) -> None:
    mine = protocol_version(PROTO.db)
    fake(uid=UID_A, info_protocol_version=mine + 7)
    r = pmactl("info")
    assert r.code == EXIT_REFUSED
    assert f"speaks protocol version {mine + 7}; this pmactl speaks {mine}" in r.out
    # nothing of its other pages is shown as if it were understood
    assert "unique id    ?" in r.out and "firmware     ?" in r.out


def test_a_device_info_of_the_wrong_length_is_reported(pmactl, fake) -> None:
    fake(uid=UID_A, info_length=6)
    r = pmactl("--timeout", "0.5", "info")
    assert r.code == EXIT_REFUSED
    assert "a DEVICE_INFO frame of 6 bytes (want 8): ignored" in r.out
    assert "incomplete DEVICE_INFO" in r.out


def test_param_table_hash_is_the_firmwares() -> None:
    """pmactl's hash of its table is the PMA_PARAM_TABLE_HASH stamped into the firmware, and it
    changes with any range or default."""
    header = (REPO / "firmware/app/generated/pma_param_table.h").read_text()
    m = re.search(r"#define PMA_PARAM_TABLE_HASH 0x([0-9A-F]{8})u", header)
    assert m is not None
    rows = [{"id": p.id, "name": p.name, "type": p.type, "min": p.min, "max": p.max,
             "default": p.default} for p in PROTO.params]
    assert param_table_hash(rows) == int(m.group(1), 16)
    rows[3] = dict(rows[3], max=float(rows[3]["max"]) + 1.0)
    assert param_table_hash(rows) != int(m.group(1), 16)


def test_protocol_version_is_the_dbcs_version_line() -> None:
    header = (REPO / "firmware/protocol/generated/pma_proto_version.h").read_text()
    assert f"#define PMA_PROTO_VERSION {protocol_version(PROTO.db)}u" in header


def test_device_tag_is_crc8_smbus() -> None:
    assert device_tag(b"123456789") == 0xF4              # the CRC's check value
    assert device_tag(bytes(12)) == 0
    assert device_tag(bytes([0x10, 0x21, 0x32, 0x43, 0x54, 0x65, 0x76, 0x87, 0x98, 0xA9, 0xBA,
                             0xCB])) == 0x99             # tests/app/test_app_identity.c's id
