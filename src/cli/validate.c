/* gransim validate: grid-refinement study of the sectional engine against
 * the analytical solutions of docs/validation.md (T1-T7), for the cell-average
 * and fixed-pivot techniques.  Writes a markdown report (default
 * docs/validation.md).  Every case is an ordinary case file built from a
 * template, so the report is also a test of the case-file path. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/utsname.h>
#include <time.h>

#include "cli/commands.h"
#include "gransim/case.h"

#define MAXMOM 10

typedef struct {
  const char *id, *title;
  int dim;
  double t_end;
  /* template: printf with (cells, cells, ...) via %1$d for cells, %2$s for the scheme */
  const char *yaml;
  int nmom;
  int powers[MAXMOM][2];
  const char *mom_names[MAXMOM];
  void (*exact)(double t, double *m);
  int cells[5];
} study_t;

/* ---- exact moments (analytic-solutions.md) --------------------------------- */
static void t1_exact(double t, double *m) { m[0] = 2 / (2 + t); m[1] = 1; m[2] = 2 + t; }
static void t2_exact(double t, double *m) { m[0] = exp(-t); m[1] = 1; m[2] = 2 * exp(2 * t); }
static void t3_exact(double t, double *m) { m[0] = 1 - 0.5 * t; m[1] = 1; m[2] = 2 / (1 - 2 * t); }
static void t4_exact(double t, double *m) { m[0] = 1 + t; m[1] = 1; m[2] = 2 / (1 + t); }
static void t6_exact(double t, double *m) {
  double m0 = 2 / (2 + t), m1 = exp(0.5 * t);
  m[0] = m0; m[1] = m1; m[2] = 2 * m1 * m1 / m0;
}
static void t5_exact(double t, double *m) { /* beta0 = 1, S0 = 0.5, M1 = 1, N0 = 1 */
  double Ninf = 1.0, th = tanh(0.5 * Ninf * t);
  double N = Ninf * (1 + Ninf * th) / (Ninf + th);
  m[0] = N; m[1] = 1; m[2] = 2 / N;
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
static const char *const solver_1d = "solver: {method: rk, rtol: 1.0e-9, atol: 1.0e-16}\n";

static const study_t studies[] = {
    {"T1", "constant kernel, exponential IC, tau = beta0 N0 t = 100", 1, 100,
     "grid: {axes: [{name: v, type: geometric, min: 1.0e-4, max: 1.0e5, cells: %1$d, zero_first: true}]}\n"
     "initial: {type: exponential, number: 1, mean: 1}\n"
     "mechanisms: [{type: aggregation, redistribution: %2$s, kernel: {type: constant, beta0: 1}}]\n",
     ONE_D_MOMENTS, t1_exact, {20, 40, 80, 160, 0}},
    {"T2", "sum kernel, exponential IC, beta0 M1 t = 2", 1, 2,
     "grid: {axes: [{name: v, type: geometric, min: 1.0e-4, max: 1.0e5, cells: %1$d, zero_first: true}]}\n"
     "initial: {type: exponential, number: 1, mean: 1}\n"
     "mechanisms: [{type: aggregation, redistribution: %2$s, kernel: {type: sum, beta0: 1}}]\n",
     ONE_D_MOMENTS, t2_exact, {20, 40, 80, 160, 0}},
    {"T3", "product kernel, exponential IC, t = 0.8 t_gel", 1, 0.4,
     "grid: {axes: [{name: v, type: geometric, min: 1.0e-4, max: 1.0e5, cells: %1$d, zero_first: true}]}\n"
     "initial: {type: exponential, number: 1, mean: 1}\n"
     "mechanisms: [{type: aggregation, redistribution: %2$s, kernel: {type: product, beta0: 1}}]\n",
     ONE_D_MOMENTS, t3_exact, {20, 40, 80, 160, 0}},
    {"T4", "binary breakage, S = v, uniform daughters, exponential IC, t = 10", 1, 10,
     "grid: {axes: [{name: v, type: geometric, min: 1.0e-6, max: 100, cells: %1$d, zero_first: true}]}\n"
     "initial: {type: exponential, number: 1, mean: 1}\n"
     "mechanisms: [{type: breakage, redistribution: %2$s, selection: {type: power, s0: 1, exponent: 1}, daughters: {type: uniform}}]\n",
     ONE_D_MOMENTS, t4_exact, {20, 40, 80, 160, 0}},
    {"T5", "aggregation (beta0 = 1) + breakage (S = 0.5 v, uniform), t = 10 (near steady state)", 1, 10,
     "grid: {axes: [{name: v, type: geometric, min: 1.0e-6, max: 200, cells: %1$d, zero_first: true}]}\n"
     "initial: {type: exponential, number: 1, mean: 1}\n"
     "mechanisms:\n"
     "  - {type: aggregation, redistribution: %2$s, kernel: {type: constant, beta0: 1}}\n"
     "  - {type: breakage, redistribution: %2$s, selection: {type: power, s0: 0.5, exponent: 1}, daughters: {type: uniform}}\n",
     ONE_D_MOMENTS, t5_exact, {20, 40, 80, 160, 0}},
    {"T6", "constant-kernel aggregation + linear growth G = 0.5 v, t = 2", 1, 2,
     "grid: {axes: [{name: v, type: geometric, min: 1.0e-4, max: 1.0e4, cells: %1$d, zero_first: true}]}\n"
     "initial: {type: exponential, number: 1, mean: 1}\n"
     "mechanisms:\n"
     "  - {type: aggregation, redistribution: %2$s, kernel: {type: constant, beta0: 1}}\n"
     "  - {type: growth, axis: v, linear: 0.5}\n",
     ONE_D_MOMENTS, t6_exact, {20, 40, 80, 160, 0}},
    {"T7b", "Vale & McKenna case 1 (2-D constant kernel), tau = 100", 2, 100,
     "grid:\n  axes:\n"
     "    - {name: x1, type: geometric, min: 0.01, max: 4000, cells: %1$d, zero_first: true}\n"
     "    - {name: x2, type: geometric, min: 0.05, max: 20000, cells: %1$d, zero_first: true}\n"
     "initial: {type: gamma, number: 1, mean: [1, 5], shape: [2, 2]}\n"
     "mechanisms: [{type: aggregation, redistribution: %2$s, kernel: {type: constant, beta0: 1}}]\n",
     10, {{0, 0}, {1, 0}, {0, 1}, {1, 1}, {2, 0}, {0, 2}, {3, 0}, {0, 3}, {2, 1}, {1, 2}},
     {"M00", "M10", "M01", "M11", "M20", "M02", "M30", "M03", "M21", "M12"}, vm_exact,
     {20, 30, 40, 50, 0}},
};

static double now(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* Run one study at one resolution and scheme; errors in percent. */
static int run_one(const study_t *s, int cells, const char *scheme, double *err_pct,
                   double *seconds, long *evals, gs_error *err) {
  char yaml[4096];
  int w = snprintf(yaml, sizeof yaml, s->yaml, cells, scheme);
  snprintf(yaml + w, sizeof yaml - (size_t)w, "%s%s", s->dim == 1 ? solver_1d : "solver: {method: rk, rtol: 1.0e-7, atol: 1.0e-14}\n", "");
  w = (int)strlen(yaml);
  /* FP over-predicts the largest sizes; tolerate some loss and report it. */
  snprintf(yaml + w, sizeof yaml - (size_t)w, "output: {times: [%.17g]}\nchecks: {max_loss: 1.0e-3}\n", s->t_end);
  gs_cfg *cfg = gs_cfg_load_string(yaml, s->id, err);
  if (!cfg) return err->code;
  gs_case c;
  int rc = gs_case_from_cfg(cfg, &c, err);
  double *y = NULL;
  gs_run_report rep;
  double t0 = now();
  if (!rc) {
    y = malloc((c.model.nstate + c.model.nledger) * sizeof(double));
    rc = y ? gs_case_run(&c, NULL, y, &rep, err) : GS_ENOMEM;
  }
  *seconds = now() - t0;
  if (!rc) {
    double exact[MAXMOM];
    s->exact(s->t_end, exact);
    for (int i = 0; i < s->nmom; i++) {
      double num = gs_moment(&c.model, y, 0, s->powers[i]);
      err_pct[i] = 100.0 * fabs(num - exact[i]) / fabs(exact[i]);
    }
    *evals = rep.stats.rhs_evals;
  }
  free(y);
  gs_case_free(&c);
  return rc;
}

static void report_header(FILE *fp) {
  struct utsname u;
  uname(&u);
  time_t now_t = time(NULL);
  char date[64];
  strftime(date, sizeof date, "%Y-%m-%d", gmtime(&now_t));
  fprintf(fp,
          "# Validation of the sectional engine\n\n"
          "Generated by `gransim validate` on %s (%s %s, %s). Do not edit by hand: rerun\n"
          "`build/gransim validate` to regenerate.\n\n"
          "Each table is a grid-refinement study of one analytical solution from\n"
          "`../shared/reference/analytic-solutions.md` (T1-T7). Grids are geometric with an extra\n"
          "first cell [0, min]; the number of cells per axis is given. Entries are relative\n"
          "errors of the moments at the final time, in percent, for the **cell-average** (CA)\n"
          "and **fixed-pivot** (FP) redistributions. Time integration is tight (GSL rkck, rtol\n"
          "1e-9 in 1-D, 1e-7 in 2-D) so the errors are those of the discretisation. Moments are\n"
          "taken over the pivots, M_p = sum N v^p (2-D: M_ij = sum N x1^i x2^j).\n\n",
          date, u.sysname, u.machine, u.nodename);
}

int gs_cmd_validate(int argc, char **argv) {
  const char *out = "docs/validation.md";
  int quick = 0;
  for (int i = 0; i < argc; i++) {
    if (!strcmp(argv[i], "--out") && i + 1 < argc) out = argv[++i];
    else if (!strcmp(argv[i], "--quick")) quick = 1;
    else {
      printf("usage: gransim validate [--out FILE] [--quick]\n\n"
             "Runs the grid-refinement study against analytical solutions and writes a\n"
             "markdown report (default docs/validation.md). --quick skips the finest grids.\n");
      return strcmp(argv[i], "--help") ? 2 : 0;
    }
  }
  FILE *fp = fopen(out, "w");
  if (!fp) {
    perror(out);
    return 1;
  }
  report_header(fp);
  static const char *const schemes[2] = {"cell_average", "fixed_pivot"};
  int failed = 0;
  double vm_ca[2] = {0}, vm_fp[2] = {0}; /* M20 and M30 at 30x30 / 50x50 */
  double vm_ca50[2] = {0};
  for (size_t s = 0; s < sizeof studies / sizeof studies[0]; s++) {
    const study_t *st = &studies[s];
    fprintf(fp, "## %s: %s\n\n| cells | scheme |", st->id, st->title);
    for (int i = 0; i < st->nmom; i++) fprintf(fp, " %s %% |", st->mom_names[i]);
    fprintf(fp, " RHS evals | wall s |\n|---|---|");
    for (int i = 0; i < st->nmom + 2; i++) fprintf(fp, "---|");
    fprintf(fp, "\n");
    for (int k = 0; k < 5 && st->cells[k]; k++) {
      if (quick && k >= 2) break;
      for (int sc = 0; sc < 2; sc++) {
        double e[MAXMOM], secs = 0;
        long evals = 0;
        gs_error err = {0};
        fprintf(stderr, "validate: %s %d cells %s...\n", st->id, st->cells[k], schemes[sc]);
        if (run_one(st, st->cells[k], schemes[sc], e, &secs, &evals, &err)) {
          fprintf(fp, "| %d | %s | failed: %s |\n", st->cells[k], sc ? "FP" : "CA", err.msg);
          fprintf(stderr, "validate: %s failed: %s\n", st->id, err.msg);
          failed = 1;
          continue;
        }
        fprintf(fp, "| %d | %s |", st->cells[k], sc ? "FP" : "CA");
        for (int i = 0; i < st->nmom; i++) fprintf(fp, " %.3g |", e[i]);
        fprintf(fp, " %ld | %.2f |\n", evals, secs);
        if (st->dim == 2 && st->cells[k] == 30) (sc ? vm_fp : vm_ca)[0] = e[4], (sc ? vm_fp : vm_ca)[1] = e[6];
        if (st->dim == 2 && st->cells[k] == 50 && sc == 0) vm_ca50[0] = e[4], vm_ca50[1] = e[6];
      }
      fflush(fp);
    }
    fprintf(fp, "\n");
  }
  fprintf(fp,
          "## Against the published fixed-pivot errors (Vale & McKenna 2005, Table 1)\n\n"
          "| grid | published FP M20 %% | published FP M30 %% | gransim FP M20 %% | gransim FP M30 %% | gransim CA M20 %% | gransim CA M30 %% |\n"
          "|---|---|---|---|---|---|---|\n"
          "| 30x30 | 13.1 | 45.6 | %.3g | %.3g | %.3g | %.3g |\n"
          "| 50x50 | 4.3 | 13.7 | see table above | | %.3g | %.3g |\n\n"
          "Target (issue 2): cell-average errors below the published fixed-pivot errors at both grids: %s.\n"
          "The grids of the paper are geometric but their exact range is not given, so the\n"
          "fixed-pivot rows of this report (same grids as the CA rows) are the like-for-like comparison.\n",
          vm_fp[0], vm_fp[1], vm_ca[0], vm_ca[1], vm_ca50[0], vm_ca50[1],
          (vm_ca[0] < 13.1 && vm_ca[1] < 45.6 && vm_ca50[0] < 4.3 && vm_ca50[1] < 13.7) ? "**met**" : "**not met**");
  fclose(fp);
  fprintf(stderr, "validate: wrote %s\n", out);
  return failed;
}
