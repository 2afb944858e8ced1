/* Mesh preprocessing: welding vertices (so triangles know which edges and
 * vertices they share) and binning triangles on a grid in the mesh's body
 * frame.  A cell lists every triangle that comes within `reach` of some point
 * of the cell, so a sphere of radius <= reach needs only the cell of its
 * centre. */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "dem/dem_internal.h"

/* A corner of a triangle, with the cell of a grid of spacing tol that holds it. */
typedef struct {
  int64_t q[3];
  int i; /* index of the corner in the mesh (3 t + k) */
} corner;

static int cmp_cell(const int64_t *a, const int64_t *b) {
  for (int k = 0; k < 3; k++)
    if (a[k] != b[k]) return a[k] < b[k] ? -1 : 1;
  return 0;
}

static int by_cell(const void *a, const void *b) {
  const corner *p = a, *q = b;
  int c = cmp_cell(p->q, q->q);
  return c ? c : (p->i > q->i) - (p->i < q->i);
}

/* First corner of the sorted array whose cell is not below q. */
static size_t first_in(const corner *cs, size_t n, const int64_t *q) {
  size_t lo = 0, hi = n;
  while (lo < hi) {
    size_t mid = lo + (hi - lo) / 2;
    if (cmp_cell(cs[mid].q, q) < 0) lo = mid + 1;
    else hi = mid;
  }
  return lo;
}

static int root(int *parent, int k) {
  while (parent[k] != k) k = parent[k] = parent[parent[k]];
  return k;
}

/* Corners closer than 1e-8 of the mesh's size (on every axis) get one id:
 * STL stores each corner once per facet, and CAD exports write the same
 * vertex with round-off differences (the CoriMix impeller has corners
 * 1e-14 mm apart), which exact comparison took for different vertices, so
 * the edge between them looked like two edges (two contacts instead of one).
 * The same tolerance as LIGGGHTS' `precision`, relative.  Corners are
 * sorted by cells of that size, so a corner's partners are in its own cell
 * or the 26 around it: n log n whatever the shape (a flat mesh puts every
 * corner at one x). */
void gs_dem_mesh_weld(gs_dem_mesh *m) {
  size_t nc = 3 * m->ntri;
  corner *cs = malloc((nc ? nc : 1) * sizeof *cs);
  int *parent = malloc((nc ? nc : 1) * sizeof *parent);
  if (!cs || !parent) {
    free(cs);
    free(parent);
    for (size_t k = 0; k < nc; k++) m->vid[k] = (int)k; /* no welding: still correct, less dedup */
    m->nvert = nc;
    return;
  }
  double lo[3], hi[3], diag2 = 0;
  gs_dem_mesh_bounds(m, lo, hi);
  for (int a = 0; a < 3; a++) diag2 += (hi[a] - lo[a]) * (hi[a] - lo[a]);
  const double tol = 1e-8 * sqrt(diag2), h = tol > 0 ? tol : 1.0;
  for (size_t k = 0; k < nc; k++) {
    for (int a = 0; a < 3; a++) cs[k].q[a] = (int64_t)floor((m->v[3 * k + (size_t)a] - lo[a]) / h);
    cs[k].i = (int)k;
    parent[k] = (int)k;
  }
  qsort(cs, nc, sizeof *cs, by_cell);
  for (size_t k = 0; k < nc; k++) {
    const double *p = m->v + 3 * (size_t)cs[k].i;
    for (int d = 0; d < 27; d++) {
      int64_t q[3] = {cs[k].q[0] + d % 3 - 1, cs[k].q[1] + d / 3 % 3 - 1, cs[k].q[2] + d / 9 - 1};
      for (size_t j = first_in(cs, nc, q); j < nc && !cmp_cell(cs[j].q, q); j++) {
        const double *o = m->v + 3 * (size_t)cs[j].i;
        if (fabs(p[0] - o[0]) > tol || fabs(p[1] - o[1]) > tol || fabs(p[2] - o[2]) > tol) continue;
        int a = root(parent, cs[k].i), b = root(parent, cs[j].i);
        if (a != b) parent[a < b ? b : a] = a < b ? a : b;
      }
    }
  }
  free(cs);
  /* ids in order of first appearance in the file: m->vid holds, for now,
   * the id given to each root corner */
  for (size_t k = 0; k < nc; k++) m->vid[k] = -1;
  int next = 0;
  for (size_t k = 0; k < nc; k++) {
    int r = root(parent, (int)k);
    if (m->vid[r] < 0) m->vid[r] = next++;
    m->vid[k] = m->vid[r];
  }
  m->nvert = (size_t)next;
  free(parent);
}

int gs_dem_mesh_build_bins(gs_dem_mesh *m, double reach, gs_error *err) {
  double lo[3], hi[3];
  gs_dem_mesh_bounds(m, lo, hi);
  double ext = 0;
  for (int a = 0; a < 3; a++) {
    lo[a] -= reach;
    hi[a] += reach;
    if (hi[a] - lo[a] > ext) ext = hi[a] - lo[a];
  }
  /* cells about two radii wide keep the triangle lists short (the contact
   * search walks the list of one cell per particle every step); cap the grid */
  double h = fmax(2 * reach, ext / 1000);
  while (((hi[0] - lo[0]) / h + 1) * ((hi[1] - lo[1]) / h + 1) * ((hi[2] - lo[2]) / h + 1) > 1.6e7)
    h *= 1.25;
  m->bh = h;
  size_t ncell = 1;
  for (int a = 0; a < 3; a++) {
    m->blo[a] = lo[a];
    m->bdim[a] = (int)((hi[a] - lo[a]) / h) + 1;
    ncell *= (size_t)m->bdim[a];
  }
  free(m->bfirst);
  free(m->btri);
  m->btri = NULL;
  m->bfirst = calloc(ncell + 1, sizeof(int));
  if (!m->bfirst) return gs_error_set(err, GS_ENOMEM, "out of memory binning a mesh");
  const double half_diag = 0.5 * sqrt(3.0) * h;
  /* two passes: count, then fill */
  for (int pass = 0; pass < 2; pass++) {
    int *fill = NULL;
    if (pass == 1) {
      for (size_t c = 0; c < ncell; c++) m->bfirst[c + 1] += m->bfirst[c];
      m->btri = malloc(((size_t)m->bfirst[ncell] + 1) * sizeof(int));
      fill = malloc((ncell + 1) * sizeof(int));
      if (!m->btri || !fill) {
        free(fill);
        return gs_error_set(err, GS_ENOMEM, "out of memory binning a mesh");
      }
      memcpy(fill, m->bfirst, (ncell + 1) * sizeof(int));
    }
    for (size_t t = 0; t < m->ntri; t++) {
      const double *v = m->v + 9 * t, *nr = m->nrm + 3 * t;
      int c0[3], c1[3];
      for (int a = 0; a < 3; a++) {
        double mn = fmin(v[a], fmin(v[3 + a], v[6 + a])) - reach;
        double mx = fmax(v[a], fmax(v[3 + a], v[6 + a])) + reach;
        c0[a] = (int)floor((mn - m->blo[a]) / h);
        c1[a] = (int)floor((mx - m->blo[a]) / h);
        if (c0[a] < 0) c0[a] = 0;
        if (c1[a] >= m->bdim[a]) c1[a] = m->bdim[a] - 1;
      }
      for (int iz = c0[2]; iz <= c1[2]; iz++)
        for (int iy = c0[1]; iy <= c1[1]; iy++)
          for (int ix = c0[0]; ix <= c1[0]; ix++) {
            double cc[3] = {m->blo[0] + (ix + 0.5) * h, m->blo[1] + (iy + 0.5) * h,
                            m->blo[2] + (iz + 0.5) * h};
            double s = (cc[0] - v[0]) * nr[0] + (cc[1] - v[1]) * nr[1] + (cc[2] - v[2]) * nr[2];
            if (fabs(s) > half_diag + reach) continue;
            /* exact bound: some point of the cell is within reach of the triangle
             * only if the cell centre is within reach + half diagonal of it */
            double q[3];
            gs_dem_closest_on_triangle(cc, v, v + 3, v + 6, q);
            double e0 = cc[0] - q[0], e1 = cc[1] - q[1], e2 = cc[2] - q[2];
            if (e0 * e0 + e1 * e1 + e2 * e2 > (half_diag + reach) * (half_diag + reach)) continue;
            size_t cell = ((size_t)iz * m->bdim[1] + iy) * m->bdim[0] + ix;
            if (pass == 0) m->bfirst[cell + 1]++;
            else m->btri[fill[cell]++] = (int)t;
          }
    }
    free(fill);
  }
  /* Most particles sit in cells without triangles; testing a bit first keeps
   * the big CSR array out of the cache for them. */
  free(m->bmask);
  m->bmask = calloc(ncell / 64 + 1, sizeof(uint64_t));
  if (!m->bmask) return gs_error_set(err, GS_ENOMEM, "out of memory binning a mesh");
  for (size_t c = 0; c < ncell; c++)
    if (m->bfirst[c + 1] > m->bfirst[c]) m->bmask[c / 64] |= 1ull << (c % 64);
  m->bin_reach = reach;
  return GS_OK;
}
