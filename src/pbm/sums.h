/* Sums over the cells of a compartment in four interleaved partial sums.
 * A single accumulator makes every addition wait for the one before, which
 * made long sums (transfer's moved volumes) a large share of a run with
 * many compartments (docs/performance.md).  The order of the additions
 * is fixed (lane c mod 4, then the lanes pairwise), so results do not
 * depend on where or how often a sum is taken. */
#ifndef GRANSIM_PBM_SUMS_H
#define GRANSIM_PBM_SUMS_H

#include <stddef.h>

/* sum_c w[c] * v[c * stride] */
static inline double gs_dot_strided(const double *restrict w, const double *restrict v,
                                    size_t stride, size_t n) {
  double s[4] = {0, 0, 0, 0};
  size_t c = 0;
  for (; c + 4 <= n; c += 4)
    for (int l = 0; l < 4; l++) s[l] += w[c + (size_t)l] * v[(c + (size_t)l) * stride];
  for (; c < n; c++) s[c % 4] += w[c] * v[c * stride];
  return (s[0] + s[1]) + (s[2] + s[3]);
}

/* sum_c v[c] */
static inline double gs_sum(const double *restrict v, size_t n) {
  double s[4] = {0, 0, 0, 0};
  size_t c = 0;
  for (; c + 4 <= n; c += 4)
    for (int l = 0; l < 4; l++) s[l] += v[c + (size_t)l];
  for (; c < n; c++) s[c % 4] += v[c];
  return (s[0] + s[1]) + (s[2] + s[3]);
}

/* dst[c] += f * v[c]: a compartment's rates moved by a first-order flow. */
static inline void gs_add_scaled(double *restrict dst, const double *restrict v, double f, size_t n) {
  for (size_t c = 0; c < n; c++) dst[c] += f * v[c];
}
#endif
