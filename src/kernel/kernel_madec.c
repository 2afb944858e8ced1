/* Madec et al. (2003) liquid-content kernel, in the form of seeds 002 (eq.
 * 2.5/3.9) and 004 (eq. 4):
 *   beta = beta0 (V + V') [ (c + c')^alpha (S - (c + c')/2)^delta ]^alpha
 * with V the granule volume (sum of all axes), c = S l / V the liquid content
 * and S = 100 for liquid content in percent (seed 002) or 1 for a fraction
 * (seed 004).  Dry pairs (c + c' = 0) do not aggregate when alpha > 0. */
#include <math.h>
#include <stdlib.h>

#include "gransim/kernel.h"

typedef struct {
  double beta0, alpha, delta, scale;
  double *volume, *content; /* per cell */
} madec_kernel;

static void madec_free(void *self) {
  madec_kernel *k = self;
  free(k->volume);
  free(k->content);
  free(k);
}

static int madec_create(gs_cfg_node *node, const gs_grid *g, const char *dir, void **self,
                        gs_error *err) {
  (void)dir;
  static const char *const units[] = {"percent", "fraction", NULL};
  madec_kernel *k = gs_calloc(1, sizeof *k, err);
  if (!k) return GS_ENOMEM;
  const char *liquid = NULL;
  int unit = 0;
  int rc = gs_cfg_double_range(node, "beta0", 1, 0, 0, 0, HUGE_VAL, 0, &k->beta0, err);
  if (!rc) rc = gs_cfg_double_range(node, "alpha", 0, 1, 0, 0, HUGE_VAL, 0, &k->alpha, err);
  if (!rc) rc = gs_cfg_double_range(node, "delta", 0, 1, 0, 0, HUGE_VAL, 0, &k->delta, err);
  if (!rc) rc = gs_cfg_enum_opt(node, "liquid_content", units, 0, &unit, err);
  if (!rc) rc = gs_cfg_string_opt(node, "liquid_axis", "liquid", &liquid, err);
  int axis = rc ? -1 : gs_grid_axis_by_name(g, liquid);
  if (!rc && axis < 0) {
    gs_cfg_node *n = gs_cfg_get(node, "liquid_axis");
    rc = n ? gs_cfg_fail(n, err, "expected the name of a grid axis")
           : gs_cfg_fail(node, err,
                         "the madec kernel needs a grid axis named 'liquid' (or set liquid_axis)");
  }
  if (!rc) rc = gs_cfg_check_unused(node, err);
  if (!rc) {
    k->scale = unit == 0 ? 100.0 : 1.0;
    k->volume = gs_malloc(g->ncells * sizeof(double), err);
    k->content = gs_malloc(g->ncells * sizeof(double), err);
    if (!k->volume || !k->content) rc = GS_ENOMEM;
  }
  if (rc) {
    madec_free(k);
    return rc;
  }
  for (size_t c = 0; c < g->ncells; c++) {
    double v = g->volume[c];
    k->volume[c] = v;
    k->content[c] = v > 0 ? k->scale * g->x[c * (size_t)g->dim + (size_t)axis] / v : 0.0;
  }
  *self = k;
  return GS_OK;
}

static void madec_row(const void *self, size_t comp, size_t a, size_t b0, size_t b1,
                      double *out) {
  (void)comp;
  const madec_kernel *k = self;
  const double va = k->volume[a], ca = k->content[a], s = k->scale;
  const int linear = k->alpha == 1.0 && k->delta == 1.0; /* the tabulated case: no pow() */
  for (size_t b = b0; b < b1; b++) {
    double c = ca + k->content[b];
    double f = linear ? c * (s - 0.5 * c)
                      : pow(pow(c, k->alpha) * pow(fmax(s - 0.5 * c, 0.0), k->delta), k->alpha);
    out[b - b0] = k->beta0 * (va + k->volume[b]) * f;
  }
}

const gs_kernel_type gs_kernel_madec = {
    .name = "madec",
    .summary = "beta0 (V+V') [(c+c')^alpha (S-(c+c')/2)^delta]^alpha, liquid content c",
    .create = madec_create,
    .row = madec_row,
    .free = madec_free,
};
