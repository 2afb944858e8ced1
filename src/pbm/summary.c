/* Moments and size statistics of a compartment.
 *
 * Percentiles d10/d50/d90 are volume-weighted percentiles of the
 * volume-equivalent diameter d = (6 V / pi)^(1/3), V = sum of the size axes.
 * Each cell's volume N V (V at the pivot) is spread evenly between the
 * granule volumes of its edges, so the cumulative volume fraction is linear
 * within cells and the percentiles move continuously with the numbers (as
 * point masses they jumped by whole cells on tiny changes); a single
 * occupied cell gives d10, d50, d90 at the diameters of 0.1, 0.5, 0.9 of its
 * volume range. */
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

/* The cells of a compartment as ranges of granule volume (r[ncells]), the
 * volume N V of each occupied cell spread evenly between the granule
 * volumes of its lower and upper edges (the size axes' edges summed, plus
 * the carried volume per particle, which vol holds at the pivot); returns
 * how many. */
static size_t cell_ranges(const gs_model *m, const double *vol, const double *N, gs_size_range *r) {
  const gs_grid *g = &m->grid;
  size_t k = 0;
  for (size_t c = 0; c < g->ncells; c++) {
    if (!(N[c] > 0 && vol[c] > 0)) continue;
    size_t idx[GS_MAX_DIM];
    gs_grid_unindex(g, c, idx);
    double lo = vol[c] - m->size_volume[c], hi = lo; /* the carried part */
    for (int d = 0; d < g->dim; d++)
      if (m->size_axes & (1 << d)) {
        lo += g->axis[d].edges[idx[d]];
        hi += g->axis[d].edges[idx[d] + 1];
      }
    r[k++] = (gs_size_range){lo, hi, N[c] * vol[c]};
  }
  return k;
}

/* Volume-weighted percentiles p[0..np-1] (fractions) of the diameter over
 * the cell ranges. */
static void percentiles(const gs_model *m, const double *vol, const double *N, const double *p,
                        int np, double *out) {
  const size_t n = m->grid.ncells;
  gs_size_range *r = malloc((n ? n : 1) * sizeof *r);
  gs_size_point *scratch = malloc(4 * (n ? n : 1) * sizeof *scratch);
  if (!r || !scratch) {
    for (int i = 0; i < np; i++) out[i] = NAN;
    free(r);
    free(scratch);
    return;
  }
  gs_size_percentiles_ranges(r, cell_ranges(m, vol, N, r), scratch, p, np, out);
  free(r);
  free(scratch);
}

int gs_model_pore_coordinates(const gs_model *m, int *liquid, int *gas) {
  *liquid = *gas = -1;
  for (int k = 0; k < m->nvol; k++) {
    if (!strcmp(gs_model_vol_name(m, k), "liquid")) *liquid = k;
    if (!strcmp(gs_model_vol_name(m, k), "gas")) *gas = k;
  }
  return *liquid >= 0 || *gas >= 0;
}

/* Number-means of porosity and liquid content (gs_summary). */
static void pores(const gs_model *m, const double *y, size_t comp, gs_summary *s) {
  const gs_grid *g = &m->grid;
  const double *N = gs_model_numbers_c(m, y, comp);
  int liquid, gas;
  s->porosity = s->liquid_content = NAN;
  if (!gs_model_pore_coordinates(m, &liquid, &gas) || !(s->m0 > 0)) return;
  const double *L = liquid >= g->dim ? gs_model_carried_c(m, y, comp, liquid - g->dim) : NULL;
  const double *G = gas >= g->dim ? gs_model_carried_c(m, y, comp, gas - g->dim) : NULL;
  double por = 0, liq = 0;
  for (size_t c = 0; c < g->ncells; c++) {
    if (!(N[c] > 0)) continue;
    const double *x = g->x + c * (size_t)g->dim;
    double sol = 0, l = 0, gv = 0;
    for (int k = 0; k < g->dim; k++) {
      if (k == liquid) l = x[k];
      else if (k == gas) gv = x[k];
      else sol += x[k];
    }
    if (L) l = L[c] / N[c];
    if (G) gv = G[c] / N[c];
    const double v = sol + l + gv;
    if (!(v > 0)) continue;
    por += N[c] * (l + gv) / v;
    liq += N[c] * l / v;
  }
  s->porosity = por / s->m0;
  s->liquid_content = liq / s->m0;
}

/* The granule volume per cell: the size axes, plus what a particle carries
 * (liquid and gas fill the pores of the granule: the external volume of
 * Sampat et al. (2018)).  Returns m->size_volume when nothing is carried,
 * else *owned (to be freed), NULL without memory. */
static const double *granule_volumes(const gs_model *m, const double *y, size_t comp,
                                     double **owned) {
  const gs_grid *g = &m->grid;
  const double *N = gs_model_numbers_c(m, y, comp);
  *owned = NULL;
  if (!m->ncarried) return m->size_volume;
  double *vol = *owned = malloc((g->ncells ? g->ncells : 1) * sizeof *vol);
  for (size_t c = 0; vol && c < g->ncells; c++) {
    vol[c] = m->size_volume[c];
    for (int q = 0; q < m->ncarried; q++)
      if (N[c] > 0) vol[c] += gs_model_carried_c(m, y, comp, q)[c] / N[c];
  }
  return vol;
}

void gs_sieve_fractions(const gs_model *m, const double *y, size_t comp, const double *d,
                        size_t nclass, double *frac) {
  const size_t n = m->grid.ncells;
  double *owned, *v = malloc((nclass + 1) * sizeof *v);
  const double *vol = granule_volumes(m, y, comp, &owned);
  gs_size_range *r = malloc((n ? n : 1) * sizeof *r);
  if (v && vol && r) {
    for (size_t k = 0; k <= nclass; k++) v[k] = M_PI / 6 * d[k] * d[k] * d[k];
    gs_size_fractions_ranges(r, cell_ranges(m, vol, gs_model_numbers_c(m, y, comp), r), v, nclass,
                             frac);
  } else {
    for (size_t k = 0; k < nclass; k++) frac[k] = NAN;
  }
  free(v);
  free(owned);
  free(r);
}

void gs_summarize(const gs_model *m, const double *y, size_t comp, gs_summary *s) {
  const gs_grid *g = &m->grid;
  const double *N = gs_model_numbers_c(m, y, comp);
  memset(s, 0, sizeof *s);
  double *vol;
  const double *size = granule_volumes(m, y, comp, &vol);
  if (!size) size = m->size_volume; /* no memory: without the carried part */
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
  percentiles(m, size, N, p, 3, d);
  free(vol);
  s->d10 = d[0];
  s->d50 = d[1];
  s->d90 = d[2];
  pores(m, y, comp, s);
}
