/* The four-lane sums of src/pbm/sums.h: every length from 0 to 40 (the tail
 * after the last full group of four included) and strides 1 to 3 pick the
 * right elements (exact on small integers) and agree with a long double sum
 * to round-off on random values in [-0.25, 0.75) (5e-14 absolute for the
 * products, 1e-15 per term for the plain sum). */
#include <stdlib.h>

#include "check.h"
#include "pbm/sums.h"

int main(void) {
  double v[3 * 40], w[40];
  unsigned s = 7;
  for (int i = 0; i < 3 * 40; i++) {
    s = s * 1664525u + 1013904223u;
    v[i] = (double)(s >> 8) / 16777216.0 - 0.25;
  }
  for (size_t n = 0; n <= 40; n++) {
    for (size_t stride = 1; stride <= 3; stride++) {
      long double want = 0, plain = 0;
      for (size_t c = 0; c < n; c++) {
        w[c] = (double)(c % 7) - 2.0; /* small integers: every partial sum exact */
        want += (long double)w[c] * (long double)((double)(stride * c));
      }
      double x[3 * 40];
      for (size_t i = 0; i < 3 * 40; i++) x[i] = (double)i;
      CHECK(gs_dot_strided(w, x, stride, n) == (double)want);
      for (size_t c = 0; c < n; c++) plain += (long double)w[c] * (long double)v[c * stride];
      double got = gs_dot_strided(w, v, stride, n);
      CHECK(fabs(got - (double)plain) <= 4e-16 * 40 * 3 || n == 0);
    }
    long double sum = 0;
    for (size_t c = 0; c < n; c++) sum += (long double)v[c];
    CHECK(fabs(gs_sum(v, n) - (double)sum) <= 1e-15 * (double)(n + 1));
  }
  CHECK(gs_sum(v, 0) == 0.0);
  TEST_EXIT();
}
