/* gransim — the stochastic weighted-particle solver (SWA, McGuire et al. 2018).
 *
 * A run is a Markov jump process on computational particles.  Particle i of
 * compartment z has a type-space vector x_i (one value per coordinate, e.g.
 * solid, external liquid, internal liquid, pores) and a statistical weight
 * w_i.  Compartment z has a sample volume V_z: particle i stands for w_i / V_z
 * real particles.  gransim counts particles (the sectional state is a count,
 * not a density), so V_z is dimensionless: the fraction of the real
 * compartment that the ensemble samples, and every rate constant keeps the
 * units it has in the sectional engine (a kernel is a rate per particle pair).
 *
 * Jump processes (coagulation, breakage, feed, transport, immersion
 * nucleation) and continuous processes (liquid penetration, deferred with
 * LPDA) are registered types.  Rates come from Fenwick-tree caches of
 * per-particle properties (O(log N) selection and update); a process may
 * return a majorant rate and reject (fictitious jump) with the ratio of the
 * true to the majorant rate.
 *
 * Independent runs (per-run GSL seeds) run in parallel with OpenMP; the
 * ensemble mean and the 90 % confidence half-width 1.64 sqrt(sum (M_r - mean)^2)
 * / n_runs (McGuire et al. 2018, eq. 65) of every output are written like the sectional
 * outputs (summary.csv with ci_* columns, result.h5). */
#ifndef GRANSIM_SWA_H
#define GRANSIM_SWA_H

#include <stddef.h>
#include <stdint.h>

#include "gransim/cfg.h"
#include "gransim/grid.h"

#ifdef __cplusplus
extern "C" {
#endif

#define GS_SWA_MAX_COORD 8 /* coordinates of the particle type space */
#define GS_SWA_MAX_PROP 12 /* cached per-particle properties (column 0 is the weight) */

/* contraction of a full compartment (solver.contraction) */
enum { GS_SWA_MERGE, GS_SWA_DROP };

typedef struct gs_swa_model gs_swa_model;
typedef struct gs_swa_sim gs_swa_sim; /* the state of one run (opaque) */

/* ---- processes (registered types) ----------------------------------------
 * A process must not modify its self during a run: runs share it across
 * threads; per-run state lives in the sim. */
typedef struct gs_swa_process_type {
  const char *name;    /* case-file `type` in an SWA case's mechanisms */
  const char *summary; /* one line for `gransim list` */
  /* Read keys from node ("type" consumed), register the particle properties
   * the process needs (gs_swa_model_add_prop) and call gs_cfg_check_unused. */
  int (*create)(gs_cfg_node *node, gs_swa_model *m, void **self, gs_error *err);
  /* Jump processes: total (majorant) rate of the process in compartment comp,
   * events per unit time, from cached sums. */
  double (*rate)(const void *self, const gs_swa_sim *s, size_t comp);
  /* Perform one event in comp (possibly fictitious: then change nothing). */
  int (*jump)(const void *self, gs_swa_sim *s, size_t comp, gs_error *err);
  /* Continuous processes (rate and jump NULL): advance one particle's vector
   * x by dt (LPDA; must keep the particle's mass). */
  void (*advance)(const void *self, size_t comp, double *x, double dt);
  void (*free)(void *self);
  /* Processes that bring particles in from a distribution (feed), else NULL:
   * that distribution, its key ("file:line: path"), the compartment, the
   * physical rate (particles per unit time) and the window [start, end), for
   * the discretisation report (src/swa/disc.c). */
  const struct gs_swa_spec *(*inflow)(const void *self, const char **key, size_t *comp,
                                      double *rate, double window[2]);
} gs_swa_process_type;

const gs_swa_process_type *const *gs_swa_process_types(void); /* NULL-terminated */

/* A cached per-particle property: f(x, w).  Must be >= 0 and finite. */
typedef double (*gs_swa_prop_fn)(const void *ctx, const double *x, double w);

typedef struct gs_swa_process {
  const gs_swa_process_type *type;
  void *self;
  char label[64]; /* "mechanisms[i] (type)" */
} gs_swa_process;

struct gs_swa_model {
  int ncoord;
  char coord[GS_SWA_MAX_COORD][GS_NAME_LEN];
  double density[GS_SWA_MAX_COORD]; /* mass m(x) = sum density_k x_k (weight transfers) */
  unsigned size_mask;               /* coordinates summed into the granule volume */
  size_t ncomp;
  size_t nmax;          /* computational particles per compartment (capacity) */
  double nmin_fraction; /* doubling below nmin_fraction * nmax (3/8, Lee et al. 2015) */
  double fill_fraction; /* initial ensemble: fill_fraction * nmax particles (0.75) */
  double reference_number; /* physical count that fill_fraction*nmax weight-1 particles stand
                              for in a compartment that starts empty (0: none given) */
  double lpda_interval; /* deferment checkpoint spacing (0: output times only) */
  int contraction;      /* GS_SWA_MERGE or GS_SWA_DROP: see gs_swa_add */
  gs_swa_process *proc;
  size_t nproc;
  int nprop;
  gs_swa_prop_fn prop_fn[GS_SWA_MAX_PROP];
  const void *prop_ctx[GS_SWA_MAX_PROP];
  int has_continuous; /* some process defers (LPDA) */
  /* The case's grid (its axes name coordinates: bin_coord[a] is the
   * coordinate of axis a) and directory, for the registered kernels, which
   * are created on grids; set before the processes are created. */
  const gs_grid *grid;
  const int *bin_coord;
  const char *dir;
};

/* Register a cached property; returns its column (>= 1) or -1 when full. */
int gs_swa_model_add_prop(gs_swa_model *m, gs_swa_prop_fn fn, const void *ctx);
int gs_swa_coord_by_name(const gs_swa_model *m, const char *name); /* -1 if absent */
double gs_swa_mass(const gs_swa_model *m, const double *x);
double gs_swa_size(const gs_swa_model *m, const double *x); /* granule volume */
/* Read a coordinate name key (default def if absent) into its index. */
int gs_swa_coord_key(gs_cfg_node *node, const char *key, const gs_swa_model *m,
                     const char *def, int *out, gs_error *err);
/* Read an optional list of coordinate names into a bit mask (def if absent). */
int gs_swa_coord_mask(gs_cfg_node *node, const char *key, const gs_swa_model *m, unsigned def,
                      unsigned *out, gs_error *err);
/* A number or a list of one number per compartment; out has m->ncomp entries. */
int gs_swa_per_comp(gs_cfg_node *node, const char *key, int required, double def, double lo,
                    int lo_strict, const gs_swa_model *m, double *out, gs_error *err);

/* ---- one run: the particle ensemble, used by processes and tests ---------- */
gs_swa_sim *gs_swa_sim_alloc(const gs_swa_model *m, uint64_t seed, gs_error *err);
void gs_swa_sim_free(gs_swa_sim *s);
const gs_swa_model *gs_swa_sim_model(const gs_swa_sim *s);
void *gs_swa_rng(gs_swa_sim *s);                   /* the run's gsl_rng */
double gs_swa_time(const gs_swa_sim *s);
size_t gs_swa_count(const gs_swa_sim *s, size_t comp);
double gs_swa_sum(const gs_swa_sim *s, size_t comp, int prop); /* sum of a property */
double gs_swa_vsamp(const gs_swa_sim *s, size_t comp);
/* Weight scale g of particles entering comp from outside (feed, droplets):
 * they enter at rate R V / (w g) with weight w g.  1 at the start; every merge
 * contraction multiplies it by nmax / (nmax - 1) (the growth of the mean
 * weight), so the computational inflow adapts to the capacity. */
double gs_swa_gain(const gs_swa_sim *s, size_t comp);
void gs_swa_set_vsamp(gs_swa_sim *s, size_t comp, double v);
/* Particle i, brought up to the current time first (LPDA).  The pointer is
 * valid until the next add/remove in comp. */
double *gs_swa_x(gs_swa_sim *s, size_t comp, size_t i);
double gs_swa_w(const gs_swa_sim *s, size_t comp, size_t i);
double gs_swa_prop(const gs_swa_sim *s, size_t comp, size_t i, int prop); /* cached value */
/* After changing x (through gs_swa_x) and/or the weight: refresh the caches. */
void gs_swa_update(gs_swa_sim *s, size_t comp, size_t i, double w);
/* Add a particle (copied, time stamp now) standing for w / V real particles.
 * A full compartment contracts (model contraction):
 *  - GS_SWA_MERGE: two particles k, j (k uniform, j the closest in mass m(x) of
 *    a few uniform candidates) become one, x_k with probability
 *    w_k m_k / (w_k m_k + w_j m_j), else x_j, carrying weight
 *    (w_k m_k + w_j m_j) / m(kept): mass exact, every estimate unbiased, V kept,
 *    and the inflow weight scale gs_swa_gain grows by nmax / (nmax - 1);
 *  - GS_SWA_DROP (Lee et al. 2015): one of the nmax + 1 particles, the new one
 *    included, is dropped uniformly and V shrinks by nmax / (nmax + 1):
 *    unbiased, equal weights stay equal, mass kept only in expectation. */
int gs_swa_add(gs_swa_sim *s, size_t comp, const double *x, double w, gs_error *err);
/* Remove particle i (the last particle takes its index). */
void gs_swa_remove(gs_swa_sim *s, size_t comp, size_t i);
/* Index of a particle chosen with probability proportional to property
 * prop (uniformly when prop < 0); GS_NOWHERE if the compartment is empty. */
size_t gs_swa_select(gs_swa_sim *s, size_t comp, int prop);
double gs_swa_uniform01(gs_swa_sim *s);
/* Count one fictitious (rejected) event, for statistics. */
void gs_swa_fictitious(gs_swa_sim *s);
/* Fill the compartments from an SWA case's `initial` entries is done by the
 * case; this places n particles directly (tests, initial sampling). */
int gs_swa_sim_place(gs_swa_sim *s, size_t comp, const double *x, double w, gs_error *err);

typedef struct gs_swa_stats {
  uint64_t jumps;      /* events performed (accepted and fictitious) */
  uint64_t fictitious; /* rejected (fictitious) events */
  uint64_t doublings, contractions;
} gs_swa_stats;

/* Advance the run to time t_end (jumps, LPDA checkpoints, ensemble control). */
int gs_swa_sim_advance(gs_swa_sim *s, double t_end, gs_error *err);
/* Bring every particle up to the current time (LPDA checkpoint). */
void gs_swa_sim_sync(gs_swa_sim *s);
gs_swa_stats gs_swa_sim_stats(const gs_swa_sim *s);

/* ---- the discretisation report of a case ----------------------------------
 * Each distribution of a case (initial entries, feeds) as asked and as its
 * computational particles hold it: the initial entries as the runs sample
 * them (every run's particles, summed over the runs and divided by their
 * number: the ensemble the results start from), a feed as a sample of the
 * particles the runs are expected to feed (at most 10^6).  Sampling makes
 * the represented values random: sigma is the relative standard error a
 * sample of that many particles has (from the distribution's moments and
 * weights).  A case is refused when some quantity misses by more than
 * discretisation.tolerance AND by more than 5 sigma: a distortion that
 * sampling does not explain (docs/reliability.md). */
typedef struct gs_swa_disc {
  char key[160];                       /* "file:line: path" of the distribution */
  double number[2];                    /* requested, represented (per unit time for feeds) */
  double volume[GS_SWA_MAX_COORD][2];  /* of every coordinate: requested, represented */
  double sigma[1 + 2 * GS_SWA_MAX_COORD]; /* relative standard error: number, volumes, mean sizes */
  double particles;                    /* computational particles in the sample */
} gs_swa_disc;

/* ---- cases: `solver: {method: swa, ...}` ---------------------------------- */
typedef struct gs_swa_case {
  gs_cfg *cfg;
  char title[256];
  gs_grid grid;        /* output bins, compartments, axis names: the grid section of the case */
  gs_swa_model model;
  int *bin_coord;      /* coordinate of each grid axis */
  double t0;
  double *times;
  size_t ntimes;
  size_t runs;
  uint64_t seed;
  /* initial ensemble, per compartment: sampled particle specs (owned) */
  void *initial;
  double *sieves; /* solver.sieves: nsieve + 1 diameter edges, or NULL */
  size_t nsieve;  /* classes */
  gs_swa_disc *disc; /* the discretisation report, ndisc entries */
  size_t ndisc;
  double disc_tolerance; /* discretisation.tolerance */
} gs_swa_case;

/* One report of a case as a line for people (gransim check, the start of a
 * run): the key, what the particles hold against what was asked, the largest
 * relative error, the sampling error and the tolerance. */
void gs_swa_disc_format(const gs_swa_case *c, const gs_swa_disc *r, char *buf, size_t len);
/* Its largest relative error (number, volumes, mean sizes). */
double gs_swa_disc_error(const gs_swa_case *c, const gs_swa_disc *r);

/* True (1) if the case file's solver.method is "swa". */
int gs_swa_case_wanted(gs_cfg *cfg);
int gs_swa_case_from_cfg(gs_cfg *cfg, gs_swa_case *c, gs_error *err);
void gs_swa_case_free(gs_swa_case *c);
/* Sample the initial ensemble of the case into a fresh run. */
int gs_swa_case_init_run(const gs_swa_case *c, gs_swa_sim *s, gs_error *err);

/* Per-output statistics of a compartment, from the particles. */
typedef struct gs_swa_summary {
  double m0, m1, m2, d10, d50, d90;
  double mean[GS_SWA_MAX_COORD], total[GS_SWA_MAX_COORD];
} gs_swa_summary;
void gs_swa_summarize(gs_swa_sim *s, size_t comp, gs_swa_summary *out);
/* Mass fraction of compartment comp in each diameter class [edges[k], edges[k+1])
 * (diameter of the granule volume; mass = sum density * x), over the total mass. */
void gs_swa_sieve(gs_swa_sim *s, size_t comp, const double *edges, size_t nclass, double *frac);

typedef struct gs_swa_report {
  double wall_seconds;
  gs_swa_stats stats; /* summed over runs */
  size_t runs;
  /* with solver.sieves: mass fraction per sieve class, [time][comp][class],
   * ensemble mean and CI (malloc'ed; gs_swa_report_free) */
  double *sieve_mean, *sieve_ci;
} gs_swa_report;
void gs_swa_report_free(gs_swa_report *r);

/* Run all runs (OpenMP over runs), write DIR/result.h5 and DIR/summary.csv
 * (out_dir NULL: no files).  mean/ci (may be NULL) receive the ensemble mean
 * and CI half-width of every summary column: [time][comp][col], columns as
 * gs_swa_columns() lists.  Under MPI (gransim/parallel.h) it is collective:
 * every rank calls it, the runs are spread over the ranks, every rank gets
 * the same mean, ci, report and status (results identical for any number of
 * ranks and threads), and only rank 0 writes files and prints progress. */
int gs_swa_case_run(gs_swa_case *c, const char *out_dir, int progress, double *mean,
                    double *ci, gs_swa_report *rep, gs_error *err);
/* Number of summary columns (M0..d90, mean_*, total_*) and their names. */
int gs_swa_ncolumns(const gs_swa_model *m);
void gs_swa_column_name(const gs_swa_model *m, int col, char *buf, size_t n);

#ifdef __cplusplus
}
#endif
#endif
