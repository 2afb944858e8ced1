/* Multi-dimensional grid: strides, pivot tables, index helpers. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "gransim/grid.h"

int gs_grid_init(gs_grid *g, gs_axis *axes, int dim, size_t ncomp, gs_error *err) {
  memset(g, 0, sizeof *g);
  if (dim < 1 || dim > GS_MAX_DIM)
    return gs_error_set(err, GS_EINPUT, "a grid needs 1 to %d axes, got %d", GS_MAX_DIM, dim);
  if (ncomp < 1) return gs_error_set(err, GS_EINPUT, "a grid needs at least one compartment");
  g->dim = dim;
  g->ncomp = ncomp;
  g->ncells = 1;
  for (int k = 0; k < dim; k++) {
    for (int j = 0; j < k; j++)
      if (!strcmp(g->axis[j].name, axes[k].name))
        return gs_error_set(err, GS_EINPUT, "two axes are both named '%s'", axes[k].name);
    g->axis[k] = axes[k];
    memset(&axes[k], 0, sizeof axes[k]);
    g->ncells *= g->axis[k].n;
  }
  for (int k = dim - 1; k >= 0; k--)
    g->stride[k] = (k == dim - 1) ? 1 : g->stride[k + 1] * g->axis[k + 1].n;
  g->x = gs_malloc(g->ncells * (size_t)dim * sizeof(double), err);
  g->volume = gs_malloc(g->ncells * sizeof(double), err);
  if (!g->x || !g->volume) {
    gs_grid_free(g);
    return GS_ENOMEM;
  }
  size_t idx[GS_MAX_DIM];
  for (size_t c = 0; c < g->ncells; c++) {
    gs_grid_unindex(g, c, idx);
    double v = 0;
    for (int k = 0; k < dim; k++) {
      g->x[c * (size_t)dim + (size_t)k] = g->axis[k].pivots[idx[k]];
      v += g->axis[k].pivots[idx[k]];
    }
    g->volume[c] = v;
  }
  return GS_OK;
}

void gs_grid_free(gs_grid *g) {
  for (int k = 0; k < g->dim; k++) gs_axis_free(&g->axis[k]);
  free(g->x);
  free(g->volume);
  memset(g, 0, sizeof *g);
}

size_t gs_grid_index(const gs_grid *g, const size_t *idx) {
  size_t c = 0;
  for (int k = 0; k < g->dim; k++) c += idx[k] * g->stride[k];
  return c;
}

void gs_grid_unindex(const gs_grid *g, size_t cell, size_t *idx) {
  for (int k = 0; k < g->dim; k++) {
    idx[k] = cell / g->stride[k];
    cell -= idx[k] * g->stride[k];
  }
}

int gs_grid_axis_by_name(const gs_grid *g, const char *name) {
  for (int k = 0; k < g->dim; k++)
    if (!strcmp(g->axis[k].name, name)) return k;
  return -1;
}

double gs_diameter(double v) { return cbrt(6.0 * v / M_PI); }
