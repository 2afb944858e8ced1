/* Low-rank separable form of an aggregation kernel over the cells of a grid:
 * beta(a, b) ~ sum_r lambda_r v_r(a) v_r(b) over the symmetrised kernel
 * matrix, so that fast schemes (src/pbm/aggregation_fft.c) take one
 * convolution per term.  lowrank.c builds it by adaptive cross
 * approximation and recompression (O(cells rank) memory, O(cells rank^2)
 * time); lowrank_dense.c by the dense eigendecomposition, the reference and
 * the fallback where the cross approximation does not converge. */
#ifndef GRANSIM_KERNEL_LOWRANK_H
#define GRANSIM_KERNEL_LOWRANK_H

#include <stddef.h>

#include "gransim/kernel.h"

/* The most terms the cross approximation takes (its memory ~6 cells x terms
 * doubles): a form needing more has no use in an FFT (each term costs a
 * transform) and is refused above GS_LOWRANK_DENSE_MAX_CELLS. */
#define GS_LOWRANK_MAX_TERMS 512
/* The largest grid (cells per compartment) the dense eigendecomposition
 * takes: the matrix and its eigenvectors hold 2 n^2 doubles (256 MiB) and
 * it costs ~10 n^3 flops. */
#define GS_LOWRANK_DENSE_MAX_CELLS 4096
/* Up to this many cells the achieved error is measured over every entry
 * (n^2 kernel evaluations); above it estimated from GS_LOWRANK_SAMPLE_ROWS
 * whole rows drawn at random (fixed seed). */
#define GS_LOWRANK_EXACT_MAX_CELLS 4096
#define GS_LOWRANK_SAMPLE_ROWS 256

typedef struct gs_kernel_lowrank {
  int rank;         /* terms kept */
  double *lambda;   /* rank eigenvalues, largest magnitude first */
  double *vec;      /* rank x ncells: v_r(c) at vec[r * ncells + c], orthonormal */
  double rel_err;   /* achieved ||B - B_r||_F / ||B||_F */
  int sampled_rows; /* 0: rel_err over every entry; else over this many random rows (an estimate) */
  int cross_terms;  /* terms of the cross approximation before recompression */
  int dense;        /* 1: built by the dense eigendecomposition */
} gs_kernel_lowrank;

/* The fewest terms whose achieved error has a Frobenius norm at most tol
 * times the matrix's, for compartment comp of kernel k on ncells cells (the
 * matrix symmetrised: (B + B^T)/2, which is what pairs see).  0 < tol < 1.
 * Adaptive cross approximation; the dense decomposition where that does not
 * converge within GS_LOWRANK_MAX_TERMS and ncells <= GS_LOWRANK_DENSE_MAX_CELLS,
 * else GS_EINPUT saying so. */
int gs_kernel_lowrank_build(const gs_kernel *k, size_t ncells, size_t comp, double tol,
                            gs_kernel_lowrank *out, gs_error *err);
/* The same by the dense eigendecomposition alone (the truncation error is
 * then exact: the dropped eigenvalues); ncells <= GS_LOWRANK_DENSE_MAX_CELLS. */
int gs_kernel_lowrank_build_dense(const gs_kernel *k, size_t ncells, size_t comp, double tol,
                                  gs_kernel_lowrank *out, gs_error *err);
void gs_kernel_lowrank_free(gs_kernel_lowrank *lr);
/* The achieved relative Frobenius error of lr for compartment comp of k,
 * over every entry (nrows 0) or estimated over nrows whole rows drawn at
 * random with the seed (the build's own measure; for tests). */
int gs_kernel_lowrank_error(const gs_kernel *k, size_t ncells, size_t comp, const gs_kernel_lowrank *lr, int nrows,
                            unsigned long seed, double *rel_err, gs_error *err);

/* Shared by both builds: all eigenpairs of the symmetric n x n matrix A
 * (destroyed; LAPACK dsyevr), w ascending, z column-major; and the indices
 * of w by decreasing |w|. */
int gs_lowrank_eigen(double *A, int n, double *w, double *z, gs_error *err);
void gs_lowrank_order(const double *w, size_t n, int *order);

#endif
