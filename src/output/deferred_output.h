/* Output times written later, piece by piece.
 *
 * Under MPI, rank 0 alone writes the result files, and while it wrote, the
 * other ranks waited for it (10 % of the CoriMix example's run).  Rank 0
 * also waits for them: with its cheaper compartments it reaches each step's
 * agreement early.  A deferred output keeps copies of the states of the last
 * few output times and writes them in pieces of tens of µs
 * (gs_output_write_part) while rank 0 waits at those agreements, so the
 * writing moves into time that was idle.  The files get the same rows in the
 * same order as with gs_output_write; only when they are written changes. */
#ifndef GRANSIM_DEFERRED_OUTPUT_H
#define GRANSIM_DEFERRED_OUTPUT_H

#include "gransim/output.h"

typedef struct gs_deferred_output gs_deferred_output;

/* Up to `depth` output times held for o (which stays the caller's), each a
 * full state and ledger of m (m->nstate + m->nledger values) and nresume
 * values of integrator state (gs_output_write). */
gs_deferred_output *gs_deferred_output_create(gs_output *o, const gs_model *m, size_t nresume,
                                              int depth, gs_error *err);
/* Hold output time t with state y (ledger after it) and integrator state
 * resume; when every slot is taken, the oldest is written to the end first. */
int gs_deferred_output_push(gs_deferred_output *q, double t, const double *y,
                            const double *resume, gs_error *err);
/* 1 while output times wait to be written (and nothing has failed). */
int gs_deferred_output_pending(const gs_deferred_output *q);
/* Write the next piece of the oldest held output time. */
int gs_deferred_output_work(gs_deferred_output *q, gs_error *err);
/* Write everything held (an error once a write has failed: what is held is
 * then lost). */
int gs_deferred_output_drain(gs_deferred_output *q, gs_error *err);
/* Seconds spent writing so far. */
double gs_deferred_output_seconds(const gs_deferred_output *q);
void gs_deferred_output_free(gs_deferred_output *q);

#endif
