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
  unsigned quantities;   /* steady.quantities: GS_DEM_STEADY_* bits the detector watches */
  double sample_every;   /* steady.sample_every [s] */
  double max_time;       /* steady.max_time [s]: the DEM's longest duration */
  double collect;        /* steady.collect [s]: statistics after the detector fired, then the DEM stops */
  const char *wall;      /* impacts.wall (NULL: all walls) */
  int two_way;           /* mode: two_way */
  double min_fraction;   /* classes.min_fraction: least share of DEM particles a class gets (two-way) */
  double trig_dv;        /* trigger.mean_volume_change (0: off) */
  double trig_interval;  /* trigger.interval [s] (0: off) */
  gs_cfg_node *restitution; /* coupling.restitution: e per grid axis (two-way), or NULL */
  double e_axis[GS_MAX_DIM]; /* its values (NAN: the axis does not count) */
  double e_now;          /* the DEM material's e for this stage (NAN: the case's own) */
  long scale_n;          /* scaling.particles: the DEM's particle count (0: no system scaling) */
  double geom_now;       /* the DEM's dem.geometry_scale for this stage (1: the case's geometry) */
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
 * with the derived classes and the coupling's run settings; fractions (NULL:
 * the case's own) replace every fill's class fractions, by number. */
int gs_couple_write_dem_case(FILE *fp, gs_cfg_node *dem_root, const char *dir,
                             const gs_couple_settings *s, const gs_couple_classes *cl,
                             const double *fractions, gs_error *err);

/* steady.c: the detector's figures from the DEM's timeseries.csv into
 * steady.csv; fails naming the last figures when it never fired. */
int gs_couple_steady_report(const char *dem_dir, const gs_couple_settings *s, double *t_steady,
                            gs_error *err);

/* A coupled case loaded (couple.c). */
typedef struct {
  gs_cfg *cfg;        /* the coupled case; handed to the PBM case at the end (one-way) */
  gs_cfg *dem_cfg;    /* the DEM case when `dem:` names a file */
  gs_cfg_node *dem;   /* root of the DEM case */
  char dem_dir[4096]; /* its directory, for relative mesh paths */
  const char *path;   /* the coupled case, and the line of its dem section, for messages */
  int dem_line;
  gs_couple_settings s;
  gs_couple_classes cl;
  gs_grid g;          /* the PBM grid, and the axes measuring size */
  unsigned mask;
} couple;

/* What a DEM stage records in the cycle table. */
typedef struct {
  size_t particles; /* at its end */
  long steps;
  double t_dem;    /* [s] DEM time run */
  double wall;     /* [s] */
  double t_steady; /* [s] when the detector fired */
  double e;        /* restitution of classes.material (NAN: the case's own) */
  double l;        /* system scaling ratio l_i (1: no scaling) */
  double geom;     /* the DEM geometry's scale against the case's (1: no scaling) */
} gs_couple_dem_record;

int gs_couple_load(const char *path, couple *k, int progress, gs_error *err);
void gs_couple_free(couple *k);
struct gs_couple_options;
/* opt: progress, and the ranks and launcher of a LIGGGHTS stage */
int gs_couple_dem_stage(couple *k, const char *part, const double *fractions, const struct gs_couple_options *opt,
                        gs_couple_dem_record *rec, gs_error *err);
int gs_couple_point_at_tables(gs_cfg_node *root, const char *kernel, const char *impacts, gs_error *err);
int gs_couple_write_classes(const couple *k, const char *dir, gs_error *err);
struct stat;
struct FTW;
int gs_couple_rm_entry(const char *p, const struct stat *sb, int flag, struct FTW *f);
int gs_couple_exists(const char *dir, const char *name);
double gs_couple_now(void);
/* Tables of the derived classes with every value 1, for reading the PBM case before a DEM ran. */
int gs_couple_write_placeholders(const couple *k, const char *kernel, const char *impacts, gs_error *err);

/* twoway.c: coupling.trigger, and the bi-directional loop into opt->out_dir. */
int gs_couple_read_trigger(gs_cfg_node *coupling, gs_couple_settings *s, gs_error *err);
/* Refuses a trigger that cannot fire within the process time [t0, t1] (cp: the coupling section). */
int gs_couple_check_trigger(gs_cfg_node *cp, const gs_couple_settings *s, double t0, double t1, gs_error *err);
int gs_couple_two_way(couple *k, const char *path, const struct gs_couple_options *opt, gs_error *err);
#endif
