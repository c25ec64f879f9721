# SPDX-License-Identifier: Apache-2.0
"""The CAN protocol and parameter table, loaded from the firmware's sources.

Frame id = base id + node id (node 0..15); the DBC lists the base ids (node 0).
"""
from __future__ import annotations

import functools
import math
import os
import re
import struct
import tomllib
import zlib
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Any

import cantools
import cantools.database

from .frame_layout import FrameLayout

NODE_ID_MASK = 0x00F
BASE_ID_MASK = 0x7F0
NODE_COUNT = 16
# Messages sent to every node at once: their frame id is the DBC's, without a node id.
BROADCASTS = ("ESTOP_ALL", "DEVICE_INFO_REQ_ALL")

# HEARTBEAT Flags bits (firmware/app/app.h PMA_HB_*, docs/protocol.md "Heartbeat flags");
# the DBC has them only in a comment. host/tests check this table against app.h.
HEARTBEAT_FLAGS: dict[int, str] = {
    0: "OUTPUT_ACTIVE", 1: "PLANT_BRIDGE", 2: "LOCKSTEP", 3: "PARAMS_CHANGED",
    4: "PARAMS_DEFAULT", 5: "CAN_PASSIVE", 6: "SENSOR_VALID", 7: "REF_ACTIVE",
    8: "SAVE_FAILED", 9: "GUARANTEE_LOST", 10: "FALLBACK",
}

# One line on what each Result (the DBC's VAL_ table of COMMAND_ACK/PARAM_RESP) means on
# the bus (docs/protocol.md "Result codes"), keyed by the DBC's name: the codes and names
# always come from the DBC. host/tests check that every DBC name has a line here.
RESULT_MEANINGS: dict[str, str] = {
    "OK": "done",
    "NULL": "internal error (a missing argument)",
    "NOT_FINITE": "a value is NaN or infinite",
    "RANGE": "a value outside its range (a parameter, an argument, a rule between "
             "parameters, or the position at ARM)",
    "BAND": "the reference (with w1 for PPC) leaves the constraint band "
            "safety.x_min_cm..safety.x_max_cm within ref.horizon_s",
    "NOT_READY": "no position yet (no sensor sample received)",
    "UNSUPPORTED": "a valid value this build does not provide",
    "FIXED_RANGE": "a value not representable in the fixed-point format",
    "NOT_IMPLEMENTED": "not available on this node (e.g. SAVE/LOAD without parameter storage)",
    "EMPTY": "no parameter after this id",
    "FULL": "a queue was full",
    "BUS_OFF": "the CAN controller is still bus-off",
    "IO": "device I/O failed (e.g. the parameter storage)",
    "NOT_ERASED": "storage: programming over data that is not erased",
    "WIRE_BREAK": "the last sensor sample is at the wire-break level",
    "NO_RECORD": "the storage holds no valid parameter record",
    "VERIFY": "storage read-back differed (worn flash); the previous record stays",
    "CORRUPT": "stored data failed the integrity check",
    "UNKNOWN_ID": "no parameter with this id",
    "TYPE": "the value's type is not the parameter's",
    "STATE": "not allowed in the node's current state (see the parameter's access class)",
    "UNKNOWN_COMMAND": "unknown command or operation",
    "LENGTH": "frame with the wrong data length",
    "FAULT": "refused because a fault is latched: clear it first",
}

TELEM_FRAMES = ("TELEM_A", "TELEM_B", "TELEM_C", "TELEM_D", "TELEM_E")


def to_f32(x: float) -> float:
    """x rounded to IEEE 754 single precision, as the node stores an f32 parameter."""
    return float(struct.unpack("<f", struct.pack("<f", x))[0])


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
    # Names this parameter had in earlier firmware versions (params.toml `renamed_from`): a
    # parameter file of such a version is mapped by them (pmactl params load).
    renamed_from: tuple[str, ...] = ()

    def parse(self, text: str) -> float | int:
        """A value from user text: a number, or an enumeration value's name.

        ValueError with a message naming the parameter when the text is neither."""
        t = text.strip()
        for k, v in self.values.items():
            if t.upper() == v:
                return k
        try:
            if self.type == "f32":
                return float(t)
            try:
                return int(t, 0)
            except ValueError:
                f = float(t)            # "3.0" or "1e3" for an integer parameter
                if not f.is_integer():
                    raise
                return int(f)
        except ValueError:
            raise ValueError(f"{self.name}: {text!r} is not {self.expects()}") from None

    def expects(self) -> str:
        """What a value of this parameter is, in words (for error messages)."""
        what = {"f32": "a number", "u32": "an unsigned integer", "i32": "an integer"}[self.type]
        if self.values:
            what = "one of " + ", ".join(self.values.values()) + f" (or {what})"
        return what

    def check(self, value: object) -> float | int:
        """The value, validated against the table (type, finite, min..max, enumeration):
        a float for f32 parameters, an int otherwise. Names of enumeration values and
        numeric strings are accepted. ValueError with a clear message otherwise."""
        if isinstance(value, str):
            value = self.parse(value)
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ValueError(f"{self.name}: {value!r} is not {self.expects()}")
        if not math.isfinite(value):
            raise ValueError(f"{self.name}: {value} is not finite")
        if self.type == "f32":
            v: float | int = float(value)
        else:
            if isinstance(value, float) and not value.is_integer():
                raise ValueError(f"{self.name}: {value} is not {self.expects()}")
            v = int(value)
        if not self.min <= v <= self.max:
            unit = f" {self.unit}" if self.unit else ""
            raise ValueError(f"{self.name}: {self.text(v)}{unit} is outside "
                             f"{self.text(self.min)}..{self.text(self.max)}{unit}")
        if self.values and int(v) not in self.values:
            raise ValueError(f"{self.name}: {int(v)} is not {self.expects()}")
        return v

    def text(self, value: float | int) -> str:
        """A value as text: the name of an enumeration value, else the number
        (f32 with 7 significant digits, the precision it has on the node)."""
        if self.values and float(value).is_integer() and int(value) in self.values:
            return self.values[int(value)]
        if self.type == "f32":
            return f"{float(value):.7g}"
        return str(int(value))

    def same(self, a: float | int, b: float | int) -> bool:
        """Whether two values are the same on the node (f32: after rounding to single)."""
        if self.type == "f32":
            return to_f32(float(a)) == to_f32(float(b))
        return int(a) == int(b)


# The protocol's single sources of truth, in the repository. A built package (wheel, sdist)
# carries copies in pmactl/data/ (host/setup.py); an editable install reads them here.
REPO_FILES = {"pma_proto.dbc": "firmware/protocol/pma_proto.dbc", "params.toml": "firmware/app/params.toml"}


def _data_file(name: str, env: str) -> Path:
    """The DBC or parameter table: $env when set, else the package's copy, else (an
    editable install in the repository) the firmware's file."""
    override = os.environ.get(env)
    if override:
        return Path(override)
    packaged = Path(str(resources.files("pmactl") / "data" / name))
    if packaged.is_file():
        return packaged
    repo = Path(__file__).resolve().parents[3] / REPO_FILES[name]
    if repo.is_file():
        return repo
    raise FileNotFoundError(f"pmactl: {name} is neither in the package ({packaged}) nor in a "
                            f"repository checkout ({repo}): reinstall pmactl, or set {env}")


def data_files() -> dict[str, Path]:
    """Where this pmactl reads the DBC and the parameter table from."""
    return {"dbc": _data_file("pma_proto.dbc", "PMA_DBC"),
            "params": _data_file("params.toml", "PMA_PARAMS_TOML")}


@dataclass
class Protocol:
    db: cantools.database.can.Database
    params: list[Param]

    def __post_init__(self) -> None:
        self.by_name = {p.name: p for p in self.params}
        self.by_id = {p.id: p for p in self.params}
        self.messages = {m.name: m for m in self.db.messages}
        # raw codecs compiled once (frame_layout.py), where a message needs no cantools
        self.layouts: dict[str, FrameLayout | None] = {m.name: FrameLayout.of(m) for m in self.db.messages}
        self.status_names: dict[int, str] = self._choices("PARAM_RESP", "Result")
        self.fault_names: dict[int, str] = self._choices("HEARTBEAT", "FaultCode")
        self.state_names: dict[int, str] = self._choices("HEARTBEAT", "State")
        self.commands: dict[str, int] = {v: k for k, v in self._choices("COMMAND", "Command").items()}
        self.param_ops: dict[str, int] = {v: k for k, v in self._choices("PARAM_REQ", "Op").items()}
        # GET_STATUS's Ids: the DBC's value table StatusId (tied to the firmware's PMA_STATUS_*)
        tables = self.db.dbc.value_tables if self.db.dbc is not None else {}
        self.status_ids: dict[str, int] = {str(v): int(k) for k, v in tables.get("StatusId", {}).items()}

    @property
    def version(self) -> str:
        """The protocol version the DBC describes, as text (protocol_version())."""
        return str(protocol_version(self.db))

    def _choices(self, msg: str, sig: str) -> dict[int, str]:
        choices: dict[Any, Any] = dict(self.messages[msg].get_signal_by_name(sig).choices or {})
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
        return base if message in BROADCASTS else base | node

    def message_of(self, frame_id: int) -> tuple[str, int] | None:
        """(message name, node id) of a received frame id, or None."""
        for name in BROADCASTS:
            if name in self.messages and frame_id == self.messages[name].frame_id:
                return name, -1
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

    def signal_range(self, message: str, signal: str) -> tuple[float | None, float | None, str]:
        """(minimum, maximum, unit) of a signal as the DBC gives them (None: no limit)."""
        sig = self.messages[message].get_signal_by_name(signal)
        return sig.minimum, sig.maximum, sig.unit or ""

    def check_signal(self, message: str, signal: str, value: float | int, what: str | None = None,
                     finite: bool = True) -> float | int:
        """value, when the signal can carry it: a number (finite unless finite=False, which
        lets a NaN through as cantools does) within the DBC's range for the signal, what
        cantools would refuse to encode. ValueError naming `what` (default MESSAGE.Signal), the
        value, the range and the unit otherwise: check before sending, nothing is sent."""
        name = what or f"{message}.{signal}"
        lo, hi, unit = self.signal_range(message, signal)
        u = f" {unit}" if unit else ""
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ValueError(f"{name}: {value!r} is not a number")
        if finite and not math.isfinite(value):
            raise ValueError(f"{name}: {value} is not finite")
        if (lo is not None and value < lo) or (hi is not None and value > hi):
            def num(x: float | int | None) -> str:
                if x is None:
                    return ""
                return str(int(x)) if float(x).is_integer() and abs(x) < 1e16 else f"{x:g}"
            raise ValueError(f"{name}: {num(value)}{u} is outside {num(lo)}..{num(hi)}{u} (the range "
                             f"{message} carries; nothing sent)")
        return value

    def encode_raw(self, message: str, data: Mapping[str, int | float]) -> bytes:
        """`encode` without cantools where the message has a compiled layout (the HIL loop's
        frames): raw values, each within its signal's bits (ValueError otherwise)."""
        layout = self.layouts[message]
        return layout.encode(data) if layout is not None else self.encode(message, dict(data))

    def decode(self, message: str, data: bytes) -> dict[str, Any]:
        """The signals of a frame (raw values). A multiplexed frame (PARAM_REQ, PARAM_RESP) whose
        multiplexer (Type) has a value the DBC does not define, such as the Type 3..15
        a node echoes from a request (docs/protocol.md), decodes to its plain signals
        (Op, Type, Id, Result) without a value signal."""
        layout = self.layouts[message]
        if layout is not None:
            return layout.decode(data)
        m = self.messages[message]
        try:
            decoded = m.decode(data, decode_choices=False, scaling=False)
            assert isinstance(decoded, dict)        # not a container message
            return dict(decoded)
        except cantools.database.DecodeError:
            mux = [s for s in m.signals if s.is_multiplexer]
            if len(mux) != 1 or mux[0].byte_order != "little_endian" or len(data) < m.length:
                raise
            sm = mux[0]
            word = int.from_bytes(bytes(data), "little")
            mask = (1 << sm.length) - 1
            raw = (word >> sm.start) & mask
            known = sorted(k for s in m.signals for k in (s.multiplexer_ids or []))
            if not known or raw in known:
                raise
            patched = word & ~(mask << sm.start) | (known[0] << sm.start)
            patched_sig = m.decode(patched.to_bytes(len(data), "little"), decode_choices=False,
                                   scaling=False)
            assert isinstance(patched_sig, dict)
            sig = dict(patched_sig)
            out = {s.name: sig[s.name] for s in m.signals if not s.multiplexer_ids and s.name in sig}
            out[sm.name] = raw
            return out

    def status_name(self, code: int) -> str:
        return self.status_names.get(code, f"status {code}")

    def status_text(self, code: int) -> str:
        """'NAME (code): meaning' of a Result code."""
        name = self.status_name(code)
        meaning = RESULT_MEANINGS.get(name)
        return f"{name} ({code})" + (f": {meaning}" if meaning else "")

    def enum_names(self, msg: str, sig: str) -> dict[int, str]:
        """The VAL_ table of a signal (value -> name)."""
        return self._choices(msg, sig)

    @staticmethod
    def flag_names(flags: int) -> list[str]:
        """Names of the HEARTBEAT Flags bits that are set (unknown bits as BIT<n>)."""
        return [HEARTBEAT_FLAGS.get(b, f"BIT{b}") for b in range(16) if flags >> b & 1]


def param_table_hash(rows: Iterable[Mapping[str, Any]]) -> int:
    """CRC-32 of a parameter table: what a node reports as ParamTableHash (DEVICE_INFO page 2).

    The one definition of the hash: tools/gen_protocol.py stamps it into the firmware
    (PMA_PARAM_TABLE_HASH) from firmware/app/params.toml, and pmactl compares a node's with its
    own table's. Over, for each parameter in id order: id, name, type, min, max, default (as
    the table writes them; floats as float32), one line each, UTF-8."""
    lines = []
    for r in sorted(rows, key=lambda q: int(q["id"])):
        def num(v: Any, r: Any = r) -> str:
            return repr(to_f32(float(v))) if r["type"] == "f32" else str(int(v))
        lines.append(f"{int(r['id'])} {r['name']} {r['type']} {num(r['min'])} {num(r['max'])} "
                     f"{num(r['default'])}\n")
    return zlib.crc32("".join(lines).encode()) & 0xFFFFFFFF


def protocol_version(db: cantools.database.can.Database) -> int:
    """The protocol version of a DBC: the number of its VERSION line ("pma_proto N")."""
    m = re.fullmatch(r"pma_proto (\d+)", (db.version or "").strip())
    if m is None:
        raise ValueError(f"the DBC's VERSION line is {db.version!r}, not 'pma_proto N'")
    return int(m.group(1))


@functools.cache
def load_protocol(dbc: str | None = None, params: str | None = None) -> Protocol:
    dbc_path = Path(dbc) if dbc else _data_file("pma_proto.dbc", "PMA_DBC")
    params_path = Path(params) if params else _data_file("params.toml", "PMA_PARAMS_TOML")
    db = cantools.database.load_file(str(dbc_path))
    with params_path.open("rb") as f:
        rows = tomllib.load(f)["param"]
    plist = [Param(id=r["id"], name=r["name"], type=r["type"], unit=r["unit"], min=r["min"],
                   max=r["max"], default=r["default"], access=r["access"], doc=r["doc"],
                   values={int(k): str(v) for k, v in r.get("values", {}).items()},
                   renamed_from=tuple(str(n) for n in r.get("renamed_from", ())))
             for r in rows]
    assert isinstance(db, cantools.database.can.Database)
    return Protocol(db=db, params=sorted(plist, key=lambda p: p.id))
