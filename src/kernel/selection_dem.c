/* Breakage selection from DEM impacts (Sampat et al. 2018, eqs. 11-12):
 *   S(cell) = scale * f_impact(class) * P(U > U_break(d))
 * f_impact: wall impacts per particle per second of the cell's size class,
 * P: the lognormal fit (mu, sigma of ln U) of that class's impact speeds,
 * U_break: the speed that breaks a granule of diameter d, a constant
 * `u_break` or from the critical Stokes deformation number (Sampat et al. 2018, after
 * Tardos et al.):
 *    U_break = (2 St_c / rho) (9/8) ((1 - e)^2 / e^2) (9/16) (mu_binder / d),
 * St_c the critical Stokes deformation number.
 * The impact table is written by `gransim dem-reduce --impacts FILE`: an
 * `edges` line and three rows per class (rate, mu, sigma), see class_table.h.
 * Particles whose size measure is below `min_volume` do not break. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include <gsl/gsl_cdf.h>

#include "gransim/kernel.h"
#include "kernel/class_table.h"
#include "kernel/size_measure.h"

typedef struct {
  double *rate; /* per cell */
} dem_sel;

static void dem_free(void *self) {
  dem_sel *s = self;
  if (s) free(s->rate);
  free(s);
}

/* U_break of a granule of diameter d: constant, or from the Stokes criterion. */
static int read_break_speed(gs_cfg_node *node, double *u_const, double *stokes_factor,
                            gs_error *err) {
  gs_cfg_node *st = gs_cfg_get(node, "stokes");
  *u_const = NAN;
  *stokes_factor = NAN;
  if (!st) return gs_cfg_double_range(node, "u_break", 1, 0, 0, 1, HUGE_VAL, 0, u_const, err);
  if (gs_cfg_get(node, "u_break"))
    return gs_cfg_fail(gs_cfg_get(node, "u_break"), err, "give either u_break or stokes, not both");
  double stc, rho, eps, mu;
  int rc = gs_cfg_require_kind(st, GS_CFG_MAP, err);
  if (!rc) rc = gs_cfg_double_range(st, "critical", 1, 0, 0, 1, HUGE_VAL, 0, &stc, err);
  if (!rc) rc = gs_cfg_double_range(st, "density", 1, 0, 0, 1, HUGE_VAL, 0, &rho, err);
  if (!rc) rc = gs_cfg_double_range(st, "porosity", 1, 0, 0, 1, 1, 1, &eps, err);
  if (!rc) rc = gs_cfg_double_range(st, "viscosity", 1, 0, 0, 1, HUGE_VAL, 0, &mu, err);
  if (!rc) rc = gs_cfg_check_unused(st, err);
  /* U_break = factor / d */
  if (!rc) *stokes_factor = 2 * stc / rho * (9.0 / 8.0) * (1 - eps) * (1 - eps) / (eps * eps) * (9.0 / 16.0) * mu;
  return rc;
}

static int dem_create(gs_cfg_node *node, const gs_grid *g, const char *dir, void **self,
                      gs_error *err) {
  static const char *const measures[] = {"volume", "diameter", NULL};
  dem_sel *s = gs_calloc(1, sizeof *s, err);
  if (!s) return GS_ENOMEM;
  gs_class_table tf = {0};
  size_t *cls = NULL;
  double *size = NULL, scale = 1, u_const, factor, min_volume = 0;
  int measure = 0;
  const char *name = NULL;
  int rc = gs_cfg_string_req(node, "file", &name, err);
  if (!rc) rc = gs_cfg_double_range(node, "scale", 0, 1, 0, 0, HUGE_VAL, 0, &scale, err);
  if (!rc) rc = gs_cfg_enum_opt(node, "measure", measures, 0, &measure, err);
  if (!rc) rc = read_break_speed(node, &u_const, &factor, err);
  if (!rc) rc = gs_cfg_double_range(node, "min_volume", 0, 0, 0, 0, HUGE_VAL, 0, &min_volume, err);
  if (!rc && !(size = gs_size_measure(node, g, err))) rc = err->code;
  if (!rc) rc = gs_cfg_check_unused(node, err);
  char path[4096];
  if (!rc) {
    snprintf(path, sizeof path, "%s%s%s", name[0] == '/' ? "" : dir, name[0] == '/' ? "" : "/", name);
    rc = gs_class_table_read(path, 3, &tf, err);
    if (rc) {
      gs_cfg_node *fn = gs_cfg_get(node, "file");
      gs_error_prefix(err, "%s:%d: %s: ", gs_cfg_file(fn), gs_cfg_line(fn), gs_cfg_path(fn));
    }
  }
  for (size_t i = 0; !rc && i < tf.n; i++)
    if (!(tf.c[i] >= 0) || !(tf.c[2 * tf.n + i] > 0) || !isfinite(tf.c[tf.n + i]))
      rc = gs_error_set(err, GS_EINPUT, "%s: class %zu: expected rate >= 0, a finite mu and sigma > 0 "
                        "(got %g, %g, %g)", path, i + 1, tf.c[i], tf.c[tf.n + i], tf.c[2 * tf.n + i]);
  if (!rc && !(cls = gs_class_table_assign(&tf, size, g->ncells, measure == 1, path, err))) rc = GS_ENOMEM;
  if (!rc && !(s->rate = gs_malloc(g->ncells * sizeof(double), err))) rc = GS_ENOMEM;
  for (size_t c = 0; !rc && c < g->ncells; c++) {
    size_t k = cls[c];
    double d = gs_diameter(g->volume[c]);
    double u = isnan(factor) ? u_const : (d > 0 ? factor / d : HUGE_VAL);
    s->rate[c] = size[c] < min_volume ? 0.0
                 : scale * tf.c[k] * gsl_cdf_lognormal_Q(u, tf.c[tf.n + k], tf.c[2 * tf.n + k]);
  }
  free(cls);
  free(size);
  gs_class_table_free(&tf);
  if (rc) {
    dem_free(s);
    return rc;
  }
  *self = s;
  return GS_OK;
}

static double dem_rate(const void *self, const gs_grid *g, size_t cell) {
  (void)g;
  return ((const dem_sel *)self)->rate[cell];
}

const gs_selection_type gs_selection_dem_impact = {
    .name = "dem_impact",
    .summary = "S = scale f_impact(class) P(U > U_break) from DEM impact statistics (Sampat et al. 2018, eq. 12)",
    .create = dem_create,
    .rate = dem_rate,
    .free = dem_free,
};
