# gransim validate-fit: the recipe-recovery study runs and writes its report
# (--quick: 40 runs per method, a smoke test of the pipeline: target with the
# time 'end', seven controls, both methods); the full study (ctest -L long)
# recovers the spray rates, binder and impeller speed within 10 %.
# ctest-long
source "$(dirname "$0")/cli-lib.sh" "$@"
CASE=$SRC/examples/recipe-recovery.yaml
run_rc 2 "$BIN" validate-fit
stderr_has "needs CASE"
if [ "${GRANSIM_TEST_LONG:-}" = 1 ]; then
  run_rc 0 "$BIN" validate-fit "$CASE" --out "$WORK/v.md"
  # the rates, binder and impeller speed (rows 1-6 of the table) within 10 % by both methods
  awk -F'|' '/^\| (liquid rate|binder|impeller)/ {
      for (c = 6; c <= 8; c += 2) { e = $c; sub(/ %.*/, "", e); if (e + 0 > 10) bad = bad $2 ": " e " %; " } }
    END { if (bad) { print bad; exit 1 } }' "$WORK/v.md" || { cat "$WORK/v.md"; fail "recipe not recovered"; }
else
  run_rc 0 "$BIN" validate-fit "$CASE" --quick --out "$WORK/v.md"
fi
for s in "# Recipe recovery (Chaudhury 2015, tables 5.6 and 5.7)" "| liquid rate 120-150 s | 2.4e-07 |" \
  "| impeller speed (rpm) | 350 |" "| wet-massing time (s) | 30 |" "Nelder-Mead (GSL nmsimplex2): objective" \
  "bounded (NLopt BOBYQA): objective"; do
  grep -qF "$s" "$WORK/v.md" || { cat "$WORK/v.md"; fail "report lacks '$s'"; }
done
echo "cli_validate_fit: ok"
