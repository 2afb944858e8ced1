/* Memory follows the occupied cells (issue 26 item 7): the 3-D Madec case
 * with 22 cells per axis (bench/cases/madec-3d-26.yaml with solid ratio 1.75
 * and liquid/gas ratio 2.0, so that the grid holds the run: 10 648 cells,
 * 56.7e6 pairs) runs to its end in under 50 MB peak resident memory.  A
 * table of the kernel for every pair of cells took 466 MB
 * (docs/performance.md, "Kernel tables follow the kernel's cost"); the
 * kernel is now evaluated for the pairs that take part.  The peak is the
 * whole test process's (getrusage): 16 MB, 11 MB of them before the case
 * is built. */
#include <omp.h>
#include <sys/resource.h>

#include "pbm_testlib.h"

static double peak_mb(void) {
  struct rusage ru;
  getrusage(RUSAGE_SELF, &ru);
  return (double)ru.ru_maxrss / 1024.0; /* kilobytes on Linux */
}

int main(void) {
  omp_set_num_threads(1);
  /* delta 1.5 makes the kernel's rows dear, so they are tabulated (lazily):
   * 95 MB, and the check below fails, as it must */
  const char *delta = "1";
  char *yaml = tl_fmt(
      "grid:\n  axes:\n"
      "    - {name: solid,  type: geometric, min: 2.6e-13, ratio: 1.75, cells: 22}\n"
      "    - {name: liquid, type: geometric, min: 2.0e-14, ratio: 2.0, cells: 22, zero_first: true}\n"
      "    - {name: gas,    type: geometric, min: 2.0e-14, ratio: 2.0, cells: 22, zero_first: true}\n"
      "initial: {type: point, number: 3.8e8, at: [5.24e-13, 1.0e-14, 3.49e-13]}\n"
      "mechanisms:\n"
      "  - {type: aggregation, kernel: {type: madec, beta0: 1.0e-2, alpha: 1, delta: %s}}\n"
      "  - {type: liquid_addition, rate: 2.0e-7, start: 0, end: 300}\n"
      "  - {type: consolidation, rate: 1.0e-3, min_porosity: 0.2}\n"
      "solver: {method: cvode, rtol: 1.0e-5, atol: 0.1}\n"
      "output: {end: 500, count: 2}\n",
      delta);
  const double before = peak_mb();
  gs_case c;
  gs_run_report rep;
  double *y = tl_build_run(yaml, &c, &rep);
  free(yaml);
  if (!y) {
    CHECK(y != NULL);
    TEST_EXIT();
  }
  const double peak = peak_mb();
  printf("3-D Madec, 22 cells per axis, delta %s: peak resident memory %.1f MB (%.1f MB before "
         "the case was built), %ld steps, volume balance %.2g\n",
         delta, peak, before, rep.stats.steps, rep.max_balance_error);
#ifndef __SANITIZE_ADDRESS__
  CHECK(peak < 50);
#else
  (void)peak; /* AddressSanitizer's shadow memory and quarantine: no bound */
#endif
  free(y);
  gs_case_free(&c);
  TEST_EXIT();
}
