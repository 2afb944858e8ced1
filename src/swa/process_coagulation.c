/* Coagulation (seed 001 eqs. 48-51).
 *
 * Weighted scheme (`scheme: swa`): an ordered pair (i, j) jumps at rate
 * K(x_i, x_j) w_j / V; particle i becomes x_i + x_j with weight
 * w_i m(x_i) / m(x_i + x_j) and j is unchanged, so the number of
 * computational particles is fixed and the mass of every jump balances
 * exactly.  Direct simulation (`scheme: dsa`): equal weights, an unordered
 * pair jumps at rate K w / V, i becomes the aggregate and j is removed
 * (doubling refills the ensemble).
 *
 * Selection uses the kernel's product form: constant K = b0 (j ~ w, i
 * uniform among the others); sum K = b0 (u_i + u_j) (two terms: i ~ u, j ~ w
 * and i uniform, j ~ u w); product K = b0 u_i u_j (i ~ u, j ~ u w).  The
 * terms are summed over all ordered pairs including i = j, which is then
 * a fictitious jump, and the majorant may be inflated by majorant_factor
 * (accepting with its inverse), which exercises the fictitious-jump path.
 * Optional: a coalescence rule and efficiency (a collision that does not
 * coalesce only compacts i, eq. 49) and compaction of the product (seed 001
 * eqs. 16-21).  `coalescence: wet_surface` stands in for the Stokes criterion
 * of Braumann et al. (2010), whose formula seed 001 does not give: only a
 * collision in which a partner has external (surface) liquid can coalesce,
 * as with a dry pair the criterion's liquid layer thickness is zero. */
#include <gsl/gsl_rng.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "swa/compaction.h"
#include "swa/sim.h"

enum { K_CONSTANT, K_SUM, K_PRODUCT };
enum { S_SWA, S_DSA };

typedef struct coag {
  const gs_swa_model *m;
  int kernel, scheme;
  double *beta0;   /* per compartment */
  unsigned axes;   /* size measure u of the kernel */
  double factor;   /* majorant factor >= 1 */
  double efficiency;
  int wet_surface, ext; /* coalesce only if a partner has external liquid */
  int col_u, col_uw;
  gs_swa_compaction comp;
} coag;

static double prop_u(const void *ctx, const double *x, double w) {
  const coag *c = ctx;
  (void)w;
  double u = 0;
  for (int k = 0; k < c->m->ncoord; k++)
    if (c->axes & (1u << k)) u += x[k];
  return u;
}
static double prop_uw(const void *ctx, const double *x, double w) { return prop_u(ctx, x, w) * w; }

static void coag_free(void *self) {
  coag *c = self;
  if (!c) return;
  gs_swa_compaction_free(&c->comp);
  free(c->beta0);
  free(c);
}

static int coag_create(gs_cfg_node *node, gs_swa_model *m, void **self, gs_error *err) {
  static const char *const kernels[] = {"constant", "sum", "product", NULL};
  static const char *const schemes[] = {"swa", "dsa", NULL};
  coag *c = gs_calloc(1, sizeof *c, err);
  if (!c) return GS_ENOMEM;
  *self = c;
  c->m = m;
  c->beta0 = gs_calloc(m->ncomp, sizeof(double), err);
  if (!c->beta0) return GS_ENOMEM;
  gs_cfg_node *k = NULL;
  int rc = gs_cfg_map_req(node, "kernel", &k, err);
  if (!rc && !gs_cfg_get(k, "type")) rc = gs_cfg_fail(k, err, "missing key 'type' (constant, sum or product)");
  if (!rc) rc = gs_cfg_enum_opt(k, "type", kernels, 0, &c->kernel, err);
  if (!rc) rc = gs_swa_per_comp(k, "beta0", 1, 0, 0, 0, m, c->beta0, err);
  if (!rc && c->kernel != K_CONSTANT) rc = gs_swa_coord_mask(k, "axes", m, m->size_mask, &c->axes, err);
  if (!rc) rc = gs_cfg_double_range(k, "majorant_factor", 0, 1, 1, 0, HUGE_VAL, 0, &c->factor, err);
  if (!rc) rc = gs_cfg_check_unused(k, err);
  if (!rc) rc = gs_cfg_enum_opt(node, "scheme", schemes, S_SWA, &c->scheme, err);
  if (!rc) rc = gs_cfg_double_range(node, "efficiency", 0, 1, 0, 0, 1, 0, &c->efficiency, err);
  static const char *const rules[] = {"always", "wet_surface", NULL};
  if (!rc) rc = gs_cfg_enum_opt(node, "coalescence", rules, 0, &c->wet_surface, err);
  if (!rc && c->wet_surface) rc = gs_swa_coord_key(node, "external_liquid", m, "external_liquid", &c->ext, err);
  if (!rc) rc = gs_swa_compaction_read(node, m, &c->comp, err);
  if (!rc && c->kernel != K_CONSTANT) {
    c->col_u = gs_swa_model_add_prop(m, prop_u, c);
    c->col_uw = gs_swa_model_add_prop(m, prop_uw, c);
    if (c->col_u < 0 || c->col_uw < 0) rc = gs_cfg_fail(node, err, "too many cached particle properties");
  }
  if (!rc) rc = gs_cfg_check_unused(node, err);
  return rc;
}

/* The majorant: all ordered pairs (i = j included) of the kernel's terms. */
static double term_a(const coag *c, const gs_swa_sim *s, size_t z) {
  double n = (double)gs_swa_count(s, z);
  switch (c->kernel) {
    case K_CONSTANT: return n * gs_swa_sum(s, z, 0);
    case K_SUM: return gs_swa_sum(s, z, c->col_u) * gs_swa_sum(s, z, 0);
    default: return gs_swa_sum(s, z, c->col_u) * gs_swa_sum(s, z, c->col_uw);
  }
}
static double term_b(const coag *c, const gs_swa_sim *s, size_t z) {
  return c->kernel == K_SUM ? (double)gs_swa_count(s, z) * gs_swa_sum(s, z, c->col_uw) : 0;
}

static double coag_rate(const void *self, const gs_swa_sim *s, size_t z) {
  const coag *c = self;
  if (gs_swa_count(s, z) < 2) return 0;
  double r = c->beta0[z] * c->factor * (term_a(c, s, z) + term_b(c, s, z)) / gs_swa_vsamp(s, z);
  return c->scheme == S_DSA ? 0.5 * r : r;
}

static int coag_jump(const void *self, gs_swa_sim *s, size_t z, gs_error *err) {
  const coag *c = self;
  const gs_swa_model *m = c->m;
  size_t i, j, n = gs_swa_count(s, z);
  if (c->kernel == K_CONSTANT) {
    j = gs_swa_select(s, z, c->scheme == S_DSA ? -1 : 0);
    i = gsl_rng_uniform_int(s->rng, n);
  } else {
    double a = term_a(c, s, z), b = term_b(c, s, z);
    if (gs_swa_uniform01(s) * (a + b) < a) {
      i = gs_swa_select(s, z, c->col_u);
      j = gs_swa_select(s, z, c->kernel == K_SUM ? 0 : c->col_uw);
    } else {
      i = gsl_rng_uniform_int(s->rng, n);
      j = gs_swa_select(s, z, c->col_uw);
    }
  }
  if (i == GS_NOWHERE || j == GS_NOWHERE || i == j ||
      (c->factor > 1 && gs_swa_uniform01(s) * c->factor >= 1)) {
    gs_swa_fictitious(s);
    return GS_OK;
  }
  double *xi = gs_swa_x(s, z, i), *xj = gs_swa_x(s, z, j);
  double wi = gs_swa_w(s, z, i), wj = gs_swa_w(s, z, j);
  int rebound = c->wet_surface && !(xi[c->ext] > 0 || xj[c->ext] > 0);
  if (rebound || (c->efficiency < 1 && gs_swa_uniform01(s) >= c->efficiency)) {
    gs_swa_compact(&c->comp, z, xi); /* rebound: compaction only (eq. 49) */
    gs_swa_update(s, z, i, wi);
    return GS_OK;
  }
  if (c->scheme == S_DSA) {
    if (wi != wj)
      return gs_error_set(err, GS_ENUMERIC,
                          "scheme dsa needs equal particle weights, found %g and %g (use scheme swa, or "
                          "solver.contraction: drop if particles are added to full compartments)", wi, wj);
    for (int k = 0; k < m->ncoord; k++) xi[k] += xj[k];
    gs_swa_compact(&c->comp, z, xi);
    gs_swa_update(s, z, i, wi);
    gs_swa_remove(s, z, j);
    return GS_OK;
  }
  double mi = gs_swa_mass(m, xi);
  for (int k = 0; k < m->ncoord; k++) xi[k] += xj[k];
  double mij = gs_swa_mass(m, xi);
  gs_swa_compact(&c->comp, z, xi);
  gs_swa_update(s, z, i, wi * mi / mij);
  return GS_OK;
}

const gs_swa_process_type gs_swa_coagulation = {
    .name = "aggregation",
    .summary = "coagulation, kernels constant/sum/product; weighted (swa) or direct (dsa)",
    .create = coag_create,
    .rate = coag_rate,
    .jump = coag_jump,
    .free = coag_free,
};
