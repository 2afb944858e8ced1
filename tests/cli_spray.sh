# `gransim dem` with spray and granulation: the example examples/spray-drum.yaml
# is valid and, shortened, runs and writes its tables; the liquid ledger
# balances in every row; the class populations add up to the particles; the
# liquid on the particles of a closed drum never falls and the mean diameter grows; the
# run's kernel table is one the PBM's `table` kernel reads; bad spray and
# granulation keys are refused naming file, line, key and value.
source "$(dirname "$0")/cli-lib.sh" "$@"

run_rc 0 "$BIN" dem --help
stdout_has "spray.csv" "granulation"
run_rc 0 "$BIN" dem --check "$SRC/examples/spray-drum.yaml"
stdout_has "valid"

sed 's/^  duration: 1.0$/  duration: 0.3/' "$SRC/examples/spray-drum.yaml" > "$WORK/drum.yaml"
grep -q '^  duration: 0.3$' "$WORK/drum.yaml" || fail "could not shorten the spray-drum example"
sed -i 's/^output: {every: 0.05}$/output: {every: 0.05, vtk_every: 0.3}/' "$WORK/drum.yaml"
run_rc 0 "$BIN" dem "$WORK/drum.yaml" --out "$WORK/out" --quiet
for f in spray.csv granulation.csv granulation_classes.csv granulation_collisions.csv granulation_kernel.csv; do
  [ -s "$WORK/out/$f" ] || fail "missing $f"
done
# the VTK frames carry each particle's liquid content, some of it wet at the end
/usr/bin/python3 - "$WORK/out/vtk/particles_000001.vtp" <<'PY' || fail "no liquid_content with a wet particle in the last VTK frame"
import sys
from vtkmodules.vtkIOXML import vtkXMLPolyDataReader
r = vtkXMLPolyDataReader()
r.SetFileName(sys.argv[1])
r.Update()
a = r.GetOutput().GetPointData().GetArray("liquid_content")
sys.exit(0 if a is not None and any(a.GetValue(i) > 0 for i in range(a.GetNumberOfTuples())) else 1)
PY
# ledger: injected = on particles + airborne + on walls + left, to round-off; droplets absorbed
awk -F, 'NR > 1 { s = $6 + $7 + $8 + $9; d = $5 - s; if (d < 0) d = -d; if (d > 1e-12 * $5) bad = 1; n++ }
         END { exit bad || n != 7 }' "$WORK/out/spray.csv" || fail "ledger: $(cat "$WORK/out/spray.csv")"
awk -F, 'END { exit !($4 > 0) }' "$WORK/out/spray.csv" || fail "no droplet was absorbed"
# the populations of each update add up to the particles of granulation.csv
awk -F, 'FNR == 1 { next } FILENAME ~ /classes/ { pop[$1] += $6; next } { np[$1] = $2 }
         END { for (t in np) { if (pop[t] != np[t]) exit 1; n++ } exit n < 7 }' \
  "$WORK/out/granulation_classes.csv" "$WORK/out/granulation.csv" ||
  fail "class populations do not add up to the particles"
# in a closed drum the liquid on the particles never falls, and the granules have grown
awk -F, 'NR > 2 && $9 < l { bad = 1 } NR == 2 { d0 = $3 } NR > 1 { d = $3; l = $9 }
         END { exit bad || !(d > d0) || !(l > 0) }' "$WORK/out/granulation.csv" ||
  fail "liquid on particles fell or no growth: $(cat "$WORK/out/granulation.csv")"
# the PBM reads the kernel table
cp "$WORK/out/granulation_kernel.csv" "$WORK/K.csv"
cat > "$WORK/pbm.yaml" <<YAML
title: DEM granulation collision frequencies as the aggregation kernel
grid:
  axes:
    - {name: solid, type: geometric, min: 1.0e-11, max: 1.0e-6, cells: 20, zero_first: true}
initial: {type: exponential, number: 1, mean: 4.0e-9}
mechanisms:
  - type: aggregation
    kernel: {type: table, file: K.csv, measure: volume, beta0: 1.0e-3}
output: {end: 1, count: 2}
YAML
if "$BIN" check "$WORK/pbm.yaml" > "$WORK/pbm.out" 2>&1; then :; else
  cat "$WORK/pbm.out" "$WORK/K.csv" >&2
  fail "the PBM does not accept granulation_kernel.csv"
fi

# bad input: file:line, key and value
bad() { # SED-EXPRESSION EXPECTED...
  local e=$1
  shift
  sed "$e" "$SRC/examples/spray-drum.yaml" > "$WORK/bad.yaml"
  run_rc 1 "$BIN" dem --check "$WORK/bad.yaml"
  stderr_has "$@"
}
bad 's/half_angle: 25/half_angle: 120/' "bad.yaml:" "spray.half_angle = '120'"
bad 's/mass_rate: 8.0e-4/mass_rate: -1/' "spray.mass_rate = '-1'"
bad 's/  every: 0.05/  every: 0.05001/' "granulation.every" "whole number of time steps"
bad 's/type: constant, efficiency: 0.05/type: sticky, efficiency: 0.05/' "sticky" "constant, stokes"
bad 's/efficiency: 0.05/efficiency: 1.5/' "granulation.rule.efficiency = '1.5'"
bad 's/min_liquid_content: 0.2/min_liquid_contnet: 0.2/' "unknown key 'min_liquid_contnet'"
bad 's/solid_classes: {count: 8}/solid_classes: {count: 200}/' "at most 1024 classes"
sed '/^spray:/,/^  start: 0.1$/d' "$SRC/examples/spray-drum.yaml" > "$WORK/bad.yaml"
run_rc 1 "$BIN" dem --check "$WORK/bad.yaml"
stderr_has "missing key 'width' in granulation.liquid_classes"
echo "cli_spray: ok"
