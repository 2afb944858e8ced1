# System scaling with the DEM geometry rescaled every cycle (coupling.scaling;
# docs/models.md, "System scaling").  A two-way coupled run of a granular gas
# (elastic, frictionless spheres of two classes, no gravity) in a closed
# cube: the PBM starts with 1600 granules, the DEM holds 200 (l_1 = 2), and
# aggregation halves the number between cycles (trigger: the mean volume
# doubled), so cycles 2 and 3 sample populations of about 800 and 400
# granules with the geometry 1.26 and 1.59 times the case's.  Each cycle is
# then run resolved: the cycle's DEM case with all N_PBM granules in the real
# equipment (geometry_scale l_1), and the scaled run's per-pair table (the
# DEM's times l_i^-3) must match the resolved per-pair frequencies: the log
# of their ratio within 3 Poisson standard errors (from the event counts)
# plus the walls' share of the smaller box (the excluded-volume bound
# 3 ln[(1 - d/L_res) / (1 - d/L_scaled)], d the largest diameter; the
# resolved box is the larger, so the scaled table may be that much higher,
# never lower).  Without the rescaling (the case's geometry every cycle)
# cycle 2's table is 2 times, cycle 3's 4 times the resolved one.  Also
# checked: cycles.csv and result.h5 record geometry_scale = (N_1 / N_i)^(1/3),
# each cycle's DEM case carries it, and a dem.geometry_scale of the user's in
# a scaled case is refused.
source "$(dirname "$0")/cli-lib.sh" "$@"

cat > "$WORK/gas.yaml" <<'YAML'
title: system scaling with the geometry rescaled per cycle (a granular gas)
grid:
  axes:
    - {name: solid, type: geometric, min: 2.0e-11, ratio: 2, cells: 14, zero_first: true}
initial: {type: exponential, number: 1600, mean: 2.5e-10}
output: {end: 0.2, count: 201, checkpoint: 0}
mechanisms:
  - type: aggregation
    kernel: {type: table, beta0: 0.1}
dem:
  dem:
    time_step: 8.0e-6
    gravity: [0, 0, 0]
    box: {lo: [-0.02, -0.02, -0.02], hi: [0.02, 0.02, 0.02]}
    seed: 7
    max_lost: 0
  materials:
    - {name: g, E: 1.0e6, nu: 0.3, e: 1.0, mu_s: 0, mu_r: 0, density: 1000}
  walls:
    - {name: x0, plane: {point: [-0.0047, 0, 0], normal: [1, 0, 0]}, material: g}
    - {name: x1, plane: {point: [0.0047, 0, 0], normal: [-1, 0, 0]}, material: g}
    - {name: y0, plane: {point: [0, -0.0047, 0], normal: [0, 1, 0]}, material: g}
    - {name: y1, plane: {point: [0, 0.0047, 0], normal: [0, -1, 0]}, material: g}
    - {name: z0, plane: {point: [0, 0, -0.0047], normal: [0, 0, 1]}, material: g}
    - {name: z1, plane: {point: [0, 0, 0.0047], normal: [0, 0, -1]}, material: g}
  fill:
    - region: {box: {lo: [-0.0047, -0.0047, -0.0047], hi: [0.0047, 0.0047, 0.0047]}}
      velocity: [0.5, 0.3, 0.2]
  output: {vtk_every: 0}
coupling:
  mode: two_way
  trigger: {mean_volume_change: 1}
  scaling: {particles: 200}
  classes: {min_diameter: 0.6e-3, max_diameter: 0.9e-3, count: 2, material: g}
  steady: {window: 3, tolerance: 0.2, sample_every: 0.02, max_time: 0.5, collect: 0.2}
YAML

# the coupling sets the geometry's scale: the user's is refused
sed 's/    max_lost: 0/    max_lost: 0\n    geometry_scale: 2/' "$WORK/gas.yaml" > "$WORK/own.yaml"
run_rc 1 "$BIN" check "$WORK/own.yaml"
stderr_has "own.yaml:17: dem.dem.geometry_scale"
stderr_has "coupling.scaling rescales the geometry every cycle"

run_rc 0 "$BIN" couple "$WORK/gas.yaml" --out "$WORK/out"
stderr_has "3 cycles to t = 0.2 s"
stderr_has "l_i = 2, geometry x 1,"
grep -q "geometry_scale: 1.26" "$WORK/out/cycle-2/case.yaml" || fail "cycle 2's DEM case: no geometry_scale 1.26..."

/usr/bin/python3 - "$WORK/out" "$BIN" <<'PY' || fail "the scaled run's tables do not match the resolved runs' (or the geometry_scale record is wrong)"
import sys, csv, math, re, subprocess, h5py, numpy as np
d, gransim = sys.argv[1], sys.argv[2]
rows = list(csv.DictReader(open(d + "/cycles.csv")))
assert len(rows) == 3, len(rows)
N = 200
npbm = [N * float(r["l_i [1]"]) ** 3 for r in rows]
geom = [float(r["geometry_scale [1]"]) for r in rows]
assert abs(npbm[0] - 1600) < 1e-6 * 1600
h5 = h5py.File(d + "/result.h5", "r")["coupling"]["cycles"]["geometry_scale"]
assert h5.attrs["units"] == b"1" and np.allclose(h5[:], geom, rtol=1e-8), (h5[:], geom)
l1, half, worst = float(rows[0]["l_i [1]"]), 0.0047, 0
for i, r in enumerate(rows, 1):
    # the geometry holds N particles of this population at the first one's fill level
    assert abs(geom[i - 1] - (npbm[0] / npbm[i - 1]) ** (1 / 3)) < 1e-8, (i, geom, npbm)
    case = open("%s/cycle-%d/case.yaml" % (d, i)).read()
    edges = [2 * float(x) for x in re.findall(r"radius: \[[^,]+, ([^\]]+)\]", case)]
    # resolved: all the granules, in the real equipment (l_1 times the case's geometry)
    case = re.sub(r"geometry_scale: [0-9.e+-]+", "geometry_scale: %.17g" % l1, case)
    case = case.replace("count: %d" % N, "count: %d" % round(npbm[i - 1]))
    open("%s/resolved-%d.yaml" % (d, i), "w").write(case)
    subprocess.run([gransim, "dem", "%s/resolved-%d.yaml" % (d, i), "--out", "%s/resolved-%d" % (d, i)], check=True,
                   stderr=subprocess.DEVNULL)
    tab = [l.split(",") for l in open("%s/cycle-%d/collision_kernel.csv" % (d, i)).read().split("\n")[1:] if l]
    sc = {(x["class_i"], x["class_j"]): x for x in csv.DictReader(open("%s/cycle-%d/collisions.csv" % (d, i)))}
    res = {(x["class_i"], x["class_j"]): x for x in csv.DictReader(open("%s/resolved-%d/collisions.csv" % (d, i)))}
    assert res.keys() == sc.keys()
    dmax, Ls, Lr = max(edges), 2 * half * geom[i - 1], 2 * half * l1
    wall = 3 * math.log((1 - dmax / Lr) / (1 - dmax / Ls))
    for k in sorted(res):
        a, b = float(res[k]["C_ij"]), float(tab[int(k[0]) - 1][int(k[1]) - 1])
        na, nb = float(res[k]["events"]), float(sc[k]["events"])
        assert na > 50 and nb > 50, (i, k, na, nb)
        s = math.sqrt(1 / na + 1 / nb)
        q = math.log(b / a)
        print("cycle %d (N_PBM %.1f, geometry x %.4f): pair %s-%s: resolved C %.4g, scaled table %.4g 1/s, "
              "ln ratio %+.4f +- %.4f (Poisson; %d and %d events), wall bound %.3f"
              % (i, npbm[i - 1], geom[i - 1], k[0], k[1], a, b, q, s, na, nb, wall))
        assert -3 * s <= q <= wall + 3 * s, (i, k, q, s, wall)
PY
