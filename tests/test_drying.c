/* Drying at a fixed bed temperature and air humidity (src/pbm/drying.c,
 * mechanism `drying`, Chaudhury 2015 eqs. 2.19-2.22 per granule):
 *  - the saturation humidity against steam-table values;
 *  - each cell dries at E(d) = gamma eta 2 pi D_w d rho_air (x_sat - x_air) / rho_l,
 *    recomputed here independently;
 *  - the water balance of a spray + drying run: liquid held - initial =
 *    sprayed - evaporated, with the evaporation known in closed form
 *    (diameters from the solid only, grid.size_axes, so each granule's rate
 *    is constant), and the ledger identity to round-off;
 *  - with `bed`, the quasi-steady heat and vapour balances of the bed hold
 *    at the solved bed temperature, which tends to the adiabatic saturation
 *    temperature of the inlet air as the wet area grows, and a run keeps
 *    its water balance;
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
  if (tl_rates_at_start(yaml, &c, &d, &dl)) return;
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
  tl_rates_free(&c, d, dl);
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

/* The bed's quasi-steady balances (key `bed`): the solved bed temperature
 * zeroes the heat balance and the outlet humidity the vapour balance; with
 * a very large wet area and no heat loss the bed sits at the adiabatic
 * saturation temperature of the inlet air (solved here on its own). */
static gs_bed table23_bed(double loss) {
  /* Chaudhury (2015) Table 2.3 air: 333 K, x_in 0.00505, 0.067 kg/s, gamma 0.002 */
  return (gs_bed){.Tin = 333, .xin = 0.00505, .air = 0.067, .loss = loss, .Tref = 298.15, .dH = 2.27e6,
                  .cpa = 1006, .cpv = 1996, .P = 101325, .k0 = 0.002 * 2 * M_PI * 2.6e-5 * 1.18, .rho_l = 1000};
}

static double adiabatic_saturation(const gs_bed *b) {
  double lo = 274.15, hi = b->Tin;
  for (int i = 0; i < 200; i++) {
    double T = 0.5 * (lo + hi), xs = gs_saturation_humidity(T, b->P);
    double f = b->cpa * (b->Tin - T) + b->cpv * (b->xin * (b->Tin - b->Tref) - xs * (T - b->Tref)) -
               (xs - b->xin) * b->dH;
    if (f > 0) lo = T;
    else hi = T;
  }
  return lo;
}

static void test_bed_balances(void) {
  /* Table 2.3's air and heat loss; 2 kg of 200 um granules give sum N d =
   * 3.5e4 m (T 313.3 K, 5.0e-4 kg/s evaporated against the 1e-3 kg/s spray).
   * Measured: heat residual <= 5.7e-15 of the air's sensible heat, vapour
   * balance <= 1.1e-16; the limit within 1e-9 K of T_as = 298.49 K.
   * Tolerances 1e-9, 1e-13, 1e-4 K. */
  const double wet[3] = {3.5e4, 3.5e7, 3.5e10}; /* sum N d (m): 2 kg of 200 um granules x 1, 1e3, 1e6 */
  for (int i = 0; i < 3; i++) {
    gs_bed b = table23_bed(200);
    double T, x, evap = gs_bed_solve(&b, wet[i], &T, &x);
    double g1 = b.air * (b.cpa * (b.Tin - T) + b.cpv * (b.xin * (b.Tin - b.Tref) - x * (T - b.Tref)));
    double heat = g1 - evap * b.dH - b.loss, sensible = b.air * b.cpa * (b.Tin - T);
    printf("bed with sum N d = %.3g m: T %.4f K, x_out %.5f, evaporation %.4g kg/s; heat residual %.2g of the"
           " sensible heat, vapour %.2g\n", wet[i], T, x, evap, fabs(heat) / sensible,
           tl_relerr(b.air * (x - b.xin), evap));
    CHECK(fabs(heat) < 1e-9 * sensible);
    CHECK_REL(b.air * (x - b.xin), evap, 1e-13);
    CHECK(T < b.Tin && x > b.xin);
  }
  gs_bed b = table23_bed(0);
  double T, x, Tas = adiabatic_saturation(&b);
  gs_bed_solve(&b, 1e15, &T, &x);
  printf("bed, wet area without limit: T %.6f K, adiabatic saturation %.6f K; x_out %.6f, x_sat %.6f\n", T, Tas, x,
         gs_saturation_humidity(T, b.P));
  CHECK(fabs(T - Tas) < 1e-4);
  CHECK(Tas > 295 && Tas < 305);
}

static void test_bed_run(void) {
  /* spray + drying with the bed's balances: the run's water balance (held
   * change = sprayed - evaporated, the evaporation as booked) to round-off
   * (measured 9.9e-15 of the sprayed; tolerance 1e-13) */
  const double Q = 1e-8, Ts = 2;
  char *yaml = tl_fmt("grid:\n  axes:\n    - {name: solid, type: geometric, min: 1.0e-13, ratio: 1.5, cells: 18, zero_first: true}\n"
                      "    - {name: liquid, type: linear, min: 0, max: 8.0e-13, cells: 80}\n"
                      "initial:\n  - {type: cell, number: 5.0e5, index: [8, 30]}\n"
                      "  - {type: cell, number: 5.0e5, index: [12, 40]}\n"
                      "mechanisms:\n  - {type: liquid_addition, rate: %g, end: %g}\n"
                      "  - {type: drying, correction: 50, bed: {inlet_temperature: 333, inlet_humidity: 0.00505,"
                      " air_flow: 2.0e-4, heat_loss: 0}}\n"
                      "solver: {method: rk, rtol: 1.0e-9, atol: 1.0e-6}\n"
                      "output: {times: [1, 2, 3]}\n", Q, Ts);
  gs_case c;
  gs_run_report rep;
  double *y = tl_build_run(yaml, &c, &rep);
  if (y) {
    const gs_model *m = &c.model;
    const double *led = y + m->nstate;
    double L0 = tl_mom(&c, c.y0, 0, 0, 1, 0), L = tl_mom(&c, y, 0, 0, 1, 0);
    double evaporated = Q * Ts - tl_ext(m, led, 0, 1);
    printf("bed run: sprayed %.4g, evaporated %.4g, held change %.4g; water balance %.2g of the sprayed\n", Q * Ts,
           evaporated, L - L0, fabs(L - L0 - (Q * Ts - evaporated) + tl_lost(m, led, 0, 1)) / (Q * Ts));
    CHECK(evaporated > 0.1 * Q * Ts);
    CHECK(fabs(L - L0 - (Q * Ts - evaporated) + tl_lost(m, led, 0, 1)) < 1e-13 * Q * Ts);
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
  EXPECT_INPUT(DGRID "bed_temperature: 333, bed: {inlet_temperature: 333, inlet_humidity: 0.005, air_flow: 0.1}}\n",
               "bed", "not both");
  EXPECT_INPUT(DGRID "bed: {inlet_temperature: 333, inlet_humidity: 0.005, air_flow: -0.1}}\n", "air_flow", "-0.1");
  EXPECT_INPUT(DGRID "bed: {inlet_temperature: 333, inlet_humidity: 0.005, air_flow: 0.1, heat_loss: -5}}\n",
               "heat_loss");
}

int main(void) {
  test_saturation();
  test_rates();
  test_water_balance();
  test_bed_balances();
  test_bed_run();
  test_errors();
  return check_failures ? 1 : 0;
}
