/* See gs_size_percentiles and gs_size_percentiles_ranges in
 * gransim/grid.h: point masses for the stochastic solver's summaries
 * (src/swa/summary.c: a point per particle), ranges for the sectional ones
 * (src/pbm/summary.c: a range per cell). */
#include <math.h>

#include "gransim/grid.h"

/* Stable sort of pts[0..n) by volume, tmp[0..n) scratch; returns where the
 * sorted points are (pts or tmp).  Bottom-up merges, inline: qsort calls
 * its comparator through a pointer for every comparison, and that was most
 * of the time of an output time's summaries, which under MPI rank 0 does
 * alone.  Stable, so equal volumes merge in their original order. */
static gs_size_point *sort_by_volume(gs_size_point *pts, gs_size_point *tmp, size_t n) {
  gs_size_point *src = pts, *dst = tmp;
  for (size_t width = 1; width < n; width *= 2) {
    for (size_t lo = 0; lo < n; lo += 2 * width) {
      size_t mid = lo + width < n ? lo + width : n, hi = lo + 2 * width < n ? lo + 2 * width : n;
      size_t i = lo, j = mid, k = lo;
      while (i < mid && j < hi) dst[k++] = src[j].v < src[i].v ? src[j++] : src[i++];
      while (i < mid) dst[k++] = src[i++];
      while (j < hi) dst[k++] = src[j++];
    }
    gs_size_point *swap = src;
    src = dst;
    dst = swap;
  }
  return src;
}

void gs_size_percentiles(gs_size_point *pts, gs_size_point *scratch, size_t n, const double *p,
                         int np, double *out) {
  double total = 0;
  for (size_t i = 0; i < n; i++) total += pts[i].w;
  if (n == 0 || !(total > 0)) {
    for (int i = 0; i < np; i++) out[i] = NAN;
    return;
  }
  pts = sort_by_volume(pts, scratch, n);
  /* merge equal volumes, then cumulative midpoints */
  size_t m = 0;
  for (size_t i = 0; i < n; i++) {
    if (m && pts[m - 1].v == pts[i].v) pts[m - 1].w += pts[i].w;
    else pts[m++] = pts[i];
  }
  /* diameters (cube roots) only where a percentile falls */
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
}

void gs_size_percentiles_ranges(const gs_size_range *r, size_t n, gs_size_point *scratch,
                                const double *p, int np, double *out) {
  /* The cumulative weight is piecewise linear: its slope changes by
   * w / (hi - lo) at lo and back at hi.  Sort those 2 n events and walk. */
  gs_size_point *ev = scratch;
  size_t m = 0;
  double total = 0;
  for (size_t i = 0; i < n; i++) {
    if (!(r[i].w > 0) || !(r[i].hi > r[i].lo)) continue;
    const double slope = r[i].w / (r[i].hi - r[i].lo);
    ev[m++] = (gs_size_point){r[i].lo, slope};
    ev[m++] = (gs_size_point){r[i].hi, -slope};
    total += r[i].w;
  }
  if (!m) {
    for (int i = 0; i < np; i++) out[i] = NAN;
    return;
  }
  ev = sort_by_volume(ev, scratch + 2 * n, m);
  double F = 0, slope = 0, x = ev[0].v;
  int next = 0;
  for (size_t i = 0; i < m && next < np; i++) {
    const double F_end = F + slope * (ev[i].v - x);
    for (; next < np && p[next] * total <= F_end; next++)
      out[next] = slope > 0 ? fmin(x + (p[next] * total - F) / slope, ev[i].v) : x;
    F = F_end;
    slope += ev[i].w;
    x = ev[i].v;
  }
  /* round-off may leave the walk's total just below the weights' sum */
  while (next < np) out[next++] = ev[m - 1].v;
  /* cube roots only for the percentiles (docs/performance.md) */
  for (int i = 0; i < np; i++) out[i] = gs_diameter(out[i]);
}

void gs_size_fractions_ranges(const gs_size_range *r, size_t n, const double *v, size_t nclass,
                              double *frac) {
  double total = 0;
  for (size_t k = 0; k < nclass; k++) frac[k] = 0;
  for (size_t i = 0; i < n; i++) {
    if (!(r[i].w > 0) || !(r[i].hi > r[i].lo)) continue;
    total += r[i].w;
    const double density = r[i].w / (r[i].hi - r[i].lo);
    for (size_t k = 0; k < nclass; k++) {
      const double a = fmax(r[i].lo, v[k]), b = fmin(r[i].hi, v[k + 1]);
      if (b > a) frac[k] += density * (b - a);
    }
  }
  for (size_t k = 0; k < nclass; k++) frac[k] = total > 0 ? frac[k] / total : NAN;
}
