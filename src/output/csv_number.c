/* See csv_number.h.
 *
 * %.10g rounds the exact binary value of x to 10 significant digits D with
 * decimal exponent X, then writes D in fixed notation when -4 <= X < 10 and
 * in exponential notation otherwise, without trailing zeros.  Here D comes
 * from s = |x| 10^(9 - X) in long double (64-bit significand): the power of
 * ten is the product of an exact 10^r (r < 16) and a correctly rounded
 * 10^(16 q) literal, so s is within ~3 units in the last place, 2e-9
 * absolute for s < 1e10.  Where the fraction of s lies within 1e-6 of one
 * half (exact ties included, which printf breaks to even on the exact
 * value) or long double is no wider than double, snprintf decides. */
#include "output/csv_number.h"

#include <float.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

/* 10^(16 q) for q = -21..21: beyond the exponents a double can ask for
 * (|x| in [4.9e-324, 1.8e308] needs 10^(9 - X), X in [-324, 308]). */
static const long double pow16[] = {
    1e-336L, 1e-320L, 1e-304L, 1e-288L, 1e-272L, 1e-256L, 1e-240L, 1e-224L, 1e-208L,
    1e-192L, 1e-176L, 1e-160L, 1e-144L, 1e-128L, 1e-112L, 1e-96L,  1e-80L,  1e-64L,
    1e-48L,  1e-32L,  1e-16L,  1e0L,    1e16L,   1e32L,   1e48L,   1e64L,   1e80L,
    1e96L,   1e112L,  1e128L,  1e144L,  1e160L,  1e176L,  1e192L,  1e208L,  1e224L,
    1e240L,  1e256L,  1e272L,  1e288L,  1e304L,  1e320L,  1e336L};
#define POW16_ZERO 21 /* index of 10^0 */

static const long double pow1[16] = {1e0L, 1e1L, 1e2L,  1e3L,  1e4L,  1e5L,  1e6L,  1e7L,
                                     1e8L, 1e9L, 1e10L, 1e11L, 1e12L, 1e13L, 1e14L, 1e15L};

/* |x| 10^k, k in [-336, 351]. */
static long double scaled(double a, int k) {
  int q = k >= 0 ? k / 16 : -((-k + 15) / 16), r = k - 16 * q; /* r in [0, 16) */
  return (long double)a * pow16[POW16_ZERO + q] * pow1[r];
}

static size_t fallback(double x, char *buf) {
  int n = snprintf(buf, GS_CSV_NUMBER_MAX, "%.10g", x);
  return n > 0 ? (size_t)n : 0;
}

size_t gs_csv_number(double x, char *buf) {
  if (!isfinite(x) || x == 0.0 || LDBL_MANT_DIG < 64) return fallback(x, buf);
  const double a = fabs(x);
  int X = (int)floor(log10(a)); /* may be off by one near powers of ten */
  long double s = scaled(a, 9 - X);
  if (s < 1e9L) s = scaled(a, 9 - --X);
  else if (s >= 1e10L) s = scaled(a, 9 - ++X);
  const long double whole = floorl(s), frac = s - whole;
  if (fabsl(frac - 0.5L) < 1e-6L) return fallback(x, buf);
  uint64_t D = (uint64_t)whole + (frac > 0.5L);
  if (D == 10000000000ull) { /* 9.9999999995... rounded up */
    D = 1000000000ull;
    X++;
  }
  char dig[10];
  for (int i = 9; i >= 0; i--, D /= 10) dig[i] = (char)('0' + D % 10);
  int nd = 10; /* significant digits, trailing zeros dropped */
  while (nd > 1 && dig[nd - 1] == '0') nd--;
  char *p = buf;
  if (signbit(x)) *p++ = '-';
  if (X < -4 || X >= 10) { /* d.ddde+XX */
    *p++ = dig[0];
    if (nd > 1) {
      *p++ = '.';
      memcpy(p, dig + 1, (size_t)nd - 1);
      p += nd - 1;
    }
    *p++ = 'e';
    *p++ = X < 0 ? '-' : '+';
    const int ax = X < 0 ? -X : X;
    if (ax >= 100) *p++ = (char)('0' + ax / 100);
    *p++ = (char)('0' + ax / 10 % 10);
    *p++ = (char)('0' + ax % 10);
  } else if (X >= 0) { /* ddd.ddd */
    memcpy(p, dig, (size_t)X + 1);
    p += X + 1;
    if (nd > X + 1) {
      *p++ = '.';
      memcpy(p, dig + X + 1, (size_t)(nd - X - 1));
      p += nd - X - 1;
    }
  } else { /* 0.000ddd */
    *p++ = '0';
    *p++ = '.';
    for (int k = 0; k < -X - 1; k++) *p++ = '0';
    memcpy(p, dig, (size_t)nd);
    p += nd;
  }
  *p = '\0';
  return (size_t)(p - buf);
}
