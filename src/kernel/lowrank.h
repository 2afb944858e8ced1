/* Low-rank separable form of an aggregation kernel over the cells of a grid
 * (lowrank.c): beta(a, b) ~ sum_r lambda_r v_r(a) v_r(b), the truncated
 * eigendecomposition of the symmetric kernel matrix, so that fast schemes
 * (src/pbm/aggregation_fft.c) take one convolution per term. */
#ifndef GRANSIM_KERNEL_LOWRANK_H
#define GRANSIM_KERNEL_LOWRANK_H

#include <stddef.h>

#include "gransim/kernel.h"

/* The largest grid (cells per compartment) whose kernel matrix is
 * decomposed: the matrix and its eigenvectors take 2 n^2 doubles (256 MiB)
 * and the decomposition ~10 n^3 flops. */
#define GS_LOWRANK_MAX_CELLS 4096
#define GS_LOWRANK_MAX_CELLS_TEXT "4096"

typedef struct gs_kernel_lowrank {
  int rank;       /* terms kept */
  double *lambda; /* rank eigenvalues, largest magnitude first */
  double *vec;    /* rank x ncells: v_r(c) at vec[r * ncells + c] */
  double rel_err; /* ||B - B_r||_F / ||B||_F of the terms dropped */
} gs_kernel_lowrank;

/* The fewest terms whose dropped part has a Frobenius norm at most tol
 * times the matrix's, for compartment comp of kernel k on ncells cells (the
 * matrix symmetrised: (B + B^T)/2, which is what pairs see).  0 < tol < 1. */
int gs_kernel_lowrank_build(const gs_kernel *k, size_t ncells, size_t comp, double tol,
                            gs_kernel_lowrank *out, gs_error *err);
void gs_kernel_lowrank_free(gs_kernel_lowrank *lr);

#endif
