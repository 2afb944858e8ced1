/* The pressure equation of the gas step, a symmetric 7-point system on the
 * cell grid, solved with hypre's structured-grid interface: conjugate
 * gradients preconditioned by one V-cycle of PFMG multigrid (red-black
 * Gauss-Seidel smoothing, symmetric, so CG applies).  hypre needs MPI running;
 * a plain (not mpirun) process starts it here as a singleton, on the first
 * gas phase only, so runs without gas never depend on the MPI runtime. */
#include <math.h>
#include <mpi.h>
#include <stdlib.h>

#include <HYPRE_struct_ls.h>

#include "cfd/cfd_internal.h"
#include "core/mpi_errors.h"

struct gs_cfd_psolver {
  int n[3];
  size_t ncell;
  HYPRE_StructGrid grid;
  HYPRE_StructStencil stencil;
  HYPRE_StructMatrix A;
  HYPRE_StructVector b, x;
  double *vals;
};

static int started_mpi;
static void stop_mpi(void) {
  int down = 0;
  MPI_Finalized(&down);
  if (!down) MPI_Finalize();
}

static int ensure_mpi(gs_error *err) {
  int up = 0;
  MPI_Initialized(&up);
  if (up) return GS_OK;
  int provided;
  if (MPI_Init_thread(NULL, NULL, MPI_THREAD_FUNNELED, &provided) != MPI_SUCCESS)
    return gs_error_set(err, GS_EINPUT, "gas phase: MPI (needed by hypre) did not start");
  if (!started_mpi) atexit(stop_mpi);
  started_mpi = 1;
  gs_mpi_errors_install();
  return GS_OK;
}

gs_cfd_psolver *gs_cfd_pressure_create(const int n[3], gs_error *err) {
  if (ensure_mpi(err)) return NULL;
  gs_cfd_psolver *ps = gs_calloc(1, sizeof *ps, err);
  if (!ps) return NULL;
  for (int a = 0; a < 3; a++) ps->n[a] = n[a];
  ps->ncell = (size_t)n[0] * n[1] * n[2];
  ps->vals = gs_malloc(7 * ps->ncell * sizeof(double), err);
  if (!ps->vals) {
    free(ps);
    return NULL;
  }
  HYPRE_Int lo[3] = {0, 0, 0}, hi[3] = {n[0] - 1, n[1] - 1, n[2] - 1};
  HYPRE_StructGridCreate(MPI_COMM_SELF, 3, &ps->grid);
  HYPRE_StructGridSetExtents(ps->grid, lo, hi);
  HYPRE_StructGridAssemble(ps->grid);
  HYPRE_Int off[7][3] = {{0, 0, 0}, {-1, 0, 0}, {1, 0, 0}, {0, -1, 0}, {0, 1, 0}, {0, 0, -1}, {0, 0, 1}};
  HYPRE_StructStencilCreate(3, 7, &ps->stencil);
  for (int e = 0; e < 7; e++) HYPRE_StructStencilSetElement(ps->stencil, e, off[e]);
  HYPRE_StructMatrixCreate(MPI_COMM_SELF, ps->grid, ps->stencil, &ps->A);
  HYPRE_StructMatrixInitialize(ps->A);
  HYPRE_StructVectorCreate(MPI_COMM_SELF, ps->grid, &ps->b);
  HYPRE_StructVectorCreate(MPI_COMM_SELF, ps->grid, &ps->x);
  HYPRE_StructVectorInitialize(ps->b);
  HYPRE_StructVectorInitialize(ps->x);
  return ps;
}

void gs_cfd_pressure_free(gs_cfd_psolver *ps) {
  if (!ps) return;
  HYPRE_StructVectorDestroy(ps->x);
  HYPRE_StructVectorDestroy(ps->b);
  HYPRE_StructMatrixDestroy(ps->A);
  HYPRE_StructStencilDestroy(ps->stencil);
  HYPRE_StructGridDestroy(ps->grid);
  free(ps->vals);
  free(ps);
}

int gs_cfd_pressure_solve(gs_cfd_psolver *ps, const double *nb, const double *diag,
                          const double *rhs, double *x, double tol, int max_iter, int *its,
                          double *res) {
  gs_mpi_doing("hypre's pressure solve of the gas phase (MPI_COMM_SELF)");
  const size_t nc = ps->ncell;
  for (size_t c = 0; c < nc; c++) {
    double s = diag[c];
    for (int e = 0; e < 6; e++) {
      s += nb[6 * c + e];
      ps->vals[7 * c + 1 + e] = -nb[6 * c + e];
    }
    ps->vals[7 * c] = s;
  }
  HYPRE_Int lo[3] = {0, 0, 0}, hi[3] = {ps->n[0] - 1, ps->n[1] - 1, ps->n[2] - 1};
  HYPRE_Int entries[7] = {0, 1, 2, 3, 4, 5, 6};
  HYPRE_StructMatrixSetBoxValues(ps->A, lo, hi, 7, entries, ps->vals);
  HYPRE_StructMatrixAssemble(ps->A);
  HYPRE_StructVectorSetBoxValues(ps->b, lo, hi, (double *)rhs);
  HYPRE_StructVectorSetBoxValues(ps->x, lo, hi, x);
  HYPRE_StructVectorAssemble(ps->b);
  HYPRE_StructVectorAssemble(ps->x);
  HYPRE_StructSolver pcg, mg;
  HYPRE_StructPCGCreate(MPI_COMM_SELF, &pcg);
  HYPRE_StructPCGSetTol(pcg, tol);
  HYPRE_StructPCGSetMaxIter(pcg, max_iter);
  HYPRE_StructPCGSetTwoNorm(pcg, 1);
  HYPRE_StructPCGSetRelChange(pcg, 0);
  HYPRE_StructPFMGCreate(MPI_COMM_SELF, &mg);
  HYPRE_StructPFMGSetMaxIter(mg, 1);
  HYPRE_StructPFMGSetTol(mg, 0.0);
  HYPRE_StructPFMGSetZeroGuess(mg);
  HYPRE_StructPFMGSetRelaxType(mg, 2);
  HYPRE_StructPFMGSetNumPreRelax(mg, 1);
  HYPRE_StructPFMGSetNumPostRelax(mg, 1);
  HYPRE_StructPCGSetPrecond(pcg, HYPRE_StructPFMGSolve, HYPRE_StructPFMGSetup, mg);
  HYPRE_StructPCGSetup(pcg, ps->A, ps->b, ps->x);
  HYPRE_StructPCGSolve(pcg, ps->A, ps->b, ps->x);
  HYPRE_Int n_it = 0;
  double r = 0;
  HYPRE_StructPCGGetNumIterations(pcg, &n_it);
  HYPRE_StructPCGGetFinalRelativeResidualNorm(pcg, &r);
  HYPRE_StructPCGDestroy(pcg);
  HYPRE_StructPFMGDestroy(mg);
  HYPRE_ClearAllErrors();
  HYPRE_StructVectorGetBoxValues(ps->x, lo, hi, x);
  *its = (int)n_it;
  *res = r;
  int finite = isfinite(r);
  for (size_t c = 0; c < nc && finite; c++) finite = isfinite(x[c]);
  return finite && r <= tol ? GS_OK : GS_ENUMERIC;
}
