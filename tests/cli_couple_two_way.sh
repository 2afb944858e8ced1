# `gransim couple` with mode two_way on a tiny case: a 15-cell PBM with the
# DEM's aggregation kernel, 250 particles in a small rotating drum, three
# cycles of 4 s (trigger.interval) over 10 s.  Checked: the cycles (DEM
# stages from the population: class fractions of its numbers; cycles.csv; one
# result.h5 over the whole process time); a run is repeatable bit for bit;
# the mean-volume trigger fires where the summary says the mean volume has
# changed by the threshold; a run SIGKILLed in a DEM stage and one killed in a
# PBM stretch resume to the uninterrupted run's results, bit for bit.
source "$(dirname "$0")/cli-lib.sh" "$@"
command -v h5diff >/dev/null || fail "h5diff (hdf5-tools) is needed"

cat > "$WORK/tw.yaml" <<'YAML'
title: tiny two-way case
grid:
  axes:
    - {name: solid, type: geometric, min: 1.0e-10, ratio: 2, cells: 15, zero_first: true}
initial: {type: exponential, number: 1000, mean: 8.0e-9}
output: {end: 10, count: 1001, checkpoint: 0}
mechanisms:
  - type: aggregation
    kernel: {type: table, beta0: 1.0e-4}
dem:
  dem:
    time_step: 5.0e-6
    box: {lo: [-0.03, -0.03, -0.001], hi: [0.03, 0.03, 0.021]}
    gravity: [0, -9.81, 0]
    seed: 3
  materials:
    - {name: granule, E: 8.0e6, nu: 0.2, e: 0.4, mu_s: 0.5, mu_r: 0.2, density: 500}
  walls:
    - name: drum
      cylinder: {point: [0, 0, 0], axis: [0, 0, 1], radius: 0.015}
      material: granule
      rotation: {origin: [0, 0, 0], axis: [0, 0, 1], rpm: 120}
    - {name: front, plane: {point: [0, 0, 0], normal: [0, 0, 1]}, material: granule}
    - {name: back, plane: {point: [0, 0, 0.02], normal: [0, 0, -1]}, material: granule}
  fill:
    - region: {cylinder: {point: [0, 0, 0], axis: [0, 0, 1], radius: 0.013, from: 0.002, to: 0.018}}
      count: 250
coupling:
  mode: two_way
  trigger: {interval: 4}
  classes: {min_diameter: 2.0e-3, max_diameter: 4.0e-3, count: 3, material: granule}
  steady: {window: 3, tolerance: 0.5, sample_every: 0.005, max_time: 0.07}
YAML

run_rc 0 "$BIN" check "$WORK/tw.yaml"
stdout_has "valid. two_way: 3 DEM classes from the grid"

run_rc 0 "$BIN" couple "$WORK/tw.yaml" --out "$WORK/ref" --threads 2
stderr_has "cycle 1 ends at t = 4 s (interval"
stderr_has "3 cycles to t = 10 s"
for f in cycle-1/collision_kernel.csv cycle-2/collision_kernel.csv cycle-3/steady.csv cycles.csv cycles.json \
         result.h5 summary.csv; do
  [ -s "$WORK/ref/$f" ] || fail "missing $f"
done
[ ! -e "$WORK/ref/cycle-4" ] && [ ! -e "$WORK/ref/cycle-4.partial" ] || fail "a fourth cycle after the end"
[ ! -e "$WORK/ref/.result.journal" ] || fail "the journal left after the last stretch"
head -n 1 "$WORK/ref/cycles.csv" | grep -q '^cycle,t_start \[s\],t_end \[s\],trigger,' || fail "cycles.csv header"
awk -F, 'NR > 1 { printf "%s %s %s %s %s;", $1, $2, $3, $4, $6 }' "$WORK/ref/cycles.csv" > "$WORK/rows"
[ "$(cat "$WORK/rows")" = "1 0 4 start interval;2 4 8 interval interval;3 8 10 interval end;" ] ||
  fail "cycles.csv rows: $(cat "$WORK/rows")"
# one result over the whole process time: every output time once
[ "$(awk -F, 'NR > 1' "$WORK/ref/summary.csv" | wc -l)" = 1001 ] || fail "summary.csv: not 1001 output times"

# result.h5's /coupling/cycles holds the cycle table and each cycle's kernel table.
/usr/bin/python3 - "$WORK/ref" <<'PY' || fail "result.h5's /coupling/cycles differs from cycles.csv and the cycles' tables"
import sys, csv, h5py, numpy as np
d = sys.argv[1]
g = h5py.File(d + "/result.h5", "r")["coupling"]
rows = list(csv.DictReader(open(d + "/cycles.csv")))
for col, key in [("t_start", "t_start [s]"), ("t_end", "t_end [s]"), ("particles", "particles [1]"),
                 ("dem_steps", "dem_steps [1]"), ("t_steady", "t_steady [s]"), ("volume_change", "volume_change [1]")]:
    assert np.allclose(g["cycles"][col][:], [float(r[key]) for r in rows], rtol=1e-8), col
assert list(g["cycles"]["trigger"][:]) == [0, 2, 2] and list(g["cycles"]["ended_by"][:]) == [2, 2, 3]
assert g["cycles"]["t_end"].attrs["units"] == b"s"
for i in range(3):
    lines = open(d + "/cycle-%d/collision_kernel.csv" % (i + 1)).read().split("\n")
    C = np.array([[float(x) for x in l.split(",")] for l in lines[1:4]])
    assert np.array_equal(g["cycles"]["collision_frequency"][i], C), i
    assert np.allclose(g["class_edges"][:], [float(x) for x in lines[0].split(",")[1:]], rtol=1e-12)
PY

# Cycle 2's DEM sampled the population at t = 4: its fractions are the
# numbers per class of the summary's state (each class at least 2 %), and
# the DEM filled its classes so.
/usr/bin/python3 - "$WORK/ref" <<'PY' || fail "cycle 2's class fractions do not follow the population at t = 4"
import sys, re, h5py, numpy as np
d = sys.argv[1]
f = h5py.File(d + "/result.h5", "r")
t = f["time"][:]
i = int(np.argmin(abs(t - 4.0)))
N = f["number"][i].reshape(-1)
case = open(d + "/cycle-2/case.yaml").read()
radii = [tuple(map(float, m)) for m in re.findall(r"radius: \[([^,]+), ([^\]]+)\]", case)]
edges = [2 * radii[0][0]] + [2 * r[1] for r in radii]
fr = [float(x) for x in re.search(r"fractions: \[([^\]]+)\]", case).group(1).split(",")]
pivots = f["grid"]["solid"]["pivots"][:]
d_c = (6 * pivots / np.pi) ** (1 / 3)
cnt = np.zeros(3)
for k in range(15):
    if pivots[k] <= 0:
        continue
    j = 0
    while j + 1 < 3 and d_c[k] >= edges[j + 1]:
        j += 1
    cnt[j] += N[k]
want = np.maximum(cnt / cnt.sum(), 0.02)
want /= want.sum()
assert np.allclose(fr, want, rtol=1e-9, atol=0), (fr, want)
PY

# Repeatable: the same case again gives the same files bit for bit.
run_rc 0 "$BIN" couple "$WORK/tw.yaml" --out "$WORK/again" --threads 2
same() { # same DIR WHAT
  h5diff --exclude-path /coupling/cycles/dem_wall "$WORK/ref/result.h5" "$1/result.h5" >"$WORK/h5diff" 2>&1 ||
    { head -n 20 "$WORK/h5diff" >&2; fail "$1/result.h5 differs from the uninterrupted run's ($2)"; }
  cmp -s "$WORK/ref/summary.csv" "$1/summary.csv" || fail "$1/summary.csv differs ($2)"
  cut -d, -f1-10,12 "$WORK/ref/cycles.csv" > "$WORK/c1"
  cut -d, -f1-10,12 "$1/cycles.csv" > "$WORK/c2"
  cmp -s "$WORK/c1" "$WORK/c2" || fail "$1/cycles.csv differs ($2): $(diff "$WORK/c1" "$WORK/c2")"
}
same "$WORK/again" "a second run"

# SIGKILL in cycle 2's DEM stage (its case written, the stage not renamed), then --resume.
for try in 1 2 3 4 5; do
  rm -rf "$WORK/k1"
  "$BIN" couple "$WORK/tw.yaml" --out "$WORK/k1" --threads 2 2> "$WORK/k1.err" &
  pid=$!
  BG_PIDS+=("$pid")
  until [ -s "$WORK/k1/cycle-2.partial/case.yaml" ]; do
    kill -0 "$pid" 2>/dev/null || fail "the run ended before it could be killed: $(cat "$WORK/k1.err")"
    sleep 0.002
  done
  sleep "0.$((RANDOM % 6))"
  kill -9 "$pid" 2>/dev/null || true
  wait "$pid" 2>/dev/null || true
  [ -d "$WORK/k1/cycle-2.partial" ] && break
  [ "$try" = 5 ] && fail "five kills missed cycle 2's DEM stage"
done
run_rc 0 "$BIN" couple "$WORK/tw.yaml" --out "$WORK/k1" --threads 2 --resume
stderr_has "resume: from cycle 2 (t = 4 s), its DEM stage run again"
same "$WORK/k1" "killed in cycle 2's DEM stage"

# SIGKILL in cycle 2's PBM stretch (the time series past t = 4.5 s, cycle 3 not begun), then --resume.
for try in 1 2 3 4 5; do
  rm -rf "$WORK/k2"
  "$BIN" couple "$WORK/tw.yaml" --out "$WORK/k2" --threads 2 2> "$WORK/k2.err" &
  pid=$!
  BG_PIDS+=("$pid")
  until [ -d "$WORK/k2/cycle-2" ] && [ -f "$WORK/k2/.summary.csv.partial" ] &&
    [ "$(wc -l < "$WORK/k2/.summary.csv.partial")" -gt $((452 + RANDOM % 200)) ]; do
    kill -0 "$pid" 2>/dev/null || break
    sleep 0.002
  done
  kill -9 "$pid" 2>/dev/null || true
  wait "$pid" 2>/dev/null || true
  [ -d "$WORK/k2/cycle-2" ] && [ ! -e "$WORK/k2/cycle-3.partial" ] && [ ! -e "$WORK/k2/result.h5" ] && break
  [ "$try" = 5 ] && fail "five kills missed cycle 2's PBM stretch"
done
# A NaN or an empty kernel table of a cycle: an error naming the cycle and the entry; the cycles kept.
cp -r "$WORK/k2" "$WORK/k3"
sed -i '2s/^[^,]*,/nan,/' "$WORK/k3/cycle-2/collision_kernel.csv"
run_rc 1 "$BIN" couple "$WORK/tw.yaml" --out "$WORK/k3" --resume
stderr_has "cycle 2 (process time 4 s): $WORK/k3/cycle-2/collision_kernel.csv:2: 'nan' is not a number"
[ -d "$WORK/k3/cycle-1" ] && [ -d "$WORK/k3/cycle-2" ] && [ -e "$WORK/k3/.result.journal" ] || fail "cycles not kept"
head -n 1 "$WORK/k2/cycle-2/collision_kernel.csv" > "$WORK/k3/cycle-2/collision_kernel.csv"
run_rc 1 "$BIN" couple "$WORK/tw.yaml" --out "$WORK/k3" --resume
stderr_has "cycle 2 (process time 4 s): $WORK/k3/cycle-2/collision_kernel.csv: 0 rows, expected 3"
# Comment lines and blank lines in a cycle's table are read as the PBM's table kernel reads them.
rm -rf "$WORK/k3" && cp -r "$WORK/k2" "$WORK/k3"
for c in 1 2; do sed -i '1a # a note\n' "$WORK/k3/cycle-$c/collision_kernel.csv"; done
[ "$(grep -c '^# a note' "$WORK/k3/cycle-2/collision_kernel.csv")" = 1 ] || fail "no comment line added"
run_rc 0 "$BIN" couple "$WORK/tw.yaml" --out "$WORK/k3" --threads 2 --resume
same "$WORK/k3" "killed in cycle 2's PBM stretch, comment lines in the tables"
# A case whose classes changed since the cycles ran: the tables of other classes are refused on --resume.
rm -rf "$WORK/k3" && cp -r "$WORK/k2" "$WORK/k3"
sed -e 's/count: 3, material: granule/count: 2, material: granule/' "$WORK/tw.yaml" > "$WORK/four.yaml"
run_rc 1 "$BIN" couple "$WORK/four.yaml" --out "$WORK/k3" --resume
stderr_has "cycle 2 (process time 4 s): $WORK/k3/cycle-2/collision_kernel.csv: a table of 3 classes, but the grid and coupling.classes give 2"
[ -d "$WORK/k3/cycle-1" ] && [ -d "$WORK/k3/cycle-2" ] || fail "cycles not kept"
run_rc 0 "$BIN" couple "$WORK/tw.yaml" --out "$WORK/k2" --threads 2 --resume
stderr_has "resume: from cycle 2 (t = 4 s), its DEM stage complete, the PBM stretch resumed"
same "$WORK/k2" "killed in cycle 2's PBM stretch"

# A complete run resumed: nothing to do.
run_rc 0 "$BIN" couple "$WORK/tw.yaml" --out "$WORK/k2" --threads 2 --resume
stderr_has "the coupled run is complete"

# The mean-volume trigger: each stretch ends at the first output time where
# the mean granule volume has changed by 30 % since the cycle's start.
sed -e 's/trigger: {interval: 4}/trigger: {mean_volume_change: 0.3}/' -e 's/count: 1001, checkpoint: 0/count: 41/' \
  "$WORK/tw.yaml" > "$WORK/dv.yaml"
run_rc 0 "$BIN" couple "$WORK/dv.yaml" --out "$WORK/dv" --threads 2
/usr/bin/python3 - "$WORK/dv" <<'PY' || fail "the mean-volume trigger fired at the wrong output times"
import sys, csv
d = sys.argv[1]
rows = list(csv.DictReader(open(d + "/summary.csv")))
t = [float(r["time [s]"]) for r in rows]
m = [float(r["mean_solid [m^3]"]) for r in rows]
cyc = list(csv.DictReader(open(d + "/cycles.csv")))
assert len(cyc) >= 2, len(cyc)
for c in cyc:
    t0, t1 = float(c["t_start [s]"]), float(c["t_end [s]"])
    i0 = t.index(t0)
    ch = [abs(m[i] / m[i0] - 1) for i in range(i0 + 1, len(t))]
    first = next((i0 + 1 + k for k, x in enumerate(ch) if x >= 0.3), None)
    if c["ended_by"] == "mean_volume_change":
        assert first is not None and t[first] == t1, (c, first and t[first])
    else:
        assert c["ended_by"] == "end" and (first is None or t[first] >= t1), c
PY

# Two components: the DEM material's restitution is the volume-weighted mean of
# coupling.restitution over the population at each cycle's start.
cat > "$WORK/two.yaml" <<'YAML'
title: tiny two-component two-way case
grid:
  axes:
    - {name: api, type: geometric, min: 1.0e-9, ratio: 2, cells: 9}
    - {name: exc, type: geometric, min: 1.0e-9, ratio: 2, cells: 9}
initial:
  type: cells
  number: 1000
  indices: [[3, 1], [1, 3]]
  weights: [0.2, 0.8]
output: {end: 10, count: 11}
mechanisms:
  - type: aggregation
    kernel: {type: table, beta0: 1.0e-4}
dem:
  dem:
    time_step: 3.0e-6
    box: {lo: [-0.03, -0.03, -0.001], hi: [0.03, 0.03, 0.021]}
    gravity: [0, -9.81, 0]
    seed: 3
  materials:
    - {name: granule, E: 8.0e6, nu: 0.2, e: 0.4, mu_s: 0.5, mu_r: 0.2, density: 500}
  walls:
    - name: drum
      cylinder: {point: [0, 0, 0], axis: [0, 0, 1], radius: 0.015}
      material: granule
      rotation: {origin: [0, 0, 0], axis: [0, 0, 1], rpm: 120}
    - {name: front, plane: {point: [0, 0, 0], normal: [0, 0, 1]}, material: granule}
    - {name: back, plane: {point: [0, 0, 0.02], normal: [0, 0, -1]}, material: granule}
  fill:
    - region: {cylinder: {point: [0, 0, 0], axis: [0, 0, 1], radius: 0.013, from: 0.002, to: 0.018}}
      count: 250
coupling:
  mode: two_way
  trigger: {interval: 4}
  restitution: {api: 0.2, exc: 0.5}
  classes: {min_diameter: 1.0e-3, max_diameter: 4.0e-3, count: 3, material: granule}
  steady: {window: 3, tolerance: 0.5, sample_every: 0.005, max_time: 0.07}
YAML
run_rc 0 "$BIN" couple "$WORK/two.yaml" --out "$WORK/two" --threads 2
stderr_has "restitution of granule: 0.404 (volume-weighted over the components)"
/usr/bin/python3 - "$WORK/two" <<'PY' || fail "the DEM's restitution is not the volume-weighted mean of the components'"
import sys, re, csv, h5py, numpy as np
d = sys.argv[1]
f = h5py.File(d + "/result.h5", "r")
t = f["time"][:]
xa, xe = f["grid"]["api"]["pivots"][:], f["grid"]["exc"]["pivots"][:]
for c in csv.DictReader(open(d + "/cycles.csv")):
    i = int(np.argmin(abs(t - float(c["t_start [s]"]))))
    N = f["number"][i, 0].reshape(len(xa), len(xe))
    va, ve = (N * xa[:, None]).sum(), (N * xe[None, :]).sum()
    want = (0.2 * va + 0.5 * ve) / (va + ve)
    e = float(re.search(r"name: \"granule\"[^}]*e: ([0-9.e+-]+)\}", open(d + "/cycle-%s/case.yaml" % c["cycle"]).read()).group(1))
    assert abs(e - want) < 1e-12 and abs(float(c["restitution [1]"]) - want) < 1e-8, (c["cycle"], e, want)
PY

# Bad input and failure: clear messages, non-zero exits.
bad() { # bad NAME SED_EXPRESSION EXPECTED_STDERR
  sed -e "$2" "$WORK/tw.yaml" > "$WORK/$1.yaml"
  run_rc 1 "$BIN" couple "$WORK/$1.yaml" --out "$WORK/bad-$1"
  stderr_has "$3"
}
bad notrig 's/trigger: {interval: 4}/trigger: {}/' \
  "missing key 'mean_volume_change' (relative change of the mean granule volume; or interval [s]; or both) in coupling.trigger"
bad zerotrig 's/trigger: {interval: 4}/trigger: {interval: 0}/' "coupling.trigger.interval = '0': expected a number > 0"
bad onewaytrig 's/mode: two_way/mode: one_way/' "coupling.trigger: a trigger belongs to mode: two_way"
bad typo 's/trigger: {interval: 4}/trigger: {intervall: 4}/' "did you mean 'interval'"
# a DEM stage that is not steady within its limit: the cycle, the detector's last figures and the limit
bad notsteady 's/max_time: 0.07/max_time: 0.02/' \
  "cycle 1 (process time 0 s): the DEM did not reach a steady state by t = 0.02 s (coupling.steady.max_time): over the last 3 samples"
stderr_has "collision rate"
[ -d "$WORK/bad-notsteady/cycle-1.partial" ] || fail "the failed DEM stage's files are not kept"
# a trigger that cannot fire within the process time: refused before any DEM stage
bad longint 's/trigger: {interval: 4}/trigger: {interval: 10}/' \
  "coupling.trigger.interval = '10': the trigger can never fire: the interval 10 s is not shorter than the process time (10 s"
[ ! -e "$WORK/bad-longint/cycle-1.partial" ] && [ ! -e "$WORK/bad-longint/cycle-1" ] || fail "a DEM stage ran"
run_rc 1 "$BIN" check "$WORK/longint.yaml"
stderr_has "the trigger can never fire"
# a trigger that never fired: the one cycle's results complete, then an error naming the trigger
sed -e 's/trigger: {interval: 4}/trigger: {mean_volume_change: 50, interval: 20}/' -e 's/count: 1001, checkpoint: 0/count: 11/' \
  "$WORK/tw.yaml" > "$WORK/never.yaml"
run_rc 1 "$BIN" couple "$WORK/never.yaml" --out "$WORK/never" --threads 2
# the value named is the summary's relative change of the mean volume from the first to the last output time
change=$(awk -F, 'NR == 1 { for (i = 1; i <= NF; i++) if ($i == "mean_solid [m^3]") c = i; next }
  NR == 2 { m0 = $c } { m = $c } END { d = m / m0 - 1; printf "%.4g", d < 0 ? -d : d }' "$WORK/never/summary.csv")
stderr_has "coupling.trigger never fired: from t = 0 s to the end, t = 10 s, the mean granule volume changed by $change "
stderr_has "(relative; trigger.mean_volume_change 50 and interval 20 s), so one DEM stage drove the whole process"
[ "$(awk -F, 'NR > 1' "$WORK/never/summary.csv" | wc -l)" = 11 ] || fail "the never-fired run's summary.csv is not complete"
[ -s "$WORK/never/result.h5" ] && [ ! -e "$WORK/never/.result.journal" ] || fail "the never-fired run's result.h5 is not complete"
awk -F, 'NR > 1 { printf "%s %s %s %s %s;", $1, $2, $3, $4, $6 }' "$WORK/never/cycles.csv" > "$WORK/rows"
[ "$(cat "$WORK/rows")" = "1 0 10 start end;" ] || fail "never-fired cycles.csv rows: $(cat "$WORK/rows")"
run_rc 1 "$BIN" couple "$WORK/never.yaml" --out "$WORK/never" --resume
stderr_has "coupling.trigger never fired: from t = 0 s to the end, t = 10 s, the mean granule volume did not change enough"
bad norest 's/trigger: {interval: 4}/trigger: {interval: 4}\n  restitution: {apii: 0.3}/' \
  "'apii' is not an axis of the grid (expected one of: solid)"
bad onewayrest 's/mode: two_way/mode: one_way/; s/trigger: {interval: 4}/restitution: {solid: 0.3}/' \
  "coupling.restitution: restitution belongs to mode: two_way"

# System scaling (coupling.scaling): the DEM holds scaling.particles particles
# whatever the population's number; l_i = (N_PBM(t_i) / N)^(1/3) and the table
# the PBM reads is the DEM's own (collision_kernel_dem.csv) times l_i^-3
# (docs/models.md, "System scaling": C_ij per pair goes as 1/volume).
sed -e 's/trigger: {interval: 4}/trigger: {interval: 4}\n  scaling: {particles: 120}/' -e '/^      count: 250$/d' \
  -e 's/count: 1001, checkpoint: 0/count: 11/' \
  "$WORK/tw.yaml" > "$WORK/sc.yaml"
run_rc 0 "$BIN" check "$WORK/sc.yaml"
run_rc 0 "$BIN" couple "$WORK/sc.yaml" --out "$WORK/sc" --threads 2
stderr_has "system scaling: 120 DEM particles for 1000 granules, l_i = 2.0"
/usr/bin/python3 - "$WORK/sc" <<'PY' || fail "system scaling: l_i or the scaled tables are wrong"
import sys, csv, re, h5py, numpy as np
d = sys.argv[1]
f = h5py.File(d + "/result.h5", "r")
t = f["time"][:]
cyc = list(csv.DictReader(open(d + "/cycles.csv")))
assert len(cyc) == 3, cyc
def table(p):
    rows = [l for l in open(p) if not l.startswith("#")]
    return np.array([[float(x) for x in r.split(",")] for r in rows[1:]])
for i, c in enumerate(cyc):
    n = f["number"][int(np.argmin(abs(t - float(c["t_start [s]"]))))].sum()
    l = (n / 120) ** (1 / 3)
    assert abs(float(c["l_i [1]"]) / l - 1) < 1e-8, (c, l)
    assert abs(f["coupling"]["cycles"]["l_i"][i] / l - 1) < 1e-12
    assert 0 < int(c["particles [1]"]) <= 120, c
    assert re.search(r"count: 120\b", open(d + "/cycle-%s/case.yaml" % c["cycle"]).read())
    raw = table(d + "/cycle-%s/collision_kernel_dem.csv" % c["cycle"])
    scaled = table(d + "/cycle-%s/collision_kernel.csv" % c["cycle"])
    assert raw.shape == (3, 3) and raw.max() > 0
    assert np.allclose(scaled, raw / l ** 3, rtol=1e-8, atol=0), (scaled, raw / l ** 3)
    assert np.allclose(f["coupling"]["cycles"]["collision_frequency"][i], scaled, rtol=1e-12)
# the population shrinks by aggregation: l_i falls from cycle to cycle
assert float(cyc[0]["l_i [1]"]) > float(cyc[2]["l_i [1]"])
PY
bad scalefew 's/trigger: {interval: 4}/trigger: {interval: 4}\n  scaling: {particles: 2}/' \
  "coupling.scaling.particles = '2': fewer than the 3 DEM classes derived from the grid"
bad scalezero 's/trigger: {interval: 4}/trigger: {interval: 4}\n  scaling: {particles: 0}/' \
  "coupling.scaling.particles = '0': expected"
bad scaleoneway 's/mode: two_way/mode: one_way/; s/trigger: {interval: 4}/scaling: {particles: 100}/' \
  "coupling.scaling: scaling belongs to mode: two_way"
bad scalecount 's/trigger: {interval: 4}/trigger: {interval: 4}\n  scaling: {particles: 100}/' \
  "set by the coupling (the PBM population and coupling.scaling)"
