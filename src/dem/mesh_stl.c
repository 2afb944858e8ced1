/* STL reader (ASCII and binary) into a gs_dem_mesh.
 *
 * Binary and ASCII are told apart by size, not by the leading "solid": many
 * exporters write "solid" at the start of binary files too.  A file is binary
 * when its length is exactly 84 + 50 * (triangle count in bytes 80..83).
 * Facet normals in the file are ignored and recomputed from the vertex order,
 * since exporters disagree on them.  A facet with a non-finite vertex or no
 * area (three vertices on a line) is refused, naming it: dropped silently, it
 * would leave a hole that particles escape through (docs/reliability.md). */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "dem/dem_internal.h"

static int finish(gs_dem_mesh *m, const char *path, gs_error *err) {
  m->nrm = malloc((m->ntri ? m->ntri : 1) * 3 * sizeof(double));
  m->vid = malloc((m->ntri ? m->ntri : 1) * 3 * sizeof(int));
  if (!m->nrm || !m->vid) return gs_error_set(err, GS_ENOMEM, "%s: out of memory", path);
  if (!m->ntri) return gs_error_set(err, GS_EINPUT, "%s: no triangles", path);
  for (size_t t = 0; t < m->ntri; t++) {
    const double *v = m->v + 9 * t;
    for (int k = 0; k < 9; k++)
      if (!isfinite(v[k]))
        return gs_error_set(err, GS_EINPUT, "%s: facet %zu (of %zu, counted from 1): vertex %d has a non-finite "
                            "coordinate (%g, %g, %g)", path, t + 1, m->ntri, k / 3 + 1, v[k / 3 * 3],
                            v[k / 3 * 3 + 1], v[k / 3 * 3 + 2]);
    double e1[3] = {v[3] - v[0], v[4] - v[1], v[5] - v[2]};
    double e2[3] = {v[6] - v[0], v[7] - v[1], v[8] - v[2]};
    double c[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                   e1[0] * e2[1] - e1[1] * e2[0]};
    double l = sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
    if (!(l > 0) || !isfinite(l))
      return gs_error_set(err, GS_EINPUT, "%s: facet %zu (of %zu, counted from 1) is degenerate (area %g): vertices "
                          "(%g, %g, %g), (%g, %g, %g), (%g, %g, %g) lie on a line; remove it or repair the mesh",
                          path, t + 1, m->ntri, 0.5 * l, v[0], v[1], v[2], v[3], v[4], v[5], v[6], v[7], v[8]);
    for (int k = 0; k < 3; k++) m->nrm[3 * t + k] = c[k] / l;
  }
  gs_dem_mesh_weld(m);
  return GS_OK;
}

static int push_tri(gs_dem_mesh *m, size_t *cap, const double t[9], gs_error *err) {
  if (m->ntri == *cap) {
    size_t nc = *cap ? 2 * *cap : 256;
    double *nv = realloc(m->v, nc * 9 * sizeof(double));
    if (!nv) return gs_error_set(err, GS_ENOMEM, "out of memory reading a mesh");
    m->v = nv;
    *cap = nc;
  }
  memcpy(m->v + 9 * m->ntri++, t, 9 * sizeof(double));
  return GS_OK;
}

static int read_binary(FILE *fp, gs_dem_mesh *m, uint32_t ntri, double scale, const char *path,
                       gs_error *err) {
  m->v = malloc((ntri ? ntri : 1) * 9 * sizeof(double));
  if (!m->v) return gs_error_set(err, GS_ENOMEM, "%s: out of memory", path);
  if (fseek(fp, 84, SEEK_SET)) return gs_error_set(err, GS_EIO, "%s: cannot seek", path);
  unsigned char rec[50];
  for (uint32_t t = 0; t < ntri; t++) {
    if (fread(rec, 1, 50, fp) != 50)
      return gs_error_set(err, GS_EINPUT, "%s: binary STL truncated at triangle %u", path, t);
    for (int k = 0; k < 9; k++) {
      float f;
      memcpy(&f, rec + 12 + 4 * k, 4); /* little-endian floats, as the format says */
      m->v[9 * (size_t)t + k] = (double)f * scale;
    }
  }
  m->ntri = ntri;
  return GS_OK;
}

static int read_ascii(FILE *fp, gs_dem_mesh *m, double scale, const char *path, gs_error *err) {
  char line[1024];
  int lineno = 0, nv = 0;
  size_t cap = 0;
  double tri[9];
  rewind(fp);
  while (fgets(line, sizeof line, fp)) {
    lineno++;
    char *s = line + strspn(line, " \t");
    if (strncmp(s, "vertex", 6)) {
      if (!strncmp(s, "endloop", 7) && nv != 3)
        return gs_error_set(err, GS_EINPUT, "%s:%d: facet with %d vertices, expected 3", path,
                            lineno, nv);
      if (!strncmp(s, "outer", 5)) nv = 0;
      continue;
    }
    double a, b, c;
    char *e1, *e2, *e3;
    errno = 0;
    a = strtod(s + 6, &e1);
    b = strtod(e1, &e2);
    c = strtod(e2, &e3);
    if (e1 == s + 6 || e2 == e1 || e3 == e2 || errno || nv >= 3)
      return gs_error_set(err, GS_EINPUT, "%s:%d: malformed vertex line '%.60s'", path, lineno, s);
    tri[3 * nv] = a * scale;
    tri[3 * nv + 1] = b * scale;
    tri[3 * nv + 2] = c * scale;
    if (++nv == 3) {
      int rc = push_tri(m, &cap, tri, err);
      if (rc) return rc;
    }
  }
  return GS_OK;
}

gs_dem_mesh *gs_dem_mesh_read_stl(const char *path, double scale, gs_error *err) {
  if (!(scale > 0)) {
    gs_error_set(err, GS_EINPUT, "%s: mesh scale must be > 0 (got %g)", path, scale);
    return NULL;
  }
  FILE *fp = fopen(path, "rb");
  if (!fp) {
    gs_error_set(err, GS_EIO, "%s: cannot open STL file: %s", path, strerror(errno));
    return NULL;
  }
  gs_dem_mesh *m = calloc(1, sizeof *m);
  if (!m) {
    fclose(fp);
    gs_error_set(err, GS_ENOMEM, "out of memory");
    return NULL;
  }
  unsigned char head[84];
  size_t got = fread(head, 1, 84, fp);
  long size = -1;
  if (!fseek(fp, 0, SEEK_END)) size = ftell(fp);
  int rc;
  uint32_t nb = 0;
  if (got == 84) memcpy(&nb, head + 80, 4);
  if (got == 84 && size == 84 + 50 * (long)nb) rc = read_binary(fp, m, nb, scale, path, err);
  else if (got >= 5 && !memcmp(head, "solid", 5)) rc = read_ascii(fp, m, scale, path, err);
  else rc = gs_error_set(err, GS_EINPUT, "%s: neither ASCII STL (starts with 'solid') nor binary STL "
                         "(84 + 50 n bytes)", path);
  fclose(fp);
  if (!rc) rc = finish(m, path, err);
  if (rc) {
    gs_dem_mesh_free(m);
    return NULL;
  }
  return m;
}

gs_dem_mesh *gs_dem_mesh_from_triangles(const double *xyz, size_t ntri, gs_error *err) {
  gs_dem_mesh *m = calloc(1, sizeof *m);
  if (m) m->v = malloc((ntri ? ntri : 1) * 9 * sizeof(double));
  if (!m || !m->v) {
    gs_dem_mesh_free(m);
    gs_error_set(err, GS_ENOMEM, "out of memory");
    return NULL;
  }
  memcpy(m->v, xyz, ntri * 9 * sizeof(double));
  m->ntri = ntri;
  if (finish(m, "mesh", err)) {
    gs_dem_mesh_free(m);
    return NULL;
  }
  return m;
}

size_t gs_dem_mesh_ntri(const gs_dem_mesh *m) { return m->ntri; }

void gs_dem_mesh_bounds(const gs_dem_mesh *m, double lo[3], double hi[3]) {
  for (int a = 0; a < 3; a++) {
    lo[a] = HUGE_VAL;
    hi[a] = -HUGE_VAL;
  }
  for (size_t k = 0; k < 3 * m->ntri; k++)
    for (int a = 0; a < 3; a++) {
      double v = m->v[3 * k + a];
      if (v < lo[a]) lo[a] = v;
      if (v > hi[a]) hi[a] = v;
    }
}

void gs_dem_mesh_free(gs_dem_mesh *m) {
  if (!m) return;
  free(m->v);
  free(m->nrm);
  free(m->vid);
  free(m->active);
  free(m->bfirst);
  free(m->btri);
  free(m->bmask);
  free(m);
}
