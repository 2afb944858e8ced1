/* A SUNDIALS dense direct linear solver that factors with LAPACK (dgetrf,
 * dgetrs) instead of SUNDIALS' own unblocked LU: Debian's SUNDIALS is built
 * without its LAPACK solvers, and on CVODE's stiff cases the LU of
 * I - gamma J is most of the run time (docs/performance.md, "Default solver
 * settings"). */
#ifndef GS_ODE_LAPACK_DENSE_H
#define GS_ODE_LAPACK_DENSE_H

#include <sundials/sundials_linearsolver.h>
#include <sundials/sundials_matrix.h>
#include <sundials/sundials_nvector.h>

/* For the n x n dense matrices (SUNDenseMatrix) of vectors like y; NULL when
 * out of memory or when n does not fit LAPACK's int. */
SUNLinearSolver gs_lapack_dense(N_Vector y, SUNMatrix A, SUNContext sunctx);

#endif
