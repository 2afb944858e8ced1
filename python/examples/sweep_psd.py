#!/usr/bin/python3
"""A small sweep from Python: constant-kernel aggregation at three rate
constants, run in process over libgransim, and the volume-weighted size
distributions at the end plotted against the diameter in micrometres.

usage: sweep_psd.py [OUT_DIR]   (default: sweep-psd); writes OUT_DIR/psd.png,
OUT_DIR/sweep.csv and a run folder per variation.
"""
import os
import sys

import matplotlib

matplotlib.use("Agg")  # files only, no display
import matplotlib.pyplot as plt  # noqa: E402

import gransim  # noqa: E402

out = sys.argv[1] if len(sys.argv) > 1 else "sweep-psd"
os.makedirs(out, exist_ok=True)

case = gransim.Case.from_dict({
    "title": "batch aggregation, constant kernel",
    "grid": {"axes": [{"name": "solid", "type": "geometric", "min": 1.0e-15, "ratio": 1.25,
                       "cells": 90, "zero_first": True}]},          # granule volume [m^3]
    "initial": {"type": "exponential", "number": 1.0e9, "mean": 1.0e-12},   # 1e9 particles, mean 1e-12 m^3
    "mechanisms": [{"type": "aggregation", "kernel": {"type": "constant", "beta0": 1.0e-9}}],  # [1/s]
    "output": {"end": 10, "count": 11},                              # [s]
})
runs = gransim.sweep(case, {"mechanisms.0.kernel.beta0": [5.0e-10, 1.0e-9, 2.0e-9]}, out)
# the columns with their units, as gransim sweep's sweep.csv ("d50_c1 [m]")
gransim.with_units(runs.drop(columns=["path"])).to_csv(os.path.join(out, "sweep.csv"), index=False)
print(runs[["run", "status", "mechanisms.0.kernel.beta0", "M0_c1", "d50_c1"]].to_string(index=False))

fig, ax = plt.subplots(figsize=(7, 4.5))
styles = ["-", "--", ":"]
for (_, run), style in zip(runs.iterrows(), styles):
    if run["status"] != "ok":
        continue
    psd = gransim.Result(run["path"]).psd()
    ax.plot(psd["d"] * 1e6, psd["q3_lnd"], style, label="beta0 = %g 1/s" % run["mechanisms.0.kernel.beta0"])
psd0 = gransim.Result(runs["path"][0]).psd(time=0)
ax.plot(psd0["d"] * 1e6, psd0["q3_lnd"], color="grey", label="t = 0")
ax.set_xscale("log")
ax.set_xlabel("volume-equivalent diameter d [µm]")
ax.set_ylabel("q3(ln d) [-]")
ax.set_title("size distribution at t = 10 s")
ax.legend()
fig.tight_layout()
fig.savefig(os.path.join(out, "psd.png"), dpi=120)
print("wrote %s" % os.path.join(out, "psd.png"))
