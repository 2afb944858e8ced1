# Units in the result files of both solvers: summary.csv's header gives each
# column's SI unit and pandas reads it with no options; every dataset of
# result.h5 has `units` and `dimensions`; the attributes the two solvers share
# have one HDF5 type (tests/result_units.py).
source "$(dirname "$0")/cli-lib.sh" "$@"
cp -r "$SRC/examples/corimix-continuous.yaml" "$SRC/examples/twin-screw.yaml" "$WORK/"
ln -s "$SRC/examples/data" "$WORK/data"
run_rc 0 "$BIN" run "$WORK/corimix-continuous.yaml" --out "$WORK/sectional" --quiet
run_rc 0 "$BIN" run "$WORK/twin-screw.yaml" --out "$WORK/swa" --quiet
/usr/bin/python3 "$SRC/tests/result_units.py" "$WORK/sectional" "$WORK/swa" || fail "units or attribute types"
echo "cli_units: all checks passed"
