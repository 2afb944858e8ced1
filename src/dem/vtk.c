/* VTK XML output for ParaView and meshio: particles as vertices with radius,
 * class, id, liquid content l / (s + l) and velocity, wall meshes as triangles at their current position,
 * each frame a PolyData file (.vtp) whose arrays follow the XML header as raw
 * appended binary (no base64: the readers take encoding="raw"), and one .pvd
 * collection per object that gives every frame its simulated time. */
#include <errno.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "dem/dem_vtk.h"

/* One appended array: its XML attributes and its bytes. */
typedef struct {
  const char *type; /* Float64, Int32, Int64 */
  const char *name; /* NULL inside <Points> */
  int ncomp;
  const void *data;
  uint64_t nbytes;
} vtp_array;

static const char *byte_order(void) {
  const uint16_t one = 1;
  return *(const unsigned char *)&one ? "LittleEndian" : "BigEndian";
}

static void xml_array(FILE *fp, const vtp_array *a, uint64_t offset) {
  fprintf(fp, "        <DataArray type=\"%s\"", a->type);
  if (a->name) fprintf(fp, " Name=\"%s\"", a->name);
  if (a->ncomp > 1) fprintf(fp, " NumberOfComponents=\"%d\"", a->ncomp);
  fprintf(fp, " format=\"appended\" offset=\"%llu\"/>\n", (unsigned long long)offset);
}

/* A PolyData file of n points with cells of one kind (`cells`: Verts or
 * Polys, ncell of them): arrays a[0..npd-1] are point data, a[npd] the
 * points, a[npd+1] and a[npd+2] the cells' connectivity and offsets. */
static int write_vtp(const char *path, double t, const char *what, size_t n, const char *cells,
                     size_t ncell, const vtp_array *a, int npd, gs_error *err) {
  FILE *fp = fopen(path, "wb");
  if (!fp) return gs_error_set(err, GS_EIO, "%s: cannot write: %s", path, strerror(errno));
  uint64_t off = 0;
  fprintf(fp,
          "<?xml version=\"1.0\"?>\n"
          "<VTKFile type=\"PolyData\" version=\"1.0\" byte_order=\"%s\" header_type=\"UInt64\">\n"
          "  <!-- gransim DEM %s -->\n  <PolyData>\n"
          "    <FieldData>\n"
          "      <DataArray type=\"Float64\" Name=\"TimeValue\" NumberOfTuples=\"1\" format=\"ascii\">%.17g</DataArray>\n"
          "    </FieldData>\n"
          "    <Piece NumberOfPoints=\"%zu\" NumberOfVerts=\"%zu\" NumberOfLines=\"0\" NumberOfStrips=\"0\" "
          "NumberOfPolys=\"%zu\">\n",
          byte_order(), what, t, n, strcmp(cells, "Verts") ? (size_t)0 : ncell,
          strcmp(cells, "Polys") ? (size_t)0 : ncell);
  fprintf(fp, "      <PointData%s>\n", npd ? " Scalars=\"radius\" Vectors=\"velocity\"" : "");
  for (int i = 0; i < npd; i++) xml_array(fp, &a[i], off), off += 8 + a[i].nbytes;
  fprintf(fp, "      </PointData>\n      <Points>\n");
  xml_array(fp, &a[npd], off);
  off += 8 + a[npd].nbytes;
  fprintf(fp, "      </Points>\n      <%s>\n", cells);
  for (int i = npd + 1; i < npd + 3; i++) xml_array(fp, &a[i], off), off += 8 + a[i].nbytes;
  fprintf(fp, "      </%s>\n    </Piece>\n  </PolyData>\n  <AppendedData encoding=\"raw\">\n   _", cells);
  for (int i = 0; i < npd + 3; i++) {
    fwrite(&a[i].nbytes, sizeof a[i].nbytes, 1, fp);
    if (a[i].nbytes) fwrite(a[i].data, 1, a[i].nbytes, fp);
  }
  fprintf(fp, "\n  </AppendedData>\n</VTKFile>\n");
  int bad = ferror(fp);
  if (fclose(fp) || bad) return gs_error_set(err, GS_EIO, "%s: write failed", path);
  return GS_OK;
}

int gs_dem_write_vtp_frame(const gs_dem_vtp_frame *f, const char *path, gs_error *err) {
  const size_t n = f->n, m = n ? n : 1;
  double *xyz = malloc(3 * m * sizeof(double)), *vel = malloc(3 * m * sizeof(double));
  double *liq = malloc(m * sizeof(double));
  int64_t *conn = malloc(m * sizeof(int64_t)), *offs = malloc(m * sizeof(int64_t));
  int rc = GS_OK;
  if (!xyz || !vel || !liq || !conn || !offs) rc = gs_error_set(err, GS_ENOMEM, "out of memory");
  for (size_t i = 0; !rc && i < n; i++) {
    xyz[3 * i] = f->x[i], xyz[3 * i + 1] = f->y[i], xyz[3 * i + 2] = f->z[i];
    vel[3 * i] = f->vx[i], vel[3 * i + 1] = f->vy[i], vel[3 * i + 2] = f->vz[i];
    liq[i] = f->liquid ? f->liquid[i] : 0;
    conn[i] = (int64_t)i;
    offs[i] = (int64_t)i + 1;
  }
  if (!rc) {
    const vtp_array a[] = {
        {"Float64", "radius", 1, f->r, n * sizeof(double)},
        {"Int32", "class", 1, f->cls, n * sizeof(int32_t)},
        {"Int64", "id", 1, f->id, n * sizeof(int64_t)},
        {"Float64", "liquid_content", 1, liq, n * sizeof(double)},
        {"Float64", "velocity", 3, vel, 3 * n * sizeof(double)},
        {"Float64", NULL, 3, xyz, 3 * n * sizeof(double)},
        {"Int64", "connectivity", 1, conn, n * sizeof(int64_t)},
        {"Int64", "offsets", 1, offs, n * sizeof(int64_t)},
    };
    rc = write_vtp(path, f->t, "particles", n, "Verts", n, a, 5, err);
  }
  free(xyz), free(vel), free(liq), free(conn), free(offs);
  return rc;
}

int gs_dem_write_vtp_particles(const gs_dem *d, const char *path, gs_error *err) {
  gs_dem_view v;
  gs_dem_get_view(d, &v);
  const size_t n = v.n, m = n ? n : 1;
  double *liq = malloc(m * sizeof(double));
  int32_t *cls = malloc(m * sizeof(int32_t));
  int64_t *id = malloc(m * sizeof(int64_t));
  int rc = GS_OK;
  if (!liq || !cls || !id) rc = gs_error_set(err, GS_ENOMEM, "out of memory");
  for (size_t i = 0; !rc && i < n; i++) {
    cls[i] = gs_dem_type_class(d, v.type[i]) + 1; /* 1-based, as in the CSV tables */
    id[i] = v.id[i];
    const double vt = v.vs[i] + v.vl[i];
    liq[i] = vt > 0 ? v.vl[i] / vt : 0;
  }
  if (!rc) {
    const gs_dem_vtp_frame f = {.n = n, .t = gs_dem_time(d), .x = v.x, .y = v.y, .z = v.z,
                                .vx = v.vx, .vy = v.vy, .vz = v.vz, .r = v.r, .liquid = liq,
                                .cls = cls, .id = id};
    rc = gs_dem_write_vtp_frame(&f, path, err);
  }
  free(liq), free(cls), free(id);
  return rc;
}

int gs_dem_write_vtp_wall(const gs_dem *d, size_t wall, const char *path, gs_error *err) {
  size_t nt = gs_dem_wall_triangles(d, wall, NULL);
  if (!nt) return GS_OK; /* analytic walls are not drawn */
  double *xyz = malloc(nt * 9 * sizeof(double));
  int64_t *conn = malloc(3 * nt * sizeof(int64_t)), *offs = malloc(nt * sizeof(int64_t));
  int rc = GS_OK;
  if (!xyz || !conn || !offs) rc = gs_error_set(err, GS_ENOMEM, "out of memory");
  if (!rc) {
    gs_dem_wall_triangles(d, wall, xyz);
    for (size_t k = 0; k < 3 * nt; k++) conn[k] = (int64_t)k;
    for (size_t t = 0; t < nt; t++) offs[t] = 3 * (int64_t)t + 3;
    char what[128];
    snprintf(what, sizeof what, "wall %s", gs_dem_wall_name(d, wall));
    const vtp_array a[] = {
        {"Float64", NULL, 3, xyz, 9 * nt * sizeof(double)},
        {"Int64", "connectivity", 1, conn, 3 * nt * sizeof(int64_t)},
        {"Int64", "offsets", 1, offs, nt * sizeof(int64_t)},
    };
    rc = write_vtp(path, gs_dem_time(d), what, 3 * nt, "Polys", nt, a, 0, err);
  }
  free(xyz), free(conn), free(offs);
  return rc;
}

int gs_dem_write_pvd(const char *path, const char *stem, const double *times, long nframes,
                     gs_error *err) {
  size_t pn = strlen(path) + sizeof ".partial";
  char *partial = malloc(pn);
  if (!partial) return gs_error_set(err, GS_ENOMEM, "out of memory");
  snprintf(partial, pn, "%s.partial", path);
  FILE *fp = fopen(partial, "w");
  int rc = GS_OK;
  if (!fp) {
    rc = gs_error_set(err, GS_EIO, "%s: cannot write: %s", partial, strerror(errno));
  } else {
    fprintf(fp, "<?xml version=\"1.0\"?>\n"
                "<VTKFile type=\"Collection\" version=\"1.0\" byte_order=\"%s\">\n  <Collection>\n",
            byte_order());
    for (long f = 0; f < nframes; f++)
      fprintf(fp, "    <DataSet timestep=\"%.17g\" part=\"0\" file=\"%s_%06ld.vtp\"/>\n", times[f], stem, f);
    fprintf(fp, "  </Collection>\n</VTKFile>\n");
    int bad = ferror(fp);
    if (fclose(fp) || bad || rename(partial, path))
      rc = gs_error_set(err, GS_EIO, "%s: write failed: %s", path, strerror(errno));
  }
  free(partial);
  return rc;
}
