# gransim run with solver.method: swa on MPI ranks (built with -DGRANSIM_MPI=ON):
# the runs spread over the ranks give summary.csv and result.h5 identical to a
# plain run (1 process) on 2 ranks and on 3 ranks (5 runs: not divisible, with
# threads); only rank 0 prints; a run that fails on rank 1 only, and a result
# directory that rank 0 cannot write, make every rank exit with status 1 and
# rank 0 print the failing rank's message, without hanging.
#
# Usage: bash mpi_swa.sh GRANSIM_BINARY SOURCE_DIR MPIEXEC [MPIEXEC_OPTIONS...]
source "$(dirname "$0")/mpi-lib.sh" "$@"

# the bundled twin-screw case (every SWA process, 3 compartments, sieves),
# shortened to 2 residence times and 5 runs
sed 's/^output: {end: 41.4, count: 10}.*/output: {end: 8.28, count: 4}/; s/^  runs: 4$/  runs: 5/' \
  "$SRC/examples/twin-screw.yaml" >"$WORK/ts.yaml"
grep -q '^  runs: 5$' "$WORK/ts.yaml" && grep -q '^output: {end: 8.28, count: 4}$' "$WORK/ts.yaml" ||
  fail "examples/twin-screw.yaml changed: cannot shorten it"

now() { date +%s.%N; }
elapsed() { awk -v a="$1" -v b="$2" 'BEGIN { printf "%.2f", b - a }'; }
# the run's own time from gransim's final message ("... in 0.415 s (")
run_seconds() { sed -n 's/.* done to t = [^ ]* in \([0-9.]*\) s (.*/\1/p' "$WORK/stderr"; }
# h5dump of DIR/result.h5 without the file name
h5text() { (cd "$1" && h5dump result.h5); }

t0=$(now)
run_rc 0 "$BIN" run "$WORK/ts.yaml" --out "$WORK/serial" --quiet --threads 1
t1=$(now)
serial_run=$(run_seconds)
h5text "$WORK/serial" >"$WORK/serial.h5.txt" || fail "h5dump failed"

t2=$(now)
run_rc 0 timeout 120 "${MPI[@]}" -np 2 "$BIN" run "$WORK/ts.yaml" --out "$WORK/np2" --quiet --threads 1
t3=$(now)
np2_run=$(run_seconds)
[ "$(grep -c 'swa, 5 runs of 1024 particles done' "$WORK/stderr")" = 1 ] || { show_output; fail "2 ranks: the final message should be printed once (by rank 0)"; }
cmp -s "$WORK/serial/summary.csv" "$WORK/np2/summary.csv" || fail "1 process and 2 ranks give different summary.csv"
h5text "$WORK/np2" >"$WORK/np2.h5.txt" || fail "h5dump failed"
cmp -s "$WORK/serial.h5.txt" "$WORK/np2.h5.txt" || fail "1 process and 2 ranks give different result.h5"

run_rc 0 timeout 120 "${MPI[@]}" -np 3 "$BIN" run "$WORK/ts.yaml" --out "$WORK/np3" --quiet --threads 2
cmp -s "$WORK/serial/summary.csv" "$WORK/np3/summary.csv" || fail "1 process and 3 ranks x 2 threads give different summary.csv"
h5text "$WORK/np3" >"$WORK/np3.h5.txt" || fail "h5dump failed"
cmp -s "$WORK/serial.h5.txt" "$WORK/np3.h5.txt" || fail "1 process and 3 ranks x 2 threads give different result.h5"

# Every rank's exit status: each rank runs gransim through this wrapper, which
# writes the status to $WORK/rc.RANK and exits 0 (a rank exiting non-zero
# makes mpirun kill the others, maybe before they wrote theirs).  A rank left
# waiting in a collective would hang: timeout, and no rc file.
cat >"$WORK/rank.sh" <<'EOF'
rc=0
"$@" || rc=$?
echo "$rc" >"$RC_DIR/rc.${OMPI_COMM_WORLD_RANK:-${PMI_RANK:-${PMIX_RANK:-x}}}"
EOF
# all_ranks_failed N: N ranks each wrote exit status 1
all_ranks_failed() {
  local k
  for ((k = 0; k < $1; k++)); do
    [ -e "$WORK/rc.$k" ] || fail "rank $k did not finish"
    [ "$(cat "$WORK/rc.$k")" = 1 ] || fail "rank $k exited with status $(cat "$WORK/rc.$k"), expected 1"
  done
  rm -f "$WORK"/rc.*
}

# Immersion nucleation with too few partner selections allowed: with seed 2,
# run 1 completes and run 2 fails (checked serially), so on 2 ranks only rank 1
# fails.  Every rank must stop with status 1 and rank 0 report run 2's error.
fails=$(write_case fails.yaml "title: run 2 of 2 fails
grid:
  axes: [{name: solid, type: geometric, min: 1e-3, max: 1e3, cells: 8, zero_first: true}]
solver:
  method: swa
  particles: 16
  runs: 2
  seed: 2
  coordinates: [solid, external_liquid, internal_liquid, pores]
initial: {type: exponential, number: 1000, mean: [1, 0, 0, 0]}
mechanisms:
  - type: immersion_nucleation
    droplet_diameter: 2
    rate: 500
    droplet_weight: 1
    max_steps: 10
output: {end: 0.2, count: 2}")
run_rc 1 "$BIN" run "$fails" --out "$WORK/fail1" --threads 1
stderr_has "gransim: run 2: mechanisms[0] (immersion_nucleation)" "did not use up its external liquid in 10 selections"
serial_msg=$(grep '^gransim: run 2: ' "$WORK/stderr")
run_rc 1 "$BIN" run "$fails" --out "$WORK/fail1" --threads 2
stderr_has "$serial_msg"
export RC_DIR=$WORK
run_rc 0 timeout 60 "${MPI[@]}" -np 2 bash "$WORK/rank.sh" "$BIN" run "$fails" --out "$WORK/fail2" --threads 1
all_ranks_failed 2
stderr_has "$serial_msg"
[ "$(grep -c '^gransim: run 2: ' "$WORK/stderr")" = 1 ] || { show_output; fail "2 ranks: the error should be printed once (by rank 0)"; }
no_result_files "$WORK/fail2"
# 3 ranks, one of them without runs
run_rc 0 timeout 60 "${MPI[@]}" -np 3 bash "$WORK/rank.sh" "$BIN" run "$fails" --out "$WORK/fail3" --threads 1
all_ranks_failed 3
stderr_has "$serial_msg"

# Rank 0 cannot write the results (DIR below a plain file): every rank fails.
: >"$WORK/plain"
run_rc 0 timeout 60 "${MPI[@]}" -np 2 bash "$WORK/rank.sh" "$BIN" run "$WORK/ts.yaml" --out "$WORK/plain/out" --quiet
all_ranks_failed 2
stderr_has "gransim: cannot create directory $WORK/plain/out: Not a directory"

echo "mpi_swa: ok (shortened twin-screw, 5 runs: 1 process $(elapsed "$t0" "$t1") s, run $serial_run s;" \
  "2 ranks $(elapsed "$t2" "$t3") s with mpirun, run $np2_run s)"
