# SPDX-License-Identifier: Apache-2.0
"""libpma_rig.so (hil/rig_core, preset host-offline): the simulated rig's dynamics in C, the
right-hand side of docs/rig.md integrated by RK4, and its constants (`Model`, the layout of
pma_rig_model in pma_rig_core.h). hil/rig.py fills a Model and advances its state with it: a
control tick's rig step without Python interpreter time (the HIL runner's step in the vcan
guest)."""
from __future__ import annotations

import ast
import ctypes
import os
import re
from pathlib import Path
from typing import Any

REPO = Path(__file__).resolve().parents[1]
LIB_PATH = Path(os.environ.get("PMA_RIG_LIB", REPO / "build/host-offline/hil/rig_core/libpma_rig.so"))
BUILD_HINT = "cmake --preset host-offline && cmake --build --preset host-offline"
HEADER = REPO / "hil/rig_core/pma_rig_core.h"
API_VERSION = 3          # the pma_rig_core.h these bindings are written for (PMA_RIG_CORE_API_VERSION)


def _header_int(name: str) -> int:
    """An integer #define of pma_rig_core.h: the array sizes live there alone. Its value is an
    integer, or a sum, difference or product of integers and other such #defines in parentheses."""
    m = re.search(rf"^#define[ \t]+{name}[ \t]+([\w \t+*()-]*?)[ \t]*(?:/\*.*)?$", HEADER.read_text(), re.MULTILINE)
    if m is None:
        raise ImportError(f"{HEADER}: no integer #define {name}")

    def value(node: ast.AST) -> int:
        if isinstance(node, ast.Constant) and type(node.value) is int:
            return node.value
        if isinstance(node, ast.Name):
            return _header_int(node.id)
        if isinstance(node, ast.BinOp) and isinstance(node.op, (ast.Add, ast.Sub, ast.Mult)):
            a, b = value(node.left), value(node.right)
            return a + b if isinstance(node.op, ast.Add) else a - b if isinstance(node.op, ast.Sub) else a * b
        raise ImportError(f"{HEADER}: #define {name} is not an integer expression: {m.group(1)!r}")

    try:
        tree = ast.parse(m.group(1).strip(), mode="eval")
    except SyntaxError as e:
        raise ImportError(f"{HEADER}: #define {name} is not an integer expression: {m.group(1)!r}") from e
    return value(tree.body)


MAX_HYST = _header_int("PMA_RIG_MAX_HYST")   # hysteresis elements the Model holds
MAX_STATE = _header_int("PMA_RIG_MAX_STATE")  # xs, v, P, y, z_i..., q, Fc: checked at load

_d, _i32, _i64 = ctypes.c_double, ctypes.c_int32, ctypes.c_int64
_pd, _pi64 = ctypes.POINTER(_d), ctypes.POINTER(_i64)


class RigLibError(RuntimeError):
    """libpma_rig.so is missing or does not match this module."""


_MODEL_FIELDS: list[tuple[str, Any]] = [(name, _d) for name in (
    "f0_n", "f1_n_per_kpa", "f_clip_width_sq_n2", "k_break_kpa", "k_blend_kpa",
    "k0_low_n_per_mm", "k1_low_n_per_mm_kpa", "k0_high_n_per_mm", "k1_high_n_per_mm_kpa",
    "b_mid_ns_per_mm", "b_half_ns_per_mm", "b_blend_mm_s", "hyst_force_n", "hyst_ramp_n")] + [
    ("hyst_delta_mm", _d * MAX_HYST), ("hyst_w_per_delta_per_mm", _d * MAX_HYST)] + [
    (name, _d) for name in (
        "drift_rate_k_per_s", "drift_max_rise_k", "drift_f_per_k", "drift_k_per_k", "drift_b_per_k",
        "tau_p_s", "tau_y_s", "w_static_n", "acc_mm_s2_per_n", "dist_tau_s")] + [
    ("dist_t_ns", _pi64), ("dist_target_n", _pd), ("dist_start_n", _pd), ("drift_knee_ns", _i64),
    ("n_hyst", _i32), ("n_dist", _i32), ("ext", _i32), ("flow", _i32)] + [
    (name, _d) for name in (
        "creep_frac_contract", "creep_frac_relax", "creep_inv_tau_contract_per_s",
        "creep_inv_tau_relax_per_s", "creep_blend_sq_n2",
        "slow_weight_rise", "slow_weight_fall", "slow_inv_tau_rise_per_s", "slow_inv_tau_fall_per_s",
        "valve_band_kpa", "valve_fill_rate_kpa_s", "valve_exhaust_rate_kpa_s", "valve_supply_abs_kpa",
        "valve_atm_kpa", "valve_b_critical", "valve_volume_gain_per_mm", "valve_polytropic_n")]


class Model(ctypes.Structure):
    """pma_rig_model (pma_rig_core.h): units in the field names' comments there."""

    _fields_ = _MODEL_FIELDS


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
