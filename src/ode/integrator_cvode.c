/* Integrator "cvode": SUNDIALS CVODE (BDF) for stiff cases.
 *
 * Keys (besides the common ones, see integrator.c):
 *   linear_solver  dense | gmres | auto (default auto: dense up to 1000
 *                  components, else matrix-free GMRES without preconditioner;
 *                  dense factors with LAPACK, lapack_dense.h)
 *   max_order      BDF order limit 1..5 (default 5)
 *   preconditioner auto | none (default auto: GMRES is left-preconditioned
 *                  with the system's psolve when it has one, i.e. when a
 *                  mechanism can invert its own stiff part, such as growth)
 *
 * Absolute tolerances are per component, atol * abs_scale[i]; components with
 * abs_scale 0 get 1e300, which removes them from the error and Newton
 * convergence tests.  Such components must not feed back nonlinearly into f:
 * the difference-quotient Jacobian perturbs them by amounts scaled with the
 * tolerance (the mass ledger, which nothing reads, is the intended use).
 *
 * The Newton iterations keep the system's linear invariants (the volume
 * ledger) to round-off however loosely they converge, provided every operator
 * they apply keeps them: the Jacobians pass through gs_ode.conserve
 * (gs_cvode_dense_jac, gs_cvode_jtimes), and psolve must conserve as well.
 *
 * CVODE is set up once in create() with a zero initial state and
 * re-initialised whenever advance() is called with a state other than the one
 * it last returned, so consecutive calls keep the BDF history. */
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cvode/cvode.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunlinsol/sunlinsol_spgmr.h>
#include <sunmatrix/sunmatrix_dense.h>

#include "gransim/integrator.h"
#include "lapack_dense.h"

int gs_integrator_common_keys(gs_cfg_node *solver, double *rtol, double *atol,
                              double *initial_step, double *min_step, double *max_step,
                              long *max_steps, gs_error *err);

#define GS_CVODE_EXCLUDED_ATOL 1e300
#define GS_CVODE_DENSE_MAX_N 1000

enum { GS_CVODE_AUTO, GS_CVODE_DENSE, GS_CVODE_GMRES };
static const char *const gs_cvode_solvers[] = {"auto", "dense", "gmres", NULL};

typedef struct {
  size_t n;
  double rtol, atol, h_init, h_min, h_max;
  long max_steps, max_order;
  int gmres, precondition;
  long jtimes_evals; /* f evaluations of our Jacobian-vector products and dense Jacobians (all runs) */
  SUNContext sunctx;
  void *mem;
  N_Vector y;      /* the state CVODE last returned (compared to detect restarts) */
  N_Vector abstol; /* per-component absolute tolerances */
  SUNMatrix jac;   /* dense only */
  SUNLinearSolver ls;
  int needs_reinit;
  double t_last;      /* time of the state in y */
  const gs_ode *ode;  /* the system of the advance() in progress */
  int rhs_failed;     /* 1: f returned an error; 2: f gave a non-finite value */
  size_t fail_index;
  double fail_t, fail_value;
  char msg[512];      /* CVODE's last error message */
  gs_integrator_stats base; /* counters accumulated before the last (re)init */
} gs_cvode;

/* Both a failing callback and a non-finite derivative stop CVODE at once
 * (negative return = unrecoverable): left to itself, CVODE keeps retrying
 * NaN steps until max_steps_per_output runs out. */
static int gs_cvode_rhs(sunrealtype t, N_Vector y, N_Vector ydot, void *data) {
  gs_cvode *self = data;
  double *f = N_VGetArrayPointer(ydot);
  self->fail_t = t;
  if (self->ode->f(self->ode->ctx, t, N_VGetArrayPointer(y), f)) {
    self->rhs_failed = 1;
    return -1;
  }
  for (size_t i = 0; !self->ode->rates_checked && i < self->n; i++) {
    if (!isfinite(f[i])) {
      self->rhs_failed = 2;
      self->fail_index = i;
      self->fail_value = f[i];
      return -1;
    }
  }
  return 0;
}

/* Keep CVODE's messages for our own error instead of letting it print;
 * warnings (positive codes) are dropped. */
static void gs_cvode_message(int code, const char *module, const char *function, char *msg,
                             void *data) {
  (void)module;
  gs_cvode *self = data;
  if (code < 0) snprintf(self->msg, sizeof self->msg, "%s: %s", function, msg);
}

static int gs_cvode_flag(gs_cvode *self, int flag, const char *call, gs_error *err) {
  if (flag >= 0) return GS_OK;
  char *name = CVodeGetReturnFlagName(flag);
  gs_error_set(err, GS_ENUMERIC, "integrator cvode: %s failed: %s%s%s", call,
               name ? name : "unknown flag", self->msg[0] ? ": " : "", self->msg);
  free(name);
  return GS_ENUMERIC;
}

static void gs_cvode_free(void *vself) {
  gs_cvode *self = vself;
  if (!self) return;
  if (self->mem) CVodeFree(&self->mem);
  if (self->ls) SUNLinSolFree(self->ls);
  if (self->jac) SUNMatDestroy(self->jac);
  if (self->abstol) N_VDestroy(self->abstol);
  if (self->y) N_VDestroy(self->y);
  if (self->sunctx) SUNContext_Free(&self->sunctx);
  free(self);
}

/* The settings: a gs_cvode with its keys filled in and nothing allocated
 * (gmres holds the linear_solver key until create resolves auto by n). */
static int gs_cvode_read(gs_cfg_node *solver, void **out, gs_error *err) {
  gs_cvode *self = gs_calloc(1, sizeof *self, err);
  if (!self) return GS_ENOMEM;
  int solver_kind = GS_CVODE_AUTO;
  int rc = gs_integrator_common_keys(solver, &self->rtol, &self->atol, &self->h_init,
                                     &self->h_min, &self->h_max, &self->max_steps, err);
  if (!rc)
    rc = gs_cfg_enum_opt(solver, "linear_solver", gs_cvode_solvers, GS_CVODE_AUTO, &solver_kind,
                         err);
  if (!rc) rc = gs_cfg_long_range(solver, "max_order", 0, 5, 1, 5, &self->max_order, err);
  static const char *const preconditioners[] = {"auto", "none", NULL};
  int pre = 0;
  if (!rc) rc = gs_cfg_enum_opt(solver, "preconditioner", preconditioners, 0, &pre, err);
  self->precondition = pre == 0;
  self->gmres = solver_kind;
  if (rc) {
    free(self);
    return rc;
  }
  *out = self;
  return GS_OK;
}

static int gs_cvode_vectors(gs_cvode *self, const gs_ode *ode, gs_error *err) {
  sunindextype n = (sunindextype)self->n;
  if (SUNContext_Create(NULL, &self->sunctx) || !(self->y = N_VNew_Serial(n, self->sunctx)) ||
      !(self->abstol = N_VNew_Serial(n, self->sunctx)))
    return gs_error_set(err, GS_ENOMEM, "integrator cvode: cannot allocate vectors of %zu", self->n);
  N_VConst(0.0, self->y);
  double *a = N_VGetArrayPointer(self->abstol);
  for (size_t i = 0; i < self->n; i++) {
    double s = ode->abs_scale ? ode->abs_scale[i] : 1.0;
    a[i] = s > 0 ? self->atol * s : GS_CVODE_EXCLUDED_ATOL;
  }
  return GS_OK;
}

/* CVODE's preconditioner solve: P z = r with P ~ I - gamma J. */
static int gs_cvode_psolve(sunrealtype t, N_Vector y, N_Vector fy, N_Vector r, N_Vector z,
                           sunrealtype gamma, sunrealtype delta, int lr, void *data) {
  (void)fy;
  (void)delta;
  (void)lr;
  gs_cvode *self = data;
  return self->ode->psolve(self->ode->ctx, t, N_VGetArrayPointer(y), gamma,
                           N_VGetArrayPointer(r), N_VGetArrayPointer(z))
             ? 1 /* recoverable: CVODE retries with a smaller step */
             : 0;
}

/* Jacobian-vector product by a forward difference, as CVODE's own (the
 * perturbation 1 / ||v|| in the weighted RMS norm), but with the system's
 * discrete choices held at the linearisation point (gs_ode.hold): a state
 * perturbed by tolerance-sized noise must not switch cells on.  The product
 * keeps the system's linear invariants (gs_ode.conserve), as J does. */
static int gs_cvode_jtimes(N_Vector v, N_Vector Jv, sunrealtype t, N_Vector y, N_Vector fy,
                           void *data, N_Vector tmp) {
  gs_cvode *self = data;
  int flag = CVodeGetErrWeights(self->mem, tmp);
  double norm = flag == CV_SUCCESS ? N_VWrmsNorm(v, tmp) : 0.0;
  if (flag != CV_SUCCESS) return -1;
  if (!(norm > 0)) {
    N_VConst(0.0, Jv);
    return 0;
  }
  double sig = 1.0 / norm;
  N_VLinearSum(sig, v, 1.0, y, tmp);
  self->ode->hold(self->ode->ctx, 1);
  int rc = gs_cvode_rhs(t, tmp, Jv, self);
  self->ode->hold(self->ode->ctx, 0);
  self->jtimes_evals++;
  if (rc) return rc;
  N_VLinearSum(1.0 / sig, Jv, -1.0 / sig, fy, Jv);
  if (self->ode->conserve) self->ode->conserve(self->ode->ctx, N_VGetArrayPointer(Jv));
  return 0;
}

/* Dense Jacobian by forward differences, column by column with CVODE's own
 * increments (cvLsDenseDQJac: sqrt(uround) |y_j|, at least 1000 |h| uround n
 * ||f|| / ewt_j), but with the system's discrete choices held (as in
 * gs_cvode_jtimes) and each column made to keep the system's linear
 * invariants (gs_ode.conserve): a column's differences carry f's round-off
 * over the increment, ~1e-8 of it, and the Newton corrections would move
 * the volume balance by as much at every step. */
static int gs_cvode_dense_jac(sunrealtype t, N_Vector y, N_Vector fy, SUNMatrix J, void *data,
                              N_Vector tmp1, N_Vector tmp2, N_Vector tmp3) {
  (void)tmp3;
  gs_cvode *self = data;
  const gs_ode *ode = self->ode;
  const size_t n = self->n;
  sunrealtype h = 0;
  if (CVodeGetErrWeights(self->mem, tmp1) != CV_SUCCESS || CVodeGetCurrentStep(self->mem, &h) != CV_SUCCESS)
    return -1;
  const double *ewt = N_VGetArrayPointer(tmp1), *f0 = N_VGetArrayPointer(fy);
  const double fnorm = N_VWrmsNorm(fy, tmp1), srur = sqrt(DBL_EPSILON);
  const double min_inc = fnorm != 0 ? 1000 * fabs(h) * DBL_EPSILON * (double)n * fnorm : 1.0;
  double *yd = N_VGetArrayPointer(y), *fj = N_VGetArrayPointer(tmp2);
  int rc = 0;
  if (ode->hold) ode->hold(ode->ctx, 1);
  for (size_t j = 0; j < n && !rc; j++) {
    const double saved = yd[j], inc = fmax(srur * fabs(saved), min_inc / ewt[j]);
    yd[j] += inc;
    rc = gs_cvode_rhs(t, y, tmp2, self);
    yd[j] = saved;
    self->jtimes_evals++;
    double *col = SM_COLUMN_D(J, j);
    for (size_t i = 0; i < n; i++) col[i] = (fj[i] - f0[i]) / inc;
    if (ode->conserve) ode->conserve(ode->ctx, col);
  }
  if (ode->hold) ode->hold(ode->ctx, 0);
  return rc;
}

static int gs_cvode_linear_solver(gs_cvode *self, const gs_ode *ode, gs_error *err) {
  sunindextype n = (sunindextype)self->n;
  if (self->gmres) {
    int pre = self->precondition && ode->psolve;
    /* maxl 0: SUNDIALS' default Krylov dimension (5) */
    self->ls = SUNLinSol_SPGMR(self->y, pre ? SUN_PREC_LEFT : SUN_PREC_NONE, 0, self->sunctx);
    if (self->ls && (pre || ode->hold)) {
      int rc = gs_cvode_flag(self, CVodeSetLinearSolver(self->mem, self->ls, NULL),
                             "CVodeSetLinearSolver", err);
      if (!rc && pre)
        rc = gs_cvode_flag(self, CVodeSetPreconditioner(self->mem, NULL, gs_cvode_psolve),
                           "CVodeSetPreconditioner", err);
      if (!rc && ode->hold)
        rc = gs_cvode_flag(self, CVodeSetJacTimes(self->mem, NULL, gs_cvode_jtimes),
                           "CVodeSetJacTimes", err);
      return rc;
    }
  } else {
    self->jac = SUNDenseMatrix(n, n, self->sunctx);
    if (self->jac) self->ls = gs_lapack_dense(self->y, self->jac, self->sunctx);
  }
  if (!self->ls)
    return gs_error_set(err, GS_ENOMEM, "integrator cvode: cannot allocate the %s linear solver",
                        self->gmres ? "gmres" : "dense");
  int rc = gs_cvode_flag(self, CVodeSetLinearSolver(self->mem, self->ls, self->jac),
                         "CVodeSetLinearSolver", err);
  if (!rc && !self->gmres && (ode->conserve || ode->hold))
    rc = gs_cvode_flag(self, CVodeSetJacFn(self->mem, gs_cvode_dense_jac), "CVodeSetJacFn", err);
  return rc;
}

static int gs_cvode_options(gs_cvode *self, gs_error *err) {
  void *m = self->mem;
  int rc = gs_cvode_flag(self, CVodeSetMaxOrd(m, (int)self->max_order), "CVodeSetMaxOrd", err);
  if (!rc)
    rc = gs_cvode_flag(self, CVodeSetMaxNumSteps(m, self->max_steps), "CVodeSetMaxNumSteps", err);
  if (!rc && !isnan(self->h_init))
    rc = gs_cvode_flag(self, CVodeSetInitStep(m, self->h_init), "CVodeSetInitStep", err);
  if (!rc && !isnan(self->h_min))
    rc = gs_cvode_flag(self, CVodeSetMinStep(m, self->h_min), "CVodeSetMinStep", err);
  if (!rc && !isnan(self->h_max))
    rc = gs_cvode_flag(self, CVodeSetMaxStep(m, self->h_max), "CVodeSetMaxStep", err);
  return rc;
}

/* Everything CVODE needs, initialised at t = 0, y = 0; the first advance()
 * re-initialises with the real state. */
static int gs_cvode_setup(gs_cvode *self, const gs_ode *ode, gs_error *err) {
  int rc = gs_cvode_vectors(self, ode, err);
  if (rc) return rc;
  self->mem = CVodeCreate(CV_BDF, self->sunctx);
  if (!self->mem) return gs_error_set(err, GS_ENOMEM, "integrator cvode: CVodeCreate failed");
  rc = gs_cvode_flag(self, CVodeSetErrHandlerFn(self->mem, gs_cvode_message, self),
                     "CVodeSetErrHandlerFn", err);
  if (!rc) rc = gs_cvode_flag(self, CVodeInit(self->mem, gs_cvode_rhs, 0.0, self->y), "CVodeInit", err);
  if (!rc) rc = gs_cvode_flag(self, CVodeSetUserData(self->mem, self), "CVodeSetUserData", err);
  if (!rc)
    rc = gs_cvode_flag(self, CVodeSVtolerances(self->mem, self->rtol, self->abstol),
                       "CVodeSVtolerances", err);
  if (!rc) rc = gs_cvode_linear_solver(self, ode, err);
  if (!rc) rc = gs_cvode_options(self, err);
  self->needs_reinit = 1;
  return rc;
}

static int gs_cvode_create(const void *settings, const gs_ode *ode, void **out, gs_error *err) {
  gs_cvode *self = gs_malloc(sizeof *self, err);
  if (!self) return GS_ENOMEM;
  *self = *(const gs_cvode *)settings;
  self->n = ode->n;
  self->gmres = self->gmres == GS_CVODE_GMRES ||
                (self->gmres == GS_CVODE_AUTO && self->n > GS_CVODE_DENSE_MAX_N);
  int rc = gs_cvode_setup(self, ode, err);
  if (rc) {
    gs_cvode_free(self);
    return rc;
  }
  *out = self;
  return GS_OK;
}

/* CVODE's counters restart at every (re)init; fold them into base first. */
static void gs_cvode_counters(const gs_cvode *self, gs_integrator_stats *s) {
  long steps = 0, nfe = 0, nfels = 0, netf = 0, nncf = 0;
  sunrealtype hlast = 0;
  CVodeGetNumSteps(self->mem, &steps);
  CVodeGetNumRhsEvals(self->mem, &nfe);
  CVodeGetNumLinRhsEvals(self->mem, &nfels);
  CVodeGetNumErrTestFails(self->mem, &netf);
  CVodeGetNumNonlinSolvConvFails(self->mem, &nncf);
  CVodeGetLastStep(self->mem, &hlast);
  s->steps = self->base.steps + steps;
  s->rhs_evals = self->base.rhs_evals + nfe + nfels + self->jtimes_evals;
  s->rejected = self->base.rejected + netf + nncf;
  s->last_step = steps ? hlast : self->base.last_step;
}

static int gs_cvode_reinit(gs_cvode *self, double t, const double *y, gs_error *err) {
  gs_cvode_counters(self, &self->base);
  memcpy(N_VGetArrayPointer(self->y), y, self->n * sizeof *y);
  self->base.rhs_evals -= self->jtimes_evals; /* counted once, in gs_cvode_counters */
  int rc = gs_cvode_flag(self, CVodeReInit(self->mem, t, self->y), "CVodeReInit", err);
  if (!rc) self->needs_reinit = 0;
  return rc;
}

static int gs_cvode_fail(gs_cvode *self, int flag, double t0, double tret, double t_out,
                         double *t, double *y, gs_error *err) {
  self->needs_reinit = 1;
  /* On a failed step CVODE returns the last accepted state at tret. */
  if (tret > t0 && tret <= t_out) {
    memcpy(y, N_VGetArrayPointer(self->y), self->n * sizeof *y);
    *t = tret;
  }
  if (self->rhs_failed == 1)
    return gs_error_set(err, GS_ENUMERIC, "integrator cvode: right-hand side failed at t = %.9g",
                        self->fail_t);
  if (self->rhs_failed == 2)
    return gs_error_set(err, GS_ENUMERIC,
                        "integrator cvode: right-hand side gave dydt[%zu] = %g at t = %.9g",
                        self->fail_index, self->fail_value, self->fail_t);
  char *name = CVodeGetReturnFlagName(flag);
  gs_error_set(err, GS_ENUMERIC, "integrator cvode: %s at t = %.9g (integrating to %.9g)%s%s",
               name ? name : "failure", *t, t_out, self->msg[0] ? ": " : "", self->msg);
  free(name);
  return GS_ENUMERIC;
}

static int gs_cvode_all_finite(const double *y, size_t n) {
  for (size_t i = 0; i < n; i++)
    if (!isfinite(y[i])) return 0;
  return 1;
}

/* Continue the previous integration only if the caller hands back exactly
 * the state we returned; anything else is a new initial value problem. */
static int gs_cvode_prepare(gs_cvode *self, double t, const double *y, gs_error *err) {
  if (self->needs_reinit || t != self->t_last ||
      memcmp(y, N_VGetArrayPointer(self->y), self->n * sizeof *y) != 0)
    return gs_cvode_reinit(self, t, y, err);
  return GS_OK;
}

static int gs_cvode_advance(void *vself, const gs_ode *ode, double *t, double t_out, double *y,
                            gs_error *err) {
  gs_cvode *self = vself;
  if (ode->n != self->n || !(t_out >= *t))
    return gs_error_set(err, GS_EINPUT,
                        "integrator cvode: bad call (n = %zu for %zu, t = %g to %g)", ode->n,
                        self->n, *t, t_out);
  if (ode->reduce_max)
    return gs_error_set(err, GS_EINPUT,
                        "integrator cvode: a state spread over several MPI ranks needs "
                        "solver.method rk or euler (or run on one rank)");
  if (t_out == *t) return GS_OK;
  self->ode = ode;
  self->rhs_failed = 0;
  self->msg[0] = '\0';
  /* across a jump in f the history of past steps is that of another f */
  if (ode->jumped) self->needs_reinit = 1;
  int rc = gs_cvode_prepare(self, *t, y, err);
  /* The stop time makes CVODE land on t_out instead of stepping past it and
   * interpolating, so f is never evaluated beyond t_out. */
  if (!rc) rc = gs_cvode_flag(self, CVodeSetStopTime(self->mem, t_out), "CVodeSetStopTime", err);
  if (rc) return rc;
  sunrealtype tret = *t;
  int flag = CVode(self->mem, t_out, self->y, &tret, CV_NORMAL);
  if (flag < 0) return gs_cvode_fail(self, flag, *t, tret, t_out, t, y, err);
  memcpy(y, N_VGetArrayPointer(self->y), self->n * sizeof *y);
  *t = self->t_last = t_out;
  if (!gs_cvode_all_finite(y, self->n)) {
    self->needs_reinit = 1;
    return gs_error_set(err, GS_ENUMERIC, "integrator cvode: state became NaN or infinite by t = %.9g",
                        t_out);
  }
  return GS_OK;
}

static void gs_cvode_stats(const void *vself, gs_integrator_stats *stats) {
  gs_cvode_counters(vself, stats);
}

/* CVODE's history (Nordsieck array, order, step, error weights) cannot be
 * handed to another CVODE, so every output time restarts it (CVodeReInit at
 * the next advance, its own first-step estimate), exactly as a resumed run
 * starts (docs/performance.md: what the restarts cost; starting from the
 * step it would have tried next failed the error test more often and cost
 * more). */
static void gs_cvode_mark(void *vself, double *state) {
  gs_cvode *self = vself;
  self->needs_reinit = 1;
  for (int i = 0; i < GS_INTEGRATOR_MARK; i++) state[i] = 0;
}

static void gs_cvode_resume(void *vself, const double *state) {
  (void)state;
  ((gs_cvode *)vself)->needs_reinit = 1;
}

const gs_integrator_type gs_integrator_cvode = {
    .name = "cvode",
    .summary = "SUNDIALS CVODE BDF for stiff cases, linear_solver dense | gmres | auto",
    .read = gs_cvode_read,
    .create = gs_cvode_create,
    .advance = gs_cvode_advance,
    .get_stats = gs_cvode_stats,
    .free = gs_cvode_free,
    .mark = gs_cvode_mark,
    .resume = gs_cvode_resume,
};
