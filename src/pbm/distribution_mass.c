/* Distributions in an engineer's terms (include/gransim/distribution.h):
 * a mass of solid with a size distribution by mass over the volume-
 * equivalent diameter, lognormal (mass median d50, geometric standard
 * deviation gsd) or normal (mass-weighted mean d50, standard deviation
 * sigma), or a measured table (sieve or laser-diffraction classes: diameter
 * edges and the mass fraction of each).  The other axes get `ratios` times
 * the solid volume (moisture, pores); a particle's volume is the sum, and
 * its diameter (6 V / pi)^(1/3), as summary.csv's d50 takes it.
 *
 * Each cell of the solid axis receives the mass of the diameters between
 * its edges' and the number that mass makes (the mass density over d^3,
 * by quadrature), placed at their mean by the lever rule: mass and number
 * are conserved cell by cell.  A table's class goes whole to the geometric
 * mean diameter of its edges, so its mass is exact. */
#include <gsl/gsl_cdf.h>
#include <gsl/gsl_integration.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "gransim/distribution.h"
#include "pbm/distribution_mass.h"
#include "pbm/lever.h"

/* Diameters a case may give: 1 nm to 10 cm, from fine powders to the
 * largest granules a granulator makes; a diameter of 5 m is a unit error. */
#define D_MIN 1e-9
#define D_MAX 0.1

typedef struct {
  int lognormal;
  double d50, spread; /* lognormal: ln(gsd); normal: sigma */
  double below;       /* normal: the mass below d = 0 that truncation removes */
} size_dist;

/* Mass fraction below diameter d. */
static double cum_mass(const size_dist *s, double d) {
  if (d <= 0) return 0;
  if (s->lognormal) return gsl_cdf_gaussian_P(log(d / s->d50), s->spread);
  return (gsl_cdf_gaussian_P(d - s->d50, s->spread) - s->below) / (1 - s->below);
}

static double mass_density(const size_dist *s, double d) {
  if (d <= 0) return 0;
  if (s->lognormal) {
    const double z = log(d / s->d50) / s->spread;
    return exp(-0.5 * z * z) / (d * s->spread * sqrt(2 * M_PI));
  }
  const double z = (d - s->d50) / s->spread;
  return exp(-0.5 * z * z) / (s->spread * sqrt(2 * M_PI) * (1 - s->below));
}

/* Particles per kg between diameters a and b: the mass density over the
 * particle mass rho_s pi d^3 / (6 (1 + R)), Gauss-Legendre on [a, b] (the
 * density is smooth there; a < b, a > 0). */
static double number_per_kg(const size_dist *s, double a, double b, double unit_mass,
                            const gsl_integration_glfixed_table *t) {
  double sum = 0;
  for (size_t i = 0; i < t->n; i++) {
    double x, w;
    gsl_integration_glfixed_point(a, b, i, &x, &w, t);
    sum += w * mass_density(s, x) / (unit_mass * x * x * x);
  }
  return sum;
}

typedef struct {
  double mass, rho, ratio[GS_MAX_DIM], R; /* R: sum of the ratios */
  int solid;
} common_t;

/* Place n particles of solid volume sv, with ratio sv on the other axes. */
static void place(const gs_grid *g, const common_t *c, double n, double sv, double *dst,
                  gs_disc_report *req) {
  double at[GS_MAX_DIM];
  for (int k = 0; k < g->dim; k++) {
    at[k] = k == c->solid ? sv : c->ratio[k] * sv;
    req->volume[k][0] += n * at[k];
  }
  req->number[0] += n;
  gs_lever_place(g, GS_NOWHERE, at, n, dst, NULL);
}

static double diameter_of_solid(const common_t *c, double sv) {
  return cbrt(6 * sv * (1 + c->R) / M_PI);
}

static int read_common(gs_cfg_node *node, const gs_grid *g, common_t *c, gs_error *err) {
  memset(c, 0, sizeof *c);
  const char *name;
  int rc = gs_cfg_double_range(node, "mass", 1, 0, 0, 1, 1e6, 0, &c->mass, err);
  if (!rc) rc = gs_cfg_double_range(node, "solid_density", 1, 0, 0, 1, 1e5, 0, &c->rho, err);
  const int has_solid = gs_grid_axis_by_name(g, "solid") >= 0;
  if (!rc) rc = gs_cfg_string_opt(node, "solid_axis", has_solid ? "solid" : g->axis[0].name, &name, err);
  if (!rc && (c->solid = gs_grid_axis_by_name(g, name)) < 0)
    rc = gs_cfg_fail(gs_cfg_get(node, "solid_axis"), err, "expected the name of a grid axis");
  gs_cfg_node *r = rc ? NULL : gs_cfg_get(node, "ratios");
  if (r) rc = gs_cfg_require_kind(r, GS_CFG_MAP, err);
  for (int k = 0; r && !rc && k < g->dim; k++)
    if (k != c->solid)
      rc = gs_cfg_double_range(r, g->axis[k].name, 0, 0, 0, 0, 1e3, 0, &c->ratio[k], err);
  if (r && !rc) rc = gs_cfg_check_unused(r, err);
  for (int k = 0; k < g->dim; k++) c->R += c->ratio[k];
  return rc;
}

static int add_continuous(gs_cfg_node *node, const gs_grid *g, int lognormal, double coverage,
                          double *dst, gs_disc_report *req, gs_error *err) {
  common_t c;
  size_dist s = {.lognormal = lognormal};
  int rc = read_common(node, g, &c, err);
  if (!rc) rc = gs_cfg_double_range(node, "d50", 1, 0, D_MIN, 0, D_MAX, 0, &s.d50, err);
  if (!rc && lognormal) {
    double gsd;
    rc = gs_cfg_double_range(node, "gsd", 1, 0, 1, 1, 10, 0, &gsd, err);
    s.spread = log(gsd);
  } else if (!rc) {
    rc = gs_cfg_double_range(node, "sigma", 1, 0, 0, 1, D_MAX, 0, &s.spread, err);
    if (!rc && s.spread > s.d50 / 3)
      rc = gs_cfg_fail(gs_cfg_get(node, "sigma"), err,
                       "a normal distribution with sigma %g > d50/3 = %g puts mass at diameters "
                       "near and below 0: describe so wide a distribution as lognormal", s.spread, s.d50 / 3);
    s.below = rc ? 0 : gsl_cdf_gaussian_P(-s.d50, s.spread);
  }
  if (rc) return rc;
  const gs_axis *ax = &g->axis[c.solid];
  const double lo = diameter_of_solid(&c, ax->edges[0]), hi = diameter_of_solid(&c, ax->edges[ax->n]);
  const double outside = cum_mass(&s, lo) + 1 - cum_mass(&s, hi);
  if (outside > coverage)
    return gs_cfg_fail(node, err, "grid axis '%s' [%g, %g] (diameters %g to %g m) does not cover this "
                       "distribution: %.3g of its mass lies outside (allowed: %g; widen the grid or set "
                       "'coverage')", ax->name, ax->edges[0], ax->edges[ax->n], lo, hi, outside, coverage);
  /* the number integral starts where the mass does (a quantile of 1e-15):
   * below it a normal's density would make the number diverge as 1/d^3 */
  const double dmin = lognormal ? s.d50 * exp(s.spread * gsl_cdf_ugaussian_Pinv(1e-15))
                                : fmax(s.d50 + s.spread * gsl_cdf_ugaussian_Pinv(1e-15), 0.0);
  gsl_integration_glfixed_table *t = gsl_integration_glfixed_table_alloc(64);
  if (!t) return gs_error_set(err, GS_ENOMEM, "out of memory");
  const double unit = c.rho * M_PI / (6 * (1 + c.R)); /* particle solid mass / d^3 */
  for (size_t i = 0; i < ax->n; i++) {
    const double a = fmax(diameter_of_solid(&c, ax->edges[i]), dmin), b = diameter_of_solid(&c, ax->edges[i + 1]);
    if (!(b > a)) continue;
    const double m = c.mass * (cum_mass(&s, b) - cum_mass(&s, a));
    const double n = c.mass * number_per_kg(&s, a, b, unit, t);
    if (m > 0 && n > 0) place(g, &c, n, m / (c.rho * n), dst, req);
  }
  gsl_integration_glfixed_table_free(t);
  return GS_OK;
}

static int add_table(gs_cfg_node *node, const gs_grid *g, double *dst, gs_disc_report *req,
                     gs_error *err) {
  common_t c;
  double *edges = NULL, *frac = NULL, total = 0;
  size_t ne = 0, nf = 0;
  int rc = read_common(node, g, &c, err);
  if (!rc) rc = gs_cfg_doubles_req(node, "edges", 2, &edges, &ne, err);
  if (!rc) rc = gs_cfg_doubles_req(node, "fractions", 1, &frac, &nf, err);
  for (size_t i = 0; !rc && i < ne; i++)
    if (!(edges[i] >= D_MIN && edges[i] <= D_MAX) || (i && !(edges[i] > edges[i - 1])))
      rc = gs_cfg_fail(gs_cfg_get(node, "edges"), err,
                       "edge %zu is %g: expected increasing diameters from %g to %g m (the smallest "
                       "edge > 0: a pan's lower edge is the smallest size expected)", i + 1, edges[i], D_MIN, D_MAX);
  if (!rc && nf != ne - 1)
    rc = gs_cfg_fail(gs_cfg_get(node, "fractions"), err, "expected one mass fraction per class (%zu), got %zu",
                     ne - 1, nf);
  for (size_t i = 0; !rc && i < nf; i++) {
    if (!(frac[i] >= 0 && frac[i] <= 1))
      rc = gs_cfg_fail(gs_cfg_get(node, "fractions"), err, "fraction %zu is %g: expected 0 to 1", i + 1, frac[i]);
    total += frac[i];
  }
  /* measured fractions are rounded: accept a sum within 1 % of 1, and scale */
  if (!rc && !(fabs(total - 1) <= 0.01))
    rc = gs_cfg_fail(gs_cfg_get(node, "fractions"), err,
                     "the mass fractions sum to %g, not 1 (within 0.01): is a class missing?", total);
  for (size_t i = 0; !rc && i < nf; i++) {
    if (frac[i] == 0) continue;
    const double d = sqrt(edges[i] * edges[i + 1]);
    const double sv = M_PI * d * d * d / (6 * (1 + c.R)), m = c.mass * frac[i] / total;
    place(g, &c, m / (c.rho * sv), sv, dst, req);
  }
  free(edges);
  free(frac);
  return rc;
}

int gs_distribution_by_mass(gs_cfg_node *node, const gs_grid *g, const char *type, double coverage,
                            double *dst, gs_disc_report *req, gs_error *err) {
  req->number[0] = 0;
  if (!strcmp(type, "table")) return add_table(node, g, dst, req, err);
  return add_continuous(node, g, !strcmp(type, "lognormal"), coverage, dst, req, err);
}
