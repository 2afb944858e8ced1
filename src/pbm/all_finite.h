/* Whether a vector of doubles is all finite, in one vectorised pass: an OR
 * of "exponent all ones" over the bits (an early-exit isfinite loop does not
 * vectorise).  Shared by the run driver and the per-compartment steps, which
 * test every rate of every evaluation. */
#ifndef GRANSIM_PBM_ALL_FINITE_H
#define GRANSIM_PBM_ALL_FINITE_H

#include <stddef.h>
#include <stdint.h>
#include <string.h>

static inline int gs_all_finite(const double *f, size_t n) {
  uint64_t bad = 0;
  for (size_t i = 0; i < n; i++) {
    uint64_t b;
    memcpy(&b, f + i, sizeof b);
    bad |= (uint64_t)((b & 0x7ff0000000000000ull) == 0x7ff0000000000000ull);
  }
  return !bad;
}

#endif
