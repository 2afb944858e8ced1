/* Whether a mesh is closed: every edge (between welded vertices) shared by
 * exactly two facets.  An edge of one facet only borders a hole; an edge of
 * three or more is a fin or a T-junction, which a closed vessel can have
 * (the CoriMix shell's inner baffles), so only the former counts.  The case
 * reader asks this of walls marked `closed: true` (docs/reliability.md). */
#include <stdlib.h>

#include "dem/dem_internal.h"

typedef struct {
  int a, b; /* welded vertex ids, a < b */
  size_t tri;
  int k;
} edge;

static int by_ends(const void *x, const void *y) {
  const edge *p = x, *q = y;
  if (p->a != q->a) return p->a < q->a ? -1 : 1;
  if (p->b != q->b) return p->b < q->b ? -1 : 1;
  return p->tri < q->tri ? -1 : p->tri > q->tri;
}

int gs_dem_mesh_open_edges(const gs_dem_mesh *m, size_t *nopen, size_t *tri, int *k, gs_error *err) {
  const size_t ne = 3 * m->ntri;
  edge *e = gs_malloc((ne ? ne : 1) * sizeof *e, err);
  if (!e) return GS_ENOMEM;
  for (size_t t = 0; t < m->ntri; t++)
    for (int j = 0; j < 3; j++) {
      int a = m->vid[3 * t + (size_t)j], b = m->vid[3 * t + (size_t)(j + 1) % 3];
      e[3 * t + (size_t)j] = (edge){a < b ? a : b, a < b ? b : a, t, j};
    }
  qsort(e, ne, sizeof *e, by_ends);
  *nopen = 0;
  size_t first_tri = (size_t)-1;
  for (size_t i = 0, j; i < ne; i = j) {
    for (j = i + 1; j < ne && e[j].a == e[i].a && e[j].b == e[i].b;) j++;
    if (j - i == 1 && e[i].a != e[i].b) {
      ++*nopen;
      if (e[i].tri < first_tri) {
        first_tri = e[i].tri;
        *tri = e[i].tri;
        *k = e[i].k;
      }
    }
  }
  free(e);
  return GS_OK;
}
