/* VTK XML writers (vtk.c): PolyData frames (.vtp, raw appended binary) and
 * their time series (.pvd). */
#ifndef GRANSIM_DEM_VTK_H
#define GRANSIM_DEM_VTK_H
#include <stdint.h>

#include "gransim/dem.h"

/* One frame of particles as plain arrays, from either engine: n particles at
 * time t; positions, velocities and radii [m, m/s]; classes from 1 (as in
 * the CSV tables); ids; liquid l / (s + l) (NULL: none, written as 0). */
typedef struct {
  size_t n;
  double t;
  const double *x, *y, *z, *vx, *vy, *vz, *r, *liquid;
  const int32_t *cls;
  const int64_t *id;
} gs_dem_vtp_frame;
/* The frame as a PolyData file of vertices with the arrays radius, class,
 * id, liquid_content and velocity and the time as TimeValue. */
int gs_dem_write_vtp_frame(const gs_dem_vtp_frame *f, const char *path, gs_error *err);
/* The embedded engine's particles now (gs_dem_write_vtp_frame). */
int gs_dem_write_vtp_particles(const gs_dem *d, const char *path, gs_error *err);
/* Nothing is written for analytic walls. */
int gs_dem_write_vtp_wall(const gs_dem *d, size_t wall, const char *path, gs_error *err);
/* path: the collection naming STEM_000000.vtp ... STEM_{nframes-1}.vtp (beside
 * it) at times[0..nframes-1]; written whole (renamed from path.partial). */
int gs_dem_write_pvd(const char *path, const char *stem, const double *times, long nframes,
                     gs_error *err);
#endif
