/* Moments and size statistics of a compartment.
 *
 * Percentiles d10/d50/d90 are volume-weighted percentiles of the
 * volume-equivalent diameter d = (6 V / pi)^(1/3), V = sum of the size axes
 * at the pivot.  Each cell is a point mass; the cumulative volume fraction is
 * taken at each distinct diameter with the midpoint rule (half of a point's
 * own mass counted below it) and interpolated linearly in between, so a
 * single occupied cell gives d10 = d50 = d90 = its diameter. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "gransim/pbm.h"

double gs_moment(const gs_model *m, const double *y, size_t comp, const int *powers) {
  const gs_grid *g = &m->grid;
  const double *N = gs_model_numbers_c(m, y, comp);
  double s = 0;
  for (size_t c = 0; c < g->ncells; c++) {
    double f = N[c];
    for (int k = 0; k < g->dim; k++)
      if (powers[k]) f *= pow(g->x[c * (size_t)g->dim + (size_t)k], powers[k]);
    s += f;
  }
  return s;
}

/* Volume-weighted percentiles p[0..np-1] (fractions) of the diameter, a
 * point per occupied cell. */
static void percentiles(const double *vol, const double *N, size_t n, const double *p, int np,
                        double *out) {
  gs_size_point *pts = malloc(2 * (n ? n : 1) * sizeof *pts);
  if (!pts) {
    for (int i = 0; i < np; i++) out[i] = NAN;
    return;
  }
  size_t k = 0;
  for (size_t c = 0; c < n; c++)
    if (N[c] > 0 && vol[c] > 0) {
      pts[k].v = vol[c];
      pts[k].w = N[c] * vol[c];
      k++;
    }
  gs_size_percentiles(pts, pts + n, k, p, np, out);
  free(pts);
}

void gs_summarize(const gs_model *m, const double *y, size_t comp, gs_summary *s) {
  const gs_grid *g = &m->grid;
  const double *N = gs_model_numbers_c(m, y, comp);
  memset(s, 0, sizeof *s);
  /* granule volume per cell: the size axes, plus what a particle carries
   * (liquid and gas fill the pores of the granule: the external volume of Sampat et al. (2018)) */
  double *vol = m->ncarried ? malloc(g->ncells * sizeof *vol) : NULL;
  const double *size = vol ? vol : m->size_volume;
  for (size_t c = 0; vol && c < g->ncells; c++) {
    vol[c] = m->size_volume[c];
    for (int q = 0; q < m->ncarried; q++)
      if (N[c] > 0) vol[c] += gs_model_carried_c(m, y, comp, q)[c] / N[c];
  }
  for (size_t c = 0; c < g->ncells; c++) {
    double v = size[c];
    s->m0 += N[c];
    s->m1 += N[c] * v;
    s->m2 += N[c] * v * v;
    for (int k = 0; k < g->dim; k++) s->total[k] += N[c] * g->x[c * (size_t)g->dim + (size_t)k];
  }
  for (int q = 0; q < m->ncarried; q++) s->total[g->dim + q] = gs_model_held(m, y, comp, g->dim + q);
  for (int k = 0; k < m->nvol; k++) s->mean[k] = s->m0 > 0 ? s->total[k] / s->m0 : NAN;
  static const double p[3] = {0.1, 0.5, 0.9};
  double d[3];
  percentiles(size, N, g->ncells, p, 3, d);
  free(vol);
  s->d10 = d[0];
  s->d50 = d[1];
  s->d90 = d[2];
}
