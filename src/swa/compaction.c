/* Compaction at collisions (McGuire et al. 2018, eqs. 16-21, corrected): see compaction.h. */
#include <stdlib.h>

#include "swa/compaction.h"

int gs_swa_roles(gs_cfg_node *node, const gs_swa_model *m, int *solid, int *ext, int *in,
                 int *pores, gs_error *err) {
  int rc = gs_swa_coord_key(node, "solid", m, "solid", solid, err);
  if (!rc) rc = gs_swa_coord_key(node, "external_liquid", m, "external_liquid", ext, err);
  if (!rc) rc = gs_swa_coord_key(node, "internal_liquid", m, "internal_liquid", in, err);
  if (!rc) rc = gs_swa_coord_key(node, "pores", m, "pores", pores, err);
  return rc;
}

int gs_swa_compaction_read(gs_cfg_node *node, const gs_swa_model *m, gs_swa_compaction *c,
                           gs_error *err) {
  c->on = 0;
  c->rate = NULL;
  gs_cfg_node *n = gs_cfg_get(node, "compaction");
  if (!n) return GS_OK;
  int rc = gs_cfg_require_kind(n, GS_CFG_MAP, err);
  if (rc) return rc;
  c->rate = gs_calloc(m->ncomp, sizeof(double), err);
  if (!c->rate) return GS_ENOMEM;
  c->on = 1;
  rc = gs_swa_per_comp(n, "rate", 1, 0, 0, 0, m, c->rate, err);
  for (size_t z = 0; !rc && z < m->ncomp; z++)
    if (c->rate[z] > 1) rc = gs_cfg_fail(gs_cfg_get(n, "rate"), err, "expected fractions in [0, 1] (k_comp)");
  if (!rc) rc = gs_cfg_double_range(n, "min_porosity", 1, 0, 0, 0, 1, 1, &c->min_porosity, err);
  if (!rc) rc = gs_swa_roles(n, m, &c->solid, &c->ext, &c->in, &c->pores, err);
  if (!rc) rc = gs_cfg_check_unused(n, err);
  return rc;
}

void gs_swa_compaction_free(gs_swa_compaction *c) {
  free(c->rate);
  c->rate = NULL;
}

void gs_swa_compact(const gs_swa_compaction *c, size_t z, double *x) {
  if (!c->on) return;
  double s = x[c->solid], le = x[c->ext], li = x[c->in], p = x[c->pores];
  double v = s + le + p;
  if (!(p > 0) || !(v > 0)) return; /* dry primaries: eps = 0 < eps_min, unchanged */
  double eps = p / v;
  if (eps < c->min_porosity) return;
  double eps1 = eps - c->rate[z] * (eps - c->min_porosity);
  double sat = li / p;
  double p1 = eps1 * (s + le + li) / (1 - eps1 * (1 - sat));
  double li1 = li * p1 / p;
  x[c->pores] = p1;
  x[c->in] = li1;
  x[c->ext] = le + (li - li1);
}
