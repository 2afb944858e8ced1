/* The population balance inside the DEM (src/dem/granulation.c,
 * success_rules.c, pair_log.c):
 *  - merging two particles conserves solid volume, liquid volume, mass and
 *    momentum to round-off, puts the aggregate at their centre of mass with
 *    the radius of the summed solid, and the next rebuild drops the partner
 *    without booking it as removed;
 *  - growth: a merged pair's contact radius starts at the larger partner's,
 *    is halfway after half the growth time and the aggregate's own after
 *    it, and a neighbour first reached while growing is pushed away (the
 *    neighbour list followed the growth);
 *  - the success rules: `constant` aggregates exactly when both (or, with
 *    `require: either`, one) liquid contents reach lc_min and u < psi0;
 *    `stokes` exactly when St_v < St* (computed here from Liu et al. 2000),
 *    never for films thinner than the asperities;
 *  - an update over 4,000 logged collisions of distinct wet pairs with
 *    psi0 = 0.1 aggregates a Binomial(4000, 0.1) number (within 4 standard
 *    deviations; the same number again with the same seed), dry pairs never,
 *    and writes C_ab = N_ab / (F_a F_b dt) per class pair;
 *  - the collision log is the same with 1 and 2 threads (threads forced
 *    on for 1,728 colliding particles): the same pairs in the same order,
 *    approach speeds to round-off;
 *  - a sprayed drum run with aggregation: at every update the class
 *    populations add up to the particles present, particles fall by exactly
 *    the aggregations, the solid volume stays to round-off and the liquid on
 *    the particles is the spray ledger's. */
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "dem/dem_wet.h"
#include "dem_testlib.h"
#include "wet_testlib.h"

static gs_dem *empty_dem(void) {
  gs_dem_params prm = {.dt = 1e-5, .gravity = {0, 0, 0}, .skin = 2e-4, .lo = {-1, -1, -1},
                       .hi = {1, 1, 1}, .nclass = 1};
  gs_error err = {0};
  gs_dem *d = gs_dem_alloc(&prm, &err);
  gs_dem_material m = {.E = 1e7, .nu = 0.25, .e = 0.5, .mu_s = 0.5, .density = 1030};
  CHECK(gs_dem_add_type(d, &m, 0, &err) == 0);
  return d;
}

static void merge_conserves(void) {
  gs_dem *d = empty_dem();
  gs_error err = {0};
  const double xa[3] = {0.01, 0.02, 0.03}, va[3] = {0.3, -1.1, 0.7}, wa[3] = {5, -3, 2};
  const double xb[3] = {0.0125, 0.0201, 0.0299}, vb[3] = {-0.9, 0.2, 1.3}, wb[3] = {-1, 4, 8};
  CHECK(gs_dem_add_particle(d, 0, 1.0e-3, xa, va, wa, &err) == 0);
  CHECK(gs_dem_add_particle(d, 0, 1.5e-3, xb, vb, wb, &err) == 1);
  CHECK(gs_dem_run(d, 0, &err) == 0);
  gs_dem_particles *p = &d->p;
  /* give both some liquid (absorbed droplets change mass and velocity too) */
  const double vdrop[3] = {0, -2, 0};
  gs_dem_absorb(d, 0, 3e-10, 3e-7, vdrop);
  gs_dem_absorb(d, 1, 7e-10, 7e-7, vdrop);
  double vs = 0, vl = 0, m = 0, P[3] = {0, 0, 0}, X[3] = {0, 0, 0};
  for (size_t i = 0; i < 2; i++) {
    vs += p->vs[i], vl += p->vl[i], m += p->m[i];
    P[0] += p->m[i] * p->vx[i], P[1] += p->m[i] * p->vy[i], P[2] += p->m[i] * p->vz[i];
    X[0] += p->m[i] * p->x[i], X[1] += p->m[i] * p->y[i], X[2] += p->m[i] * p->z[i];
  }
  size_t keep = p->id[0] == 1 ? 0 : 1, gone = 1 - keep;
  gs_dem_merge(d, keep, gone);
  CHECK_REL(p->vs[keep], vs, 1e-15);
  CHECK_REL(p->vl[keep], vl, 1e-15);
  CHECK_REL(p->m[keep], m, 1e-15);
  CHECK_REL(p->m[keep] * p->vx[keep], P[0], 1e-14);
  CHECK_REL(p->m[keep] * p->vy[keep], P[1], 1e-14);
  CHECK_REL(p->m[keep] * p->vz[keep], P[2], 1e-14);
  CHECK_REL(p->x[keep], X[0] / m, 1e-15);
  CHECK_REL(p->y[keep], X[1] / m, 1e-15);
  CHECK_REL(p->z[keep], X[2] / m, 1e-15);
  CHECK_REL(4.0 / 3.0 * M_PI * pow(p->r[keep], 3), vs, 1e-14);
  CHECK_REL(p->invm[keep], 1 / m, 1e-15);
  CHECK(p->dead[gone]);
  CHECK(gs_dem_run(d, 1, &err) == 0);
  CHECK(d->p.n == 1);
  CHECK(d->vs_removed == 0 && d->vl_removed == 0);
  CHECK_REL(d->p.vs[0], vs, 1e-15);
  gs_dem_free(d);
}

static void growth(void) {
  gs_dem *d = empty_dem();
  gs_error err = {0};
  const double xa[3] = {-1e-3, 0, 0}, xb[3] = {1e-3, 0, 0}, xc[3] = {0, 2.25e-3, 0};
  CHECK(gs_dem_add_particle(d, 0, 1e-3, xa, NULL, NULL, &err) == 0);
  CHECK(gs_dem_add_particle(d, 0, 1e-3, xb, NULL, NULL, &err) == 1);
  CHECK(gs_dem_add_particle(d, 0, 1e-3, xc, NULL, NULL, &err) == 2);
  CHECK(gs_dem_run(d, 0, &err) == 0);
  gs_dem_granulation g = {.growth_k = 20};
  size_t ia = 0, ib = 0, ic = 0;
  for (size_t i = 0; i < 3; i++) {
    if (d->p.id[i] == 0) ia = i;
    if (d->p.id[i] == 1) ib = i;
    if (d->p.id[i] == 2) ic = i;
  }
  gs_dem_merge(d, ia, ib);
  const double r1 = d->p.r[ia];
  CHECK_REL(r1, 1e-3 * cbrt(2.0), 1e-15);
  CHECK(gs_dem_growth_add(&g, d, ia, 1e-3, &err) == 0);
  CHECK(d->p.r[ia] == 1e-3 && g.ngrow == 1);
  CHECK(gs_dem_prepare(d, &err) == 0 && gs_dem_rebuild(d, &err) == 0);
  for (int s = 0; s < 20; s++) {
    CHECK(gs_dem_run(d, 1, &err) == 0);
    gs_dem_growth_step(&g, d);
    if (s == 9) {
      for (size_t i = 0; i < d->p.n; i++)
        if (d->p.id[i] == 0) CHECK_REL(d->p.r[i], 1e-3 + 0.5 * (r1 - 1e-3), 1e-12);
    }
  }
  CHECK(g.ngrow == 0);
  CHECK(gs_dem_run(d, 5, &err) == 0);
  CHECK(d->p.n == 2);
  for (size_t i = 0; i < d->p.n; i++) {
    if (d->p.id[i] == 0) CHECK(d->p.r[i] == r1);
    if (d->p.id[i] == 2) CHECK(d->p.vy[i] > 1e-6);
  }
  (void)ic;
  free(g.grow);
  gs_dem_free(d);
}

static void rules(void) {
  const gs_dem_rule_type *cst = gs_registry_find((const void *const *)gs_dem_rule_types, "constant");
  const gs_dem_rule_type *sto = gs_registry_find((const void *const *)gs_dem_rule_types, "stokes");
  CHECK(cst && sto);
  if (!cst || !sto) return;
  gs_dem_rule r = {.type = cst, .efficiency = 0.01, .lc_min = 0.2};
  /* liquid contents 0.19 and 0.3 */
  gs_dem_partner dry = {1e-5, 1e-3, 0.81e-9, 0.19e-9}, wet = {1e-5, 1e-3, 0.7e-9, 0.3e-9};
  CHECK_REL(gs_dem_liquid_content(&dry), 0.19, 1e-14);
  CHECK(cst->success(&r, &wet, &wet, 1, 0.0099) == 1);
  CHECK(cst->success(&r, &wet, &wet, 1, 0.01) == 0);
  CHECK(cst->success(&r, &dry, &wet, 1, 0.0) == 0);
  CHECK(cst->success(&r, &wet, &dry, 1, 0.0) == 0);
  r.either = 1;
  CHECK(cst->success(&r, &dry, &wet, 1, 0.0099) == 1);
  CHECK(cst->success(&r, &dry, &dry, 1, 0.0) == 0);
  /* exactly at lc_min counts as wet */
  gs_dem_partner edge = {1e-5, 1e-3, 0.8e-9, 0.2e-9};
  r.either = 0;
  r.lc_min = gs_dem_liquid_content(&edge);
  CHECK(cst->success(&r, &edge, &edge, 1, 0.0) == 1);

  /* Stokes: St_v = 8 m~ (vn/2) / (3 pi mu d~^2) against (1 + 1/e) ln(h/ha) */
  gs_dem_rule s = {.type = sto, .viscosity = 0.05, .restitution = 0.4, .asperity = 1e-6};
  gs_dem_partner a = {4.3e-6, 1.0e-3, 4.19e-9, 2.0e-9}, b = {1.2e-5, 1.4e-3, 1.15e-8, 3.0e-9};
  const double h = 0.5 * (a.vl / (4 * M_PI * a.r * a.r) + b.vl / (4 * M_PI * b.r * b.r));
  const double mh = 2 * a.m * b.m / (a.m + b.m), dh = 2 * (2 * a.r) * (2 * b.r) / (2 * a.r + 2 * b.r);
  const double stc = (1 + 1 / 0.4) * log(h / 1e-6);
  const double vcrit = stc * 3 * M_PI * 0.05 * dh * dh / (8 * mh * 0.5);
  CHECK(stc > 0);
  CHECK(sto->success(&s, &a, &b, vcrit * (1 - 1e-9), 0.99) == 1);
  CHECK(sto->success(&s, &a, &b, vcrit * (1 + 1e-9), 0.0) == 0);
  gs_dem_partner ad = a, bd = b;
  ad.vl = bd.vl = 0;
  CHECK(sto->success(&s, &ad, &bd, 0.0, 0.0) == 0);
}

/* 2 N particles far apart; pairs (2k, 2k+1) logged as collisions, wet when k is even. */
static long update_once(uint64_t seed, int N, const char *dir, long *wet_aggs) {
  gs_dem *d = empty_dem();
  gs_error err = {0};
  for (int k = 0; k < 2 * N; k++) {
    const double x[3] = {-0.9 + 1.8 * (k % 60) / 60.0, -0.9 + 1.8 * ((k / 60) % 60) / 60.0,
                         -0.9 + 1.8 * (k / 3600) / 60.0};
    CHECK(gs_dem_add_particle(d, 0, 1e-3, x, NULL, NULL, &err) == k);
  }
  CHECK(gs_dem_run(d, 0, &err) == 0);
  for (size_t i = 0; i < d->p.n; i++)
    if ((d->p.id[i] / 2) % 2 == 0) d->p.vl[i] = d->p.vs[i]; /* liquid content 0.5 */
  gs_dem_granulation g = {.every = 1e-4, .every_k = 10, .ds = d->p.vs[0], .dl = d->p.vs[0], .ns = 4, .nl = 3};
  g.rule = (gs_dem_rule){.type = gs_registry_find((const void *const *)gs_dem_rule_types, "constant"),
                         .efficiency = 0.1, .lc_min = 0.2};
  CHECK(gs_dem_granulation_start(&g, d, dir, seed, &err) == 0);
  CHECK(gs_dem_run(d, 10, &err) == 0);
  for (int k = 0; k < N; k++) gs_dem_pair_log_push(d->plog, 2 * k + 1, 2 * k, 1.0);
  double vs0 = 0;
  for (size_t i = 0; i < d->p.n; i++) vs0 += d->p.vs[i];
  CHECK(gs_dem_granulation_update(&g, d, &err) == 0);
  CHECK(gs_dem_granulation_finish(&g, &err) == 0);
  long aggs = (long)g.aggregations;
  CHECK(g.collisions == (uint64_t)N);
  CHECK(d->p.n == (size_t)(2 * N - aggs));
  double vs1 = 0;
  *wet_aggs = 0;
  for (size_t i = 0; i < d->p.n; i++) {
    vs1 += d->p.vs[i];
    if (d->p.vs[i] > 1.5 * g.ds) *wet_aggs += (d->p.id[i] / 2) % 2 == 0;
  }
  CHECK_REL(vs1, vs0, 1e-13);
  gs_dem_granulation_free(&g);
  gs_dem_free(d);
  return aggs;
}

static void update_statistics(void) {
  char dir[700];
  snprintf(dir, sizeof dir, "%s/update", dt_dir);
  CHECK(mkdir(dir, 0777) == 0);
  const int N = 8000; /* 4000 wet pairs, 4000 dry */
  long wet1, wet2;
  long a1 = update_once(17, N, dir, &wet1), a2 = update_once(17, N, dir, &wet2);
  const double mean = 0.1 * N / 2, sd = sqrt(N / 2 * 0.1 * 0.9);
  fprintf(stderr, "update: %ld aggregations of %d wet pairs (expected %.0f +- %.1f)\n", a1, N / 2, mean, sd);
  CHECK(fabs(a1 - mean) < 4 * sd);
  CHECK(a1 == a2 && wet1 == a1 && wet2 == a2);
  /* C_ab of the (1,0)-(1,0) dry pairs and (1,1)-(1,1) wet pairs: N / (F^2 dt) */
  char *t = dt_slurp("update", "granulation_collisions.csv");
  /* same-class pairs: C_aa = 2 N_aa / (F_a^2 dt), the PBM pair loop's convention */
  const double F = N, C = 2.0 * (N / 2) / (F * F * 1e-4);
  char want[2][200];
  snprintf(want[0], sizeof want[0], ",1,0,1,0,%d,%d,0.0001,%d,0,", N, N, N / 2);
  snprintf(want[1], sizeof want[1], ",1,1,1,1,%d,%d,0.0001,%d,%ld,", N, N, N / 2, a1);
  for (int q = 0; q < 2; q++) {
    const char *r = strstr(t, want[q]);
    if (!r) fprintf(stderr, "granulation_collisions.csv lacks '%s':\n%s", want[q], t);
    CHECK(r != NULL);
    if (r) CHECK_REL(strtod(r + strlen(want[q]), NULL), C, 1e-8);
  }
  free(t);
  /* the run's kernel table between solid classes: all 2N particles in class 1 */
  t = dt_slurp("update", "granulation_kernel.csv");
  const char *row = strncmp(t, "edges, ", 7) ? strstr(t, "\nedges, ") : t; /* header first */
  CHECK(row != NULL);
  if (row) {
    row = strchr(row + 1, '\n') + 1;
    char *end;
    CHECK_REL(strtod(row, &end), 2.0 * N / (4.0 * F * F * 1e-4), 1e-8);
    for (int q = 0; q < 3; q++) CHECK(strtod(end + 1, &end) == 0);
  }
  free(t);
}

static const char *DRUM =
    "dem:\n"
    "  time_step: 2.0e-5\n"
    "  duration: 0.4\n"
    "  box: {lo: [-0.04, -0.04, -0.001], hi: [0.04, 0.04, 0.021]}\n"
    "  gravity: [0, -9.81, 0]\n"
    "  seed: 9\n"
    WET_DRUM_BED
    "spray:\n"
    "  point: [0, 0.005, 0.01]\n"
    "  axis: [0, -1, 0]\n"
    "  half_angle: 15\n"
    "  droplet_diameter: 1.26e-3\n"
    "  mass_rate: 3.0e-3\n"
    "  speed: 1.0\n"
    "granulation:\n"
    "  every: 0.02\n"
    "  rule: {type: constant, efficiency: 0.5, min_liquid_content: 0.1, require: either}\n"
    "  solid_classes: {count: 6}\n"
    "  liquid_classes: {count: 5}\n"
    "output: {every: 0.02}\n";

/* Column col (0-based) of every data row of a CSV, as numbers. */
static size_t col(const char *text, int c, double *out, size_t max) {
  size_t n = 0;
  const char *p = strchr(text, '\n');
  while (p && p[1] && n < max) {
    const char *q = p + 1;
    for (int k = 0; k < c; k++) q = strchr(q, ',') + 1;
    out[n++] = strtod(q, NULL);
    p = strchr(p + 1, '\n');
  }
  return n;
}

static void drum_classes(void) {
  gs_dem_case *c = dt_load("drum", DRUM);
  if (!c) return;
  dt_run(c, "drum");
  char *g = dt_slurp("drum", "granulation.csv"), *k = dt_slurp("drum", "granulation_classes.csv");
  char *s = dt_slurp("drum", "spray.csv"), *ts = dt_slurp("drum", "timeseries.csv");
  enum { M = 4096 };
  static double gt[M], np[M], agg[M], vs[M], vl[M], kt[M], kp[M], on[M], tsn[M];
  size_t n = col(g, 0, gt, M);
  col(g, 1, np, M);
  col(g, 6, agg, M);
  col(g, 7, vs, M);
  col(g, 8, vl, M);
  size_t nk = col(k, 0, kt, M);
  col(k, 5, kp, M);
  CHECK(col(s, 5, on, M) == n);
  CHECK(col(ts, 1, tsn, M) == n);
  CHECK(n == 21 && nk == 30 * n);
  double total_agg = 0;
  for (size_t r = 0; r < n; r++) {
    double sum = 0;
    for (size_t q = 0; q < 30; q++) {
      CHECK(kt[30 * r + q] == gt[r]);
      sum += kp[30 * r + q];
    }
    CHECK(sum == np[r]);
    CHECK(tsn[r] == np[r]);
    total_agg += agg[r];
    CHECK(np[r] == 250 - total_agg);
    CHECK_REL(vs[r], vs[0], 1e-13);
    CHECK_REL(vl[r], on[r], 1e-13);
  }
  fprintf(stderr, "drum: %.0f aggregations, %.0f particles left\n", total_agg, np[n - 1]);
  CHECK(total_agg > 10);
  free(g);
  free(k);
  free(s);
  free(ts);
  gs_dem_case_free(c);
}

/* The collision log of a gas of 12^3 particles in a box of planes. */
static gs_dem_pair_log log_run(int threads) {
  omp_set_num_threads(threads);
  gs_dem_params prm = {.dt = 2e-6, .gravity = {0, 0, -9.81}, .skin = 5e-4, .lo = {0, 0, 0},
                       .hi = {0.04, 0.04, 0.04}, .nclass = 1};
  gs_error err = {0};
  gs_dem *d = gs_dem_alloc(&prm, &err);
  gs_dem_set_parallel_min(d, 0);
  gs_dem_material m = {.E = 8e6, .nu = 0.2, .e = 0.4, .mu_s = 0.5, .mu_r = 0.2, .density = 500};
  CHECK(gs_dem_add_type(d, &m, 0, &err) == 0);
  const double o[3] = {0, 0, 0}, n[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  const double h[3] = {0.04, 0.04, 0.04}, nm[3][3] = {{-1, 0, 0}, {0, -1, 0}, {0, 0, -1}};
  for (int a = 0; a < 3; a++) {
    CHECK(gs_dem_add_plane(d, "lo", o, n[a], &m, &err) >= 0);
    CHECK(gs_dem_add_plane(d, "hi", h, nm[a], &m, &err) >= 0);
  }
  uint64_t q = 12345;
  for (int k = 0; k < 1728; k++) {
    double x[3] = {0.0025 + 0.003 * (k % 12), 0.0025 + 0.003 * ((k / 12) % 12), 0.0025 + 0.003 * (k / 144)}, v[3];
    for (int a = 0; a < 3; a++) {
      q = q * 6364136223846793005ULL + 1442695040888963407ULL;
      v[a] = ((double)(q >> 11) / 9007199254740992.0 - 0.5) * 2.0;
    }
    CHECK(gs_dem_add_particle(d, 0, 1.2e-3, x, v, NULL, &err) == k);
  }
  CHECK(gs_dem_pair_log_enable(d, &err) == 0);
  CHECK(gs_dem_run(d, 700, &err) == 0);
  gs_dem_pair_log L = *d->plog;
  d->plog->r = NULL;
  gs_dem_free(d);
  omp_set_num_threads(1);
  return L;
}

static void log_threads(void) {
  gs_dem_pair_log a = log_run(1), b = log_run(2);
  int same = a.n == b.n;
  double dv = 0;
  for (size_t k = 0; same && k < a.n; k++) {
    same &= a.r[k].ida == b.r[k].ida && a.r[k].idb == b.r[k].idb && a.r[k].ida < a.r[k].idb;
    dv = fmax(dv, fabs(a.r[k].vn - b.r[k].vn) / fmax(1e-3, a.r[k].vn));
  }
  fprintf(stderr, "log: %zu vs %zu collisions with 1 and 2 threads, %s pairs, largest vn difference %.3g\n", a.n,
          b.n, same ? "same" : "DIFFERENT", dv);
  CHECK(a.n > 500);
  CHECK(same);
  CHECK(dv < 1e-9);
  free(a.r);
  free(b.r);
}

int main(void) {
  if (dt_scratch_begin("granulation")) return 1;
  merge_conserves();
  growth();
  rules();
  log_threads();
  update_statistics();
  drum_classes();
  dt_scratch_end();
  return check_failures != 0;
}
