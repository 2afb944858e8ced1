/* The aggregation rates are the same bit for bit whether the kernel is read
 * from the precomputed table or its rows are evaluated in the right-hand
 * side (table_limit_mb: 0, and kernels with cheap rows, which never
 * tabulate): both paths call the kernel's row() for the same pairs, and the
 * pair loop does the same arithmetic on the values.  Both redistribution
 * schemes, kernels with and without cheap rows, two compartments, a random
 * dense state. */
#include "pbm_testlib.h"

static const char *kernels[] = {
    "{type: constant, beta0: 1}",
    "{type: sum, beta0: 1}",
    "{type: product, beta0: [1, 2]}",
    "{type: madec, beta0: 1e-3, liquid_axis: l}",
    "{type: madec, beta0: 1e-3, alpha: 2, delta: 0.5, liquid_axis: l}",
    "{type: brownian, beta0: [1, 3]}",
    "{type: brownian, regime: free_molecular, beta0: 1}",
};

static double *rates(const char *kernel, const char *scheme, const char *limit, const double *y0) {
  char *yaml = tl_fmt("grid:\n  compartments: 2\n  axes:\n"
                      "    - {name: s, type: geometric, min: 1e-2, ratio: 1.5, cells: 14}\n"
                      "    - {name: l, type: geometric, min: 1e-3, ratio: 1.6, cells: 12, zero_first: true}\n"
                      "mechanisms:\n  - {type: aggregation, redistribution: %s, %s kernel: %s}\n"
                      "output: {end: 1}\n",
                      scheme, limit, kernel);
  gs_case c;
  double *d = NULL;
  if (!tl_case(yaml, &c)) {
    const gs_model *m = &c.model;
    d = calloc(m->nstate, sizeof(double));
    double *dl = calloc(m->nledger, sizeof(double));
    gs_model_rhs(m, NULL, 0.0, y0, d, dl);
    free(dl);
    gs_case_free(&c);
  }
  free(yaml);
  return d;
}

int main(void) {
  const size_t n = 2 * 14 * 12;
  double *y = calloc(n, sizeof(double));
  tl_rng r = {3};
  for (size_t i = 0; i < n; i++) y[i] = tl_uniform(&r) < 0.8 ? tl_uniform(&r) : 0.0;
  const char *schemes[] = {"cell_average", "fixed_pivot"};
  for (size_t k = 0; k < sizeof kernels / sizeof kernels[0]; k++)
    for (int s = 0; s < 2; s++) {
      double *a = rates(kernels[k], schemes[s], "", y);
      double *b = rates(kernels[k], schemes[s], "table_limit_mb: 0,", y);
      CHECK(a && b);
      if (a && b) {
        size_t differ = 0;
        for (size_t i = 0; i < n; i++) differ += memcmp(&a[i], &b[i], sizeof(double)) != 0;
        if (differ) fprintf(stderr, "%s, %s: %zu of %zu rates differ\n", kernels[k], schemes[s], differ, n);
        CHECK(differ == 0);
      }
      free(a);
      free(b);
    }
  free(y);
  TEST_EXIT();
}
