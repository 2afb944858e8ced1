/* The embedded DEM's particle frames read back: a .pvd collection
 * (<DataSet timestep="t" file="..."/> lines) and the PolyData files it
 * names, as src/dem/vtk.c writes them (raw appended arrays, UInt64 headers,
 * this machine's byte order): points, `id`, `velocity` and `radius`. */
#ifndef GRANSIM_DEMDATA_VTP_FRAMES_H
#define GRANSIM_DEMDATA_VTP_FRAMES_H

#include "demdata/zones.h"
#include "gransim/error.h"

/* Append every frame of the collection pvd (files relative to its folder). */
int gs_vtp_frames_read(gs_zone_frames *fr, const char *pvd, gs_error *err);
/* One particle frame file at time t. */
int gs_vtp_frame_read(gs_zone_frames *fr, const char *path, double t, gs_error *err);
#endif
