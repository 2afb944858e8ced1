# gransim run --resume: a run killed with SIGKILL part-way is continued from
# its partial files and ends where an uninterrupted run ends.
#
# To be independent of the machine's speed, the run is killed only once its
# partial summary holds a few output times (so there is something to resume),
# plus a random delay of up to the time those took; the case has enough output
# times (41) that it is then still far from done.
source "$(dirname "$0")/cli-lib.sh" "$@"

case_text="$(sum_kernel_2d "resume test (2-D sum-kernel aggregation, 2025 cells)" 1 45 1.25 1)
output: {end: 1, count: 41, checkpoint: 0}   # commit every output time"
c=$(write_case resume.yaml "$case_text")
ntimes=41

# the reference: an uninterrupted run
run_rc 0 "$BIN" run "$c" --out "$WORK/ref" --threads 1 --quiet
[ "$(wc -l <"$WORK/ref/summary.csv")" -eq $((ntimes + 1)) ] || fail "the reference run did not write $ntimes rows"

# start the same run and kill it after a few output times
res=$WORK/res
"$BIN" run "$c" --out "$res" --threads 1 --quiet 2>"$WORK/killed.err" &
pid=$!
BG_PIDS+=("$pid")
partial=$res/.summary.csv.partial
kill_part_way "$pid" "$partial" "$WORK/killed.err"
rc=0
wait "$pid" 2>/dev/null || rc=$?
[ "$rc" -eq 137 ] || fail "the killed run exited with $rc, expected 137 (SIGKILL)"
[ -f "$res/.result.h5.partial" ] || fail "the killed run left no .result.h5.partial"
[ ! -e "$res/result.h5" ] && [ ! -e "$res/summary.csv" ] ||
  fail "the killed run left files under the final names"
done_rows=$(($(wc -l <"$partial") - 1))
[ "$done_rows" -lt "$ntimes" ] || fail "the run was killed only after writing all $ntimes output times"

# resuming with a different grid is refused and leaves the partial files usable
other=$WORK/other.yaml
awk '!done && sub(/cells: 45/, "cells: 44") { done = 1 } 1' "$c" >"$other"
grep -q "cells: 44" "$other" || fail "could not build the case with a different grid"
run_rc 1 "$BIN" run "$other" --out "$res" --resume --threads 1 --quiet
stderr_has "cannot resume" "different grid" "axis 'solid' has 45 cells, case has 44"
[ -f "$res/.result.journal" ] || fail "a refused resume removed .result.journal"

# resume and compare with the uninterrupted run
run_rc 0 "$BIN" run "$c" --out "$res" --resume --threads 1 --quiet
stderr_has "done to t = 1"
[ -f "$res/result.h5" ] && [ -f "$res/summary.csv" ] || fail "the resumed run wrote no result files"
for f in .result.h5.partial .summary.csv.partial .result.h5.new .result.journal; do
  [ ! -e "$res/$f" ] || fail "partial file $res/$f left after the resumed run"
done
[ "$(wc -l <"$res/summary.csv")" -eq $((ntimes + 1)) ] ||
  fail "the resumed summary.csv has $(($(wc -l <"$res/summary.csv") - 1)) rows, expected $ntimes"
[ "$(head -n 1 "$res/summary.csv")" = "$(head -n 1 "$WORK/ref/summary.csv")" ] ||
  fail "the resumed summary.csv has a different header"
# the last row (final time) to 1e-6 relative, and every row as well
csv_rows_close "$WORK/ref/summary.csv" "$res/summary.csv" 1e-6 $((ntimes + 1))
csv_rows_close "$WORK/ref/summary.csv" "$res/summary.csv" 1e-6

if command -v h5ls >/dev/null 2>&1; then
  h5ls "$res/result.h5/time" >"$WORK/h5ls" 2>&1 || fail "h5ls cannot read the resumed result.h5"
  grep -Eq "\\{$ntimes(/Inf)?\\}" "$WORK/h5ls" || { cat "$WORK/h5ls" >&2; fail "/time of the resumed result.h5 does not have $ntimes entries"; }
fi

# checkpoints: committing all output times together at the end (a long
# checkpoint interval) writes the same files as committing each one
sed 's/checkpoint: 0}/checkpoint: 1000}/' "$c" >"$WORK/batched.yaml"
grep -q "checkpoint: 1000}" "$WORK/batched.yaml" || fail "could not set output.checkpoint in the case"
run_rc 0 "$BIN" run "$WORK/batched.yaml" --out "$WORK/batched" --threads 1 --quiet
cmp -s "$WORK/ref/summary.csv" "$WORK/batched/summary.csv" || fail "checkpoint 1000 and 0 give different summary.csv"
if command -v h5dump >/dev/null 2>&1; then
  for ds in /time /number /ledger /summary/d50; do
    h5dump -m %.17g -d "$ds" "$WORK/ref/result.h5" | tail -n +3 >"$WORK/a"
    h5dump -m %.17g -d "$ds" "$WORK/batched/result.h5" | tail -n +3 >"$WORK/b"
    cmp -s "$WORK/a" "$WORK/b" || fail "checkpoint 1000 and 0 give different $ds in result.h5"
  done
fi

echo "cli_resume: ok (killed after $done_rows of $ntimes output times)"
