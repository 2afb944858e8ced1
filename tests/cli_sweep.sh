# gransim sweep: bad input is refused with a clear message before any run; a
# grid's gathered outputs equal those of `gransim run` of the same variation;
# a failing variation is recorded without stopping the others; a killed sweep
# resumes running only the unfinished runs; a Latin hypercube is reproducible
# from its seed.
source "$(dirname "$0")/cli-lib.sh" "$@"

# 1-D constant kernel on 4 cells: beta0 = 1 loses mass past the grid's end
# (checks.max_loss fails the run), beta0 <= 2e-3 does not
c=$(write_case tiny.yaml "$(lossy_case 1 'output: {end: 2, count: 3}')")
B=mechanisms.0.kernel.beta0

run_rc 0 "$BIN" sweep --help
stdout_has "usage: gransim sweep CASE --set KEY=V1,V2" "--design lhs:N" "--resume" "d50_c<j>"
run_rc 0 "$BIN" --help
stdout_has "sweep CASE --set KEY=V1,V2,..."

# bad input: exit 2 for the command line, 1 for what the case says
run_rc 2 "$BIN" sweep "$c" --out "$WORK/x"
stderr_has "nothing to vary"
run_rc 2 "$BIN" sweep "$c" --set "$B" --out "$WORK/x"
stderr_has "--set '$B': expected KEY=V1,V2,..."
run_rc 2 "$BIN" sweep "$c" --set "$B=1,,2" --out "$WORK/x"
stderr_has "empty value in the list of $B"
run_rc 2 "$BIN" sweep "$c" --set "$B=1,2"
stderr_has "needs a CASE and --out DIR"
run_rc 2 "$BIN" sweep "$c" --design lhs:0 --range "$B=1:2" --out "$WORK/x"
stderr_has "--design lhs:0: N must be at least 1"
run_rc 2 "$BIN" sweep "$c" --design lhs:x --range "$B=1:2" --out "$WORK/x"
stderr_has "--design: expected lhs:N, got 'lhs:x'"
run_rc 2 "$BIN" sweep "$c" --design lhs:4 --range "$B=2:1" --out "$WORK/x"
stderr_has "LO must be below HI"
run_rc 2 "$BIN" sweep "$c" --design lhs:4 --range "$B=" --out "$WORK/x"
stderr_has "expected KEY=LO:HI with two numbers"
run_rc 2 "$BIN" sweep "$c" --design lhs:4 --out "$WORK/x"
stderr_has "needs at least one --range"
run_rc 2 "$BIN" sweep "$c" --range "$B=1:2" --out "$WORK/x"
stderr_has "--range needs --design lhs:N"
run_rc 2 "$BIN" sweep "$c" --set "$B=1" --set "$B=2" --out "$WORK/x"
stderr_has "key '$B' is varied twice"
run_rc 1 "$BIN" sweep "$c" --set "mechanisms.0.kernel.beta=1,2" --out "$WORK/x"
stderr_has "key 'mechanisms.0.kernel.beta': the case has no 'beta' in mechanisms[0].kernel (it has: type, beta0)"
run_rc 1 "$BIN" sweep "$c" --set "solver.rtol=1e-6" --out "$WORK/x"
stderr_has "key 'solver.rtol': the case has no 'solver' in the top level"
run_rc 1 "$BIN" sweep "$c" --set "$B=1,-2" --out "$WORK/x"
stderr_has "run 2 ($B=-2): " "tiny.yaml:10: mechanisms[0].kernel.beta0 = '-2'"
run_rc 1 "$BIN" sweep "$c" --set "$B=1" --outputs d51 --out "$WORK/x"
stderr_has "unknown summary column 'd51'"
if "$BIN" --version | grep -q "MPI: no"; then # under mpirun, a gransim without MPI refuses
  run_rc 2 env OMPI_COMM_WORLD_SIZE=2 "$BIN" sweep "$c" --set "$B=1" --out "$WORK/x"
  stderr_has "started by mpirun with 2 ranks, but this gransim was built without MPI"
fi
[ ! -e "$WORK/x" ] || fail "a refused sweep wrote $WORK/x"

# a grid: 3 x 2 runs, one of which (beta0 = 1) loses mass through the grid's end
out=$WORK/grid
run_rc 0 "$BIN" sweep "$c" --set "$B=1e-3,1,2e-3" --set output.end=1,2 --outputs M2 --out "$out" --threads 2
stderr_has "6 runs: 6 run now, 0 finished before" "4 ok, 2 failed" "$out/sweep.csv"
stderr_lacks "runs done" # no progress line when stderr is no terminal
# every column but run, status and error with its unit, as summary.csv's (beta0's
# depends on the kernel: "case", the unit the case file gives it)
[ "$(head -n 1 "$out/sweep.csv")" = "run,status,$B [case],output.end [s],M0 [1],M1_solid [m^3],d10_c1 [m],d50_c1 [m],d90_c1 [m],M2_c1 [m^6],error" ] ||
  fail "sweep.csv header: $(head -n 1 "$out/sweep.csv")"
head -n 1 "$out/sweep.csv" | tr ',' '\n' | grep -vxE 'run|status|error|.* \[[^]]+\]' &&
  fail "sweep.csv: a column without its unit"
[ "$(head -n 1 "$out/runs.csv")" = "$(head -n 1 "$out/sweep.csv")" ] || fail "runs.csv's header is not sweep.csv's"
[ "$(wc -l <"$out/sweep.csv")" -eq 7 ] || fail "sweep.csv has $(wc -l <"$out/sweep.csv") lines, expected 7"
grep -q '^3,error,1,1,nan,.*checks.max_loss' "$out/sweep.csv" || fail "run 3 (beta0 = 1) not recorded as failed"
grep -q '^6,ok,2e-3,2,' "$out/sweep.csv" || fail "run 6 (beta0 = 2e-3, end 2) missing or failed"

# sweep.h5: the same numbers as sweep.csv (17 digits), nan for the failed runs
if command -v h5dump >/dev/null 2>&1; then
  h5dump -A 0 -y -w 0 -m %.17g -d /outputs/d50_c1 "$out/sweep.h5" |
    awk '/DATA \{/ { f = 1; next } f && /\}/ { f = 0 } f' | tr -d ' \n' | tr ',' '\n' >"$WORK/h5col"
  echo >>"$WORK/h5col"
  awk -F, 'NR > 1 { print $8 }' "$out/sweep.csv" >"$WORK/csvcol"
  cmp "$WORK/h5col" "$WORK/csvcol" || fail "sweep.h5's /outputs/d50_c1 differs from sweep.csv's d50_c1"
  # every dataset's units and dimensions, the units sweep.csv's
  for a in /outputs/d50_c1/units=m /outputs/M2_c1/units=m^6 /outputs/M0/units=1 \
    "/params/output.end/units=s" "/params/$B/units=case" /run/units=1 /status/units= \
    /outputs/d50_c1/dimensions=run "/params/$B/dimensions=run" /error/dimensions=run; do
    got=$(h5dump -a "${a%%=*}" "$out/sweep.h5" | sed -n 's/^ *(0): "\(.*\)"$/\1/p')
    [ "$got" = "${a#*=}" ] || fail "sweep.h5 attribute ${a%%=*} is '$got', expected '${a#*=}'"
  done
fi

# run 6 again with gransim run: the same final M0, M1, d10, d50, d90, M2
sed -e 's/beta0: 1}/beta0: 2e-3}/' "$c" >"$WORK/run6.yaml"
run_rc 0 "$BIN" run "$WORK/run6.yaml" --out "$WORK/run6" --threads 1 --quiet
# summary.csv: time [s],compartment,M0 [1],M1 [m^3],M2 [m^6],d10 [m],d50 [m],d90 [m],...; its numbers have 10 digits
awk -F, 'END { print $3 "," $4 "," $6 "," $7 "," $8 "," $5 }' "$WORK/run6/summary.csv" >"$WORK/want"
awk -F, '$1 == 6 { print $5 "," $6 "," $7 "," $8 "," $9 "," $10 }' "$out/sweep.csv" >"$WORK/got"
csv_rows_close "$WORK/want" "$WORK/got" 1e-9

# --at: the same outputs also at an earlier output time, equal to gransim run's summary.csv there
run_rc 2 "$BIN" sweep "$c" --set "$B=2e-3" --at 1,x --out "$WORK/x"
stderr_has "--at: expected output times T1,T2,... [s] >= 0, got '1,x'"
run_rc 1 "$BIN" sweep "$c" --set "$B=2e-3" --at 0.7 --out "$WORK/x"
stderr_has "--at 0.7: not an output time of the case"
run_rc 1 "$BIN" sweep "$c" --set "$B=2e-3" --at 1,1 --out "$WORK/x"
stderr_has "--at 1 is given twice"
[ ! -e "$WORK/x" ] || fail "a refused sweep wrote $WORK/x"
run_rc 0 "$BIN" sweep "$c" --set "$B=1e-3,2e-3" --at 1 --outputs M2 --out "$WORK/at" --threads 2
head -n 1 "$WORK/at/sweep.csv" | grep -q ',M2_c1 \[m^6\],M0@1 \[1\],M1_solid@1 \[m^3\],d10_c1@1 \[m\],d50_c1@1 \[m\],d90_c1@1 \[m\],M2_c1@1 \[m^6\],error$' ||
  fail "--at columns: $(head -n 1 "$WORK/at/sweep.csv")"
awk -F, '$1 + 0 == 1 { print $3 "," $4 "," $6 "," $7 "," $8 "," $5 }' "$WORK/run6/summary.csv" >"$WORK/want"
awk -F, '$1 == 2 { print $10 "," $11 "," $12 "," $13 "," $14 "," $15 }' "$WORK/at/sweep.csv" >"$WORK/got"
[ -s "$WORK/want" ] || fail "run6 has no output time 1"
csv_rows_close "$WORK/want" "$WORK/got" 1e-9
awk -F, '$1 == 2 { print $4 "," $5 "," $6 "," $7 "," $8 "," $9 }' "$WORK/at/sweep.csv" >"$WORK/final"
cmp -s "$WORK/final" "$WORK/got" && fail "--at 1 gave the final time's values"

# resume: a sweep killed after two runs (and in the middle of a third row's write)
cp "$out/sweep.csv" "$WORK/complete.csv"
head -n 3 "$out/runs.csv" >"$WORK/part"
printf '4,ok,1e-3' >>"$WORK/part"
cp "$WORK/part" "$out/runs.csv"
rm "$out/sweep.csv"
run_rc 1 "$BIN" sweep "$c" --set "$B=1e-3,1,2e-3" --set output.end=1,2 --outputs M2 --out "$out"
stderr_has "holds the runs of an earlier sweep: add --resume"
run_rc 0 "$BIN" sweep "$c" --set "$B=1e-3,1,2e-3" --set output.end=1,2 --outputs M2 --out "$out" --resume
stderr_has "6 runs: 4 run now, 2 finished before" "4 ok, 2 failed"
cmp "$out/sweep.csv" "$WORK/complete.csv" || fail "the resumed sweep.csv differs from the uninterrupted one"
run_rc 0 "$BIN" sweep "$c" --set "$B=1e-3,1,2e-3" --set output.end=1,2 --outputs M2 --out "$out" --resume --progress
stderr_has "6 runs: 0 run now, 6 finished before"
stderr_lacks "runs done" # nothing run now
run_rc 1 "$BIN" sweep "$c" --set "$B=1e-3,1,2e-3" --set output.end=1,2 --out "$out" --resume
stderr_has "cannot resume" "other keys or outputs"
# a journal of a gransim before the units (header without them) still resumes
{ head -n 1 "$out/runs.csv" | sed 's/ \[[^]]*\]//g'; sed -n 2,3p "$out/runs.csv"; } >"$WORK/old"
grep -q '^run,status,mechanisms.0.kernel.beta0,output.end,M0,M1_solid,d10_c1' "$WORK/old" || fail "old header"
cp "$WORK/old" "$out/runs.csv"
run_rc 0 "$BIN" sweep "$c" --set "$B=1e-3,1,2e-3" --set output.end=1,2 --outputs M2 --out "$out" --resume
stderr_has "6 runs: 4 run now, 2 finished before"
cmp "$out/sweep.csv" "$WORK/complete.csv" || fail "the sweep resumed from an old journal differs"
sed -i '1s/d50_c1/d55_c1/' "$WORK/old"
cp "$WORK/old" "$out/runs.csv"
run_rc 1 "$BIN" sweep "$c" --set "$B=1e-3,1,2e-3" --set output.end=1,2 --outputs M2 --out "$out" --resume
stderr_has "cannot resume" "other keys or outputs"
cmp "$c" "$out/base-case.yaml" || fail "$out/base-case.yaml is not the case file"
sed 's/count: 3/count: 4/' "$c" >"$WORK/edited.yaml"
run_rc 1 "$BIN" sweep "$WORK/edited.yaml" --set "$B=1e-3,1,2e-3" --set output.end=1,2 --outputs M2 --out "$out" --resume
stderr_has "cannot resume: the case file '$WORK/edited.yaml' differs from '$out/base-case.yaml'"

# a Latin hypercube: N rows, the same for the same seed, others for another
for s in 7 7 8; do
  run_rc 0 "$BIN" sweep "$c" --design lhs:5 --range "$B=1e-4:1e-2:log" --range output.end=1:2 \
    --seed $s --out "$WORK/lhs$s-$RANDOM"
  stderr_has "5 runs: 5 run now"
done
set -- "$WORK"/lhs7-*/sweep.csv
[ $# = 2 ] || fail "expected two sweeps with seed 7"
[ "$(wc -l <"$1")" -eq 6 ] || fail "the hypercube has $(wc -l <"$1") lines, expected 6"
cmp "$1" "$2" || fail "two hypercubes with seed 7 differ"
! cmp -s "$1" "$WORK"/lhs8-*/sweep.csv || fail "the hypercubes with seeds 7 and 8 are the same"
echo "cli_sweep: ok"
