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

typedef struct {
  double v, w;
} vw_t;

/* Stable sort of pts[0..n) by volume, tmp[0..n) scratch; returns where the
 * sorted points are (pts or tmp).  Bottom-up merges, inline: qsort's
 * comparator calls were most of an output time's summaries (~6 µs per
 * compartment of 256 cells; rank 0's work alone under MPI).  Stable, like
 * glibc's merge sort, so equal volumes merge in cell order as before. */
static vw_t *sort_by_volume(vw_t *pts, vw_t *tmp, size_t n) {
  vw_t *src = pts, *dst = tmp;
  for (size_t width = 1; width < n; width *= 2) {
    for (size_t lo = 0; lo < n; lo += 2 * width) {
      size_t mid = lo + width < n ? lo + width : n, hi = lo + 2 * width < n ? lo + 2 * width : n;
      size_t i = lo, j = mid, k = lo;
      while (i < mid && j < hi) dst[k++] = src[j].v < src[i].v ? src[j++] : src[i++];
      while (i < mid) dst[k++] = src[i++];
      while (j < hi) dst[k++] = src[j++];
    }
    vw_t *swap = src;
    src = dst;
    dst = swap;
  }
  return src;
}

/* Volume-weighted percentiles p[0..np-1] (fractions) of the diameter. */
static void percentiles(const double *vol, const double *N, size_t n, const double *p, int np,
                        double *out) {
  vw_t *pts = malloc(2 * n * sizeof *pts), *scratch = pts;
  size_t k = 0;
  double total = 0;
  for (size_t c = 0; pts && c < n; c++)
    if (N[c] > 0 && vol[c] > 0) {
      pts[k].v = vol[c];
      pts[k].w = N[c] * vol[c];
      total += pts[k].w;
      k++;
    }
  if (!pts || k == 0 || !(total > 0)) {
    for (int i = 0; i < np; i++) out[i] = NAN;
    free(pts);
    return;
  }
  pts = sort_by_volume(scratch, scratch + n, k);
  /* merge equal volumes, then cumulative midpoints */
  size_t m = 0;
  for (size_t i = 0; i < k; i++) {
    if (m && pts[m - 1].v == pts[i].v) pts[m - 1].w += pts[i].w;
    else pts[m++] = pts[i];
  }
  /* diameters (cube roots) only where a percentile falls: the output
   * summaries are rank 0's work alone under MPI */
  double below = 0, prev_q = 0;
  size_t prev = 0;
  int next = 0;
  for (size_t i = 0; i < m && next < np; i++) {
    double q = (below + 0.5 * pts[i].w) / total;
    if (p[next] <= q) {
      double d = gs_diameter(pts[i].v), prev_d = gs_diameter(pts[prev].v);
      while (next < np && p[next] <= q) {
        out[next] = (i == 0 || q == prev_q) ? d : prev_d + (d - prev_d) * (p[next] - prev_q) / (q - prev_q);
        next++;
      }
    }
    below += pts[i].w;
    prev_q = q;
    prev = i;
  }
  while (next < np) out[next++] = gs_diameter(pts[prev].v);
  free(scratch);
}

void gs_summarize(const gs_model *m, const double *y, size_t comp, gs_summary *s) {
  const gs_grid *g = &m->grid;
  const double *N = gs_model_numbers_c(m, y, comp);
  memset(s, 0, sizeof *s);
  /* granule volume per cell: the size axes, plus what a particle carries
   * (liquid and gas fill the pores of the granule: seed 000's external volume) */
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
