/* Multi-column Fenwick tree: see fenwick.h. */
#include "swa/fenwick.h"

#include <stdlib.h>
#include <string.h>

int gs_fenwick_init(gs_fenwick *f, size_t cap, int ncol, gs_error *err) {
  memset(f, 0, sizeof *f);
  f->cap = cap;
  f->ncol = ncol < 16 ? ncol : 16;
  f->top = 1;
  while (f->top * 2 <= cap) f->top *= 2;
  f->val = gs_calloc(cap * (size_t)ncol, sizeof(double), err);
  f->sum = gs_calloc((cap + 1) * (size_t)ncol, sizeof(double), err);
  if (!f->val || !f->sum) {
    gs_fenwick_free(f);
    return GS_ENOMEM;
  }
  return GS_OK;
}

void gs_fenwick_free(gs_fenwick *f) {
  free(f->val);
  free(f->sum);
  memset(f, 0, sizeof *f);
}

void gs_fenwick_rebuild(gs_fenwick *f) {
  size_t nc = (size_t)f->ncol;
  memset(f->sum, 0, (f->cap + 1) * nc * sizeof(double));
  for (size_t k = 1; k <= f->cap; k++) {
    double *node = f->sum + k * nc;
    const double *leaf = f->val + (k - 1) * nc;
    for (size_t c = 0; c < nc; c++) node[c] += leaf[c];
    size_t parent = k + (k & (~k + 1));
    if (parent <= f->cap)
      for (size_t c = 0; c < nc; c++) f->sum[parent * nc + c] += node[c];
  }
  for (size_t c = 0; c < nc; c++) {
    double s = 0;
    for (size_t k = f->cap; k > 0; k -= k & (~k + 1)) s += f->sum[k * nc + c];
    f->total[c] = s;
  }
  f->updates = 0;
}

void gs_fenwick_set(gs_fenwick *f, size_t i, const double *v) {
  size_t nc = (size_t)f->ncol;
  double d[16];
  double *leaf = f->val + i * nc;
  int any = 0;
  for (size_t c = 0; c < nc; c++) {
    d[c] = v[c] - leaf[c];
    leaf[c] = v[c];
    any |= d[c] != 0;
  }
  if (!any) return;
  for (size_t c = 0; c < nc; c++) f->total[c] += d[c];
  if (++f->updates >= f->cap) {
    gs_fenwick_rebuild(f);
    return;
  }
  for (size_t k = i + 1; k <= f->cap; k += k & (~k + 1)) {
    double *node = f->sum + k * nc;
    for (size_t c = 0; c < nc; c++) node[c] += d[c];
  }
}

size_t gs_fenwick_find(const gs_fenwick *f, int col, double u, size_t n) {
  size_t nc = (size_t)f->ncol, pos = 0;
  for (size_t step = f->top; step; step >>= 1) {
    size_t next = pos + step;
    if (next <= f->cap) {
      double s = f->sum[next * nc + (size_t)col];
      if (s <= u) {
        pos = next;
        u -= s;
      }
    }
  }
  /* pos = number of slots whose cumulative sum is <= u; the answer is slot pos */
  if (n == 0) return 0;
  return pos < n ? pos : n - 1;
}
