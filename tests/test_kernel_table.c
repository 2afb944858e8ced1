/* The aggregation rates are the same bit for bit whether the kernel is read
 * from the precomputed table or its rows are evaluated in the right-hand
 * side (table_limit_mb: 0, and kernels with cheap rows, which never
 * tabulate): both paths call the kernel's row() for the same pairs, and the
 * pair loop does the same arithmetic on the values.  Both redistribution
 * schemes, kernels with and without cheap rows, two compartments, a random
 * dense state.  Then threads that take whole compartments sharing one table
 * (its rows filled at first use, by whichever thread gets there first):
 * the first and a later evaluation equal the rows evaluated per segment. */
#include <omp.h>

#include "pbm_testlib.h"

static const char *kernels[] = {
    "{type: constant, beta0: 1}",
    "{type: sum, beta0: 1}",
    "{type: product, beta0: [1, 2]}",
    "{type: madec, beta0: 1e-3, liquid_axis: l}",
    "{type: madec, beta0: 1e-3, alpha: 2, delta: 0.5, liquid_axis: l}",
    "{type: brownian, beta0: [1, 3]}",
    "{type: brownian, regime: free_molecular, beta0: 1}",
    "{type: semi_mechanistic, beta0: [1, 2], velocity: 1e-3, viscosity: 0.1, contact_angle: 60, "
    "solid_density: 1500, critical_saturation: 0.2, liquid_axis: l}",
};

/* The rates of `evals` evaluations (each into its own block of the result)
 * of the state y0 on ncomp compartments of s x l cells. */
static double *rates_on(const char *kernel, const char *scheme, const char *limit, const double *y0,
                        int ncomp, int s, int l, int evals) {
  char *yaml = tl_fmt("grid:\n  compartments: %d\n  axes:\n"
                      "    - {name: s, type: geometric, min: 1e-2, ratio: 1.5, cells: %d}\n"
                      "    - {name: l, type: geometric, min: 1e-3, ratio: 1.6, cells: %d, zero_first: true}\n"
                      "mechanisms:\n  - {type: aggregation, redistribution: %s, %s kernel: %s}\n"
                      "output: {end: 1}\n",
                      ncomp, s, l, scheme, limit, kernel);
  gs_case c;
  double *d = NULL;
  if (!tl_case(yaml, &c)) {
    const gs_model *m = &c.model;
    d = calloc((size_t)evals * m->nstate, sizeof(double));
    double *dl = calloc(m->nledger, sizeof(double));
    for (int e = 0; e < evals; e++) gs_model_rhs(m, NULL, 0.0, y0, d + (size_t)e * m->nstate, dl);
    free(dl);
    gs_case_free(&c);
  }
  free(yaml);
  return d;
}

static double *rates(const char *kernel, const char *scheme, const char *limit, const double *y0) {
  return rates_on(kernel, scheme, limit, y0, 2, 14, 12, 1);
}

static size_t differing(const double *a, const double *b, size_t n) {
  size_t k = 0;
  for (size_t i = 0; i < n; i++) k += memcmp(&a[i], &b[i], sizeof(double)) != 0;
  return k;
}

/* Eight compartments of 24 x 24 cells on 2 threads, one shared table. */
static void shared_table_threads(void) {
  const size_t n = 8 * 24 * 24;
  double *y = calloc(n, sizeof(double));
  tl_rng r = {5};
  for (size_t i = 0; i < n; i++) y[i] = tl_uniform(&r) < 0.5 ? tl_uniform(&r) : 0.0;
  omp_set_num_threads(2);
  const char *k = "{type: brownian, regime: free_molecular, beta0: 1}";
  double *a = rates_on(k, "cell_average", "", y, 8, 24, 24, 2);
  double *b = rates_on(k, "cell_average", "table_limit_mb: 0,", y, 8, 24, 24, 1);
  CHECK(a && b);
  if (a && b) {
    size_t first = differing(a, b, n), later = differing(a + n, b, n);
    fprintf(stderr, "shared table on 2 threads: %zu and %zu of %zu rates differ (first, second evaluation)\n",
            first, later, n);
    CHECK(first == 0 && later == 0);
  }
  free(a);
  free(b);
  free(y);
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
        size_t differ = differing(a, b, n);
        if (differ) fprintf(stderr, "%s, %s: %zu of %zu rates differ\n", kernels[k], schemes[s], differ, n);
        CHECK(differ == 0);
      }
      free(a);
      free(b);
    }
  free(y);
  shared_table_threads();
  TEST_EXIT();
}
