# The system-scaling identity of coupling.scaling (docs/models.md, "System
# scaling"): a DEM bed in a geometry scaled down by l, with particles of their
# true size at the same fill level (N / l^3 of them), measures per-pair
# collision frequencies C_ij = N_coll / (N_i N_j dt) l^3 times the resolved
# bed's.  Two boxes of elastic, frictionless spheres (two classes, no gravity:
# a granular gas whose temperature is conserved): side 16 mm with 800
# particles and side 8 mm with 100 (l = 2).  Each pair's exponent
# p = log2(C_scaled / C_resolved) must be 3 within 0.25; its Poisson error
# (from the event counts) is about 0.02-0.04, the rest of the band is the
# walls' share of the small box (docs/models.md gives the figures).  The
# paper's l^4 (p = 4) and the coarse-grained reading's l^2 (p = 2) fail.
source "$(dirname "$0")/cli-lib.sh" "$@"

gas() { # NAME HALF_SIDE COUNT
  cat > "$WORK/$1.yaml" <<YAML
dem:
  time_step: 1.0e-5
  gravity: [0, 0, 0]
  box: {lo: [-0.02, -0.02, -0.02], hi: [0.02, 0.02, 0.02]}
  duration: 0.3
  seed: 7
  max_lost: 0
materials:
  - {name: g, E: 1.0e6, nu: 0.3, e: 1.0, mu_s: 0, mu_r: 0, density: 1000}
classes:
  - {name: small, radius: 4.0e-4, material: g}
  - {name: large, radius: 6.0e-4, material: g}
walls:
  - {name: x0, plane: {point: [-$2, 0, 0], normal: [1, 0, 0]}, material: g}
  - {name: x1, plane: {point: [$2, 0, 0], normal: [-1, 0, 0]}, material: g}
  - {name: y0, plane: {point: [0, -$2, 0], normal: [0, 1, 0]}, material: g}
  - {name: y1, plane: {point: [0, $2, 0], normal: [0, -1, 0]}, material: g}
  - {name: z0, plane: {point: [0, 0, -$2], normal: [0, 0, 1]}, material: g}
  - {name: z1, plane: {point: [0, 0, $2], normal: [0, 0, -1]}, material: g}
fill:
  - region: {box: {lo: [-$2, -$2, -$2], hi: [$2, $2, $2]}}
    count: $3
    velocity: [0.5, 0.3, 0.2]
statistics: {start: 0.1, sample_every: 0.01}
output: {every: 0.05, vtk_every: 0}
YAML
  run_rc 0 "$BIN" dem "$WORK/$1.yaml" --out "$WORK/$1"
}
gas resolved 0.008 800
gas scaled 0.004 100

/usr/bin/python3 - "$WORK" <<'PY' || fail "the per-pair collision frequency does not scale with l^3"
import sys, csv, math
d = sys.argv[1]
def pairs(name):
    return {(r["class_i"], r["class_j"]): r for r in csv.DictReader(open("%s/%s/collisions.csv" % (d, name)))}
res, sc = pairs("resolved"), pairs("scaled")
for k in res:
    a, b = float(res[k]["C_ij"]), float(sc[k]["C_ij"])
    na, nb = float(res[k]["events"]), float(sc[k]["events"])
    assert na > 1000 and nb > 500, (k, na, nb)
    p = math.log2(b / a)
    sp = math.sqrt(1 / na + 1 / nb) / math.log(2)
    print("pair %s-%s: C_resolved %.4g, C_scaled %.4g 1/s, exponent %.3f +- %.3f (Poisson)" % (k + (a, b, p, sp)))
    assert abs(p - 3) < 0.25, (k, p, sp)
    assert abs(p - 4) > 10 * sp and abs(p - 2) > 10 * sp
PY
