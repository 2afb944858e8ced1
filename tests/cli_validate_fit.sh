# gransim validate-fit: the recipe-recovery study.  The default suite checks
# its arguments only: a run of the semi-mechanistic case takes about a second,
# so even --quick (12 runs per method) takes half a minute on an idle machine.
# With ctest -L long (GRANSIM_TEST_LONG=1) the full study runs (some 1700 runs,
# half an hour on two cores), its report must hold every row, and the spray
# rates, binder and impeller speed must be recovered within 10 % by both methods.
# ctest-long
source "$(dirname "$0")/cli-lib.sh" "$@"
CASE=$SRC/examples/recipe-recovery.yaml
run_rc 2 "$BIN" validate-fit
stderr_has "needs CASE"
run_rc 0 "$BIN" validate-fit --help
stdout_has "usage: gransim validate-fit CASE [--quick] [--out FILE]"
run_rc 1 "$BIN" validate-fit "$WORK/none.yaml" --quick
stderr_has "none.yaml"
[ "${GRANSIM_TEST_LONG:-}" = 1 ] || { echo "cli_validate_fit: ok (arguments; the study runs under -L long)"; exit 0; }

run_rc 0 "$BIN" validate-fit "$CASE" --out "$WORK/v.md"
for s in "# Recipe recovery (Chaudhury 2015, tables 5.6 and 5.7)" "| liquid rate 120-150 s | 2.4e-07 |" \
  "| impeller speed (rpm) | 350 |" "| wet-massing time (s) | 30 |" "Nelder-Mead (GSL nmsimplex2): objective" \
  "bounded (NLopt BOBYQA): objective"; do
  grep -qF "$s" "$WORK/v.md" || { cat "$WORK/v.md"; fail "report lacks '$s'"; }
done
# the rates, binder and impeller speed (rows 1-6 of the table) within 10 % by both methods
awk -F'|' '/^\| (liquid rate|binder|impeller)/ {
    for (c = 6; c <= 8; c += 2) { e = $c; sub(/ %.*/, "", e); if (e + 0 > 10) bad = bad $2 ": " e " %; " } }
  END { if (bad) { print bad; exit 1 } }' "$WORK/v.md" || { cat "$WORK/v.md"; fail "recipe not recovered"; }
echo "cli_validate_fit: ok"
