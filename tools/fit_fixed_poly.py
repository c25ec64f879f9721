#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Reproduce the polynomial coefficients of firmware/control/src/fixed.c.

tan(pi r / 2) = r g(r^2) / (1 - r^2): g is smooth on [0, 1] (pi/2 at 0, 4/pi
at 1), so a low-degree polynomial fitted for *relative* error keeps the
relative error of tan uniform right up to the pole.
cos(pi s) = 1 + x Q(x), x = s^2 on |s| <= 1/2: cos(0) = 1 exactly.
Prints the coefficients, their fixed-point integers and the max errors.
"""
import numpy as np


def cheb_nodes(n: int, lo: float, hi: float) -> np.ndarray:
    return lo + (hi - lo) * (np.cos(np.pi * (np.arange(n) + 0.5) / n) * 0.5 + 0.5)


def tan_g(u: np.ndarray) -> np.ndarray:
    r = np.sqrt(u)
    out = np.full_like(u, np.pi / 2)
    nz = r > 1e-6
    out[nz] = np.tan(np.pi / 2 * r[nz]) * (1 - r[nz] ** 2) / r[nz]
    return out


def main() -> None:
    u = cheb_nodes(400, 0.0, 1.0)
    ut = np.linspace(0, 1 - 1e-9, 200001)
    for degree, use in ((3, "fixed.c, Q2.30"), (4, "trig_f32.c, float")):
        g = np.polynomial.polynomial.polyfit(u, tan_g(u), degree, w=1 / tan_g(u))
        rel = np.max(np.abs(np.polynomial.polynomial.polyval(ut, g) / tan_g(ut) - 1))
        print(f"tan g(u), degree {degree} ({use}): max relative error {rel:.3g}")
        for k, c in enumerate(g):
            print(f"  G{k} = {c:.16g}  Q2.30 {round(c * 2**30)}")

    x = cheb_nodes(600, 0.0, 0.25)
    a = np.stack([x**k for k in range(1, 5)], 1)
    q, *_ = np.linalg.lstsq(a, np.cos(np.pi * np.sqrt(x)) - 1, rcond=None)
    s = np.linspace(0, 0.5, 200001)
    approx = 1 + sum(q[k - 1] * (s * s) ** k for k in range(1, 5))
    print(f"cos(pi s): max abs error {np.max(np.abs(approx - np.cos(np.pi * s))):.3g}")
    for k, c in enumerate(q, start=1):
        print(f"  C{k} = {c:.16g}  Q4.28 {round(c * 2**28)}")


if __name__ == "__main__":
    main()
