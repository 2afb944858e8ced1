/* See core/mpi_errors.h.  MPI is always linked (hypre needs it), so this file
 * does not depend on GRANSIM_HAVE_MPI: a gas phase starts MPI in a plain
 * process too (src/cfd/pressure.c). */
#include "core/mpi_errors.h"

#include <mpi.h>
#include <stdio.h>
#include <string.h>
#include <fcntl.h>
#include <unistd.h>

#include "gransim/parallel.h"

static const char *doing = "an MPI call";
static char context[1024];
static MPI_Errhandler handler = MPI_ERRHANDLER_NULL;
/* standard error as it was when the handler was installed: a rank may point
 * stderr at /dev/null later (gransim sweep's ranks other than 0), but its
 * MPI error must still be seen */
static int error_fd = 2;

const char *gs_mpi_doing(const char *what) {
  const char *was = doing;
  doing = what ? what : "an MPI call";
  return was;
}

void gs_parallel_context(const char *text) {
  snprintf(context, sizeof context, "%s", text ? text : "");
}

/* After an error MPI leaves the state of the communicator undefined (MPI
 * 4.0, section 9.3): the other ranks may wait in a collective or a receive
 * that can never complete, so no rank can return an error and go on.  The
 * message is printed first, then MPI_Abort ends every rank; what a run has
 * committed (its journal, a sweep's runs.csv) is complete on disk, since
 * those are written record by record, and --resume continues from there. */
static void on_error(MPI_Comm *comm, int *code, ...) {
  char reason[MPI_MAX_ERROR_STRING + 1] = "";
  int len = 0, rank = 0, size = 1;
  if (MPI_Error_string(*code, reason, &len) != MPI_SUCCESS) snprintf(reason, sizeof reason, "error code %d", *code);
  else reason[len] = '\0';
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  fflush(stderr);
  dprintf(error_fd, "gransim: MPI error in %s on rank %d of %d: %s%s%s\n", doing, rank, size, reason,
          context[0] ? "; " : "", context);
  (void)comm;
  MPI_Abort(MPI_COMM_WORLD, GS_MPI_EXIT);
}

void gs_mpi_errors_install(void) {
  int up = 0, down = 0;
  MPI_Initialized(&up);
  MPI_Finalized(&down);
  if (!up || down) return;
  if (handler == MPI_ERRHANDLER_NULL) {
    MPI_Comm_create_errhandler(on_error, &handler);
    int fd = fcntl(2, F_DUPFD_CLOEXEC, 3);
    if (fd >= 0) error_fd = fd;
  }
  MPI_Comm_set_errhandler(MPI_COMM_WORLD, handler);
  MPI_Comm_set_errhandler(MPI_COMM_SELF, handler);
}
