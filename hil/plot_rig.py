# SPDX-License-Identifier: Apache-2.0
"""Figures and tables of the simulated rig for docs/rig.md.

    .venv/bin/python hil/plot_rig.py [--out docs/img] [--no-plots]

Writes docs/img/rig_static.png (static x(p) with the hysteresis loop) and
docs/img/rig_steps.png (open-loop pressure steps from p0), and prints the tables
of docs/rig.md (calibrated values, static points, step-response figures). Runs in
about a minute. Everything is simulated with the default RigParams (noise off for
the figures' curves); nothing here changes the rig.
"""

from __future__ import annotations

import argparse
import os
from typing import Any

import numpy as np

from hil.rig import Rig, RigParams
from hil.rig_params import calibrate_mas10

STEPS_KPA = (25, 50, 100, -50, -100)
T_PRE, T_POST, DT = 0.1, 1.5, 0.001


def quiet(params: RigParams) -> RigParams:
    params.sensor.noise_cm = 0.0
    params.sensor.adc_noise_counts = 0.0
    return params


def step_response(dp: float, hyst: bool) -> dict[str, np.ndarray]:
    p = quiet(RigParams())
    if not hyst:
        p.muscle.hyst_force_n = 0.0
    rig = Rig(p, seed=0)
    c0, c1 = rig.kpa_to_dac(p.p0_kpa), rig.kpa_to_dac(p.p0_kpa + dp)
    n_pre, n = int(round(T_PRE / DT)), int(round((T_PRE + T_POST) / DT))
    t, x, pr = np.empty(n), np.empty(n), np.empty(n)
    for k in range(n):
        rig.apply_dac(c0 if k < n_pre else c1)
        rig.step(DT)
        t[k], x[k], pr[k] = rig.time_s - T_PRE, rig.x_cm, rig.p_kpa
    return {"t": t, "x": x, "p": pr}


def step_metrics(t: np.ndarray, y: np.ndarray, y0: float) -> dict[str, float]:
    """Dead time (2 %), 10-90 % rise time, time to 63 %, overshoot, 5 % settling,
    all from the step at t = 0, relative to the final value (end of the record)."""
    d = y[-1] - y0
    r = (y - y0) / d
    after = t >= 0
    tt, rr = t[after], r[after]
    def first(cond: np.ndarray) -> float:
        return float(tt[np.argmax(cond)]) if np.any(cond) else float("nan")
    outside = np.nonzero(np.abs(rr - 1.0) > 0.05)[0]
    return {
        "final": float(d),
        "dead_s": first(np.abs(rr) > 0.02),
        "t63_s": first(rr >= 0.632),
        "rise_s": first(rr >= 0.9) - first(rr >= 0.1),
        "overshoot_pct": float(max(0.0, rr.max() - 1.0) * 100.0),
        "settle5_s": float(tt[outside[-1]]) if len(outside) else 0.0,
    }


def staircase_loop(p_lo: float, p_hi: float, dp: float, hold_s: float) -> tuple[np.ndarray, np.ndarray]:
    """Quasi-static hysteresis loop: pressure staircase up then down, x at the end of each hold."""
    rig = Rig(quiet(RigParams()), seed=0)
    levels = list(np.arange(p_lo, p_hi + 1e-9, dp)) + list(np.arange(p_hi - dp, p_lo - 1e-9, -dp))
    # approach p_lo from below so that the loop starts on its rising branch
    for p in np.linspace(rig.params.p0_kpa, 0.0, 10).tolist() + [p_lo]:
        rig.apply_pressure_kpa(p)
        rig.step(hold_s)
    ps, xs = [], []
    for p in levels:
        rig.apply_pressure_kpa(p)
        rig.step(hold_s)
        ps.append(rig.p_cmd_kpa)
        xs.append(rig.x_cm)
    return np.array(ps), np.array(xs)


def table_calibration(rig: Rig) -> str:
    cal = calibrate_mas10()
    m, r, s, ld = rig.params.muscle, rig.params.regulator, rig.params.sensor, rig.params.load
    rows = [
        ("F0", f"{m.f0_n:.2f} N", "Martens & Boblan 2017: line through 283.8 N @ 360 kPa and 542.5 N @ 650 kPa"),
        ("F1", f"{m.f1_n_per_kpa:.4f} N/kPa", "same"),
        ("K scale", f"{cal['k_scale']:.4f}", "K(650) = 542.5 N / (21 % x 100 mm) = 25.83 N/mm over Serres's K(650) = 28.64 N/mm"),
        ("K0, K1 (P < 314 kPa)", f"{m.k0_low_n_per_mm:.3f} N/mm, {m.k1_low_n_per_mm_kpa:.5f} N/(mm kPa)", "Serres 2009 32.7 - 0.0321 P, x scale"),
        ("K0, K1 (P > 314 kPa)", f"{m.k0_high_n_per_mm:.3f} N/mm, {m.k1_high_n_per_mm_kpa:.5f} N/(mm kPa)", "Serres 2009 17 + 0.0179 P, x scale"),
        ("B contracting", f"{m.b_contract_ns_per_mm:.3f} N s/mm", "Serres 2009 2.90, x scale (keeps B/K)"),
        ("B relaxing", f"{m.b_relax_ns_per_mm:.3f} N s/mm", "Serres 2009 1.57, x scale"),
        ("hysteresis", f"{m.hyst_force_n:.1f} N x (1 - exp(-F(P)/{m.hyst_ramp_n:.0f} N))", "loop width 16 % of stroke at 300 kPa with 2.55 kg (Appl. Sci. 2021)"),
        ("load m0", f"{ld.mass_kg:.2f} kg, hanging", "the hysteresis source's test load (the paper gives none)"),
        ("regulator", f"0-{r.p_max_kpa:.0f} kPa, tau {r.tau_s * 1e3:.0f} ms, dead {r.dead_time_s * 1e3:.0f} ms, lin {r.linearity_frac_fs * 100:.1f} % FS, hyst {r.hysteresis_frac_fs * 100:.1f} % FS", "SMC ITV2050 (controller.md)"),
        ("sensor", f"{s.span_cm:.0f} cm span, {s.i_min_ma:.0f}-{s.i_max_ma:.0f} mA, out of range {s.out_of_range_ma:.0f} mA, noise {s.noise_cm * 1e4:.0f} um", "Baumer OADM 20; firmware adc.* defaults"),
    ]
    out = ["| quantity | value | source |", "|---|---|---|"]
    out += [f"| {a} | {b} | {c} |" for a, b, c in rows]
    return "\n".join(out)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "docs", "img"))
    ap.add_argument("--no-plots", action="store_true")
    args = ap.parse_args()

    print("## Calibrated values\n")
    print(table_calibration(Rig(RigParams(), seed=0)))
    rig = Rig(quiet(RigParams()), seed=0)
    p0 = rig.params.p0_kpa

    print("\n## Equilibrium and the static curve (default rig)\n")
    lin = rig.linearised_eq7()
    print(f"p0 = {p0:.0f} kPa command -> {lin['p_kpa']:.1f} kPa actual (regulator linearity); "
          f"x0 = contraction {rig.x0_contraction_mm:.2f} mm = {rig.x0_contraction_mm / rig.params.muscle.length_mm * 100:.1f} % of 100 mm")
    print("\n| p command [kPa] | contraction [mm] | x [cm] | rising branch x [cm] | falling branch x [cm] |")
    print("|---|---|---|---|---|")
    for p in (0, 50, 100, 200, 300, 400, 500, 600, 700, 800, 900):
        xs = rig.static_xs_mm(rig.regulator_static_kpa(p))
        print(f"| {p} | {xs:.2f} | {rig.static_x_cm(p):+.3f} | {rig.static_x_cm(p, friction=1):+.3f} | {rig.static_x_cm(p, friction=-1):+.3f} |")
    print("\nPressure command holding x (static, no friction):")
    for x in (0.0, -0.5, -1.0, -1.5, -2.0, -2.5, -3.0):
        pc = rig.p_cmd_for_x_cm(x)
        print(f"  x = {x:+.1f} cm: " + (f"{pc:.0f} kPa" if pc is not None else "out of reach (0-900 kPa)"))
    # the p0 that lets the paper's references (down to x = -2.5 cm) be reached
    for p0_alt in (60.0, 65.0, 70.0, 100.0):
        alt = Rig(quiet(RigParams(p0_kpa=p0_alt)), seed=0)
        need = {x: alt.p_cmd_for_x_cm(x) for x in (-1.5, -2.0, -2.5)}
        txt = ", ".join(f"x={x:+.1f}: " + (f"{v:.0f} kPa" if v else "unreachable") for x, v in need.items())
        print(f"  with p0 = {p0_alt:.0f} kPa (x0 = {alt.x0_contraction_mm:.2f} mm contraction): {txt}")
    print("\nLinearised eq. 7 (x in cm, u in kPa):")
    for p in (100, 200, 300, 400, 600):
        L = rig.linearised_eq7(p)
        print(f"  p = {p} kPa: H = {L['H_cm_s2_per_kpa']:+.2f} cm/s^2/kPa, G = {L['G_1_s2']:.0f} 1/s^2, "
              f"D = {L['D_contract_1_s']:.0f} (contracting) / {L['D_relax_1_s']:.0f} (relaxing) 1/s, "
              f"gain {L['static_gain_cm_per_kpa']:+.5f} cm/kPa, B/K = {L['mechanical_time_constant_contract_s'] * 1e3:.0f} / {L['mechanical_time_constant_relax_s'] * 1e3:.0f} ms")

    print("\n## Open-loop steps from p0 (command step at t = 0, rig at rest at x = 0)\n")
    print("| step [kPa] | hysteresis | final dx [cm] | static dx [cm] | x dead time [ms] | x t63 [ms] | x rise 10-90 % [ms] | x overshoot [%] | x settling 5 % [ms] | p dead time [ms] | p t63 [ms] |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    responses = {}
    for hyst in (True, False):
        for dp in STEPS_KPA:
            rsp = step_response(dp, hyst)
            responses[(dp, hyst)] = rsp
            mx = step_metrics(rsp["t"], rsp["x"], 0.0)
            mp = step_metrics(rsp["t"], rsp["p"], rsp["p"][0])
            print(f"| {dp:+d} | {'on' if hyst else 'off'} | {mx['final']:+.4f} | {rig.static_x_cm(p0 + dp):+.4f} | "
                  f"{mx['dead_s'] * 1e3:.0f} | {mx['t63_s'] * 1e3:.0f} | {mx['rise_s'] * 1e3:.0f} | {mx['overshoot_pct']:.1f} | "
                  f"{mx['settle5_s'] * 1e3:.0f} | {mp['dead_s'] * 1e3:.1f} | {mp['t63_s'] * 1e3:.1f} |")

    loop_p, loop_x = staircase_loop(50.0, 850.0, 25.0, 1.0)
    up = loop_p[: len(loop_p) // 2 + 1]
    i300_up = int(np.argmin(np.abs(up - 300)))
    i300_dn = len(loop_p) - 1 - int(np.argmin(np.abs(loop_p[::-1] - 300)))
    print(f"\nQuasi-static loop (25 kPa steps held 1 s, 50-850-50 kPa): width at 300 kPa = "
          f"{abs(loop_x[i300_up] - loop_x[i300_dn]):.3f} cm (model: {abs(rig.static_x_cm(300, friction=1) - rig.static_x_cm(300, friction=-1)):.3f} cm muscle friction "
          f"+ regulator backlash)")

    if args.no_plots:
        return
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    os.makedirs(args.out, exist_ok=True)
    pp = np.linspace(0, 900, 451)
    fig, ax = plt.subplots(figsize=(8, 5.2))
    ax.axhspan(-3, 0, color="0.92", label="paper's band -3 < x < 0")
    ax.plot(pp, [rig.static_x_cm(p) for p in pp], "k-", lw=1.5, label="static x(p), no friction")
    ax.plot(pp, [rig.static_x_cm(p, friction=1) for p in pp], "b--", lw=1, label="rising branch (friction saturated)")
    ax.plot(pp, [rig.static_x_cm(p, friction=-1) for p in pp], "r--", lw=1, label="falling branch")
    ax.plot(loop_p, loop_x, "o-", color="tab:purple", ms=2.5, lw=0.7, label="simulated staircase 50-850-50 kPa")
    ax.plot([p0], [0.0], "ks", ms=7)
    ax.annotate(f"p0 = {p0:.0f} kPa, x0 = 0\n(contraction {rig.x0_contraction_mm:.1f} mm)", (p0, 0.0), (p0 + 40, 0.55),
                arrowprops={"arrowstyle": "->"})
    ax.axvline(800, color="0.6", ls=":", lw=1)
    ax.text(805, 1.0, "MAS-10 max\n800 kPa", fontsize=8, color="0.4")
    ax.set_xlabel("pressure command p [kPa]")
    ax.set_ylabel("x [cm] (contraction -> negative)")
    ax.set_ylim(-3.2, 1.6)
    ax.set_xlim(0, 900)
    length_mm = rig.params.muscle.length_mm

    def to_contraction(x: Any) -> Any:
        return (rig.x0_contraction_mm - 10 * x) / length_mm * 100

    def to_x(c: Any) -> Any:
        return (rig.x0_contraction_mm - c * length_mm / 100) / 10

    sec = ax.secondary_yaxis("right", functions=(to_contraction, to_x))
    sec.set_ylabel("contraction [% of 100 mm]")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="lower left")
    ax.set_title("Simulated MAS-10-100N, 2.55 kg hanging load: static x(p)")
    fig.tight_layout()
    fig.savefig(os.path.join(args.out, "rig_static.png"), dpi=110)
    plt.close(fig)

    fig, (a1, a2) = plt.subplots(2, 1, figsize=(8, 6.5), sharex=True)
    colors = dict(zip(STEPS_KPA, ["tab:blue", "tab:orange", "tab:green", "tab:red", "tab:purple"]))
    for (dp, hyst), rsp in responses.items():
        ls = "-" if hyst else "--"
        a1.plot(rsp["t"] * 1e3, rsp["p"] - p0, ls, color=colors[dp], lw=1, label=f"{dp:+d} kPa" if hyst else None)
        a2.plot(rsp["t"] * 1e3, rsp["x"], ls, color=colors[dp], lw=1)
    a1.set_ylabel("actual p - 300 kPa [kPa]")
    a1.legend(fontsize=8, ncol=5)
    a1.grid(alpha=0.3)
    a1.set_title("Open-loop command steps from p0 = 300 kPa (solid: hysteresis on, dashed: off)")
    a2.set_ylabel("x [cm]")
    a2.set_xlabel("time after the command step [ms]")
    a2.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(os.path.join(args.out, "rig_steps.png"), dpi=110)
    plt.close(fig)
    print(f"\nwrote {os.path.join(args.out, 'rig_static.png')} and rig_steps.png")


if __name__ == "__main__":
    main()
