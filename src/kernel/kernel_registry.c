/* Registry of aggregation kernels: adding a kernel is one file and one line here. */
#include "gransim/kernel.h"

extern const gs_kernel_type gs_kernel_constant, gs_kernel_sum, gs_kernel_product,
    gs_kernel_madec, gs_kernel_table;

static const gs_kernel_type *const registry[] = {
    &gs_kernel_constant, &gs_kernel_sum, &gs_kernel_product, &gs_kernel_madec, &gs_kernel_table,
    NULL};

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
