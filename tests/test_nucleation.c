/* Drop-controlled nucleation from the spray (src/pbm/nucleation.c):
 *  - external solid, solid x liquid axes with pivots at the nucleus: every
 *    nucleus lands in the cell of the nucleus size; Q T / V_d nuclei form,
 *    holding exactly the sprayed liquid Q T and Q T / R of solid;
 *  - off a pivot, the lever rule splits the nuclei between the neighbours
 *    and keeps number and volume;
 *  - solid from the fines, liquid carried (grid.carried): the solid going
 *    into nuclei is the solid the fines lose, and the liquid in the nuclei
 *    is the liquid sprayed into them, to round-off;
 *  - bad keys (droplet diameter, rate, ratio, porosity) are refused naming them. */
#include "pbm_testlib.h"

static const double D = 1e-4, R = 0.5; /* droplet diameter (m), liquid/solid ratio */

static void test_external(void) {
  /* Measured: nuclei outside their cell 0; number, liquid and solid
   * exact (0 relative error).  Tolerance 1e-12. */
  const double vd = M_PI * D * D * D / 6, sn = vd / R, Q = 3e-10, T = 2;
  char *yaml = tl_fmt("grid:\n  axes:\n"
                      "    - {name: solid, type: edges, edges: [0, %.17g, %.17g, %.17g, %.17g], pivots: [%.17g, %.17g, %.17g, %.17g]}\n"
                      "    - {name: liquid, type: edges, edges: [0, %.17g, %.17g, %.17g], pivots: [0, %.17g, %.17g]}\n"
                      "initial: {type: cell, number: 1.0e3, index: [4, 1]}\n"
                      "mechanisms:\n  - {type: nucleation, source: external, rate: %g, droplet_diameter: %g,"
                      " liquid_solid_ratio: %g, end: %g}\n"
                      "output: {times: [1, 3]}\n",
                      0.5 * sn, 1.5 * sn, 2.5 * sn, 4 * sn, 0.25 * sn, sn, 2 * sn, 3 * sn,
                      0.5 * vd, 1.5 * vd, 3 * vd, vd, 2 * vd, Q, D, R, T);
  gs_case c;
  gs_run_report rep;
  double *y = tl_build_run(yaml, &c, &rep);
  if (y) {
    const gs_model *m = &c.model;
    const size_t target = 1 * 3 + 1; /* solid pivot sn, liquid pivot vd */
    double nuclei = Q * T / vd, added = 0, elsewhere = 0;
    for (size_t i = 0; i < m->grid.ncells; i++) {
      double dn = y[i] - c.y0[i];
      if (i == target) added = dn;
      else elsewhere += fabs(dn);
    }
    double dS = tl_mom(&c, y, 0, 1, 0, 0) - tl_mom(&c, c.y0, 0, 1, 0, 0);
    double dL = tl_mom(&c, y, 0, 0, 1, 0) - tl_mom(&c, c.y0, 0, 0, 1, 0);
    printf("nucleation, external solid: %.6g nuclei (want %.6g), %.3g outside their cell; liquid %.3g, solid %.3g\n",
           added, nuclei, elsewhere, tl_relerr(dL, Q * T), tl_relerr(dS, Q * T / R));
    CHECK_REL(added, nuclei, 1e-12);
    CHECK(elsewhere < 1e-12 * nuclei);
    CHECK_REL(dL, Q * T, 1e-12);
    CHECK_REL(dS, Q * T / R, 1e-12);
    /* both come in from outside: the ledger books them */
    CHECK_REL(tl_ext(m, y + m->nstate, 0, 0), dS, 1e-13);
    CHECK_REL(tl_ext(m, y + m->nstate, 0, 1), dL, 1e-13);
    free(y);
    gs_case_free(&c);
  }
  free(yaml);
}

static void test_lever(void) {
  /* the nucleus between two solid pivots: split by the lever rule (rates
   * at t = 0), conserving number and solid */
  const double vd = M_PI * D * D * D / 6, sn = vd / R, Q = 1e-10;
  char *yaml = tl_fmt("grid:\n  axes:\n    - {name: solid, type: linear, min: 0, max: %.17g, cells: 7}\n"
                      "    - {name: liquid, type: linear, min: 0, max: %.17g, cells: 5}\n"
                      "initial: {type: cell, number: 1, index: [7, 1]}\n"
                      "mechanisms:\n  - {type: nucleation, source: external, rate: %g, droplet_diameter: %g,"
                      " liquid_solid_ratio: %g}\n"
                      "output: {end: 1}\n", 3.3 * sn, 2.5 * vd, Q, D, R);
  gs_case c;
  double *d, *dl;
  if (tl_rates_at_start(yaml, &c, &d, &dl)) return;
  const gs_model *m = &c.model;
  const gs_grid *g = &m->grid;
  double n = 0, s = 0, l = 0;
  size_t used = 0;
  for (size_t i = 0; i < g->ncells; i++) {
    n += d[i];
    s += d[i] * g->x[2 * i];
    l += d[i] * g->x[2 * i + 1];
    used += d[i] != 0.0;
  }
  const double rate = Q / vd;
  printf("nucleation off the pivots: %zu cells receive nuclei; number %.3g, solid %.3g, liquid %.3g\n", used,
         tl_relerr(n, rate), tl_relerr(s, rate * sn), tl_relerr(l, rate * vd));
  CHECK(used == 4);
  CHECK_REL(n, rate, 1e-13);
  CHECK_REL(s, rate * sn, 1e-13);
  CHECK_REL(l, rate * vd, 1e-13);
  tl_rates_free(&c, d, dl);
}

static void test_fines(void) {
  /* Solid axis (geometric) with carried liquid; fines below 1e-13 m^3, the
   * nucleus (2 V_d = 1.05e-12) well above.  Spray for 5 s (63 % of the
   * fines nucleate).  Measured: solid held, fines' loss against nuclei's
   * solid, nuclei's liquid against the sprayed: all 0 relative error.
   * Tolerance 1e-12. */
  const double Q = 2e-9, T = 5;
  char *yaml = tl_fmt("grid:\n  axes: [{name: solid, type: geometric, min: 1.0e-15, ratio: 2, cells: 20, zero_first: true}]\n"
                      "  carried: [liquid]\n"
                      "initial:\n  - {type: gamma, number: 1.0e6, mean: 2.0e-14, shape: 4}\n"
                      "mechanisms:\n  - {type: nucleation, rate: %g, droplet_diameter: %g, liquid_solid_ratio: %g,"
                      " fines_max: 1.0e-13, end: %g}\n"
                      "solver: {method: rk, rtol: 1.0e-9, atol: 1.0e-6}\n"
                      "output: {times: [2, 6]}\n", Q, D, R, T);
  gs_case c;
  gs_run_report rep;
  double *y = tl_build_run(yaml, &c, &rep);
  if (y) {
    const gs_model *m = &c.model;
    const gs_grid *g = &m->grid;
    double fines0 = 0, fines = 0, nuc_s = 0, nuc_l = 0, fines_l = 0;
    const double *L = gs_model_carried_c(m, y, 0, 0);
    for (size_t i = 0; i < g->ncells; i++) {
      if (g->x[i] <= 1e-13) {
        fines0 += c.y0[i] * g->x[i];
        fines += y[i] * g->x[i];
        fines_l += L[i];
      } else {
        nuc_s += (y[i] - c.y0[i]) * g->x[i];
        nuc_l += L[i];
      }
    }
    double S0 = tl_mom(&c, c.y0, 0, 1, 0, 0), S = tl_mom(&c, y, 0, 1, 0, 0);
    double sprayed = tl_ext(m, y + m->nstate, 0, 1);
    printf("nucleation from fines: %.3g of the fines' solid nucleated; solid held %.3g, nuclei's solid against the"
           " fines' loss %.3g, nuclei's liquid against the liquid sprayed into them %.3g (%.3g of Q T: the"
           " share that fell on fines), nuclei's l/s %.6g (want %g)\n",
           (fines0 - fines) / fines0, tl_relerr(S, S0), tl_relerr(nuc_s, fines0 - fines), tl_relerr(nuc_l, sprayed),
           sprayed / (Q * T), nuc_l / nuc_s, R);
    CHECK((fines0 - fines) / fines0 > 0.05);
    CHECK_REL(S, S0, 1e-12);
    CHECK_REL(nuc_s, fines0 - fines, 1e-12);
    CHECK_REL(nuc_l, sprayed, 1e-12);
    CHECK(fines_l == 0.0);
    CHECK_REL(nuc_l / nuc_s, R, 1e-12);
    CHECK(fabs(tl_ext(m, y + m->nstate, 0, 0)) < 1e-13 * nuc_s); /* solid: moved, not exchanged */
    free(y);
    gs_case_free(&c);
  }
  free(yaml);
}

#define NGRID "grid: {axes: [{name: solid, type: geometric, min: 1.0e-15, ratio: 2, cells: 20}], carried: [liquid, gas]}\n" \
              "output: {end: 1}\nmechanisms:\n  - {type: nucleation, source: external, "
static void test_errors(void) {
  EXPECT_INPUT(NGRID "rate: 1.0e-9, droplet_diameter: 1, liquid_solid_ratio: 0.5}\n", "droplet_diameter", "'1'");
  EXPECT_INPUT(NGRID "rate: 1.0e-9, droplet_diameter: 0, liquid_solid_ratio: 0.5}\n", "droplet_diameter");
  EXPECT_INPUT(NGRID "rate: -1.0e-9, droplet_diameter: 1.0e-4, liquid_solid_ratio: 0.5}\n", "rate", "-1e-09");
  EXPECT_INPUT(NGRID "rate: 1.0e-9, droplet_diameter: 1.0e-4, liquid_solid_ratio: 0}\n", "liquid_solid_ratio");
  EXPECT_INPUT(NGRID "rate: 1.0e-9, droplet_diameter: 1.0e-4, liquid_solid_ratio: 0.5, porosity: 1.5}\n", "porosity", "1.5");
  EXPECT_INPUT(NGRID "rate: 1.0e-9, droplet_diameter: 1.0e-4, liquid_solid_ratio: 0.5, porosity: 0.2}\n", "porosity",
               "does not fit");
  EXPECT_INPUT(NGRID "rate: 1.0e-9, droplet_diameter: 1.0e-3, liquid_solid_ratio: 0.5}\n", "droplet_diameter",
               "outside the grid");
}

int main(void) {
  test_external();
  test_lever();
  test_fines();
  test_errors();
  return check_failures ? 1 : 0;
}
