/* Spray schedules of liquid_addition (src/pbm/schedule.c):
 *  - a liquid-to-solid ratio over the three pulses of Chaudhury (2015,
 *    Fig. 2.7): the liquid sprayed after the first pulse is a third of
 *    ratio * solid mass / liquid density, after all three all of it, to
 *    round-off (upwind growth keeps sum G N exactly);
 *  - piecewise rates: the liquid held is the integral of the rates;
 *  - bad schedules refused naming file, line and key. */
#include "pbm_testlib.h"

#define GRID "grid:\n  axes:\n    - {name: solid, type: geometric, min: 1.0e-13, ratio: 2, cells: 10}\n" \
             "    - {name: liquid, type: geometric, min: 1.0e-15, ratio: 1.5, cells: 30, zero_first: true}\n" \
             "initial: {type: point, number: 1.0e5, at: [1.0e-12, 1.0e-14]}\n"

/* liquid volume added by the end of a run of the schedule in yaml */
static double sprayed(const char *mech, double end) {
  char *yaml = tl_fmt(GRID "mechanisms:\n%soutput: {times: [%g]}\nsolver: {method: rk, rtol: 1.0e-9}\n", mech, end);
  gs_case c;
  gs_run_report rep;
  double *y = tl_build_run(yaml, &c, &rep), out = NAN;
  if (y) {
    out = tl_mom(&c, y, 0, 0, 1, 0) - tl_mom(&c, c.y0, 0, 0, 1, 0);
    free(y);
  }
  gs_case_free(&c);
  free(yaml);
  return out;
}

static void test_ratio_pulses(void) {
  /* 1e5 particles of 1e-12 m^3 at 1500 kg/m^3: 1.5e-4 kg of solid; L/S 0.3 */
  const char *mech = "  - type: liquid_addition\n    liquid_solid_ratio: 0.3\n    solid_mass: 1.5e-4\n"
                     "    schedule: [{start: 200, end: 320}, {start: 440, end: 560}, {start: 680, end: 800}]\n";
  const double total = 0.3 * 1.5e-4 / 1000;
  const double first = sprayed(mech, 320), all = sprayed(mech, 900);
  printf("L/S 0.3 in three pulses: after the first %.10g m^3 (a third: %.2g), after all %.10g (%.2g)\n", first,
         tl_relerr(first, total / 3), all, tl_relerr(all, total));
  CHECK_REL(first, total / 3, 1e-12);
  CHECK_REL(all, total, 1e-12);
}

static void test_piecewise(void) {
  const char *mech = "  - type: liquid_addition\n"
                     "    schedule: [{start: 0, end: 10, rate: 1.0e-12}, {start: 10, end: 30, rate: 3.0e-12},"
                     " {start: 50, end: 60, rate: 2.0e-12}]\n";
  const double want = 1e-12 * 10 + 3e-12 * 20 + 2e-12 * 10, got = sprayed(mech, 70), part = sprayed(mech, 40);
  printf("piecewise rates: sprayed %.10g m^3 (%.2g), by t = 40 %.10g (%.2g)\n", got, tl_relerr(got, want), part,
         tl_relerr(part, 7e-11));
  CHECK_REL(got, want, 1e-12);
  CHECK_REL(part, 7e-11, 1e-12);
}

#define BAD GRID "output: {end: 1}\nmechanisms:\n  - type: liquid_addition\n"
static void test_errors(void) {
  EXPECT_INPUT(BAD "    schedule:\n      - {start: 0, end: 10, rate: 1.0e-12}\n      - {start: 5, end: 20, rate: 1.0e-12}\n",
               "bad.yaml:11", "start", "phase 2 begins at 5 s, before phase 1 ends (10 s)");
  EXPECT_INPUT(BAD "    schedule:\n      - {start: 0, end: 10, rate: -1.0e-12}\n", "bad.yaml:10", "rate", "-1.0e-12");
  EXPECT_INPUT(BAD "    rate: 1.0e-12\n    schedule:\n      - {start: 0, end: 10, rate: 1.0e-12}\n", "not both");
  EXPECT_INPUT(BAD "    schedule:\n      - {start: 0, end: 10}\n", "missing key 'rate'");
  EXPECT_INPUT(BAD "    schedule:\n      - {start: 0, end: 10, rate: 1.0e-12, weight: 2}\n", "weight", "liquid_solid_ratio");
  EXPECT_INPUT(BAD "    liquid_solid_ratio: 0.3\n    solid_mass: 1.0\n    schedule:\n      - {start: 0, end: 10, rate: 1.0e-12}\n",
               "rate", "weight");
  EXPECT_INPUT(BAD "    liquid_solid_ratio: -0.3\n    solid_mass: 1.0\n    schedule:\n      - {start: 0, end: 10}\n",
               "liquid_solid_ratio", "-0.3");
  EXPECT_INPUT(BAD "    liquid_solid_ratio: 0.3\n    schedule:\n      - {start: 0, end: 10}\n", "missing key 'solid_mass'");
  EXPECT_INPUT(BAD "    liquid_solid_ratio: 0.3\n    solid_mass: 1.0\n    schedule:\n      - {start: 0, end: 10, weight: 0}\n",
               "weights are all 0");
  EXPECT_INPUT(BAD "    schedule:\n      - {start: 10, end: 5, rate: 1.0e-12}\n", "end", "5");
}

int main(void) {
  test_ratio_pulses();
  test_piecewise();
  test_errors();
  return check_failures ? 1 : 0;
}
