/* VTK XML writers (vtk.c): PolyData frames (.vtp, raw appended binary) and
 * their time series (.pvd). */
#ifndef GRANSIM_DEM_VTK_H
#define GRANSIM_DEM_VTK_H
#include "gransim/dem.h"
int gs_dem_write_vtp_particles(const gs_dem *d, const char *path, gs_error *err);
/* Nothing is written for analytic walls. */
int gs_dem_write_vtp_wall(const gs_dem *d, size_t wall, const char *path, gs_error *err);
/* path: the collection naming STEM_000000.vtp ... STEM_{nframes-1}.vtp (beside
 * it) at times[0..nframes-1]; written whole (renamed from path.partial). */
int gs_dem_write_pvd(const char *path, const char *stem, const double *times, long nframes,
                     gs_error *err);
#endif
