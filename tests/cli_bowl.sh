# The bowl-and-impeller example of De et al. (2025) (examples/bowl-one-way.yaml), in a quick
# variant made from it here (fewer DEM particles, a shorter DEM and process): `gransim couple`
# generates the bowl and impeller into dem/geometry/, runs the DEM until steady and the 3-D PBM
# (api, excipient, liquid) with the absorption law.  Checked: the meshes written and closed
# (`gransim geometry` on the same case); the liquid the PBM holds at the end is exactly
# LS x rho_s/rho_l x solid (the absorption law sprays what the ratio says, to round-off); the
# API:excipient ratio stays 0.25 (aggregation and liquid addition move no solid; the paper's
# Figs. 20-21); the number of granules falls (aggregation of wet granules).  With LIGGGHTS
# installed, the generated meshes also run there (engine: liggghts): LIGGGHTS refuses no facet
# of them and keeps every particle.
source "$(dirname "$0")/cli-lib.sh" "$@"

sed -e 's/      count: 280/      count: 60/' \
    -e 's/steady: {window: 6, tolerance: 0.15, sample_every: 2.0e-3, max_time: 0.045}/steady: {window: 3, tolerance: 0.5, sample_every: 1.0e-3, max_time: 0.015}/' \
    -e 's/    end: 250/    end: 50/' -e 's/output: {end: 500, count: 51}/output: {end: 80, count: 9}/' \
    "$SRC/examples/bowl-one-way.yaml" >"$WORK/bowl.yaml"
grep -q 'count: 60' "$WORK/bowl.yaml" && grep -q 'max_time: 0.015' "$WORK/bowl.yaml" && grep -q 'end: 50' "$WORK/bowl.yaml" ||
  fail "the quick variant's edits did not apply: examples/bowl-one-way.yaml changed"

run_rc 0 "$BIN" geometry "$WORK/bowl.yaml" --out "$WORK/geo"
stdout_has "bowl.stl: "
stdout_has "impeller.stl: "
[ "$(grep -c ', closed, ' "$WORK/stdout")" = 2 ] || fail "expected two closed meshes"

run_rc 0 "$BIN" couple "$WORK/bowl.yaml" --out "$WORK/out" --quiet
for m in bowl impeller; do
  head -1 "$WORK/out/dem/geometry/$m.stl" | grep -q "^solid $m" || fail "dem/geometry/$m.stl missing"
done
awk -F, '
  NR == 1 { for (i = 1; i <= NF; i++) col[$i] = i; next }
  { api = $col["total_api [m^3]"]; exc = $col["total_excipient [m^3]"]; liq = $col["total_liquid [m^3]"]
    n = $col["M0 [1]"]
    r = api / exc; if (r < 0.25 * (1 - 1e-12) || r > 0.25 * (1 + 1e-12)) { print "API:excipient " r " at t = " $1; bad = 1 }
    if (NR == 2) n0 = n }
  END {
    want = 0.15 * 1668 / 1000 * (api + exc)
    if (liq < want * (1 - 1e-9) || liq > want * (1 + 1e-9)) { print "liquid " liq " want " want; bad = 1 }
    if (!(n < 0.999 * n0)) { print "number " n0 " -> " n ": no aggregation"; bad = 1 }
    printf "liquid held %.12g of %.12g sprayed; granules %g -> %g\n", liq, want, n0, n
    exit bad }' "$WORK/out/summary.csv" || fail "the coupled run's summary.csv (above)"
if command -v "${GRANSIM_LIGGGHTS:-liggghts}" >/dev/null && command -v mpirun >/dev/null; then
  sed -e 's/duration: 0.25,/duration: 0.05, engine: liggghts,/' "$SRC/fuzz/corpus/dem_case/bowl-impeller.yaml" >"$WORK/lig.yaml"
  grep -q 'engine: liggghts' "$WORK/lig.yaml" || fail "fuzz/corpus/dem_case/bowl-impeller.yaml changed"
  run_rc 0 "$BIN" dem "$WORK/lig.yaml" --out "$WORK/lig" --ranks 1 --quiet
  grep -q "mesh/surface file wall0_bowl.stl" "$WORK/lig/liggghts/in.gransim" || fail "the deck does not read wall0_bowl.stl"
  cmp -s "$WORK/lig/liggghts/wall0_bowl.stl" "$WORK/lig/geometry/bowl.stl" || fail "the deck's wall0_bowl.stl is not geometry/bowl.stl"
  for f in "$WORK"/lig/liggghts/ex_wall*.txt; do [ ! -s "$f" ] || fail "LIGGGHTS refused facets: $f"; done
  [ "$(tail -1 "$WORK/lig/timeseries.csv" | cut -d, -f2)" = 20 ] || fail "LIGGGHTS lost particles of the bowl"
fi
echo "cli_bowl: ok"

# The two-way example (examples/bowl-two-way.yaml) in the same kind of quick variant (150 DEM
# particles, since a two-way DEM fills its classes by the population's numbers, nearly all
# primaries at first; cycles every 30 s; the impeller at rest for the first 10 ms): three cycles, each
# DEM found steady only after the impeller started; the conservation identities as above; the
# DEM's restitution the volume-weighted 0.2 x 0.2 + 0.275 x 0.8 = 0.26 of the API:excipient mix
# (constant: aggregation and liquid move no solid).
sed -e 's/      count: 280/      count: 150/' \
    -e 's/steady: {window: 4, tolerance: 0.35, sample_every: 3.0e-3, max_time: 0.06}/steady: {window: 3, tolerance: 0.5, sample_every: 1.0e-3, max_time: 0.03}/' \
    -e 's/    end: 250/    end: 50/' -e 's/output: {end: 500, count: 51}/output: {end: 80, count: 9}/' \
    -e 's/trigger: {mean_volume_change: 0.5}/trigger: {mean_volume_change: 0.5, interval: 30}/' \
    -e 's/rpm: 240, start: 0.02}/rpm: 240, start: 0.01}/' \
    "$SRC/examples/bowl-two-way.yaml" >"$WORK/bowl2.yaml"
[ "$(grep -c 'count: 150\|max_time: 0.03\|    end: 50\|interval: 30\|start: 0.01}' "$WORK/bowl2.yaml")" = 5 ] ||
  fail "the two-way quick variant's edits did not apply: examples/bowl-two-way.yaml changed"
run_rc 0 "$BIN" couple "$WORK/bowl2.yaml" --out "$WORK/out2" --quiet
[ "$(awk -F, 'NR > 1' "$WORK/out2/cycles.csv" | wc -l)" = 3 ] || fail "the two-way quick variant: not 3 cycles"
# each cycle's bed settled with the impeller at rest until 0.01 s: the detector fired after it
awk -F, 'NR > 1 && !($12 > 0.01) { bad = 1 } END { exit bad }' "$WORK/out2/cycles.csv" ||
  fail "a two-way DEM stage was found steady before the impeller started: $(cat "$WORK/out2/cycles.csv")"
grep -q 'rpm: "240", start: "0.01"' "$WORK/out2/cycle-1/case.yaml" || fail "the cycle's DEM case lacks the impeller's start"
awk -F, 'NR > 1 && ($13 < 0.26 * (1 - 1e-9) || $13 > 0.26 * (1 + 1e-9)) { bad = 1 } END { exit bad }' \
  "$WORK/out2/cycles.csv" || fail "the two-way DEM's restitution is not 0.26: $(cat "$WORK/out2/cycles.csv")"
awk -F, '
  NR == 1 { for (i = 1; i <= NF; i++) col[$i] = i; next }
  { api = $col["total_api [m^3]"]; exc = $col["total_excipient [m^3]"]; liq = $col["total_liquid [m^3]"]
    n = $col["M0 [1]"]
    r = api / exc; if (r < 0.25 * (1 - 1e-12) || r > 0.25 * (1 + 1e-12)) { print "API:excipient " r " at t = " $1; bad = 1 }
    if (NR == 2) n0 = n }
  END {
    want = 0.15 * 1668 / 1000 * (api + exc)
    if (liq < want * (1 - 1e-9) || liq > want * (1 + 1e-9)) { print "liquid " liq " want " want; bad = 1 }
    if (!(n < 0.999 * n0)) { print "number " n0 " -> " n ": no aggregation"; bad = 1 }
    exit bad }' "$WORK/out2/summary.csv" || fail "the two-way run's summary.csv (above)"
