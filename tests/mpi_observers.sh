# The run driver's observers on 2 MPI ranks (compartments over ranks): the
# test program test_run_observers, launched on 2 ranks, checks that a
# caller's observer on rank 0 sees every output time, that one ending the
# run leaves every rank with the state of that time, and that one failing
# stops every rank (tests/test_run_observers.c).
#
# Usage: bash mpi_observers.sh GRANSIM_BINARY SOURCE_DIR MPIEXEC [MPIEXEC_OPTIONS...]
set -euo pipefail
BIN=$1 SRC=$2
shift 2
TEST="$(dirname "$BIN")/tests/test_run_observers"
[ -x "$TEST" ] || { echo "mpi_observers: $TEST not built" >&2; exit 1; }
export OMPI_MCA_mpi_yield_when_idle=1 OMP_WAIT_POLICY=passive OMP_NUM_THREADS=1
cd "$SRC/tests"
"$@" -np 2 "$TEST"
echo "mpi_observers: passed"
