# SPDX-License-Identifier: Apache-2.0
"""Node identity: DEVICE_INFO (firmware version, build, protocol version, parameter table hash,
unique device id), asked of one node (DEVICE_INFO_REQ) or of every node at once
(DEVICE_INFO_REQ_ALL: how a scan finds two devices answering on one node id).

A node answers with five frames, Page 0..4 (docs/protocol.md "DEVICE_INFO"). Pages are read from
the raw frames, not through PmaNode.receive(), so that a page of the wrong length is reported
rather than silently dropped, and a node that speaks another protocol version is reported
rather than misread: of such a node only the version page, whose layout every version keeps,
is decoded.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import can

from pmactl.protocol import NODE_ID_MASK, param_table_hash, protocol_version

if TYPE_CHECKING:
    from pmactl.client import PmaNode, Status

PAGES = 5                      # Page 0..4
PAGE_BYTES = 8                 # DEVICE_INFO's DLC
UID_BYTES = 12


def device_tag(uid: bytes) -> int:
    """DEVICE_INFO's DeviceTag of a unique id: CRC-8/SMBUS (polynomial 0x07, initial value 0,
    no reflection, no final XOR) of its bytes."""
    crc = 0
    for byte in uid:
        crc ^= byte
        for _ in range(8):
            crc = ((crc << 1) ^ 0x07) & 0xFF if crc & 0x80 else (crc << 1) & 0xFF
    return crc


@dataclass
class DeviceInfo:
    """What one device said about itself (fields None until their page arrived)."""
    node: int
    tag: int | None = None             # DeviceTag: which device of the node id
    protocol_version: int | None = None
    fw_version: tuple[int, int, int] | None = None
    build_target: str | None = None
    dirty: bool | None = None
    commit_known: bool | None = None
    param_count: int | None = None
    fw_commit: int | None = None
    param_table_hash: int | None = None
    uid_low: int | None = None
    uid_high: int | None = None
    pages: set[int] = field(default_factory=set)
    problems: list[str] = field(default_factory=list)

    @property
    def complete(self) -> bool:
        return self.pages == set(range(PAGES))

    @property
    def uid(self) -> bytes | None:
        """The 12-byte unique id (byte 0 first), None until both pages arrived."""
        if self.uid_low is None or self.uid_high is None:
            return None
        return self.uid_low.to_bytes(6, "little") + self.uid_high.to_bytes(6, "little")

    @property
    def uid_hex(self) -> str:
        u = self.uid
        return u.hex() if u is not None else "?"

    @property
    def fw_text(self) -> str:
        if self.fw_version is None:
            return "?"
        text = "%d.%d.%d" % self.fw_version
        if self.commit_known and self.fw_commit is not None:
            text += f"+{self.fw_commit:08x}"
        if self.dirty:
            text += "-dirty"
        return text

    def as_dict(self) -> dict[str, Any]:
        """JSON-friendly (HIL summary.json, pmactl --json)."""
        return {
            "node": self.node, "protocol_version": self.protocol_version,
            "firmware": self.fw_text, "build_target": self.build_target,
            "dirty": self.dirty, "commit": None if not self.commit_known or self.fw_commit is None
            else f"{self.fw_commit:08x}", "param_count": self.param_count,
            "param_table_hash": None if self.param_table_hash is None
            else f"{self.param_table_hash:08x}", "uid": None if self.uid is None else self.uid_hex,
            "problems": list(self.problems),
        }


class InfoCollector:
    """Turns raw DEVICE_INFO frames into DeviceInfo per (node id, device).

    The devices' replies may interleave on the bus; every page carries the device's DeviceTag
    (a CRC-8 of its unique id), so pages are grouped per (node id, tag), and a repeated page
    of a group starts a new device (two devices with equal tags, 1 in 256, that interleave are
    then told apart by their UIDs only if their pages do not mix)."""

    def __init__(self, node: PmaNode) -> None:
        self.node = node
        self.proto = node.proto
        self.msg = self.proto.messages["DEVICE_INFO"]
        self.base = self.msg.frame_id
        self.my_version = protocol_version(self.proto.db)
        self.my_hash = param_table_hash(
            {"id": p.id, "name": p.name, "type": p.type, "min": p.min, "max": p.max,
             "default": p.default} for p in self.proto.params)
        self.devices: dict[int, list[DeviceInfo]] = {}

    def feed(self, msg: can.Message) -> None:
        if msg.is_extended_id or msg.is_error_frame or msg.is_remote_frame:
            return
        if msg.arbitration_id & ~NODE_ID_MASK != self.base:
            return
        nid = msg.arbitration_id & NODE_ID_MASK
        data = bytes(msg.data)
        devs = self.devices.setdefault(nid, [])
        if len(data) != PAGE_BYTES:
            target = devs[-1] if devs else self._new(nid)
            target.problems.append(f"a DEVICE_INFO frame of {len(data)} bytes (want "
                                   f"{PAGE_BYTES}): ignored")
            return
        page, tag = data[0], data[7]
        mine = [d for d in devs if d.tag == tag]
        if not mine or page in mine[-1].pages:
            dev = self._new(nid)
            dev.tag = tag
        else:
            dev = mine[-1]
        if page >= PAGES:
            dev.problems.append(f"unknown DEVICE_INFO page {page}: ignored")
            return
        if page == 0:
            # Bytes 0..1 (Page, ProtocolVersion) keep their place in every protocol version.
            dev.protocol_version = data[1]
        if page != 0 and dev.protocol_version is not None and dev.protocol_version != self.my_version:
            dev.pages.add(page)  # received, not decoded: its layout may differ
            return
        decoded = self.msg.decode(data, decode_choices=False, scaling=False)
        assert isinstance(decoded, dict)        # not a container message
        sig: dict[str, Any] = decoded
        dev.pages.add(page)
        if page == 0:
            if dev.protocol_version != self.my_version:
                dev.problems.append(
                    f"speaks protocol version {dev.protocol_version}; this pmactl speaks "
                    f"{self.my_version}: its other messages are not decoded (update pmactl or "
                    f"the firmware)")
                return
            dev.fw_version = (int(sig["FwMajor"]), int(sig["FwMinor"]), int(sig["FwPatch"]))
            targets = self.proto.enum_names("DEVICE_INFO", "BuildTarget")
            dev.build_target = targets.get(int(sig["BuildTarget"]), f"target {sig['BuildTarget']}")
            flags = int(sig["BuildFlags"])
            dev.dirty = bool(flags & 1)
            dev.commit_known = not flags & 2
        elif page == 1:
            dev.fw_commit = int(sig["FwCommit"])
            dev.param_count = int(sig["ParamCount"])
        elif page == 2:
            dev.param_table_hash = int(sig["ParamTableHash"])
            if dev.param_table_hash != self.my_hash:
                dev.problems.append(
                    f"parameter table hash {dev.param_table_hash:08x} differs from pmactl's "
                    f"{self.my_hash:08x}: another firmware version's table (parameters map by "
                    f"name; see pmactl params load)")
        elif page == 3:
            dev.uid_low = int(sig["UidLow"])
        else:
            dev.uid_high = int(sig["UidHigh"])
        uid = dev.uid
        if uid is not None and device_tag(uid) != dev.tag:
            dev.problems.append(f"DeviceTag {dev.tag:02x} is not the CRC-8 of the unique id "
                                f"{uid.hex()} ({device_tag(uid):02x}): pages of two devices mixed?")

    def _new(self, nid: int) -> DeviceInfo:
        dev = DeviceInfo(node=nid)
        self.devices.setdefault(nid, []).append(dev)
        return dev

    def result(self) -> dict[int, list[DeviceInfo]]:
        """Per node id, its devices; two devices with the same UID (one device that answered
        twice) are one, whatever else they said."""
        out: dict[int, list[DeviceInfo]] = {}
        for nid, devs in sorted(self.devices.items()):
            merged: list[DeviceInfo] = []
            seen: dict[bytes, DeviceInfo] = {}
            for d in devs:
                u = d.uid
                if u is not None and u in seen:
                    seen[u].problems.extend(p for p in d.problems if p not in seen[u].problems)
                    continue
                if u is not None:
                    seen[u] = d
                merged.append(d)
            for d in merged:
                if not d.complete and not any("protocol version" in p for p in d.problems):
                    missing = sorted(set(range(PAGES)) - d.pages)
                    d.problems.append(f"incomplete DEVICE_INFO: pages {missing} missing")
            out[nid] = merged
        return out


def _collect(node: PmaNode, send: tuple[int, bytes], seconds: float,
             done: Any = None) -> dict[int, list[DeviceInfo]]:
    col = InfoCollector(node)
    node.raw_listeners.append(col.feed)
    try:
        node.send_raw(*send)
        deadline = time.monotonic() + seconds
        while (left := deadline - time.monotonic()) > 0:
            node.receive(left)
            if done is not None and done(col):
                break
    finally:
        node.raw_listeners.remove(col.feed)
    return col.result()


def device_info(node: PmaNode, node_id: int | None = None,
                timeout_s: float | None = None) -> DeviceInfo:
    """The identity of one node (DEVICE_INFO_REQ). NoReply when nothing answered; with two
    devices on the id, the first (discover() lists both)."""
    from pmactl.client import NoReply

    nid = node.node if node_id is None else node_id
    req = (node.proto.frame_id("DEVICE_INFO_REQ", nid), b"")

    def complete(col: InfoCollector) -> bool:
        devs = col.devices.get(nid, [])
        return len(devs) == 1 and devs[0].complete

    found = _collect(node, req, node.timeout_s if timeout_s is None else timeout_s, complete)
    devs = found.get(nid, [])
    if not devs:
        raise NoReply(f"no DEVICE_INFO from node {nid} (firmware before protocol version 2 does "
                      f"not send one)")
    return devs[0]


def discover(node: PmaNode, seconds: float = 0.5) -> dict[int, list[DeviceInfo]]:
    """Every device on the bus (DEVICE_INFO_REQ_ALL), per node id: more than one device under a
    node id means two devices answer on that id."""
    req = (node.proto.messages["DEVICE_INFO_REQ_ALL"].frame_id, b"")
    return _collect(node, req, seconds)


def scan_with_identity(node: PmaNode, seconds: float = 1.0
                       ) -> tuple[dict[int, Status], dict[int, list[DeviceInfo]]]:
    """One listening window for heartbeats (client.scan) with DEVICE_INFO_REQ_ALL sent at its
    start: the nodes' last Status, and every device per node id."""
    from pmactl.client import scan

    col = InfoCollector(node)
    node.raw_listeners.append(col.feed)
    try:
        node.send_raw(node.proto.messages["DEVICE_INFO_REQ_ALL"].frame_id, b"")
        statuses = scan(node, seconds)
    finally:
        node.raw_listeners.remove(col.feed)
    return statuses, col.result()
