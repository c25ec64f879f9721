# SPDX-License-Identifier: Apache-2.0
"""Raw (unscaled) encode and decode of a DBC message from a layout compiled once.

cantools builds its codec per call around general machinery (byte orders, multiplexers,
containers, scaling, choices); the lockstep HIL loop encodes a PLANT_SENSOR and decodes a
PLANT_ACTUATOR, telemetry and heartbeats every millisecond. A `FrameLayout` is taken from the
cantools message itself (each signal's start bit, length, signedness, IEEE float or integer),
so the DBC stays the one truth; it covers the messages whose signals are all little-endian
and not multiplexed (every message the loop handles), and `FrameLayout.of` returns None for
the others, which keep cantools. Its results equal cantools' `decode(data,
decode_choices=False, scaling=False)` and `encode(values, scaling=False)` (host/tests check
every such message of the DBC against cantools).
"""
from __future__ import annotations

import struct
from collections.abc import Mapping
from dataclasses import dataclass

import cantools.database

_F32 = struct.Struct("<f")
_F64 = struct.Struct("<d")


@dataclass(frozen=True)
class _Field:
    name: str
    start: int          # bit, little-endian numbering (bit 0 = byte 0's LSB)
    mask: int           # (1 << length) - 1
    sign: int           # 1 << (length - 1) for a signed integer, else 0
    float_struct: struct.Struct | None   # IEEE single or double, else None


class FrameLayout:
    """One message's signals, for raw values: `decode(data)` -> {signal: int | float},
    `encode(values)` -> bytes of the message's length (bits no signal covers are 0)."""

    def __init__(self, name: str, length: int, fields: tuple[_Field, ...]) -> None:
        self.name, self.length, self.fields = name, length, fields

    @classmethod
    def of(cls, message: cantools.database.can.Message) -> FrameLayout | None:
        """The message's layout, or None where it needs cantools (a big-endian or multiplexed
        signal, a container message)."""
        if message.is_container:
            return None
        fields = []
        for s in message.signals:
            if s.byte_order != "little_endian" or s.is_multiplexer or s.multiplexer_ids:
                return None
            fs = None
            if s.is_float:
                if s.length not in (32, 64) or s.start % 8:
                    return None
                fs = _F32 if s.length == 32 else _F64
            fields.append(_Field(s.name, s.start, (1 << s.length) - 1,
                                 (1 << (s.length - 1)) if s.is_signed and fs is None else 0, fs))
        return cls(message.name, message.length, tuple(fields))

    def decode(self, data: bytes) -> dict[str, int | float]:
        """The raw signal values of a frame: DecodeError when it is shorter than the message
        (extra bytes are ignored, as cantools does)."""
        if len(data) < self.length:
            raise cantools.database.DecodeError(
                f"{self.name}: {len(data)} data bytes, the message has {self.length}")
        word = int.from_bytes(data[:self.length], "little")
        out: dict[str, int | float] = {}
        for f in self.fields:
            raw = (word >> f.start) & f.mask
            if f.float_struct is not None:
                out[f.name] = f.float_struct.unpack(raw.to_bytes(f.float_struct.size, "little"))[0]
            elif f.sign and raw & f.sign:
                out[f.name] = raw - (f.mask + 1)
            else:
                out[f.name] = raw
        return out

    def encode(self, values: Mapping[str, int | float]) -> bytes:
        """The frame of these raw values: every signal must be given, an integer within its
        bits (KeyError, ValueError otherwise)."""
        word = 0
        for f in self.fields:
            v = values[f.name]
            if f.float_struct is not None:
                raw = int.from_bytes(f.float_struct.pack(float(v)), "little")
            else:
                iv = int(v)
                if iv != v:
                    raise ValueError(f"{self.name}.{f.name}: {v!r} is not an integer")
                lo, hi = (-f.sign, f.sign - 1) if f.sign else (0, f.mask)
                if not lo <= iv <= hi:
                    raise ValueError(f"{self.name}.{f.name}: {iv} outside {lo}..{hi}")
                raw = iv & f.mask
            word |= raw << f.start
        return word.to_bytes(self.length, "little")
