/* Which edges and corners of a mesh may carry a contact in the
 * LIGGGHTS-compatible contact mode (`dem.mesh_contacts: liggghts`).
 *
 * gransim's own rule (wall_forces.c) keeps the closest feature and drops
 * edge and corner contacts that touch a contact already kept: one contact
 * per touching region.  LIGGGHTS 3.8 instead asks every triangle for a
 * contact on its own and gives each shared edge and corner to one triangle
 * (SurfaceMesh::handleSharedEdge / handleCorner):
 *  - an edge shared by two triangles that are coplanar (|n_i . n_j| >
 *    1 - 1e-5, its default curvature) is inactive on both, unless they fold
 *    back over each other; otherwise it is active only on the triangle that
 *    comes later in the file.  Pairs are taken in file order and a later
 *    pair overrides an earlier one (edges with more than two triangles);
 *  - a corner is inactive on every triangle when none of the edges that meet
 *    there is active or when two of them are colinear (a vertex inside a
 *    straight line of edges); otherwise it is active only on the last
 *    triangle in the file that has it;
 *  - edges and corners that no other triangle shares stay active.
 * A face contact is always taken, so a sphere on a face near a sharp edge
 * also gets the neighbour's edge contact: the two overlaps add up (at a
 * 90-degree blade edge the force doubles).  The mode exists to compare with
 * LIGGGHTS on the same meshes, as `dem.damping: liggghts` does for damping. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "dem/dem_internal.h"

#define COPLANAR_COS (1.0 - 1e-5)
#define COLINEAR_COS (1.0 - 1e-6)

typedef struct {
  int a, b; /* welded vertex ids, a < b */
  int tri, k; /* triangle and its edge k (vertex k -> k + 1) */
} edge_ref;

static int by_edge(const void *x, const void *y) {
  const edge_ref *p = x, *q = y;
  if (p->a != q->a) return p->a < q->a ? -1 : 1;
  if (p->b != q->b) return p->b < q->b ? -1 : 1;
  return (p->tri > q->tri) - (p->tri < q->tri);
}

static const double *vert(const gs_dem_mesh *m, int t, int k) { return m->v + 9 * (size_t)t + 3 * (size_t)k; }

/* Coplanar triangles t and u folded back over their shared edge (both third
 * vertices on the same side of it): LIGGGHTS treats them as not coplanar. */
static int fold_back(const gs_dem_mesh *m, int t, int kt, int u, int ku) {
  const double *a = vert(m, t, kt), *b = vert(m, t, (kt + 1) % 3);
  const double *ct = vert(m, t, (kt + 2) % 3), *cu = vert(m, u, (ku + 2) % 3);
  const double *n = m->nrm + 3 * (size_t)t;
  double e[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
  double side[2];
  for (int s = 0; s < 2; s++) {
    const double *c = s ? cu : ct;
    double w[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    double x[3] = {e[1] * w[2] - e[2] * w[1], e[2] * w[0] - e[0] * w[2], e[0] * w[1] - e[1] * w[0]};
    side[s] = x[0] * n[0] + x[1] * n[1] + x[2] * n[2];
  }
  return side[0] * side[1] > 0;
}

static void edges_activity(const gs_dem_mesh *m, uint8_t *act, edge_ref *e) {
  const size_t ne = 3 * m->ntri;
  for (size_t t = 0; t < m->ntri; t++)
    for (int k = 0; k < 3; k++) {
      int a = m->vid[3 * t + (size_t)k], b = m->vid[3 * t + (size_t)(k + 1) % 3];
      edge_ref *r = &e[3 * t + (size_t)k];
      r->a = a < b ? a : b;
      r->b = a < b ? b : a;
      r->tri = (int)t;
      r->k = k;
    }
  qsort(e, ne, sizeof *e, by_edge);
  for (size_t i = 0; i < ne;) {
    size_t j = i;
    while (j < ne && e[j].a == e[i].a && e[j].b == e[i].b) j++;
    for (size_t p = i; p < j; p++) /* pairs in file order; later ones override */
      for (size_t q = p + 1; q < j; q++) {
        const edge_ref *x = &e[p], *y = &e[q]; /* x->tri < y->tri */
        const double *nx = m->nrm + 3 * (size_t)x->tri, *ny = m->nrm + 3 * (size_t)y->tri;
        double c = fabs(nx[0] * ny[0] + nx[1] * ny[1] + nx[2] * ny[2]);
        int coplanar = c > COPLANAR_COS && !fold_back(m, x->tri, x->k, y->tri, y->k);
        uint8_t bx = (uint8_t)(1u << x->k), by = (uint8_t)(1u << y->k);
        act[x->tri] &= (uint8_t)~bx;
        if (coplanar) act[y->tri] &= (uint8_t)~by;
        else act[y->tri] |= by;
      }
    i = j;
  }
}

static void unit_edge(const double *from, const double *to, double u[3]) {
  double d[3] = {to[0] - from[0], to[1] - from[1], to[2] - from[2]};
  double l = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
  for (int q = 0; q < 3; q++) u[q] = l > 0 ? d[q] / l : 0;
}

/* Corners: triangles grouped by welded vertex (CSR), then LIGGGHTS' rule. */
static int corners_activity(const gs_dem_mesh *m, uint8_t *act, gs_error *err) {
  int *first = calloc(m->nvert + 1, sizeof(int)), *list = malloc(3 * m->ntri * sizeof(int));
  if (!first || !list) {
    free(first);
    free(list);
    return gs_error_set(err, GS_ENOMEM, "out of memory for the mesh topology");
  }
  for (size_t i = 0; i < 3 * m->ntri; i++) first[m->vid[i] + 1]++;
  for (size_t v = 0; v < m->nvert; v++) first[v + 1] += first[v];
  int *fill = malloc((m->nvert + 1) * sizeof(int));
  if (!fill) {
    free(first);
    free(list);
    return gs_error_set(err, GS_ENOMEM, "out of memory for the mesh topology");
  }
  memcpy(fill, first, (m->nvert + 1) * sizeof(int));
  for (size_t i = 0; i < 3 * m->ntri; i++) list[fill[m->vid[i]]++] = (int)i; /* 3 t + k, t ascending */
  free(fill);
  for (size_t v = 0; v < m->nvert; v++) {
    int n = first[v + 1] - first[v];
    if (!n) continue;
    int any_active = 0, colinear = 0, last = -1;
    for (int p = first[v]; p < first[v + 1]; p++) {
      int t = list[p] / 3, k = list[p] % 3, km = (k + 2) % 3; /* edges k and k - 1 meet at k */
      if (act[t] & (1u << k) || act[t] & (1u << km)) any_active = 1;
      if (t > last) last = t;
    }
    for (int p = first[v]; p < first[v + 1] && !colinear; p++)
      for (int q = p; q < first[v + 1] && !colinear; q++) {
        int tp = list[p] / 3, kp = list[p] % 3, tq = list[q] / 3, kq = list[q] % 3;
        const int ends_p[2] = {(kp + 1) % 3, (kp + 2) % 3}, ends_q[2] = {(kq + 1) % 3, (kq + 2) % 3};
        for (int i = 0; i < 2 && !colinear; i++)
          for (int j = (p == q ? i + 1 : 0); j < 2 && !colinear; j++) {
            int vp = m->vid[3 * (size_t)tp + (size_t)ends_p[i]], vq = m->vid[3 * (size_t)tq + (size_t)ends_q[j]];
            if (vp == vq) continue; /* the same edge seen from two triangles */
            double up[3], uq[3];
            unit_edge(vert(m, tp, kp), vert(m, tp, ends_p[i]), up);
            unit_edge(vert(m, tq, kq), vert(m, tq, ends_q[j]), uq);
            if (fabs(up[0] * uq[0] + up[1] * uq[1] + up[2] * uq[2]) > COLINEAR_COS) colinear = 1;
          }
      }
    for (int p = first[v]; p < first[v + 1]; p++) {
      int t = list[p] / 3, k = list[p] % 3;
      uint8_t bit = (uint8_t)(8u << k);
      if (!colinear && any_active && t == last) act[t] |= bit;
      else act[t] &= (uint8_t)~bit;
    }
  }
  free(first);
  free(list);
  return GS_OK;
}

int gs_dem_mesh_liggghts_activity(gs_dem_mesh *m, gs_error *err) {
  if (m->active) return GS_OK;
  m->active = malloc(m->ntri ? m->ntri : 1);
  edge_ref *e = malloc((m->ntri ? 3 * m->ntri : 1) * sizeof *e);
  if (!m->active || !e) {
    free(e);
    return gs_error_set(err, GS_ENOMEM, "out of memory for the mesh topology");
  }
  memset(m->active, 0x3f, m->ntri); /* bits 0-2 edges, 3-5 corners: all active */
  edges_activity(m, m->active, e);
  free(e);
  return corners_activity(m, m->active, err);
}
