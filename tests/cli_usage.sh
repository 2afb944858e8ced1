# gransim --help, --version, run --help, check --help, list, usage errors.
source "$(dirname "$0")/cli-lib.sh" "$@"

run_rc 0 "$BIN" --help
stdout_has "usage: gransim <command>" "run CASE --out DIR" "check CASE" "list" "docs/case-files.md"
run_rc 0 "$BIN" -h
stdout_has "usage: gransim <command>"

run_rc 0 "$BIN" --version
version=$(sed -n 's/^project(gransim VERSION \([0-9.]*\).*/\1/p' "$SRC/CMakeLists.txt")
[ -n "$version" ] || fail "cannot find the project version in $SRC/CMakeLists.txt"
grep -qx "gransim $version" "$WORK/stdout" || { show_output; fail "--version should print 'gransim $version'"; }
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
expect_section "mechanisms:" aggregation breakage growth liquid_addition consolidation feed transfer spray pore_consolidation layering nucleation drying
expect_section "breakage selection functions:" power shear dem_impact
expect_section "daughter distributions:" uniform halves power beta
expect_section "integrators (solver.method):" rk cvode euler
# every kernel in the registry is listed (catches a kernel added without updating this test)
registered=$(grep -o '&gs_kernel_[a-z_0-9]*' "$SRC/src/kernel/kernel_registry.c" | wc -l)
listed=$(section_names "aggregation kernels:" | wc -l)
[ "$registered" -eq "$listed" ] ||
  fail "kernel_registry.c registers $registered kernels but gransim list shows $listed"
# every kernel has a one-line summary
awk '/^aggregation kernels:/ { on = 1; next } /^[^ ]/ { on = 0 } on && NF < 2 { bad = 1 } END { exit bad }' \
  "$WORK/stdout" || fail "a kernel in gransim list has no summary"

echo "cli_usage: ok"
