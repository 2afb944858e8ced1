/* Statistics of a DEM run for the PBM (stats.c): numbers per class,
 * velocities per class and compartment, hold-up, residence times, and the
 * tables written from them and from the engine's event counters. */
#ifndef GRANSIM_DEM_STATS_H
#define GRANSIM_DEM_STATS_H
#include <stdio.h>

#include "dem/dem_case.h"
#include "demdata/csv_meta.h"

typedef struct {
  int ncl;
  size_t ncmp;
  double t0;
  long nsamples;
  double *num_sum;                    /* per class */
  double *cv_n, *cv_s, *cv_s2, *cv_a; /* per class x compartment: samples, sums of speed,
                                          speed^2 and axial velocity */
  double *cv_v, *cv_v2;               /* 3 per class x compartment: sums of vx, vy, vz and squares */
  double *cv_ref;                     /* 4 per class x compartment: the first speed, vx, vy, vz seen;
                                         the sums above are of differences from it (no cancellation
                                         in the standard deviations of nearly constant values) */
  double hold_n_sum, hold_m_sum;
  double *rt;                         /* residence times of removed particles */
  int *rt_cls;
  size_t nrt, rt_cap;
  double out_mass;                    /* mass removed since t0 */
} gs_dem_stats;

int gs_dem_stats_init(gs_dem_stats *s, const gs_dem_case *c, gs_error *err);
void gs_dem_stats_free(gs_dem_stats *s);
/* Forget everything and restart the window at time t (also resets the
 * engine's event counters and discards the particles removed before t). */
void gs_dem_stats_reset(gs_dem_stats *s, gs_dem_case *c, double t);
/* The steady-state detector (Sampat et al. 2018): 1 when, over the last w of the n
 * samples, both series a (hold-up mass) and b (collision rate) stay within
 * tol * mean of their window means, and both means are > 0. */
int gs_dem_is_steady(const double *a, const double *b, long n, long w, double tol);
/* The same over nq series s[0..nq-1] (the quantities of statistics.steady). */
int gs_dem_is_steady_n(const double *const *s, int nq, long n, long w, double tol);
/* Hold-up of the case (number and mass in the hold-up region, or all). */
void gs_dem_holdup(const gs_dem_case *c, double *n, double *m);
/* One sample of the state; takes the removed particles' residence times. */
int gs_dem_stats_sample(gs_dem_stats *s, gs_dem_case *c, gs_error *err);
/* Write collisions.csv, collision_kernel.csv, impacts.csv, impact_table.csv
 * (and impact_table_WALL.csv per wall), impact_velocity.csv, velocity.csv,
 * residence.csv and residence_class.csv into dir.  t_steady < 0: the steady
 * state was not detected.  Without a statistics window (start: steady never
 * fired, or no sample in the window) the rates are written as nan with a
 * note in each file's header.  stopped: NULL, or why the run stopped early,
 * added to every header so tables from a failed run are never mistaken for
 * a finished run's. */
int gs_dem_stats_write(const gs_dem_stats *s, const gs_dem_case *c, const char *dir, double t_end,
                       double t_steady, const char *stopped, gs_error *err);
/* 1 if the window holds statistics (gs_dem_stats_write writes rates). */
int gs_dem_stats_have_window(const gs_dem_stats *s, const gs_dem_case *c, double t_end, double t_steady);
/* The tables' helpers, shared with the LIGGGHTS engine's reduction
 * (src/liggghts/tables.c) so that both write the same edges and files.
 * A table written at the end: dir/name begun in memory (its "# " lines
 * become the description in dir/NAME.json, demdata/csv_meta.h) and ended
 * with the units of its columns.  A table written row by row as the run goes
 * (header line first, no "#" lines): dir/name opened for writing (path
 * receives it) and closed with its error checked.  And the class edges in
 * diameter (nclass + 1 values). */
FILE *gs_dem_table_begin(gs_csv_out *t, const char *dir, const char *name, gs_error *err);
int gs_dem_table_end(gs_csv_out *t, const char *const *units, gs_error *err);
FILE *gs_dem_table_open(const char *dir, const char *name, char *path, size_t n, gs_error *err);
int gs_dem_table_close(FILE *fp, const char *path, gs_error *err);
/* the units of each table's columns (gs_csv_meta_write) */
extern const char *const gs_dem_units_collisions[], *const gs_dem_units_kernel[],
    *const gs_dem_units_impacts[], *const gs_dem_units_impact_velocity[], *const gs_dem_units_velocity[],
    *const gs_dem_units_residence[], *const gs_dem_units_residence_class[];
void gs_dem_class_edges(const gs_dem_case *c, double *e);
/* residence.csv and residence_class.csv: the nrt residence times rt (class
 * rt_cls) of the particles that left through outlets from t0 to t_end
 * (out_mass kg), the mean hold-up (hold_n particles, hold_m kg) and the note
 * for the headers. */
int gs_dem_residence_write(const gs_dem_case *c, const char *dir, const double *rt, const int *rt_cls, size_t nrt,
                           double out_mass, double t0, double t_end, double hold_n, double hold_m, const char *note,
                           gs_error *err);
/* timeseries.json beside path (timeseries.csv, written row by row as the run
 * goes): the description and the units of its columns, walls included. */
int gs_dem_timeseries_meta(const char *path, const char *description, size_t nw,
                           const char *const *wall_names, gs_error *err);
#endif
