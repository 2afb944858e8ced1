/* A DEM case read from YAML (case_dem.c) and its run driver (run_dem.c). */
#ifndef GRANSIM_DEM_CASE_INTERNAL_H
#define GRANSIM_DEM_CASE_INTERNAL_H

#include "gransim/cfg.h"
#include "gransim/dem.h"

#define GS_DEM_MAX_CLASSES 64

typedef struct {
  gs_dem_region reg;
  long count;          /* fill: number (or LONG_MAX) */
  double mass;         /* fill: kg (or inf) */
  double mass_rate, number_rate, every, start, end; /* feed */
  double v[3];
  double *frac;        /* per class */
  int by_mass;
  /* running state */
  double done_n, done_m;
  double next_t;
} gs_dem_inserter;

typedef struct {
  char name[64];
  int type;
  double rmin, rmax;   /* fixed (equal), uniform range, or the lognormal's truncation */
  double median, gsd;  /* lognormal radius when gsd > 1 (else 0) */
} gs_dem_class;

struct gs_dem_case_s {
  gs_cfg *cfg;
  char path[1024];
  gs_dem *dem;
  gs_dem_params prm;
  double duration;
  uint64_t seed;
  size_t nclass;
  gs_dem_class cls[GS_DEM_MAX_CLASSES];
  gs_dem_inserter *fill, *feed;
  size_t nfill, nfeed;
  gs_dem_region *outlets;
  size_t noutlets;
  /* statistics */
  int start_steady;
  double stats_start, sample_every;
  double cmp_axis[3], cmp_origin[3], *cmp_edges;
  size_t ncmp;
  int has_holdup;
  gs_dem_region holdup;
  long steady_window;
  double steady_tol;
  /* output */
  double out_every, vtk_every;
};

#endif
