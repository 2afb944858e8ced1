/* Gas-phase outputs of a coupled run: gas.csv (one row per output time) and
 * the gas fields as VTK rectilinear grids (vtk/gas_NNNNNN.vtr) with the
 * ParaView time series gas.pvd.  Each row and each file is complete when
 * written (rows flushed, the .pvd rewritten after every field file), so a
 * run stopped by an error leaves its outputs readable up to there. */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "cfd/cfd_internal.h"

int gs_cfd_set_output(gs_cfd *g, const char *dir, double every, double vtk_every, gs_error *err) {
  snprintf(g->out_dir, sizeof g->out_dir, "%s", dir);
  g->out_every = every;
  g->vtk_every = vtk_every;
  g->next_out = 0;
  g->next_vtk = 0;
  char path[4200];
  snprintf(path, sizeof path, "%s/gas.csv", dir);
  if (!(g->csv = fopen(path, "w"))) return gs_error_set(err, GS_EIO, "%s: %s", path, strerror(errno));
  fprintf(g->csv, "t_s,gas_step,inlet_pressure_Pa,mean_void_fraction,min_void_fraction,max_gas_speed_m_s,"
                  "solver_iterations,solver_residual,drag_on_particles_z_N,drag_from_gas_z_N\n");
  fflush(g->csv);
  if (vtk_every > 0) {
    snprintf(path, sizeof path, "%s/vtk", dir);
    if (mkdir(path, 0777) && errno != EEXIST) return gs_error_set(err, GS_EIO, "%s: %s", path, strerror(errno));
  }
  return GS_OK;
}

static void write_row(gs_cfd *g) {
  double mean = 0, mn = 1, umax = 0;
  for (size_t c = 0; c < g->ncell; c++) {
    mean += g->eps[c];
    mn = fmin(mn, g->eps[c]);
    double u[3];
    gs_cfd_cell_velocity(g, c, u);
    umax = fmax(umax, sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]));
  }
  fprintf(g->csv, "%.9g,%ld,%.9g,%.9g,%.9g,%.9g,%d,%.3g,%.9g,%.9g\n", g->t, g->steps, gs_cfd_inlet_pressure(g),
          mean / (double)g->ncell, mn, umax, g->its, g->res, g->ex_part[2], g->ex_gas[2]);
  fflush(g->csv);
}

/* The particles' liquid content l/(s + l) per cell: the liquid over the
 * particle volume of the particles whose centre lies in the cell (0 where
 * none), the map of the wetter spray zone beside the gas fields. */
static int cell_liquid(const gs_cfd *g, const gs_dem_view *v, double **out, gs_error *err) {
  double *lq = gs_calloc(2 * g->ncell, sizeof(double), err);
  if (!lq) return err->code;
  for (size_t i = 0; v->vs && v->vl && i < v->n; i++) {
    const double x[3] = {v->x[i], v->y[i], v->z[i]};
    size_t c = 0, stride = 1;
    for (int a = 0; a < 3; a++) {
      long k = (long)floor((x[a] - g->prm.lo[a]) / g->h[a]);
      k = k < 0 ? 0 : k >= g->n[a] ? g->n[a] - 1 : k;
      c += (size_t)k * stride;
      stride *= (size_t)g->n[a];
    }
    lq[c] += v->vl[i];
    lq[g->ncell + c] += v->vs[i] + v->vl[i];
  }
  for (size_t c = 0; c < g->ncell; c++) lq[c] = lq[g->ncell + c] > 0 ? lq[c] / lq[g->ncell + c] : 0;
  *out = lq;
  return GS_OK;
}

static int write_vtk(gs_cfd *g, const gs_dem_view *v, gs_error *err) {
  double *lq = NULL;
  if (cell_liquid(g, v, &lq, err)) return err->code;
  char path[4200], tmp[4300];
  snprintf(path, sizeof path, "%s/vtk/gas_%06d.vtr", g->out_dir, g->nvtk);
  snprintf(tmp, sizeof tmp, "%s.partial", path);
  FILE *fp = fopen(tmp, "w");
  if (!fp) {
    free(lq);
    return gs_error_set(err, GS_EIO, "%s: %s", tmp, strerror(errno));
  }
  const int *n = g->n;
  fprintf(fp, "<?xml version=\"1.0\"?>\n<VTKFile type=\"RectilinearGrid\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
              "<RectilinearGrid WholeExtent=\"0 %d 0 %d 0 %d\">\n<Piece Extent=\"0 %d 0 %d 0 %d\">\n<Coordinates>\n",
          n[0], n[1], n[2], n[0], n[1], n[2]);
  for (int a = 0; a < 3; a++) {
    fprintf(fp, "<DataArray type=\"Float64\" Name=\"%c\" format=\"ascii\">\n", "xyz"[a]);
    for (int i = 0; i <= n[a]; i++) fprintf(fp, "%.9g ", g->prm.lo[a] + i * g->h[a]);
    fprintf(fp, "\n</DataArray>\n");
  }
  fprintf(fp, "</Coordinates>\n<CellData Scalars=\"void_fraction\" Vectors=\"gas_velocity\">\n"
              "<DataArray type=\"Float64\" Name=\"void_fraction\" format=\"ascii\">\n");
  for (size_t c = 0; c < g->ncell; c++) fprintf(fp, "%.9g\n", g->eps[c]);
  fprintf(fp, "</DataArray>\n<DataArray type=\"Float64\" Name=\"pressure\" format=\"ascii\">\n");
  for (size_t c = 0; c < g->ncell; c++) fprintf(fp, "%.9g\n", g->p[c]);
  fprintf(fp, "</DataArray>\n<DataArray type=\"Float64\" Name=\"gas_velocity\" NumberOfComponents=\"3\" "
              "format=\"ascii\">\n");
  for (size_t c = 0; c < g->ncell; c++) {
    double u[3];
    gs_cfd_cell_velocity(g, c, u);
    fprintf(fp, "%.9g %.9g %.9g\n", u[0], u[1], u[2]);
  }
  fprintf(fp, "</DataArray>\n<DataArray type=\"Float64\" Name=\"liquid_content\" format=\"ascii\">\n");
  for (size_t c = 0; c < g->ncell; c++) fprintf(fp, "%.9g\n", lq[c]);
  free(lq);
  fprintf(fp, "</DataArray>\n</CellData>\n</Piece>\n</RectilinearGrid>\n</VTKFile>\n");
  if (fclose(fp) || rename(tmp, path)) return gs_error_set(err, GS_EIO, "%s: %s", path, strerror(errno));
  /* the time series, rewritten whole after every file */
  double *tt = realloc(g->vtk_t, (size_t)(g->nvtk + 1) * sizeof(double));
  if (!tt) return gs_error_set(err, GS_ENOMEM, "out of memory");
  g->vtk_t = tt;
  g->vtk_t[g->nvtk++] = g->t;
  snprintf(path, sizeof path, "%s/gas.pvd", g->out_dir);
  snprintf(tmp, sizeof tmp, "%s.partial", path);
  if (!(fp = fopen(tmp, "w"))) return gs_error_set(err, GS_EIO, "%s: %s", tmp, strerror(errno));
  fprintf(fp, "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\">\n<Collection>\n");
  for (int k = 0; k < g->nvtk; k++)
    fprintf(fp, "<DataSet timestep=\"%.9g\" file=\"vtk/gas_%06d.vtr\"/>\n", g->vtk_t[k], k);
  fprintf(fp, "</Collection>\n</VTKFile>\n");
  if (fclose(fp) || rename(tmp, path)) return gs_error_set(err, GS_EIO, "%s: %s", path, strerror(errno));
  return GS_OK;
}

int gs_cfd_write_outputs(gs_cfd *g, const gs_dem_view *v, gs_error *err) {
  const double eps_t = 1e-9 * g->prm.dt;
  if (g->csv && g->t >= g->next_out - eps_t) {
    write_row(g);
    while (g->next_out <= g->t + eps_t) g->next_out += g->out_every;
  }
  if (g->vtk_every > 0 && g->t >= g->next_vtk - eps_t) {
    int rc = write_vtk(g, v, err);
    if (rc) return rc;
    while (g->next_vtk <= g->t + eps_t) g->next_vtk += g->vtk_every;
  }
  return GS_OK;
}
