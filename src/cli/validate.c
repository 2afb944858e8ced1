/* gransim validate: grid-refinement study of the sectional engine against
 * the analytical solutions of docs/validation.md (T1-T7), for the cell-average
 * and fixed-pivot techniques.  Writes a markdown report (default
 * docs/validation.md).  Every case is an ordinary case file built from a
 * template, so the report is also a test of the case-file path.
 *
 * Exit status: 0 when every run of the study finished and the published-error
 * target of issue 2 (Vale & McKenna case 1) is met; 1 when a run failed or the
 * target was missed (the report is written either way and says which); 2 on a
 * usage error. */
#include <errno.h>
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/utsname.h>
#include <time.h>

#include <gsl/gsl_errno.h>
#include <gsl/gsl_integration.h>

#include "cli/commands.h"
#include "cli/options.h"
#include "gransim/case.h"
#include "gransim/run.h"

#define MAXMOM 10
#define MAXCELLS 5

typedef struct {
  const char *id, *title;
  int dim;
  double t_end;
  /* The grid.  1-D: axis v, edges [0, lo, lo r, ...] (zero_first) up to at
   * least hi, refined by the ratio r = 2^(1/q), q = levels[k] (Kumar &
   * Ramkrishna's grids); with first_pivot_one, no zero-width first cell and
   * lo = 2/(1+r), so that the first pivot is 1.  2-D: the printf template
   * grid2d taking the number of cells per axis, levels[k]. */
  double lo, hi;
  int first_pivot_one;
  const char *grid2d;
  /* initial + mechanisms: a printf template whose only argument is the
   * redistribution scheme (%1$s, may appear several times). */
  const char *body;
  int nmom;
  int powers[MAXMOM][2];
  const char *mom_names[MAXMOM];
  void (*exact)(double t, double *m);
  int levels[MAXCELLS];
  const char *note; /* printed under the table, or NULL */
} study_t;

/* ---- exact moments (the analytic solutions of docs/validation.md) ---------- */
static void t1_exact(double t, double *m) { m[0] = 2 / (2 + t); m[1] = 1; m[2] = 2 + t; }
/* T1 discrete, c_1(0) = 1 at v = 1: M2 = M2(0) + beta0 M1^2 t */
static void t1d_exact(double t, double *m) { m[0] = 2 / (2 + t); m[1] = 1; m[2] = 1 + t; }
static void t2_exact(double t, double *m) { m[0] = exp(-t); m[1] = 1; m[2] = 2 * exp(2 * t); }
static void t3_exact(double t, double *m) { m[0] = 1 - 0.5 * t; m[1] = 1; m[2] = 2 / (1 - 2 * t); }
static void t4_exact(double t, double *m) { m[0] = 1 + t; m[1] = 1; m[2] = 2 / (1 + t); }

/* T4, S = v^2, exponential IC: n = [1 + 2t(1 + v)] exp(-t v^2 - v); its
 * moments by adaptive quadrature (GSL QAGIU, relative tolerance 1e-12). */
typedef struct { double t; int p; } t4b_par;
static double t4b_integrand(double v, void *q) {
  const t4b_par *a = q;
  return pow(v, a->p) * (1 + 2 * a->t * (1 + v)) * exp(-a->t * v * v - v);
}
static void t4b_exact(double t, double *m) {
  gsl_integration_workspace *ws = gsl_integration_workspace_alloc(1000);
  for (int p = 0; p < 3; p++) {
    t4b_par a = {t, p};
    gsl_function F = {t4b_integrand, &a};
    double r = NAN, e;
    gs_gsl_clear();
    if (!ws || gsl_integration_qagiu(&F, 0, 0, 1e-12, 1000, ws, &r, &e)) {
      /* the case's reference is then unknown: its comparison fails, and says why */
      fprintf(stderr, "gransim validate: T4b: the reference moment M%d at t = %g: GSL: %s\n", p, t,
              ws ? gs_gsl_reason() : "out of memory");
      r = NAN;
    }
    m[p] = r;
  }
  gsl_integration_workspace_free(ws);
}
static void t6_exact(double t, double *m) {
  double m0 = 2 / (2 + t), m1 = exp(0.5 * t);
  m[0] = m0; m[1] = m1; m[2] = 2 * m1 * m1 / m0;
}
static void t8_exact(double t, double *m) { /* n0 = exp(-v) shifted by G t, G = 1 */
  m[0] = 1; m[1] = 1 + t; m[2] = 2 + 2 * t + t * t;
}
static void t5_exact(double t, double *m) { /* beta0 = 1, S0 = 0.5, M1 = 1, N0 = 1 */
  double Ninf = 1.0, th = tanh(0.5 * Ninf * t);
  double N = Ninf * (1 + Ninf * th) / (Ninf + th);
  m[0] = N; m[1] = 1; m[2] = 2 / N;
}
/* T7 (a): exponential-product IC, N0 = 1, x0 = 1, y0 = 5.  From the general
 * constant-kernel solution n = (N0/l^2) sum_k r^(k-1) g^{*k}, l = 1 + tau/2,
 * r = tau/(tau+2), with the moments of sums of k exponentials:
 * M30 = (3/2) x0^3 (tau+2)^2, M21 = (1/2) x0^2 y0 (3 tau + 2)(tau + 2). */
static void t7a_exact(double tau, double *m) {
  const double a = 1, b = 5;
  m[0] = 2 / (tau + 2);
  m[1] = a; m[2] = b;
  m[3] = a * b * (1 + tau);
  m[4] = a * a * (2 + tau); m[5] = b * b * (2 + tau);
  m[6] = 1.5 * a * a * a * (tau + 2) * (tau + 2); m[7] = 1.5 * b * b * b * (tau + 2) * (tau + 2);
  m[8] = 0.5 * a * a * b * (3 * tau + 2) * (tau + 2); m[9] = 0.5 * a * b * b * (3 * tau + 2) * (tau + 2);
}
static void vm_exact(double tau, double *m) { /* Vale & McKenna case 1: N0 = 1, m10 = 1, m20 = 5 */
  const double a = 1, b = 5;
  m[0] = 2 / (tau + 2);
  m[1] = a; m[2] = b;
  m[3] = a * b * (1 + tau);
  m[4] = 0.5 * a * a * (2 * tau + 3); m[5] = 0.5 * b * b * (2 * tau + 3);
  m[6] = 1.5 * a * a * a * (tau + 1) * (tau + 2); m[7] = 1.5 * b * b * b * (tau + 1) * (tau + 2);
  m[8] = 0.5 * a * a * b * (3 * tau * tau + 7 * tau + 3); m[9] = 0.5 * a * b * b * (3 * tau * tau + 7 * tau + 3);
}

#define ONE_D_MOMENTS 3, {{0, 0}, {1, 0}, {2, 0}}, {"M0", "M1", "M2"}
#define TWO_D_MOMENTS                                                                    \
  10, {{0, 0}, {1, 0}, {0, 1}, {1, 1}, {2, 0}, {0, 2}, {3, 0}, {0, 3}, {2, 1}, {1, 2}}, \
      {"M00", "M10", "M01", "M11", "M20", "M02", "M30", "M03", "M21", "M12"}
#define RATIO_LEVELS {1, 2, 4, 8, 0}
#define GRID_VM                                                                     \
  "grid:\n  axes:\n"                                                                \
  "    - {name: x1, type: geometric, min: 0.01, max: 4000, cells: %1$d, zero_first: true}\n" \
  "    - {name: x2, type: geometric, min: 0.05, max: 20000, cells: %1$d, zero_first: true}\n"
/* Volume allowed to leave a grid before a run fails (checks.max_loss); the
 * grids are chosen so that no run comes near it.  --max-loss overrides it
 * (e.g. to see the failure path). */
static double max_loss = 1e-3;
static const char *const solver_1d = "solver: {method: rk, rtol: 1.0e-9, atol: 1.0e-16}\n";
static const char *const solver_2d = "solver: {method: rk, rtol: 1.0e-7, atol: 1.0e-14}\n";

static const study_t studies[] = {
    {"T1", "constant kernel, exponential IC, tau = beta0 N0 t = 100", 1, 100,
     1e-4, 1e5, 0, NULL,
     "initial: {type: exponential, number: 1, mean: 1}\n"
     "mechanisms: [{type: aggregation, redistribution: %1$s, kernel: {type: constant, beta0: 1}}]\n",
     ONE_D_MOMENTS, t1_exact, RATIO_LEVELS, NULL},
    {"T1d", "constant kernel, discrete monodisperse IC (all particles of size 1), tau = 100", 1, 100,
     0, 1e5, 1, NULL,
     "initial: {type: cell, number: 1, index: [1]}\n"
     "mechanisms: [{type: aggregation, redistribution: %1$s, kernel: {type: constant, beta0: 1}}]\n",
     ONE_D_MOMENTS, t1d_exact, RATIO_LEVELS,
     "Grid without the cell [0, min]: min = 2/(1 + r), so that the first pivot is the monomer size 1;\n"
     "the exact moments are those of the discrete solution, M0 = 2/(2 + tau), M2 = 1 + tau.\n"},
    {"T2", "sum kernel, exponential IC, beta0 M1 t = 2", 1, 2,
     1e-4, 1e7, 0, NULL,
     "initial: {type: exponential, number: 1, mean: 1}\n"
     "mechanisms: [{type: aggregation, redistribution: %1$s, kernel: {type: sum, beta0: 1}}]\n",
     ONE_D_MOMENTS, t2_exact, RATIO_LEVELS,
     "The grid reaches 1e7 (the solution holds no measurable volume beyond ~1e4): on the ratio-2\n"
     "grid the fixed-pivot solution over-predicts the large sizes so much that with a grid ending\n"
     "at 1e5 it loses 3e-5 of the volume (and failed the 1e-3 loss check on the 20-cell grid of\n"
     "earlier reports, ratio 2.97); at 1e7 it loses 4e-10.\n"},
    {"T3", "product kernel, exponential IC, t = 0.8 t_gel", 1, 0.4,
     1e-4, 1e6, 0, NULL,
     "initial: {type: exponential, number: 1, mean: 1}\n"
     "mechanisms: [{type: aggregation, redistribution: %1$s, kernel: {type: product, beta0: 1}}]\n",
     ONE_D_MOMENTS, t3_exact, {2, 4, 8, 16, 0},
     "The refinement starts at ratio 2^(1/2): on the ratio-2 grid the fixed-pivot solution gels\n"
     "numerically before t = 0.8 t_gel (it over-predicts M2, Kumar et al. 2006), and about 0.2 % of\n"
     "the volume runs off the end of the grid by t = 0.4 whether the grid ends at 1e5, 1e6 or 1e7\n"
     "(measured when the study was set up), so no grid range keeps that run on the grid.\n"},
    {"T4", "binary breakage, S = v, uniform daughters, exponential IC, t = 10", 1, 10,
     1e-6, 100, 0, NULL,
     "initial: {type: exponential, number: 1, mean: 1}\n"
     "mechanisms: [{type: breakage, redistribution: %1$s, selection: {type: power, s0: 1, exponent: 1}, daughters: {type: uniform}}]\n",
     ONE_D_MOMENTS, t4_exact, RATIO_LEVELS, NULL},
    {"T4b", "binary breakage, S = v^2, uniform daughters, exponential IC, t = 10", 1, 10,
     1e-6, 40, 0, NULL,
     "initial: {type: exponential, number: 1, mean: 1}\n"
     "mechanisms: [{type: breakage, redistribution: %1$s, selection: {type: power, s0: 1, exponent: 2}, daughters: {type: uniform}}]\n",
     ONE_D_MOMENTS, t4b_exact, RATIO_LEVELS,
     "Exact moments by quadrature of n = [1 + 2t(1 + v)] exp(-t v^2 - v). The grid ends at 40 (the\n"
     "initial volume beyond it is 2e-16): S = v^2 makes the largest cells stiff for the explicit\n"
     "integrator, hence the RHS counts.\n"},
    {"T5", "aggregation (beta0 = 1) + breakage (S = 0.5 v, uniform), t = 10 (near steady state)", 1, 10,
     1e-6, 200, 0, NULL,
     "initial: {type: exponential, number: 1, mean: 1}\n"
     "mechanisms:\n"
     "  - {type: aggregation, redistribution: %1$s, kernel: {type: constant, beta0: 1}}\n"
     "  - {type: breakage, redistribution: %1$s, selection: {type: power, s0: 0.5, exponent: 1}, daughters: {type: uniform}}\n",
     ONE_D_MOMENTS, t5_exact, RATIO_LEVELS, NULL},
    {"T6", "constant-kernel aggregation + linear growth G = 0.5 v, t = 2", 1, 2,
     1e-4, 1e4, 0, NULL,
     "initial: {type: exponential, number: 1, mean: 1}\n"
     "mechanisms:\n"
     "  - {type: aggregation, redistribution: %1$s, kernel: {type: constant, beta0: 1}}\n"
     "  - {type: growth, axis: v, linear: 0.5}\n",
     ONE_D_MOMENTS, t6_exact, RATIO_LEVELS, NULL},
    {"T8", "layering at constant rate G = 1 (external powder), exponential IC, t = 1", 1, 1,
     1e-4, 100, 0, NULL,
     "initial: {type: exponential, number: 1, mean: 1}\n"
     "mechanisms: [{type: layering, axis: v, source: external, max_rate: 1}]\n",
     ONE_D_MOMENTS, t8_exact, RATIO_LEVELS,
     "n(v, t) = n0(v - G t): M0 and M1 = M0 (1 + G t) are exact for the upwind pivot transfer (the\n"
     "errors left are the initial distribution's on the pivots); M2 carries its numerical diffusion,\n"
     "a variance growing by about G t times the local pivot spacing, which refinement removes.\n"
     "No redistribution takes part: the CA and FP rows are the same run.\n"},
    {"T7a", "2-D constant kernel, exponential-product IC (x0 = 1, y0 = 5), tau = 100", 2, 100,
     0, 0, 0, GRID_VM,
     "initial: {type: exponential, number: 1, mean: [1, 5]}\n"
     "mechanisms: [{type: aggregation, redistribution: %1$s, kernel: {type: constant, beta0: 1}}]\n",
     TWO_D_MOMENTS, t7a_exact, {20, 30, 40, 50, 0},
     "Exact moments from the general constant-kernel solution (T1):\n"
     "M30 = (3/2) x0^3 (tau + 2)^2, M21 = (1/2) x0^2 y0 (3 tau + 2)(tau + 2). The M10/M01 errors\n"
     "of 8e-6 % are those of the initial distribution: in the first cell [0, min] the exponential's\n"
     "mean is not the pivot (docs/case-files.md, distribution specs); the runs conserve them.\n"},
    {"T7b", "Vale & McKenna case 1 (2-D constant kernel), tau = 100", 2, 100,
     0, 0, 0, GRID_VM,
     "initial: {type: gamma, number: 1, mean: [1, 5], shape: [2, 2]}\n"
     "mechanisms: [{type: aggregation, redistribution: %1$s, kernel: {type: constant, beta0: 1}}]\n",
     TWO_D_MOMENTS, vm_exact, {20, 30, 40, 50, 0}, NULL},
};
#define NSTUDIES (sizeof studies / sizeof studies[0])

static double now(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* The grid section of a study at refinement level `level`; the number of
 * cells per axis and the (first axis') ratio in *cells, *ratio. */
static void study_grid(const study_t *s, int level, char *buf, size_t n, int *cells,
                       double *ratio) {
  if (s->dim == 2) {
    snprintf(buf, n, s->grid2d, level);
    *cells = level;
    *ratio = pow(4000 / 0.01, 1.0 / (level - 1)); /* GRID_VM, x1 (x2 the same) */
    return;
  }
  double r = pow(2.0, 1.0 / level), lo = s->first_pivot_one ? 2 / (1 + r) : s->lo;
  double hi = s->hi;
  int geo = (int)ceil(log(hi / lo) / log(r) - 1e-9);
  *cells = geo + !s->first_pivot_one;
  *ratio = r;
  snprintf(buf, n,
           "grid: {axes: [{name: v, type: geometric, min: %.17g, ratio: %.17g, cells: %d, zero_first: %s}]}\n",
           lo, r, *cells, s->first_pivot_one ? "false" : "true");
}

/* Run one study at one refinement level and scheme; signed errors in percent. */
static int run_one(const study_t *s, int level, const char *scheme, double *err_pct,
                   double *seconds, long *evals, int *cells, double *ratio, gs_error *err) {
  char yaml[8192];
  size_t w;
  study_grid(s, level, yaml, sizeof yaml, cells, ratio);
  w = strlen(yaml);
  snprintf(yaml + w, sizeof yaml - w, s->body, scheme);
  w = strlen(yaml);
  /* FP over-predicts the largest sizes; the grids reach far enough that it
   * stays on them, and a loss beyond 1e-3 of the volume fails the run. */
  snprintf(yaml + w, sizeof yaml - w, "%soutput: {times: [%.17g]}\nchecks: {max_loss: %.17g}\n",
           s->dim == 1 ? solver_1d : solver_2d, s->t_end, max_loss);
  *seconds = 0;
  *evals = 0;
  gs_cfg *cfg = gs_cfg_load_string(yaml, s->id, err);
  if (!cfg) return err->code ? err->code : GS_EINPUT;
  gs_case c;
  int rc = gs_case_from_cfg(cfg, &c, err);
  if (rc) return rc;
  double *y = NULL;
  gs_run_report rep;
  double t0 = now();
  y = malloc((c.model.nstate + c.model.nledger) * sizeof(double));
  rc = y ? gs_case_run(&c, NULL, y, &rep, err) : GS_ENOMEM;
  *seconds = now() - t0;
  if (!rc) {
    double exact[MAXMOM];
    s->exact(s->t_end, exact);
    for (int i = 0; i < s->nmom; i++) {
      double num = gs_moment(&c.model, y, 0, s->powers[i]);
      err_pct[i] = 100.0 * (num - exact[i]) / fabs(exact[i]); /* signed: + over-predicts */
      if (!isfinite(err_pct[i])) {
        rc = err->code = GS_ENUMERIC;
        snprintf(err->msg, sizeof err->msg, "%s is not finite (numerical %g, exact %g)",
                 s->mom_names[i], num, exact[i]);
        break;
      }
    }
    *evals = rep.stats.rhs_evals;
  }
  free(y);
  gs_case_free(&c);
  return rc;
}

static void report_header(FILE *fp, const char *args, double total_s, int threads) {
  struct utsname u;
  uname(&u);
  time_t now_t = time(NULL);
  char date[64];
  strftime(date, sizeof date, "%Y-%m-%d", gmtime(&now_t));
  fprintf(fp,
          "# Validation of the sectional engine\n\n"
          "Generated by `gransim validate%s` on %s (%s %s, %s) in %.0f s of wall time with %d\n"
          "OpenMP thread%s (the wall s column: per run). Do not edit by hand: rerun `gransim validate`\n"
          "from the repository root (`build/gransim validate --threads 1 --out docs/validation.md`) to\n"
          "regenerate; without `--out` the report goes to standard output. It\n"
          "exits non-zero if any run fails or the published-error target at the end is missed.\n\n"
          "Each table is a grid-refinement study of one analytical solution (T1-T8, from the publications\n"
          "in [references.md](references.md)). Grids are geometric with an extra\n"
          "first cell [0, min] (T1d: without it). In 1-D they are refined as Kumar & Ramkrishna's,\n"
          "by the ratio of consecutive edges r = 2^(1/q), q = 1, 2, 4, 8 (T3: 2 to 16), every resolution\n"
          "covering the same range [0, max], with max chosen so that even the coarsest fixed-pivot run keeps\n"
          "its volume on the grid up to the final time (a loss beyond 1e-3 of the volume fails the\n"
          "run); the cells column counts the cells this takes. In 2-D (T7) the grids are those of\n"
          "Vale & McKenna's comparison, n x n cells on fixed ranges (ratio of the x1 axis given).\n"
          "Entries are **signed** relative errors of the moments at the final time, in percent,\n"
          "100 (numerical - exact) / |exact|: **positive means the scheme over-predicts** the moment,\n"
          "negative that it under-predicts; they are given for the\n"
          "**cell-average** (CA) and **fixed-pivot** (FP) redistributions. Time integration is tight\n"
          "(GSL rkck, rtol 1e-9 in 1-D, 1e-7 in 2-D) so the errors are those of the discretisation.\n"
          "Moments are taken over the pivots, M_p = sum N v^p (2-D: M_ij = sum N x1^i x2^j).\n\n",
          args, date, u.sysname, u.machine, u.nodename, total_s, threads,
          threads == 1 ? "" : "s");
}

static int selected(const char *only, const char *id) {
  if (!only) return 1;
  size_t n = strlen(id);
  for (const char *p = only; *p;) {
    const char *e = strchr(p, ',');
    size_t len = e ? (size_t)(e - p) : strlen(p);
    if (len == n && !strncmp(p, id, n)) return 1;
    if (!e) break;
    p = e + 1;
  }
  return 0;
}

static void validate_usage(void) {
  printf("usage: gransim validate [--out FILE] [--quick] [--only ID[,ID...]] [--threads N]\n"
         "                        [--max-loss X]\n\n"
         "Runs the grid-refinement study against analytical solutions and writes a\n"
         "markdown report to FILE (written whole or not at all), by default to standard\n"
         "output; errors are signed, + meaning over-prediction. --quick skips the finest grids;\n"
         "--threads sets the OpenMP threads (default: OMP_NUM_THREADS or all);\n"
         "--max-loss: volume fraction allowed to leave a grid before a run fails\n"
         "(default 1e-3);\n"
         "--only runs the named studies (");
  for (size_t s = 0; s < NSTUDIES; s++) printf("%s%s", s ? ", " : "", studies[s].id);
  printf(").\nExits 1 if a run fails or the published-error target is missed.\n");
}

int gs_cmd_validate(int argc, char **argv) {
  const char *out = NULL, *only = NULL; /* out NULL: standard output */
  int quick = 0, n;
  char args[256] = ""; /* the options that shape the report, echoed in its header */
  static const struct option opts[] = {
      {"help", no_argument, NULL, GS_CLI_HELP}, {"out", required_argument, NULL, 'o'},
      {"only", required_argument, NULL, 'O'},  {"quick", no_argument, NULL, 'q'},
      {"threads", required_argument, NULL, 't'}, {"max-loss", required_argument, NULL, 'm'},
      {0}};
  gs_cli_begin();
  for (int o; (o = gs_cli_next(argc, argv, opts)) != -1;) switch (o) {
    case GS_CLI_HELP: validate_usage(); return 0;
    case 'o': out = optarg; break;
    case 'O':
      only = optarg;
      snprintf(args + strlen(args), sizeof args - strlen(args), " --only %s", only);
      break;
    case 'q':
      quick = 1;
      snprintf(args + strlen(args), sizeof args - strlen(args), " --quick");
      break;
    case 't':
      if (gs_cli_positive("validate", "threads", optarg, &n)) return 2;
      omp_set_num_threads(n);
      snprintf(args + strlen(args), sizeof args - strlen(args), " --threads %d", n);
      break;
    case 'm': {
      char *end;
      max_loss = strtod(optarg, &end);
      if (*end || !(max_loss >= 0 && max_loss <= 1)) {
        fprintf(stderr, "gransim validate: --max-loss needs a number in [0, 1], got '%s'\n", optarg);
        return 2;
      }
      snprintf(args + strlen(args), sizeof args - strlen(args), " --max-loss %s", optarg);
      break;
    }
    default: return 2;
    }
  if (optind < argc) {
    fprintf(stderr, "gransim validate: unexpected argument '%s'\n", argv[optind]);
    validate_usage();
    return 2;
  }
  if (only)
    for (const char *p = only; *p;) {
      const char *e = strchr(p, ',');
      size_t len = e ? (size_t)(e - p) : strlen(p);
      int known = 0;
      for (size_t s = 0; s < NSTUDIES; s++)
        known |= strlen(studies[s].id) == len && !strncmp(studies[s].id, p, len);
      if (!known) {
        fprintf(stderr, "gransim validate: --only: unknown study '%.*s'\n", (int)len, p);
        return 2;
      }
      if (!e) break;
      p = e + 1;
    }
  /* The body goes to memory first: the header states the total run time.
   * FILE.partial is opened before any run, so an unwritable place fails at
   * once rather than after the whole study, and renamed when complete. */
  char *partial = NULL;
  FILE *of = stdout;
  if (out) {
    size_t pn = strlen(out) + sizeof ".partial";
    partial = malloc(pn);
    of = partial ? (snprintf(partial, pn, "%s.partial", out), fopen(partial, "w")) : NULL;
    if (!of) {
      fprintf(stderr, "gransim validate: cannot write %s: %s\n", partial ? partial : out,
              strerror(errno));
      free(partial);
      return 1;
    }
  }
  char *body = NULL;
  size_t body_len = 0;
  FILE *fp = open_memstream(&body, &body_len);
  if (!fp) {
    perror("gransim validate");
    if (out) fclose(of), remove(partial);
    free(partial);
    return 1;
  }
  static const char *const schemes[2] = {"cell_average", "fixed_pivot"};
  int failed = 0, vm_done = 0;
  double vm[2][2][2] = {{{0}}}; /* [30x30, 50x50][CA, FP][M20, M30] */
  int vm_have[2][2] = {{0}};
  double t_start = now();
  for (size_t s = 0; s < NSTUDIES; s++) {
    const study_t *st = &studies[s];
    if (!selected(only, st->id)) continue;
    int is_vm = !strcmp(st->id, "T7b");
    fprintf(fp, "## %s: %s\n\n| cells | ratio | scheme |", st->id, st->title);
    for (int i = 0; i < st->nmom; i++) fprintf(fp, " %s %% (+ over) |", st->mom_names[i]);
    fprintf(fp, " RHS evals | wall s |\n|---|---|---|");
    for (int i = 0; i < st->nmom + 2; i++) fprintf(fp, "---|");
    fprintf(fp, "\n");
    for (int k = 0; k < MAXCELLS && st->levels[k]; k++) {
      if (quick && k >= 2) break;
      for (int sc = 0; sc < 2; sc++) {
        double e[MAXMOM], secs = 0, ratio = 0;
        long evals = 0;
        int cells = 0;
        gs_error err = {0};
        fprintf(stderr, "validate: %s level %d %s...\n", st->id, st->levels[k], schemes[sc]);
        int rc = run_one(st, st->levels[k], schemes[sc], e, &secs, &evals, &cells, &ratio, &err);
        fprintf(fp, "| %d | %.4g | %s |", cells, ratio, sc ? "FP" : "CA");
        if (rc) {
          fprintf(fp, " failed: %s |\n", err.msg);
          fprintf(stderr, "validate: %s %d cells %s failed: %s\n", st->id, cells, schemes[sc],
                  err.msg);
          failed = 1;
          continue;
        }
        for (int i = 0; i < st->nmom; i++) fprintf(fp, " %.3g |", e[i]);
        fprintf(fp, " %ld | %.2f |\n", evals, secs);
        int g = cells == 30 ? 0 : cells == 50 ? 1 : -1;
        if (is_vm && g >= 0) {
          vm[g][sc][0] = e[4];
          vm[g][sc][1] = e[6];
          vm_have[g][sc] = 1;
        }
      }
    }
    fprintf(fp, "\n");
    if (st->note) fprintf(fp, "%s\n", st->note);
    vm_done |= is_vm;
  }
  if (vm_done) {
    static const double published[2][2] = {{13.1, 45.6}, {4.3, 13.7}};
    static const char *const grid_name[2] = {"30x30", "50x50"};
    fprintf(fp,
            "## Against the published fixed-pivot errors (Vale & McKenna 2005, Table 1)\n\n"
            "The published errors are magnitudes; gransim's are signed (+ over-predicts) and judged by\n"
            "their magnitude.\n\n"
            "| grid | published FP M20 %% | published FP M30 %% | gransim FP M20 %% (+ over) | gransim FP M30 %% (+ over) | gransim CA M20 %% (+ over) | gransim CA M30 %% (+ over) |\n"
            "|---|---|---|---|---|---|---|\n");
    int met = 1, judged = 1;
    for (int g = 0; g < 2; g++) {
      fprintf(fp, "| %s | %.3g | %.3g |", grid_name[g], published[g][0], published[g][1]);
      for (int sc = 1; sc >= 0; sc--) {
        if (vm_have[g][sc]) fprintf(fp, " %.3g | %.3g |", vm[g][sc][0], vm[g][sc][1]);
        else fprintf(fp, " not run | not run |");
      }
      fprintf(fp, "\n");
      judged &= vm_have[g][0];
      met &= vm_have[g][0] && fabs(vm[g][0][0]) < published[g][0] &&
             fabs(vm[g][0][1]) < published[g][1];
    }
    fprintf(fp,
            "\nTarget (issue 2): cell-average errors below the published fixed-pivot errors at both grids: %s.\n"
            "The grids of the paper are geometric but their exact range is not given, so the\n"
            "fixed-pivot rows of this report (same grids as the CA rows) are the like-for-like comparison.\n"
            "The same bounds are asserted by the test `test_vm_target`.\n",
            !judged ? "**not judged** (a grid was not run or its run failed)" : met ? "**met**" : "**not met**");
    met |= !judged; /* a partial study (--quick) cannot miss the target */
    if (!met) {
      fprintf(stderr, "validate: the published-error target (T7b) is not met\n");
      failed = 1;
    }
  }
  /* the validation that lives elsewhere: written here so the report is the index */
  fprintf(fp,
          "\n## Elsewhere\n\n"
          "- **Low-rank kernel forms (`rank_tolerance`)**: [validation-lowrank.md](validation-lowrank.md): rank\n"
          "  against tolerance, truncation error and rates against the pair loop for Brownian, Madec and\n"
          "  semi-mechanistic kernels, conservation at every rank, regenerated by `test_aggregation_lowrank`.\n"
          "- **Stochastic solver (SWA, McGuire et al. 2018)**: [validation-swa.md](validation-swa.md): ensemble means\n"
          "  against T1 and T2 within their 90 %% confidence intervals, the interval shrinking like\n"
          "  1/sqrt(N) and 1/sqrt(runs), mass exact per jump (contractions included), agreement with\n"
          "  this engine on a shared 1-D and 2-D case, and that paper's numerical studies (VWI vs EWI,\n"
          "  droplet weight, N_max x runs), regenerated by `bench/swa_run`.\n"
          "- **Recipe recovery (Chaudhury 2015, tables 5.6 and 5.7)**: [validation-fit.md](validation-fit.md):\n"
          "  the seven controls of the thesis's open-loop recipe (four spray rates, binder, impeller\n"
          "  speed, wet-massing time) recovered by `gransim optimise`'s Nelder–Mead and bounded methods\n"
          "  from a start 15–40 %% off, beside the thesis's errors; generated by `scripts/validation-fit`,\n"
          "  checked by the `long` test `cli_validate_fit_long`.\n"
          "- **CoriMix granulator (Sampat et al. 2018)**: `test_corimix` checks the shipped example at every right-hand side\n"
          "  (aggregation 1/2 and breakage 2 number ratios, conservation of both solids, liquid and gas)\n"
          "  and at every output time (tanks-in-series closed forms for the solids and the sprayed\n"
          "  liquid, ledger balance); `tests/mpi_sectional.sh` checks that results do not depend on\n"
          "  the number of MPI ranks or threads.\n"
          "- **DEM**: contact law, walls, meshes, insertion and statistics tests (`test_dem_*`);\n"
          "  comparison with LIGGGHTS in [performance.md](performance.md).\n");
  double total = now() - t_start;
  int bad = fclose(fp);
  if (!bad) {
    report_header(of, args, total, omp_get_max_threads());
    fwrite(body, 1, body_len, of);
    bad = out ? ferror(of) | fclose(of) : ferror(of) | fflush(of);
    if (!bad && out) bad = rename(partial, out);
  } else if (out) {
    fclose(of);
  }
  if (bad) {
    fprintf(stderr, "gransim validate: cannot write %s: %s\n", out ? out : "standard output",
            strerror(errno));
    if (out) remove(partial);
  }
  free(partial);
  free(body);
  if (bad) return 1;
  fprintf(stderr, "validate: wrote %s (%.1f s)%s\n", out ? out : "the report to standard output",
          total, failed ? "; some runs failed or the target was missed" : "");
  return failed;
}
