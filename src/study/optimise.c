/* Optimising case controls against a target: GSL's Nelder-Mead simplex over
 * logistic-bounded controls, or NLopt's BOBYQA inside the box (see
 * gransim/study.h).  The model is fit's: outputs at the target's times as
 * residuals scaled by each column's RMS. */
#include "gransim/study.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <gsl/gsl_errno.h>
#include <gsl/gsl_multimin.h>
#include <nlopt.h>

#include "study/study_internal.h"

typedef struct {
  gs_fit_problem fp;
  gs_fit_batches bs; /* one batch borrowing the target */
  const double *weights;
  double *r;   /* residuals of one run */
  double best; /* the least objective seen, and where */
  double *best_x;
  long max_runs;
  long failed; /* runs that failed */
} opt_ctx;

/* The objective of a failed run: far above any real one but finite, since
 * both minimisers give up on inf or nan; the step is simply not taken. */
#define FAILED_RUN 1e100

/* The weighted sum of squares at control values x; NAN (and oc->fp.err)
 * when the run fails, which both methods treat as a step to avoid. */
static double objective(opt_ctx *oc, const double *x) {
  gs_error e = {0};
  oc->fp.runs++;
  if (gs_fit_problem_residuals(&oc->fp, x, oc->r, NULL, &e)) {
    if (!oc->fp.err.code) oc->fp.err = e;
    oc->failed++;
    return NAN;
  }
  const gs_fit_data *d = &oc->fp.bs->batch[0].data;
  double sum = 0;
  for (size_t t = 0; t < d->ntimes; t++)
    for (size_t j = 0; j < d->ncols; j++)
      sum += (oc->weights ? oc->weights[j] : 1) * pow(oc->r[t * d->ncols + j], 2);
  /* kept apart from the minimiser's own state: both report the best point
   * they hold, but a run cut at max_runs should still give the best seen */
  if (sum < oc->best) {
    oc->best = sum;
    memcpy(oc->best_x, x, oc->fp.np * sizeof *x);
  }
  return sum;
}

static double nm_f(const gsl_vector *z, void *params) {
  opt_ctx *oc = params;
  double x[64];
  for (size_t k = 0; k < oc->fp.np; k++) x[k] = gs_study_to_x(&oc->fp.params[k], z->data[k], NULL);
  double f = objective(oc, x);
  return isfinite(f) ? f : FAILED_RUN; /* the simplex shrinks away from a failed run */
}

/* Nelder & Mead (1965) as GSL's nmsimplex2 in z, x = logistic(z) on each
 * range: unconstrained steps, every trial a valid case. */
static int run_nelder_mead(opt_ctx *oc, const double *x0, double tol, int *converged, const char **stop,
                           gs_error *err) {
  const size_t n = oc->fp.np;
  gsl_multimin_fminimizer *s = gsl_multimin_fminimizer_alloc(gsl_multimin_fminimizer_nmsimplex2, n);
  gsl_vector *z = gsl_vector_alloc(n), *step = gsl_vector_alloc(n);
  if (!s || !z || !step) {
    if (s) gsl_multimin_fminimizer_free(s);
    if (z) gsl_vector_free(z);
    if (step) gsl_vector_free(step);
    return gs_error_set(err, GS_ENOMEM, "out of memory");
  }
  for (size_t k = 0; k < n; k++) {
    gsl_vector_set(z, k, gs_study_to_z(&oc->fp.params[k], x0[k]));
    gsl_vector_set(step, k, 1.0); /* the logistic's own scale: a quarter of the range at the middle */
  }
  gsl_multimin_function f = {.f = nm_f, .n = n, .params = oc};
  int st = gsl_multimin_fminimizer_set(s, &f, z, step);
  *stop = "stopped at its run limit";
  while (!st && oc->fp.runs < oc->max_runs) {
    st = gsl_multimin_fminimizer_iterate(s);
    if (st) break;
    /* the simplex's size in z is about its size in units of the range near
     * the middle (dx/dz = range/4 there), tol in those units */
    if (gsl_multimin_test_size(gsl_multimin_fminimizer_size(s), 4 * tol) == GSL_SUCCESS) {
      *converged = 1;
      *stop = "converged";
      break;
    }
  }
  gsl_multimin_fminimizer_free(s);
  gsl_vector_free(z);
  gsl_vector_free(step);
  if (st && gs_gsl_reason()[0]) return gs_gsl_error(err, GS_ENUMERIC, "the simplex failed (gsl_multimin nmsimplex2)");
  if (st) return gs_error_set(err, GS_ENUMERIC, "the simplex failed: %s", gsl_strerror(st));
  return GS_OK;
}

static double bobyqa_f(unsigned n, const double *u, double *grad, void *data) {
  (void)grad; /* derivative-free */
  opt_ctx *oc = data;
  double x[64];
  for (unsigned k = 0; k < n; k++) x[k] = gs_study_axis_value(&oc->fp.params[k], u[k]);
  double f = objective(oc, x);
  return isfinite(f) ? f : FAILED_RUN;
}

/* Powell's (2009) BOBYQA from NLopt: quadratic models inside the box, each
 * range mapped onto [0,1] (in log for log ranges) so that the trust region
 * sees every control at one scale. */
static int run_bobyqa(opt_ctx *oc, const double *x0, double tol, int *converged, const char **stop,
                      gs_error *err) {
  const unsigned n = (unsigned)oc->fp.np;
  nlopt_opt o = nlopt_create(NLOPT_LN_BOBYQA, n);
  if (!o) return gs_error_set(err, GS_ENOMEM, "out of memory");
  double u[64], lo[64], hi[64];
  for (unsigned k = 0; k < n; k++) {
    const gs_study_axis *a = &oc->fp.params[k];
    u[k] = a->log ? log(x0[k] / a->lo) / log(a->hi / a->lo) : (x0[k] - a->lo) / (a->hi - a->lo);
    lo[k] = 0;
    hi[k] = 1;
  }
  nlopt_set_lower_bounds(o, lo);
  nlopt_set_upper_bounds(o, hi);
  nlopt_set_min_objective(o, bobyqa_f, oc);
  nlopt_set_xtol_abs1(o, tol);
  nlopt_set_maxeval(o, (int)(oc->max_runs - oc->fp.runs));
  nlopt_set_initial_step1(o, 0.1);
  double f;
  nlopt_result st = nlopt_optimize(o, u, &f);
  nlopt_destroy(o);
  *converged = st == NLOPT_XTOL_REACHED || st == NLOPT_FTOL_REACHED || st == NLOPT_STOPVAL_REACHED ||
               st == NLOPT_SUCCESS;
  /* NLOPT_SUCCESS is NLopt's generic success (BOBYQA's trust region at its
   * final radius); round-off limited: it cannot shrink further in floating
   * point, short of the step tolerance but not at the run limit */
  *stop = st == NLOPT_SUCCESS            ? "converged (NLopt: success)"
          : *converged                   ? "converged"
          : st == NLOPT_ROUNDOFF_LIMITED ? "stopped by round-off (NLopt), before its run limit"
          : st == NLOPT_MAXEVAL_REACHED  ? "stopped at its run limit"
                                         : "stopped by NLopt before its run limit";
  if (st < 0 && st != NLOPT_ROUNDOFF_LIMITED)
    return gs_error_set(err, GS_ENUMERIC, "BOBYQA failed (NLopt result %d)", (int)st);
  return GS_OK;
}

void gs_opt_result_free(gs_opt_result *r) {
  if (!r) return;
  free(r->x);
  memset(r, 0, sizeof *r);
}

int gs_optimise_run(const gs_cfg *base, const gs_study_axis *controls, size_t nc,
                    const gs_fit_data *target, const gs_opt_options *opt, gs_opt_result *res,
                    gs_error *err) {
  memset(res, 0, sizeof *res);
  if (nc < 1 || nc > 64) return gs_error_set(err, GS_EINPUT, "optimise 1 to 64 controls (got %zu)", nc);
  for (size_t k = 0; k < nc; k++)
    if (controls[k].values || !(controls[k].lo < controls[k].hi))
      return gs_error_set(err, GS_EINPUT, "--controls %s: expected a range KEY=LO:HI with LO < HI",
                          controls[k].key);
  for (size_t j = 0; opt->weights && j < target->ncols; j++)
    if (!(opt->weights[j] >= 0) || !isfinite(opt->weights[j]))
      return gs_error_set(err, GS_EINPUT, "weight of target column '%s' must be >= 0, got %g",
                          target->names[j], opt->weights[j]);
  if (opt->method != GS_OPT_NELDER_MEAD && opt->method != GS_OPT_BOUNDED)
    return gs_error_set(err, GS_EINPUT, "unknown optimisation method %d", (int)opt->method);
  opt_ctx oc = {.weights = opt->weights, .best = INFINITY,
                .max_runs = opt->max_runs ? (long)opt->max_runs : 4000};
  double x0[64];
  gs_fit_batch batch = {.name = "target", .where = target->path ? target->path : "target",
                        .data = *target};
  oc.bs = (gs_fit_batches){.n = 1, .batch = &batch};
  int rc = gs_fit_problem_init(&oc.fp, base, controls, nc, &oc.bs, x0, err);
  if (rc) return rc;
  oc.r = malloc(target->ntimes * target->ncols * sizeof *oc.r);
  oc.best_x = malloc(nc * sizeof *oc.best_x);
  res->x = malloc(nc * sizeof *res->x);
  if (!oc.r || !oc.best_x || !res->x) rc = gs_error_set(err, GS_ENOMEM, "out of memory");
  gs_gsl_clear(); /* GSL's reason is kept by libgransim's handler (src/core/error.c) */
  const double tol = opt->tol > 0 ? opt->tol : 1e-9;
  if (!rc) {
    res->start_objective = objective(&oc, x0);
    if (!isfinite(res->start_objective)) {
      *err = oc.fp.err;
      rc = gs_error_prefix(err, "the start: ");
    }
  }
  if (!rc)
    rc = opt->method == GS_OPT_NELDER_MEAD ? run_nelder_mead(&oc, x0, tol, &res->converged, &res->stop, err)
                                           : run_bobyqa(&oc, x0, tol, &res->converged, &res->stop, err);
  if (!rc) {
    res->ncontrols = nc;
    memcpy(res->x, oc.best_x, nc * sizeof *res->x);
    res->objective = oc.best;
    res->runs = oc.fp.runs;
    res->failed_runs = oc.failed;
    if (oc.failed) res->first_failure = oc.fp.err;
  } else {
    gs_opt_result_free(res);
  }
  free(oc.r);
  free(oc.best_x);
  gs_fit_problem_free(&oc.fp);
  return rc;
}
