# bench/dyssol without Dyssol itself (a Dyssol run takes half a minute): gransim's side of
# the comparison, the Dyssol agglomerator case with the constant kernel, against the closed
# form of its total number that bench/dyssol/compare.py prints for both codes; and the bench's
# skip and usage messages.
source "$(dirname "$0")/cli-lib.sh" "$@"

# The case as bench/dyssol/run makes its constant-kernel variant.
sed -e 's#kernel: {type: brownian, regime: continuum, beta0: 1.0e-11}#kernel: {type: constant, beta0: 1.0e-11}#' \
  "$SRC/bench/dyssol/agglomerator.yaml" >"$WORK/constant.yaml"
grep -q 'type: constant, beta0: 1.0e-11' "$WORK/constant.yaml" || fail "cannot set the constant kernel in agglomerator.yaml"
run_rc 0 "$BIN" run "$WORK/constant.yaml" --out "$WORK/c" --threads 1 --quiet
# M0 against the Riccati closed form (measured 8e-13; a feed or outflow off by 1e-6 of its
# rate, or aggregation rates off by 1e-6, move it by more than 1e-8), the volume against
# the exact identity (inflow = outflow: constant).
/usr/bin/python3 - "$SRC/bench/dyssol" "$WORK/c/result.h5" <<'PY' || fail "gransim's constant-kernel run is not the closed form"
import sys
import h5py
sys.path.insert(0, sys.argv[1])
from compare import DENSITY, MASS, TAU, closed_form_m0
with h5py.File(sys.argv[2], "r") as f:
    t = f["time"][:]
    m0 = f["summary/M0"][:, 0]
    m1 = f["summary/M1"][:, 0]
    feed = float(f["discretisation/represented"][2])
exact = closed_form_m0(m0[0], feed, 1e-11, TAU, t[-1])
err = abs(m0[-1] / exact - 1)
verr = abs(m1[-1] / (MASS / DENSITY) - 1)
print(f"M0 {m0[-1]:.10g}, closed form {exact:.10g}: {err:.2e}; M1 against the holdup volume {verr:.2e}")
sys.exit(0 if err < 1e-8 and verr < 1e-9 and m0[-1] < 0.99 * m0[0] else 1)
PY

# Without Dyssol the bench says so and succeeds (CI machines without the package).
out=$(DYSSOLC=/nonexistent/DyssolC "$SRC/bench/dyssol/run" 2>&1) || fail "bench/dyssol/run without Dyssol failed: $out"
grep -q 'skipped: /nonexistent/DyssolC not found (Debian package dyssol' <<<"$out" ||
  fail "bench/dyssol/run without Dyssol did not say why it skipped: $out"
# A bad repeat count is refused with the usage.
if out=$("$SRC/bench/dyssol/run" 0 2>&1); then fail "bench/dyssol/run 0 was accepted: $out"; fi
grep -q 'usage: bench/run dyssol \[REPEAT\]' <<<"$out" || fail "bench/dyssol/run 0: no usage: $out"
echo "PASS"
