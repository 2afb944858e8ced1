# gransim dem-reduce on the bundled CoriMix dumps: summary, kernel table, and
# the table read back by a case (gransim check); bad arguments.
source "$(dirname "$0")/cli-lib.sh" "$@"

data=$SRC/examples/data/corimix/dem_dumps
run_rc 2 "$BIN" dem-reduce
run_rc 2 "$BIN" dem-reduce "$data" --contacts bogus
stderr_has "expected auto, ppcoll, cc or cc-partner"
run_rc 1 "$BIN" dem-reduce "$WORK"
stderr_has "no pair of collision<STEP>.atom and impact<STEP>.atom"
[ -d "$data" ] || fail "the bundled dumps are missing: $data"
# all 16 types have one diameter: the table needs the PBM's edges
run_rc 1 "$BIN" dem-reduce "$data" --out "$WORK/t.csv"
stderr_has "give the PBM's class edges"
edges=$(awk 'BEGIN { e = 1e-9; for (k = 0; k <= 16; k++) { printf "%s%.6g", k ? "," : "", e; e *= 2 } }')
run_rc 2 "$BIN" dem-reduce "$data" --edges 1,2,3 --out "$WORK/t.csv"
stderr_has "expected 17 (nclass + 1)"
run_rc 0 "$BIN" dem-reduce "$data" --edges "$edges" --measure volume --out "$WORK/dem-kernel.csv"
stdout_has "9 snapshots (steps 18600000..19000000), 16 classes"
stdout_has "from the ppcoll pair dumps"
stdout_has "wrote $WORK/dem-kernel.csv"
[ "$(grep -c '^[0-9]' "$WORK/dem-kernel.csv")" = 16 ] || fail "expected 16 rows in the table"
cat > "$WORK/case.yaml" <<'YAML'
grid:
  axes:
    - {name: solid, type: geometric, min: 1e-9, max: 6.5e-5, cells: 16, zero_first: true}
initial: {type: exponential, number: 100, mean: 1e-6}
mechanisms:
  - type: aggregation
    kernel: {type: table, file: dem-kernel.csv, measure: volume, beta0: 1e-3}
output: {end: 1, count: 2}
YAML
run_rc 0 "$BIN" check "$WORK/case.yaml"
stdout_has "valid"
echo "cli_dem_reduce: ok"
