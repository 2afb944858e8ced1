/* The `spray:` and `granulation:` sections of a DEM case (docs/case-files.md,
 * "Spray and granulation"), validated where read. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "dem/dem_wet.h"

static int read_spray(gs_dem_case *c, gs_cfg_node *s, gs_dem_nozzle *z, gs_error *err) {
  int rc = gs_cfg_require_kind(s, GS_CFG_MAP, err);
  double deg = 0;
  if (rc || (rc = gs_dem_case_vec3(s, "point", 1, NULL, z->point, err)) ||
      (rc = gs_dem_case_unit_vec(s, "axis", z->axis, err)) ||
      (rc = gs_cfg_double_range(s, "half_angle", 1, 0, 0, 1, 90, 0, &deg, err)) ||
      (rc = gs_cfg_double_range(s, "droplet_diameter", 1, 0, 0, 1, HUGE_VAL, 0, &z->diameter, err)) ||
      (rc = gs_cfg_double_range(s, "mass_rate", 1, 0, 0, 1, HUGE_VAL, 0, &z->mass_rate, err)) ||
      (rc = gs_cfg_double_range(s, "density", 0, 1000, 0, 1, HUGE_VAL, 0, &z->density, err)) ||
      (rc = gs_cfg_double_range(s, "speed", 1, 0, 0, 0, HUGE_VAL, 0, &z->speed, err)) ||
      (rc = gs_cfg_double_range(s, "start", 0, 0, 0, 0, HUGE_VAL, 0, &z->start, err)) ||
      (rc = gs_cfg_double_range(s, "end", 0, HUGE_VAL, z->start, 1, HUGE_VAL, 0, &z->end, err)) ||
      (rc = gs_cfg_double_range(s, "ledger_tolerance", 0, 1e-9, 0, 1, 1e-3, 0, &c->wet->tol, err)))
    return rc;
  z->half_angle = deg * M_PI / 180;
  for (int a = 0; a < 3; a++) z->point[a] *= c->geom; /* dem.geometry_scale */
  for (int a = 0; a < 3; a++)
    if (!(z->point[a] > c->prm.lo[a] && z->point[a] < c->prm.hi[a]))
      return gs_cfg_fail(gs_cfg_get(s, "point"), err, "expected a point inside dem.box");
  return gs_cfg_check_unused(s, err);
}

/* classes: {width: m^3, count: n} */
static int read_classes(gs_cfg_node *g, const char *key, double def_width, double *width, int *count,
                        gs_error *err) {
  gs_cfg_node *n = gs_cfg_get(g, key);
  long k = 10;
  *width = def_width;
  if (!n) {
    *count = (int)k;
    if (!(def_width > 0))
      return gs_cfg_fail(g, err, "missing key '%s' ({width: m^3, count}; no droplet volume to default to)", key);
    return GS_OK;
  }
  int rc = gs_cfg_require_kind(n, GS_CFG_MAP, err);
  if (rc || (rc = gs_cfg_double_range(n, "width", !(def_width > 0), def_width, 0, 1, HUGE_VAL, 0, width, err)) ||
      (rc = gs_cfg_long_range(n, "count", 0, 10, 1, 256, &k, err)))
    return rc;
  *count = (int)k;
  return gs_cfg_check_unused(n, err);
}

static int read_granulation(gs_dem_case *c, gs_cfg_node *g, double rmin, gs_error *err) {
  gs_dem_granulation *q = &c->wet->gran;
  gs_cfg_node *rule;
  int rc = gs_cfg_require_kind(g, GS_CFG_MAP, err);
  if (rc || (rc = gs_cfg_double_range(g, "every", 1, 0, 0, 1, HUGE_VAL, 0, &q->every, err)) ||
      (rc = gs_cfg_map_req(g, "rule", &rule, err)))
    return rc;
  q->every_k = (long)fmax(1, round(q->every / c->prm.dt));
  if (fabs(q->every_k * c->prm.dt - q->every) > 1e-6 * q->every)
    return gs_cfg_fail(gs_cfg_get(g, "every"), err, "expected a whole number of time steps (dem.time_step %g s)",
                       c->prm.dt);
  double tg = 100 * c->prm.dt;
  if ((rc = gs_cfg_double_range(g, "growth_time", 0, tg, 0, 0, HUGE_VAL, 0, &tg, err))) return rc;
  q->growth_k = (long)round(tg / c->prm.dt);
  q->rule.type = gs_registry_pick(rule, (const void *const *)gs_dem_rule_types, "success rule", err);
  if (!q->rule.type) return err->code;
  if ((rc = q->rule.type->read(rule, &q->rule, err)) || (rc = gs_cfg_check_unused(rule, err))) return rc;
  const double vd = c->wet->has_spray ? M_PI / 6 * pow(c->wet->noz.diameter, 3) : 0;
  if ((rc = read_classes(g, "solid_classes", 4.0 / 3.0 * M_PI * rmin * rmin * rmin, &q->ds, &q->ns, err)) ||
      (rc = read_classes(g, "liquid_classes", vd, &q->dl, &q->nl, err)))
    return rc;
  /* the per-update counts are a dense matrix over pairs of classes */
  if (q->ns * q->nl > 1024)
    return gs_cfg_fail(g, err, "solid_classes.count x liquid_classes.count = %d: at most 1024 classes", q->ns * q->nl);
  return gs_cfg_check_unused(g, err);
}

int gs_dem_wet_read(gs_dem_case *c, gs_cfg_node *root, double rmin, gs_error *err) {
  gs_cfg_node *s = gs_cfg_get(root, "spray"), *g = gs_cfg_get(root, "granulation");
  if (!s && !g) return GS_OK;
  if (c->engine != GS_DEM_ENGINE_EMBEDDED)
    return gs_cfg_fail(s ? s : g, err, "spray and granulation need dem.engine: embedded");
  if (!(c->wet = calloc(1, sizeof *c->wet))) return gs_error_set(err, GS_ENOMEM, "out of memory");
  c->wet->has_spray = s != NULL;
  c->wet->has_gran = g != NULL;
  c->wet->tol = 1e-9;
  int rc = GS_OK;
  if (s) rc = read_spray(c, s, &c->wet->noz, err);
  if (!rc && g) rc = read_granulation(c, g, rmin, err);
  return rc;
}
