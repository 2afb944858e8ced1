# gransim run --resume on two MPI ranks is exact: a 2-rank run killed with
# SIGKILL at a random moment and resumed on two ranks writes the very files
# an uninterrupted 2-rank run writes (h5diff without tolerance, summary.csv
# byte for byte), with rk and euler (the integrators that run on ranks), also
# when compartments move between ranks at every decision, and with rk taking
# per-compartment steps (each rank's block its own, the records sent between
# them, blocks moved at output times).  The case is the
# CoriMix example on more compartments with shared steps (cli_resume_exact.sh
# in one process).
#
# Default: 8 compartments to t = 30, 1 kill each; GRANSIM_TEST_LONG=1
# (mpi_resume_exact_long, ctest -L long): 32 compartments to t = 85, 10 kills.
# ctest-long
#
# Usage: bash mpi_resume_exact.sh GRANSIM_BINARY SOURCE_DIR MPIEXEC [MPIEXEC_OPTIONS...]
source "$(dirname "$0")/mpi-lib.sh" "$@"
command -v h5diff >/dev/null || fail "h5diff (hdf5-tools) is needed"

ncomp=8 end=30 trials=1
if [ "${GRANSIM_TEST_LONG:-0}" = 1 ]; then ncomp=32 end=85 trials=10; fi
ln -s "$(cd "$SRC" && pwd)/examples/data" "$WORK/data"
at="" # output times committed at each kill
length=$(awk -v n="$ncomp" 'BEGIN { printf "%.6g", 0.38 / n }')

n=0
for solver in "rk, rtol: 1.0e-6, atol: 1.0, steps: shared" "euler, steps: shared" \
  "rk, rtol: 1.0e-6, atol: 1.0, steps: per_compartment"; do
  for move in 0 1; do
    n=$((n + 1))
    c=$WORK/case$n.yaml
    sed -e "s/compartments: 4/compartments: $ncomp/" -e "s/length: 0.095/length: $length/" \
      -e "s/^output: .*/output: {end: $end, count: $((end + 1)), checkpoint: 0}/" \
      -e "s/^solver: .*/solver: {method: $solver}/" "$SRC/examples/corimix-continuous.yaml" >"$c"
    grep -q "compartments: $ncomp" "$c" || fail "could not build the case"
    mpi=("${MPI[@]}" -np 2)
    [ "$move" = 0 ] || mpi+=(-x GRANSIM_TEST_MOVE_COMPARTMENTS=1)
    start=$(date +%s.%N)
    run_rc 0 "${mpi[@]}" "$BIN" run "$c" --out "$WORK/ref$n" --threads 1 --quiet
    seconds=$(awk -v a="$start" -v b="$(date +%s.%N)" 'BEGIN { print b - a }')
    for trial in $(seq "$trials"); do
      d=$WORK/run$n-$trial
      fraction=$(random_fraction)
      for try in 1 2 3 4 5 6; do
        rm -rf "$d"
        "${mpi[@]}" "$BIN" run "$c" --out "$d" --threads 1 --quiet >/dev/null 2>"$WORK/killed.err" &
        pid=$!
        BG_PIDS+=("$pid")
        killed=0
        kill_at_random "$pid" "$d/.summary.csv.partial" "$seconds" "$fraction" --match "run $c --out $d" && killed=1
        wait "$pid" 2>/dev/null || true
        [ "$killed" = 1 ] && [ ! -e "$d/result.h5" ] && break
        [ "$try" -lt 6 ] || fail "the 2-rank run ($solver) always ended before it was killed: $(cat "$WORK/killed.err")"
        fraction=$(awk -v f="$fraction" 'BEGIN { print f / 2 }')
      done
      at="$at $((($(wc -l <"$d/.summary.csv.partial") - 1) / ncomp))"
      run_rc 0 "${mpi[@]}" "$BIN" run "$c" --out "$d" --resume --threads 1 --quiet
      what="$solver, moves $move, kill $trial"
      h5diff "$WORK/ref$n/result.h5" "$d/result.h5" >"$WORK/h5diff" 2>&1 ||
        { head -n 20 "$WORK/h5diff" >&2; fail "$d/result.h5 differs from the uninterrupted run's ($what)"; }
      cmp -s "$WORK/ref$n/summary.csv" "$d/summary.csv" || fail "$d/summary.csv differs ($what)"
      rm -rf "$d"
    done
  done
done
echo "mpi_resume_exact: ok ($trials kills each of rk and euler, with and without moves, and of per-compartment steps, on 2 ranks; output times committed at the kills:$at of $((end + 1)))"
