# Physically impossible or implausible recipes (issue 24, item 8): `gransim
# check` and `gransim run` refuse each with exit status 1 and a message naming
# file, line and key, and a refused run leaves no result files behind.
source "$(dirname "$0")/cli-lib.sh" "$@"
base=$SRC/examples/fluid-bed-batch.yaml

# bad NAME 'sed expression' 'file:line: key' 'words of the reason'...
bad() {
  local name=$1 expr=$2 where=$3
  shift 3
  sed "$expr" "$base" >"$WORK/$name.yaml"
  cmp -s "$base" "$WORK/$name.yaml" && fail "$name: the sed expression changed nothing"
  run_rc 1 "$BIN" check "$WORK/$name.yaml"
  stderr_has "$name.yaml:$where" "$@"
  run_rc 1 "$BIN" run "$WORK/$name.yaml" --out "$WORK/out-$name" --quiet
  stderr_has "$name.yaml:$where" "$@"
  no_result_files "$WORK/out-$name"
}

bad negative-spray 's/rate: 9.0e-7 /rate: -9.0e-7 /' '24: mechanisms[1].rate' 'rates must be >= 0'
bad overlapping-phases 's/{start: 600, end: 900, temperature: 333/{start: 500, end: 900, temperature: 333/' \
  '36: mechanisms[2].air[1].start' 'phase 2 begins at 500 s, before phase 1 ends (600 s)'
bad humid-inlet 's/{start: 0,   end: 600, temperature: 333, humidity: 0.00505/{start: 0,   end: 600, temperature: 333, humidity: 0.2/' \
  '35: mechanisms[2].air[0].humidity' 'saturation'
bad negative-air 's/humidity: 0.00505, air_flow: 0.067}   # drying/humidity: 0.00505, air_flow: -0.067}   # drying/' \
  '36: mechanisms[2].air[1].air_flow' '-0.067'
bad hot-inlet 's/{start: 0,   end: 600, temperature: 333/{start: 0,   end: 600, temperature: 733/' \
  '35: mechanisms[2].air[0].temperature' '733'
bad negative-loss 's/heat_loss: 200 /heat_loss: -200 /' '32: mechanisms[2].heat_loss' '-200'
bad porosity-above-one 's/^  - type: liquid_addition/  - {type: consolidation, rate: 0.01, min_porosity: 1.2, gas_axis: liquid}\n  - type: liquid_addition/' \
  '23: mechanisms[1].min_porosity' '1.2'
bad five-metre-granules '/^  number: 4.19e8/,/^  at: /d; s/^  type: point/  {type: lognormal, mass: 2, solid_density: 2700, d50: 5, gsd: 1.5}/' \
  '17: initial.d50' 'expected a number between 1e-09 and 0.1'
echo "cli_bad_recipes: all checks passed"
