/* Fitting case parameters to measured summary quantities with GSL's
 * nonlinear least squares (see gransim/study.h). */
#include "gransim/study.h"

#include <errno.h>
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <gsl/gsl_blas.h>
#include <gsl/gsl_errno.h>
#include <gsl/gsl_multifit_nlinear.h>

#include "gransim/run.h"
#include "study/study_internal.h"

/* ---- measured data ------------------------------------------------------- */

void gs_fit_data_free(gs_fit_data *d) {
  if (!d) return;
  for (size_t j = 0; d->names && j < d->ncols; j++) free(d->names[j]);
  free(d->names);
  free(d->times);
  free(d->values);
  memset(d, 0, sizeof *d);
}

/* Fields of one CSV line (no quoting: the data are numbers and plain names). */
static size_t split_fields(char *line, char **field, size_t max) {
  size_t n = 0;
  line[strcspn(line, "\r\n")] = '\0';
  for (char *p = line; n < max;) {
    field[n++] = p;
    p = strchr(p, ',');
    if (!p) break;
    *p++ = '\0';
  }
  return n;
}

/* A header field without its unit: summary.csv writes "d50 [m]", and data
 * taken from it may keep the units. */
static void strip_unit(char *f) {
  size_t n = strlen(f);
  char *b = n && f[n - 1] == ']' ? strstr(f, " [") : NULL;
  if (b) *b = '\0';
}

int gs_fit_data_read(const char *path, gs_fit_data *d, gs_error *err) {
  memset(d, 0, sizeof *d);
  FILE *f = fopen(path, "r");
  if (!f) return gs_error_set(err, GS_EIO, "cannot read data file '%s': %s", path, strerror(errno));
  char *line = NULL, *field[256];
  size_t cap = 0, lineno = 0, nf;
  int rc = GS_OK;
  while (!rc && getline(&line, &cap, f) > 0) {
    lineno++;
    if (line[0] == '#' || line[strspn(line, " \t\r\n")] == '\0') continue;
    nf = split_fields(line, field, 256);
    if (!d->names) { /* the header: time, then the measured columns */
      for (size_t j = 0; j < nf; j++) strip_unit(field[j]);
      if (nf < 2 || strcmp(field[0], "time")) {
        rc = gs_error_set(err, GS_EINPUT,
                          "%s:%zu: expected a header 'time,NAME,...' (e.g. time,M0,d50_c1)", path,
                          lineno);
        break;
      }
      d->ncols = nf - 1;
      d->names = calloc(d->ncols, sizeof *d->names);
      for (size_t j = 0; d->names && j < d->ncols; j++) d->names[j] = strdup(field[j + 1]);
      if (!d->names) rc = gs_error_set(err, GS_ENOMEM, "out of memory");
      continue;
    }
    if (nf != d->ncols + 1) {
      rc = gs_error_set(err, GS_EINPUT, "%s:%zu: %zu fields, the header has %zu", path, lineno, nf,
                        d->ncols + 1);
      break;
    }
    double *t = realloc(d->times, (d->ntimes + 1) * sizeof *t);
    if (t) d->times = t;
    double *v = realloc(d->values, (d->ntimes + 1) * d->ncols * sizeof *v);
    if (v) d->values = v;
    if (!t || !v) {
      rc = gs_error_set(err, GS_ENOMEM, "out of memory");
      break;
    }
    for (size_t j = 0; j <= d->ncols && !rc; j++) {
      char *end;
      double x = strtod(field[j], &end);
      if (end == field[j] || *end || !isfinite(x))
        rc = gs_error_set(err, GS_EINPUT, "%s:%zu: column %s = '%s': expected a finite number",
                          path, lineno, j ? d->names[j - 1] : "time", field[j]);
      else if (j == 0) d->times[d->ntimes] = x;
      else d->values[d->ntimes * d->ncols + j - 1] = x;
    }
    d->ntimes++;
  }
  free(line);
  fclose(f);
  if (!rc && !d->ntimes) rc = gs_error_set(err, GS_EINPUT, "%s: no data rows", path);
  if (rc) gs_fit_data_free(d);
  return rc;
}

/* ---- the model as residuals of transformed parameters ---------------------- */


/* Records the outputs at the data's times. */
typedef struct {
  const gs_fit_problem *fc;
  const gs_case *c;
  double *rows; /* ntimes x out.ncol */
  char *seen;
} fit_obs;

static int fit_obs_output(void *self, const gs_run_view *run, double t, const double *Y, int *stop,
                          gs_error *err) {
  (void)run, (void)stop, (void)err;
  fit_obs *o = self;
  const gs_fit_data *d = o->fc->data;
  for (size_t i = 0; i < d->ntimes; i++)
    if (fabs(t - d->times[i]) <= 1e-12 * fmax(1, fabs(t))) {
      gs_study_outputs_eval(&o->fc->out, &o->c->model, t, Y, o->rows + i * o->fc->out.ncol);
      o->seen[i] = 1;
    }
  return GS_OK;
}

static const gs_observer_type fit_obs_type = {.name = "fit", .output = fit_obs_output};

int gs_fit_problem_residuals(gs_fit_problem *fc, const double *x, double *r, gs_error *err) {
  gs_design d = {.nkeys = fc->np, .nruns = 1};
  char *keys[64], *values[64], text[64][40];
  for (size_t k = 0; k < fc->np; k++) {
    keys[k] = fc->params[k].key;
    snprintf(text[k], sizeof text[k], "%.17g", x[k]);
    values[k] = text[k];
  }
  d.keys = keys;
  d.values = values;
  gs_case c;
  const gs_fit_data *data = fc->data;
  fit_obs obs = {.fc = fc, .c = &c};
  obs.rows = calloc(data->ntimes * fc->out.ncol, sizeof *obs.rows);
  obs.seen = calloc(data->ntimes, 1);
  int rc = obs.rows && obs.seen ? gs_study_case(fc->base, &d, 0, &c, err)
                                : gs_error_set(err, GS_ENOMEM, "out of memory");
  if (!rc) {
    gs_observer ob = {.type = &fit_obs_type, .self = &obs};
    gs_run_options opt = {.progress = 0, .observers = &ob, .nobservers = 1};
    gs_run_report rep;
    rc = gs_case_run(&c, &opt, NULL, &rep, err);
    gs_case_free(&c);
  }
  for (size_t i = 0; !rc && i < data->ntimes; i++) {
    if (!obs.seen[i]) {
      rc = gs_error_set(err, GS_EINPUT,
                        "data time %g is not an output time of the case: list the data's times "
                        "in output.times",
                        data->times[i]);
      break;
    }
    for (size_t j = 0; j < data->ncols; j++)
      r[i * data->ncols + j] =
          (obs.rows[i * fc->out.ncol + fc->col[j]] - data->values[i * data->ncols + j]) /
          fc->scale[j];
  }
  if (rc) {
    char what[512] = "";
    for (size_t k = 0, at = 0; k < fc->np && at < sizeof what; k++)
      at += (size_t)snprintf(what + at, sizeof what - at, "%s%s=%s", k ? ", " : "", keys[k], values[k]);
    gs_error_prefix(err, "the model at %s: ", what);
  }
  free(obs.rows);
  free(obs.seen);
  return rc;
}

static int fit_f(const gsl_vector *z, void *params, gsl_vector *f) {
  gs_fit_problem *fc = params;
  fc->runs++;
  double x[64];
  for (size_t k = 0; k < fc->np; k++) x[k] = gs_study_to_x(&fc->params[k], z->data[k], NULL);
  if (gs_fit_problem_residuals(fc, x, f->data, &fc->err)) return GSL_EBADFUNC;
  return GSL_SUCCESS;
}

/* Forward differences, the p perturbed runs at once on the threads (each
 * run single-threaded): a Jacobian costs one run's time on p cores. */
static int fit_df(const gsl_vector *z, void *params, gsl_matrix *J) {
  gs_fit_problem *fc = params;
  const size_t n = J->size1, p = fc->np;
  double *f0 = malloc(n * (p + 1) * sizeof *f0);
  if (!f0) return GSL_ENOMEM;
  int failed = 0;
#pragma omp parallel for schedule(dynamic, 1)
  for (size_t j = 0; j <= p; j++) {
    double x[64];
    for (size_t k = 0; k < p; k++) {
      const double zk = z->data[k], h = j == k + 1 ? 1e-6 * (1 + fabs(zk)) : 0;
      x[k] = gs_study_to_x(&fc->params[k], zk + h, NULL);
    }
    gs_error e = {0};
    if (gs_fit_problem_residuals(fc, x, f0 + j * n, &e)) {
#pragma omp critical(gs_fit_error)
      if (!failed++) fc->err = e;
    }
  }
  fc->runs += (long)p + 1;
  for (size_t j = 1; j <= p && !failed; j++) {
    double h = 1e-6 * (1 + fabs(z->data[j - 1]));
    for (size_t i = 0; i < n; i++) gsl_matrix_set(J, i, j - 1, (f0[j * n + i] - f0[i]) / h);
  }
  free(f0);
  return failed ? GSL_EBADFUNC : GSL_SUCCESS;
}

void gs_fit_problem_free(gs_fit_problem *fc) {
  free(fc->col);
  free(fc->scale);
  gs_study_outputs_free(&fc->out);
  memset(fc, 0, sizeof *fc);
}

int gs_fit_problem_init(gs_fit_problem *fc, const gs_cfg *base, const gs_study_axis *params,
                        size_t np, const gs_fit_data *data, double *x0, gs_error *err) {
  memset(fc, 0, sizeof *fc);
  *fc = (gs_fit_problem){.base = base, .params = params, .np = np, .data = data};
  /* the start: the case's own values where they lie inside the ranges */
  gs_cfg *probe = gs_cfg_copy(base, err);
  if (!probe) return err->code;
  int rc = GS_OK;
  for (size_t k = 0; k < np && !rc; k++) {
    gs_cfg_node *node = gs_cfg_find(probe, params[k].key, err);
    double x;
    if (!node || gs_cfg_kind_of(node) != GS_CFG_SCALAR)
      rc = node ? gs_error_set(err, GS_EINPUT, "key '%s' is not a single value", params[k].key)
                : GS_EINPUT;
    else if (gs_cfg_node_double(node, &x, err)) rc = gs_error_prefix(err, "key '%s': ", params[k].key);
    else x0[k] = x > params[k].lo && x < params[k].hi ? x : gs_study_axis_value(&params[k], 0.5);
  }
  gs_cfg_free(probe);
  if (rc) return rc;
  /* output columns named by the data */
  gs_design d0 = {.nkeys = 0, .nruns = 1};
  gs_case c;
  if ((rc = gs_study_case(base, &d0, 0, &c, err))) return rc;
  gs_study_extras extra;
  gs_study_extras_all(&c.model, &extra);
  rc = gs_study_outputs_init(&fc->out, &c.model, extra.name, extra.n, err);
  gs_case_free(&c);
  if (rc) return rc;
  fc->col = calloc(data->ncols, sizeof *fc->col);
  double *scale = fc->scale = calloc(data->ncols, sizeof *scale);
  if (!fc->col || !scale) rc = gs_error_set(err, GS_ENOMEM, "out of memory");
  for (size_t j = 0; j < data->ncols && !rc; j++) {
    if ((rc = gs_study_outputs_find(&fc->out, data->names[j], "data column", &fc->col[j], err)))
      break;
    /* columns of different units weigh alike: each scaled by its RMS */
    double s = 0;
    for (size_t t = 0; t < data->ntimes; t++) s += pow(data->values[t * data->ncols + j], 2);
    scale[j] = s > 0 ? sqrt(s / (double)data->ntimes) : 1;
  }
  if (rc) gs_fit_problem_free(fc);
  return rc;
}

void gs_fit_result_free(gs_fit_result *r) {
  if (!r) return;
  free(r->x);
  free(r->stderr_x);
  free(r->corr);
  memset(r, 0, sizeof *r);
}

int gs_fit_run(const gs_cfg *base, const gs_study_axis *params, size_t np,
               const gs_fit_data *data, gs_fit_result *res, gs_error *err) {
  memset(res, 0, sizeof *res);
  const size_t n = data->ntimes * data->ncols;
  if (np < 1 || np > 64) return gs_error_set(err, GS_EINPUT, "fit 1 to 64 parameters (got %zu)", np);
  for (size_t k = 0; k < np; k++)
    if (params[k].values)
      return gs_error_set(err, GS_EINPUT, "--params %s: expected a range KEY=LO:HI", params[k].key);
  if (n <= np)
    return gs_error_set(err, GS_EINPUT, "%zu measured values for %zu parameters: need more values",
                        n, np);
  gs_fit_problem fc;
  double z0[64];
  int rc = gs_fit_problem_init(&fc, base, params, np, data, z0, err);
  if (rc) return rc;
  for (size_t k = 0; k < np; k++) z0[k] = gs_study_to_z(&params[k], z0[k]);
  const double *scale = fc.scale;

  gsl_multifit_nlinear_workspace *w = NULL;
  gsl_vector *zv = gsl_vector_alloc(np);
  gsl_matrix *covar = gsl_matrix_alloc(np, np);
  /* a GSL failure is recorded by libgransim's handler (src/core/error.c)
   * and reported with its reason: in a run, by the run's error; in the
   * solver, below */
  gs_gsl_clear();
  omp_set_max_active_levels(1);
  if (!rc) {
    gsl_multifit_nlinear_parameters fp = gsl_multifit_nlinear_default_parameters();
    w = gsl_multifit_nlinear_alloc(gsl_multifit_nlinear_trust, &fp, n, np);
    gsl_multifit_nlinear_fdf fdf = {.f = fit_f, .df = fit_df, .n = n, .p = np, .params = &fc};
    for (size_t k = 0; k < np; k++) gsl_vector_set(zv, k, z0[k]);
    int info = 0, st = w ? gsl_multifit_nlinear_init(zv, &fdf, w) : GSL_ENOMEM;
    if (!st) st = gsl_multifit_nlinear_driver(200, 1e-12, 1e-12, 1e-14, NULL, NULL, &info, w);
    if (fc.err.code) {
      *err = fc.err;
      rc = err->code;
    } else if (st && st != GSL_EMAXITER && st != GSL_ENOPROG) {
      rc = gs_gsl_reason()[0] ? gs_gsl_error(err, GS_ENUMERIC, "the fit failed (gsl_multifit_nlinear)")
                              : gs_error_set(err, GS_ENUMERIC, "the fit failed: %s", gsl_strerror(st));
    } else {
      res->converged = st == GSL_SUCCESS;
      res->iterations = gsl_multifit_nlinear_niter(w);
    }
  }
  if (!rc) {
    const gsl_vector *z = gsl_multifit_nlinear_position(w), *f = gsl_multifit_nlinear_residual(w);
    double chi2;
    gsl_blas_ddot(f, f, &chi2);
    gsl_multifit_nlinear_covar(gsl_multifit_nlinear_jac(w), 0.0, covar);
    const double s2 = chi2 / (double)(n - np);
    res->nparams = np;
    res->nresid = n;
    res->x = malloc(np * sizeof *res->x);
    res->stderr_x = malloc(np * sizeof *res->stderr_x);
    res->corr = malloc(np * np * sizeof *res->corr);
    for (size_t k = 0; k < np; k++) {
      double dxdz;
      res->x[k] = gs_study_to_x(&params[k], gsl_vector_get(z, k), &dxdz);
      /* the delta method: the covariance of z carried to x by dx/dz */
      res->stderr_x[k] = fabs(dxdz) * sqrt(s2 * gsl_matrix_get(covar, k, k));
      for (size_t q = 0; q < np; q++)
        res->corr[k * np + q] = gsl_matrix_get(covar, k, q) /
                                sqrt(gsl_matrix_get(covar, k, k) * gsl_matrix_get(covar, q, q));
    }
    /* R² of the scaled values against each column's mean */
    double sst = 0;
    for (size_t j = 0; j < data->ncols; j++) {
      double mean = 0;
      for (size_t t = 0; t < data->ntimes; t++) mean += data->values[t * data->ncols + j];
      mean /= (double)data->ntimes;
      for (size_t t = 0; t < data->ntimes; t++)
        sst += pow((data->values[t * data->ncols + j] - mean) / scale[j], 2);
    }
    res->chi2 = chi2;
    res->r2 = sst > 0 ? 1 - chi2 / sst : NAN;
    res->runs = fc.runs;
  }
  if (w) gsl_multifit_nlinear_free(w);
  gsl_vector_free(zv);
  gsl_matrix_free(covar);
  gs_fit_problem_free(&fc);
  return rc;
}
