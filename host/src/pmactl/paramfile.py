# SPDX-License-Identifier: Apache-2.0
"""Parameter files: a node's parameters as JSON (or YAML, when PyYAML is installed).

    {
      "format": "pmactl-params 1",
      "node": 0,
      "firmware": {"version": "0.2.0+1ecbb2e0", "protocol_version": 2,
                   "param_table_hash": "9fde4e7c", "unique_id": "0011..."},
      "params": {"ctrl.mode": "PPC", "ppc.w1_cm": 0.2, ...},
      "units": {"ctrl.mode": "", "ppc.w1_cm": "cm", ...}
    }

``params`` is required: parameter name -> value (a number, or for enumerations the
value's name). ``format`` and ``node`` are optional and informational (``format`` must
be this one when present); ``units``, when present, must give each listed parameter
the unit of the parameter table (so a file never means other units than the node's).
f32 values are written with the fewest digits that give the node's single-precision
value back. ``firmware`` (written by ``params dump`` from the node's DEVICE_INFO) says which
firmware and parameter table the values come from.

Loading (plan()): a file whose table hash is pmactl's own, or that records none (written by
hand), is checked strictly (an unknown name, a value out of range: the file is refused, nothing
sent). A file from another firmware version (another table hash recorded) is mapped by name: a parameter the table does
not know is dropped, one known under an earlier name (params.toml ``renamed_from``) is renamed,
a value outside the new range is clamped to it, an enumeration value or unit the table no longer
has is dropped; each is reported, and so are the table's parameters the file lacks (they keep
the node's values). ``sys.node_id`` is never loaded unless asked (a file copied from one node
to another must not give both one id).
"""
from __future__ import annotations

import json
import math
import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from pmactl.protocol import Param, Protocol, param_table_hash, to_f32

FORMAT = "pmactl-params 1"
NODE_ID_PARAM = "sys.node_id"
TOP_LEVEL = ("format", "node", "firmware", "params", "units")
JSON_SUFFIXES = (".json",)
YAML_SUFFIXES = (".yaml", ".yml")


class ParamFileError(ValueError):
    """A parameter file that cannot be used; `problems` lists every reason."""

    def __init__(self, path: str, problems: list[str]) -> None:
        super().__init__(f"{path}: " + "; ".join(problems))
        self.path = path
        self.problems = problems


def _yaml() -> Any:
    try:
        import yaml
    except ImportError:
        return None
    return yaml


def yaml_available() -> bool:
    return _yaml() is not None


def _kind(path: str) -> str:
    if path == "-":
        return "json"
    suffix = Path(path).suffix.lower()
    if suffix in JSON_SUFFIXES:
        return "json"
    if suffix in YAML_SUFFIXES:
        if not yaml_available():
            raise ParamFileError(path, ["YAML needs PyYAML (pip install 'pmactl[yaml]'); "
                                        "use a .json file"])
        return "yaml"
    raise ParamFileError(path, [f"unknown file type {suffix or '(none)'!r}: use .json"
                                + (", .yaml or .yml" if yaml_available() else "")])


def f32_short(value: float) -> float:
    """The float with the fewest significant digits that rounds to the same single."""
    target = to_f32(value)
    if not math.isfinite(target):
        return target
    for digits in range(1, 10):
        candidate = float(f"{target:.{digits}g}")
        if to_f32(candidate) == target:
            return candidate
    return target


def file_value(p: Param, value: float | int) -> float | int | str:
    """A node's value as it is written to a file (enumerations by name)."""
    if p.values and int(value) in p.values:
        return p.values[int(value)]
    return f32_short(float(value)) if p.type == "f32" else int(value)


def table_hash(proto: Protocol) -> int:
    """pmactl's own parameter table's hash (a node of the same table reports the same)."""
    return param_table_hash({"id": p.id, "name": p.name, "type": p.type, "min": p.min,
                             "max": p.max, "default": p.default} for p in proto.params)


def dumps(proto: Protocol, values: dict[int, float | int], node: int | None, kind: str = "json",
          firmware: dict[str, Any] | None = None) -> str:
    params: dict[str, Any] = {}
    units: dict[str, str] = {}
    for pid, value in sorted(values.items()):
        p = proto.by_id.get(pid)
        if p is None:
            continue
        params[p.name] = file_value(p, value)
        units[p.name] = p.unit
    doc: dict[str, Any] = {"format": FORMAT}
    if node is not None:
        doc["node"] = node
    if firmware is not None:
        doc["firmware"] = firmware
    doc["params"] = params
    doc["units"] = units
    if kind == "yaml":
        return str(_yaml().safe_dump(doc, sort_keys=False, default_flow_style=False))
    return json.dumps(doc, indent=2) + "\n"


def write(path: str, proto: Protocol, values: dict[int, float | int], node: int | None,
          firmware: dict[str, Any] | None = None) -> None:
    """Writes the values (by id; ids unknown to the table are left out) to path ('-':
    stdout), replacing the file only once it is complete."""
    kind = _kind(path)
    text = dumps(proto, values, node, kind, firmware)
    if path == "-":
        sys.stdout.write(text)
        return
    target = Path(path)
    tmp = target.with_name(target.name + ".tmp")
    try:
        tmp.write_text(text)
        tmp.replace(target)
    except OSError as e:
        raise ParamFileError(path, [f"cannot write: {e.strerror or e}"]) from e


def read(path: str) -> Any:
    """The parsed document (not yet validated)."""
    kind = _kind(path)
    try:
        text = sys.stdin.read() if path == "-" else Path(path).read_text()
    except (OSError, UnicodeDecodeError) as e:
        raise ParamFileError(path, [f"cannot read: {getattr(e, 'strerror', None) or e}"]) from e
    try:
        if kind == "yaml":
            return _yaml().safe_load(text)
        return json.loads(text)
    except Exception as e:  # json.JSONDecodeError, yaml.YAMLError
        raise ParamFileError(path, [f"not valid {kind.upper()}: {e}"]) from e


def validate(path: str, doc: Any, proto: Protocol) -> list[tuple[Param, float | int]]:
    """Every entry checked against the parameter table (name, type, range, enumeration,
    unit), in id order; ParamFileError listing every problem when any."""
    problems: list[str] = []
    if not isinstance(doc, dict):
        raise ParamFileError(path, ["not a mapping with a 'params' entry"])
    unknown_keys = sorted(set(doc) - set(TOP_LEVEL))
    if unknown_keys:
        problems.append(f"unknown top-level entries {', '.join(map(str, unknown_keys))} "
                        f"(a parameter file has {', '.join(TOP_LEVEL)})")
    if "firmware" in doc and not isinstance(doc["firmware"], dict):
        problems.append("'firmware' is not a mapping")
    if "format" in doc and doc["format"] != FORMAT:
        problems.append(f"format {doc['format']!r} is not {FORMAT!r}")
    params = doc.get("params")
    if not isinstance(params, dict):
        raise ParamFileError(path, problems + ["no 'params' mapping (name: value)"])
    units = doc.get("units", {})
    if not isinstance(units, dict):
        problems.append("'units' is not a mapping (name: unit)")
        units = {}
    out: list[tuple[Param, float | int]] = []
    for name, value in params.items():
        p = proto.by_name.get(str(name))
        if p is None:
            problems.append(f"unknown parameter {name!r}")
            continue
        try:
            out.append((p, p.check(value)))
        except ValueError as e:
            problems.append(str(e))
    for name, unit in units.items():
        p = proto.by_name.get(str(name))
        if p is not None and name in params and unit != p.unit:
            problems.append(f"{name}: unit {unit!r} in the file, the node's is {p.unit or '(none)'!r}")
    if problems:
        raise ParamFileError(path, problems)
    return sorted(out, key=lambda e: e[0].id)


def load(path: str, proto: Protocol) -> list[tuple[Param, float | int]]:
    return validate(path, read(path), proto)


@dataclass
class LoadPlan:
    """What loading a file would do (plan()): the entries to send, and what was mapped."""
    entries: list[tuple[Param, float | int]] = field(default_factory=list)
    same_table: bool = True          # the file's table hash is pmactl's
    file_firmware: str | None = None
    dropped: list[str] = field(default_factory=list)        # "name: why"
    renamed: list[tuple[str, str]] = field(default_factory=list)   # (file name, table name)
    clamped: list[tuple[Param, float | int, float | int]] = field(default_factory=list)
    lacking: list[Param] = field(default_factory=list)     # in the table, not in the file
    node_id_skipped: bool = False


def _file_hash(doc: dict[str, Any]) -> int | None:
    fw = doc.get("firmware")
    if not isinstance(fw, dict):
        return None
    try:
        return int(str(fw.get("param_table_hash")), 16)
    except ValueError:
        return None


def plan(path: str, doc: Any, proto: Protocol, with_node_id: bool = False) -> LoadPlan:
    """The load of a parsed file: strict for a file of pmactl's own table (validate()), mapped
    by name for one of another table (see the module's doc). ParamFileError when the file is
    unusable (not a parameter file; in strict mode any bad entry)."""
    if not isinstance(doc, dict) or not isinstance(doc.get("params"), dict):
        validate(path, doc, proto)   # raises with the reasons
    fw = doc.get("firmware") if isinstance(doc.get("firmware"), dict) else {}
    out = LoadPlan(file_firmware=str(fw["version"]) if fw.get("version") is not None else None)
    # A file that records no table (written by hand, or by a pmactl before DEVICE_INFO) is held
    # to the current table: a typo must not be dropped silently.
    recorded = _file_hash(doc)
    out.same_table = recorded is None or recorded == table_hash(proto)
    if out.same_table:
        entries = validate(path, doc, proto)
    else:
        problems: list[str] = []
        unknown_keys = sorted(set(doc) - set(TOP_LEVEL))
        if unknown_keys:
            problems.append(f"unknown top-level entries {', '.join(map(str, unknown_keys))}")
        if "format" in doc and doc["format"] != FORMAT:
            problems.append(f"format {doc['format']!r} is not {FORMAT!r}")
        if problems:
            raise ParamFileError(path, problems)
        units = doc.get("units") if isinstance(doc.get("units"), dict) else {}
        old_names = {old: p for p in proto.params for old in p.renamed_from}
        entries = []
        seen: set[int] = set()
        for name, value in doc["params"].items():
            name = str(name)
            p = proto.by_name.get(name)
            if p is None and name in old_names:
                p = old_names[name]
                out.renamed.append((name, p.name))
            if p is None:
                out.dropped.append(f"{name}: not a parameter of this firmware")
                continue
            if p.id in seen:
                out.dropped.append(f"{name}: {p.name} is in the file twice (old and new name)")
                continue
            if name in units and units[name] != p.unit:
                out.dropped.append(f"{name}: unit {units[name]!r} in the file, now "
                                   f"{p.unit or '(none)'!r}")
                continue
            try:
                entries.append((p, p.check(value)))
            except ValueError as e:
                clamped = _clamp(p, value)
                if clamped is None:
                    out.dropped.append(f"{name}: {e}")
                    continue
                out.clamped.append((p, value, clamped))
                entries.append((p, clamped))
            seen.add(p.id)
    names = {p.name for p, _ in entries}
    out.lacking = [p for p in proto.params if p.name not in names and p.name != NODE_ID_PARAM]
    if not with_node_id and any(p.name == NODE_ID_PARAM for p, _ in entries):
        entries = [(p, v) for p, v in entries if p.name != NODE_ID_PARAM]
        out.node_id_skipped = True
    out.entries = sorted(entries, key=lambda e: e[0].id)
    return out


def _clamp(p: Param, value: object) -> float | int | None:
    """A finite number of the right kind outside p's range, clamped into it; None otherwise."""
    if isinstance(value, bool) or not isinstance(value, (int, float)) or p.values:
        return None
    if not math.isfinite(float(value)):
        return None
    if p.type != "f32" and not float(value).is_integer():
        return None
    v = min(max(float(value), float(p.min)), float(p.max))
    try:
        return p.check(v if p.type == "f32" else int(v))
    except ValueError:
        return None
