/* The classical kernels with analytical solutions: constant, sum (Golovin)
 * and product.  beta0 scales each; sum and product act on a size measure
 * (default the granule volume, the sum of all axes; key "axes" to choose). */
#include <math.h>
#include <stdlib.h>

#include "gransim/kernel.h"
#include "kernel/size_measure.h"

typedef struct {
  double beta0;
  double *size; /* per cell; NULL for the constant kernel */
} basic_kernel;

static int basic_create(gs_cfg_node *node, const gs_grid *g, void **self, int needs_size,
                        gs_error *err) {
  basic_kernel *k = gs_calloc(1, sizeof *k, err);
  if (!k) return GS_ENOMEM;
  int rc = gs_cfg_double_range(node, "beta0", 1, 0, 0, 0, HUGE_VAL, 0, &k->beta0, err);
  if (!rc && needs_size && !(k->size = gs_size_measure(node, g, err))) rc = err->code;
  if (!rc) rc = gs_cfg_check_unused(node, err);
  if (rc) {
    free(k->size);
    free(k);
    return rc;
  }
  *self = k;
  return GS_OK;
}

static void basic_free(void *self) {
  basic_kernel *k = self;
  free(k->size);
  free(k);
}

static int constant_create(gs_cfg_node *n, const gs_grid *g, const char *dir, void **s,
                           gs_error *e) {
  (void)dir;
  return basic_create(n, g, s, 0, e);
}
static int sized_create(gs_cfg_node *n, const gs_grid *g, const char *dir, void **s, gs_error *e) {
  (void)dir;
  return basic_create(n, g, s, 1, e);
}

static void constant_row(const void *self, size_t comp, size_t a, size_t b0, size_t b1,
                         double *out) {
  (void)comp;
  (void)a;
  const basic_kernel *k = self;
  for (size_t b = b0; b < b1; b++) out[b - b0] = k->beta0;
}

static void sum_row(const void *self, size_t comp, size_t a, size_t b0, size_t b1, double *out) {
  (void)comp;
  const basic_kernel *k = self;
  for (size_t b = b0; b < b1; b++) out[b - b0] = k->beta0 * (k->size[a] + k->size[b]);
}

static void product_row(const void *self, size_t comp, size_t a, size_t b0, size_t b1,
                        double *out) {
  (void)comp;
  const basic_kernel *k = self;
  for (size_t b = b0; b < b1; b++) out[b - b0] = k->beta0 * k->size[a] * k->size[b];
}

const gs_kernel_type gs_kernel_constant = {
    .name = "constant",
    .summary = "beta = beta0",
    .create = constant_create,
    .row = constant_row,
    .free = basic_free,
};
const gs_kernel_type gs_kernel_sum = {
    .name = "sum",
    .summary = "beta = beta0 (u + v) (Golovin)",
    .create = sized_create,
    .row = sum_row,
    .free = basic_free,
};
const gs_kernel_type gs_kernel_product = {
    .name = "product",
    .summary = "beta = beta0 u v",
    .create = sized_create,
    .row = product_row,
    .free = basic_free,
};
