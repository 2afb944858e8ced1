/* gs_csv_number (src/output/csv_number.c) writes exactly what snprintf's
 * "%.10g" writes: on 3 million random bit patterns (every exponent, subnormals
 * included), 1 million short decimals (k / 10^j, where ties to 10 digits are
 * common), integers up to 2^53, the neighbours of every power of ten, exact
 * ties at the 10th digit, and zeros, infinities, NaN and the extremes. */
#include <float.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "check.h"
#include "output/csv_number.h"

static long mismatches;

static void same(double x) {
  char want[GS_CSV_NUMBER_MAX], got[GS_CSV_NUMBER_MAX];
  snprintf(want, sizeof want, "%.10g", x);
  size_t n = gs_csv_number(x, got);
  if (n == strlen(want) && !strcmp(got, want)) return;
  if (mismatches++ < 10) fprintf(stderr, "%a: printf %s, gs_csv_number %s (%zu)\n", x, want, got, n);
}

static uint64_t state = 0x9e3779b97f4a7c15ull;
static uint64_t next(void) { /* xorshift64* */
  state ^= state >> 12;
  state ^= state << 25;
  state ^= state >> 27;
  return state * 0x2545f4914f6cdd1dull;
}

int main(void) {
  for (int i = 0; i < 3000000; i++) {
    uint64_t b = next();
    double x;
    memcpy(&x, &b, sizeof x);
    if (isfinite(x)) same(x);
  }
  for (int i = 0; i < 1000000; i++) {
    double k = (double)(next() % 100000000000ull), p = pow(10.0, (double)(next() % 40) - 20.0);
    same(k * p);
    same(-k / p);
  }
  for (int i = 0; i < 200000; i++) same((double)(next() >> 11));
  for (int e = -323; e <= 308; e++) {
    double p = pow(10.0, e);
    same(p);
    same(nextafter(p, 0.0));
    same(nextafter(p, INFINITY));
    same(-p);
  }
  /* ties at the 10th significant digit, exact in binary: printf breaks them
   * to even */
  for (long long d = 1000000000; d < 1000000000 + 20000; d++) {
    same((double)(10 * d + 5));
    same((double)(10 * d + 5) / 1024.0);
  }
  const double special[] = {0.0, -0.0, INFINITY, -INFINITY, NAN, DBL_MAX, -DBL_MAX, DBL_MIN,
                            DBL_TRUE_MIN, 1.0, 0.1, 1e-4, 9.99999999949e-5, 9.9999999995,
                            9999999999.5, 99999999995.0, 123456789012.0, 1e10, 1e-5,
                            0.00012345678901, 1.5, 2.5, 0.3};
  for (size_t i = 0; i < sizeof special / sizeof *special; i++) same(special[i]);
  CHECK(mismatches == 0);
  if (mismatches) fprintf(stderr, "%ld values differ\n", mismatches);
  TEST_EXIT();
}
