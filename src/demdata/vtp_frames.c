/* Reader of the embedded DEM's particle frames (vtp_frames.h).  Only the
 * layout src/dem/vtk.c writes is accepted; anything else is refused naming
 * the file and what was expected. */
#include "demdata/vtp_frames.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define VTP_MAX_BYTES (1ull << 34) /* 16 GiB: refuse absurd sizes instead of allocating them */

/* The whole file, NUL-terminated, in *buf (malloc'ed), its size in *n. */
static int slurp(const char *path, char **buf, size_t *n, gs_error *err) {
  FILE *fp = fopen(path, "rb");
  if (!fp) return gs_error_set(err, GS_EIO, "%s: cannot open", path);
  int rc = fseek(fp, 0, SEEK_END);
  long size = rc ? -1 : ftell(fp);
  if (size < 0 || (unsigned long long)size > VTP_MAX_BYTES || fseek(fp, 0, SEEK_SET)) {
    fclose(fp);
    return gs_error_set(err, GS_EIO, "%s: cannot read its size", path);
  }
  *buf = malloc((size_t)size + 1);
  if (!*buf) {
    fclose(fp);
    return gs_error_set(err, GS_ENOMEM, "%s: out of memory for %ld bytes", path, size);
  }
  *n = fread(*buf, 1, (size_t)size, fp);
  (*buf)[*n] = 0;
  fclose(fp);
  if (*n != (size_t)size) {
    free(*buf);
    return gs_error_set(err, GS_EIO, "%s: short read", path);
  }
  return GS_OK;
}

/* The value of attribute name="..." inside the tag starting at tag (up to
 * its '>'), copied into out (size n); 0 if absent. */
static int attr(const char *tag, const char *name, char *out, size_t n) {
  const char *end = strchr(tag, '>');
  char key[64];
  snprintf(key, sizeof key, " %s=\"", name);
  const char *p = strstr(tag, key);
  if (!p || !end || p > end) return 0;
  p += strlen(key);
  const char *q = strchr(p, '"');
  if (!q || q > end || (size_t)(q - p) >= n) return 0;
  memcpy(out, p, (size_t)(q - p));
  out[q - p] = 0;
  return 1;
}

typedef struct {
  const char *name; /* NULL: the points */
  const char *type;
  int ncomp;
  unsigned long long offset;
  int found;
} want_array;

/* Find the arrays' offsets in the XML header (before the appended data). */
static int find_arrays(const char *path, const char *xml, const char *stop, want_array *w, int nw, gs_error *err) {
  const char *points = strstr(xml, "<Points>");
  for (const char *p = strstr(xml, "<DataArray"); p && p < stop; p = strstr(p + 1, "<DataArray")) {
    char name[64] = "", type[32] = "", off[32] = "", comps[16] = "1";
    attr(p, "Name", name, sizeof name);
    attr(p, "type", type, sizeof type);
    attr(p, "NumberOfComponents", comps, sizeof comps);
    if (!attr(p, "offset", off, sizeof off)) continue; /* the ascii TimeValue */
    const int in_points = points && p > points && p < strstr(points, "</Points>");
    for (int i = 0; i < nw; i++) {
      if (w[i].name ? strcmp(w[i].name, name) != 0 : !in_points) continue;
      char *end;
      w[i].offset = strtoull(off, &end, 10);
      if (*end || strcmp(type, w[i].type) || atoi(comps) != w[i].ncomp)
        return gs_error_set(err, GS_EINPUT, "%s: array '%s' is not %s x %d with a numeric offset", path,
                            w[i].name ? w[i].name : "points", w[i].type, w[i].ncomp);
      w[i].found = 1;
    }
  }
  for (int i = 0; i < nw; i++)
    if (!w[i].found)
      return gs_error_set(err, GS_EINPUT, "%s: no array '%s' (not a gransim DEM particle frame?)", path,
                          w[i].name ? w[i].name : "points");
  return GS_OK;
}

int gs_vtp_frame_read(gs_zone_frames *fr, const char *path, double t, gs_error *err) {
  char *buf = NULL;
  size_t size = 0;
  int rc = slurp(path, &buf, &size, err);
  if (rc) return rc;
  const uint16_t one = 1;
  const char *mine = *(const unsigned char *)&one ? "LittleEndian" : "BigEndian";
  char order[32] = "", header[32] = "", npts[32] = "";
  const char *vtk = strstr(buf, "<VTKFile"), *piece = strstr(buf, "<Piece");
  const char *app = strstr(buf, "<AppendedData encoding=\"raw\">");
  const char *data = app ? strchr(app, '_') : NULL;
  if (!vtk || !piece || !data || !attr(vtk, "byte_order", order, sizeof order) ||
      !attr(vtk, "header_type", header, sizeof header) || !attr(piece, "NumberOfPoints", npts, sizeof npts))
    rc = gs_error_set(err, GS_EINPUT, "%s: not a VTK PolyData file with raw appended data", path);
  else if (strcmp(order, mine) || strcmp(header, "UInt64"))
    rc = gs_error_set(err, GS_EINPUT, "%s: byte order %s, header %s: expected %s and UInt64 (written here)", path,
                      order, header, mine);
  char *end = NULL;
  const unsigned long long n = rc ? 0 : strtoull(npts, &end, 10);
  if (!rc && (*end || n > VTP_MAX_BYTES / 56))
    rc = gs_error_set(err, GS_EINPUT, "%s: NumberOfPoints '%s' is not a count", path, npts);
  want_array w[] = {{NULL, "Float64", 3, 0, 0}, {"id", "Int64", 1, 0, 0},
                    {"velocity", "Float64", 3, 0, 0}, {"radius", "Float64", 1, 0, 0}};
  if (!rc) rc = find_arrays(path, buf, app, w, 4, err);
  const void *src[4] = {NULL};
  for (int i = 0; !rc && i < 4; i++) {
    const size_t at = (size_t)(data + 1 - buf), want = (size_t)n * (size_t)w[i].ncomp * 8;
    uint64_t bytes = 0;
    if (w[i].offset > size || at + w[i].offset + 8 > size) {
      rc = gs_error_set(err, GS_EINPUT, "%s: array '%s' lies past the end of the file", path, w[i].name ? w[i].name : "points");
      break;
    }
    memcpy(&bytes, buf + at + w[i].offset, 8);
    if (bytes != want || at + w[i].offset + 8 + want > size)
      rc = gs_error_set(err, GS_EINPUT, "%s: array '%s' holds %llu bytes, expected %zu (%llu points)", path,
                        w[i].name ? w[i].name : "points", (unsigned long long)bytes, want, n);
    else src[i] = buf + at + w[i].offset + 8;
  }
  gs_zone_frame f = {.t = t, .n = (size_t)n};
  if (!rc) {
    f.id = malloc((n + 1) * sizeof(long));
    f.x = malloc((3 * n + 1) * sizeof(double));
    f.v = malloc((3 * n + 1) * sizeof(double));
    f.volume = malloc((n + 1) * sizeof(double));
    if (!f.id || !f.x || !f.v || !f.volume) rc = gs_error_set(err, GS_ENOMEM, "%s: out of memory", path);
  }
  if (!rc) {
    memcpy(f.x, src[0], 3 * n * sizeof(double));
    memcpy(f.v, src[2], 3 * n * sizeof(double));
  }
  for (size_t i = 0; !rc && i < n; i++) {
    int64_t id;
    double r;
    memcpy(&id, (const char *)src[1] + 8 * i, 8);
    memcpy(&r, (const char *)src[3] + 8 * i, 8);
    f.id[i] = (long)id;
    if (!(r > 0 && r < 1)) rc = gs_error_set(err, GS_EINPUT, "%s: particle %zu has radius %g, not in (0, 1) m", path, i, r);
    else f.volume[i] = 4.0 / 3.0 * 3.14159265358979323846 * r * r * r;
    for (int a = 0; !rc && a < 3; a++)
      if (!isfinite(f.x[3 * i + (size_t)a]) || !isfinite(f.v[3 * i + (size_t)a]))
        rc = gs_error_set(err, GS_EINPUT, "%s: particle %zu has a non-finite position or velocity", path, i);
  }
  free(buf);
  if (!rc) rc = gs_zone_frames_add(fr, &f, err);
  free(f.id), free(f.x), free(f.v), free(f.volume);
  if (!rc && !fr->source[0]) snprintf(fr->source, sizeof fr->source, "%s", path);
  return rc;
}

int gs_vtp_frames_read(gs_zone_frames *fr, const char *pvd, gs_error *err) {
  char *buf = NULL;
  size_t size = 0;
  int rc = slurp(pvd, &buf, &size, err);
  if (rc) return rc;
  if (!strstr(buf, "type=\"Collection\"")) rc = gs_error_set(err, GS_EINPUT, "%s: not a VTK collection (.pvd)", pvd);
  const char *slash = strrchr(pvd, '/');
  const size_t dirlen = slash ? (size_t)(slash - pvd + 1) : 0;
  size_t frames = 0;
  for (const char *p = rc ? NULL : strstr(buf, "<DataSet"); !rc && p; p = strstr(p + 1, "<DataSet")) {
    char ts[64], file[512], path[1024];
    if (!attr(p, "timestep", ts, sizeof ts) || !attr(p, "file", file, sizeof file)) {
      rc = gs_error_set(err, GS_EINPUT, "%s: a DataSet without timestep and file", pvd);
      break;
    }
    char *end;
    const double t = strtod(ts, &end);
    if (*end || !isfinite(t)) {
      rc = gs_error_set(err, GS_EINPUT, "%s: timestep '%s' is not a number", pvd, ts);
      break;
    }
    snprintf(path, sizeof path, "%.*s%s", (int)dirlen, pvd, file);
    rc = gs_vtp_frame_read(fr, path, t, err);
    frames++;
  }
  if (!rc && !frames) rc = gs_error_set(err, GS_EINPUT, "%s: the collection names no frames", pvd);
  if (!rc) snprintf(fr->source, sizeof fr->source, "%s", pvd);
  free(buf);
  return rc;
}
