# SPDX-License-Identifier: Apache-2.0
"""The rules between parameters (docs/parameters.md "Rules between parameters";
firmware/app/app_config.c pma_app_param_rule, the same numbers), for clients that set many
parameters: check a whole set before sending it, and find an order of SETs in which
every step keeps the rules a SET enforces (rules 1-5: the sensor and DAC scalings)."""
from __future__ import annotations

from typing import Mapping

SET_RULES = (1, 2, 3, 4, 5)


def broken_rule(v: Mapping[str, float], set_only: bool = False) -> int:
    """The number of the first rule the values v (every parameter involved) break, 0 if none."""
    if v["adc.gain_cm_per_count"] == 0:
        return 1
    if v["adc.raw_min_counts"] > v["adc.raw_max_counts"]:
        return 2
    if v["adc.wire_break_below_counts"] > v["adc.raw_min_counts"]:
        return 3
    if v["dac.counts_per_kpa"] == 0:
        return 4
    if v["dac.min_counts"] > v["dac.max_counts"]:
        return 5
    if set_only:
        return 0
    if v["act.polarity"] not in (1, -1):
        return 6
    if not (0 <= v["act.p_min_kpa"] < v["act.p_max_kpa"]):
        return 7
    if not (v["act.p_min_kpa"] <= v["act.p0_kpa"] <= v["act.p_max_kpa"]):
        return 8
    if v["safety.safe_mode"] == 2 and not v["safety.safe_kpa"] <= v["act.p_max_kpa"]:
        return 9
    if not v["safety.x_min_cm"] < v["safety.x_max_cm"]:
        return 10
    if not v["ctrl.u_min"] < v["ctrl.u_max"]:
        return 11
    k = v["act.polarity"] * v["act.kpa_per_u"]
    tol = 1e-3 + 1e-6 * abs(v["act.p_max_kpa"])
    for u in (v["ctrl.u_min"], v["ctrl.u_max"]):
        p = v["act.p0_kpa"] + k * u
        if not (v["act.p_min_kpa"] - tol <= p <= v["act.p_max_kpa"] + tol):
            return 12
    return 0


class RuleError(ValueError):
    def __init__(self, rule: int, message: str) -> None:
        super().__init__(message)
        self.rule = rule


def set_order(current: Mapping[str, float], target: Mapping[str, float]) -> list[str]:
    """The names of target in an order of SETs that starts from current (every parameter
    the rules involve) and never breaks a set-time rule on the way: target's own order
    where it can, a parameter postponed while setting it now would break one. RuleError
    when the target set itself breaks a set-time rule (no order helps)."""
    final = {**current, **target}
    rule = broken_rule(final, set_only=True)
    if rule:
        raise RuleError(rule, f"the parameter set breaks rule {rule} (docs/parameters.md)")
    now = dict(current)
    pending = list(target)
    order: list[str] = []
    while pending:
        for name in pending:
            trial = {**now, name: target[name]}
            if name not in trial or broken_rule(trial, set_only=True) == 0:
                break
        else:   # every next step breaks a rule: cannot happen for rules 1-5, but never loop
            raise RuleError(broken_rule({**now, pending[0]: target[pending[0]]}, True),
                            f"no order of SETs reaches the set: {', '.join(pending)}")
        now[name] = target[name]
        pending.remove(name)
        order.append(name)
    return order
