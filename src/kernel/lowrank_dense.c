/* Truncated eigendecomposition of the whole kernel matrix (LAPACK dsyevr):
 * the reference form and the fallback of the cross approximation
 * (lowrank.c) where that does not converge within GS_LOWRANK_MAX_TERMS.
 *
 * The kernel matrix B_ab = beta(a, b) over the cells is symmetric, so its
 * best approximation of rank r in the Frobenius and the spectral norm is
 * the sum of its r eigenpairs of largest |lambda| (Eckart & Young 1936),
 * with ||B - B_r||_F^2 the sum of the dropped lambda^2.  An SVD would give
 * the same terms with signs moved into the vectors; the eigenvectors keep
 * each term symmetric, v_r(a) v_r(b), so one transform per term serves both
 * factors of its convolution.  O(n^2) memory and O(n^3) time. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "kernel/lowrank.h"

void dsyevr_(const char *jobz, const char *range, const char *uplo, const int *n, double *a,
             const int *lda, const double *vl, const double *vu, const int *il, const int *iu,
             const double *abstol, int *m, double *w, double *z, const int *ldz, int *isuppz,
             double *work, const int *lwork, int *iwork, const int *liwork, int *info);

void gs_kernel_lowrank_free(gs_kernel_lowrank *lr) {
  if (!lr) return;
  free(lr->lambda);
  free(lr->vec);
  memset(lr, 0, sizeof *lr);
}

int gs_lowrank_eigen(double *A, int n, double *w, double *z, gs_error *err) {
  const double zero = 0, abstol = 0;
  const int one = 1;
  int m = 0, info = 0, lwork = -1, liwork = -1, iwq = 0;
  double wq = 0;
  int *isuppz = gs_malloc(2 * (size_t)n * sizeof(int), err);
  if (!isuppz) return GS_ENOMEM;
  dsyevr_("V", "A", "L", &n, A, &n, &zero, &zero, &one, &one, &abstol, &m, w, z, &n, isuppz, &wq,
          &lwork, &iwq, &liwork, &info);
  lwork = (int)wq;
  liwork = iwq;
  double *work = gs_malloc((size_t)lwork * sizeof(double), err);
  int *iwork = gs_malloc((size_t)liwork * sizeof(int), err);
  int rc = work && iwork ? GS_OK : GS_ENOMEM;
  if (!rc)
    dsyevr_("V", "A", "L", &n, A, &n, &zero, &zero, &one, &one, &abstol, &m, w, z, &n, isuppz, work,
            &lwork, iwork, &liwork, &info);
  if (!rc && (info != 0 || m != n))
    rc = gs_error_set(err, GS_ENUMERIC, "LAPACK dsyevr failed (info %d) on a %d x %d kernel matrix", info, n, n);
  free(isuppz);
  free(work);
  free(iwork);
  return rc;
}

void gs_lowrank_order(const double *w, size_t n, int *order) {
  /* dsyevr sorts by value: largest |lambda| from both ends of the list */
  size_t lo = 0, hi = n;
  for (size_t r = 0; r < n; r++) order[r] = fabs(w[lo]) > fabs(w[hi - 1]) ? (int)lo++ : (int)--hi;
}

int gs_kernel_lowrank_build_dense(const gs_kernel *k, size_t ncells, size_t comp, double tol,
                                  gs_kernel_lowrank *out, gs_error *err) {
  memset(out, 0, sizeof *out);
  if (ncells > GS_LOWRANK_DENSE_MAX_CELLS)
    return gs_error_set(err, GS_EINPUT,
                        "the dense decomposition of a kernel matrix takes at most %d cells per compartment, not %zu "
                        "(%.0f MiB)",
                        GS_LOWRANK_DENSE_MAX_CELLS, ncells, 2.0 * (double)ncells * (double)ncells * 8 / 1048576);
  const size_t n = ncells;
  double *A = gs_malloc(n * n * sizeof(double), err);
  double *z = gs_malloc(n * n * sizeof(double), err);
  double *w = gs_malloc(n * sizeof(double), err);
  int *order = gs_malloc(n * sizeof(int), err);
  int rc = A && z && w && order ? GS_OK : GS_ENOMEM;
  double total = 0;
  for (size_t a = 0; !rc && a < n; a++) k->type->row(k->self, comp, a, 0, n, A + a * n);
  for (size_t a = 0; !rc && a < n; a++)
    for (size_t b = 0; b < a; b++) {
      const double s = 0.5 * (A[a * n + b] + A[b * n + a]);
      A[a * n + b] = A[b * n + a] = s;
    }
  for (size_t i = 0; !rc && i < n * n; i++) {
    if (!isfinite(A[i])) rc = gs_error_set(err, GS_ENUMERIC, "the kernel is not finite between cells %zu and %zu", i / n, i % n);
    total += A[i] * A[i];
  }
  if (!rc) rc = gs_lowrank_eigen(A, (int)n, w, z, err);
  if (!rc) {
    gs_lowrank_order(w, n, order);
    /* drop from the smallest while the dropped part stays within tol */
    double dropped = 0, bound = tol * tol * total;
    size_t rank = n;
    while (rank > 0 && dropped + w[order[rank - 1]] * w[order[rank - 1]] <= bound) {
      dropped += w[order[rank - 1]] * w[order[rank - 1]];
      rank--;
    }
    out->rank = (int)rank;
    out->rel_err = total > 0 ? sqrt(dropped / total) : 0;
    out->dense = 1;
    out->lambda = gs_malloc((rank ? rank : 1) * sizeof(double), err);
    out->vec = gs_malloc((rank ? rank : 1) * n * sizeof(double), err);
    if (!out->lambda || !out->vec) rc = GS_ENOMEM;
    for (size_t r = 0; !rc && r < rank; r++) {
      out->lambda[r] = w[order[r]];
      memcpy(out->vec + r * n, z + (size_t)order[r] * n, n * sizeof(double));
    }
  }
  free(A);
  free(z);
  free(w);
  free(order);
  if (rc) gs_kernel_lowrank_free(out);
  return rc;
}
