/* Statistics of `gransim dem` runs (src/dem/stats.c, run_dem.c):
 *  - the steady-state detector fires on steady synthetic signals, at the first
 *    sample whose window is steady, and not on a ramp or without collisions;
 *  - residence times: particles that left before statistics.start are not
 *    counted (they were, at the first sample), and the per-class distribution
 *    books every particle under its class;
 *  - velocity statistics per axial compartment for a prescribed velocity
 *    field: mean number, mean and sample sd of the speed and of each velocity
 *    component, mean axial velocity;
 *  - the collision frequencies of one like and one unlike head-on collision:
 *    C_11 = 2/(N_1^2 W) and C_12 = 1/(N_1 N_2 W), the PBM pair loop's convention;
 *  - with `start: steady` that never fires, a warning on stderr, a note in the
 *    headers and nan rates instead of zeros. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "dem_testlib.h"
#include "dem/dem_stats.h"
#include "gransim/dem.h"

/* the numbers of the first data line starting with prefix (up to max) */
static int row(const char *text, const char *prefix, double *v, int max) {
  const char *p = text;
  size_t lp = strlen(prefix);
  while (p && *p) {
    if (!strncmp(p, prefix, lp)) {
      int n = 0;
      const char *q = p;
      while (n < max && *q && *q != '\n') {
        char *end;
        double x = strtod(q, &end);
        if (end != q) v[n++] = x, q = end;
        else if (!strncmp(q, "nan", 3)) v[n++] = NAN, q += 3;
        else {
          while (*q && *q != ',' && *q != '\n') q++; /* a name */
        }
        if (*q == ',') q++;
      }
      return n;
    }
    p = strchr(p, '\n');
    if (p) p++;
  }
  return 0;
}

/* ---- steady-state detector ----------------------------------------------- */
static void test_detector(void) {
  enum { N = 60 };
  double a[N], b[N], zero[N];
  for (int k = 0; k < N; k++) {
    a[k] = 2.0 * (1 + 0.05 * sin(1.3 * k)); /* hold-up mass within 5 % */
    b[k] = 1e4 * (1 + 0.08 * cos(0.7 * k)); /* collision rate within 8 % */
    zero[k] = 0;
  }
  CHECK(gs_dem_is_steady(a, b, N, 10, 0.1) == 1);
  CHECK(gs_dem_is_steady(a, b, 9, 10, 0.1) == 0);   /* fewer samples than the window */
  CHECK(gs_dem_is_steady(a, b, N, 10, 0.06) == 0);  /* the rate varies by 8 % */
  CHECK(gs_dem_is_steady(a, zero, N, 10, 0.1) == 0); /* no collisions: nothing to be steady about */
  /* a ramp of 3 % per sample: over any 10 samples the ends lie 13-14 % from
   * the mean */
  double ramp[N];
  for (int k = 0; k < N; k++) ramp[k] = pow(1.03, k);
  int fired = 0;
  for (int n = 1; n <= N; n++) fired |= gs_dem_is_steady(ramp, b, n, 10, 0.1);
  CHECK(!fired);
  for (int n = 1; n <= N; n++) fired |= gs_dem_is_steady(a, ramp, n, 10, 0.1);
  CHECK(!fired);
  /* a ramp that levels off at sample 20: with window 5 and tolerance 1e-9 the
   * first steady window is samples 20..24, i.e. n = 25 */
  double lvl[N];
  for (int k = 0; k < N; k++) lvl[k] = k < 20 ? 0.05 * k : 1.0;
  int first = 0;
  for (int n = 1; n <= N && !first; n++)
    if (gs_dem_is_steady(lvl, lvl, n, 5, 1e-9)) first = n;
  fprintf(stderr, "detector: steady signal fires, ramps do not; levelling ramp first steady at n = %d\n", first);
  CHECK(first == 25);
  /* statistics.steady.quantities: hold-up and collision rate steady while the
   * kinetic energy still decays by 3 % a sample: steady on the first two, not
   * with the third (gs_dem_is_steady_n) */
  const double *two[2] = {a, b}, *three[3] = {a, b, ramp};
  CHECK(gs_dem_is_steady_n(two, 2, N, 10, 0.1) == 1);
  CHECK(gs_dem_is_steady_n(three, 3, N, 10, 0.1) == 0);
  CHECK(gs_dem_is_steady_n(three, 3, N, 10, 0.15) == 1); /* the ramp's ends lie 13-14 % from its mean */
  CHECK(gs_dem_is_steady_n(three, 0, N, 10, 0.1) == 0);  /* nothing watched: never steady */
}

/* ---- residence times ----------------------------------------------------- */
static const char *RES =
    "dem:\n"
    "  time_step: 2.0e-6\n"
    "  duration: 0.06\n"
    "  gravity: [0, 0, 0]\n"
    "  skin: 2.0e-4\n"
    "  box: {lo: [-0.03, -0.03, -0.02], hi: [0.03, 0.03, 0.06]}\n"
    "materials:\n"
    "  - {name: g, E: 8.0e6, nu: 0.2, e: 0.4, mu_s: 0.5, density: 500}\n"
    "classes:\n"
    "  - {name: low, radius: 1.0e-3, material: g}\n"
    "  - {name: high, radius: 1.0e-3, material: g}\n"
    "fill:\n"
    "  - {region: {box: {lo: [-0.02, -0.02, 0.01], hi: [0.02, 0.02, 0.03]}}, count: 40, fractions: [1, 0],"
    " velocity: [0, 0, -1]}\n"
    "  - {region: {box: {lo: [-0.02, -0.02, 0.03], hi: [0.02, 0.02, 0.05]}}, count: 30, fractions: [0, 1],"
    " velocity: [0, 0, -1]}\n"
    "outlets:\n"
    "  - {region: {box: {lo: [-0.03, -0.03, -0.02], hi: [0.03, 0.03, 0.0]}}}\n"
    "statistics: {start: 0.02, sample_every: 0.001}\n"
    "output: {every: 0.01}\n";

static void test_residence(void) {
  gs_dem_case *c = dt_load("res", RES);
  if (!c || dt_run(c, "res")) {
    gs_dem_case_free(c);
    return;
  }
  gs_dem_view v;
  gs_dem_get_view(c->dem, &v);
  CHECK(v.n == 0); /* everything left at 1 m/s within 0.05 s */
  gs_dem_case_free(c);
  /* particles present when the window opened: the time series row at 0.02 s */
  char *ts = dt_slurp("res", "timeseries.csv");
  double r[3] = {0};
  CHECK(row(ts, "0.02,", r, 2) == 2);
  long at_start = (long)r[1];
  free(ts);
  /* the counts and means are in the tables' descriptions (their JSON sidecars) */
  char *res = dt_slurp("res", "residence.json"), *cls = dt_slurp("res", "residence_class.csv");
  char *clsj = dt_slurp("res", "residence_class.json");
  long pooled = -1, n_low = -1, n_high = -1;
  double mean_low = 0, mean_high = 0;
  const char *d = strstr(res, "\"description\": \"");
  CHECK(d && sscanf(d, "\"description\": \"%ld particles left", &pooled) == 1);
  const char *p = strstr(clsj, "class 1 (low): "), *q = strstr(clsj, "class 2 (high): ");
  CHECK(p && q);
  if (p) CHECK(sscanf(p, "class 1 (low): %ld particles, mean residence %lf", &n_low, &mean_low) == 2);
  if (q) CHECK(sscanf(q, "class 2 (high): %ld particles, mean residence %lf", &n_high, &mean_high) == 2);
  CHECK(strncmp(cls, "class,name,t_lo,t_hi,count,fraction\n", 36) == 0); /* the header first */
  fprintf(stderr, "residence: %ld particles present at the window start, %ld counted (%ld low, %ld high; mean "
          "residence %.4f, %.4f s)\n", at_start, pooled, n_low, n_high, mean_low, mean_high);
  /* all 30 'high' particles start above 0.03 m and leave inside the window;
   * of the 'low' ones, only those still there at 0.02 s count */
  CHECK(at_start > 30 && at_start < 70);
  CHECK(pooled == at_start);
  CHECK(n_high == 30);
  CHECK(n_low == at_start - 30);
  /* per class: residence ~ the fall time from the start height (+ up to 1e-4 s
   * to the next list rebuild): low in [0.02, 0.03], high in [0.03, 0.05] */
  int bad = 0;
  long cnt[2] = {0, 0};
  for (const char *l = strchr(cls, '\n'); l && l[1]; l = strchr(l + 1, '\n')) {
    int k;
    double lo, hi, f;
    long n;
    if (sscanf(l + 1, "%d,%*[^,],%lf,%lf,%ld,%lf", &k, &lo, &hi, &n, &f) != 5) continue;
    if (n == 0) continue;
    cnt[k - 1] += n;
    if (k == 1 && (hi < 0.0199 || lo > 0.0302)) bad++;
    if (k == 2 && (hi < 0.0299 || lo > 0.0502)) bad++;
  }
  CHECK(cnt[0] == n_low && cnt[1] == n_high);
  CHECK(bad == 0);
  CHECK(mean_low > 0.02 && mean_low < 0.0302);
  CHECK(mean_high > 0.03 && mean_high < 0.0502);
  free(res);
  free(cls);
  free(clsj);
}

/* ---- velocities per compartment ------------------------------------------- */
static const char *VEL =
    "dem:\n"
    "  time_step: 5.0e-6\n"
    "  duration: 0.002\n"
    "  gravity: [0, 0, 0]\n"
    "  box: {lo: [-0.01, -0.01, -0.01], hi: [0.11, 0.05, 0.05]}\n"
    "materials:\n"
    "  - {name: g, E: 8.0e6, nu: 0.2, e: 0.4, mu_s: 0.5, density: 500}\n"
    "classes:\n"
    "  - {name: a, radius: 1.0e-3, material: g}\n"
    "  - {name: b, radius: 1.5e-3, material: g}\n"
    "statistics:\n"
    "  sample_every: 2.0e-4\n"
    "  compartments: {axis: [1, 0, 0], origin: [0, 0, 0], edges: [0, 0.05, 0.1]}\n";

/* n particles of class cls on a lattice (5 mm apart: in 2 ms at <= 0.3 m/s
 * none can reach another) from x0 along x, all with velocity v */
static void lattice(gs_dem_case *c, int cls, int n, double x0, const double v[3], int *site) {
  gs_error err = {0};
  for (int k = 0; k < n; k++, (*site)++) {
    double x[3] = {x0 + 0.005 * (*site % 7), 0.005 * (*site / 7 % 7), 0.005 * (*site / 49)};
    CHECK(gs_dem_add_particle(c->dem, c->cls[cls].type, cls ? 1.5e-3 : 1.0e-3, x, v, NULL, &err) >= 0);
  }
}

/* sample mean and sd over ns samples of the values x[k] held by n[k] particles */
static void stats_of(const double *x, const int *n, int m, int ns, double *mean, double *sd) {
  double N = 0, s = 0, s2 = 0;
  for (int k = 0; k < m; k++) N += n[k], s += n[k] * x[k];
  *mean = s / N;
  for (int k = 0; k < m; k++) s2 += n[k] * (x[k] - *mean) * (x[k] - *mean);
  *sd = sqrt(s2 * ns / (N * ns - 1));
}

static void test_velocity(void) {
  gs_dem_case *c = dt_load("vel", VEL);
  if (c) {
    /* compartment 1 (x 0..0.05): class a, 40 at (0.2, 0, 0) and 60 at (0, 0.1, 0);
     * compartment 2 (x 0.05..0.1): class a, 50 at (-0.1, 0, 0.3), class b, 30 at (0, 0, -0.05) */
    const double v1[3] = {0.2, 0, 0}, v2[3] = {0, 0.1, 0}, v3[3] = {-0.1, 0, 0.3}, v4[3] = {0, 0, -0.05};
    int s1 = 0, s2 = 0;
    lattice(c, 0, 40, 0.01, v1, &s1);
    lattice(c, 0, 60, 0.01, v2, &s1);
    lattice(c, 0, 50, 0.06, v3, &s2);
    lattice(c, 1, 30, 0.06, v4, &s2);
  }
  if (!c || dt_run(c, "vel")) {
    gs_dem_case_free(c);
    return;
  }
  gs_dem_case_free(c);
  char *col = dt_slurp("vel", "collisions.csv"), *vel = dt_slurp("vel", "velocity.csv");
  double e[10] = {0};
  /* class_i, class_j, events, ... (names skipped): nobody met, so the velocities stay as prescribed */
  CHECK(row(col, "1,1,", e, 10) == 8 && e[2] == 0);
  CHECK(row(col, "1,2,", e, 10) == 8 && e[2] == 0);
  /* expected: compartment 1 holds class a with 40 at (0.2,0,0) and 60 at (0,0.1,0); compartment 2
   * class a with 50 at (-0.1,0,0.3) and class b with 30 at (0,0,-0.05); 10 samples */
  const int ns = 10;
  struct {
    const char *prefix;
    int m, n[2];
    double v[2][3];
  } want[4] = {{"1,a,1,", 2, {40, 60}, {{0.2, 0, 0}, {0, 0.1, 0}}},
               {"1,a,2,", 1, {50, 0}, {{-0.1, 0, 0.3}, {0}}},
               {"2,b,1,", 0, {0, 0}, {{0}}},
               {"2,b,2,", 1, {30, 0}, {{0, 0, -0.05}, {0}}}};
  for (int w = 0; w < 4; w++) {
    double f[16]; /* f[k]: column k of the file (f[0] unused: the name is skipped) */
    int got = row(vel, want[w].prefix, f + 1, 15);
    CHECK(got == 14);
    if (got != 14) continue;
    /* columns: class, (name), compartment, from, to, mean_number, mean_speed, std_speed, mean_axial,
     * mean_vx, mean_vy, mean_vz, std_vx, std_vy, std_vz; class lands in f[1], compartment in f[2] */
    const int m = want[w].m;
    double N = want[w].n[0] + want[w].n[1];
    fprintf(stderr, "velocity class %s compartment: n %.6g, speed %.6g +- %.6g, axial %.6g, v (%.4g %.4g %.4g) +- "
            "(%.4g %.4g %.4g)\n", want[w].prefix, f[5], f[6], f[7], f[8], f[9], f[10], f[11], f[12], f[13], f[14]);
    CHECK_ABS(f[3], w % 2 ? 0.05 : 0, 1e-12);
    CHECK_ABS(f[4], w % 2 ? 0.1 : 0.05, 1e-12);
    CHECK_ABS(f[5], N, 1e-9);
    if (!m) {
      for (int k = 6; k <= 14; k++) CHECK(isnan(f[k]));
      continue;
    }
    double sp[2], mean, sd;
    for (int k = 0; k < m; k++) sp[k] = sqrt(want[w].v[k][0] * want[w].v[k][0] + want[w].v[k][1] * want[w].v[k][1] +
                                             want[w].v[k][2] * want[w].v[k][2]);
    stats_of(sp, want[w].n, m, ns, &mean, &sd);
    CHECK_ABS(f[6], mean, 1e-6 * mean);
    CHECK_ABS(f[7], sd, 1e-6 * mean);
    for (int a = 0; a < 3; a++) {
      double x[2] = {want[w].v[0][a], want[w].v[1][a]};
      stats_of(x, want[w].n, m, ns, &mean, &sd);
      CHECK_ABS(f[9 + a], mean, 1e-6);
      CHECK_ABS(f[12 + a], sd, 1e-6);
      if (a == 0) CHECK_ABS(f[8], mean, 1e-6); /* the axis is x */
    }
  }
  free(col);
  free(vel);
}

/* ---- the diagonal of C: two head-on collisions, one like, one unlike ------------ */
static void test_meet(void) {
  gs_dem_case *c = dt_load("meet", VEL);
  if (c) {
    gs_error err = {0};
    /* a-a closing at 0.4 m/s from a 0.2 mm gap (touch at 0.5 ms), a-b from a 0.3 mm gap
     * (0.75 ms); the rebound (e = 0.4) parts them for good within the 2 ms of the run */
    const double pa[3] = {0.01, 0.01, 0.01}, pb[3] = {0.0122, 0.01, 0.01};
    const double pc[3] = {0.01, 0.03, 0.01}, pd[3] = {0.0128, 0.03, 0.01};
    const double vr[3] = {0.2, 0, 0}, vl[3] = {-0.2, 0, 0};
    CHECK(gs_dem_add_particle(c->dem, c->cls[0].type, 1.0e-3, pa, vr, NULL, &err) >= 0);
    CHECK(gs_dem_add_particle(c->dem, c->cls[0].type, 1.0e-3, pb, vl, NULL, &err) >= 0);
    CHECK(gs_dem_add_particle(c->dem, c->cls[0].type, 1.0e-3, pc, vr, NULL, &err) >= 0);
    CHECK(gs_dem_add_particle(c->dem, c->cls[1].type, 1.5e-3, pd, vl, NULL, &err) >= 0);
  }
  if (!c || dt_run(c, "meet")) {
    gs_dem_case_free(c);
    return;
  }
  gs_dem_case_free(c);
  char *col = dt_slurp("meet", "collisions.csv"), *ker = dt_slurp("meet", "collision_kernel.csv");
  double r11[10] = {0}, r12[10] = {0}, r22[10] = {0};
  /* class_i, class_j, events, N_i, N_j, window_s, events_per_s, C_ij (names skipped) */
  CHECK(row(col, "1,1,", r11, 10) == 8 && row(col, "1,2,", r12, 10) == 8 && row(col, "2,2,", r22, 10) == 8);
  const double W = r11[5];
  fprintf(stderr, "meet: events 1-1 %g, 1-2 %g, 2-2 %g; N %g, %g; window %g s; C_11 %.6g, C_12 %.6g\n", r11[2],
          r12[2], r22[2], r11[3], r12[4], W, r11[7], r12[7]);
  CHECK(r11[2] == 1 && r12[2] == 1 && r22[2] == 0);
  CHECK(r11[3] == 3 && r12[4] == 1);
  /* the PBM's convention: C_ii = 2 E_ii / (N_i^2 W), C_ij = E_ij / (N_i N_j W) */
  CHECK_ABS(r11[7], 2.0 / (9 * W), 1e-9 / W);
  CHECK_ABS(r12[7], 1.0 / (3 * W), 1e-9 / W);
  /* the kernel table holds the same matrix: first row C_11, C_12 */
  const char *m = ker && !strncmp(ker, "edges", 5) ? strchr(ker, '\n') : NULL; /* the header first */
  double k11 = 0, k12 = 0;
  CHECK(m && sscanf(m + 1, "%lf, %lf", &k11, &k12) == 2);
  CHECK_ABS(k11, r11[7], 1e-6 * r11[7]);
  CHECK_ABS(k12, r12[7], 1e-6 * r12[7]);
  free(col);
  free(ker);
}

/* ---- start: steady that never fires ---------------------------------------- */
static const char *NEVER =
    "dem:\n"
    "  time_step: 5.0e-6\n"
    "  duration: 0.01\n"
    "  gravity: [0, 0, 0]\n"
    "  box: {lo: [0, 0, 0], hi: [0.05, 0.05, 0.05]}\n"
    "materials:\n"
    "  - {name: g, E: 8.0e6, nu: 0.2, e: 0.4, mu_s: 0.5, density: 500}\n"
    "classes:\n"
    "  - {name: a, radius: 1.0e-3, material: g}\n"
    "fill:\n"
    "  - {region: {box: {lo: [0.01, 0.01, 0.01], hi: [0.04, 0.04, 0.04]}}, count: 20}\n"
    "statistics: {start: steady, sample_every: 0.001, steady: {window: 3, tolerance: 0.5}}\n";

static void test_never_steady(void) {
  gs_dem_case *c = dt_load("never", NEVER);
  if (!c) return;
  char log[700];
  snprintf(log, sizeof log, "%s/never.log", dt_dir);
  fflush(stderr);
  int fd = dup(2);
  FILE *fp = freopen(log, "w", stderr);
  CHECK(fp != NULL);
  int rc = dt_run(c, "never");
  fflush(stderr);
  dup2(fd, 2);
  close(fd);
  gs_dem_case_free(c);
  if (rc) return;
  char *msg = dt_slurp("never", "../never.log");
  char *col = dt_slurp("never", "collisions.csv"), *ker = dt_slurp("never", "collision_kernel.json");
  char *imp = dt_slurp("never", "impact_table.json"), *colj = dt_slurp("never", "collisions.json");
  char *kerc = dt_slurp("never", "collision_kernel.csv");
  fprintf(stderr, "never steady: stderr: %s", msg);
  CHECK(strstr(msg, "warning") && strstr(msg, "steady state was not reached"));
  CHECK(strstr(colj, "NO STATISTICS WINDOW") && strstr(ker, "NO STATISTICS WINDOW") &&
        strstr(imp, "NO STATISTICS WINDOW"));
  double r[10] = {0};
  CHECK(row(col, "1,1,", r, 10) == 8); /* class_i, class_j, events, N_i, N_j, window, per s, C (names skipped) */
  CHECK(isnan(r[3]) && isnan(r[6]) && isnan(r[7]));
  CHECK(strstr(kerc, "\nnan\n") != NULL);
  free(msg);
  free(col);
  free(ker);
  free(imp);
  free(colj);
  free(kerc);
}

int main(void) {
  if (dt_scratch_begin("test-dem-stats")) TEST_EXIT();
  test_detector();
  test_residence();
  test_velocity();
  test_meet();
  test_never_steady();
  dt_scratch_end();
  TEST_EXIT();
}
