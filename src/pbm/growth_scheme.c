/* Upwind pivot-transfer growth scheme; see growth_scheme.h. */
#include <math.h>

#include "pbm/growth_scheme.h"

void gs_growth_apply(const gs_grid *g, int axis, const double *G, const double *N, double *d,
                     double *exchanged, double *lost_out) {
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
        if (d) {
          d[c] -= r;
          d[c + stride] += r;
        }
        ext += rate * num;
      } else if (n > 1) { /* leaves the grid through the top */
        double step = ax->pivots[i] - ax->pivots[i - 1];
        double r = rate * num / step;
        if (d) d[c] -= r;
        ext += rate * num;
        for (int k = 0; k < dim; k++)
          lost[k] += r * (g->x[c * (size_t)dim + (size_t)k] + (k == axis ? step : 0.0));
      }
    } else if (i > 0) {
      double r = -rate * num / (ax->pivots[i] - ax->pivots[i - 1]);
      if (d) {
        d[c] -= r;
        d[c - stride] += r;
      }
      ext += rate * num;
    }
  }
  if (exchanged) exchanged[axis] += ext;
  if (lost_out)
    for (int k = 0; k < dim; k++) lost_out[k] += lost[k];
}

/* Transfer rate coefficient of the cell at index i along the axis: particles
 * leave at k * N towards i+1 (k > 0) or i-1 (k < 0). */
static double transfer_coefficient(const gs_axis *ax, size_t i, double rate) {
  const size_t n = ax->n;
  if (rate > 0) {
    if (i + 1 < n) return rate / (ax->pivots[i + 1] - ax->pivots[i]);
    return n > 1 ? rate / (ax->pivots[i] - ax->pivots[i - 1]) : 0.0;
  }
  if (rate < 0 && i > 0) return rate / (ax->pivots[i] - ax->pivots[i - 1]);
  return 0.0;
}

void gs_growth_solve(const gs_grid *g, int axis, const double *G, double gamma, double *z,
                     double *zexchanged, double *zlost, double *work) {
  const gs_axis *ax = &g->axis[axis];
  const size_t n = ax->n, stride = g->stride[axis];
  double *cp = work, *k = work + n; /* Thomas: modified super-diagonal; coefficients */
  for (size_t base = 0; base < g->ncells; base++) {
    if ((base / stride) % n != 0) continue; /* one line per first cell along the axis */
    for (size_t i = 0; i < n; i++) k[i] = transfer_coefficient(ax, i, G[base + i * stride]);
    /* row i: -gamma k+_{i-1} z_{i-1} + (1 + gamma |k_i|) z_i - gamma k-_{i+1} z_{i+1} = r_i */
    double prev_c = 0, prev_z = 0;
    for (size_t i = 0; i < n; i++) {
      const size_t c = base + i * stride;
      double a = i > 0 && k[i - 1] > 0 ? -gamma * k[i - 1] : 0.0;
      double b = 1 + gamma * fabs(k[i]);
      double up = i + 1 < n && k[i + 1] < 0 ? gamma * k[i + 1] : 0.0; /* -gamma |k-| */
      double den = b - a * prev_c;
      cp[i] = up / den;
      z[c] = (z[c] - a * prev_z) / den;
      prev_c = cp[i];
      prev_z = z[c];
    }
    for (size_t i = n - 1; i-- > 0;) {
      const size_t c = base + i * stride;
      z[c] -= cp[i] * z[c + stride];
    }
  }
  /* the ledger's rows of I - gamma J: its entries are linear in the numbers
   * (frozen rates), so z_ledger = r_ledger + gamma * ledger rate of z.  Left
   * as identity, the preconditioner would not conserve volume, and every
   * inexact Krylov solve would move the volume balance off round-off. */
  if (!zexchanged && !zlost) return;
  double ext[GS_MAX_DIM] = {0}, lost[GS_MAX_DIM] = {0};
  gs_growth_apply(g, axis, G, z, NULL, ext, lost);
  for (int k = 0; k < g->dim; k++) {
    if (zexchanged) zexchanged[k] += gamma * ext[k];
    if (zlost) zlost[k] += gamma * lost[k];
  }
}

int gs_growth_axis_key(gs_cfg_node *node, const gs_grid *g, const char *key, const char *def,
                       int *out, gs_error *err) {
  const char *name;
  int rc = def ? gs_cfg_string_opt(node, key, def, &name, err) : gs_cfg_string_req(node, key, &name, err);
  if (rc) return rc;
  *out = gs_grid_axis_by_name(g, name);
  if (*out >= 0) return GS_OK;
  gs_cfg_node *n = gs_cfg_get(node, key);
  if (n) return gs_cfg_fail(n, err, "expected the name of a grid axis");
  return gs_cfg_fail(node, err, "needs a grid axis named '%s' (or set '%s')", def ? def : "?", key);
}

int gs_mech_read_window(gs_cfg_node *node, double *start, double *end, gs_error *err) {
  int rc = gs_cfg_double_range(node, "start", 0, 0, -HUGE_VAL, 0, HUGE_VAL, 0, start, err);
  if (!rc) rc = gs_cfg_double_range(node, "end", 0, HUGE_VAL, *start, 1, HUGE_VAL, 0, end, err);
  return rc;
}
