# gransim sweep on MPI ranks (built with -DGRANSIM_MPI=ON): the ranks share
# the runs and give a sweep.csv identical to one process's, rank 0 alone
# prints, a failing run is recorded, and a killed sweep resumes on 2 ranks.
#
# Usage: bash mpi_sweep.sh GRANSIM_BINARY SOURCE_DIR MPIEXEC [MPIEXEC_OPTIONS...]
source "$(dirname "$0")/mpi-lib.sh" "$@"

c=$(write_case tiny.yaml "$(lossy_case 1 'output: {end: 2, count: 3}')")
SET=(--set mechanisms.0.kernel.beta0=1e-3,1,2e-3,5e-4,1e-4 --set output.end=1,2 --outputs M2)

run_rc 0 "$BIN" sweep "$c" "${SET[@]}" --out "$WORK/one" --threads 2
for np in 2 3; do
  run_rc 0 timeout 120 "${MPI[@]}" -np $np "$BIN" sweep "$c" "${SET[@]}" --out "$WORK/np$np" --threads 1
  [ "$(grep -c '10 runs: 10 run now, 0 finished before' "$WORK/stderr")" = 1 ] ||
    { show_output; fail "$np ranks: the final message should be printed once (by rank 0)"; }
  stderr_has "8 ok, 2 failed"
  cmp "$WORK/one/sweep.csv" "$WORK/np$np/sweep.csv" || fail "1 process and $np ranks give different sweep.csv"
  [ "$(wc -l <"$WORK/np$np/runs.csv")" = 11 ] || fail "$np ranks: runs.csv has $(wc -l <"$WORK/np$np/runs.csv") lines, expected 11"
done

# resume on 2 ranks after a kill that left 3 rows and a torn one
head -n 4 "$WORK/np2/runs.csv" >"$WORK/part"
printf '7,ok,2e-3' >>"$WORK/part"
cp "$WORK/part" "$WORK/np2/runs.csv"
rm "$WORK/np2/sweep.csv"
run_rc 0 timeout 120 "${MPI[@]}" -np 2 "$BIN" sweep "$c" "${SET[@]}" --out "$WORK/np2" --threads 1 --resume
stderr_has "10 runs: 7 run now, 3 finished before"
cmp "$WORK/one/sweep.csv" "$WORK/np2/sweep.csv" || fail "the sweep resumed on 2 ranks differs"

# a refused sweep: every rank exits 1, rank 0 says why, once
run_rc 1 timeout 120 "${MPI[@]}" -np 2 "$BIN" sweep "$c" --set nosuch.key=1 --out "$WORK/bad"
[ "$(grep -c "key 'nosuch.key'" "$WORK/stderr")" = 1 ] || { show_output; fail "the refusal should be printed once"; }
echo "mpi_sweep: ok"
