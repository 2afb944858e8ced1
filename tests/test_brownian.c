/* The brownian kernel (src/kernel/kernel_brownian.c; formulas in
 * docs/models.md):
 *  - continuum, equal sizes: beta = 8 kT / (3 mu) exactly, at every size;
 *    free molecular, equal sizes: 4 sqrt(2) K_f v^(1/6);
 *  - symmetry of row(), and at() equal to row() at the pivots (bit for bit:
 *    the same arithmetic);
 *  - the majorant (sum form) bounds at() for random states, also below the
 *    smallest pivot and far above the grid, with equality at (v_lo, v_lo);
 *  - sectional self-consistency: with every product inside the grid, the
 *    total number rate at t = 0 is -1/2 sum_ij beta_ij N_i N_j (from the
 *    kernel's own rows), for both regimes and both redistribution schemes;
 *  - input errors: beta0 together with physical properties, a property of
 *    the other regime, neither beta0 nor the property.
 * The stochastic solver against the sectional one: tests/test_swa_kernels.c. */
#include "pbm_testlib.h"
#include "gransim/grid.h"
#include "gransim/kernel.h"

#define KB 1.380649e-23

typedef struct {
  gs_grid g;
  gs_cfg *cfg;
  gs_kernel k;
} kfix;

/* A 2-D grid (solid, liquid) of n x n geometric cells and the kernel of yaml. */
static int kernel_on_grid(const char *yaml, size_t n, kfix *f, gs_error *err) {
  memset(f, 0, sizeof *f);
  gs_axis ax[2];
  if (gs_axis_geometric(&ax[0], "solid", 1e-18, 2.0, n, 0, err) ||
      gs_axis_geometric(&ax[1], "liquid", 1e-19, 2.0, n, 1, err) || gs_grid_init(&f->g, ax, 2, 2, err))
    return GS_EINPUT;
  f->cfg = gs_cfg_load_string(yaml, "kernel", err);
  if (!f->cfg) return GS_EINPUT;
  return gs_kernel_create(gs_cfg_root(f->cfg), &f->g, ".", &f->k, err);
}

static void kfix_free(kfix *f) {
  gs_kernel_free(&f->k);
  gs_cfg_free(f->cfg);
  gs_grid_free(&f->g);
}

static double pivot_volume(const gs_grid *g, size_t c) { return g->volume[c]; }

static void values_and_bounds(int fm) {
  const double T = 300, mu = 1.8e-5, rho = 1500;
  const char *yaml = fm ? "type: brownian\nregime: free_molecular\ntemperature: 300\ndensity: 1500\n"
                        : "type: brownian\ntemperature: 300\nviscosity: 1.8e-5\n";
  kfix f;
  gs_error err;
  int rc = kernel_on_grid(yaml, 12, &f, &err);
  CHECK(rc == 0);
  if (rc) {
    fprintf(stderr, "%s\n", err.msg);
    kfix_free(&f);
    return;
  }
  const gs_grid *g = &f.g;
  const size_t n = g->ncells;
  const gs_kernel_type *kt = f.k.type;
  double *rows = malloc(n * n * sizeof(double));
  for (size_t a = 0; a < n; a++) kt->row(f.k.self, 1, a, 0, n, rows + a * n);
  const double Kf = pow(3 / (4 * M_PI), 1.0 / 6) * sqrt(6 * KB * T / rho);
  size_t asym = 0, differ = 0;
  for (size_t a = 0; a < n; a++) {
    /* equal sizes */
    const double v = pivot_volume(g, a);
    const double want = fm ? 4 * sqrt(2.0) * Kf * pow(v, 1.0 / 6) : 8 * KB * T / (3 * mu);
    CHECK_REL(rows[a * n + a], want, 1e-13);
    for (size_t b = 0; b < n; b++) {
      asym += rows[a * n + b] != rows[b * n + a];
      double at = kt->at(f.k.self, 1, g->x + a * 2, g->x + b * 2);
      differ += at != rows[a * n + b];
    }
  }
  CHECK(asym == 0);
  CHECK(differ == 0);
  /* two sizes a factor 8 apart in volume (2 in diameter): continuum
   * K_c (2 + 2 + 1/2), free molecular K_f (9/8 / v)^(1/2) 9 v^(2/3) */
  double x[2] = {3e-18, 1e-18}, y[2] = {24e-18, 8e-18};
  double v = 4e-18, b = kt->at(f.k.self, 0, x, y);
  CHECK_REL(b, fm ? Kf * sqrt(1.125 / v) * 9 * pow(v, 2.0 / 3) : 2 * KB * T / (3 * mu) * 4.5, 1e-13);
  /* majorant */
  gs_kernel_form form;
  kt->form(f.k.self, &form);
  CHECK(form.kind == GS_KERNEL_FORM_SUM && !form.exact && form.axes == 3u);
  double vlo = HUGE_VAL;
  for (size_t c = 0; c < n; c++) vlo = fmin(vlo, pivot_volume(g, c));
  tl_rng r = {7};
  double worst = 0;
  for (int i = 0; i < 200000; i++) {
    double p[2], q[2];
    /* volumes from 1e-3 v_lo to 1e6 v_lo, any liquid share */
    for (int k = 0; k < 2; k++) {
      double s = vlo * pow(10, -3 + 9 * tl_uniform(&r)), w = tl_uniform(&r);
      (k ? q : p)[0] = s * w;
      (k ? q : p)[1] = s * (1 - w);
    }
    double bound = form.coef[0] * (p[0] + p[1] + q[0] + q[1]);
    worst = fmax(worst, kt->at(f.k.self, 0, p, q) / bound);
  }
  /* equality at (v_lo, v_lo): the bound is tight */
  double lo[2] = {vlo, 0};
  double tight = kt->at(f.k.self, 0, lo, lo) / (form.coef[0] * 2 * vlo);
  fprintf(stderr, "%s: at / majorant at most %.6f over random states, %.15f at (v_lo, v_lo)\n",
          fm ? "free molecular" : "continuum", worst, tight);
  CHECK(worst <= 1.0 + 1e-12); /* round-off where the bound is tight */
  CHECK_REL(tight, 1.0, 1e-12);
  free(rows);
  kfix_free(&f);
}

/* dN/dt at t = 0 summed over the cells against -1/2 sum beta N N. */
static void number_rate(int fm, const char *scheme) {
  char *yaml = tl_fmt("grid:\n  axes: [{name: v, type: geometric, min: 1e-2, ratio: 1.5, cells: 40}]\n"
                      "mechanisms:\n  - type: aggregation\n    redistribution: %s\n"
                      "    kernel: {type: brownian, regime: %s, beta0: 1e-3}\n"
                      "output: {end: 1}\n",
                      scheme, fm ? "free_molecular" : "continuum");
  gs_case c;
  if (tl_case(yaml, &c)) {
    free(yaml);
    return;
  }
  const gs_model *m = &c.model;
  const size_t n = m->grid.ncells;
  double *y = calloc(m->nstate, sizeof(double)), *d = calloc(m->nstate, sizeof(double));
  double *dl = calloc(m->nledger, sizeof(double)), *row = malloc(n * sizeof(double));
  tl_rng r = {11};
  /* the lower half only: every pivot sum stays inside the grid */
  for (size_t i = 0; i < n / 2; i++) y[i] = 1 + 10 * tl_uniform(&r);
  gs_model_rhs(m, NULL, 0.0, y, d, dl);
  double got = 0, want = 0;
  for (size_t i = 0; i < n; i++) got += d[i];
  gs_kernel k;
  gs_error err;
  gs_cfg *cfg = gs_cfg_load_string(fm ? "{type: brownian, regime: free_molecular, beta0: 1e-3}"
                                      : "{type: brownian, beta0: 1e-3}", "k", &err);
  CHECK(cfg && gs_kernel_create(gs_cfg_root(cfg), &m->grid, ".", &k, &err) == 0);
  for (size_t a = 0; a < n; a++) {
    k.type->row(k.self, 0, a, 0, n, row);
    for (size_t b = 0; b < n; b++) want -= 0.5 * row[b] * y[a] * y[b];
  }
  fprintf(stderr, "%s, %s: dM0/dt %.15g, -1/2 sum beta N N %.15g\n", fm ? "free molecular" : "continuum", scheme,
          got, want);
  CHECK_REL(got, want, 1e-12);
  gs_kernel_free(&k);
  gs_cfg_free(cfg);
  free(y);
  free(d);
  free(dl);
  free(row);
  free(yaml);
  gs_case_free(&c);
}

static void input_errors(void) {
  static const struct {
    const char *kernel, *msg;
  } bad[] = {
      {"{type: brownian, beta0: 1, viscosity: 1e-5}", "not both"},
      {"{type: brownian, beta0: 1, temperature: 300}", "not both"},
      {"{type: brownian, density: 1000, viscosity: 1e-5}", "not a key of the continuum regime"},
      {"{type: brownian, regime: free_molecular, temperature: 300}", "needs beta0 or density"},
      {"{type: brownian, regime: slip, beta0: 1}", "slip"},
      {"{type: brownian, beta0: 1, min_volume: 1}", "min_volume"},
  };
  for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
    char *yaml = tl_fmt("grid:\n  axes: [{name: v, type: geometric, min: 1e-2, ratio: 2, cells: 10}]\n"
                        "mechanisms:\n  - {type: aggregation, kernel: %s}\noutput: {end: 1}\n",
                        bad[i].kernel);
    gs_case c;
    gs_error err;
    int rc = tl_case_try(yaml, "t.yaml", &c, &err);
    CHECK(rc != 0 && strstr(err.msg, bad[i].msg));
    if (rc == 0 || !strstr(err.msg, bad[i].msg)) fprintf(stderr, "%s -> %s\n", bad[i].kernel, err.msg);
    free(yaml);
  }
}

int main(void) {
  values_and_bounds(0);
  values_and_bounds(1);
  for (int fm = 0; fm < 2; fm++) {
    number_rate(fm, "cell_average");
    number_rate(fm, "fixed_pivot");
  }
  input_errors();
  TEST_EXIT();
}
