# SPDX-License-Identifier: Apache-2.0
"""The derivation of `pmactl commission`: pure functions from what was measured on the rig to
the controllers' parameters (docs/commissioning.md, "The rules"). No CAN, no node: the
procedure (pmactl/commission.py) measures, these functions decide.

Units: positions x in cm, pressures p in kPa (gauge), times in s, the controller's input u in
its unit (u = polarity * (p - p0) / act.kpa_per_u).

The model the rules use is the one a step response shows on any such rig: around an operating
point the position follows the pressure like a first-order lag with a dead time (FOPDT),
x(s) / p(s) = g e^{-theta s} / (tau s + 1), with g in cm/kPa, fitted by the two-point method
(the times to 35.3 % and 85.3 % of the step), or, where a slow tail stretches that fit, the lag of
the response's early part (a step into the dead band, which moved too little to read a lag from,
takes the steps that moved); the loop's FOPDT takes the median lag and the median of the steps'
slopes g / tau (MFAC the median gain). The loop is then shaped by the SIMC rule
(Skogestad 2003) with the closed-loop time constant tau_c the tightest in TAU_C_PER_THETA_MIN..MAX x
theta_eff whose loop as built (with the observer below) keeps PM_MIN_DEG and GM_MIN on the measured
FOPDT (never below tau / SPEEDUP_MAX): a PI equivalent
Kc, tau_I, which the paper's law realises in its small-signal form
u = -K_v ((x' - x_r') + K_p e) plus the steady-state feedforward integrator
(u_ff' = k_ff u_law), i.e. the PID  K_v (K_p + k_ff) + K_v s + K_v K_p k_ff / s. The law sees the
position and velocity through the tracking observer, placed at FC_PER_CROSSOVER x the crossover of
the tightest loop the rule allows; the margins of the loop with that observer in it (law_margins,
"as built") decide, and are reported beside the PID's. Where the sensor's noise through that loop would
move the input more than CHATTER_WARN_PER_NEED times what the reference needs, the law's command goes
through a first-order low-pass (ppc.u_lpf_hz): the highest corner, down to the observer's bandwidth,
that keeps the noise within that, in the loop as built too.
The reference feedforward takes the static map's slope, and its hysteresis term (_hysteresis_ff) the
branch of the map's loop the reference is on; MFAC's reset threshold is a tenth of the measured gain.
"""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np

# two-point FOPDT fit (Sundaresan & Krishnaswamy 1978)
FIT_LOW, FIT_HIGH = 0.353, 0.853
# the response's early lag: from FIT_EARLY to FIT_LOW of the step an FOPDT takes tau ln(0.9 / 0.647);
# a response with a slow tail (creep, a slow valve stage) gets there faster than its fitted lag says
FIT_EARLY = 0.1
EARLY_SMOOTH = 5             # samples of the centred moving average the early lag's crossings are read on
# SIMC's closed-loop time constant tau_c in units of theta_eff: the tightest in this range whose loop
# as built (the law with its velocity observer, law_margins) keeps both margins below on the measured
# FOPDT, found by bisection (SIMC's own "tight control" is tau_c = theta)
TAU_C_PER_THETA_MIN, TAU_C_PER_THETA_MAX = 0.35, 3.0
PM_MIN_DEG, GM_MIN = 45.0, 2.0
SPEEDUP_MAX = 5.0            # tau_c >= tau / 5: the closed loop at most 5x faster than the open loop
# the velocity observer's bandwidth in units of the crossover of the tightest loop the rule allows
# (TAU_C_PER_THETA_MIN; a looser loop keeps the observer and gains phase): the law's feedforward integrator
# takes r / (1 + r) (r = FF_PER_KP) of its proportional action through the observer's velocity, whose lag
# at the crossover is at most 2 atan(1 / FC_PER_CROSSOVER): 14 deg here, 28 deg at 4x (docs/commissioning.md,
# "The rules")
FC_PER_CROSSOVER = 8.0
FC_MIN_HZ, FC_MAX_HZ = 2.0, 50.0
# the command's low-pass (ppc.u_lpf_hz) in units of the observer's bandwidth: the law passes the
# sensor's noise to the input with a first-order roll-off above the observer's bandwidth, and the
# low-pass makes it second-order. At the observer's bandwidth it cuts what white noise moves the
# input to about a fifth (law_noise_rate) for atan(1 / FC_PER_CROSSOVER) = 7 deg at the tightest
# loop's crossover, which the margins as built include: the loop comes out a little looser. So it
# is used only where the noise through the loop without it would move the input more than
# CHATTER_WARN_PER_NEED (or the user's noise limit) times what the reference needs, where the report
# would warn of chatter, and no lower than that needs: from FU_PER_FC_MAX x the observer's
# bandwidth down in steps of FU_STEP to FU_PER_FC_MIN x, the first corner whose loop (shaped with
# it) keeps the noise within that (docs/commissioning.md, "The rules"). At half the observer's
# bandwidth it lags atan(2 / FC_PER_CROSSOVER) = 14 deg at the tightest loop's crossover; it stops
# there because below it the margins loosen the loop faster than the noise falls
FU_PER_FC_MAX, FU_PER_FC_MIN, FU_STEP = 4.0, 0.5, 0.8
# The sensor's noise through the law as built (law_noise_rate) moves the input; where it moves it
# more than CHATTER_WARN_PER_NEED times the rate the task's reference needs (|ppc.ref_ff| x the
# reference's mean speed), the report warns that the valve will chatter. The user may bound it
# (Task.noise_limit, `pmactl commission --noise-limit K`): the observer's bandwidth then comes down
# in steps of FC_NOISE_STEP, and with it the loop the margins allow, until the noise moves the input
# at most K times the need. That buys a quieter valve with accuracy (docs/commissioning.md, "A
# quieter valve"), so it is the user's choice, not a default. The input's total variation is about
# the noise's and the need's in quadrature, the need's own part 1.2-2 times the need (the lag, the
# hysteresis), and this estimate of the need 0.75-1.45 times the rig's.
CHATTER_WARN_PER_NEED = 2.0
FC_NOISE_STEP = 0.9
# the feedforward integrator's gain k_ff in units of K_p: the law's derivative (velocity) term is
# 1 + r times smaller than Kc / K_p. Its phase lead at the crossover is in the margins as built, so
# a larger one lets the bisection take a tighter tau_c; its noise is in law_noise_rate (the command's
# low-pass where it would chatter). 10 rather than 30: a lower RMSTE on the drawn rigs for a little
# more valve activity (docs/hil.md, "The velocity term's weight")
FF_PER_KP = 10.0
W2_PER_A = 5.0               # lambda2's barrier at 5 a: theta = a tan(pi r / 2) reaches it at r = 0.87
NOISE_SIGMAS_IN_W1 = 6.0     # w1 must hold 6 standard deviations of the position noise
# a step's first movement: x MOVE_SIGMAS noise standard deviations away from its start; counted
# only for steps that moved MOVED_SIGMAS of them in all (a smaller one is mostly noise)
MOVE_SIGMAS, MOVED_SIGMAS = 4.0, 10.0
MFAC_ETA, MFAC_MU, MFAC_RHO, MFAC_LAMBDA = 0.5, 1.9, 31.7, 0.03   # the paper's MFAC gains
# MFAC's reset threshold eps in units of the measured gain g (the paper's "about 1e-5" is a number in
# its own units): an estimate phi below g / 10 learned from a stretch where the input moved and the
# muscle could not (the hysteresis' dead band, the end of the stroke, a saturated valve), and its
# step rho phi / (lambda + phi^2) then all but stops the loop; the reset rule puts it back to phi(1)
MFAC_EPS_PER_GAIN = 0.1
# the reference feedforward's hysteresis term (ppc.ref_ff_hyst): this part of the half-width of the
# static map's loop. A slow sweep's loop is the widest the muscle shows (minor loops are narrower, and
# creep and the valve's own hysteresis widen a slow sweep's); under-compensation leaves the rest to
# the feedforward integrator, over-compensation makes an error of the other sign at every reversal
HYST_FF_PART = 0.25
HYST_PLAY_MIN_CM = 0.001     # the play's half-width at least 10 um (an ideal backlash: a step of 2 H)
# ... and the play at most this many times as steep as the static map (H / b <= HYST_SLOPE_MAX x
# |ppc.ref_ff|): a steeper one is a step of 2 H at the reference's reversal, taken a lag ahead, and
# wherever the muscle's own reversal falls elsewhere (creep, a valve that waits longer to exhaust
# than to fill, a dead-band step that the sweep's unsettled levels made too small) the step lands as
# an error at every reversal. On 303 runs of drawn and shipped rigs the cap made 42 better (up to
# 45 %), 5 worse (up to 14 %, each still ahead of MFAC)
HYST_SLOPE_MAX = 4.0
# the gain the law's loop is shaped on at least this part of the static map's slope over the
# reference's range. On 447 commissionings of shipped and drawn rigs the steps' gain sat at
# 0.35-1.05 of the map's (5-95 %); at 0.11 (a 49 N friction: three of the six steps in its dead
# band) the loop came out nine times too stiff and swung its input from limit to limit at 4 Hz
LOOP_GAIN_PER_MAP_MIN = 0.25
# the hysteresis term's adaptation on the node (ppc.ref_ff_hyst_gain_per_s): this part of the feedforward
# integrator's gain. Each reversal moves H by about 2 x this part of the gap to the step the law
# had to make (docs/commissioning.md): 6 % per reversal, settled after some tens of them; a larger
# part follows a slow valve's and creep's lag as if it were hysteresis (0.1: the paper's rig's
# variants better, the realistic profiles' slow valves up to 40 % worse in a Case 3 window)
HYST_ADAPT_PER_FF = 0.03


class CommissionError(ValueError):
    """The measurements do not allow a derivation (the message says what to check)."""


@dataclass
class StepFit:
    """One step response: x(t) after a pressure step of dp_kpa at t = 0."""
    p_kpa: float            # the pressure before the step
    dp_kpa: float
    gain_cm_per_kpa: float  # dx / dp, signed
    tau_s: float
    theta_s: float
    rms_cm: float           # fit residual
    # the time x takes to move MOVE_SIGMAS noise standard deviations from its start: the dead
    # time as the loop meets it (nan: not measured, or the step moved too little to tell)
    first_move_s: float = math.nan
    # the lag of the response's early part (FIT_EARLY to FIT_LOW of the step), what the loop
    # meets at its crossover: below tau_s where a slow tail stretches the fit (nan: not measured)
    tau_early_s: float = math.nan


@dataclass
class StaticMap:
    """x(p) along a pressure sweep up and down (both branches of the hysteresis)."""
    p_up_kpa: list[float]
    x_up_cm: list[float]
    p_down_kpa: list[float]
    x_down_cm: list[float]

    def all_x(self) -> list[float]:
        return self.x_up_cm + self.x_down_cm

    def stroke_cm(self) -> tuple[float, float]:
        xs = self.all_x()
        return min(xs), max(xs)

    def rising_kpa(self, x_cm: float) -> float:
        """The pressure at x on the rising branch (linear between points; at the branch's end,
        its end). CommissionError outside the stroke."""
        self._check(x_cm)
        return _interp_p(self.p_up_kpa, self.x_up_cm, x_cm)

    def falling_kpa(self, x_cm: float) -> float:
        """The pressure at x on the falling branch (as rising_kpa)."""
        self._check(x_cm)
        return _interp_p(self.p_down_kpa, self.x_down_cm, x_cm)

    def rising_x_cm(self, p_kpa: float) -> float:
        """x at p on the rising branch, where a muscle raised to p from below rests."""
        return _interp_x(self.p_up_kpa, self.x_up_cm, p_kpa)

    def hold_kpa(self, x_cm: float) -> float:
        """The pressure that holds x: the middle of the two branches."""
        return 0.5 * (self.rising_kpa(x_cm) + self.falling_kpa(x_cm))

    def hysteresis_kpa(self, x_cm: float) -> float:
        return abs(self.rising_kpa(x_cm) - self.falling_kpa(x_cm))

    def _check(self, x_cm: float) -> None:
        lo, hi = self.stroke_cm()
        if not lo <= x_cm <= hi:
            raise CommissionError(f"x = {x_cm:.3f} cm lies outside the measured stroke {lo:.3f}..{hi:.3f} cm")


def _interp_x(p: list[float], x: list[float], p_kpa: float) -> float:
    """x at p on one branch (sorted by p; beyond its ends, its end)."""
    order = np.argsort(p)
    return float(np.interp(p_kpa, np.asarray(p, float)[order], np.asarray(x, float)[order]))


def _interp_p(p: list[float], x: list[float], x_cm: float) -> float:
    """p at x on one branch (sorted by x; beyond its ends, its end)."""
    order = np.argsort(x)
    return float(np.interp(x_cm, np.asarray(x, float)[order], np.asarray(p, float)[order]))


def fit_step(t_s: np.ndarray, x_cm: np.ndarray, p_kpa: float, dp_kpa: float,
             noise_cm: float | None = None) -> StepFit:
    """FOPDT of one step response (t from the step, x measured; the first samples before the
    response moves give the start value, the last 20 % the end value). With the noise at rest,
    also the time of the first movement (StepFit.first_move_s)."""
    t = np.asarray(t_s, float)
    x = np.asarray(x_cm, float)
    if len(t) < 20 or t[-1] <= 0:
        raise CommissionError("a step response needs at least 20 samples after the step")
    x0 = float(np.mean(x[: max(3, len(x) // 50)]))
    x1 = float(np.mean(x[int(0.8 * len(x)):]))
    dx = x1 - x0
    if dp_kpa == 0 or dx == 0:
        raise CommissionError("the step moved nothing")
    y = (x - x0) / dx                       # 0 .. 1
    t_low, t_high = _first_crossing(t, y, FIT_LOW), _first_crossing(t, y, FIT_HIGH)
    tau = max(0.67 * (t_high - t_low), 1e-4)
    theta = max(1.3 * t_low - 0.29 * t_high, 0.0)
    model = np.where(t > theta, 1.0 - np.exp(-(t - theta) / tau), 0.0)
    rms = float(np.sqrt(np.mean((y - model) ** 2)) * abs(dx))
    first_move = tau_early = math.nan
    if noise_cm is not None and noise_cm > 0 and abs(dx) >= MOVED_SIGMAS * noise_cm:
        moved = np.nonzero(np.abs(x - x0) >= MOVE_SIGMAS * noise_cm)[0]
        first_move = float(t[moved[0]]) if len(moved) else math.nan
        # on the smoothed response, where FIT_EARLY of a step of MOVED_SIGMAS stands clear of the noise
        # (a noise crossing before the movement makes the early lag longer: then the fit's stands);
        # the last EARLY_SMOOTH // 2 samples are dropped: "same" averages zeros in beyond the record
        smooth = np.convolve(y, np.ones(EARLY_SMOOTH) / EARLY_SMOOTH, mode="same")[: len(y) - EARLY_SMOOTH // 2]
        t_early, t_low_s = _first_crossing(t, smooth, FIT_EARLY), _first_crossing(t, smooth, FIT_LOW)
        tau_early = max(t_low_s - t_early, 0.0) / math.log((1.0 - FIT_EARLY) / (1.0 - FIT_LOW))
    return StepFit(p_kpa=p_kpa, dp_kpa=dp_kpa, gain_cm_per_kpa=dx / dp_kpa, tau_s=tau, theta_s=theta, rms_cm=rms,
                   first_move_s=first_move, tau_early_s=tau_early)


def _first_crossing(t: np.ndarray, y: np.ndarray, level: float) -> float:
    above = np.nonzero(y >= level)[0]
    if len(above) == 0:
        raise CommissionError(f"the step response never reached {100 * level:.0f} % of its end value: "
                              "hold each step longer")
    i = int(above[0])
    if i == 0:
        return float(t[0])
    # linear between the samples around the crossing
    return float(t[i - 1] + (level - y[i - 1]) / (y[i] - y[i - 1]) * (t[i] - t[i - 1]))


@dataclass
class Task:
    """What the user asks for: the accuracy w1 after t_u, the output constraints."""
    w1_cm: float
    t_u_s: float
    x_min_cm: float
    x_max_cm: float
    x_start_cm: float | None = None   # where the reference starts (default: the band's middle)
    speed_cm_s: float = 0.0           # the reference's largest speed (0: a set-point task)
    # the reference's mean speed |dx_r/dt| [cm/s] (None: a sine's, 2 / pi of speed_cm_s; 0: the
    # noise is not weighed against it)
    mean_speed_cm_s: float | None = None
    # the sensor's noise may move the input at most this many times the rate the reference needs
    # (None: no bound, the observer as fast as the margins want; CHATTER_WARN_PER_NEED)
    noise_limit: float | None = None
    x_ref_min_cm: float | None = None  # the range the reference spans (default: the band less w1)
    x_ref_max_cm: float | None = None


def band_problem(x_min_cm: float, x_max_cm: float, w1_cm: float, x_start_cm: float | None = None,
                 names: tuple[str, str, str] = ("x_min", "x_max", "x_start")) -> str | None:
    """What is wrong with a task's band, or None (docs/commissioning.md, "What it needs"): x_min
    below x_max, the band wider than 2 w1 (eq. 14: no reference keeps w1 inside a narrower one),
    and x_start, where given, inside the band less w1, where the reference can run. `names`
    are how the caller calls x_min, x_max and x_start (pmactl: its options)."""
    n_min, n_max, n_start = names
    if not x_min_cm < x_max_cm:
        return f"{n_min} {x_min_cm:g} cm must be below {n_max} {x_max_cm:g} cm"
    if not x_max_cm - x_min_cm > 2.0 * w1_cm:
        return (f"the band {x_min_cm:g}..{x_max_cm:g} cm is not wider than 2 w1 = {2.0 * w1_cm:g} cm (eq. 14): "
                "no reference keeps w1 inside it")
    if x_start_cm is not None and not x_min_cm + w1_cm <= x_start_cm <= x_max_cm - w1_cm:
        return (f"{n_start} {x_start_cm:g} cm is outside {x_min_cm + w1_cm:g}..{x_max_cm - w1_cm:g} cm: the band "
                f"{x_min_cm:g}..{x_max_cm:g} cm less w1 = {w1_cm:g} cm")
    return None


@dataclass
class Measured:
    polarity_measured: int              # sign of dx/dp
    noise_cm: float                     # the position's noise [cm, 1 sigma]: at rest, at least resolution_cm / sqrt(12)
    static_map: StaticMap
    steps: list[StepFit]
    period_s: float
    kpa_per_u: float
    p_min_kpa: float
    p_max_kpa: float
    noise_rest_cm: float | None = None  # the standard deviation at rest as measured [cm]
    resolution_cm: float = 0.0          # one ADC count [cm] (adc.gain_cm_per_count); 0: not known


@dataclass
class Derivation:
    params: dict[str, float | int]
    figures: dict[str, float]
    margins: dict[str, float]
    promises: list[str] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)

    def as_dict(self) -> dict[str, Any]:
        return asdict(self)


_W = np.logspace(-2, 5, 20000)   # the frequency grid of the margins [rad/s]


def loop_margins(kc: float, ki: float, kd: float, gain: float, tau_s: float, theta_s: float) -> dict[str, float]:
    """Phase margin [deg], gain margin [-], crossover [rad/s] and delay margin [s] of the PID
    kc + kd s + ki / s on the FOPDT gain e^{-theta s} / (tau s + 1), on a frequency grid."""
    s = 1j * _W
    return _margins((kc + kd * s + ki / s) * gain * np.exp(-theta_s * s) / (tau_s * s + 1.0))


def law_margins(k_v: float, k_p: float, k_ff: float, fc_hz: float, gain: float, tau_s: float,
                theta_s: float, fu_hz: float = 0.0) -> dict[str, float]:
    """The margins (as loop_margins) of the paper's law in its small-signal form with the options
    commissioning sets (ppc.obs_pos, ppc.ref_vel: the law sees the tracking observer's position
    and velocity) on the FOPDT: u_law = K_v (K_p x_hat + v_hat), u = (1 + k_ff / s) u_law. The
    observer with both poles at -w_o = -2 pi fc passes the position as (2 w_o s + w_o^2) / (s + w_o)^2
    and the velocity as s w_o^2 / (s + w_o)^2. Without it (fc infinite) this is loop_margins' PID
    K_v (K_p + k_ff) + K_v s + K_v K_p k_ff / s. With fu_hz > 0 the command goes through the
    low-pass ppc.u_lpf_hz, w_u / (s + w_u) with w_u = 2 pi fu. Units: k_v in input units per cm/s,
    k_p and k_ff in 1/s, fc_hz and fu_hz in Hz, gain in cm per input unit, tau_s and theta_s in s."""
    s = 1j * _W
    wo = 2.0 * math.pi * fc_hz
    h_x = (2.0 * wo * s + wo * wo) / (s + wo) ** 2
    h_v = s * wo * wo / (s + wo) ** 2
    law = k_v * (1.0 + k_ff / s) * (k_p * h_x + h_v)
    if fu_hz > 0.0:
        wu = 2.0 * math.pi * fu_hz
        law = law * wu / (s + wu)
    return _margins(law * gain * np.exp(-theta_s * s) / (tau_s * s + 1.0))


def law_noise_rate(k_v: float, k_p: float, k_ff: float, fc_hz: float, period_s: float, noise_cm: float,
                   fu_hz: float = 0.0) -> float:
    """The mean |du/dt| [input units per s] that white position noise of standard deviation
    noise_cm [cm] puts on the law's input u, ticked at period_s: the firmware's tracking observer
    (pma/velest.h: both poles at exp(-2 pi fc T)) feeding the law's small-signal form with the
    options commissioning sets (law_margins: u_law = K_v (K_p x_hat + v_hat), u = u_law plus its
    integral at k_ff). With h the impulse response from x to u, a tick's change of u has the
    standard deviation noise_cm ||h_k - h_{k-1}||, and a Gaussian's mean magnitude is sqrt(2 / pi)
    of that. With fu_hz > 0, u through the command's low-pass as the firmware runs it (pma/lpf.h:
    y += (1 - exp(-2 pi fu T)) (u - y)). Units as law_margins'."""
    p = math.exp(-2.0 * math.pi * fc_hz * period_s)
    ga, gb = 1.0 - p * p, (1.0 - p) ** 2
    k_u = -math.expm1(-2.0 * math.pi * fu_hz * period_s) if fu_hz > 0.0 else 1.0
    # until the observer's and the low-pass' responses have decayed (below 1e-9; the integral's part
    # decays with them)
    n = int(math.ceil(30.0 / min(1.0 - p, k_u))) + 8
    x_hat = v_hat = u_ff = y = 0.0
    u = np.empty(n)
    for k in range(n):
        r = (1.0 if k == 0 else 0.0) - (x_hat + period_s * v_hat)
        x_hat += period_s * v_hat + ga * r
        v_hat += gb / period_s * r
        u_law = k_v * (k_p * x_hat + v_hat)
        u_ff += k_ff * period_s * u_law
        y += k_u * (u_law + u_ff - y)
        u[k] = y
    du = np.diff(u, prepend=0.0)
    return math.sqrt(2.0 / math.pi) * noise_cm * float(np.sqrt(np.sum(du * du))) / period_s


def _margins(loop: np.ndarray) -> dict[str, float]:
    w = _W
    mag = np.abs(loop)
    phase = np.unwrap(np.angle(loop))
    cross = np.nonzero((mag[:-1] >= 1.0) & (mag[1:] < 1.0))[0]
    if len(cross) == 0:
        return {"phase_margin_deg": math.nan, "gain_margin": math.nan, "crossover_rad_s": math.nan,
                "delay_margin_s": math.nan}
    i = int(cross[-1])
    wc = float(w[i])
    pm = float(math.degrees(phase[i]) + 180.0)
    while pm > 180.0:
        pm -= 360.0
    pc = np.nonzero((phase[:-1] > -math.pi) & (phase[1:] <= -math.pi))[0]
    gm = float(1.0 / mag[int(pc[0])]) if len(pc) else math.inf
    return {"phase_margin_deg": pm, "gain_margin": gm, "crossover_rad_s": wc,
            "delay_margin_s": math.radians(pm) / wc if wc > 0 else math.nan}


def mfac_phi1(ki_per_tick: float, rho: float = MFAC_RHO, lam: float = MFAC_LAMBDA) -> float:
    """MFAC's phi(1) whose step gain rho phi / (lambda + phi^2) equals the given integral gain
    per tick (the smaller root: MFAC starts gentle; at most sqrt(lambda), its largest gain)."""
    if ki_per_tick <= 0:
        raise CommissionError("the integral gain must be positive")
    disc = rho * rho - 4.0 * ki_per_tick * ki_per_tick * lam
    if disc <= 0:
        return math.sqrt(lam)
    return (rho - math.sqrt(disc)) / (2.0 * ki_per_tick)


def _integral_loop_keeps_margins(k_per_s: float, tau_s: float, theta_s: float) -> bool:
    """Whether the loop K e^{-theta s} / (s (tau s + 1)) keeps PM_MIN_DEG and GM_MIN."""
    mg = loop_margins(0.0, k_per_s, 0.0, 1.0, tau_s, theta_s)
    return mg["phase_margin_deg"] >= PM_MIN_DEG and mg["gain_margin"] >= GM_MIN


def integral_loop_gain_max(tau_s: float, theta_s: float) -> float:
    """The largest integral loop gain K [1/s] that keeps PM_MIN_DEG and GM_MIN on the FOPDT:
    bisection on the margins, which fall as K rises (0.1 1/s, the bisection's floor, where
    none does)."""
    lo, hi = 0.1, 1e4            # within loop_margins' frequency grid (from 0.01 rad/s)
    if not _integral_loop_keeps_margins(lo, tau_s, theta_s):
        return lo
    for _ in range(60):
        mid = math.sqrt(lo * hi)
        lo, hi = (mid, hi) if _integral_loop_keeps_margins(mid, tau_s, theta_s) else (lo, mid)
    return lo


@dataclass
class MfacGains:
    phi1: float
    lam: float
    k_loop_per_s: float          # the integral loop gain rho g^2 / ((lambda + g^2) T) at phi = g
    margins: dict[str, float]    # that loop's, on the measured FOPDT
    margins_kept: bool           # PM_MIN_DEG and GM_MIN hold (false only on a lag too long for any K)


def mfac_gains(gain: float, tau_s: float, theta_eff_s: float, period_s: float, ki_per_tick: float) -> MfacGains:
    """MFAC on the measured FOPDT. Its phi estimates dy/du and settles, for inputs slower than
    the lag, near the measured gain g; with phi = g its step is an integral controller of
    rho g / (lambda + g^2) per tick, the loop's integral gain K = rho g^2 / ((lambda + g^2) T).
    lambda: the paper's, unless that K would cost PM_MIN_DEG or GM_MIN on the measured lag and
    dead time; then just large enough for the largest K that keeps them (the margins returned
    are the loop's at phi = g). phi(1): the smaller root that gives MFAC's first steps the PI's
    integral gain ki_per_tick (mfac_phi1, with that lambda)."""
    if gain <= 0 or period_s <= 0:
        raise CommissionError("the gain and the period must be positive")
    k_max = integral_loop_gain_max(tau_s, theta_eff_s)
    g2 = gain * gain
    lam = max(MFAC_LAMBDA, MFAC_RHO * g2 / (k_max * period_s) - g2)
    k = MFAC_RHO * g2 / ((lam + g2) * period_s)
    return MfacGains(phi1=mfac_phi1(ki_per_tick, lam=lam), lam=lam, k_loop_per_s=k,
                     margins=loop_margins(0.0, k / gain, 0.0, gain, tau_s, theta_eff_s),
                     # k <= k_max by construction (to rounding), and the margins fall as K rises
                     margins_kept=_integral_loop_keeps_margins(k_max, tau_s, theta_eff_s))


@dataclass
class _Shape:
    tau_c: float
    kc: float
    tau_i: float
    ki: float
    k_p: float
    k_v: float
    margins: dict[str, float]


def _shape(gain: float, tau: float, theta_eff: float, tau_c_per_theta: float) -> _Shape:
    """SIMC's PI for the FOPDT (gain, tau, theta_eff) with tau_c = tau_c_per_theta * theta_eff,
    in the paper's law's small-signal form K_v ((1 + r) K_p + s + r K_p^2 / s), k_ff = r K_p:
    the PI's Kc and Ki, and a derivative K_v r + 1 times smaller than Kc / K_p; with the
    margins of that PID on the FOPDT (without the observer: its crossover places the observer)."""
    # at most SPEEDUP_MAX times faster than the open loop's lag: a step response with next to no
    # dead time (a valve whose small steps answer at once) must not ask for an unbounded gain
    tau_c = max(tau_c_per_theta * theta_eff, tau / SPEEDUP_MAX)
    kc = tau / (gain * (tau_c + theta_eff))
    tau_i = min(tau, 4.0 * (tau_c + theta_eff))
    r = FF_PER_KP
    k_p = (1.0 + r) / (r * tau_i)
    k_v = kc / ((1.0 + r) * k_p)
    margins = loop_margins(k_v * (1.0 + r) * k_p, k_v * r * k_p * k_p, k_v, gain, tau, theta_eff)
    return _Shape(tau_c=tau_c, kc=kc, tau_i=tau_i, ki=kc / tau_i, k_p=k_p, k_v=k_v, margins=margins)


def _observer_hz(shape: _Shape, theta_eff: float, period_s: float) -> float:
    """The velocity observer's bandwidth: FC_PER_CROSSOVER x the crossover of the shape's loop
    without it, within FC_MIN_HZ..FC_MAX_HZ and below the tick's Nyquist frequency."""
    wc = shape.margins["crossover_rad_s"]
    if not math.isfinite(wc):
        wc = 1.0 / (shape.tau_c + theta_eff)
    return min(max(FC_PER_CROSSOVER * wc / (2.0 * math.pi), FC_MIN_HZ), FC_MAX_HZ, 0.4 / period_s)


def _shaped(gain: float, tau: float, theta_eff: float, fc_hz: float,
            tau_c_per_theta: float, fu_per_fc: float = 0.0) -> tuple[_Shape, dict[str, float]]:
    """_shape with the observer at fc_hz: the shape and the margins of the law's loop as built
    (law_margins)."""
    shape = _shape(gain, tau, theta_eff, tau_c_per_theta)
    return shape, law_margins(shape.k_v, shape.k_p, FF_PER_KP * shape.k_p, fc_hz, gain, tau, theta_eff,
                              fu_per_fc * fc_hz)


def _keeps_margins(margins: dict[str, float]) -> bool:
    return margins["phase_margin_deg"] >= PM_MIN_DEG and margins["gain_margin"] >= GM_MIN


def _tightest_shape(gain: float, tau: float, theta_eff: float, period_s: float,
                    fu_per_fc: float = 0.0) -> tuple[_Shape, dict[str, float], float]:
    """The observer's bandwidth (_observer_hz of the tightest loop the rule allows, tau_c =
    TAU_C_PER_THETA_MIN theta_eff) and _tightest_at that bandwidth. Returns the shape, its margins
    as built and fc [Hz]."""
    fc_hz = _observer_hz(_shape(gain, tau, theta_eff, TAU_C_PER_THETA_MIN), theta_eff, period_s)
    return (*_tightest_at(gain, tau, theta_eff, fc_hz, fu_per_fc), fc_hz)


def _tightest_at(gain: float, tau: float, theta_eff: float, fc_hz: float,
                 fu_per_fc: float = 0.0) -> tuple[_Shape, dict[str, float]]:
    """The loop with the smallest tau_c / theta_eff in TAU_C_PER_THETA_MIN..MAX whose margins as
    built, with the observer at fc_hz, keep PM_MIN_DEG and GM_MIN (bisection: they grow as tau_c
    does); the most robust (TAU_C_PER_THETA_MAX) where none does. The shape and its margins as
    built."""
    tight = _shaped(gain, tau, theta_eff, fc_hz, TAU_C_PER_THETA_MIN, fu_per_fc)
    if _keeps_margins(tight[1]):
        return tight
    loose = _shaped(gain, tau, theta_eff, fc_hz, TAU_C_PER_THETA_MAX, fu_per_fc)
    if not _keeps_margins(loose[1]):
        return loose
    lo, hi = TAU_C_PER_THETA_MIN, TAU_C_PER_THETA_MAX
    for _ in range(12):          # to 0.1 % of the range
        mid = 0.5 * (lo + hi)
        shaped = _shaped(gain, tau, theta_eff, fc_hz, mid, fu_per_fc)
        if _keeps_margins(shaped[1]):
            hi, loose = mid, shaped
        else:
            lo = mid
    return loose


def _noise_rate(shape: _Shape, fc_hz: float, period_s: float, noise_cm: float,
                fu_per_fc: float = 0.0) -> float:
    return law_noise_rate(shape.k_v, shape.k_p, FF_PER_KP * shape.k_p, fc_hz, period_s, noise_cm,
                          fu_per_fc * fc_hz)


def _low_passed(unfiltered: tuple[_Shape, dict[str, float], float], rate_unfiltered: float, gain: float,
                tau: float, theta_eff: float, period_s: float, noise_cm: float,
                bound_u_per_s: float) -> tuple[tuple[_Shape, dict[str, float], float], float]:
    """The command's low-pass: none where the noise through the tightest loop without it
    (rate_unfiltered, input units per s) stays within bound_u_per_s (0: no bound); else the
    highest corner from FU_PER_FC_MAX x the observer's bandwidth down in steps of FU_STEP to
    FU_PER_FC_MIN x whose tightest loop, shaped with it (its lag in the margins), keeps the noise
    within the bound, the lowest where none does. Returns that tightest shape (as _tightest_shape)
    and the corner in units of the observer's bandwidth (0: none)."""
    if bound_u_per_s <= 0 or rate_unfiltered <= bound_u_per_s:
        return unfiltered, 0.0
    fu_per_fc = FU_PER_FC_MAX
    while True:
        tightest = _tightest_shape(gain, tau, theta_eff, period_s, fu_per_fc)
        rate = _noise_rate(tightest[0], tightest[2], period_s, noise_cm, fu_per_fc)
        if rate <= bound_u_per_s or fu_per_fc <= FU_PER_FC_MIN:
            return tightest, fu_per_fc
        fu_per_fc = max(fu_per_fc * FU_STEP, FU_PER_FC_MIN)


def _quiet_shape(tightest: tuple[_Shape, dict[str, float], float], gain: float, tau: float, theta_eff: float,
                 period_s: float, noise_cm: float, need_u_per_s: float,
                 limit: float | None, fu_per_fc: float = 0.0) -> tuple[_Shape, dict[str, float], float, float]:
    """From the tightest shape (_tightest_shape), with a limit (Task.noise_limit; None: none) and
    while the sensor's noise through that loop (law_noise_rate) moves the input more than limit x
    need_u_per_s (the rate the task's reference needs; 0: no bound), the observer FC_NOISE_STEP
    slower and _tightest_at it, down to FC_MIN_HZ but never to a bandwidth at which no loop keeps
    the margins (the noise does not buy back stability); the command's low-pass at fu_per_fc x the
    observer's bandwidth throughout (0: none). Returns the shape, its margins as built, fc [Hz] and
    the noise's rate [input units per s]."""
    shape, margins, fc_hz = tightest
    rate = _noise_rate(shape, fc_hz, period_s, noise_cm, fu_per_fc)
    while limit is not None and need_u_per_s > 0 and rate > limit * need_u_per_s and fc_hz > FC_MIN_HZ:
        fc_next = max(FC_NOISE_STEP * fc_hz, FC_MIN_HZ)
        shape_next, margins_next = _tightest_at(gain, tau, theta_eff, fc_next, fu_per_fc)
        if _keeps_margins(margins) and not _keeps_margins(margins_next):
            break
        shape, margins, fc_hz = shape_next, margins_next, fc_next
        rate = _noise_rate(shape, fc_hz, period_s, noise_cm, fu_per_fc)
    return shape, margins, fc_hz, rate


def _ref_span(task: Task, reach_lo: float, reach_hi: float) -> tuple[float, float]:
    """Where the reference feedforward's slope is measured: the reference's range within the
    reachable band, at least 4 w1 wide (a set-point task: around its start)."""
    lo = reach_lo if task.x_ref_min_cm is None else min(max(task.x_ref_min_cm, reach_lo), reach_hi)
    hi = reach_hi if task.x_ref_max_cm is None else min(max(task.x_ref_max_cm, reach_lo), reach_hi)
    lo, hi = min(lo, hi), max(lo, hi)
    half = 2.0 * task.w1_cm
    if hi - lo < 2.0 * half:
        mid = 0.5 * (lo + hi)
        lo, hi = max(reach_lo, mid - half), min(reach_hi, mid + half)
    return lo, hi


def _hysteresis_ff(m: Measured, xs: list[float], ref_ff: float) -> tuple[float, float, float]:
    """The reference feedforward's hysteresis term: its height H (ppc.ref_ff_hyst, input units),
    HYST_FF_PART of the half-width of the static map's loop, its median over the reference's range;
    the play's half-width b (ppc.ref_ff_hyst_cm): how far the muscle moves while the pressure
    crosses the loop after a reversal, the smallest step gain (a step into the dead band: the
    steps that raise the pressure after a settle from above) times half the loop's width, and at
    least what keeps the play within HYST_SLOPE_MAX times the static map's slope ref_ff [input
    units per cm]; and that width [kPa]."""
    h_kpa = float(np.median([m.static_map.hysteresis_kpa(x) for x in xs]))
    height = HYST_FF_PART * 0.5 * h_kpa / m.kpa_per_u
    g_dead = min(abs(s.gain_cm_per_kpa) for s in m.steps)
    gentle = height / (HYST_SLOPE_MAX * abs(ref_ff)) if ref_ff != 0.0 else 0.0
    return height, max(g_dead * 0.5 * h_kpa, gentle, HYST_PLAY_MIN_CM), h_kpa


def derive(m: Measured, task: Task) -> Derivation:
    """The parameters for the paper's controller and MFAC on this rig and task (module doc)."""
    if not m.steps:
        raise CommissionError("no step response")
    if task.w1_cm <= 0 or task.t_u_s <= 0 or task.x_min_cm >= task.x_max_cm:
        raise CommissionError("the task needs w1 > 0, t_u > 0 and x_min < x_max")
    if task.noise_limit is not None and not (math.isfinite(task.noise_limit) and task.noise_limit > 0):
        raise CommissionError(f"the noise limit {task.noise_limit} must be a number above 0")
    lo, hi = m.static_map.stroke_cm()
    band_lo, band_hi = task.x_min_cm + task.w1_cm, task.x_max_cm - task.w1_cm
    if band_hi <= lo or band_lo >= hi:
        raise CommissionError(f"the task's band {task.x_min_cm:g}..{task.x_max_cm:g} cm (minus w1) lies outside "
                              f"the measured stroke {lo:.3f}..{hi:.3f} cm")
    warnings: list[str] = []
    reach_lo, reach_hi = max(band_lo, lo), min(band_hi, hi)
    if reach_lo > band_lo or reach_hi < band_hi:
        warnings.append(f"only {reach_lo:.3f}..{reach_hi:.3f} cm of the band {band_lo:.3f}..{band_hi:.3f} cm "
                        "(the constraints minus w1) is within the measured stroke: references outside it "
                        "cannot be tracked")
    ref_lo = band_lo if task.x_ref_min_cm is None else task.x_ref_min_cm
    ref_hi = band_hi if task.x_ref_max_cm is None else task.x_ref_max_cm
    if ref_lo < band_lo or ref_hi > band_hi:
        warnings.append(f"the reference spans {ref_lo:.3f}..{ref_hi:.3f} cm, beyond the band less w1 ({band_lo:.3f}.."
                        f"{band_hi:.3f} cm): the paper's controller refuses START (BAND, eq. 14) while ppc.band_check "
                        "is 1; narrow the reference, widen the constraints or lower w1")
    polarity = 1 if m.polarity_measured > 0 else -1
    x_mid = 0.5 * (reach_lo + reach_hi)
    x_start = x_mid if task.x_start_cm is None else min(max(task.x_start_cm, reach_lo), reach_hi)
    if task.x_start_cm is not None and x_start != task.x_start_cm:
        warnings.append(f"x_start = {task.x_start_cm:g} cm is outside {reach_lo:.3f}..{reach_hi:.3f} cm (the band less "
                        f"w1 within the measured stroke): the start's holding input is taken at {x_start:.3f} cm")
    p0 = m.static_map.hold_kpa(x_mid)

    # the plant as the controller sees it: u in its unit, dx/du > 0 with the derived polarity. The
    # median of the six steps (three operating points, up and down): a step through the hysteresis'
    # dead band shows a late, slow response that is not the loop's. MFAC's rules take this gain
    gain = float(np.median([abs(s.gain_cm_per_kpa) for s in m.steps])) * m.kpa_per_u   # cm per input unit
    # each step's lag, or its early part's where that is shorter: a slow tail (creep, a slow valve
    # stage) fits as a long lag, but the loop's crossover meets the fast part, whose gain per second
    # is larger than the fit's g / tau (a design on the fit's lag runs the loop faster than it can go)
    lags = [min(s.tau_s, s.tau_early_s) if math.isfinite(s.tau_early_s) else s.tau_s for s in m.steps]
    # a step that moved less than MOVED_SIGMAS noise deviations (into the hysteresis' dead band) has a
    # gain but no lag to read: its fit is of the noise, often a lag of a sample or two, whose slope
    # g / tau would pass for the fastest step of all. It takes the lag of the steps that moved
    moved = [math.isfinite(s.first_move_s) for s in m.steps]
    moving_lags = [lag for lag, mv in zip(lags, moved) if mv]
    if moving_lags:
        lag_moving = float(np.median(moving_lags))
        lags = [lag if mv else lag_moving for lag, mv in zip(lags, moved)]
    tau = float(np.median(lags))
    tau_fit = float(np.median([s.tau_s for s in m.steps]))
    # the gain the law's loop is shaped on: the median of the steps' slopes g / tau (what its
    # crossover meets), times the median lag. The median gain over the median lag would pair one
    # step's gain with another's lag: where the steps into the dead band pull the median gain down
    # and the moving steps' lags are long, a loop faster than the moving steps allow
    slopes = [abs(s.gain_cm_per_kpa) / lag for s, lag in zip(m.steps, lags)]                    # cm/kPa/s
    loop_gain_median = float(np.median(slopes)) * tau * m.kpa_per_u                              # cm per input unit
    # ... and at least 1 / GM_MIN of the moving steps' own (their median slope): the steps into the
    # dead band, with next to no gain, pull the median of all down, and where half of them stayed
    # there the loop came out three times stiffer than the muscle moving along a branch and hunted
    # at 5 Hz from limit to limit. A loop that keeps GM_MIN as built stays stable up to GM_MIN
    # times the gain it was shaped on, so this keeps it stable where the muscle moves
    moving_slopes = [slope for slope, mv in zip(slopes, moved) if mv]
    moving_gain = float(np.median(moving_slopes)) * tau * m.kpa_per_u if moving_slopes else 0.0
    on_moving_steps = moving_gain / GM_MIN > loop_gain_median
    loop_gain = moving_gain / GM_MIN if on_moving_steps else loop_gain_median
    theta_fit = float(np.median([s.theta_s for s in m.steps]))
    # the fit's dead time, but never less than the steps' first movement: a response whose slow
    # tail (creep, a slow valve stage) dominates fits as a long lag with no dead time, though the
    # loop still waits that long for any answer, and too short a dead time is what costs margin
    moves = [s.first_move_s for s, mv in zip(m.steps, moved) if mv]
    theta_move = float(np.median(moves)) if moves else 0.0
    theta = max(theta_fit, theta_move)
    theta_eff = theta + m.period_s             # one sample of the loop's own delay

    def u_of(p_kpa: float) -> float:
        return polarity * (p_kpa - p0) / m.kpa_per_u
    # the reference feedforward: the static map's slope over the reachable band (the input per cm
    # that holds the muscle a cm further, a least-squares line through the holding inputs), taken
    # tau + theta ahead for the lag and dead time of the step responses
    xs = np.linspace(*_ref_span(task, reach_lo, reach_hi), 9)
    ref_ff = float(np.polyfit(xs, [u_of(m.static_map.hold_kpa(x)) for x in xs], 1)[0])
    # the loop's gain at least LOOP_GAIN_PER_MAP_MIN of the static map's: below it, most of the steps
    # stayed in the hysteresis' dead band, and a loop shaped on them is that much too stiff wherever
    # the muscle moves along a branch
    map_gain = 1.0 / abs(ref_ff) if ref_ff != 0.0 else 0.0
    if loop_gain < LOOP_GAIN_PER_MAP_MIN * map_gain:
        warnings.append(f"the step responses' gain {loop_gain:.3g} cm per input unit is below "
                        f"{LOOP_GAIN_PER_MAP_MIN:g} of the static map's {map_gain:.3g}: most steps stayed in the "
                        "hysteresis' dead band (a large friction); the loop is shaped on that part of the map's gain")
        loop_gain = LOOP_GAIN_PER_MAP_MIN * map_gain
        on_moving_steps = False
    # the input's mean rate that the reference needs, against which the sensor's noise through the
    # law is weighed (CHATTER_WARN_PER_NEED, Task.noise_limit)
    mean_speed = 2.0 / math.pi * task.speed_cm_s if task.mean_speed_cm_s is None else task.mean_speed_cm_s
    need_rate = abs(ref_ff) * mean_speed
    # the tightest tau_c that keeps the margins. Those that decide are the loop's as built, with the
    # velocity observer in it (its lag at the crossover costs about 14 deg and a third of the gain
    # margin): shaped on the PID's margins alone, every loop kept about 35 deg and 1.5 as built,
    # and on mas10-itv2050 with a valve that waits 45 / 80 ms (fill / exhaust) the law hunted at
    # 4 Hz and lost the guarantee (docs/commissioning.md, "The rules"). The observer as fast as
    # those margins want, unless the user bounds what the sensor's noise through it may move the
    # input (Task.noise_limit)
    # The command's low-pass where the noise needs it: where through the tightest loop without it
    # the sensor's noise would move the input more than the noise limit times what the reference
    # needs (by default CHATTER_WARN_PER_NEED, where the report would warn of chatter). Its lag
    # loosens the loop a little (the margins include it), so where the noise is below that the
    # loop goes without it and loses nothing
    warn_at = CHATTER_WARN_PER_NEED if task.noise_limit is None else task.noise_limit
    unfiltered = _tightest_shape(loop_gain, tau, theta_eff, m.period_s, fu_per_fc=0.0)
    rate_unfiltered = _noise_rate(unfiltered[0], unfiltered[2], m.period_s, m.noise_cm, 0.0)
    tightest, fu_per_fc = _low_passed(unfiltered, rate_unfiltered, loop_gain, tau, theta_eff, m.period_s,
                                      m.noise_cm, warn_at * need_rate)
    shape, with_observer, fc_hz, noise_rate = _quiet_shape(tightest, loop_gain, tau, theta_eff, m.period_s,
                                                          m.noise_cm, need_rate, task.noise_limit, fu_per_fc)
    if not _keeps_margins(with_observer):
        warnings.append(f"no loop keeps a phase margin of {PM_MIN_DEG:g} deg and a gain margin of {GM_MIN:g} on the "
                        "measured lag: the most robust one is used (see its margins)")
    tau_c, kc, tau_i, r, k_p, k_v, margins = (shape.tau_c, shape.kc, shape.tau_i, FF_PER_KP,
                                             shape.k_p, shape.k_v, shape.margins)
    a = 2.0 * task.w1_cm * k_p / math.pi
    w2 = W2_PER_A * a
    c = 2.0 * w2 * w2 * k_v / math.pi
    u_lo, u_hi = sorted((u_of(m.p_min_kpa), u_of(m.p_max_kpa)))
    # the start's holding input, on the path the muscle takes there. ARM raises the pressure from
    # vented to p0, so the armed muscle rests on the rising branch (x_armed); a start further along
    # that branch (dx/dp has the sign of the polarity) is reached by raising the pressure still, and
    # held by the rising branch's pressure. The middle of the branches there is a pressure below
    # the path: the muscle drifts the wrong way while the tuning function still holds the law's
    # gain low, and on a slow valve the law met its barrier, swung from limit to limit and handed
    # over to MFAC (docs/commissioning.md, "The rules"). A start back from x_armed reverses onto a
    # minor loop between the branches, whose middle stays the best guess
    x_armed = m.static_map.rising_x_cm(p0)
    start_on_rise = (x_start - x_armed) * polarity > 0
    p_start = m.static_map.rising_kpa(x_start) if start_on_rise else m.static_map.hold_kpa(x_start)
    u_start = u_of(p_start)
    # MFAC's first steps at the integral gain of the tightest loop: the noise limit and the command's
    # low-pass are the paper's law's, and MFAC has neither
    mfac_ki = unfiltered[0].ki
    mfac = mfac_gains(gain, tau, theta_eff, m.period_s, mfac_ki * m.period_s)
    ref_ff_lead = tau + theta_eff
    hyst_ff, hyst_cm, hyst_kpa = _hysteresis_ff(m, [float(x) for x in xs], ref_ff)
    hyst_max = 0.5 * hyst_kpa / m.kpa_per_u   # the static loop's half-width: no minor loop is wider
    ff_gain = r * k_p                         # the feedforward integrator's gain [1/s]

    w1_min = NOISE_SIGMAS_IN_W1 * m.noise_cm
    promises = [f"|e| < w1 = {task.w1_cm:g} cm needs w1 >= {w1_min:.4f} cm for this sensor's noise "
                f"({NOISE_SIGMAS_IN_W1:g} x {m.noise_cm:.5f} cm)"]
    v_max = task.w1_cm / (2.0 * (tau_c + theta_eff))
    promises.append(f"the loop's lag tau_c + theta = {1000 * (tau_c + theta_eff):.1f} ms: w1 holds for references "
                    f"slower than about {v_max:.2f} cm/s")
    t_u_min = 4.0 * (tau_c + theta_eff)
    if task.w1_cm < w1_min:
        warnings.append(f"the requested w1 = {task.w1_cm:g} cm is below what the noise allows ({w1_min:.4f} cm): "
                        "the guarantee cannot hold; ask for a larger w1 or filter the sensor")
    if task.speed_cm_s > v_max:
        warnings.append(f"the reference's speed {task.speed_cm_s:g} cm/s exceeds {v_max:.2f} cm/s: expect |e| "
                        "near w1 and a loss of the guarantee (the fallback to MFAC takes over)")
    if need_rate > 0 and noise_rate > warn_at * need_rate:
        warnings.append(f"the sensor's noise ({m.noise_cm:.5f} cm) moves the input {noise_rate:.1f} units/s "
                        f"with the observer at {fc_hz:.3g} Hz, over {warn_at:g}x what the reference needs "
                        f"({need_rate:.1f} units/s): expect the valve to chatter; "
                        + ("--noise-limit bounds it, at some accuracy, or " if task.noise_limit is None
                           else "that is already the slowest observer the margins allow; ")
                        + "a finer or quieter sensor")
    if not mfac.margins_kept:
        warnings.append(f"MFAC's integral loop keeps no phase margin of {PM_MIN_DEG:g} deg and gain margin of "
                        f"{GM_MIN:g} on the measured lag (its margins are printed): expect it to hunt")
    if task.t_u_s < t_u_min:
        warnings.append(f"t_u = {task.t_u_s:g} s is shorter than 4 (tau_c + theta) = {t_u_min:.3f} s: the error may "
                        "not have entered the band by then")
    # the large-signal side of t_u: the funnel asks the loop to cover the distance from the armed
    # muscle (x_armed, above) to the reference's start within t_u, and it follows about v_max
    e0 = math.nan if task.x_start_cm is None else abs(task.x_start_cm - x_armed)
    t_u_travel = e0 / v_max if v_max > 0 else math.inf
    if task.x_start_cm is not None and task.t_u_s < t_u_travel:
        warnings.append(f"the armed muscle rests about {e0:.2f} cm from where the reference starts (the rising branch "
                        f"at act.p0_kpa {p0:.0f} kPa: {x_armed:.3f} cm), and the loop follows about {v_max:.2f} cm/s: "
                        f"t_u = {task.t_u_s:g} s asks for it faster; expect the guarantee to be lost in the transient "
                        f"and MFAC to take over; ask t_u >= {t_u_travel:.1f} s (a floor: a slow valve's large "
                        "steps may need more)")
    hold_hyst = m.static_map.hysteresis_kpa(x_mid)
    params: dict[str, float | int] = {
        "act.polarity": polarity,
        "act.p0_kpa": round(p0, 2),
        "ctrl.u_min": round(u_lo, 2),
        "ctrl.u_max": round(u_hi, 2),
        "ppc.w1_cm": task.w1_cm,
        "ppc.t_u_s": task.t_u_s,
        "ppc.a_cm_s": round(a, 4),
        "ppc.w2_cm_s": round(w2, 4),
        "ppc.c": round(c, 4),
        "ppc.ff_gain_per_s": round(ff_gain, 3),
        "ppc.ff_init": round(u_start, 2),
        "ppc.ff_hold_speed_cm_s": round(v_max, 4),
        "ppc.ref_vel": 1,
        "ppc.ref_ff": round(ref_ff, 3),
        "ppc.ref_ff_lead_s": round(ref_ff_lead, 4),
        "ppc.ref_ff_hyst": round(hyst_ff, 3),
        "ppc.ref_ff_hyst_cm": round(hyst_cm, 4),
        "ppc.ref_ff_hyst_gain_per_s": round(HYST_ADAPT_PER_FF * ff_gain, 3) if hyst_max > 0.0 else 0.0,
        "ppc.ref_ff_hyst_max": round(hyst_max, 3),
        "ppc.obs_pos": 1,
        "vel.kind": 1,
        "vel.fc_hz": round(fc_hz, 2),
        "ppc.u_lpf_hz": round(fu_per_fc * fc_hz, 2),
        "mfac.eta": MFAC_ETA,
        "mfac.mu": MFAC_MU,
        "mfac.rho": MFAC_RHO,
        "mfac.lambda": round(mfac.lam, 5),
        "mfac.eps": float(f"{MFAC_EPS_PER_GAIN * gain:.3g}"),
        "mfac.phi1": round(mfac.phi1, 5),
        "mfac.u_init": round(u_start, 2),
        "safety.x_min_cm": task.x_min_cm,
        "safety.x_max_cm": task.x_max_cm,
    }
    figures = {"gain_cm_per_u": gain, "loop_gain_cm_per_u": loop_gain,
               "loop_gain_median_cm_per_u": loop_gain_median, "loop_gain_moving_cm_per_u": moving_gain,
               "loop_gain_on_moving_steps": float(on_moving_steps),
               "tau_s": tau, "tau_fit_s": tau_fit,
               "theta_s": theta, "theta_fit_s": theta_fit,
               "theta_first_move_s": theta_move, "theta_eff_s": theta_eff, "tau_c_s": tau_c,
               "noise_cm": m.noise_cm, "stroke_min_cm": lo, "stroke_max_cm": hi, "hysteresis_kpa_at_p0": hold_hyst,
               "hysteresis_kpa_over_ref": hyst_kpa,
               "kc_u_per_cm": kc, "tau_i_s": tau_i, "k_p_per_s": k_p, "k_v_u_per_cm_s": k_v, "w1_min_cm": w1_min,
               "v_max_cm_s": v_max, "t_u_min_s": t_u_min,
               "x_armed_cm": x_armed, "p_start_kpa": p_start, "start_on_rising_branch": float(start_on_rise),
               "t_u_travel_s": t_u_travel if math.isfinite(t_u_travel) else 0.0,
               "with_observer_phase_margin_deg": with_observer["phase_margin_deg"],
               "with_observer_gain_margin": with_observer["gain_margin"],
               "with_observer_delay_margin_s": with_observer["delay_margin_s"],
               "noise_input_rate_u_per_s": noise_rate, "need_input_rate_u_per_s": need_rate,
               "noise_input_rate_unfiltered_u_per_s": rate_unfiltered,
               "noise_limit": 0.0 if task.noise_limit is None else task.noise_limit,
               "mfac_k_loop_per_s": mfac.k_loop_per_s,
               "mfac_phase_margin_deg": mfac.margins["phase_margin_deg"],
               "mfac_gain_margin": mfac.margins["gain_margin"],
               "mfac_delay_margin_s": mfac.margins["delay_margin_s"]}
    return Derivation(params=params, figures=figures, margins=margins, promises=promises, warnings=warnings)
