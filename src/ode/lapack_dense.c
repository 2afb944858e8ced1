/* The dense linear solver of integrator "cvode" over LAPACK (lapack_dense.h).
 * CVODE hands setup() the matrix I - gamma J, which is factored in place, and
 * solve() the same matrix with a right-hand side: the contract of SUNDIALS'
 * own SUNLinSol_Dense, with the LU computed by LAPACK's blocked dgetrf. */
#include "lapack_dense.h"

#include <limits.h>
#include <stdlib.h>

#include <sunmatrix/sunmatrix_dense.h>

/* LAPACK's Fortran interface (Debian's liblapack-dev ships no C header);
 * dgetrs takes the length of its character argument last. */
void dgetrf_(const int *m, const int *n, double *a, const int *lda, int *ipiv, int *info);
void dgetrs_(const char *trans, const int *n, const int *nrhs, const double *a, const int *lda,
             const int *ipiv, double *b, const int *ldb, int *info, size_t trans_len);

typedef struct {
  int n;
  int *pivots;
  int last_flag;
} gs_lapack_dense_content;

#define GS_LD(S) ((gs_lapack_dense_content *)(S)->content)

static SUNLinearSolver_Type gs_ld_type(SUNLinearSolver S) {
  (void)S;
  return SUNLINEARSOLVER_DIRECT;
}

static SUNLinearSolver_ID gs_ld_id(SUNLinearSolver S) {
  (void)S;
  return SUNLINEARSOLVER_CUSTOM;
}

static int gs_ld_initialize(SUNLinearSolver S) {
  GS_LD(S)->last_flag = SUNLS_SUCCESS;
  return SUNLS_SUCCESS;
}

/* A singular matrix is recoverable (positive): CVODE retries with a smaller
 * step, as with SUNDIALS' own dense solver. */
static int gs_ld_setup(SUNLinearSolver S, SUNMatrix A) {
  gs_lapack_dense_content *c = GS_LD(S);
  int info = 0;
  dgetrf_(&c->n, &c->n, SUNDenseMatrix_Data(A), &c->n, c->pivots, &info);
  c->last_flag = info > 0 ? SUNLS_LUFACT_FAIL : info < 0 ? SUNLS_PACKAGE_FAIL_UNREC : SUNLS_SUCCESS;
  return c->last_flag;
}

static int gs_ld_solve(SUNLinearSolver S, SUNMatrix A, N_Vector x, N_Vector b, sunrealtype tol) {
  (void)tol;
  gs_lapack_dense_content *c = GS_LD(S);
  const int one = 1;
  int info = 0;
  N_VScale(1.0, b, x);
  dgetrs_("N", &c->n, &one, SUNDenseMatrix_Data(A), &c->n, c->pivots, N_VGetArrayPointer(x),
          &c->n, &info, 1);
  c->last_flag = info ? SUNLS_PACKAGE_FAIL_UNREC : SUNLS_SUCCESS;
  return c->last_flag;
}

static sunindextype gs_ld_last_flag(SUNLinearSolver S) {
  return GS_LD(S)->last_flag;
}

static int gs_ld_free(SUNLinearSolver S) {
  if (!S) return SUNLS_SUCCESS;
  if (S->content) {
    free(GS_LD(S)->pivots);
    free(S->content);
    S->content = NULL;
  }
  SUNLinSolFreeEmpty(S);
  return SUNLS_SUCCESS;
}

SUNLinearSolver gs_lapack_dense(N_Vector y, SUNMatrix A, SUNContext sunctx) {
  const sunindextype n = SUNDenseMatrix_Rows(A);
  if (n <= 0 || n > INT_MAX || SUNDenseMatrix_Columns(A) != n || N_VGetLength(y) != n)
    return NULL;
  SUNLinearSolver S = SUNLinSolNewEmpty(sunctx);
  if (!S) return NULL;
  S->ops->gettype = gs_ld_type;
  S->ops->getid = gs_ld_id;
  S->ops->initialize = gs_ld_initialize;
  S->ops->setup = gs_ld_setup;
  S->ops->solve = gs_ld_solve;
  S->ops->lastflag = gs_ld_last_flag;
  S->ops->free = gs_ld_free;
  gs_lapack_dense_content *c = calloc(1, sizeof *c);
  S->content = c;
  if (c) {
    c->n = (int)n;
    c->pivots = malloc((size_t)n * sizeof *c->pivots);
  }
  if (!c || !c->pivots) {
    gs_ld_free(S);
    return NULL;
  }
  return S;
}
