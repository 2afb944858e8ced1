# Shared by tests/cli_liggghts*.sh (sourced: `source liggghts-lib.sh NAME "$@"`): BIN (the
# gransim binary), W (a temporary folder, removed at exit) holding box.stl, a closed box
# 20 x 20 x 30 mm as an STL mesh (12 facets) in millimetres (scale 1e-3), and fail MESSAGE.
# Skips the test (exit 0) only when the liggghts binary or mpirun is absent (scripts/setup
# installs them).
set -euo pipefail
LIG_TEST=$1
BIN=$2
if ! command -v "${GRANSIM_LIGGGHTS:-liggghts}" >/dev/null || ! command -v mpirun >/dev/null; then
  echo "$LIG_TEST: SKIPPED: no liggghts or mpirun on PATH (scripts/setup installs liggghts, mpi-default-bin)"
  exit 0
fi
W=$(mktemp -d)
trap 'rm -rf "$W"' EXIT
fail() { echo "$LIG_TEST: FAIL: $*" >&2; exit 1; }
python3 - "$W/box.stl" <<'PY'
import sys
q = [((0,0,0),(0,1,0),(1,1,0),(1,0,0)), ((0,0,1),(1,0,1),(1,1,1),(0,1,1)), ((0,0,0),(1,0,0),(1,0,1),(0,0,1)),
     ((0,1,0),(0,1,1),(1,1,1),(1,1,0)), ((0,0,0),(0,0,1),(0,1,1),(0,1,0)), ((1,0,0),(1,1,0),(1,1,1),(1,0,1))]
with open(sys.argv[1], "w") as f:
    f.write("solid box\n")
    for a, b, c, d in q:
        for t in ((a, b, c), (a, c, d)):
            f.write(" facet normal 0 0 0\n  outer loop\n")
            for x, y, z in t: f.write("   vertex %g %g %g\n" % (20 * x - 10, 20 * y - 10, 30 * z))
            f.write("  endloop\n endfacet\n")
    f.write("endsolid box\n")
PY

# outlet_yaml ENGINE DURATION STATISTICS OUTPUT: 70 particles of two classes (40 'low' below 30
# 'high') falling at 1 m/s, without gravity, into an outlet across the box's floor
outlet_yaml() {
  cat <<YAML
dem:
  time_step: 2.0e-6
  duration: $2
  gravity: [0, 0, 0]
  skin: 2.0e-4
  box: {lo: [-0.03, -0.03, -0.02], hi: [0.03, 0.03, 0.06]}
  engine: $1
materials:
  - {name: g, E: 8.0e6, nu: 0.2, e: 0.4, mu_s: 0.5, density: 500}
classes:
  - {name: low, radius: 1.0e-3, material: g}
  - {name: high, radius: 1.0e-3, material: g}
fill:
  - {region: {box: {lo: [-0.02, -0.02, 0.01], hi: [0.02, 0.02, 0.03]}}, count: 40, fractions: [1, 0], velocity: [0, 0, -1]}
  - {region: {box: {lo: [-0.02, -0.02, 0.03], hi: [0.02, 0.02, 0.05]}}, count: 30, fractions: [0, 1], velocity: [0, 0, -1]}
outlets:
  - {region: {box: {lo: [-0.03, -0.03, -0.02], hi: [0.03, 0.03, 0.0]}}}
statistics: $3
output: $4
YAML
}

# blade_stl: $W/blade.stl, a blade in the plane y = 0, x from -8 to 8 mm, z from 11 to 18.5 mm,
# in millimetres (scale 1e-3), beside box.stl
blade_stl() {
  cat > "$W/blade.stl" <<'STL'
solid blade
 facet normal 0 1 0
  outer loop
   vertex -8 0 11
   vertex 8 0 11
   vertex 8 0 18.5
  endloop
 endfacet
 facet normal 0 1 0
  outer loop
   vertex -8 0 11
   vertex 8 0 18.5
   vertex -8 0 18.5
  endloop
 endfacet
endsolid blade
STL
}
