/* gransim — reader and reducer of LIGGGHTS DEM dumps for the PBM.
 *
 * Reads the snapshots of a directory (collision<STEP>.atom: `dump custom` with
 * id, type, vx vy vz, c_cc_1..c_cc_n, radius; impact<STEP>.atom: `dump local`
 * of compute wall/gran/local `id vel force contactArea delta`, 14 columns;
 * optional ppcoll<STEP>.atom: `dump local` of compute pair/gran/local with the
 * same keywords) and turns their *current contacts* into collision and impact
 * rates per size class with their spread over the snapshots.  The reduction
 * (formulas and choices) is documented in docs/models.md, "DEM data reduction".
 *
 * Conventions (those of the PBM pair loop): for i != j C_ij = E_ij / (N_i N_j);
 * C_ii = 2 E_ii / N_i^2, with E_ij the collision events per second between the
 * classes and N_i the number of particles of class i. */
#ifndef GRANSIM_DEM_DATA_H
#define GRANSIM_DEM_DATA_H

#include <stddef.h>

#include "gransim/error.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct gs_dem_options {
  double youngs, poisson, density, restitution; /* particle material, for the Hertz contact time;
                                                   restitution in (0,1): damped (LIGGGHTS) contact,
                                                   1 (or 0): elastic Hertz, t_c = 2.868 (...)^(1/5) */
  double contact_time;  /* > 0: use this contact duration (s) for all contacts; 0: Hertz theory */
  double wall_youngs, wall_poisson; /* wall material; wall_youngs = 0: rigid wall */
  double min_speed;     /* impact rows slower than this (m/s) are resting contacts, left out of the
                           speed fits (they still count as wall contacts); 0: keep all (> 0 speeds) */
  const char *contact_prefix; /* per-type contact columns: prefix + k (NULL: "c_cc_") */
  const double *edges;  /* optional class edges (nclass + 1) for the kernel table; NULL: from diameters */
  int edges_volume;     /* edges measure particle volume (1) or diameter (0) */
  int contacts_from;    /* GS_DEM_CONTACTS_*: where the current contacts K_ij come from */
  int quiet;            /* no warnings on stderr (skipped files) */
} gs_dem_options;

/* Sources of the current contacts K_ij (docs/models.md, "DEM data reduction"):
 *  AUTO       - PPCOLL if every snapshot has a ppcoll file, else CC_OWNER;
 *  PPCOLL     - count the rows (overlap > 0) of the pair/gran/local dump by the
 *               types of their two atoms: every contact once;
 *  CC_OWNER   - per-type contact columns with the semantics of LAMMPS/LIGGGHTS
 *               compute contact/atom on group typej (a contact is tallied on both
 *               atoms, in the column of the type of the atom that owns it in the
 *               half neighbour list): K_ij = S_ij + S_ji, K_ii = (R_i - sum_j!=i K_ij)/2
 *               with S_ij = sum over type-i atoms of c_cc_j and R_i its row sum;
 *  CC_PARTNER - the naive reading "c_cc_j = contacts with type-j atoms":
 *               K_ij = (S_ij + S_ji)/2, K_ii = S_ii/2 (for comparisons only: the
 *               bundled dumps contradict it). */
enum { GS_DEM_CONTACTS_AUTO = 0, GS_DEM_CONTACTS_PPCOLL, GS_DEM_CONTACTS_CC_OWNER, GS_DEM_CONTACTS_CC_PARTNER };

/* The material of the bundled CoriMix data (its README): E = 8e6 Pa, nu = 0.2,
 * rho = 500 kg/m^3, e = 0.4, wall E = 9.99e8 Pa (nu 0.2), min_speed 1e-3 m/s. */
void gs_dem_options_default(gs_dem_options *opt);

typedef struct gs_dem_data {
  size_t nclass, nsnap;     /* DEM particle types = size classes; snapshots averaged */
  long *steps;              /* nsnap time steps read */
  double *diameter;         /* per class (m), mean of 2 * radius; NAN if the class never occurs */
  double *count, *count_sd; /* mean (and sd over snapshots) number of particles per class */
  double contact_time;      /* the duration used for contacts between class-1 particles (s) */
  double *pair_contact_time;/* nclass*nclass: duration of an i-j contact (s) */
  double *wall_contact_time;/* nclass: duration of a wall contact (s) */
  double v_pair, v_wall;    /* effective impact velocities the Hertz durations use (m/s; 0 if given) */
  size_t nv_pair, nv_wall;  /* samples behind them */
  const char *v_pair_source;/* "ppcoll relative velocities" or "particle velocity fluctuations" or "given" */
  int contacts_from;        /* the GS_DEM_CONTACTS_* source used (never AUTO) */
  double *contacts;         /* nclass*nclass: mean current contacts K_ij (K_ii counts each once) */
  double *cc_sum;           /* nclass*nclass: mean of S_ij = sum over type-i atoms of c_cc_j (raw) */
  double *collision;        /* nclass*nclass, symmetric: C_ij in 1/s per pair of particles, mean over snapshots */
  double *collision_sd;     /* standard deviation over snapshots */
  double asymmetry;         /* sum_{i!=j} |S_ij - S_ji| / sum_{i!=j} S_ij of the raw per-type sums */
  double like_share_cc, like_share_pp; /* share of all contacts that are like-type (i == i) according to
                                          c_cc (CC_OWNER formulas) and to ppcoll (NAN without ppcoll) */
  double *impact_rate, *impact_rate_sd; /* per class: wall impacts per particle per second */
  double *impeller_rate, *shell_rate;   /* the same split by wall (moving mesh = impeller: impactType 1) */
  double *wall_contacts;    /* per class: mean current wall contacts per snapshot */
  size_t *nvel;             /* per class: impact-velocity samples */
  size_t nresting;          /* impact rows below min_speed (left out of the fits) */
  double *vel_mu, *vel_sigma; /* per class: lognormal fit of the impact speed (ln m/s); NAN if < 2 samples */
  double all_mu, all_sigma;   /* pooled lognormal fit over all classes */
  size_t all_nvel;
  double *edges;            /* nclass + 1 edges for the kernel table, or NULL (from diameters) */
  int edges_volume;
} gs_dem_data;

/* Read every collision<STEP>.atom / impact<STEP>.atom pair in dir (matching steps; ppcoll<STEP>.atom
 * used if present).  opt NULL: gs_dem_options_default.  out is overwritten. */
int gs_dem_data_read(const char *dir, const gs_dem_options *opt, gs_dem_data *out, gs_error *err);
/* P(U > u_break) for class cls from its lognormal fit (pooled fit if the class has too few samples). */
double gs_dem_break_probability(const gs_dem_data *d, size_t cls, double u_break);
/* Write C as a kernel table CSV readable by src/kernel/kernel_table.c (class edges by diameter, or by
 * volume: d->edges if set, else midpoints between increasing class diameters). */
int gs_dem_data_write_table(const gs_dem_data *d, const char *path, gs_error *err);
/* Write the wall-impact table read by the `dem_impact` selection function:
 * the class edges, then one row each of impacts per particle per second, mu
 * and sigma of the lognormal impact-speed fits (pooled fit for classes with
 * fewer than 2 samples). */
int gs_dem_data_write_impacts(const gs_dem_data *d, const char *path, gs_error *err);
void gs_dem_data_free(gs_dem_data *d);

/* Collision frequency of classes i and j from `events` collisions (or
 * collision rate times window) in `window` seconds with N_i, N_j particles:
 * C_ij = E / (N_i N_j window) for i != j and C_ii = 2 E / (N_i^2 window),
 * the convention of the PBM's pair loop, which counts a like pair once
 * (rate 1/2 beta N_i^2; docs/models.md, "Collision frequencies").  0 without
 * particles of a class.  Every writer of C (dem, dem-reduce, the LIGGGHTS
 * engine) takes it from here so that they agree. */
double gs_dem_collision_frequency(double events, double Ni, double Nj, double window, int same_class);

/* Lognormal fit of impact speeds from their logarithms ln_u: mu = mean and
 * sigma = sample standard deviation of ln U (GSL); both NAN below 2 samples.
 * Used by the dump reducer and by `gransim dem` (src/dem/stats.c). */
void gs_dem_lognormal_fit(const double *ln_u, size_t n, double *mu, double *sigma);
/* Write the table the `dem_impact` selection function reads
 * (src/kernel/selection_dem.c): the comment lines (each starting with '#',
 * may be NULL), a line naming the measure of the edges, `edges, e0, ..., en`,
 * then the rows rate, mu and sigma with one value per class. */
int gs_dem_impact_table_write(const char *path, const char *comment, size_t nclass, const double *edges,
                              int edges_volume, const double *rate, const double *mu, const double *sigma,
                              gs_error *err);

/* Write a collision-frequency kernel table, the file the `table` kernel
 * reads (src/kernel/kernel_table.c): the comment lines (each starting with
 * '#', may be NULL), a line naming the measure of the edges, `edges, e0, ...,
 * en`, then the n x n matrix C (row-major). */
int gs_dem_kernel_table_write(const char *path, const char *comment, size_t nclass, const double *edges,
                              int edges_volume, const double *C, gs_error *err);

/* Duration of a head-on Hertz contact (s): effective mass meff (kg), radius reff (m), modulus estar
 * (Pa, 1/E* = sum (1 - nu^2)/E), impact speed v (m/s), restitution e (>= 1 or <= 0: elastic,
 * 2.868 (meff^2 / (reff estar^2 v))^(1/5); else the LIGGGHTS viscoelastic damping for e, contact
 * until the overlap returns to zero). */
double gs_dem_hertz_contact_time(double meff, double reff, double estar, double v, double e);

/* ---- the damped Hertz contact law (src/demdata/hertz.c), shared with the
 * embedded DEM ---------------------------------------------------------- */
/* How the damping coefficient follows from e (see docs/models.md, DEM):
 *  EXACT    - solve the damped Hertz impact once so that a head-on collision
 *             rebounds with exactly e (default);
 *  LIGGGHTS - c = 2 sqrt(5/6) beta, beta = -ln e / sqrt(ln^2 e + pi^2), the
 *             closed form LIGGGHTS uses (realises e to within about 1 %,
 *             e.g. 0.3995 for 0.4); chosen for side-by-side comparisons. */
enum { GS_DEM_DAMPING_EXACT = 0, GS_DEM_DAMPING_LIGGGHTS = 1 };
/* Coefficient c of the damping law gamma = c * sqrt(S m*) for restitution e
 * under the given damping mode (exposed for tests and documentation). */
double gs_dem_damping_coefficient(double e, int mode);
/* Restitution a head-on Hertz impact with damping coefficient c realises. */
double gs_dem_restitution_of(double c);
/* The scaled head-on impact behind both (src/demdata/hertz.c): its duration in
 * units of (v^2 m* / (4/3 E* sqrt R*))^(2/5) / v and its restitution, for the
 * scaled damping c, integrated with step h; either output may be NULL. */
void gs_dem_scaled_impact(double c, double h, double *duration, double *restitution);

#ifdef __cplusplus
}
#endif
#endif
