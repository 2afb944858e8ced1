/* Aggregation by FFT convolutions (src/pbm/aggregation_fft.c) against the
 * pair scheme (fixed pivot, same grid) and the discrete analytical solution.
 *
 *  - rates: on linear grids in 1-D, 2-D and 3-D, with populations that fill the
 *    grid (so products are placed, clamped to the last pivot and lost), the
 *    FFT's number rates, lost volumes and birth/death totals equal the pair
 *    loop's to 1e-12 of the largest rate, for the constant, sum and product
 *    kernels;
 *  - conservation: number (births - deaths = sum of rates) and the volume
 *    of every axis (placed + lost = 0) to 1e-12;
 *  - T1 discrete (constant kernel, pivots 1..K): the same tolerance as the
 *    pair scheme's in test_aggregation.c;
 *  - geometric, zero_first and explicit-edge grids (the near/far split,
 *    src/pbm/aggregation_split.c): the same comparison against the pairs,
 *    1-, 2- and 3-D, exact and low-rank kernel forms and the linear Madec
 *    kernel's separable terms (also on linear grids), all to 1e-12; and a
 *    broken split (far partners not moved to node i + 1) fails it;
 *  - T1 (constant kernel, exponential initial) on a geometric grid by the
 *    split: errors against the analytical solution those of the pairs;
 *  - method: auto takes the FFT on a large grid and the pairs on a small one
 *    (identical results bit for bit); method: fft refuses what it cannot do. */
#include <omp.h>

#include "pbm_testlib.h"

static const char *kernels[] = {"constant", "sum", "product"};

/* Case on a linear grid of n cells per axis (dim 1 or 2) with the given
 * method and kernel; its initial state replaced by fixed-seed random numbers
 * over the whole grid. */
static int random_case(int dim, int n, const char *method, const char *kernel, gs_case *c) {
  char *second = dim == 1 ? tl_fmt("%s", "")
                 : tl_fmt(", {name: l, type: linear, min: 0.25, max: 1.25, cells: %d}%s", n,
                          dim == 3 ? ", {name: g, type: linear, min: 0, max: 0.5, cells: 8}" : "");
  char *yaml = tl_fmt("grid: {axes: [{name: s, type: linear, min: 0, max: 2, cells: %d}%s]}\n"
                      "initial: {type: cell, number: 1, index: [%s]}\n"
                      "mechanisms:\n  - {type: aggregation, redistribution: fixed_pivot, method: %s,"
                      " negligible: 0, kernel: {type: %s, beta0: 1.5}}\n"
                      "output: {end: 1}\n",
                      n, second, dim == 3 ? "1, 1, 1" : dim == 2 ? "1, 1" : "1", method, kernel);
  free(second);
  int rc = tl_case(yaml, c);
  free(yaml);
  if (rc) return rc;
  tl_rng r = {42};
  for (size_t k = 0; k < c->model.grid.ncells; k++) c->y0[k] = tl_uniform(&r);
  return 0;
}

/* Cases c[0] (pairs) and c[1] (the fast scheme) with rates d, ledgers dl
 * and birth/death totals: rates, lost volumes and totals equal to 1e-12 of
 * the largest, number (births - deaths = sum of rates) and every axis's
 * volume (placed + lost = 0) conserved to 1e-12, products lost or clamped
 * on every axis.  Frees the cases; returns the largest rate difference
 * over the largest rate. */
static double compare_rates(gs_case *c, double **d, double **dl, const double *birth, const double *death,
                            const char *label) {
  const gs_model *m = &c[1].model;
  const gs_grid *g = &m->grid;
  const int dim = g->dim;
  double scale = 0, diff = 0, sum = 0, lostdiff = 0, volerr = 0;
  for (size_t k = 0; k < g->ncells; k++) {
    scale = fmax(scale, fabs(d[0][k]));
    diff = fmax(diff, fabs(d[1][k] - d[0][k]));
    sum += d[1][k];
  }
  for (int q = 0; q < dim; q++) {
    double vrate = 0, vscale = 0;
    for (size_t k = 0; k < g->ncells; k++) {
      vrate += d[1][k] * g->x[k * (size_t)dim + (size_t)q];
      vscale += fabs(d[1][k]) * g->x[k * (size_t)dim + (size_t)q];
    }
    const double l0 = tl_lost(m, dl[0], 0, q), l1 = tl_lost(m, dl[1], 0, q);
    lostdiff = fmax(lostdiff, fabs(l1 - l0) / vscale);
    volerr = fmax(volerr, fabs(vrate + l1) / vscale);
    CHECK(l1 > 0); /* products are clamped or lost: the ledger path is exercised */
  }
  const double nerr = fabs(sum - (birth[1] - death[1])) / death[1];
  const double berr = fmax(fabs(birth[1] - birth[0]), fabs(death[1] - death[0])) / death[0];
  printf("%s - pairs, largest rate %.3g, lost volume %.3g, totals %.3g; conservation: number %.3g, volume %.3g\n",
         label, diff / scale, lostdiff, berr, nerr, volerr);
  CHECK(diff <= 1e-12 * scale);
  CHECK(lostdiff <= 1e-12);
  CHECK(berr <= 1e-12);
  CHECK(nerr <= 1e-12);
  CHECK(volerr <= 1e-12);
  for (int s = 0; s < 2; s++) tl_rates_free(&c[s], d[s], dl[s]);
  return diff / scale;
}

static void test_rates_equal(void) {
  for (int dim = 1; dim <= 3; dim++)
    for (int kk = 0; kk < 3; kk++) {
      const int n = dim == 1 ? 200 : dim == 2 ? 24 : 8; /* 3-D: 8 x 8 x 8 */
      gs_case c[2];
      double *d[2], *dl[2], birth[2], death[2];
      const char *methods[2] = {"pairs", "fft"};
      int ok = 1;
      for (int s = 0; s < 2; s++) {
        if (random_case(dim, n, methods[s], kernels[kk], &c[s])) {
          ok = 0;
          continue;
        }
        d[s] = calloc(c[s].model.nstate, sizeof(double));
        dl[s] = calloc(c[s].model.nledger, sizeof(double));
        gs_model_rhs(&c[s].model, &c[s].eval, 0, c[s].y0, d[s], dl[s]);
        gs_mech_number_rates(&c[s].model, &c[s].model.mech[0], NULL, 0.0, c[s].y0, &birth[s], &death[s]);
      }
      CHECK(ok);
      if (!ok) continue;
      char *label = tl_fmt("%d-D %s kernel, %d cells per axis: FFT", dim, kernels[kk], n);
      compare_rates(c, d, dl, birth, death, label);
      free(label);
    }
}

/* T1 discrete on pivots 1..K (linear grid [1/2, K + 1/2]): products above K
 * leave the grid (their volume to the ledger) without touching c_k, k <= K.
 * The FFT's error is absolute (round-off of the largest rates, ~1e-16 of
 * c_1 per evaluation), not relative per cell like the pairs': the pair
 * scheme's tolerance (5e-10 relative, measured 1.4e-10) holds for c_k >=
 * 1e-6, and the absolute error of every c_k must stay below 1e-13 (measured
 * 1.0e-14; c_40 = 4.5e-13 has a relative error of 1.3e-6). */
static void test_t1_discrete(void) {
  const int K = 40;
  char *yaml = tl_fmt("grid: {axes: [{name: v, type: linear, min: 0.5, max: %g, cells: %d}]}\n"
                      "initial: {type: cell, number: 1, index: [1]}\n"
                      "mechanisms:\n  - {type: aggregation, redistribution: fixed_pivot, method: fft,\n"
                      "     kernel: {type: constant, beta0: 1}}\n"
                      "output: {times: [0.5, 2]}\n"
                      "solver: {method: rk, variant: rk8pd, rtol: 1.0e-10, atol: 1.0e-16}\n",
                      K + 0.5, K);
  gs_case c;
  gs_run_report rep;
  double *y = tl_build_run(yaml, &c, &rep);
  if (y) {
    double tau = 2, worst = 0, worst_abs = 0;
    int kmax = 0;
    for (int k = 1; k <= K; k++) {
      double want = pow(tau / 2, k - 1) / pow(1 + tau / 2, k + 1), e = fabs(y[k - 1] - want);
      if (want >= 1e-6) {
        worst = fmax(worst, e / want);
        kmax = k;
      }
      worst_abs = fmax(worst_abs, e);
    }
    printf("T1 discrete, fft: largest relative error of c_k >= 1e-6 (k = 1..%d) at tau = 2: %.3g; "
           "largest absolute error, k = 1..%d: %.3g (c_1 = 0.25)\n", kmax, worst, K, worst_abs);
    CHECK(worst < 5e-10);
    CHECK(worst_abs < 1e-13);
    free(y);
    gs_case_free(&c);
  }
  free(yaml);
}

/* A population in cells 3 and 4 of 64: the births fall on index sums 6..8
 * alone, and every cell the pairs leave at exactly 0 (no event reaches it)
 * stays exactly 0 under the FFT too (not round-off of either sign). */
static void test_unreached_cells(void) {
  gs_case c[2];
  double *d[2], *dl[2];
  const char *methods[2] = {"pairs", "fft"};
  for (int s = 0; s < 2; s++) {
    char *yaml = tl_fmt("grid: {axes: [{name: v, type: linear, min: 0, max: 1, cells: 64}]}\n"
                        "initial: {type: cell, number: 1, index: [3]}\n"
                        "mechanisms:\n  - {type: aggregation, redistribution: fixed_pivot, method: %s,"
                        " kernel: {type: constant, beta0: 1}}\n"
                        "output: {end: 1}\n",
                        methods[s]);
    if (tl_case(yaml, &c[s])) {
      free(yaml);
      return;
    }
    free(yaml);
    memset(c[s].y0, 0, c[s].model.grid.ncells * sizeof(double));
    c[s].y0[3] = 1.0;
    c[s].y0[4] = 0.5;
    d[s] = calloc(c[s].model.nstate, sizeof(double));
    dl[s] = calloc(c[s].model.nledger, sizeof(double));
    gs_model_rhs(&c[s].model, &c[s].eval, 0, c[s].y0, d[s], dl[s]);
  }
  int zeros = 0, stray = 0;
  for (size_t k = 0; k < 64; k++)
    if (d[0][k] == 0.0) {
      zeros++;
      stray += d[1][k] != 0.0;
    }
  printf("population in cells 3, 4: %d cells without events, %d of them with FFT rates\n", zeros, stray);
  CHECK(zeros >= 56);
  CHECK(stray == 0);
  for (int s = 0; s < 2; s++) tl_rates_free(&c[s], d[s], dl[s]);
}

/* auto: the FFT from 256 cells on, else the pairs; the choice shows as
 * rates identical bit for bit to one method's. */
static void test_auto(void) {
  for (int i = 0; i < 2; i++) {
    const int n = i == 0 ? 15 : 16; /* 2-D: 225 and 256 cells */
    gs_case c[3];
    double *d[3], *dl[3];
    const char *methods[3] = {"auto", "pairs", "fft"};
    int ok = 1;
    for (int s = 0; s < 3; s++) {
      if (random_case(2, n, methods[s], "sum", &c[s])) {
        ok = 0;
        continue;
      }
      d[s] = calloc(c[s].model.nstate, sizeof(double));
      dl[s] = calloc(c[s].model.nledger, sizeof(double));
      gs_model_rhs(&c[s].model, &c[s].eval, 0, c[s].y0, d[s], dl[s]);
    }
    CHECK(ok);
    if (!ok) continue;
    const size_t nc = c[0].model.grid.ncells;
    const int same_pairs = !memcmp(d[0], d[1], nc * sizeof(double));
    const int same_fft = !memcmp(d[0], d[2], nc * sizeof(double));
    printf("auto, %zu cells: same as pairs %d, same as fft %d\n", nc, same_pairs, same_fft);
    CHECK(i == 0 ? same_pairs && !same_fft : same_fft && !same_pairs);
    for (int s = 0; s < 3; s++) tl_rates_free(&c[s], d[s], dl[s]);
  }
}

/* Four compartments with their own beta0, evaluated by two threads (each
 * with its own FFT scratch): the FFT's rates equal the pairs' in every
 * compartment; for the sum kernel, and for the continuum Brownian kernel
 * through its low-rank form (exact rank 3, one decomposition per
 * compartment). */
static void test_compartments_threads(const char *kernel, const char *fft) {
  omp_set_num_threads(2);
  gs_case c[2];
  double *d[2], *dl[2];
  const char *methods[2] = {"pairs", fft};
  int ok = 1;
  for (int s = 0; s < 2; s++) {
    char *yaml = tl_fmt("grid: {compartments: 4, axes: [{name: s, type: linear, min: 0, max: 2, cells: 12},"
                        " {name: l, type: linear, min: 0, max: 1, cells: 12}]}\n"
                        "initial: {type: cell, number: 1, index: [1, 1]}\n"
                        "mechanisms:\n  - {type: aggregation, redistribution: fixed_pivot, method: %s,"
                        " negligible: 0, kernel: {type: %s, beta0: [1, 2, 3, 4]}}\n"
                        "output: {end: 1}\n",
                        methods[s], kernel);
    if (tl_case(yaml, &c[s])) {
      ok = 0;
      free(yaml);
      continue;
    }
    free(yaml);
    tl_rng r = {7};
    for (size_t k = 0; k < c[s].model.nstate; k++) c[s].y0[k] = tl_uniform(&r);
    d[s] = calloc(c[s].model.nstate, sizeof(double));
    dl[s] = calloc(c[s].model.nledger, sizeof(double));
    gs_model_rhs(&c[s].model, &c[s].eval, 0, c[s].y0, d[s], dl[s]);
  }
  omp_set_num_threads(1);
  CHECK(ok);
  if (!ok) return;
  const size_t nc = c[0].model.grid.ncells;
  double worst = 0;
  for (size_t comp = 0; comp < 4; comp++) {
    double scale = 0, diff = 0;
    for (size_t k = comp * nc; k < (comp + 1) * nc; k++) {
      scale = fmax(scale, fabs(d[0][k]));
      diff = fmax(diff, fabs(d[1][k] - d[0][k]));
    }
    worst = fmax(worst, diff / scale);
  }
  printf("4 compartments, %s kernel, beta0 1..4, 2 threads: %s - pairs, largest rate %.3g\n", kernel, fft, worst);
  CHECK(worst <= 1e-12);
  for (int s = 0; s < 2; s++) tl_rates_free(&c[s], d[s], dl[s]);
}

/* The axes of the non-uniform grids: geometric of ratios 1.6 and 1.15 (a
 * band of 2 and 29 near partners), zero_first (a pivot at 0, which every
 * cell takes as a far partner) and explicit uneven edges. */
static const char *nonuniform_axes[] = {
    "{name: s, type: geometric, min: 0.01, ratio: 1.6, cells: %d}",
    "{name: l, type: geometric, min: 0.002, ratio: 1.15, cells: %d, zero_first: true}",
    "{name: g, type: edges, edges: [0, 0.1, 0.15, 0.4, 0.45, 1.3, 1.4, 4]}",
};

/* The rates of a case with a fixed-seed random population over the whole
 * grid: d and the ledger dl (allocated) and the birth and death totals. */
static int rates_of(const char *yaml, unsigned long seed, gs_case *c, double **d, double **dl, double *birth,
                    double *death) {
  if (tl_case(yaml, c)) return 1;
  tl_rng r = {seed};
  for (size_t k = 0; k < c->model.nstate; k++) c->y0[k] = tl_uniform(&r);
  *d = calloc(c->model.nstate, sizeof(double));
  *dl = calloc(c->model.nledger, sizeof(double));
  gs_model_rhs(&c->model, &c->eval, 0, c->y0, *d, *dl);
  gs_mech_number_rates(&c->model, &c->model.mech[0], NULL, 0.0, c->y0, birth, death);
  return 0;
}

/* fft on non-uniform grids against the pairs: rates, lost volumes and
 * totals to 1e-12 of the largest; conservation of number and of every
 * axis's volume to 1e-12.  Returns the largest rate difference. */
static double nonuniform_case(int dim, int n, const char *kernel, const char *extra) {
  char *axes = tl_fmt(nonuniform_axes[0], n);
  for (int q = 1; q < dim; q++) {
    char *ax = tl_fmt(nonuniform_axes[q], n), *all = tl_fmt("%s, %s", axes, ax);
    free(ax);
    free(axes);
    axes = all;
  }
  gs_case c[2];
  double *d[2], *dl[2], birth[2], death[2];
  const char *methods[2] = {"pairs", "fft"};
  int ok = 1;
  for (int s = 0; s < 2; s++) {
    char *yaml = tl_fmt("grid: {axes: [%s]}\n"
                        "initial: {type: cell, number: 1, index: [%s]}\n"
                        "mechanisms:\n  - {type: aggregation, redistribution: fixed_pivot, method: %s%s,"
                        " negligible: 0, kernel: {type: %s, beta0: 1.5}}\n"
                        "output: {end: 1}\n",
                        axes, dim == 3 ? "1, 1, 1" : dim == 2 ? "1, 1" : "1", methods[s], s ? extra : "", kernel);
    ok &= !rates_of(yaml, 11, &c[s], &d[s], &dl[s], &birth[s], &death[s]);
    free(yaml);
  }
  free(axes);
  CHECK(ok);
  if (!ok) return INFINITY;
  char *label = tl_fmt("%d-D non-uniform, %s kernel%s, %zu cells: split", dim, kernel, extra,
                       c[1].model.grid.ncells);
  const double diff = compare_rates(c, d, dl, birth, death, label);
  free(label);
  return diff;
}

static void test_nonuniform_rates(void) {
  for (int dim = 1; dim <= 3; dim++)
    for (int kk = 0; kk < 3; kk++) {
      const int n = dim == 1 ? 120 : dim == 2 ? 30 : 12;
      CHECK(nonuniform_case(dim, n, kernels[kk], "") <= 1e-12);
    }
  /* low-rank forms: continuum Brownian (exact rank 3) */
  CHECK(nonuniform_case(1, 40, "brownian", ", rank_tolerance: 1.0e-10") <= 1e-12);
  CHECK(nonuniform_case(2, 24, "brownian", ", rank_tolerance: 1.0e-10") <= 1e-12);
  /* the linear Madec kernel's own separable terms (ten, six functions) */
  CHECK(nonuniform_case(2, 30, "madec, liquid_axis: l", "") <= 1e-12);
  CHECK(nonuniform_case(3, 12, "madec, liquid_axis: l, liquid_content: fraction", "") <= 1e-12);
}

/* T1 (constant kernel, exponential initial, N0 = v0 = beta0 = 1) to tau =
 * 10 on the zero_first geometric grid of ratio 2^(1/4) of test_aggregation.c:
 * method fft (the split) against the analytical solution, with the pairs'
 * errors on the same grid as the yardstick (the two schemes are the same
 * fixed pivot, so their errors must agree to the integrator's tolerance). */
static double t1_density(double v, void *p) {
  const double tau = *(const double *)p;
  return 4 / ((tau + 2) * (tau + 2)) * exp(-2 * v / (tau + 2));
}

static void test_t1_geometric(void) {
  const double ratio = pow(2, 0.25), tau = 10;
  const int cells = 1 + (int)ceil(log(3e2 / 1e-3) / log(ratio));
  double err[2][3];
  const char *methods[2] = {"pairs", "fft"};
  for (int s = 0; s < 2; s++) {
    char *yaml = tl_fmt("grid: {axes: [{name: v, type: geometric, min: 1.0e-3, ratio: %.17g, cells: %d, zero_first: true}]}\n"
                        "initial: {type: exponential, number: 1, mean: 1}\n"
                        "mechanisms:\n  - {type: aggregation, redistribution: fixed_pivot, method: %s,"
                        " kernel: {type: constant, beta0: 1}}\n"
                        "output: {times: [2, 10]}\n",
                        ratio, cells, methods[s]);
    gs_case c;
    gs_run_report rep;
    double *y = tl_build_run(yaml, &c, &rep);
    free(yaml);
    CHECK(y != NULL);
    if (!y) return;
    const double M0 = tl_mom(&c, y, 0, 0, 0, 0), M1 = tl_mom(&c, y, 0, 1, 0, 0), M2 = tl_mom(&c, y, 0, 2, 0, 0);
    err[s][0] = tl_relerr(M0, 2 / (2 + tau));
    err[s][1] = tl_relerr(M2, 2 + M1 * M1 * tau);
    const gs_axis *ax = &c.model.grid.axis[0];
    double *P = malloc(ax->n * sizeof(double)), t = tau;
    tl_project(ax, t1_density, &t, P);
    err[s][2] = tl_wl1(ax, y, P);
    free(P);
    free(y);
    gs_case_free(&c);
  }
  printf("T1 exponential, geometric 2^(1/4), %d cells, tau = 10: fft (split) M0 %.3g M2 %.3g dist %.3g; "
         "pairs M0 %.3g M2 %.3g dist %.3g\n", cells, err[1][0], err[1][1], err[1][2], err[0][0], err[0][1], err[0][2]);
  /* test_aggregation.c's tolerances for fixed pivot on this grid */
  CHECK(err[1][0] < 3e-8);
  CHECK(err[1][1] < 0.03);
  CHECK(err[1][2] < 0.035);
  for (int k = 1; k < 3; k++) CHECK(fabs(err[1][k] - err[0][k]) <= 1e-3 * err[0][k]);
}

/* auto on geometric grids: the split in 2-D (32 x 32, ratio 1.6: its work
 * within cells^2 / 8), the pairs in 3-D (sparse 3-D states ran faster on the
 * pairs) and on a 2-D grid too small to pay; bit for bit one method's rates. */
static void test_auto_geometric(void) {
  const int dims[3] = {2, 3, 2}, ns[3] = {32, 8, 12}, want_split[3] = {1, 0, 0};
  for (int i = 0; i < 3; i++) {
    char axes[256] = "";
    for (int q = 0; q < dims[i]; q++) {
      char *ax = tl_fmt("%s{name: a%d, type: geometric, min: 1, ratio: 1.6, cells: %d}", q ? ", " : "", q, ns[i]);
      strcat(axes, ax);
      free(ax);
    }
    gs_case c[3];
    double *d[3], *dl[3], b, e;
    const char *methods[3] = {"auto", "pairs", "fft"};
    int ok = 1;
    for (int s = 0; s < 3; s++) {
      char *yaml = tl_fmt("grid: {axes: [%s]}\ninitial: {type: cell, number: 1, index: [%s]}\n"
                          "mechanisms:\n  - {type: aggregation, redistribution: fixed_pivot, method: %s,"
                          " negligible: 0, kernel: {type: constant, beta0: 1}}\noutput: {end: 1}\n",
                          axes, dims[i] == 3 ? "1, 1, 1" : "1, 1", methods[s]);
      ok &= !rates_of(yaml, 5, &c[s], &d[s], &dl[s], &b, &e);
      free(yaml);
    }
    CHECK(ok);
    if (!ok) continue;
    const size_t nc = c[0].model.grid.ncells;
    const int same_pairs = !memcmp(d[0], d[1], nc * sizeof(double));
    const int same_fft = !memcmp(d[0], d[2], nc * sizeof(double));
    printf("auto, %d-D geometric, %zu cells: same as pairs %d, same as fft (split) %d\n", dims[i], nc, same_pairs, same_fft);
    CHECK(want_split[i] ? same_fft && !same_pairs : same_pairs && !same_fft);
    for (int s = 0; s < 3; s++) tl_rates_free(&c[s], d[s], dl[s]);
  }
}

static void test_refusals(void) {
  EXPECT_INPUT("grid: {axes: [{name: v, type: linear, min: 0, max: 1, cells: 8}]}\n"
               "initial: {type: cell, number: 1, index: [1]}\n"
               "mechanisms:\n  - {type: aggregation, method: fft, kernel: {type: constant, beta0: 1}}\n"
               "output: {end: 1}\n",
               "bad.yaml:4", "method", "fft needs redistribution: fixed_pivot");
  EXPECT_INPUT("grid: {axes: [{name: v, type: linear, min: 0, max: 1, cells: 8}]}\n"
               "initial: {type: cell, number: 1, index: [1]}\n"
               "mechanisms:\n  - {type: aggregation, redistribution: fixed_pivot, method: fft,"
               " kernel: {type: brownian, beta0: 1}}\n"
               "output: {end: 1}\n",
               "fft needs a kernel of separable form");
  EXPECT_INPUT("grid: {axes: [{name: v, type: linear, min: 0, max: 1, cells: 8}]}\n"
               "initial: {type: cell, number: 1, index: [1]}\n"
               "mechanisms:\n  - {type: aggregation, redistribution: fixed_pivot, method: fast,"
               " kernel: {type: constant, beta0: 1}}\n"
               "output: {end: 1}\n",
               "method", "fast");
}

int main(void) {
  omp_set_num_threads(1);
  test_rates_equal();
  test_nonuniform_rates();
  test_t1_geometric();
  test_t1_discrete();
  test_unreached_cells();
  test_auto();
  test_auto_geometric();
  test_compartments_threads("sum", "fft");
  test_compartments_threads("brownian", "fft, rank_tolerance: 1.0e-10");
  test_compartments_threads("madec, liquid_axis: l", "fft");
  test_refusals();
  TEST_EXIT();
}
