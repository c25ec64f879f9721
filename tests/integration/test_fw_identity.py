# SPDX-License-Identifier: Apache-2.0
"""pma-fw-host's identity on the wire (DEVICE_INFO): what it reports (VERSION, the git commit,
the build target, the protocol version, the parameter table, the unique id from --uid or from
its storage file), the broadcast request, a malformed request, and two devices on one node id
found by a scan."""
from __future__ import annotations

import re
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
    # what the build stamped (cmake/PmaBuildInfo.cmake writes it beside the program's objects)
    stamp = (FW_HOST.parents[2] / "app" / "pma_build_info.c").read_text()
    m = re.search(r"\.fw_commit = (0x[0-9a-f]+|0)u", stamp)
    assert m is not None
    assert dev.fw_commit == int(m.group(1), 16 if m.group(1).startswith("0x") else 10)
    f = re.search(r"\.build_flags = (\d+)u", stamp)
    assert f is not None and dev.dirty == bool(int(f.group(1)) & 1)
    assert dev.commit_known == (not int(f.group(1)) & 2)


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


def wait_devices(client: PmaNode, node_id: int, n: int) -> None:
    """Until n devices answer on node_id (the fixture waits for a heartbeat of the id, which
    the first device already gives)."""
    for _ in range(50):
        if len(identity.discover(client, seconds=0.3).get(node_id, [])) >= n:
            return
    raise AssertionError(f"{n} devices never answered on node id {node_id}")


def test_scan_finds_two_devices_on_one_node_id(firmware, bus: can.BusABC, proto: Protocol,
                                               tmp_path: Path) -> None:
    firmware(node=4, storage=tmp_path / "x.nvm", extra=["--uid", UID])
    firmware(node=4, storage=tmp_path / "y.nvm", extra=["--uid", "ff" * 12])
    firmware(node=6, storage=tmp_path / "z.nvm", extra=["--uid", "ee" * 12])
    client = PmaNode(bus, 0, proto, timeout_s=2.0)
    wait_devices(client, 4, 2)
    found = identity.discover(client, seconds=1.0)
    assert sorted(d.uid_hex for d in found[4]) == sorted([UID, "ff" * 12])
    assert [d.uid_hex for d in found[6]] == ["ee" * 12]
    assert all(d.complete and not d.problems for devs in found.values() for d in devs)


def test_pmactl_scan_reports_the_duplicate(firmware, bus: can.BusABC, proto: Protocol,
                                           tmp_path: Path,
                                           capsys: pytest.CaptureFixture[str]) -> None:
    firmware(node=4, storage=tmp_path / "x.nvm", extra=["--uid", UID])
    firmware(node=4, storage=tmp_path / "y.nvm", extra=["--uid", "ff" * 12])
    wait_devices(PmaNode(bus, 0, proto, timeout_s=2.0), 4, 2)
    code = cli.main(["--interface", "socketcan", "--channel", CHANNEL, "scan", "--seconds", "1"])
    out, err = capsys.readouterr()
    assert code == cli.EXIT_REFUSED, (out, err)
    assert "node id 4 is used by 2 devices" in err and UID in err
    assert UID in out and "ff" * 12 in out


def test_pmactl_moves_a_node_to_another_id(bus: can.BusABC, proto: Protocol, tmp_path: Path,
                                           capsys: pytest.CaptureFixture[str]) -> None:
    """set, save, RESTART, verify: the node (started without --node, so its stored sys.node_id
    counts) restarts itself (the same process, re-executed) and answers on the new id, with the
    same unique id and reset cause SOFTWARE."""
    from hil.fw_process import FirmwareProcess

    store = tmp_path / "move.nvm"
    args = ["--storage", str(store), "--lockstep", "--watchdog-ms", "10000"]
    fw = FirmwareProcess(tmp_path, args).start()
    try:
        assert fw.proc is not None
        pid = fw.proc.pid
        PmaNode(bus, 0, proto, timeout_s=5.0).heartbeat(timeout_s=10.0)
        code = cli.main(["--interface", "socketcan", "--channel", CHANNEL, "--node", "0", "node-id",
                         "9", "--wait", "60"])
        out, err = capsys.readouterr()
        assert code == cli.EXIT_OK, (out, err)
        assert "sys.node_id = 9 set and saved; restarting it" in out
        assert "verified: the device" in out and "answers on node id 9" in out
        st = PmaNode(bus, 9, proto, timeout_s=5.0).wait_state("IDLE", timeout_s=10.0)
        assert st.reset_cause_name == "SOFTWARE"
        assert fw.proc.poll() is None and fw.proc.pid == pid
    finally:
        fw.stop()
    assert "software reset: re-executing" in fw.output()
