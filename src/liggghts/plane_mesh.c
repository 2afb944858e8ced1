/* A plane wall as the STL mesh the LIGGGHTS deck reads: the polygon in which
 * the plane cuts the simulation box, as a fan of triangles.  A mesh rather
 * than LIGGGHTS' `primitive` plane, because `compute wall/gran/local` reports
 * mesh contacts only and the impact tables need them; the polygon is exact
 * (coplanar triangles: a sphere's foot point lies in one of them, so it gets
 * one contact, as from the embedded engine's plane), and no particle centre
 * leaves the box, so nothing outside the polygon is missed for planes normal
 * to an axis (an oblique plane's polygon is cut a largest radius wider). */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "liggghts/lig_internal.h"

typedef struct {
  double x[3];
  double ang;
} corner;

static int by_angle(const void *a, const void *b) {
  double u = ((const corner *)a)->ang, v = ((const corner *)b)->ang;
  return (u > v) - (u < v);
}

/* The corners of the polygon in which the plane (p, unit n) cuts the box
 * [lo, hi]: the crossings of its twelve edges, ordered round their centre. */
static size_t cut_box(const double lo[3], const double hi[3], const double p[3], const double n[3], corner *out) {
  size_t m = 0;
  for (int ax = 0; ax < 3; ax++) { /* edges along axis ax: four, one per corner of the other two */
    int b1 = (ax + 1) % 3, b2 = (ax + 2) % 3;
    for (int q = 0; q < 4; q++) {
      double a[3], e[3];
      a[ax] = lo[ax], e[ax] = hi[ax];
      a[b1] = e[b1] = q & 1 ? hi[b1] : lo[b1];
      a[b2] = e[b2] = q & 2 ? hi[b2] : lo[b2];
      double da = 0, de = 0;
      for (int k = 0; k < 3; k++) da += (a[k] - p[k]) * n[k], de += (e[k] - p[k]) * n[k];
      if ((da > 0 && de > 0) || (da < 0 && de < 0) || da == de) continue;
      double t = da / (da - de);
      double x[3];
      for (int k = 0; k < 3; k++) x[k] = a[k] + t * (e[k] - a[k]);
      int dup = 0; /* a crossing at a box corner belongs to three edges */
      for (size_t j = 0; j < m && !dup; j++)
        dup = fabs(out[j].x[0] - x[0]) + fabs(out[j].x[1] - x[1]) + fabs(out[j].x[2] - x[2]) <=
              1e-12 * (fabs(hi[0] - lo[0]) + fabs(hi[1] - lo[1]) + fabs(hi[2] - lo[2]));
      if (!dup && m < 12) memcpy(out[m++].x, x, sizeof x);
    }
  }
  if (m < 3) return m;
  double c[3] = {0, 0, 0};
  for (size_t j = 0; j < m; j++)
    for (int k = 0; k < 3; k++) c[k] += out[j].x[k] / (double)m;
  /* two directions in the plane */
  double u[3], v[3], t[3] = {fabs(n[0]) < 0.9 ? 1.0 : 0.0, fabs(n[0]) < 0.9 ? 0.0 : 1.0, 0};
  double tn = t[0] * n[0] + t[1] * n[1] + t[2] * n[2], ul;
  for (int k = 0; k < 3; k++) u[k] = t[k] - tn * n[k];
  ul = sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
  for (int k = 0; k < 3; k++) u[k] /= ul;
  v[0] = n[1] * u[2] - n[2] * u[1], v[1] = n[2] * u[0] - n[0] * u[2], v[2] = n[0] * u[1] - n[1] * u[0];
  for (size_t j = 0; j < m; j++) {
    double d[3] = {out[j].x[0] - c[0], out[j].x[1] - c[1], out[j].x[2] - c[2]};
    out[j].ang = atan2(d[0] * v[0] + d[1] * v[1] + d[2] * v[2], d[0] * u[0] + d[1] * u[1] + d[2] * u[2]);
  }
  qsort(out, m, sizeof *out, by_angle);
  return m;
}

int gs_lig_write_plane_mesh(const gs_dem_case *c, size_t w, const char *path, gs_error *err) {
  const gs_dem_wall_src *s = &c->wall_src[w];
  double lo[3], hi[3], rmax = 0;
  for (size_t i = 0; i < c->nclass; i++) rmax = fmax(rmax, c->cls[i].rmax);
  int oblique = 1;
  for (int k = 0; k < 3; k++) oblique &= fabs(fabs(s->normal[k]) - 1) > 1e-12;
  for (int k = 0; k < 3; k++) {
    double m = oblique ? rmax : 0;
    lo[k] = c->prm.lo[k] - m, hi[k] = c->prm.hi[k] + m;
  }
  corner cn[12];
  size_t m = cut_box(lo, hi, s->point, s->normal, cn);
  if (m < 3)
    return gs_error_set(err, GS_EINPUT, "walls[%zu] (%s).plane: the plane does not cut the box dem.box, so no "
                        "particle can touch it; move it into the box or leave it out", w, s->name);
  FILE *fp = fopen(path, "w");
  if (!fp) return gs_error_set(err, GS_EIO, "%s: cannot write: %s", path, strerror(errno));
  fprintf(fp, "solid plane_%s\n", s->name);
  for (size_t j = 1; j + 1 < m; j++) {
    const double *a = cn[0].x, *b = cn[j].x, *d = cn[j + 1].x;
    fprintf(fp, " facet normal %.17g %.17g %.17g\n  outer loop\n", s->normal[0], s->normal[1], s->normal[2]);
    fprintf(fp, "   vertex %.17g %.17g %.17g\n   vertex %.17g %.17g %.17g\n   vertex %.17g %.17g %.17g\n", a[0], a[1],
            a[2], b[0], b[1], b[2], d[0], d[1], d[2]);
    fprintf(fp, "  endloop\n endfacet\n");
  }
  fprintf(fp, "endsolid plane_%s\n", s->name);
  int bad = ferror(fp);
  if (fclose(fp) || bad) return gs_error_set(err, GS_EIO, "%s: write failed", path);
  return GS_OK;
}
