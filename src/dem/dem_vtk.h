/* Legacy VTK writers (vtk.c). */
#ifndef GRANSIM_DEM_VTK_H
#define GRANSIM_DEM_VTK_H
#include "gransim/dem.h"
int gs_dem_write_vtk_particles(const gs_dem *d, const char *path, gs_error *err);
/* Nothing is written for analytic walls. */
int gs_dem_write_vtk_wall(const gs_dem *d, size_t wall, const char *path, gs_error *err);
#endif
