# `gransim couple` with mode two_way and every DEM stage on LIGGGHTS (dem.engine: liggghts):
# a 20 x 19 (solid, liquid) PBM sprayed with liquid and aggregating by the DEM's kernel, 100
# spheres of two derived classes in a box stirred by a blade (tests/liggghts-lib.sh's box),
# three cycles of 4 s (trigger.interval) over 10 s, --ranks 1.  Checked: the options
# (--ranks/--launcher reach LIGGGHTS, are refused on the embedded engine naming dem.engine);
# every cycle in cycles.csv and result.h5 with its trigger, particle count and steady-state
# time; each cycle's kernel table finite, non-empty, the one its DEM stage wrote; the PBM's
# volume ledger (solid constant, liquid = sprayed) to round-off over the stretches; a run
# killed (with its LIGGGHTS) in cycle 2's DEM stage resumes, through --launcher, to the
# uninterrupted run's results bit for bit (LIGGGHTS on one rank repeats itself exactly).
# Skips (exit 0) only when the liggghts binary or mpirun is absent (liggghts-lib.sh).
# Usage: bash cli_couple_liggghts.sh GRANSIM_BINARY SOURCE_DIR
source "$(dirname "$0")/liggghts-lib.sh" cli_couple_liggghts "$@"
command -v h5diff >/dev/null || fail "h5diff (hdf5-tools) is needed"
blade_stl
# The blade turns about the x axis at 600 rpm from 0.05 s (the bed settles first); the detector
# (kinetic energy and collision rate, the two-way default) looks at samples after it.  Liquid at
# a volume ratio 0.05 to the solid is sprayed over [0, 6) s; the grid is large enough that
# nothing aggregates off it.
cat > "$W/tw.yaml" <<'YAML'
title: tiny two-way case on LIGGGHTS
grid:
  axes:
    - {name: solid, type: geometric, min: 1.0e-10, ratio: 2, cells: 20, zero_first: true}
    - {name: liquid, type: geometric, min: 1.0e-11, ratio: 2, cells: 19, zero_first: true}
  size_axes: [solid]
initial: {type: cells, number: 1000, indices: [[7, 1], [8, 1], [9, 1]], weights: [0.3, 0.4, 0.3]}
output: {end: 10, count: 41}
mechanisms:
  - type: liquid_addition
    liquid_solid_ratio: 0.05
    ratio_basis: volume
    end: 6
  - type: aggregation
    kernel: {type: table, beta0: 1.0e-4}
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
      count: 100
coupling:
  mode: two_way
  trigger: {interval: 4}
  classes: {min_diameter: 2.0e-3, max_diameter: 3.0e-3, count: 2, material: granule}
  steady: {window: 4, tolerance: 0.8, sample_every: 0.01, max_time: 0.3, collect: 0.03}
YAML

"$BIN" check "$W/tw.yaml" > "$W/check.out" || fail "gransim check refuses the coupled LIGGGHTS case"
grep -q "valid. two_way: 2 DEM classes from the grid" "$W/check.out" || fail "check: $(cat "$W/check.out")"
"$BIN" couple --check "$W/tw.yaml" --ranks 1 --launcher "mpirun -np 1" > /dev/null || fail "couple --check with --ranks/--launcher"

# --ranks and --launcher on the embedded engine: refused before anything runs, naming dem.engine
# at its line (or the DEM case's `dem` map's, when the key is left out)
sed 's/    engine: liggghts/    engine: embedded/' "$W/tw.yaml" > "$W/emb.yaml"
sed '/    engine: liggghts/d' "$W/tw.yaml" > "$W/noeng.yaml"
if "$BIN" couple "$W/emb.yaml" --out "$W/emb" --ranks 2 2> "$W/emb.err"; then fail "--ranks accepted on the embedded engine"; fi
grep -q "emb.yaml:22: dem: dem.engine is 'embedded': --ranks is for DEM stages on LIGGGHTS" "$W/emb.err" ||
  fail "embedded --ranks message: $(cat "$W/emb.err")"
[ ! -e "$W/emb" ] || fail "the refused run wrote $W/emb"
if "$BIN" couple "$W/noeng.yaml" --out "$W/emb" --ranks 2 --launcher srun 2> "$W/emb.err"; then
  fail "--ranks and --launcher accepted without dem.engine"; fi
grep -q "noeng.yaml:18: dem: dem.engine is not given, so 'embedded': --ranks and --launcher are for DEM stages on LIGGGHTS .* or leave them out$" "$W/emb.err" ||
  fail "no-engine message: $(cat "$W/emb.err")"
if "$BIN" couple --check "$W/emb.yaml" --launcher srun > /dev/null 2> "$W/emb.err"; then fail "couple --check took --launcher on the embedded engine"; fi
grep -q "dem.engine is 'embedded': --launcher is for DEM stages on LIGGGHTS" "$W/emb.err" || fail "check message: $(cat "$W/emb.err")"
"$BIN" check "$W/emb.yaml" > /dev/null || fail "gransim check refuses the embedded variant"
if "$BIN" couple "$W/tw.yaml" --out "$W/zero" --ranks 0 2> "$W/zero.err"; then fail "--ranks 0 accepted"; fi
grep -q "ranks" "$W/zero.err" || fail "--ranks 0 message: $(cat "$W/zero.err")"

# The uninterrupted run, one rank per DEM stage.
"$BIN" couple "$W/tw.yaml" --out "$W/ref" --ranks 1 --threads 1 2> "$W/ref.log" || { cat "$W/ref.log"; fail "the coupled run"; }
grep -q "3 cycles to t = 10 s" "$W/ref.log" || { cat "$W/ref.log"; fail "not 3 cycles"; }
# --ranks 1 reached every stage: the command shown and LIGGGHTS' own processor grid
[ "$(grep -c "liggghts && .*mpirun -np 1 liggghts -log log.liggghts, reading in.setup" "$W/ref.log")" = 3 ] ||
  fail "not three stages started with mpirun -np 1: $(grep mpirun "$W/ref.log")"
for c in 1 2 3; do
  grep -q "^  1 by 1 by 1 MPI processor grid" "$W/ref/cycle-$c/liggghts/log.liggghts" || fail "cycle $c: LIGGGHTS not on one rank"
  [ -s "$W/ref/cycle-$c/liggghts/in.setup" ] || fail "cycle $c: no LIGGGHTS deck"
done
awk -F, 'NR > 1 { printf "%s %s %s %s %s %s;", $1, $2, $3, $4, $6, $7 }' "$W/ref/cycles.csv" > "$W/rows"
[ "$(cat "$W/rows")" = "1 0 4 start interval 100;2 4 8 interval interval 100;3 8 10 interval end 100;" ] ||
  fail "cycles.csv rows: $(cat "$W/rows")"
/usr/bin/python3 - "$W/ref" <<'PY' || fail "the cycles, their tables or the ledger (above)"
import csv, sys, h5py, numpy as np
d = sys.argv[1]
f = h5py.File(d + "/result.h5", "r")
g = f["coupling"]["cycles"]
rows = list(csv.DictReader(open(d + "/cycles.csv")))
assert len(rows) == 3 and all(g[c].shape == (3,) for c in g if c != "collision_frequency"), rows
for col, key in [("t_start", "t_start [s]"), ("t_end", "t_end [s]"), ("particles", "particles [1]"),
                 ("dem_steps", "dem_steps [1]"), ("dem_time", "dem_time [s]"), ("t_steady", "t_steady [s]")]:
    assert np.allclose(g[col][:], [float(r[key]) for r in rows], rtol=1e-8, atol=0), col
assert list(g["trigger"][:]) == [0, 2, 2] and list(g["ended_by"][:]) == [2, 2, 3]
assert list(g["particles"][:]) == [100, 100, 100]
for i, r in enumerate(rows):
    # the detector fired on a sample after the blade started, the stage stopped 0.03 s later
    ts, td = float(r["t_steady [s]"]), float(r["dem_time [s]"])
    assert 0.05 < ts < 0.3 and abs(td - (ts + 0.03)) < 1e-9, r
    assert int(r["dem_steps [1]"]) == round(td / 5e-6), r
    # the kernel table: 2 x 2, finite, not all zero, the one the DEM stage wrote
    lines = [l for l in open(d + "/cycle-%d/collision_kernel.csv" % (i + 1)) if not l.startswith("#")]
    C = np.array([[float(x) for x in l.split(",")] for l in lines[1:3]])
    H = g["collision_frequency"][i]
    assert H.shape == (2, 2) and np.all(np.isfinite(H)) and H.min() >= 0 and H.max() > 0, H
    assert np.array_equal(H, C), (i, H, C)
    print("cli_couple_liggghts: cycle %d from t = %s s: DEM steady at %g s, stopped at %g s, C = %s" % (i + 1, r["t_start [s]"], ts, td, H.tolist()))
# the ledger: total_k(t) = total_k(t0) + in_k - lost_k for both axes; nothing lost; the liquid
# brought in is what was sprayed, 0.05 of the solid over [0, 6) s
t = f["time"][:]
xs, xl = f["grid"]["solid"]["pivots"][:], f["grid"]["liquid"]["pivots"][:]
N = f["number"][:].reshape(len(t), len(xs), len(xl))
S, L = (N * xs[None, :, None]).sum(axis=(1, 2)), (N * xl[None, None, :]).sum(axis=(1, 2))
led = f["ledger"][:].reshape(len(t), 4)
assert len(t) == 41 and abs(t[-1] - 10) < 1e-12
err_s = np.abs(S - S[0] - led[:, 0] + led[:, 2]).max() / S[0]
err_l = np.abs(L - L[0] - led[:, 1] + led[:, 3]).max() / L[-1]
sprayed = 0.05 * S[0] * np.minimum(t, 6) / 6
err_q = np.abs(led[:, 1] - sprayed).max() / sprayed[-1]
lost = np.abs(led[:, 2:]).max() / S[0]
print("cli_couple_liggghts: ledger: solid %.2g, liquid %.2g (relative), liquid in vs sprayed %.2g, lost %.2g; granules %g -> %g"
      % (err_s, err_l, err_q, lost, N[0].sum(), N[-1].sum()))
assert err_s < 1e-12 and err_l < 1e-12 and err_q < 1e-12 and lost < 1e-12
# no solid brought in: under CVODE the exchanged entry carries the Newton iterations' error,
# as the held solid does (measured 1.2e-13 of it), so that their balance holds to round-off
assert np.abs(led[:, 0]).max() < 1e-11 * S[0] and abs(S[-1] / S[0] - 1) < 1e-11
assert N[-1].sum() < 0.9 * N[0].sum()  # the DEM's kernel aggregated
PY

# SIGKILL to gransim's process group (it, sh and mpirun) once cycle 2's DEM stage is running;
# LIGGGHTS, in a process group of its own under Open MPI, ends when its input does, after the
# chunk it was given: the test waits for every process working in the stage's folder to end.
# Then --resume through --launcher: cycle 2's stage runs again from its start state and the run
# ends with the uninterrupted run's files (but dem_wall).
printf '#!/bin/sh\necho "$@" >> "%s/launched"\nexec env OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 mpirun -np 1 "$@"\n' "$W" > "$W/launch"
chmod +x "$W/launch"
setsid "$BIN" couple "$W/tw.yaml" --out "$W/k1" --ranks 1 --threads 1 --quiet 2> "$W/k1.err" &
pid=$!
until grep -qs "^gransim: chunk done" "$W/k1/cycle-2.partial/liggghts/log.liggghts"; do # mid-stage
  kill -0 "$pid" 2>/dev/null || fail "the run ended before it could be killed: $(cat "$W/k1.err")"
  sleep 0.01
done
kill -9 -- "-$pid" 2>/dev/null || true
wait "$pid" 2>/dev/null || true
while kill -0 -- "-$pid" 2>/dev/null; do sleep 0.05; done
stage=$(cd "$W/k1/cycle-2.partial/liggghts" && pwd -P)
in_stage() { # a process whose working directory is the killed stage's LIGGGHTS folder
  local p
  for p in /proc/[0-9]*; do [ "$(readlink "$p/cwd" 2>/dev/null)" = "$stage" ] && return 0; done
  return 1
}
for i in $(seq 600); do in_stage || break; sleep 0.1; done
in_stage && fail "LIGGGHTS of the killed run still runs in $stage after 60 s"
echo "cli_couple_liggghts: killed in cycle 2's DEM stage; its LIGGGHTS ended within $(((i - 1) / 10)).$(((i - 1) % 10)) s"
[ -d "$W/k1/cycle-1" ] && [ -d "$W/k1/cycle-2.partial" ] && [ ! -e "$W/k1/cycle-2" ] || fail "not killed in cycle 2's DEM stage"
"$BIN" couple "$W/tw.yaml" --out "$W/k1" --launcher "$W/launch" --threads 1 --resume 2> "$W/k1r.err" ||
  { cat "$W/k1r.err"; fail "the resumed run"; }
grep -q "resume: from cycle 2 (t = 4 s), its DEM stage run again" "$W/k1r.err" || fail "resume message: $(cat "$W/k1r.err")"
[ "$(grep -c -- "^liggghts -echo screen -log log.liggghts$" "$W/launched")" = 2 ] || fail "--launcher did not start cycles 2 and 3: $(cat "$W/launched")"
grep -q "$W/launch liggghts -log log.liggghts, reading in.setup" "$W/k1r.err" || fail "the launcher not shown"
h5diff --exclude-path /coupling/cycles/dem_wall "$W/ref/result.h5" "$W/k1/result.h5" > "$W/h5diff" 2>&1 ||
  { head -n 20 "$W/h5diff" >&2; fail "the resumed result.h5 differs from the uninterrupted run's"; }
cmp -s "$W/ref/summary.csv" "$W/k1/summary.csv" || fail "the resumed summary.csv differs"
cut -d, -f1-10,12- "$W/ref/cycles.csv" > "$W/c1"
cut -d, -f1-10,12- "$W/k1/cycles.csv" > "$W/c2"
cmp -s "$W/c1" "$W/c2" || fail "the resumed cycles.csv differs: $(diff "$W/c1" "$W/c2")"
for c in 1 2 3; do
  cmp -s "$W/ref/cycle-$c/collision_kernel.csv" "$W/k1/cycle-$c/collision_kernel.csv" || fail "cycle $c's kernel differs"
done
echo "cli_couple_liggghts: ok"
