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
