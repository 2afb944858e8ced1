#!/usr/bin/python3
"""Compare Dyssol's agglomerator result with gransim's on the same grid.

Usage: compare.py DYSSOL_EXPORT GRANSIM_RESULT_H5 KERNEL BETA0

Dyssol exports the holdup's size distribution as mass fractions per class,
which its unit computes from its state, the number of particles per class
N_i, as N_i d_i^3 normalised, with d_i the mean of the class's edge
diameters (ConvertNumbersToMassFractions); its numbers are recovered here
by inverting that with the holdup's volume.  gransim's numbers are read from
result.h5.  Moments and distributions are then taken alike for both, at the
grid's pivots (cell midpoints in volume, where both codes evaluate the
kernel).  For the constant kernel the total number has a closed form
(Riccati: dM0/dt = F - M0/tau - beta0 M0^2 / 2), printed beside both.
"""
import math
import sys

import h5py
import numpy as np

MASS, DENSITY, FEED, TAU = 20.0, 1320.0, 0.003, 20.0 / 0.003  # the case (README.md)


def dyssol_psd(path, line_key):
    """{time: mass fractions} of the export line starting with line_key."""
    for line in open(path, encoding="utf-8"):
        if line.startswith(line_key):
            vals = [float(x) for x in line[len(line_key):].split()]
            out = {}
            for k in range(0, len(vals), 321):
                out[vals[k]] = np.array(vals[k + 1:k + 321])
            return out
    sys.exit(f"compare.py: {path}: no line starting with {line_key!r}")


def closed_form_m0(m00, feed, beta0, tau, t):
    """Total number at t in a well-mixed holdup with the constant kernel: the
    Riccati equation dM0/dt = feed - M0/tau - beta0 M0^2 / 2 from M0(0) = m00,
    through its two equilibria m+ > 0 > m-: (M0 - m+)/(M0 - m-) decays as
    exp(-beta0/2 (m+ - m-) t)."""
    b = beta0 / 2
    disc = math.sqrt(1 / tau ** 2 + 4 * feed * b)
    mp, mm = (-1 / tau + disc) / (2 * b), (-1 / tau - disc) / (2 * b)
    e = (m00 - mp) / (m00 - mm) * math.exp(-b * (mp - mm) * t)
    return (mp - e * mm) / (1 - e)


def d50_by_mass(edges, w):
    """Mass median diameter: mass fractions cumulated over the diameter edges, interpolated."""
    d = (6 * edges / math.pi) ** (1 / 3)
    cum = np.concatenate(([0.0], np.cumsum(w) / w.sum()))
    return float(np.interp(0.5, cum, d))


def main():
    res, h5, kernel, beta0 = sys.argv[1], sys.argv[2], sys.argv[3], float(sys.argv[4])
    with h5py.File(h5, "r") as f:
        edges = f["grid/solid/edges"][:]
        piv = f["grid/solid/pivots"][:]
        t_g = f["time"][:]
        n_g = f["number"][:, 0, :]
    vol = MASS / DENSITY
    dmean = ((6 * edges[:-1] / math.pi) ** (1 / 3) + (6 * edges[1:] / math.pi) ** (1 / 3)) / 2
    vd = math.pi / 6 * dmean ** 3  # Dyssol's particle volume of each class
    psd = dyssol_psd(res, 'HOLDUP_PSD "Agglomerator" "Holdup"')
    t_end = max(psd)
    if abs(t_end - t_g[-1]) > 1e-6 * t_end:
        sys.exit(f"compare.py: Dyssol ends at t = {t_end}, gransim at {t_g[-1]}")
    n_d0 = psd[min(psd)] * vol / vd
    n_d = psd[t_end] * vol / vd
    n_gend = n_g[-1]

    def moments(n):
        return [float(np.sum(n * piv ** p)) for p in (0, 1, 2)]

    md, mg = moments(n_d), moments(n_gend)
    # the two discretise the initial normal distribution differently: that part of the
    # difference is there before either solver takes a step
    m0d, m0g = moments(n_d0), moments(n_g[0])
    print(f"  at t = 0 (initial state as each code discretises it): gransim/Dyssol - 1 = "
          f"{m0g[0] / m0d[0] - 1:+.2e} (M0), {m0g[1] / m0d[1] - 1:+.2e} (M1), {m0g[2] / m0d[2] - 1:+.2e} (M2)")
    print(f"  at t = {t_end:g} s, moments at the pivots (M1 exact: {vol:.10g} m3, inflow = outflow):")
    print(f"    {'':4} {'Dyssol':>14} {'gransim':>14} {'gransim/Dyssol - 1':>19}")
    for p, (a, b) in enumerate(zip(md, mg)):
        print(f"    M{p}   {a:14.7g} {b:14.7g} {b / a - 1:+19.2e}")
    print(f"    M1 against the exact volume: Dyssol {md[1] / vol - 1:+.2e}, gransim {mg[1] / vol - 1:+.2e}")
    wd = n_d * piv / np.sum(n_d * piv)
    wg = n_gend * piv / np.sum(n_gend * piv)
    print(f"  PSD by mass at t = {t_end:g} s: total variation distance sum|w_D - w_g|/2 = "
          f"{0.5 * np.sum(np.abs(wd - wg)):.2e}, largest |w_D - w_g| = {np.max(np.abs(wd - wg)):.2e} "
          f"(largest fraction {max(wd.max(), wg.max()):.3g})")
    print(f"    d50 by mass: Dyssol {d50_by_mass(edges, wd) * 1e3:.5f} mm, gransim "
          f"{d50_by_mass(edges, wg) * 1e3:.5f} mm")
    if kernel == "constant":
        # the same closed form from each code's own start and feed (they discretise the
        # normal distributions differently)
        inflow = dyssol_psd(res, 'STREAM_PSD "In"')
        feed_d = float(np.sum(inflow[min(inflow)] * FEED / DENSITY / vd))
        print(f"  constant kernel, M0 against the closed form from each code's own M0(0) and feed:")
        for name, m00, feed, m0 in (("Dyssol", float(np.sum(n_d0)), feed_d, md[0]),
                                    ("gransim", float(np.sum(n_g[0])), feed_g(h5), mg[0])):
            exact = closed_form_m0(m00, feed, beta0, TAU, t_end)
            print(f"    {name:8} M0 {m0:.7g}, closed form {exact:.7g}: {m0 / exact - 1:+.2e} "
                  f"(M0(0) {m00:.7g}, feed {feed:.6g}/s)")


def feed_g(h5):
    """gransim's feed in particles per second: the discretisation report's third entry
    (number, volume of the initial state, then of the feed)."""
    with h5py.File(h5, "r") as f:
        return float(f["discretisation/represented"][2])


if __name__ == "__main__":
    main()
