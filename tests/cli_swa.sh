# gransim check / run with solver.method: swa: the result files have the
# documented layout (summary.csv with ci_ columns, result.h5 datasets), the
# same seed gives identical results with 1 and 2 threads, bad SWA keys
# are reported with file, line, key, value and expectation, and a run whose
# jump rate diverges (a gelling kernel) or that spends solver.max_jumps_per_output
# stops with exit 1, the reason and no result files.
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

# bad_solver NAME SOLVER_KEYS MESSAGE: a one-particle-type case whose solver
# map holds SOLVER_KEYS is refused by check at line 4 with MESSAGE.
bad_solver() {
  local f
  f=$(write_case "$1.yaml" "grid:
  axes: [{name: solid, type: linear, min: 0, max: 10, cells: 10}]
initial: {type: point, number: 10, at: 1}
solver: {method: swa, $2}
output: {end: 1}")
  run_rc 1 "$BIN" check "$f"
  stderr_has "$1.yaml:4: $3"
}

bad_solver bad "particles: 8" "solver.particles = '8': expected"

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

bad_solver bad4 "contraction: shrink" "solver.contraction = 'shrink': expected one of: merge, drop"

bad_solver bad5 "max_jumps_per_output: 0" "solver.max_jumps_per_output = '0': expected an integer >= 1"

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

# The product kernel gels (t_gel = 1/(beta0 M2(0)) = 0.5 here), after which the
# swa scheme's largest particles grow ever faster: seed 1 reaches a total rate
# of ~1e17/s at t = 0.479 after ~25 000 jumps, and the time then stands still.
# The run had looped for ever; it now stops a million jumps later.
gel() {
  write_case gel.yaml "grid:
  axes:
    - {name: v, type: geometric, min: 1e-3, max: 1e3, cells: 30, zero_first: true}
initial: {type: exponential, number: 1000, mean: 1}
mechanisms:
  - type: aggregation
    kernel: {type: product, beta0: 1e-3}
solver: {method: swa, particles: 128, runs: 1, seed: 1${1:-}}
output: {end: 2, count: 2}"
}
run_rc 1 timeout 120 "$BIN" run "$(gel)" --out "$WORK/gel" --quiet
stderr_has "gransim: run 1: the simulated time stands still at t = 0.4790444 after " \
  " jumps of the output interval from t = 0 to 2: the jump rate diverges, and the last 1000000 jumps did not advance the time at all" \
  "; mechanisms[0] (aggregation) with kernel product gives 100 % of the rate (compartment 1): a kernel of product form gels" \
  "use a non-gelling kernel (constant or sum) or an end time before the gel point"
stderr_lacks "max_jumps_per_output"
no_result_files "$WORK/gel"
# the same with a budget it spends first: the last tenth of the budget took
# under a thousandth of the time of the first (a rate grown a thousandfold)
run_rc 1 timeout 120 "$BIN" run "$(gel ", max_jumps_per_output: 20000")" --out "$WORK/gel" --quiet
stderr_has "gransim: run 1: solver.max_jumps_per_output = 20000 jumps took the run from t = 0 only to t = 0.4790444" \
  " on the way to the output time 2: the jump rate diverges, the simulated time advanced by only " \
  " over the last 2000 jumps against " "(compartment 1): a kernel of product form gels" \
  ", fewer solver.particles, or a larger solver.max_jumps_per_output"
no_result_files "$WORK/gel"

# The budget counts the jumps (accepted and fictitious, as the report's
# total) of each output interval of each run: a case whose intervals take J1
# and J2 jumps passes with max(J1, J2) and with J1 + J2 - 1 (the count
# restarts at every output time), gives the same results, and fails with
# max(J1, J2) - 1, saying that the rate does not diverge.
budget() {
  write_case budget.yaml "grid:
  axes: [{name: solid, type: geometric, min: 1e-3, max: 1e3, cells: 24, zero_first: true}]
initial: {type: exponential, number: 1000, mean: 1}
mechanisms:
  - type: aggregation
    kernel: {type: constant, beta0: 1e-3, majorant_factor: 2}
solver: {method: swa, particles: 256, runs: 1, seed: 5$2}
output: {end: $1, count: $3}"
}
jumps() { sed -n 's/.* done to t = .* (\([0-9]*\) jumps, .*/\1/p' "$WORK/stderr"; }
run_rc 0 "$BIN" run "$(budget 2 "" 2)" --out "$WORK/j1"
j1=$(jumps)
run_rc 0 "$BIN" run "$(budget 4 "" 3)" --out "$WORK/j"
j=$(jumps)
j2=$((j - j1))
[ "$j1" -gt 100 ] && [ "$j2" -gt 100 ] || fail "expected over 100 jumps in each interval, got $j1 and $j2"
most=$((j1 > j2 ? j1 : j2))
for n in "$most" $((j - 1)); do
  run_rc 0 "$BIN" run "$(budget 4 ", max_jumps_per_output: $n" 3)" --out "$WORK/jn"
  cmp -s "$WORK/j/summary.csv" "$WORK/jn/summary.csv" || fail "max_jumps_per_output: $n changed the results"
done
run_rc 1 "$BIN" run "$(budget 4 ", max_jumps_per_output: $((most - 1))" 3)" --out "$WORK/jf"
t0=$([ "$j1" -ge "$j2" ] && echo 0 || echo 2)
stderr_has "gransim: run 1: solver.max_jumps_per_output = $((most - 1)) jumps took the run from t = $t0 only to t = " \
  "the interval needs about " "; mechanisms[0] (aggregation) with kernel constant gives 100 % of the rate (compartment 1): " \
  "use output times closer together, fewer solver.particles, or a larger solver.max_jumps_per_output"
stderr_lacks "diverges"
no_result_files "$WORK/jf"

echo "cli_swa: ok"
