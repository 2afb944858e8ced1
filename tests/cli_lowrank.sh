# aggregation method fft with rank_tolerance: the run log and result.h5 say
# the rank the tolerance chose (a continuum Brownian kernel is exactly rank
# 3) and how the form was built (cross approximation, error over every entry;
# on 8192 cells estimated from sampled rows); a run whose kernel has an exact form says nothing of ranks; gransim
# check refuses rank_tolerance with method pairs at its line.
source "$(dirname "$0")/cli-lib.sh" "$@"

# brownian_case NAME CELLS: a continuum Brownian kernel through its low-rank form
brownian_case() {
  write_case "$1.yaml" "grid: {axes: [{name: v, type: linear, min: 0.5, max: 40, cells: $2}]}
initial: {type: cell, number: 1, index: [2]}
mechanisms:
  - {type: aggregation, redistribution: fixed_pivot, method: fft, rank_tolerance: 1.0e-8,
     kernel: {type: brownian, beta0: 0.05}}
output: {end: 1}"
}

lowrank=$(brownian_case lowrank 80)
run_rc 0 "$BIN" run "$lowrank" --out "$WORK/out" --threads 1
stderr_has "mechanisms[0] (aggregation): method fft with a low-rank kernel form of rank 3" \
  "adaptive cross approximation of" "error over all entries"
h5dump -a /mechanism_notes "$WORK/out/result.h5" | grep -qF "low-rank kernel form of rank 3" ||
  fail "result.h5 has no attribute mechanism_notes naming rank 3"

# above the dense decomposition's 4096 cells: accepted, the error estimated
# from sampled rows
large=$(brownian_case large 8192)
run_rc 0 "$BIN" run "$large" --out "$WORK/out3" --threads 1
stderr_has "low-rank kernel form of rank 3" "error estimated from 256 random rows"

exact=$(write_case exact.yaml "grid: {axes: [{name: v, type: linear, min: 0.5, max: 40, cells: 80}]}
initial: {type: cell, number: 1, index: [2]}
mechanisms:
  - {type: aggregation, redistribution: fixed_pivot, method: fft, kernel: {type: constant, beta0: 0.05}}
output: {end: 1}")
run_rc 0 "$BIN" run "$exact" --out "$WORK/out2" --threads 1
stderr_lacks "low-rank"

pairs=$(write_case pairs.yaml "grid: {axes: [{name: v, type: linear, min: 0.5, max: 40, cells: 80}]}
initial: {type: cell, number: 1, index: [2]}
mechanisms:
  - {type: aggregation, redistribution: fixed_pivot, rank_tolerance: 1.0e-8,
     kernel: {type: brownian, beta0: 0.05}}
output: {end: 1}")
run_rc 1 "$BIN" check "$pairs"
stderr_has "pairs.yaml:4" "rank_tolerance" "applies to method fft or auto"
echo "cli_lowrank: ok"
