# gransim run --threads 1 and --threads 2 give the same results: the parallel
# aggregation pair loop only changes the order of some additions, so the
# summaries agree to 1e-12 relative; two runs on 2 threads agree bit for bit.
source "$(dirname "$0")/cli-lib.sh" "$@"

c=$(write_case threads.yaml "$(sum_kernel_2d "threads test (2-D, two compartments, both redistributions)" 2 24 1.6 0.5)
  - type: aggregation
    redistribution: fixed_pivot
    table_limit_mb: 0            # kernel rows evaluated in the right-hand side
    kernel: {type: product, beta0: 1}
  - type: transfer
    rate: 1
output: {end: 1, count: 11}")

# Threads that sleep instead of spinning keep this test quick on a busy machine;
# it does not change the results.
export OMP_WAIT_POLICY=passive
run_rc 0 "$BIN" run "$c" --out "$WORK/t1" --threads 1 --quiet
run_rc 0 "$BIN" run "$c" --out "$WORK/t2" --threads 2 --quiet
rows=$(($(wc -l <"$WORK/t1/summary.csv") - 1))
[ "$rows" -eq 22 ] || fail "summary.csv has $rows rows, expected 22 (11 times x 2 compartments)"
csv_rows_close "$WORK/t1/summary.csv" "$WORK/t2/summary.csv" 1e-12
# the threads take fixed rows of the pair loop: the same thread count gives
# the same numbers bit for bit, run after run
run_rc 0 "$BIN" run "$c" --out "$WORK/t2again" --threads 2 --quiet
cmp -s "$WORK/t2/summary.csv" "$WORK/t2again/summary.csv" ||
  fail "two runs with --threads 2 differ (the pair loop's rows must go to fixed threads)"
if command -v h5diff >/dev/null 2>&1; then
  for ds in /number /ledger; do
    h5diff "$WORK/t2/result.h5" "$WORK/t2again/result.h5" "$ds" >"$WORK/h5diff.out" ||
      { cat "$WORK/h5diff.out" >&2; fail "two runs with --threads 2 differ in $ds"; }
  done
fi

# full precision from result.h5 when hdf5-tools are installed
if command -v h5dump >/dev/null 2>&1; then
  # values of a dataset, one per line, in full precision (its DATA, not its attributes')
  values() {
    h5dump -y -m %.17g -d "$2" "$1" |
      awk '/DATA \{/ && !done { on = 1; next } on && /^ *\}/ { on = 0; done = 1 } on' | tr ',' '\n' | awk 'NF { print $1 }'
  }
  for col in M0 M1 M2 d10 d50 d90 mean_solid mean_liquid total_solid total_liquid; do
    values "$WORK/t1/result.h5" "/summary/$col" >"$WORK/a"
    values "$WORK/t2/result.h5" "/summary/$col" >"$WORK/b"
    [ "$(wc -l <"$WORK/a")" -eq 22 ] || fail "h5dump gave $(wc -l <"$WORK/a") values of /summary/$col, expected 22"
    paste -d, "$WORK/a" "$WORK/b" | awk -F, -v col="$col" '
      function abs(v) { return v < 0 ? -v : v }
      { m = abs($1); if (abs($2) > m) m = abs($2)
        if ($1 != $2 && abs($1 - $2) > 1e-12 * m) { printf "/summary/%s row %d: %s vs %s\n", col, NR, $1, $2; bad = 1 } }
      END { exit bad }' || fail "--threads 1 and --threads 2 differ in /summary/$col by more than 1e-12 relative"
  done
else
  echo "cli_threads: h5dump not found (install hdf5-tools); compared summary.csv only" >&2
fi

# The CoriMix granulator (4 compartments, carried liquid and gas, wet switch),
# with its own steps per compartment: on 2 threads the compartments run at
# once, and the files are those of one thread byte for byte.
run_rc 0 "$BIN" run "$SRC/examples/corimix-continuous.yaml" --out "$WORK/c1" --threads 1 --quiet
run_rc 0 "$BIN" run "$SRC/examples/corimix-continuous.yaml" --out "$WORK/c2" --threads 2 --timings
stderr_has "per-compartment steps (steps / rejected / evaluations / ms in rates / ms in tasks):" "2 threads, waiting" "  thread 1: compartments" "page faults while it ran:"
cmp "$WORK/c1/summary.csv" "$WORK/c2/summary.csv" >&2 || fail "per-compartment steps: summary.csv differs on 2 threads"
if command -v h5diff >/dev/null 2>&1; then
  h5diff "$WORK/c1/result.h5" "$WORK/c2/result.h5" >&2 || fail "per-compartment steps: result.h5 differs on 2 threads"
fi

# Eight compartments of 24 x 24 cells (4608 in all): the threads take whole
# compartments, each with its own accumulators; the same results.
sed 's/compartments: 2/compartments: 8/; s/title: threads test/title: threads over compartments/' \
  "$c" >"$WORK/eight.yaml"
run_rc 0 "$BIN" run "$WORK/eight.yaml" --out "$WORK/e1" --threads 1 --quiet
run_rc 0 "$BIN" run "$WORK/eight.yaml" --out "$WORK/e2" --threads 2 --quiet
rows=$(($(wc -l <"$WORK/e1/summary.csv") - 1))
[ "$rows" -eq 88 ] || fail "summary.csv has $rows rows, expected 88 (11 times x 8 compartments)"
csv_rows_close "$WORK/e1/summary.csv" "$WORK/e2/summary.csv" 1e-12

# Waiting threads sleep by default (src/cli/main.c: the variable is set and
# the program executes itself again before libgomp reads it): libgomp's last
# display of its settings shows no spinning; a user's setting is kept.
env -u OMP_WAIT_POLICY -u GOMP_SPINCOUNT OMP_DISPLAY_ENV=verbose \
  "$BIN" run "$c" --out "$WORK/w1" --threads 2 --quiet 2>"$WORK/w1.err" || fail "default run failed"
spin=$(grep "GOMP_SPINCOUNT" "$WORK/w1.err" | tail -1 | tr -d " '")
[ "$spin" = "GOMP_SPINCOUNT=0" ] || fail "default run: libgomp spins ($spin), expected passive waits"
cmp -s "$WORK/t2/summary.csv" "$WORK/w1/summary.csv" || fail "passive waits changed the results"
env -u OMP_WAIT_POLICY GOMP_SPINCOUNT=1234 OMP_DISPLAY_ENV=verbose \
  "$BIN" run "$c" --out "$WORK/w2" --quiet 2>"$WORK/w2.err" || fail "run with GOMP_SPINCOUNT set failed"
spin=$(grep "GOMP_SPINCOUNT" "$WORK/w2.err" | tail -1 | tr -d " '")
[ "$spin" = "GOMP_SPINCOUNT=1234" ] || fail "the user's GOMP_SPINCOUNT was not kept ($spin)"

echo "cli_threads: ok"
