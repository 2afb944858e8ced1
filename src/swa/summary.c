/* Per-compartment statistics of one run, from the particles: particle i
 * stands for w_i / V real particles.  Columns as in the sectional summary
 * (M0, M1, M2 of the granule volume, volume-weighted d10/d50/d90 of the
 * volume-equivalent diameter, mean and total of every coordinate); the
 * percentiles use the same midpoint rule as src/pbm/summary.c. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "swa/sim.h"

int gs_swa_ncolumns(const gs_swa_model *m) { return 6 + 2 * m->ncoord; }

void gs_swa_column_name(const gs_swa_model *m, int col, char *buf, size_t n) {
  static const char *const fixed[] = {"M0", "M1", "M2", "d10", "d50", "d90"};
  if (col < 6) snprintf(buf, n, "%s", fixed[col]);
  else if (col < 6 + m->ncoord) snprintf(buf, n, "mean_%s", m->coord[col - 6]);
  else snprintf(buf, n, "total_%s", m->coord[col - 6 - m->ncoord]);
}

void gs_swa_summarize(gs_swa_sim *s, size_t z, gs_swa_summary *o) {
  const gs_swa_model *m = s->m;
  const swa_comp *c = &s->comp[z];
  size_t nc = (size_t)m->ncoord;
  memset(o, 0, sizeof *o);
  /* a point per particle with a size (and scratch for the sort) */
  gs_size_point *pts = malloc(2 * (c->n ? c->n : 1) * sizeof *pts);
  size_t np = 0;
  for (size_t i = 0; i < c->n; i++) {
    const double *x = c->x + i * nc;
    double n = c->w[i] / c->vsamp, v = gs_swa_size(m, x);
    o->m0 += n;
    o->m1 += n * v;
    o->m2 += n * v * v;
    for (size_t k = 0; k < nc; k++) o->total[k] += n * x[k];
    if (pts && v > 0) {
      pts[np].v = v;
      pts[np++].w = n * v;
    }
  }
  for (size_t k = 0; k < nc; k++) o->mean[k] = o->m0 > 0 ? o->total[k] / o->m0 : NAN;
  const double p[3] = {0.1, 0.5, 0.9};
  double d[3] = {NAN, NAN, NAN};
  if (pts) gs_size_percentiles(pts, pts + c->n, np, p, 3, d);
  o->d10 = d[0];
  o->d50 = d[1];
  o->d90 = d[2];
  free(pts);
}

void gs_swa_sieve(gs_swa_sim *s, size_t z, const double *edges, size_t nclass, double *frac) {
  const gs_swa_model *m = s->m;
  const swa_comp *c = &s->comp[z];
  size_t nc = (size_t)m->ncoord;
  double total = 0;
  memset(frac, 0, nclass * sizeof(double));
  for (size_t i = 0; i < c->n; i++) {
    const double *x = c->x + i * nc;
    double mass = c->w[i] * gs_swa_mass(m, x), d = gs_diameter(gs_swa_size(m, x));
    total += mass;
    if (d < edges[0] || d >= edges[nclass]) continue;
    size_t lo = 0, hi = nclass; /* edges[lo] <= d < edges[hi] */
    while (hi - lo > 1) {
      size_t mid = (lo + hi) / 2;
      if (d >= edges[mid]) lo = mid;
      else hi = mid;
    }
    frac[lo] += mass;
  }
  for (size_t k = 0; k < nclass; k++) frac[k] = total > 0 ? frac[k] / total : NAN;
}
