/* Lever-rule placement of a packet of particles onto the 2^dim pivots that
 * surround its mean position, conserving number and the volume of every
 * coordinate (the redistribution step shared by the cell-average and
 * fixed-pivot techniques, for aggregation, breakage and initial data).
 *
 * Boundary rule (documented in docs/models.md): a coordinate below the first
 * pivot or above the last pivot of its axis is clamped to that pivot; number
 * is conserved and the volume this removes, count * (v - clamped v), is added
 * to excess[k] (negative below, positive above) so the caller books it in the
 * ledger as lost.  The rule is continuous in v, so rates stay smooth when a
 * pooled mean crosses the last pivot.  (Products beyond the last edge are
 * not placed at all: the callers book them as lost.) */
#ifndef GRANSIM_LEVER_H
#define GRANSIM_LEVER_H

#include "gransim/grid.h"

/* Lever around a known cell t of axis ax for value v: the node pair is
 * (t, t+1) when v >= pivot[t], else (t-1, t).  Returns -1 below the first
 * pivot, +1 above the last, 0 with *lo and weight *w of node lo+1. */
static inline int gs_lever_near(const gs_axis *ax, size_t t, double v, size_t *lo, double *w) {
  const double *p = ax->pivots;
  if (v >= p[t]) {
    if (t + 1 >= ax->n) {
      if (v > p[t]) return 1;
      *lo = t;
      *w = 0.0;
      return 0;
    }
    if (v > p[t + 1]) return gs_axis_lever(ax, v, lo, w); /* not adjacent: search */
    *lo = t;
    *w = (v - p[t]) / (p[t + 1] - p[t]);
    return 0;
  }
  if (t == 0) return -1;
  if (v < p[t - 1]) return gs_axis_lever(ax, v, lo, w);
  *lo = t - 1;
  *w = (v - p[t - 1]) / (p[t] - p[t - 1]);
  return 0;
}

/* Place `count` particles with mean coordinates v (dim entries) found in
 * cell `cell` (or GS_NOWHERE to search) into dst (one compartment).  Returns
 * the number of axes that had to be clamped; excess may be NULL. */
int gs_lever_place(const gs_grid *g, size_t cell, const double *v, double count, double *dst,
                   double *excess);
/* The same, and the packet's carried totals qtot[q] (q < nq) spread over the
 * same nodes with the same weights into qdst[q]: each node receives the
 * share of the carried volume that it receives of the particles. */
int gs_lever_place_carried(const gs_grid *g, size_t cell, const double *v, double count,
                           double *dst, double *excess, int nq, const double *qtot,
                           double *const *qdst);

/* Spread count over the 2^dim nodes given per-axis lower nodes and weights. */
static inline void gs_lever_spread(const gs_grid *g, const size_t *lo, const double *w,
                                   double count, double *dst) {
  const int dim = g->dim;
  for (int corner = 0; corner < (1 << dim); corner++) {
    double f = count;
    size_t idx = 0;
    for (int k = 0; k < dim; k++) {
      int up = (corner >> k) & 1;
      double wk = up ? w[k] : 1.0 - w[k];
      if (wk == 0.0) {
        f = 0.0;
        break;
      }
      f *= wk;
      idx += (lo[k] + (size_t)up) * g->stride[k];
    }
    if (f != 0.0) dst[idx] += f;
  }
}
#endif
