/* Multi-column Fenwick (binary indexed) tree over particle slots.
 *
 * Each particle slot i has ncol property values; the tree keeps prefix sums
 * of every column so that the total, an update and a selection with
 * probability proportional to one column all cost O(log cap).  Columns are
 * interleaved (node-major) because an update touches the same nodes of every
 * column.  Deltas accumulate round-off, so the tree is rebuilt from the leaf
 * values every `cap` updates (amortised O(ncol) per update). */
#ifndef GS_SWA_FENWICK_H
#define GS_SWA_FENWICK_H

#include <stddef.h>

#include "gransim/error.h"

typedef struct gs_fenwick {
  size_t cap;  /* slots 0..cap-1 */
  size_t top;  /* largest power of two <= cap */
  int ncol;
  double *val; /* cap * ncol leaf values */
  double *sum; /* (cap + 1) * ncol tree nodes, 1-based */
  double total[16]; /* column totals, kept alongside (reset by rebuild) */
  size_t updates;
} gs_fenwick;

int gs_fenwick_init(gs_fenwick *f, size_t cap, int ncol, gs_error *err);
void gs_fenwick_free(gs_fenwick *f);
/* Set all ncol values of slot i. */
void gs_fenwick_set(gs_fenwick *f, size_t i, const double *v);
/* Recompute every node from the leaves (slots >= n must already be 0). */
void gs_fenwick_rebuild(gs_fenwick *f);
static inline double gs_fenwick_total(const gs_fenwick *f, int col) { return f->total[col]; }
/* Smallest slot i with prefix(i+1) > u, for 0 <= u < total(col); clamped to
 * [0, n-1]. */
size_t gs_fenwick_find(const gs_fenwick *f, int col, double u, size_t n);

static inline double gs_fenwick_get(const gs_fenwick *f, size_t i, int col) {
  return f->val[i * (size_t)f->ncol + (size_t)col];
}
#endif
