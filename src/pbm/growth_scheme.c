/* Upwind pivot-transfer growth scheme; see growth_scheme.h. */
#include "pbm/growth_scheme.h"

void gs_growth_apply(const gs_grid *g, int axis, const double *G, const double *N, double *d,
                     double *ledger) {
  const gs_axis *ax = &g->axis[axis];
  const size_t n = ax->n, stride = g->stride[axis];
  const int dim = g->dim;
  double ext = 0, lost[GS_MAX_DIM] = {0};
  for (size_t c = 0; c < g->ncells; c++) {
    double rate = G[c], num = N[c];
    if (rate == 0.0 || num == 0.0) continue;
    size_t i = (c / stride) % n;
    if (rate > 0) {
      if (i + 1 < n) {
        double r = rate * num / (ax->pivots[i + 1] - ax->pivots[i]);
        d[c] -= r;
        d[c + stride] += r;
        ext += rate * num;
      } else if (n > 1) { /* leaves the grid through the top */
        double step = ax->pivots[i] - ax->pivots[i - 1];
        double r = rate * num / step;
        d[c] -= r;
        ext += rate * num;
        for (int k = 0; k < dim; k++)
          lost[k] += r * (g->x[c * (size_t)dim + (size_t)k] + (k == axis ? step : 0.0));
      }
    } else if (i > 0) {
      double r = -rate * num / (ax->pivots[i] - ax->pivots[i - 1]);
      d[c] -= r;
      d[c - stride] += r;
      ext += rate * num;
    }
  }
  if (ledger) {
    ledger[axis] += ext;
    for (int k = 0; k < dim; k++) ledger[dim + k] += lost[k];
  }
}
