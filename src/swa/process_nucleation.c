/* Immersion nucleation: droplet addition and the unified nucleation jump of
 * McGuire et al. (2018) (Section 3.4, eqs. 40-47, 73-77; Appendix A), in the limit of
 * instantaneous nuclei growth.
 *
 * A droplet (0, v_drop, 0, 0) of weight w_drop is incepted at rate
 * R_drop V / w_drop and, before time moves on, absorbs ensemble particles
 * until its external liquid is used up.  Partners are selected with the
 * majorant k v_i (w_nuc + w_i) over particles with v_i < max_volume in two
 * stages (with probability w_nuc S_v / (w_nuc S_v + S_vw) proportional to
 * v, else to v w) and accepted with max(w_i, w_nuc) / (w_i + w_nuc), so a
 * partner is taken with probability proportional to v_i max(w_i, w_nuc)
 * (eq. 42).  The weight gamma = min(w_i, w_nuc) moves from the partner to
 * the nucleus, and the two nucleus products are merged (eq. 73), so the
 * nucleus keeps weight w_drop.  Every accepted step balances mass exactly. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "swa/compaction.h"
#include "swa/sim.h"

typedef struct nuc {
  const gs_swa_model *m;
  size_t comp;
  double rate;   /* physical droplets per unit time */
  double vdrop, wdrop, phimax, sat, vmax;
  double start, end;
  int solid, ext, in, pores;
  int col_v, col_vw;
  long max_steps;
} nuc;

static double prop_v(const void *ctx, const double *x, double w) {
  const nuc *n = ctx;
  (void)w;
  double v = gs_swa_size(n->m, x);
  return v < n->vmax ? v : 0;
}
static double prop_vw(const void *ctx, const double *x, double w) { return prop_v(ctx, x, w) * w; }

static void nuc_free(void *self) { free(self); }

static int nuc_create(gs_cfg_node *node, gs_swa_model *m, void **self, gs_error *err) {
  nuc *n = gs_calloc(1, sizeof *n, err);
  if (!n) return GS_ENOMEM;
  *self = n;
  n->m = m;
  long comp = 1;
  double d = 0;
  int rc = gs_cfg_long_range(node, "compartment", 0, 1, 1, (long)m->ncomp, &comp, err);
  n->comp = (size_t)(comp - 1);
  if (!rc) rc = gs_cfg_double_range(node, "droplet_diameter", 1, 0, 0, 1, HUGE_VAL, 0, &d, err);
  n->vdrop = M_PI / 6 * d * d * d;
  if (!rc && !!gs_cfg_get(node, "rate") == !!gs_cfg_get(node, "liquid_rate"))
    rc = gs_cfg_fail(node, err, "immersion_nucleation needs exactly one of 'rate' (droplets per unit time) or 'liquid_rate' (liquid volume per unit time)");
  if (!rc && gs_cfg_get(node, "rate")) rc = gs_cfg_double_range(node, "rate", 1, 0, 0, 0, HUGE_VAL, 0, &n->rate, err);
  if (!rc && gs_cfg_get(node, "liquid_rate")) {
    rc = gs_cfg_double_range(node, "liquid_rate", 1, 0, 0, 0, HUGE_VAL, 0, &n->rate, err);
    n->rate /= n->vdrop; /* eq. 8 */
  }
  if (!rc) rc = gs_cfg_double_range(node, "droplet_weight", 1, 0, 0, 1, HUGE_VAL, 0, &n->wdrop, err);
  if (!rc) rc = gs_cfg_double_range(node, "max_saturation", 0, 1.08, 0, 1, HUGE_VAL, 0, &n->phimax, err);
  if (!rc) rc = gs_cfg_double_range(node, "pore_saturation", 0, 1, 0, 1, 1, 0, &n->sat, err);
  if (!rc) rc = gs_cfg_double_range(node, "max_volume", 0, n->vdrop, 0, 1, HUGE_VAL, 0, &n->vmax, err);
  if (!rc) rc = gs_cfg_long_range(node, "max_steps", 0, 10000000, 1, 2000000000L, &n->max_steps, err);
  if (!rc) rc = gs_cfg_double_opt(node, "start", -HUGE_VAL, &n->start, err);
  if (!rc) rc = gs_cfg_double_range(node, "end", 0, HUGE_VAL, n->start, 1, HUGE_VAL, 0, &n->end, err);
  if (!rc) rc = gs_swa_roles(node, m, &n->solid, &n->ext, &n->in, &n->pores, err);
  if (!rc) {
    n->col_v = gs_swa_model_add_prop(m, prop_v, n);
    n->col_vw = gs_swa_model_add_prop(m, prop_vw, n);
    if (n->col_v < 0 || n->col_vw < 0) rc = gs_cfg_fail(node, err, "too many cached particle properties");
  }
  if (!rc) rc = gs_cfg_check_unused(node, err);
  return rc;
}

static double nuc_rate(const void *self, const gs_swa_sim *s, size_t z) {
  const nuc *n = self;
  if (z != n->comp || s->t < n->start || s->t >= n->end) return 0;
  return n->rate * gs_swa_vsamp(s, z) / (n->wdrop * gs_swa_gain(s, z)); /* eq. 47 */
}

/* T_nuc(x_nuc, x_i), eqs. 10-13: the partner's solid joins, all its liquid
 * becomes internal, and it absorbs external liquid of the nucleus up to
 * max_saturation; the pores are reset to l_i / s*. */
static void t_nuc(const nuc *n, const double *xn, const double *xi, double *out) {
  int nc = n->m->ncoord;
  for (int k = 0; k < nc; k++) out[k] = xn[k] + xi[k];
  double so = xi[n->solid];
  double phi = so > 0 ? (xi[n->ext] + xi[n->in]) / so : HUGE_VAL;
  double cap = phi <= n->phimax ? (n->phimax - phi) * so : 0;
  double a = fmin(cap, xn[n->ext]);
  out[n->ext] = xn[n->ext] - a;
  out[n->in] = xn[n->in] + xi[n->in] + xi[n->ext] + a;
  out[n->pores] = out[n->in] / n->sat;
}

static int nuc_jump(const void *self, gs_swa_sim *s, size_t z, gs_error *err) {
  const nuc *n = self;
  const gs_swa_model *m = n->m;
  int nc = m->ncoord;
  double xn[GS_SWA_MAX_COORD] = {0}, t[GS_SWA_MAX_COORD];
  xn[n->ext] = n->vdrop;
  double wn = n->wdrop * gs_swa_gain(s, z), tol = 1e-12 * n->vdrop;
  for (long step = 0; xn[n->ext] > tol; step++) {
    if (step >= n->max_steps)
      return gs_error_set(err, GS_ENUMERIC,
                          "a nucleus did not use up its external liquid in %ld selections (left %g of %g); "
                          "raise solver.particles or droplet_weight", n->max_steps, xn[n->ext], n->vdrop);
    double sv = gs_swa_sum(s, z, n->col_v), svw = gs_swa_sum(s, z, n->col_vw);
    if (!(sv > 0))
      return gs_error_set(err, GS_ENUMERIC,
                          "no particles left for a nucleus to absorb (liquid left %g of %g); the ensemble "
                          "is too small for this droplet weight (McGuire et al. 2018: unstable below N_max = 128)",
                          xn[n->ext], n->vdrop);
    int col = gs_swa_uniform01(s) * (wn * sv + svw) < wn * sv ? n->col_v : n->col_vw; /* eqs. 76-77 */
    size_t i = gs_swa_select(s, z, col);
    if (i == GS_NOWHERE) continue;
    double *xi = gs_swa_x(s, z, i); /* LPDA: bring the partner up to date */
    double wi = gs_swa_w(s, z, i);
    if (!(gs_swa_prop(s, z, i, n->col_v) > 0)) continue; /* grew past max_volume meanwhile */
    if (gs_swa_uniform01(s) * (wi + wn) >= fmax(wi, wn)) continue; /* fictitious, eq. 44 */
    double g = fmin(wi, wn);
    t_nuc(n, xn, xi, t);
    for (int k = 0; k < nc; k++) xn[k] += g / wn * (t[k] - xn[k]); /* eq. 73 merge */
    if (wi - g <= 1e-14 * wi) gs_swa_remove(s, z, i);
    else gs_swa_update(s, z, i, wi - g);
  }
  /* round-off remainder: keep the liquid, as internal liquid */
  xn[n->in] += xn[n->ext];
  xn[n->ext] = 0;
  xn[n->pores] = xn[n->in] / n->sat;
  return gs_swa_add(s, z, xn, wn, err);
}

const gs_swa_process_type gs_swa_nucleation = {
    .name = "immersion_nucleation",
    .summary = "droplet addition and unified immersion-nucleation jump (McGuire et al. 2018)",
    .create = nuc_create,
    .rate = nuc_rate,
    .jump = nuc_jump,
    .free = nuc_free,
};
