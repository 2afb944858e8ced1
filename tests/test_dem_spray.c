/* Binder spray in the embedded DEM (src/dem/spray.c, case_wet.c, wet_run.c):
 *  - one droplet hitting one particle at rest: the particle's liquid becomes
 *    exactly the droplet's volume, its mass grows by the droplet's, momentum
 *    is conserved to round-off, and the droplet is gone;
 *  - cone directions: u = (0, .) is the axis and u = (1, .) the cone's edge;
 *    a fixed seed gives the same droplets twice (another seed others); the
 *    polar angles of 20,000 injected droplets pass a Kolmogorov–Smirnov test
 *    (1 %) against the exact distribution P(theta <= x) = (1 - cos x) /
 *    (1 - cos half_angle) of directions uniform over the cone's solid angle,
 *    and the mean direction across the axis is 0 within 4 standard errors;
 *  - a droplet under gravity and an added acceleration that cancels it
 *    flies straight at its exit speed (the hook the gas drag will use);
 *  - the injected number follows the mass rate exactly (whole droplets);
 *  - a sprayed drum with an outlet: the liquid ledger of spray.csv balances
 *    to round-off at every output, with liquid on particles, on walls and
 *    leaving, and the liquid the granulation sees on the particles is the
 *    ledger's;
 *  - bad input: a nozzle outside the box, a zero droplet diameter and a
 *    LIGGGHTS engine are refused naming the key. */
#include <gsl/gsl_cdf.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "dem/dem_wet.h"
#include "dem_testlib.h"
#include "wet_testlib.h"

static gs_dem *one_particle(double r, double gy) {
  gs_dem_params prm = {.dt = 1e-5, .gravity = {0, gy, 0}, .skin = 2e-4, .lo = {-0.05, -0.05, -0.05},
                       .hi = {0.05, 0.05, 0.05}, .nclass = 1};
  gs_error err = {0};
  gs_dem *d = gs_dem_alloc(&prm, &err);
  gs_dem_material m = {.E = 1e7, .nu = 0.25, .e = 0.5, .mu_s = 0.5, .density = 1030};
  CHECK(gs_dem_add_type(d, &m, 0, &err) == 0);
  const double x[3] = {0, 0, 0};
  CHECK(gs_dem_add_particle(d, 0, r, x, NULL, NULL, &err) == 0);
  CHECK(gs_dem_run(d, 0, &err) == 0);
  return d;
}

static gs_dem_nozzle nozzle(double half_deg, double rate) {
  gs_dem_nozzle z = {.point = {0, 0.01, 0}, .axis = {0, -1, 0}, .half_angle = half_deg * M_PI / 180,
                     .diameter = 1e-3, .mass_rate = rate, .density = 1000, .speed = 2.0, .start = 0,
                     .end = HUGE_VAL};
  return z;
}

static void single_droplet(void) {
  gs_dem *d = one_particle(1e-3, 0);
  gs_dem_spray s;
  gs_error err = {0};
  gs_dem_nozzle z = nozzle(1e-6, 0);
  /* exactly one droplet: the rate gives 1.5 droplets over the window */
  const double md = 1000 * M_PI / 6 * 1e-9;
  z.end = 1e-3;
  z.mass_rate = 1.5 * md / z.end;
  CHECK(gs_dem_spray_init(&s, &z, 7, &err) == 0);
  const double m0 = d->p.m[0], I0 = 1.0 / d->p.invI[0];
  d->p.wz[0] = 3.0; /* a spinning particle keeps its angular momentum */
  int steps = 0;
  while (s.absorbed == 0 && steps < 2000) {
    CHECK(gs_dem_run(d, 1, &err) == 0);
    CHECK(gs_dem_spray_step(&s, d, &err) == 0);
    steps++;
  }
  for (int k = 0; k < 200; k++) {
    CHECK(gs_dem_run(d, 1, &err) == 0);
    CHECK(gs_dem_spray_step(&s, d, &err) == 0);
  }
  CHECK(s.injected == 1);
  CHECK(s.absorbed == 1);
  CHECK(s.n == 0);
  CHECK(d->p.vl[0] == s.vd); /* exactly its volume */
  CHECK_REL(d->p.m[0], m0 + s.md, 1e-15);
  CHECK_REL(1.0 / d->p.invI[0], I0 * d->p.m[0] / m0, 1e-14);
  CHECK_REL(d->p.wz[0] / d->p.invI[0], 3.0 * I0, 1e-14);
  /* momentum: the droplet's at impact (it moved at 2 m/s straight down) */
  CHECK_REL(d->p.m[0] * d->p.vy[0], -2.0 * s.md, 1e-12);
  CHECK(fabs(d->p.vx[0]) < 1e-6 * fabs(d->p.vy[0]));
  gs_dem_liquid_ledger l;
  gs_dem_spray_ledger(&s, d, &l);
  CHECK(l.injected == l.on_particles);
  CHECK(l.airborne == 0 && l.on_walls == 0 && l.left == 0);
  gs_dem_spray_free(&s);
  gs_dem_free(d);
}

static void cancel_gravity(void *ctx, const double x[3], const double v[3], double a[3]) {
  (void)x, (void)v;
  const double *g = ctx;
  for (int k = 0; k < 3; k++) a[k] = -g[k];
}

static void accel_hook(void) {
  gs_dem *d = one_particle(1e-4, -9.81);
  d->p.x[0] = 0.04;
  gs_error err = {0};
  gs_dem_nozzle z = nozzle(1e-6, 0);
  const double md = 1000 * M_PI / 6 * 1e-9;
  z.end = d->prm.dt * 1.5;
  z.mass_rate = 1.5 * md / z.end;
  gs_dem_spray s;
  CHECK(gs_dem_spray_init(&s, &z, 1, &err) == 0);
  s.accel = cancel_gravity;
  s.accel_ctx = d->prm.gravity;
  for (int k = 0; k < 100; k++) {
    CHECK(gs_dem_run(d, 1, &err) == 0);
    CHECK(gs_dem_spray_step(&s, d, &err) == 0);
  }
  CHECK(s.n == 1);
  if (s.n == 1) {
    CHECK_ABS(s.drop[0].v[1], -2.0, 1e-12);
    CHECK_ABS(s.drop[0].x[1], 0.01 - 100 * d->prm.dt * 2.0, 1e-12);
  }
  /* a non-finite acceleration stops the run naming the step */
  double nan_g[3] = {NAN, 0, 0};
  s.accel_ctx = nan_g;
  CHECK(gs_dem_run(d, 1, &err) == 0);
  CHECK(gs_dem_spray_step(&s, d, &err) == GS_ENUMERIC);
  CHECK(strstr(err.msg, "non-finite") && strstr(err.msg, "step 101"));
  fprintf(stderr, "stopped as expected: %s\n", err.msg);
  gs_dem_spray_free(&s);
  gs_dem_free(d);
}

static int cmp_double(const void *a, const void *b) {
  double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

static void cone_statistics(void) {
  gs_error err = {0};
  const double half = 30;
  gs_dem_nozzle z = nozzle(half, 0);
  gs_dem_spray s, s2, s3;
  CHECK(gs_dem_spray_init(&s, &z, 42, &err) == 0);
  double dir[3], u0[2] = {0, 0.3}, u1[2] = {1, 0.7};
  gs_dem_spray_direction(&s, u0, dir);
  CHECK_ABS(dir[1], -1, 1e-15);
  gs_dem_spray_direction(&s, u1, dir);
  CHECK_ABS(acos(-dir[1]), half * M_PI / 180, 1e-12);
  CHECK_ABS(dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2], 1, 1e-14);

  /* inject 20,000 droplets in one step into an empty box (no particles) */
  const long N = 20000;
  gs_dem *d = one_particle(1e-4, 0);
  d->p.x[0] = 0.04; /* out of the way */
  const double md = 1000 * M_PI / 6 * 1e-9;
  z.mass_rate = (N + 0.5) * md / d->prm.dt;
  z.end = d->prm.dt * 1.5;
  CHECK(gs_dem_spray_init(&s2, &z, 42, &err) == 0);
  CHECK(gs_dem_spray_init(&s3, &z, 43, &err) == 0);
  CHECK(gs_dem_run(d, 1, &err) == 0);
  CHECK(gs_dem_spray_step(&s2, d, &err) == 0);
  CHECK(gs_dem_spray_step(&s3, d, &err) == 0);
  CHECK(s2.injected == N && s2.n == (size_t)N);
  /* fixed seed: the same droplets as a second spray with the same seed */
  gs_dem_spray s4;
  CHECK(gs_dem_spray_init(&s4, &z, 42, &err) == 0);
  CHECK(gs_dem_spray_step(&s4, d, &err) == 0);
  CHECK(s4.n == s2.n && memcmp(s4.drop, s2.drop, s2.n * sizeof *s2.drop) == 0);
  CHECK(memcmp(s3.drop, s2.drop, sizeof *s2.drop) != 0);
  double *th = malloc(N * sizeof *th), mx = 0, mz = 0, sx = 0, sz = 0;
  const double c0 = cos(half * M_PI / 180);
  for (long k = 0; k < N; k++) {
    const double *v = s2.drop[k].v;
    const double sp = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    th[k] = acos(fmin(1, -v[1] / sp));
    mx += v[0] / sp, mz += v[2] / sp;
    sx += v[0] * v[0] / (sp * sp), sz += v[2] * v[2] / (sp * sp);
  }
  qsort(th, N, sizeof *th, cmp_double);
  double D = 0;
  for (long k = 0; k < N; k++) {
    const double F = (1 - cos(th[k])) / (1 - c0);
    D = fmax(D, fmax(fabs(F - (double)k / N), fabs((double)(k + 1) / N - F)));
  }
  /* Kolmogorov–Smirnov at 1 %: sqrt(N) D < 1.628 */
  fprintf(stderr, "cone: KS sqrt(N) D = %.3f (1 %% critical 1.628)\n", sqrt((double)N) * D);
  CHECK(sqrt((double)N) * D < 1.628);
  CHECK(th[N - 1] <= half * M_PI / 180 + 1e-12);
  /* the cross-axis components average out */
  mx /= N, mz /= N;
  CHECK(fabs(mx) < 4 * sqrt(sx / N / N));
  CHECK(fabs(mz) < 4 * sqrt(sz / N / N));
  free(th);
  gs_dem_spray_free(&s);
  gs_dem_spray_free(&s2);
  gs_dem_spray_free(&s3);
  gs_dem_spray_free(&s4);
  gs_dem_free(d);
}

static const char *DRUM =
    "dem:\n"
    "  time_step: 2.0e-5\n"
    "  duration: 0.3\n"
    "  box: {lo: [-0.04, -0.04, -0.001], hi: [0.04, 0.04, 0.021]}\n"
    "  gravity: [0, -9.81, 0]\n"
    "  seed: 5\n"
    WET_DRUM_BED
    "outlets:\n"
    "  - region: {box: {lo: [0.012, -0.03, -0.001], hi: [0.03, -0.02, 0.021]}}\n"
    "spray:\n"
    "  point: [0, 0.01, 0.01]\n"
    "  axis: [0, -1, 0]\n"
    "  half_angle: 30\n"
    "  droplet_diameter: 1.0e-3\n"
    "  mass_rate: 2.0e-3\n"
    "  speed: 1.0\n"
    "  start: 0.02\n"
    "granulation:\n"
    "  every: 0.02\n"
    "  rule: {type: constant, efficiency: 0.0}\n"
    "output: {every: 0.02}\n";

/* The values of a CSV's column (by header name) on every row. */
static size_t column(const char *text, const char *name, double *out, size_t max) {
  const char *nl = strchr(text, '\n');
  int col = -1, k = 0;
  for (const char *p = text; p < nl; k++) {
    const char *e = strpbrk(p, ",\n");
    if ((size_t)(e - p) == strlen(name) && !strncmp(p, name, (size_t)(e - p))) col = k;
    p = e + 1;
  }
  CHECK(col >= 0);
  size_t n = 0;
  for (const char *p = nl + 1; *p && n < max; p = strchr(p, '\n') + 1) {
    const char *q = p;
    for (int c = 0; c < col; c++) q = strchr(q, ',') + 1;
    out[n++] = strtod(q, NULL);
    if (!strchr(p, '\n')) break;
  }
  return n;
}

static void drum_ledger(void) {
  gs_dem_case *c = dt_load("drum", DRUM);
  if (!c) return;
  dt_run(c, "drum");
  char *s = dt_slurp("drum", "spray.csv"), *g = dt_slurp("drum", "granulation.csv");
  double inj[64], on[64], air[64], wall[64], left[64], gl[64];
  size_t n = column(s, "injected", inj, 64);
  CHECK(n == 16);
  column(s, "on_particles", on, 64);
  column(s, "airborne", air, 64);
  column(s, "on_walls", wall, 64);
  column(s, "left", left, 64);
  CHECK(column(g, "liquid_volume", gl, 64) == n);
  for (size_t k = 0; k < n; k++) {
    CHECK_ABS(inj[k] - (on[k] + air[k] + wall[k] + left[k]), 0, 1e-12 * inj[k]);
    CHECK_REL(gl[k], on[k], 1e-12);
  }
  /* every fate occurred */
  CHECK(on[n - 1] > 0 && air[n - 1] > 0 && wall[n - 1] > 0 && left[n - 1] > 0);
  /* the mass rate: 0.28 s of spraying, whole droplets */
  const double vd = M_PI / 6 * 1e-9;
  CHECK_ABS(inj[n - 1] / vd, floor(2.0e-3 * 0.28 / (1000 * vd) + 1e-9), 1e-6);
  free(s);
  free(g);
  gs_dem_case_free(c);
}

/* A case that must not load, with the message naming want. */
static void refused(const char *name, const char *yaml, const char *want) {
  char path[600];
  snprintf(path, sizeof path, "%s/%s.yaml", dt_dir, name);
  FILE *fp = fopen(path, "w");
  fputs(yaml, fp);
  fclose(fp);
  gs_error err = {0};
  gs_dem_case *c = gs_dem_case_load(path, &err);
  CHECK(c == NULL);
  fprintf(stderr, "refused as expected: %s\n", err.msg);
  if (!strstr(err.msg, want)) fprintf(stderr, "%s: message '%s' lacks '%s'\n", name, err.msg, want);
  CHECK(strstr(err.msg, want) != NULL);
  gs_dem_case_free(c);
}

static char *replaced(const char *text, const char *from, const char *to) {
  const char *p = strstr(text, from);
  CHECK(p != NULL);
  char *s = malloc(strlen(text) + strlen(to) + 1);
  size_t k = (size_t)(p - text);
  memcpy(s, text, k);
  strcpy(s + k, to);
  strcat(s, p + strlen(from));
  return s;
}

static void bad_input(void) {
  char *a = replaced(DRUM, "point: [0, 0.01, 0.01]", "point: [0, 0.05, 0.01]");
  refused("outside", a, "spray.point");
  char *b = replaced(DRUM, "droplet_diameter: 1.0e-3", "droplet_diameter: 0");
  refused("diameter", b, "droplet_diameter");
  char *e = replaced(DRUM, "  seed: 5\n", "  seed: 5\n  engine: liggghts\n");
  refused("engine", e, "embedded");
  free(a);
  free(b);
  free(e);
}

int main(void) {
  if (dt_scratch_begin("spray")) return 1;
  single_droplet();
  cone_statistics();
  accel_hook();
  drum_ledger();
  bad_input();
  dt_scratch_end();
  return check_failures != 0;
}
