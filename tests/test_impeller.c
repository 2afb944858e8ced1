/* The impeller speed as a schedule (src/pbm/impeller.c): the shear-dependent
 * mechanisms see the speed of the phase on at t, and nothing between phases.
 *  - shear breakage with b = 0 (S = sqrt(4/15pi) G, G = G_ref N / N_ref): the
 *    number depletion at 600 rpm is exactly twice that at 300 rpm and half at
 *    150, zero while the impeller stands; the rates equal those of a plain
 *    case at the phase's shear rate;
 *  - a run through the phases ends where a run at the reference speed for
 *    sum_i dt_i N_i / N_ref ends (b = 0: the state is exp(A int G dt) N0);
 *  - the semi_mechanistic kernel: at each phase the rates are those of a
 *    plain case with impeller_speed = the phase's speed (and they differ);
 *  - bad input is refused naming the key. */
#include <omp.h>

#include "pbm_testlib.h"

#define GRID1 "grid: {axes: [{name: v, type: geometric, min: 1.0e-12, ratio: 2, cells: 12}]}\n"
#define INITIAL1 "initial: [{type: gamma, number: 1000, mean: 2.0e-10, shape: 4}, {type: cell, number: 1000, index: [12]}]\n"
#define DAUGHTERS "daughters: {type: beta, fragments: 2, shape: 1}"
#define PHASES "phases: [{start: 0, end: 10, speed: 300}, {start: 10, end: 20, speed: 600}, {start: 30, end: 40, speed: 150}]"

static double death_at(gs_case *c, double t, double *dydt) {
  const gs_model *m = &c->model;
  double birth = 0, death = 0, *dl = calloc(m->nledger, sizeof *dl);
  gs_mech_number_rates(m, &m->mech[0], &c->eval, t, c->y0, &birth, &death);
  if (dydt) gs_model_rhs(m, &c->eval, t, c->y0, dydt, dl);
  free(dl);
  return death;
}

static void test_shear_breakage(void) {
  gs_case c, plain;
  char *yaml = tl_fmt(GRID1 INITIAL1 "mechanisms:\n  - type: impeller_schedule\n    " PHASES "\n"
                      "    reference_speed: 300\n"
                      "    mechanism: {type: breakage, selection: {type: shear, shear_rate: 0.05, b: 0}, " DAUGHTERS "}\n"
                      "solver: {rtol: 1.0e-11, atol: 1.0e-12}\nchecks: {max_loss: 1}\noutput: {end: 40}\n");
  char *yaml2 = tl_fmt(GRID1 INITIAL1 "mechanisms:\n  - {type: breakage, selection: {type: shear, shear_rate: 0.1, b: 0}, "
                       DAUGHTERS "}\noutput: {end: 40}\n");
  if (tl_case(yaml, &c) == 0) {
    if (tl_case(yaml2, &plain) == 0) {
      const size_t n = c.model.nstate;
      double *d = calloc(n, sizeof *d), *dp = calloc(n, sizeof *dp);
      const double d300 = death_at(&c, 5, NULL), d600 = death_at(&c, 15, d), d0 = death_at(&c, 25, NULL);
      const double d150 = death_at(&c, 35, NULL);
      death_at(&plain, 15, dp);
      double diff = 0;
      for (size_t i = 0; i < n; i++) diff = fmax(diff, fabs(d[i] - dp[i]));
      printf("shear breakage: depletion at 300, 600, standing, 150 rpm: %.6g %.6g %.6g %.6g; rates at 600 rpm "
             "against a plain case with G = 0.1: largest difference %.3g\n", d300, d600, d0, d150, diff);
      CHECK(d300 > 0);
      CHECK_REL(d600, 2 * d300, 1e-14);
      CHECK_REL(d150, 0.5 * d300, 1e-14);
      CHECK(d0 == 0);
      CHECK(diff == 0);
      free(d);
      free(dp);
      gs_case_free(&plain);
    }
    /* the run: with b = 0 every cell breaks at the same S ~ G, so the state is
     * exp(A integral of G dt) N0 with A fixed: the schedule's end state is a
     * plain run at G_ref for 10 x 1 + 10 x 2 + 10 x 0.5 = 35 s */
    double *y = tl_run(&c, NULL, NULL, NULL);
    char *yaml3 = tl_fmt(GRID1 INITIAL1 "mechanisms:\n  - {type: breakage, selection: {type: shear, shear_rate: 0.05, b: 0}, "
                         DAUGHTERS "}\nsolver: {rtol: 1.0e-11, atol: 1.0e-12}\nchecks: {max_loss: 1}\noutput: {end: 35}\n");
    gs_case ref;
    double *yr = tl_case(yaml3, &ref) == 0 ? tl_run(&ref, NULL, NULL, NULL) : NULL;
    if (y && yr) {
      double worst = 0, top = 0;
      for (size_t i = 0; i < c.model.grid.ncells; i++) top = fmax(top, yr[i]);
      for (size_t i = 0; i < c.model.grid.ncells; i++) worst = fmax(worst, fabs(y[i] - yr[i]) / top);
      printf("after the schedule against 35 s at 300 rpm: largest difference %.3g of the largest number\n", worst);
      CHECK(worst < 1e-8);
      gs_case_free(&ref);
    }
    free(y);
    free(yr);
    free(yaml3);
    gs_case_free(&c);
  }
  free(yaml);
  free(yaml2);
}

#define GRID3                                                                                       \
  "grid:\n  axes:\n"                                                                                \
  "    - {name: solid,  type: geometric, min: 2.6e-13, ratio: 2, cells: 6}\n"                       \
  "    - {name: liquid, type: geometric, min: 1.0e-14, ratio: 2.5, cells: 8, zero_first: true}\n"   \
  "    - {name: gas,    type: geometric, min: 1.0e-14, ratio: 2.5, cells: 8, zero_first: true}\n"   \
  "initial: {type: point, number: 1.0e6, at: [5.24e-13, 4.0e-13, 1.87e-13]}\n"
#define SEMIMECH(speed)                                                                             \
  "{type: semi_mechanistic, beta0: 5.0e-9, impeller_speed: " speed ", impeller_diameter: 0.2,"     \
  " viscosity: 0.05, contact_angle: 60, solid_density: 1500, critical_saturation: 0.05}"

static void test_semimech(void) {
  gs_case c;
  char *yaml = tl_fmt(GRID3 "mechanisms:\n  - type: impeller_schedule\n    " PHASES "\n"
                      "    mechanism: {type: aggregation, kernel: " SEMIMECH("1") "}\noutput: {end: 40}\n");
  if (tl_case(yaml, &c) == 0) {
    const size_t n = c.model.nstate;
    /* a random state, so that pairs of many sizes and liquids take part */
    tl_rng r = {99};
    double *y = calloc(n, sizeof *y), *d = calloc(n, sizeof *d), *dp = calloc(n, sizeof *dp);
    double *dl = calloc(c.model.nledger, sizeof *dl);
    for (size_t i = 0; i < n; i++) y[i] = tl_uniform(&r) < 0.3 ? 1e3 * tl_uniform(&r) : 0;
    static const char *speeds[] = {"300", "600", "150"};
    static const double at[] = {5, 15, 35};
    double total[3];
    for (int p = 0; p < 3; p++) {
      gs_model_rhs(&c.model, &c.eval, at[p], y, d, dl);
      char *plain_yaml = tl_fmt(GRID3 "mechanisms:\n  - {type: aggregation, kernel: " SEMIMECH("%s") "}\n"
                                "output: {end: 40}\n", speeds[p]);
      gs_case plain;
      if (tl_case(plain_yaml, &plain) == 0) {
        gs_model_rhs(&plain.model, &plain.eval, at[p], y, dp, dl);
        double diff = 0, scale = 0;
        total[p] = 0;
        for (size_t i = 0; i < n; i++) {
          diff = fmax(diff, fabs(d[i] - dp[i]));
          scale = fmax(scale, fabs(dp[i]));
          total[p] += fabs(d[i]);
        }
        printf("semi_mechanistic at %s rpm (t = %g): turnover %.6g, difference from the plain case %.3g\n",
               speeds[p], at[p], total[p], diff);
        CHECK(scale > 0 && diff == 0);
        gs_case_free(&plain);
      }
      free(plain_yaml);
    }
    /* faster impeller, larger Stokes numbers, fewer successful collisions */
    CHECK(total[1] < total[0] && total[0] < total[2]);
    gs_model_rhs(&c.model, &c.eval, 25, y, d, dl);
    double standing = 0;
    for (size_t i = 0; i < n; i++) standing += fabs(d[i]);
    CHECK(standing == 0);
    free(y), free(d), free(dp), free(dl);
    gs_case_free(&c);
  }
  free(yaml);
}

static void test_bad_input(void) {
  char *y;
#define BAD(body, ...)                                                                              \
  do {                                                                                              \
    y = tl_fmt(GRID1 "mechanisms:\n  - {type: impeller_schedule, %s}\noutput: {end: 1}\n", body);   \
    EXPECT_INPUT(y, __VA_ARGS__);                                                                   \
    free(y);                                                                                        \
  } while (0)
  BAD("phases: [{start: 0, end: 1, speed: 0}], reference_speed: 1, mechanism: {type: breakage, selection: {type: shear, shear_rate: 5, b: 0}, " DAUGHTERS "}",
      "speed must be > 0");
  BAD("phases: [{start: 0, end: 2, speed: 1}, {start: 1, end: 3, speed: 2}], reference_speed: 1, mechanism: {type: breakage, selection: {type: shear, shear_rate: 5, b: 0}, " DAUGHTERS "}",
      "overlap");
  BAD("phases: [{start: 0, end: 1, speed: 100}], mechanism: {type: breakage, selection: {type: shear, shear_rate: 5, b: 0}, " DAUGHTERS "}",
      "reference_speed");
  BAD("phases: [{start: 0, end: 1, speed: 100}], reference_speed: 1, mechanism: {type: breakage, selection: {type: power, s0: 1}, " DAUGHTERS "}",
      "follows no impeller speed");
  BAD("phases: [{start: 0, end: 1, speed: 100}], mechanism: {type: transfer, rate: 1}", "follows no impeller speed");
  BAD("phases: [{start: 0, end: 1, speed: 100}], reference_speed: 1, mechanism: {type: breakage, selection: {type: shear, shear_rat: 5, b: 0}, " DAUGHTERS "}",
      "did you mean 'shear_rate'");
  BAD("phases: [{start: 0, end: 1, speed: 100}], mechanism: {type: exchange, rates: [[0]]}", "cannot follow");
  BAD("phases: [{start: 0, end: 1, speed: 100}], mechanism: {type: agregation}", "unknown mechanism type 'agregation'");
  BAD("phases: [{start: 0, end: 1, speed: 100}], mechanism: {type: aggregation, kernel: {type: semi_mechanistic, beta0: 1, velocity: 1}}",
      "impeller_speed");
#undef BAD
}

int main(void) {
  omp_set_num_threads(2);
  test_shear_breakage();
  test_semimech();
  test_bad_input();
  TEST_EXIT();
}
