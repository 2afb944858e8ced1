# gransim run --resume is exact: a run killed with SIGKILL at a random moment
# and resumed writes the very files an uninterrupted run writes (h5diff
# without tolerance, summary.csv byte for byte), with every integrator (rk,
# euler, cvode, auto) and with shared and per-compartment steps (the outflow
# stepped exponentially and explicitly).  The case is the
# CoriMix example (aggregation with wetness choices, breakage, spray from
# t = 10, transfer) on more compartments, committing every output time.
#
# Default: 8 compartments to t = 30, 2 kills per integrator and strategy;
# GRANSIM_TEST_LONG=1 (cli_resume_exact_long, ctest -L long): 32 compartments
# to t = 85, 10 kills each.  mpi_resume_exact.sh does the same on two MPI ranks.
# ctest-long
source "$(dirname "$0")/cli-lib.sh" "$@"

ncomp=8 end=30 trials=2
if [ "${GRANSIM_TEST_LONG:-0}" = 1 ]; then ncomp=32 end=85 trials=10; fi
command -v h5diff >/dev/null || fail "h5diff (hdf5-tools) is needed"

ln -s "$(cd "$SRC" && pwd)/examples/data" "$WORK/data"
# the example's granulator cut into ncomp compartments of the same total length
at="" # output times committed at each kill
length=$(awk -v n="$ncomp" 'BEGIN { printf "%.6g", 0.38 / n }')
base_case() {
  sed -e "s/compartments: 4/compartments: $ncomp/" -e "s/length: 0.095/length: $length/" \
    -e "s/^output: .*/output: {end: $end, count: $((end + 1)), checkpoint: 0}/" \
    -e "s/^solver: .*/solver: {method: $1}/" "$SRC/examples/corimix-continuous.yaml"
}

# exact DIR_REF DIR: the same result files, bit for bit
exact() {
  h5diff "$1/result.h5" "$2/result.h5" >"$WORK/h5diff" 2>&1 ||
    { head -n 20 "$WORK/h5diff" >&2; fail "$2/result.h5 differs from the uninterrupted run's ($3)"; }
  cmp -s "$1/summary.csv" "$2/summary.csv" ||
    fail "$2/summary.csv differs from the uninterrupted run's ($3)"
}

n=0
for solver in "rk, rtol: 1.0e-6, atol: 1.0, steps: shared" \
  "rk, rtol: 1.0e-6, atol: 1.0, steps: per_compartment" \
  "rk, rtol: 1.0e-6, atol: 1.0, steps: per_compartment, outflow: explicit" \
  "euler" "cvode, rtol: 1.0e-6, atol: 1.0" "auto, rtol: 1.0e-6, atol: 1.0"; do
  n=$((n + 1))
  c=$WORK/case$n.yaml
  base_case "$solver" >"$c"
  grep -q "compartments: $ncomp" "$c" && grep -q "method: ${solver%%,*}" "$c" || fail "could not build the case ($solver)"
  start=$(date +%s.%N)
  run_rc 0 "$BIN" run "$c" --out "$WORK/ref$n" --threads 1 --quiet
  seconds=$(awk -v a="$start" -v b="$(date +%s.%N)" 'BEGIN { print b - a }')
  for trial in $(seq "$trials"); do
    d=$WORK/run$n-$trial
    fraction=$(random_fraction)
    # killed at a random moment of the run (earlier if the run was quicker)
    for try in 1 2 3 4 5 6; do
      rm -rf "$d"
      "$BIN" run "$c" --out "$d" --threads 1 --quiet 2>"$WORK/killed.err" &
      pid=$!
      BG_PIDS+=("$pid")
      killed=0
      kill_at_random "$pid" "$d/.summary.csv.partial" "$seconds" "$fraction" && killed=1
      wait "$pid" 2>/dev/null || true
      [ "$killed" = 1 ] && [ ! -e "$d/result.h5" ] && break
      [ "$try" -lt 6 ] || fail "the run ($solver) always ended before it was killed: $(cat "$WORK/killed.err")"
      fraction=$(awk -v f="$fraction" 'BEGIN { print f / 2 }')
    done
    at="$at $((($(wc -l <"$d/.summary.csv.partial") - 1) / ncomp))"
    run_rc 0 "$BIN" run "$c" --out "$d" --resume --threads 1 --quiet
    exact "$WORK/ref$n" "$d" "$solver, kill $trial"
    rm -rf "$d"
  done
done
echo "cli_resume_exact: ok ($trials kills each of 4 integrators and strategies, $ncomp compartments; output times committed at the kills:$at of $((end + 1)))"
