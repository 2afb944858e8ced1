/* MPI errors become gransim errors.  MPI's default handler on MPI_COMM_WORLD,
 * MPI_ERRORS_ARE_FATAL, ends every rank with the runtime's message only;
 * gransim's handler first says which operation failed, on which rank, MPI's
 * reason, and what the run leaves behind (gs_parallel_context), then ends
 * every rank with exit status GS_MPI_EXIT (1, as for any other error). */
#ifndef GRANSIM_CORE_MPI_ERRORS_H
#define GRANSIM_CORE_MPI_ERRORS_H

/* the exit status of every rank after an MPI error */
#define GS_MPI_EXIT 1

/* Install the handler on MPI_COMM_WORLD and MPI_COMM_SELF (hypre's
 * communicator); MPI must be running.  Call once after MPI_Init; again is
 * harmless. */
void gs_mpi_errors_install(void);

/* Name the MPI operation about to run ("the boundary exchange
 * (MPI_Isend)"), for the message of an error in it.  The text must live
 * until the next call (a literal); only the thread that calls MPI calls
 * this (MPI_THREAD_FUNNELED).  Returns the previous label. */
const char *gs_mpi_doing(const char *what);

#endif
