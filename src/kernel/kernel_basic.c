/* The classical kernels with analytical solutions: constant, sum (Golovin)
 * and product.  beta0 scales each (one value, or one per compartment); sum
 * and product act on a size measure (default the granule volume, the sum of
 * all axes; key "axes" to choose).  Each is its own product form, which the
 * stochastic solver selects pairs from without rejection. */
#include <math.h>
#include <stdlib.h>

#include "gransim/kernel.h"
#include "kernel/size_measure.h"

typedef struct {
  double *beta0; /* per compartment */
  int differ;    /* beta0 differs between compartments */
  int dim;
  unsigned axes; /* the axes of the size measure */
  double *size;  /* per cell; NULL for the constant kernel */
} basic_kernel;

static void basic_free(void *self) {
  basic_kernel *k = self;
  free(k->beta0);
  free(k->size);
  free(k);
}

static int basic_create(gs_cfg_node *node, const gs_grid *g, void **self, int needs_size,
                        gs_error *err) {
  basic_kernel *k = gs_calloc(1, sizeof *k, err);
  if (!k) return GS_ENOMEM;
  k->dim = g->dim;
  int rc = gs_kernel_beta0(node, 1, 0, g, &k->beta0, &k->differ, err);
  if (!rc && needs_size && !(k->size = gs_size_measure_mask(node, g, &k->axes, err))) rc = err->code;
  if (!rc) rc = gs_cfg_check_unused(node, err);
  if (rc) {
    basic_free(k);
    return rc;
  }
  *self = k;
  return GS_OK;
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
  (void)a;
  const double beta0 = ((const basic_kernel *)self)->beta0[comp];
  for (size_t b = b0; b < b1; b++) out[b - b0] = beta0;
}

static void sum_row(const void *self, size_t comp, size_t a, size_t b0, size_t b1, double *out) {
  const basic_kernel *k = self;
  const double beta0 = k->beta0[comp], sa = k->size[a], *size = k->size;
  for (size_t b = b0; b < b1; b++) out[b - b0] = beta0 * (sa + size[b]);
}

static void product_row(const void *self, size_t comp, size_t a, size_t b0, size_t b1,
                        double *out) {
  const basic_kernel *k = self;
  const double beta0 = k->beta0[comp], sa = k->size[a], *size = k->size;
  for (size_t b = b0; b < b1; b++) out[b - b0] = beta0 * sa * size[b];
}

static int basic_per_compartment(const void *self) { return ((const basic_kernel *)self)->differ; }

/* a fill, a sum or a product of two numbers per pair */
static int basic_cheap_row(const void *self) {
  (void)self;
  return 1;
}

static double constant_at(const void *self, size_t comp, const double *x, const double *y) {
  (void)x;
  (void)y;
  return ((const basic_kernel *)self)->beta0[comp];
}
static double sum_at(const void *self, size_t comp, const double *x, const double *y) {
  const basic_kernel *k = self;
  return k->beta0[comp] * (gs_size_of(k->axes, k->dim, x) + gs_size_of(k->axes, k->dim, y));
}
static double product_at(const void *self, size_t comp, const double *x, const double *y) {
  const basic_kernel *k = self;
  return k->beta0[comp] * gs_size_of(k->axes, k->dim, x) * gs_size_of(k->axes, k->dim, y);
}

static void form_of(const void *self, int kind, gs_kernel_form *out) {
  const basic_kernel *k = self;
  *out = (gs_kernel_form){.kind = kind, .coef = k->beta0, .axes = k->axes, .exact = 1};
}
static void constant_form(const void *self, gs_kernel_form *out) {
  form_of(self, GS_KERNEL_FORM_CONSTANT, out);
}
static void sum_form(const void *self, gs_kernel_form *out) { form_of(self, GS_KERNEL_FORM_SUM, out); }
static void product_form(const void *self, gs_kernel_form *out) {
  form_of(self, GS_KERNEL_FORM_PRODUCT, out);
}

const gs_kernel_type gs_kernel_constant = {
    .name = "constant",
    .summary = "beta = beta0",
    .create = constant_create,
    .row = constant_row,
    .free = basic_free,
    .per_compartment = basic_per_compartment,
    .cheap_row = basic_cheap_row,
    .at = constant_at,
    .form = constant_form,
};
const gs_kernel_type gs_kernel_sum = {
    .name = "sum",
    .summary = "beta = beta0 (u + v) (Golovin)",
    .create = sized_create,
    .row = sum_row,
    .free = basic_free,
    .per_compartment = basic_per_compartment,
    .cheap_row = basic_cheap_row,
    .at = sum_at,
    .form = sum_form,
};
const gs_kernel_type gs_kernel_product = {
    .name = "product",
    .summary = "beta = beta0 u v",
    .create = sized_create,
    .row = product_row,
    .free = basic_free,
    .per_compartment = basic_per_compartment,
    .cheap_row = basic_cheap_row,
    .at = product_at,
    .form = product_form,
};
