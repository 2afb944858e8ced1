# gransim check: a valid case passes; invalid cases fail with exit status 1 and
# a message naming the file, the line, the key and the offending value.
source "$(dirname "$0")/cli-lib.sh" "$@"

# ---- a valid case exercising most sections --------------------------------
cat >"$WORK/kernel.csv" <<'EOF'
# DEM collision frequencies
edges, 0, 1, 100
1, 0.5
0.5, 0.25
EOF
valid=$(write_case valid.yaml "title: everything
description: >
  a case touching most keys
grid:
  compartments: 2
  axes:
    - {name: solid, type: geometric, min: 0.01, max: 50, cells: 20, zero_first: true}
    - {name: liquid, type: edges, edges: [0, 0.01, 0.1, 1, 10], pivots: [0.005, 0.05, 0.5, 5]}
  size_axes: [solid]
initial:
  - {type: gamma, number: 100, mean: [0.5, 0.3], shape: [3, 2], coverage: 1e-3}
  - {type: point, number: 5, at: [1, 0.5], compartment: 2}
  - {type: cell, number: 1, index: [3, 2]}
mechanisms:
  - type: aggregation
    redistribution: fixed_pivot
    table_limit_mb: 10
    kernel: {type: table, file: kernel.csv, beta0: 0.01, measure: volume, axes: [solid, liquid]}
  - type: aggregation
    kernel: {type: madec, beta0: 1e-4, alpha: 1, delta: 1, liquid_content: fraction, liquid_axis: liquid}
  - type: breakage
    selection: {type: shear, shear_rate: 10, b: 0.5, axes: [solid]}
    daughters: {type: beta, fragments: 3, shape: 2}
  - type: breakage
    redistribution: fixed_pivot
    selection: {type: power, s0: 0.01, exponent: 0.5}
    daughters: {type: power, exponent: 1}
  - {type: growth, axis: solid, constant: 0.001, linear: 0.01, start: 0, end: 5}
  - {type: liquid_addition, rate: [0.1, 0], start: 1, end: 4, solid_axes: [solid]}
  - type: feed
    compartment: 1
    start: 0
    end: 3
    distribution: {type: exponential, number: 2, mean: [0.5, 0.2], coverage: 1e-3}
  - {type: transfer, velocity: [1, 2], length: 10}
solver: {method: cvode, rtol: 1e-5, atol: 1e-10, linear_solver: dense, max_order: 4, max_step: 1}
output: {start: 0, end: 10, count: 6, spacing: log, first: 0.5}
checks: {mass_tolerance: 1e-8, negative_tolerance: 1e-6, max_loss: 1e-3}")
run_rc 0 "$BIN" check "$valid"
stdout_has "valid.yaml: valid" "2 axes" "compartments" "8 mechanisms" "6 output times" "integrator cvode"

# the smallest valid case: a grid and output times
minimal=$(write_case minimal.yaml "$GRID_1D
output: {end: 1}")
run_rc 0 "$BIN" check "$minimal"
stdout_has "11 output times from 0 to 1" "integrator auto"

# ---- invalid cases ------------------------------------------------------------
# bad NAME EXPECTED_LINE TEXT FRAGMENT...: `gransim check` of TEXT (written to
# NAME) exits 1 and stderr holds "NAME:LINE:" and every FRAGMENT.
bad() {
  local name=$1 line=$2 text=$3 f
  shift 3
  f=$(write_case "$name" "$text")
  run_rc 1 "$BIN" check "$f"
  stderr_has "$name:$line:" "$@"
  [ ! -s "$WORK/stdout" ] || { show_output; fail "check of $name printed on stdout"; }
}

# unknown keys, with the list of expected ones
bad unknown-key.yaml 4 "$GRID_1D
output: {end: 1, cont: 5}" \
  "unknown key 'cont' in output" "expected one of: start, times, end, count, spacing"
bad unknown-axis-key.yaml 9 "grid:
  axes:
    - name: solid
      type: linear
      min: 0
      max: 1
      cells: 10
      # a comment line
      ratoi: 2
output: {end: 1}" \
  "unknown key 'ratoi' in grid.axes[0]" "expected one of: name, type, min, max, cells"
bad unknown-top.yaml 5 "$GRID_1D
output: {end: 1}
outptu: {end: 2}" \
  "unknown key 'outptu' in the top level" "expected one of: title, description, grid"
bad unknown-kernel-key.yaml 9 "$GRID_1D
mechanisms:
  - type: aggregation
    kernel:
      type: constant
      beta0: 1
      beta1: 2
output: {end: 1}" \
  "unknown key 'beta1' in mechanisms[0].kernel" "expected one of: type, beta0"
bad unknown-solver-key.yaml 5 "$GRID_1D
output: {end: 1}
solver: {method: cvode, variant: rkf45}" \
  "unknown key 'variant' in solver" "linear_solver, max_order"

# wrong types
bad type-number.yaml 4 "$GRID_1D
output: {end: abc}" \
  "output.end = 'abc': expected a number"
bad type-integer.yaml 3 "grid:
  axes:
    - {name: solid, type: linear, min: 0, max: 10, cells: 1e2}
output: {end: 1}" \
  "grid.axes[0].cells = '1e2': expected an integer"
bad type-list.yaml 5 "$GRID_1D
output: {end: 1}
mechanisms: {type: growth, axis: solid}" \
  "mechanisms: expected a list"
bad type-bool.yaml 3 "grid:
  axes:
    - {name: solid, type: geometric, min: 1, ratio: 2, cells: 5, zero_first: maybe}
output: {end: 1}" \
  "grid.axes[0].zero_first = 'maybe': expected true or false"
bad type-enum.yaml 8 "$GRID_1D
output: {end: 1}
mechanisms:
  - type: aggregation
    kernel: {type: constant, beta0: 1}
    redistribution: cell_avg" \
  "mechanisms[0].redistribution = 'cell_avg': expected one of: cell_average, fixed_pivot"
bad type-nonfinite.yaml 4 "$GRID_1D
output: {end: .inf}" \
  "output.end = '.inf': expected a finite number"

# out of range
bad negative-min.yaml 3 "grid:
  axes:
    - {name: solid, type: linear, min: -1, max: 10, cells: 10}
output: {end: 1}" \
  "grid.axes[0].min = '-1': expected a number >= 0"
bad geometric-min.yaml 3 "grid:
  axes:
    - {name: solid, type: geometric, min: 0, ratio: 2, cells: 10}
output: {end: 1}" \
  "grid.axes[0].min = '0': expected a number > 0"
bad rtol-range.yaml 5 "$GRID_1D
output: {end: 1}
solver: {rtol: 2}" \
  "solver.rtol = '2': expected a number > 0 and < 1"
bad rebalance-range.yaml 5 "$GRID_1D
output: {end: 1}
solver: {rebalance: 1.5}" \
  "solver.rebalance = '1.5': expected a fraction in [0, 1) or 'none'"
bad rebalance-word.yaml 5 "$GRID_1D
output: {end: 1}
solver: {rebalance: never}" \
  "solver.rebalance = 'never': expected a fraction in [0, 1) or 'none'"
bad cell-index.yaml 4 "$GRID_1D
initial: {type: cell, index: 0, number: 1}
output: {end: 1}" \
  "initial.index" "index 0 on axis 'solid' must be an integer from 1 to 20"
bad compartment-range.yaml 4 "$GRID_1D
initial: {type: point, at: 1, number: 1, compartment: 2}
output: {end: 1}" \
  "initial.compartment = '2': expected an integer between 1 and 1"
bad point-outside.yaml 4 "$GRID_1D
initial: {type: point, at: 10, number: 1}
output: {end: 1}" \
  "initial.at = '10': coordinate 10 on axis 'solid' lies outside the pivots [0.25, 9.75]"
bad times-order.yaml 4 "$GRID_1D
output: {times: [1, 3, 2]}" \
  "output.times" "times must increase" "entry 2 is 2"
bad log-first.yaml 4 "$GRID_1D
output: {start: -5, end: 10, spacing: log, first: -1}" \
  "output.first = '-1': expected a number > 0 and < 10"
bad same-axis-names.yaml 3 "grid:
  axes:
    - {name: solid, type: linear, min: 0, max: 10, cells: 10}
    - {name: solid, type: linear, min: 0, max: 10, cells: 10}
output: {end: 1}" \
  "two axes are both named 'solid'"

# grid not covering the initial distribution
bad coverage.yaml 4 "$GRID_1D
initial: {type: gamma, number: 1, mean: 8, shape: 2}
output: {end: 1}" \
  "initial: grid axis 'solid' [0, 10] does not cover this distribution" "coverage"

# unknown types
bad unknown-mechanism.yaml 6 "$GRID_1D
output: {end: 1}
mechanisms:
  - type: agregation" \
  "mechanisms[0].type = 'agregation': unknown mechanism" \
  "expected one of: aggregation, breakage, growth, liquid_addition, consolidation, feed, transfer"
bad unknown-kernel.yaml 7 "$GRID_1D
output: {end: 1}
mechanisms:
  - type: aggregation
    kernel: {type: constnat, beta0: 1}" \
  "mechanisms[0].kernel.type = 'constnat': unknown kernel type" \
  "expected one of: constant, sum, product, madec, table"
bad unknown-method.yaml 5 "$GRID_1D
output: {end: 1}
solver: {method: rk45}" \
  "solver.method = 'rk45': unknown integrator method; expected one of: auto"

# missing keys
bad missing-beta0.yaml 7 "$GRID_1D
output: {end: 1}
mechanisms:
  - type: aggregation
    kernel: {type: constant}" \
  "missing key 'beta0' in mechanisms[0].kernel"
bad missing-output.yaml 1 "$GRID_1D" "missing key 'output' in the top level"
bad missing-madec-axis.yaml 8 "$GRID_1D
output: {end: 1}
mechanisms:
  - type: aggregation
    kernel:
      type: madec
      beta0: 1" \
  "mechanisms[0].kernel" "needs a grid axis named 'liquid'"
bad missing-table.yaml 9 "$GRID_1D
output: {end: 1}
mechanisms:
  - type: aggregation
    kernel:
      type: table
      file: no-such-table.csv" \
  "mechanisms[0].kernel.file" "no-such-table.csv" "cannot open kernel table"

# misspelt keys: the nearest valid key is suggested; a misspelt required key
# is reported at its own line, not as missing at its section's
bad misspelt-optional.yaml 4 "$GRID_1D
output: {end: 1, cuont: 5}" \
  "unknown key 'cuont' in output; did you mean 'count'?"
bad misspelt-required.yaml 8 "$GRID_1D
output: {end: 1}
mechanisms:
  - type: aggregation
    # the kernel, misspelt
    kernal: {type: constant, beta0: 1}" \
  "unknown key 'kernal' in mechanisms[0]: did you mean 'kernel'?" "missing key 'kernel'"
bad misspelt-type.yaml 7 "$GRID_1D
output: {end: 1}
mechanisms:
  - type: aggregation
    kernel: {type: constnat, beta0: 1}" \
  "unknown kernel type (did you mean 'constant'?)"
bad misspelt-grid.yaml 1 "gird:
  axes:
    - {name: solid, type: linear, min: 0, max: 10, cells: 20}
output: {end: 1}" \
  "unknown key 'gird' in the top level: did you mean 'grid'?"

bad misspelt-axis-type.yaml 3 "grid:
  axes:
    - {name: solid, tpye: linear, min: 0, max: 10, cells: 20}
output: {end: 1}" \
  "unknown key 'tpye' in grid.axes[0]: did you mean 'type'?" "(linear, geometric or edges)"

# every kind of case: stochastic, DEM and coupled cases are recognised
run_rc 0 "$BIN" check "$SRC/examples/twin-screw.yaml"
stdout_has "twin-screw.yaml: valid. swa solver"
run_rc 0 "$BIN" check "$SRC/examples/dem-corimix.yaml"
stdout_has "dem-corimix.yaml: valid. DEM case: 3 size classes"
run_rc 1 "$BIN" run "$SRC/examples/dem-corimix.yaml" --out "$WORK/dem-run"
stderr_has "is a DEM case (a \`dem:\` section and no grid): run it with \`gransim dem "
[ ! -e "$WORK/dem-run" ] || fail "gransim run of a DEM case created its output folder"
run_rc 0 "$BIN" check "$SRC/examples/corimix-coupled.yaml"
stdout_has "corimix-coupled.yaml: valid. one_way:"
bad dem-misspelt.yaml 3 "dem: {time_step: 1.0e-5, duration: 0.01, box: {lo: [0, 0, 0], hi: [1, 1, 1]}}
materials: [{name: glass, E: 1.0e7, nu: 0.3, e: 0.5, mu_s: 0.5, density: 2500}]
clases: [{name: a, radius: 1.0e-3, material: glass}]" \
  "unknown key 'clases' in the top level: did you mean 'classes'?"

# YAML-level errors
bad syntax.yaml 5 "$GRID_1D
output: {end: 1
  count: [3" \
  "YAML syntax error"
bad duplicate.yaml 5 "$GRID_1D
output: {end: 1}
output: {end: 2}" \
  "duplicate key 'output' in the top level (first given on line 4)"
bad anchor.yaml 3 "grid:
  axes:
    - &ax {name: solid, type: linear, min: 0, max: 10, cells: 20}
output: {end: 1}" \
  "YAML anchors (&ax) are not supported"

# empty and missing files
f=$(write_case empty.yaml "# nothing but a comment")
run_rc 1 "$BIN" check "$f"
stderr_has "empty.yaml: the case file is empty"
run_rc 1 "$BIN" check "$WORK/no-such-case.yaml"
stderr_has "cannot open case file '$WORK/no-such-case.yaml'" "No such file or directory"

# run refuses an invalid case the same way and creates nothing
f=$(write_case run-bad.yaml "$GRID_1D
output: {end: -1}")
run_rc 1 "$BIN" run "$f" --out "$WORK/out-bad"
stderr_has "run-bad.yaml:4: output.end = '-1': expected a number > 0"
[ ! -e "$WORK/out-bad" ] || fail "run of an invalid case created $WORK/out-bad"

# A beta daughter of large shape: its incomplete beta lies below the smallest
# double far into the tails, where GSL's default handler aborted (exit 134).
# Shape 100 is computed (check and run exit 0); shape 1e300 is beyond GSL's
# continued fraction and refused naming the key, never aborted.
beta_case() {
  printf 'grid:\n  axes:\n    - {name: v, type: geometric, min: 1.0, ratio: 2, cells: 20}\n'
  printf 'initial: {type: point, number: 1, at: [1000]}\nmechanisms:\n'
  printf '  - type: breakage\n    selection: {type: power, s0: 1.0e-4, exponent: 1}\n'
  printf '    daughters: {type: beta, fragments: 2, shape: %s}\n' "$1"
  printf 'output: {end: 1, count: 3}\n'
}
f=$(write_case beta100.yaml "$(beta_case 100)")
run_rc 0 "$BIN" check "$f"
stdout_has "beta100.yaml: valid"
run_rc 0 "$BIN" run "$f" --out "$WORK/out-beta" --quiet
[ -s "$WORK/out-beta/result.h5" ] || fail "the beta case wrote no result.h5"
f=$(write_case beta-huge.yaml "$(beta_case 1e300)")
for cmd in check "run --out $WORK/out-beta-huge"; do
  run_rc 1 "$BIN" $cmd "$f"
  stderr_has "beta-huge.yaml:8: mechanisms[0].daughters" "daughter distribution 'beta' cannot be evaluated" \
    "GSL: " "exceeded max number of iterations"
done

# Distributions the grid would distort: the issue's constant-kernel case on a
# 400-cell linear grid started with 2.52 times the requested volume; refused
# by check and run, naming the key and both values.  With a tolerance above
# the error it runs, check and run report the comparison, and result.h5 keeps it.
distorted() {
  printf 'grid:\n  axes:\n    - {name: v, type: linear, min: 0, max: 400, cells: 400}\n'
  printf 'initial: {type: exponential, number: 1, mean: 0.2}\n'
  printf 'mechanisms:\n  - {type: aggregation, kernel: {type: constant, beta0: 1}}\n'
  printf 'output: {end: 1, count: 3}\n%s\n' "$1"
}
f=$(write_case distorted.yaml "$(distorted "")")
for cmd in check "run --out $WORK/out-distorted"; do
  run_rc 1 "$BIN" $cmd "$f"
  stderr_has "distorted.yaml:4: initial" "volume of axis 'v' of 0.504717 instead of the requested 0.2" \
    "discretisation.tolerance = 0.01"
done
[ ! -e "$WORK/out-distorted/result.h5" ] || fail "a refused case wrote result.h5"
f=$(write_case distorted-ok.yaml "$(distorted "discretisation: {tolerance: 2}")")
run_rc 0 "$BIN" check "$f"
stdout_has "discretisation: $f:4: initial: the grid holds number 1 (asked 1), volume of 'v' 0.504717 (asked 0.2); largest relative error 1.5 (discretisation.tolerance 2)"
run_rc 0 "$BIN" run "$f" --out "$WORK/out-distorted-ok"
stderr_has "discretisation: $f:4: initial: the grid holds number 1"
h5dump -d /discretisation/error "$WORK/out-distorted-ok/result.h5" | grep -q "1.5235" ||
  fail "result.h5 lacks /discretisation/error"
h5dump -a /discretisation/keys "$WORK/out-distorted-ok/result.h5" | grep -qF "distorted-ok.yaml:4: initial" ||
  fail "result.h5 lacks /discretisation keys"

# A table kernel whose class edge lies on a pivot (0.75, the pivot of the
# second cell of [0, 10] in 20 cells; 2.25 within round-off of 1.5 + 0.75):
# the cell takes the class above the edge, and the user is told.
printf 'edges, 0, 0.75, 2.25, 10\n1, 1, 1\n1, 1, 1\n1, 1, 1\n' >"$WORK/edge-kernel.csv"
f=$(write_case table-edge.yaml "$GRID_1D
initial: {type: point, number: 1, at: [5]}
mechanisms:
  - type: aggregation
    kernel: {type: table, file: edge-kernel.csv, beta0: 1}
output: {end: 1}")
run_rc 0 "$BIN" check "$f"
stderr_has "edge-kernel.csv: 2 of 20 grid cells have their size on an edge between two classes" \
  "(the first: cell 1, 0.75) and take the class above it"

# Magnitudes beyond what doubles hold, refused where they are written (the
# fuzzed case files that had overflowed into an unnamed integrator error,
# run with an empty state, or tried to allocate 320 GB).
bad overflow-axis.yaml 3 "grid:
  axes:
    - {name: solid, type: geometric, min: 1.0e-13, ratio: 2.5, cells: 1000}
initial: {type: point, number: 1.0e6, at: [1.0e-12]}
output: {end: 1}" "grid.axes[0]: axis 'solid': its last edge is inf, beyond 1e+100"
bad overflow-number.yaml 4 "grid:
  axes:
    - {name: solid, type: geometric, min: 1.0e-13, ratio: 2, cells: 10}
initial: {type: point, number: 1.0e308, at: [1.0e-12]}
output: {end: 1}" "initial: the case's totals" "overflow the solver's error scales"
# a gamma distribution whose every edge is infinitely many means above it:
# GSL's CDF is NaN there, which the coverage test had let through
bad gamma-far-below.yaml 4 "grid:
  axes:
    - {name: solid, type: geometric, min: 1.0e50, ratio: 2, cells: 10}
initial: {type: gamma, number: 1.0e6, mean: [1.0e-270], shape: [8]}
output: {end: 1}" "does not cover this distribution: 1 of its number and 1 of its volume lie outside"
bad pair-tables.yaml 6 "grid:
  axes:
    - {name: solid, type: linear, min: 0, max: 1, cells: 20000}
initial: {type: point, number: 1.0e6, at: [0.5]}
mechanisms:
  - {type: aggregation, kernel: {type: constant, beta0: 1.0e-9}}
limits: {memory_gb: 1}
output: {end: 1}" "mechanisms[0]: its tables over pairs of cells need 12.8 GB (axes of 20000 cells)" \
  "limits.memory_gb = 1 GB"

echo "cli_check: ok"
