/* Breakage selection functions (src/kernel/selection.c) on their own:
 *  - `shear`, Chaudhury (2015) eq. 2.7 (after Soos et al. 2006):
 *        S = sqrt(4/(15 pi)) G exp(-B / (G^2 R)),
 *    R the volume-equivalent radius of the size v (sum of the chosen axes),
 *    compared cell by cell with the formula evaluated here from the axis
 *    pivots, for several grids and parameters; against the sanity numbers of
 *    the project's reading notes on Chaudhury (2015) (G = 64 1/s, B = 10:
 *    S = 4.7e-10, 9.3e-5, 0.141, 1.62 1/s at R = 100 um, 200 um, 500 um, 1 mm);
 *    its limits (B = 0: the constant sqrt(4/(15 pi)) G; monotone in R);
 *    `axes` and `min_volume`;
 *  - `power`, S = s0 v^exponent, the same way;
 *  - parameter validation: missing, out-of-range and unknown keys, unknown
 *    axis names, each refused with a message naming file, line, key and value. */
#include "check.h"

#include <stdlib.h>
#include <string.h>

#include "gransim/cfg.h"
#include "gransim/grid.h"
#include "gransim/kernel.h"

#define PREF sqrt(4 / (15 * M_PI)) /* 0.2913 in the notes */

/* S of the shear form for a size v, written out here independently of the
 * library (no gs_diameter). */
static double shear_formula(double G, double B, double v) {
  double R = pow(3 * v / (4 * M_PI), 1.0 / 3.0);
  return sqrt(4 / (15 * M_PI)) * G * exp(-B / (G * G * R));
}

/* Create a selection function from YAML on grid g; GS_OK or the error. */
static int sel_create(const char *yaml, const gs_grid *g, gs_selection *s, gs_error *err) {
  memset(err, 0, sizeof *err);
  memset(s, 0, sizeof *s);
  gs_cfg *cfg = gs_cfg_load_string(yaml, "sel.yaml", err);
  if (!cfg) return err->code ? err->code : GS_EINPUT;
  int rc = gs_selection_create(gs_cfg_root(cfg), g, ".", s, err);
  gs_cfg_free(cfg);
  return rc;
}

/* 2-D grid solid x liquid, geometric, 24 x 6 cells (sizes 1e-14 .. ~5e-9 m^3,
 * R from 13 um to ~1 mm). */
static int grid_2d(gs_grid *g) {
  gs_error err;
  gs_axis ax[2];
  memset(g, 0, sizeof *g);
  if (gs_axis_geometric(&ax[0], "solid", 1e-14, 1.8, 23, 1, &err) ||
      gs_axis_geometric(&ax[1], "liquid", 1e-15, 4, 5, 1, &err) ||
      gs_grid_init(g, ax, 2, 1, &err)) {
    fprintf(stderr, "grid: %s\n", err.msg);
    return 1;
  }
  return 0;
}

/* Sizes of the cells of g from the axis pivots: all axes, or only axis 0. */
static double cell_size(const gs_grid *g, size_t cell, int solid_only) {
  size_t idx[GS_MAX_DIM];
  gs_grid_unindex(g, cell, idx);
  double v = 0;
  for (int k = 0; k < (solid_only ? 1 : g->dim); k++) v += g->axis[k].pivots[idx[k]];
  return v;
}

static void test_shear_values(void) {
  gs_grid g;
  if (grid_2d(&g)) {
    check_failures++;
    return;
  }
  const struct {
    double G, B;
  } par[] = {{64, 10}, {3, 1e-4}, {10, 5e-3}, {200, 1}, {1, 0}, {0.5, 2e-6}};
  for (size_t p = 0; p < sizeof par / sizeof par[0]; p++)
    for (int solid_only = 0; solid_only < 2; solid_only++) {
      char yaml[256];
      snprintf(yaml, sizeof yaml, "{type: shear, shear_rate: %.17g, b: %.17g%s}", par[p].G,
               par[p].B, solid_only ? ", axes: [solid]" : "");
      gs_selection s;
      gs_error err;
      int rc = sel_create(yaml, &g, &s, &err);
      CHECK(rc == GS_OK);
      if (rc) {
        fprintf(stderr, "%s: %s\n", yaml, err.msg);
        continue;
      }
      CHECK(!strcmp(s.type->name, "shear"));
      size_t nonzero = 0, between = 0;
      for (size_t c = 0; c < g.ncells; c++) {
        double v = cell_size(&g, c, solid_only), want = shear_formula(par[p].G, par[p].B, v);
        double got = s.type->rate(s.self, &g, c);
        CHECK(isfinite(got) && got >= 0);
        /* exp(-x) carries x times the relative rounding error of x (x up to ~1e3 here) */
        double x = par[p].B / (par[p].G * par[p].G * pow(3 * v / (4 * M_PI), 1.0 / 3.0));
        CHECK_REL(got, want, 1e-14 * (10 + x));
        if (want > 0) nonzero++;
        if (want > 1e-3 * PREF * par[p].G && want < 0.999 * PREF * par[p].G) between++;
      }
      /* each parameter set tests the exponential over a range where it
       * matters (not only underflow or saturation) */
      CHECK(nonzero > 0 && (par[p].B == 0 || between >= 3));
      if (par[p].B == 0)
        for (size_t c = 0; c < g.ncells; c++)
          CHECK_REL(s.type->rate(s.self, &g, c), PREF * par[p].G, 1e-13);
      /* along the solid axis at fixed liquid, S grows with the size */
      for (size_t i = 1; i < g.axis[0].n; i++) {
        size_t a[2] = {i - 1, 2}, b[2] = {i, 2};
        double sa = s.type->rate(s.self, &g, gs_grid_index(&g, a));
        double sb = s.type->rate(s.self, &g, gs_grid_index(&g, b));
        CHECK(par[p].B == 0 ? sb == sa : sb >= sa);
      }
      gs_selection_free(&s);
    }
  gs_grid_free(&g);
}

/* The sanity numbers of the reference notes, on a grid whose pivots are the
 * volumes of spheres of R = 100 um, 200 um, 500 um and 1 mm (SI units). */
static void test_shear_reference_numbers(void) {
  const double R[4] = {100e-6, 200e-6, 500e-6, 1e-3}, want[4] = {4.7e-10, 9.3e-5, 0.141, 1.62};
  double piv[4], edges[5];
  for (int i = 0; i < 4; i++) piv[i] = 4.0 / 3.0 * M_PI * R[i] * R[i] * R[i];
  edges[0] = 0.5 * piv[0];
  for (int i = 1; i < 4; i++) edges[i] = 0.5 * (piv[i - 1] + piv[i]);
  edges[4] = 2 * piv[3];
  gs_error err;
  gs_axis ax;
  gs_grid g;
  memset(&g, 0, sizeof g);
  if (gs_axis_from_edges(&ax, "solid", edges, 5, piv, &err) || gs_grid_init(&g, &ax, 1, 1, &err)) {
    fprintf(stderr, "grid: %s\n", err.msg);
    check_failures++;
    return;
  }
  gs_selection s;
  int rc = sel_create("{type: shear, shear_rate: 64, b: 10}", &g, &s, &err);
  CHECK(rc == GS_OK);
  if (!rc) {
    for (size_t c = 0; c < 4; c++) {
      double got = s.type->rate(s.self, &g, c);
      printf("shear, G = 64 1/s, B = 10: R = %g m: S = %.4g 1/s (notes: %g)\n", R[c], got, want[c]);
      CHECK_REL(got, want[c], 0.015); /* the notes give 2-3 digits */
    }
    gs_selection_free(&s);
  }
  /* min_volume: cells below it do not break, the others keep their rate */
  rc = sel_create("{type: shear, shear_rate: 64, b: 10, min_volume: 1.0e-10}", &g, &s, &err);
  CHECK(rc == GS_OK);
  if (!rc) {
    for (size_t c = 0; c < 4; c++) {
      double got = s.type->rate(s.self, &g, c);
      if (piv[c] < 1e-10) CHECK(got == 0);
      else CHECK_REL(got, shear_formula(64, 10, piv[c]), 1e-13);
    }
    CHECK(piv[0] < 1e-10 && piv[1] < 1e-10 && piv[2] > 1e-10); /* both branches taken */
    gs_selection_free(&s);
  }
  gs_grid_free(&g);
}

static void test_power_values(void) {
  gs_grid g;
  if (grid_2d(&g)) {
    check_failures++;
    return;
  }
  const double s0[3] = {1, 2.5e9, 0}, ex[3] = {1, 2, -0.5};
  for (int p = 0; p < 3; p++) {
    char yaml[160];
    snprintf(yaml, sizeof yaml, "{type: power, s0: %.17g, exponent: %.17g}", s0[p], ex[p]);
    gs_selection s;
    gs_error err;
    int rc = sel_create(yaml, &g, &s, &err);
    CHECK(rc == GS_OK);
    if (rc) continue;
    for (size_t c = 0; c < g.ncells; c++)
      CHECK_REL(s.type->rate(s.self, &g, c), s0[p] * pow(cell_size(&g, c, 0), ex[p]), 1e-13);
    gs_selection_free(&s);
  }
  gs_grid_free(&g);
}

/* The YAML must be refused with GS_EINPUT and a message containing every
 * part (NULL-terminated). */
static void expect_refused(const gs_grid *g, const char *yaml, const char *const *parts) {
  gs_selection s;
  gs_error err;
  int rc = sel_create(yaml, g, &s, &err);
  if (rc != GS_EINPUT) {
    fprintf(stderr, "expected GS_EINPUT, got %d for %s (%s)\n", rc, yaml, rc ? err.msg : "created");
    check_failures++;
    if (!rc) gs_selection_free(&s);
    return;
  }
  for (size_t i = 0; parts[i]; i++)
    if (!strstr(err.msg, parts[i])) {
      fprintf(stderr, "message for %s lacks '%s':\n  %s\n", yaml, parts[i], err.msg);
      check_failures++;
    }
}
#define REFUSED(g, yaml, ...) expect_refused(g, yaml, (const char *const[]){__VA_ARGS__, NULL})

static void test_shear_validation(void) {
  gs_grid g;
  if (grid_2d(&g)) {
    check_failures++;
    return;
  }
  REFUSED(&g, "{type: shear, b: 10}", "sel.yaml:1:", "missing key 'shear_rate'");
  REFUSED(&g, "{type: shear, shear_rate: 64}", "sel.yaml:1:", "missing key 'b'");
  REFUSED(&g, "{type: shear, shear_rate: 0, b: 10}", "sel.yaml:1:", "shear_rate = '0'", "> 0");
  REFUSED(&g, "{type: shear, shear_rate: -3, b: 10}", "sel.yaml:1:", "shear_rate = '-3'", "> 0");
  REFUSED(&g, "{type: shear, shear_rate: 64, b: -1}", "sel.yaml:1:", "b = '-1'", ">= 0");
  REFUSED(&g, "{type: shear, shear_rate: fast, b: 10}", "sel.yaml:1:", "shear_rate = 'fast'", "number");
  REFUSED(&g, "{type: shear, shear_rate: .nan, b: 10}", "sel.yaml:1:", "shear_rate");
  REFUSED(&g, "{type: shear, shear_rate: 64, b: 10, min_volume: -1.0e-12}", "sel.yaml:1:",
          "min_volume = '-1.0e-12'", ">= 0");
  REFUSED(&g, "{type: shear, shear_rate: 64, b: 10, s0: 1}", "sel.yaml:1:", "unknown key 's0'",
          "shear_rate", "b");
  REFUSED(&g, "{type: shear, shear_rate: 64, b: 10, axes: [solid, gas]}", "sel.yaml:1:", "'gas'",
          "expected the name of a grid axis");
  REFUSED(&g, "{type: shear, shear_rate: 64, b: 10, axes: solid}", "sel.yaml:1:", "axes");
  REFUSED(&g, "{type: sheer, shear_rate: 64, b: 10}", "sel.yaml:1:", "type = 'sheer'", "power, shear");
  REFUSED(&g, "{type: power}", "sel.yaml:1:", "missing key 's0'");
  REFUSED(&g, "{type: power, s0: -1}", "sel.yaml:1:", "s0 = '-1'", ">= 0");
  /* limits accepted: b = 0, a tiny shear rate */
  gs_selection s;
  gs_error err;
  CHECK(sel_create("{type: shear, shear_rate: 1.0e-300, b: 0}", &g, &s, &err) == GS_OK);
  if (s.type) gs_selection_free(&s);
  gs_grid_free(&g);
}

int main(void) {
  CHECK(fabs(PREF - 0.2913) < 5e-5);
  test_shear_values();
  test_shear_reference_numbers();
  test_power_values();
  test_shear_validation();
  TEST_EXIT();
}
