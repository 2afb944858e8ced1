# Shared helpers of the command-line tests tests/cli_*.sh (sourced, not a test
# itself: its name does not match cli_*.sh).
#
# Usage at the top of a test:
#   source "$(dirname "$0")/cli-lib.sh" "$@"     # arguments: BINARY SOURCE_DIR
# Then: $BIN (the gransim binary), $SRC (source tree), $WORK (a fresh temporary
# directory removed on exit), and the helpers below.  Every helper fails the
# test (exit 1) with a message saying what was expected and what happened.

set -euo pipefail

if [ $# -lt 2 ]; then
  echo "usage: bash $0 GRANSIM_BINARY SOURCE_DIR" >&2
  exit 2
fi
BIN=$1
SRC=$2
[ -x "$BIN" ] || { echo "FAIL: $BIN is not an executable" >&2; exit 1; }
[ -d "$SRC" ] || { echo "FAIL: $SRC is not a directory" >&2; exit 1; }
TEST_NAME=$(basename "$0" .sh)
WORK=$(mktemp -d "${TMPDIR:-/tmp}/gransim-$TEST_NAME.XXXXXX")
BG_PIDS=()

cli_cleanup() {
  local pid
  for pid in "${BG_PIDS[@]+"${BG_PIDS[@]}"}"; do
    kill -9 "$pid" 2>/dev/null || true
    wait "$pid" 2>/dev/null || true
  done
  rm -rf "$WORK"
}
trap cli_cleanup EXIT

fail() {
  echo "FAIL ($TEST_NAME): $*" >&2
  exit 1
}

# Last command's output, for messages.
show_output() {
  echo "--- stdout:" >&2
  cat "$WORK/stdout" >&2 || true
  echo "--- stderr:" >&2
  cat "$WORK/stderr" >&2 || true
}

# run_rc EXPECTED_RC CMD...: runs CMD with stdout/stderr in $WORK/stdout and
# $WORK/stderr and checks its exit status.
run_rc() {
  local want=$1 rc=0
  shift
  "$@" >"$WORK/stdout" 2>"$WORK/stderr" || rc=$?
  if [ "$rc" != "$want" ]; then
    show_output
    fail "'$*' exited with status $rc, expected $want"
  fi
}

# stdout_has / stderr_has FIXED_STRING...: the last command's output contains
# every given string.
stdout_has() {
  local s
  for s in "$@"; do
    grep -qF -- "$s" "$WORK/stdout" || { show_output; fail "stdout lacks '$s'"; }
  done
}
stderr_has() {
  local s
  for s in "$@"; do
    grep -qF -- "$s" "$WORK/stderr" || { show_output; fail "stderr lacks '$s'"; }
  done
}
stderr_lacks() {
  local s
  for s in "$@"; do
    ! grep -qF -- "$s" "$WORK/stderr" || { show_output; fail "stderr has '$s'"; }
  done
}

# A small valid grid section (one axis), for cases that only vary other keys.
GRID_1D='grid:
  axes:
    - {name: solid, type: linear, min: 0, max: 10, cells: 20}'

# grid_2d COMPARTMENTS CELLS [RATIO]: the grid section of the 2-D test cases,
# geometric solid and liquid axes from 1e-3 (ratio 1.6 unless given).
grid_2d() {
  printf 'grid:\n  compartments: %s\n  axes:\n' "$1"
  local axis
  for axis in solid liquid; do
    printf '    - {name: %s, type: geometric, min: 1.0e-3, ratio: %s, cells: %s, zero_first: true}\n' \
      "$axis" "${3:-1.6}" "$2"
  done
}

# sum_kernel_2d TITLE NCOMP CELLS RATIO BETA0: the head of a 2-D test case (the
# title, grid_2d, an exponential initial population) whose first mechanism is
# sum-kernel aggregation; callers append further mechanisms and the output.
sum_kernel_2d() {
  printf 'title: %s\n' "$1"
  grid_2d "$2" "$3" "$4"
  printf 'initial: {type: exponential, number: 1, mean: [0.1, 0.05]}\nmechanisms:\n'
  printf '  - type: aggregation\n    kernel: {type: sum, beta0: %s}\n' "$5"
}

# lossy_case COMPARTMENTS [OUTPUT_AND_SOLVER]: a case whose aggregation pushes
# mass past the end of its 4-cell axis by t = 1, beyond the default
# checks.max_loss (fixed pivot: with cell_average it takes ~1e5 steps, the
# pooled births of the last cell switching between kept and lost); output
# times 0..5 unless given.
lossy_case() {
  cat <<YAML
title: mass lost through the end of the grid
grid:
  compartments: $1
  axes:
    - {name: solid, type: linear, min: 0, max: 4, cells: 4}
initial: {type: cell, index: 1, number: 10}
mechanisms:
  - type: aggregation
    redistribution: fixed_pivot
    kernel: {type: constant, beta0: 1}
${2:-output: {end: 5, count: 6\}}
YAML
}

# write_case NAME TEXT: writes $WORK/NAME and prints its path.
write_case() {
  printf '%s\n' "$2" >"$WORK/$1"
  printf '%s\n' "$WORK/$1"
}

# write_beta_breakage_case: writes $WORK/beta.yaml, a 1-D breakage case with
# beta daughters whose `shape` a study may push to where GSL's incomplete beta
# fails (cli_fit, cli_optimise); prints its path.
write_beta_breakage_case() {
  write_case beta.yaml "grid:
  axes:
    - {name: v, type: geometric, min: 1.0, ratio: 2, cells: 20}
initial: {type: point, number: 1, at: [1000]}
mechanisms:
  - type: breakage
    selection: {type: power, s0: 1.0e-4, exponent: 1}
    daughters: {type: beta, fragments: 2, shape: 2}
output: {times: [0.5, 1]}"
}

# rel_close A B TOL: |A - B| <= TOL * max(|A|, |B|) (numbers as text; nan == nan).
rel_close() {
  awk -v a="$1" -v b="$2" -v tol="$3" 'BEGIN {
    if (a == b) exit 0
    if (a ~ /nan/ || b ~ /nan/) exit 1
    x = a + 0; y = b + 0; d = x - y; if (d < 0) d = -d
    m = (x < 0 ? -x : x); n = (y < 0 ? -y : y); if (n > m) m = n
    exit !(d <= tol * m)
  }'
}

# csv_rows_close FILE_A FILE_B TOL [LINE]: the two CSV files have the same
# number of lines and, on every line (or only on line LINE, counted from 1),
# the same number of fields, equal within relative TOL.
csv_rows_close() {
  local a=$1 b=$2 tol=$3 line=${4:-0}
  [ "$(wc -l <"$a")" = "$(wc -l <"$b")" ] ||
    fail "$a has $(wc -l <"$a") lines, $b has $(wc -l <"$b")"
  awk -F, -v tol="$tol" -v only="$line" '
    function abs(v) { return v < 0 ? -v : v }
    # a number (1.5e-05 included); text such as nan must match exactly
    function num(v) { return v ~ /^[-+]?([0-9]+[.]?[0-9]*|[.][0-9]+)([eE][-+]?[0-9]+)?$/ }
    NR == FNR { row[FNR] = $0; next }
    only && FNR != only { next }
    {
      n = split(row[FNR], x, ",")
      if (n != NF) { printf "line %d: %d fields vs %d\n", FNR, n, NF; bad = 1; next }
      for (i = 1; i <= NF; i++) {
        if (x[i] == $i) continue
        if (!num(x[i]) || !num($i)) { printf "line %d field %d: %s vs %s\n", FNR, i, x[i], $i; bad = 1; continue }
        m = abs(x[i] + 0); if (abs($i + 0) > m) m = abs($i + 0)
        if (abs(x[i] - $i) > tol * m) { printf "line %d field %d: %s vs %s\n", FNR, i, x[i], $i; bad = 1 }
      }
    }
    END { exit bad }' "$a" "$b" >"$WORK/csvdiff" ||
    { cat "$WORK/csvdiff" >&2; fail "$a and $b differ by more than $tol relative"; }
}

# no_result_files DIR: DIR holds neither results nor partial files.
no_result_files() {
  local f
  for f in result.h5 summary.csv .result.h5.partial .summary.csv.partial .result.h5.new .result.journal; do
    [ ! -e "$1/$f" ] || fail "$1/$f exists but should not"
  done
}

# kill_part_way PID PARTIAL_CSV ERR_FILE [--match PATTERN]: waits until the
# partial summary PARTIAL_CSV holds a few output times (so there is something
# to resume), then a random part of the time the last four took (not of the
# start-up, which a loaded machine can make longer than the whole rest), so
# that the kill lands anywhere in the computation or the writing of the next
# ones; then SIGKILLs PID, or with `--match PATTERN` every process whose
# command line matches PATTERN then (the ranks of an mpirun PID).  PID is the
# process watched for ending early (its stderr in ERR_FILE names why).
kill_part_way() {
  local pid=$1 partial=$2 errfile=$3 pattern=
  [ "${4:-}" = --match ] && pattern=$5
  local deadline=$((SECONDS + 120)) t_first want
  for want in 2 6; do
    while :; do
      if [ -f "$partial" ] && [ "$(wc -l <"$partial")" -ge "$want" ]; then break; fi
      kill -0 "$pid" 2>/dev/null || fail "the run ended before it could be killed (stderr: $(cat "$errfile"))"
      [ "$SECONDS" -lt "$deadline" ] || fail "no output written by the run within 120 s"
      sleep 0.005
    done
    [ "$want" = 2 ] && t_first=$(date +%s.%N)
  done
  sleep "$(awk -v a="$t_first" -v b="$(date +%s.%N)" -v r=$RANDOM 'BEGIN { printf "%.3f", (b - a) * r / 32768 }')"
  local victims=("$pid")
  [ -n "$pattern" ] && mapfile -t victims < <(pgrep -f -- "$pattern")
  [ "${#victims[@]}" -gt 0 ] && kill -9 "${victims[@]}" 2>/dev/null ||
    fail "the run ended before it could be killed"
}

# kill_at_random PID PARTIAL_CSV SECONDS FRACTION [--match PATTERN]: once the
# partial summary PARTIAL_CSV holds a row (it is flushed after a commit, so
# the start time is committed and there is something to resume), sleeps
# FRACTION (0 to 1) of SECONDS (an uninterrupted run's wall time) and then
# SIGKILLs PID, or with `--match PATTERN` every process whose command line
# matches PATTERN (the ranks of an mpirun PID).  Returns 1 when the run ended
# before the kill (the caller tries an earlier moment).
kill_at_random() {
  local pid=$1 partial=$2 seconds=$3 fraction=$4 pattern=
  [ "${5:-}" = --match ] && pattern=$6
  local deadline=$((SECONDS + 120))
  until [ -f "$partial" ] && [ "$(wc -l <"$partial")" -ge 2 ]; do
    kill -0 "$pid" 2>/dev/null || return 1
    [ "$SECONDS" -lt "$deadline" ] || fail "no output written by the run within 120 s"
    sleep 0.005
  done
  sleep "$(awk -v s="$seconds" -v f="$fraction" 'BEGIN { printf "%.3f", s * f }')"
  local victims=("$pid")
  [ -n "$pattern" ] && mapfile -t victims < <(pgrep -f -- "$pattern")
  [ "${#victims[@]}" -gt 0 ] && kill -9 "${victims[@]}" 2>/dev/null
}

# random_fraction: a number in [0.05, 0.85)
random_fraction() { awk -v r="$RANDOM" 'BEGIN { printf "%.3f", 0.05 + 0.8 * r / 32768 }'; }
