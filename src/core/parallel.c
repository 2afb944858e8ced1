/* See gransim/parallel.h.  GRANSIM_HAVE_MPI is defined by CMake with
 * -DGRANSIM_MPI=ON. */
#include "gransim/parallel.h"

#include "core/mpi_errors.h"

#include <limits.h>
#include <stdlib.h>

#ifdef GRANSIM_HAVE_MPI
#include <mpi.h>

static int started; /* 1: this process called MPI_Init */

/* Launched by mpirun (Open MPI, MPICH/PMI, PMIx)?  Only then is MPI started:
 * a singleton MPI_Init would make every plain run depend on the runtime. */
static int under_mpirun(void) {
  static const char *const vars[] = {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_RANK", NULL};
  for (const char *const *v = vars; *v; v++)
    if (getenv(*v)) return 1;
  return 0;
}

void gs_parallel_init(int *argc, char ***argv) {
  int up = 0;
  MPI_Initialized(&up);
  if (up || !under_mpirun()) return;
  /* Open MPI's shared-memory transport sends messages above 4 KiB by a
   * rendezvous with a single-copy system call, which takes several times as
   * long as an eager send for a compartment's numbers and carried volumes
   * (a few KiB; docs/performance.md, "The boundary exchange").  Compartments
   * of up to 32 KiB go eagerly unless the user set the limit in the
   * environment (a value in an MCA parameter file is overridden; other MPIs
   * ignore the variables; Open MPI 5 calls the transport "sm"). */
  setenv("OMPI_MCA_btl_vader_eager_limit", "32768", 0);
  setenv("OMPI_MCA_btl_sm_eager_limit", "32768", 0);
  int provided;
  /* the threads of per-compartment steps call MPI, one at a time
   * (src/run/compartment_ranks.c); the rest only from the main thread */
  MPI_Init_thread(argc, argv, MPI_THREAD_SERIALIZED, &provided);
  started = 1;
  gs_mpi_errors_install();
}

void gs_parallel_finalize(void) {
  int down = 0;
  MPI_Finalized(&down);
  if (started && !down) MPI_Finalize();
  started = 0;
}

int gs_parallel_have_mpi(void) { return 1; }

static int mpi_up(void) {
  int up = 0, down = 0;
  MPI_Initialized(&up);
  if (up) MPI_Finalized(&down);
  return up && !down;
}

int gs_parallel_rank(void) {
  int r = 0;
  if (mpi_up()) MPI_Comm_rank(MPI_COMM_WORLD, &r);
  return r;
}

int gs_parallel_size(void) {
  int s = 1;
  if (mpi_up()) MPI_Comm_size(MPI_COMM_WORLD, &s);
  return s;
}

double gs_parallel_max(double v) {
  if (gs_parallel_size() < 2) return v;
  const char *was = gs_mpi_doing("the maximum over ranks (MPI_Allreduce)");
  MPI_Allreduce(MPI_IN_PLACE, &v, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
  gs_mpi_doing(was);
  return v;
}

/* MPI counts are int: long buffers go in chunks. */
#define CHUNK ((size_t)INT_MAX / 8)

void gs_parallel_sum(double *v, size_t n) {
  if (gs_parallel_size() < 2) return;
  const char *was = gs_mpi_doing("the sum over ranks (MPI_Allreduce)");
  for (size_t i = 0; i < n; i += CHUNK) {
    size_t k = n - i < CHUNK ? n - i : CHUNK;
    MPI_Allreduce(MPI_IN_PLACE, v + i, (int)k, MPI_DOUBLE, MPI_SUM, MPI_COMM_WORLD);
  }
  gs_mpi_doing(was);
}

void gs_parallel_broadcast(double *v, size_t n) {
  if (gs_parallel_size() < 2) return;
  const char *was = gs_mpi_doing("the broadcast from rank 0 (MPI_Bcast)");
  for (size_t i = 0; i < n; i += CHUNK) {
    size_t k = n - i < CHUNK ? n - i : CHUNK;
    MPI_Bcast(v + i, (int)k, MPI_DOUBLE, 0, MPI_COMM_WORLD);
  }
  gs_mpi_doing(was);
}

void gs_parallel_broadcast_bytes(void *v, size_t n) {
  if (gs_parallel_size() < 2) return;
  const char *was = gs_mpi_doing("the broadcast from rank 0 (MPI_Bcast)");
  for (size_t i = 0; i < n; i += CHUNK) {
    size_t k = n - i < CHUNK ? n - i : CHUNK;
    MPI_Bcast((char *)v + i, (int)k, MPI_BYTE, 0, MPI_COMM_WORLD);
  }
  gs_mpi_doing(was);
}

#else /* one process */

void gs_parallel_init(int *argc, char ***argv) {
  (void)argc;
  (void)argv;
}
void gs_parallel_finalize(void) {}
int gs_parallel_have_mpi(void) { return 0; }
int gs_parallel_rank(void) { return 0; }
int gs_parallel_size(void) { return 1; }
double gs_parallel_max(double v) { return v; }
void gs_parallel_sum(double *v, size_t n) {
  (void)v;
  (void)n;
}
void gs_parallel_broadcast(double *v, size_t n) {
  (void)v;
  (void)n;
}
void gs_parallel_broadcast_bytes(void *v, size_t n) {
  (void)v;
  (void)n;
}
#endif
