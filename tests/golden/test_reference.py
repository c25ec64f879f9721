# SPDX-License-Identifier: Apache-2.0
"""Property tests of the double-precision reference (pma_reference.py) and of the generator.

Run: python3 -m pytest tests/golden/test_reference.py
These check the reference against the specification's properties (not against the C code):
bumpless start, tuning-function profile, tan/sec identities and the barrier/soft-barrier
continuation, feedforward anti-windup, MFAC reset rules, PID, velocity estimators on ramps
and noise, reference generators against finite differences; then that the committed golden
vectors are exactly what the generator produces (--check), that --check notices a change,
and that every input is a multiple of 2^-16.
"""
from __future__ import annotations

import math
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from pma_golden import gen_vectors
from pma_golden import pma_reference as ref

HERE = Path(__file__).resolve().parent

CASE3 = ref.PpcConfig(a_cm_s=2.0, c=2.0, w1_cm=0.2, w2_cm_s=0.5, t_u_s=2.0,
                      u_min=-400.0, u_max=400.0)


# --------------------------------------------------------------------------------------------
# the paper's controller

@pytest.mark.parametrize("w1,t_u", [(0.5, 6.0), (0.3, 2.0), (0.2, 2.0)])
def test_ppc_u_is_zero_at_t0_whatever_the_error(w1: float, t_u: float) -> None:
    rng = np.random.default_rng(1)
    for _ in range(50):
        p = ref.Ppc(ref.PpcConfig(a_cm_s=2.0, c=2.0, w1_cm=w1, w2_cm_s=0.5, t_u_s=t_u,
                                  u_min=-400.0, u_max=400.0))
        o = p.step(0.0, rng.uniform(-10, 10), rng.uniform(-50, 50), rng.uniform(-3, 0))
        assert o.alpha == 0.0 and o.lambda1_cm == 0.0 and o.lambda2_cm_s == 0.0
        assert o.u == 0.0 and o.u_law == 0.0 and o.flags == 0


def test_ppc_u_at_t0_is_the_feedforward() -> None:
    cfg = ref.PpcConfig(**{**CASE3.__dict__, "ff_gain_per_s": 4.0, "ff_init": 123.0})
    o = ref.Ppc(cfg).step(0.0, 5.0, 3.0, -2.0)
    assert o.u == 123.0 and o.u_ff == 123.0


def test_alpha_profile() -> None:
    t_u = 6.0
    ts = np.linspace(0.0, 2 * t_u, 2001)
    a = np.array([ref.ppc_alpha(t, t_u) for t in ts])
    assert a[0] == 0.0
    assert ref.ppc_alpha(t_u / 2, t_u) == pytest.approx(0.5, abs=1e-15)
    assert ref.ppc_alpha(t_u, t_u) == 1.0
    assert np.all(np.diff(a) >= 0.0)                  # monotone
    assert np.all(a[ts >= t_u] == 1.0)
    # C1 at both ends: slope 0 at t = 0 and at t_u
    h = 1e-6
    assert ref.ppc_alpha(h, t_u) / h == pytest.approx(0.0, abs=1e-5)
    assert (1.0 - ref.ppc_alpha(t_u - h, t_u)) / h == pytest.approx(0.0, abs=1e-5)
    # the analytic form
    for t in (0.3, 1.7, 4.2):
        assert ref.ppc_alpha(t, t_u) == pytest.approx(0.5 - 0.5 * math.cos(math.pi * t / t_u))


def test_tan_sec_identity_and_barrier_clamp() -> None:
    tr = ref.TanTransform(r_max=0.999, soft_r=1.0)
    for r in np.linspace(-0.998, 0.998, 401):
        t, s2, clamped, soft = tr.apply(float(r))
        assert not clamped and not soft
        assert t == pytest.approx(math.tan(0.5 * math.pi * r), rel=1e-14, abs=1e-15)
        assert s2 == pytest.approx(1.0 / math.cos(0.5 * math.pi * r) ** 2, rel=1e-12)
    for r in (0.999, 1.0, 1.5, 40.0):
        for sgn in (1.0, -1.0):
            t, s2, clamped, _ = tr.apply(sgn * r)
            assert clamped
            assert t == pytest.approx(sgn * math.tan(0.5 * math.pi * 0.999), rel=1e-14)
            assert s2 == pytest.approx(1.0 + t * t, rel=1e-14)


def test_soft_barrier_is_the_tangent_line() -> None:
    tr = ref.TanTransform(r_max=0.999, soft_r=0.9)
    ts = math.tan(0.45 * math.pi)
    ss = 1.0 + ts * ts
    # continuous in value and slope at the soft point
    below = tr.apply(0.9)[0]
    above = tr.apply(0.9 + 1e-9)[0]
    assert below == pytest.approx(ts, rel=1e-12)
    assert above == pytest.approx(ts, rel=1e-6)
    slope_in = (tr.apply(0.9)[0] - tr.apply(0.9 - 1e-7)[0]) / 1e-7
    slope_out = (tr.apply(0.95)[0] - tr.apply(0.94)[0]) / 0.01
    assert slope_in == pytest.approx(0.5 * math.pi * ss, rel=1e-5)
    assert slope_out == pytest.approx(0.5 * math.pi * ss, rel=1e-12)
    for r in (0.91, 0.99, 0.999, 3.0):
        for sgn in (1.0, -1.0):
            t, s2, clamped, soft = tr.apply(sgn * r)
            assert soft and s2 == ss and clamped == (r >= 0.999)
            rr = min(r, 0.999)
            assert t == pytest.approx(sgn * (ts + 0.5 * math.pi * ss * (rr - 0.9)), rel=1e-14)


def test_ppc_linear_gain_and_odd_symmetry() -> None:
    p = ref.Ppc(CASE3)
    e = 1e-6
    o = p.step(10.0, -2.0 + e, 0.0, -2.0)
    gain = (2.0 * math.pi / (2 * 0.2)) * (2.0 * math.pi / (2 * 0.5 ** 2))   # about 197
    assert -o.u / e == pytest.approx(gain, rel=1e-5)
    rng = np.random.default_rng(3)
    for _ in range(100):
        t, e, v = rng.uniform(0, 5), rng.uniform(-0.3, 0.3), rng.uniform(-2, 2)
        a = ref.Ppc(CASE3).step(t, -2.0 + e, v, -2.0)
        b = ref.Ppc(CASE3).step(t, -2.0 - e, -v, -2.0)
        assert a.u == pytest.approx(-b.u, rel=1e-12, abs=1e-12)
        sat = ref.PPC_FLAG_SAT_HIGH | ref.PPC_FLAG_SAT_LOW
        swapped = (b.flags & ~sat) | (sat if b.flags & sat else 0) & ~(b.flags & sat)
        assert a.flags == swapped


def test_ppc_saturation_flags() -> None:
    p = ref.Ppc(CASE3)
    o = p.step(5.0, -2.0, 0.5 * 0.95, -2.0)       # r2 = 0.95: u_law about -8200
    assert o.u == -400.0 and o.flags == ref.PPC_FLAG_SAT_LOW
    o = p.step(5.0, -2.0, -0.5 * 0.95, -2.0)
    assert o.u == 400.0 and o.flags == ref.PPC_FLAG_SAT_HIGH
    o = p.step(5.0, -1.0, 0.0, -2.0)               # r1 = 5: beyond
    assert o.flags == (ref.PPC_FLAG_BARRIER1 | ref.PPC_FLAG_BARRIER2 | ref.PPC_FLAG_SAT_LOW)
    assert math.isfinite(o.u_law) and o.u == -400.0


def test_ppc_feedforward_integrates_and_holds() -> None:
    cfg = ref.PpcConfig(**{**CASE3.__dict__, "ff_gain_per_s": 4.0, "period_s": 0.01,
                           "ff_init": 350.0})
    p = ref.Ppc(cfg)
    # e < 0 and v = 0 give u_law > 0
    o = p.step(5.0, -2.01, 0.0, -2.0)
    assert o.u_law > 0 and o.u_ff == 350.0 and not o.flags & ref.PPC_FLAG_SAT_HIGH
    assert p.u_ff == pytest.approx(350.0 + 0.04 * o.u_law)
    # drive it into saturation high: u_ff must then hold
    o = p.step(5.0, -2.1, 0.0, -2.0)
    assert o.flags & ref.PPC_FLAG_SAT_HIGH and o.u_law > 0
    held = p.u_ff
    o = p.step(5.0, -2.1, 0.0, -2.0)
    assert p.u_ff == held
    # a negative u_law integrates even from a saturated state
    o = p.step(5.0, -1.99, 0.0, -2.0)
    assert o.u_law < 0 and p.u_ff < held
    p.reset()
    assert p.u_ff == 350.0


def test_ppc_funnel_widening_known_values() -> None:
    """ppc.h's funnel widening by hand: |r1| = widen_r at the widening, g1 = widen_r / |raw1|,
    half way back after t_u / 2 (the tuning function's middle), as assigned after t_u; no
    clamp meanwhile."""
    cfg = ref.PpcConfig(**{**CASE3.__dict__, "widen_r": 0.5})
    p = ref.Ppc(cfg)
    o = p.step(5.0, -2.0 + 0.2 * 1.6, 0.0, -2.0)      # raw1 = 1.6 after t_u
    assert o.flags & ref.PPC_FLAG_WIDEN1 and o.flags & ref.PPC_FLAG_WIDE
    assert not o.flags & ref.PPC_FLAG_BARRIER1
    assert o.g1 == pytest.approx(0.5 / 1.6) and o.r1 == pytest.approx(0.5)
    assert o.chi == pytest.approx(1.0)                # tan(pi / 4)
    k = o.g1
    o = p.step(6.0, -2.0, 0.0, -2.0)                  # t_u / 2 later
    assert o.g1 == pytest.approx(1.0 - (1.0 - k) * 0.5) and o.flags == ref.PPC_FLAG_WIDE
    o = p.step(7.0, -2.0 + 0.2 * 0.9, 0.0, -2.0)      # t_u later: assigned, raw1 0.9 inside
    assert o.g1 == 1.0 and o.flags & ref.PPC_FLAG_WIDE == 0 and o.r1 == pytest.approx(0.9)
    # off: the paper's clamp
    o = ref.Ppc(CASE3).step(5.0, -2.0 + 0.2 * 1.6, 0.0, -2.0)
    assert o.flags & ref.PPC_FLAG_BARRIER1 and o.g1 == 1.0


def test_ppc_velocity_funnel_widens_on_the_nth_clamped_step() -> None:
    cfg = ref.PpcConfig(**{**CASE3.__dict__, "widen_r": 0.5, "widen2_steps": 3})
    p = ref.Ppc(cfg)
    flags = [p.step(5.0 + 0.001 * k, -2.0, 0.5 * 1.5, -2.0).flags for k in range(3)]
    assert [f & (ref.PPC_FLAG_BARRIER2 | ref.PPC_FLAG_WIDEN2) for f in flags] == \
        [ref.PPC_FLAG_BARRIER2, ref.PPC_FLAG_BARRIER2, ref.PPC_FLAG_WIDEN2]
    o = p.step(5.002, -2.0, 0.0, -2.0)                # at the widening's time: g2 = k2
    assert o.g2 == pytest.approx(0.5 / 1.5) and o.flags == ref.PPC_FLAG_WIDE
    assert o.beta_s_cm == pytest.approx((1.0 + o.delta ** 2) * o.g2 / 0.5)
    # widen2_steps 0: lambda2 never widens
    p0 = ref.Ppc(ref.PpcConfig(**{**CASE3.__dict__, "widen_r": 0.5}))
    assert all(p0.step(5.0 + 0.001 * k, -2.0, 0.75, -2.0).flags & ref.PPC_FLAG_BARRIER2 for k in range(5))


def test_ppc_u_ext_and_the_feedforward_bound() -> None:
    cfg = ref.PpcConfig(**{**CASE3.__dict__, "ff_gain_per_s": 2.0, "period_s": 0.01, "ff_init": 100.0})
    p = ref.Ppc(cfg)
    o = p.step(5.0, -2.0, 0.0, -2.0, u_ext=30.0)
    assert o.u == pytest.approx(130.0) and o.u_law == 0.0
    o = p.step(5.0, -2.0, 0.0, -2.0, u_ext=350.0)     # 100 + 0 + 350 > 400: SAT_HIGH
    assert o.flags & ref.PPC_FLAG_SAT_HIGH and o.u == 400.0
    assert p.u_ff == 50.0                             # u_law = 0 integrates: u_ff <= 400 - u_ext
    o = p.step(5.0, -2.0, 0.1, -2.0, u_ext=350.0)
    assert o.u_law < 0 and not o.flags and p.u_ff == pytest.approx(50.0 + 0.02 * o.u_law)


# --------------------------------------------------------------------------------------------
# MFAC

def test_mfac_first_step_resets() -> None:
    m = ref.Mfac(ref.MfacConfig(phi1=0.5, u_init=3.0))
    o = m.step(-2.0, -1.9)
    assert o.flags & ref.MFAC_FLAG_RESET and o.du == 0.0 and o.phi == 0.5
    assert o.u == pytest.approx(3.0 + 31.7 * 0.5 / (0.03 + 0.25) * 0.1)


def _mfac_at(phi: float, u1: float, u2: float, y1: float) -> ref.Mfac:
    m = ref.Mfac(ref.MfacConfig(phi1=0.5))
    m.phi, m.u1, m.u2, m.y1, m.k = phi, u1, u2, y1, 5
    return m


def test_mfac_reset_conditions() -> None:
    cfg = ref.MfacConfig()
    # normal update, no reset
    m = _mfac_at(0.3, 2.0, 1.0, -2.0)
    o = m.step(-1.9, -1.9)
    g = cfg.eta * 1.0 / (cfg.mu + 1.0)
    assert not o.flags & ref.MFAC_FLAG_RESET
    assert o.phi == pytest.approx(0.3 + g * (0.1 - 0.3 * 1.0))
    # |du| <= eps
    o = _mfac_at(0.3, 1.0, 1.0 - 0.5e-5, -2.0).step(-1.9, -1.9)
    assert o.flags & ref.MFAC_FLAG_RESET and o.phi == 0.5
    # sign flip: pick dy so that phi_c = -0.1
    dy = (-0.1 - 0.3) / g + 0.3
    o = _mfac_at(0.3, 2.0, 1.0, -2.0).step(-2.0 + dy, -1.9)
    assert o.phi_candidate == pytest.approx(-0.1) and o.flags & ref.MFAC_FLAG_RESET
    assert o.phi == 0.5
    # |phi| <= eps (positive, no sign flip)
    dy = (5e-6 - 0.3) / g + 0.3
    o = _mfac_at(0.3, 2.0, 1.0, -2.0).step(-2.0 + dy, -1.9)
    assert 0 < o.phi_candidate <= cfg.eps and o.flags & ref.MFAC_FLAG_RESET


def test_mfac_float32_loses_increments_below_half_an_ulp_of_u() -> None:
    """float32=True: the float firmware's arithmetic. At u = 530 an ulp is 2^-14 = 6.1e-5:
    an increment G (y* - y) of 2.5e-5 (above eps = 1e-5) is lost in float (u unchanged,
    next du = 0 and the reset rule sets phi back to phi1), kept in double (phi adapts)."""
    cfg = ref.MfacConfig(phi1=0.2, u_init=-530.0, u_min=-800.0, u_max=100.0)
    g = 31.7 * 0.2 / (0.03 + 0.04)                       # G at phi = phi1 [input units/cm]
    err = 2.5e-5 / g                                     # an increment of 2.5e-5 in u
    runs = {}
    for f32 in (False, True):
        m = ref.Mfac(cfg, float32=f32)
        m.step(-2.0, -2.0)                               # first step: u stays u_init
        o1 = m.step(-2.0, -2.0 + err)
        o2 = m.step(-2.0, -2.0)
        runs[f32] = (o1, o2)
    (d1, d2), (s1, s2) = runs[False], runs[True]
    assert d1.u == pytest.approx(-530.0 + 2.5e-5, abs=1e-9) and s1.u == -530.0
    assert d2.du == pytest.approx(2.5e-5, abs=1e-9) and s2.du == 0.0
    assert s2.flags & ref.MFAC_FLAG_RESET and s2.phi == ref._f32(0.2)
    assert not d2.flags & ref.MFAC_FLAG_RESET and d2.phi != 0.2
    # away from that edge both agree to float rounding
    for f32 in (False, True):
        m = ref.Mfac(cfg, float32=f32)
        runs[f32] = [m.step(-2.0 + 0.01 * math.sin(k / 7), -2.0 + 0.01 * math.sin((k + 1) / 7)).u
                     for k in range(50)]
    assert runs[True] == pytest.approx(runs[False], rel=1e-5)
    assert runs[True] != runs[False]


def test_mfac_saturation_and_clamped_history() -> None:
    m = ref.Mfac(ref.MfacConfig(u_min=-10.0, u_max=10.0))
    o = m.step(-2.0, 0.0)                 # +2 cm error: u_raw = 113 -> 10
    assert o.u == 10.0 and o.flags & ref.MFAC_FLAG_SAT_HIGH
    o = m.step(-2.0, 0.0)                 # du = 10 (clamped history)
    assert o.du == 10.0
    o = m.step(-2.0, 0.0)
    o = m.step(-2.0, 0.0)
    assert o.du == 0.0 and o.flags & ref.MFAC_FLAG_RESET
    o = m.step(-2.0, -6.0)
    assert o.u == -10.0 and o.flags & ref.MFAC_FLAG_SAT_LOW


# --------------------------------------------------------------------------------------------
# PID

def test_pid_p_only_and_first_step() -> None:
    p = ref.Pid(ref.PidConfig(kp=10.0, ki=0.0, kd=5.0, tf_s=0.0, k_aw_per_s=0.0,
                              period_s=0.01, u_min=-100.0, u_max=100.0))
    o = p.step(1.0, 3.0)                  # first step: no derivative kick
    assert o.u == pytest.approx(-20.0) and o.d == 0.0
    o = p.step(1.0, 3.1)                  # D = -kd/T dy = -50
    assert o.d == pytest.approx(-50.0) and o.u == pytest.approx(-21.0 - 50.0)


def test_pid_anti_windup() -> None:
    base = dict(kp=1.0, ki=50.0, kd=0.0, tf_s=0.0, period_s=0.01, u_min=-5.0, u_max=5.0)
    with_aw = ref.Pid(ref.PidConfig(k_aw_per_s=60.0, **base))
    without = ref.Pid(ref.PidConfig(k_aw_per_s=0.0, **base))
    for _ in range(300):
        a, b = with_aw.step(3.0, 0.0), without.step(3.0, 0.0)
    assert a.flags & ref.PID_FLAG_SAT_HIGH and b.flags & ref.PID_FLAG_SAT_HIGH
    assert a.u == b.u == 5.0
    assert without.i == 5.0                     # only the clamp at u_max stops it
    # back-calculation settles where ki e = k_aw (v - u): v = 5 + 50 * 3 / 60, I = v - P
    assert with_aw.i == pytest.approx(5.0 + 50.0 * 3.0 / 60.0 - 3.0, rel=1e-9)


# --------------------------------------------------------------------------------------------
# velocity estimators

@pytest.mark.parametrize("kind", [ref.VELEST_FILTERED_DIFF, ref.VELEST_TRACKING])
def test_velest_ramp(kind: int) -> None:
    est = ref.Velest(ref.VelestConfig(kind=kind, fc_hz=30.0, period_s=1e-3))
    rate = 2.5
    vs = [est.step(-2.0 + rate * k * 1e-3) for k in range(400)]
    assert vs[0] == 0.0
    assert vs[-1] == pytest.approx(rate, rel=1e-9)
    if kind == ref.VELEST_TRACKING:
        assert est.xh == pytest.approx(-2.0 + rate * 399e-3, abs=1e-9)   # type 2: no lag


def test_velest_filtered_difference_noise_gain() -> None:
    cfg = ref.VelestConfig(kind=ref.VELEST_FILTERED_DIFF, fc_hz=30.0, period_s=1e-3)
    est = ref.Velest(cfg)
    rng = np.random.default_rng(11)
    v = np.array([est.step(x) for x in rng.normal(0.0, 1.0, 200_000)])[1000:]
    assert np.std(v) == pytest.approx(est.noise_gain(), rel=0.02)


def test_velest_step_response_decays() -> None:
    for kind in (ref.VELEST_FILTERED_DIFF, ref.VELEST_TRACKING):
        est = ref.Velest(ref.VelestConfig(kind=kind, fc_hz=15.0, period_s=1e-3))
        vs = [est.step(0.0 if k < 20 else 0.5) for k in range(1000)]
        assert max(vs) > 1.0 and abs(vs[-1]) < 1e-6


# --------------------------------------------------------------------------------------------
# reference generators

@pytest.mark.parametrize("kind", [ref.REF_SINE, ref.REF_CASE1, ref.REF_CASE3])
def test_ref_derivative_matches_finite_difference(kind: int) -> None:
    g = ref.Ref(ref.RefConfig(kind=kind, offset_cm=-2.0, amplitude_cm=0.5, freq_hz=0.5,
                              phase_rad=0.3))
    h = 1e-6
    for t in np.linspace(0.5, 179.0, 37):
        x1, _ = g.eval(t - h)
        x2, _ = g.eval(t + h)
        _, xd = g.eval(t)
        assert xd == pytest.approx((x2 - x1) / (2 * h), rel=1e-5, abs=1e-8)


def test_ref_case3_values() -> None:
    assert ref.case3_ref(0.0) == (-2.0, pytest.approx(-1.0 / 360.0))
    x, _ = ref.case3_ref(55.0)
    phi = 2 * math.pi * 55 * 2 / 55 - math.pi / 2
    assert x == pytest.approx(55 * math.sin(phi) / 360 - 2)


def test_ref_step_and_ramp() -> None:
    s = ref.Ref(ref.RefConfig(kind=ref.REF_STEP, offset_cm=-1.0, amplitude_cm=-1.25, t0_s=1.5))
    assert s.eval(1.4999) == (-1.0, 0.0) and s.eval(1.5) == (-2.25, 0.0)
    r = ref.Ref(ref.RefConfig(kind=ref.REF_RAMP, offset_cm=-2.0, amplitude_cm=-0.75, t0_s=1.0,
                              rate_cm_s=0.25))
    assert r.eval(0.5) == (-2.0, 0.0)
    assert r.eval(1.0) == (-2.0, 0.25)
    assert r.eval(3.0) == (pytest.approx(-1.5), 0.25)
    assert r.eval(5.0) == (-1.25, 0.0)              # limited to offset + |amplitude|


def test_ref_stream_rate_limit() -> None:
    g = ref.Ref(ref.RefConfig(kind=ref.REF_STREAM, offset_cm=-2.0, rate_cm_s=0.5))
    assert g.eval(0.0) == (-2.0, 0.0)
    g.stream(-1.0)
    assert g.eval(0.0) == (-2.0, 0.0)               # dt = 0: no move
    x, xd = g.eval(0.4)
    assert x == pytest.approx(-1.8) and xd == pytest.approx(0.5)
    x, xd = g.eval(0.4)
    assert x == pytest.approx(-1.8) and xd == 0.0
    x, xd = g.eval(5.0)                             # arrives, average rate over the interval
    assert x == -1.0 and xd == pytest.approx(0.8 / 4.6)
    j = ref.Ref(ref.RefConfig(kind=ref.REF_STREAM, offset_cm=-1.5, rate_cm_s=0.0))
    j.stream(-2.5)
    assert j.eval(0.5) == (-2.5, pytest.approx(-2.0))


# --------------------------------------------------------------------------------------------
# the generator and the committed vectors

def test_gen_vectors_check_passes() -> None:
    r = subprocess.run([sys.executable, str(HERE / "gen_vectors.py"), "--check"],
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stdout + r.stderr


def test_gen_vectors_check_detects_a_change(tmp_path: Path) -> None:
    for name in gen_vectors.BUILDERS:
        (tmp_path / name).write_text((HERE / "vectors" / name).read_text())
    p = tmp_path / "pid_vectors.h"
    text = p.read_text()
    m = re.search(r"\{ (-?[0-9.]+f), (-?[0-9.]+f), (-?[0-9.e+-]+f),", text)
    assert m
    bumped = "%.9gf" % (float(m.group(3).rstrip("f")) * 1.001 + 0.001)
    p.write_text(text[:m.start(3)] + bumped + text[m.end(3):])
    r = subprocess.run([sys.executable, str(HERE / "gen_vectors.py"), "--check", "--out",
                        str(tmp_path)], capture_output=True, text=True)
    assert r.returncode == 1 and "pid_vectors.h" in r.stderr


INPUT_FIELDS = {"ppc": 4, "mfac": 2, "pid": 2, "velest": 1, "ref": 2}
ROW_BYTES = {"ppc": 64, "mfac": 20, "pid": 16, "velest": 8, "ref": 16}
ROW_RE = re.compile(r"^\s*\{ ([^{}]*) \},$", re.M)


def _rows(module: str) -> list[list[str]]:
    text = (HERE / "vectors" / ("%s_vectors.h" % module)).read_text()
    return [[f.strip() for f in m.group(1).split(",")] for m in ROW_RE.finditer(text)]


@pytest.mark.parametrize("module", sorted(INPUT_FIELDS))
def test_inputs_are_multiples_of_2_pow_minus_16(module: str) -> None:
    rows = _rows(module)
    assert rows
    for row in rows:
        for f in row[:INPUT_FIELDS[module]]:
            if f == "NAN":
                continue
            x = float(np.float32(float(f.rstrip("f"))))   # the float the C compiler makes
            assert x * 65536.0 == round(x * 65536.0), (module, row)


def test_vectors_fit_the_small_targets() -> None:
    """Each row array <= 250 rows; all of them well under 100 KB of binary data."""
    total = 0
    for module, size in ROW_BYTES.items():
        text = (HERE / "vectors" / ("%s_vectors.h" % module)).read_text()
        arrays = re.findall(r"static const golden_\w+_row_t \w+\[\] = \{\n(.*?)\n\};", text,
                            re.S)
        assert arrays
        for body in arrays:
            n = len(ROW_RE.findall(body + "\n"))
            assert 0 < n <= 250
            total += n * size
    assert total < 80 * 1024
