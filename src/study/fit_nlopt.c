/* The fit's NLopt phases (study_internal.h): a global search for the start
 * of the least squares, and the epsilon-constrained fit of Chaudhury's
 * thesis (the PSD's error least with the porosity's error at most eps).
 * Both work in u, each parameter's fraction of its range. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <nlopt.h>

#include "gransim/cfg.h"
#include "study/study_internal.h"

/* A failed run's objective: far above any real one but finite (NLopt's
 * methods give up on nan); the point is simply not taken. */
#define FAILED_RUN 1e100

typedef struct {
  gs_fit_problem *fc;
  double *r;       /* residuals of one run */
  double *model;   /* model values of one run */
  double best;     /* the least objective seen among feasible points, and where */
  double *best_u;
  double eps;      /* the porosity's bound (constrained fit), 0 otherwise */
  long failed;
  nlopt_opt opt;   /* the global search, stopped at its budget */
  long left;       /* runs left to it */
} phase_ctx;

static int to_x(const gs_fit_problem *fc, const double *u, double *x) {
  for (size_t k = 0; k < fc->np; k++) x[k] = gs_study_axis_value(&fc->params[k], u[k]);
  return GS_OK;
}

/* The residuals at u; 1 when the run failed (the first failure kept). */
static int run_at(phase_ctx *pc, const double *u) {
  double x[64];
  to_x(pc->fc, u, x);
  gs_error e = {0};
  pc->fc->runs++;
  if (gs_fit_problem_residuals(pc->fc, x, pc->r, pc->model, &e)) {
    if (!pc->fc->err.code) pc->fc->err = e;
    pc->failed++;
    return 1;
  }
  return 0;
}

/* Sum of squares of the residuals that are (porosity 0) or are not
 * (porosity 1) porosity columns' (scaled) and the RMS of the porosity
 * columns' errors in their own unit. */
static void sums(const phase_ctx *pc, double *sse_other, double *rms_porosity) {
  const gs_fit_problem *fc = pc->fc;
  double so = 0, sp = 0;
  size_t np = 0;
  for (size_t b = 0; b < fc->bs->n; b++) {
    const gs_fit_data *d = &fc->bs->batch[b].data;
    const gs_fit_map *m = &fc->map[b];
    for (size_t i = 0; i < d->ntimes; i++)
      for (size_t j = 0; j < d->ncols; j++) {
        const size_t q = m->off + i * d->ncols + j;
        if (m->porosity[j]) {
          sp += pow(pc->model[q] - d->values[i * d->ncols + j], 2);
          np++;
        } else {
          so += pc->r[q] * pc->r[q];
        }
      }
  }
  *sse_other = so;
  *rms_porosity = np ? sqrt(sp / (double)np) : 0;
}

static double global_f(unsigned n, const double *u, double *grad, void *data) {
  (void)n, (void)grad; /* derivative-free */
  phase_ctx *pc = data;
  /* NLopt's maxeval is checked between a method's steps, which CRS2 and
   * MLSL may overrun: the budget is kept here */
  if (--pc->left <= 0) nlopt_force_stop(pc->opt);
  if (run_at(pc, u)) return FAILED_RUN;
  double s = 0;
  for (size_t i = 0; i < pc->fc->nresid; i++) s += pc->r[i] * pc->r[i];
  if (s < pc->best) {
    pc->best = s;
    memcpy(pc->best_u, u, pc->fc->np * sizeof *u);
  }
  return s;
}

/* The methods of the global start (registered types, gs_registry_find). */
typedef struct {
  const char *name;
  nlopt_algorithm algorithm;
  nlopt_algorithm local; /* MLSL's local searches; NLOPT_NUM_ALGORITHMS for none */
} global_method;

static const global_method crs2 = {.name = "crs2", .algorithm = NLOPT_GN_CRS2_LM,
                                   .local = NLOPT_NUM_ALGORITHMS};
static const global_method mlsl = {.name = "mlsl", .algorithm = NLOPT_G_MLSL_LDS,
                                   .local = NLOPT_LN_BOBYQA};
static const global_method isres = {.name = "isres", .algorithm = NLOPT_GN_ISRES,
                                    .local = NLOPT_NUM_ALGORITHMS};
static const global_method *const global_methods[] = {&crs2, &mlsl, &isres, NULL};

int gs_fit_global_check(const char *method, gs_error *err) {
  if (gs_registry_find((const void *const *)global_methods, method)) return GS_OK;
  char names[128];
  gs_registry_names((const void *const *)global_methods, names, sizeof names);
  return gs_error_set(err, GS_EINPUT, "--global %s: unknown method; expected one of %s", method,
                      names);
}

int gs_fit_global_start(gs_fit_problem *fc, const char *method, size_t max_runs,
                        unsigned long seed, double *u, gs_error *err) {
  int rc = gs_fit_global_check(method, err);
  if (rc) return rc;
  const global_method *gm = gs_registry_find((const void *const *)global_methods, method);
  const unsigned p = (unsigned)fc->np;
  phase_ctx pc = {.fc = fc, .best = INFINITY, .left = (long)max_runs};
  pc.r = malloc(fc->nresid * sizeof *pc.r);
  pc.model = malloc(fc->nresid * sizeof *pc.model);
  pc.best_u = malloc(p * sizeof *pc.best_u);
  nlopt_opt o = nlopt_create(gm->algorithm, p), local = NULL;
  if (!pc.r || !pc.model || !pc.best_u || !o) rc = gs_error_set(err, GS_ENOMEM, "out of memory");
  if (!rc) {
    double lo[64], hi[64], f;
    for (unsigned k = 0; k < p; k++) lo[k] = 0, hi[k] = 1;
    nlopt_srand(seed); /* the same seed, the same search */
    nlopt_set_lower_bounds(o, lo);
    nlopt_set_upper_bounds(o, hi);
    nlopt_set_min_objective(o, global_f, &pc);
    nlopt_set_maxeval(o, (int)max_runs);
    pc.opt = o;
    if (gm->local != NLOPT_NUM_ALGORITHMS) {
      local = nlopt_create(gm->local, p);
      nlopt_set_xtol_rel(local, 1e-4); /* a local search only finds a basin: LM finishes it */
      nlopt_set_local_optimizer(o, local);
    }
    nlopt_result st = nlopt_optimize(o, u, &f);
    if (st < 0 && st != NLOPT_ROUNDOFF_LIMITED && st != NLOPT_FORCED_STOP && !isfinite(pc.best))
      rc = gs_error_set(err, GS_ENUMERIC, "the global start (%s) failed (NLopt result %d)", method,
                        (int)st);
  }
  if (!rc && !isfinite(pc.best)) {
    *err = fc->err;
    rc = gs_error_prefix(err, "the global start (%s): every run failed; the first: ", method);
  }
  if (!rc) memcpy(u, pc.best_u, p * sizeof *u);
  if (local) nlopt_destroy(local);
  if (o) nlopt_destroy(o);
  free(pc.r);
  free(pc.model);
  free(pc.best_u);
  return rc;
}

/* ---- the epsilon-constraint ---------------------------------------------- */

/* Objective and constraint come from one run: NLopt asks for the objective
 * first, then the constraint at the same point, so the constraint reuses
 * the run when u is the last point run. */
typedef struct {
  phase_ctx pc;
  double *last_u;
  int have_last, last_failed;
  double sse, rms;
} eps_ctx;

static void eval_eps(eps_ctx *ec, const double *u) {
  const size_t p = ec->pc.fc->np;
  if (ec->have_last && !memcmp(u, ec->last_u, p * sizeof *u)) return;
  memcpy(ec->last_u, u, p * sizeof *u);
  ec->have_last = 1;
  ec->last_failed = run_at(&ec->pc, u);
  if (!ec->last_failed) sums(&ec->pc, &ec->sse, &ec->rms);
  if (!ec->last_failed && ec->rms <= ec->pc.eps && ec->sse < ec->pc.best) {
    ec->pc.best = ec->sse;
    memcpy(ec->pc.best_u, u, p * sizeof *u);
  }
}

static double eps_f(unsigned n, const double *u, double *grad, void *data) {
  (void)n, (void)grad;
  eps_ctx *ec = data;
  eval_eps(ec, u);

  return ec->last_failed ? FAILED_RUN : ec->sse;
}

static double eps_g(unsigned n, const double *u, double *grad, void *data) {
  (void)n, (void)grad;
  eps_ctx *ec = data;
  eval_eps(ec, u);
  return ec->last_failed ? FAILED_RUN : ec->rms - ec->pc.eps;
}

int gs_fit_eps_constrained(gs_fit_problem *fc, double eps, size_t max_runs, double *u,
                           double *rms_porosity, gs_error *err) {
  int has_porosity = 0;
  for (size_t b = 0; b < fc->bs->n; b++)
    for (size_t j = 0; j < fc->bs->batch[b].data.ncols; j++) has_porosity |= fc->map[b].porosity[j];
  if (!has_porosity)
    return gs_error_set(err, GS_EINPUT,
                        "--porosity-tol: no data column is a porosity (porosity, porosity_c<j>)");
  const unsigned p = (unsigned)fc->np;
  eps_ctx ec = {.pc = {.fc = fc, .best = INFINITY, .eps = eps}};
  ec.pc.r = malloc(fc->nresid * sizeof *ec.pc.r);
  ec.pc.model = malloc(fc->nresid * sizeof *ec.pc.model);
  ec.pc.best_u = malloc(p * sizeof *ec.pc.best_u);
  ec.last_u = malloc(p * sizeof *ec.last_u);
  nlopt_opt o = nlopt_create(NLOPT_LN_COBYLA, p);
  int rc = ec.pc.r && ec.pc.model && ec.pc.best_u && ec.last_u && o
               ? GS_OK
               : gs_error_set(err, GS_ENOMEM, "out of memory");
  if (!rc) {
    double lo[64], hi[64], f;
    for (unsigned k = 0; k < p; k++) lo[k] = 0, hi[k] = 1;
    nlopt_set_lower_bounds(o, lo);
    nlopt_set_upper_bounds(o, hi);
    nlopt_set_min_objective(o, eps_f, &ec);
    nlopt_add_inequality_constraint(o, eps_g, &ec, 1e-6 * eps);
    nlopt_set_xtol_abs1(o, 1e-9);
    nlopt_set_maxeval(o, (int)max_runs);
    nlopt_set_initial_step1(o, 0.1);
    nlopt_result st = nlopt_optimize(o, u, &f);
    if (st < 0 && st != NLOPT_ROUNDOFF_LIMITED && !isfinite(ec.pc.best))
      rc = gs_error_set(err, GS_ENUMERIC, "the constrained fit (COBYLA) failed (NLopt result %d)",
                        (int)st);
  }
  if (!rc && !isfinite(ec.pc.best)) {
    if (fc->err.code && ec.pc.failed == fc->runs) {
      *err = fc->err;
      rc = gs_error_prefix(err, "the constrained fit: every run failed; the first: ");
    } else {
      rc = gs_error_set(err, GS_ENUMERIC,
                        "--porosity-tol %g: no point found whose porosity RMS error is at most "
                        "%g (%ld runs): the bound is below what the parameters reach",
                        eps, eps, fc->runs);
    }
  }
  if (!rc) {
    memcpy(u, ec.pc.best_u, p * sizeof *u);
    eval_eps(&ec, u);
    *rms_porosity = ec.rms;
  }
  if (o) nlopt_destroy(o);
  free(ec.pc.r);
  free(ec.pc.model);
  free(ec.pc.best_u);
  free(ec.last_u);
  return rc;
}
