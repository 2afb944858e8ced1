# `gransim dem` with a `gas` section (CFD-DEM, src/cfd): the fluid-bed example,
# shortened, runs and writes gas.csv and the gas fields as a VTK series; the
# drag exchange in gas.csv balances; bad gas keys name file:line, key and value;
# a run stopped by a failure keeps its gas.csv rows and the DEM tables up to there.
source "$(dirname "$0")/cli-lib.sh" "$@"

run_rc 0 "$BIN" list
stdout_has "di_felice"
run_rc 0 "$BIN" validate-cfd --help
stdout_has "Ergun"

sed 's/^  duration: 0.8$/  duration: 0.02/; s/count: 2000/count: 300/; s/vtk_every: 0.05/vtk_every: 0.01/' \
  "$SRC/examples/fluid-bed-cfd.yaml" > "$WORK/bed.yaml"
grep -q '^  duration: 0.02$' "$WORK/bed.yaml" || fail "could not shorten the fluid-bed example"
run_rc 0 "$BIN" dem --check "$WORK/bed.yaml"
stdout_has "gas on 4 x 1 x 20 cells"
run_rc 0 "$BIN" dem "$WORK/bed.yaml" --out "$WORK/out" --quiet
for f in gas.csv gas.pvd vtk/gas_000000.vtr vtk/gas_000002.vtr timeseries.csv collisions.csv; do
  [ -s "$WORK/out/$f" ] || fail "missing $f"
done
grep -q 'file="vtk/gas_000002.vtr"' "$WORK/out/gas.pvd" || fail "gas.pvd lacks the third frame"
grep -q 'Name="void_fraction"' "$WORK/out/vtk/gas_000001.vtr" || fail "no void fraction in the .vtr"
grep -q 'Name="liquid_content"' "$WORK/out/vtk/gas_000001.vtr" || fail "no liquid content in the .vtr"
# the drag on the particles equals what the gas lost, and the pressure solve converged
awk -F, 'NR > 1 { d = $9 - $10; if (d < 0) d = -d; if (d > 1e-12 * ($9 < 0 ? -$9 : $9) + 1e-18 || $8 > 1e-10) bad = 1 }
         END { exit bad }' "$WORK/out/gas.csv" || fail "drag exchange or residual off: $(cat "$WORK/out/gas.csv")"

# bad input: file:line, key, value, what was expected
bad() { # bad SED_EXPR WORDS...
  sed "$1" "$WORK/bed.yaml" > "$WORK/bad.yaml"
  shift
  run_rc 1 "$BIN" dem --check "$WORK/bad.yaml"
  for w in "$@"; do stderr_has "$w"; done
}
bad 's/^  cells: \[4, 1, 20\]$/  cells: [4, 0, 20]/' "bad.yaml:" "gas.cells" "whole numbers from 1"
bad 's/^  drag: di_felice$/  drag: stokes/' "gas.drag" "stokes" "di_felice, gidaspow"
bad 's/^  inlet_velocity: 1.8$/  inlet_velocity: -1/' "gas.inlet_velocity" "-1"
bad 's/^  box: {lo: \[0, 0, 0\].*$/  bogus: 1/' "gas" "missing key 'box'"
bad 's/^  time_step: 5.0e-4$/  time_step: 3.1e-4/' "not a whole number of DEM time steps"

# a failure part-way: a gas box ending at 60 mm and a gas fast enough to blow particles out of
# it; the run stops naming the particle and where, and gas.csv keeps its rows up to there
sed 's/hi: \[0.039, 0.009, 0.1\]/hi: [0.039, 0.009, 0.04]/; s/hi: \[0.04, 0.01, 0.2\]/hi: [0.04, 0.01, 0.06]/;
     s/cells: \[4, 1, 20\]/cells: [8, 2, 12]/; s/inlet_velocity: 1.8/inlet_velocity: 9/;
     s/^  time_step: 5.0e-4/  time_step: 2.5e-4/; s/^  duration: 0.02$/  duration: 0.1/' "$WORK/bed.yaml" > "$WORK/blow.yaml"
run_rc 1 "$BIN" dem "$WORK/blow.yaml" --out "$WORK/blow" --quiet
stderr_has "left the gas domain"
stderr_has "gas step"
[ "$(wc -l < "$WORK/blow/gas.csv")" -ge 3 ] || fail "gas.csv lost its rows"
# and the DEM's tables up to there (issue 27, item 8)
for f in timeseries.csv collisions.csv collision_kernel.csv impact_table.csv; do
  [ -s "$WORK/blow/$f" ] || fail "the stopped run left no $f"
done
grep -q "RUN STOPPED EARLY" "$WORK/blow/collision_kernel".* || fail "collision_kernel.csv does not say the run stopped"
echo "PASS"
