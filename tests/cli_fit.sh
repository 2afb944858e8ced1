# gransim fit: bad input is refused with a clear message; parameters are
# recovered from data written by `gransim run` of the true case (summary.csv,
# 10 digits) from a distant start.
source "$(dirname "$0")/cli-lib.sh" "$@"

case_at() { # case_at BETA0 NUMBER: 1-D constant kernel, outputs at 0.5, 1, 2, 4
  printf '%s\n' "title: fit test
grid:
  axes:
    - {name: solid, type: geometric, min: 1.0e-3, ratio: 1.5, cells: 30, zero_first: true}
initial: {type: exponential, number: $2, mean: 0.01}
mechanisms:
  - type: aggregation
    kernel: {type: constant, beta0: $1}
solver: {rtol: 1.0e-12, atol: 1.0e-20}
output: {times: [0.5, 1, 2, 4]}"
}
truth=$(write_case truth.yaml "$(case_at 0.7 1.3)")
start=$(write_case start.yaml "$(case_at 3 0.4)")
P=(--params mechanisms.0.kernel.beta0=0.01:100:log --params initial.number=0.1:10)

run_rc 0 "$BIN" fit --help
stdout_has "usage: gransim fit CASE --data MEASURED.csv --params KEY=LO:HI"
run_rc 2 "$BIN" fit "$start" --data "$WORK/none.csv"
stderr_has "needs CASE, --data FILE and --params KEY=LO:HI"
run_rc 2 "$BIN" fit "$start" --data "$WORK/none.csv" --params a=2:1
stderr_has "LO must be below HI"
run_rc 1 "$BIN" fit "$start" --data "$WORK/none.csv" "${P[@]}"
stderr_has "cannot read data file"

run_rc 0 "$BIN" run "$truth" --out "$WORK/truth" --quiet --threads 1
# summary.csv: time [s],compartment,M0 [1],M1 [m^3],M2 [m^6],d10 [m],d50 [m],...; the data: M0
# and d50 after t = 0, their units kept (one compartment: d50 names d50_c1)
awk -F, 'NR == 1 { print $1 "," $3 "," $7 } NR > 2 { print $1 "," $3 "," $7 }' \
  "$WORK/truth/summary.csv" >"$WORK/data.csv"
run_rc 0 "$BIN" fit "$start" --data "$WORK/data.csv" "${P[@]}"
stdout_has "R^2 = " "correlations:" "4 times x 2 columns"
b=$(awk '$1 == "mechanisms.0.kernel.beta0" && NF >= 4 { print $2; exit }' "$WORK/stdout")
n=$(awk '$1 == "initial.number" && NF >= 4 { print $2; exit }' "$WORK/stdout")
rel_close "$b" 0.7 1e-6 || { show_output; fail "beta0 = $b, expected 0.7"; }
rel_close "$n" 1.3 1e-6 || { show_output; fail "initial.number = $n, expected 1.3"; }

# a data time the case does not output
sed 's/^1,/1.5,/' "$WORK/data.csv" >"$WORK/shifted.csv"
run_rc 1 "$BIN" fit "$start" --data "$WORK/shifted.csv" "${P[@]}"
stderr_has "data time 1.5 is not an output time of the case"
# A GSL failure in a model run keeps GSL's reason (the fit used to switch
# GSL's error handler off): a beta daughter of shape ~3e299 cannot be evaluated.
beta=$(write_case beta.yaml "grid:
  axes:
    - {name: v, type: geometric, min: 1.0, ratio: 2, cells: 20}
initial: {type: point, number: 1, at: [1000]}
mechanisms:
  - type: breakage
    selection: {type: power, s0: 1.0e-4, exponent: 1}
    daughters: {type: beta, fragments: 2, shape: 2}
output: {times: [0.5, 1]}")
printf 'time,M0\n0.5,1.0001\n1,1.0002\n' >"$WORK/beta-data.csv"
run_rc 1 "$BIN" fit "$beta" --data "$WORK/beta-data.csv" --params mechanisms.0.daughters.shape=1e299:1e300:log
stderr_has "the model at mechanisms.0.daughters.shape=3.16" "GSL: error (exceeded max number of iterations, in GSL's beta_inc.c"
echo "cli_fit: ok"
