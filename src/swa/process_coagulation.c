/* Coagulation (McGuire et al. 2018, eqs. 48-51).
 *
 * Weighted scheme (`scheme: swa`): an ordered pair (i, j) jumps at rate
 * K(x_i, x_j) w_j / V; particle i becomes x_i + x_j with weight
 * w_i m(x_i) / m(x_i + x_j) and j is unchanged, so the number of
 * computational particles is fixed and the mass of every jump balances
 * exactly.  Direct simulation (`scheme: dsa`): equal weights, an unordered
 * pair jumps at rate K w / V, i becomes the aggregate and j is removed
 * (doubling refills the ensemble).
 *
 * The kernel is a registered aggregation kernel (src/kernel, the same
 * `kernel` map as the sectional solver), evaluated at the particles'
 * coordinates that the grid axes name.  Selection uses the product form the
 * kernel type gives (gs_kernel_form), a majorant K^ >= K: constant K^ = b0
 * (j ~ w, i uniform among the others); sum K^ = b0 (u_i + u_j) (two terms:
 * i ~ u, j ~ w and i uniform, j ~ u w); product K^ = b0 u_i u_j (i ~ u,
 * j ~ u w).  The terms are summed over all ordered pairs including i = j,
 * which is then a fictitious jump, and the majorant may be inflated by
 * majorant_factor (accepting with its inverse), which exercises the
 * fictitious-jump path.  When the form is only a bound (madec, table), a
 * selected pair jumps with probability K(x_i, x_j) / K^(x_i, x_j), both taken
 * at the particles' current states (thinning), else the jump is fictitious.
 * Optional: a coalescence rule and efficiency (a collision that does not
 * coalesce only compacts i, eq. 49) and compaction of the product (McGuire et al. 2018
 * eqs. 16-21).  `coalescence: wet_surface` stands in for the Stokes criterion
 * of Braumann et al. (2010), whose formula McGuire et al. (2018) do not give: only a
 * collision in which a partner has external (surface) liquid can coalesce,
 * as with a dry pair the criterion's liquid layer thickness is zero. */
#include <gsl/gsl_rng.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "gransim/kernel.h"
#include "swa/compaction.h"
#include "swa/sim.h"

enum { S_SWA, S_DSA };

typedef struct coag {
  const gs_swa_model *m;
  gs_kernel kernel;
  gs_kernel_form form; /* the majorant; form.coef per compartment */
  int scheme;
  unsigned axes;   /* size measure u of the form, as a mask of coordinates */
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
  gs_kernel_free(&c->kernel);
  free(c);
}

/* The kernel from the registry, as the sectional aggregation reads it;
 * majorant_factor, a key of this solver alone, is taken out first. */
static int read_kernel(gs_cfg_node *k, gs_swa_model *m, coag *c, gs_error *err) {
  int rc = gs_cfg_double_range(k, "majorant_factor", 0, 1, 1, 0, HUGE_VAL, 0, &c->factor, err);
  if (!rc && !m->grid) rc = gs_cfg_fail(k, err, "the swa model has no grid to create the kernel on");
  if (!rc) rc = gs_kernel_create(k, m->grid, m->dir, &c->kernel, err);
  if (rc) return rc;
  const gs_kernel_type *t = c->kernel.type;
  if (!t->at || !t->form)
    return gs_cfg_fail(gs_cfg_get(k, "type"), err, "kernel type '%s' gives no majorant, so the swa solver cannot use it",
                       t->name);
  t->form(c->kernel.self, &c->form);
  c->axes = 0;
  for (int a = 0; a < m->grid->dim; a++)
    if (c->form.axes & (1u << a)) c->axes |= 1u << m->bin_coord[a];
  return GS_OK;
}

static int coag_create(gs_cfg_node *node, gs_swa_model *m, void **self, gs_error *err) {
  static const char *const schemes[] = {"swa", "dsa", NULL};
  coag *c = gs_calloc(1, sizeof *c, err);
  if (!c) return GS_ENOMEM;
  *self = c;
  c->m = m;
  gs_cfg_node *k = NULL;
  int rc = gs_cfg_map_req(node, "kernel", &k, err);
  if (!rc) rc = read_kernel(k, m, c, err);
  if (!rc) rc = gs_cfg_enum_opt(node, "scheme", schemes, S_SWA, &c->scheme, err);
  if (!rc) rc = gs_cfg_double_range(node, "efficiency", 0, 1, 0, 0, 1, 0, &c->efficiency, err);
  static const char *const rules[] = {"always", "wet_surface", NULL};
  if (!rc) rc = gs_cfg_enum_opt(node, "coalescence", rules, 0, &c->wet_surface, err);
  if (!rc && c->wet_surface) rc = gs_swa_coord_key(node, "external_liquid", m, "external_liquid", &c->ext, err);
  if (!rc) rc = gs_swa_compaction_read(node, m, &c->comp, err);
  if (!rc && c->form.kind != GS_KERNEL_FORM_CONSTANT) {
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
  switch (c->form.kind) {
    case GS_KERNEL_FORM_CONSTANT: return n * gs_swa_sum(s, z, 0);
    case GS_KERNEL_FORM_SUM: return gs_swa_sum(s, z, c->col_u) * gs_swa_sum(s, z, 0);
    default: return gs_swa_sum(s, z, c->col_u) * gs_swa_sum(s, z, c->col_uw);
  }
}
static double term_b(const coag *c, const gs_swa_sim *s, size_t z) {
  return c->form.kind == GS_KERNEL_FORM_SUM ? (double)gs_swa_count(s, z) * gs_swa_sum(s, z, c->col_uw) : 0;
}

/* Thinning for a form that only bounds the kernel: K / K^ at the current
 * states (1 for an exact form, which draws nothing). */
static int accepted(const coag *c, gs_swa_sim *s, size_t z, const double *xi, const double *xj) {
  if (c->form.exact) return 1;
  const gs_grid *g = c->m->grid;
  double gi[GS_MAX_DIM], gj[GS_MAX_DIM];
  for (int a = 0; a < g->dim; a++) {
    gi[a] = xi[c->m->bin_coord[a]];
    gj[a] = xj[c->m->bin_coord[a]];
  }
  double k = c->kernel.type->at(c->kernel.self, z, gi, gj), hat = c->form.coef[z];
  if (c->form.kind == GS_KERNEL_FORM_SUM) hat *= prop_u(c, xi, 0) + prop_u(c, xj, 0);
  if (c->form.kind == GS_KERNEL_FORM_PRODUCT) hat *= prop_u(c, xi, 0) * prop_u(c, xj, 0);
  return gs_swa_uniform01(s) * hat < k;
}

static double coag_rate(const void *self, const gs_swa_sim *s, size_t z) {
  const coag *c = self;
  if (gs_swa_count(s, z) < 2) return 0;
  double r = c->form.coef[z] * c->factor * (term_a(c, s, z) + term_b(c, s, z)) / gs_swa_vsamp(s, z);
  return c->scheme == S_DSA ? 0.5 * r : r;
}

static int coag_jump(const void *self, gs_swa_sim *s, size_t z, gs_error *err) {
  const coag *c = self;
  const gs_swa_model *m = c->m;
  size_t i, j, n = gs_swa_count(s, z);
  if (c->form.kind == GS_KERNEL_FORM_CONSTANT) {
    j = gs_swa_select(s, z, c->scheme == S_DSA ? -1 : 0);
    i = gsl_rng_uniform_int(s->rng, n);
  } else {
    double a = term_a(c, s, z), b = term_b(c, s, z);
    if (gs_swa_uniform01(s) * (a + b) < a) {
      i = gs_swa_select(s, z, c->col_u);
      j = gs_swa_select(s, z, c->form.kind == GS_KERNEL_FORM_SUM ? 0 : c->col_uw);
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
  if (!accepted(c, s, z, xi, xj)) {
    gs_swa_fictitious(s);
    return GS_OK;
  }
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
    .summary = "coagulation with a registered kernel (majorant and thinning); weighted (swa) or direct (dsa)",
    .create = coag_create,
    .rate = coag_rate,
    .jump = coag_jump,
    .free = coag_free,
};

const char *gs_swa_coag_kernel(const gs_swa_process *p, int *product) {
  if (p->type != &gs_swa_coagulation) return NULL;
  const coag *c = p->self;
  *product = c->form.kind == GS_KERNEL_FORM_PRODUCT;
  return c->kernel.type->name;
}
