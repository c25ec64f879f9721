# SPDX-License-Identifier: Apache-2.0
"""Independent double-precision reference of the PMA control algorithms.

This module restates, in plain numpy/double arithmetic, the equations that the
firmware implements in C (``firmware/control``) in float (``_f32``) and
Q16.16 fixed point (``_q16``). It is written from the public headers
(``firmware/control/include/pma/*.h``), the controller specification
(``/work/shared/spec/controller.md``, eq. 15-22 and CFDL-MFAC) and the precise
semantics given to the golden-vector tier; it deliberately does not follow the
structure of the C code. ``gen_vectors.py`` runs it on quantised inputs to
produce the golden vectors in ``vectors/*.h``.

Every class mirrors the C life cycle: construct (= init, validates the
configuration), :meth:`reset`, and one ``step`` (or ``eval``) per sample.
Outputs are returned as small frozen dataclasses. Besides the fields the C
code reports, some outputs carry diagnostics (e.g. the unclamped value behind
a saturation decision) that the generator uses to keep the vectors away from
decision thresholds.

Configuration values are used exactly as passed; the generator passes the
float32-rounded values the C code receives. ``Mfac(cfg, float32=True)`` rounds each
operation to single precision instead (closed-loop predictions of the float firmware).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = [
    "PPC_FLAG_BARRIER1", "PPC_FLAG_BARRIER2", "PPC_FLAG_SAT_HIGH", "PPC_FLAG_SAT_LOW",
    "PPC_FLAG_SOFT1", "PPC_FLAG_SOFT2", "PPC_FLAG_WIDEN1", "PPC_FLAG_WIDEN2", "PPC_FLAG_WIDE",
    "PPC_FLAG_FF_HOLD",
    "MFAC_FLAG_RESET", "MFAC_FLAG_SAT_HIGH", "MFAC_FLAG_SAT_LOW",
    "PID_FLAG_SAT_HIGH", "PID_FLAG_SAT_LOW",
    "VELEST_FILTERED_DIFF", "VELEST_TRACKING",
    "REF_HOLD", "REF_STEP", "REF_RAMP", "REF_SINE", "REF_CASE1", "REF_CASE3", "REF_STREAM",
    "PpcConfig", "PpcOutput", "Ppc", "ppc_alpha", "TanTransform",
    "MfacConfig", "MfacOutput", "Mfac",
    "PidConfig", "PidOutput", "Pid",
    "VelestConfig", "Velest",
    "RefConfig", "Ref", "case1_ref", "case3_ref",
    "quantise_q16", "f32",
]

# ---------------------------------------------------------------------------------------------
# Flags and enumerations: values of the C headers.
PPC_FLAG_BARRIER1 = 0x01
PPC_FLAG_BARRIER2 = 0x02
PPC_FLAG_SAT_HIGH = 0x04
PPC_FLAG_SAT_LOW = 0x08
PPC_FLAG_SOFT1 = 0x10
PPC_FLAG_SOFT2 = 0x20
PPC_FLAG_WIDEN1 = 0x40
PPC_FLAG_WIDEN2 = 0x80
PPC_FLAG_WIDE = 0x100
PPC_FLAG_FF_HOLD = 0x200
WIDEN_G_MIN = 2.0 ** -20    # the widened funnel's scale is kept at or above this

MFAC_FLAG_RESET = 0x01
MFAC_FLAG_SAT_HIGH = 0x04
MFAC_FLAG_SAT_LOW = 0x08

PID_FLAG_SAT_HIGH = 0x04
PID_FLAG_SAT_LOW = 0x08

VELEST_FILTERED_DIFF = 0
VELEST_TRACKING = 1

REF_HOLD = 0
REF_STEP = 1
REF_RAMP = 2
REF_SINE = 3
REF_CASE1 = 4
REF_CASE3 = 5
REF_STREAM = 6

Q16_SCALE = 65536.0


def quantise_q16(x: float) -> float:
    """Round ``x`` to the nearest multiple of 2^-16 (exact in float and in Q16.16)."""
    return float(np.round(float(x) * Q16_SCALE) / Q16_SCALE)


def f32(x: float) -> float:
    """The float32 value nearest to ``x``, as a Python float."""
    return float(np.float32(x))


def _clamp(x: float, lo: float, hi: float) -> float:
    return lo if x < lo else hi if x > hi else x


def _f32(x: float) -> float:
    """x rounded to the nearest float32 (as a Python float)."""
    return float(np.float32(x))


def _finite(*values: float) -> bool:
    return all(math.isfinite(v) for v in values)


# ---------------------------------------------------------------------------------------------
# The paper's controller (eq. 15-22) with barrier clamp, soft barrier, feedforward, an added
# input u_ext and funnel widening.

@dataclass(frozen=True)
class PpcConfig:
    """Mirror of ``pma_ppc_config_t`` (units as in ppc.h)."""

    a_cm_s: float
    c: float
    w1_cm: float
    w2_cm_s: float
    t_u_s: float
    u_min: float
    u_max: float
    barrier_margin: float = 1e-3
    soft_barrier_r: float = 1.0
    ff_gain_per_s: float = 0.0
    ff_init: float = 0.0
    ff_hold_speed_cm_s: float = 0.0   # the integrator holds while the muscle closes faster (0: off)
    period_s: float = 1e-3
    band_enabled: int = 0
    k_low_cm: float = -3.0
    k_high_cm: float = 0.0
    widen_r: float = 0.0        # 0: off (the paper's clamp); else |r| after a widening
    widen2_steps: int = 0       # lambda2's funnel widens after this many clamped steps (0: never)

    def validate(self) -> None:
        """Raise ValueError on a configuration ppc.h declares invalid."""
        if not _finite(self.a_cm_s, self.c, self.w1_cm, self.w2_cm_s, self.t_u_s, self.u_min,
                       self.u_max, self.barrier_margin, self.soft_barrier_r,
                       self.ff_gain_per_s, self.ff_init, self.ff_hold_speed_cm_s, self.period_s):
            raise ValueError("non-finite ppc configuration")
        if min(self.a_cm_s, self.c, self.w1_cm, self.w2_cm_s, self.t_u_s, self.period_s) <= 0:
            raise ValueError("a, c, w1, w2, t_u and period must be > 0")
        if not self.u_min < self.u_max:
            raise ValueError("u_min < u_max required")
        if not 0.0 < self.barrier_margin <= 0.5:
            raise ValueError("barrier_margin must be in (0, 0.5]")
        if not 0.0 < self.soft_barrier_r <= 1.0:
            raise ValueError("soft_barrier_r must be in (0, 1]")
        if self.ff_gain_per_s < 0 or self.ff_hold_speed_cm_s < 0:
            raise ValueError("ff_gain_per_s and ff_hold_speed_cm_s must be >= 0")
        if not self.u_min <= self.ff_init <= self.u_max:
            raise ValueError("ff_init must be within [u_min, u_max]")
        if not _finite(self.widen_r) or not (self.widen_r == 0.0 or
                                             0.05 <= self.widen_r < 1.0 - self.barrier_margin):
            raise ValueError("widen_r must be 0 or in [0.05, 1 - barrier_margin)")
        if self.widen2_steps < 0:
            raise ValueError("widen2_steps must be >= 0")
        if self.band_enabled:
            if not self.k_low_cm < self.k_high_cm:
                raise ValueError("k_low < k_high required")
            if not self.k_high_cm - self.k_low_cm > 2.0 * self.w1_cm:
                raise ValueError("constraint band narrower than 2 w1 (eq. 14)")


@dataclass(frozen=True)
class PpcOutput:
    """One step of the paper's controller: the fields of ``pma_ppc_out_f32_t``.

    ``u_ff`` is the feedforward used in this step (before its update). ``g1``, ``g2`` are
    the funnels' scales (1: as assigned; w_i / g_i is the funnel of the step).
    ``r1``, ``r2`` (normalised arguments lambda_i g_i / w_i before the barrier clamp),
    ``raw1``, ``raw2`` (lambda_i / w_i, the funnels as assigned), ``u_unclamped``
    (u_ff + u_law + u_ext), ``dt1``, ``dt2`` (time since the channel's last widening, or
    None) and ``pre1``, ``pre2`` (|r_i| in the funnel of the step before it widens: what the
    widening decision compares with r_max) are diagnostics, not part of the C output.
    """

    alpha: float
    e_cm: float
    lambda1_cm: float
    chi: float
    theta_cm_s: float
    lambda2_cm_s: float
    delta: float
    beta_s_cm: float
    u_law: float
    u_ff: float
    u: float
    flags: int
    r1: float
    r2: float
    u_unclamped: float
    g1: float = 1.0
    g2: float = 1.0
    raw1: float = 0.0
    raw2: float = 0.0
    dt1: float | None = None
    dt2: float | None = None
    pre1: float = 0.0
    pre2: float = 0.0


def ppc_alpha(t_s: float, t_u_s: float) -> float:
    """Tuning function (15): 0.5 - 0.5 cos(pi t / t_u) for t < t_u, 1 afterwards."""
    if t_s < t_u_s:
        return 0.5 - 0.5 * math.cos(math.pi * t_s / t_u_s)
    return 1.0


class TanTransform:
    """The error transformation r -> tan(pi r / 2) with barrier clamp and soft barrier.

    ``apply(r)`` returns (tanx, sec2x, clamped, soft):
      * |r| >= r_max: r is clamped to +-r_max (clamped = True);
      * then, with the soft barrier on (soft_r < 1) and |r| > soft_r, the tangent-line
        continuation tanx = sign(r) (T_s + (pi/2) S_s (|r| - soft_r)), sec2x = S_s with
        T_s = tan(pi soft_r / 2), S_s = 1 + T_s^2 (soft = True);
      * otherwise tanx = tan(pi r / 2), sec2x = 1 + tanx^2.
    """

    def __init__(self, r_max: float, soft_r: float) -> None:
        self.r_max = r_max
        self.soft_r = soft_r
        self.soft_on = soft_r < 1.0
        if self.soft_on:
            self.soft_tan = math.tan(0.5 * math.pi * soft_r)
            self.soft_sec2 = 1.0 + self.soft_tan * self.soft_tan
        else:
            self.soft_tan = math.inf
            self.soft_sec2 = math.inf

    def apply(self, r: float) -> tuple[float, float, bool, bool]:
        clamped = abs(r) >= self.r_max
        if clamped:
            r = math.copysign(self.r_max, r)
        if self.soft_on and abs(r) > self.soft_r:
            tanx = math.copysign(
                self.soft_tan + 0.5 * math.pi * self.soft_sec2 * (abs(r) - self.soft_r), r)
            return tanx, self.soft_sec2, clamped, True
        tanx = math.tan(0.5 * math.pi * r)
        return tanx, 1.0 + tanx * tanx, clamped, False


class Ppc:
    """The paper's controller (prescribed performance control, eq. 15-22).

    State: the feedforward u_ff (starts at ff_init); with funnel widening (widen_r > 0) each
    channel's last widening (its scale and time) and lambda2's run of clamped steps.

    Funnel widening, as ppc.h states it: where |lambda_i / w_i| (in the funnel of the step)
    reaches the clamp r_max, channel i's funnel widens instead (lambda1's at once, lambda2's
    on the widen2_steps-th step of a run at the clamp; widen2_steps 0: never): its scale g_i
    is multiplied by widen_r / |r_i| (at least WIDEN_G_MIN), so that |r_i| = widen_r, flag
    WIDEN1/2. Afterwards g_i(t) = 1 - (1 - k_i)(1 - alpha(t - t_i)) with alpha the tuning
    function (eq. 15) and k_i, t_i the scale and time of the last widening; t_u after it the
    funnel is as assigned. r_i = lambda_i g_i / w_i; beta = sec^2(delta) g2 / w2; flag WIDE
    while a g_i < 1.
    """

    def __init__(self, cfg: PpcConfig) -> None:
        cfg.validate()
        self.cfg = cfg
        self.transform = TanTransform(1.0 - cfg.barrier_margin, cfg.soft_barrier_r)
        self.reset()

    def reset(self) -> None:
        """Feedforward back to ff_init, counters cleared, funnels as assigned."""
        self.u_ff = self.cfg.ff_init
        self.breaches1 = 0
        self.breaches2 = 0
        self.widened: list[tuple[float, float] | None] = [None, None]   # (k_i, t_i) while wide
        self.clamp_run2 = 0

    def _funnel(self, i: int, t_s: float, raw: float) -> tuple[float, float, int, float | None, float]:
        """(r_i, g_i, flags, t - t_i, |r_i| before a widening) of channel i from
        raw = lambda_i / w_i."""
        cfg = self.cfg
        flags = 0
        g, dt = 1.0, None
        last = self.widened[i]
        if last is not None:
            k, t_i = last
            dt = t_s - t_i
            if dt >= cfg.t_u_s:
                self.widened[i] = None
            else:
                g = 1.0 - (1.0 - k) * (1.0 - ppc_alpha(max(dt, 0.0), cfg.t_u_s))
        widens_at_all = cfg.widen_r > 0.0 and (i == 0 or cfg.widen2_steps > 0)
        pre = abs(raw * g)
        at_clamp = widens_at_all and pre >= self.transform.r_max
        if i == 1:
            self.clamp_run2 = self.clamp_run2 + 1 if at_clamp else 0
        if at_clamp and (i == 0 or self.clamp_run2 >= cfg.widen2_steps):
            if i == 1:
                self.clamp_run2 = 0
            g = max(g * cfg.widen_r / pre, WIDEN_G_MIN)
            self.widened[i] = (g, t_s)
            flags |= PPC_FLAG_WIDEN1 if i == 0 else PPC_FLAG_WIDEN2
            dt = 0.0
        if g < 1.0:
            flags |= PPC_FLAG_WIDE
        return raw * g, g, flags, dt, pre

    def step(self, t_s: float, x_cm: float, v_cm_s: float, xr_cm: float,
             u_ext: float = 0.0) -> PpcOutput:
        """One control step at time t_s (since task start) with position, velocity, reference,
        and the input u_ext added to the law's output before the clamp."""
        if not _finite(t_s, x_cm, v_cm_s, xr_cm, u_ext):
            raise ValueError("non-finite input")
        cfg = self.cfg
        alpha = ppc_alpha(t_s, cfg.t_u_s)
        e = x_cm - xr_cm
        lambda1 = alpha * e
        raw1 = lambda1 / cfg.w1_cm
        r1, g1, flags1, dt1, pre1 = self._funnel(0, t_s, raw1)
        chi, _, clamped1, soft1 = self.transform.apply(r1)
        theta = -cfg.a_cm_s * chi
        lambda2 = alpha * v_cm_s - theta
        raw2 = lambda2 / cfg.w2_cm_s
        r2, g2, flags2, dt2, pre2 = self._funnel(1, t_s, raw2)
        flags = flags1 | flags2
        delta, sec2_2, clamped2, soft2 = self.transform.apply(r2)
        beta = sec2_2 * g2 / cfg.w2_cm_s
        u_law = -cfg.c * beta * delta
        if clamped1:
            flags |= PPC_FLAG_BARRIER1
            self.breaches1 += 1
        if clamped2:
            flags |= PPC_FLAG_BARRIER2
            self.breaches2 += 1
        if soft1:
            flags |= PPC_FLAG_SOFT1
        if soft2:
            flags |= PPC_FLAG_SOFT2
        u_ff = self.u_ff
        u_unclamped = u_ff + u_law + u_ext
        if u_unclamped > cfg.u_max:
            flags |= PPC_FLAG_SAT_HIGH
        if u_unclamped < cfg.u_min:
            flags |= PPC_FLAG_SAT_LOW
        u = _clamp(u_unclamped, cfg.u_min, cfg.u_max)
        if cfg.ff_gain_per_s > 0.0:
            hv = cfg.ff_hold_speed_cm_s   # the muscle closes on the reference faster than hv
            if hv > 0.0 and ((e > 0.0 and v_cm_s < -hv) or (e < 0.0 and v_cm_s > hv)):
                flags |= PPC_FLAG_FF_HOLD
            hold = (flags & PPC_FLAG_FF_HOLD) or ((flags & PPC_FLAG_SAT_HIGH) and u_law > 0.0) or \
                   ((flags & PPC_FLAG_SAT_LOW) and u_law < 0.0)
            if not hold:   # bounded so that u_ff + u_ext stays within the input range
                self.u_ff = _clamp(u_ff + cfg.ff_gain_per_s * cfg.period_s * u_law,
                                   cfg.u_min - u_ext, cfg.u_max - u_ext)
        return PpcOutput(alpha=alpha, e_cm=e, lambda1_cm=lambda1, chi=chi, theta_cm_s=theta,
                         lambda2_cm_s=lambda2, delta=delta, beta_s_cm=beta, u_law=u_law,
                         u_ff=u_ff, u=u, flags=flags, r1=r1, r2=r2, u_unclamped=u_unclamped,
                         g1=g1, g2=g2, raw1=raw1, raw2=raw2, dt1=dt1, dt2=dt2, pre1=pre1,
                         pre2=pre2)


# ---------------------------------------------------------------------------------------------
# CFDL-MFAC (Hou and Jin), the paper's baseline.

@dataclass(frozen=True)
class MfacConfig:
    """Mirror of ``pma_mfac_config_t``."""

    eta: float = 0.5
    mu: float = 1.9
    rho: float = 31.7
    lam: float = 0.03
    eps: float = 1e-5
    phi1: float = 0.5
    u_min: float = -400.0
    u_max: float = 400.0
    u_init: float = 0.0

    def validate(self) -> None:
        """Raise ValueError on a configuration mfac.h declares invalid."""
        if not _finite(self.eta, self.mu, self.rho, self.lam, self.eps, self.phi1,
                       self.u_min, self.u_max, self.u_init):
            raise ValueError("non-finite mfac configuration")
        if not 0.0 < self.eta <= 2.0:
            raise ValueError("eta must be in (0, 2]")
        if self.mu <= 0 or self.rho <= 0 or self.lam <= 0 or self.eps < 0:
            raise ValueError("mu, rho, lambda > 0 and eps >= 0 required")
        if not abs(self.phi1) > self.eps:
            raise ValueError("|phi1| > eps required")
        if not self.u_min < self.u_max or not self.u_min <= self.u_init <= self.u_max:
            raise ValueError("u_min < u_max and u_init within the limits required")


@dataclass(frozen=True)
class MfacOutput:
    """phi(k), u(k) and flags; du, phi_candidate (before the reset rule) and u_unclamped
    are diagnostics."""

    phi: float
    u: float
    flags: int
    du: float
    phi_candidate: float
    u_unclamped: float


class Mfac:
    """CFDL-MFAC. Start: y(-1) = y(0), u(-1) = u(-2) = u_init, phi(0) = phi1.

    float32=True rounds every operation to single precision in the order
    pma_mfac_step_f32 evaluates it (for closed-loop predictions of the float firmware;
    the golden vectors use the default double precision). In closed loop the two differ
    more than rounding suggests: near a steady state an increment of u below half an
    ulp of u (6e-5 kPa at u = 530 kPa) is lost in float, du is then exactly 0 and the
    reset rule (|du| <= eps) sets phi back to phi1, where double keeps adapting phi."""

    def __init__(self, cfg: MfacConfig, float32: bool = False) -> None:
        cfg.validate()
        self.cfg = cfg
        self.float32 = float32
        self._round = _f32 if float32 else float     # the rounding of each operation
        self.reset()

    def reset(self) -> None:
        """Back to the start conditions."""
        r = self._round
        self.phi = r(self.cfg.phi1)
        self.u1 = r(self.cfg.u_init)
        self.u2 = r(self.cfg.u_init)
        self.y1 = 0.0
        self.k = 0
        self.resets = 0

    def step(self, y_cm: float, yref_next_cm: float) -> MfacOutput:
        """y_cm = y(k), yref_next_cm = y*(k+1); returns u(k) (clamped) and phi(k)."""
        if not _finite(y_cm, yref_next_cm):
            raise ValueError("non-finite input")
        cfg = self.cfg
        r = self._round
        y_cm, yref_next_cm = r(y_cm), r(yref_next_cm)
        if self.k == 0:
            self.y1 = y_cm
        du = r(self.u1 - self.u2)
        dy = r(y_cm - self.y1)
        g_phi = r(r(r(cfg.eta) * du) / r(r(cfg.mu) + r(du * du)))
        phi_c = r(self.phi + r(g_phi * r(dy - r(self.phi * du))))
        flags = 0
        eps = r(cfg.eps)
        reset = (abs(phi_c) <= eps or abs(du) <= eps
                 or np.sign(phi_c) != np.sign(cfg.phi1))
        phi = r(cfg.phi1) if reset else phi_c
        if reset:
            flags |= MFAC_FLAG_RESET
            self.resets += 1
        g_u = r(r(r(cfg.rho) * phi) / r(r(cfg.lam) + r(phi * phi)))
        u_raw = r(self.u1 + r(g_u * r(yref_next_cm - y_cm)))
        if u_raw > cfg.u_max:
            flags |= MFAC_FLAG_SAT_HIGH
        if u_raw < cfg.u_min:
            flags |= MFAC_FLAG_SAT_LOW
        u = r(_clamp(u_raw, cfg.u_min, cfg.u_max))
        self.u2 = self.u1
        self.u1 = u
        self.y1 = y_cm
        self.phi = phi
        self.k += 1
        return MfacOutput(phi=phi, u=u, flags=flags, du=du, phi_candidate=phi_c,
                          u_unclamped=u_raw)


# ---------------------------------------------------------------------------------------------
# PID baseline.

@dataclass(frozen=True)
class PidConfig:
    """Mirror of ``pma_pid_config_t``."""

    kp: float
    ki: float
    kd: float
    tf_s: float
    k_aw_per_s: float
    period_s: float
    u_min: float
    u_max: float

    def validate(self) -> None:
        """Raise ValueError on a configuration pid.h declares invalid."""
        if not _finite(self.kp, self.ki, self.kd, self.tf_s, self.k_aw_per_s, self.period_s,
                       self.u_min, self.u_max):
            raise ValueError("non-finite pid configuration")
        if min(self.kp, self.ki, self.kd, self.tf_s, self.k_aw_per_s) < 0:
            raise ValueError("gains and tf must be >= 0")
        if self.period_s <= 0 or not self.u_min < self.u_max:
            raise ValueError("period > 0 and u_min < u_max required")


@dataclass(frozen=True)
class PidOutput:
    """u (clamped) and flags; v (unclamped) and the three terms are diagnostics."""

    u: float
    flags: int
    v: float
    p: float
    i: float
    d: float


class Pid:
    """Parallel PID on e = r - y, filtered derivative on the measurement, back-calculation
    anti-windup, integrator clamped to the output limits. First step: y(k-1) = y(0)."""

    def __init__(self, cfg: PidConfig) -> None:
        cfg.validate()
        self.cfg = cfg
        self.d_a = cfg.tf_s / (cfg.tf_s + cfg.period_s)
        self.d_b = cfg.kd / (cfg.tf_s + cfg.period_s)
        self.reset()

    def reset(self) -> None:
        """Integrator and derivative to 0, history forgotten."""
        self.i = 0.0
        self.d = 0.0
        self.y1 = 0.0
        self.primed = False

    def step(self, r_cm: float, y_cm: float) -> PidOutput:
        """One step with reference r and measurement y."""
        if not _finite(r_cm, y_cm):
            raise ValueError("non-finite input")
        cfg = self.cfg
        if not self.primed:
            self.y1 = y_cm
            self.primed = True
        e = r_cm - y_cm
        p = cfg.kp * e
        self.d = self.d_a * self.d - self.d_b * (y_cm - self.y1)
        i_used = self.i
        v = p + i_used + self.d
        flags = 0
        if v > cfg.u_max:
            flags |= PID_FLAG_SAT_HIGH
        if v < cfg.u_min:
            flags |= PID_FLAG_SAT_LOW
        u = _clamp(v, cfg.u_min, cfg.u_max)
        self.i = _clamp(self.i + cfg.period_s * (cfg.ki * e + cfg.k_aw_per_s * (u - v)),
                        cfg.u_min, cfg.u_max)
        self.y1 = y_cm
        return PidOutput(u=u, flags=flags, v=v, p=p, i=i_used, d=self.d)


# ---------------------------------------------------------------------------------------------
# Velocity estimators.

@dataclass(frozen=True)
class VelestConfig:
    """Mirror of ``pma_velest_config_t``."""

    kind: int
    fc_hz: float
    period_s: float

    def validate(self) -> None:
        """Raise ValueError on a configuration velest.h declares invalid."""
        if self.kind not in (VELEST_FILTERED_DIFF, VELEST_TRACKING):
            raise ValueError("unknown estimator kind")
        if not _finite(self.fc_hz, self.period_s) or self.period_s <= 0:
            raise ValueError("period > 0 required")
        if not 0.0 < self.fc_hz < 0.5 / self.period_s:
            raise ValueError("0 < fc < 1/(2 T) required")


class Velest:
    """Filtered backward difference or critically damped alpha-beta tracking observer.

    The first sample primes the estimator: x1 = xh = x, v = 0, output 0."""

    def __init__(self, cfg: VelestConfig) -> None:
        cfg.validate()
        self.cfg = cfg
        self.p = math.exp(-2.0 * math.pi * cfg.fc_hz * cfg.period_s)
        self.reset()

    def reset(self) -> None:
        """Forget the history (the next sample primes)."""
        self.x1 = 0.0
        self.xh = 0.0
        self.v = 0.0
        self.primed = False

    def noise_gain(self) -> float:
        """Steady-state std of v per unit std of white position noise (filtered difference
        only: sigma (1-p)/T sqrt(2/(1+p)), as velest.h states)."""
        if self.cfg.kind != VELEST_FILTERED_DIFF:
            raise NotImplementedError("closed form given for the filtered difference only")
        p, t = self.p, self.cfg.period_s
        return (1.0 - p) / t * math.sqrt(2.0 / (1.0 + p))

    def step(self, x_cm: float) -> float:
        """One position sample; returns the velocity estimate [cm/s]."""
        if not math.isfinite(x_cm):
            raise ValueError("non-finite input")
        t = self.cfg.period_s
        p = self.p
        if not self.primed:
            self.x1 = x_cm
            self.xh = x_cm
            self.v = 0.0
            self.primed = True
            return 0.0
        if self.cfg.kind == VELEST_FILTERED_DIFF:
            self.v = p * self.v + (1.0 - p) / t * (x_cm - self.x1)
            self.x1 = x_cm
        else:
            ga = 1.0 - p * p
            gb = (1.0 - p) ** 2
            xp = self.xh + t * self.v
            res = x_cm - xp
            self.xh = xp + ga * res
            self.v = self.v + gb / t * res
            self.x1 = x_cm
        return self.v


# ---------------------------------------------------------------------------------------------
# Reference generators.

def case1_ref(t_s: float) -> tuple[float, float]:
    """The paper's Cases 1 and 2: x_r = -0.5 sin(t) - 2 and its derivative."""
    return -0.5 * math.sin(t_s) - 2.0, -0.5 * math.cos(t_s)


def case3_ref(t_s: float) -> tuple[float, float]:
    """The paper's Case 3 chirp x_r = t sin(phi)/360 - 2, phi = 2 pi t (1 + t/55)/55 - pi/2,
    and its derivative sin(phi)/360 + t cos(phi) phi'/360, phi' = 2 pi (1 + 2t/55)/55."""
    phi = 2.0 * math.pi * t_s * (1.0 + t_s / 55.0) / 55.0 - 0.5 * math.pi
    dphi = 2.0 * math.pi * (1.0 + 2.0 * t_s / 55.0) / 55.0
    x = t_s * math.sin(phi) / 360.0 - 2.0
    xdot = math.sin(phi) / 360.0 + t_s * math.cos(phi) * dphi / 360.0
    return x, xdot


@dataclass(frozen=True)
class RefConfig:
    """Mirror of ``pma_ref_config_t``."""

    kind: int
    offset_cm: float = 0.0
    amplitude_cm: float = 0.0
    freq_hz: float = 0.0
    phase_rad: float = 0.0
    t0_s: float = 0.0
    rate_cm_s: float = 0.0

    def validate(self) -> None:
        """Raise ValueError on a configuration ref.h declares invalid."""
        if self.kind not in (REF_HOLD, REF_STEP, REF_RAMP, REF_SINE, REF_CASE1, REF_CASE3,
                             REF_STREAM):
            raise ValueError("unknown reference kind")
        if not _finite(self.offset_cm, self.amplitude_cm, self.freq_hz, self.phase_rad,
                       self.t0_s, self.rate_cm_s):
            raise ValueError("non-finite reference configuration")
        if self.freq_hz < 0 or self.t0_s < 0:
            raise ValueError("freq >= 0 and t0 >= 0 required")
        if self.kind == REF_STREAM and self.rate_cm_s < 0:
            raise ValueError("STREAM rate >= 0 required")


class Ref:
    """Reference generator x_r(t) with derivative; STREAM follows streamed targets."""

    def __init__(self, cfg: RefConfig) -> None:
        cfg.validate()
        self.cfg = cfg
        self.reset()

    def reset(self) -> None:
        """STREAM: target and value back to offset, last_t = 0."""
        self.stream_target = self.cfg.offset_cm
        self.stream_value = self.cfg.offset_cm
        self.last_t = 0.0

    def stream(self, target_cm: float) -> None:
        """STREAM only: set a new target."""
        if self.cfg.kind != REF_STREAM:
            raise ValueError("stream targets are for STREAM references only")
        if not math.isfinite(target_cm):
            raise ValueError("non-finite target")
        self.stream_target = target_cm

    def eval(self, t_s: float) -> tuple[float, float]:
        """x_r(t) [cm] and x_r'(t) [cm/s]."""
        cfg = self.cfg
        kind = cfg.kind
        if kind == REF_HOLD:
            return cfg.offset_cm, 0.0
        if kind == REF_STEP:
            return (cfg.offset_cm if t_s < cfg.t0_s else cfg.offset_cm + cfg.amplitude_cm), 0.0
        if kind == REF_RAMP:
            if t_s < cfg.t0_s:
                return cfg.offset_cm, 0.0
            raw = cfg.offset_cm + cfg.rate_cm_s * (t_s - cfg.t0_s)
            lo = cfg.offset_cm - abs(cfg.amplitude_cm)
            hi = cfg.offset_cm + abs(cfg.amplitude_cm)
            if raw > hi:
                return hi, 0.0
            if raw < lo:
                return lo, 0.0
            return raw, cfg.rate_cm_s
        if kind == REF_SINE:
            arg = 2.0 * math.pi * cfg.freq_hz * t_s + cfg.phase_rad
            return (cfg.offset_cm + cfg.amplitude_cm * math.sin(arg),
                    cfg.amplitude_cm * 2.0 * math.pi * cfg.freq_hz * math.cos(arg))
        if kind == REF_CASE1:
            return case1_ref(t_s)
        if kind == REF_CASE3:
            return case3_ref(t_s)
        # STREAM
        dt = max(t_s - self.last_t, 0.0)
        old = self.stream_value
        if cfg.rate_cm_s == 0.0:
            new = self.stream_target
        else:
            step = cfg.rate_cm_s * dt
            gap = self.stream_target - old
            new = self.stream_target if abs(gap) <= step else old + math.copysign(step, gap)
        self.stream_value = new
        self.last_t = t_s
        return new, ((new - old) / dt if dt > 0.0 else 0.0)

    def stream_gap(self, t_s: float) -> tuple[float, float]:
        """Diagnostic for the generator: (|target - value|, rate dt) that the next eval at t_s
        compares (does not change the state)."""
        dt = max(t_s - self.last_t, 0.0)
        return abs(self.stream_target - self.stream_value), self.cfg.rate_cm_s * dt
