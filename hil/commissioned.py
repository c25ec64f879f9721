# SPDX-License-Identifier: Apache-2.0
"""A scenario's paper-controller lane with the parameters `pmactl commission` derives on the
scenario's own rig, instead of the hand-tuned set in its file.

`commission(sc)` runs the real procedure (pmactl.commission, over python-can frames) against
the real firmware on the scenario's rig (hil/offline_bus.py), as a user would on a freshly
wired rig: the node knows only the rig's sensor and DAC scalings, the actuator's pressure
range and the constraints. `commissioned(sc, derivation)` is the scenario with its `ppc` lane
set from the derivation plus only the task's own w1 and t_u (and its reference, constraints
and events as the file has them).
"""
from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np

from pmactl.client import PmaNode
from pmactl.commission import Commissioning, Result
from pmactl.commission_rules import Task

from .offline_bus import OfflineBus
from .reference import reference_function
from .scenario import Scenario, protocol

# the rig's wiring and the user's limits: what a freshly wired node knows before commissioning
USER_LIMITS = ("act.p_min_kpa", "act.p_max_kpa", "safety.x_min_cm", "safety.x_max_cm")
# what the derivation sets on the node (the rest of its output are the task's or MFAC's)
NODE_WIDE = ("act.polarity", "act.p0_kpa", "ctrl.u_min", "ctrl.u_max")


def task_of(sc: Scenario, label: str = "ppc") -> Task:
    """The task of the scenario's lane: its w1, t_u, constraints, where its reference starts and
    how fast it gets (over the scenario's run)."""
    ctrl = next(c for c in sc.controllers if c.label == label)
    params = sc.node_params(ctrl)
    t = np.arange(0.0, sc.duration_s, 1e-3)
    xr = reference_function(sc.reference)(t)
    return Task(w1_cm=float(params["ppc.w1_cm"]), t_u_s=float(params["ppc.t_u_s"]),
                x_min_cm=float(params["safety.x_min_cm"]), x_max_cm=float(params["safety.x_max_cm"]),
                x_start_cm=float(xr[0]), speed_cm_s=float(np.max(np.abs(np.diff(xr))) / 1e-3))


def commission(sc: Scenario, task: Task | None = None) -> Result:
    """`pmactl commission` on a fresh node on the scenario's rig (control time, offline)."""
    rig_params = sc.rig_params()
    bus = OfflineBus(rig_params, node_id=1, seed=sc.seed)
    try:
        node = PmaNode(bus, node=1, host_heartbeat_s=0.1)
        proto = protocol()
        wiring = rig_params.firmware_scaling()
        wiring.pop("act.p0_kpa", None)
        for name, value in wiring.items():
            node.set(name, float(value) if proto.param(name).type == "f32" else int(round(value)))
        for name in USER_LIMITS:
            if name in sc.params:
                node.set(name, sc.params[name])
        bus.run_for(sc.settle_s)
        return Commissioning(node, task or task_of(sc)).run()
    finally:
        bus.shutdown()


def commissioned(sc: Scenario, result: Result, label: str = "ppc") -> Scenario:
    """The scenario with lane `label` on the derived parameters plus the task's w1 and t_u."""
    d = result.derivation.params
    ctrls = []
    for c in sc.controllers:
        if c.label == label:
            own: dict[str, Any] = {k: v for k, v in d.items() if k.startswith(("ppc.", "vel."))}
            own.update({k: c.params[k] for k in ("ppc.w1_cm", "ppc.t_u_s") if k in c.params})
            c = dataclasses.replace(c, params=own, description=f"{c.description} [commissioned: the set derived "
                                    "by pmactl commission on this rig, plus the task's w1 and t_u]")
        ctrls.append(c)
    params = dict(sc.params)
    params.update({k: d[k] for k in NODE_WIDE})
    return dataclasses.replace(sc, controllers=ctrls, params=params)
