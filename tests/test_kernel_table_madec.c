/* The table kernel composed with the Madec liquid-content kernel
 * (`kernel: {type: table, times: {type: madec, ...}}`), De et al.'s (2025)
 * eq. 5 as the two-way coupling uses it: beta = beta0_t C[class][class'] *
 * beta0_m (V + V') [(c + c')^alpha (S - (c + c')/2)^delta]^alpha.
 * Checked against the formula written out here (not the madec kernel's own
 * code, so a wrong liquid factor fails):
 *  - every pair of a 2-D (solid, liquid) grid, row() and at(), two parameter
 *    sets (the linear fraction case and alpha = 2, delta = 0.5 in percent);
 *  - the majorant (form) bounds every pair;
 *  - the aggregation rate of a monodisperse population at two liquid contents:
 *    the ratio of the rates is the Madec factor ratio to round-off, and each
 *    rate is -beta N^2;
 *  - bad input: `times` not a map, an unknown kernel type. */
#include <unistd.h>

#include "gransim/kernel.h"
#include "pbm_testlib.h"

static const char *GRID = "grid:\n  axes:\n"
                          "    - {name: s, type: geometric, min: 1.0e-2, ratio: 2, cells: 6}\n"
                          "    - {name: l, type: geometric, min: 1.0e-3, ratio: 2, cells: 6, zero_first: true}\n";
static const double C[2][2] = {{2.0, 3.0}, {3.0, 5.0}};

/* Madec's beta at (s, l) and (s', l'), written out. */
static double madec(double b0, double alpha, double delta, double S, double s, double l, double s2, double l2) {
  const double V = s + l, V2 = s2 + l2, c = S * l / V + S * l2 / V2;
  return b0 * (V + V2) * pow(pow(c, alpha) * pow(S - c / 2, delta), alpha);
}

/* Class of a solid volume (edges 0, 0.05, 1 on axis s). */
static int cls(double s) { return s >= 0.05; }

static void pairs(const char *table, const char *times, double b0, double alpha, double delta, double S) {
  char *yaml = tl_fmt("%skernel: {type: table, beta0: 1.5, file: %s, measure: volume, axes: [s], times: %s}\n", GRID,
                      table, times);
  gs_error err = {0};
  gs_cfg *cfg = gs_cfg_load_string(yaml, "k.yaml", &err);
  gs_grid g;
  memset(&g, 0, sizeof g);
  gs_cfg_node *sec = NULL;
  int size_axes = 0;
  CHECK(cfg && !gs_case_read_grid_only(gs_cfg_root(cfg), &g, &size_axes, &sec, &err));
  gs_kernel k = {0};
  int rc = cfg ? gs_kernel_create(gs_cfg_get(gs_cfg_root(cfg), "kernel"), &g, ".", &k, &err) : -1;
  if (rc) fprintf(stderr, "kernel did not build: %s\n", err.msg);
  CHECK(rc == 0);
  if (!rc) {
    const size_t n = g.ncells;
    double *row = calloc(n, sizeof *row), worst = 0, worst_at = 0, slack = HUGE_VAL;
    gs_kernel_form f;
    k.type->form(k.self, &f);
    CHECK(f.kind == GS_KERNEL_FORM_SUM);
    for (size_t a = 0; a < n; a++) {
      k.type->row(k.self, 0, a, 0, n, row);
      const double *x = g.x + a * 2;
      for (size_t b = 0; b < n; b++) {
        const double *y = g.x + b * 2;
        const double want = 1.5 * C[cls(x[0])][cls(y[0])] * madec(b0, alpha, delta, S, x[0], x[1], y[0], y[1]);
        const double at = k.type->at(k.self, 0, x, y);
        worst = fmax(worst, fabs(row[b] - want) / fmax(want, 1e-300));
        worst_at = fmax(worst_at, fabs(at - want) / fmax(want, 1e-300));
        const double bound = f.coef[0] * (g.volume[a] + g.volume[b]);
        slack = fmin(slack, bound - want);
      }
    }
    fprintf(stderr, "times %s: worst relative error of row %.2g, of at %.2g, least majorant slack %.3g\n", times,
            worst, worst_at, slack);
    CHECK(worst < 1e-14);
    CHECK(worst_at < 1e-14);
    CHECK(slack >= 0);
    free(row);
  }
  gs_kernel_free(&k);
  gs_grid_free(&g);
  gs_cfg_free(cfg);
  free(yaml);
}

/* dN/dt of cell (3, j) holding all 1000 particles (1-based j of the liquid axis). */
static double loss_rate(const char *table, int j, double *s, double *l) {
  char *yaml = tl_fmt("%sinitial: {type: cell, number: 1000, index: [3, %d]}\n"
                      "mechanisms:\n  - type: aggregation\n"
                      "    kernel: {type: table, beta0: 1.5, file: %s, measure: volume, axes: [s],\n"
                      "             times: {type: madec, beta0: 1.0e-3, liquid_axis: l, liquid_content: fraction}}\n"
                      "output: {end: 1}\n",
                      GRID, j, table);
  gs_case c;
  double *d = NULL, *dl = NULL, r = NAN;
  if (!tl_rates_at_start(yaml, &c, &d, &dl)) {
    const size_t idx[2] = {2, (size_t)j - 1}, cell = gs_grid_index(&c.model.grid, idx);
    r = d[cell];
    *s = c.model.grid.x[cell * 2];
    *l = c.model.grid.x[cell * 2 + 1];
    tl_rates_free(&c, d, dl);
  }
  return r;
}

static void two_liquid_contents(const char *table) {
  double s1 = 0, l1 = 0, s2 = 0, l2 = 0;
  const double r1 = loss_rate(table, 2, &s1, &l1), r2 = loss_rate(table, 5, &s2, &l2);
  const double b1 = 1.5 * C[cls(s1)][cls(s1)] * madec(1e-3, 1, 1, 1, s1, l1, s1, l1);
  const double b2 = 1.5 * C[cls(s2)][cls(s2)] * madec(1e-3, 1, 1, 1, s2, l2, s2, l2);
  fprintf(stderr, "liquid %g and %g on solid %g: rates %.10g and %.10g 1/s, ratio %.15g, Madec factor ratio %.15g\n",
          l1, l2, s1, r1, r2, r1 / r2, b1 / b2);
  CHECK(s1 == s2 && l1 != l2);
  CHECK_REL(r1 / r2, b1 / b2, 1e-13);
  CHECK_REL(r1, -b1 * 1000 * 1000, 1e-13);
  CHECK_REL(r2, -b2 * 1000 * 1000, 1e-13);
}

int main(void) {
  char table[] = "/tmp/gransim-table-madec-XXXXXX";
  int fd = mkstemp(table);
  CHECK(fd >= 0);
  FILE *fp = fdopen(fd, "w");
  fprintf(fp, "edges, 0, 0.05, 1\n%g, %g\n%g, %g\n", C[0][0], C[0][1], C[1][0], C[1][1]);
  fclose(fp);
  pairs(table, "{type: madec, beta0: 1.0e-3, liquid_axis: l, liquid_content: fraction}", 1e-3, 1, 1, 1);
  pairs(table, "{type: madec, beta0: 2.0e-5, alpha: 2, delta: 0.5, liquid_axis: l}", 2e-5, 2, 0.5, 100);
  two_liquid_contents(table);
  char *bad = tl_fmt("%smechanisms:\n  - {type: aggregation, kernel: {type: table, file: %s, times: 3}}\n"
                     "output: {end: 1}\n", GRID, table);
  EXPECT_INPUT(bad, "times", "expected a map");
  free(bad);
  bad = tl_fmt("%smechanisms:\n  - {type: aggregation, kernel: {type: table, file: %s, times: {type: madek}}}\n"
               "output: {end: 1}\n", GRID, table);
  EXPECT_INPUT(bad, "madek", "madec");
  free(bad);
  unlink(table);
  TEST_EXIT();
}
