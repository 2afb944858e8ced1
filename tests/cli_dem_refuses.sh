# The embedded DEM refuses nonsense (docs/reliability.md): a time step above
# half the Rayleigh time, particles so soft that they sink into each other,
# a wall mesh with a hole (refused when marked closed; particles lost
# through it otherwise), a mesh with a non-finite or degenerate facet; each
# exits 1 with a message naming the key, facet, particles, step and figure,
# and the time series is written up to the failure.
source "$(dirname "$0")/cli-lib.sh" "$@"

# 500 particles of 1 mm falling into a 20 mm box; WALLS is replaced below
cat > "$WORK/base.yaml" <<'YAML'
dem:
  time_step: TS
  duration: 0.05
  gravity: [0, 0, GZ]
  box: {lo: [-0.003, -0.003, -0.003], hi: [0.025, 0.025, 0.045]}
materials:
  - {name: g, E: EMOD, nu: 0.2, e: 0.4, mu_s: 0.5, density: 500}
classes:
  - {name: a, radius: 1.0e-3, material: g}
walls:
WALLS
fill:
  - {region: {box: {lo: [0.001, 0.001, 0.001], hi: [0.019, 0.019, 0.039]}}, count: 500}
output: {every: 0.005}
YAML
planes='  - {name: floor, plane: {point: [0, 0, 0], normal: [0, 0, 1]}, material: g}
  - {name: x0, plane: {point: [0, 0, 0], normal: [1, 0, 0]}, material: g}
  - {name: x1, plane: {point: [0.02, 0, 0], normal: [-1, 0, 0]}, material: g}
  - {name: y0, plane: {point: [0, 0, 0], normal: [0, 1, 0]}, material: g}
  - {name: y1, plane: {point: [0, 0.02, 0], normal: [0, -1, 0]}, material: g}'
# case NAME TS GZ EMOD WALLS: writes $WORK/NAME.yaml
case_file() {
  awk -v ts="$2" -v gz="$3" -v e="$4" -v walls="$5" \
    '{ sub(/TS/, ts); sub(/GZ/, gz); sub(/EMOD/, e); if ($0 == "WALLS") print walls; else print }' \
    "$WORK/base.yaml" > "$WORK/$1.yaml"
}

# the reference: at 24 % of the Rayleigh time every particle stays in the box
case_file ok 1.0e-5 -9.81 8.0e6 "$planes"
run_rc 0 "$BIN" dem "$WORK/ok.yaml" --out "$WORK/ok" --quiet
awk -F, 'NR > 1 { n = $2 } END { exit n != 500 }' "$WORK/ok/timeseries.csv" ||
  fail "the reference case lost particles: $(tail -1 "$WORK/ok/timeseries.csv")"

# 2.4 times the Rayleigh time (4.23e-5 s): refused when the case is read
case_file big 1.0e-4 -9.81 8.0e6 "$planes"
run_rc 1 "$BIN" dem "$WORK/big.yaml" --out "$WORK/big" --quiet
stderr_has "big.yaml:2: dem.time_step = '1.0e-4'" "236 % of the Rayleigh time" "at most 50 %"
run_rc 1 "$BIN" dem --check "$WORK/big.yaml"
[ ! -e "$WORK/big/timeseries.csv" ] || fail "a refused case wrote outputs"

# very soft particles under strong gravity sink into each other: stopped at
# the first check, with the time series up to there
case_file soft 1.0e-5 -2000 1.0e4 "$planes"
run_rc 1 "$BIN" dem "$WORK/soft.yaml" --out "$WORK/soft" --quiet
stderr_has "overlap by" "of the smaller radius (0.001 m) at step " "more than 50 %"
grep -q '^0,500,' "$WORK/soft/timeseries.csv" || fail "no time series up to the failure"

# the same box as a mesh: 12 facets (file units mm), and without its two floor facets
cube() { # cube SKIP: an ASCII STL of the 20 mm cube without facets SKIP (a regex)
  printf 'solid cube\n'
  printf '%s\n' "0 0 0;20 20 0;20 0 0" "0 0 0;0 20 0;20 20 0" "0 0 20;20 0 20;20 20 20" \
    "0 0 20;20 20 20;0 20 20" "0 0 0;20 0 0;20 0 20" "0 0 0;20 0 20;0 0 20" "20 0 0;20 20 0;20 20 20" \
    "20 0 0;20 20 20;20 0 20" "20 20 0;0 20 0;0 20 20" "20 20 0;0 20 20;20 20 20" \
    "0 20 0;0 0 0;0 0 20" "0 20 0;0 0 20;0 20 20" | awk -v skip="$1" -F';' '
    skip != "" && NR ~ skip { next }
    { print " facet normal 0 0 0\n  outer loop"; for (i = 1; i <= 3; i++) print "   vertex " $i
      print "  endloop\n endfacet" }'
  printf 'endsolid cube\n'
}
cube "" > "$WORK/cube.stl"
cube '^[12]$' > "$WORK/open.stl"
mesh() { echo "  - {name: box, mesh: $1, scale: 1.0e-3, material: g${2:-}}"; }
case_file cube 1.0e-5 -9.81 8.0e6 "$(mesh cube.stl ', closed: true')"
run_rc 0 "$BIN" dem "$WORK/cube.yaml" --out "$WORK/cube" --quiet
# a hole where a closed wall is expected: refused when read, naming the edge
case_file hole 1.0e-5 -9.81 8.0e6 "$(mesh open.stl ', closed: true')"
run_rc 1 "$BIN" dem "$WORK/hole.yaml" --out "$WORK/hole" --quiet
stderr_has "hole.yaml:11: walls[0].closed = 'true'" "the mesh open.stl is not closed: 4 edges belong to one facet only" \
  "the first of facet 3 (counted from 1), from (0, 0, 0) to (0.02, 0, 0) m"
# not marked closed: the run stops when the particles fall through it
case_file hole2 1.0e-5 -9.81 8.0e6 "$(mesh open.stl)"
run_rc 1 "$BIN" dem "$WORK/hole2.yaml" --out "$WORK/hole2" --quiet
stderr_has "of the 500 particles inserted have left the box other than through an outlet" "dem.max_lost = 0.01"
# a generous dem.max_lost lets the same run finish
sed 's/^  duration: 0.05$/  duration: 0.05\n  max_lost: 1/' "$WORK/hole2.yaml" > "$WORK/hole3.yaml"
run_rc 0 "$BIN" dem "$WORK/hole3.yaml" --out "$WORK/hole3" --quiet

# one nan vertex, and a facet whose vertices lie on a line
sed '0,/vertex 20 20 0/s//vertex 20 nan 0/' "$WORK/cube.stl" > "$WORK/nan.stl"
case_file nan 1.0e-5 -9.81 8.0e6 "$(mesh nan.stl)"
run_rc 1 "$BIN" dem "$WORK/nan.yaml" --out "$WORK/nan" --quiet
stderr_has "nan.yaml:11: walls:" "nan.stl: facet 1 (of 12, counted from 1): vertex 2 has a non-finite coordinate"
sed '0,/vertex 20 20 0/s//vertex 10 0 0/' "$WORK/cube.stl" > "$WORK/flat.stl"
case_file flat 1.0e-5 -9.81 8.0e6 "$(mesh flat.stl)"
run_rc 1 "$BIN" dem "$WORK/flat.yaml" --out "$WORK/flat" --quiet
stderr_has "flat.stl: facet 1 (of 12, counted from 1) is degenerate (area 0)"
echo "cli_dem_refuses: ok"
