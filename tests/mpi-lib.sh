# Shared set-up of the MPI tests: cli-lib.sh's (BIN, SRC, WORK, fail, ...) and
# the launcher.  Usage, first in a test:
#   source "$(dirname "$0")/mpi-lib.sh" "$@"   # GRANSIM_BINARY SOURCE_DIR MPIEXEC [OPTIONS...]
# MPI then holds the launcher and its options; ranks and OpenMP threads that
# sleep instead of spinning keep the tests quick on a busy machine.
source "$(dirname "${BASH_SOURCE[0]}")/cli-lib.sh" "$1" "$2"
[ $# -ge 3 ] || fail "no MPI launcher given (usage: bash $0 GRANSIM_BINARY SOURCE_DIR MPIEXEC [OPTIONS...])"
MPI=("${@:3}")
export OMPI_MCA_mpi_yield_when_idle=1 OMP_WAIT_POLICY=passive
