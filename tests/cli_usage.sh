# gransim --help, --version, run --help, check --help, list, usage errors.
source "$(dirname "$0")/cli-lib.sh" "$@"

run_rc 0 "$BIN" --help
stdout_has "usage: gransim <command>" "run CASE --out DIR" "check CASE" "list" "docs/case-files.md"
run_rc 0 "$BIN" -h
stdout_has "usage: gransim <command>"

run_rc 0 "$BIN" --version
version=$(sed -n 's/^project(gransim VERSION \([0-9.]*\).*/\1/p' "$SRC/CMakeLists.txt")
[ -n "$version" ] || fail "cannot find the project version in $SRC/CMakeLists.txt"
grep -Eqx "gransim $version( \(.*\))?" "$WORK/stdout" || { show_output; fail "--version should print 'gransim $version', then git describe in parentheses in a checkout"; }
grep -Eqx "MPI: (yes|no)" "$WORK/stdout" || { show_output; fail "--version should say whether gransim was built with MPI"; }

run_rc 0 "$BIN" run --help
stdout_has "usage: gransim run CASE --out DIR" "--resume" "--threads" "result.h5" "summary.csv"

run_rc 0 "$BIN" check --help
stdout_has "usage: gransim check CASE"

# usage errors: exit status 2 with a usage line
run_rc 2 "$BIN"
stdout_has "usage: gransim <command>"
run_rc 2 "$BIN" frobnicate
stderr_has "unknown command 'frobnicate'"
run_rc 2 "$BIN" run
stderr_has "usage: gransim run CASE --out DIR"
run_rc 2 "$BIN" run case.yaml
stderr_has "usage: gransim run CASE --out DIR"
run_rc 2 "$BIN" run case.yaml --out "$WORK/o" --bogus
stderr_has "unknown option '--bogus'"
run_rc 2 "$BIN" run case.yaml --out "$WORK/o" --threads 0
stderr_has "--threads needs a positive integer"
run_rc 2 "$BIN" check
run_rc 2 "$BIN" check a.yaml b.yaml
# options by getopt_long: --key=value as well as --key value, anywhere on the line
ok=$(write_case ok.yaml "$GRID_1D
initial: {type: cell, index: 3, number: 1}
mechanisms: [{type: aggregation, kernel: {type: constant, beta0: 0.01}}]
output: {end: 1, count: 3}")
run_rc 0 "$BIN" run --out="$WORK/eq" --threads=1 "$ok" --quiet
[ -s "$WORK/eq/summary.csv" ] || fail "run --out=DIR wrote no $WORK/eq/summary.csv"
run_rc 0 "$BIN" run "$ok" --out "$WORK/sp" --threads 1 --quiet
cmp -s "$WORK/eq/summary.csv" "$WORK/sp/summary.csv" || fail "--out=DIR and --out DIR ran differently"
run_rc 0 "$BIN" sweep "$ok" --set=mechanisms.0.kernel.beta0=0.01,0.02 --out="$WORK/sw" --threads=1 --quiet
[ "$(grep -c ',ok,' "$WORK/sw/sweep.csv")" = 2 ] || fail "sweep with --set=KEY=V1,V2 did not run 2 runs"
run_rc 2 "$BIN" run "$ok" --ot "$WORK/o"
stderr_has "gransim run: unknown option '--ot'; did you mean '--out'?"
run_rc 2 "$BIN" run "$ok" --out
stderr_has "gransim run: option '--out' needs a value"
run_rc 2 "$BIN" run "$ok" --out "$WORK/o" --quiet=yes
stderr_has "gransim run: option '--quiet' takes no value"
run_rc 2 "$BIN" run "$ok" --out "$WORK/o" --threads=0
stderr_has "--threads needs a positive integer, got '0'"
run_rc 2 "$BIN" dem --chek "$ok"
stderr_has "gransim dem: unknown option '--chek'; did you mean '--check'?"
run_rc 2 "$BIN" sweep "$ok" --sett=a=1 --out "$WORK/o"
stderr_has "unknown option '--sett=a=1'; did you mean '--set'?"

# list: every registered type under its heading
run_rc 0 "$BIN" list
stdout_has "mechanisms:" "aggregation kernels:" "breakage selection functions:" \
  "daughter distributions:" "integrators (solver.method):"
# section_names HEADING: the names listed under HEADING (two-space indented lines)
section_names() {
  awk -v h="$1" '$0 == h { on = 1; next } /^[^ ]/ { on = 0 } on && /^  [^ ]/ { print $1 }' "$WORK/stdout"
}
expect_section() {
  local heading=$1 got
  shift
  got=$(section_names "$heading" | tr '\n' ' ')
  [ "$got" = "$* " ] || fail "gransim list: under '$heading' expected '$*', got '$got'"
}
expect_section "aggregation kernels:" constant sum product madec table brownian semi_mechanistic
expect_section "mechanisms:" aggregation breakage growth liquid_addition consolidation feed transfer spray pore_consolidation layering nucleation drying fluid_bed exchange impeller_schedule
expect_section "breakage selection functions:" power shear dem_impact
expect_section "daughter distributions:" uniform halves power beta
expect_section "integrators (solver.method):" auto rk cvode euler
# every kernel in the registry is listed (catches a kernel added without updating this test)
registered=$(grep -o '&gs_kernel_[a-z_0-9]*' "$SRC/src/kernel/kernel_registry.c" | wc -l)
listed=$(section_names "aggregation kernels:" | wc -l)
[ "$registered" -eq "$listed" ] ||
  fail "kernel_registry.c registers $registered kernels but gransim list shows $listed"
# every kernel has a one-line summary
awk '/^aggregation kernels:/ { on = 1; next } /^[^ ]/ { on = 0 } on && NF < 2 { bad = 1 } END { exit bad }' \
  "$WORK/stdout" || fail "a kernel in gransim list has no summary"

echo "cli_usage: ok"
