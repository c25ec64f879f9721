"""pma-fw-host's identity on the wire (DEVICE_INFO): what it reports (VERSION, the git commit,
the build target, the protocol version, the parameter table, the unique id from --uid or from
its storage file), the broadcast request, a malformed request, and two devices on one node id
found by a scan."""
from __future__ import annotations

import subprocess
from pathlib import Path

import can
import pytest

from conftest import CHANNEL, FW_HOST
from pmactl import cli, identity
from pmactl.client import PmaNode
from pmactl.protocol import Protocol, param_table_hash, protocol_version

REPO = Path(__file__).resolve().parents[2]
UID = "00112233445566778899aabb"


def test_device_info_reports_the_build_and_the_given_uid(firmware, proto: Protocol) -> None:
    _, node = firmware(node=3, extra=["--uid", UID])
    dev = identity.device_info(node)
    assert dev.complete and dev.problems == []
    version = tuple(int(v) for v in (REPO / "VERSION").read_text().split("."))
    assert dev.fw_version == version
    assert dev.protocol_version == protocol_version(proto.db)
    assert dev.build_target == "HOST"
    assert dev.param_count == len(proto.params)
    rows = [{"id": p.id, "name": p.name, "type": p.type, "min": p.min, "max": p.max,
             "default": p.default} for p in proto.params]
    assert dev.param_table_hash == param_table_hash(rows)
    assert dev.uid_hex == UID
    head = subprocess.run(["git", "-C", str(REPO), "rev-parse", "--short=8", "HEAD"],
                          capture_output=True, text=True)
    if head.returncode == 0:   # built from this checkout (the build stamps the commit)
        assert dev.commit_known and f"{dev.fw_commit:08x}" == head.stdout.strip()


def test_the_uid_follows_the_storage_file(firmware, tmp_path: Path) -> None:
    fw, node = firmware(node=1, storage=tmp_path / "a.nvm")
    first = identity.device_info(node).uid_hex
    fw.stop()
    fw, node = firmware(node=1, storage=tmp_path / "a.nvm")
    assert identity.device_info(node).uid_hex == first      # same storage: same device
    fw.stop()
    _, node = firmware(node=1, storage=tmp_path / "b.nvm")
    assert identity.device_info(node).uid_hex != first      # another storage: another device


def test_bad_uid_option_is_a_usage_error() -> None:
    for bad in ("0011", UID + "00", "zz" * 12):
        r = subprocess.run([str(FW_HOST), "--can", CHANNEL, "--uid", bad], capture_output=True,
                           text=True, timeout=10)
        assert r.returncode == 2 and "--uid wants 24 hexadecimal digits" in r.stderr, r


def test_wrong_length_request_is_dropped(firmware, bus: can.BusABC, proto: Protocol) -> None:
    _, node = firmware(node=2, extra=["--uid", UID])
    node.listen_to(["DEVICE_INFO"])
    bus.send(can.Message(arbitration_id=proto.frame_id("DEVICE_INFO_REQ", 2), data=b"\x00",
                         is_extended_id=False))
    bus.send(can.Message(arbitration_id=proto.messages["DEVICE_INFO_REQ_ALL"].frame_id,
                         data=b"\x01\x02", is_extended_id=False))
    got = []
    while (m := bus.recv(0.5)) is not None:
        got.append(m)
    assert got == []
    assert identity.device_info(node).uid_hex == UID          # a valid one is still answered


def test_scan_finds_two_devices_on_one_node_id(firmware, bus: can.BusABC, proto: Protocol,
                                               tmp_path: Path) -> None:
    firmware(node=4, storage=tmp_path / "x.nvm", extra=["--uid", UID])
    firmware(node=4, storage=tmp_path / "y.nvm", extra=["--uid", "ff" * 12])
    firmware(node=6, storage=tmp_path / "z.nvm", extra=["--uid", "ee" * 12])
    client = PmaNode(bus, 0, proto, timeout_s=2.0)
    found = identity.discover(client, seconds=1.0)
    assert sorted(d.uid_hex for d in found[4]) == sorted([UID, "ff" * 12])
    assert [d.uid_hex for d in found[6]] == ["ee" * 12]
    assert all(d.complete and not d.problems for devs in found.values() for d in devs)


def test_pmactl_scan_reports_the_duplicate(firmware, tmp_path: Path,
                                           capsys: pytest.CaptureFixture[str]) -> None:
    firmware(node=4, storage=tmp_path / "x.nvm", extra=["--uid", UID])
    firmware(node=4, storage=tmp_path / "y.nvm", extra=["--uid", "ff" * 12])
    code = cli.main(["--interface", "socketcan", "--channel", CHANNEL, "scan", "--seconds", "1"])
    out, err = capsys.readouterr()
    assert code == cli.EXIT_REFUSED, (out, err)
    assert "node id 4 is used by 2 devices" in err and UID in err
    assert UID in out and "ff" * 12 in out
