# gransim run of sectional cases on MPI ranks (built with -DGRANSIM_MPI=ON): each
# rank owns a contiguous block of compartments; the results must not depend on
# the number of ranks or threads.  Checks: the CoriMix example (rk) on 1, 2 and
# 3 ranks (blocks 2+2 and 1+1+2), on 2 ranks x 2 threads, and on 2 and 3 ranks
# with compartments moved between ranks between steps (solver.rebalance)
# gives the same
# summary.csv and the same numbers, carried volumes and ledger in result.h5 to
# 1e-12 relative (they are identical in practice; on 2 ranks, where rank 0
# writes while it waits, the whole result.h5 and summary.csv are checked
# identical to the serial run's); a 2-D case with the
# adaptive Euler of Sampat et al. (2018) the same; only rank 0 prints; cvode and more ranks than
# compartments are refused with a message, and so is an exchange network; a fluid bed (three
# compartments, each its own bed) equals one process's on 2 ranks, moves included; an Euler step that goes negative on
# rank 1 only stops every rank with status 1 and rank 1's message, without
# hanging; so does a non-finite rate on rank 1 only under rk, and a result
# file that cannot grow (rank 0's writes fail mid-run); a 2-rank run killed
# part-way resumes on 2 ranks and ends as an uninterrupted run.
#
# Usage: bash mpi_sectional.sh GRANSIM_BINARY SOURCE_DIR MPIEXEC [MPIEXEC_OPTIONS...]
source "$(dirname "$0")/mpi-lib.sh" "$@"

# values of a dataset of DIR/result.h5, one per line, in full precision
values() {
  h5dump -y -m %.17g -d "$2" "$1/result.h5" |
    awk '/DATA \{/ { on = 1; next } on && /^ *\}/ { on = 0 } on' | tr ',' '\n' | awk 'NF { print $1 }'
}
# same_results DIR_A DIR_B WHAT: summary.csv and the full state agree to 1e-12
same_results() {
  csv_rows_close "$1/summary.csv" "$2/summary.csv" 1e-12
  local ds
  for ds in /number /ledger ${3:-}; do
    values "$1" "$ds" >"$WORK/a"
    values "$2" "$ds" >"$WORK/b"
    [ -s "$WORK/a" ] || fail "no values in $ds of $1/result.h5"
    paste -d, "$WORK/a" "$WORK/b" | awk -F, -v ds="$ds" '
      function abs(v) { return v < 0 ? -v : v }
      { m = abs($1); if (abs($2) > m) m = abs($2)
        if ($1 != $2 && abs($1 - $2) > 1e-12 * m) { printf "%s value %d: %s vs %s\n", ds, NR, $1, $2; bad = 1 } }
      END { exit bad }' || fail "$1 and $2 differ in $ds by more than 1e-12 relative"
  done
}

# same_on_two_ranks CASE TAG: CASE run in one process ($WORK/TAG1), on two
# ranks ($WORK/TAG2) and on two ranks with a move at every decision
# ($WORK/TAG2m) gives the same results.
same_on_two_ranks() {
  run_rc 0 "$BIN" run "$1" --out "$WORK/${2}1" --quiet --threads 1
  run_rc 0 "${MPI[@]}" -np 2 "$BIN" run "$1" --out "$WORK/${2}2" --quiet --threads 1
  same_results "$WORK/${2}1" "$WORK/${2}2"
  run_rc 0 "${MPI[@]}" -np 2 -x GRANSIM_TEST_MOVE_COMPARTMENTS=1 "$BIN" run "$1" --out "$WORK/${2}2m" --quiet --threads 1
  stderr_has "compartments moved between ranks"
  same_results "$WORK/${2}1" "$WORK/${2}2m"
}

# (the example's own per-compartment steps on ranks: mpi_compartment_steps.sh)
# an exchange network reads every compartment, which runs in one process
cat >"$WORK/net.yaml" <<'EOF'
grid: {compartments: 2, axes: [{name: v, type: geometric, min: 1, ratio: 2, cells: 4}]}
initial: {type: cell, number: 10, index: [1]}
mechanisms: [{type: exchange, rates: [[0, 1], [2, 0]]}]
output: {end: 1}
EOF
run_rc 1 "${MPI[@]}" -np 2 "$BIN" run "$WORK/net.yaml" --out "$WORK/net2" --quiet
stderr_has "exchange network couples every compartment"
no_result_files "$WORK/net2"
run_rc 0 "$BIN" run "$WORK/net.yaml" --out "$WORK/net1" --quiet
# a fluid bed's balances (each compartment's own bed: scalar state that the
# ranks' blocks carry) on 2 ranks, and with compartments moved between the
# ranks at every decision, equal one process's bit for bit
cat >"$WORK/bed.yaml" <<'EOF'
grid:
  compartments: 3
  axes:
    - {name: solid,  type: geometric, min: 1.0e-12, ratio: 2, cells: 12}
    - {name: liquid, type: geometric, min: 1.0e-14, ratio: 2, cells: 20, zero_first: true}
initial:
  - {type: point, number: 4.19e8, at: [1.767e-12, 8.59e-14], compartment: 1}
  - {type: point, number: 2.0e8, at: [1.767e-12, 8.59e-14], compartment: 2}
  - {type: point, number: 1.0e8, at: [3.534e-12, 3.0e-13], compartment: 3}
mechanisms:
  - type: aggregation
    kernel: {type: madec, beta0: 5.0e-4, alpha: 1, delta: 1, liquid_content: percent}
  - {type: liquid_addition, rate: [9.0e-7, 0, 4.0e-7], start: 0, end: 40}
  - type: fluid_bed
    solid_density: 2700
    air_mass: 0.0107
    air_density: 1.18
    correction: 0.002
    heat_loss: 200
    spray_temperature: 293.15
    air:
      - {start: 0,  end: 40, temperature: 333, humidity: 0.00505, air_flow: 0.067}
      - {start: 40, end: 60, temperature: 343, humidity: 0.00505, air_flow: 0.09}
solver: {method: rk, rtol: 1.0e-6}
output: {end: 60, count: 4}
EOF
run_rc 0 "$BIN" run "$WORK/bed.yaml" --out "$WORK/bed1" --quiet --threads 1
run_rc 0 "${MPI[@]}" -np 2 "$BIN" run "$WORK/bed.yaml" --out "$WORK/bed2" --quiet --threads 1
run_rc 0 "${MPI[@]}" -np 2 -x GRANSIM_TEST_MOVE_COMPARTMENTS=1 "$BIN" run "$WORK/bed.yaml" --out "$WORK/bed2m" --quiet --threads 1
for d in bed2 bed2m; do
  cmp -s "$WORK/bed1/summary.csv" "$WORK/$d/summary.csv" || fail "fluid bed on 2 ranks ($d): summary.csv differs from one process's"
  same_results "$WORK/bed1" "$WORK/$d"
done
grep -q "bed_temperature" "$WORK/bed1/summary.csv" || fail "no bed temperature in the fluid bed's summary"
mkdir -p "$WORK/data"
cp "$SRC/examples/data/"*.csv "$WORK/data/"
ex="$WORK/corimix-shared.yaml"
sed 's/steps: per_compartment/steps: shared/' "$SRC/examples/corimix-continuous.yaml" >"$ex"
grep -q "steps: shared" "$ex" || fail "could not give the example shared steps"
run_rc 0 "$BIN" run "$ex" --out "$WORK/serial" --quiet --threads 1
run_rc 0 "${MPI[@]}" -np 2 "$BIN" run "$ex" --out "$WORK/np2" --quiet --threads 1 --timings
stderr_has "done to t = 85"
[ "$(grep -cE '^  [01] ' "$WORK/stderr")" = 2 ] || { show_output; fail "--timings on 2 ranks: expected a row per rank"; }
# the blocks at the end: contiguous, from compartment 1 to 4
awk '/^  [01] / { split($8, b, "-"); lo = b[1]; hi = (2 in b) ? b[2] : b[1]
                  if (lo != next_lo) bad = 1; next_lo = hi + 1 }
     BEGIN { next_lo = 1 } END { exit bad || next_lo != 5 }' "$WORK/stderr" ||
  { show_output; fail "--timings on 2 ranks: the compartments of the ranks are not 1-4 in contiguous blocks"; }
[ "$(grep -c 'done to t' "$WORK/stderr")" = 1 ] || { show_output; fail "expected one final message (rank 0's) on 2 ranks"; }
same_results "$WORK/serial" "$WORK/np2" /carried
# rank 0 writes its output times later, in pieces, while it waits for rank 1
# at step agreements: the files are still those of the serial run, every
# object of result.h5 and summary.csv byte for byte
if command -v h5diff >/dev/null 2>&1; then
  h5diff "$WORK/serial/result.h5" "$WORK/np2/result.h5" >"$WORK/h5diff.out" ||
    { cat "$WORK/h5diff.out" >&2; fail "result.h5 on 2 ranks differs from the serial run's"; }
fi
cmp "$WORK/serial/summary.csv" "$WORK/np2/summary.csv" >&2 || fail "summary.csv on 2 ranks differs from the serial run's"
# an output time passed without a stop of its own (84.99999999999999, then 85
# in the same step: the loop skips the last one): the output times rank 0
# still holds are written all the same (they were lost: /time [0] against
# [0, 85, 85])
mkdir -p "$WORK/data"
cp "$SRC/examples/data/"*.csv "$WORK/data/"
sed 's/^output: .*/output: {end: 85, count: 6, spacing: log, first: 84.99999999999999}/' "$ex" >"$WORK/skip.yaml"
run_rc 0 "$BIN" run "$WORK/skip.yaml" --out "$WORK/skip1" --quiet --threads 1
run_rc 0 "${MPI[@]}" -np 2 "$BIN" run "$WORK/skip.yaml" --out "$WORK/skip2" --quiet --threads 1
same_results "$WORK/skip1" "$WORK/skip2" /carried
cmp "$WORK/skip1/summary.csv" "$WORK/skip2/summary.csv" >&2 || fail "summary.csv differs on 2 ranks when the last output time is skipped"
run_rc 0 "${MPI[@]}" -np 3 "$BIN" run "$ex" --out "$WORK/np3" --quiet --threads 1
same_results "$WORK/serial" "$WORK/np3" /carried
run_rc 0 "${MPI[@]}" -np 2 "$BIN" run "$ex" --out "$WORK/np2t2" --quiet --threads 2
same_results "$WORK/serial" "$WORK/np2t2" /carried
# compartments moved between ranks between steps, in the middle of output
# intervals (solver.rebalance): the integrators carry on with the same steps,
# so the results stay the same. Moves follow measured times;
# GRANSIM_TEST_MOVE_COMPARTMENTS makes one at every decision (every other
# step) whatever the times, so this does not depend on them.
for np in 2 3; do
  run_rc 0 "${MPI[@]}" -np $np -x GRANSIM_TEST_MOVE_COMPARTMENTS=1 "$BIN" run "$ex" --out "$WORK/moved$np" \
    --quiet --threads 1
  stderr_has "compartments moved between ranks"
  same_results "$WORK/serial" "$WORK/moved$np" /carried
done

# Threads on ranks with moves: sixteen 24 x 24 compartments (9216 cells), so
# threads take whole compartments whatever a rank's block after a move (the
# choice once depended on the block: a block of 7 switched to the shared
# pair loop and changed the last bits); the same numbers bit for bit as one
# process on one thread.
c16=$(write_case sixteen.yaml "$(sum_kernel_2d "threads and moves (2-D, sixteen compartments)" 16 24 1.6 0.5)
  - type: transfer
    rate: 1
output: {end: 0.5, count: 6}")
run_rc 0 "$BIN" run "$c16" --out "$WORK/s1" --quiet --threads 1
run_rc 0 "${MPI[@]}" -np 2 --bind-to none -x GRANSIM_TEST_MOVE_COMPARTMENTS=1 "$BIN" run "$c16" \
  --out "$WORK/s2" --quiet --threads 2
stderr_has "compartments moved between ranks"
for ds in /number /ledger; do
  h5diff "$WORK/s1/result.h5" "$WORK/s2/result.h5" "$ds" >"$WORK/h5diff.out" ||
    { cat "$WORK/h5diff.out" >&2; fail "threads on moving ranks changed $ds"; }
done

# the adaptive Euler of Sampat et al. (2018): one step size agreed by all ranks
c=$(write_case euler.yaml "title: Euler on ranks (2-D, four compartments, feed, transfer)
$(grid_2d 4 20)
initial: {type: exponential, number: 1, mean: [0.05, 0.02]}
mechanisms:
  - type: feed
    compartment: 1
    distribution: {type: exponential, number: 2, mean: [0.05, 0.02]}
  - type: aggregation
    kernel: {type: sum, beta0: 0.5}
  - type: transfer
    rate: 0.5
solver: {method: euler, safety: 0.05}
output: {end: 2, count: 5}")
# Euler carries over moves too
same_on_two_ranks "$c" e
# solver.rebalance: none keeps the blocks even when forced
sed 's/method: euler, safety: 0.05/method: euler, safety: 0.05, rebalance: none/' "$c" >"$WORK/fixed.yaml"
run_rc 0 "${MPI[@]}" -np 2 -x GRANSIM_TEST_MOVE_COMPARTMENTS=1 "$BIN" run "$WORK/fixed.yaml" --out "$WORK/e2f" --quiet --threads 1
stderr_lacks "compartments moved between ranks"
same_results "$WORK/e1" "$WORK/e2f"

# every kind of mechanism on ranks (the ranks' right-hand sides work on their
# packed local vectors with the previous rank's last compartment as a halo):
# size growth, liquid addition, fixed-pivot breakage, a Madec kernel, feed
# and transfer on a (solid, liquid) grid, moved or not
cm=$(write_case mechanisms.yaml "title: every mechanism on ranks (2-D, four compartments)
grid:
  compartments: 4
  axes:
    - {name: solid, type: geometric, min: 1.0e-3, ratio: 1.6, cells: 18, zero_first: true}
    - {name: liquid, type: geometric, min: 1.0e-3, ratio: 1.6, cells: 18, zero_first: true}
initial: {type: exponential, number: 1, mean: [0.05, 0.02]}
mechanisms:
  - type: aggregation
    kernel: {type: madec, beta0: 1e-3, alpha: 1, delta: 1, liquid_content: fraction, liquid_axis: liquid}
  - type: breakage
    redistribution: fixed_pivot
    selection: {type: power, s0: 0.01, exponent: 0.5}
    daughters: {type: power, exponent: 1}
  - {type: growth, axis: solid, constant: 0.001, linear: 0.01, start: 0, end: 1.5}
  - {type: liquid_addition, rate: [0.01, 0, 0.005, 0], start: 0.5, end: 1.5, solid_axes: [solid]}
  - type: feed
    compartment: 2
    distribution: {type: exponential, number: 2, mean: [0.05, 0.02]}
  - {type: transfer, rate: 1}
solver: {method: rk, rtol: 1e-6}
output: {end: 2, count: 5}")
same_on_two_ranks "$cm" k

# refused: cvode on several ranks; more ranks than compartments
sed 's/method: euler, safety: 0.05/method: cvode/' "$c" >"$WORK/cvode.yaml"
run_rc 1 timeout 120 "${MPI[@]}" -np 2 "$BIN" run "$WORK/cvode.yaml" --out "$WORK/cv" --quiet
stderr_has "needs solver.method rk or euler"
no_result_files "$WORK/cv"
run_rc 1 timeout 120 "${MPI[@]}" -np 5 "$BIN" run "$c" --out "$WORK/five" --quiet
stderr_has "5 MPI ranks for 4 compartments"

# a failure on rank 1 only: material fed into compartment 3, drained fast by
# transfer, with Euler steps held too long; rank 0 (compartments 1-2, empty)
# must stop too
cat >"$WORK/neg.yaml" <<YAML
title: a negative density on rank 1 only
grid:
  compartments: 4
  axes:
    - {name: v, type: geometric, min: 1.0e-3, ratio: 2, cells: 12, zero_first: true}
mechanisms:
  - type: feed
    compartment: 3
    distribution: {type: exponential, number: 1, mean: 0.1}
  - type: transfer
    rate: 50
solver: {method: euler, initial_step: 0.1, min_step: 0.1, max_step: 0.1}
output: {end: 1, count: 3}
YAML
run_rc 1 timeout 120 "${MPI[@]}" -np 2 "$BIN" run "$WORK/neg.yaml" --out "$WORK/neg" --quiet
stderr_has "negative number density" "failed on another MPI rank"
no_result_files "$WORK/neg"

# rk: a non-finite rate in compartment 4 only (its kernel table overflows)
printf 'edges, 0, 100\n1\n' >"$WORK/ok.csv"
printf 'edges, 0, 100\n1e300\n' >"$WORK/huge.csv"
cat >"$WORK/inf.yaml" <<YAML
title: a non-finite rate on rank 1 only
grid:
  compartments: 4
  axes:
    - {name: v, type: geometric, min: 1.0e-3, ratio: 2, cells: 12, zero_first: true}
initial: {type: exponential, number: 1.0e10, mean: 0.1}
mechanisms:
  - type: aggregation
    kernel: {type: table, file: [ok.csv, ok.csv, ok.csv, huge.csv], beta0: 1.0e-12}
  - {type: transfer, rate: 1}
output: {end: 1, count: 3}
YAML
run_rc 1 timeout 120 "${MPI[@]}" -np 2 "$BIN" run "$WORK/inf.yaml" --out "$WORK/inf" --quiet
stderr_has "compartment 4" "rate of change is not finite" "failed on another MPI rank"
no_result_files "$WORK/inf"

# a failed check at an output time, found by rank 0 (which alone checks the
# whole state): rank 1 learns of it one step later, every rank stops with
# status 1 and rank 0's message, with its time; rank 1 says nothing of the
# step it took meanwhile (here the next output time is far: running on to it
# would exhaust max_steps_per_output)
lossy_case 2 "output: {times: [1, 1.0e6]}
solver: {method: rk, max_steps_per_output: 34}" >"$WORK/lossy.yaml"
run_rc 1 timeout 120 "${MPI[@]}" -np 2 "$BIN" run "$WORK/lossy.yaml" --out "$WORK/lossy" --quiet --threads 1
stderr_has "checks.max_loss" "axis 'solid'" "at t = 1,"
stderr_lacks "failed on another MPI rank" "MPI rank 1" "max_steps"
no_result_files "$WORK/lossy"

# a run on two ranks killed part-way (rank 0 holding output times back between
# its commits, every 0.02 s) resumes on two ranks from what was committed and
# ends where an uninterrupted run ends
c=$(write_case resume.yaml "$(sum_kernel_2d "resume on two ranks (2-D sum kernel and transfer, 4 compartments)" 4 40 1.25 1)
  - {type: transfer, rate: 1}
output: {end: 1, count: 41, checkpoint: 0.02}")
run_rc 0 "$BIN" run "$c" --out "$WORK/rref" --quiet --threads 1
"${MPI[@]}" -np 2 "$BIN" run "$c" --out "$WORK/rres" --quiet --threads 1 >/dev/null 2>"$WORK/killed.err" &
pid=$!
BG_PIDS+=("$pid")
kill_part_way "$pid" "$WORK/rres/.summary.csv.partial" "$WORK/killed.err" --match "run $c --out $WORK/rres"
wait "$pid" 2>/dev/null || true
[ -f "$WORK/rres/.result.h5.partial" ] || fail "the killed 2-rank run left no .result.h5.partial"
[ ! -e "$WORK/rres/result.h5" ] || fail "the killed 2-rank run left result.h5"
run_rc 0 "${MPI[@]}" -np 2 "$BIN" run "$c" --out "$WORK/rres" --resume --quiet --threads 1
[ "$(wc -l <"$WORK/rres/summary.csv")" -eq 165 ] || fail "the resumed 2-rank run has $(wc -l <"$WORK/rres/summary.csv") lines in summary.csv, expected 1 + 41 x 4"
csv_rows_close "$WORK/rref/summary.csv" "$WORK/rres/summary.csv" 1e-6

# a write that fails mid-run (the file size limit stands in for a full disk),
# most likely while rank 0 writes held output times during the steps: every
# rank stops with status 1 and the write's message, leaving no result files.
# TCP between the ranks: the limit would also stop Open MPI's shared memory
# (SIGXFSZ ignored: the write fails instead of killing the process)
run_rc 1 timeout 120 "${MPI[@]}" -np 2 --mca btl self,tcp \
  bash -c 'trap "" XFSZ; ulimit -f 600; exec "$0" "$@"' "$BIN" run "$ex" --out "$WORK/full" --quiet --threads 1
stderr_has "cannot write dataset" "File too large"
stderr_lacks "Segmentation"
no_result_files "$WORK/full"

echo "mpi_sectional: ok"
