/* CVODE's dense linear solver over LAPACK (src/ode/lapack_dense.c): a system
 * needing row exchanges solved against its known solution, the factors reused
 * for a second right-hand side, a singular matrix reported as recoverable. */
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunmatrix/sunmatrix_dense.h>

#include "check.h"
#include "ode/lapack_dense.h"

/* A x = b for the 3 x 3 A with a zero first pivot (dgetrf must pivot). */
static void test_solve(SUNContext ctx) {
  const double a[3][3] = {{0, 2, 1}, {1, 1, 0}, {3, 0, 4}}; /* a[row][col] */
  const double x1[3] = {1, -2, 0.5}, x2[3] = {-3, 0.25, 7};
  SUNMatrix A = SUNDenseMatrix(3, 3, ctx);
  N_Vector x = N_VNew_Serial(3, ctx), b = N_VNew_Serial(3, ctx);
  SUNLinearSolver ls = gs_lapack_dense(x, A, ctx);
  CHECK(ls != NULL);
  if (!ls) return;
  for (int i = 0; i < 3; i++)
    for (int j = 0; j < 3; j++) SM_ELEMENT_D(A, i, j) = a[i][j];
  CHECK(SUNLinSolGetType(ls) == SUNLINEARSOLVER_DIRECT);
  CHECK(SUNLinSolInitialize(ls) == SUNLS_SUCCESS);
  CHECK(SUNLinSolSetup(ls, A) == SUNLS_SUCCESS);
  const double *want[2] = {x1, x2};
  for (int k = 0; k < 2; k++) { /* the same factors, two right-hand sides */
    double *bb = N_VGetArrayPointer(b);
    for (int i = 0; i < 3; i++)
      bb[i] = a[i][0] * want[k][0] + a[i][1] * want[k][1] + a[i][2] * want[k][2];
    CHECK(SUNLinSolSolve(ls, A, x, b, 0.0) == SUNLS_SUCCESS);
    for (int i = 0; i < 3; i++) CHECK_ABS(N_VGetArrayPointer(x)[i], want[k][i], 1e-14);
  }
  SUNLinSolFree(ls);
  N_VDestroy(x);
  N_VDestroy(b);
  SUNMatDestroy(A);
}

/* A singular matrix: recoverable (CVODE then retries with a smaller step). */
static void test_singular(SUNContext ctx) {
  SUNMatrix A = SUNDenseMatrix(2, 2, ctx);
  N_Vector x = N_VNew_Serial(2, ctx);
  SUNLinearSolver ls = gs_lapack_dense(x, A, ctx);
  SM_ELEMENT_D(A, 0, 0) = 1;
  SM_ELEMENT_D(A, 0, 1) = 2;
  SM_ELEMENT_D(A, 1, 0) = 2;
  SM_ELEMENT_D(A, 1, 1) = 4;
  CHECK(SUNLinSolSetup(ls, A) == SUNLS_LUFACT_FAIL);
  CHECK(SUNLinSolLastFlag(ls) == SUNLS_LUFACT_FAIL);
  SUNLinSolFree(ls);
  /* a vector of another length than the matrix: refused */
  N_Vector y = N_VNew_Serial(3, ctx);
  CHECK(gs_lapack_dense(y, A, ctx) == NULL);
  N_VDestroy(y);
  N_VDestroy(x);
  SUNMatDestroy(A);
}

int main(void) {
  SUNContext ctx;
  if (SUNContext_Create(NULL, &ctx)) return 1;
  test_solve(ctx);
  test_singular(ctx);
  SUNContext_Free(&ctx);
  TEST_EXIT();
}
