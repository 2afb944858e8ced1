# gransim couple under mpirun with 2 ranks refuses to run (every rank would run
# its own DEM stage into the same folder), says why once, and writes nothing.
#
# Usage: bash mpi_couple.sh GRANSIM_BINARY SOURCE_DIR MPIEXEC [MPIEXEC_OPTIONS...]
source "$(dirname "$0")/mpi-lib.sh" "$@"

rc=0
"${MPI[@]}" -np 2 "$BIN" couple "$SRC/examples/corimix-coupled.yaml" --out "$WORK/out" >"$WORK/stdout" 2>"$WORK/stderr" || rc=$?
[ "$rc" -ne 0 ] || fail "gransim couple ran on 2 ranks"
[ "$(grep -c 'gransim couple: runs on one process' "$WORK/stderr")" = 1 ] ||
  fail "expected the refusal once: $(cat "$WORK/stderr")"
[ ! -e "$WORK/out" ] || fail "gransim couple on 2 ranks wrote $WORK/out"
echo "mpi_couple: ok"
