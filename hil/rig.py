# SPDX-License-Identifier: Apache-2.0
"""The simulated pneumatic-muscle rig: muscle, load, pressure regulator, laser sensor.

Independent of the firmware's code: it only shares the wiring conventions (the
default adc.* and dac.* scalings) that a real rig would share. The runner talks
to it as the plant behind the CAN plant bridge:

    rig = Rig(RigParams(), seed=1)
    counts = rig.sensor_counts()        # -> PLANT_SENSOR RawCounts
    rig.apply_dac(dac_counts)           # <- PLANT_ACTUATOR DacCounts
    rig.step(0.001)                     # one control period

Model (docs/rig.md has the values and their sources):

* Muscle, three-element model with the load, xs = contraction in mm (positive:
  shorter), P = actual muscle pressure in kPa, T the temperature rise:
      m xs'' = F(P) - K(P) xs - B(xs') xs' - Fh - W(t)
  F(P) = F0 + F1 P (smoothly clipped at 0: a muscle cannot push),
  K(P) = K0 - K1 P on two pressure branches, B = B_contract for xs' > 0 and
  B_relax for xs' < 0 (smoothly blended), Fh a smooth Maxwell-slip friction
  (parallel Dahl elements, amplitude ramping in with F(P) to hyst_force_n), W = m g sin(incline) +
  bias force + the cylinder's disturbance force. F, K, B drift with T.
* x (cm) = the displacement from x0, the static equilibrium at the preset
  command p0; by default contraction gives negative x (the paper's sign).
* Regulator: DAC counts -> command kPa (clipped to 0..900), backlash (its
  hysteresis), a bow-shaped linearity error, a dead time, then a first-order lag.
* Sensor: first-order response, position noise, out-of-range drop to 4 mA,
  4-20 mA over a shunt into a 12-bit ADC with noise, a wire-break switch.
* Integration: fixed-step classical RK4, sub-steps of at most params.substep_s,
  split exactly at every event (a delayed command taking effect, the
  disturbance switching on), so the input is smooth inside every sub-step.
  Time is kept in integer nanoseconds. The right-hand side and its RK4 steps are
  C (hil/rig_core, libpma_rig.so: hil/rig_lib.py): this module keeps the
  parameters, the regulator's dead time and events, the sensor and the static model.
"""

from __future__ import annotations

import copy
import ctypes
import math
from collections import deque
from typing import Any, Mapping

import numpy as np

from . import rig_lib
from .rig_params import (
    CreepParams,
    DriftParams,
    LoadParams,
    MuscleParams,
    RegulatorParams,
    RigParams,
    SensorParams,
    ValveParams,
)

__all__ = [
    "Rig",
    "RigParams",
    "MuscleParams",
    "LoadParams",
    "RegulatorParams",
    "SensorParams",
    "DriftParams",
    "ValveParams",
    "CreepParams",
]

_NS = 1_000_000_000
NOISE_BLOCK = 4096         # sensor noise values drawn at once (even: two per sample)


def _ns(seconds: float) -> int:
    return int(round(seconds * _NS))


class Rig:
    """One simulated rig. Deterministic: the same params, seed and calls give
    the same results (the seed drives only the sensor noise)."""

    # ------------------------------------------------------------------ set-up
    def __init__(self, params: RigParams | None = None, seed: int = 0):
        self.params = copy.deepcopy(params) if params is not None else RigParams()
        self.params.validate()
        self.seed = int(seed)
        self._rng = np.random.default_rng(self.seed)
        # the sensor's noise, drawn NOISE_BLOCK values at a time: the same stream as two
        # draws per sample, without a draw's lock per sample (in the vcan guest a lock
        # costs about 60 us, a system call)
        self._noise: list[float] = []
        self._noise_i = 0
        p = self.params
        self._sign = -1.0 if p.contraction_is_negative_x else 1.0
        self._t_ns = 0
        self._mass = p.load.mass_kg
        self._bias = p.load.bias_force_n
        self._sin_incl = math.sin(math.radians(p.load.incline_deg))
        # disturbance profile: switch events (t_on_ns, target N, start N), sorted
        self._d_events: list[tuple[int, float, float]] = []
        self._wire_broken = False
        self._blocked = False
        self._n_hyst = len(p.muscle.hyst_delta_mm)
        self._dead_ns = _ns(p.regulator.dead_time_s)
        self._queue: deque[tuple[int, float]] = deque()
        self._dac_max = (1 << p.regulator.dac_bits) - 1
        self._adc_max = (1 << p.sensor.adc_bits) - 1
        self._counts_per_ma = (p.sensor.shunt_ohm / 1000.0) / p.sensor.adc_vref_v * self._adc_max

        # x0: the static equilibrium at the preset command p0, with the initial
        # load, no disturbance, no temperature rise, virgin hysteresis.
        self._xs0 = self.static_xs_mm(self.regulator_static_kpa(p.p0_kpa))

        p_init = p.p0_kpa if p.initial_p_kpa is None else p.initial_p_kpa
        p_init = min(max(p_init, p.regulator.p_min_kpa), p.regulator.p_max_kpa)
        self._p_cmd = p_init
        self._dac_counts: int | None = None
        self._backlash = p_init  # regulator hysteresis (backlash) output
        self._p_set = self.regulator_static_kpa(p_init)
        xs = self.static_xs_mm(self._p_set)
        # state: xs [mm], v [mm/s], P [kPa], y (sensor) [mm], z_i (hysteresis) [mm]
        s = [xs, 0.0, self._p_set, xs] + [0.0] * self._n_hyst
        # The extended model (docs/rig.md, "Against a real muscle"): the flow-limited
        # valve and/or creep. Off in the nominal profile, whose code path and
        # arithmetic stay exactly those of the three-element rig above.
        v, c = p.valve, p.creep
        self._ext = v.model == "flow" or c.frac_contract > 0.0 or c.frac_relax > 0.0
        if self._ext:
            self._flow = v.model == "flow"
            self._dead_rise_ns = _ns(v.dead_time_rise_s if self._flow else p.regulator.dead_time_s)
            self._dead_fall_ns = _ns(v.dead_time_fall_s if self._flow else p.regulator.dead_time_s)
            self._q_rise: deque[tuple[int, int, float]] = deque()
            self._q_fall: deque[tuple[int, int, float]] = deque()
            self._seq_sent = 0
            self._seq_applied = 0
            self._last_sent = self._p_set
            self._last_rising = True
            # extra state: the valve's slow pilot set point q [kPa], the creep element Fc [N]
            s += [self._p_set, self._f_pos(self._p_set)]
        # the set points waiting for their dead time: one queue, or one per direction
        self._set_points = (self._q_rise, self._q_fall) if self._ext else (self._queue,)
        self._bind(s)
        self._update_substep()

    def _bind(self, state: list[float]) -> None:
        """The state and the C model (libpma_rig.so) from the Python attributes."""
        self._s = rig_lib.State(*state)     # advanced in place by libpma_rig.so
        self._lib = rig_lib.library()
        self._model = rig_lib.Model()
        self._model_p = ctypes.pointer(self._model)
        self._advance = self._lib.pma_rig_advance
        self._cache()
        self._sync_disturbance()

    _NATIVE = ("_s", "_lib", "_model", "_model_p", "_advance", "_dist_arrays")

    def __getstate__(self) -> dict[str, Any]:
        """Picklable (a run's result crosses processes): the ctypes objects as plain data."""
        d = {k: v for k, v in self.__dict__.items() if k not in self._NATIVE}
        d["_state_list"] = list(self._s)[:rig_lib.state_len(self._model)]
        return d

    def __setstate__(self, d: dict[str, Any]) -> None:
        d = dict(d)
        state = d.pop("_state_list")
        self.__dict__.update(d)
        self._bind(state)

    @classmethod
    def from_dict(cls, data: Mapping[str, Any] | None, seed: int = 0) -> "Rig":
        return cls(RigParams.from_dict(data), seed)

    # -------------------------------------------------------------- the inputs
    def apply_dac(self, counts: int) -> None:
        """The pressure command as DAC counts (PLANT_ACTUATOR DacCounts). It
        reaches the regulator's output stage after the dead time."""
        r = self.params.regulator
        c = int(counts)
        c = 0 if c < 0 else (self._dac_max if c > self._dac_max else c)
        self._dac_counts = c
        p_cmd = (c - r.dac_counts_at_zero_kpa) / r.dac_counts_per_kpa
        p_cmd = min(max(p_cmd, r.p_min_kpa), r.p_max_kpa)
        self._p_cmd = p_cmd
        p_set = self._regulator_map(p_cmd)
        if self._ext:
            self._enqueue_ext(p_set)
        elif self._dead_ns == 0:
            self._p_set = p_set
        else:
            self._queue.append((self._t_ns + self._dead_ns, p_set))

    def kpa_to_dac(self, p_kpa: float) -> int:
        """DAC counts for a pressure, as the firmware's default dac.* scaling does."""
        r = self.params.regulator
        c = int(round(r.dac_counts_at_zero_kpa + r.dac_counts_per_kpa * p_kpa))
        return 0 if c < 0 else (self._dac_max if c > self._dac_max else c)

    def apply_pressure_kpa(self, p_kpa: float) -> None:
        """Open-loop convenience: command a pressure through the DAC."""
        self.apply_dac(self.kpa_to_dac(p_kpa))

    def set_load_mass(self, mass_kg: float) -> None:
        """Change the load mass now (velocity is kept)."""
        if not mass_kg > 0:
            raise ValueError("mass must be > 0")
        self._mass = float(mass_kg)
        self._cache()
        self._update_substep()

    def set_bias_force(self, force_n: float) -> None:
        """A constant pull on the free end from now on (e.g. the cylinder fed at port B)."""
        self._bias = float(force_n)
        self._cache()

    def set_disturbance(self, force_n: float, t_on_s: float | None = None) -> None:
        """The cylinder's force (N, positive pulls the muscle longer) switched on
        at t_on_s (default: now); it rises with load.disturbance_tau_s. Call
        again with 0 to switch it off."""
        t_on_ns = self._t_ns if t_on_s is None else max(_ns(t_on_s), self._t_ns)
        events = [(t, f) for t, f, _ in self._d_events if t < t_on_ns] + [(t_on_ns, float(force_n))]
        # each switch starts from the value the profile had just before it
        self._d_events = []
        for t, f in events:
            self._sync_disturbance()    # each start from the profile of the switches before it
            self._d_events.append((t, f, self._disturbance_at(t * 1e-9)))
        self._sync_disturbance()

    def _sync_disturbance(self) -> None:
        """The disturbance's switch events into the C model (arrays it points to, kept here)."""
        ev = self._d_events
        n = max(1, len(ev))
        self._dist_arrays = ((ctypes.c_int64 * n)(*[e[0] for e in ev]), (ctypes.c_double * n)(*[e[1] for e in ev]),
                             (ctypes.c_double * n)(*[e[2] for e in ev]))
        m = self._model
        m.dist_t_ns = ctypes.cast(self._dist_arrays[0], ctypes.POINTER(ctypes.c_int64))
        m.dist_target_n = ctypes.cast(self._dist_arrays[1], ctypes.POINTER(ctypes.c_double))
        m.dist_start_n = ctypes.cast(self._dist_arrays[2], ctypes.POINTER(ctypes.c_double))
        m.n_dist = len(ev)

    def break_wire(self, on: bool = True) -> None:
        """Sensor cable cut: the loop current drops to 0 mA."""
        self._wire_broken = bool(on)

    def set_sensor_blocked(self, on: bool = True) -> None:
        """The laser loses its target (or it leaves the range): 4 mA, like out of range."""
        self._blocked = bool(on)

    def apply_event(self, action: str, value: float) -> bool:
        """A scenario event (hil/scenario.py [[events]]) that acts on the rig; False for one
        that does not (e.g. host_heartbeat, which acts on the host side)."""
        if action == "load_mass":
            self.set_load_mass(value)          # kg
        elif action == "bias_force":
            self.set_bias_force(value)         # N
        elif action == "disturbance":
            self.set_disturbance(value)        # N
        elif action == "wire_break":
            self.break_wire(bool(value))
        elif action == "sensor_block":
            self.set_sensor_blocked(bool(value))
        else:
            return False
        return True

    # ------------------------------------------------------------- the output
    def sensor_counts(self) -> int:
        """One ADC sample of the position sensor (PLANT_SENSOR RawCounts)."""
        s = self.params.sensor
        i = self._noise_i                   # always drawn: the noise stream never depends on faults
        if i + 2 > len(self._noise):
            self._noise = self._rng.standard_normal(NOISE_BLOCK).tolist()
            i = 0
        n_pos, n_adc = self._noise[i], self._noise[i + 1]
        self._noise_i = i + 2
        if self._wire_broken:
            current = s.wire_break_ma
        else:
            x = self._sign * (self._s[3] - self._xs0) / 10.0 + s.noise_cm * n_pos
            lo = s.centre_cm - s.span_cm / 2.0
            hi = s.centre_cm + s.span_cm / 2.0
            if self._blocked or not (lo <= x <= hi):
                current = s.out_of_range_ma
            else:
                frac = (hi - x) / s.span_cm if s.inverted else (x - lo) / s.span_cm
                current = s.i_min_ma + (s.i_max_ma - s.i_min_ma) * frac
        c = int(round(current * self._counts_per_ma + s.adc_noise_counts * n_adc))
        return 0 if c < 0 else (self._adc_max if c > self._adc_max else c)

    # ------------------------------------------------------------ integration
    def step(self, dt_s: float) -> None:
        """Advance the rig by dt_s seconds (RK4 sub-steps, split at events): libpma_rig.so
        integrates up to the next regulator set point that takes effect, then it does."""
        if dt_s < 0:
            raise ValueError("dt must be >= 0")
        end = self._t_ns + _ns(dt_s)
        while self._t_ns < end:
            t = self._t_ns
            stop = end
            for q in self._set_points:
                if q and q[0][0] < stop:
                    stop = max(q[0][0], t)
            if stop > t:
                if self._advance(self._model_p, self._s, t, stop, self._h_ns, self._p_set) != 0:
                    raise rig_lib.RigLibError(f"libpma_rig.so refused the model ({self._n_hyst} hysteresis "
                                              f"elements, sub-step {self._h_ns} ns)")
                self._t_ns = stop
            if self._ext:
                self._apply_due_ext()
            else:
                while self._queue and self._queue[0][0] <= self._t_ns:
                    self._p_set = self._queue.popleft()[1]

    def _cache(self) -> None:
        """The constants of the right-hand side into the C model (rig_lib.Model)."""
        p = self.params
        m, d, c = p.muscle, p.drift, self._model
        c.f0_n, c.f1_n_per_kpa, c.f_clip_width_sq_n2 = m.f0_n, m.f1_n_per_kpa, m.f_clip_width_n ** 2
        c.k_break_kpa, c.k_blend_kpa = m.k_break_kpa, m.k_blend_kpa
        ks = m.stiffness_scale
        c.k0_low_n_per_mm, c.k1_low_n_per_mm_kpa = ks * m.k0_low_n_per_mm, ks * m.k1_low_n_per_mm_kpa
        c.k0_high_n_per_mm, c.k1_high_n_per_mm_kpa = ks * m.k0_high_n_per_mm, ks * m.k1_high_n_per_mm_kpa
        c.b_mid_ns_per_mm = 0.5 * (m.b_contract_ns_per_mm + m.b_relax_ns_per_mm)
        c.b_half_ns_per_mm = 0.5 * (m.b_contract_ns_per_mm - m.b_relax_ns_per_mm)
        c.b_blend_mm_s = m.b_blend_mm_s
        c.hyst_force_n, c.hyst_ramp_n = m.hyst_force_n, m.hyst_ramp_n
        c.n_hyst = self._n_hyst
        for i, (w, dl) in enumerate(zip(m.hyst_weights, m.hyst_delta_mm)):
            c.hyst_delta_mm[i], c.hyst_w_per_delta_per_mm[i] = dl, w / dl
        c.drift_rate_k_per_s, c.drift_max_rise_k = d.temp_rate_k_per_s, d.temp_max_rise_k
        c.drift_f_per_k, c.drift_k_per_k, c.drift_b_per_k = d.f_per_k, d.k_per_k, d.b_per_k
        knee = self._drift_knee_ns
        c.drift_knee_ns = -1 if knee is None else knee
        c.tau_p_s, c.tau_y_s = p.regulator.tau_s, p.sensor.tau_s
        c.w_static_n = self._mass * p.load.g_m_s2 * self._sin_incl + self._bias
        c.acc_mm_s2_per_n = 1000.0 / self._mass
        c.dist_tau_s = p.load.disturbance_tau_s
        c.ext, c.flow = int(self._ext), int(self._ext and self._flow)
        if self._ext:
            v, cr = p.valve, p.creep
            c.creep_frac_contract, c.creep_frac_relax = cr.frac_contract, cr.frac_relax
            c.creep_inv_tau_contract_per_s, c.creep_inv_tau_relax_per_s = 1.0 / cr.tau_contract_s, 1.0 / cr.tau_relax_s
            c.creep_blend_sq_n2 = cr.blend_n ** 2
            c.slow_weight_rise, c.slow_weight_fall = v.slow_weight_rise, v.slow_weight_fall
            c.slow_inv_tau_rise_per_s, c.slow_inv_tau_fall_per_s = 1.0 / v.slow_tau_rise_s, 1.0 / v.slow_tau_fall_s
            c.valve_band_kpa, c.valve_fill_rate_kpa_s = v.p_band_kpa, v.fill_rate_kpa_s
            c.valve_exhaust_rate_kpa_s, c.valve_supply_abs_kpa = v.exhaust_rate_kpa_s, v.supply_kpa + v.atm_kpa
            c.valve_atm_kpa, c.valve_b_critical = v.atm_kpa, v.b_critical
            c.valve_volume_gain_per_mm, c.valve_polytropic_n = v.volume_gain_per_mm, v.polytropic_n

    # ------------------------------------------------- the extended model
    def _enqueue_ext(self, p_set: float) -> None:
        """A new regulator set point, delayed by the dead time of its direction
        (rising or falling against the previous command; a command equal to the one
        before keeps the direction of the last change: a held set point is no new
        rising one, which would overtake a falling step still in its longer dead
        time). A set point that takes effect replaces every older one still waiting
        (a later command wins)."""
        if p_set != self._last_sent:
            self._last_rising = p_set > self._last_sent
        rising = self._last_rising
        self._last_sent = p_set
        self._seq_sent += 1
        dead = self._dead_rise_ns if rising else self._dead_fall_ns
        if dead == 0:
            self._p_set = p_set
            self._seq_applied = self._seq_sent
        else:
            (self._q_rise if rising else self._q_fall).append((self._t_ns + dead, self._seq_sent, p_set))

    def _apply_due_ext(self) -> None:
        best_seq, best_p = self._seq_applied, self._p_set
        for q in (self._q_rise, self._q_fall):
            while q and q[0][0] <= self._t_ns:
                _, seq, p_set = q.popleft()
                if seq > best_seq:
                    best_seq, best_p = seq, p_set
        self._seq_applied, self._p_set = best_seq, best_p

    # ------------------------------------------------------- model functions
    def _f_pos(self, p_kpa: float) -> float:
        """Contractile element F(P) [N], smoothly clipped at zero."""
        m = self.params.muscle
        f = m.f0_n + m.f1_n_per_kpa * p_kpa
        w = m.f_clip_width_n
        return 0.5 * (f + math.sqrt(f * f + w * w))

    def _k_of_p(self, p_kpa: float) -> float:
        """Spring K(P) [N/mm]: the low and high pressure branches, blended over
        +-k_blend_kpa around the break so that K is smooth (as the dynamics in
        hil/rig_core/pma_rig_core.c)."""
        m = self.params.muscle
        u = (p_kpa - m.k_break_kpa) / m.k_blend_kpa
        k_lo = m.k0_low_n_per_mm - m.k1_low_n_per_mm_kpa * p_kpa
        k_hi = m.k0_high_n_per_mm - m.k1_high_n_per_mm_kpa * p_kpa
        return m.stiffness_scale * (k_lo + (k_hi - k_lo) * 0.5 * (1.0 + u / math.sqrt(u * u + 1.0)))

    def _b_of_v(self, v_mm_s: float) -> float:
        """Damper B [N s/mm]: contracting (v > 0) or relaxing (v < 0)."""
        m = self.params.muscle
        mid = 0.5 * (m.b_contract_ns_per_mm + m.b_relax_ns_per_mm)
        half = 0.5 * (m.b_contract_ns_per_mm - m.b_relax_ns_per_mm)
        return mid + half * math.tanh(v_mm_s / m.b_blend_mm_s)

    def _temp_rise(self, t: float) -> float:
        d = self.params.drift
        return min(d.temp_rate_k_per_s * t, d.temp_max_rise_k) if d.temp_rate_k_per_s > 0 else 0.0

    @property
    def _drift_knee_ns(self) -> int | None:
        d = self.params.drift
        if d.temp_rate_k_per_s > 0 and d.temp_max_rise_k > 0:
            return _ns(d.temp_max_rise_k / d.temp_rate_k_per_s)
        return None

    def _disturbance_at(self, t: float) -> float:
        """The cylinder's force [N] at time t [s]: after each switch it moves from its value
        before the switch towards the new target with load.disturbance_tau_s."""
        if not self._d_events:      # (the recording asks every tick)
            return 0.0
        return float(self._lib.pma_rig_disturbance_n(self._model_p, t))

    def _regulator_map(self, p_cmd: float) -> float:
        """Backlash (the regulator's hysteresis) then its linearity error."""
        r = self.params.regulator
        half = 0.5 * r.hysteresis_frac_fs * r.fs_kpa
        if p_cmd > self._backlash + half:
            self._backlash = p_cmd - half
        elif p_cmd < self._backlash - half:
            self._backlash = p_cmd + half
        return self._linearity(self._backlash)

    def _linearity(self, p: float) -> float:
        r = self.params.regulator
        q = min(max(p, 0.0), r.fs_kpa)
        out = p + r.linearity_frac_fs * r.fs_kpa * math.sin(math.pi * q / r.fs_kpa)
        return min(max(out, r.p_min_kpa), r.p_max_kpa)

    def _update_substep(self) -> None:
        """Sub-step: params.substep_s, shortened if needed to keep RK4 well inside
        its stability region for the stiffest mode of the current parameters."""
        p = self.params
        m = p.muscle
        k_max = max(self._k_of_p(0.0), self._k_of_p(p.regulator.p_max_kpa))
        k_h = m.hyst_force_n * sum(w / dlt for w, dlt in zip(m.hyst_weights, m.hyst_delta_mm))
        b_max = (max(m.b_contract_ns_per_mm, m.b_relax_ns_per_mm)
                 * (1.0 + abs(p.drift.b_per_k) * p.drift.temp_max_rise_k))
        lam = 1000.0 * b_max / self._mass + math.sqrt(1000.0 * (k_max + k_h) / self._mass)
        lam += 1.0 / p.regulator.tau_s + (1.0 / p.sensor.tau_s if p.sensor.tau_s > 0 else 0.0)
        if m.hyst_force_n > 0:
            lam += 100.0 / min(m.hyst_delta_mm)  # Dahl elements at 100 mm/s
        if self._ext:
            v, c = p.valve, p.creep
            if self._flow:
                lam += max(v.fill_rate_kpa_s, v.exhaust_rate_kpa_s) / v.p_band_kpa
                lam += 1.0 / min(v.slow_tau_rise_s, v.slow_tau_fall_s)
            lam += 1.0 / min(c.tau_contract_s, c.tau_relax_s)
        h = min(p.substep_s, 2.0 / lam)
        self._h_ns = max(1, int(h * _NS))

    # ---------------------------------------------------------- static model
    def regulator_static_kpa(self, p_cmd_kpa: float) -> float:
        """Steady regulator output for a command (linearity error; no backlash)."""
        r = self.params.regulator
        return self._linearity(min(max(p_cmd_kpa, r.p_min_kpa), r.p_max_kpa))

    def static_xs_mm(self, p_kpa: float, mass_kg: float | None = None, extra_force_n: float = 0.0,
                     temp_rise_k: float = 0.0, friction: float = 0.0) -> float:
        """Equilibrium contraction [mm] at the actual pressure p_kpa. friction:
        +1 after rising pressure (the friction saturated against contraction),
        -1 after falling pressure, 0 virgin (no friction force)."""
        p = self.params
        d = p.drift
        mass = self._mass if mass_kg is None else mass_kg
        force = self._f_pos(p_kpa) * (1.0 + d.f_per_k * temp_rise_k)
        k = self._k_of_p(p_kpa) * (1.0 + d.k_per_k * temp_rise_k)
        w = mass * p.load.g_m_s2 * self._sin_incl + self._bias + extra_force_n
        return (force - friction * self.friction_amplitude_n(force) - w) / k

    def friction_amplitude_n(self, force_n: float) -> float:
        """Saturated friction (hysteresis) force for a contractile force F(P)."""
        m = self.params.muscle
        return m.hyst_force_n * (1.0 - math.exp(-force_n / m.hyst_ramp_n))

    def static_x_cm(self, p_cmd_kpa: float, **kwargs: Any) -> float:
        """Static x [cm] for a steady pressure command (see static_xs_mm for kwargs)."""
        xs = self.static_xs_mm(self.regulator_static_kpa(p_cmd_kpa), **kwargs)
        return self._sign * (xs - self._xs0) / 10.0

    def p_cmd_for_x_cm(self, x_cm: float, **kwargs: Any) -> float | None:
        """The steady pressure command that holds x_cm (static model), or None
        when x_cm is outside what the regulator's range reaches."""
        r = self.params.regulator
        lo_p, hi_p = max(r.p_min_kpa, 45.0), r.p_max_kpa  # F(P) > 0 above ~42 kPa: monotone
        x_lo, x_hi = self.static_x_cm(lo_p, **kwargs), self.static_x_cm(hi_p, **kwargs)
        if not (min(x_lo, x_hi) <= x_cm <= max(x_lo, x_hi)):
            return None
        for _ in range(80):
            mid = 0.5 * (lo_p + hi_p)
            x_mid = self.static_x_cm(mid, **kwargs)
            if (x_mid - x_cm) * (x_lo - x_cm) > 0:
                lo_p, x_lo = mid, x_mid
            else:
                hi_p = mid
        return 0.5 * (lo_p + hi_p)

    def linearised_eq7(self, p_kpa: float | None = None) -> dict[str, float]:
        """The paper's eq. 7 coefficients at a steady pressure (default p0), in the
        firmware's units (x in cm, u = pressure change in kPa, this rig's sign):
        x'' = H u - D x' - G x. D differs in contraction and relaxation."""
        p = self.params
        p_cmd = p.p0_kpa if p_kpa is None else p_kpa
        pr = self.regulator_static_kpa(p_cmd)
        xs = self.static_xs_mm(pr)
        dp = 1e-3
        dforce = (self._f_pos(pr + dp) - self._f_pos(pr - dp)) / (2 * dp)
        dk = (self._k_of_p(pr + dp) - self._k_of_p(pr - dp)) / (2 * dp)
        dlin = (self.regulator_static_kpa(p_cmd + dp) - self.regulator_static_kpa(p_cmd - dp)) / (2 * dp)
        m = self._mass
        k = self._k_of_p(pr)
        mu = p.muscle
        # H: d(xs'')/dP in mm/s^2 per kPa -> cm/s^2 per kPa of command, with the sign of x
        h = self._sign * (1000.0 * (dforce - dk * xs) / m) / 10.0 * dlin
        return {
            "p_kpa": pr,
            "xs_mm": xs,
            "H_cm_s2_per_kpa": h,
            "D_contract_1_s": 1000.0 * mu.b_contract_ns_per_mm / m,
            "D_relax_1_s": 1000.0 * mu.b_relax_ns_per_mm / m,
            "G_1_s2": 1000.0 * k / m,
            "static_gain_cm_per_kpa": h / (1000.0 * k / m),
            "mechanical_time_constant_contract_s": mu.b_contract_ns_per_mm / k,
            "mechanical_time_constant_relax_s": mu.b_relax_ns_per_mm / k,
        }

    # ------------------------------------------------------------ properties
    @property
    def time_s(self) -> float:
        return self._t_ns * 1e-9

    @property
    def time_ns(self) -> int:
        return self._t_ns

    @property
    def x_cm(self) -> float:
        """True position, cm from x0 (the paper's sign by default)."""
        return self._sign * (self._s[0] - self._xs0) / 10.0

    @property
    def v_cm_s(self) -> float:
        return self._sign * self._s[1] / 10.0

    @property
    def x_sensor_cm(self) -> float:
        """What the sensor sees before noise and quantisation (its response lag only)."""
        return self._sign * (self._s[3] - self._xs0) / 10.0

    @property
    def contraction_mm(self) -> float:
        return self._s[0]

    @property
    def x0_contraction_mm(self) -> float:
        """Contraction at x = 0 (the equilibrium at p0)."""
        return self._xs0

    @property
    def p_kpa(self) -> float:
        """Actual pressure in the muscle."""
        return self._s[2]

    @property
    def p_cmd_kpa(self) -> float:
        """Last pressure command (quantised by the DAC, clipped to the regulator's range)."""
        return self._p_cmd

    @property
    def p_set_kpa(self) -> float:
        """Regulator set point now in effect (after dead time, backlash, linearity)."""
        return self._p_set

    @property
    def dac_counts(self) -> int | None:
        return self._dac_counts

    @property
    def load_mass_kg(self) -> float:
        return self._mass

    @property
    def disturbance_force_n(self) -> float:
        return self._disturbance_at(self.time_s)

    @property
    def temperature_rise_k(self) -> float:
        return self._temp_rise(self.time_s)

    @property
    def hysteresis_force_n(self) -> float:
        m = self.params.muscle
        if m.hyst_force_n <= 0:
            return 0.0
        acc = sum(w * self._s[4 + i] / dlt for i, (dlt, w) in enumerate(zip(m.hyst_delta_mm, m.hyst_weights)))
        force = self._f_pos(self.p_kpa) * (1.0 + self.params.drift.f_per_k * self.temperature_rise_k)
        return self.friction_amplitude_n(force) * acc

    @property
    def wire_broken(self) -> bool:
        return self._wire_broken

    @property
    def sensor_blocked(self) -> bool:
        return self._blocked

    @property
    def substep_s(self) -> float:
        """The sub-step in use (params.substep_s unless stability needed less)."""
        return self._h_ns * 1e-9

    def state(self) -> dict[str, float]:
        """A snapshot of every signal, for recording."""
        return {
            "t_s": self.time_s,
            "x_cm": self.x_cm,
            "v_cm_s": self.v_cm_s,
            "x_sensor_cm": self.x_sensor_cm,
            "p_kpa": self.p_kpa,
            "p_cmd_kpa": self.p_cmd_kpa,
            "p_set_kpa": self.p_set_kpa,
            "load_mass_kg": self._mass,
            "disturbance_n": self.disturbance_force_n,
            "hysteresis_n": self.hysteresis_force_n,
            "temperature_rise_k": self.temperature_rise_k,
            "wire_broken": float(self._wire_broken),
            "sensor_blocked": float(self._blocked),
        }
