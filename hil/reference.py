# SPDX-License-Identifier: Apache-2.0
"""The reference x_r(t) of a scenario, evaluated by the harness (cm, t in s since
START) from the formulas in docs/controllers.md and the paper, independently of
the firmware's generator. The runner checks it against the x_r the firmware
reports in TELEM_B, so a drift between the two is an error, not a silent offset.
"""
from __future__ import annotations

import math
from typing import Any, Callable

import numpy as np

from .scenario import protocol


def _p(ref: dict[str, Any], name: str) -> float:
    return float(ref.get(name, protocol().param(f"ref.{name}").default))


def reference_function(ref: dict[str, Any]) -> Callable[[np.ndarray], np.ndarray]:
    """x_r(t) [cm] for an array of control times t [s]."""
    kind = str(ref.get("kind", "HOLD")).upper()
    offset, amp = _p(ref, "offset_cm"), _p(ref, "amplitude_cm")
    if kind == "HOLD":
        return lambda t: np.full_like(t, offset, dtype=float)
    if kind == "STEP":
        t0 = _p(ref, "t0_s")
        return lambda t: np.where(t < t0, offset, offset + amp)
    if kind == "SINE":
        f, ph = _p(ref, "freq_hz"), _p(ref, "phase_rad")
        return lambda t: offset + amp * np.sin(2.0 * math.pi * f * t + ph)
    if kind == "CASE1":
        return lambda t: -0.5 * np.sin(t) - 2.0
    if kind == "CASE3":
        return lambda t: t * np.sin(2.0 * math.pi * t * (1.0 + t / 55.0) / 55.0 - math.pi / 2.0) / 360.0 - 2.0
    raise ValueError(f"reference kind {kind!r} has no formula here")
