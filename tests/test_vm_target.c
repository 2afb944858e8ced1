/* The published-error target of issue 2: on Vale & McKenna's case study 1
 * (T7b of docs/validation.md: 2-D constant kernel, product of Gamma(2)
 * shapes, N0 = 1, m10 = 1, m20 = 5, tau = 100) the cell-average technique
 * must give M20/M30 errors below the published fixed-pivot errors of Vale &
 * McKenna 2005, Table 1:  30x30: M20 13.1 %, M30 45.6 %;  50x50: 4.3 %, 13.7 %.
 *
 * The case is the one `gransim validate` runs (src/cli/validate.c, study T7b:
 * GRID_VM, the gamma initial distribution, rk with rtol 1e-7, atol 1e-14), so
 * this test asserts the figures of docs/validation.md; the 50x50 run relaxes
 * rtol to 1e-4 (the benchmark's, bench/cases/vm-50x50.yaml), which gives the
 * same errors (below) in 0.8 s instead of 5 s on one core.  Besides the published
 * bounds, tighter bounds near the documented errors catch a regression that
 * stays under the published ones.  Documented (docs/validation.md), CA:
 *   30x30  M20 1.15 %   M30 4.39 %   (bounds 2 % and 6 %)
 *   50x50  M20 0.213 %  M30 0.718 %  (bounds 0.4 % and 1.2 %)
 * and fixed pivot on the same 30x30 grid M20 10.7 %, M30 36.7 %: cell average
 * must beat it by a wide margin (below a third).  By symmetry of the case
 * (x2 = 5 x1 in distribution) M02/M03 have the same relative errors; they are
 * checked too.  M00, M10 and M01 are conserved or closed-form exact for the
 * scheme (M00 = 2/(tau+2) to the integrator's accuracy). */
#include <omp.h>

#include "pbm_testlib.h"

static void vm_exact(double tau, double *m) {
  const double a = 1, b = 5;
  m[0] = 2 / (tau + 2);                                 /* M00 */
  m[1] = a;                                             /* M10 */
  m[2] = b;                                             /* M01 */
  m[3] = 0.5 * a * a * (2 * tau + 3);                   /* M20 */
  m[4] = 0.5 * b * b * (2 * tau + 3);                   /* M02 */
  m[5] = 1.5 * a * a * a * (tau + 1) * (tau + 2);       /* M30 */
  m[6] = 1.5 * b * b * b * (tau + 1) * (tau + 2);       /* M03 */
}
static const int powers[7][2] = {{0, 0}, {1, 0}, {0, 1}, {2, 0}, {0, 2}, {3, 0}, {0, 3}};

/* Relative errors (percent) of the moments above after a run to tau = 100. */
static int vm_run(int cells, const char *scheme, double rtol, double atol, double *err_pct) {
  char *yaml = tl_fmt(
      "grid:\n  axes:\n"
      "    - {name: x1, type: geometric, min: 0.01, max: 4000, cells: %d, zero_first: true}\n"
      "    - {name: x2, type: geometric, min: 0.05, max: 20000, cells: %d, zero_first: true}\n"
      "initial: {type: gamma, number: 1, mean: [1, 5], shape: [2, 2]}\n"
      "mechanisms: [{type: aggregation, redistribution: %s, kernel: {type: constant, beta0: 1}}]\n"
      "solver: {method: rk, rtol: %g, atol: %g}\n"
      "output: {times: [100]}\nchecks: {max_loss: 1.0e-3}\n",
      cells, cells, scheme, rtol, atol);
  gs_case c;
  gs_run_report rep;
  double *y = tl_build_run(yaml, &c, &rep);
  free(yaml);
  if (!y) return 1;
  double exact[7];
  vm_exact(100, exact);
  for (int i = 0; i < 7; i++) {
    int p[3] = {powers[i][0], powers[i][1], 0};
    err_pct[i] = 100 * tl_relerr(gs_moment(&c.model, y, 0, p), exact[i]);
  }
  printf("VM case 1, %dx%d, %s, rtol %g, atol %g: M00 %.3g %%, M10 %.3g %%, M01 %.3g %%, M20 %.4g %%, "
         "M02 %.4g %%, M30 %.4g %%, M03 %.4g %% (%ld RHS evaluations)\n",
         cells, cells, scheme, rtol, atol, err_pct[0], err_pct[1], err_pct[2], err_pct[3], err_pct[4],
         err_pct[5], err_pct[6], rep.stats.rhs_evals);
  free(y);
  gs_case_free(&c);
  return 0;
}

static void check_grid(int cells, double rtol, double atol, const double published[2],
                       const double tight[2]) {
  double e[7];
  if (vm_run(cells, "cell_average", rtol, atol, e)) return;
  CHECK(e[0] < 1e-5 && e[1] < 1e-9 && e[2] < 1e-9); /* percent */
  for (int k = 0; k < 2; k++) { /* M20/M02, then M30/M03 */
    CHECK(e[3 + 2 * k] < published[k]);
    CHECK(e[4 + 2 * k] < published[k]);
    CHECK(e[3 + 2 * k] < tight[k]);
    CHECK(e[4 + 2 * k] < tight[k]);
  }
  if (cells == 30) {
    double f[7];
    if (!vm_run(cells, "fixed_pivot", rtol, atol, f)) {
      CHECK(e[3] < f[3] / 3 && e[5] < f[5] / 3);
      /* gransim's fixed pivot is itself below the published fixed-pivot errors
       * on this grid (10.7 %, 36.7 %), not far from them */
      CHECK(f[3] > 8 && f[3] < 13.1 && f[5] > 30 && f[5] < 45.6);
    }
  }
}

int main(void) {
  /* one thread: the errors do not depend on it, and under `ctest -j` two
   * tests' spinning OpenMP teams on a 2-core machine cost 5x in wall time */
  omp_set_num_threads(1);
  const double pub30[2] = {13.1, 45.6}, tight30[2] = {2.0, 6.0};
  const double pub50[2] = {4.3, 13.7}, tight50[2] = {0.4, 1.2};
  /* 30x30 at the tolerances of `gransim validate`; 50x50 with rtol 1e-4: the
   * M20/M30 errors are the same to 3 digits at rtol 1e-4 ... 1e-7 with atol
   * 1e-14 (measured 0.2135 % / 0.7179 % at 1e-4, 0.2135 % / 0.7178 % at 1e-7).
   * (The benchmark's atol 1e-8 lets cells below 1e-8 drop out of the pair
   * loop: M00 0.012 %, M20/M30 0.215 % / 0.724 %.) */
  check_grid(30, 1e-7, 1e-14, pub30, tight30);
  check_grid(50, 1e-4, 1e-14, pub50, tight50);
  TEST_EXIT();
}
