/* Success rules of a collision between two particles in the DEM granulation
 * (docs/models.md, "Spray and granulation in the DEM"):
 *  - constant: Sen et al. (2014) after Biggs et al. (2003): a collision of
 *    two particles whose liquid contents l / (s + l) reach lc_min aggregates
 *    with the constant efficiency psi0 (one wet partner suffices with
 *    `require: either`);
 *  - stokes: the viscous Stokes criterion of Ennis, Tardos & Pfeffer (1991)
 *    in the form of Liu et al. (2000): St_v = 8 m~ u0 / (3 pi mu d~^2) with
 *    the harmonic means m~ and d~ and u0 half the approach speed; the pair
 *    aggregates when St_v < St* = (1 + 1/e) ln(h / h_a), h the mean binder
 *    film thickness l / (4 pi r^2) of the two. */
#include <math.h>

#include "dem/dem_wet.h"

double gs_dem_liquid_content(const gs_dem_partner *p) {
  const double t = p->vs + p->vl;
  return t > 0 ? p->vl / t : 0;
}

static int read_constant(gs_cfg_node *n, gs_dem_rule *r, gs_error *err) {
  static const char *const req[] = {"both", "either", NULL};
  int rc;
  if ((rc = gs_cfg_double_range(n, "efficiency", 0, 0.01, 0, 0, 1, 0, &r->efficiency, err)) ||
      (rc = gs_cfg_double_range(n, "min_liquid_content", 0, 0.2, 0, 0, 1, 0, &r->lc_min, err)) ||
      (rc = gs_cfg_enum_opt(n, "require", req, 0, &r->either, err)))
    return rc;
  return GS_OK;
}

static int success_constant(const gs_dem_rule *r, const gs_dem_partner *a, const gs_dem_partner *b,
                            double vn, double u) {
  (void)vn;
  const int wa = gs_dem_liquid_content(a) >= r->lc_min, wb = gs_dem_liquid_content(b) >= r->lc_min;
  const int wet = r->either ? (wa || wb) : (wa && wb);
  return wet && u < r->efficiency;
}

static int read_stokes(gs_cfg_node *n, gs_dem_rule *r, gs_error *err) {
  int rc;
  if ((rc = gs_cfg_double_range(n, "viscosity", 1, 0, 0, 1, HUGE_VAL, 0, &r->viscosity, err)) ||
      (rc = gs_cfg_double_range(n, "restitution", 1, 0, 0, 1, 1, 0, &r->restitution, err)) ||
      (rc = gs_cfg_double_range(n, "asperity", 1, 0, 0, 1, HUGE_VAL, 0, &r->asperity, err)))
    return rc;
  return GS_OK;
}

static int success_stokes(const gs_dem_rule *r, const gs_dem_partner *a, const gs_dem_partner *b,
                          double vn, double u) {
  (void)u;
  const double h = 0.5 * (a->vl / (4 * M_PI * a->r * a->r) + b->vl / (4 * M_PI * b->r * b->r));
  if (!(h > r->asperity)) return 0;
  const double mh = 2 * a->m * b->m / (a->m + b->m);
  const double dh = 2 * (2 * a->r) * (2 * b->r) / (2 * a->r + 2 * b->r);
  const double st = 8 * mh * (0.5 * vn) / (3 * M_PI * r->viscosity * dh * dh);
  const double st_crit = (1 + 1 / r->restitution) * log(h / r->asperity);
  return st < st_crit;
}

static const gs_dem_rule_type constant = {
    .name = "constant", .read = read_constant, .success = success_constant};
static const gs_dem_rule_type stokes = {.name = "stokes", .read = read_stokes, .success = success_stokes};

const gs_dem_rule_type *const gs_dem_rule_types[] = {&constant, &stokes, NULL};
