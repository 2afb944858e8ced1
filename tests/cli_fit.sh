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
stdout_has "usage: gransim fit CASE (--data MEASURED.csv | --batches BATCHES.yaml)"
run_rc 2 "$BIN" fit "$start" --data "$WORK/none.csv"
stderr_has "needs CASE, --data FILE (or --batches FILE) and --params KEY=LO:HI"
run_rc 2 "$BIN" fit "$start" --data "$WORK/none.csv" --params a=2:1
stderr_has "LO must be below HI"
run_rc 1 "$BIN" fit "$start" --data "$WORK/none.csv" "${P[@]}"
stderr_has "cannot read data file"
run_rc 2 "$BIN" fit "$start" --data "$WORK/none.csv" "${P[@]}" --global pso
stderr_has "--global pso: unknown method; expected one of crs2, mlsl, isres"
run_rc 2 "$BIN" fit "$start" --data "$WORK/none.csv" "${P[@]}" --global crs2:0
stderr_has "--global crs2:0: RUNS must be > 0"
run_rc 2 "$BIN" fit "$start" --data "$WORK/none.csv" "${P[@]}" --porosity-tol -1
stderr_has "--porosity-tol needs a number > 0, got '-1'"
run_rc 2 "$BIN" fit "$start" --data "$WORK/none.csv" "${P[@]}" --seed x
stderr_has "--seed needs a whole number >= 0, got 'x'"

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

# the same with a global start: the search's runs are reported
run_rc 0 "$BIN" fit "$start" --data "$WORK/data.csv" "${P[@]}" --global mlsl:12 --seed 2
stdout_has "(12 in the global start, mlsl)"
b=$(awk '$1 == "mechanisms.0.kernel.beta0" && NF >= 4 { print $2; exit }' "$WORK/stdout")
rel_close "$b" 0.7 1e-6 || { show_output; fail "--global: beta0 = $b, expected 0.7"; }

# a data time the case does not output
sed 's/^1,/1.5,/' "$WORK/data.csv" >"$WORK/shifted.csv"
run_rc 1 "$BIN" fit "$start" --data "$WORK/shifted.csv" "${P[@]}"
stderr_has "shifted.csv:3: column 1 (time) = 1.5 is not an output time of the case"
# A GSL failure in a model run keeps GSL's reason (the fit used to switch
# GSL's error handler off): a beta daughter of shape ~3e299 cannot be evaluated.
beta=$(write_beta_breakage_case)
printf 'time,M0\n0.5,1.0001\n1,1.0002\n' >"$WORK/beta-data.csv"
run_rc 1 "$BIN" fit "$beta" --data "$WORK/beta-data.csv" --params mechanisms.0.daughters.shape=1e299:1e300:log
stderr_has "the model at mechanisms.0.daughters.shape=3.16" "GSL: error (exceeded max number of iterations, in GSL's beta_inc.c"

stdout_lacks() { ! grep -qF "$1" "$WORK/stdout" || { show_output; fail "stdout has '$1'"; }; }

# ---- several batches, each with its own recipe (the binder rate) ----------
# a 2-D case (solid, liquid); the data per batch: d50 and the moisture and
# porosity (liquid-to-solid ratio of the totals; summary.csv's porosity column) from
# summary.csv's totals
case2_at() { # case2_at BETA0 NUMBER RATE
  printf '%s\n' "title: batches test
grid:
  axes:
    - {name: solid, type: geometric, min: 1.0e-3, ratio: 2, cells: 14, zero_first: true}
    - {name: liquid, type: geometric, min: 1.0e-4, ratio: 3, cells: 14, zero_first: true}
initial: {type: point, number: $2, at: [0.01, 0.001]}
mechanisms:
  - type: aggregation
    kernel: {type: constant, beta0: $1}
  - type: liquid_addition
    rate: $3
    start: 0
    end: 4
solver: {rtol: 1.0e-9, atol: 1.0e-20}
output: {times: [0.5, 1, 2, 4]}"
}
start2=$(write_case start2.yaml "$(case2_at 1.5 0.6 0.003)")
for b in a:0.01 b:0.03; do
  name=${b%%:*} rate=${b#*:}
  t=$(write_case "truth-$name.yaml" "$(case2_at 0.7 1.0 "$rate")")
  run_rc 0 "$BIN" run "$t" --out "$WORK/truth-$name" --quiet --threads 1
  # time [s],compartment,M0,M1,M2,d10,d50,d90,mean_solid,mean_liquid,total_solid,total_liquid
  awk -F, 'NR == 1 { print "time [s],d50 [m],moisture [1],porosity [1]" }
           NR > 2 { printf "%s,%s,%.10g,%.10g\n", $1, $7, $12 / $11, $13 }' \
    "$WORK/truth-$name/summary.csv" >"$WORK/batch-$name.csv"
done
printf '%s\n' "# two recipes of one formulation
batches:
  - name: low
    data: batch-a.csv
    set: {mechanisms.1.rate: 0.01}
  - name: high
    data: batch-b.csv
    set: {mechanisms.1.rate: 0.03}" >"$WORK/batches.yaml"
P2=(--params mechanisms.0.kernel.beta0=0.1:3:log --params initial.number=0.1:10)
# a third recipe held out: predicted at the estimates; the files for plots
t=$(write_case "truth-c.yaml" "$(case2_at 0.7 1.0 0.02)")
run_rc 0 "$BIN" run "$t" --out "$WORK/truth-c" --quiet --threads 1
awk -F, 'NR == 1 { print "time [s],d50 [m],porosity [1]" }
         NR > 2 { printf "%s,%s,%.10g\n", $1, $7, $13 }' \
  "$WORK/truth-c/summary.csv" >"$WORK/batch-c.csv"
printf 'batches: [{name: mid, data: batch-c.csv, set: {mechanisms.1.rate: 0.02}}]\n' >"$WORK/held.yaml"
run_rc 0 "$BIN" fit "$start2" --batches "$WORK/batches.yaml" "${P2[@]}" --predict "$WORK/held.yaml" \
  --out "$WORK/fit"
stdout_has "24 values in 2 batches" "singular values" "held-out batches at the estimates (--predict)"
b=$(awk '$1 == "mechanisms.0.kernel.beta0" && NF >= 4 { print $2; exit }' "$WORK/stdout")
n=$(awk '$1 == "initial.number" && NF >= 4 { print $2; exit }' "$WORK/stdout")
rel_close "$b" 0.7 1e-6 || { show_output; fail "batches: beta0 = $b, expected 0.7"; }
rel_close "$n" 1.0 1e-6 || { show_output; fail "batches: initial.number = $n, expected 1"; }
# the held-out batch's errors are those of the true values: ~1e-9 of the data
awk '$1 == "mid" && $2 == "d50" { exit !($5 < 1e-6) }' "$WORK/stdout" || { show_output; fail "d50 of the held-out batch"; }
awk '$1 == "mid" && $2 == "porosity" { exit !($5 < 1e-6) }' "$WORK/stdout" || { show_output; fail "porosity of the held-out batch"; }
# measured and model in the unit of their column, the row's unit; the estimates
# in their keys' (rate 1/s here, beta0's depends on the kernel: "case")
[ "$(head -1 "$WORK/fit/fitted.csv")" = "role,batch,time [s],column,d_lo [um],d_hi [um],measured [unit],model [unit],unit" ] ||
  fail "fitted.csv header"
awk -F, 'NR > 1 && !(($4 == "d50" && $9 == "m") || (($4 == "porosity" || $4 == "moisture") && $9 == "1")) { bad = 1 } END { exit bad }' \
  "$WORK/fit/fitted.csv" || fail "fitted.csv: a value without its column's unit"
[ "$(head -1 "$WORK/fit/estimates.csv")" = "parameter,estimate [unit],std_error [unit],ci95_lo [unit],ci95_hi [unit],range_lo [unit],range_hi [unit],log_range [1],identifiable [1],unit" ] ||
  fail "estimates.csv header"
grep -q '^mechanisms.0.kernel.beta0,.*,case$' "$WORK/fit/estimates.csv" || fail "estimates.csv: beta0's unit"
grep -q '^initial.number,.*,1$' "$WORK/fit/estimates.csv" || fail "estimates.csv: initial.number's unit"
[ "$(grep -c '^predict,mid,' "$WORK/fit/fitted.csv")" = 8 ] || fail "fitted.csv: 8 held-out values expected"
[ "$(grep -c '^fit,' "$WORK/fit/fitted.csv")" = 24 ] || fail "fitted.csv: 24 fitted values expected"
grep -q '^mechanisms.0.kernel.beta0,0.69999' "$WORK/fit/estimates.csv" || fail "estimates.csv"
# a held-out batch with a bad key is refused before the fit runs
printf 'batches: [{name: mid, data: batch-c.csv, set: {mechanisms.9.rate: 0.02}}]\n' >"$WORK/held-bad.yaml"
run_rc 1 "$BIN" fit "$start2" --batches "$WORK/batches.yaml" "${P2[@]}" --predict "$WORK/held-bad.yaml"
stderr_has "held-bad.yaml:1: batch 'mid': unknown key 'mechanisms.9.rate'"
stdout_lacks "parameter"
stdout_lacks "NOT IDENTIFIABLE"

# one batch alone with the moisture only: beta0 does not change it
awk -F, '{ print $1 "," $3 }' "$WORK/batch-a.csv" >"$WORK/moisture.csv"
printf 'batches:\n  - {name: low, data: moisture.csv, set: {mechanisms.1.rate: 0.01}}\n' \
  >"$WORK/moist.yaml"
run_rc 0 "$BIN" fit "$start2" --batches "$WORK/moist.yaml" "${P2[@]}"
stdout_has "NOT IDENTIFIABLE from these data" "mechanisms.0.kernel.beta0"
grep -q "^NOT IDENTIFIABLE.*beta0" "$WORK/stdout" || { show_output; fail "beta0 not reported"; }
grep -q "^NOT IDENTIFIABLE.*initial.number" "$WORK/stdout" && { show_output; fail "initial.number reported"; }

# bad batches and data: the file, line and column
bad_batches() { printf '%s\n' "$1" >"$WORK/bad.yaml"; }
bad_batches "batches:
  - name: low
    data: batch-a.csv
    set: {mechanisms.1.rat: 0.01}"
run_rc 1 "$BIN" fit "$start2" --batches "$WORK/bad.yaml" "${P2[@]}"
stderr_has "bad.yaml:4: batch 'low': unknown key 'mechanisms.1.rat'"
bad_batches "batches:
  - name: low
    data: batch-a.csv
    set: {mechanisms.0.kernel.beta0: 1}"
run_rc 1 "$BIN" fit "$start2" --batches "$WORK/bad.yaml" "${P2[@]}"
stderr_has "bad.yaml:2: batch 'low' sets 'mechanisms.0.kernel.beta0', which the fit estimates"
bad_batches "sievs: [0, 1.0e-4]
batches: [{name: low, data: batch-a.csv}]"
run_rc 1 "$BIN" fit "$start2" --batches "$WORK/bad.yaml" "${P2[@]}"
stderr_has "bad.yaml:1: unknown key 'sievs'" "did you mean 'sieves'?"
bad_batches "batches: []"
run_rc 1 "$BIN" fit "$start2" --batches "$WORK/bad.yaml" "${P2[@]}"
stderr_has "bad.yaml:1: " "expected at least one batch"
bad_batches "batches: [{name: low, data: nan.csv}]"
sed '3s/,[^,]*$/,nan/' "$WORK/batch-a.csv" >"$WORK/nan.csv"
run_rc 1 "$BIN" fit "$start2" --batches "$WORK/bad.yaml" "${P2[@]}"
stderr_has "nan.csv:3: column 4 (porosity) = 'nan': expected a finite number"
bad_batches "batches: [{name: low, data: late.csv}]"
sed '$s/^4,/5,/' "$WORK/batch-a.csv" >"$WORK/late.csv"
run_rc 1 "$BIN" fit "$start2" --batches "$WORK/bad.yaml" "${P2[@]}"
stderr_has "late.csv:5: column 1 (time) = 5 is outside the run of batch 'low' (0 to 4)"
printf 'time,sieve_0_100,sieve_100_inf\n4,0.5,0.5\n' >"$WORK/sieve.csv"
bad_batches "sieves: [0, 150.0e-6, .inf]
batches: [{name: low, data: sieve.csv}]"
run_rc 1 "$BIN" fit "$start2" --batches "$WORK/bad.yaml" "${P2[@]}"
stderr_has "sieve.csv:1: column 2 'sieve_0_100' is not a class of the sieves (" \
  "their classes in micrometres: 0_150, 150_inf"
printf 'time,sieve_0_100,sieve_50_inf\n4,0.5,0.5\n' >"$WORK/sieve.csv"
bad_batches "batches: [{name: low, data: sieve.csv}]"
run_rc 1 "$BIN" fit "$start2" --batches "$WORK/bad.yaml" "${P2[@]}"
stderr_has "sieve.csv:1: column 3 'sieve_50_inf' overlaps column 2 'sieve_0_100'"
printf 'time,sieve_0_x\n4,0.5\n' >"$WORK/sieve.csv"
run_rc 1 "$BIN" fit "$start2" --batches "$WORK/bad.yaml" "${P2[@]}"
stderr_has "sieve.csv:1: column 2 'sieve_0_x': expected a sieve class sieve_<LO>_<HI>"
run_rc 2 "$BIN" fit "$start2" --batches "$WORK/bad.yaml" --data "$WORK/sieve.csv" "${P2[@]}"
stderr_has "--data and --batches exclude each other"

# sieve classes measured (numbers made up: the fit need not match), drawn
# beside the model by gransim plot
printf '%s\n' "time [s],sieve_0_200000,sieve_200000_300000,sieve_300000_inf" "1,0.3,0.5,0.2" \
  "4,0.1,0.4,0.5" >"$WORK/sieves.csv"
printf 'sieves: [0, 0.2, 0.3, .inf]\nbatches: [{name: S, data: sieves.csv}]\n' >"$WORK/sieves.yaml"
run_rc 0 "$BIN" fit "$start" --batches "$WORK/sieves.yaml" --params mechanisms.0.kernel.beta0=0.01:100:log \
  --out "$WORK/sfit"
grep -q '^fit,S,4,sieve_300000_inf,300000,inf,0.5,.*,1$' "$WORK/sfit/fitted.csv" || fail "sieve rows of fitted.csv"
run_rc 0 "$BIN" plot "$WORK/sfit"
/usr/bin/python3 "$SRC/tests/plot_check.py" "$WORK/sfit/plots" \
  "fit-psd=sieve size [um]|mass fraction [-]|t = 4 s measured|t = 4 s fitted|S (fitted)" || fail "fit-psd plot"
run_rc 0 "$BIN" plot "$WORK/fit"
/usr/bin/python3 "$SRC/tests/plot_check.py" "$WORK/fit/plots" \
  "fit-parity=porosity [1] (held out)|d50 [m] (fitted)|measured / RMS of the measured column [-]" || fail "fit-parity plot"
echo "cli_fit: ok"
