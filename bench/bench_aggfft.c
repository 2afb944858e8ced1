/* Aggregation right-hand side by FFT convolutions (method: fft) against the
 * pair loop (method: pairs), both fixed pivot with the constant kernel on
 * the same linear grid and the same dense state, measured in the same run:
 * 2-D with n = 32 ... 256 cells per axis and 1-D with 2^10 ... 2^16 cells.
 * Prints seconds per right-hand side (fastest of the repeats that fit in
 * about 0.3 s), the ratio, the largest difference of the two (relative to
 * the largest rate) and the exponent of the cost between successive sizes.
 * The pair scheme keeps per axis a table of where each sum of two pivots
 * lands (n^2 entries): in 1-D it runs up to 4096 cells only (128 MB).
 * Then low-rank kernel forms (rank_tolerance 1e-8) against the pairs in 2-D:
 * Brownian (free molecular) and Madec, 256 to 16 384 cells, with the set-up
 * time, the rank, and the form's build by cross approximation against the
 * dense eigendecomposition (up to 4 096 cells) in the same run.
 * Then non-uniform grids (the near/far split, src/pbm/aggregation_split.c):
 * geometric grids in 1-, 2- and 3-D with the constant kernel and a dense
 * state, and the 3-D n = 26 Madec case (bench/cases/madec-3d-26.yaml) at its
 * own state after 250 s (run with its default scheme first), fixed pivot
 * pairs against fft.
 * Usage: bench_aggfft [max pair cells in 2-D, default 65536 [lowrank | geometric: that series alone]] */
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "gransim/case.h"
#include "gransim/run.h"
#include "kernel/lowrank.h"

static double now(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* The fastest right-hand side of case c at its y0 (rates into d) of the
 * repeats that fit in about 0.3 s; frees the case. */
static double best_rhs(gs_case *c, double *d) {
  double *dl = calloc(c->model.nledger, sizeof(double));
  double best = INFINITY, spent = 0;
  for (int r = 0; r < 50 && spent < 0.3; r++) {
    double t0 = now();
    gs_model_rhs(&c->model, &c->eval, 0, c->y0, d, dl);
    double t = now() - t0;
    spent += t;
    if (t < best) best = t;
  }
  free(dl);
  gs_case_free(c);
  return best;
}

/* Seconds per right-hand side of the case (rates into d), or NAN if it
 * does not build. */
static double time_rhs(int dim, int n, const char *method, const char *kernel, double *d,
                       double *setup) {
  char yaml[1024];
  snprintf(yaml, sizeof yaml,
           "grid: {axes: [{name: s, type: linear, min: %s, max: 1, cells: %d}%s]}\n"
           "initial: {type: cell, number: 1, index: [%s]}\n"
           "mechanisms:\n  - {type: aggregation, redistribution: fixed_pivot, method: %s,"
           " kernel: %s}\n"
           "output: {end: 1}\n",
           setup ? "0.05" : "0", n, dim == 2 ? ", {name: l, type: linear, min: 0, max: 1, cells: AXIS2}" : "",
           dim == 2 ? "1, 1" : "1", method, kernel);
  char *p = strstr(yaml, "AXIS2");
  if (p) { /* the second axis has the same cells */
    char tail[1024];
    snprintf(tail, sizeof tail, "%d%s", n, p + 5);
    strcpy(p, tail);
  }
  gs_error err = {0};
  gs_cfg *cfg = gs_cfg_load_string(yaml, "bench.yaml", &err);
  gs_case c;
  memset(&c, 0, sizeof c);
  const double t_build = now();
  const int failed = !cfg || gs_case_from_cfg(cfg, &c, &err);
  if (setup) *setup = now() - t_build;
  if (failed) {
    fprintf(stderr, "case did not build: %s\n", err.msg);
    return NAN;
  }
  /* a dense population: every cell holds particles (exponential in the
   * coordinates, falling 20 times across each axis) */
  const gs_grid *g = &c.model.grid;
  for (size_t k = 0; k < g->ncells; k++) {
    double s = 0;
    for (int q = 0; q < dim; q++) s += g->x[k * (size_t)dim + (size_t)q];
    c.y0[k] = exp(-3.0 * s);
  }
  return best_rhs(&c, d);
}

static void series(int dim, const int *ns, int count, size_t max_pairs) {
  if (dim == 1 && max_pairs > 4096) max_pairs = 4096;
  double prev[2] = {NAN, NAN};
  int prev_n = 0;
  printf("%d-D, constant kernel, fixed pivot, one right-hand side:\n", dim);
  printf("  %8s %8s %12s %12s %9s %10s %10s %10s\n", "n/axis", "cells", "pairs [s]", "fft [s]",
         "pairs/fft", "difference", "exp pairs", "exp fft");
  for (int i = 0; i < count; i++) {
    const int n = ns[i];
    const size_t cells = dim == 2 ? (size_t)n * (size_t)n : (size_t)n;
    double *d[2] = {calloc(cells, sizeof(double)), calloc(cells, sizeof(double))};
    double t[2];
    t[1] = time_rhs(dim, n, "fft", "{type: constant, beta0: 1}", d[1], NULL);
    t[0] = cells <= max_pairs ? time_rhs(dim, n, "pairs", "{type: constant, beta0: 1}", d[0], NULL) : NAN;
    double scale = 0, diff = 0;
    for (size_t k = 0; k < cells && !isnan(t[0]); k++) {
      scale = fmax(scale, fabs(d[0][k]));
      diff = fmax(diff, fabs(d[1][k] - d[0][k]));
    }
    double e[2] = {NAN, NAN};
    for (int s = 0; s < 2 && prev_n; s++) e[s] = log(t[s] / prev[s]) / log((double)n / prev_n);
    printf("  %8d %8zu %12.4g %12.4g %9.3g %10.2g %10.2f %10.2f\n", n, cells, t[0], t[1], t[0] / t[1],
           isnan(t[0]) ? NAN : diff / scale, e[0], e[1]);
    prev[0] = t[0];
    prev[1] = t[1];
    prev_n = n;
    free(d[0]);
    free(d[1]);
  }
}

/* Low-rank forms (rank_tolerance 1e-8) of kernels without an exact one, 2-D,
 * against the pair loop: the rank decides whether the FFT pays.  The set-up
 * (building the case) is timed apart, and the form itself built again twice
 * on the case's grid: by cross approximation (kernel/lowrank.c, what the case
 * uses) and by the dense eigendecomposition (lowrank_dense.c, O(cells^3),
 * up to 4 096 cells). */
static void lowrank_series(const char *name, const char *kernel, const int *ns, int count) {
  printf("2-D, %s, fixed pivot, rank_tolerance 1e-8, one right-hand side:\n", name);
  printf("  %8s %8s %12s %12s %9s %10s %12s %6s %10s %10s %10s %9s\n", "n/axis", "cells", "pairs [s]", "fft [s]",
         "pairs/fft", "difference", "set-up [s]", "rank", "ACA [s]", "dense [s]", "dense/ACA", "ACA error");
  for (int i = 0; i < count; i++) {
    const int n = ns[i];
    const size_t cells = (size_t)n * (size_t)n;
    double *d[2] = {calloc(cells, sizeof(double)), calloc(cells, sizeof(double))};
    char method[64];
    snprintf(method, sizeof method, "fft, rank_tolerance: 1.0e-8");
    double setup = NAN, unused = NAN;
    double t1 = time_rhs(2, n, method, kernel, d[1], &setup);
    double t0 = time_rhs(2, n, "pairs", kernel, d[0], &unused);
    /* the rank: from a case built again (cheap next to the timing) */
    char yaml[512];
    snprintf(yaml, sizeof yaml,
             "grid: {axes: [{name: s, type: linear, min: 0.05, max: 1, cells: %d}, {name: l, type: linear, min: 0,"
             " max: 1, cells: %d}]}\ninitial: {type: cell, number: 1, index: [1, 1]}\nmechanisms:\n  - {type: aggregation,"
             " redistribution: fixed_pivot, method: %s, kernel: %s}\noutput: {end: 1}\n", n, n, method, kernel);
    gs_error err = {0};
    gs_cfg *cfg = gs_cfg_load_string(yaml, "bench.yaml", &err);
    gs_case c;
    memset(&c, 0, sizeof c);
    char notes[1024] = "";
    int rank = -1;
    double t_aca = NAN, t_dense = NAN, e_aca = NAN;
    if (cfg && !gs_case_from_cfg(cfg, &c, &err)) {
      const char *r = gs_model_notes(&c.model, notes, sizeof notes) ? strstr(notes, "of rank ") : NULL;
      if (r) rank = atoi(r + 8);
      gs_cfg *kcfg = gs_cfg_load_string(kernel, "kernel", &err);
      gs_kernel k;
      if (kcfg && !gs_kernel_create(gs_cfg_root(kcfg), &c.model.grid, ".", &k, &err)) {
        gs_kernel_lowrank lr;
        double t = now();
        if (!gs_kernel_lowrank_build(&k, cells, 0, 1e-8, &lr, &err)) {
          t_aca = now() - t;
          e_aca = lr.rel_err;
          gs_kernel_lowrank_free(&lr);
        }
        t = now();
        if (cells <= GS_LOWRANK_DENSE_MAX_CELLS && !gs_kernel_lowrank_build_dense(&k, cells, 0, 1e-8, &lr, &err)) {
          t_dense = now() - t;
          gs_kernel_lowrank_free(&lr);
        }
        gs_kernel_free(&k);
      }
      gs_cfg_free(kcfg);
      gs_case_free(&c);
    }
    double scale = 0, diff = 0;
    for (size_t k = 0; k < cells; k++) {
      scale = fmax(scale, fabs(d[0][k]));
      diff = fmax(diff, fabs(d[1][k] - d[0][k]));
    }
    printf("  %8d %8zu %12.4g %12.4g %9.3g %10.2g %12.4g %6d %10.4g %10.4g %10.3g %9.2g\n", n, cells, t0, t1, t0 / t1,
           diff / scale, setup, rank, t_aca, t_dense, t_dense / t_aca, e_aca);
    free(d[0]);
    free(d[1]);
  }
}

/* Seconds per right-hand side (fastest of the repeats that fit in about
 * 0.3 s) of the case yaml at state y0 (NULL: the dense exponential state
 * of time_rhs), rates into d (nstate). */
static double time_yaml(const char *yaml, const double *y0, double *d) {
  gs_error err = {0};
  gs_cfg *cfg = gs_cfg_load_string(yaml, "bench.yaml", &err);
  gs_case c;
  memset(&c, 0, sizeof c);
  if (!cfg || gs_case_from_cfg(cfg, &c, &err)) {
    fprintf(stderr, "case did not build: %s\n", err.msg);
    return NAN;
  }
  const gs_grid *g = &c.model.grid;
  for (size_t k = 0; k < g->ncells; k++) {
    double s = 0;
    for (int q = 0; q < g->dim; q++) s += g->x[k * (size_t)g->dim + (size_t)q] / g->axis[q].pivots[g->axis[q].n - 1];
    c.y0[k] = y0 ? y0[k] : exp(-3.0 * s);
  }
  return best_rhs(&c, d);
}

/* fixed pivot pairs against fft (the split) on geometric grids of ratio r,
 * constant kernel, dense state */
static void geometric_series(int dim, double r, const int *ns, int count) {
  printf("%d-D geometric grid, ratio %g, constant kernel, fixed pivot, one right-hand side:\n", dim, r);
  printf("  %8s %8s %12s %12s %9s %10s\n", "n/axis", "cells", "pairs [s]", "fft [s]", "pairs/fft", "difference");
  for (int i = 0; i < count; i++) {
    const int n = ns[i];
    size_t cells = 1;
    char axes[512] = "", yaml[1024];
    for (int q = 0; q < dim; q++) {
      char ax[128];
      snprintf(ax, sizeof ax, "%s{name: a%d, type: geometric, min: 1, ratio: %g, cells: %d}", q ? ", " : "", q, r, n);
      strcat(axes, ax);
      cells *= (size_t)n;
    }
    double *d[2] = {calloc(cells, sizeof(double)), calloc(cells, sizeof(double))}, t[2];
    const char *methods[2] = {"pairs", "fft"};
    for (int m = 0; m < 2; m++) {
      snprintf(yaml, sizeof yaml,
               "grid: {axes: [%s]}\ninitial: {type: cell, number: 1, index: [%s]}\nmechanisms:\n"
               "  - {type: aggregation, redistribution: fixed_pivot, method: %s, kernel: {type: constant, beta0: 1}}\n"
               "output: {end: 1}\n", axes, dim == 3 ? "1, 1, 1" : dim == 2 ? "1, 1" : "1", methods[m]);
      t[m] = time_yaml(yaml, NULL, d[m]);
    }
    double scale = 0, diff = 0;
    for (size_t k = 0; k < cells; k++) {
      scale = fmax(scale, fabs(d[0][k]));
      diff = fmax(diff, fabs(d[1][k] - d[0][k]));
    }
    printf("  %8d %8zu %12.4g %12.4g %9.3g %10.2g\n", n, cells, t[0], t[1], t[0] / t[1], diff / scale);
    free(d[0]);
    free(d[1]);
  }
}

/* The 3-D n = 26 Madec case: its state after 250 s (the case's own scheme),
 * then the aggregation rates there, fixed pivot pairs against fft. */
static void madec26(void) {
  FILE *f = fopen(BENCH_CASES "/madec-3d-26.yaml", "r");
  if (!f) {
    printf("3-D Madec n = 26: %s not found\n", BENCH_CASES "/madec-3d-26.yaml");
    return;
  }
  char base[4096];
  size_t len = fread(base, 1, sizeof base - 1, f);
  fclose(f);
  base[len] = 0;
  char *out = strstr(base, "output:");
  if (!out) return;
  *out = 0;
  char yaml[8192];
  snprintf(yaml, sizeof yaml, "%soutput: {end: 250}\n", base);
  gs_error err = {0};
  gs_cfg *cfg = gs_cfg_load_string(yaml, "madec-3d-26.yaml", &err);
  gs_case c;
  memset(&c, 0, sizeof c);
  if (!cfg || gs_case_from_cfg(cfg, &c, &err)) {
    printf("3-D Madec n = 26: %s\n", err.msg);
    return;
  }
  double *y = calloc(c.model.nstate + c.model.nledger, sizeof(double));
  gs_run_options opt = {0};
  gs_run_report rep;
  const double t0 = now();
  const int rc = gs_case_run(&c, &opt, y, &rep, &err);
  const double trun = now() - t0;
  const size_t cells = c.model.grid.ncells;
  size_t occupied = 0;
  for (size_t k = 0; k < cells; k++) occupied += y[k] > 0;
  gs_case_free(&c);
  if (rc) {
    printf("3-D Madec n = 26: the run to 250 s failed: %s\n", err.msg);
    free(y);
    return;
  }
  printf("3-D Madec n = 26 (%zu cells, %zu occupied after 250 s; that run took %.3g s wall):\n", cells, occupied, trun);
  double *d[2] = {calloc(cells, sizeof(double)), calloc(cells, sizeof(double))}, t[2];
  const char *methods[2] = {"pairs", "fft"};
  for (int m = 0; m < 2; m++) {
    /* aggregation alone: the rates of the other mechanisms are the same for both */
    char *mech = strstr(base, "mechanisms:");
    snprintf(yaml, sizeof yaml, "%.*smechanisms:\n  - {type: aggregation, redistribution: fixed_pivot, method: %s,"
             " kernel: {type: madec, beta0: 1.0e-2, alpha: 1, delta: 1}}\noutput: {end: 1}\n",
             (int)(mech - base), base, methods[m]);
    t[m] = time_yaml(yaml, y, d[m]);
  }
  double scale = 0, diff = 0;
  for (size_t k = 0; k < cells; k++) {
    scale = fmax(scale, fabs(d[0][k]));
    diff = fmax(diff, fabs(d[1][k] - d[0][k]));
  }
  printf("  aggregation right-hand side: pairs %.4g s, fft %.4g s, pairs/fft %.3g, difference %.2g\n", t[0], t[1],
         t[0] / t[1], diff / scale);
  free(d[0]);
  free(d[1]);
  free(y);
}

int main(int argc, char **argv) {
  size_t max_pairs = argc > 1 ? (size_t)atol(argv[1]) : 65536;
  omp_set_num_threads(1);
  setvbuf(stdout, NULL, _IOLBF, 0); /* lines as they come: the series take minutes */
  const int only_lowrank = argc > 2 && !strcmp(argv[2], "lowrank");
  if (argc > 2 && !strcmp(argv[2], "geometric")) {
    const int g1[] = {64, 128, 256, 512}, g2[] = {16, 32, 64}, g3[] = {8, 16, 26};
    geometric_series(1, 1.19, g1, 4);
    geometric_series(2, 1.6, g2, 3);
    geometric_series(3, 1.6, g3, 3);
    madec26();
    return 0;
  }
  const int n2[] = {8, 16, 32, 64, 128, 256};
  const int n1[] = {128, 256, 512, 1024, 2048, 4096, 8192, 16384, 32768, 65536};
  if (!only_lowrank) {
    series(2, n2, 6, max_pairs);
    series(1, n1, 10, max_pairs);
    printf("exp: cost exponent in n against the size above (n^d log n: a little above d for the FFT)\n");
  }
  /* the dense decomposition is O(cells^3): timed at 256 and 1 024 cells only
   * (2 304 take minutes on a loaded VM); 80 x 80 and 128 x 128 are above its
   * 4 096-cell limit */
  const int nl[] = {16, 32, 80, 128};
  lowrank_series("brownian free_molecular", "{type: brownian, regime: free_molecular, beta0: 1}", nl, 4);
  lowrank_series("madec alpha 0.8 delta 1.5", "{type: madec, beta0: 1, alpha: 0.8, delta: 1.5, liquid_content: fraction, liquid_axis: l}",
                 nl, 4);
  return 0;
}
