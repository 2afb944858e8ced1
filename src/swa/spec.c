/* Exact sampling of particle distributions: see spec.h. */
#include <gsl/gsl_randist.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "swa/spec.h"

enum { SPEC_POINT, SPEC_CELL, SPEC_EXPONENTIAL, SPEC_GAMMA, SPEC_DIAMETERS };

static int per_coord(gs_cfg_node *n, const char *key, const gs_swa_model *m, double lo,
                     int strict, double *out, gs_error *err) {
  double *v = NULL;
  size_t cnt = 0;
  int rc = gs_cfg_doubles_req(n, key, 1, &v, &cnt, err);
  if (!rc && cnt != 1 && cnt != (size_t)m->ncoord)
    rc = gs_cfg_fail(gs_cfg_get(n, key), err, "expected one number or one per particle coordinate (%d), got %zu",
                     m->ncoord, cnt);
  for (int k = 0; !rc && k < m->ncoord; k++) {
    out[k] = v[cnt == 1 ? 0 : (size_t)k];
    if (strict ? !(out[k] > lo) : !(out[k] >= lo))
      rc = gs_cfg_fail(gs_cfg_get(n, key), err, "expected numbers %s %g", strict ? ">" : ">=", lo);
  }
  free(v);
  return rc;
}

static int read_diameters(gs_cfg_node *n, const gs_swa_model *m, gs_swa_spec *sp, gs_error *err) {
  static const char *const weighting[] = {"equal", "variable", NULL};
  double *q3 = NULL;
  size_t nq = 0;
  int rc = gs_swa_coord_key(n, "coordinate", m, m->coord[0], &sp->coord, err);
  if (!rc) rc = gs_cfg_double_range(n, "min", 1, 0, 0, 1, HUGE_VAL, 0, &sp->dmin, err);
  if (!rc) rc = gs_cfg_double_range(n, "max", 1, 0, sp->dmin, 1, HUGE_VAL, 0, &sp->dmax, err);
  if (!rc) rc = gs_cfg_enum_opt(n, "weighting", weighting, 1, &sp->variable, err);
  if (!rc) rc = gs_cfg_double_range(n, "mean_weight", 0, 1, 0, 1, HUGE_VAL, 0, &sp->mean_weight, err);
  if (!rc) rc = gs_cfg_doubles_req(n, "q3", 0, &q3, &nq, err);
  if (rc) { free(q3); return rc; }
  double tot = 0;
  for (size_t k = 0; k < nq; k++) {
    if (!(q3[k] >= 0)) rc = gs_cfg_fail(gs_cfg_get(n, "q3"), err, "expected volume fractions >= 0 (entry %zu is %g)", k, q3[k]);
    tot += q3[k];
  }
  if (!rc && !(tot > 0)) rc = gs_cfg_fail(gs_cfg_get(n, "q3"), err, "expected at least one volume fraction > 0");
  sp->nsec = nq;
  sp->edges = calloc(nq + 1, sizeof(double));
  sp->cnum = calloc(nq, sizeof(double));
  sp->dens = calloc(nq, sizeof(double));
  if (!rc && (!sp->edges || !sp->cnum || !sp->dens)) rc = gs_error_set(err, GS_ENOMEM, "out of memory");
  if (rc) { free(q3); return rc; }
  double ratio = pow(sp->dmax / sp->dmin, 1.0 / (double)nq), num = 0, vol = 0;
  for (size_t k = 0; k <= nq; k++) sp->edges[k] = sp->dmin * pow(ratio, (double)k);
  sp->edges[nq] = sp->dmax;
  /* q3 is a piecewise-constant density in d per section; q0(d) ~ q3(d) d^-3 (eq. 5) */
  for (size_t k = 0; k < nq; k++) {
    double a = sp->edges[k], b = sp->edges[k + 1];
    double c = q3[k] / tot / (b - a);
    sp->dens[k] = c;
    num += c * 0.5 * (1 / (a * a) - 1 / (b * b));
    sp->cnum[k] = num;
    vol += c * M_PI / 6 * (b - a);
  }
  for (size_t k = 0; k < nq; k++) {
    sp->dens[k] /= num;
    sp->cnum[k] /= num;
  }
  sp->vmean = vol / num;
  free(q3);
  return GS_OK;
}

int gs_swa_spec_read(gs_cfg_node *n, const gs_swa_model *m, const gs_grid *g,
                     const int *grid_coord, const char *number_key, gs_swa_spec *sp,
                     gs_error *err) {
  static const char *const types[] = {"point", "cell", "exponential", "gamma", "diameters", NULL};
  memset(sp, 0, sizeof *sp);
  sp->ncoord = m->ncoord;
  sp->mean_weight = 1;
  int rc = gs_cfg_require_kind(n, GS_CFG_MAP, err);
  if (!rc && !gs_cfg_get(n, "type")) rc = gs_cfg_missing(n, "type", "(point, cell, exponential, gamma or diameters)", err);
  if (!rc) rc = gs_cfg_enum_opt(n, "type", types, 0, &sp->type, err);
  if (!rc && number_key) rc = gs_cfg_double_range(n, number_key, 1, 0, 0, 1, HUGE_VAL, 0, &sp->number, err);
  if (rc) return rc;
  double cov;
  if (sp->type == SPEC_EXPONENTIAL || sp->type == SPEC_GAMMA)
    rc = gs_cfg_double_range(n, "coverage", 0, 1e-6, 0, 0, 1, 0, &cov, err); /* the grid only bins outputs */
  switch (sp->type) {
    case SPEC_POINT: rc = per_coord(n, "at", m, 0, 0, sp->at, err); break;
    case SPEC_CELL: {
      double idx[GS_SWA_MAX_COORD];
      if (!g) return gs_cfg_fail(n, err, "type cell needs a grid");
      rc = gs_cfg_get(n, "index") ? GS_OK : gs_cfg_missing(n, "index", NULL, err);
      double *v = NULL;
      size_t cnt = 0;
      if (!rc) rc = gs_cfg_doubles_req(n, "index", 1, &v, &cnt, err);
      if (!rc && cnt != 1 && cnt != (size_t)g->dim)
        rc = gs_cfg_fail(gs_cfg_get(n, "index"), err, "expected one index or one per grid axis (%d)", g->dim);
      for (int a = 0; !rc && a < g->dim; a++) {
        idx[a] = v[cnt == 1 ? 0 : (size_t)a];
        if (idx[a] != floor(idx[a]) || idx[a] < 1 || idx[a] > (double)g->axis[a].n)
          rc = gs_cfg_fail(gs_cfg_get(n, "index"), err, "expected whole numbers from 1 to the cells of each axis");
        else sp->at[grid_coord[a]] = g->axis[a].pivots[(size_t)idx[a] - 1];
      }
      free(v);
      sp->type = SPEC_POINT;
      break;
    }
    case SPEC_EXPONENTIAL:
      if (!rc) rc = per_coord(n, "mean", m, 0, 0, sp->mean, err);
      for (int k = 0; k < m->ncoord; k++) sp->shape[k] = 1;
      break;
    case SPEC_GAMMA:
      if (!rc) rc = per_coord(n, "mean", m, 0, 0, sp->mean, err);
      if (!rc) rc = per_coord(n, "shape", m, 0, 1, sp->shape, err);
      break;
    default: rc = read_diameters(n, m, sp, err); break;
  }
  if (!rc) rc = gs_cfg_check_unused(n, err);
  return rc;
}

void gs_swa_spec_free(gs_swa_spec *sp) {
  free(sp->edges);
  free(sp->cnum);
  free(sp->dens);
  memset(sp, 0, sizeof *sp);
}

void gs_swa_spec_moments(const gs_swa_spec *sp, gs_swa_moments *mo) {
  memset(mo, 0, sizeof *mo);
  mo->ew2 = 1;
  switch (sp->type) {
    case SPEC_POINT:
      for (int k = 0; k < sp->ncoord; k++) {
        mo->mu[k] = mo->ew2x[k] = sp->at[k];
        mo->ew2x2[k] = sp->at[k] * sp->at[k];
      }
      return;
    case SPEC_EXPONENTIAL:
    case SPEC_GAMMA: /* Gamma(a, m/a): E[x^2] = m^2 (1 + 1/a) */
      for (int k = 0; k < sp->ncoord; k++) {
        mo->mu[k] = mo->ew2x[k] = sp->mean[k];
        mo->ew2x2[k] = sp->mean[k] > 0 ? sp->mean[k] * sp->mean[k] * (1 + 1 / sp->shape[k]) : 0;
      }
      return;
    default: break;
  }
  /* diameters: number density c_k d^-3 per section [a, b], v = pi/6 d^3;
   * VWI draws d uniformly on [dmin, dmax] with w = (dmax - dmin) q0(d) */
  const double k6 = M_PI / 6, len = sp->dmax - sp->dmin;
  double ew2 = 0, ew2v = 0, ew2v2 = 0;
  for (size_t k = 0; k < sp->nsec; k++) {
    double a = sp->edges[k], b = sp->edges[k + 1], c = sp->dens[k];
    if (sp->variable) {
      ew2 += len * c * c * (pow(a, -5) - pow(b, -5)) / 5;
      ew2v += len * c * c * k6 * (1 / (a * a) - 1 / (b * b)) / 2;
      ew2v2 += len * c * c * k6 * k6 * (b - a);
    } else {
      ew2v += c * k6 * (b - a);
      ew2v2 += c * k6 * k6 * (pow(b, 4) - pow(a, 4)) / 4;
    }
  }
  mo->ew2 = sp->variable ? ew2 : 1;
  mo->mu[sp->coord] = sp->vmean;
  mo->ew2x[sp->coord] = ew2v;
  mo->ew2x2[sp->coord] = ew2v2;
}

static double q0(const gs_swa_spec *sp, double d) {
  size_t k = (size_t)(log(d / sp->dmin) / log(sp->edges[1] / sp->dmin));
  if (k >= sp->nsec) k = sp->nsec - 1;
  while (k > 0 && d < sp->edges[k]) k--;
  while (k + 1 < sp->nsec && d >= sp->edges[k + 1]) k++;
  return sp->dens[k] / (d * d * d);
}

void gs_swa_spec_sample(const gs_swa_spec *sp, gsl_rng *r, double *x, double *w) {
  *w = 1;
  switch (sp->type) {
    case SPEC_POINT: memcpy(x, sp->at, (size_t)sp->ncoord * sizeof(double)); return;
    case SPEC_EXPONENTIAL:
    case SPEC_GAMMA:
      for (int k = 0; k < sp->ncoord; k++)
        x[k] = sp->mean[k] > 0 ? gsl_ran_gamma(r, sp->shape[k], sp->mean[k] / sp->shape[k]) : 0;
      return;
    default: break;
  }
  double d;
  if (sp->variable) {
    d = sp->dmin + (sp->dmax - sp->dmin) * gsl_rng_uniform(r);
    *w = (sp->dmax - sp->dmin) * q0(sp, d);
  } else {
    double u = gsl_rng_uniform(r);
    size_t k = 0;
    while (k + 1 < sp->nsec && sp->cnum[k] <= u) k++;
    double a = sp->edges[k], b = sp->edges[k + 1], v = gsl_rng_uniform(r);
    /* inverse CDF of d^-3 on [a, b] */
    d = 1 / sqrt(1 / (a * a) - v * (1 / (a * a) - 1 / (b * b)));
  }
  memset(x, 0, (size_t)sp->ncoord * sizeof(double));
  x[sp->coord] = M_PI / 6 * d * d * d;
}
