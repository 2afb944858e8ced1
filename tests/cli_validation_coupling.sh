# scripts/validation-coupling (docs/validation-coupling.md): the verification of De et al.
# (2025) on gransim's coupled runs: ASSM accuracy (scaled and unscaled against resolved), ASSM
# cost, and the LS-ratio and spray-duration trends of its test examples.  The script exits
# non-zero when a row's criterion fails (a trend reversed, the scaled run no closer to the
# resolved one than the unscaled, liquid not conserved, or an explained difference from the
# paper that no longer occurs).  Default suite: --quick (fewer DEM particles and cycles, about
# 10 s of CPU); GRANSIM_TEST_LONG=1 runs the full command, as it writes the report.
# ctest-long
source "$(dirname "$0")/cli-lib.sh" "$@"
cd "$SRC"
mode=--quick
[ "${GRANSIM_TEST_LONG:-0}" = 1 ] && mode=
# the report's absorption section is carried over from the committed one
cp docs/validation-coupling.md "$WORK/report.md"
/usr/bin/python3 scripts/validation-coupling $mode --gransim "$BIN" --out "$WORK/report.md" 2>"$WORK/err" ||
  { tail -n 20 "$WORK/err" >&2; fail "validation-coupling $mode: a criterion failed (above)"; }
for want in "## ASSM accuracy" "| scaled (l⁻³ C_DEM) |" "| unscaled (C_DEM) |" "## ASSM cost" "| resolved |" \
            "Higher LS → larger granules at 500 s" "Shorter t_liq → faster early growth" \
            "Liquid added equals liquid sprayed" "<!-- absorption: begin -->" "## The liquid absorption law"; do
  grep -qF -- "$want" "$WORK/report.md" || fail "the report lacks '$want'"
done
# every trend row is decided: yes, or an explained no
! grep -q '| \*\*NO\*\* |' "$WORK/report.md" || fail "an unexplained trend row"
