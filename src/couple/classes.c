/* DEM size classes derived from the PBM grid (docs/models.md, "Coupled
 * cases"): every cell's size measure as a volume-equivalent diameter; the
 * diameters inside the window the DEM can afford are binned into `count`
 * classes of equal width in ln d (a geometric 1-D grid with count = its cells
 * in the window gives one DEM class per PBM cell); a class without a PBM cell
 * is an error, since its DEM particles would represent nothing. */
#include <math.h>
#include <stdlib.h>

#include "couple/couple_internal.h"
#include "gransim/kernel.h"

static int cmp_double(const void *a, const void *b) {
  double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

int gs_couple_classes_derive(const gs_grid *g, unsigned mask, const gs_couple_settings *s,
                             const gs_cfg_node *where, gs_couple_classes *cl, gs_error *err) {
  double *d = gs_malloc(g->ncells * sizeof(double), err);
  if (!d) return GS_ENOMEM;
  size_t nd = 0;
  for (size_t c = 0; c < g->ncells; c++) {
    double v = 0;
    for (int k = 0; k < g->dim; k++)
      if (mask & (1u << k)) v += g->x[c * (size_t)g->dim + k];
    double dc = gs_diameter(v);
    if (dc >= s->dmin && dc <= s->dmax) d[nd++] = dc;
  }
  qsort(d, nd, sizeof *d, cmp_double);
  /* cells of a 2-D grid share diameters (a + b = b + a): merge those within round-off */
  size_t u = 0;
  for (size_t i = 0; i < nd; i++)
    if (u == 0 || d[i] > d[u - 1] * (1 + 1e-9)) d[u++] = d[i];
  int rc = GS_OK;
  if (u == 0)
    rc = gs_cfg_fail(where, err, "no PBM cell has a diameter in [min_diameter, max_diameter] = [%g, %g] m: "
                     "the DEM would sample no class of the grid", s->dmin, s->dmax);
  size_t n = s->count ? (size_t)s->count : (u < GS_COUPLE_MAX_CLASSES ? u : GS_COUPLE_MAX_CLASSES);
  if (!rc && n > u)
    rc = gs_cfg_fail(where, err, "count = %zu classes but only %zu distinct PBM cell diameters lie in [%g, %g] m "
                     "(a class without cells); lower count or widen the window", n, u, s->dmin, s->dmax);
  if (rc) {
    free(d);
    return rc;
  }
  cl->n = n;
  /* n classes of equal width in ln d, centred on the smallest and the largest
   * diameter: on a geometric 1-D grid with one class per cell, each class is
   * one cell; on 2-D grids, whose sums cluster, classes follow the sizes */
  double lo = log(d[0]), hi = log(d[u - 1]);
  double h = n > 1 ? (hi - lo) / (double)(n - 1) : 0;
  if (!(h > 0)) h = n > 1 ? log(1.1) : 2 * log(1.05) + (hi - lo); /* one class: the whole span */
  if (n > 1)
    for (size_t k = 0; k <= n; k++) cl->edges[k] = exp(lo + h * ((double)k - 0.5));
  else {
    cl->edges[0] = exp(lo) / 1.05;
    cl->edges[1] = exp(hi) * 1.05;
  }
  free(d);
  /* which cells each class holds, and how many fall outside (nearest class) */
  cl->outside = 0;
  for (size_t k = 0; k < n; k++) cl->cells_in[k] = 0;
  for (size_t c = 0; c < g->ncells; c++) {
    double v = 0;
    for (int k = 0; k < g->dim; k++)
      if (mask & (1u << k)) v += g->x[c * (size_t)g->dim + k];
    double dc = gs_diameter(v);
    if (dc < cl->edges[0] || dc > cl->edges[n]) {
      if (s->outside_error)
        return gs_cfg_fail(where, err, "PBM cell %zu (diameter %g m) lies outside the DEM classes [%g, %g] m "
                           "and outside is 'error'; widen min_diameter/max_diameter or set outside: nearest",
                           c + 1, dc, cl->edges[0], cl->edges[n]);
      cl->outside++;
      continue;
    }
    size_t k = 0;
    while (k + 1 < n && dc >= cl->edges[k + 1]) k++;
    cl->cells_in[k]++;
  }
  for (size_t k = 0; k < n; k++)
    if (!cl->cells_in[k])
      return gs_cfg_fail(where, err, "DEM class %zu of %zu, diameters [%g, %g] m, holds no PBM cell; lower count",
                         k + 1, n, cl->edges[k], cl->edges[k + 1]);
  return GS_OK;
}
