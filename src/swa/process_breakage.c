/* Binary breakage (McGuire et al. 2018, eqs. 22, 52-57), number-conserving: particle i
 * breaks at rate s0_z * g(x_i), with g = v^exponent for v >= min_volume
 * (and, with wet_only, only if it holds liquid or pores: dry primaries never
 * break); a fraction f ~ Beta(a, b) of the parent (every coordinate scaled
 * by f) is one fragment, the remainder the other.  The particle becomes the
 * first fragment with probability f, else the second, and its weight becomes
 * w m(x) / m(y), so the mass of every jump balances exactly and the fragment
 * count is right in expectation.  The cached g may be stale under LPDA; it
 * is then a majorant (penetration only shrinks particles) and the jump is
 * accepted with g_now / g_cached. */
#include <gsl/gsl_randist.h>
#include <math.h>
#include <stdlib.h>

#include "swa/compaction.h"
#include "swa/sim.h"

typedef struct brk {
  const gs_swa_model *m;
  double *s0;
  double exponent, min_volume, a, b;
  int wet_only, solid, ext, in, pores;
  int col;
} brk;

static double prop_g(const void *ctx, const double *x, double w) {
  const brk *b = ctx;
  (void)w;
  double v = gs_swa_size(b->m, x);
  if (!(v > 0) || v < b->min_volume) return 0;
  if (b->wet_only && !(x[b->ext] + x[b->in] + x[b->pores] != 0)) return 0;
  return pow(v, b->exponent);
}

static void brk_free(void *self) {
  brk *b = self;
  if (b) free(b->s0);
  free(b);
}

static int brk_create(gs_cfg_node *node, gs_swa_model *m, void **self, gs_error *err) {
  brk *b = gs_calloc(1, sizeof *b, err);
  if (!b) return GS_ENOMEM;
  *self = b;
  b->m = m;
  b->s0 = gs_calloc(m->ncomp, sizeof(double), err);
  if (!b->s0) return GS_ENOMEM;
  gs_cfg_node *sel = NULL, *d = NULL;
  int rc = gs_cfg_map_req(node, "selection", &sel, err);
  if (!rc) rc = gs_swa_per_comp(sel, "s0", 1, 0, 0, 0, m, b->s0, err);
  if (!rc) rc = gs_cfg_double_opt(sel, "exponent", 1, &b->exponent, err);
  if (!rc) rc = gs_cfg_double_range(sel, "min_volume", 0, 0, 0, 0, HUGE_VAL, 0, &b->min_volume, err);
  if (!rc) rc = gs_cfg_bool_opt(sel, "wet_only", 0, &b->wet_only, err);
  if (!rc && b->wet_only) rc = gs_swa_roles(sel, m, &b->solid, &b->ext, &b->in, &b->pores, err);
  if (!rc) rc = gs_cfg_check_unused(sel, err);
  if (!rc) rc = gs_cfg_map_req(node, "daughters", &d, err);
  if (!rc) {
    static const char *const types[] = {"beta", "uniform", NULL};
    int type = 0;
    if (!gs_cfg_get(d, "type")) rc = gs_cfg_missing(d, "type", "(beta or uniform)", err);
    if (!rc) rc = gs_cfg_enum_opt(d, "type", types, 0, &type, err);
    b->a = b->b = 1;
    if (!rc && type == 0) rc = gs_cfg_double_range(d, "alpha", 1, 0, 0, 1, HUGE_VAL, 0, &b->a, err);
    if (!rc && type == 0) rc = gs_cfg_double_range(d, "beta", 1, 0, 0, 1, HUGE_VAL, 0, &b->b, err);
    if (!rc) rc = gs_cfg_check_unused(d, err);
  }
  if (!rc) {
    b->col = gs_swa_model_add_prop(m, prop_g, b);
    if (b->col < 0) rc = gs_cfg_fail(node, err, "too many cached particle properties");
  }
  if (!rc) rc = gs_cfg_check_unused(node, err);
  return rc;
}

static double brk_rate(const void *self, const gs_swa_sim *s, size_t z) {
  const brk *b = self;
  return b->s0[z] * gs_swa_sum(s, z, b->col); /* eq. 57 */
}

static int brk_jump(const void *self, gs_swa_sim *s, size_t z, gs_error *err) {
  const brk *b = self;
  (void)err;
  size_t i = gs_swa_select(s, z, b->col);
  if (i == GS_NOWHERE) {
    gs_swa_fictitious(s);
    return GS_OK;
  }
  double cached = gs_swa_prop(s, z, i, b->col);
  double *x = gs_swa_x(s, z, i);
  double now = gs_swa_prop(s, z, i, b->col);
  if (now < cached && gs_swa_uniform01(s) * cached >= now) {
    gs_swa_fictitious(s);
    return GS_OK;
  }
  double f = gsl_ran_beta(s->rng, b->a, b->b);
  if (!(f > 0 && f < 1)) {
    gs_swa_fictitious(s); /* a fragment of zero mass changes nothing */
    return GS_OK;
  }
  double keep = gs_swa_uniform01(s) < f ? f : 1 - f; /* eq. 55-56 */
  for (int k = 0; k < b->m->ncoord; k++) x[k] *= keep;
  gs_swa_update(s, z, i, gs_swa_w(s, z, i) / keep); /* eq. 54: w m(x) / m(y) */
  return GS_OK;
}

const gs_swa_process_type gs_swa_breakage = {
    .name = "breakage",
    .summary = "binary breakage, rate s0 v^exponent, Beta(a, b) fragments, mass-based weights",
    .create = brk_create,
    .rate = brk_rate,
    .jump = brk_jump,
    .free = brk_free,
};
