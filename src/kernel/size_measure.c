/* Size measure of each cell from a chosen set of axes. */
#include <stdlib.h>

#include "kernel/size_measure.h"

int gs_size_axes(gs_cfg_node *node, const gs_grid *g, unsigned *mask, gs_error *err) {
  gs_cfg_node *axes = gs_cfg_get(node, "axes");
  *mask = 0;
  if (!axes) {
    *mask = (1u << g->dim) - 1;
    return GS_OK;
  }
  if (gs_cfg_require_kind(axes, GS_CFG_SEQ, err)) return GS_EINPUT;
  for (size_t i = 0; i < gs_cfg_size(axes); i++) {
    gs_cfg_node *item = gs_cfg_item(axes, i);
    const char *name = gs_cfg_scalar(item);
    int k = name ? gs_grid_axis_by_name(g, name) : -1;
    if (k < 0) return gs_cfg_fail(item, err, "expected the name of a grid axis");
    *mask |= 1u << k;
  }
  return GS_OK;
}

double gs_size_of(unsigned mask, int dim, const double *x) {
  double v = 0;
  for (int k = 0; k < dim; k++)
    if (mask & (1u << k)) v += x[k];
  return v;
}

double *gs_size_measure_mask(gs_cfg_node *node, const gs_grid *g, unsigned *mask, gs_error *err) {
  if (gs_size_axes(node, g, mask, err)) return NULL;
  double *size = gs_malloc(g->ncells * sizeof(double), err);
  if (!size) return NULL;
  for (size_t c = 0; c < g->ncells; c++) size[c] = gs_size_of(*mask, g->dim, g->x + c * (size_t)g->dim);
  return size;
}

double *gs_size_measure(gs_cfg_node *node, const gs_grid *g, gs_error *err) {
  unsigned mask;
  return gs_size_measure_mask(node, g, &mask, err);
}
