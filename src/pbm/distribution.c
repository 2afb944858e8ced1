/* Discretisation of distribution specs; see include/gransim/distribution.h. */
#include <gsl/gsl_cdf.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gransim/distribution.h"
#include "pbm/distribution_mass.h"
#include "pbm/lever.h"

enum { D_POINT, D_CELL, D_EXPONENTIAL, D_GAMMA, D_CELLS, D_LOGNORMAL, D_NORMAL, D_TABLE };

/* Marginal of one axis: cumulative number F and cumulative first moment M,
 * both normalised to total number 1. */
typedef struct {
  double mean, shape;
  int exponential;
} marginal_t;

/* Beyond x / mean = inf (an edge of 1e300 against a mean of 1e-12) GSL's
 * gamma CDF is NaN and the exponential's u e^-u is inf * 0: all of the
 * distribution lies below such an edge. */
static double cum_number(const marginal_t *m, double x) {
  if (x <= 0) return 0;
  if (isinf(x / m->mean)) return 1;
  if (m->exponential) return -expm1(-x / m->mean);
  return gsl_cdf_gamma_P(x, m->shape, m->mean / m->shape);
}

static double cum_moment(const marginal_t *m, double x) {
  if (x <= 0) return 0;
  if (isinf(x / m->mean)) return m->mean;
  if (m->exponential) {
    double u = x / m->mean;
    return m->mean * (-expm1(-u) - u * exp(-u));
  }
  return m->mean * gsl_cdf_gamma_P(x, m->shape + 1, m->mean / m->shape);
}

/* Per-axis weights conserving number and first moment cell by cell; in
 * inside[0..1] the number and first moment within the grid's edges (what
 * the weights should hold: `coverage` governs the rest). */
static int marginal_weights(const marginal_t *m, const gs_axis *ax, double coverage,
                            gs_cfg_node *node, double *w, double *inside, gs_error *err) {
  memset(w, 0, ax->n * sizeof(double));
  double below_n = cum_number(m, ax->edges[0]), below_m = cum_moment(m, ax->edges[0]);
  double above_n = 1 - cum_number(m, ax->edges[ax->n]);
  double above_m = m->mean - cum_moment(m, ax->edges[ax->n]);
  /* written so that a NaN fails */
  if (!(below_n <= coverage && above_n <= coverage && above_m <= coverage * m->mean &&
        below_m <= coverage * m->mean))
    return gs_cfg_fail(node, err,
                       "grid axis '%s' [%g, %g] does not cover this distribution: %.3g of its "
                       "number and %.3g of its volume lie outside (allowed: %g; widen the grid or "
                       "set 'coverage')",
                       ax->name, ax->edges[0], ax->edges[ax->n], below_n + above_n,
                       (below_m + above_m) / m->mean, coverage);
  inside[0] = cum_number(m, ax->edges[ax->n]) - below_n;
  inside[1] = cum_moment(m, ax->edges[ax->n]) - below_m;
  for (size_t i = 0; i < ax->n; i++) {
    double cn = cum_number(m, ax->edges[i + 1]) - cum_number(m, ax->edges[i]);
    double cm = cum_moment(m, ax->edges[i + 1]) - cum_moment(m, ax->edges[i]);
    if (!(cn > 0)) continue;
    double vbar = cm / cn, frac;
    size_t lo;
    int st = gs_lever_near(ax, i, vbar, &lo, &frac);
    if (st < 0) { lo = 0; frac = 0; }            /* below the first pivot: number kept */
    if (st > 0) { lo = ax->n - 1; frac = 0; }    /* above the last pivot: number kept */
    w[lo] += cn * (1 - frac);
    if (frac > 0) w[lo + 1] += cn * frac;
  }
  return GS_OK;
}

static int per_axis(gs_cfg_node *node, const char *key, const gs_grid *g, double **out,
                    gs_error *err) {
  size_t n = 0;
  int rc = gs_cfg_doubles_req(node, key, 1, out, &n, err);
  if (rc) return rc;
  if (n == 1 && g->dim > 1) {
    double *all = realloc(*out, (size_t)g->dim * sizeof(double));
    if (!all) return gs_error_set(err, GS_ENOMEM, "out of memory");
    *out = all;
    for (int k = 1; k < g->dim; k++) all[k] = all[0];
    n = (size_t)g->dim;
  }
  if (n != (size_t)g->dim)
    return gs_cfg_fail(gs_cfg_get(node, key), err, "expected %d values (one per grid axis), got %zu",
                       g->dim, n);
  return GS_OK;
}

static int add_product(gs_cfg_node *node, const gs_grid *g, double number, int type,
                       double coverage, double *dst, gs_disc_report *req, gs_error *err) {
  double *mean = NULL, *shape = NULL, *w[GS_MAX_DIM] = {0}, inside[GS_MAX_DIM][2];
  int rc = per_axis(node, "mean", g, &mean, err);
  if (!rc && type == D_GAMMA) rc = per_axis(node, "shape", g, &shape, err);
  for (int k = 0; !rc && k < g->dim; k++) {
    if (!(mean[k] > 0)) rc = gs_cfg_fail(gs_cfg_get(node, "mean"), err, "means must be > 0");
    else if (shape && !(shape[k] > 0)) rc = gs_cfg_fail(gs_cfg_get(node, "shape"), err, "shapes must be > 0");
    if (rc) break;
    marginal_t m = {mean[k], shape ? shape[k] : 1, type == D_EXPONENTIAL};
    w[k] = gs_malloc(g->axis[k].n * sizeof(double), err);
    if (!w[k]) rc = GS_ENOMEM;
    else rc = marginal_weights(&m, &g->axis[k], coverage, node, w[k], inside[k], err);
  }
  /* asked: the part within the grid's edges, of the product of the axes */
  for (int k = 0; !rc && k < g->dim; k++) {
    req->number[0] *= inside[k][0];
    req->volume[k][0] = number * inside[k][1];
    for (int j = 0; j < g->dim; j++)
      if (j != k) req->volume[k][0] *= inside[j][0];
  }
  size_t idx[GS_MAX_DIM];
  for (size_t c = 0; !rc && c < g->ncells; c++) {
    gs_grid_unindex(g, c, idx);
    double f = number;
    for (int k = 0; k < g->dim; k++) f *= w[k][idx[k]];
    dst[c] += f;
  }
  free(mean);
  free(shape);
  for (int k = 0; k < GS_MAX_DIM; k++) free(w[k]);
  return rc;
}

static int add_point(gs_cfg_node *node, const gs_grid *g, double number, double *dst,
                     gs_disc_report *req, gs_error *err) {
  double *at = NULL;
  int rc = per_axis(node, "at", g, &at, err);
  for (int k = 0; !rc && k < g->dim; k++) {
    const gs_axis *ax = &g->axis[k];
    if (!(at[k] >= ax->pivots[0] && at[k] <= ax->pivots[ax->n - 1]))
      rc = gs_cfg_fail(gs_cfg_get(node, "at"), err,
                       "coordinate %g on axis '%s' lies outside the pivots [%g, %g]", at[k],
                       ax->name, ax->pivots[0], ax->pivots[ax->n - 1]);
  }
  if (!rc) gs_lever_place(g, GS_NOWHERE, at, number, dst, NULL);
  for (int k = 0; !rc && k < g->dim; k++) req->volume[k][0] = number * at[k];
  free(at);
  return rc;
}

static int add_cell(gs_cfg_node *node, const gs_grid *g, double number, double *dst,
                    gs_disc_report *req, gs_error *err) {
  double *index = NULL;
  size_t idx[GS_MAX_DIM];
  int rc = per_axis(node, "index", g, &index, err);
  for (int k = 0; !rc && k < g->dim; k++) {
    if (index[k] != floor(index[k]) || index[k] < 1 || index[k] > (double)g->axis[k].n)
      rc = gs_cfg_fail(gs_cfg_get(node, "index"), err,
                       "index %g on axis '%s' must be an integer from 1 to %zu", index[k],
                       g->axis[k].name, g->axis[k].n);
    else idx[k] = (size_t)index[k] - 1;
  }
  if (!rc) dst[gs_grid_index(g, idx)] += number;
  for (int k = 0; !rc && k < g->dim; k++) req->volume[k][0] = number * g->axis[k].pivots[idx[k]];
  free(index);
  return rc;
}

/* cells: `indices` (a list of 1-based cell indices, one list per cell) and
 * `weights` (one per cell, >= 0): `number` shared in proportion to weights
 * (the inlet of Sampat et al. (2018): given numbers on the diagonal of the solid bins). */
static int add_cells(gs_cfg_node *node, const gs_grid *g, double number, double *dst,
                     gs_disc_report *req, gs_error *err) {
  gs_cfg_node *list = NULL;
  double *w = NULL, total = 0;
  size_t nw = 0;
  int rc = gs_cfg_seq_req(node, "indices", &list, err);
  if (!rc) rc = gs_cfg_doubles_req(node, "weights", 1, &w, &nw, err);
  if (!rc && nw != gs_cfg_size(list))
    rc = gs_cfg_fail(gs_cfg_get(node, "weights"), err, "expected one weight per entry of 'indices' (%zu), got %zu",
                     gs_cfg_size(list), nw);
  for (size_t i = 0; !rc && i < nw; i++) {
    if (!(w[i] >= 0) || !isfinite(w[i])) rc = gs_cfg_fail(gs_cfg_get(node, "weights"), err, "weights must be finite and >= 0");
    total += w[i];
  }
  if (!rc && !(total > 0)) rc = gs_cfg_fail(gs_cfg_get(node, "weights"), err, "weights must not all be 0");
  for (size_t i = 0; !rc && i < nw; i++) {
    gs_cfg_node *item = gs_cfg_item(list, i);
    size_t idx[GS_MAX_DIM];
    if (gs_cfg_kind_of(item) != GS_CFG_SEQ || gs_cfg_size(item) != (size_t)g->dim) {
      rc = gs_cfg_fail(item, err, "expected a list of %d cell indices (one per axis)", g->dim);
      break;
    }
    for (int k = 0; !rc && k < g->dim; k++) {
      double v;
      gs_cfg_node *e = gs_cfg_item(item, (size_t)k);
      if (gs_cfg_node_double(e, &v, err) || v != floor(v) || v < 1 || v > (double)g->axis[k].n)
        rc = gs_cfg_fail(e, err, "expected an integer cell index from 1 to %zu on axis '%s'",
                         g->axis[k].n, g->axis[k].name);
      else idx[k] = (size_t)v - 1;
    }
    if (!rc) dst[gs_grid_index(g, idx)] += number * w[i] / total;
    for (int k = 0; !rc && k < g->dim; k++) req->volume[k][0] += number * w[i] / total * g->axis[k].pivots[idx[k]];
  }
  free(w);
  return rc;
}

double gs_disc_error(const gs_disc_report *r) {
  /* a quantity asked or held that is not finite is an infinite error (fmax
   * below would drop a NaN) */
  if (!isfinite(r->number[0]) || !isfinite(r->number[1])) return INFINITY;
  for (int k = 0; k < r->dim; k++)
    if (!isfinite(r->volume[k][0]) || !isfinite(r->volume[k][1])) return INFINITY;
  double e = r->number[0] > 0 ? fabs(r->number[1] / r->number[0] - 1) : 0;
  for (int k = 0; k < r->dim; k++) {
    const double *v = r->volume[k];
    if (!(v[0] > 0)) continue;
    e = fmax(e, fabs(v[1] / v[0] - 1));
    if (r->number[1] > 0) e = fmax(e, fabs((v[1] / r->number[1]) / (v[0] / r->number[0]) - 1));
  }
  return e;
}

void gs_disc_log_free(gs_disc_log *log) {
  free(log->r);
  log->r = NULL;
  log->n = 0;
}

void gs_disc_format(const gs_disc_report *r, const gs_grid *g, double tolerance, char *buf,
                    size_t len) {
  size_t at = (size_t)snprintf(buf, len, "%s: the grid holds number %.6g (asked %.6g)", r->key,
                               r->number[1], r->number[0]);
  for (int k = 0; k < r->dim && at < len; k++)
    at += (size_t)snprintf(buf + at, len - at, ", volume of '%s' %.6g (asked %.6g)",
                           g->axis[k].name, r->volume[k][1], r->volume[k][0]);
  if (at < len)
    snprintf(buf + at, len - at, "; largest relative error %.2g (discretisation.tolerance %g)",
             gs_disc_error(r), tolerance);
}

/* What the cells added (add) hold against what was asked (rep); refuses an
 * error above the log's tolerance naming the worst quantity. */
static int compare(gs_cfg_node *node, const gs_grid *g, const double *add, gs_disc_report *rep,
                   gs_disc_log *log, gs_error *err) {
  for (size_t c = 0; c < g->ncells; c++) {
    rep->number[1] += add[c];
    for (int k = 0; k < g->dim; k++) rep->volume[k][1] += add[c] * g->x[c * (size_t)g->dim + (size_t)k];
  }
  snprintf(rep->key, sizeof rep->key, "%s:%d: %s", gs_cfg_file(node), gs_cfg_line(node), gs_cfg_path(node));
  gs_disc_report *grown = realloc(log->r, (log->n + 1) * sizeof *grown);
  if (!grown) return gs_error_set(err, GS_ENOMEM, "out of memory");
  log->r = grown;
  log->r[log->n++] = *rep;
  const double e = gs_disc_error(rep);
  if (e <= log->tolerance) return GS_OK;
  /* name the quantity with the largest error */
  char what[GS_NAME_LEN + 32] = "number";
  double asked = rep->number[0], held = rep->number[1], worst = fabs(held / asked - 1);
  for (int k = 0; k < g->dim; k++) {
    const double *v = rep->volume[k];
    if (v[0] > 0 && fabs(v[1] / v[0] - 1) > worst) {
      worst = fabs(v[1] / v[0] - 1);
      snprintf(what, sizeof what, "volume of axis '%s'", g->axis[k].name);
      asked = v[0];
      held = v[1];
    }
  }
  return gs_cfg_fail(node, err,
                     "the grid holds this distribution with a %s of %.6g instead of the requested "
                     "%.6g (relative error %.3g; with the mean sizes %.3g > "
                     "discretisation.tolerance = %g): its cells are too coarse where it lies "
                     "(a cell's content with its mean below the first pivot or above the last "
                     "can only sit on that pivot); refine the grid there or raise "
                     "discretisation.tolerance",
                     what, held, asked, worst, e, log->tolerance);
}

int gs_distribution_add(gs_cfg_node *node, const gs_grid *g, double *dst, int keep_open,
                        gs_disc_log *log, gs_error *err) {
  static const char *const types[] = {"point", "cell", "exponential", "gamma", "cells",
                                      "lognormal", "normal", "table", NULL};
  int type = 0;
  double number = 0, coverage = 0;
  int rc = gs_cfg_require_kind(node, GS_CFG_MAP, err);
  if (!rc && !gs_cfg_get(node, "type"))
    rc = gs_cfg_missing(node, "type", "(point, cell, cells, exponential, gamma, lognormal, normal or table)", err);
  if (!rc) rc = gs_cfg_enum_opt(node, "type", types, 0, &type, err);
  const int by_mass = type >= D_LOGNORMAL; /* a mass, not a number */
  if (!rc && !by_mass) rc = gs_cfg_double_range(node, "number", 1, 0, 0, 1, HUGE_VAL, 0, &number, err);
  if (!rc) rc = gs_cfg_double_range(node, "coverage", 0, 1e-6, 0, 0, 1, 0, &coverage, err);
  if (rc) return rc;
  /* into a field of its own first, to compare it with what was asked */
  double *add = gs_calloc(g->ncells, sizeof *add, err);
  if (!add) return GS_ENOMEM;
  gs_disc_report rep = {.dim = g->dim, .number = {number, 0}};
  switch (type) {
  case D_POINT: rc = add_point(node, g, number, add, &rep, err); break;
  case D_CELL: rc = add_cell(node, g, number, add, &rep, err); break;
  case D_CELLS: rc = add_cells(node, g, number, add, &rep, err); break;
  case D_LOGNORMAL: case D_NORMAL: case D_TABLE:
    rc = gs_distribution_by_mass(node, g, types[type], coverage, add, &rep, err);
    break;
  default: rc = add_product(node, g, number, type, coverage, add, &rep, err); break;
  }
  if (!rc && log) rc = compare(node, g, add, &rep, log, err);
  for (size_t c = 0; !rc && c < g->ncells; c++) dst[c] += add[c];
  free(add);
  if (!rc && !keep_open) rc = gs_cfg_check_unused(node, err);
  return rc;
}
