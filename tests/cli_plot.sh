# gransim plot DIR (and scripts/plot DIR): PNG and SVG figures of every kind
# of result folder, checked by tests/plot_check.py: the files exist and are
# non-trivial, their labels are plain text with units, the size distribution
# of an exponential distribution (whose particles carry gas) follows its closed
# form and agrees with summary.csv's d50; errors are stated.
source "$(dirname "$0")/cli-lib.sh" "$@"
CHECK=(/usr/bin/python3 "$SRC/tests/plot_check.py")
SIZES='sizes=d10 [um]|d50 [um]|d90 [um]|time [s]|compartment 1'
PSD='psd=q3 [1/um]|Q3 [-]|compartment 1: Q3'

# ---- sectional, one compartment, analytic size distribution
cat > "$WORK/expo.yaml" <<'YAML'
title: exponential distribution carrying gas
grid:
  axes: [{name: solid, type: geometric, min: 1.0e-13, ratio: 1.1, cells: 150, zero_first: true}]
  carried: [gas]
initial: {type: exponential, number: 1.0e6, mean: 1.0e-11, carried_ratio: {gas: 1.0}}
mechanisms: []
output: {end: 1, count: 2}
YAML
run_rc 0 "$BIN" run "$WORK/expo.yaml" --out "$WORK/expo" --quiet
run_rc 0 "$BIN" plot "$WORK/expo"
stdout_has "wrote 7 files" "psd, sizes, volumes"
"${CHECK[@]}" "$WORK/expo/plots" --d50 "$WORK/expo/summary.csv" --exponential 1.0e-11 1.0 \
  "$SIZES" "$PSD|diameter [um]" "volumes=total solid [m^3]|total gas [m^3]" || fail "expo plots"

# ---- sectional, 4 compartments (the CoriMix example), chosen times, SVG only, scripts/plot
mkdir -p "$WORK/cm"
cp "$SRC/examples/corimix-continuous.yaml" "$WORK/cm/"
ln -s "$SRC/examples/data" "$WORK/cm/data"
run_rc 0 "$BIN" run "$WORK/cm/corimix-continuous.yaml" --out "$WORK/cm/out" --quiet
run_rc 0 "$SRC/scripts/plot" "$WORK/cm/out" --times 20,85
"${CHECK[@]}" "$WORK/cm/out/plots" --d50 "$WORK/cm/out/summary.csv" \
  "$SIZES|compartment 4" "$PSD|compartment 4: q3|t = 20 s|t = 85 s" "volumes=total liquid [m^3]" || fail "CoriMix plots"
[ "$(cut -d, -f1 "$WORK/cm/out/plots/psd.csv" | sort -u | tr '\n' ' ')" = "20 85 time [s] " ] ||
  fail "psd.csv times: $(cut -d, -f1 "$WORK/cm/out/plots/psd.csv" | sort -u | tr '\n' ' ')"
run_rc 0 "$BIN" plot "$WORK/expo" --format svg --out "$WORK/svg"
[ -s "$WORK/svg/sizes.svg" ] && [ ! -e "$WORK/svg/sizes.png" ] || fail "--format svg"

# ---- stochastic solver: confidence bands (sizes) and sieve classes (psd)
run_rc 0 "$BIN" run "$SRC/examples/twin-screw.yaml" --out "$WORK/swa" --quiet
run_rc 0 "$BIN" plot "$WORK/swa"
"${CHECK[@]}" "$WORK/swa/plots" "$SIZES|confidence intervals" "$PSD|sieve size [um]|confidence intervals" ||
  fail "stochastic plots"
head -1 "$WORK/swa/plots/psd.csv" | grep -qF 'ci_q3 [1/um]' || fail "psd.csv of the sieves lacks ci_q3"

# ---- DEM: collision heat map, impact speeds, time series with the statistics window
sed 's/duration: 0.02/duration: 0.01/' "$SRC/examples/dem-corimix.yaml" > "$WORK/cm/dem.yaml"
run_rc 0 "$BIN" dem "$WORK/cm/dem.yaml" --out "$WORK/dem" --quiet
run_rc 0 "$BIN" plot "$WORK/dem"
stdout_has "collisions, dem-series, impacts"
"${CHECK[@]}" "$WORK/dem/plots" "collisions=C_ij [1/s]|class i|fine" \
  "impacts=normal impact speed [m/s]|wall impeller|class 3" \
  "dem-series=hold-up [g]|wall impacts [1/s]|statistics window from 0.005 s" || fail "DEM plots"

# ---- coupled: the PBM and its DEM stage, the steady state marked
run_rc 0 "$BIN" couple "$SRC/examples/corimix-coupled.yaml" --out "$WORK/cpl" --quiet
run_rc 0 "$BIN" plot "$WORK/cpl"
"${CHECK[@]}" "$WORK/cpl/plots" "$SIZES|PBM stage" "$PSD" "dem-stage-collisions=C_ij [1/s]|DEM stage" \
  "dem-stage-impacts=normal impact speed [m/s]" "dem-stage-dem-series=steady state at|PBM stage runs" ||
  fail "coupled plots"
! grep -q 'coupling-cycle' "$WORK/cpl/plots/sizes.svg" || fail "one_way coupling: cycles marked without cycles.csv"
# two-way coupling writes DIR/cycles.csv: each cycle's start is a dotted line on both time plots
printf 'cycle,t_start [s],t_end [s],trigger\n1,0,20,start\n2,20,47.5,drift\n3,47.5,85,drift\n' > "$WORK/cpl/cycles.csv"
run_rc 0 "$BIN" plot "$WORK/cpl"
"${CHECK[@]}" "$WORK/cpl/plots" "sizes=coupling cycle starts|the starts of 3 coupling cycles" \
  "volumes=coupling cycle starts|the starts of 3 coupling cycles" || fail "coupling cycles"
[ "$(grep -c 'id="coupling-cycle-[123]"' "$WORK/cpl/plots/sizes.svg")" = 9 ] || fail "sizes.svg: not 3 cycle lines on each of 3 panels"
grep -q 'id="coupling-cycle-3"' "$WORK/cpl/plots/volumes.svg" || fail "volumes.svg: no line of cycle 3"
printf 'cycle,t_start [s]\n1,0\n2,soon\n' > "$WORK/cpl/cycles.csv"
run_rc 1 "$BIN" plot "$WORK/cpl"
stderr_has "cycles.csv:3: t_start [s] 'soon' is not a number"
printf 'cycle,start\n1,0\n' > "$WORK/cpl/cycles.csv"
run_rc 1 "$BIN" plot "$WORK/cpl"
stderr_has "no column 't_start [s]'"
rm "$WORK/cpl/cycles.csv"

# ---- errors
run_rc 1 "$BIN" plot "$WORK/cm"
stderr_has "no summary.csv"
run_rc 1 "$BIN" plot "$WORK/expo" --format gif
stderr_has "--format 'gif'"
run_rc 1 "$BIN" plot "$WORK/expo" --times 1,x
stderr_has "--times '1,x'"
GRANSIM_PLOT_SCRIPT=$WORK/none run_rc 1 "$BIN" plot "$WORK/expo"
stderr_has "not installed" "GRANSIM_PLOT_SCRIPT"
echo "cli_plot: all checks passed"
