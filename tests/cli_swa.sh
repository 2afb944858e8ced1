# gransim check / run with solver.method: swa: the result files have the
# documented layout (summary.csv with ci_ columns, result.h5 datasets), the
# same seed gives identical results with 1 and 2 threads, and bad SWA keys
# are reported with file, line, key, value and expectation.
source "$(dirname "$0")/cli-lib.sh" "$@"

ok=$(write_case swa.yaml "title: swa run
grid:
  compartments: 2
  axes: [{name: solid, type: geometric, min: 1e-3, max: 1e3, cells: 24, zero_first: true}]
initial: {type: exponential, number: 1000, mean: 1}
mechanisms:
  - type: aggregation
    kernel: {type: constant, beta0: 1e-3}
  - type: transfer
    residence_time: 4
solver: {method: swa, particles: 512, runs: 4, seed: 3}
output: {end: 4, count: 3}")

run_rc 0 "$BIN" check "$ok"
stdout_has "swa.yaml: valid. swa solver" "2 compartments" "4 runs of 512 particles"
# the discretisation report: 4 runs x 384 particles of an exponential (number exact)
stdout_has "discretisation: $WORK/swa.yaml:5: initial: the particles hold number 1000 (asked 1000), volume of 'solid' " \
  "expected from sampling 0.026 (one standard error of 1536 particles), above the tolerance"

run_rc 0 "$BIN" run "$ok" --out "$WORK/a" --threads 1
stderr_has "swa, 4 runs of 512 particles done to t = 4" "discretisation: $WORK/swa.yaml:5: initial: the particles hold number 1000"
for f in .result.h5.partial .summary.csv.partial; do [ ! -e "$WORK/a/$f" ] || fail "$f left behind"; done
head -1 "$WORK/a/summary.csv" | grep -qxF 'time [s],compartment,M0 [1],M1 [m^3],M2 [m^6],d10 [m],d50 [m],d90 [m],mean_solid [m^3],total_solid [m^3],ci_M0 [1],ci_M1 [m^3],ci_M2 [m^6],ci_d10 [m],ci_d50 [m],ci_d90 [m],ci_mean_solid [m^3],ci_total_solid [m^3]' ||
  fail "unexpected summary.csv header: $(head -1 "$WORK/a/summary.csv")"
[ "$(wc -l <"$WORK/a/summary.csv")" = 7 ] || fail "expected 1 + 3 times x 2 compartments lines"
# at t = 0: compartment 1 holds 1000 particles exactly (the weights), compartment 2 none
awk -F, 'NR == 2 && ($3 != 1000) { exit 1 } NR == 3 && ($3 != 0) { exit 1 }' "$WORK/a/summary.csv" ||
  fail "initial M0 should be 1000 and 0: $(sed -n 2,3p "$WORK/a/summary.csv")"
h5ls -r "$WORK/a/result.h5" >"$WORK/h5" || fail "h5ls failed"
for d in /time /number /number_ci /outside /particles /summary/M0 /summary_ci/d50 /grid/solid/edges /case \
  /discretisation/requested /discretisation/represented /discretisation/sampling_error /discretisation/error; do
  grep -q "^$d " "$WORK/h5" || fail "result.h5 lacks $d"
done

run_rc 0 "$BIN" run "$ok" --out "$WORK/b" --threads 2
cmp -s "$WORK/a/summary.csv" "$WORK/b/summary.csv" || fail "1 and 2 threads give different results"

run_rc 2 "$BIN" run "$ok" --out "$WORK/c" --resume
stderr_has "--resume is not available with the swa solver"

bad=$(write_case bad.yaml "grid:
  axes: [{name: solid, type: linear, min: 0, max: 10, cells: 10}]
initial: {type: point, number: 10, at: 1}
solver: {method: swa, particles: 8}
output: {end: 1}")
run_rc 1 "$BIN" check "$bad"
stderr_has "bad.yaml:4: solver.particles = '8': expected"

bad=$(write_case bad2.yaml "grid:
  axes: [{name: solid, type: linear, min: 0, max: 10, cells: 10}]
initial: {type: point, number: 10, at: 1}
mechanisms:
  - type: aggregation
    kernel: {type: constant, beta0: 1}
    scheme: direct
solver: {method: swa}
output: {end: 1}")
run_rc 1 "$BIN" check "$bad"
stderr_has "bad2.yaml:7: mechanisms[0].scheme = 'direct': expected"

bad=$(write_case bad3.yaml "grid:
  axes: [{name: solid, type: linear, min: 0, max: 10, cells: 10}]
initial: {type: point, number: 10, at: 1}
mechanisms:
  - type: growth
solver: {method: swa}
output: {end: 1}")
run_rc 1 "$BIN" check "$bad"
stderr_has "bad3.yaml:5: mechanisms[0].type = 'growth': unknown mechanism (swa solver) type; expected one of: aggregation"

bad=$(write_case bad4.yaml "grid:
  axes: [{name: solid, type: linear, min: 0, max: 10, cells: 10}]
initial: {type: point, number: 10, at: 1}
solver: {method: swa, contraction: shrink}
output: {end: 1}")
run_rc 1 "$BIN" check "$bad"
stderr_has "bad4.yaml:4: solver.contraction = 'shrink': expected one of: merge, drop"

empty=$(write_case empty.yaml "grid:
  axes: [{name: solid, type: linear, min: 0, max: 10, cells: 10}]
mechanisms:
  - {type: feed, rate: 10, distribution: {type: point, at: 1}}
solver: {method: swa}
output: {end: 1}")
run_rc 1 "$BIN" check "$empty"
stderr_has "set solver.reference_number"

# the bundled twin-screw example (McGuire et al. 2018) is valid and runs
run_rc 0 "$BIN" check "$SRC/examples/twin-screw.yaml"
stdout_has "valid. swa solver, 4 coordinates, 3 compartments, 6 mechanisms"
run_rc 0 "$BIN" run "$SRC/examples/twin-screw.yaml" --out "$WORK/ts" --quiet
[ "$(wc -l <"$WORK/ts/summary.csv")" = 31 ] || fail "twin-screw: expected 1 + 10 times x 3 compartments lines"
h5ls -r "$WORK/ts/result.h5" >"$WORK/h5" || fail "h5ls failed"
for d in /sieve/edges /sieve/mass_fraction /sieve/mass_fraction_ci; do
  grep -q "^$d " "$WORK/h5" || fail "twin-screw result.h5 lacks $d"
done

# a result file that cannot grow (as on a full disk): exit 1 with the cause,
# no result files; HDF5's exit handler had crashed on the half-closed file
# (status 139).  SIGXFSZ ignored: the write fails instead of killing the process
run_rc 1 bash -c 'trap "" XFSZ; ulimit -f 20; exec "$0" "$@"' "$BIN" run "$SRC/examples/twin-screw.yaml" --out "$WORK/full" --quiet
stderr_has "cannot write $WORK/full/.result.h5.partial: file write failed: File too large"
no_result_files "$WORK/full"

echo "cli_swa: ok"
