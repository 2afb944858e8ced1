/* Generated walls (dem_generate.h): the registry, the surface of revolution
 * both generators are made of, the checks every generated mesh passes before
 * the engine sees it (closed, outward, no degenerate facet: the ones a user's
 * STL gets from mesh_stl.c and mesh_closed.c), and the STL writer. */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "dem/dem_generate.h"
#include "dem/dem_internal.h"

const gs_dem_generator *const gs_dem_generators[] = {&gs_dem_gen_bowl, &gs_dem_gen_impeller, NULL};

void gs_dem_list_generators(FILE *fp) {
  for (const gs_dem_generator *const *g = gs_dem_generators; *g; g++) fprintf(fp, "  %-16s %s\n", (*g)->name, (*g)->summary);
}

int gs_dem_tris_add(gs_dem_tris *t, const double a[3], const double b[3], const double c[3], gs_error *err) {
  if (t->ntri == t->cap) {
    size_t nc = t->cap ? 2 * t->cap : 256;
    double *nv = realloc(t->v, nc * 9 * sizeof(double));
    if (!nv) return gs_error_set(err, GS_ENOMEM, "out of memory generating a mesh");
    t->v = nv;
    t->cap = nc;
  }
  double *v = t->v + 9 * t->ntri++;
  memcpy(v, a, 3 * sizeof(double));
  memcpy(v + 3, b, 3 * sizeof(double));
  memcpy(v + 6, c, 3 * sizeof(double));
  return GS_OK;
}

void gs_dem_tris_free(gs_dem_tris *t) {
  free(t->v);
  memset(t, 0, sizeof *t);
}

int gs_dem_tris_revolve(gs_dem_tris *t, const double *r, const double *z, size_t np, int nseg,
                        const double origin[3], gs_error *err) {
  /* one table of angles, the last equal to the first, so that the seam's
   * vertices are the same numbers on both sides */
  double *cs = malloc(2 * ((size_t)nseg + 1) * sizeof(double));
  if (!cs) return gs_error_set(err, GS_ENOMEM, "out of memory generating a mesh");
  for (int k = 0; k < nseg; k++) {
    cs[2 * k] = cos(2 * M_PI * k / nseg);
    cs[2 * k + 1] = sin(2 * M_PI * k / nseg);
  }
  cs[2 * nseg] = cs[0];
  cs[2 * nseg + 1] = cs[1];
  int rc = GS_OK;
  for (size_t i = 0; i + 1 < np && !rc; i++) {
    if (r[i] == 0 && r[i + 1] == 0) continue; /* along the axis: no surface */
    for (int k = 0; k < nseg && !rc; k++) {
      const double *c0 = cs + 2 * k, *c1 = cs + 2 * (k + 1);
      double a0[3] = {origin[0] + r[i] * c0[0], origin[1] + r[i] * c0[1], origin[2] + z[i]};
      double a1[3] = {origin[0] + r[i] * c1[0], origin[1] + r[i] * c1[1], origin[2] + z[i]};
      double b0[3] = {origin[0] + r[i + 1] * c0[0], origin[1] + r[i + 1] * c0[1], origin[2] + z[i + 1]};
      double b1[3] = {origin[0] + r[i + 1] * c1[0], origin[1] + r[i + 1] * c1[1], origin[2] + z[i + 1]};
      /* along the profile (a -> b) then around (0 -> 1): for a profile
       * running counter-clockwise the normal (b - a) x (a1 - a0) points out */
      if (r[i] == 0) rc = gs_dem_tris_add(t, a0, b1, b0, err);
      else if (r[i + 1] == 0) rc = gs_dem_tris_add(t, a0, a1, b0, err);
      else if (!(rc = gs_dem_tris_add(t, a0, b1, b0, err))) rc = gs_dem_tris_add(t, a0, a1, b1, err);
    }
  }
  free(cs);
  return rc;
}

void gs_dem_tris_measure(const double *v, size_t ntri, double *volume, double *area) {
  double vol = 0, ar = 0;
  for (size_t t = 0; t < ntri; t++) {
    const double *a = v + 9 * t, *b = a + 3, *c = a + 6;
    double e1[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, e2[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    double x[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
    ar += 0.5 * sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]);
    /* divergence theorem: each facet's tetrahedron with the origin */
    vol += (a[0] * (b[1] * c[2] - b[2] * c[1]) + a[1] * (b[2] * c[0] - b[0] * c[2]) +
            a[2] * (b[0] * c[1] - b[1] * c[0])) / 6;
  }
  if (volume) *volume = vol;
  if (area) *area = ar;
}

int gs_dem_generate(gs_cfg_node *n, gs_dem_tris *out, gs_dem_gen_motion *motion, gs_error *err) {
  const gs_dem_generator *g = gs_registry_pick(n, (const void *const *)gs_dem_generators, "generated wall", err);
  if (!g) return err->code;
  memset(motion, 0, sizeof *motion);
  int rc = g->build(n, out, motion, err);
  if (!rc) rc = gs_cfg_check_unused(n, err);
  if (rc) return rc;
  /* the checks a user's mesh gets: a failure here is a bug of the generator
   * or keys it should have refused, so it says which */
  gs_error merr = {0};
  gs_dem_mesh *m = gs_dem_mesh_from_triangles(out->v, out->ntri, &merr);
  if (!m) return gs_cfg_fail(n, err, "the generated %s mesh is invalid: %s", g->name, merr.msg);
  size_t nopen = 0, tri = 0;
  int k = 0;
  rc = gs_dem_mesh_open_edges(m, &nopen, &tri, &k, err);
  gs_dem_mesh_free(m);
  if (rc) return rc;
  if (nopen)
    return gs_cfg_fail(n, err, "the generated %s mesh is not closed (%zu edges of one facet, the first of facet %zu)",
                       g->name, nopen, tri + 1);
  double vol;
  gs_dem_tris_measure(out->v, out->ntri, &vol, NULL);
  if (!(vol > 0))
    return gs_cfg_fail(n, err, "the generated %s mesh encloses a volume of %g m^3; expected > 0 (normals outward)",
                       g->name, vol);
  return GS_OK;
}

int gs_dem_write_stl(const char *path, const char *name, const double *v, size_t ntri, gs_error *err) {
  FILE *fp = fopen(path, "w");
  if (!fp) return gs_error_set(err, GS_EIO, "%s: cannot write: %s", path, strerror(errno));
  fprintf(fp, "solid %s\n", name);
  for (size_t t = 0; t < ntri; t++) {
    const double *a = v + 9 * t;
    double e1[3] = {a[3] - a[0], a[4] - a[1], a[5] - a[2]}, e2[3] = {a[6] - a[0], a[7] - a[1], a[8] - a[2]};
    double x[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
    double l = sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]);
    /* 17 significant digits: the file holds the same doubles the embedded
     * engine used, so both engines see one geometry */
    fprintf(fp, "  facet normal %.9g %.9g %.9g\n    outer loop\n", x[0] / l, x[1] / l, x[2] / l);
    for (int k = 0; k < 3; k++)
      fprintf(fp, "      vertex %.17g %.17g %.17g\n", a[3 * k], a[3 * k + 1], a[3 * k + 2]);
    fprintf(fp, "    endloop\n  endfacet\n");
  }
  fprintf(fp, "endsolid %s\n", name);
  if (ferror(fp) | fclose(fp)) return gs_error_set(err, GS_EIO, "%s: write failed", path);
  return GS_OK;
}
