/* The multi-column Fenwick tree behind SWA selection: totals, prefix search
 * and sampling frequencies against a linear scan, after random updates,
 * removals (zeroed slots) and rebuilds, for capacities that are and are not
 * powers of two. */
#include <gsl/gsl_rng.h>
#include <math.h>
#include <stdlib.h>

#include "check.h"
#include "swa/fenwick.h"

static void one(size_t cap, int ncol, gsl_rng *r) {
  gs_fenwick f;
  CHECK(gs_fenwick_init(&f, cap, ncol, NULL) == 0);
  double *v = calloc(cap * (size_t)ncol, sizeof(double));
  size_t n = cap - cap / 3; /* occupied slots 0..n-1 */
  for (int it = 0; it < 5000; it++) {
    size_t i = gsl_rng_uniform_int(r, n);
    double p[4];
    for (int c = 0; c < ncol; c++) p[c] = v[i * (size_t)ncol + (size_t)c] = gsl_rng_uniform(r) < 0.2 ? 0 : gsl_rng_uniform(r);
    gs_fenwick_set(&f, i, p);
  }
  for (int c = 0; c < ncol; c++) {
    double tot = 0;
    for (size_t i = 0; i < n; i++) tot += v[i * (size_t)ncol + (size_t)c];
    CHECK_REL(gs_fenwick_total(&f, c), tot, 1e-12);
    /* find: the slot whose cumulative range contains u, for u across the total */
    int bad = 0;
    for (int k = 0; k < 200; k++) {
      double u = tot * (k + 0.5) / 200, acc = 0;
      size_t want = 0;
      for (size_t i = 0; i < n; i++) {
        acc += v[i * (size_t)ncol + (size_t)c];
        if (acc > u) { want = i; break; }
      }
      bad += gs_fenwick_find(&f, c, u, n) != want;
    }
    CHECK(bad == 0);
  }
  /* rebuild gives the same totals */
  double before = gs_fenwick_total(&f, 0);
  gs_fenwick_rebuild(&f);
  CHECK_REL(gs_fenwick_total(&f, 0), before, 1e-12);
  /* sampling frequency proportional to the values (chi-square-like bound) */
  size_t m = n < 8 ? n : 8;
  double zero[4] = {0};
  for (size_t i = m; i < n; i++) gs_fenwick_set(&f, i, zero);
  int hits[8] = {0}, draws = 80000;
  for (int k = 0; k < draws; k++) hits[gs_fenwick_find(&f, 0, gsl_rng_uniform(r) * gs_fenwick_total(&f, 0), n)]++;
  double tot = gs_fenwick_total(&f, 0);
  for (size_t i = 0; i < m; i++) {
    double p = gs_fenwick_get(&f, i, 0) / tot, sd = sqrt(draws * p * (1 - p)) + 1;
    CHECK(fabs(hits[i] - draws * p) < 5 * sd);
  }
  free(v);
  gs_fenwick_free(&f);
}

int main(void) {
  gsl_rng *r = gsl_rng_alloc(gsl_rng_mt19937);
  gsl_rng_set(r, 5);
  one(1, 1, r);
  one(16, 1, r);
  one(1000, 3, r);
  one(1024, 4, r);
  one(4099, 2, r);
  gsl_rng_free(r);
  TEST_EXIT();
}
