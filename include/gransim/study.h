/* gransim — studies over many runs of one case: variations of a case by
 * dotted keys, designs (a full grid or a Latin hypercube) and the sweep that
 * runs them all and gathers one row of outputs per run.
 *
 * A variation sets scalars of the case's configuration tree at dotted paths
 * ("mechanisms.0.kernel.beta0", "solver.rtol", "output.end"); every run's
 * case is built from its own copy of the tree (gs_cfg_copy), so the case
 * reader validates a varied value exactly as if the file held it.  The whole
 * design is checked (keys exist, every run's case builds) before any run
 * starts. */
#ifndef GRANSIM_STUDY_H
#define GRANSIM_STUDY_H

#include <stddef.h>

#include "gransim/case.h"

#ifdef __cplusplus
extern "C" {
#endif

/* One varied key: a list of values (--set KEY=V1,V2,...) or a range
 * (--range KEY=LO:HI, or KEY=LO:HI:log for a range sampled uniformly in
 * log(value), LO > 0). */
typedef struct gs_study_axis {
  char *key;
  char **values; /* the listed values (text, set as written); NULL for a range */
  size_t nvalues;
  double lo, hi;
  int log;
} gs_study_axis;

/* Parse "KEY=V1,V2,..." / "KEY=LO:HI[:log]"; a clear GS_EINPUT for an empty
 * key or value, LO >= HI, a non-number or a log range with LO <= 0.  Free
 * with gs_study_axis_free (also after a failure). */
int gs_study_parse_set(const char *arg, gs_study_axis *a, gs_error *err);
int gs_study_parse_range(const char *arg, gs_study_axis *a, gs_error *err);
void gs_study_axis_free(gs_study_axis *a);

/* The runs of a study: nruns rows of nkeys values (text). */
typedef struct gs_design {
  size_t nkeys, nruns;
  char **keys;   /* dotted paths */
  char **values; /* values[run * nkeys + k] */
  double *unit;  /* Latin hypercube only: the point in [0,1)^nkeys of each run; NULL for a grid */
} gs_design;

/* Every combination of the listed values, the first axis varying slowest
 * (nested loops in the order given).  All axes must be lists. */
int gs_design_grid(const gs_study_axis *axes, size_t naxes, gs_design *d, gs_error *err);
/* A Latin hypercube of n points over ranges: every axis's range split into n
 * equal strata (in log(value) for log axes), each stratum holding exactly one
 * point, strata paired at random (GSL mt19937 seeded with seed: the same
 * seed gives the same design).  Values are written with 17 significant
 * digits, so that the text set into the case is the number drawn. */
int gs_design_lhs(const gs_study_axis *axes, size_t naxes, size_t n, unsigned long seed,
                  gs_design *d, gs_error *err);
/* A design of n given points x[n * naxes] (the values of the axes' keys,
 * written with 17 digits): the runs of a sensitivity analysis. */
int gs_design_values(const gs_study_axis *axes, size_t naxes, const double *x, size_t n,
                     gs_design *d, gs_error *err);
/* The value of a range axis at u in [0,1]: LO + (HI - LO) u, in log(value)
 * for a log range; clamped into [LO, HI] against rounding. */
double gs_study_axis_value(const gs_study_axis *a, double u);
void gs_design_free(gs_design *d);

/* The case of run r: a copy of base with the run's values set, built by the
 * case reader (which takes the copy over).  Errors name the run and its
 * values. */
int gs_study_case(const gs_cfg *base, const gs_design *d, size_t r, gs_case *c, gs_error *err);

/* The outputs gathered per run, at the final output time: M0 (number, all
 * compartments), M1_<coordinate> (total volume of each volume coordinate, all
 * compartments), d10_c<j>, d50_c<j>, d90_c<j> per compartment j (1-based, as
 * in summary.csv), then for every extra summary column NAME (M0, M1, M2, d10,
 * d50, d90, mean_<coordinate>, total_<coordinate>, porosity, liquid_content,
 * a mechanism's column such as bed_temperature) NAME_c<j> per compartment. */
typedef struct gs_study_outputs {
  size_t ncol;
  char **names;
  const char **units; /* per column: its SI unit ("1": dimensionless), summary.csv's */
  int *what;    /* per column: which statistic (internal code) */
  int *index;   /* volume coordinate, where the statistic has one */
  size_t *comp; /* compartment, where it has one */
  size_t ncomp; /* the shape the columns were made for */
  int nvol;
  int nmech_col; /* the mechanisms' summary columns (gs_model_ncolumns) */
  /* With earlier output times (gs_study_outputs_add_times): the first nbase
   * columns are at the final time, then the same nbase columns at each of
   * times[0..ntimes), named NAME@T. */
  size_t nbase, ntimes;
  double *times;
} gs_study_outputs;

/* The SI unit of a case key a study varies, from the last name of the
 * dotted key that is not a list index (docs/case-files.md, "Units of the
 * keys": output.end s, solver.rtol 1); GS_STUDY_CASE_UNIT where it depends
 * on the model (beta0, s0, a `rate`, a grid's `min`) or the name is not in
 * the table: the unit the case file gives the key. */
#define GS_STUDY_CASE_UNIT "case"
const char *gs_study_key_unit(const char *key);

int gs_study_outputs_init(gs_study_outputs *o, const gs_model *m, const char *const *extra,
                          size_t nextra, gs_error *err);
/* GS_EINPUT when model m does not have the shape o was made for (a
 * variation that changes the compartments or the volume coordinates). */
int gs_study_outputs_fit(const gs_study_outputs *o, const gs_model *m, gs_error *err);
/* values[0..ncol) from the state y (full layout) of model m at time t. */
void gs_study_outputs_eval(const gs_study_outputs *o, const gs_model *m, double t, const double *y,
                           double *values);
/* Repeat the columns at each of times[0..n) (seconds, each an output time of
 * every run's case; checked by gs_study_outputs_times_fit), named NAME@T. */
int gs_study_outputs_add_times(gs_study_outputs *o, const double *times, size_t n, gs_error *err);
/* GS_EINPUT when one of o's times is not an output time of case times[0..n). */
int gs_study_outputs_times_fit(const gs_study_outputs *o, const double *times, size_t n, gs_error *err);
/* The columns of slot k (0: the final time, k: o->times[k - 1]) from the
 * state y at time t into values[0..nbase). */
void gs_study_outputs_eval_slot(const gs_study_outputs *o, const gs_model *m, size_t k, double t,
                                const double *y, double *values);
void gs_study_outputs_free(gs_study_outputs *o);

typedef struct gs_sweep_options {
  const char *out_dir; /* DIR: base-case.yaml, runs.csv (the journal), sweep.csv, sweep.h5 */
  int resume;          /* skip the runs DIR/runs.csv records as finished */
  const char *const *outputs; /* extra summary columns (see gs_study_outputs) */
  size_t noutputs;
  const double *at; /* the outputs also at these output times [s] (NAME@T columns) */
  size_t nat;
  int threads; /* runs at once (0: omp_get_max_threads()); each run single-threaded */
  int progress; /* a line on stderr as runs finish: -1 when stderr is a terminal, 0 off, 1 on */
} gs_sweep_options;

typedef struct gs_sweep_report {
  size_t runs;    /* in the design */
  size_t skipped; /* finished before (resume) */
  size_t ran;     /* run now */
  size_t failed;  /* of all runs, recorded with status error */
} gs_sweep_report;

/* Check every run's case, then run those not yet finished (OpenMP over
 * runs), appending each run's row to DIR/runs.csv as it finishes (one
 * write() of a whole line: a killed sweep leaves whole rows, and --resume
 * drops a torn last line), then write DIR/sweep.csv (rows in run order)
 * and DIR/sweep.h5 (the same table, a dataset per column), each under a
 * temporary name renamed into place.  A run that fails (numerics,
 * checks) is a row with status error and its message; the others go on.
 * DIR/base-case.yaml keeps the case file as read; a resume with a case
 * file that differs is refused.  Under MPI the ranks share the unfinished
 * runs and rank 0 writes the tables.  Returns an error only when the sweep
 * itself cannot go on (a bad variation, files). */
int gs_sweep_run(const gs_cfg *base, const gs_design *d, const gs_sweep_options *opt,
                 gs_sweep_report *rep, gs_error *err);

/* ---- fitting ------------------------------------------------------------
 * Measured data of one batch: a CSV with a header "time,NAME,..." (units in
 * brackets after a name are dropped: "d50 [m]") and one row per time, the
 * times increasing; NAME is an output column as above (M0, M1_<coordinate>,
 * d50_c1, M2_c1, mean_liquid_c2, porosity_c1, ...; in a case of one
 * compartment also without the _c1) or a sieve class sieve_<LO>_<HI>[_c<j>]
 * (edges in micrometres, HI may be inf: the volume fraction of the
 * compartment's granules in [LO, HI), gs_sieve_fractions).  Every data time
 * must be an output time of the case (list them in output.times); the
 * time of the last row may be "end", the run's last output time whatever
 * it is (times[] holds INFINITY), so that a control may move the end.
 * Errors name the file, line and column. */
typedef struct gs_fit_data {
  size_t ntimes, ncols;
  double *times;  /* ntimes */
  char **names;   /* ncols */
  double *values; /* values[time * ncols + col] */
  char *path;     /* for messages */
  size_t header_line;
  size_t *lines; /* the file's line of each time */
} gs_fit_data;
int gs_fit_data_read(const char *path, gs_fit_data *d, gs_error *err);
void gs_fit_data_free(gs_fit_data *d);

/* 1 when name is a sieve column sieve_<LO>_<HI>[_c<j>] with 0 <= LO < HI
 * (micrometres): *lo, *hi in metres, *comp j (0 when not given); 0 when
 * name is no sieve column; -1 when it starts so but is malformed. */
int gs_fit_sieve_column(const char *name, double *lo, double *hi, size_t *comp);

/* A batch: key overrides of the case (its recipe) and its measured data. */
typedef struct gs_fit_batch {
  char *name;
  char *where; /* "FILE:LINE" of its entry, for messages */
  size_t nset;
  char **keys, **values; /* dotted keys and their values (text, set as written) */
  int *key_lines;
  gs_fit_data data;
} gs_fit_batch;

/* The batches of a fit (a YAML file):
 *   sieves: [0, 53.0e-6, 106.0e-6, ..., .inf]   # optional, metres
 *   batches:
 *     - {name: B3, data: b3.csv, set: {KEY: VALUE, ...}}
 * data paths relative to the file.  With sieves, every sieve column must
 * be one of their classes. */
typedef struct gs_fit_batches {
  char *path;
  size_t n;
  gs_fit_batch *batch;
  double *sieves; /* nsieves edges [m], or NULL */
  size_t nsieves;
  int sieves_line;
} gs_fit_batches;
int gs_fit_batches_read(const char *path, gs_fit_batches *bs, gs_error *err);
/* One batch: the case as it is, with the data file path. */
int gs_fit_batches_single(const char *data_path, gs_fit_batches *bs, gs_error *err);
void gs_fit_batches_free(gs_fit_batches *bs);

typedef struct gs_fit_result {
  size_t nparams, nresid;
  double *x;        /* the estimates */
  double *stderr_x; /* standard errors from the Jacobian at the estimates (see gs_fit_run_batches) */
  double *ci_lo, *ci_hi; /* 95 % confidence intervals x -+ t(0.975, n - p) stderr_x */
  double *corr;     /* correlations, nparams x nparams */
  double *sv;       /* singular values of the scaled Jacobian (in the mapped variables), descending */
  int *unidentified; /* per parameter: 1 when it is not identifiable from the data (see gs_fit_run) */
  double chi2;      /* sum of squared scaled residuals */
  double r2;        /* 1 - chi2 / (sum of squared scaled deviations from each column's mean) */
  size_t iterations;
  int converged; /* 0: stopped at the iteration limit or without progress */
  long runs;     /* model runs, all phases */
  long global_runs;    /* of them in the global start */
  double porosity_rms; /* the porosity columns' RMS error at the estimates (their unit); nan without */
} gs_fit_result;

/* How a fit searches (NULL or all zero: least squares from the case's values). */
typedef struct gs_fit_options {
  const char *global;  /* crs2 | mlsl | isres: a global search over the ranges (NLopt) first,
                          the least squares (or the constrained fit) from its best point */
  size_t global_runs;  /* its model runs (0: 50 per parameter) */
  unsigned long seed;  /* of the global search */
  double porosity_tol; /* > 0: the epsilon-constraint: the squared scaled residuals of all
                          columns but porosity least subject to the porosity columns' RMS
                          error <= porosity_tol (NLopt COBYLA instead of the least squares) */
  size_t max_runs;     /* of the constrained fit (0: 2000) */
} gs_fit_options;

/* Least squares (GSL multifit_nlinear, trust region, Levenberg-Marquardt)
 * of the case's outputs at the data's times against the data, over the
 * parameters' ranges (axes from gs_study_parse_range; each kept inside its
 * range by a logistic map, in log for log ranges), all batches' residuals
 * in one problem, each batch run with its own key overrides.  Residuals are
 * (model - data) / scale of the column: the RMS of the column's values over
 * all batches, one scale shared by every sieve column (their sum of
 * squares is the PSD's), so columns of different units weigh alike.  The
 * start is the case's own value where it lies inside the range, else the
 * range's middle.  The Jacobian is by forward differences, its p runs at
 * once on the threads.  Data, keys and times are checked before the fit
 * runs: errors name the file, line and column. */
int gs_fit_run_batches(const gs_cfg *base, const gs_study_axis *params, size_t np,
                       const gs_fit_batches *bs, const gs_fit_options *opt, gs_fit_result *res,
                       gs_error *err);
/* The same with one batch: the case as it is. */
int gs_fit_run(const gs_cfg *base, const gs_study_axis *params, size_t np,
               const gs_fit_data *data, gs_fit_result *res, gs_error *err);
void gs_fit_result_free(gs_fit_result *r);
/* GS_EINPUT naming the methods when method is not one of --global's. */
int gs_fit_global_check(const char *method, gs_error *err);

/* The case at parameter values x against batches (fitted or held out):
 * the model's value of every data value and the scaled residuals, batch
 * after batch in the data's order ([time][column]), with the same checks
 * and scales as the fit; x NULL: the checks alone (nothing run). */
typedef struct gs_fit_eval {
  size_t nresid;
  double *model, *resid;
  const char **unit; /* per value: its column's SI unit (static strings) */
  double chi2, r2;
} gs_fit_eval;
int gs_fit_evaluate(const gs_cfg *base, const gs_study_axis *params, size_t np, const double *x,
                    const gs_fit_batches *bs, gs_fit_eval *ev, gs_error *err);
void gs_fit_eval_free(gs_fit_eval *ev);

/* DIR/estimates.csv (a row per parameter: estimate, standard error,
 * interval, range, identifiable) and DIR/fitted.csv (a row per measured
 * value of the fitted batches, role fit, and of the held-out ones, role
 * predict, if pred is not NULL: measured and model value, the sieve class's
 * edges), each with its JSON sidecar; DIR is made if missing. */
int gs_fit_write(const char *dir, const gs_study_axis *params, size_t np, const gs_fit_result *res,
                 const gs_fit_batches *fit, const gs_fit_eval *fit_ev, const gs_fit_batches *pred,
                 const gs_fit_eval *pred_ev, gs_error *err);

/* ---- optimisation --------------------------------------------------------
 * Controls (dotted keys over ranges) chosen so that the case's outputs at a
 * target's times come closest to the target (a CSV as gs_fit_data):
 * minimises sum_j w_j sum_t ((model - target) / RMS_j)^2, RMS_j the target
 * column's RMS (columns of different units weigh alike), w_j the weights. */
typedef enum gs_opt_method {
  GS_OPT_NELDER_MEAD = 1, /* GSL nmsimplex2 over the logistic map of each range */
  GS_OPT_BOUNDED = 2      /* NLopt BOBYQA inside the box (each range mapped to [0,1]) */
} gs_opt_method;

typedef struct gs_opt_options {
  gs_opt_method method;
  const double *weights; /* per target column; NULL: all 1 */
  size_t max_runs;       /* model runs at most (0: 4000) */
  double tol;            /* stop when the step (in [0,1] units of the ranges) is below (0: 1e-9) */
} gs_opt_options;

typedef struct gs_opt_result {
  size_t ncontrols;
  double *x;        /* the controls found */
  double objective; /* at x */
  double start_objective;
  long runs;
  long failed_runs;       /* trial runs that failed (treated as very bad points) */
  gs_error first_failure; /* the first one's message */
  int converged;          /* 0: stopped at max_runs, or by round-off (see stop) */
  const char *stop;       /* why the method stopped, in words (static text) */
} gs_opt_result;

/* GS_EINPUT for no controls, a list instead of a range, a negative weight,
 * unknown keys or target columns (before any run). */
int gs_optimise_run(const gs_cfg *base, const gs_study_axis *controls, size_t nc,
                    const gs_fit_data *target, const gs_opt_options *opt, gs_opt_result *res,
                    gs_error *err);
void gs_opt_result_free(gs_opt_result *r);

/* ---- global sensitivity ------------------------------------------------
 * Variance-based (Sobol') indices by Saltelli sampling and Morris's
 * elementary-effects screening, over ranges (axes from gs_study_parse_range)
 * of any model given as a callback, so that the estimators are tested on
 * analytic functions and a case runs through the sweep. */
typedef enum gs_sens_method { GS_SENS_SOBOL = 1, GS_SENS_MORRIS = 2 } gs_sens_method;

/* The model at npoints points x[npoints * nin] (values inside the ranges):
 * y[npoints * nout].  Called once with every point of the analysis, so an
 * implementation may run them in parallel. */
typedef int (*gs_sens_model)(void *ctx, size_t npoints, size_t nin, const double *x, size_t nout,
                             double *y, gs_error *err);

typedef struct gs_sens_options {
  gs_sens_method method;
  size_t n;           /* Sobol: base sample N (N (k+2) runs); Morris: trajectories R (R (k+1) runs) */
  int levels;         /* Morris: grid levels p, even (0: 4) */
  size_t nboot;       /* Sobol: bootstrap resamples for the intervals (0: 500) */
  double conf;        /* level of the intervals (0: 0.95) */
  unsigned long seed; /* random shift of the Sobol' sequence, bootstrap, Morris trajectories */
} gs_sens_options;

typedef struct gs_sens_result {
  gs_sens_method method;
  size_t nin, nout, runs;
  double conf;
  /* Sobol: [out * nin + k]; first-order S1 and total ST with percentile
   * bootstrap intervals [lo, hi] */
  double *s1, *s1_lo, *s1_hi, *st, *st_lo, *st_hi;
  /* Morris: [out * nin + k]; mean elementary effect, mean of |effects|,
   * their standard deviation (effects per unit of the range) */
  double *mu, *mu_star, *sigma;
  /* per output: its SI unit (gs_sensitivity_case; NULL from gs_sensitivity,
   * whose model's units gransim does not know) */
  char **unit;
} gs_sens_result;

/* Runs the analysis: GS_EINPUT for no keys, a list instead of a range, N
 * too small (Sobol N >= 16, Morris R >= 2), too many keys (Sobol <= 20: the
 * Sobol' sequence has 40 dimensions), an odd p; a model error or a
 * non-finite output fails it. */
int gs_sensitivity(const gs_study_axis *axes, size_t nin, size_t nout, gs_sens_model model,
                   void *ctx, const gs_sens_options *opt, gs_sens_result *res, gs_error *err);
/* The same with the case's outputs (sweep output columns, as gs_fit_data
 * names them: d50_c1, M0, ...; with one compartment d50 for d50_c1) at the
 * final time as the model: all points run as one sweep into sweep->out_dir
 * (resumable; sweep->outputs is ignored).  Unknown keys and columns are
 * refused before any run. */
int gs_sensitivity_case(const gs_cfg *base, const gs_study_axis *axes, size_t nin,
                        const char *const *outputs, size_t nout, const gs_sens_options *opt,
                        const gs_sweep_options *sweep, gs_sens_result *res, gs_error *err);
/* A CSV, its header first: Sobol "output,key,S1 [1],S1_lo [1],S1_hi [1],
 * ST [1],ST_lo [1],ST_hi [1]", Morris "output,key,mu [unit],mu_star [unit],
 * sigma [unit],unit" (the effects are in the output's unit, the row's
 * `unit`, per range of the key); a row per output and key; what the columns
 * mean in the JSON sidecar PATH.json (path ends in .csv). */
int gs_sens_write_csv(const char *path, const gs_sens_result *r, const gs_study_axis *axes,
                      const char *const *outputs, gs_error *err);
void gs_sens_result_free(gs_sens_result *r);

#ifdef __cplusplus
}
#endif
#endif
