#!/usr/bin/python3
"""Checks the plots `gransim plot` drew in a folder: each named figure exists
as a PNG of some substance and as an SVG whose text holds the given labels
verbatim (plain text: units in brackets, underscores as underscores); psd.csv,
the numbers of the size distribution, has Q3 rising to 1 and, for a sectional
run, the d50 of summary.csv in the class where Q3 crosses 1/2.
With --exponential MEAN RATIO (an exponential number distribution of solid
volume with mean MEAN, each particle carrying RATIO times its volume) Q3 at
the class edges must follow the closed form of its volume-weighted
distribution, Q3(s) = 1 - (1 + s/MEAN) exp(-s/MEAN), s = pi d^3 / (6 (1 + RATIO)).
Usage: plot_check.py PLOTS_DIR [--d50 SUMMARY.csv] [--exponential MEAN RATIO] NAME=LABEL|LABEL... ..."""
import sys

import numpy as np
import pandas as pd


def fail(msg):
    sys.exit("FAIL (plot_check.py): " + msg)


folder, args = sys.argv[1], sys.argv[2:]
summary = expo = None
while args and args[0].startswith("--"):
    if args[0] == "--d50":
        summary, args = args[1], args[2:]
    else:
        expo, args = (float(args[1]), float(args[2])), args[3:]
for a in args:
    name, labels = a.split("=", 1)
    png = open(f"{folder}/{name}.png", "rb").read()
    if png[:8] != b"\x89PNG\r\n\x1a\n" or len(png) < 10000:
        fail(f"{name}.png: {len(png)} bytes")
    svg = open(f"{folder}/{name}.svg").read()
    if "<svg" not in svg:
        fail(f"{name}.svg is no SVG")
    for label in labels.split("|"):
        if label.replace("&", "&amp;") not in svg:
            fail(f"{name}.svg lacks the text '{label}'")
if summary:
    psd = pd.read_csv(f"{folder}/psd.csv")
    s = pd.read_csv(summary)
    checked = 0
    for (t, c), g in psd.groupby(["time [s]", "compartment"]):
        Q = g["Q3 [1]"].to_numpy()
        if np.any(np.diff(Q) < -1e-12) or abs(Q[-1] - 1) > 1e-9:
            fail(f"psd.csv at t = {t}, compartment {c}: Q3 {Q}")
        k = int(np.argmax(Q >= 0.5))
        d50 = s.loc[(abs(s["time [s]"] - t) < 1e-9 * max(1, t)) & (s.compartment == c), "d50 [m]"].iloc[0] * 1e6
        lo, hi = g["d_lo [um]"].iloc[max(k - 1, 0)], g["d_hi [um]"].iloc[min(k + 1, len(g) - 1)]
        if not lo <= d50 <= hi:
            fail(f"t = {t}, compartment {c}: summary.csv d50 {d50} um outside the classes around "
                 f"Q3 = 1/2, [{lo}, {hi}] um")
        checked += 1
    if not checked:
        fail("psd.csv is empty")
if expo:
    psd = pd.read_csv(f"{folder}/psd.csv")
    sv = np.pi * (psd["d_hi [um]"] * 1e-6) ** 3 / (6 * (1 + expo[1]))
    exact = 1 - (1 + sv / expo[0]) * np.exp(-sv / expo[0])
    err = np.abs(exact - psd["Q3 [1]"]).max()
    if not err < 0.04:  # the grid's cells (ratio 1.1) hold their volume at the pivot
        fail(f"Q3 differs from the exponential distribution's by {err}")
    print(f"plot_check.py: Q3 of the exponential distribution within {err:.3g}")
print(f"plot_check.py: {len(args)} figures in {folder}")
