/* Drying at a fixed bed temperature and air humidity (src/pbm/drying.c,
 * mechanism `drying`, Chaudhury 2015 eqs. 2.19-2.22 per granule):
 *  - the saturation humidity against steam-table values;
 *  - each cell dries at E(d) = gamma eta 2 pi D_w d rho_air (x_sat - x_air) / rho_l,
 *    recomputed here independently;
 *  - the water balance of a spray + drying run: liquid held - initial =
 *    sprayed - evaporated, with the evaporation known in closed form
 *    (diameters from the solid only, grid.size_axes, so each granule's rate
 *    is constant), and the ledger identity to round-off;
 *  - bad keys are refused naming them. */
#include "pbm/drying.h"
#include "pbm_testlib.h"

static void test_saturation(void) {
  /* steam tables: p_sat(40 C) = 7.384 kPa, p_sat(60 C) = 19.946 kPa, p_sat(80 C) = 47.414 kPa;
   * Buck's (1996) equation: measured within 1e-4 of them */
  const double T[3] = {313.15, 333.15, 353.15}, p[3] = {7384, 19946, 47414};
  for (int i = 0; i < 3; i++) {
    double want = 0.621945 * p[i] / (101325 - p[i]), got = gs_saturation_humidity(T[i], 101325);
    printf("saturation humidity at %.2f K: %.5g kg/kg (steam tables %.5g, %.2g)\n", T[i], got, want,
           tl_relerr(got, want));
    CHECK_REL(got, want, 5e-4);
  }
}

static const char *dry_keys = "bed_temperature: 333, air_humidity: 0.00505, correction: 0.002, wetted_fraction: 0.8";

static double rate_per_diameter(void) { /* the formula with the keys above and the defaults */
  double xsat = gs_saturation_humidity(333, 101325);
  return 0.002 * 0.8 * 2 * M_PI * 2.6e-5 * 1.18 * (xsat - 0.00505) / 1000;
}

static void test_rates(void) {
  char *yaml = tl_fmt("grid:\n  axes:\n    - {name: solid, type: geometric, min: 1.0e-13, ratio: 1.5, cells: 18, zero_first: true}\n"
                      "    - {name: liquid, type: linear, min: 0, max: 8.0e-13, cells: 40}\n"
                      "initial: {type: gamma, number: 1.0e6, mean: [5.0e-13, 2.0e-13], shape: [6, 10]}\n"
                      "mechanisms:\n  - {type: drying, %s}\n"
                      "output: {end: 1}\n", dry_keys);
  gs_case c;
  double *d, *dl;
  if (tl_rates_at_start(yaml, &c, &d, &dl)) {
    free(yaml);
    return;
  }
  const gs_model *m = &c.model;
  const gs_grid *g = &m->grid;
  double want = 0, got = 0, dn = 0;
  for (size_t i = 0; i < g->ncells; i++) {
    const double s = g->x[2 * i], l = g->x[2 * i + 1];
    if (i % g->axis[1].n > 0) want -= c.y0[i] * rate_per_diameter() * cbrt(6 * (s + l) / M_PI);
    got += d[i] * l;
    dn += d[i];
  }
  printf("drying rates: liquid rate %.6g (want %.6g, %.2g), booked %.2g, number rate %.2g\n", got, want,
         tl_relerr(got, want), tl_relerr(dl[1], want), dn);
  CHECK_REL(got, want, 1e-12);
  CHECK_REL(dl[1], want, 1e-12);
  CHECK(fabs(dn) < 1e-9);
  free(d);
  free(dl);
  free(yaml);
  gs_case_free(&c);
}

static void test_water_balance(void) {
  /* Spray Q = 1e-8 m^3/s on 1e6 granules in two cells far from dry (30 and
   * 40 liquid cells up) during [0, 2), drying throughout, to t = 3;
   * granule sizes from the solid (size_axes), so E per granule is constant
   * and, as no granule comes near the first liquid pivot (where the scheme
   * stops drying), evaporated = sum_cells E(d_s) N t.  Measured: held
   * change against sprayed - evaporated 8.8e-15, ledger identity 2e-15 of
   * the sprayed.  Tolerances 1e-11 and 1e-13. */
  const double Q = 1e-8, Ts = 2, T = 3;
  char *yaml = tl_fmt("grid:\n  axes:\n    - {name: solid, type: geometric, min: 1.0e-13, ratio: 1.5, cells: 18, zero_first: true}\n"
                      "    - {name: liquid, type: linear, min: 0, max: 8.0e-13, cells: 80}\n"
                      "  size_axes: [solid]\n"
                      "initial:\n  - {type: cell, number: 5.0e5, index: [8, 30]}\n"
                      "  - {type: cell, number: 5.0e5, index: [12, 40]}\n"
                      "mechanisms:\n  - {type: liquid_addition, rate: %g, end: %g}\n  - {type: drying, %s}\n"
                      "solver: {method: rk, rtol: 1.0e-11, atol: 1.0e-9}\n"
                      "output: {times: [1, 2, %g]}\n", Q, Ts, dry_keys, T);
  gs_case c;
  gs_run_report rep;
  double *y = tl_build_run(yaml, &c, &rep);
  if (y) {
    const gs_model *m = &c.model;
    const gs_grid *g = &m->grid;
    double evaporated = 0;
    for (size_t i = 0; i < g->ncells; i++)
      evaporated += c.y0[i] * rate_per_diameter() * cbrt(6 * g->x[2 * i] / M_PI) * T;
    double L0 = tl_mom(&c, c.y0, 0, 0, 1, 0), L = tl_mom(&c, y, 0, 0, 1, 0);
    const double *led = y + m->nstate;
    double bal = (L - L0) - (tl_ext(m, led, 0, 1) - tl_lost(m, led, 0, 1));
    printf("water balance: sprayed %.6g, evaporated %.6g, held change %.6g (sprayed - evaporated %.2g);"
           " ledger identity %.2g\n", Q * Ts, evaporated, L - L0, tl_relerr(L - L0, Q * Ts - evaporated),
           fabs(bal) / (Q * Ts));
    CHECK(evaporated > 0.5 * Q * Ts); /* the test means something */
    CHECK_REL(L - L0, Q * Ts - evaporated, 1e-11);
    CHECK(fabs(bal) < 1e-13 * Q * Ts);
    CHECK_REL(tl_ext(m, led, 0, 1), Q * Ts - evaporated, 1e-11);
    free(y);
    gs_case_free(&c);
  }
  free(yaml);
}

#define DGRID "grid: {axes: [{name: solid, type: linear, min: 0, max: 1.0e-12, cells: 4}, " \
              "{name: liquid, type: linear, min: 0, max: 1.0e-12, cells: 4}]}\noutput: {end: 1}\nmechanisms:\n  - {type: drying, "
static void test_errors(void) {
  EXPECT_INPUT(DGRID "bed_temperature: 500, air_humidity: 0.01}\n", "bed_temperature", "500");
  EXPECT_INPUT(DGRID "bed_temperature: 300, air_humidity: 0.4}\n", "air_humidity", "saturation");
  EXPECT_INPUT(DGRID "bed_temperature: 333, air_humidity: 0.01, wetted_fraction: 0}\n", "wetted_fraction");
  EXPECT_INPUT(DGRID "bed_temperature: 333, air_humidity: 0.01, correction: -1}\n", "correction", "-1");
  EXPECT_INPUT(DGRID "bed_temperature: 333}\n", "missing key 'air_humidity'");
}

int main(void) {
  test_saturation();
  test_rates();
  test_water_balance();
  test_errors();
  return check_failures ? 1 : 0;
}
