#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Generate the figures of docs/controllers.md from the numpy reference.

    python tools/plot_docs.py --out docs/img

The controllers come from tests/golden/pma_reference.py (the double-precision
reference of the firmware's algorithms), imported as pma_golden.pma_reference. The plant used
for the closed-loop figure is a small RK4 model of the paper's eq. 7 with the
coefficients of tests/unit/test_closed_loop.c: test code for an illustration,
not a measurement and not part of the firmware.

Deterministic: fixed noise seed, Agg backend, no timestamps in the PNGs.
Besides the figures, the script prints the numbers that docs/controllers.md
quotes (gains, barrier points, estimator noise gains and lags) so that they
can be checked against the reference.
"""
from __future__ import annotations

import argparse
import math
import sys
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402
from numpy.typing import NDArray  # noqa: E402

REPO = Path(__file__).resolve().parent.parent
from pma_golden import pma_reference as pref  # noqa: E402

FloatArray = NDArray[np.float64]

PERIOD_S = 1e-3                   # control period of every figure [s]
NOISE_SEED = 7                    # sensor-noise seed of the closed-loop figure
SENSOR_NOISE_CM = 0.0005          # 5 um, as in tests/unit/test_closed_loop.c
DPI = 110


# --------------------------------------------------------------------------------------------
# Configurations

def case3_config(t_u_s: float = 2.0, w1_cm: float = 0.2) -> pref.PpcConfig:
    """The firmware's default: the paper's Case 3 (a = c = 2, w1 = 0.2 cm, w2 = 0.5 cm/s,
    t_u = 2 s), u in kPa within +-400, 1 kHz, switches off; t_u and w1 overridable."""
    return pref.PpcConfig(a_cm_s=2.0, c=2.0, w1_cm=w1_cm, w2_cm_s=0.5, t_u_s=t_u_s,
                          u_min=-400.0, u_max=400.0, barrier_margin=1e-3, soft_barrier_r=1.0,
                          ff_gain_per_s=0.0, ff_init=0.0, period_s=PERIOD_S)


# --------------------------------------------------------------------------------------------
# Small numeric helpers

def velest_impulse_noise_gain(kind: int, fc_hz: float, period_s: float = PERIOD_S) -> float:
    """Std of v per unit std of white position noise: root of the summed squared impulse
    response of the reference estimator (prime with 0, then a unit impulse)."""
    est = pref.Velest(pref.VelestConfig(kind, fc_hz, period_s))
    est.step(0.0)
    total = 0.0
    for k in range(200000):
        v = est.step(1.0 if k == 0 else 0.0)
        total += v * v
        if k > 10 and v * v < 1e-30 * total:
            break
    return math.sqrt(total)


def velest_accel_lag(kind: int, fc_hz: float, period_s: float = PERIOD_S) -> float:
    """Steady-state delay [s] of the velocity estimate under constant acceleration
    (x = t^2/2, so the true velocity is t): t - v_hat(t)."""
    est = pref.Velest(pref.VelestConfig(kind, fc_hz, period_s))
    n = max(2000, int(40.0 / (fc_hz * period_s)))
    t = 0.0
    v = 0.0
    for k in range(n):
        t = k * period_s
        v = est.step(0.5 * t * t)
    return t - v


def velest_ramp_error(kind: int, fc_hz: float, period_s: float = PERIOD_S) -> float:
    """Steady-state velocity error [cm/s] on a constant-velocity ramp of 2 cm/s."""
    est = pref.Velest(pref.VelestConfig(kind, fc_hz, period_s))
    v = 0.0
    for k in range(max(2000, int(40.0 / (fc_hz * period_s)))):
        v = est.step(2.0 * k * period_s)
    return v - 2.0


def bisect(f: Callable[[float], float], lo: float, hi: float, n: int = 200) -> float:
    """Root of an increasing f on [lo, hi]."""
    for _ in range(n):
        mid = 0.5 * (lo + hi)
        if f(mid) < 0.0:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


def save(fig: Figure, out: Path, name: str) -> None:
    path = out / name
    fig.savefig(path, dpi=DPI, metadata={"Software": None})
    plt.close(fig)
    print(f"wrote {path}")


# --------------------------------------------------------------------------------------------
# (a) tuning function

def plot_alpha(out: Path) -> None:
    t = np.linspace(0.0, 8.0, 1601)
    fig, ax = plt.subplots(figsize=(6.4, 3.4), layout="constrained")
    for t_u, style in ((2.0, "-"), (6.0, "--")):
        alpha = np.array([pref.ppc_alpha(float(tk), t_u) for tk in t])
        ax.plot(t, alpha, style, lw=2, label=f"$t_u$ = {t_u:g} s")
        ax.axvline(t_u, color="0.6", lw=0.8, ls=":")
    ax.annotate("alpha(0) = 0: lambda1 = lambda2 = 0,\nu = u_ff (0 with the feedforward off)",
                xy=(0.0, 0.0), xytext=(2.3, 0.12), fontsize=8,
                arrowprops=dict(arrowstyle="->", lw=0.8))
    ax.set_xlabel("time since task start t [s]")
    ax.set_ylabel("alpha [-]")
    ax.set_title("Tuning function (eq. 15): 0.5 - 0.5 cos(pi t / $t_u$), 1 from $t_u$ on",
                 fontsize=10)
    ax.set_ylim(-0.05, 1.1)
    ax.grid(alpha=0.3)
    ax.legend(loc="lower right")
    save(fig, out, "ppc_alpha.png")


# --------------------------------------------------------------------------------------------
# (b) error transformation with the barrier clamp and the soft barrier

def plot_transform(out: Path) -> None:
    margin = 1e-3
    paper = pref.TanTransform(1.0 - margin, 1.0)
    soft = pref.TanTransform(1.0 - margin, 0.9)
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(10.0, 4.0), layout="constrained")

    r_lin = np.linspace(0.0, 0.9995, 2000)
    exact = np.tan(0.5 * np.pi * r_lin)
    ax1.plot(r_lin, exact, color="C0", lw=2, label="tan(pi r / 2) (paper, switch off)")
    ax1.plot(r_lin, [soft.apply(float(r))[0] for r in r_lin], color="C3", lw=2, ls="--",
             label="soft barrier, soft_barrier_r = 0.9")
    ax1.axvline(0.9, color="C3", lw=0.8, ls=":")
    ax1.text(0.895, 30.0, "soft_barrier_r = 0.9", color="C3", fontsize=8, ha="right")
    ax1.set_xlim(0.0, 1.0)
    ax1.set_ylim(0.0, 40.0)
    ax1.set_xlabel("normalised argument r = lambda / w [-]")
    ax1.set_ylabel("chi or delta [-]")
    ax1.set_title("Linear scale, r in [0, 1)", fontsize=10)
    ax1.grid(alpha=0.3)
    ax1.legend(loc="upper left", fontsize=8)

    # distance to the barrier 1 - r on a log axis: the clamp becomes a plateau
    gap = np.geomspace(0.5, 1e-6, 1500)
    r_near = 1.0 - gap
    ax2.loglog(gap, np.tan(0.5 * np.pi * r_near), color="0.45", lw=1.2, ls=":",
               label="tan(pi r / 2) without clamp: -> infinity at r = 1")
    ax2.loglog(gap, [paper.apply(float(r))[0] for r in r_near], color="C0", lw=2,
               label="firmware, paper's law: clamp at r_max = 1 - margin")
    ax2.loglog(gap, [soft.apply(float(r))[0] for r in r_near], color="C3", lw=2, ls="--",
               label="firmware, soft barrier 0.9, then the clamp")
    ax2.axvline(margin, color="k", lw=0.8, ls="--")
    cap = math.tan(0.5 * math.pi * (1.0 - margin))
    ax2.annotate(f"clamp at r_max = {1.0 - margin:g}:\n|tan| <= {cap:.0f}, BARRIER\n"
                 "flag + breach counter",
                 xy=(margin, cap), xytext=(6e-4, 40.0), fontsize=8,
                 arrowprops=dict(arrowstyle="->", lw=0.8))
    ax2.set_xlim(0.5, 1e-6)
    ax2.set_ylim(0.8, 1e6)
    ax2.set_xlabel("distance to the barrier 1 - |r| [-] (log, decreasing)")
    ax2.set_title("Near the barrier (log-log)", fontsize=10)
    ax2.grid(alpha=0.3, which="both")
    ax2.legend(loc="upper left", fontsize=8)
    fig.suptitle("Error transformation (eq. 18, 22) with the barrier clamp (margin 1e-3)",
                 fontsize=11)
    save(fig, out, "ppc_transform.png")


# --------------------------------------------------------------------------------------------
# (c) the control law after t_u, Case 3

def law_u(ctrl: pref.Ppc, e_cm: float, v_cm_s: float) -> tuple[float, float, int]:
    """(u_law, u, flags) after t_u for error e and velocity v (reference at -2 cm)."""
    o = ctrl.step(10.0, -2.0 + e_cm, v_cm_s, -2.0)
    return o.u_law, o.u, o.flags


def plot_law(out: Path) -> None:
    cfg = case3_config()
    ctrl = pref.Ppc(cfg)
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(11.0, 4.4), layout="constrained")

    e = np.linspace(-0.1, 0.1, 2001)
    for i, v in enumerate((-0.4, -0.2, 0.0, 0.2, 0.4)):
        u = np.array([law_u(ctrl, float(ek), v)[1] for ek in e])
        ax1.plot(e, u, lw=1.8, color=f"C{i}", label=f"x' = {v:+.1f} cm/s")
    ax1.axhline(cfg.u_max, color="k", lw=0.8, ls=":")
    ax1.axhline(cfg.u_min, color="k", lw=0.8, ls=":")
    ax1.text(0.098, 410.0, "u_max = 400 kPa", fontsize=8, ha="right")
    ax1.text(-0.098, -430.0, "u_min = -400 kPa", fontsize=8)
    ax1.set_xlim(-0.1, 0.1)
    ax1.set_ylim(-450.0, 450.0)
    ax1.set_xlabel("error e = x - x_r [cm]")
    ax1.set_ylabel("u [kPa] (clamped to the limits)")
    ax1.set_title("Slices: u vs e for a few velocities", fontsize=10)
    ax1.grid(alpha=0.3)
    ax1.legend(fontsize=8, loc="lower left", bbox_to_anchor=(0.0, 0.06))

    eg = np.linspace(-0.1, 0.1, 241)
    vg = np.linspace(-1.5, 1.5, 241)
    uu = np.empty((vg.size, eg.size))
    l2 = np.empty_like(uu)
    for j, v in enumerate(vg):
        for i, ek in enumerate(eg):
            o = ctrl.step(10.0, -2.0 + float(ek), float(v), -2.0)
            uu[j, i] = o.u
            l2[j, i] = o.lambda2_cm_s
    mesh = ax2.pcolormesh(eg, vg, uu, cmap="coolwarm", vmin=-400.0, vmax=400.0,
                          shading="auto")
    fig.colorbar(mesh, ax=ax2, label="u [kPa]")
    cs = ax2.contour(eg, vg, l2, levels=[-cfg.w2_cm_s, cfg.w2_cm_s], colors="k",
                     linewidths=1.2)
    ax2.clabel(cs, fmt={-cfg.w2_cm_s: "lambda2 = -w2", cfg.w2_cm_s: "lambda2 = +w2"},
               fontsize=7)
    ax2.set_xlabel("error e = x - x_r [cm]")
    ax2.set_ylabel("velocity x' [cm/s]")
    ax2.set_title("u(e, x'): |lambda2| < w2 between the black lines", fontsize=10)
    fig.suptitle("Paper's law after $t_u$ (alpha = 1), Case 3: a = c = 2, w1 = 0.2 cm, "
                 "w2 = 0.5 cm/s, u in [-400, 400] kPa", fontsize=11)
    save(fig, out, "ppc_law_case3.png")


# --------------------------------------------------------------------------------------------
# (d) closed-loop illustration with a test plant (eq. 7), Case 1

@dataclass
class TestPlant:
    """x'' = H u - D x' - G x, H = l x' + b x + f (tests/unit/test_closed_loop.c)."""

    x: float = -0.5
    v: float = 0.0
    l: float = 0.0  # noqa: E741 (the coefficient named l in the test plant it mirrors)
    b: float = 0.05
    f: float = 2.0
    d: float = 30.0
    g: float = 20.0

    def accel(self, x: float, v: float, u: float) -> float:
        return (self.l * v + self.b * x + self.f) * u - self.d * v - self.g * x

    def step(self, u: float, dt: float, substeps: int = 10) -> None:
        """RK4 with a zero-order hold on u."""
        h = dt / substeps
        x, v = self.x, self.v
        for _ in range(substeps):
            k1x, k1v = v, self.accel(x, v, u)
            k2x, k2v = v + 0.5 * h * k1v, self.accel(x + 0.5 * h * k1x, v + 0.5 * h * k1v, u)
            k3x, k3v = v + 0.5 * h * k2v, self.accel(x + 0.5 * h * k2x, v + 0.5 * h * k2v, u)
            k4x, k4v = v + h * k3v, self.accel(x + h * k3x, v + h * k3v, u)
            x += h / 6.0 * (k1x + 2.0 * k2x + 2.0 * k3x + k4x)
            v += h / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v)
        self.x, self.v = x, v


@dataclass
class LoopTrace:
    t: FloatArray
    x: FloatArray
    xr: FloatArray
    u: FloatArray
    barrier: NDArray[np.bool_]


def simulate_case1(duration_s: float, t_u_s: float, w1_cm: float) -> LoopTrace:
    cfg = case3_config(t_u_s=t_u_s, w1_cm=w1_cm)
    ctrl = pref.Ppc(cfg)
    est = pref.Velest(pref.VelestConfig(pref.VELEST_FILTERED_DIFF, 30.0, PERIOD_S))
    plant = TestPlant()
    n = int(round(duration_s / PERIOD_S))
    noise = np.random.default_rng(NOISE_SEED).standard_normal(n) * SENSOR_NOISE_CM
    tr = LoopTrace(t=np.arange(n, dtype=np.float64) * PERIOD_S, x=np.empty(n), xr=np.empty(n), u=np.empty(n),
                   barrier=np.zeros(n, dtype=bool))
    for k in range(n):
        t = k * PERIOD_S
        xm = plant.x + float(noise[k])
        xr, _ = pref.case1_ref(t)
        o = ctrl.step(t, xm, est.step(xm), xr)
        tr.x[k], tr.xr[k], tr.u[k] = plant.x, xr, o.u
        tr.barrier[k] = (o.flags & (pref.PPC_FLAG_BARRIER1 | pref.PPC_FLAG_BARRIER2)) != 0
        plant.step(o.u, PERIOD_S)
    return tr


def plot_closed_loop(out: Path) -> None:
    t_u, w1 = 6.0, 0.5
    tr = simulate_case1(20.0, t_u, w1)
    after = tr.t >= t_u
    e = tr.x - tr.xr
    print(f"closed loop (illustration) Case 1: max|e| after t_u {np.max(np.abs(e[after])):.3f} cm,"
          f" barrier steps after t_u {int(np.count_nonzero(tr.barrier & after))},"
          f" x in [{tr.x.min():.3f}, {tr.x.max():.3f}] cm")
    fig, axs = plt.subplots(3, 1, figsize=(9.0, 8.0), sharex=True, layout="constrained",
                            gridspec_kw=dict(height_ratios=[2.2, 1.3, 1.3]))
    ax = axs[0]
    ax.axhspan(-3.0, 0.0, color="C2", alpha=0.07, label="constraint band -3 < x < 0 cm")
    ax.axhline(-3.0, color="C2", lw=1.0)
    ax.axhline(0.0, color="C2", lw=1.0)
    ax.fill_between(tr.t, tr.xr - w1, tr.xr + w1, color="C1", alpha=0.25,
                    label="x_r +- w1 (w1 = 0.5 cm)")
    ax.plot(tr.t, tr.xr, color="C1", lw=1.2, ls="--", label="x_r = -0.5 sin(t) - 2")
    ax.plot(tr.t, tr.x, color="C0", lw=1.4, label="x (plant)")
    ax.axvline(t_u, color="0.4", lw=0.8, ls=":")
    ax.text(t_u + 0.1, -0.35, "$t_u$ = 6 s", fontsize=8)
    ax.set_ylim(-3.3, 0.3)
    ax.set_ylabel("position [cm]")
    ax.legend(loc="lower right", fontsize=8, ncol=2)
    ax.grid(alpha=0.3)

    ax = axs[1]
    ax.plot(tr.t, e, color="C0", lw=1.0)
    ax.axhline(w1, color="C1", lw=1.0, ls="--")
    ax.axhline(-w1, color="C1", lw=1.0, ls="--")
    ax.axvline(t_u, color="0.4", lw=0.8, ls=":")
    ax.set_ylim(-0.8, 2.1)
    ax.set_ylabel("e = x - x_r [cm]")
    ax.text(19.8, w1 + 0.06, "+w1", color="C1", fontsize=8, ha="right")
    ax.text(19.8, -w1 + 0.06, "-w1", color="C1", fontsize=8, ha="right")
    ax.grid(alpha=0.3)

    ax = axs[2]
    ax.plot(tr.t, tr.u, color="C3", lw=0.4, alpha=0.6, label="u applied (1 kHz)")
    window = 50
    u_avg = np.convolve(tr.u, np.ones(window) / window, mode="valid")
    ax.plot(tr.t[window - 1:], u_avg, color="k", lw=1.2, label="u, 50 ms moving average")
    ax.plot(tr.t[tr.barrier], np.full(np.count_nonzero(tr.barrier), 430.0), "|", color="k",
            ms=5, label="barrier clamp (BARRIER1/2 flag)")
    ax.axvline(t_u, color="0.4", lw=0.8, ls=":")
    ax.set_ylim(-450.0, 480.0)
    ax.set_ylabel("u [kPa]")
    ax.set_xlabel("t [s]")
    ax.legend(loc="lower right", fontsize=8, ncol=3)
    ax.grid(alpha=0.3)
    fig.suptitle("ILLUSTRATION, not a result: Case 1 (t_u = 6 s, w1 = 0.5 cm, w2 = 0.5 cm/s) on "
                 "the unit-test plant\n(eq. 7, H = 2 + 0.05 x, D = 30, G = 20, 1 kHz, 5 um noise, "
                 "filtered difference 30 Hz; numpy reference controllers)", fontsize=10)
    save(fig, out, "closed_loop_case1.png")


# --------------------------------------------------------------------------------------------
# (e) velocity estimators: noise gain and lag vs bandwidth

def plot_velest(out: Path) -> None:
    fc = np.geomspace(3.0, 300.0, 61)
    names = {pref.VELEST_FILTERED_DIFF: "filtered difference",
             pref.VELEST_TRACKING: "tracking observer"}
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(10.5, 4.2), layout="constrained")
    for kind, color in ((pref.VELEST_FILTERED_DIFF, "C0"), (pref.VELEST_TRACKING, "C3")):
        gain = np.array([velest_impulse_noise_gain(kind, float(f)) for f in fc])
        lag = np.array([velest_accel_lag(kind, float(f)) for f in fc])
        ax1.loglog(fc, gain, color=color, lw=2, label=names[kind])
        ax2.loglog(fc, lag * 1e3, color=color, lw=2, label=names[kind])
        g30 = velest_impulse_noise_gain(kind, 30.0)
        ax1.plot([30.0], [g30], "o", color=color)
        ax1.annotate(f"{g30:.0f} at 30 Hz", xy=(30.0, g30), xytext=(8, -12),
                     textcoords="offset points", fontsize=8, color=color)
    p = np.exp(-2.0 * np.pi * fc * PERIOD_S)
    ax1.loglog(fc, (1.0 - p) / PERIOD_S * np.sqrt(2.0 / (1.0 + p)), "k:", lw=1,
               label="closed form (1-p)/T sqrt(2/(1+p))")
    ax1.set_xlabel("bandwidth fc [Hz]")
    ax1.set_ylabel("velocity noise / position noise [(cm/s)/cm = 1/s]")
    ax1.set_title("Noise gain sigma_v / sigma_x (white noise, T = 1 ms)", fontsize=10)
    ax1.grid(alpha=0.3, which="both")
    ax1.legend(fontsize=8)
    ax2.loglog(fc, 1e3 / (2.0 * np.pi * fc), "k:", lw=1, label="1/(2 pi fc)")
    ax2.loglog(fc, 1e3 / (np.pi * fc), "k--", lw=0.8, label="1/(pi fc)")
    ax2.set_xlabel("bandwidth fc [Hz]")
    ax2.set_ylabel("lag [ms]")
    ax2.set_title("Velocity lag under constant acceleration (T = 1 ms)", fontsize=10)
    ax2.grid(alpha=0.3, which="both")
    ax2.legend(fontsize=8)
    fig.suptitle("Velocity estimators: both give the exact velocity of a constant-velocity "
                 "ramp once settled", fontsize=11)
    save(fig, out, "velest_noise_lag.png")


# --------------------------------------------------------------------------------------------
# Numbers quoted by the documentation

def print_numbers() -> None:
    cfg = case3_config()
    kv = cfg.c * math.pi / (2.0 * cfg.w2_cm_s ** 2)
    print(f"velocity gain c pi/(2 w2^2) = {kv:.2f} kPa/(cm/s)")
    for w1 in (0.2, 0.3, 0.5):
        kp = cfg.a_cm_s * math.pi / (2.0 * w1)
        e_bar = 2.0 * w1 / math.pi * math.atan(cfg.w2_cm_s / cfg.a_cm_s)
        print(f"w1 = {w1}: a pi/(2 w1) = {kp:.2f} 1/s, linear gain {kp * kv:.1f} kPa/cm, "
              f"|e| at rest where lambda2 = w2: {e_bar:.4f} cm")

    def u_of_r2(r: float) -> float:
        d = math.tan(0.5 * math.pi * r)
        return cfg.c * (1.0 + d * d) * d / cfg.w2_cm_s

    r_sat = bisect(lambda r: u_of_r2(r) - cfg.u_max, 0.0, 0.9999)
    print(f"|u_law| = 400 kPa at r2 = {r_sat:.4f}")
    u_hold = 20.0 * 2.0 / (2.0 - 0.05 * 2.0)
    r_hold = bisect(lambda r: u_of_r2(r) - u_hold, 0.0, 0.9999)
    chi = r_hold * cfg.w2_cm_s / cfg.a_cm_s
    for w1 in (0.3, 0.5):
        print(f"test plant, hold x = -2 cm: |u| = {u_hold:.2f} kPa -> r2 = {r_hold:.3f}, "
              f"lambda2 = {r_hold * cfg.w2_cm_s:.3f} cm/s, e at rest (w1 = {w1}) = "
              f"{2.0 * w1 / math.pi * math.atan(chi):.4f} cm")
    r_max = 1.0 - cfg.barrier_margin
    t_max = math.tan(0.5 * math.pi * r_max)
    print(f"clamp r_max = {r_max}: tan = {t_max:.1f}, sec^2 = {1 + t_max * t_max:.4g}")
    soft = pref.TanTransform(r_max, 0.9)
    print(f"soft 0.9: tan = {soft.soft_tan:.3f}, sec^2 = {soft.soft_sec2:.2f}, "
          f"chi at r_max = {soft.apply(r_max)[0]:.2f}")
    r_q16 = bisect(lambda r: 1.0 + math.tan(0.5 * math.pi * r) ** 2 - 32767.0, 0.99, 0.9999)
    print(f"fixed point: sec^2 < 32767 up to soft_r = {r_q16:.5f}")
    print("fc [Hz] | FD gain | FD accel lag [ms] | TO gain | TO accel lag [ms] | ramp err")
    for fc in (10.0, 20.0, 30.0, 50.0, 80.0, 120.0, 200.0):
        fd = (velest_impulse_noise_gain(0, fc), velest_accel_lag(0, fc) * 1e3)
        to = (velest_impulse_noise_gain(1, fc), velest_accel_lag(1, fc) * 1e3)
        err = max(abs(velest_ramp_error(0, fc)), abs(velest_ramp_error(1, fc)))
        print(f"{fc:6.0f} | {fd[0]:7.1f} | {fd[1]:6.2f} | {to[0]:7.1f} | {to[1]:6.2f} | {err:.1e}")


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=REPO / "docs" / "img",
                        help="output directory for the PNG files (default: docs/img)")
    args = parser.parse_args(argv)
    out: Path = args.out
    out.mkdir(parents=True, exist_ok=True)
    plt.rcParams.update({"font.size": 9})
    plot_alpha(out)
    plot_transform(out)
    plot_law(out)
    plot_closed_loop(out)
    plot_velest(out)
    print_numbers()
    return 0


if __name__ == "__main__":
    sys.exit(main())
