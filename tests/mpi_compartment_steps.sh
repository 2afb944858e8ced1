# gransim run with per-compartment steps (solver.steps: per_compartment) on
# MPI ranks (built with -DGRANSIM_MPI=ON): each rank advances its block of
# compartments, the record of a block's last compartment going to the next
# rank step by step.  Checks: the CoriMix example on 1 process and on 2 and 3
# ranks (blocks 2+2 and 1+1+2), and on 2 ranks x 2 threads, writes the same
# result.h5 (h5diff without tolerance) and summary.csv (byte for byte); so
# does the example on 8 compartments (blocks 2+3+3 on 3 ranks, 4+4 on 2 x 2
# threads), also with compartments moved between the ranks at every output
# time (the final message says that they moved); a non-finite rate in one compartment, in two (the earliest one
# by stretch, then compartment, is the one reported, as in one process) and
# in a compartment of the middle rank stops every rank with status 1 and one
# process's message, without hanging, and leaves what one process leaves; so
# does a check that fails at an output time (rank 0's observers).  Resume:
# mpi_resume_exact.sh.
#
# Usage: bash mpi_compartment_steps.sh GRANSIM_BINARY SOURCE_DIR MPIEXEC [MPIEXEC_OPTIONS...]
source "$(dirname "$0")/mpi-lib.sh" "$@"
command -v h5diff >/dev/null || fail "h5diff (hdf5-tools) is needed"
ln -s "$(cd "$SRC" && pwd)/examples/data" "$WORK/data"

# identical CASE TAG NP THREADS [moved]: CASE on NP ranks x THREADS threads
# writes the files of the one-process run $WORK/TAG-1; moved: with a block
# boundary moved at every output time (GRANSIM_TEST_MOVE_COMPARTMENTS)
identical() {
  local d=$WORK/$2-$3x$4${5:-} env=()
  [ -z "${5:-}" ] || env=(-x GRANSIM_TEST_MOVE_COMPARTMENTS=1)
  run_rc 0 timeout 300 "${MPI[@]}" -np "$3" --bind-to none "${env[@]}" "$BIN" run "$1" --out "$d" --quiet --threads "$4"
  grep -q "per-compartment steps" "$WORK/stderr" || { show_output; fail "$1 did not take per-compartment steps"; }
  if [ -n "${5:-}" ]; then
    grep -q "compartments moved between ranks [0-9]* times" "$WORK/stderr" ||
      { show_output; fail "$1 on $3 ranks: no compartment moved"; }
  fi
  h5diff "$WORK/$2-1/result.h5" "$d/result.h5" >"$WORK/h5diff.out" 2>&1 ||
    { head -n 20 "$WORK/h5diff.out" >&2; fail "$1 on $3 ranks x $4 threads: result.h5 differs from one process's"; }
  cmp "$WORK/$2-1/summary.csv" "$d/summary.csv" >&2 || fail "$1 on $3 ranks x $4 threads: summary.csv differs"
  # every rank's steps are counted in the final message
  grep -o "per-compartment steps: [0-9]* steps and [0-9]* evaluations" "$WORK/stderr" >"$WORK/count"
  cmp -s "$WORK/count" "$WORK/$2-count" || fail "$1 on $3 ranks x $4 threads: $(cat "$WORK/count") where one process took $(cat "$WORK/$2-count")"
}

ex=$WORK/corimix.yaml
sed 's/^output: .*/output: {end: 60, count: 61}/' "$SRC/examples/corimix-continuous.yaml" >"$ex"
grep -q "steps: per_compartment" "$ex" || fail "the example no longer takes per-compartment steps"
c8=$WORK/corimix8.yaml
sed -e "s/compartments: 4/compartments: 8/" -e "s/length: 0.095/length: 0.0475/" \
  -e "s/^output: .*/output: {end: 40, count: 41}/" "$SRC/examples/corimix-continuous.yaml" >"$c8"
grep -q "compartments: 8" "$c8" || fail "could not build the 8-compartment case"
for c in "$ex:c4" "$c8:c8"; do
  case=${c%:*} tag=${c##*:}
  run_rc 0 "$BIN" run "$case" --out "$WORK/$tag-1" --quiet --threads 1
  grep -o "per-compartment steps: [0-9]* steps and [0-9]* evaluations" "$WORK/stderr" >"$WORK/$tag-count"
  identical "$case" "$tag" 2 1
  identical "$case" "$tag" 3 1
  identical "$case" "$tag" 2 2
  identical "$case" "$tag" 2 1 moved
  identical "$case" "$tag" 3 1 moved
  identical "$case" "$tag" 2 2 moved
done

# failures: a kernel table that overflows in some compartments (a rate that is
# not finite); one process's message and files, on 2 and 3 ranks
printf 'edges, 0, 100\n1\n' >"$WORK/ok.csv"
printf 'edges, 0, 100\n1e300\n' >"$WORK/huge.csv"
n=0
for tables in "ok.csv, ok.csv, ok.csv, huge.csv" "ok.csv, huge.csv, ok.csv, huge.csv" "ok.csv, ok.csv, huge.csv, ok.csv"; do
  n=$((n + 1))
  cat >"$WORK/inf$n.yaml" <<YAML
title: a non-finite rate in some compartments
grid:
  compartments: 4
  axes:
    - {name: v, type: geometric, min: 1.0e-3, ratio: 2, cells: 12, zero_first: true}
initial: {type: exponential, number: 1.0e10, mean: 0.1}
mechanisms:
  - type: aggregation
    kernel: {type: table, file: [$tables], beta0: 1.0e-12}
  - {type: transfer, rate: 1}
solver: {steps: per_compartment}
output: {end: 1, count: 3}
YAML
  run_rc 1 "$BIN" run "$WORK/inf$n.yaml" --out "$WORK/inf$n-1" --quiet --threads 1
  grep "^gransim: " "$WORK/stderr" >"$WORK/msg1"
  grep -q "rate of change is not finite" "$WORK/msg1" || { show_output; fail "inf$n: no failure in one process"; }
  [ $n != 2 ] || grep -q "compartment 2," "$WORK/msg1" ||
    fail "with tables overflowing in compartments 2 and 4 the failure reported is not compartment 2's"
  for np in 2 3; do
    run_rc 1 timeout 120 "${MPI[@]}" -np $np "$BIN" run "$WORK/inf$n.yaml" --out "$WORK/inf$n-$np" --quiet --threads 1
    grep "^gransim: " "$WORK/stderr" >"$WORK/msg"
    cmp -s "$WORK/msg1" "$WORK/msg" || { show_output; fail "inf$n on $np ranks: rank 0 says '$(cat "$WORK/msg")', one process '$(cat "$WORK/msg1")'"; }
    for f in result.h5 summary.csv .result.h5.partial .summary.csv.partial; do
      if [ -e "$WORK/inf$n-1/$f" ] && [ ! -e "$WORK/inf$n-$np/$f" ]; then fail "inf$n on $np ranks left no $f"; fi
      if [ ! -e "$WORK/inf$n-1/$f" ] && [ -e "$WORK/inf$n-$np/$f" ]; then fail "inf$n on $np ranks left $f"; fi
    done
  done
done

# a check that fails at an output time (rank 0 alone checks the whole state)
lossy_case 2 "output: {end: 5, count: 6}
solver: {method: rk, steps: per_compartment}" >"$WORK/lossy.yaml"
run_rc 1 "$BIN" run "$WORK/lossy.yaml" --out "$WORK/lossy1" --quiet --threads 1
grep "^gransim: " "$WORK/stderr" >"$WORK/msg1"
grep -q "checks.max_loss" "$WORK/msg1" || { show_output; fail "the lossy case did not fail its check in one process"; }
run_rc 1 timeout 120 "${MPI[@]}" -np 2 "$BIN" run "$WORK/lossy.yaml" --out "$WORK/lossy2" --quiet --threads 1
grep "^gransim: " "$WORK/stderr" >"$WORK/msg"
cmp -s "$WORK/msg1" "$WORK/msg" || { show_output; fail "the failed check on 2 ranks: '$(cat "$WORK/msg")', one process '$(cat "$WORK/msg1")'"; }
stderr_lacks "MPI rank 1"
no_result_files "$WORK/lossy2"

echo "mpi_compartment_steps: ok"
