/* Helpers shared by the study layer's fit, optimisation and sensitivity
 * (not part of the public API). */
#ifndef GRANSIM_STUDY_INTERNAL_H
#define GRANSIM_STUDY_INTERNAL_H

#include "gransim/study.h"

/* Every extra statistic a study may name (M0 M1 M2 d10 d50 d90, then
 * mean_<coordinate> and total_<coordinate> per volume coordinate of m, then
 * porosity and moisture where m has coordinates solid and liquid): names
 * point into buf; returns how many (at most GS_STUDY_MAX_EXTRA). */
#define GS_STUDY_MAX_EXTRA 24
typedef struct {
  const char *name[GS_STUDY_MAX_EXTRA];
  char buf[16][80];
  size_t n;
} gs_study_extras;
void gs_study_extras_all(const gs_model *m, gs_study_extras *x);

/* The column of output o called name (a sweep column; with one compartment
 * also without the _c1); GS_EINPUT naming the known columns otherwise.
 * what says what the name is ("data column", "--outputs"). */
int gs_study_outputs_find(const gs_study_outputs *o, const char *name, const char *what,
                          size_t *col, gs_error *err);

/* A study table's header field: "NAME [UNIT]", as summary.csv's. */
void gs_study_header(const char *name, const char *unit, char *buf, size_t n);

/* The logistic map from an unbounded z to (LO, HI) (in log for log ranges),
 * so that every trial point of an unconstrained method is a valid case;
 * *dxdz (if not NULL) its derivative.  gs_study_to_z is its inverse. */
double gs_study_to_x(const gs_study_axis *a, double z, double *dxdz);
double gs_study_to_z(const gs_study_axis *a, double x);

/* Case outputs at measured times as residuals (model - data) / scale of
 * the column, batch after batch: fit's least squares and optimise's
 * objective. */
#define GS_FIT_SIEVE ((size_t)-1)
typedef struct {
  size_t *col;   /* per data column: its output column, or GS_FIT_SIEVE */
  double *sieve; /* per data column: the class's lo, hi diameters [m] (sieve columns) */
  size_t *comp;  /* per data column: the compartment of a sieve column (0-based) */
  double *scale; /* per data column */
  char *porosity; /* per data column: 1 for a porosity column (the epsilon-constraint's) */
  size_t off;    /* the batch's first residual */
} gs_fit_map;

typedef struct {
  const gs_cfg *base;
  const gs_study_axis *params;
  size_t np;
  const gs_fit_batches *bs;
  gs_fit_map *map; /* per batch */
  size_t nresid;
  gs_study_outputs out;
  long runs;
  gs_error err; /* the first failed model evaluation */
} gs_fit_problem;
/* Checks the parameters' keys, the batches' keys, times and columns against
 * the case (errors name the file, line and column); x0: the start, the
 * case's own values where they lie inside the ranges, else the ranges'
 * middles. */
int gs_fit_problem_init(gs_fit_problem *fc, const gs_cfg *base, const gs_study_axis *params,
                        size_t np, const gs_fit_batches *bs, double *x0, gs_error *err);
/* r[nresid] at parameter values x[np] (one run of the case per batch);
 * model (if not NULL) gets the model's values in the same layout. */
int gs_fit_problem_residuals(gs_fit_problem *fc, const double *x, double *r, double *model,
                             gs_error *err);
void gs_fit_problem_free(gs_fit_problem *fc);
/* Reads DIR/runs.csv left by an earlier sweep (path): checks its header
 * against this sweep's and that every row's values are this design's, keeps
 * the whole rows (row[r] for run r + 1, with its newline; d->nruns entries,
 * rows already there are kept) and cuts a torn last line (a write a kill
 * interrupted) off the file; an empty or torn header leaves it empty (the
 * caller writes the header again).  *nfinished counts the rows taken. */
int gs_sweep_journal_read(const char *path, const char *header, const gs_design *d, char **row,
                          size_t *nfinished, gs_error *err);

/* R² of the scaled values: 1 - chi2 over their sum of squares about the
 * mean of each column name over all batches. */
double gs_fit_problem_r2(const gs_fit_problem *fc, double chi2);

/* NLopt phases of a fit (fit_nlopt.c), in u, the parameters' fractions of
 * their ranges.  The global start: method crs2, mlsl or isres over the box
 * with at most max_runs runs (the seed fixes the search), u set to the
 * best point; gs_fit_global_check refuses an unknown method.  The
 * epsilon-constrained fit: COBYLA from u, minimising the squared scaled
 * residuals of every column but porosity, subject to the RMS error of the
 * porosity columns (in their unit) at most eps; u set to the best feasible
 * point, *rms_porosity its porosity error. */
int gs_fit_global_start(gs_fit_problem *fc, const char *method, size_t max_runs,
                        unsigned long seed, double *u, gs_error *err);
int gs_fit_eps_constrained(gs_fit_problem *fc, double eps, size_t max_runs, double *u,
                           double *rms_porosity, gs_error *err);
#endif
