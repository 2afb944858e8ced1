/* Fitting case parameters to measured batches with GSL's nonlinear least
 * squares (see gransim/study.h); the residuals are fit_problem.c's. */
#include "gransim/study.h"

#include <errno.h>
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <gsl/gsl_blas.h>
#include <gsl/gsl_cdf.h>
#include <gsl/gsl_errno.h>
#include <gsl/gsl_multifit_nlinear.h>

#include "gransim/run.h"
#include "study/study_internal.h"

#include <gsl/gsl_linalg.h>

static int fit_f(const gsl_vector *z, void *params, gsl_vector *f) {
  gs_fit_problem *fc = params;
  fc->runs++;
  double x[64];
  for (size_t k = 0; k < fc->np; k++) x[k] = gs_study_to_x(&fc->params[k], z->data[k], NULL);
  if (gs_fit_problem_residuals(fc, x, f->data, NULL, &fc->err)) return GSL_EBADFUNC;
  return GSL_SUCCESS;
}

/* Forward differences at v (in z, the logistic map's variable, or in u, the
 * fraction of each range), the p perturbed runs at once on the threads
 * (each run single-threaded): a Jacobian costs one run's time on p cores.
 * In u the steps go inwards, so that a parameter at its bound still has
 * a column. */
static int fd_jacobian(gs_fit_problem *fc, const double *v, int in_u, gsl_matrix *J, double *f) {
  const size_t n = J->size1, p = fc->np;
  double *f0 = malloc(n * (p + 1) * sizeof *f0), h[64];
  if (!f0) return GSL_ENOMEM;
  for (size_t k = 0; k < p; k++) h[k] = in_u ? (v[k] > 0.5 ? -1e-5 : 1e-5) : 1e-6 * (1 + fabs(v[k]));
  int failed = 0;
#pragma omp parallel for schedule(dynamic, 1)
  for (size_t j = 0; j <= p; j++) {
    double x[64];
    for (size_t k = 0; k < p; k++) {
      const double vk = v[k] + (j == k + 1 ? h[k] : 0);
      x[k] = in_u ? gs_study_axis_value(&fc->params[k], vk) : gs_study_to_x(&fc->params[k], vk, NULL);
    }
    gs_error e = {0};
    if (gs_fit_problem_residuals(fc, x, f0 + j * n, NULL, &e)) {
#pragma omp critical(gs_fit_error)
      if (!failed++) fc->err = e;
    }
  }
  fc->runs += (long)p + 1;
  for (size_t j = 1; j <= p && !failed; j++)
    for (size_t i = 0; i < n; i++) gsl_matrix_set(J, i, j - 1, (f0[j * n + i] - f0[i]) / h[j - 1]);
  if (f && !failed) memcpy(f, f0, n * sizeof *f);
  free(f0);
  return failed ? GSL_EBADFUNC : GSL_SUCCESS;
}

static int fit_df(const gsl_vector *z, void *params, gsl_matrix *J) {
  return fd_jacobian(params, z->data, 0, J, NULL);
}

/* u of x: the fraction of the range (of log(value) for log ranges) and dx/du. */
static double to_u(const gs_study_axis *a, double x, double *dxdu) {
  if (a->log) {
    *dxdu = x * log(a->hi / a->lo);
    return log(x / a->lo) / log(a->hi / a->lo);
  }
  *dxdu = a->hi - a->lo;
  return (x - a->lo) / (a->hi - a->lo);
}

void gs_fit_result_free(gs_fit_result *r) {
  if (!r) return;
  free(r->x);
  free(r->stderr_x);
  free(r->ci_lo);
  free(r->ci_hi);
  free(r->corr);
  free(r->sv);
  free(r->unidentified);
  memset(r, 0, sizeof *r);
}

/* Identifiability from the singular values of J_u, the Jacobian in u
 * (each parameter's fraction of its range, of log(value) for log ranges):
 * a direction whose singular value is below GS_FIT_IDENT_TOL of the
 * largest moves the scaled residuals by less than a thousandth of what the
 * best-determined direction does, so the data cannot fix it; every
 * parameter with a component above 0.1 in such a direction is reported. */
#define GS_FIT_IDENT_TOL 1e-3
static int identifiability(const gsl_matrix *Ju, gs_fit_result *res) {
  const size_t n = Ju->size1, p = Ju->size2;
  gsl_matrix *A = gsl_matrix_alloc(n, p), *V = gsl_matrix_alloc(p, p);
  gsl_vector *S = gsl_vector_alloc(p), *work = gsl_vector_alloc(p);
  res->sv = calloc(p, sizeof *res->sv);
  res->unidentified = calloc(p, sizeof *res->unidentified);
  int ok = A && V && S && work && res->sv && res->unidentified;
  if (ok) {
    gsl_matrix_memcpy(A, Ju);
    ok = !gsl_linalg_SV_decomp(A, V, S, work);
  }
  if (ok) {
    const double smax = gsl_vector_get(S, 0);
    for (size_t i = 0; i < p; i++) {
      res->sv[i] = gsl_vector_get(S, i);
      if (res->sv[i] > GS_FIT_IDENT_TOL * smax) continue;
      for (size_t k = 0; k < p; k++)
        if (fabs(gsl_matrix_get(V, k, i)) > 0.1) res->unidentified[k] = 1;
    }
  }
  if (A) gsl_matrix_free(A);
  if (V) gsl_matrix_free(V);
  if (S) gsl_vector_free(S);
  if (work) gsl_vector_free(work);
  return ok ? GS_OK : GS_ENOMEM;
}

/* Levenberg-Marquardt from x (in the logistic map's z), x the solution. */
static int least_squares(gs_fit_problem *fc, double *x, gs_fit_result *res, gs_error *err) {
  const size_t n = fc->nresid, np = fc->np;
  gsl_vector *zv = gsl_vector_alloc(np);
  gsl_multifit_nlinear_parameters fp = gsl_multifit_nlinear_default_parameters();
  gsl_multifit_nlinear_workspace *w = gsl_multifit_nlinear_alloc(gsl_multifit_nlinear_trust, &fp, n, np);
  gsl_multifit_nlinear_fdf fdf = {.f = fit_f, .df = fit_df, .n = n, .p = np, .params = fc};
  for (size_t k = 0; zv && k < np; k++) gsl_vector_set(zv, k, gs_study_to_z(&fc->params[k], x[k]));
  int rc = GS_OK, info = 0, st = w && zv ? gsl_multifit_nlinear_init(zv, &fdf, w) : GSL_ENOMEM;
  if (!st) st = gsl_multifit_nlinear_driver(200, 1e-12, 1e-12, 1e-14, NULL, NULL, &info, w);
  if (fc->err.code) {
    *err = fc->err;
    rc = err->code;
  } else if (st && st != GSL_EMAXITER && st != GSL_ENOPROG) {
    rc = gs_gsl_reason()[0] ? gs_gsl_error(err, GS_ENUMERIC, "the fit failed (gsl_multifit_nlinear)")
                            : gs_error_set(err, GS_ENUMERIC, "the fit failed: %s", gsl_strerror(st));
  } else {
    res->converged = st == GSL_SUCCESS;
    res->iterations = gsl_multifit_nlinear_niter(w);
    const gsl_vector *z = gsl_multifit_nlinear_position(w);
    for (size_t k = 0; k < np; k++) x[k] = gs_study_to_x(&fc->params[k], gsl_vector_get(z, k), NULL);
  }
  if (w) gsl_multifit_nlinear_free(w);
  if (zv) gsl_vector_free(zv);
  return rc;
}

/* The porosity columns' RMS error in their unit from the scaled residuals
 * r; nan without porosity columns. */
static double porosity_rms(const gs_fit_problem *fc, const double *r) {
  double s = 0;
  size_t cnt = 0;
  for (size_t b = 0; b < fc->bs->n; b++) {
    const gs_fit_data *d = &fc->bs->batch[b].data;
    for (size_t i = 0; i < d->ntimes; i++)
      for (size_t j = 0; j < d->ncols; j++)
        if (fc->map[b].porosity[j]) {
          s += pow(r[fc->map[b].off + i * d->ncols + j] * fc->map[b].scale[j], 2);
          cnt++;
        }
  }
  return cnt ? sqrt(s / (double)cnt) : NAN;
}

/* The report at the estimates x: the Jacobian in u (p + 1 runs), chi², the
 * standard errors, intervals, correlations and identifiability. */
static int report(gs_fit_problem *fc, const double *x, gs_fit_result *res, gs_error *err) {
  const size_t n = fc->nresid, np = fc->np;
  gsl_matrix *Ju = gsl_matrix_alloc(n, np), *covar = gsl_matrix_alloc(np, np);
  double *f = malloc(n * sizeof *f), u[64], dxdu[64], chi2 = 0;
  res->nparams = np;
  res->nresid = n;
  res->x = malloc(np * sizeof *res->x);
  res->stderr_x = malloc(np * sizeof *res->stderr_x);
  res->corr = malloc(np * np * sizeof *res->corr);
  res->ci_lo = malloc(np * sizeof *res->ci_lo);
  res->ci_hi = malloc(np * sizeof *res->ci_hi);
  int rc = GS_OK;
  if (!Ju || !covar || !f || !res->x || !res->stderr_x || !res->corr || !res->ci_lo || !res->ci_hi)
    rc = gs_error_set(err, GS_ENOMEM, "out of memory");
  for (size_t k = 0; !rc && k < np; k++) {
    res->x[k] = x[k];
    u[k] = to_u(&fc->params[k], x[k], &dxdu[k]);
  }
  /* The Jacobian again, in u: the one in z vanishes where the logistic map
   * saturates (a parameter at its bound), and u is the scale at which
   * identifiability is judged. */
  if (!rc && fd_jacobian(fc, u, 1, Ju, f)) {
    *err = fc->err;
    rc = gs_error_prefix(err, "the Jacobian at the estimates: ");
  }
  if (!rc && identifiability(Ju, res)) rc = gs_error_set(err, GS_ENOMEM, "out of memory");
  if (!rc) {
    for (size_t i = 0; i < n; i++) chi2 += f[i] * f[i];
    gsl_multifit_nlinear_covar(Ju, 0.0, covar);
  }
  const double s2 = chi2 / (double)(n - np), tq = gsl_cdf_tdist_Pinv(0.975, (double)(n - np));
  for (size_t k = 0; !rc && k < np; k++) {
    /* s² (J_uᵀ J_u)⁻¹ carried to x by dx/du */
    res->stderr_x[k] = dxdu[k] * sqrt(s2 * gsl_matrix_get(covar, k, k));
    res->ci_lo[k] = res->x[k] - tq * res->stderr_x[k];
    res->ci_hi[k] = res->x[k] + tq * res->stderr_x[k];
    for (size_t q = 0; q < np; q++)
      res->corr[k * np + q] = gsl_matrix_get(covar, k, q) /
                              sqrt(gsl_matrix_get(covar, k, k) * gsl_matrix_get(covar, q, q));
  }
  if (!rc) {
    res->chi2 = chi2;
    res->r2 = gs_fit_problem_r2(fc, chi2);
    res->porosity_rms = porosity_rms(fc, f);
  }
  if (Ju) gsl_matrix_free(Ju);
  if (covar) gsl_matrix_free(covar);
  free(f);
  return rc;
}

int gs_fit_run_batches(const gs_cfg *base, const gs_study_axis *params, size_t np,
                       const gs_fit_batches *bs, const gs_fit_options *opt, gs_fit_result *res,
                       gs_error *err) {
  memset(res, 0, sizeof *res);
  const gs_fit_options none = {0};
  if (!opt) opt = &none;
  if (np < 1 || np > 64) return gs_error_set(err, GS_EINPUT, "fit 1 to 64 parameters (got %zu)", np);
  for (size_t k = 0; k < np; k++)
    if (params[k].values)
      return gs_error_set(err, GS_EINPUT, "--params %s: expected a range KEY=LO:HI", params[k].key);
  if (opt->global && gs_fit_global_check(opt->global, err)) return err->code;
  if (opt->porosity_tol < 0 || !isfinite(opt->porosity_tol))
    return gs_error_set(err, GS_EINPUT, "--porosity-tol %g: expected a number > 0", opt->porosity_tol);
  gs_fit_problem fc;
  double x[64], u[64], dxdu;
  int rc = gs_fit_problem_init(&fc, base, params, np, bs, x, err);
  if (rc) return rc;
  const size_t n = fc.nresid;
  if (n <= np) {
    gs_fit_problem_free(&fc);
    return gs_error_set(err, GS_EINPUT, "%zu measured values for %zu parameters: need more values",
                        n, np);
  }
  /* a GSL failure is recorded by libgransim's handler (src/core/error.c)
   * and reported with its reason */
  gs_gsl_clear();
  omp_set_max_active_levels(1);
  for (size_t k = 0; k < np; k++) u[k] = to_u(&params[k], x[k], &dxdu);
  if (opt->global) {
    rc = gs_fit_global_start(&fc, opt->global, opt->global_runs ? opt->global_runs : 50 * np,
                             opt->seed, u, err);
    res->global_runs = fc.runs;
    fc.err = (gs_error){0}; /* its failed runs were points not taken, not the fit's failure */
    /* the least squares' logistic map cannot start on a bound */
    for (size_t k = 0; !rc && k < np; k++)
      x[k] = gs_study_axis_value(&params[k], fmin(fmax(u[k], 1e-6), 1 - 1e-6));
  }
  if (!rc && opt->porosity_tol > 0) {
    double rms;
    rc = gs_fit_eps_constrained(&fc, opt->porosity_tol, opt->max_runs ? opt->max_runs : 2000, u,
                                &rms, err);
    for (size_t k = 0; !rc && k < np; k++) x[k] = gs_study_axis_value(&params[k], u[k]);
    res->converged = !rc;
    fc.err = (gs_error){0};
  } else if (!rc) {
    rc = least_squares(&fc, x, res, err);
  }
  if (!rc) rc = report(&fc, x, res, err);
  res->runs = fc.runs;
  gs_fit_problem_free(&fc);
  return rc;
}

int gs_fit_run(const gs_cfg *base, const gs_study_axis *params, size_t np,
               const gs_fit_data *data, gs_fit_result *res, gs_error *err) {
  /* one batch borrowing the data: nothing of it is freed here */
  gs_fit_batch b = {.name = "data", .where = data->path ? data->path : "data", .data = *data};
  gs_fit_batches bs = {.n = 1, .batch = &b};
  return gs_fit_run_batches(base, params, np, &bs, NULL, res, err);
}
