/* Distributions given as a mass with a size distribution by mass
 * (src/pbm/distribution_mass.c: types lognormal, normal, table):
 *  - lognormal by mass on a fine grid: the solid mass exactly, the number
 *    against the closed form (Hatch-Choate: N = M (1 + R) 6 / (rho pi d50^3)
 *    exp(4.5 ln^2 gsd)), d10/d50/d90 against the mass quantiles, the other
 *    axes at their ratios;
 *  - normal by mass: mass exactly, d50 = the mean;
 *  - a sieve table on a grid whose pivots are the classes' representative
 *    diameters: the mass of every class exactly;
 *  - bad recipes refused naming file, line and key. */
#include <gsl/gsl_cdf.h>

#include "pbm_testlib.h"

#define GRID2 "grid:\n  axes:\n    - {name: solid, type: geometric, min: 1.0e-15, ratio: 1.1, cells: 200, zero_first: true}\n" \
              "    - {name: liquid, type: geometric, min: 1.0e-15, ratio: 1.2, cells: 80, zero_first: true}\n"

static void test_lognormal(void) {
  const double M = 2, rho = 2700, d50 = 150e-6, gsd = 1.5, r = 0.05;
  char *yaml = tl_fmt(GRID2 "initial: {type: lognormal, mass: %g, solid_density: %g, d50: %g, gsd: %g, ratios: {liquid: %g}}\n"
                      "output: {end: 1}\n", M, rho, d50, gsd, r);
  gs_case c;
  if (tl_case(yaml, &c)) {
    free(yaml);
    return;
  }
  const double ms = rho * tl_mom(&c, c.y0, 0, 1, 0, 0), ml = tl_mom(&c, c.y0, 0, 0, 1, 0);
  const double N = tl_mom(&c, c.y0, 0, 0, 0, 0), ls = log(gsd);
  const double Nwant = M * (1 + r) * 6 / (rho * M_PI * d50 * d50 * d50) * exp(4.5 * ls * ls);
  gs_summary s;
  gs_summarize(&c.model, c.y0, 0, &s);
  const double d10 = d50 * exp(ls * gsl_cdf_ugaussian_Pinv(0.1)), d90 = d50 * exp(ls * gsl_cdf_ugaussian_Pinv(0.9));
  printf("lognormal by mass: solid %.15g kg (%.2g), liquid/solid %.6g (%.2g), number %.6g (closed form %.6g, %.2g),"
         " d10 %.4g (%.4g, %.2g) d50 %.4g (%.2g) d90 %.4g (%.4g, %.2g)\n", ms, tl_relerr(ms, M), ml / (ms / rho),
         tl_relerr(ml / (ms / rho), r), N, Nwant, tl_relerr(N, Nwant), s.d10, d10, tl_relerr(s.d10, d10), s.d50,
         tl_relerr(s.d50, d50), s.d90, d90, tl_relerr(s.d90, d90));
  CHECK_REL(ms, M, 1e-12);
  CHECK_REL(ml / (ms / rho), r, 1e-3);
  CHECK_REL(N, Nwant, 1e-8);
  /* ratio-1.1 cells in volume are 3.2 % wide in diameter: the percentiles,
   * read off the cells' edges, to 0.5 % */
  CHECK_REL(s.d50, d50, 5e-3);
  CHECK_REL(s.d10, d10, 5e-3);
  CHECK_REL(s.d90, d90, 5e-3);
  gs_case_free(&c);
  free(yaml);
}

static void test_normal(void) {
  const double M = 0.2, rho = 1500, d50 = 181.2e-6, sigma = 8.215e-6; /* Chaudhury (2015) Table 2.1 */
  char *yaml = tl_fmt("grid:\n  axes:\n    - {name: solid, type: geometric, min: 1.0e-13, ratio: 1.02, cells: 300, zero_first: true}\n"
                      "initial: {type: normal, mass: %g, solid_density: %g, d50: %g, sigma: %g}\n"
                      "output: {end: 1}\n", M, rho, d50, sigma);
  gs_case c;
  if (tl_case(yaml, &c)) {
    free(yaml);
    return;
  }
  const double ms = rho * tl_mom(&c, c.y0, 0, 1, 0, 0);
  gs_summary s;
  gs_summarize(&c.model, c.y0, 0, &s);
  printf("normal by mass: solid %.15g kg (%.2g), d50 %.6g (%.2g), d90 %.6g (%.6g)\n", ms, tl_relerr(ms, M), s.d50,
         tl_relerr(s.d50, d50), s.d90, d50 + 1.2816 * sigma);
  CHECK_REL(ms, M, 1e-12);
  CHECK_REL(s.d50, d50, 1e-3);
  CHECK_REL(s.d90, d50 + 1.2815516 * sigma, 1e-3);
  gs_case_free(&c);
  free(yaml);
}

static void test_table(void) {
  /* US sieves 53..590 um (Chaudhury 2015, sec. 2.4): five classes; the
   * grid's edges are the sieves' volumes and its pivots the volumes of the
   * classes' geometric-mean diameters, so each class sits on its pivot */
  const double d[6] = {53e-6, 106e-6, 180e-6, 250e-6, 420e-6, 590e-6}, f[5] = {0.1, 0.2, 0.35, 0.25, 0.1};
  const double M = 0.2, rho = 1500;
  char edges[512] = "", pivots[512] = "";
  for (int i = 0; i < 6; i++) {
    snprintf(edges + strlen(edges), sizeof edges - strlen(edges), "%s%.17g", i ? ", " : "", M_PI * pow(d[i], 3) / 6);
    if (i < 5)
      snprintf(pivots + strlen(pivots), sizeof pivots - strlen(pivots), "%s%.17g", i ? ", " : "",
               M_PI * pow(sqrt(d[i] * d[i + 1]), 3) / 6);
  }
  char *yaml = tl_fmt("grid:\n  axes:\n    - {name: solid, type: edges, edges: [%s], pivots: [%s]}\n"
                      "initial: {type: table, mass: %g, solid_density: %g, edges: [53.0e-6, 106.0e-6, 180.0e-6, 250.0e-6, 420.0e-6, 590.0e-6],"
                      " fractions: [0.1, 0.2, 0.35, 0.25, 0.1]}\noutput: {end: 1}\n", edges, pivots, M, rho);
  gs_case c;
  if (tl_case(yaml, &c)) {
    free(yaml);
    return;
  }
  double worst = 0;
  for (int i = 0; i < 5; i++) worst = fmax(worst, tl_relerr(rho * c.y0[i] * c.model.grid.x[i], M * f[i]));
  printf("sieve table: largest error of a class's mass %.2g\n", worst);
  CHECK(worst < 1e-13);
  gs_case_free(&c);
  free(yaml);
}

#define BAD GRID2 "output: {end: 1}\ninitial:\n  type: lognormal\n  mass: 2\n  solid_density: 2700\n"
static void test_errors(void) {
  EXPECT_INPUT(BAD "  d50: 5\n  gsd: 1.5\n", "bad.yaml:10", "d50", "5");
  EXPECT_INPUT(BAD "  d50: 150.0e-6\n  gsd: 0.5\n", "bad.yaml:11", "gsd");
  EXPECT_INPUT(BAD "  d50: 150.0e-6\n", "missing key 'gsd'");
  EXPECT_INPUT(BAD "  d50: 150.0e-6\n  gsd: 1.5\n  ratios: {liquid: -0.1}\n", "liquid", "-0.1");
  EXPECT_INPUT(BAD "  d50: 1.0e-3\n  gsd: 3\n", "does not cover", "coverage");
  EXPECT_INPUT(GRID2 "output: {end: 1}\ninitial: {type: lognormal, mass: -2, solid_density: 2700, d50: 1.0e-4, gsd: 1.5}\n",
               "mass", "-2");
  EXPECT_INPUT(GRID2 "output: {end: 1}\ninitial: {type: normal, mass: 2, solid_density: 2700, d50: 1.0e-4, sigma: 5.0e-5}\n",
               "sigma", "lognormal");
  EXPECT_INPUT(GRID2 "output: {end: 1}\ninitial: {type: table, mass: 2, solid_density: 2700, edges: [5.0e-5, 1.0e-4, 2.0e-4],"
               " fractions: [0.5, 0.3]}\n", "fractions", "sum to 0.8");
  EXPECT_INPUT(GRID2 "output: {end: 1}\ninitial: {type: table, mass: 2, solid_density: 2700, edges: [5.0e-5, 2.0e-4, 1.0e-4],"
               " fractions: [0.5, 0.5]}\n", "edges", "increasing");
  EXPECT_INPUT(GRID2 "output: {end: 1}\ninitial: {type: table, mass: 2, solid_density: 2700, edges: [5.0e-5, 1.0e-4, 2.0e-4],"
               " fractions: [0.5, 0.3, 0.2]}\n", "fractions", "one mass fraction per class (2), got 3");
}

int main(void) {
  test_lognormal();
  test_normal();
  test_table();
  test_errors();
  return check_failures ? 1 : 0;
}
