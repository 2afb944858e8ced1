# Nothing committed is lost to a kill at any write: a small run is killed
# (strace injects SIGKILL) at its N-th call of each system call that writes
# or publishes files (pwrite64: HDF5; writev: the journal; write: the CSV and
# messages; ftruncate, rename, unlink: opening, resuming and publishing), and
# `--resume` then ends with the files an uninterrupted run writes (h5diff
# without tolerance, summary.csv byte for byte) and no partial file left.
# Every fourth killed run's resume is itself killed at one of its writes and
# resumed again.  A resume may find nothing to resume only when the kill came
# before the first commit (then no result file exists, and a fresh run is
# compared) or after the run was complete.
#
# Default: every third call of HDF5's and the journal's writes (about 80
# kills); GRANSIM_TEST_LONG=1 (cli_kill_writes_long, ctest -L long): every call.
# ctest-long
source "$(dirname "$0")/cli-lib.sh" "$@"

step=3
[ "${GRANSIM_TEST_LONG:-0}" = 1 ] && step=1
command -v strace >/dev/null || fail "strace is needed (scripts/setup installs it)"
command -v h5diff >/dev/null || fail "h5diff (hdf5-tools) is needed"
strace -f -o /dev/null true 2>"$WORK/strace.err" ||
  fail "strace cannot trace here: $(cat "$WORK/strace.err")"

c=$(write_case kill.yaml "title: kill at every write
grid:
  compartments: 3
  axes:
    - {name: solid, type: geometric, min: 1.0e-5, ratio: 2, cells: 16}
initial: {type: exponential, number: 1, mean: 0.002, coverage: 0.01}
mechanisms:
  - type: aggregation
    kernel: {type: sum, beta0: 1}
  - {type: transfer, rate: 0.5}
output: {end: 1, count: 6, checkpoint: 0}")
# LeakSanitizer cannot run under ptrace (strace): in a sanitized build the
# runs here check memory errors only (the other tests check leaks)
export ASAN_OPTIONS="${ASAN_OPTIONS:+$ASAN_OPTIONS:}detect_leaks=0"
SYSCALLS=(pwrite64 writev write ftruncate rename unlink)

run_rc 0 "$BIN" run "$c" --out "$WORK/ref" --threads 1 --quiet
# how often an uninterrupted run calls each
strace -f -o "$WORK/trace" -e trace="$(IFS=,; echo "${SYSCALLS[*]}")" \
  "$BIN" run "$c" --out "$WORK/counted" --threads 1 --quiet 2>/dev/null
calls() { grep -c "^[0-9]* *$1(" "$WORK/trace" || true; }

# killed RUN_DIR SYSCALL N [ARGS]: gransim run (ARGS) killed at call N of SYSCALL
killed() {
  (strace -f -o /dev/null -e trace="$2" -e inject="$2:signal=SIGKILL:when=$3" \
    "$BIN" run "$c" --out "$1" --threads 1 --quiet ${4:-} || true) >/dev/null 2>&1
}

check_same() {
  h5diff "$WORK/ref/result.h5" "$1/result.h5" >"$WORK/h5diff" 2>&1 ||
    { head -n 20 "$WORK/h5diff" >&2; fail "$1/result.h5 differs from the uninterrupted run's ($2)"; }
  cmp -s "$WORK/ref/summary.csv" "$1/summary.csv" || fail "$1/summary.csv differs ($2)"
  local f
  for f in .result.h5.partial .summary.csv.partial .result.h5.new .result.journal .result.journal.new; do
    [ ! -e "$1/$f" ] || fail "$1/$f left after a successful resume ($2)"
  done
}

kills=0 nested=0
for sc in "${SYSCALLS[@]}"; do
  total=$(calls "$sc")
  [ "$sc" != pwrite64 ] || [ "$total" -gt 50 ] || fail "only $total pwrite64 calls counted"
  by=1
  [ "$sc" = pwrite64 ] || [ "$sc" = writev ] && by=$step
  for ((n = 1; n <= total; n += by)); do
    d=$WORK/k-$sc-$n
    killed "$d" "$sc" "$n"
    kills=$((kills + 1))
    what="killed at $sc call $n of $total"
    if [ $((kills % 4)) = 0 ] && [ -e "$d/.result.journal" ]; then
      # the resume itself killed part-way, at one of its HDF5 writes
      killed "$d" pwrite64 $((n % 40 + 1)) --resume
      nested=$((nested + 1))
      what="$what, its resume killed too"
    fi
    rc=0
    "$BIN" run "$c" --out "$d" --resume --threads 1 --quiet >"$WORK/stdout" 2>"$WORK/stderr" || rc=$?
    if [ "$rc" != 0 ]; then
      grep -q "nothing to resume" "$WORK/stderr" || { show_output; fail "--resume failed ($what)"; }
      if [ ! -e "$d/result.h5" ]; then # killed before the first commit: start afresh
        [ ! -e "$d/summary.csv" ] || fail "summary.csv without result.h5 ($what)"
        run_rc 0 "$BIN" run "$c" --out "$d" --threads 1 --quiet
      fi
    fi
    check_same "$d" "$what"
    rm -rf "$d"
  done
done
echo "cli_kill_writes: ok ($kills kills, $nested of them with the resume killed too)"
