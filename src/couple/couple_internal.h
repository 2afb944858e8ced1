/* Pieces of the coupled driver (src/couple/couple.c). */
#ifndef GRANSIM_COUPLE_INTERNAL_H
#define GRANSIM_COUPLE_INTERNAL_H
#include <stdio.h>

#include "gransim/cfg.h"
#include "gransim/grid.h"

#define GS_COUPLE_MAX_CLASSES 64 /* as many as a DEM case takes */

/* The `coupling:` section, typed. */
typedef struct {
  double dmin, dmax;     /* classes.min_diameter, max_diameter: what the DEM can afford */
  long count;            /* classes.count (0: one class per distinct cell diameter) */
  const char *material;  /* classes.material: a material of the DEM case */
  int outside_error;     /* classes.outside: 0 nearest, 1 error */
  long window;           /* steady.window: samples */
  double tolerance;      /* steady.tolerance */
  double sample_every;   /* steady.sample_every [s] */
  double max_time;       /* steady.max_time [s]: the DEM's longest duration */
  double collect;        /* steady.collect [s]: statistics after the detector fired, then the DEM stops */
  const char *wall;      /* impacts.wall (NULL: all walls) */
} gs_couple_settings;

/* DEM classes derived from the grid: edges in volume-equivalent diameter. */
typedef struct {
  size_t n;
  double edges[GS_COUPLE_MAX_CLASSES + 1];
  size_t cells_in[GS_COUPLE_MAX_CLASSES]; /* PBM cells inside each class */
  size_t outside;                         /* PBM cells outside every class */
} gs_couple_classes;

/* classes.c: bin the cells' diameters (size measure: the axes of mask). */
int gs_couple_classes_derive(const gs_grid *g, unsigned mask, const gs_couple_settings *s,
                             const gs_cfg_node *where, gs_couple_classes *cl, gs_error *err);

/* emit.c: write the DEM case (root of its tree, relative paths against dir)
 * with the derived classes and the coupling's run settings. */
int gs_couple_write_dem_case(FILE *fp, gs_cfg_node *dem_root, const char *dir,
                             const gs_couple_settings *s, const gs_couple_classes *cl,
                             gs_error *err);

/* steady.c: the detector's figures from the DEM's timeseries.csv into
 * steady.csv; fails naming the last figures when it never fired. */
int gs_couple_steady_report(const char *dem_dir, const gs_couple_settings *s, double *t_steady,
                            gs_error *err);
#endif
