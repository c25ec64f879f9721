# SPDX-License-Identifier: Apache-2.0
"""The summary's figures say what they count. Violations of the band
are split into the controller's (output active) and the safe state's after a fault (a
vented muscle under a pull sits outside the band by physics); the unreachable-reference
count is named for the curve it uses. No CAN."""
from __future__ import annotations

import inspect

import numpy as np

from hil import summary
from hil.metrics import lane_metrics


def test_violations_are_split_by_who_commands_the_pressure() -> None:
    n = 10
    t = np.arange(n) * 0.001
    x = np.full(n, -1.0)
    x[2] = -3.5                     # outside while the controller runs
    x[7:] = 0.14                    # after a fault: vented, pulled above the band
    active = np.array([1] * 6 + [0] * 4, np.int8)
    m = lane_metrics("ppc", "PPC", t, x + 1.0, x, x, np.zeros(n), np.zeros(n), [(0.0, 0.01)],
                     (-3.0, 0.0), None, None, None, output_active=active)
    assert m.constraint_violations == 4
    assert m.constraint_violations_controlled == 1
    assert m.constraint_violations_safe_state == 3
    d = m.to_dict()
    assert d["constraint_violations_controlled"] + d["constraint_violations_safe_state"] == d["constraint_violations"]


def test_summary_names_the_split_and_the_curve() -> None:
    src = inspect.getsource(summary)
    for key in ('"constraint_violations_controlled"', '"constraint_violations_safe_state"',
                '"reference_unreachable_virgin_curve_samples"'):
        assert key in src, key
    assert '"reference_unreachable_samples"' not in src
