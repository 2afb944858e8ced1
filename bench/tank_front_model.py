#!/usr/bin/env python3
"""Why per-compartment steps grew with the number of compartments, in a model.

One tank c of a chain of n tanks in series (rate k = n * 7.76e-3 / 0.38 per s, the CoriMix
case cut into n compartments), fed from t = 0 by the exact Erlang inflow k N_{c-1}(t),
N_{c-1} = (F/k) P(c, k t), integrated alone by the Cash-Karp pair with GSL's step rule
(rtol 1e-6, atol 1, outputs every second to 85 s) in three ways:
  held         u' = (G - g0) / phi: the integrating factor with the rates held at the
               step's start (gransim's `outflow: integrating_factor`);
  extrapolated the same with G's slope from the step before added to the frame
               (Krogstad's generalized integrating factor, first order);
  quadrature   y1 = e^{-kh} y0 + h sum_i b_i(-kh) G(t_i), the exponential quadrature of the
               inflow on the six Cash-Karp nodes, embedded in the five-node rule (what
               stepping the inflow's curve exactly achieves: gransim's `outflow: exponential`).
It prints the steps, rejected tries and evaluations of the middle tank for n = 64, 256, 1024,
and the worst error at the outputs against the exact (F/k) P(c + 1, k t).
The model has no record bound and no other mechanism; the figures it gives are in
docs/design-notes.md ("Per-compartment steps").  Needs python3-numpy only.
Usage: bench/tank_front_model.py
"""
import math

import numpy as np

C = np.array([0, 1 / 5, 3 / 10, 3 / 5, 1, 7 / 8])
A = [[], [1 / 5], [3 / 40, 9 / 40], [3 / 10, -9 / 10, 6 / 5], [-11 / 54, 5 / 2, -70 / 27, 35 / 27],
     [1631 / 55296, 175 / 512, 575 / 13824, 44275 / 110592, 253 / 4096]]
B5 = np.array([37 / 378, 0, 250 / 621, 125 / 594, 0, 512 / 1771])
B4 = np.array([2825 / 27648, 0, 18575 / 48384, 13525 / 55296, 277 / 14336, 1 / 4])
XG, WG = np.polynomial.legendre.leggauss(30)
XG, WG = (XG + 1) / 2, WG / 2


def erlang_p(j, x):
    """P(j, x) for integer j: 1 - e^{-x} sum_{i<j} x^i / i!, summed in logs."""
    if x <= 0:
        return 0.0
    lx = math.log(x)
    q = sum(math.exp(i * lx - x - math.lgamma(i + 1)) for i in range(j))
    return max(0.0, 1.0 - q)


def exp_weights(z, nodes):
    """b_i(z) = int_0^1 e^{z (1 - s)} l_i(s) ds, l_i the Lagrange basis on the nodes."""
    out = []
    for i, ci in enumerate(nodes):
        li = np.ones_like(XG)
        for m, cm in enumerate(nodes):
            if m != i:
                li *= (XG - cm) / (ci - cm)
        out.append(np.sum(WG * np.exp(z * (1 - XG)) * li))
    return np.array(out)


def run(n, c, way, rtol=1e-6, atol=1.0, F=7e8, T=85):
    k = n * 7.76e-3 / 0.38
    G = lambda t: F * erlang_p(c, k * t)  # the inflow k N_{c-1}
    t, y, h, steps, rejected, evals = 0.0, 0.0, 1e-3, 0, 0, 0
    g_prev, worst = None, 0.0
    for t_out in range(1, T + 1):
        while t < t_out - 1e-12:
            hh = min(h, t_out - t)
            g0 = G(t)
            slope = (g0 - g_prev[1]) / (t - g_prev[0]) if way == "extrapolated" and g_prev else 0.0
            while True:
                E = math.exp(-k * hh)
                if way == "quadrature":
                    g = np.array([G(t + ci * hh) for ci in C])
                    y1 = E * y + hh * exp_weights(-k * hh, C) @ g
                    err = abs(y1 - (E * y + hh * exp_weights(-k * hh, C[[0, 1, 2, 3, 5]]) @ g[[0, 1, 2, 3, 5]]))
                else:
                    K = []
                    for i in range(6):
                        tau = C[i] * hh
                        K.append((G(t + tau) - g0 - slope * tau) * math.exp(k * tau))
                    u5 = y + hh * np.dot(B5, K)
                    # y = phi u + psi g0 + slope (tau - psi) / k
                    psi = -math.expm1(-k * hh) / k
                    y1 = E * u5 + psi * g0 + slope * (hh - psi) / k
                    err = E * abs(hh * np.dot(B5 - B4, K))
                evals += 6
                r = err / (rtol * abs(y1) + atol)
                if r > 1.1:
                    hh *= max(0.2, 0.9 / r ** (1 / 5))
                    rejected += 1
                    continue
                break
            g_prev = (t, g0)
            t, y = t + hh, y1
            steps += 1
            if r < 0.5:
                h = hh * max(1.0, min(5.0, 0.9 / max(r, 1e-300) ** (1 / 6)))
            elif hh >= h:
                h = hh
        worst = max(worst, abs(y - F / k * erlang_p(c + 1, k * t)) / (F / k))
    return steps, rejected, evals, worst


def main():
    print("one tank in the middle of n tanks in series, Cash-Karp, rtol 1e-6 (steps / rejected / evaluations; worst error at the outputs, of F/k)")
    for n in (64, 256, 1024):
        row = []
        for way in ("held", "extrapolated", "quadrature"):
            s, rj, ev, e = run(n, n // 2, way)
            row.append(f"{way} {s} / {rj} / {ev} ({e:.1e})")
        print(f"  n = {n:4d}: " + "; ".join(row))


if __name__ == "__main__":
    main()
