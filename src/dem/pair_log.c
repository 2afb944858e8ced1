/* The log of particle–particle collision onsets that the granulation
 * (src/dem/granulation.c) reads at each of its updates: which two particles
 * began to touch, and how fast they approached.  The class matrix of
 * pair_forces.c counts the same events, but a success rule needs the two
 * particles themselves (their liquid, masses, approach speed).
 *
 * Each thread of the force loop fills its own buffer; the buffers of one
 * evaluation are sorted by the pair's ids before they are appended, so the
 * log is the same for any number of threads. */
#include <stdlib.h>

#include "dem/dem_internal.h"

int gs_dem_pair_log_enable(gs_dem *d, gs_error *err) {
  if (d->plog) return GS_OK;
  d->plog = gs_calloc(1, sizeof *d->plog, err);
  return d->plog ? GS_OK : err->code;
}

void gs_dem_pair_log_push(gs_dem_pair_log *b, long ida, long idb, double vn) {
  if (b->n == b->cap) {
    size_t nc = b->cap ? 2 * b->cap : 64;
    gs_dem_pair_rec *r = realloc(b->r, nc * sizeof *r);
    if (!r) {
      b->oom = 1;
      return;
    }
    b->r = r;
    b->cap = nc;
  }
  if (ida > idb) {
    long q = ida;
    ida = idb;
    idb = q;
  }
  b->r[b->n++] = (gs_dem_pair_rec){ida, idb, vn};
}

static int cmp_rec(const void *a, const void *b) {
  const gs_dem_pair_rec *x = a, *y = b;
  if (x->ida != y->ida) return x->ida < y->ida ? -1 : 1;
  return (x->idb > y->idb) - (x->idb < y->idb);
}

void gs_dem_pair_log_merge(gs_dem *d, gs_dem_pair_log *bufs, int nt) {
  gs_dem_pair_log *L = d->plog;
  size_t n0 = L->n;
  for (int t = 0; t < nt; t++) {
    if (bufs[t].oom) d->oom = 1;
    for (size_t k = 0; k < bufs[t].n; k++) {
      gs_dem_pair_rec *q = &bufs[t].r[k];
      gs_dem_pair_log_push(L, q->ida, q->idb, q->vn);
    }
    free(bufs[t].r);
  }
  if (L->oom) d->oom = 1;
  /* a pair begins to touch at most once per evaluation: the sort is total */
  if (L->n - n0 > 1) qsort(L->r + n0, L->n - n0, sizeof *L->r, cmp_rec);
}

void gs_dem_pair_log_free(gs_dem *d) {
  if (!d->plog) return;
  free(d->plog->r);
  free(d->plog);
  d->plog = NULL;
}
