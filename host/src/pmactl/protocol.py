"""The CAN protocol and parameter table, loaded from the firmware's sources.

Frame id = base id + node id (node 0..15); the DBC lists the base ids (node 0).
"""
from __future__ import annotations

import functools
import os
import tomllib
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Any

import cantools
import cantools.database

NODE_ID_MASK = 0x00F
BASE_ID_MASK = 0x7F0
NODE_COUNT = 16


@dataclass(frozen=True)
class Param:
    """One row of the parameter table (firmware/app/params.toml)."""
    id: int
    name: str
    type: str            # "f32" | "u32" | "i32"
    unit: str
    min: float | int
    max: float | int
    default: float | int
    access: str          # "live" | "stopped" | "idle"
    doc: str
    values: dict[int, str] = field(default_factory=dict)

    def parse(self, text: str) -> float | int:
        """A value from user text: a number, or an enumeration value's name."""
        for k, v in self.values.items():
            if text.strip().upper() == v:
                return k
        if self.type == "f32":
            return float(text)
        return int(text, 0)


def _data_file(name: str, env: str) -> Path:
    override = os.environ.get(env)
    if override:
        return Path(override)
    return Path(str(resources.files("pmactl") / "data" / name))


@dataclass
class Protocol:
    db: cantools.database.can.Database
    params: list[Param]

    def __post_init__(self) -> None:
        self.by_name = {p.name: p for p in self.params}
        self.by_id = {p.id: p for p in self.params}
        self.messages = {m.name: m for m in self.db.messages}
        self.status_names: dict[int, str] = {
            int(k): str(v)
            for k, v in self.messages["PARAM_RESP"].get_signal_by_name("Result").choices.items()}
        self.fault_names: dict[int, str] = self._choices("HEARTBEAT", "FaultCode")
        self.state_names: dict[int, str] = self._choices("HEARTBEAT", "State")
        self.commands: dict[str, int] = {v: k for k, v in self._choices("COMMAND", "Command").items()}

    def _choices(self, msg: str, sig: str) -> dict[int, str]:
        choices = self.messages[msg].get_signal_by_name(sig).choices or {}
        return {int(k): str(v) for k, v in choices.items()}

    def param(self, key: str | int) -> Param:
        """A parameter by name or id; KeyError with the name when unknown."""
        if isinstance(key, int) or (isinstance(key, str) and key.isdigit()):
            p = self.by_id.get(int(key))
        else:
            p = self.by_name.get(key)
        if p is None:
            raise KeyError(f"no parameter {key!r}")
        return p

    def frame_id(self, message: str, node: int) -> int:
        if not 0 <= node < NODE_COUNT:
            raise ValueError(f"node id {node} outside 0..15")
        base = self.messages[message].frame_id
        return base if message == "ESTOP_ALL" else base | node

    def message_of(self, frame_id: int) -> tuple[str, int] | None:
        """(message name, node id) of a received frame id, or None."""
        if frame_id == self.messages["ESTOP_ALL"].frame_id:
            return "ESTOP_ALL", -1
        try:
            m = self.db.get_message_by_frame_id(frame_id & BASE_ID_MASK)
        except KeyError:
            return None
        return m.name, frame_id & NODE_ID_MASK

    def encode(self, message: str, data: dict[str, Any] | None = None) -> bytes:
        m = self.messages[message]
        if not m.signals:
            return b""
        return bytes(m.encode(data or {}, scaling=False, strict=True))

    def decode(self, message: str, data: bytes) -> dict[str, Any]:
        return dict(self.messages[message].decode(data, decode_choices=False, scaling=False))

    def status_name(self, code: int) -> str:
        return self.status_names.get(code, f"status {code}")


@functools.cache
def load_protocol(dbc: str | None = None, params: str | None = None) -> Protocol:
    dbc_path = Path(dbc) if dbc else _data_file("pma_proto.dbc", "PMA_DBC")
    params_path = Path(params) if params else _data_file("params.toml", "PMA_PARAMS_TOML")
    db = cantools.database.load_file(str(dbc_path))
    with params_path.open("rb") as f:
        rows = tomllib.load(f)["param"]
    plist = [Param(id=r["id"], name=r["name"], type=r["type"], unit=r["unit"], min=r["min"],
                   max=r["max"], default=r["default"], access=r["access"], doc=r["doc"],
                   values={int(k): str(v) for k, v in r.get("values", {}).items()})
             for r in rows]
    assert isinstance(db, cantools.database.can.Database)
    return Protocol(db=db, params=sorted(plist, key=lambda p: p.id))
