/* Liquid inflow and its sharing rules (liquid_share.h). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gransim/pbm.h"
#include "pbm/liquid_share.h"

static double solid_weight(const gs_liquid_share *s, double solid, double gross) {
  (void)s;
  (void)gross;
  return solid;
}

/* psi of a granule of gross volume V: the constant, or the table's class of
 * its diameter (granules outside the table take its first or last class) */
static double psi_of(const gs_liquid_share *s, double gross) {
  if (!s->npsi) return s->psi;
  const double d = cbrt(6 * gross / M_PI);
  size_t k = 0;
  while (k + 1 < s->npsi && d >= s->psi_edges[k + 1]) k++;
  return s->psi_values[k];
}

static double absorption_weight(const gs_liquid_share *s, double solid, double gross) {
  (void)solid;
  return gross * psi_of(s, gross);
}

/* probability: a number in (0, 1], or {diameters: [n + 1 edges, m], values: [n]} */
static int absorption_read(gs_cfg_node *n, gs_liquid_share *s, gs_error *err) {
  gs_cfg_node *p = gs_cfg_get(n, "probability");
  s->psi = 1;
  if (!p || gs_cfg_kind_of(p) != GS_CFG_MAP)
    return gs_cfg_double_range(n, "probability", 0, 1, 0, 1, 1, 0, &s->psi, err);
  size_t ne = 0, nv = 0;
  int rc = gs_cfg_doubles_req(p, "diameters", 0, &s->psi_edges, &ne, err);
  if (!rc) rc = gs_cfg_doubles_req(p, "values", 0, &s->psi_values, &nv, err);
  if (!rc && (nv < 1 || ne != nv + 1))
    rc = gs_cfg_fail(p, err, "expected n + 1 diameters (class edges, m) and n values, got %zu and %zu", ne, nv);
  for (size_t k = 0; !rc && k < ne; k++)
    if (!(s->psi_edges[k] >= 0) || (k && !(s->psi_edges[k] > s->psi_edges[k - 1])))
      rc = gs_cfg_fail(gs_cfg_get(p, "diameters"), err, "expected increasing diameters >= 0 [m]");
  for (size_t k = 0; !rc && k < nv; k++)
    if (!(s->psi_values[k] > 0 && s->psi_values[k] <= 1))
      rc = gs_cfg_fail(gs_cfg_get(p, "values"), err, "expected probabilities in (0, 1], got %g", s->psi_values[k]);
  if (!rc) rc = gs_cfg_check_unused(p, err);
  if (!rc) s->npsi = nv;
  return rc;
}

const gs_liquid_share_type gs_share_solid_volume = {
    .name = "solid_volume",
    .summary = "in proportion to solid volume (Sampat et al. 2018, eq. 5)",
    .weight = solid_weight,
};
const gs_liquid_share_type gs_share_absorption = {
    .name = "absorption",
    .summary = "in proportion to granule volume times absorption probability (De et al. 2025, eqs. 7-9)",
    .read = absorption_read,
    .weight = absorption_weight,
    .needs_gross = 1,
};
const gs_liquid_share_type *const gs_liquid_shares[] = {&gs_share_solid_volume, &gs_share_absorption, NULL};

void gs_liquid_share_list(FILE *fp) {
  for (const gs_liquid_share_type *const *t = gs_liquid_shares; *t; t++) fprintf(fp, "  %-16s %s\n", (*t)->name, (*t)->summary);
}

int gs_liquid_share_read(gs_cfg_node *node, gs_liquid_share *s, gs_error *err) {
  memset(s, 0, sizeof *s);
  s->type = &gs_share_solid_volume;
  gs_cfg_node *n = gs_cfg_get(node, "share");
  if (!n) return GS_OK;
  s->type = gs_registry_pick(n, (const void *const *)gs_liquid_shares, "liquid sharing rule", err);
  if (!s->type) return err->code;
  int rc = s->type->read ? s->type->read(n, s, err) : GS_OK;
  return rc ? rc : gs_cfg_check_unused(n, err);
}

void gs_liquid_share_free(gs_liquid_share *s) {
  free(s->psi_edges);
  free(s->psi_values);
  s->psi_edges = s->psi_values = NULL;
}

int gs_liquid_inflow_read(gs_cfg_node *node, size_t ncomp, double start, double end, gs_liquid_inflow *f,
                          gs_error *err) {
  memset(f, 0, sizeof *f);
  gs_cfg_node *rate = gs_cfg_get(node, "rate"), *drops = gs_cfg_get(node, "droplets"),
              *ratio = gs_cfg_get(node, "liquid_solid_ratio");
  if ((rate != NULL) + (drops != NULL) + (ratio != NULL) != 1) {
    if (!rate && !drops && !ratio)
      return gs_cfg_missing(node, "rate", "([m^3/s]; or droplets: {rate, volume}, or liquid_solid_ratio)", err);
    return gs_cfg_fail(node, err, "expected one of 'rate' [m^3/s], 'droplets' {rate [1/s], volume [m^3]} or "
                       "'liquid_solid_ratio'");
  }
  int rc = GS_OK;
  if (ratio) {
    static const char *const bases[] = {"mass", "volume", NULL};
    double ls, rho_s = 1, rho_l = 1;
    int by_volume = 0;
    rc = gs_cfg_double_range(node, "liquid_solid_ratio", 1, 0, 0, 0, HUGE_VAL, 0, &ls, err);
    if (!rc) rc = gs_cfg_enum_opt(node, "ratio_basis", bases, 0, &by_volume, err);
    if (!rc && !by_volume) rc = gs_cfg_double_range(node, "solid_density", 1, 0, 0, 1, HUGE_VAL, 0, &rho_s, err);
    if (!rc && !by_volume) rc = gs_cfg_double_range(node, "liquid_density", 0, 1000, 0, 1, HUGE_VAL, 0, &rho_l, err);
    if (!rc && !(isfinite(end) && isfinite(start)))
      rc = gs_cfg_fail(ratio, err, "a liquid_solid_ratio is sprayed over the window [start, end): give 'end' (and "
                       "'start', default 0)");
    if (!rc) f->per_solid = ls * rho_s / rho_l / (end - start);
    return rc;
  }
  f->q = gs_malloc(ncomp * sizeof(double), err);
  if (!f->q) return GS_ENOMEM;
  if (drops) {
    double nd, vd;
    rc = gs_cfg_require_kind(drops, GS_CFG_MAP, err);
    if (!rc) rc = gs_cfg_double_range(drops, "rate", 1, 0, 0, 0, HUGE_VAL, 0, &nd, err);
    if (!rc) rc = gs_cfg_double_range(drops, "volume", 1, 0, 0, 1, HUGE_VAL, 0, &vd, err);
    if (!rc) rc = gs_cfg_check_unused(drops, err);
    for (size_t i = 0; !rc && i < ncomp; i++) f->q[i] = nd * vd;
    return rc;
  }
  double *q = NULL;
  size_t nq = 0;
  rc = gs_cfg_doubles_req(node, "rate", 1, &q, &nq, err);
  if (!rc && nq != 1 && nq != ncomp)
    rc = gs_cfg_fail(rate, err, "expected one rate or one per compartment (%zu)", ncomp);
  for (size_t i = 0; !rc && i < nq; i++)
    if (!(q[i] >= 0)) rc = gs_cfg_fail(rate, err, "rates must be >= 0");
  for (size_t i = 0; !rc && i < ncomp; i++) f->q[i] = q[nq == 1 ? 0 : i];
  free(q);
  return rc;
}

double gs_liquid_inflow_rate(const gs_liquid_inflow *f, size_t comp, double solid) {
  return f->q ? f->q[comp] : f->per_solid * solid;
}

void gs_liquid_inflow_free(gs_liquid_inflow *f) {
  free(f->q);
  f->q = NULL;
}
