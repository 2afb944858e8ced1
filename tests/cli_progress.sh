# The progress line: `gransim run` (sectional and swa) and `gransim dem` show
# one on a terminal (faked with util-linux `script`), with the time reached,
# the rate and the time left, rewritten between output times too; nothing
# when stderr is a pipe or a file, nor with --quiet; a DEM run's results do
# not depend on it (it advances in pieces while the line shows).
source "$(dirname "$0")/cli-lib.sh" "$@"
command -v script >/dev/null || fail "util-linux 'script' is missing (package bsdutils)"

# on a fake terminal: stdout and stderr of CMD... together in $WORK/tty
on_tty() {
  local cmd
  printf -v cmd '%q ' "$@"
  script -qec "$cmd" /dev/null >"$WORK/tty" </dev/null || { cat "$WORK/tty" >&2; fail "'$*' failed on a terminal"; }
}
# the line's rewrites, one per line
rewrites() { tr '\r' '\n' <"$WORK/tty" | grep "$1" || true; }

# one output interval (0 to 120 s) whose steps take all the time, ~1.4 s:
# the high-shear example with rk on 3 cells per doubling of each axis (on
# its own grid it takes 0.1 s since cell average pools negative noise births
# apart; before, its wet massing took rk 100 000 steps and 35 s)
r=1.2599210498948732
sed "s/^solver:.*/solver: {method: rk, rtol: 1.0e-5, atol: 0.1}/; s/^output:.*/output: {end: 120, count: 2}/
     s/ratio: 2, cells: 18}/ratio: $r, cells: 54}/; s/ratio: 2, cells: 20, zero_first/ratio: $r, cells: 60, zero_first/" \
  "$SRC/examples/high-shear-batch.yaml" >"$WORK/batch.yaml"
grep -q "cells: 54}" "$WORK/batch.yaml" && grep -q "cells: 60, zero_first" "$WORK/batch.yaml" ||
  fail "could not refine the high-shear example's grid"
on_tty "$BIN" run "$WORK/batch.yaml" --out "$WORK/o1" --threads 1
rewrites 'gransim: t = ' >"$WORK/lines"
grep -q 't = 120 of 120 s (100%), .* s/s, 0 s left, [0-9]* steps' "$WORK/lines" ||
  fail "no final progress line: $(cat "$WORK/tty")"
# between the output times 0 and 120 the line moved (from the integrator's evaluations)
grep -Eq 't = [0-9.e+-]+ of 120 s \(([1-9]|[1-9][0-9])%\), .* left' "$WORK/lines" ||
  fail "the line was not rewritten between output times: $(cat "$WORK/tty")"
grep -q 'done to t = 120' "$WORK/tty" || fail "no summary line"
# a pipe and a file get the summary only
"$BIN" run "$WORK/batch.yaml" --out "$WORK/o2" --threads 1 2>&1 | cat >"$WORK/piped"
grep -q 'done to t = 120' "$WORK/piped" || fail "no summary line in the pipe"
! grep -q $'\r\|s left' "$WORK/piped" || fail "a progress line went into a pipe: $(cat -A "$WORK/piped")"
run_rc 0 "$BIN" run "$WORK/batch.yaml" --out "$WORK/o3" --threads 1
stderr_lacks "s left"
# --quiet on a terminal
on_tty "$BIN" run "$WORK/batch.yaml" --out "$WORK/o4" --threads 1 --quiet
! grep -q 's left' "$WORK/tty" || fail "--quiet still showed a progress line"

# the stochastic solver: run-seconds of all runs
sed 's/^  runs: 4/  runs: 2/; s/particles: 1024 /particles: 256 /' "$SRC/examples/twin-screw.yaml" >"$WORK/swa.yaml"
on_tty "$BIN" run "$WORK/swa.yaml" --out "$WORK/s1" --threads 1
rewrites 'gransim swa: t = ' | grep -q 'run-s (100%), .* 2 of 2 runs done' ||
  fail "no swa progress line: $(cat "$WORK/tty")"
run_rc 0 "$BIN" run "$WORK/swa.yaml" --out "$WORK/s2" --threads 1
stderr_lacks "runs done"
stderr_lacks "s left"

# DEM: the CoriMix example, shortened; the same results with and without the line
sed 's/duration: 0.02/duration: 0.004/; s/vtk_every: 0.01/vtk_every: 0/; s/start: 0.005/start: 0.001/' \
  "$SRC/examples/dem-corimix.yaml" >"$WORK/dem.yaml"
grep -q '^  duration: 0.004$' "$WORK/dem.yaml" || fail "could not shorten the CoriMix example"
mkdir -p "$WORK/data"
ln -s "$SRC/examples/data/corimix" "$WORK/data/corimix"
on_tty "$BIN" dem "$WORK/dem.yaml" --out "$WORK/d1" --threads 1
rewrites 'gransim dem: t = ' | grep -q 't = 0.004 of 0.004 s (100%), .* particles, .* contacts' ||
  fail "no DEM progress line: $(cat "$WORK/tty")"
run_rc 0 "$BIN" dem "$WORK/dem.yaml" --out "$WORK/d2" --threads 1
stderr_lacks "s left"
for f in timeseries.csv collisions.csv impacts.csv; do
  # the last column of the time series is the wall clock
  if [ $f = timeseries.csv ]; then
    cut -d, -f1-8 "$WORK/d1/$f" >"$WORK/a"
    cut -d, -f1-8 "$WORK/d2/$f" >"$WORK/b"
  else
    cp "$WORK/d1/$f" "$WORK/a"
    cp "$WORK/d2/$f" "$WORK/b"
  fi
  cmp -s "$WORK/a" "$WORK/b" || fail "$f differs with the progress line: $(diff "$WORK/a" "$WORK/b" | head)"
done
echo "cli_progress: ok"
