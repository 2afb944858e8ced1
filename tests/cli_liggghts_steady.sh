# The LIGGGHTS engine with what its deck expresses between runs: a wall's rotation.start (its
# fix move/mesh defined after the run up to then) and statistics.start: steady (further below).
# Skips (exit 0) only when the liggghts binary is absent (liggghts-lib.sh).
# Usage: bash cli_liggghts_steady.sh GRANSIM_BINARY SOURCE_DIR
source "$(dirname "$0")/liggghts-lib.sh" cli_liggghts_steady "$@"

blade_stl
# blade_yaml ENGINE ROTATION_START STATISTICS DURATION OUTPUT: about 100 spheres settle on the
# floor of the box; the blade turns about the x axis through z = 10 mm at 600 rpm: pointing up
# at rest it is clear of the bed, and it sweeps down to z = 1.5 mm half a turn (0.05 s) after
# it starts
blade_yaml() {
  cat <<YAML
dem:
  time_step: 5.0e-6
  duration: $4
  gravity: [0, 0, -9.81]
  box: {lo: [-0.011, -0.011, -0.001], hi: [0.011, 0.011, 0.031]}
  damping: liggghts
  mesh_contacts: liggghts
  seed: 3
  engine: $1
materials:
  - {name: granule, E: 8.0e6, nu: 0.2, e: 0.4, mu_s: 0.5, mu_r: 0.2, density: 500}
classes:
  - {name: small, radius: 1.0e-3, material: granule}
  - {name: large, radius: 1.5e-3, material: granule}
walls:
  - {name: box, mesh: box.stl, scale: 1.0e-3, material: granule}
  - {name: blade, mesh: blade.stl, scale: 1.0e-3, material: granule,
     rotation: {origin: [0, 0, 0.010], axis: [1, 0, 0], rpm: 600$2}}
fill:
  - region: {box: {lo: [-0.009, -0.009, 0.001], hi: [0.009, 0.009, 0.009]}}
    count: 97
statistics: $3
output: {$5}
YAML
}

# rotation.start 0.05 s: the deck defines the blade's move/mesh after the run to 0.05 s; the blade
# is where it was at rest until then and has turned by omega (t - 0.05 s) after (its STL frames:
# the tip's height within 1e-6 m); the blade's impacts and torque are exactly 0 up to 0.075 s
# (a quarter turn: still clear of the bed) and not 0 after
blade_yaml liggghts ", start: 0.05" "{start: 0, sample_every: 0.0025}" 0.12 "every: 0.0025, vtk_every: 0.01" > "$W/rot.yaml"
"$BIN" check "$W/rot.yaml" > /dev/null || fail "check refuses rotation.start for LIGGGHTS"
"$BIN" dem "$W/rot.yaml" --out "$W/rot" --ranks 1 --quiet 2> "$W/rot.log" || { cat "$W/rot.log"; fail "rotation.start run"; }
grep -A1 "^run 10000$" "$W/rot/liggghts/in.gransim" | grep -q "^# blade starts to turn" || fail "deck: no run to the rotation start"
grep -q "^fix rot1 all move/mesh mesh wall1 rotate origin 0 0 0.01 axis 1 0 0 period 0.1$" "$W/rot/liggghts/in.gransim" ||
  fail "deck: no move/mesh after the run to the rotation start"
python3 - "$W/rot" <<'PY'
import csv, math, sys
d = sys.argv[1]
for step in (0, 8000, 10000, 14000, 18000, 20000):
    t = step * 5e-6
    th = 2 * math.pi / 0.1 * max(0.0, t - 0.05)
    z = [float(l.split()[3]) for l in open("%s/vtk/walls_%d.stl" % (d, step)) if l.split()[:1] == ["vertex"]
         and abs(abs(float(l.split()[1])) - 0.008) < 1e-9]
    want = 0.010 + 0.0085 * math.cos(th)
    print("cli_liggghts_steady: t = %.3f s: blade tip at z = %.7f m, turned by omega (t - 0.05 s): %.7f m" % (t, max(z, key=lambda v: abs(v - 0.010)), want))
    assert abs(max(z, key=lambda v: abs(v - 0.010)) - want) < 1e-6, (step, z, want)
ts = list(csv.DictReader(open(d + "/timeseries.csv")))
before = [r for r in ts if float(r["time"]) <= 0.075]
after = [r for r in ts if float(r["time"]) > 0.075]
assert len(before) == 31 and after, len(before)
assert all(float(r["torque_axis_blade"]) == 0 and float(r["impacts_per_s_blade"]) == 0 for r in before[1:]), before
nz = sum(float(r["torque_axis_blade"]) != 0 for r in after), sum(float(r["impacts_per_s_blade"]) > 0 for r in after)
print("cli_liggghts_steady: blade: torque and impacts 0 in the %d rows to 0.075 s; of the %d after, %d with a torque, %d with impacts" % (len(before), len(after), *nz))
assert nz[0] >= len(after) // 2 and nz[1] >= 2, nz
PY

# statistics.start: steady on the same case for 0.4 s (a sample every 0.01 s, the detector over 6
# samples within 30 %): gransim runs the deck in chunks (in.setup, then the runs on LIGGGHTS'
# standard input) and reports the steady state; the detector, recomputed here from the time
# series (one row per sample: the same contact lists and hold-up), fires at the reported time
# and not before; the steady flag is 1 from then on; the tables cover the window from then to the
# end only; --reduce of the folder (the detector on the finished run's dumps) writes the same tables
blade_yaml liggghts ", start: 0.05" "{start: steady, sample_every: 0.01, steady: {window: 6, tolerance: 0.3}}" 0.4 "every: 0.01" \
  > "$W/st.yaml"
"$BIN" check "$W/st.yaml" > /dev/null || fail "check refuses statistics.start: steady for LIGGGHTS"
"$BIN" dem "$W/st.yaml" --out "$W/st" --ranks 1 2> "$W/st.log" || { cat "$W/st.log"; fail "steady run"; }
tl=$(sed -n 's/^gransim dem (liggghts): steady state at t = \([0-9.e+-]*\) s$/\1/p' "$W/st.log")
[ -n "$tl" ] || { cat "$W/st.log"; fail "no steady state reported"; }
grep -q "reading in.setup and then the runs in chunks" "$W/st.log" || fail "no chunked run"
grep -q "^gransim: chunk done 80000$" "$W/st/liggghts/screen.liggghts" || fail "the chunks did not reach the end"
! grep -q "^run " "$W/st/liggghts/in.setup" || fail "in.setup holds runs"
python3 - "$W/st" "$tl" <<'PY'
import csv, json, sys
d, tl = sys.argv[1], float(sys.argv[2])
ts = list(csv.DictReader(open(d + "/timeseries.csv")))
rows = [r for r in ts if float(r["time"]) > 0.05 + 1e-9]  # the samples after the blade starts
m = [float(r["holdup_mass"]) for r in rows]
c = [float(r["collisions_per_s"]) for r in rows]
def steady(a, b):
    for s in (a, b):
        mean = sum(s) / len(s)
        if not mean > 0 or any(abs(x - mean) > 0.3 * mean for x in s): return False
    return True
fired = next((float(rows[k]["time"]) for k in range(5, len(rows)) if steady(m[k - 5:k + 1], c[k - 5:k + 1])), None)
print("cli_liggghts_steady: LIGGGHTS steady at t = %g s (reported), %s s (recomputed from the time series)" % (tl, fired))
assert fired is not None and abs(fired - tl) < 1e-9, (fired, tl)
flags = [(float(r["time"]), r["steady"]) for r in ts]
assert all(f == ("1" if t >= tl - 1e-9 else "0") for t, f in flags), flags
desc = json.load(open(d + "/collisions.json"))["description"]
want = "from t = %g to 0.4 s (%g s, %d snapshots from t = %g to 0.4 s)" % (tl, 0.4 - tl, round((0.4 - tl) / 0.01) + 1, tl)
assert want in desc, (want, desc)
for r in csv.DictReader(open(d + "/collisions.csv")):
    assert abs(float(r["window_s"]) - (0.4 - tl)) < 1e-9 and float(r["events"]) > 0, r
PY
mkdir "$W/st_tables"
cp "$W/st"/*.csv "$W/st_tables/"
"$BIN" dem "$W/st.yaml" --out "$W/st" --reduce --quiet 2> "$W/re.log" || { cat "$W/re.log"; fail "--reduce of the steady run"; }
for f in "$W/st_tables"/*.csv; do
  [ "$(basename "$f")" = timeseries.csv ] && continue
  cmp -s "$f" "$W/st/$(basename "$f")" || fail "--reduce wrote another $(basename "$f")"
done
# the embedded engine on the same case: its detector's firing time, for comparison (the engines'
# trajectories part after a few collisions, so the times agree only as far as the steady state does)
blade_yaml embedded ", start: 0.05" "{start: steady, sample_every: 0.01, steady: {window: 6, tolerance: 0.3}}" 0.4 "every: 0.01" \
  > "$W/ste.yaml"
"$BIN" dem "$W/ste.yaml" --out "$W/ste" --threads 1 2> "$W/ste.log" || { cat "$W/ste.log"; fail "embedded steady run"; }
te=$(sed -n 's/^gransim dem: steady state at t = \([0-9.e+-]*\) s$/\1/p' "$W/ste.log")
[ -n "$te" ] || { cat "$W/ste.log"; fail "embedded: no steady state"; }
echo "cli_liggghts_steady: steady state at t = $te s (embedded) and $tl s (LIGGGHTS)"
awk -v a="$te" -v b="$tl" 'BEGIN { exit !(a >= 0.1 && b >= 0.1) }' || fail "a steady state before the window of samples after the blade started"

# statistics.steady.quantities on LIGGGHTS: kinetic energy (translational + rotational of every
# particle; it swings by ~70 % in this 97-sphere bed, so within 80 %) and collision rate; recomputed here from the snapshots themselves (v, omega, radius,
# density 500) and the time series' collision rates, the detector fires at the reported time
blade_yaml liggghts ", start: 0.05" "{start: steady, sample_every: 0.01, steady: {window: 6, tolerance: 0.8, quantities: [kinetic_energy, collision_rate]}}" 0.4 "every: 0.01" \
  > "$W/stk.yaml"
"$BIN" dem "$W/stk.yaml" --out "$W/stk" --ranks 1 2> "$W/stk.log" || { cat "$W/stk.log"; fail "steady run on kinetic energy"; }
tk=$(sed -n 's/^gransim dem (liggghts): steady state at t = \([0-9.e+-]*\) s$/\1/p' "$W/stk.log")
[ -n "$tk" ] || { cat "$W/stk.log"; fail "no steady state reported (kinetic energy)"; }
python3 - "$W/stk" "$tk" <<'PY'
import csv, glob, math, re, sys
d, tk = sys.argv[1], float(sys.argv[2])
dt = 5.0e-6
def ke_of(path):
    lines = open(path).read().split("\n")
    i = next(k for k, l in enumerate(lines) if l.startswith("ITEM: ATOMS"))
    cols = lines[i].split()[2:]
    e = 0.0
    for l in lines[i + 1:]:
        if not l.strip(): continue
        v = dict(zip(cols, map(float, l.split())))
        m = 500 * 4 / 3 * math.pi * v["radius"] ** 3
        e += 0.5 * m * (v["vx"] ** 2 + v["vy"] ** 2 + v["vz"] ** 2) + 0.5 * 0.4 * m * v["radius"] ** 2 * (v["omegax"] ** 2 + v["omegay"] ** 2 + v["omegaz"] ** 2)
    return e
ke = {round(int(re.findall(r"(\d+)\.atom$", p)[0]) * dt, 9): ke_of(p) for p in glob.glob(d + "/liggghts/post/collision*.atom")}
rows = [r for r in csv.DictReader(open(d + "/timeseries.csv")) if float(r["time"]) > 0.05 + 1e-9]
t = [float(r["time"]) for r in rows]
k = [ke[round(x, 9)] for x in t]
c = [float(r["collisions_per_s"]) for r in rows]
def steady(*series):
    for s in series:
        mean = sum(s) / len(s)
        if not mean > 0 or any(abs(x - mean) > 0.8 * mean for x in s): return False
    return True
fired = next((t[j] for j in range(5, len(t)) if steady(k[j - 5:j + 1], c[j - 5:j + 1])), None)
print("cli_liggghts_steady: on kinetic energy and collision rate, LIGGGHTS steady at t = %g s (reported), %s s (recomputed from the snapshots)" % (tk, fired))
assert fired is not None and abs(fired - tk) < 1e-9, (fired, tk)
PY
[ $? -eq 0 ] || fail "the kinetic-energy detector's time"

# a run that does not become steady (tolerance 0.1 %) stops with the detector's figures, no tables
blade_yaml liggghts ", start: 0.05" "{start: steady, sample_every: 0.01, steady: {window: 6, tolerance: 0.001}}" 0.15 "every: 0.01" \
  > "$W/ns.yaml"
if "$BIN" dem "$W/ns.yaml" --out "$W/ns" --ranks 1 --quiet 2> "$W/ns.log"; then fail "a run that never became steady succeeded"; fi
grep -q "ns.yaml: statistics.start is 'steady' but the steady state was not reached by t = 0.15 s (holdup_mass, collision_rate within 0.001 of their means over 6 samples; over the last 6 samples they are within [0-9.e+-]*, [0-9.e+-]* of their means" "$W/ns.log" ||
  { cat "$W/ns.log"; fail "not-steady message"; }
[ ! -e "$W/ns/collisions.csv" ] || fail "tables of a run that never became steady"

# with an outlet the chunks write the outlets' 200-step runs out in full (a `jump SELF` loop cannot
# be read from standard input): 70 particles fall through it, the hold-up drains, so the detector
# never fires, but every chunk runs to the end
outlet_yaml liggghts 0.03 "{start: steady, sample_every: 0.001, steady: {window: 4, tolerance: 0.5}}" "{every: 0.001}" > "$W/out.yaml"
if "$BIN" dem "$W/out.yaml" --out "$W/out" --ranks 1 --quiet 2> "$W/out.log"; then fail "the draining bed became steady"; fi
grep -q "out.yaml: statistics.start is 'steady' but the steady state was not reached by t = 0.03 s" "$W/out.log" ||
  { cat "$W/out.log"; fail "outlet run message"; }
[ "$(grep -c '^delete_atoms region outlet0 compress no$' "$W/out/liggghts/screen.liggghts")" = 75 ] || fail "not 75 outlet runs"
grep -q "^gransim: chunk done 15000$" "$W/out/liggghts/screen.liggghts" || fail "the outlet run's chunks did not reach the end"

# LIGGGHTS killed part-way (a launcher that stops it after 2 s): the error, and no tables
printf '#!/bin/sh\nexec timeout -s KILL 2 "$@"\n' > "$W/killer"
chmod +x "$W/killer"
if "$BIN" dem "$W/st.yaml" --out "$W/killed" --ranks 1 --launcher "$W/killer" --quiet 2> "$W/k.log"; then
  fail "a killed run succeeded"; fi
grep -q "LIGGGHTS failed (in.setup in " "$W/k.log" || { cat "$W/k.log"; fail "killed run message"; }
[ ! -e "$W/killed/collisions.csv" ] && [ ! -e "$W/killed/timeseries.csv" ] || fail "tables of a killed run"

# `gransim couple` (one way) with the DEM stage on LIGGGHTS: the blade case with two classes from
# the PBM grid; the stage stops 0.05 s (coupling.steady.collect) after the detector fired, at a
# sample, the tables covering just that window; `gransim dem` of the stage's case as run (its
# duration cut there) writes the same kernel and impact tables
mkdir "$W/cp"
cp "$W/box.stl" "$W/blade.stl" "$W/cp/"
cat > "$W/cp/tiny.yaml" <<'YAML'
title: tiny coupled case on LIGGGHTS
grid:
  axes:
    - {name: solid, type: geometric, min: 1.0e-10, ratio: 2, cells: 15, zero_first: true}
initial: {type: exponential, number: 1000, mean: 8.0e-9}
output: {end: 10, count: 6}
mechanisms:
  - type: aggregation
    kernel: {type: table, beta0: 1.0e-4}
  - type: breakage
    selection: {type: dem_impact, scale: 1.0e-3, u_break: 0.5}
    daughters: {type: halves}
dem:
  dem:
    time_step: 5.0e-6
    box: {lo: [-0.011, -0.011, -0.001], hi: [0.011, 0.011, 0.031]}
    gravity: [0, 0, -9.81]
    seed: 3
    engine: liggghts
  materials:
    - {name: granule, E: 8.0e6, nu: 0.2, e: 0.4, mu_s: 0.5, mu_r: 0.2, density: 500}
  walls:
    - {name: box, mesh: box.stl, scale: 1.0e-3, material: granule}
    - {name: blade, mesh: blade.stl, scale: 1.0e-3, material: granule,
       rotation: {origin: [0, 0, 0.010], axis: [1, 0, 0], rpm: 600, start: 0.05}}
  fill:
    - region: {box: {lo: [-0.009, -0.009, 0.001], hi: [0.009, 0.009, 0.009]}}
      count: 60
      fractions: [0.5, 0.5]
coupling:
  mode: one_way
  classes: {min_diameter: 2.0e-3, max_diameter: 3.0e-3, count: 2, material: granule}
  steady: {window: 4, tolerance: 0.5, sample_every: 0.01, max_time: 0.3, collect: 0.05}
YAML
"$BIN" check "$W/cp/tiny.yaml" > /dev/null || fail "check refuses a coupled case with engine liggghts"
"$BIN" couple "$W/cp/tiny.yaml" --out "$W/cp/out" 2> "$W/cp.log" || { cat "$W/cp.log"; fail "coupled run on LIGGGHTS"; }
tc=$(sed -n 's/^gransim couple: DEM steady at t = \([0-9.e+-]*\) s; tables in .*/\1/p' "$W/cp.log")
[ -n "$tc" ] || { cat "$W/cp.log"; fail "the coupled DEM stage reported no steady state"; }
grep -q "^gransim couple: PBM to t = 10 " "$W/cp.log" || { cat "$W/cp.log"; fail "no PBM stage"; }
python3 - "$W/cp/out/dem" "$tc" <<'PY'
import csv, json, sys
d, tc = sys.argv[1], float(sys.argv[2])
stop = tc + 0.05
desc = json.load(open(d + "/collisions.json"))["description"]
want = "from t = %g to %g s" % (tc, stop)
assert want in desc, (want, desc)
ts = list(csv.DictReader(open(d + "/timeseries.csv")))
assert abs(float(ts[-1]["time"]) - stop) < 1e-9, ts[-1]["time"]
assert "duration: %r" % stop in open(d + "/case.yaml").read() or "duration: %.17g" % stop in open(d + "/case.yaml").read(), "case duration"
print("cli_liggghts_steady: coupled DEM stage on LIGGGHTS: steady at t = %g s, stopped at %g s" % (tc, stop))
PY
"$BIN" dem "$W/cp/out/dem/case.yaml" --out "$W/cp/manual" --quiet 2> "$W/cpm.log" || { cat "$W/cpm.log"; fail "manual DEM run"; }
for f in collision_kernel.csv impact_table.csv; do
  cmp -s "$W/cp/out/dem/$f" "$W/cp/manual/$f" || fail "gransim dem of the stage's case wrote another $f"
done
