/* Legacy VTK output for ParaView: particles as points with radius, class,
 * id, liquid content l / (s + l) and velocity; wall meshes as triangles at their current position. */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "dem/dem_vtk.h"

int gs_dem_write_vtk_particles(const gs_dem *d, const char *path, gs_error *err) {
  FILE *fp = fopen(path, "w");
  if (!fp) return gs_error_set(err, GS_EIO, "%s: cannot write: %s", path, strerror(errno));
  gs_dem_view v;
  gs_dem_get_view(d, &v);
  fprintf(fp, "# vtk DataFile Version 3.0\ngransim DEM particles t=%.9g\nASCII\nDATASET POLYDATA\n",
          gs_dem_time(d));
  fprintf(fp, "POINTS %zu double\n", v.n);
  for (size_t i = 0; i < v.n; i++) fprintf(fp, "%.9g %.9g %.9g\n", v.x[i], v.y[i], v.z[i]);
  fprintf(fp, "VERTICES %zu %zu\n", v.n, 2 * v.n);
  for (size_t i = 0; i < v.n; i++) fprintf(fp, "1 %zu\n", i);
  fprintf(fp, "POINT_DATA %zu\nSCALARS radius double 1\nLOOKUP_TABLE default\n", v.n);
  for (size_t i = 0; i < v.n; i++) fprintf(fp, "%.6g\n", v.r[i]);
  fprintf(fp, "SCALARS class int 1\nLOOKUP_TABLE default\n");
  for (size_t i = 0; i < v.n; i++) fprintf(fp, "%d\n", gs_dem_type_class(d, v.type[i]));
  fprintf(fp, "SCALARS id int 1\nLOOKUP_TABLE default\n");
  for (size_t i = 0; i < v.n; i++) fprintf(fp, "%ld\n", v.id[i]);
  fprintf(fp, "SCALARS liquid_content double 1\nLOOKUP_TABLE default\n");
  for (size_t i = 0; i < v.n; i++) {
    const double t = v.vs[i] + v.vl[i];
    fprintf(fp, "%.6g\n", t > 0 ? v.vl[i] / t : 0);
  }
  fprintf(fp, "VECTORS velocity double\n");
  for (size_t i = 0; i < v.n; i++) fprintf(fp, "%.6g %.6g %.6g\n", v.vx[i], v.vy[i], v.vz[i]);
  int bad = ferror(fp);
  if (fclose(fp) || bad) return gs_error_set(err, GS_EIO, "%s: write failed", path);
  return GS_OK;
}

int gs_dem_write_vtk_wall(const gs_dem *d, size_t wall, const char *path, gs_error *err) {
  size_t nt = gs_dem_wall_triangles(d, wall, NULL);
  if (!nt) return GS_OK; /* analytic walls are not drawn */
  double *xyz = malloc(nt * 9 * sizeof(double));
  if (!xyz) return gs_error_set(err, GS_ENOMEM, "out of memory");
  gs_dem_wall_triangles(d, wall, xyz);
  FILE *fp = fopen(path, "w");
  if (!fp) {
    free(xyz);
    return gs_error_set(err, GS_EIO, "%s: cannot write: %s", path, strerror(errno));
  }
  fprintf(fp, "# vtk DataFile Version 3.0\ngransim DEM wall %s t=%.9g\nASCII\nDATASET POLYDATA\n",
          gs_dem_wall_name(d, wall), gs_dem_time(d));
  fprintf(fp, "POINTS %zu double\n", 3 * nt);
  for (size_t k = 0; k < 3 * nt; k++) fprintf(fp, "%.9g %.9g %.9g\n", xyz[3 * k], xyz[3 * k + 1], xyz[3 * k + 2]);
  fprintf(fp, "POLYGONS %zu %zu\n", nt, 4 * nt);
  for (size_t t = 0; t < nt; t++) fprintf(fp, "3 %zu %zu %zu\n", 3 * t, 3 * t + 1, 3 * t + 2);
  free(xyz);
  int bad = ferror(fp);
  if (fclose(fp) || bad) return gs_error_set(err, GS_EIO, "%s: write failed", path);
  return GS_OK;
}
