/* Registry of aggregation kernels: adding a kernel is one file and one line here. */
#include <math.h>
#include <stdlib.h>

#include "gransim/kernel.h"
#include "kernel/size_measure.h"

extern const gs_kernel_type gs_kernel_constant, gs_kernel_sum, gs_kernel_product,
    gs_kernel_madec, gs_kernel_table, gs_kernel_brownian, gs_kernel_semimech;

static const gs_kernel_type *const registry[] = {
    &gs_kernel_constant, &gs_kernel_sum, &gs_kernel_product, &gs_kernel_madec, &gs_kernel_table,
    &gs_kernel_brownian, &gs_kernel_semimech, NULL};

const gs_kernel_type *const *gs_kernel_types(void) { return registry; }

int gs_kernel_create(gs_cfg_node *node, const gs_grid *g, const char *dir, gs_kernel *k,
                     gs_error *err) {
  k->type = gs_registry_pick(node, (const void *const *)registry, "kernel", err);
  k->self = NULL;
  if (!k->type) return GS_EINPUT;
  return k->type->create(node, g, dir, &k->self, err);
}

void gs_kernel_free(gs_kernel *k) {
  if (k->type && k->self) k->type->free(k->self);
  k->type = NULL;
  k->self = NULL;
}

int gs_kernel_beta0(gs_cfg_node *node, int required, double def, const gs_grid *g, double **out,
                    int *differ, gs_error *err) {
  gs_cfg_node *n = gs_cfg_get(node, "beta0");
  double *b = gs_calloc(g->ncomp, sizeof(double), err);
  int rc = b ? GS_OK : GS_ENOMEM;
  if (!rc && n && gs_cfg_kind_of(n) == GS_CFG_SEQ) {
    rc = gs_cfg_per_comp(node, "beta0", required, def, 0, 0, g->ncomp, b, err);
  } else if (!rc) {
    rc = gs_cfg_double_range(node, "beta0", required, def, 0, 0, HUGE_VAL, 0, &b[0], err);
    for (size_t z = 1; !rc && z < g->ncomp; z++) b[z] = b[0];
  }
  *differ = 0;
  for (size_t z = 1; !rc && z < g->ncomp; z++) *differ |= b[z] != b[0];
  if (rc) {
    free(b);
    b = NULL;
  }
  *out = b;
  return rc;
}
