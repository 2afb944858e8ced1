/* Lever-rule placement; see lever.h. */
#include "pbm/lever.h"

int gs_lever_place(const gs_grid *g, size_t cell, const double *v, double count, double *dst,
                   double *excess) {
  return gs_lever_place_carried(g, cell, v, count, dst, excess, 0, NULL, NULL);
}

/* Two axes, a known cell, no clamping (the births and fragments of the
 * CoriMix grids): the four nodes and their factors found once for the
 * particles and every carried quantity.  Each amount is multiplied by the
 * factors in the order gs_lever_spread uses, so the results are the same bit
 * for bit (as built here, without contraction into fused multiply-adds,
 * which a compiler could apply to the two paths differently).  Returns 0
 * when the general path must place the packet. */
static int place_two_axes(const gs_grid *g, size_t cell, const double *v, double count,
                          double *dst, int nq, const double *qtot, double *const *qdst) {
  const size_t n1 = g->stride[0], i0 = cell / n1, i1 = cell - i0 * n1;
  size_t lo0, lo1;
  double w0, w1;
  if (gs_lever_near(&g->axis[0], i0, v[0], &lo0, &w0) != 0 ||
      gs_lever_near(&g->axis[1], i1, v[1], &lo1, &w1) != 0)
    return 0;
  /* corner c: bit k set = upper node along axis k (gs_lever_spread's order) */
  const double f0[4] = {1.0 - w0, w0, 1.0 - w0, w0}, f1[4] = {1.0 - w1, 1.0 - w1, w1, w1};
  const size_t base = lo0 * n1 + lo1;
  const size_t at[4] = {base, base + n1, base + 1, base + n1 + 1};
  for (int c = 0; c < 4; c++) {
    if (f0[c] == 0.0 || f1[c] == 0.0) continue; /* no such node (an edge), or no share */
    double f = count * f0[c] * f1[c];
    if (f != 0.0) dst[at[c]] += f;
    for (int q = 0; q < nq; q++) {
      f = qtot[q] * f0[c] * f1[c];
      if (f != 0.0) qdst[q][at[c]] += f;
    }
  }
  return 1;
}

int gs_lever_place_carried(const gs_grid *g, size_t cell, const double *v, double count,
                           double *dst, double *excess, int nq, const double *qtot,
                           double *const *qdst) {
  if (g->dim == 2 && cell != GS_NOWHERE && place_two_axes(g, cell, v, count, dst, nq, qtot, qdst))
    return 0;
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
