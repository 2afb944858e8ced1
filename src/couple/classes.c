/* DEM size classes derived from the PBM grid (docs/models.md, "Coupled
 * cases"): every cell's size measure as a volume-equivalent diameter; the
 * distinct diameters inside the window the DEM can afford are split into
 * `count` runs of consecutive values, so every DEM class holds PBM cells and a
 * 1-D grid with count = cells gives one DEM class per PBM cell. */
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
  /* class k takes distinct diameters [k*u/n, (k+1)*u/n); edges halfway (geometric) between runs */
  double lo_step = u > 1 ? sqrt(d[1] / d[0]) : 1.05, hi_step = u > 1 ? sqrt(d[u - 1] / d[u - 2]) : 1.05;
  cl->edges[0] = d[0] / lo_step;
  for (size_t k = 1; k < n; k++) {
    size_t first = k * u / n;
    cl->edges[k] = sqrt(d[first - 1] * d[first]);
  }
  cl->edges[n] = d[u - 1] * hi_step;
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
  return GS_OK;
}
