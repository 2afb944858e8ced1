/* Fixed-pivot aggregation on uniform grids as FFT convolutions
 * (aggregation_fft.c), on non-uniform grids by the near/far split
 * (aggregation_split.c), used by the aggregation mechanism (aggregation.c)
 * when `method` chooses it. */
#ifndef GRANSIM_PBM_AGGREGATION_FFT_H
#define GRANSIM_PBM_AGGREGATION_FFT_H

#include <stddef.h>

#include "gransim/kernel.h"

typedef struct gs_agg_fft gs_agg_fft;

/* NULL if the scheme applies to grid g and kernel k, else why it does not
 * (a phrase for an error message).  rank_tolerance > 0 admits kernels
 * without an exact separable form through a low-rank one (kernel/lowrank.h)
 * of that relative Frobenius error; 0: exact forms alone. */
const char *gs_agg_fft_unusable(const gs_grid *g, const gs_kernel *k, double rank_tolerance);

/* Scratch for nslots evaluators that may run at once.  k must outlive it. */
int gs_agg_fft_create(const gs_grid *g, const gs_kernel *k, double rank_tolerance, int nslots,
                      gs_agg_fft **out, gs_error *err);

/* The rank of the low-rank form (the most terms over the compartments; 0
 * for an exact form) and in *rel_err (NULL: not wanted) the largest
 * relative Frobenius error of its truncation. */
int gs_agg_fft_rank(const gs_agg_fft *F, double *rel_err);
/* How the low-rank form was built and its error measured, as a phrase into
 * msg (n bytes), e.g. "adaptive cross approximation of 21 terms; error over
 * all entries"; "" for an exact form. */
void gs_agg_fft_rank_how(const gs_agg_fft *F, char *msg, size_t n);
void gs_agg_fft_free(gs_agg_fft *F);

/* Pivots not equally spaced: the near/far split's work per evaluation on a
 * full grid (entry tuples times terms, aggregation_split.h); 0 on the FFT. */
double gs_agg_fft_split_work(const gs_agg_fft *F);

/* Rates of compartment comp with numbers N, in slot `slot`'s scratch:
 * deaths and fixed-pivot births added to dN (NULL: totals only), the volume
 * of products beyond the grid (or clamped to its last pivot) added to
 * lost[k] per axis (NULL: not wanted); *born and *dead get the number placed
 * and removed. */
void gs_agg_fft_rates(gs_agg_fft *F, size_t comp, const double *N, int slot, double *dN,
                      double *lost, double *born, double *dead);

#endif
