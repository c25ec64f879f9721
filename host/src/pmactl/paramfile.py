"""Parameter files: a node's parameters as JSON (or YAML, when PyYAML is installed).

    {
      "format": "pmactl-params 1",
      "node": 0,
      "params": {"ctrl.mode": "PPC", "ppc.w1_cm": 0.2, ...},
      "units": {"ctrl.mode": "", "ppc.w1_cm": "cm", ...}
    }

``params`` is required: parameter name -> value (a number, or for enumerations the
value's name). ``format`` and ``node`` are optional and informational (``format`` must
be this one when present); ``units``, when present, must give each listed parameter
the unit of the parameter table (so a file never means other units than the node's).
f32 values are written with the fewest digits that give the node's single-precision
value back.
"""
from __future__ import annotations

import json
import math
import sys
from pathlib import Path
from typing import Any

from pmactl.protocol import Param, Protocol, to_f32

FORMAT = "pmactl-params 1"
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
        import yaml  # type: ignore[import-untyped]
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


def dumps(proto: Protocol, values: dict[int, float | int], node: int | None, kind: str = "json") -> str:
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
    doc["params"] = params
    doc["units"] = units
    if kind == "yaml":
        return str(_yaml().safe_dump(doc, sort_keys=False, default_flow_style=False))
    return json.dumps(doc, indent=2) + "\n"


def write(path: str, proto: Protocol, values: dict[int, float | int], node: int | None) -> None:
    """Writes the values (by id; ids unknown to the table are left out) to path ('-':
    stdout), replacing the file only once it is complete."""
    kind = _kind(path)
    text = dumps(proto, values, node, kind)
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
    unknown_keys = sorted(set(doc) - {"format", "node", "params", "units"})
    if unknown_keys:
        problems.append(f"unknown top-level entries {', '.join(map(str, unknown_keys))} "
                        f"(a parameter file has format, node, params, units)")
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
