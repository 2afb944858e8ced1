/* gransim — the MPI environment, optional at build time.
 *
 * Built with -DGRANSIM_MPI=ON, gransim starts MPI when it was launched by
 * mpirun (and only then, so that a plain `gransim run` never needs an MPI
 * runtime); otherwise, or when built without MPI, there is one rank.  The
 * sectional solver spreads compartments over the ranks (src/run/distributed.c),
 * the stochastic solver its independent runs. */
#ifndef GRANSIM_PARALLEL_H
#define GRANSIM_PARALLEL_H

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Start MPI if built with it and launched by mpirun; harmless otherwise.
 * Call once, first thing in main. */
void gs_parallel_init(int *argc, char ***argv);
/* What an MPI error leaves behind and how to go on ("case c.yaml, results in
 * out: ... --resume"), appended to the message that an MPI error prints before
 * it ends every rank with exit status 1 (src/core/mpi_errors.c).  Copied. */
void gs_parallel_context(const char *text);
/* Stop MPI if gs_parallel_init started it. */
void gs_parallel_finalize(void);
/* 1 when the binary was built with MPI. */
int gs_parallel_have_mpi(void);
/* This process's rank and the number of ranks (0 and 1 without MPI). */
int gs_parallel_rank(void);
int gs_parallel_size(void);
/* Collective helpers over all ranks; plain identities with one rank. */
double gs_parallel_max(double v);
void gs_parallel_sum(double *v, size_t n);           /* in place, every rank gets the sum */
void gs_parallel_broadcast(double *v, size_t n);     /* from rank 0 */
void gs_parallel_broadcast_bytes(void *v, size_t n); /* from rank 0 */

#ifdef __cplusplus
}
#endif
#endif
