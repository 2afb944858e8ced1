/* Low-rank kernel forms through the FFT (src/kernel/lowrank.c: adaptive
 * cross approximation; lowrank_dense.c: the dense eigendecomposition;
 * src/pbm/aggregation_fft.c) against the pair scheme on the same grid.
 *
 *  - the cross approximation against the dense decomposition at every
 *    tolerance of the table: the same rank, errors equal to 2 % of the
 *    tolerance; exact ranks recovered exactly and without the fallback; the
 *    semi-mechanistic kernel's Stokes cut (high rank) takes the fallback;
 *  - above the dense limit (2-D 80 x 80 = 6 400 cells): accepted, rates
 *    against the pair loop on every cell within 10 tol, error estimated from
 *    256 sampled rows within tol, conservation to round-off; a form of more
 *    than 512 terms on 4 913 cells refused at its key (method auto: pairs);
 *  - exact ranks: the product and constant kernels are rank 1 and the sum
 *    kernel rank 2 (the truncated form rebuilds the matrix to 1e-13), the
 *    continuum Brownian kernel 2 + r + 1/r is rank 3 on any grid, and its
 *    FFT rates equal the pairs' to 1e-12 of the largest rate;
 *  - tolerance 1e-8: Madec (2-D) and free-molecular Brownian (1-D) rates
 *    equal the pairs' to 1e-7 of the largest rate;
 *  - conservation: number (births - deaths = sum of rates) and every axis's
 *    volume (placed + lost = 0) to 1e-12, at every rank;
 *  - the rank is the smallest whose dropped singular values stay within the
 *    tolerance, checked against GSL's eigenvalues of the same matrix (a truncation
 *    one term short or long fails), and the rate error of each rank is
 *    printed as the table of docs/validation.md;
 *  - a whole run (Madec, 2-D) with rank_tolerance 1e-8 ends where the pairs'
 *    does to 1e-7;
 *  - method auto takes the low-rank FFT while rank <= cells / 64, else pairs;
 *  - (compartments with their own beta0, one decomposition each, under two
 *    threads: test_aggregation_fft.c, test_compartments_threads);
 *  - refusals: rank_tolerance with method pairs, out of range, rank above the cap. */
#include <gsl/gsl_eigen.h>
#include <time.h>
#include <unistd.h>

#include "kernel/lowrank.h"
#include "pbm/aggregation_fft.h"
#include "pbm_testlib.h"

static double tl_now(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* A case with method pairs and the kernel of kyaml on a linear grid of n
 * cells per axis (dim 1: volume; dim 2: solid and liquid), its state fixed-
 * seed random numbers, and the same kernel created on its grid. */
typedef struct {
  gs_case c;
  gs_cfg *cfg;
  gs_kernel k;
  int ok;
} fix;

static char *case_yaml(int dim, int n, const char *kyaml, const char *method) {
  /* dim 3: the semi-mechanistic kernel's axes in SI (granules of ~0.1 mm) */
  char *axes = dim == 1 ? tl_fmt("{name: solid, type: linear, min: 0.25, max: 2, cells: %d}", n)
               : dim == 2 ? tl_fmt("{name: solid, type: linear, min: 0.25, max: 2, cells: %d},"
                                   " {name: liquid, type: linear, min: 0.05, max: 0.6, cells: %d}", n, n)
                          : tl_fmt("{name: solid, type: linear, min: 2.0e-13, max: 4.0e-12, cells: %d},"
                                   " {name: liquid, type: linear, min: 1.0e-14, max: 1.0e-12, cells: %d},"
                                   " {name: gas, type: linear, min: 1.0e-14, max: 1.0e-12, cells: %d}", n, n, n);
  char *yaml = tl_fmt("grid: {axes: [%s]}\n"
                      "initial: {type: cell, number: 1, index: [%s]}\n"
                      "mechanisms:\n  - {type: aggregation, redistribution: fixed_pivot, negligible: 0,"
                      " %s, kernel: %s}\n"
                      "output: {end: 1}\n",
                      axes, dim == 3 ? "1, 1, 1" : dim == 2 ? "1, 1" : "1", method, kyaml);
  free(axes);
  return yaml;
}

/* A kernel table of nclass classes over volumes [0.2, 2.1] (the 1-D grid's
 * cells map onto them), C_ij = (i + 1)(j + 1) when rank1, else a fixed-seed
 * random symmetric matrix; returns the kernel's YAML (malloc'ed). */
static char *table_kernel(int nclass, int rank1, const char *path) {
  FILE *f = fopen(path, "w");
  if (!f) return NULL;
  fprintf(f, "edges");
  for (int i = 0; i <= nclass; i++) fprintf(f, ", %.17g", 0.2 + 1.9 * i / nclass);
  fprintf(f, "\n");
  tl_rng r = {5};
  double C[16][16];
  for (int i = 0; i < nclass; i++)
    for (int j = 0; j <= i; j++) C[i][j] = C[j][i] = rank1 ? (i + 1.0) * (j + 1.0) : tl_uniform(&r);
  for (int i = 0; i < nclass; i++)
    for (int j = 0; j < nclass; j++) fprintf(f, "%.17g%s", C[i][j], j + 1 < nclass ? ", " : "\n");
  fclose(f);
  return tl_fmt("{type: table, file: %s, beta0: 1.5}", path);
}

static int fix_make_m(int dim, int n, const char *kyaml, const char *method, fix *f) {
  memset(f, 0, sizeof *f);
  char *yaml = case_yaml(dim, n, kyaml, method);
  int rc = tl_case(yaml, &f->c);
  free(yaml);
  if (rc) return rc;
  tl_rng r = {42};
  for (size_t k = 0; k < f->c.model.grid.ncells; k++) f->c.y0[k] = tl_uniform(&r);
  gs_error err;
  f->cfg = gs_cfg_load_string(kyaml, "kernel", &err);
  if (!f->cfg || gs_kernel_create(gs_cfg_root(f->cfg), &f->c.model.grid, ".", &f->k, &err)) {
    fprintf(stderr, "kernel %s: %s\n", kyaml, err.msg);
    check_failures++;
    gs_cfg_free(f->cfg);
    gs_case_free(&f->c);
    return 1;
  }
  f->ok = 1;
  return 0;
}

static int fix_make(int dim, int n, const char *kyaml, fix *f) { return fix_make_m(dim, n, kyaml, "method: pairs", f); }

static void fix_free(fix *f) {
  if (!f->ok) return;
  gs_kernel_free(&f->k);
  gs_cfg_free(f->cfg);
  gs_case_free(&f->c);
}

typedef struct {
  int rank;
  double rel_err; /* of the truncation (Frobenius) */
  double diff;    /* largest |FFT - pairs| rate over the largest pairs rate */
  double tot;     /* births and deaths totals, relative */
  double nerr, verr; /* conservation of the FFT's number and volume */
} cmp_t;

/* The FFT with a low-rank form of tolerance tol against the pair loop. */
static int compare(fix *f, double tol, cmp_t *o) {
  const gs_model *m = &f->c.model;
  const gs_grid *g = &m->grid;
  const int dim = g->dim;
  gs_error err;
  gs_agg_fft *F = NULL;
  if (gs_agg_fft_create(g, &f->k, tol, 1, &F, &err)) {
    fprintf(stderr, "fft: %s\n", err.msg);
    check_failures++;
    return 1;
  }
  o->rank = gs_agg_fft_rank(F, &o->rel_err);
  double *d0 = calloc(m->nstate, sizeof(double)), *dl0 = calloc(m->nledger, sizeof(double));
  double *d1 = calloc(g->ncells, sizeof(double));
  double lost[3] = {0, 0, 0}, born = 0, dead = 0, b0 = 0, x0 = 0;
  gs_model_rhs(m, &f->c.eval, 0, f->c.y0, d0, dl0);
  gs_mech_number_rates(m, &m->mech[0], NULL, 0.0, f->c.y0, &b0, &x0);
  gs_agg_fft_rates(F, 0, f->c.y0, 0, d1, lost, &born, &dead);
  double scale = 0, diff = 0, sum = 0;
  for (size_t k = 0; k < g->ncells; k++) {
    scale = fmax(scale, fabs(d0[k]));
    diff = fmax(diff, fabs(d1[k] - d0[k]));
    sum += d1[k];
  }
  o->diff = diff / scale;
  o->tot = fmax(fabs(born - b0), fabs(dead - x0)) / x0;
  o->nerr = fabs(sum - (born - dead)) / dead;
  o->verr = 0;
  for (int q = 0; q < dim; q++) {
    double vrate = 0, vscale = 0;
    for (size_t k = 0; k < g->ncells; k++) {
      vrate += d1[k] * g->x[k * (size_t)dim + (size_t)q];
      vscale += fabs(d1[k]) * g->x[k * (size_t)dim + (size_t)q];
    }
    o->verr = fmax(o->verr, fabs(vrate + lost[q]) / vscale);
  }
  free(d0);
  free(dl0);
  free(d1);
  gs_agg_fft_free(F);
  return 0;
}

/* The largest |B_ab - sum_r lambda_r v_r(a) v_r(b)| over the largest |B_ab|. */
static double rebuild_error(const gs_kernel *k, size_t n, const gs_kernel_lowrank *lr) {
  double *row = malloc(n * sizeof(double)), worst = 0, big = 0;
  for (size_t a = 0; a < n; a++) {
    k->type->row(k->self, 0, a, 0, n, row);
    for (size_t b = 0; b < n; b++) {
      double s = 0;
      for (int r = 0; r < lr->rank; r++) s += lr->lambda[r] * lr->vec[(size_t)r * n + a] * lr->vec[(size_t)r * n + b];
      worst = fmax(worst, fabs(s - row[b]));
      big = fmax(big, fabs(row[b]));
    }
  }
  free(row);
  return worst / big;
}

static void test_exact_ranks(void) {
  char path[2][64];
  char *tables[2];
  for (int i = 0; i < 2; i++) {
    snprintf(path[i], sizeof path[i], "/tmp/gs_lowrank_table_%d_%ld.csv", i, (long)getpid());
    tables[i] = table_kernel(5, i == 0, path[i]);
    CHECK(tables[i] != NULL);
  }
  const struct {
    const char *kernel;
    int dim, rank, lowrank; /* lowrank: no exact form of its own (2: separable terms of its own,
                             * which the FFT takes instead of a low-rank form: no rank) */
  } cases[] = {
      {"{type: constant, beta0: 1.5}", 1, 1, 0},
      {"{type: product, beta0: 1.5}", 2, 1, 0},
      {"{type: sum, beta0: 1.5}", 2, 2, 0},
      {"{type: brownian, beta0: 1.5}", 1, 3, 1},
      {"{type: brownian, beta0: 1.5}", 2, 3, 1},
      /* (V + V') c (1 - c/2), c = c_a + c_b: degree 1 in V, 2 in c */
      {"{type: madec, beta0: 1.5, liquid_content: fraction}", 2, 6, 2},
      /* cells take their class's entries: the rank of C */
      {tables[0], 1, 1, 1},
      {tables[1], 1, 5, 1},
      /* below the Stokes cut (viscosity 0.1: every pair's Stokes number under
       * the critical one) the product of the wet-area fractions: rank 1 */
      {"{type: semi_mechanistic, beta0: 5.0e-9, velocity: 0.5, viscosity: 0.1, contact_angle: 60,"
       " solid_density: 1500, critical_saturation: 0.05}", 3, 1, 1},
  };
  for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
    fix f;
    if (fix_make(cases[i].dim, cases[i].dim == 1 ? 200 : cases[i].dim == 2 ? 16 : 8, cases[i].kernel, &f)) continue;
    const size_t n = f.c.model.grid.ncells;
    gs_kernel_lowrank lr;
    gs_error err;
    CHECK(gs_kernel_lowrank_build(&f.k, n, 0, 1e-10, &lr, &err) == 0);
    const double e = rebuild_error(&f.k, n, &lr);
    printf("%s on %d-D, %zu cells: rank %d (expected %d) at tolerance 1e-10, largest entry error %.3g\n",
           cases[i].kernel, cases[i].dim, n, lr.rank, cases[i].rank, e);
    CHECK(lr.rank == cases[i].rank);
    CHECK(e <= 1e-13);
    CHECK(!lr.dense && lr.sampled_rows == 0); /* the cross approximation, its error over every entry */
    gs_kernel_lowrank_free(&lr);
    if (cases[i].lowrank) {
      /* the kernels without an exact form through the FFT: no truncation, so round-off alone */
      cmp_t o;
      if (!compare(&f, 1e-10, &o)) {
        printf("  FFT - pairs: largest rate %.3g, totals %.3g; conservation: number %.3g, volume %.3g\n", o.diff,
               o.tot, o.nerr, o.verr);
        CHECK(o.rank == (cases[i].lowrank == 2 ? 0 : cases[i].rank));
        CHECK(o.diff <= 1e-12);
        CHECK(o.tot <= 1e-12);
        CHECK(o.nerr <= 1e-12);
        CHECK(o.verr <= 1e-12);
      }
    }
    fix_free(&f);
  }
  for (int i = 0; i < 2; i++) {
    free(tables[i]);
    remove(path[i]);
  }
}

static int by_magnitude(const void *x, const void *y) {
  const double a = fabs(*(const double *)x), b = fabs(*(const double *)y);
  return (a < b) - (a > b);
}

/* The smallest r with sum_{i >= r} sigma_i^2 <= tol^2 sum sigma_i^2, the
 * singular values sigma_i = |lambda_i| from GSL's symmetric QR eigenvalue
 * solver (another algorithm than LAPACK's dsyevr in lowrank.c) of the
 * symmetrised kernel matrix. */
static int svd_rank(const gs_kernel *k, size_t n, const double *tols, int ntol, int *ranks) {
  gsl_matrix *A = gsl_matrix_alloc(n, n);
  gsl_vector *S = gsl_vector_alloc(n);
  gsl_eigen_symm_workspace *w = gsl_eigen_symm_alloc(n);
  double *row = malloc(n * sizeof(double));
  for (size_t a = 0; a < n; a++) {
    k->type->row(k->self, 0, a, 0, n, row);
    for (size_t b = 0; b < n; b++) gsl_matrix_set(A, a, b, row[b]);
  }
  for (size_t a = 0; a < n; a++)
    for (size_t b = 0; b < a; b++) {
      double s = 0.5 * (gsl_matrix_get(A, a, b) + gsl_matrix_get(A, b, a));
      gsl_matrix_set(A, a, b, s);
      gsl_matrix_set(A, b, a, s);
    }
  int rc = gsl_eigen_symm(A, S, w);
  qsort(S->data, n, sizeof(double), by_magnitude);
  double total = 0;
  for (size_t i = 0; i < n; i++) total += gsl_vector_get(S, i) * gsl_vector_get(S, i);
  for (int t = 0; t < ntol; t++) {
    double tail = 0;
    size_t r = n;
    while (r > 0 && tail + gsl_vector_get(S, r - 1) * gsl_vector_get(S, r - 1) <= tols[t] * tols[t] * total) {
      r--;
      tail += gsl_vector_get(S, r) * gsl_vector_get(S, r);
    }
    ranks[t] = (int)r;
  }
  free(row);
  gsl_eigen_symm_free(w);
  gsl_vector_free(S);
  gsl_matrix_free(A);
  return rc;
}

/* The rank/tolerance trade-off (docs/validation.md): per kernel and
 * tolerance, the rank, the truncation's Frobenius error and the rates'
 * error against the pairs, with the rank checked against GSL's eigenvalues. */
static void test_tolerances(void) {
  static const struct {
    const char *name, *kernel;
    int dim, n;
  } cases[] = {
      {"brownian free_molecular, 1-D 400 cells", "{type: brownian, regime: free_molecular, beta0: 1}", 1, 400},
      {"madec alpha 0.8 delta 1.5, 2-D 24 x 24 cells",
       "{type: madec, beta0: 1, alpha: 0.8, delta: 1.5, liquid_content: fraction}", 2, 24},
      {"semi_mechanistic, 3-D 8 x 8 x 8 cells",
       "{type: semi_mechanistic, beta0: 5.0e-9, velocity: 0.5, viscosity: 0.01, contact_angle: 60,"
       " solid_density: 1500, critical_saturation: 0.05}", 3, 8},
  };
  /* not below 1e-8: the SVDs' round-off (1e-16 of the largest singular
   * value, a few hundred of them) would decide the rank */
  const double tols[] = {1e-1, 1e-2, 1e-3, 1e-4, 1e-6, 1e-8};
  const int ntol = (int)(sizeof tols / sizeof tols[0]);
  static char aca_rows[8192]; /* the cross approximation against the dense decomposition, printed after */
  size_t used = 0;
  printf("\n| kernel, grid | rank_tolerance | rank | truncation error (Frobenius) | FFT - pairs, largest rate "
         "| number conservation | volume conservation |\n|---|---|---|---|---|---|---|\n");
  for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
    fix f;
    if (fix_make(cases[i].dim, cases[i].n, cases[i].kernel, &f)) continue;
    int want[8];
    CHECK(svd_rank(&f.k, f.c.model.grid.ncells, tols, ntol, want) == 0);
    int last = 0;
    for (int t = 0; t < ntol; t++) {
      cmp_t o;
      if (compare(&f, tols[t], &o)) continue;
      printf("| %s | %.0e | %d (GSL: %d) | %.2e | %.2e | %.1e | %.1e |\n", cases[i].name, tols[t], o.rank, want[t],
             o.rel_err, o.diff, o.nerr, o.verr);
      CHECK(o.rank == want[t]);
      CHECK(o.rank >= last);
      CHECK(o.rel_err <= tols[t]);
      /* the rates' error follows the kernel's: within 10 tol */
      CHECK(o.diff <= 10 * tols[t]);
      if (tols[t] == 1e-8) CHECK(o.diff <= 1e-7);
      CHECK(o.nerr <= 1e-12);
      CHECK(o.verr <= 1e-12);
      /* the cross approximation against the dense eigendecomposition:
       * the same rank, errors equal to a small part of the tolerance */
      gs_kernel_lowrank d;
      gs_error err;
      CHECK(gs_kernel_lowrank_build_dense(&f.k, f.c.model.grid.ncells, 0, tols[t], &d, &err) == 0);
      gs_kernel_lowrank a;
      CHECK(gs_kernel_lowrank_build(&f.k, f.c.model.grid.ncells, 0, tols[t], &a, &err) == 0);
      if (used < sizeof aca_rows)
        used += (size_t)snprintf(aca_rows + used, sizeof aca_rows - used,
                                 "| %s | %.0e | %d | %d (%s) | %.3e | %d | %.3e |\n", cases[i].name, tols[t], a.rank,
                                 a.cross_terms, a.dense ? "dense fallback" : "converged", a.rel_err, d.rank, d.rel_err);
      /* the Stokes cut's step needs more cross terms than cells / 8: the
       * dense decomposition takes over (lowrank.c, aca_terms_cap) */
      CHECK(a.rank == d.rank);
      CHECK(a.dense == (cases[i].dim == 3));
      CHECK(fabs(a.rel_err - d.rel_err) <= 0.02 * tols[t]);
      gs_kernel_lowrank_free(&a);
      gs_kernel_lowrank_free(&d);
      last = o.rank;
    }
    fix_free(&f);
  }
  printf("\n| kernel, grid | rank_tolerance | rank | cross terms | error (measured) | dense: rank | dense: error "
         "|\n|---|---|---|---|---|---|---|\n%s\n", aca_rows);
}

/* A whole run: Madec (alpha 0.8, delta 1.5) on 2-D 16 x 16 cells with
 * rank_tolerance 1e-8 ends where the pairs' run does to 1e-7 of the largest
 * number. */
static void test_run(void) {
  const char *k = "{type: madec, beta0: 0.1, alpha: 0.8, delta: 1.5, liquid_content: fraction}";
  double *y[2] = {NULL, NULL};
  gs_case c[2];
  const char *methods[2] = {"method: pairs", "method: fft, rank_tolerance: 1.0e-8"};
  for (int s = 0; s < 2; s++) {
    char *yaml = case_yaml(2, 16, k, methods[s]);
    /* a tight integration, so the methods differ by their rates alone */
    char *p = strstr(yaml, "output: {end: 1}");
    char *full = p ? tl_fmt("%.*soutput: {end: 1}\nsolver: {rtol: 1.0e-10, atol: 1.0e-14}\n", (int)(p - yaml), yaml)
                   : tl_fmt("%s", yaml);
    y[s] = tl_build_run(full, &c[s], NULL);
    free(yaml);
    free(full);
  }
  if (y[0] && y[1]) {
    double big = 0, diff = 0;
    for (size_t i = 0; i < c[0].model.grid.ncells; i++) {
      big = fmax(big, fabs(y[0][i]));
      diff = fmax(diff, fabs(y[1][i] - y[0][i]));
    }
    printf("Madec 2-D 16 x 16, t = 1: low-rank FFT (1e-8) - pairs, largest number %.3g\n", diff / big);
    CHECK(diff <= 1e-7 * big);
  }
  for (int s = 0; s < 2; s++)
    if (y[s]) {
      free(y[s]);
      gs_case_free(&c[s]);
    }
}

/* method auto with rank_tolerance: the FFT while the rank is at most
 * cells / 64, else the pairs; the choice shows as rates identical bit for
 * bit to one method's.  Free-molecular Brownian on 400 cells: rank 6 at
 * 1e-8 (<= 6: FFT), 7 at 1e-10 (> 6: pairs). */
static void test_auto(void) {
  const char *k = "{type: brownian, regime: free_molecular, beta0: 1}";
  const double tols[2] = {1e-8, 1e-10};
  for (int i = 0; i < 2; i++) {
    gs_case c[3];
    double *d[3], *dl[3];
    char methods[3][96];
    snprintf(methods[0], sizeof methods[0], "method: auto, rank_tolerance: %g", tols[i]);
    snprintf(methods[1], sizeof methods[1], "method: pairs");
    snprintf(methods[2], sizeof methods[2], "method: fft, rank_tolerance: %g", tols[i]);
    int ok = 1;
    for (int s = 0; s < 3; s++) {
      if (tl_rates_at_start(case_yaml(1, 400, k, methods[s]), &c[s], &d[s], &dl[s])) {
        ok = 0;
        continue;
      }
    }
    CHECK(ok);
    if (!ok) continue;
    const size_t nc = c[0].model.grid.ncells;
    const int same_pairs = !memcmp(d[0], d[1], nc * sizeof(double));
    const int same_fft = !memcmp(d[0], d[2], nc * sizeof(double));
    printf("auto, rank_tolerance %g, 400 cells: same as pairs %d, same as fft %d\n", tols[i], same_pairs, same_fft);
    CHECK(i == 0 ? same_fft && !same_pairs : same_pairs && !same_fft);
    for (int s = 0; s < 3; s++) tl_rates_free(&c[s], d[s], dl[s]);
  }
}

/* Above the dense limit (4 096 cells): 2-D 80 x 80 = 6 400 cells, the
 * cross approximation's form through the FFT against the pair loop on every
 * cell (the kernel's rows evaluated as needed: table_limit_mb 0), its error
 * estimated from the sampled rows, conservation to round-off. */
static void test_large(void) {
  static const struct {
    const char *name, *kernel;
    double tol;
  } cases[] = {
      {"madec alpha 0.8 delta 1.5", "{type: madec, beta0: 1, alpha: 0.8, delta: 1.5, liquid_content: fraction}", 1e-8},
      {"brownian free_molecular", "{type: brownian, regime: free_molecular, beta0: 1}", 1e-6},
  };
  for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
    fix f;
    if (fix_make_m(2, 80, cases[i].kernel, "method: pairs, table_limit_mb: 0", &f)) continue;
    const double t0 = tl_now();
    gs_kernel_lowrank lr;
    gs_error err;
    CHECK(gs_kernel_lowrank_build(&f.k, f.c.model.grid.ncells, 0, cases[i].tol, &lr, &err) == 0);
    const double t_build = tl_now() - t0;
    cmp_t o;
    if (!compare(&f, cases[i].tol, &o)) {
      if (i == 0)
        printf("\n| kernel, 2-D 80 x 80 = 6 400 cells | rank_tolerance | rank | cross terms | error (256 rows) "
               "| FFT - pairs, largest rate | number conservation | volume conservation |\n"
               "|---|---|---|---|---|---|---|---|\n");
      printf("| %s | %.0e | %d | %d | %.2e | %.2e | %.1e | %.1e |\n", cases[i].name, cases[i].tol, o.rank,
             lr.cross_terms, o.rel_err, o.diff, o.nerr, o.verr);
      fprintf(stderr, "%s on 6400 cells: form built in %.3g s, error from %d sampled rows\n", cases[i].name, t_build,
              lr.sampled_rows);
      /* the estimate against the error over every entry (n^2), and as a
       * statistic: 16 other samples of 256 rows, their mean within 4
       * standard errors of the truth */
      double exact = NAN, est[16], mean = 0, var = 0;
      CHECK(gs_kernel_lowrank_error(&f.k, f.c.model.grid.ncells, 0, &lr, 0, 0, &exact, &err) == 0);
      for (int r = 0; r < 16; r++) {
        CHECK(gs_kernel_lowrank_error(&f.k, f.c.model.grid.ncells, 0, &lr, GS_LOWRANK_SAMPLE_ROWS, 1000 + (unsigned)r,
                                      &est[r], &err) == 0);
        mean += est[r] / 16;
      }
      for (int r = 0; r < 16; r++) var += (est[r] - mean) * (est[r] - mean) / 15;
      const double se = sqrt(var / 16);
      fprintf(stderr, "  error over every entry %.4e; the build's estimate %.4e; 16 other samples: mean %.4e, sd %.2e\n",
              exact, lr.rel_err, mean, sqrt(var));
      CHECK(exact <= cases[i].tol);
      CHECK(fabs(lr.rel_err - exact) <= 0.5 * exact);
      CHECK(fabs(mean - exact) <= 4 * se + 1e-3 * exact);
      CHECK(o.rank == lr.rank && o.rank > 0 && !lr.dense);
      CHECK(lr.sampled_rows == GS_LOWRANK_SAMPLE_ROWS);
      CHECK(o.rel_err <= cases[i].tol);
      CHECK(o.diff <= 10 * cases[i].tol);
      CHECK(o.nerr <= 1e-12);
      CHECK(o.verr <= 1e-12);
    }
    gs_kernel_lowrank_free(&lr);
    fix_free(&f);
  }
}

static void test_refusals(void) {
  EXPECT_INPUT("grid: {axes: [{name: v, type: linear, min: 0.5, max: 1, cells: 8}]}\n"
               "initial: {type: cell, number: 1, index: [1]}\n"
               "mechanisms:\n  - {type: aggregation, redistribution: fixed_pivot, rank_tolerance: 1.0e-6,"
               " kernel: {type: brownian, beta0: 1}}\n"
               "output: {end: 1}\n",
               "bad.yaml:4", "rank_tolerance", "applies to method fft or auto");
  EXPECT_INPUT("grid: {axes: [{name: v, type: linear, min: 0.5, max: 1, cells: 8}]}\n"
               "initial: {type: cell, number: 1, index: [1]}\n"
               "mechanisms:\n  - {type: aggregation, redistribution: fixed_pivot, method: fft, rank_tolerance: 2,"
               " kernel: {type: brownian, beta0: 1}}\n"
               "output: {end: 1}\n",
               "rank_tolerance");
  /* above 4 096 cells a form of more than 512 terms is refused: the
   * semi-mechanistic kernel's Stokes cut (a step in beta) on 17^3 cells */
  char *yaml = case_yaml(3, 17,
                         "{type: semi_mechanistic, beta0: 5.0e-9, velocity: 0.5, viscosity: 0.01, contact_angle: 60,"
                         " solid_density: 1500, critical_saturation: 0.05}",
                         "method: fft, rank_tolerance: 1.0e-6");
  const double t0 = tl_now();
  EXPECT_INPUT(yaml, "bad.yaml:4", "rank_tolerance", "1e-06 needs more than 512 terms on 4913 cells", "MiB",
               "method: pairs");
  printf("refusal of a rank above 512 on 4913 cells after %.3g s\n", tl_now() - t0);
  free(yaml);
  /* method auto takes the pairs there instead of refusing */
  yaml = case_yaml(3, 17,
                   "{type: semi_mechanistic, beta0: 5.0e-9, velocity: 0.5, viscosity: 0.01, contact_angle: 60,"
                   " solid_density: 1500, critical_saturation: 0.05}",
                   "method: auto, rank_tolerance: 1.0e-6");
  gs_case c;
  if (tl_case(yaml, &c) == 0) {
    char notes[512] = "";
    CHECK(!gs_model_notes(&c.model, notes, sizeof notes)); /* no low-rank form noted */
    gs_case_free(&c);
  }
  free(yaml);
}

int main(void) {
  test_exact_ranks();
  test_tolerances();
  test_run();
  test_auto();
  test_large();
  test_refusals();
  TEST_EXIT();
}
