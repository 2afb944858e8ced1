/* The absorption law checked as De et al. (2025, section 3.1) check it: a
 * DEM of the generated bowl and impeller with a polydisperse bed under a
 * spray whose droplets are removed on first contact and credit their volume
 * to the particle they touch (src/dem/spray.c); the liquid each size class
 * holds at the end (spray_classes.csv, src/dem/spray_classes.c) is set
 * against the law's shares N_k V_k / sum N V.
 *  - default run (fixed seed): the per-class liquid adds up to the liquid
 *    ledger's on-particle volume to round-off, every class is wetted, and
 *    two classes of identical particles (a and b) share their liquid in
 *    proportion to their numbers within 4 standard errors (a statistical
 *    test of the bookkeeping: for identical particles every law agrees);
 *  - GRANSIM_TEST_LONG=1 (test_absorption_dem_long): five size classes, a
 *    longer spray; prints the class-by-class table that
 *    docs/validation-coupling.md reports. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "check.h"
#include "dem/dem_case.h"
#include "dem/dem_internal.h"
#include "dem/dem_wet.h"
#include "gransim/dem.h"

static const char *BOWL =
    "dem: {time_step: 1.0e-5, duration: %g, gravity: [0, 0, -9.81], seed: 11,\n"
    "      box: {lo: [-0.07, -0.07, -0.02], hi: [0.07, 0.07, 0.12]}}\n"
    "materials:\n"
    "  - {name: granule, E: 5.0e6, nu: 0.3, e: 0.3, mu_s: 0.5, mu_r: 0.1, density: 1668}\n"
    "  - {name: steel, E: 5.0e6, nu: 0.3, e: 0.3, mu_s: 0.5, mu_r: 0.1}\n"
    "classes:\n%s"
    "walls:\n"
    "  - {name: bowl, material: steel, generate: {type: bowl, diameter: 0.1, height: 0.08}}\n"
    "  - name: impeller\n"
    "    material: steel\n"
    "    generate: {type: impeller, blades: 3, blade_length: 0.028, blade_height: 0.012, blade_thickness: 0.003,\n"
    "               hub_diameter: 0.02, clearance: 0.008, rpm: 240}\n"
    "fill:\n"
    "  - region: {cylinder: {point: [0, 0, 0], axis: [0, 0, 1], radius: 0.045, inner_radius: 0.012, from: 0.012,\n"
    "                        to: 0.07}}\n"
    "    count: %d\n"
    "spray: {point: [0, 0, 0.075], axis: [0, 0, -1], half_angle: 35, droplet_diameter: 5.0e-4,\n"
    "        mass_rate: %g, speed: 2, start: %g, end: %g}\n"
    "output: {every: 0.05}\n";

typedef struct {
  gs_dem_spray_class k[8];
  int n;
  double on_particles, injected, absorbed_share;
  double sigma_ab; /* standard error of a's share of a + b */
} result;

static int run(const char *classes, int count, double rate, double start, double end, double duration, result *out) {
  char yaml[4096];
  snprintf(yaml, sizeof yaml, BOWL, duration, classes, count, rate, start, end);
  gs_error err = {0};
  gs_cfg *cfg = gs_cfg_load_string(yaml, "absorption.yaml", &err);
  gs_dem_case *c = cfg ? gs_dem_case_from_cfg(cfg, &err) : NULL;
  if (!c) {
    fprintf(stderr, "%s\n", err.msg);
    return 1;
  }
  char dir[] = "/tmp/gransim_absorb_XXXXXX";
  int rc = mkdtemp(dir) ? gs_dem_case_run(c, dir, 0, &err) : 1;
  if (rc) fprintf(stderr, "%s\n", err.msg);
  if (!rc) {
    out->n = (int)c->nclass;
    gs_dem_spray_classes(c->dem, out->n, out->k);
    gs_dem_liquid_ledger l;
    gs_dem_spray_ledger(&c->wet->spray, c->dem, &l);
    out->on_particles = l.on_particles;
    out->injected = l.injected;
    /* a's share of the liquid of a and b, and its standard error from the
     * spread of the per-particle liquid (particles as independent samples) */
    const gs_dem_particles *p = &c->dem->p;
    double sum[2] = {0, 0}, sq[2] = {0, 0}, num[2] = {0, 0};
    for (size_t i = 0; i < p->n; i++) {
      int k = c->dem->types[p->type[i]].cls;
      if (k > 1 || p->dead[i]) continue;
      sum[k] += p->vl[i], sq[k] += p->vl[i] * p->vl[i], num[k] += 1;
    }
    const double mean = (sum[0] + sum[1]) / (num[0] + num[1]);
    const double var = (sq[0] + sq[1]) / (num[0] + num[1]) - mean * mean, tot = sum[0] + sum[1];
    out->absorbed_share = sum[0] / tot;
    /* share = A / (A + B): with A, B sums of na, nb draws of variance var,
     * d share = (B dA - A dB) / T^2 */
    out->sigma_ab = sqrt(var * (sum[1] * sum[1] * num[0] + sum[0] * sum[0] * num[1])) / (tot * tot);
    /* the table beside the run */
    char path[4200];
    snprintf(path, sizeof path, "%s/spray_classes.csv", dir);
    CHECK(access(path, R_OK) == 0);
  }
  char cmd[4300];
  snprintf(cmd, sizeof cmd, "rm -rf %s", dir);
  CHECK(system(cmd) == 0);
  gs_dem_case_free(c);
  return rc;
}

static void report(const result *r, const char *const *names) {
  double L = 0, S = 0, A = 0;
  for (int i = 0; i < r->n; i++) L += r->k[i].liquid, S += r->k[i].solid, A += r->k[i].area;
  printf("| class | particles | d [mm] | liquid share | volume law (De et al.) | surface law | share / volume law |\n"
         "|---|---|---|---|---|---|---|\n");
  for (int i = 0; i < r->n; i++) {
    const gs_dem_spray_class *k = &r->k[i];
    const double d = cbrt(6 * k->solid / k->particles / M_PI);
    printf("| %s | %.0f | %.2f | %.4f | %.4f | %.4f | %.3f |\n", names[i], k->particles, 1e3 * d, k->liquid / L,
           k->solid / S, k->area / A, (k->liquid / L) / (k->solid / S));
  }
  printf("droplets' liquid on particles %.4g of %.4g m^3 injected\n", r->on_particles, r->injected);
}

int main(void) {
  const int lng = getenv("GRANSIM_TEST_LONG") && !strcmp(getenv("GRANSIM_TEST_LONG"), "1");
  result r;
  memset(&r, 0, sizeof r);
  if (!lng) {
    /* a and b: the same 2 mm particles under two names; c: 3 mm */
    const char *cls = "  - {name: a, radius: 2.0e-3, material: granule}\n"
                      "  - {name: b, radius: 2.0e-3, material: granule}\n"
                      "  - {name: c, radius: 3.0e-3, material: granule}\n";
    const char *names[] = {"a", "b", "c"};
    CHECK(run(cls, 600, 6.5e-4, 0.12, 0.32, 0.36, &r) == 0);
    if (r.n != 3) return 1;
    report(&r, names);
    double L = 0;
    for (int i = 0; i < 3; i++) {
      L += r.k[i].liquid;
      CHECK(r.k[i].liquid > 0);
    }
    CHECK_REL(L, r.on_particles, 1e-12);
    CHECK(r.on_particles > 0.5 * r.injected);
    const double want = r.k[0].particles / (r.k[0].particles + r.k[1].particles);
    printf("a's share of a + b: %.4f, its number share %.4f, standard error %.4f\n", r.absorbed_share, want,
           r.sigma_ab);
    CHECK(fabs(r.absorbed_share - want) <= 4 * r.sigma_ab);
    CHECK(r.sigma_ab < 0.05); /* enough droplets for the test to mean something */
  } else {
    const char *cls = "  - {name: d3, radius: 1.5e-3, material: granule}\n"
                      "  - {name: d4, radius: 2.0e-3, material: granule}\n"
                      "  - {name: d5, radius: 2.5e-3, material: granule}\n"
                      "  - {name: d6, radius: 3.0e-3, material: granule}\n"
                      "  - {name: d7, radius: 3.5e-3, material: granule}\n";
    const char *names[] = {"3 mm", "4 mm", "5 mm", "6 mm", "7 mm"};
    CHECK(run(cls, 1100, 6.5e-4, 0.2, 1.4, 1.5, &r) == 0);
    if (r.n != 5) return 1;
    report(&r, names);
    double L = 0;
    for (int i = 0; i < 5; i++) L += r.k[i].liquid;
    CHECK_REL(L, r.on_particles, 1e-12);
  }
  TEST_EXIT();
}
