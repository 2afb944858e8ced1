/* Size measure of each cell from a chosen set of axes. */
#include <stdlib.h>

#include "kernel/size_measure.h"

double *gs_size_measure(gs_cfg_node *node, const gs_grid *g, gs_error *err) {
  int use[GS_MAX_DIM] = {0};
  gs_cfg_node *axes = gs_cfg_get(node, "axes");
  if (!axes) {
    for (int k = 0; k < g->dim; k++) use[k] = 1;
  } else {
    if (gs_cfg_require_kind(axes, GS_CFG_SEQ, err)) return NULL;
    for (size_t i = 0; i < gs_cfg_size(axes); i++) {
      gs_cfg_node *item = gs_cfg_item(axes, i);
      const char *name = gs_cfg_scalar(item);
      int k = name ? gs_grid_axis_by_name(g, name) : -1;
      if (k < 0) {
        gs_cfg_fail(item, err, "expected the name of a grid axis");
        return NULL;
      }
      use[k] = 1;
    }
  }
  double *size = gs_malloc(g->ncells * sizeof(double), err);
  if (!size) return NULL;
  for (size_t c = 0; c < g->ncells; c++) {
    double v = 0;
    for (int k = 0; k < g->dim; k++)
      if (use[k]) v += g->x[c * (size_t)g->dim + (size_t)k];
    size[c] = v;
  }
  return size;
}
