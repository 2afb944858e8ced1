# gransim compartments: zones and exchange rates from DEM particle frames.
#  - LIGGGHTS-style dumps of two separated clouds that swap particles on a schedule:
#    two zones found (the silhouette), every crossing counted (the schedule's exact rates), the fragment read by the exchange mechanism of a PBM case that runs;
#    a grid with another compartment count is refused naming grid.compartments;
#  - a real short DEM run of the bowl-and-impeller example (quick variant of
#    examples/bowl-zones-dem.yaml): its particle frames (.pvd/.vtp) give three zones whose
#    hold-ups add up to the particles, and examples/bowl-zones.yaml runs on that fragment;
#  - bad input: dumps without --time-step, a missing column, a file that is no frame
#    collection, too few frames, --clusters out of range: clear messages, status 1 or 2,
#    no fragment left behind.
source "$(dirname "$0")/cli-lib.sh" "$@"

run_rc 0 "$BIN" compartments --help
stdout_has "--clusters" "--time-step" "silhouette"

# 24 particles, 41 frames 1000 steps apart: particle i sits in cloud A (z = 0) or B
# (z = 0.1 m, moving at 0.5 m/s in x), switching every 8 frames, offset by i: the rates
# are the schedule's crossings over its particle-time in each cloud, to the 6 digits written.
mkdir -p "$WORK/dumps"
for f in $(seq 0 40); do
  awk -v f="$f" 'BEGIN {
    printf "ITEM: TIMESTEP\n%d\nITEM: NUMBER OF ATOMS\n24\nITEM: BOX BOUNDS pp pp pp\n-1 1\n-1 1\n-1 1\n", f * 1000
    printf "ITEM: ATOMS id type x y z vx vy vz radius\n"
    for (i = 0; i < 24; i++) {
      b = int((f + i) / 8) % 2
      dx = 0.001 * ((i * 7 + f * 3) % 11 - 5); dy = 0.001 * ((i * 5 + f) % 9 - 4)
      printf "%d 1 %.6f %.6f %.6f %.4f 0 0 0.001\n", i + 1, dx, dy, b * 0.1 + dx / 2, b * 0.5 + dy
    }
  }' >"$WORK/dumps/frame$f.atom"
done
run_rc 0 "$BIN" compartments "$WORK/dumps" --time-step 1e-4 --out "$WORK/two.yaml"
stdout_has "41 frames, 984 particle samples; 2 zones"
grep -q '^compartments: 2$' "$WORK/two.yaml" || fail "the fragment does not give 2 compartments: $(cat "$WORK/two.yaml")"
# crossings / exposure, counted from the schedule itself: K_AB = n_AB / T_A
want=$(awk 'BEGIN { for (i = 0; i < 24; i++) for (f = 0; f < 40; f++) {
                      b = int((f + i) / 8) % 2; c = int((f + 1 + i) / 8) % 2; T[b] += 0.1; if (b != c) n[b]++ }
                    printf "%.9g %.9g", n[0] / T[0], n[1] / T[1] }')
awk -v want="$want" '/^rates:/ { on = 1; next } on && /^  - / { gsub(/[][,]/, " "); row[++n] = $0 } n == 2 { exit }
     END { split(want, w, " "); split(row[1], a, " "); split(row[2], b, " ")
           if (a[2] != "0" || b[3] != "0") exit 1
           e1 = a[3] / w[1] - 1; e2 = b[2] / w[2] - 1
           if (e1 < -1e-5 || e1 > 1e-5 || e2 < -1e-5 || e2 > 1e-5) exit 1 }' "$WORK/two.yaml" ||
  fail "rates of the two clouds are not the schedule's $want 1/s: $(grep -A2 '^rates:' "$WORK/two.yaml")"
# the PBM reads it
cat >"$WORK/pbm.yaml" <<'YAML'
grid: {compartments: 2, axes: [{name: v, type: geometric, min: 1, ratio: 2, cells: 4}]}
initial: {type: cell, number: 10, index: [1], compartment: 1}
mechanisms: [{type: exchange, file: two.yaml}]
output: {end: 1}
YAML
run_rc 0 "$BIN" run "$WORK/pbm.yaml" --out "$WORK/pbm" --quiet
sed 's/compartments: 2/compartments: 3/' "$WORK/pbm.yaml" >"$WORK/pbm3.yaml"
run_rc 1 "$BIN" check "$WORK/pbm3.yaml"
stderr_has "two.yaml has 2 compartments, the grid 3" "grid.compartments"
# a fragment that is not there is named at the line that names it
sed 's/file: two.yaml/file: no-such.yaml/' "$WORK/pbm.yaml" >"$WORK/pbm-missing.yaml"
run_rc 1 "$BIN" check "$WORK/pbm-missing.yaml"
stderr_has "pbm-missing.yaml:3: mechanisms[0].file: fragment: cannot open" "no-such.yaml"

# a real short DEM run: the bowl-and-impeller example, 150 particles for 0.3 s
sed -e 's/duration: 0.8/duration: 0.3/; s/count: 400/count: 150/' "$SRC/examples/bowl-zones-dem.yaml" >"$WORK/bowl.yaml"
grep -q 'count: 150' "$WORK/bowl.yaml" || fail "the quick variant's edits did not apply: examples/bowl-zones-dem.yaml changed"
run_rc 0 "$BIN" dem "$WORK/bowl.yaml" --out "$WORK/dem" --quiet
mkdir -p "$WORK/data"
run_rc 0 "$BIN" compartments "$WORK/dem/vtk/particles.pvd" --clusters 3 --start 0.099 --out "$WORK/data/bowl-zones.yaml"
stdout_has "101 frames, 15150 particle samples; 3 zones"
awk '/^holdup:/ { gsub(/[][,]/, " "); s = $2 + $3 + $4; exit !(s > 149.999 && s < 150.001) }' "$WORK/data/bowl-zones.yaml" ||
  fail "hold-ups do not add up to 150 particles: $(grep holdup "$WORK/data/bowl-zones.yaml")"
sed 's/output: {end: 120, count: 12}/output: {end: 20, count: 4}/' "$SRC/examples/bowl-zones.yaml" >"$WORK/bowl-zones.yaml"
run_rc 0 "$BIN" run "$WORK/bowl-zones.yaml" --out "$WORK/zones" --quiet
stderr_has "done to t = 20"
[ "$(grep -c '^20,' "$WORK/zones/summary.csv")" = 3 ] || fail "no row per zone at t = 20"

# bad input
run_rc 2 "$BIN" compartments "$WORK/dumps" --out "$WORK/bad.yaml"
stderr_has "give --time-step"
sed 's/ vz radius$/ vw radius/' "$WORK/dumps/frame0.atom" >"$WORK/novz.atom"
run_rc 1 "$BIN" compartments "$WORK/novz.atom" "$WORK/dumps/frame1.atom" --time-step 1e-4 --out "$WORK/bad.yaml"
stderr_has "novz.atom: no column 'vz'"
run_rc 1 "$BIN" compartments "$WORK/dumps/frame1.atom" --time-step 1e-4 --out "$WORK/bad.yaml"
stderr_has "1 particle frame(s): crossings need at least two"
run_rc 1 "$BIN" compartments "$WORK/pbm.yaml.pvd" --out "$WORK/bad.yaml"
stderr_has "pbm.yaml.pvd: cannot open"
cp "$WORK/pbm.yaml" "$WORK/notpvd.pvd"
run_rc 1 "$BIN" compartments "$WORK/notpvd.pvd" --out "$WORK/bad.yaml"
stderr_has "not a VTK collection"
head -c 1500 "$WORK/dem/vtk/particles_000003.vtp" >"$WORK/dem/vtk/cut.vtp"
sed 's/particles_000003.vtp/cut.vtp/' "$WORK/dem/vtk/particles.pvd" >"$WORK/dem/vtk/cut.pvd"
run_rc 1 "$BIN" compartments "$WORK/dem/vtk/cut.pvd" --out "$WORK/bad.yaml"
stderr_has "cut.vtp: "
run_rc 2 "$BIN" compartments "$WORK/dumps" --time-step 1e-4 --clusters 16 --out "$WORK/bad.yaml"
stderr_has "--clusters and --max-clusters"
[ ! -e "$WORK/bad.yaml" ] && [ ! -e "$WORK/bad.yaml.tmp" ] || fail "a refused run left a fragment behind"
echo "cli_compartments: ok"
