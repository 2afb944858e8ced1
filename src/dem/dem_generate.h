/* Walls whose geometry gransim generates from a few keys (`walls[].generate`,
 * docs/case-files.md "Generated walls"): a registry of generator types, each
 * reading its keys and producing a closed triangle mesh with outward normals
 * in metres, plus the motion it implies (an impeller turns about the bowl's
 * axis).  The mesh is written as STL beside the run's output so that
 * LIGGGHTS reads the same triangles and users can open them in ParaView. */
#ifndef GRANSIM_DEM_GENERATE_H
#define GRANSIM_DEM_GENERATE_H

#include <stddef.h>

#include "gransim/cfg.h"

/* A growing list of triangles, 9 coordinates each. */
typedef struct {
  double *v;
  size_t ntri, cap;
} gs_dem_tris;

int gs_dem_tris_add(gs_dem_tris *t, const double a[3], const double b[3], const double c[3], gs_error *err);
void gs_dem_tris_free(gs_dem_tris *t);
/* The closed surface swept by turning the polyline (r[i], z[i]), i < np, in
 * the r-z half-plane about the z axis in nseg segments, translated by
 * origin.  Points with r = 0 lie on the axis (the facets meeting there form
 * a fan); a profile that runs counter-clockwise in the r-z plane (the solid
 * on its left) gives normals pointing out of the solid. */
int gs_dem_tris_revolve(gs_dem_tris *t, const double *r, const double *z, size_t np, int nseg,
                        const double origin[3], gs_error *err);

/* What a generated wall does besides standing still. */
typedef struct {
  int rotating;
  double origin[3], axis[3], omega; /* omega in rad/s about the unit axis */
  double start;                     /* [s]: at rest until then (a bed settles first) */
} gs_dem_gen_motion;

typedef struct {
  const char *name;
  const char *summary;
  /* Reads the keys of n (validated where read, unknown keys refused) and
   * appends the triangles; sets *motion when the geometry moves. */
  int (*build)(gs_cfg_node *n, gs_dem_tris *out, gs_dem_gen_motion *motion, gs_error *err);
} gs_dem_generator;

extern const gs_dem_generator gs_dem_gen_bowl, gs_dem_gen_impeller;
/* NULL-terminated, for gs_registry_pick and `gransim list`. */
extern const gs_dem_generator *const gs_dem_generators[];

/* The signed volume enclosed by the triangles (positive when the normals
 * point outward) and their area. */
void gs_dem_tris_measure(const double *v, size_t ntri, double *volume, double *area);

/* Build the wall of generate node n: the mesh (checked closed, outward and
 * free of degenerate facets) and its motion. */
int gs_dem_generate(gs_cfg_node *n, gs_dem_tris *out, gs_dem_gen_motion *motion, gs_error *err);

/* Write ntri triangles as an ASCII STL file named solid name. */
int gs_dem_write_stl(const char *path, const char *name, const double *v, size_t ntri, gs_error *err);

#endif
