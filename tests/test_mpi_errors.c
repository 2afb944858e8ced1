/* An MPI error becomes a gransim error (src/core/mpi_errors.c): this program
 * starts itself on 2 ranks with mpiexec, makes a real MPI error there (a send
 * to a rank that does not exist, a send with an invalid tag from rank 1 after
 * it pointed stderr at /dev/null as gransim sweep's ranks do, an error raised
 * on MPI_COMM_SELF, hypre's communicator) and checks that every rank ended
 * with exit status 1 after the message "gransim: MPI error in <what> on rank
 * r of n: <MPI's reason>; <context>" was printed, instead of Open MPI's
 * default abort, which names neither the operation nor the run. */
#include <mpi.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

#include "check.h"
#include "core/mpi_errors.h"
#include "gransim/parallel.h"

#define CONTEXT "case c.yaml, results in out: continue with --resume"

static int child(const char *what) {
  gs_parallel_init(NULL, NULL);
  int up = 0;
  MPI_Initialized(&up);
  if (!up) { /* built without GRANSIM_MPI: start MPI as the gas phase does */
    int provided;
    MPI_Init_thread(NULL, NULL, MPI_THREAD_FUNNELED, &provided);
    gs_mpi_errors_install();
  }
  gs_parallel_context(CONTEXT);
  int rank, size;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  double x = 1;
  if (!strcmp(what, "rank") && rank == 0) {
    gs_mpi_doing("a send to a rank that does not exist (MPI_Send)");
    MPI_Send(&x, 1, MPI_DOUBLE, size + 3, 0, MPI_COMM_WORLD);
  } else if (!strcmp(what, "tag") && rank == 1) {
    if (!freopen("/dev/null", "w", stderr)) return 9;
    gs_mpi_doing("a send with a negative tag (MPI_Send)");
    MPI_Send(&x, 1, MPI_DOUBLE, 0, -7, MPI_COMM_WORLD);
  } else if (!strcmp(what, "self") && rank == 0) {
    gs_mpi_doing("an error raised on MPI_COMM_SELF");
    MPI_Comm_call_errhandler(MPI_COMM_SELF, MPI_ERR_OTHER);
  }
  /* the other rank waits where it would wait in a run: in a collective */
  gs_parallel_sum(&x, 1);
  printf("returned from the collective after the error\n");
  MPI_Finalize();
  return 0;
}

/* Run this program on 2 ranks in mode WHAT; its output in out, its status returned. */
static int launch(const char *what, char *out, size_t cap) {
  char cmd[4096];
  snprintf(cmd, sizeof cmd,
           "GS_MPI_ERRORS_CHILD=%s timeout 120 '%s' -np 2 --allow-run-as-root --oversubscribe "
           "-x GS_MPI_ERRORS_CHILD /proc/%d/exe 2>&1",
           what, GS_TEST_MPIEXEC, (int)getpid());
  FILE *p = popen(cmd, "r");
  if (!p) return -1;
  size_t n = fread(out, 1, cap - 1, p);
  out[n] = '\0';
  int st = pclose(p);
  return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}

static void expect(const char *what, const char *message, const char *reason) {
  static char out[1 << 16];
  int rc = launch(what, out, sizeof out);
  CHECK(rc == 1);
  CHECK(strstr(out, message) != NULL);
  CHECK(strstr(out, reason) != NULL);
  CHECK(strstr(out, "; " CONTEXT "\n") != NULL);
  CHECK(strstr(out, "returned from the collective") == NULL);
  if (rc != 1 || !strstr(out, message) || !strstr(out, reason))
    fprintf(stderr, "mode %s: exit status %d, output:\n%s\n", what, rc, out);
}

int main(void) {
  const char *what = getenv("GS_MPI_ERRORS_CHILD");
  if (what) return child(what);
  expect("rank", "gransim: MPI error in a send to a rank that does not exist (MPI_Send) on rank 0 of 2: ",
         "invalid rank");
  expect("tag", "gransim: MPI error in a send with a negative tag (MPI_Send) on rank 1 of 2: ", "invalid tag");
  expect("self", "gransim: MPI error in an error raised on MPI_COMM_SELF on rank 0 of 2: ", "MPI_ERR_OTHER");
  /* the label of a wrapped call is the caller's again afterwards */
  gs_mpi_doing("before");
  double v = 2;
  gs_parallel_sum(&v, 1);
  CHECK(!strcmp(gs_mpi_doing(NULL), "before"));
  TEST_EXIT();
}
