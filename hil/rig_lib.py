# SPDX-License-Identifier: Apache-2.0
"""libpma_rig.so (hil/rig_core, preset host-offline): the simulated rig's dynamics in C, the
right-hand side of docs/rig.md integrated by RK4, and its constants (`Model`, the layout of
pma_rig_model in pma_rig_core.h). hil/rig.py fills a Model and advances its state with it: a
control tick's rig step without Python interpreter time (the HIL runner's step in the vcan
guest)."""
from __future__ import annotations

import ast
import ctypes
import operator
import os
import re
from pathlib import Path
from typing import Any, Callable

REPO = Path(__file__).resolve().parents[1]
LIB_PATH = Path(os.environ.get("PMA_RIG_LIB", REPO / "build/host-offline/hil/rig_core/libpma_rig.so"))
BUILD_HINT = "cmake --preset host-offline && cmake --build --preset host-offline"
HEADER = REPO / "hil/rig_core/pma_rig_core.h"
API_VERSION = 3          # the pma_rig_core.h these bindings are written for (PMA_RIG_CORE_API_VERSION)


_INT_OPS: dict[type[ast.operator], Callable[[int, int], int]] = {
    ast.Add: operator.add, ast.Sub: operator.sub, ast.Mult: operator.mul}


def _header_int(name: str) -> int:
    """An integer #define of pma_rig_core.h: the array sizes live there alone. Its value is an
    integer, or a sum, difference or product of integers and other such #defines in parentheses."""
    m = re.search(rf"^#define[ \t]+{name}[ \t]+([\w \t+*()-]*?)[ \t]*(?:/\*.*)?$", HEADER.read_text(), re.MULTILINE)
    if m is None:
        raise ImportError(f"{HEADER}: no integer #define {name}")
    not_int = f"{HEADER}: #define {name} is not an integer expression: {m.group(1)!r}"

    def value(node: ast.AST) -> int:
        if isinstance(node, ast.Constant) and type(node.value) is int:
            return node.value
        if isinstance(node, ast.Name):
            return _header_int(node.id)
        if isinstance(node, ast.BinOp) and type(node.op) in _INT_OPS:
            return _INT_OPS[type(node.op)](value(node.left), value(node.right))
        raise ImportError(not_int)

    try:
        tree = ast.parse(m.group(1).strip(), mode="eval")
    except SyntaxError as e:
        raise ImportError(not_int) from e
    return value(tree.body)


MAX_HYST = _header_int("PMA_RIG_MAX_HYST")   # hysteresis elements the Model holds
MAX_STATE = _header_int("PMA_RIG_MAX_STATE")  # xs, v, P, y, z_i..., q, Fc: checked at load

_d, _i32, _i64 = ctypes.c_double, ctypes.c_int32, ctypes.c_int64
_pd, _pi64 = ctypes.POINTER(_d), ctypes.POINTER(_i64)


class RigLibError(RuntimeError):
    """libpma_rig.so is missing or does not match this module."""


_C_TYPES: dict[str, Any] = {"double": _d, "int32_t": _i32, "int64_t": _i64,
                            "const double *": _pd, "const int64_t *": _pi64}


def _struct_fields(name: str) -> list[tuple[str, Any]]:
    """The ctypes fields of `typedef struct { ... } name;` in pma_rig_core.h, in its order: the
    header is the layout's one source (declarations of the types in _C_TYPES, several names to a
    declaration, arrays sized by an integer #define)."""
    text = re.sub(r"/\*.*?\*/", " ", HEADER.read_text(), flags=re.DOTALL)
    m = re.search(rf"typedef\s+struct\s*\{{([^{{}}]*)\}}\s*{name}\s*;", text)
    if m is None:
        raise ImportError(f"{HEADER}: no typedef struct {name}")
    fields: list[tuple[str, Any]] = []
    for decl in filter(None, (d.strip() for d in m.group(1).split(";"))):
        d = re.fullmatch(r"((?:const\s+)?\w+)\s*(\*?)\s*(.+)", decl, re.DOTALL)
        ctype = None if d is None else _C_TYPES.get(d.group(1) + (" *" if d.group(2) else ""))
        if d is None or ctype is None:
            raise ImportError(f"{HEADER}: {name}: a declaration of a type rig_lib.py does not map: {decl!r}")
        for item in (i.strip() for i in d.group(3).split(",")):
            a = re.fullmatch(r"(\w+)(?:\s*\[\s*(\w+)\s*\])?", item)
            if a is None:
                raise ImportError(f"{HEADER}: {name}: cannot read the field {item!r}")
            n = a.group(2)
            size = None if n is None else int(n) if n.isdigit() else _header_int(n)
            fields.append((a.group(1), ctype if size is None else ctype * size))
    return fields


class Model(ctypes.Structure):
    """pma_rig_model (pma_rig_core.h, read from there: _struct_fields; its size checked against
    the library's at load): units in the field names' comments there."""

    _fields_ = _struct_fields("pma_rig_model")


State = _d * MAX_STATE


def state_len(model: Model) -> int:
    """How many state variables a model uses (pma_rig_state_len)."""
    return int(library().pma_rig_state_len(ctypes.byref(model)))


def open_library(path: Path, error: type[Exception]) -> ctypes.CDLL:
    """A shared library of the preset host-offline (this one, libpma_offline.so), or `error`
    saying how to build it."""
    if not path.exists():
        raise error(f"{path} not found: build it first ({BUILD_HINT})")
    try:
        return ctypes.CDLL(str(path))
    except OSError as e:
        raise error(f"cannot load {path}: {e}") from e


def _load(path: Path) -> ctypes.CDLL:
    lib = open_library(path, RigLibError)
    pm = ctypes.POINTER(Model)
    # the version first: a library of another version may lack the functions bound after it
    lib.pma_rig_core_api_version.restype, lib.pma_rig_core_api_version.argtypes = _i32, []
    version = lib.pma_rig_core_api_version()
    if version != API_VERSION:
        raise RigLibError(f"{path}: API version {version}, hil/rig_lib.py needs {API_VERSION}: rebuild ({BUILD_HINT})")
    for name, res, args in (("pma_rig_model_size", _i32, []), ("pma_rig_max_state", _i32, []),
                            ("pma_rig_state_len", _i32, [pm]),
                            ("pma_rig_advance", _i32, [pm, _pd, _i64, _i64, _i64, _d]),
                            ("pma_rig_disturbance_n", _d, [pm, _d])):
        fn = getattr(lib, name)
        fn.restype, fn.argtypes = res, args
    if lib.pma_rig_max_state() != MAX_STATE:
        raise RigLibError(f"{path}: a state of {lib.pma_rig_max_state()} variables, hil/rig_lib.py's {MAX_STATE}: "
                          f"rebuild ({BUILD_HINT})")
    if lib.pma_rig_model_size() != ctypes.sizeof(Model):
        raise RigLibError(f"{path}: pma_rig_model is {lib.pma_rig_model_size()} bytes, hil/rig_lib.py's Model "
                          f"{ctypes.sizeof(Model)}: rebuild ({BUILD_HINT})")
    return lib


_LIB: ctypes.CDLL | None = None


def library() -> ctypes.CDLL:
    """libpma_rig.so, loaded once per process."""
    global _LIB
    if _LIB is None:
        _LIB = _load(LIB_PATH)
    return _LIB
