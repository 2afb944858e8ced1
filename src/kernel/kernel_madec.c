/* Madec et al. (2003) liquid-content kernel, in the form of seeds 002 (eq.
 * 2.5/3.9) and 004 (eq. 4):
 *   beta = beta0 (V + V') [ (c + c')^alpha (S - (c + c')/2)^delta ]^alpha
 * with V the granule volume (sum of all axes), c = S l / V the liquid content
 * and S = 100 for liquid content in percent (Chaudhury 2015) or 1 for a fraction
 * (De et al. 2025).  Dry pairs (c + c' = 0) do not aggregate when alpha > 0.
 *
 * Majorant (stochastic solver): the liquid is one of the axes summed into V,
 * so 0 <= c <= S and s = c + c' lies in [0, 2S].  On that interval
 * s^alpha (S - s/2)^delta is largest where alpha/s = delta/(2S - s), at
 * s* = 2S alpha/(alpha + delta), and raising it to alpha >= 0 keeps the
 * maximiser, so beta <= beta0 f(s*) (V + V'): a sum-kernel form on the
 * granule volume that holds for every state, however the population moves.
 * (Linear case alpha = delta = 1: f(s*) = S^2/2.) */
#include <math.h>
#include <stdlib.h>

#include "gransim/kernel.h"
#include "kernel/size_measure.h"

typedef struct {
  double *beta0; /* per compartment */
  int differ;    /* beta0 differs between compartments */
  double alpha, delta, scale;
  int dim, axis;  /* axis: the liquid */
  double *volume, *content; /* per cell */
  double *bound;  /* per compartment: beta0 f(s*), the majorant's coefficient */
} madec_kernel;

static void madec_free(void *self) {
  madec_kernel *k = self;
  free(k->beta0);
  free(k->bound);
  free(k->volume);
  free(k->content);
  free(k);
}

/* The liquid-content factor of a pair whose contents sum to c. */
static double madec_f(const madec_kernel *k, double c) {
  const double s = k->scale;
  if (k->alpha == 1.0 && k->delta == 1.0) return c * (s - 0.5 * c); /* the tabulated case: no pow() */
  return pow(pow(c, k->alpha) * pow(fmax(s - 0.5 * c, 0.0), k->delta), k->alpha);
}

static int madec_create(gs_cfg_node *node, const gs_grid *g, const char *dir, void **self,
                        gs_error *err) {
  (void)dir;
  static const char *const units[] = {"percent", "fraction", NULL};
  madec_kernel *k = gs_calloc(1, sizeof *k, err);
  if (!k) return GS_ENOMEM;
  const char *liquid = NULL;
  int unit = 0;
  int rc = gs_kernel_beta0(node, 1, 0, g, &k->beta0, &k->differ, err);
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
    k->bound = gs_malloc(g->ncomp * sizeof(double), err);
    if (!k->volume || !k->content || !k->bound) rc = GS_ENOMEM;
  }
  if (rc) {
    madec_free(k);
    return rc;
  }
  k->dim = g->dim;
  k->axis = axis;
  for (size_t c = 0; c < g->ncells; c++) {
    double v = g->volume[c];
    k->volume[c] = v;
    k->content[c] = v > 0 ? k->scale * g->x[c * (size_t)g->dim + (size_t)axis] / v : 0.0;
  }
  double top = k->alpha + k->delta > 0 ? 2 * k->scale * k->alpha / (k->alpha + k->delta) : 0;
  for (size_t z = 0; z < g->ncomp; z++) k->bound[z] = k->beta0[z] * madec_f(k, top);
  *self = k;
  return GS_OK;
}

static void madec_row(const void *self, size_t comp, size_t a, size_t b0, size_t b1,
                      double *out) {
  const madec_kernel *k = self;
  /* loads hoisted and the linear case apart: the loop then vectorises (out
   * might alias the kernel's arrays as far as the compiler knows) */
  const double va = k->volume[a], ca = k->content[a], s = k->scale, beta0 = k->beta0[comp];
  const double *volume = k->volume, *content = k->content;
  if (k->alpha == 1.0 && k->delta == 1.0) {
    for (size_t b = b0; b < b1; b++) {
      const double c = ca + content[b];
      out[b - b0] = beta0 * (va + volume[b]) * (c * (s - 0.5 * c));
    }
    return;
  }
  for (size_t b = b0; b < b1; b++) out[b - b0] = beta0 * (va + volume[b]) * madec_f(k, ca + content[b]);
}

static int madec_per_compartment(const void *self) { return ((const madec_kernel *)self)->differ; }

/* The linear case (alpha = delta = 1) is a few multiplications per pair on
 * two per-cell arrays, which the row loop vectorises: as fast as reading a
 * table, and a 3-D table is large (docs/performance.md, "Kernel tables").
 * The general case calls pow twice per pair. */
static int madec_cheap_row(const void *self) {
  const madec_kernel *k = self;
  return k->alpha == 1.0 && k->delta == 1.0;
}

/* V and c of a particle, as create() takes them at the pivots. */
static double madec_content(const madec_kernel *k, const double *x, double *v) {
  *v = gs_size_of((1u << k->dim) - 1, k->dim, x);
  return *v > 0 ? k->scale * x[k->axis] / *v : 0.0;
}

static double madec_at(const void *self, size_t comp, const double *x, const double *y) {
  const madec_kernel *k = self;
  double vx, vy, cx = madec_content(k, x, &vx), cy = madec_content(k, y, &vy);
  return k->beta0[comp] * (vx + vy) * madec_f(k, cx + cy);
}

static void madec_form(const void *self, gs_kernel_form *out) {
  const madec_kernel *k = self;
  *out = (gs_kernel_form){.kind = GS_KERNEL_FORM_SUM, .coef = k->bound, .axes = (1u << k->dim) - 1, .exact = 0};
}

/* The linear case as separable terms: with s = c + c',
 *   (V + V') s (S - s/2) = (V + V') (S c + S c' - c^2/2 - c'^2/2 - c c'),
 * ten products of the per-cell functions 1, V, c, c^2, V c, V c^2 (the
 * rows' own arrays, so the terms equal the rows up to round-off). */
static int madec_terms(const void *self, size_t ncells, gs_kernel_terms *out) {
  const madec_kernel *k = self;
  if (!(k->alpha == 1.0 && k->delta == 1.0)) return 0;
  enum { ONE, V, C, C2, VC, VC2, NPHI };
  double *phi = malloc(NPHI * ncells * sizeof(double));
  if (!phi) return -1;
  for (size_t i = 0; i < ncells; i++) {
    const double v = k->volume[i], c = k->content[i];
    phi[ONE * ncells + i] = 1;
    phi[V * ncells + i] = v;
    phi[C * ncells + i] = c;
    phi[C2 * ncells + i] = c * c;
    phi[VC * ncells + i] = v * c;
    phi[VC2 * ncells + i] = v * c * c;
  }
  const double S = k->scale;
  /* V's terms (a's function first), then V''s (the same, a and b swapped) */
  static const int f[5][2] = {{VC, ONE}, {V, C}, {VC2, ONE}, {V, C2}, {VC, C}};
  const double w[5] = {S, S, -0.5, -0.5, -1};
  *out = (gs_kernel_terms){.nphi = NPHI, .nterm = 10, .phi = phi, .coef = k->beta0};
  for (int t = 0; t < 5; t++) {
    out->c[t] = out->c[t + 5] = w[t];
    out->m1[t] = out->m2[t + 5] = f[t][0];
    out->m2[t] = out->m1[t + 5] = f[t][1];
  }
  return 10;
}

const gs_kernel_type gs_kernel_madec = {
    .name = "madec",
    .summary = "beta0 (V+V') [(c+c')^alpha (S-(c+c')/2)^delta]^alpha, liquid content c",
    .create = madec_create,
    .row = madec_row,
    .free = madec_free,
    .per_compartment = madec_per_compartment,
    .cheap_row = madec_cheap_row,
    .at = madec_at,
    .form = madec_form,
    .terms = madec_terms,
};
