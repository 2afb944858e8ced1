/* The batch fluid bed as ODE state (src/pbm/fluid_bed.c, mechanism
 * `fluid_bed`, Chaudhury 2015 eqs. 2.16-2.28):
 *  - without wet granules the bed is a heat exchanger with a wall: its
 *    temperature relaxes exponentially to T_inf = (m c T_in - Q + UA T_amb) /
 *    (m c + UA) with tau = C / (m c + UA), phase after phase (closed form);
 *  - with wet granules of constant area and no spray, it reaches the steady
 *    state of the quasi-steady bed of `drying` (drying.c, solved there by
 *    bisection): the same balances without their accumulation terms;
 *  - spraying, aggregation and drying over two air phases keep the water
 *    (vapour = initial + in - out + evaporated; sprayed = held change of the
 *    granules' liquid + evaporated) and energy (enthalpy = initial + in -
 *    out - lost) balances to round-off;
 *  - bad recipes are refused naming file, line and key. */
#include "pbm/drying.h"
#include "pbm_testlib.h"

enum { S_H, S_W, S_EVAP, S_VIN, S_VOUT, S_QIN, S_QOUT, S_QLOST };

/* summary column `name` of compartment 1 of y */
static double column(const gs_model *m, const double *y, double t, const char *name) {
  double v[16];
  gs_model_report(m, 0, t, y, v);
  for (int i = 0; i < gs_model_ncolumns(m); i++)
    if (!strcmp(gs_model_column(m, i)->name, name)) return v[i];
  return NAN;
}

static void test_heat_exchanger(void) {
  /* 1e8 granules of 3e-11 m^3 solid (8.1 kg at 2700 kg/m^3), dry (first
   * liquid pivot): no evaporation, the air's vapour stays at x_in M_air.
   * Phases 333 K then 353 K, 200 W loss, a wall of 5 W/K to 293.15 K. */
  const double N = 1e8, rho = 2700, cs = 1000, Ma = 0.0107, ca = 1006, cv = 1996;
  const double air = 0.067, xin = 0.00505, Q = 200, UA = 5, Tamb = 293.15, T0 = 300;
  char *yaml = tl_fmt("grid:\n  axes:\n    - {name: solid, type: linear, min: 0, max: 4.0e-11, cells: 2}\n"
                      "    - {name: liquid, type: linear, min: 0, max: 1.0e-12, cells: 4}\n"
                      "initial: {type: cell, number: %g, index: [2, 1]}\n"
                      "mechanisms:\n  - {type: fluid_bed, solid_density: %g, air_mass: %g, heat_loss: %g,"
                      " wall_coefficient: %g, initial_temperature: %g,\n"
                      "     air: [{start: 0, end: 30, temperature: 333, humidity: %g, air_flow: %g},\n"
                      "           {start: 30, end: 60, temperature: 353, humidity: %g, air_flow: %g}]}\n"
                      "solver: {method: rk, rtol: 1.0e-11}\n"
                      "output: {times: [30, 60]}\n", N, rho, Ma, Q, UA, T0, xin, air, xin, air);
  gs_case c;
  gs_run_report rep;
  double *y = tl_build_run(yaml, &c, &rep);
  if (y) {
    const gs_model *m = &c.model;
    /* the first liquid pivot of this grid is 1.25e-13 m^3: 12.5 g of water, which does not dry */
    const double ms = tl_mom(&c, c.y0, 0, 1, 0, 0) * rho, ml = tl_mom(&c, c.y0, 0, 0, 1, 0) * 1000;
    const double C = ms * cs + ml * 4187 + Ma * (ca + xin * cv);
    const double mc = air * (ca + xin * cv), tau = C / (mc + UA);
    double T = T0;
    const double Tin[2] = {333, 353};
    for (int p = 0; p < 2; p++) {
      const double Tinf = (mc * Tin[p] - Q + UA * Tamb) / (mc + UA);
      T = Tinf + (T - Tinf) * exp(-30 / tau);
    }
    const double got = column(m, y, 60, "bed_temperature"), x = column(m, y, 60, "outlet_humidity");
    char msg[512] = "";
    const double bal = gs_model_balance(m, y, msg, sizeof msg);
    printf("heat exchanger: T(60 s) %.10f K, closed form %.10f K (%.2g K); x_out %.8g (x_in %.8g); "
           "balances %.2g; solid %.4g kg\n", got, T, got - T, x, xin, bal, ms);
    CHECK(fabs(got - T) < 1e-6);
    CHECK(fabs(T - T0) > 10); /* the test means something */
    CHECK(fabs(x - xin) < 1e-14);
    CHECK(bal < 1e-13);
    CHECK(column(m, y, 60, "evaporated") == 0);
    free(y);
  }
  gs_case_free(&c);
  free(yaml);
}

static void test_steady_limit(void) {
  /* Table 2.3's air, 200 W loss, gamma 0.002; 2 kg of 150 um (solid)
   * granules holding 1.5 kg of water (liquid cell 75 of 81), diameters from the solid
   * (size_axes) so the wet area stays constant while none dries out; the
   * liquid's heat capacity ~0 as in the quasi-steady bed of `drying`.  No
   * spray: after 20 relaxation times (C / (m c_air) = 30 s) the state is
   * the steady one. */
  const double N = 4.19e8;
  char *yaml = tl_fmt("grid:\n  axes:\n    - {name: solid, type: linear, min: 1.0e-12, max: 2.0e-12, cells: 2}\n"
                      "    - {name: liquid, type: linear, min: 0, max: 4.0e-12, cells: 81}\n"
                      "  size_axes: [solid]\n"
                      "initial: {type: cell, number: %g, index: [2, 75]}\n"
                      "mechanisms:\n  - {type: fluid_bed, solid_density: 2700, air_mass: 0.0107, heat_loss: 200,"
                      " correction: 0.002, liquid_heat_capacity: 1.0e-6, spray_temperature: 298.15,\n"
                      "     air: [{start: 0, end: 600, temperature: 333, humidity: 0.00505, air_flow: 0.067}]}\n"
                      "solver: {method: rk, rtol: 1.0e-10}\n"
                      "output: {times: [600]}\n", N);
  gs_case c;
  gs_run_report rep;
  double *y = tl_build_run(yaml, &c, &rep);
  if (y) {
    const gs_model *m = &c.model;
    const gs_grid *g = &m->grid;
    double wet = 0, dry = 0;
    for (size_t i = 0; i < g->ncells; i++) {
      const double d = cbrt(6 * g->x[2 * i] / M_PI);
      if (i % g->axis[1].n) wet += y[i] * d;
      else dry += y[i];
    }
    gs_bed b = {.Tin = 333, .xin = 0.00505, .air = 0.067, .loss = 200, .Tref = 298.15, .dH = 2.27e6,
                .cpa = 1006, .cpv = 1996, .P = 101325, .k0 = 0.002 * 2 * M_PI * 2.6e-5 * 1.18, .rho_l = 1000};
    double T, x, evap = gs_bed_solve(&b, wet, &T, &x);
    const double gotT = column(m, y, 600, "bed_temperature"), gotx = column(m, y, 600, "outlet_humidity");
    const double gote = column(m, y, 600, "evaporation_rate");
    printf("steady limit: T %.9f K (steady bed %.9f, %.2g K), x_out %.9g (%.9g), evaporation %.6g kg/s "
           "(%.6g); granules dried out %.2g\n", gotT, T, gotT - T, gotx, x, gote, evap, dry / N);
    CHECK(fabs(gotT - T) < 1e-6);
    CHECK_REL(gotx, x, 1e-8);
    CHECK_REL(gote, evap, 1e-7);
    CHECK(dry < 1e-6 * N); /* the wet area was constant */
    CHECK(T < 320 && evap > 1e-4); /* the test means something */
    free(y);
  }
  gs_case_free(&c);
  free(yaml);
}

static void test_balances(void) {
  /* spray 9e-10 m^3/s for 60 s onto aggregating granules, air 333 K then
   * 313 K with another humidity and flow; rk, so the linear identities hold
   * to round-off at every output time (the run's checks) and at the end */
  const double Qs = 9e-10, ts = 60;
  char *yaml = tl_fmt("grid:\n  axes:\n    - {name: solid, type: geometric, min: 1.0e-12, ratio: 2, cells: 8}\n"
                      "    - {name: liquid, type: geometric, min: 1.0e-14, ratio: 2, cells: 14, zero_first: true}\n"
                      "initial: {type: point, number: 4.0e5, at: [1.767e-12, 8.6e-14]}\n"
                      "mechanisms:\n  - {type: aggregation, kernel: {type: madec, beta0: 2.0, alpha: 1, delta: 1, "
                      "liquid_content: percent}}\n"
                      "  - {type: liquid_addition, rate: %g, end: %g}\n"
                      "  - {type: fluid_bed, solid_density: 2700, air_mass: 1.0e-5, heat_loss: 0.2, correction: 0.002,\n"
                      "     air: [{start: 0, end: 60, temperature: 333, humidity: 0.00505, air_flow: 6.7e-5},\n"
                      "           {start: 60, end: 120, temperature: 313, humidity: 0.002, air_flow: 1.0e-4}]}\n"
                      "solver: {method: rk, rtol: 1.0e-8}\n"
                      "output: {times: [30, 60, 90, 120]}\n", Qs, ts);
  gs_case c;
  gs_run_report rep;
  double *y = tl_build_run(yaml, &c, &rep);
  if (y) {
    const gs_model *m = &c.model;
    const double *s = gs_model_scalars_c(m, y, 0), *s0 = gs_model_scalars_c(m, c.y0, 0);
    const double L0 = tl_mom(&c, c.y0, 0, 0, 1, 0), L = tl_mom(&c, y, 0, 0, 1, 0);
    const double lost = tl_lost(m, y + m->nstate, 0, 1);
    const double sprayed = 1000 * Qs * ts, evap = s[S_EVAP];
    const double water = 1000 * (L - L0 + lost) + evap - sprayed;
    const double vapour = s[S_W] - (s0[S_W] + s[S_VIN] - s[S_VOUT] + evap);
    const double heat = s[S_H] - (s0[S_H] + s[S_QIN] - s[S_QOUT] - s[S_QLOST]);
    printf("balances: sprayed %.6g kg, evaporated %.6g kg, held change %.6g kg: water %.2g of the sprayed;"
           " vapour %.2g of the vapour in; energy %.2g of the heat in; run's largest %.2g\n", sprayed, evap,
           1000 * (L - L0), water / sprayed, vapour / s[S_VIN], heat / s[S_QIN], rep.max_balance_error);
    CHECK(evap > 0.3 * sprayed && column(m, y, 120, "moisture") > 0); /* the test means something */
    CHECK(fabs(water) < 1e-12 * sprayed);
    CHECK(fabs(vapour) < 1e-13 * s[S_VIN]);
    CHECK(fabs(heat) < 1e-13 * s[S_QIN]);
    CHECK(rep.max_balance_error < 1e-12);
    CHECK(tl_mom(&c, y, 0, 0, 0, 0) < 0.9 * tl_mom(&c, c.y0, 0, 0, 0, 0)); /* it aggregated */
    free(y);
  }
  gs_case_free(&c);
  free(yaml);
}

#define FGRID "grid: {axes: [{name: solid, type: linear, min: 0, max: 1.0e-12, cells: 4}, " \
              "{name: liquid, type: linear, min: 0, max: 1.0e-12, cells: 4}]}\noutput: {end: 1}\n" \
              "mechanisms:\n  - type: fluid_bed\n    solid_density: 2700\n    air_mass: 0.01\n"
#define PHASE1 "      - {start: 0, end: 600, temperature: 333, humidity: 0.005, air_flow: 0.067}\n"
static void test_errors(void) {
  EXPECT_INPUT(FGRID "    air:\n" PHASE1 "      - {start: 500, end: 900, temperature: 333, humidity: 0.005, air_flow: 0.067}\n",
               "bad.yaml:9", "start", "phase 2 begins at 500 s, before phase 1 ends (600 s)", "overlap");
  EXPECT_INPUT(FGRID "    air:\n      - {start: 0, end: 600, temperature: 303, humidity: 0.05, air_flow: 0.067}\n",
               "bad.yaml:8", "humidity", "saturation");
  EXPECT_INPUT(FGRID "    air:\n      - {start: 0, end: 600, temperature: 333, humidity: 0.005, air_flow: -0.067}\n",
               "bad.yaml:8", "air_flow", "-0.067");
  EXPECT_INPUT(FGRID "    air:\n      - {start: 0, end: 600, temperature: 600, humidity: 0.005, air_flow: 0.067}\n",
               "temperature", "600");
  EXPECT_INPUT(FGRID "    air:\n      - {start: 100, end: 50, temperature: 333, humidity: 0.005, air_flow: 0.067}\n",
               "end", "50");
  EXPECT_INPUT(FGRID "    air: []\n", "air", "at least one phase");
  EXPECT_INPUT(FGRID "    heat_loss: -5\n    air:\n" PHASE1, "heat_loss", "-5");
  EXPECT_INPUT(FGRID "    initial_humidity: 0.3\n    air:\n" PHASE1, "initial_humidity", "saturation");
  EXPECT_INPUT(FGRID "    aer:\n" PHASE1, "aer", "did you mean 'air'");
  EXPECT_INPUT(FGRID "    air:\n" PHASE1 "solver: {steps: per_compartment}\n", "steps", "shared");
  EXPECT_INPUT(FGRID "    air:\n" PHASE1 "  - {type: drying, bed_temperature: 333, air_humidity: 0.005}\n",
               "drying cannot join fluid_bed");
  EXPECT_INPUT(FGRID "    air:\n" PHASE1 "  - {type: fluid_bed, solid_density: 2700, air_mass: 0.01, air: [{start: 0, "
               "end: 1, temperature: 333, humidity: 0.005, air_flow: 0.067}]}\n", "one fluid_bed", "mechanisms[0]");
}

int main(void) {
  test_heat_exchanger();
  test_steady_limit();
  test_balances();
  test_errors();
  return check_failures ? 1 : 0;
}
