/* Porosity and liquid content of summary.csv (src/pbm/summary.c;
 * Chaudhury 2015, eqs. 2.38-2.39): number-means of (l + g)/(s + l + g) and
 * l/(s + l + g) per particle, from liquid and gas axes or carried
 * quantities alike, computed here by hand for two populated cells; a model
 * with neither reports none. */
#include "pbm_testlib.h"

static void check_two_cells(const char *yaml, double n1, const double *x1, double n2, const double *x2) {
  gs_case c;
  if (tl_case(yaml, &c)) return;
  gs_summary s;
  gs_summarize(&c.model, c.y0, 0, &s);
  const double v1 = x1[0] + x1[1] + x1[2], v2 = x2[0] + x2[1] + x2[2];
  const double por = (n1 * (x1[1] + x1[2]) / v1 + n2 * (x2[1] + x2[2]) / v2) / (n1 + n2);
  const double liq = (n1 * x1[1] / v1 + n2 * x2[1] / v2) / (n1 + n2);
  printf("porosity %.15g (by hand %.15g), liquid content %.15g (%.15g)\n", s.porosity, por, s.liquid_content, liq);
  CHECK_REL(s.porosity, por, 1e-14);
  CHECK_REL(s.liquid_content, liq, 1e-14);
  gs_case_free(&c);
}

int main(void) {
  /* axes (solid, liquid, gas): cells (2, 3, 1) and (4, 1, 2) of linear unit cells (pivots i - 0.5) */
  const double a[3] = {1.5, 2.5, 0.5}, b[3] = {3.5, 0.5, 1.5};
  check_two_cells("grid:\n  axes:\n    - {name: solid, type: linear, min: 0, max: 4, cells: 4}\n"
                  "    - {name: liquid, type: linear, min: 0, max: 4, cells: 4}\n"
                  "    - {name: gas, type: linear, min: 0, max: 4, cells: 4}\n"
                  "initial:\n  - {type: cell, number: 3, index: [2, 3, 1]}\n  - {type: cell, number: 5, index: [4, 1, 2]}\n"
                  "output: {end: 1}\n", 3, a, 5, b);
  /* one solid axis, liquid and gas carried at 2.5/1.5 and 0.5/3.5 per unit solid volume */
  const double c1[3] = {1.5, 2.5, 0.5}, c2[3] = {3.5, 0.5, 1.5};
  check_two_cells("grid:\n  axes:\n    - {name: solid, type: linear, min: 0, max: 4, cells: 4}\n  carried: [liquid, gas]\n"
                  "initial:\n  - {type: cell, number: 3, index: [2], carried_ratio: {liquid: 1.6666666666666667, gas: 0.33333333333333333}}\n"
                  "  - {type: cell, number: 5, index: [4], carried_ratio: {liquid: 0.14285714285714285, gas: 0.42857142857142855}}\n"
                  "output: {end: 1}\n", 3, c1, 5, c2);
  gs_case c;
  if (!tl_case("grid: {axes: [{name: v, type: linear, min: 0, max: 4, cells: 4}]}\n"
               "initial: {type: cell, number: 3, index: [2]}\noutput: {end: 1}\n", &c)) {
    gs_summary s;
    gs_summarize(&c.model, c.y0, 0, &s);
    int l, g;
    CHECK(!gs_model_pore_coordinates(&c.model, &l, &g) && isnan(s.porosity));
    gs_case_free(&c);
  }
  return check_failures ? 1 : 0;
}
