/* Layering of fines onto granules (Chaudhury 2015, eq. 2.14; src/pbm/layering.c):
 *  - at a constant rate (external powder, no moisture factor) it is growth at
 *    constant G: n(x, t) = n0(x - G t), so M0 stays and M1 grows by M0 G t.
 *    The upwind pivot transfer on a uniform grid of spacing D moves each
 *    particle by Poisson(G t / D) cells: its exact solution is n0 convolved
 *    with that Poisson law, whose mean shift is G t exactly and whose
 *    variance grows by G t D (the scheme's numerical diffusion);
 *  - from the compartment's fines it conserves the solid to round-off: what
 *    the granules gain the fines lose, the granules' number is unchanged;
 *  - the moisture factor exp(-alpha (x_w - x_wc)^2) on a solid x liquid grid;
 *  - bad keys are refused with messages naming them. */
#include "pbm_testlib.h"

static void test_constant_rate(void) {
  /* Linear grid [0, 40], 200 cells (D = 0.2); Gamma(shape 40, mean 10),
   * G = 0.5 to t = 4: 10 cells.  Measured: M0 1.5e-15, M1 gain 3e-16,
   * variance gain 1.6e-12, relative L1 distance to the scheme's exact
   * solution 1.2e-12, to n0(x - G t) 0.074 (numerical diffusion: std
   * sqrt(10) cells against the distribution's 7.9).  Tolerances: 1e-12
   * (exact identities), 1e-7 (integrator), 0.3 (diffusion). */
  const double G = 0.5, t = 4, D = 0.2;
  char *yaml = tl_fmt("grid: {axes: [{name: solid, type: linear, min: 0, max: 40, cells: 200}]}\n"
                      "initial: {type: gamma, number: 3, mean: 10, shape: 40}\n"
                      "mechanisms:\n  - {type: layering, source: external, max_rate: %g}\n"
                      "solver: {method: rk, rtol: 1.0e-10, atol: 1.0e-14}\n"
                      "output: {end: %g, count: 4}\n", G, t);
  gs_case c;
  gs_run_report rep;
  double *y = tl_build_run(yaml, &c, &rep);
  if (y) {
    const gs_model *m = &c.model;
    const size_t n = m->grid.ncells;
    double M0_0 = tl_mom(&c, c.y0, 0, 0, 0, 0), M0 = tl_mom(&c, y, 0, 0, 0, 0);
    double M1_0 = tl_mom(&c, c.y0, 0, 1, 0, 0), M1 = tl_mom(&c, y, 0, 1, 0, 0);
    double M2_0 = tl_mom(&c, c.y0, 0, 2, 0, 0), M2 = tl_mom(&c, y, 0, 2, 0, 0);
    double var0 = M2_0 / M0_0 - pow(M1_0 / M0_0, 2), var = M2 / M0 - pow(M1 / M0, 2);
    /* the scheme's exact solution: Poisson(lambda) shifts; n0 shifted by exactly G t / D cells */
    const double lambda = G * t / D;
    const int shift = (int)lround(lambda);
    double d_scheme = 0, d_shift = 0, norm = 0;
    for (size_t i = 0; i < n; i++) {
      double want = 0, lw = -lambda;
      for (size_t j = i + 1; j-- > 0;) { /* j = i - k, weight Poisson(k) */
        size_t k = i - j;
        if (k > 0) lw += log(lambda) - log((double)k);
        want += c.y0[j] * exp(lw);
      }
      double shifted = i >= (size_t)shift ? c.y0[i - (size_t)shift] : 0.0;
      d_scheme += fabs(y[i] - want);
      d_shift += fabs(y[i] - shifted);
      norm += y[i];
    }
    printf("layering at constant rate G = %g, t = %g: M0 %.3g, M1 gain %.3g (want M0 G t), variance gain %.3g"
           " (want G t D), distance to the scheme's exact solution %.3g, to n0(x - G t) %.3g\n",
           G, t, tl_relerr(M0, M0_0), tl_relerr(M1 - M1_0, M0_0 * G * t),
           tl_relerr(var - var0, G * t * D), d_scheme / norm, d_shift / norm);
    CHECK_REL(M0, M0_0, 1e-12);
    CHECK_REL(M1 - M1_0, M0_0 * G * t, 1e-12);
    CHECK_REL(var - var0, G * t * D, 1e-7);
    CHECK(d_scheme / norm < 1e-7);
    CHECK(d_shift / norm < 0.3);
    /* the external powder is booked as coming in: held - initial = exchanged */
    CHECK_REL(tl_ext(m, y + m->nstate, 0, 0), M1 - M1_0, 1e-13);
    CHECK(rep.max_loss < 1e-12); /* measured 0: nothing reaches the top */
    free(y);
    gs_case_free(&c);
  }
  free(yaml);
}

static void test_from_fines(void) {
  /* Fines Gamma(mean 1, shape 20) x 100 particles, granules Gamma(mean 20,
   * shape 40) x 10 on [0, 80] (400 cells); fines_max 3, k_layer 0.5,
   * G_max 2, to t = 10.  Exact: solid held constant, the ledger's
   * exchanged solid nets to 0 (granules +, fines -), the granules' number
   * unchanged.  Measured (60.5 of 100 fines layered): solid 1.3e-15,
   * exchanged 1.5e-16 of the layered volume, granule number 5e-16,
   * granules' gain against the fines' loss 2.4e-16.  Tolerance 1e-13. */
  char *yaml = tl_fmt("grid: {axes: [{name: solid, type: linear, min: 0, max: 80, cells: 400}]}\n"
                      "initial:\n  - {type: gamma, number: 100, mean: 1, shape: 20}\n"
                      "  - {type: gamma, number: 10, mean: 20, shape: 40}\n"
                      "mechanisms:\n  - {type: layering, max_rate: 2, fines_max: 3, k_layer: 0.5}\n"
                      "solver: {method: rk, rtol: 1.0e-9, atol: 1.0e-14}\n"
                      "output: {times: [2, 10]}\n");
  gs_case c;
  gs_run_report rep;
  double *y = tl_build_run(yaml, &c, &rep);
  if (y) {
    const gs_model *m = &c.model;
    const double *p = m->grid.axis[0].pivots;
    double fines0 = 0, fines = 0, gran0 = 0, gran = 0, gv0 = 0, gv = 0;
    for (size_t i = 0; i < m->grid.ncells; i++) {
      if (p[i] <= 3) {
        fines0 += c.y0[i] * p[i];
        fines += y[i] * p[i];
      } else {
        gran0 += c.y0[i];
        gran += y[i];
        gv0 += c.y0[i] * p[i];
        gv += y[i] * p[i];
      }
    }
    double S0 = tl_mom(&c, c.y0, 0, 1, 0, 0), S = tl_mom(&c, y, 0, 1, 0, 0);
    double ext = tl_ext(m, y + m->nstate, 0, 0), layered = gv - gv0;
    printf("layering from fines: %.4g of %.4g fines solid layered; solid held %.3g, exchanged %.3g of the layered,"
           " granule number %.3g, granules gained %.3g of what the fines lost\n",
           fines0 - fines, fines0, tl_relerr(S, S0), fabs(ext) / layered, tl_relerr(gran, gran0),
           tl_relerr(layered, fines0 - fines));
    CHECK(layered > 0.5 * fines0); /* most of the powder is layered by t = 10 */
    CHECK(fines > 0);             /* ... and it runs out smoothly, never below 0 */
    CHECK_REL(S, S0, 1e-13);
    CHECK(fabs(ext) < 1e-13 * layered);
    CHECK_REL(gran, gran0, 1e-13);
    CHECK_REL(layered, fines0 - fines, 1e-12);
    CHECK(rep.max_loss < 1e-12);
    free(y);
    gs_case_free(&c);
  }
  free(yaml);
}

static void test_moisture_factor(void) {
  /* solid x liquid grid: each granule cell layers at G_max exp(-alpha (l/s -
   * x_wc)^2); the rate of solid gained is that sum, exactly (round-off). */
  const double gmax = 2e-3, alpha = 30, xwc = 0.2;
  char *yaml = tl_fmt("grid:\n  axes:\n    - {name: solid, type: linear, min: 0, max: 20, cells: 40}\n"
                      "    - {name: liquid, type: linear, min: 0, max: 6, cells: 24}\n"
                      "initial: {type: gamma, number: 5, mean: [4, 1], shape: [8, 4]}\n"
                      "mechanisms:\n  - {type: layering, source: external, max_rate: %g, fines_max: 1,"
                      " moisture_width: %g, critical_moisture: %g}\n"
                      "output: {end: 1}\n", gmax, alpha, xwc);
  gs_case c;
  double *d, *dl;
  if (tl_rates_at_start(yaml, &c, &d, &dl)) return;
  const gs_model *m = &c.model;
  const gs_grid *g = &m->grid;
  double got = 0, want = 0, dn = 0;
  for (size_t i = 0; i < g->ncells; i++) {
    const double s = g->x[2 * i], l = g->x[2 * i + 1];
    got += d[i] * s;
    dn += d[i];
    if (s > 1) want += c.y0[i] * gmax * exp(-alpha * (l / s - xwc) * (l / s - xwc));
  }
  /* granules at the last pivot leave the grid: their volume is booked as lost */
  got += dl[m->nvol];
  printf("layering moisture factor: solid rate %.6g (want %.6g), number rate %.3g\n", got, want, dn);
  CHECK_REL(got, want, 1e-12);
  CHECK_REL(dl[0], want, 1e-12);
  CHECK(dn <= 0 && fabs(dn) < 1e-9 * tl_mom(&c, c.y0, 0, 0, 0, 0)); /* only what leaves at the top */
  tl_rates_free(&c, d, dl);
}

#define LGRID "grid: {axes: [{name: solid, type: linear, min: 0, max: 40, cells: 20}]}\noutput: {end: 1}\n"
static void test_errors(void) {
  EXPECT_INPUT(LGRID "mechanisms:\n  - {type: layering, max_rate: -1, fines_max: 3}\n", "max_rate", "-1");
  EXPECT_INPUT(LGRID "mechanisms:\n  - {type: layering, max_rate: 1}\n", "missing key 'fines_max'");
  EXPECT_INPUT(LGRID "mechanisms:\n  - {type: layering, max_rate: 1, fines_max: 0.5}\n", "fines_max", "no cell");
  EXPECT_INPUT(LGRID "mechanisms:\n  - {type: layering, max_rate: 1, fines_max: 3, k_layer: 0}\n", "k_layer");
  EXPECT_INPUT(LGRID "mechanisms:\n  - {type: layering, max_rate: 1, source: outside}\n", "source", "external, fines");
  EXPECT_INPUT(LGRID "mechanisms:\n  - {type: layering, max_rate: 1, source: external, moisture_width: 2}\n",
               "liquid_axis", "liquid");
}

int main(void) {
  test_constant_rate();
  test_from_fines();
  test_moisture_factor();
  test_errors();
  return check_failures ? 1 : 0;
}
