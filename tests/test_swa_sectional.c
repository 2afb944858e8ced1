/* The stochastic (swa) and sectional solvers on the same case files: a 1-D
 * case (constant-kernel aggregation) and a 2-D two-compartment case (solid
 * and liquid, sum kernel over solid + liquid, transfer between compartments).
 * The case text differs only in `solver`.  At the last output time, in every
 * compartment, the SWA ensemble mean of M0, of the total volume of each
 * coordinate and of d50 must agree with the sectional result within the 90 %
 * CI (2.5 CI, plus the sectional discretisation error: 1 % for M0 and the
 * totals, 5 % for d50 on these grids). */
#include <math.h>

#include "pbm_testlib.h"
#include "test_swa.h"

static void compare(const char *body, const char *what) {
  gs_case sc;
  char *yaml = tl_fmt("%ssolver: {method: rk, rtol: 1e-8, atol: 1e-10}\n", body);
  if (tl_case(yaml, &sc)) return;
  free(yaml);
  gs_swa_case wc;
  sw_case(sw_fmt("%ssolver: {method: swa, particles: 4096, runs: 16, seed: 9}\n", body), &wc);
  sw_result r;
  CHECK(sw_run(&wc, &r) == 0);
  /* the sectional run, output time by output time */
  size_t n = sc.model.nstate + sc.model.nledger, nz = sc.model.grid.ncomp, dim = (size_t)sc.model.grid.dim;
  double *y = calloc(n, sizeof(double));
  double *times = sc.times;
  size_t nt = sc.ntimes;
  CHECK(nt == wc.ntimes);
  int worst_ok = 1;
  {
    size_t t = nt - 1;
    gs_error err = {0};
    gs_run_options opt = {0};
    gs_run_report rep;
    if (gs_case_run(&sc, &opt, y, &rep, &err)) {
      fprintf(stderr, "sectional run failed: %s\n", err.msg);
      CHECK(0);
    }
    for (size_t z = 0; z < nz; z++) {
      gs_summary s;
      gs_summarize(&sc.model, y, z, &s);
      double m0 = sw_col(&wc, &r, r.mean, t, z, 0), c0 = sw_col(&wc, &r, r.ci, t, z, 0);
      double d50 = sw_col(&wc, &r, r.mean, t, z, 4), cd = sw_col(&wc, &r, r.ci, t, z, 4);
      int ok = fabs(m0 - s.m0) <= 2.5 * c0 + 0.01 * s.m0 && fabs(d50 - s.d50) <= 2.5 * cd + 0.05 * s.d50;
      for (size_t k = 0; k < dim; k++) {
        double tot = sw_col(&wc, &r, r.mean, t, z, 6 + wc.model.ncoord + (int)k);
        double ct = sw_col(&wc, &r, r.ci, t, z, 6 + wc.model.ncoord + (int)k);
        ok &= fabs(tot - s.total[k]) <= 2.5 * ct + 0.01 * s.total[k];
      }
      fprintf(stderr, "%s: t = %g comp %zu: M0 swa %.5g +- %.3g sectional %.5g; d50 swa %.4g +- %.2g sectional %.4g%s\n",
              what, times[t], z + 1, m0, c0, s.m0, d50, cd, s.d50, ok ? "" : "  <-- disagree");
      worst_ok &= ok;
    }
  }
  CHECK(worst_ok);
  free(y);
  sw_free(&r);
  gs_swa_case_free(&wc);
  gs_case_free(&sc);
}

int main(void) {
  compare("grid:\n  axes: [{name: v, type: geometric, min: 1e-3, ratio: 1.25, cells: 70, zero_first: true}]\n"
          "initial: {type: exponential, number: 1000, mean: 1}\n"
          "mechanisms:\n  - type: aggregation\n    kernel: {type: constant, beta0: 1e-3}\n"
          "output: {end: 10, count: 3}\n",
          "1-D constant");
  compare("grid:\n  compartments: 2\n  axes:\n"
          "    - {name: solid, type: geometric, min: 1e-3, ratio: 1.8, cells: 24, zero_first: true}\n"
          "    - {name: liquid, type: geometric, min: 1e-4, ratio: 1.8, cells: 24, zero_first: true}\n"
          "initial: {type: gamma, number: 1000, mean: [1, 0.3], shape: [2, 2]}\n"
          "mechanisms:\n  - type: aggregation\n    kernel: {type: sum, beta0: 2e-4}\n"
          "  - {type: transfer, residence_time: 5}\n"
          "output: {end: 5, count: 3}\n",
          "2-D sum + transfer");
  TEST_EXIT();
}
