/* Global sensitivity: Sobol' indices by Saltelli sampling and Morris
 * screening, over any model given as a callback; for a case, the points run
 * as one sweep (see gransim/study.h). */
#include "gransim/study.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <gsl/gsl_qrng.h>
#include <gsl/gsl_randist.h>
#include <gsl/gsl_rng.h>
#include <gsl/gsl_sort.h>
#include <gsl/gsl_statistics_double.h>

#include "demdata/csv_meta.h"
#include "study/study_internal.h"

void gs_sens_result_free(gs_sens_result *r) {
  if (!r) return;
  double **all[] = {&r->s1, &r->s1_lo, &r->s1_hi, &r->st, &r->st_lo, &r->st_hi,
                    &r->mu, &r->mu_star, &r->sigma};
  for (size_t i = 0; i < sizeof all / sizeof *all; i++) free(*all[i]);
  for (size_t o = 0; r->unit && o < r->nout; o++) free(r->unit[o]);
  free(r->unit);
  memset(r, 0, sizeof *r);
}

/* The model at unit points u[n * k]: mapped onto the ranges, called once,
 * outputs checked finite (an index of nan helps nobody). */
static int eval_points(const gs_study_axis *axes, size_t k, size_t nout, gs_sens_model model,
                       void *ctx, const double *u, size_t n, double *y, gs_error *err) {
  double *x = gs_malloc(n * k * sizeof *x, err);
  if (!x) return GS_ENOMEM;
  for (size_t i = 0; i < n * k; i++) x[i] = gs_study_axis_value(&axes[i % k], u[i]);
  int rc = model(ctx, n, k, x, nout, y, err);
  for (size_t i = 0; !rc && i < n * nout; i++)
    if (!isfinite(y[i]))
      rc = gs_error_set(err, GS_ENUMERIC, "the model gave a non-finite output %zu at point %zu",
                        i % nout + 1, i / nout + 1);
  free(x);
  return rc;
}

/* First-order (Saltelli et al. 2010, eq. (b) of table 2) and total
 * (Jansen 1999) indices of key i from the N rows idx[] of the matrices
 * f(A), f(B), f(A_B^i), for output o; the variance and mean are of f(A) and
 * f(B) together. */
static void sobol_estimate(const double *y, size_t N, size_t k, size_t nout, size_t o,
                           const size_t *idx, double *s1, double *st) {
  /* rows: A = 0..N, B = N..2N, A_B^i = (2 + i) N .. */
#define Y(block, j) y[((block) * N + idx[j]) * nout + o]
  double mean = 0, var = 0;
  for (size_t j = 0; j < N; j++) mean += Y(0, j) + Y(1, j);
  mean /= (double)(2 * N);
  for (size_t j = 0; j < N; j++) var += pow(Y(0, j) - mean, 2) + pow(Y(1, j) - mean, 2);
  var /= (double)(2 * N - 1);
  for (size_t i = 0; i < k; i++) {
    double a = 0, b = 0;
    for (size_t j = 0; j < N; j++) {
      /* f(B) centred: the same expectation (f(A_B^i) - f(A) has mean 0) but
       * no variance from a mean far from 0 (a d50 of 1e-4 m +- 1 %) */
      a += (Y(1, j) - mean) * (Y(2 + i, j) - Y(0, j));
      b += pow(Y(0, j) - Y(2 + i, j), 2);
    }
    s1[i] = var > 0 ? a / (double)N / var : 0;
    st[i] = var > 0 ? b / (2.0 * (double)N) / var : 0;
  }
#undef Y
}

static int run_sobol(const gs_study_axis *axes, size_t k, size_t nout, gs_sens_model model,
                     void *ctx, const gs_sens_options *opt, gs_sens_result *res, gs_error *err) {
  const size_t N = opt->n, npts = N * (k + 2);
  const size_t nboot = opt->nboot ? opt->nboot : 500;
  double *u = gs_malloc(npts * k * sizeof *u, err), *y = gs_malloc(npts * nout * sizeof *y, err);
  double *bs1 = gs_malloc(nboot * k * sizeof *bs1, err), *bst = gs_malloc(nboot * k * sizeof *bst, err);
  size_t *idx = gs_malloc(N * sizeof *idx, err);
  gsl_qrng *q = gsl_qrng_alloc(gsl_qrng_sobol, (unsigned)(2 * k));
  gsl_rng *rng = gsl_rng_alloc(gsl_rng_mt19937);
  int rc = u && y && bs1 && bst && idx && q && rng ? GS_OK : gs_error_set(err, GS_ENOMEM, "out of memory");
  if (!rc) {
    /* A and B side by side from one 2k-dimensional Sobol' sequence (Saltelli
     * 2010), shifted at random modulo 1 by the seed so that the seed gives
     * another, equally even, sample (Cranley-Patterson rotation) */
    gsl_rng_set(rng, opt->seed);
    double shift[40], p[40];
    for (size_t d = 0; d < 2 * k; d++) shift[d] = gsl_rng_uniform(rng);
    for (size_t j = 0; j < N; j++) {
      gsl_qrng_get(q, p);
      for (size_t d = 0; d < 2 * k; d++) {
        double v = p[d] + shift[d];
        v -= floor(v);
        if (d < k) u[j * k + d] = v;                 /* A */
        else u[(N + j) * k + d - k] = v;             /* B */
      }
    }
    for (size_t i = 0; i < k; i++) /* A_B^i: A with column i from B */
      for (size_t j = 0; j < N; j++)
        for (size_t d = 0; d < k; d++)
          u[((2 + i) * N + j) * k + d] = u[((d == i ? N : 0) + j) * k + d];
    rc = eval_points(axes, k, nout, model, ctx, u, npts, y, err);
  }
  const size_t m = k * nout;
  res->s1 = rc ? NULL : gs_calloc(m, sizeof(double), err);
  res->st = res->s1 ? gs_calloc(m, sizeof(double), err) : NULL;
  res->s1_lo = res->st ? gs_calloc(m, sizeof(double), err) : NULL;
  res->s1_hi = res->s1_lo ? gs_calloc(m, sizeof(double), err) : NULL;
  res->st_lo = res->s1_hi ? gs_calloc(m, sizeof(double), err) : NULL;
  res->st_hi = res->st_lo ? gs_calloc(m, sizeof(double), err) : NULL;
  if (!rc && !res->st_hi) rc = GS_ENOMEM;
  const double conf = opt->conf > 0 ? opt->conf : 0.95;
  for (size_t o = 0; o < nout && !rc; o++) {
    for (size_t j = 0; j < N; j++) idx[j] = j;
    sobol_estimate(y, N, k, nout, o, idx, res->s1 + o * k, res->st + o * k);
    /* percentile bootstrap: the rows resampled with replacement (the seed's
     * stream goes on, so the same seed gives the same intervals) */
    for (size_t b = 0; b < nboot; b++) {
      for (size_t j = 0; j < N; j++) idx[j] = gsl_rng_uniform_int(rng, N);
      sobol_estimate(y, N, k, nout, o, idx, bs1 + b * k, bst + b * k);
    }
    for (size_t i = 0; i < k; i++) {
      gsl_sort(bs1 + i, k, nboot);
      gsl_sort(bst + i, k, nboot);
      res->s1_lo[o * k + i] = gsl_stats_quantile_from_sorted_data(bs1 + i, k, nboot, (1 - conf) / 2);
      res->s1_hi[o * k + i] = gsl_stats_quantile_from_sorted_data(bs1 + i, k, nboot, (1 + conf) / 2);
      res->st_lo[o * k + i] = gsl_stats_quantile_from_sorted_data(bst + i, k, nboot, (1 - conf) / 2);
      res->st_hi[o * k + i] = gsl_stats_quantile_from_sorted_data(bst + i, k, nboot, (1 + conf) / 2);
    }
  }
  res->runs = npts;
  res->conf = conf;
  free(u);
  free(y);
  free(bs1);
  free(bst);
  free(idx);
  if (q) gsl_qrng_free(q);
  if (rng) gsl_rng_free(rng);
  return rc;
}

/* Morris (1991): R trajectories of k + 1 points on a grid of p levels in
 * [0,1]^k, each step moving one key (in random order) by delta = p / (2 (p -
 * 1)) up or down; the elementary effect of key i is the step's change of
 * the output over its delta (per unit of the key's range). */
static int run_morris(const gs_study_axis *axes, size_t k, size_t nout, gs_sens_model model,
                      void *ctx, const gs_sens_options *opt, gs_sens_result *res, gs_error *err) {
  const size_t R = opt->n, npts = R * (k + 1);
  const int p = opt->levels ? opt->levels : 4;
  const double delta = p / (2.0 * (p - 1));
  double *u = gs_malloc(npts * k * sizeof *u, err), *y = gs_malloc(npts * nout * sizeof *y, err);
  double *ee = gs_malloc(R * sizeof *ee, err), *step = gs_malloc(R * k * sizeof *step, err);
  size_t *order = gs_malloc(R * k * sizeof *order, err);
  gsl_rng *rng = gsl_rng_alloc(gsl_rng_mt19937);
  int rc = u && y && ee && step && order && rng ? GS_OK : gs_error_set(err, GS_ENOMEM, "out of memory");
  if (!rc) {
    gsl_rng_set(rng, opt->seed);
    for (size_t t = 0; t < R; t++) {
      double *x0 = u + t * (k + 1) * k;
      for (size_t i = 0; i < k; i++) {
        /* levels below p/2 step up, the others down: both stay on the grid */
        unsigned long l = gsl_rng_uniform_int(rng, (unsigned long)p);
        x0[i] = (double)l / (p - 1);
        step[t * k + i] = l < (unsigned long)p / 2 ? delta : -delta;
        order[t * k + i] = i;
      }
      gsl_ran_shuffle(rng, order + t * k, k, sizeof *order);
      for (size_t s = 0; s < k; s++) {
        double *from = x0 + s * k, *to = from + k;
        memcpy(to, from, k * sizeof *to);
        size_t i = order[t * k + s];
        to[i] += step[t * k + i];
        if (to[i] < 0) to[i] = 0; /* rounding: the grid's ends exactly */
        if (to[i] > 1) to[i] = 1;
      }
    }
    rc = eval_points(axes, k, nout, model, ctx, u, npts, y, err);
  }
  const size_t m = k * nout;
  res->mu = rc ? NULL : gs_calloc(m, sizeof(double), err);
  res->mu_star = res->mu ? gs_calloc(m, sizeof(double), err) : NULL;
  res->sigma = res->mu_star ? gs_calloc(m, sizeof(double), err) : NULL;
  if (!rc && !res->sigma) rc = GS_ENOMEM;
  for (size_t o = 0; o < nout && !rc; o++)
    for (size_t i = 0; i < k; i++) {
      double abs_sum = 0;
      for (size_t t = 0; t < R; t++) {
        size_t s = 0;
        while (order[t * k + s] != i) s++;
        const size_t at = t * (k + 1) + s;
        ee[t] = (y[(at + 1) * nout + o] - y[at * nout + o]) / step[t * k + i];
        abs_sum += fabs(ee[t]);
      }
      res->mu[o * k + i] = gsl_stats_mean(ee, 1, R);
      res->mu_star[o * k + i] = abs_sum / (double)R;
      res->sigma[o * k + i] = gsl_stats_sd(ee, 1, R);
    }
  res->runs = npts;
  free(u);
  free(y);
  free(ee);
  free(step);
  free(order);
  if (rng) gsl_rng_free(rng);
  return rc;
}

int gs_sensitivity(const gs_study_axis *axes, size_t nin, size_t nout, gs_sens_model model,
                   void *ctx, const gs_sens_options *opt, gs_sens_result *res, gs_error *err) {
  memset(res, 0, sizeof *res);
  if (nin < 1) return gs_error_set(err, GS_EINPUT, "a sensitivity analysis needs at least one --range KEY=LO:HI");
  if (nout < 1) return gs_error_set(err, GS_EINPUT, "a sensitivity analysis needs at least one output");
  for (size_t k = 0; k < nin; k++)
    if (axes[k].values || !(axes[k].lo < axes[k].hi))
      return gs_error_set(err, GS_EINPUT, "key '%s': needs a range KEY=LO:HI with LO < HI", axes[k].key);
  res->method = opt->method;
  res->nin = nin;
  res->nout = nout;
  int rc;
  if (opt->method == GS_SENS_SOBOL) {
    if (opt->n < 16)
      return gs_error_set(err, GS_EINPUT, "sobol:N needs N >= 16 (got %zu); the indices' error "
                          "falls like 1/N, a few hundred is a start", opt->n);
    if (nin > 20)
      return gs_error_set(err, GS_EINPUT, "sobol: at most 20 keys (got %zu): the Sobol' sequence has 40 dimensions", nin);
    if (opt->conf < 0 || opt->conf >= 1)
      return gs_error_set(err, GS_EINPUT, "the interval level must lie in (0, 1), got %g", opt->conf);
    rc = run_sobol(axes, nin, nout, model, ctx, opt, res, err);
  } else if (opt->method == GS_SENS_MORRIS) {
    if (opt->n < 2)
      return gs_error_set(err, GS_EINPUT, "morris:R needs R >= 2 trajectories (got %zu) for sigma", opt->n);
    if (opt->levels && (opt->levels < 2 || opt->levels % 2))
      return gs_error_set(err, GS_EINPUT, "morris: the number of levels must be even and >= 2 (got %d)", opt->levels);
    rc = run_morris(axes, nin, nout, model, ctx, opt, res, err);
  } else {
    return gs_error_set(err, GS_EINPUT, "unknown sensitivity method %d", (int)opt->method);
  }
  if (rc) gs_sens_result_free(res);
  return rc;
}

/* ---- a case as the model: the points run as one sweep ------------------- */

typedef struct {
  const gs_cfg *base;
  const gs_study_axis *axes;
  const gs_sweep_options *sweep;
  gs_study_extras extra; /* every statistic, so that any column named is in sweep.csv */
  size_t ncol;           /* output columns of the sweep */
  size_t *col;           /* requested output -> sweep output column */
} case_ctx;

/* Reads the requested columns of DIR/sweep.csv: run,status,keys...,outputs...,error. */
static int read_sweep(const case_ctx *cc, size_t npoints, size_t nin, size_t nout, double *y,
                      gs_error *err) {
  char path[4096];
  snprintf(path, sizeof path, "%s/sweep.csv", cc->sweep->out_dir);
  FILE *f = fopen(path, "r");
  if (!f) return gs_error_set(err, GS_EIO, "cannot read '%s': %s", path, strerror(errno));
  char *line = NULL;
  size_t cap = 0, r = 0;
  const size_t nf = 2 + nin + cc->ncol;
  char **field = gs_malloc(nf * sizeof *field, err);
  int rc = field ? GS_OK : GS_ENOMEM;
  if (!rc && getline(&line, &cap, f) <= 0) rc = gs_error_set(err, GS_EIO, "'%s' is empty", path);
  while (!rc && getline(&line, &cap, f) > 0 && r < npoints) {
    size_t n = 0;
    line[strcspn(line, "\r\n")] = '\0';
    for (char *p = line; p && n < nf; n++) {
      field[n] = p;
      if ((p = strchr(p, ','))) *p++ = '\0';
    }
    if (n < nf || strcmp(field[1], "ok")) {
      /* the error field follows the outputs: the row's last, quoted */
      const char *msg = n == nf ? strchr(field[nf - 1] + strlen(field[nf - 1]) + 1, '"') : NULL;
      rc = gs_error_set(err, GS_ENUMERIC, "run %zu of the sweep failed%s%.400s: an index needs "
                        "every run (narrow the ranges; %s has all)", r + 1, msg ? ": " : "",
                        msg ? msg : "", path);
      break;
    }
    for (size_t o = 0; o < nout; o++) y[r * nout + o] = strtod(field[2 + nin + cc->col[o]], NULL);
    r++;
  }
  if (!rc && r != npoints)
    rc = gs_error_set(err, GS_EIO, "'%s' has %zu runs, expected %zu", path, r, npoints);
  free(field);
  free(line);
  fclose(f);
  return rc;
}

static int case_model(void *ctx, size_t npoints, size_t nin, const double *x, size_t nout,
                      double *y, gs_error *err) {
  case_ctx *cc = ctx;
  gs_design d;
  int rc = gs_design_values(cc->axes, nin, x, npoints, &d, err);
  if (rc) return rc;
  gs_sweep_options so = *cc->sweep;
  so.outputs = cc->extra.name;
  so.noutputs = cc->extra.n;
  gs_sweep_report rep;
  rc = gs_sweep_run(cc->base, &d, &so, &rep, err);
  gs_design_free(&d);
  return rc ? rc : read_sweep(cc, npoints, nin, nout, y, err);
}

int gs_sensitivity_case(const gs_cfg *base, const gs_study_axis *axes, size_t nin,
                        const char *const *outputs, size_t nout, const gs_sens_options *opt,
                        const gs_sweep_options *sweep, gs_sens_result *res, gs_error *err) {
  memset(res, 0, sizeof *res);
  if (!sweep->out_dir) return gs_error_set(err, GS_EINPUT, "a sensitivity analysis needs --out DIR");
  case_ctx cc = {.base = base, .axes = axes, .sweep = sweep};
  /* the keys and columns first: a typo is named before any run */
  gs_cfg *probe = gs_cfg_copy(base, err);
  if (!probe) return err->code ? err->code : GS_ENOMEM;
  int rc = GS_OK;
  for (size_t k = 0; k < nin && !rc; k++) {
    char v[40];
    snprintf(v, sizeof v, "%.17g", gs_study_axis_value(&axes[k], 0.5));
    if (axes[k].values) rc = gs_error_set(err, GS_EINPUT, "key '%s': needs a range KEY=LO:HI", axes[k].key);
    else rc = gs_cfg_set(probe, axes[k].key, v, err);
  }
  gs_cfg_free(probe);
  if (rc) return rc;
  gs_design d0 = {.nkeys = 0, .nruns = 1};
  gs_case c;
  if ((rc = gs_study_case(base, &d0, 0, &c, err))) return rc;
  gs_study_outputs o;
  gs_study_extras_all(&c.model, &cc.extra);
  rc = gs_study_outputs_init(&o, &c.model, cc.extra.name, cc.extra.n, err);
  gs_case_free(&c);
  if (rc) return rc;
  cc.ncol = o.ncol;
  cc.col = gs_calloc(nout ? nout : 1, sizeof *cc.col, err);
  if (!cc.col) rc = GS_ENOMEM;
  for (size_t j = 0; j < nout && !rc; j++)
    rc = gs_study_outputs_find(&o, outputs[j], "--outputs column", &cc.col[j], err);
  char **unit = gs_calloc(nout ? nout : 1, sizeof *unit, err);
  if (!rc && !unit) rc = GS_ENOMEM;
  for (size_t j = 0; j < nout && !rc; j++)
    if (!(unit[j] = strdup(o.units[cc.col[j]]))) rc = gs_error_set(err, GS_ENOMEM, "out of memory");
  gs_study_outputs_free(&o);
  if (!rc) rc = gs_sensitivity(axes, nin, nout, case_model, &cc, opt, res, err);
  if (!rc) res->unit = unit, unit = NULL;
  for (size_t j = 0; unit && j < nout; j++) free(unit[j]);
  free(unit);
  free(cc.col);
  return rc;
}

int gs_sens_write_csv(const char *path, const gs_sens_result *r, const gs_study_axis *axes,
                      const char *const *outputs, gs_error *err) {
  gs_csv_out t;
  FILE *f = gs_csv_open(&t, path, err);
  if (!f) return err->code;
  const int sobol = r->method == GS_SENS_SOBOL;
  if (sobol)
    fputs("# Sobol' indices of each output (a summary column at the final time) and key: "
          "first-order S1 and total ST with bootstrap intervals [lo, hi], fractions of the "
          "output's variance (dimensionless).\n"
          "output,key,S1 [1],S1_lo [1],S1_hi [1],ST [1],ST_lo [1],ST_hi [1]\n",
          f);
  else
    fputs("# Morris elementary effects of each output (a summary column at the final time) and "
          "key: mean mu, mean of the absolute values mu_star and standard deviation sigma of "
          "the output's change per whole range of the key, in the output's unit (the row's "
          "unit).\n"
          "output,key,mu [unit],mu_star [unit],sigma [unit],unit\n",
          f);
  for (size_t o = 0; o < r->nout; o++)
    for (size_t k = 0; k < r->nin; k++) {
      const size_t i = o * r->nin + k;
      if (sobol)
        fprintf(f, "%s,%s,%.10g,%.10g,%.10g,%.10g,%.10g,%.10g\n", outputs[o], axes[k].key, r->s1[i],
                r->s1_lo[i], r->s1_hi[i], r->st[i], r->st_lo[i], r->st_hi[i]);
      else
        fprintf(f, "%s,%s,%.10g,%.10g,%.10g,%s\n", outputs[o], axes[k].key, r->mu[i], r->mu_star[i],
                r->sigma[i], r->unit ? r->unit[o] : "");
    }
  static const char *const sobol_units[] = {"S1", "1", "S1_lo", "1", "S1_hi", "1", "ST", "1",
                                            "ST_lo", "1", "ST_hi", "1", NULL};
  static const char *const morris_units[] = {"mu", "the row's unit", "mu_star", "the row's unit",
                                             "sigma", "the row's unit", NULL};
  return gs_csv_close(&t, "gransim sensitivity", sobol ? sobol_units : morris_units, err);
}
