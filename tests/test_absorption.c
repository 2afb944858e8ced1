/* The liquid absorption law of De et al. (2025), eqs. 7-9, as the sharing
 * rule `absorption` of the spray (src/pbm/liquid_share.c):
 *  - carried liquid: every cell's liquid rate is Q N V psi(d) / sum(N V psi),
 *    V = s + l + g the granule's gross volume and psi from a table of
 *    diameters, to round-off; the rates add up to Q and the ledger books Q;
 *  - liquid as an axis (`liquid_addition`): per solid column, the liquid the
 *    column's granules gain equals the law's share of Q, to round-off; the
 *    inflow from `liquid_solid_ratio` is LS rho_s/rho_l S / (end - start),
 *    from `droplets` rate x volume;
 *  - a run: the liquid added over the window equals the liquid sprayed,
 *    LS rho_s/rho_l S, to round-off, while solid and number stay;
 *  - the default rule still shares by solid volume; bad keys are refused;
 *  - aggregation's wet switch with liquid as a grid axis (the paper's 3-D
 *    PBM): a dry cell neither aggregates nor is aggregated with, a wet
 *    cell's death rate is beta0 N^2 exactly. */
#include "pbm_testlib.h"

static const char *CARRIED =
    "grid:\n  axes:\n"
    "    - {name: api, type: geometric, min: 1.0e-13, ratio: 2, cells: 8}\n"
    "    - {name: excipient, type: geometric, min: 1.0e-13, ratio: 2, cells: 8}\n"
    "  carried: [liquid, gas]\n"
    "mechanisms:\n"
    "  - {type: spray, rate: 2.0e-9, share: {type: absorption,\n"
    "     probability: {diameters: [0, 1.0e-4, 1.5e-4, 1.0], values: [0.5, 1.0, 0.7]}}}\n"
    "output: {end: 1}\n";

static double psi_of(double V) {
  double d = cbrt(6 * V / M_PI);
  return d < 1.0e-4 ? 0.5 : d < 1.5e-4 ? 1.0 : 0.7;
}

static void carried(void) {
  gs_case c;
  if (tl_case(CARRIED, &c)) return;
  gs_model *m = &c.model;
  const gs_grid *g = &m->grid;
  double *y = calloc(m->nstate, sizeof *y), *d = calloc(m->nstate, sizeof *d), *dl = calloc(m->nledger, sizeof *dl);
  tl_rng r = {7};
  for (size_t i = 0; i < g->ncells; i++) {
    y[i] = 1e6 * tl_uniform(&r);
    gs_model_carried(m, y, 0, 0)[i] = 0.3 * tl_uniform(&r) * y[i] * g->volume[i];
    gs_model_carried(m, y, 0, 1)[i] = 0.2 * tl_uniform(&r) * y[i] * g->volume[i];
  }
  gs_model_rhs(m, &c.eval, 0.5, y, d, dl);
  double wsum = 0, total = 0, worst = 0;
  int classes[3] = {0, 0, 0};
  for (size_t i = 0; i < g->ncells; i++) {
    double V = g->volume[i] + (gs_model_carried(m, y, 0, 0)[i] + gs_model_carried(m, y, 0, 1)[i]) / y[i];
    wsum += y[i] * V * psi_of(V);
  }
  for (size_t i = 0; i < g->ncells; i++) {
    double V = g->volume[i] + (gs_model_carried(m, y, 0, 0)[i] + gs_model_carried(m, y, 0, 1)[i]) / y[i];
    double want = 2.0e-9 * y[i] * V * psi_of(V) / wsum, got = gs_model_carried(m, d, 0, 0)[i];
    worst = fmax(worst, fabs(got - want) / want);
    total += got;
    classes[psi_of(V) == 0.5 ? 0 : psi_of(V) == 1.0 ? 1 : 2]++;
    CHECK(d[i] == 0 && gs_model_carried(m, d, 0, 1)[i] == 0); /* numbers and gas untouched */
  }
  printf("absorption (carried liquid): worst relative error of a cell's share %.3g; cells per psi class %d %d %d\n",
         worst, classes[0], classes[1], classes[2]);
  CHECK(worst < 1e-13);
  CHECK(classes[0] > 0 && classes[1] > 0 && classes[2] > 0); /* the table is exercised */
  CHECK_REL(total, 2.0e-9, 1e-14);
  CHECK_REL(tl_ext(m, dl, 0, g->dim + 0), 2.0e-9, 1e-15);
  free(y);
  free(d);
  free(dl);
  gs_case_free(&c);
}

/* solid x liquid grid; liquid only in the lower pivots (no loss at the top) */
static const char *AXIS =
    "grid:\n  axes:\n"
    "    - {name: solid, type: geometric, min: 5.0e-14, ratio: 1.5, cells: 16}\n"
    "    - {name: liquid, type: linear, min: 0, max: 4.0e-11, cells: 40}\n"
    "initial:\n"
    "  - {type: gamma, number: 1.0e6, mean: [1.0e-12, 2.0e-12], shape: [8, 8]}\n"
    "mechanisms:\n  - %s\n"
    "output: {end: %g}\n";

/* The AXIS case with mechanism mech, to t = end (a static buffer: one at a time). */
static const char *axis_case(const char *mech, double end) {
  static char buf[4096];
  snprintf(buf, sizeof buf, AXIS, mech, end);
  return buf;
}

/* rates at the start: per solid column, the liquid gained */
static void axis_rates(const char *mech, double Q, int absorb) {
  gs_case c;
  double *d, *dl;
  if (tl_rates_at_start(tl_fmt(AXIS, mech, 1.0), &c, &d, &dl)) return;
  const gs_grid *g = &c.model.grid;
  const gs_axis *sa = &g->axis[0], *la = &g->axis[1];
  double wsum = 0, total = 0, worst = 0;
  for (size_t i = 0; i < g->ncells; i++) wsum += c.y0[i] * (absorb ? g->volume[i] : g->x[2 * i]);
  for (size_t i = 0; i < sa->n; i++) {
    double got = 0, want = 0;
    for (size_t j = 0; j < la->n; j++) {
      size_t cell = i * g->stride[0] + j;
      got += d[cell] * la->pivots[j];
      want += Q * c.y0[cell] * (absorb ? g->volume[cell] : sa->pivots[i]) / wsum;
    }
    total += got;
    if (want > 1e-12 * Q) worst = fmax(worst, fabs(got - want) / want);
  }
  printf("%s: liquid %.15g per second (want %.15g); worst column error %.3g\n", absorb ? "absorption" : "solid_volume",
         total, Q, worst);
  CHECK_REL(total, Q, 1e-12);
  CHECK(worst < 1e-11);
  tl_rates_free(&c, d, dl);
}

static void axis(void) {
  /* the batch's solid volume S: the initial distribution's */
  gs_case c;
  if (tl_case(axis_case("{type: liquid_addition, rate: 1.0e-6}", 1.0), &c)) return;
  const double S = tl_mom(&c, c.y0, 0, 1, 0, 0);
  gs_case_free(&c);
  char mech[512];
  /* LS 0.15 by mass over 10 s, rho_s 1668, rho_l 1000 */
  snprintf(mech, sizeof mech, "{type: liquid_addition, liquid_solid_ratio: 0.15, solid_density: 1668, start: 0, "
                              "end: 10, share: {type: absorption, probability: 0.8}}");
  axis_rates(mech, 0.15 * 1668 / 1000 * S / 10, 1);
  snprintf(mech, sizeof mech, "{type: liquid_addition, droplets: {rate: 1.0e5, volume: 3.0e-12}, "
                              "share: {type: absorption}}");
  axis_rates(mech, 3.0e-7, 1);
  snprintf(mech, sizeof mech, "{type: liquid_addition, rate: 3.0e-7}");
  axis_rates(mech, 3.0e-7, 0);
  /* a run over the window and past it: LS by volume this time */
  gs_run_report rep;
  char *yaml = tl_fmt(AXIS, "{type: liquid_addition, liquid_solid_ratio: 0.2, ratio_basis: volume, start: 1, end: 4, "
                            "share: {type: absorption}}", 5.0);
  double *y = tl_build_run(yaml, &c, &rep);
  free(yaml);
  if (y) {
    const gs_model *m = &c.model;
    double L0 = tl_mom(&c, c.y0, 0, 0, 1, 0), L = tl_mom(&c, y, 0, 0, 1, 0);
    double N0 = tl_mom(&c, c.y0, 0, 0, 0, 0), N = tl_mom(&c, y, 0, 0, 0, 0);
    printf("absorption run: liquid added %.15g, sprayed %.15g\n", L - L0, 0.2 * S);
    CHECK_REL(L - L0, 0.2 * S, 1e-12);
    CHECK_REL(tl_ext(m, y + m->nstate, 0, 1), 0.2 * S, 1e-12);
    CHECK_REL(tl_mom(&c, y, 0, 1, 0, 0), S, 1e-13);
    CHECK_REL(N, N0, 1e-13);
    CHECK(fabs(tl_lost(m, y + m->nstate, 0, 1)) <= 1e-12 * 0.2 * S); /* none reach the grid's end */
  }
  free(y);
  gs_case_free(&c);
}

static void bad_input(void) {
  EXPECT_INPUT(axis_case("{type: liquid_addition, rate: 1.0e-6, share: {type: absorbtion}}", 1.0),
               "did you mean 'absorption'");
  EXPECT_INPUT(axis_case("{type: liquid_addition, liquid_solid_ratio: 0.1, solid_density: 1668}", 1.0),
               "give 'end'");
  EXPECT_INPUT(axis_case("{type: liquid_addition, liquid_solid_ratio: 0.1, end: 2}", 1.0), "solid_density");
  EXPECT_INPUT(axis_case("{type: liquid_addition, rate: 1.0e-6, liquid_solid_ratio: 0.1, end: 2}", 1.0),
               "expected one of 'rate'");
  EXPECT_INPUT(axis_case("{type: liquid_addition, rate: 1.0e-6, share: {type: absorption, probability: 1.5}}", 1.0),
               "probability");
  EXPECT_INPUT(axis_case("{type: liquid_addition, rate: 1.0e-6, share: {type: absorption, "
                            "probability: {diameters: [0, 1], values: [0.5, 0.5]}}}", 1.0), "n + 1 diameters");
  EXPECT_INPUT(axis_case("{type: liquid_addition, droplets: {rate: 10}}", 1.0), "volume");
}

static void wet_axis(void) {
  gs_case c;
  const char *yaml = "grid:\n  axes:\n"
                     "    - {name: solid, type: geometric, min: 1.0e-12, ratio: 2, cells: 8}\n"
                     "    - {name: liquid, type: linear, min: 0, max: 4.0e-12, cells: 8}\n"
                     "mechanisms:\n  - {type: aggregation, kernel: {type: constant, beta0: 1.0e-6},\n"
                     "     wet: {min_content: 0.2, liquid: liquid}}\n"
                     "output: {end: 1}\n";
  if (tl_case(yaml, &c)) return;
  gs_model *m = &c.model;
  const gs_grid *g = &m->grid;
  double *y = calloc(m->nstate, sizeof *y), *d = calloc(m->nstate, sizeof *d), *dl = calloc(m->nledger, sizeof *dl);
  /* wet: solid pivot 0 (1e-12), liquid pivot 3 (content ~ 1.75); dry: solid
   * pivot 2 (4e-12), liquid pivot 0 (content ~ 0.06) */
  const size_t wet = 0 * g->stride[0] + 3, dry = 2 * g->stride[0] + 0;
  const double lw = g->axis[1].pivots[3], ld = g->axis[1].pivots[0];
  CHECK(lw / g->axis[0].pivots[0] > 0.22 && ld / g->axis[0].pivots[2] < 0.18); /* outside the ramp */
  y[wet] = 1e3;
  y[dry] = 2e3;
  gs_model_rhs(m, &c.eval, 0, y, d, dl);
  printf("wet switch on a liquid axis: dry cell's rate %g, wet cell's %.15g (want %.15g)\n", d[dry], d[wet],
         -1.0e-6 * 1e3 * 1e3);
  CHECK(d[dry] == 0);
  CHECK_REL(d[wet], -1.0e-6 * 1e3 * 1e3, 1e-12);
  free(y);
  free(d);
  free(dl);
  gs_case_free(&c);
}

int main(void) {
  wet_axis();
  carried();
  axis();
  bad_input();
  TEST_EXIT();
}
