# `gransim dem`: the CoriMix example runs and writes its tables; the collision
# table is one the PBM's `table` kernel reads and the impact table one its
# `dem_impact` breakage selection reads; case-file errors name file:line, key
# and value; a too large time step is warned about once; --check validates the
# DEM examples of docs/case-files.md (blocks starting "# dem-example: NAME").
source "$(dirname "$0")/cli-lib.sh" "$@"

run_rc 0 "$BIN" dem --help
stdout_has "collision_kernel.csv"

# the example, shortened to 2000 steps; its mesh paths are relative to the case
# file, so the copy gets the bundled meshes beside it
sed 's/duration: 0.02/duration: 0.01/; s/vtk_every: 0.01/vtk_every: 0.005/' \
  "$SRC/examples/dem-corimix.yaml" > "$WORK/corimix.yaml"
grep -q '^  duration: 0.01$' "$WORK/corimix.yaml" || fail "could not shorten the CoriMix example"
mkdir -p "$WORK/data"
ln -s "$SRC/examples/data/corimix" "$WORK/data/corimix"
run_rc 0 "$BIN" dem "$WORK/corimix.yaml" --out "$WORK/out" --quiet
for f in timeseries.csv collisions.csv collision_kernel.csv impacts.csv impact_velocity.csv \
         impact_table.csv impact_table_impeller.csv impact_table_shell.csv velocity.csv residence.csv \
         residence_class.csv vtk/particles_000001.vtp vtk/impeller_000001.vtp vtk/particles.pvd; do
  [ -s "$WORK/out/$f" ] || fail "missing $f"
done
# collisions happened between every pair of classes, and impacts on the impeller
awk -F, 'NR > 1 && $5 <= 0 { bad = 1 } END { exit bad }' "$WORK/out/collisions.csv" ||
  fail "a class pair without collisions: $(cat "$WORK/out/collisions.csv")"
grep -q '^impeller,1,fine,[1-9]' "$WORK/out/impacts.csv" || fail "no impeller impacts"
# pandas reads the tables and VTK the frames as they are (the meshes: 2802 and 1948 faces)
/usr/bin/python3 "$SRC/tests/dem_outputs.py" "$WORK/out" 0.005 1.0e-3,1.5e-3,2.0e-3 impeller=2802 shell=1948 ||
  fail "the DEM outputs do not read as they are"
# the PBM reads the collision table as its aggregation kernel
cp "$WORK/out/collision_kernel.csv" "$WORK/C.csv"
# the PBM cases below share their grid and initial distribution
pbm_head='grid:
  axes:
    - {name: solid, type: geometric, min: 1.0e-11, max: 1.0e-6, cells: 20, zero_first: true}
initial: {type: exponential, number: 1, mean: 4.0e-9}'
cat > "$WORK/pbm.yaml" <<YAML
title: DEM collision frequencies as the aggregation kernel
$pbm_head
mechanisms:
  - type: aggregation
    kernel: {type: table, file: C.csv, measure: diameter, beta0: 1.0e-3}
output: {end: 1, count: 2}
YAML
if "$BIN" check "$WORK/pbm.yaml" > "$WORK/pbm.out" 2>&1; then :; else
  cat "$WORK/pbm.out" >&2
  fail "the PBM does not accept collision_kernel.csv"
fi
# ... and the impact tables as its breakage selection (all walls, the impeller alone)
cp "$WORK/out/impact_table.csv" "$WORK/I.csv"
cp "$WORK/out/impact_table_impeller.csv" "$WORK/Iimp.csv"
for t in I.csv Iimp.csv; do
  cat > "$WORK/pbm-break.yaml" <<YAML
title: DEM wall impacts as the breakage selection
$pbm_head
mechanisms:
  - type: breakage
    selection: {type: dem_impact, file: $t, measure: diameter, u_break: 2.0}
    daughters: {type: halves}
output: {end: 1, count: 2}
YAML
  if "$BIN" check "$WORK/pbm-break.yaml" > "$WORK/pbm.out" 2>&1; then :; else
    cat "$WORK/pbm.out" "$WORK/$t" >&2
    fail "the PBM does not accept $t (impact table) as a dem_impact selection"
  fi
done

# errors name file, line, key and value
cat > "$WORK/bad.yaml" <<'YAML'
dem:
  time_step: 1.0e-6
  duration: 0.001
  box: {lo: [0, 0, 0], hi: [0.1, 0.1, 0.1]}
materials:
  - {name: g, E: -5, nu: 0.2, e: 0.4, mu_s: 0.5, density: 500}
classes:
  - {name: a, radius: 1.0e-3, material: g}
YAML
run_rc 1 "$BIN" dem "$WORK/bad.yaml" --out "$WORK/bad"
stderr_has "bad.yaml:6: materials[0].E = '-5'"
sed -i 's/E: -5/E: 8.0e6/; s/radius: 1.0e-3/radius: 1.0e-3, colour: red/' "$WORK/bad.yaml"
run_rc 1 "$BIN" dem "$WORK/bad.yaml" --out "$WORK/bad"
stderr_has "unknown key 'colour'"
sed -i 's/, colour: red//; s/^  duration: 0.001$/  duration: 0.001\n  mesh_contacts: nearest/' "$WORK/bad.yaml"
run_rc 1 "$BIN" dem "$WORK/bad.yaml" --out "$WORK/bad"
stderr_has "bad.yaml:4: dem.mesh_contacts = 'nearest'"

# a time step above 20 % of the Rayleigh time: one warning, from reading the case
cat > "$WORK/big-step.yaml" <<'YAML'
dem:
  time_step: 2.0e-5
  duration: 1.0e-4
  gravity: [0, 0, -9.81]
  box: {lo: [0, 0, 0], hi: [0.02, 0.02, 0.02]}
materials:
  - {name: g, E: 8.0e6, nu: 0.2, e: 0.4, mu_s: 0.5, density: 500}
classes:
  - {name: a, radius: 1.0e-3, material: g}
fill:
  - {region: {box: {lo: [0.002, 0.002, 0.002], hi: [0.018, 0.018, 0.018]}}, count: 5}
YAML
run_rc 0 "$BIN" dem "$WORK/big-step.yaml" --out "$WORK/big" --quiet
stderr_has "of the Rayleigh time"
[ "$(grep -c 'Rayleigh' "$WORK/stderr")" = 1 ] || { show_output; fail "the Rayleigh-time warning is not printed exactly once"; }

# DEM examples of the case-file documentation
ex=$WORK/doc
mkdir -p "$ex"
awk -v dir="$ex" '
  /^```/ { if (inblock) { if (out) close(out); out = ""; inblock = 0 } else { inblock = 1; first = 1 }; next }
  inblock && first { first = 0; if ($0 ~ /^# dem-example: [A-Za-z0-9._-]+$/) out = dir "/" $3 }
  out { print > out }' "$SRC/docs/case-files.md"
n=0
for f in "$ex"/*.yaml; do
  [ -e "$f" ] || break
  run_rc 0 "$BIN" dem --check "$f"
  stdout_has "valid"
  n=$((n + 1))
done
[ "$n" -ge 1 ] || fail "no '# dem-example:' blocks in docs/case-files.md"
echo "cli_dem: ok ($n documented examples)"
