# SPDX-License-Identifier: Apache-2.0
"""Lanes whose parameter set comes from `pmactl commission` on the lane's own rig.

A scenario's lane with `commission = true` (hil/scenario.py) gives only the task's own
parameters (w1, t_u, the band check); before ARM the harness runs the real procedure
(pmactl.commission, over python-can frames) on that lane's fresh node, as a user would on a
freshly wired rig: the node knows only the rig's sensor and DAC scalings, the actuator's
pressure range and the constraints (`before_commissioning`). Over CAN, `python -m hil run
--commission` does that on each lane's node (hil/runner.py); offline, `commission(sc)` does it
against the real firmware on the scenario's rig through hil/offline_bus.py, and
`commissioned(sc, result)` is the scenario with every such lane on the derived set.
"""
from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np

from pmactl.client import PmaNode
from pmactl.commission import Commissioning, Result
from pmactl.commission_rules import Task
from pmactl.rules import set_order

from .offline_bus import OfflineBus
from .reference import reference_function
from .scenario import COMMISSIONED_NODE_WIDE, RULE_PARAMS, USER_LIMITS, Controller, Scenario, protocol

# the derived parameters a lane takes, by its mode (the PPC's fallback is MFAC: it takes MFAC's)
DERIVED_BY_MODE = {"PPC": ("ppc.", "vel.", "mfac."), "MFAC": ("mfac.",)}


def before_commissioning(sc: Scenario) -> dict[str, float | int]:
    """What a freshly wired node is told before commissioning: the rig's sensor and DAC
    scalings and the user's pressure range and constraints (the scenario's)."""
    proto = protocol()
    wiring = sc.rig_params().firmware_scaling()
    wiring.pop("act.p0_kpa", None)
    out: dict[str, float | int] = {n: float(v) if proto.param(n).type == "f32" else int(round(v))
                                   for n, v in wiring.items()}
    out.update({n: sc.params[n] for n in USER_LIMITS if n in sc.params})
    return out


def tell_wiring(node: PmaNode, sc: Scenario) -> None:
    """Sets before_commissioning(sc) on the node, in the order the rules between parameters
    allow from its current values (a 10-bit sensor's lower range first needs a lower
    wire-break level, as a user setting them by hand would find)."""
    wiring = before_commissioning(sc)
    current = {name: node.get(name) for name in RULE_PARAMS}
    for name in set_order(current, wiring):
        node.set(name, wiring[name])


def task_of(sc: Scenario, label: str | None = None) -> Task:
    """The task of the scenario's lane (default: its first commissioned or PPC lane): w1 and t_u
    (a lane without them, e.g. MFAC, takes those of the scenario's first PPC lane), the
    constraints, where the reference starts, the range it spans and how fast it gets (its largest and
    mean speed), and the scenario's noise_limit."""
    ctrl = _lane(sc, label)
    own = {**sc.params, **next((c.params for c in sc.controllers if c.mode == "PPC"), {}), **ctrl.params}
    proto = protocol()
    t = np.arange(0.0, sc.duration_s, 1e-3)
    xr = reference_function(sc.reference)(t)
    x_min, x_max = sc.band_cm()
    return Task(w1_cm=float(own.get("ppc.w1_cm", proto.param("ppc.w1_cm").default)),
                t_u_s=float(own.get("ppc.t_u_s", proto.param("ppc.t_u_s").default)),
                x_min_cm=x_min, x_max_cm=x_max,
                x_start_cm=float(xr[0]), speed_cm_s=float(np.max(np.abs(np.diff(xr))) / 1e-3),
                mean_speed_cm_s=float(np.mean(np.abs(np.diff(xr))) / 1e-3), noise_limit=sc.noise_limit,
                x_ref_min_cm=float(np.min(xr)), x_ref_max_cm=float(np.max(xr)))


def _lane(sc: Scenario, label: str | None) -> Controller:
    if label is not None:
        return next(c for c in sc.controllers if c.label == label)
    return next((c for c in sc.controllers if c.commission),
                next((c for c in sc.controllers if c.mode == "PPC"), sc.controllers[0]))


def commission(sc: Scenario, task: Task | None = None) -> Result:
    """`pmactl commission` on a fresh node on the scenario's rig (control time, offline)."""
    bus = OfflineBus(sc.rig_params(), node_id=1, seed=sc.seed)
    try:
        node = PmaNode(bus, node=1, host_heartbeat_s=0.1)
        tell_wiring(node, sc)
        bus.run_for(sc.settle_s)
        return Commissioning(node, task or task_of(sc)).run()
    finally:
        bus.shutdown()


def derived_params(ctrl: Controller, derivation: dict[str, Any]) -> dict[str, Any]:
    """A commissioned lane's own parameters: the derivation's (Result.derivation.params) for its
    mode, the node-wide input set-up (polarity, p0, input range), and over them the lane's own:
    from a file only the task's (COMMISSION_TASK_PARAMS, as the loader checks), plus whatever a
    user set on the lane explicitly (`hil offline --set`)."""
    own: dict[str, Any] = {k: v for k, v in derivation.items() if k.startswith(DERIVED_BY_MODE[ctrl.mode])}
    own.update({k: derivation[k] for k in COMMISSIONED_NODE_WIDE})
    own.update(ctrl.params)
    return own


def with_derivation(ctrl: Controller, derivation: dict[str, Any]) -> Controller:
    """The lane on the derivation (Result.derivation.params)."""
    return dataclasses.replace(ctrl, params=derived_params(ctrl, derivation), derived=True, commission=True,
                               description=f"{ctrl.description} [commissioned: the set pmactl commission "
                                           "derived on this rig, plus the task's own parameters]")


def commissioned(sc: Scenario, result: Result, labels: tuple[str, ...] | None = None) -> Scenario:
    """The scenario with its commissioned lanes (or the lanes `labels`, commissioned or not) on
    the derivation."""
    d = result.derivation.params
    ctrls = [with_derivation(c, d) if (c.label in labels if labels is not None else c.commission) else c
             for c in sc.controllers]
    return dataclasses.replace(sc, controllers=ctrls)


def commission_offline(sc: Scenario) -> tuple[Scenario, Result | None]:
    """The scenario ready to run offline: when it has lanes that take their set from
    commissioning, `commission(sc)` once on its rig (every lane's rig is the same, seeded) and
    those lanes on the derivation; else the scenario as it is (and None)."""
    if not sc.needs_commissioning():
        return sc, None
    result = commission(sc)
    return commissioned(sc, result), result
