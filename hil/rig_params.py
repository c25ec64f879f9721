# SPDX-License-Identifier: Apache-2.0
"""Parameters of the simulated PMA rig, with the published sources they come from.

Every number of the rig lives in one of the dataclasses below; `RigParams.from_dict`
builds them from a (nested) dict such as a scenario's TOML/JSON table, `to_dict`
writes them back. docs/rig.md explains each value and its source; `SOURCES` holds
the raw published numbers the defaults are derived from (`calibrate_mas10`), so the
derivation is code, not a comment.

Units: pressure kPa (gauge), force N, length mm inside the muscle model (the
published coefficients are per mm), the rig's x in cm, time s.
"""

from __future__ import annotations

import dataclasses
import math
import numbers
from dataclasses import dataclass, field
from typing import Any, Mapping

from .rig_lib import MAX_HYST

# ---------------------------------------------------------------------------
# Published numbers (see docs/rig.md, "Sources"). Nothing here is tuned.
# ---------------------------------------------------------------------------
SOURCES: dict[str, Any] = {
    # Festo MAS-10-100N (the paper, Section 5.1; Festo catalogue data in
    # ../shared/spec/controller.md): inner diameter 10 mm, nominal length 100 mm,
    # about 25 % maximum stroke, about 630 N theoretical force at 600 kPa,
    # operating pressure 0-800 kPa.
    "mas10_length_mm": 100.0,
    "mas10_max_stroke_frac": 0.25,
    "mas10_theoretical_force_n_at_600kpa": 630.0,
    "mas10_max_pressure_kpa": 800.0,
    # Martens and Boblan, Actuators 2017, 6(4):33, measured static force map of a
    # Festo DMSP-10-250 (same 10 mm muscle tube): force at nominal length at two
    # pressures, zero force at about 21 % contraction at 650 kPa, no force below
    # about 50 kPa.
    "martens_force_n_at_nominal": {650.0: 542.5, 360.0: 283.8},
    "martens_zero_force_contraction_frac_at_650kpa": 0.21,
    "martens_no_force_below_kpa": 50.0,
    # Serres et al. 2009, Comput Methods Biomech Biomed Engin 12(4):423-430
    # (three-element model of a larger muscle): K [N/mm] = 32.7 - 0.0321 P
    # (150-314 kPa), 17 + 0.0179 P (314-550 kPa); B [N s/mm] = 2.90 contracting,
    # 1.57 relaxing (150-372 kPa); F [N] = 2.91 P + 44.6.
    "serres_k_low": (32.7, 0.0321),  # K = a - b P below the break
    "serres_k_high": (17.0, -0.0179),  # K = a - b P above the break
    "serres_k_break_kpa": 314.0,
    "serres_b_contract_ns_per_mm": 2.90,
    "serres_b_relax_ns_per_mm": 1.57,
    # SMC ITV2050 electro-pneumatic regulator (the paper; controller.md):
    # 0.005-0.9 MPa output, linearity about +-1 % FS, hysteresis about 0.5 % FS,
    # output lags the command by tens of ms plus a small dead time.
    "itv2050_fs_kpa": 900.0,
    "itv2050_linearity_frac_fs": 0.01,
    "itv2050_hysteresis_frac_fs": 0.005,
    # Pressure-length hysteresis of a small fluidic muscle (Appl. Sci. 2021, 11,
    # hysteresis of a small pneumatic muscle under 0, 2.55 and 4.55 kg loads):
    # with 2.55 kg at 300 kPa the contraction was 5.1 mm rising and 7.5 mm
    # falling, of a 14.8 mm stroke at 600 kPa (loop width 16 % of the stroke).
    "hyst_source_load_kg": 2.55,
    "hyst_source_loop_width_frac_of_stroke_at_300kpa": (7.5 - 5.1) / 14.8,
    # Firmware defaults the rig's wiring must match (firmware/app/params.toml):
    # 4-20 mA over 165 ohm into a 12-bit 3.3 V ADC; DAC 0-10 V over 12 bit for
    # 0-900 kPa (4.55 counts/kPa).
    # Baumer OADM 20 laser sensors: out of range (or no usable signal) the
    # analog output shows 4 mA / 0 V (Baumer operating manual OADM 20x659x, "Alarm
    # output"; controller.md).
    "oadm_out_of_range_ma": 4.0,
}


def _serres_k(p_kpa: float) -> float:
    a, b = SOURCES["serres_k_low"] if p_kpa < SOURCES["serres_k_break_kpa"] else SOURCES["serres_k_high"]
    return float(a - b * p_kpa)


def calibrate_mas10() -> dict[str, float]:
    """Derive the MAS-10-100N three-element coefficients from `SOURCES`.

    F(P) = F0 + F1 P through Martens and Boblan's two forces at nominal length.
    K(P): Serres's piecewise-linear shape, scaled so that at 650 kPa the force
    F(650) reaches zero at Martens's 21 % contraction of the 100 mm muscle (the
    secant stiffness). B: Serres's values scaled by the same factor (keeps the
    viscoelastic time constant B/K of the published muscle).
    """
    forces = SOURCES["martens_force_n_at_nominal"]
    (p_hi, f_hi), (p_lo, f_lo) = sorted(forces.items(), reverse=True)
    f1 = (f_hi - f_lo) / (p_hi - p_lo)
    f0 = f_lo - f1 * p_lo
    length = SOURCES["mas10_length_mm"]
    k650 = f_hi / (SOURCES["martens_zero_force_contraction_frac_at_650kpa"] * length)
    scale = k650 / _serres_k(650.0)
    a_lo, b_lo = SOURCES["serres_k_low"]
    a_hi, b_hi = SOURCES["serres_k_high"]
    return {
        "f0_n": f0,
        "f1_n_per_kpa": f1,
        "k_scale": scale,
        "k_break_kpa": SOURCES["serres_k_break_kpa"],
        "k0_low_n_per_mm": a_lo * scale,
        "k1_low_n_per_mm_kpa": b_lo * scale,
        "k0_high_n_per_mm": a_hi * scale,
        "k1_high_n_per_mm_kpa": b_hi * scale,
        "b_contract_ns_per_mm": SOURCES["serres_b_contract_ns_per_mm"] * scale,
        "b_relax_ns_per_mm": SOURCES["serres_b_relax_ns_per_mm"] * scale,
    }


_CAL = calibrate_mas10()


HYST_RAMP_N = 100.0


def _hyst_force_default() -> float:
    """Friction amplitude Fh_max(P) = A (1 - exp(-F(P)/HYST_RAMP_N)) with A chosen so
    that the quasi-static loop width 2 Fh_max / K at 300 kPa is the source's width
    relative to the stroke (16 % of the 0-600 kPa stroke of the calibrated MAS-10
    without load). The source's loop is about as wide from 250 to 450 kPa and
    narrower below 200 kPa: a friction force that ramps in with F(P) and then stays
    (HYST_RAMP_N = 100 N follows the narrower loops at 100-200 kPa)."""
    def f(p: float) -> float:
        return _CAL["f0_n"] + _CAL["f1_n_per_kpa"] * p

    def k(p: float) -> float:
        return _serres_k(p) * _CAL["k_scale"]

    stroke_mm = f(600.0) / k(600.0)
    width_mm = SOURCES["hyst_source_loop_width_frac_of_stroke_at_300kpa"] * stroke_mm
    return float(width_mm * k(300.0) / 2.0 / (1.0 - math.exp(-f(300.0) / HYST_RAMP_N)))


# ---------------------------------------------------------------------------
# Parameter groups
# ---------------------------------------------------------------------------
@dataclass
class MuscleParams:
    """Three-element model m xs'' + B(P, xs') xs' + K(P) xs = F(P) - loads,
    xs = contraction in mm (positive: shorter), P the actual muscle pressure."""

    length_mm: float = SOURCES["mas10_length_mm"]
    # Contractile element F(P) = F0 + F1 P, smoothly clipped at 0 N (no push).
    f0_n: float = _CAL["f0_n"]
    f1_n_per_kpa: float = _CAL["f1_n_per_kpa"]
    f_clip_width_n: float = 2.0  # width of the smooth zero clip (numerics only)
    # Spring K(P) = K0 - K1 P, two branches split at k_break_kpa (continuous).
    k_break_kpa: float = _CAL["k_break_kpa"]
    k_blend_kpa: float = 10.0  # smooth blend of the two branches (numerics only)
    k0_low_n_per_mm: float = _CAL["k0_low_n_per_mm"]
    k1_low_n_per_mm_kpa: float = _CAL["k1_low_n_per_mm_kpa"]
    k0_high_n_per_mm: float = _CAL["k0_high_n_per_mm"]
    k1_high_n_per_mm_kpa: float = _CAL["k1_high_n_per_mm_kpa"]
    # A rig variant: the spring K(P) scaled by this factor (another muscle of the same type,
    # another length; hil/scenarios/variants). 1: the calibrated muscle.
    stiffness_scale: float = 1.0
    # Damper: contracting (xs' > 0) and relaxing (xs' < 0), blended smoothly over
    # +-b_blend_mm_s so that the right-hand side stays smooth (numerics only).
    b_contract_ns_per_mm: float = _CAL["b_contract_ns_per_mm"]
    b_relax_ns_per_mm: float = _CAL["b_relax_ns_per_mm"]
    b_blend_mm_s: float = 0.1
    # Hysteresis: smooth Maxwell-slip (parallel Dahl elements). Friction force
    # amplitude Fh_max(P) = hyst_force_n * (1 - exp(-F(P) / hyst_ramp_n)); element
    # i saturates over hyst_delta_mm[i] with weight hyst_weights[i] (weights sum
    # to 1). hyst_force_n = 0 disables.
    hyst_force_n: float = field(default_factory=_hyst_force_default)
    hyst_ramp_n: float = HYST_RAMP_N
    hyst_delta_mm: tuple[float, ...] = (0.1, 0.25, 0.5, 1.0)
    hyst_weights: tuple[float, ...] = (0.25, 0.25, 0.25, 0.25)


@dataclass
class LoadParams:
    mass_kg: float = SOURCES["hyst_source_load_kg"]  # load mass m0 (moving mass)
    incline_deg: float = 90.0  # 90: load hangs from the muscle (eq. 1's m g); 0: horizontal rig
    bias_force_n: float = 0.0  # constant pull on the free end (e.g. cylinder fed at port B)
    g_m_s2: float = 9.80665
    disturbance_tau_s: float = 0.1  # the cylinder's force rises with this time constant


@dataclass
class RegulatorParams:
    fs_kpa: float = SOURCES["itv2050_fs_kpa"]  # full scale (0.9 MPa)
    p_min_kpa: float = 0.0
    p_max_kpa: float = SOURCES["itv2050_fs_kpa"]
    tau_s: float = 0.030  # first-order lag ("tens of ms")
    dead_time_s: float = 0.005  # "a small dead time"
    linearity_frac_fs: float = SOURCES["itv2050_linearity_frac_fs"]  # bow amplitude (signed)
    hysteresis_frac_fs: float = SOURCES["itv2050_hysteresis_frac_fs"]  # backlash width
    # The DAC in front of it (the firmware's default dac.*): counts -> kPa.
    dac_counts_at_zero_kpa: float = 0.0
    dac_counts_per_kpa: float = 4.55
    dac_bits: int = 12


@dataclass
class SensorParams:
    span_cm: float = 10.0  # measuring range of the laser (firmware default scaling)
    centre_cm: float = 0.0  # x at mid-range (mounted centred on x0)
    inverted: bool = True  # True: current rises as x falls (the firmware's negative gain)
    i_min_ma: float = 4.0
    i_max_ma: float = 20.0
    out_of_range_ma: float = SOURCES["oadm_out_of_range_ma"]  # Baumer: drops to 4 mA / 0 V
    wire_break_ma: float = 0.0
    shunt_ohm: float = 165.0
    adc_vref_v: float = 3.3
    adc_bits: int = 12
    noise_cm: float = 0.0005  # position noise, standard deviation (5 um)
    adc_noise_counts: float = 0.3  # ADC noise, standard deviation
    tau_s: float = 0.001  # response of the laser's analog output (first order)


@dataclass
class DriftParams:
    """Slow drift of the muscle's coefficients with its temperature rise dT(t) =
    min(rate * t, max_rise): each coefficient is scaled by (1 + c * dT)."""

    temp_rate_k_per_s: float = 0.01
    temp_max_rise_k: float = 10.0
    k_per_k: float = -0.003  # spring
    f_per_k: float = -0.001  # contractile element (and the hysteresis amplitude)
    b_per_k: float = -0.01  # damper


@dataclass
class ValveParams:
    """The valve/regulator beyond the first-order lag (docs/rig.md, "Against a real
    muscle"). model = "lag" (the default) keeps the regulator's dead time and
    first-order lag (RegulatorParams) and ignores everything below; "flow" replaces
    them: a dead time per direction, then a proportional valve whose opening
    saturates beyond p_band_kpa, filling from the supply and exhausting to the
    atmosphere through an ISO 6358 orifice (choked below the critical pressure
    ratio b, subsonic above, so exhausting slows down as the muscle approaches
    atmospheric pressure), into the muscle's volume V(xs) = V0 (1 +
    volume_gain_per_mm xs) (a contraction draws the pressure down while the
    volume grows). The set point the valve regulates to approaches a command in
    two parts: slow_weight of the step with slow_tau (the pilot stage and the
    slow final approach seen in measured steps), the rest at once. Pressures are
    gauge kPa; rates are dP/dt in kPa/s of the muscle at V0, valve fully open,
    choked flow."""

    model: str = "lag"
    dead_time_rise_s: float = 0.005
    dead_time_fall_s: float = 0.005
    supply_kpa: float = 600.0
    atm_kpa: float = 101.325
    fill_rate_kpa_s: float = 7000.0  # fully open, choked, from the supply into V0
    exhaust_rate_kpa_s: float = 7000.0  # fully open, choked, from supply_kpa to the atmosphere
    b_critical: float = 0.3  # ISO 6358 critical pressure ratio
    p_band_kpa: float = 20.0  # proportional band: fully open beyond this error
    slow_weight_rise: float = 0.0
    slow_weight_fall: float = 0.0
    slow_tau_rise_s: float = 0.5
    slow_tau_fall_s: float = 0.5
    volume_gain_per_mm: float = 0.0  # (V - V0)/V0 per mm of contraction
    polytropic_n: float = 1.0  # 1: isothermal (slow changes), 1.4: adiabatic


@dataclass
class CreepParams:
    """Creep at constant pressure: a slow viscoelastic part of the contractile
    element. A fraction of F(P) reaches the muscle only through a first-order lag,
    F_eff = F(P) - frac (F(P) - Fc), Fc' = (F(P) - Fc)/tau, with frac and tau of
    contraction (F(P) > Fc) or relaxation (F(P) < Fc), blended over blend_n. At
    rest F_eff = F(P): the static model is unchanged. frac = 0 disables."""

    frac_contract: float = 0.0
    frac_relax: float = 0.0
    tau_contract_s: float = 1.0
    tau_relax_s: float = 0.5
    blend_n: float = 1.0  # smooth switch between the two directions (numerics only)


@dataclass
class RigParams:
    muscle: MuscleParams = field(default_factory=MuscleParams)
    load: LoadParams = field(default_factory=LoadParams)
    regulator: RegulatorParams = field(default_factory=RegulatorParams)
    sensor: SensorParams = field(default_factory=SensorParams)
    drift: DriftParams = field(default_factory=DriftParams)
    valve: ValveParams = field(default_factory=ValveParams)
    creep: CreepParams = field(default_factory=CreepParams)
    # The rig profile these values started from ("nominal": the defaults above;
    # others in hil/rig_profiles.py). RigParams.from_dict({"profile": name, ...})
    # takes the profile's values, then the other keys on top.
    profile: str = "nominal"
    # The preset pressure p0 (must equal the firmware's act.p0_kpa): the static
    # equilibrium at the command p0 defines x = 0.
    p0_kpa: float = 300.0
    # Pressure command the rig starts with, at rest (None: p0, so x = 0).
    initial_p_kpa: float | None = None
    # The paper's sign: its sensor reads contraction as negative x (band -3 < x < 0).
    contraction_is_negative_x: bool = True
    # Integration: fixed-step RK4, at most this long a sub-step (also split at events).
    substep_s: float = 1e-4

    # -- dict round trip ---------------------------------------------------
    @classmethod
    def from_dict(cls, data: Mapping[str, Any] | None) -> "RigParams":
        """Defaults overridden by `data` (nested like `to_dict()`); unknown keys
        and invalid values raise ValueError so that a typo in a scenario file is
        not ignored."""
        data = dict(data or {})
        name = data.get("profile", "nominal")
        if not isinstance(name, str):
            raise RigParamError("profile", f"rig.profile: expected a profile's name (text), got {name!r}")
        if name != "nominal":
            from .rig_profiles import profile_dict  # here: rig_profiles imports this module

            data = _merge_tables(profile_dict(str(name)), data)
        params: RigParams = _from_dict(cls, data, "rig")
        params.validate()
        return params

    def to_dict(self) -> dict[str, Any]:
        return dataclasses.asdict(self)

    def replace(self, **changes: Any) -> "RigParams":
        """A copy with changes given as 'group.name' or top-level names. A change of
        'profile' starts from that profile's values (the other changes on top)."""
        base = RigParams.from_dict({"profile": changes.pop("profile")}) if "profile" in changes else self
        data = base.to_dict()
        for key, value in changes.items():
            parts = key.replace("__", ".").split(".")
            node = data
            for p in parts[:-1]:
                node = node[p]
            if parts[-1] not in node:
                raise ValueError(f"unknown rig parameter {key!r}")
            node[parts[-1]] = value
        return RigParams.from_dict(data)

    # -- derived quantities ------------------------------------------------
    def firmware_scaling(self) -> dict[str, float]:
        """The adc.* and dac.* firmware parameters that match this rig's wiring."""
        s = self.sensor
        counts_per_ma = (s.shunt_ohm / 1000.0) / s.adc_vref_v * ((1 << s.adc_bits) - 1)
        cm_per_ma = s.span_cm / (s.i_max_ma - s.i_min_ma)
        gain = (-cm_per_ma if s.inverted else cm_per_ma) / counts_per_ma
        x_at_imin = s.centre_cm + (s.span_cm / 2 if s.inverted else -s.span_cm / 2)
        offset = x_at_imin - gain * s.i_min_ma * counts_per_ma
        r = self.regulator
        return {
            "adc.offset_cm": offset,
            "adc.gain_cm_per_count": gain,
            "adc.raw_min_counts": 3.8 * counts_per_ma,  # NAMUR NE 43
            "adc.wire_break_below_counts": 3.6 * counts_per_ma,
            "dac.counts_at_zero_kpa": r.dac_counts_at_zero_kpa,
            "dac.counts_per_kpa": r.dac_counts_per_kpa,
            "dac.max_counts": float((1 << r.dac_bits) - 1),
            "act.p0_kpa": self.p0_kpa,
        }

    def validate(self) -> None:
        """ValueError naming the first value that is not finite or outside its physical range
        (RigParamError: its .path is the dotted name, e.g. load.bias_force_n)."""
        for path, value in _numbers(self, ""):
            if not math.isfinite(value):
                raise RigParamError(path, f"{path} must be finite, got {value!r}")
        m, ld, r, s, d = self.muscle, self.load, self.regulator, self.sensor, self.drift
        v, c = self.valve, self.creep
        checks: list[tuple[bool, str, str]] = [
            (m.length_mm > 0, "muscle.length_mm", "must be > 0"),
            (m.f1_n_per_kpa > 0, "muscle.f1_n_per_kpa", "must be > 0 (the force rises with the pressure)"),
            (m.stiffness_scale > 0, "muscle.stiffness_scale", "must be > 0"),
            (m.k_break_kpa >= 0, "muscle.k_break_kpa", "must be >= 0"),
            (m.b_contract_ns_per_mm > 0, "muscle.b_contract_ns_per_mm", "must be > 0 (damping)"),
            (m.b_relax_ns_per_mm > 0, "muscle.b_relax_ns_per_mm", "must be > 0 (damping)"),
            (m.b_blend_mm_s > 0, "muscle.b_blend_mm_s", "must be > 0 (a smoothing width)"),
            (m.f_clip_width_n > 0, "muscle.f_clip_width_n", "must be > 0 (a smoothing width)"),
            (m.k_blend_kpa > 0, "muscle.k_blend_kpa", "must be > 0 (a smoothing width)"),
            (m.hyst_force_n >= 0, "muscle.hyst_force_n", "must be >= 0"),
            (m.hyst_ramp_n > 0, "muscle.hyst_ramp_n", "must be > 0"),
            (len(m.hyst_delta_mm) == len(m.hyst_weights), "muscle.hyst_weights",
             "hyst_delta_mm (> 0) and hyst_weights need the same length"),
            (all(dl > 0 for dl in m.hyst_delta_mm), "muscle.hyst_delta_mm", "every element must be > 0"),
            (len(m.hyst_delta_mm) <= MAX_HYST, "muscle.hyst_delta_mm",
             f"at most {MAX_HYST} elements (PMA_RIG_MAX_HYST, hil/rig_core)"),
            (all(w >= 0 for w in m.hyst_weights), "muscle.hyst_weights", "every element must be >= 0"),
            (ld.mass_kg > 0, "load.mass_kg", "must be > 0"),
            (-90 <= ld.incline_deg <= 90, "load.incline_deg", "must be in [-90, 90]"),
            (ld.g_m_s2 >= 0, "load.g_m_s2", "must be >= 0"),
            (ld.disturbance_tau_s >= 0, "load.disturbance_tau_s", "must be >= 0"),
            (r.fs_kpa > 0, "regulator.fs_kpa", "must be > 0"),
            (r.p_min_kpa >= 0, "regulator.p_min_kpa", "must be >= 0 (regulator pressure range)"),
            (r.p_min_kpa < r.p_max_kpa, "regulator.p_max_kpa", "must be > regulator.p_min_kpa "
                                                               "(regulator pressure range)"),
            (r.tau_s > 0, "regulator.tau_s", "must be > 0"),
            (r.dead_time_s >= 0, "regulator.dead_time_s", "must be >= 0"),
            (-1 < r.linearity_frac_fs < 1, "regulator.linearity_frac_fs", "must be in (-1, 1)"),
            (0 <= r.hysteresis_frac_fs < 1, "regulator.hysteresis_frac_fs", "must be in [0, 1)"),
            (r.dac_counts_per_kpa != 0, "regulator.dac_counts_per_kpa", "must not be 0"),
            (1 <= r.dac_bits <= 24, "regulator.dac_bits", "must be 1..24"),
            (s.span_cm > 0, "sensor.span_cm", "must be > 0 (sensor range)"),
            (s.i_min_ma >= 0, "sensor.i_min_ma", "must be >= 0"),
            (s.i_max_ma > s.i_min_ma, "sensor.i_max_ma", "must be > sensor.i_min_ma (sensor range)"),
            (s.out_of_range_ma >= 0, "sensor.out_of_range_ma", "must be >= 0"),
            (s.wire_break_ma >= 0, "sensor.wire_break_ma", "must be >= 0"),
            (s.shunt_ohm > 0, "sensor.shunt_ohm", "must be > 0"),
            (s.adc_vref_v > 0, "sensor.adc_vref_v", "must be > 0"),
            (1 <= s.adc_bits <= 24, "sensor.adc_bits", "must be 1..24"),
            (s.noise_cm >= 0, "sensor.noise_cm", "must be >= 0"),
            (s.adc_noise_counts >= 0, "sensor.adc_noise_counts", "must be >= 0"),
            (s.tau_s >= 0, "sensor.tau_s", "must be >= 0"),
            (d.temp_rate_k_per_s >= 0, "drift.temp_rate_k_per_s", "must be >= 0"),
            (d.temp_max_rise_k >= 0, "drift.temp_max_rise_k", "must be >= 0"),
            (v.model in ("lag", "flow"), "valve.model", "must be 'lag' or 'flow'"),
            (v.dead_time_rise_s >= 0, "valve.dead_time_rise_s", "must be >= 0"),
            (v.dead_time_fall_s >= 0, "valve.dead_time_fall_s", "must be >= 0"),
            (v.fill_rate_kpa_s > 0, "valve.fill_rate_kpa_s", "must be > 0"),
            (v.exhaust_rate_kpa_s > 0, "valve.exhaust_rate_kpa_s", "must be > 0"),
            (v.p_band_kpa > 0, "valve.p_band_kpa", "must be > 0"),
            (0 <= v.b_critical < 1, "valve.b_critical", "must be in [0, 1)"),
            (v.supply_kpa > 0, "valve.supply_kpa", "must be > 0"),
            (v.atm_kpa > 0, "valve.atm_kpa", "must be > 0"),
            (0 <= v.slow_weight_rise < 1, "valve.slow_weight_rise", "must be in [0, 1)"),
            (0 <= v.slow_weight_fall < 1, "valve.slow_weight_fall", "must be in [0, 1)"),
            (v.slow_tau_rise_s > 0, "valve.slow_tau_rise_s", "must be > 0"),
            (v.slow_tau_fall_s > 0, "valve.slow_tau_fall_s", "must be > 0"),
            (v.polytropic_n >= 1, "valve.polytropic_n", "must be >= 1"),
            (0 <= c.frac_contract < 1, "creep.frac_contract", "must be in [0, 1)"),
            (0 <= c.frac_relax < 1, "creep.frac_relax", "must be in [0, 1)"),
            (c.tau_contract_s > 0, "creep.tau_contract_s", "must be > 0"),
            (c.tau_relax_s > 0, "creep.tau_relax_s", "must be > 0"),
            (c.blend_n > 0, "creep.blend_n", "must be > 0"),
            (r.p_min_kpa <= self.p0_kpa <= r.p_max_kpa, "p0_kpa",
             f"must be within the regulator's range {r.p_min_kpa:g}..{r.p_max_kpa:g} kPa"),
            (self.initial_p_kpa is None or r.p_min_kpa <= self.initial_p_kpa <= r.p_max_kpa, "initial_p_kpa",
             f"must be within the regulator's range {r.p_min_kpa:g}..{r.p_max_kpa:g} kPa"),
            (self.substep_s > 0, "substep_s", "must be > 0"),
        ]
        for ok, path, msg in checks:
            if not ok:
                value = _get(self, path)
                raise RigParamError(path, f"{path} {msg}, got {value!r}")


class RigParamError(ValueError):
    """A rig value of the wrong type or outside its range; path: its dotted name."""

    def __init__(self, path: str, message: str) -> None:
        super().__init__(message)
        self.path = path


def _get(obj: Any, path: str) -> Any:
    for part in path.split("."):
        obj = getattr(obj, part)
    return obj


def _numbers(obj: Any, prefix: str) -> list[tuple[str, float]]:
    """Every number of a parameter group (nested groups and tuples' elements included), by path."""
    out: list[tuple[str, float]] = []
    for f in dataclasses.fields(obj):
        value = getattr(obj, f.name)
        path = f"{prefix}{f.name}"
        if dataclasses.is_dataclass(value):
            out += _numbers(value, f"{path}.")
        elif isinstance(value, tuple):
            out += [(f"{path}[{i}]", float(x)) for i, x in enumerate(value)]
        elif isinstance(value, (int, float)) and not isinstance(value, bool):
            out.append((path, float(value)))
    return out


def _merge_tables(base: Mapping[str, Any], over: Mapping[str, Any]) -> dict[str, Any]:
    """over on top of base, nested tables merged key by key."""
    out = dict(base)
    for k, v in over.items():
        b = out.get(k)
        out[k] = _merge_tables(b, v) if isinstance(v, Mapping) and isinstance(b, Mapping) else v
    return out


def _is_number(value: Any) -> bool:
    return isinstance(value, numbers.Real) and not isinstance(value, bool)


def _typed(where: str, current: Any, value: Any) -> Any:
    """value as the type of the field's default `current` (a TOML/JSON value): a number for a
    number (an integer for an int field), true/false for a bool, text for text, an array of
    numbers for a tuple. RigParamError otherwise (no silent conversion: "false" is not False)."""
    if isinstance(current, bool):
        if not isinstance(value, bool):
            raise RigParamError(where, f"{where}: expected true or false, got {value!r}")
        return bool(value)
    if isinstance(current, tuple):
        if not isinstance(value, (list, tuple)) or not all(_is_number(x) for x in value):
            raise RigParamError(where, f"{where}: expected an array of numbers, got {value!r}")
        return tuple(float(x) for x in value)
    if isinstance(current, int):
        if not _is_number(value) or not float(value).is_integer():
            raise RigParamError(where, f"{where}: expected an integer, got {value!r}")
        return int(value)
    if current is None or isinstance(current, float):
        if value is None and current is None:
            return None
        if not _is_number(value):
            raise RigParamError(where, f"{where}: expected a number, got {value!r}")
        return float(value)
    if isinstance(current, str):
        if not isinstance(value, str):
            raise RigParamError(where, f"{where}: expected text, got {value!r}")
        return value
    raise RigParamError(where, f"{where}: cannot be set")      # pragma: no cover (every field is one of the above)


def _from_dict(cls: type, data: Mapping[str, Any], where: str) -> Any:
    if not isinstance(data, Mapping):
        raise RigParamError(where, f"{where}: expected a table, got {type(data).__name__}")
    fields = {f.name: f for f in dataclasses.fields(cls)}
    unknown = set(data) - set(fields)
    if unknown:
        raise RigParamError(where, f"{where}: unknown parameter(s) {sorted(unknown)}")
    kwargs: dict[str, Any] = {}
    defaults = cls()
    for name, value in data.items():
        current = getattr(defaults, name)
        if dataclasses.is_dataclass(current):
            kwargs[name] = _from_dict(type(current), value, f"{where}.{name}")
        else:
            kwargs[name] = _typed(f"{where}.{name}", current, value)
    return cls(**kwargs)


def parse_text(path: str, text: str) -> Any:
    """A rig value given as text on a command line (`--rig load.bias_force_n=5`), as the type of
    the parameter at the dotted `path`: a number, an integer, true/false (also 1/0) for a bool,
    text. RigParamError for an unknown path, a group, a list or text of another type."""
    current: Any = RigParams()
    for part in path.split("."):
        if not dataclasses.is_dataclass(current) or part not in {f.name for f in dataclasses.fields(current)}:
            raise RigParamError(path, f"{path}: no such rig parameter (hil/rig_params.py, docs/rig.md)")
        current = getattr(current, part)
    t = text.strip()
    if dataclasses.is_dataclass(current):
        raise RigParamError(path, f"{path}: a group of rig parameters, not one (e.g. {path}."
                                  f"{dataclasses.fields(current)[0].name})")
    if isinstance(current, bool):
        low = t.lower()
        if low in ("true", "1"):
            return True
        if low in ("false", "0"):
            return False
        raise RigParamError(path, f"{path}: expected true or false (or 1 or 0), got {t!r}")
    if isinstance(current, tuple):
        raise RigParamError(path, f"{path}: an array: set it in a scenario file's [rig] table")
    if isinstance(current, str):
        return t
    kind = "an integer" if isinstance(current, int) else "a number"
    try:
        number = float(t)
    except ValueError:
        raise RigParamError(path, f"{path}: expected {kind}, got {t!r}") from None
    if isinstance(current, int):
        if not number.is_integer():
            raise RigParamError(path, f"{path}: expected {kind}, got {t!r}")
        return int(number)
    return number
