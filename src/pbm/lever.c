/* Lever-rule placement; see lever.h. */
#include "pbm/lever.h"

int gs_lever_place(const gs_grid *g, size_t cell, const double *v, double count, double *dst,
                   double *excess) {
  return gs_lever_place_carried(g, cell, v, count, dst, excess, 0, NULL, NULL);
}

int gs_lever_place_carried(const gs_grid *g, size_t cell, const double *v, double count,
                           double *dst, double *excess, int nq, const double *qtot,
                           double *const *qdst) {
  int clamped = 0;
  size_t lo[GS_MAX_DIM], idx[GS_MAX_DIM];
  double w[GS_MAX_DIM];
  if (cell != GS_NOWHERE) gs_grid_unindex(g, cell, idx);
  for (int k = 0; k < g->dim; k++) {
    const gs_axis *ax = &g->axis[k];
    int st = cell != GS_NOWHERE ? gs_lever_near(ax, idx[k], v[k], &lo[k], &w[k])
                                : gs_axis_lever(ax, v[k], &lo[k], &w[k]);
    if (st != 0) {
      size_t edge = st < 0 ? 0 : ax->n - 1;
      lo[k] = edge;
      w[k] = 0.0;
      if (excess) excess[k] += count * (v[k] - ax->pivots[edge]);
      clamped++;
    }
  }
  gs_lever_spread(g, lo, w, count, dst);
  for (int q = 0; q < nq; q++) gs_lever_spread(g, lo, w, qtot[q], qdst[q]);
  return clamped;
}
