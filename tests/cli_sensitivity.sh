# gransim sensitivity: which kernel constants drive d50 in the high-shear
# example (shortened to 5 s): Morris and Sobol over the sweep write
# DIR/sensitivity.csv with their columns; bad input is refused clearly.
source "$(dirname "$0")/cli-lib.sh" "$@"

sed 's/output: {end: 120, count: 25}/output: {end: 5, count: 2}/' \
  "$SRC/examples/high-shear-batch.yaml" >"$WORK/hs.yaml"
grep -q 'end: 5, count: 2' "$WORK/hs.yaml" || fail "the example's output line changed"
R=(--range mechanisms.0.kernel.beta0=0.02:0.05:log --range mechanisms.0.kernel.alpha=0.8:1.1)

run_rc 0 "$BIN" sensitivity --help
stdout_has "usage: gransim sensitivity CASE --range KEY=LO:HI" "--method sobol:N" "morris:R"
run_rc 2 "$BIN" sensitivity "$WORK/hs.yaml" "${R[@]}" --out "$WORK/x"
stderr_has "needs CASE, --range KEY=LO:HI, --outputs COLS, --method"
run_rc 2 "$BIN" sensitivity "$WORK/hs.yaml" --range a=2:1 --outputs d50 --method morris:2 --out "$WORK/x"
stderr_has "LO must be below HI"
run_rc 2 "$BIN" sensitivity "$WORK/hs.yaml" "${R[@]}" --outputs d50 --method sobol:8 --out "$WORK/x"
stderr_has "N >= 16"
run_rc 2 "$BIN" sensitivity "$WORK/hs.yaml" "${R[@]}" --outputs d50 --method halton:8 --out "$WORK/x"
stderr_has "expected sobol:N or morris:R"
run_rc 2 "$BIN" sensitivity "$WORK/hs.yaml" --range mechanisms.0.kernel.nope=1:2 --outputs d50 \
  --method morris:2 --out "$WORK/x"
stderr_has "nope"
run_rc 2 "$BIN" sensitivity "$WORK/hs.yaml" "${R[@]}" --outputs d55 --method morris:2 --out "$WORK/x"
stderr_has "--outputs column 'd55' is no output of the case; known: M0"

# not under mpirun: every rank would run the whole sample into DIR
OMPI_COMM_WORLD_SIZE=2 run_rc 2 "$BIN" sensitivity "$WORK/hs.yaml" "${R[@]}" --outputs d50 \
  --method morris:2 --out "$WORK/mpi"
stderr_has "started by mpirun with 2 ranks"

run_rc 0 "$BIN" sensitivity "$WORK/hs.yaml" "${R[@]}" --outputs d50,M0 --method morris:2 \
  --out "$WORK/morris" --threads 2 --quiet
stdout_has "mechanisms.0.kernel.alpha" "6 runs"
# the effects are in the output's unit, the row's `unit`; the notes in the sidecar
[ "$(head -1 "$WORK/morris/sensitivity.csv")" = "output,key,mu [unit],mu_star [unit],sigma [unit],unit" ] ||
  fail "morris header: $(head -1 "$WORK/morris/sensitivity.csv")"
awk -F, 'NR > 1 && !(($1 == "d50" && $6 == "m") || ($1 == "M0" && $6 == "1")) { bad = 1 } END { exit bad }' \
  "$WORK/morris/sensitivity.csv" || fail "morris: a row without its output's unit"
grep -q '"mu": "the row'"'"'s unit"' "$WORK/morris/sensitivity.json" || fail "morris: no sidecar"
head -1 "$WORK/morris/sweep.csv" | grep -q ',d50_c1 \[m\],' || fail "the sweep's columns lack their units"
[ "$(wc -l <"$WORK/morris/sensitivity.csv")" -eq 5 ] || fail "morris: expected 4 rows"
[ "$(wc -l <"$WORK/morris/sweep.csv")" -eq 7 ] || fail "morris: the sweep has 6 runs"

run_rc 0 "$BIN" sensitivity "$WORK/hs.yaml" "${R[@]}" --outputs d50 --method sobol:16 --seed 2 \
  --bootstrap 50 --out "$WORK/sobol" --threads 2 --quiet
stdout_has "64 runs" "percentile bootstrap"
[ "$(head -1 "$WORK/sobol/sensitivity.csv")" = "output,key,S1 [1],S1_lo [1],S1_hi [1],ST [1],ST_lo [1],ST_hi [1]" ] ||
  fail "sobol header"
awk -F, 'NR > 1 && ($3 == "nan" || $6 == "nan" || NF != 8) { bad = 1 } END { exit bad }' \
  "$WORK/sobol/sensitivity.csv" || fail "sobol: a row is not 8 numbers"
# the same options again continue (here: find finished) the sweep
run_rc 0 "$BIN" sensitivity "$WORK/hs.yaml" "${R[@]}" --outputs d50 --method sobol:16 --seed 2 \
  --bootstrap 50 --out "$WORK/sobol" --threads 2 --quiet --resume
echo "cli_sensitivity: ok"
