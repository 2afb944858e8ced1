# `gransim couple` (mode one_way) on a tiny case: 250 particles in a small
# rotating drum, a 15-cell PBM grid, a second or two.  Checked: the DEM
# classes derived from the grid; the tables produced and used (the PBM's
# result equals a manual two-command run, `gransim dem` then `gransim run`,
# with the same tables, bit for bit); the steady-state detector firing, and
# its error when it does not; --resume skipping a complete DEM stage; the
# `dem:` section as a file name; bad input (class mismatch, missing sections,
# keys the coupling sets) with clear errors.
source "$(dirname "$0")/cli-lib.sh" "$@"

run_rc 0 "$BIN" couple --help
stdout_has "steady.csv"

# The PBM keys, shared with the manual run below.
pbm='title: tiny coupled case
grid:
  axes:
    - {name: solid, type: geometric, min: 1.0e-10, ratio: 2, cells: 15, zero_first: true}
initial: {type: exponential, number: 1000, mean: 8.0e-9}
output: {end: 10, count: 6}'
mechs() { # mechs KERNEL_FILE_KEYS SELECTION_FILE_KEYS
  cat <<YAML
mechanisms:
  - type: aggregation
    kernel: {type: table, $1beta0: 1.0e-4}
  - type: breakage
    selection: {type: dem_impact, $2scale: 1.0e-3, u_break: 0.5}
    daughters: {type: halves}
YAML
}
demcase='dem:
  time_step: 5.0e-6
  box: {lo: [-0.03, -0.03, -0.001], hi: [0.03, 0.03, 0.021]}
  gravity: [0, -9.81, 0]
materials:
  - {name: granule, E: 8.0e6, nu: 0.2, e: 0.4, mu_s: 0.5, mu_r: 0.2, density: 500}
walls:
  - name: drum
    cylinder: {point: [0, 0, 0], axis: [0, 0, 1], radius: 0.015}
    material: granule
    rotation: {origin: [0, 0, 0], axis: [0, 0, 1], rpm: 120}
  - {name: front, plane: {point: [0, 0, 0], normal: [0, 0, 1]}, material: granule}
  - {name: back, plane: {point: [0, 0, 0.02], normal: [0, 0, -1]}, material: granule}
fill:
  - region: {cylinder: {point: [0, 0, 0], axis: [0, 0, 1], radius: 0.013, from: 0.002, to: 0.018}}
    count: 250
    fractions: [0.3, 0.4, 0.3]'
coupling='coupling:
  mode: one_way
  classes: {min_diameter: 2.0e-3, max_diameter: 4.0e-3, count: 3, material: granule}
  steady: {window: 3, tolerance: 0.5, sample_every: 0.005, max_time: 0.07}'
{ echo "$pbm"; mechs "" ""; echo "dem:"; echo "$demcase" | sed 's/^/  /'; echo "$coupling"; } > "$WORK/tiny.yaml"

run_rc 0 "$BIN" check "$WORK/tiny.yaml"
stdout_has "valid. one_way: 3 DEM classes from the grid"
run_rc 0 "$BIN" couple --check "$WORK/tiny.yaml"
stdout_has "12 PBM cells outside: nearest class"

run_rc 0 "$BIN" couple "$WORK/tiny.yaml" --out "$WORK/out" --threads 2
stderr_has "3 DEM classes from the grid"
stderr_has "take the nearest class (coupling.classes.outside: nearest)"
stderr_has "DEM steady at t = "
for f in dem/case.yaml dem/collision_kernel.csv dem/impact_table.csv dem/steady.csv dem/timeseries.csv \
         result.h5 summary.csv; do
  [ -s "$WORK/out/$f" ] || fail "missing $f"
done
[ ! -e "$WORK/out/dem.partial" ] || fail "dem.partial left after a complete DEM stage"

# Classes from the grid: the pivots 1.5e-10 * 2^k m^3 with diameters in
# [2, 4] mm are k = 5, 6, 7; three classes of equal width in ln d take one
# each, edges halfway (geometric) between them and half a step outside.
awk 'function d(v) { return (6 * v / 3.141592653589793)^(1 / 3) }
     BEGIN { d0 = d(1.5e-10 * 32); d1 = d(1.5e-10 * 64); d2 = d(1.5e-10 * 128)
             printf "%.6g %.6g %.6g %.6g\n", d0 / sqrt(d1 / d0) / 2, sqrt(d0 * d1) / 2, sqrt(d1 * d2) / 2,
                    d2 * sqrt(d2 / d1) / 2 }' \
  > "$WORK/expected-radii"
sed -n 's/.*radius: \[\([^,]*\), \([^]]*\)\].*/\1 \2/p' "$WORK/out/dem/case.yaml" |
  awk '{ printf "%.6g %.6g\n", $1, $2 }' | tr '\n' ' ' > "$WORK/radii"
read -r e0 e1 e2 e3 < "$WORK/expected-radii"
[ "$(cat "$WORK/radii")" = "$e0 $e1 $e1 $e2 $e2 $e3 " ] ||
  fail "derived radii $(cat "$WORK/radii"), expected $e0 $e1 | $e1 $e2 | $e2 $e3"
[ "$(cut -d, -f1,2,5 "$WORK/out/dem/classes.csv" | tr '\n' ' ')" = "class,name,pbm_cells 1,c1,1 2,c2,1 3,c3,1 " ] ||
  fail "classes.csv: $(cat "$WORK/out/dem/classes.csv")"
grep -q '12 PBM cells outside them take the nearest class' "$WORK/out/dem/classes.json" || fail "classes.json lacks the outside count"
grep -q '^edges' "$WORK/out/dem/collision_kernel.csv" || fail "collision_kernel.csv has no edges line"
[ "$(grep '^edges' "$WORK/out/dem/collision_kernel.csv" | tr ',' '\n' | wc -l)" = 5 ] ||
  fail "collision_kernel.csv: expected 3 classes"

# The detector fired and its figures are written (the verdict in steady.json's description).
grep -qF '\nsteady\n' "$WORK/out/dem/steady.json" || fail "steady.json does not say steady"
head -1 "$WORK/out/dem/steady.csv" | grep -q '^time,holdup_mass,collisions_per_s,kinetic_energy,holdup_mean,holdup_deviation,collisions_mean,collisions_deviation,kinetic_mean,kinetic_deviation,steady$' ||
  fail "steady.csv header: $(head -1 "$WORK/out/dem/steady.csv")"
! grep -q '^#' "$WORK/out/dem/steady.csv" "$WORK/out/dem/classes.csv" || fail "'#' lines in steady.csv or classes.csv"
grep -q ',1$' "$WORK/out/dem/steady.csv" || fail "no steady row in steady.csv"
grep -qF '\ndrift of the window means from the firing to the end: hold-up mass 0 %' "$WORK/out/dem/steady.json" ||
  fail "steady.json lacks the drift after the firing (the closed drum's hold-up is constant)"

# The DEM stops steady.collect (default window x sample_every = 0.015 s) after the detector
# fired, not at max_time (0.07 s); dem/case.yaml holds the duration as run.
t_fire=$(awk -F, 'NR > 1 && $NF == 1 { print $1; exit }' "$WORK/out/dem/steady.csv")
t_last=$(tail -1 "$WORK/out/dem/timeseries.csv" | cut -d, -f1)
awk -v a="$t_fire" -v b="$t_last" 'BEGIN { exit !(a > 0 && b < 0.07 && (b - a - 0.015)^2 < 1e-12) }' ||
  fail "the DEM did not stop 0.015 s after the detector fired ($t_fire s): last sample at $t_last s"
dur=$(sed -n 's/.*duration: "\{0,1\}\([0-9.e+-]*\).*/\1/p' "$WORK/out/dem/case.yaml")
awk -v a="$dur" -v b="$t_last" 'BEGIN { exit !((a - b)^2 < 1e-18) }' ||
  fail "dem/case.yaml's duration '$dur' is not the duration as run ($t_last s)"

# The same two commands by hand: the DEM case as written, then the PBM with its tables.
run_rc 0 "$BIN" dem "$WORK/out/dem/case.yaml" --out "$WORK/manual-dem" --quiet
for f in collision_kernel.csv impact_table.csv; do
  cmp -s "$WORK/out/dem/$f" "$WORK/manual-dem/$f" || fail "$f differs from a manual gransim dem run"
done
{ echo "$pbm"; mechs "file: manual-dem/collision_kernel.csv, measure: diameter, " \
                     "file: manual-dem/impact_table.csv, measure: diameter, "; } > "$WORK/manual.yaml"
run_rc 0 "$BIN" run "$WORK/manual.yaml" --out "$WORK/manual" --quiet
cmp -s "$WORK/out/summary.csv" "$WORK/manual/summary.csv" || fail "summary.csv differs from the manual run"
if command -v h5dump >/dev/null; then
  for ds in /number /ledger; do
    [ "$(h5dump -d $ds -m %.17g "$WORK/out/result.h5" | tail -n +3)" = \
      "$(h5dump -d $ds -m %.17g "$WORK/manual/result.h5" | tail -n +3)" ] || fail "$ds differs from the manual run"
  done
fi

# --resume: a complete DEM stage is skipped, the PBM result is the same.
cp "$WORK/out/summary.csv" "$WORK/summary-first.csv"
run_rc 0 "$BIN" couple "$WORK/tiny.yaml" --out "$WORK/out" --resume
stderr_has "DEM stage complete"
stderr_lacks "DEM stage ("
cmp -s "$WORK/out/summary.csv" "$WORK/summary-first.csv" || fail "summary.csv changed on --resume"
# a DEM stage killed before its tables were complete (only dem.partial) runs again
mv "$WORK/out/dem" "$WORK/out/dem.partial"
rm "$WORK/out/dem.partial/collision_kernel.csv"
run_rc 0 "$BIN" couple "$WORK/tiny.yaml" --out "$WORK/out" --resume --quiet
[ -s "$WORK/out/dem/collision_kernel.csv" ] || fail "--resume did not rerun an incomplete DEM stage"
cmp -s "$WORK/out/dem/collision_kernel.csv" "$WORK/manual-dem/collision_kernel.csv" || fail "rerun DEM stage differs"

# Killed in the PBM stage: --resume skips the DEM and continues the PBM from its
# partial files, ending where an uninterrupted run ends (more output times and
# shorter steps than above, so that the PBM lasts long enough to be killed).
sed 's/output: {end: 10, count: 6}/output: {end: 10, count: 41, checkpoint: 0}\nsolver: {method: rk, max_step: 1.0e-4}/' \
  "$WORK/tiny.yaml" > "$WORK/slow.yaml"
run_rc 0 "$BIN" couple "$WORK/slow.yaml" --out "$WORK/slow-ref" --quiet --threads 1
"$BIN" couple "$WORK/slow.yaml" --out "$WORK/slow" --quiet --threads 1 2>"$WORK/killed.err" &
pid=$!
BG_PIDS+=("$pid")
kill_part_way "$pid" "$WORK/slow/.summary.csv.partial" "$WORK/killed.err"
wait "$pid" 2>/dev/null || true
[ -s "$WORK/slow/dem/collision_kernel.csv" ] || fail "the DEM stage was not complete when the PBM ran"
[ ! -e "$WORK/slow/summary.csv" ] || fail "the killed run wrote summary.csv"
run_rc 0 "$BIN" couple "$WORK/slow.yaml" --out "$WORK/slow" --resume --threads 1
stderr_has "DEM stage complete"
cmp -s "$WORK/slow/summary.csv" "$WORK/slow-ref/summary.csv" || fail "the resumed PBM differs from an uninterrupted one"

# The dem section as a file name (relative to the coupled case).
echo "$demcase" > "$WORK/drum-dem.yaml"
{ echo "$pbm"; mechs "" ""; echo "dem: drum-dem.yaml"; echo "$coupling"; } > "$WORK/byname.yaml"
run_rc 0 "$BIN" couple --check "$WORK/byname.yaml"
stdout_has "3 size classes, 3 walls"

# The detector not firing: a clear error with its last figures, no tables in dem/.
sed 's/max_time: 0.07/max_time: 0.015/' "$WORK/tiny.yaml" > "$WORK/short.yaml"
run_rc 1 "$BIN" couple "$WORK/short.yaml" --out "$WORK/short" --quiet
stderr_has "did not reach a steady state by t = 0.015 s (coupling.steady.max_time)"
stderr_has "the collision rate"
stderr_has "tolerance 50 %"
[ ! -e "$WORK/short/dem" ] || fail "an unsteady DEM stage was taken as complete"
grep -qF '\nNOT STEADY' "$WORK/short/dem.partial/steady.json" || fail "steady.json does not say NOT STEADY"

# Bad input.
bad() { # bad NAME SED_SCRIPT EXPECTED_STDERR
  sed "$2" "$WORK/tiny.yaml" > "$WORK/$1.yaml"
  run_rc 1 "$BIN" check "$WORK/$1.yaml"
  stderr_has "$3"
}
bad fractions 's/fractions: \[0.3, 0.4, 0.3\]/fractions: [0.5, 0.5]/' \
  "$WORK/fractions.yaml:30: dem: fill[0].fractions: expected 3 fractions (one per class), got 2"
bad count 's/count: 3,/count: 5,/' "count = 5 classes but only 3 distinct PBM cell diameters lie in"
bad outside 's/material: granule}$/material: granule, outside: error}/' \
  "PBM cell 1 (diameter 0.000457078 m) lies outside the DEM classes"
bad window 's/min_diameter: 2.0e-3, max_diameter: 4.0e-3/min_diameter: 1.0, max_diameter: 2.0/' \
  "no PBM cell has a diameter in [min_diameter, max_diameter] = [1, 2] m"
bad classes 's/^  materials:/  classes: [{name: a, radius: 1.0e-3, material: granule}]\n  materials:/' \
  "dem.classes: the DEM classes of a coupled case come from the PBM grid (coupling.classes)"
bad duration 's/^    time_step: 5.0e-6/&\n    duration: 1/' \
  "set by the coupling (coupling.steady.max_time) in a coupled case"
bad file 's/type: table, /type: table, file: x.csv, /' \
  "mechanisms[0].kernel.file = 'x.csv': set by the coupling in a coupled case"
bad wall 's/  steady: {window/  impacts: {wall: lid}\n  steady: {window/' "coupling.impacts: wall 'lid' is not a wall of the DEM case"
bad nomode 's/mode: one_way/mode_: one_way/' "missing key 'mode' (one_way | two_way)"
bad mode 's/mode: one_way/mode: three_way/' "coupling.mode = 'three_way'"
bad twofrac 's/mode: one_way/mode: two_way/' "dem.fill[0].fractions: set by the coupling (the PBM population, coupling.mode two_way)"
bad nodem '/^dem:/,/^coupling:/{/^coupling:/!d}' "missing key 'dem' (the DEM case"
bad nosteady '/steady: {window/d' "missing key 'steady' in coupling"
sed '/^coupling:/,$d' "$WORK/tiny.yaml" > "$WORK/nocoupling.yaml"
run_rc 1 "$BIN" couple "$WORK/nocoupling.yaml" --out "$WORK/x"
stderr_has "missing key 'coupling' in the top level"
sed 's/kernel: {type: table, /kernel: {type: constant, /; s/type: dem_impact, /type: power, rate: 1, /; s/, u_break: 0.5//' \
  "$WORK/tiny.yaml" > "$WORK/notable.yaml"
run_rc 1 "$BIN" check "$WORK/notable.yaml"
stderr_has "needs a \`table\` aggregation kernel or a \`dem_impact\` breakage selection"
# gransim run points at gransim couple
run_rc 1 "$BIN" run "$WORK/tiny.yaml" --out "$WORK/x"
stderr_has "is a coupled PBM-DEM case (a \`coupling:\` section): run it with \`gransim couple"

# The CoriMix example validates (its run, ~5 s, is in the README).
run_rc 0 "$BIN" check "$SRC/examples/corimix-coupled.yaml"
stdout_has "valid. one_way: 3 DEM classes from the grid"
echo "cli_couple: ok"
