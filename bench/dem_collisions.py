#!/usr/bin/env python3
"""Collision frequencies of gransim and LIGGGHTS from one bench/dem_vs_liggghts work folder.

Usage: bench/dem_collisions.py WORK NWINDOW SAMPLE DT
(run by bench/dem_vs_liggghts; run it again on a folder kept with KEEP=1).

C_ij = N_coll,ij / (N_i N_j window) for both engines, with N_i the MEAN number of class-i
particles present over the window (particles leave through the chutes: several per cent of the
bed in 0.3 s), as gransim's collisions.csv defines it.  gransim counts events exactly (a contact
that begins).  LIGGGHTS lists current contacts only (compute pair/gran/local), dumped every
SAMPLE steps: a pair absent from the previous dump counts as a new event.  Its N_i is the mean
over its atom dumps (every NSTEPS steps through the window, both ends included).
"""
import glob
import math
import os
import re
import sys

W, nwindow, sample, dt = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), float(sys.argv[4])


def rows(path):
    lines = open(path).read().split("\n")
    i = next(k for k, l in enumerate(lines) if l.startswith("ITEM: ENTRIES") or l.startswith("ITEM: ATOMS"))
    return [l.split() for l in lines[i + 1:] if l.strip()]


def step_of(path):
    return int(re.findall(r"\d+", os.path.basename(path))[0])


typ, counts, speeds = {}, [], {1: [], 2: [], 3: []}
for p in sorted(glob.glob(W + "/post/at_*.txt"), key=step_of):
    c = {1: 0, 2: 0, 3: 0}
    for r in rows(p):
        typ[int(r[0])] = int(r[1])
        c[int(r[1])] = c.get(int(r[1]), 0) + 1
        if len(r) >= 8:  # id type x y z vx vy vz
            speeds[int(r[1])].append(math.sqrt(sum(float(v) ** 2 for v in r[5:8])))
    counts.append(c)
N = {k: sum(c[k] for c in counts) / len(counts) for k in (1, 2, 3)}
steps = sorted(step_of(p) for p in glob.glob(W + "/post/pp_*.txt"))
ev, prev = {}, None
for s in steps:
    cur = set()
    for r in rows("%s/post/pp_%d.txt" % (W, s)):
        a, b = int(float(r[0])), int(float(r[1]))
        cur.add((min(a, b), max(a, b)))
    if prev is not None:
        for a, b in cur - prev:
            if a in typ and b in typ:
                k = tuple(sorted((typ[a], typ[b])))
                ev[k] = ev.get(k, 0) + 1
    prev = cur
win = (steps[-1] - steps[0]) * dt
g = {}
for l in open(W + "/g/collisions.csv"):
    if l[0].isdigit():
        f = l.split(",")
        g[(int(f[0]), int(f[1]))] = (float(f[4]), float(f[9]), float(f[5]), float(f[6]))
gN = {i: g[(i, i)][2] for i in (1, 2, 3) if (i, i) in g}
print("\ncollision frequency C_ij = N_coll / (N_i N_j dt) [1/s], phase 2 (%d steps):" % nwindow)
print("  mean N over the window: gransim %s, LIGGGHTS %s (%d atom dumps); window %.4g s"
      % ({k: round(v, 1) for k, v in gN.items()}, {k: round(v, 1) for k, v in N.items()}, len(counts), win))
print("  LIGGGHTS: contacts sampled every %d steps" % sample)
gv = {}
for l in open(W + "/g/velocity.csv"):
    f = l.split(",")
    if l[0].isdigit() and f[3] == "-inf":
        gv[int(f[0])] = float(f[6])
if all(speeds.values()):
    print("  mean speed [m/s] per class, gransim (every 100 steps) / LIGGGHTS (its atom dumps): %s" % ", ".join(
        "%d: %.3f / %.3f" % (k, gv.get(k, float("nan")), sum(v) / len(v)) for k, v in speeds.items()))
print("  pair   gransim events    C_ij          LIGGGHTS events    C_ij       ratio  +-(2 sigma, Poisson)")
for i in (1, 2, 3):
    for j in range(i, 4):
        le = ev.get((i, j), 0)
        lc = le / (N[i] * N[j] * win) if N[i] and N[j] and win > 0 else 0
        ge, gc, _, _ = g.get((i, j), (0, 0, 0, 0))
        rel = 2 * math.sqrt(1 / max(ge, 1) + 1 / max(le, 1))
        print("  %d-%d  %14.0f  %12.5g   %14d  %12.5g   %6.3f  %.3f"
              % (i, j, ge, gc, le, lc, gc / lc if lc else float("nan"), rel))
