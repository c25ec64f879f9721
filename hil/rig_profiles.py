# SPDX-License-Identifier: Apache-2.0
"""Rig profiles: named sets of RigParams values (docs/rig.md, "Against a real muscle").

    RigParams.from_dict({"profile": "dmsp10"})           # in a scenario: [rig] profile = "dmsp10"
    RigParams.from_dict({"profile": "mas10-itv2050", "p0_kpa": 40.0})

* "nominal": the defaults of hil/rig_params.py (the idealised MAS-10 rig every
  existing HIL figure was measured on; no creep, the regulator's first-order lag).
* "dmsp10": a Festo DMSP-10-250 fitted to public measurements (tools/fit_rig_dmsp10.py
  writes hil/profiles/dmsp10.json; that file holds the fitted values and the fit's
  report, never the data).
* "mas10-itv2050": the paper's MAS-10-100N with the SMC ITV2050 made realistic: the
  nominal muscle, the ITV2050's response and flow from its datasheet, and the creep,
  hysteresis shape and slow final approach of the fitted DMSP-10 (the same 10 mm
  tube), scaled to the MAS-10's stroke. Each value's source: MAS10_SOURCES below.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

PROFILE_DIR = Path(__file__).resolve().parent / "profiles"
PROFILES = ("nominal", "dmsp10", "mas10-itv2050")


def _dmsp10() -> dict[str, Any]:
    doc = json.loads((PROFILE_DIR / "dmsp10.json").read_text())
    rig: dict[str, Any] = doc["rig"]
    return rig


def dmsp10_fit_report() -> dict[str, Any]:
    """The fit's own report (figures, targets, RMS errors) stored with the profile."""
    doc = json.loads((PROFILE_DIR / "dmsp10.json").read_text())
    fit: dict[str, Any] = doc["fit"]
    return fit


# The ITV2050 (SMC catalogue of the ITV1000/2000/3000 series; the paper names the
# ITV2050): set pressure 0.005-0.9 MPa, supply 1.0 MPa max, maximum flow 1500 L/min
# (ANR) for the ITV2000 size, response time 0.1 s or less (without load), linearity
# +-1 % FS, hysteresis 0.5 % FS.
MAS10_SOURCES: dict[str, Any] = {
    "itv2050_supply_kpa": 1000.0,  # maximum supply pressure 1.0 MPa (used as the supply)
    "itv2000_max_flow_l_min_anr": 1500.0,
    "itv2050_response_time_s": 0.1,  # "0.1 s or less (without load)"
    # the muscle's volume: MAS-10-100N, 10 mm inner diameter, 100 mm long (7.9 cm^3),
    # plus 1 m of 4 mm inner-diameter tubing to the regulator (12.6 cm^3; an assumption)
    "volume_cm3": math.pi / 4 * 1.0 ** 2 * 10.0 + math.pi / 4 * 0.4 ** 2 * 100.0,
    "atm_kpa": 101.325,
}


def _mas10_itv2050() -> dict[str, Any]:
    from .rig import Rig
    from .rig_params import RigParams

    d = _dmsp10()
    dm = RigParams.from_dict(d)
    nominal = RigParams()
    s = MAS10_SOURCES
    # choked flow of the datasheet's maximum flow into the volume: dP/dt = p_atm Q / V
    q_cm3_s = s["itv2000_max_flow_l_min_anr"] * 1000.0 / 60.0
    rate_flow = s["atm_kpa"] * q_cm3_s / s["volume_cm3"]
    # The flow alone would fill the muscle in milliseconds; the datasheet's response
    # time (0.1 s) is the regulator's own (its pilot valves). The profile limits the
    # fill and exhaust rates so that a 0 -> 500 kPa step reaches 90 % in 0.1 s after
    # the dead time: 450 kPa in (0.1 s - dead time).
    dead_rise, dead_fall = 0.020, 0.035
    rate = min(rate_flow, 450.0 / (s["itv2050_response_time_s"] - dead_rise))
    # stroke ratio (0-600 kPa, no load) scales the hysteresis of the DMSP-10 fit
    rn, rd = Rig(nominal), Rig(dm)
    stroke_n = rn._f_pos(600.0) / rn._k_of_p(600.0)
    stroke_d = rd._f_pos(600.0) / rd._k_of_p(600.0)
    ratio = stroke_n / stroke_d
    # friction force that gives the same loop in percent of the stroke: Fh ~ K * width
    a_force = dm.muscle.hyst_force_n * ratio * rn._k_of_p(300.0) / rd._k_of_p(300.0)
    return {
        "muscle": {
            "hyst_force_n": a_force,
            "hyst_ramp_n": dm.muscle.hyst_ramp_n,
            "hyst_delta_mm": [dl * ratio for dl in dm.muscle.hyst_delta_mm],
            "hyst_weights": list(dm.muscle.hyst_weights),
        },
        "valve": {
            "model": "flow",
            "dead_time_rise_s": dead_rise,
            "dead_time_fall_s": dead_fall,
            "supply_kpa": s["itv2050_supply_kpa"],
            "atm_kpa": s["atm_kpa"],
            "fill_rate_kpa_s": rate,
            "exhaust_rate_kpa_s": rate * d["valve"]["exhaust_rate_kpa_s"] / d["valve"]["fill_rate_kpa_s"],
            "b_critical": dm.valve.b_critical,
            "p_band_kpa": dm.valve.p_band_kpa,
            "slow_weight_rise": dm.valve.slow_weight_rise,
            "slow_weight_fall": dm.valve.slow_weight_fall,
            "slow_tau_rise_s": dm.valve.slow_tau_rise_s,
            "slow_tau_fall_s": dm.valve.slow_tau_fall_s,
            "volume_gain_per_mm": dm.valve.volume_gain_per_mm * dm.muscle.length_mm / nominal.muscle.length_mm,
            "polytropic_n": dm.valve.polytropic_n,
        },
        "creep": {
            "frac_contract": dm.creep.frac_contract,
            "frac_relax": dm.creep.frac_relax,
            "tau_contract_s": dm.creep.tau_contract_s,
            "tau_relax_s": dm.creep.tau_relax_s,
        },
    }


def profile_dict(name: str) -> dict[str, Any]:
    """The RigParams overrides of a profile (nested like RigParams.to_dict())."""
    if name == "nominal":
        out: dict[str, Any] = {}
    elif name == "dmsp10":
        out = _dmsp10()
    elif name == "mas10-itv2050":
        out = _mas10_itv2050()
    else:
        raise ValueError(f"rig profile {name!r} unknown (one of {', '.join(PROFILES)})")
    return {**out, "profile": name}
