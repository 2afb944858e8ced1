/* The observer of a DEM case's run (gs_dem_case_set_observer) and the
 * delayed start of a wall's rotation (rotation.start):
 *  - the observer sees every statistics sample, at t = k * sample_every,
 *    with the figures the time series reports at that time;
 *  - stopping at a sample ends the run there, with tables equal bit for bit
 *    to those of the same case whose duration ends at that time;
 *  - opening the statistics window at a sample gives the tables of the same
 *    case with statistics.start at that time;
 *  - a rotating mesh stands still before rotation.start and has turned by
 *    omega * (t - start) after it. */
#include "dem_testlib.h"

/* a closed rotating drum of 120 particles in three classes */
#define DRUM(DURATION, START, ROT_START)                                                             \
  "dem: {time_step: 5.0e-6, box: {lo: [-0.03, -0.03, -0.001], hi: [0.03, 0.03, 0.021]}, "            \
  "gravity: [0, -9.81, 0], duration: " DURATION ", seed: 3}\n"                                        \
  "materials:\n  - {name: g, E: 8.0e6, nu: 0.2, e: 0.4, mu_s: 0.5, mu_r: 0.2, density: 500}\n"       \
  "classes:\n  - {name: a, radius: 1.0e-3, material: g}\n  - {name: b, radius: 1.3e-3, material: g}\n" \
  "  - {name: c, radius: 1.6e-3, material: g}\n"                                                     \
  "walls:\n  - {name: drum, cylinder: {point: [0, 0, 0], axis: [0, 0, 1], radius: 0.015}, material: g,\n" \
  "     rotation: {origin: [0, 0, 0], axis: [0, 0, 1], rpm: 120" ROT_START "}}\n"                      \
  "  - {name: front, plane: {point: [0, 0, 0], normal: [0, 0, 1]}, material: g}\n"                   \
  "  - {name: back, plane: {point: [0, 0, 0.02], normal: [0, 0, -1]}, material: g}\n"                \
  "fill:\n  - region: {cylinder: {point: [0, 0, 0], axis: [0, 0, 1], radius: 0.013, from: 0.002, to: 0.018}}\n" \
  "    count: 120\n    fractions: [0.3, 0.4, 0.3]\n"                                                  \
  "statistics: {sample_every: 0.002, start: " START "}\n"                                            \
  "output: {every: 0.002, vtk_every: 0}\n"

typedef struct {
  long n;
  double t[64], ke[64], m[64], coll[64];
  long stop_at, open_at; /* 1-based sample at which to stop / open the window (0: never) */
  int window_seen;
} obs_state;

static int on_sample(const gs_dem_sample *s, void *user, int *open_window, int *stop, gs_error *err) {
  (void)err;
  obs_state *o = user;
  if (o->n < 64) {
    o->t[o->n] = s->t;
    o->ke[o->n] = s->kinetic_energy;
    o->m[o->n] = s->holdup_mass;
    o->coll[o->n] = s->collisions_per_s;
  }
  o->n++;
  if (o->open_at && o->n > o->open_at) o->window_seen += s->window;
  if (o->n == o->open_at) *open_window = 1;
  if (o->n == o->stop_at) *stop = 1;
  return GS_OK;
}

static void same_file(const char *a, const char *b, const char *file) {
  char *x = dt_slurp(a, file), *y = dt_slurp(b, file);
  if (strcmp(x, y)) fprintf(stderr, "%s differs between %s and %s\n", file, a, b);
  CHECK(!strcmp(x, y));
  free(x);
  free(y);
}

static void observer_stops_and_opens(void) {
  /* the reference: runs to 0.03 s, statistics from 0.01 s */
  gs_dem_case *ref = dt_load("ref", DRUM("0.03", "0.01", ""));
  if (!ref) return;
  CHECK(dt_run(ref, "ref") == 0);
  gs_dem_case_free(ref);

  /* observed: 0.1 s asked, window opened at sample 5 (0.01 s), stopped at sample 15 (0.03 s);
   * the start given (0.09 s) is never reached */
  gs_dem_case *c = dt_load("obs", DRUM("0.1", "0.09", ""));
  if (!c) return;
  obs_state o = {.stop_at = 15, .open_at = 5};
  gs_dem_observer ob = {.sample = on_sample, .user = &o};
  gs_dem_case_set_observer(c, &ob);
  CHECK(dt_run(c, "obs") == 0);
  gs_dem_case_free(c);
  printf("observer: %ld samples, last at t = %g s; window open in %d of them\n", o.n, o.t[o.n - 1],
         o.window_seen);
  CHECK(o.n == 15);
  for (long k = 0; k < o.n && k < 64; k++) {
    CHECK_REL(o.t[k], 0.002 * (double)(k + 1), 1e-9);
    CHECK(o.ke[k] > 0 && o.m[k] > 0 && o.coll[k] >= 0);
  }
  CHECK(o.window_seen == 10);
  /* the same tables as the reference, and the same time series up to the collision-rate
   * column of the opening (the reference's counters restart one step earlier) */
  same_file("obs", "ref", "collision_kernel.csv");
  same_file("obs", "ref", "collisions.csv");
  same_file("obs", "ref", "impact_table.csv");
  same_file("obs", "ref", "velocity.csv");
  char *ts = dt_slurp("obs", "timeseries.csv");
  int rows = 0;
  for (char *p = ts; *p; p++) rows += *p == '\n';
  CHECK(rows == 1 + 16); /* header, t = 0 and 15 samples */
  CHECK(strstr(ts, "\n0.03,") != NULL);
  free(ts);
}

/* An error of the observer stops the run with its status. */
static int failing(const gs_dem_sample *s, void *user, int *open_window, int *stop, gs_error *err) {
  (void)user;
  (void)open_window;
  (void)stop;
  return s->t > 0.005 ? gs_error_set(err, GS_ENUMERIC, "observer failed at t = %g", s->t) : GS_OK;
}

static void observer_error_stops(void) {
  gs_dem_case *c = dt_load("fail", DRUM("0.05", "0", ""));
  if (!c) return;
  gs_dem_observer ob = {.sample = failing};
  gs_dem_case_set_observer(c, &ob);
  char out[600];
  snprintf(out, sizeof out, "%s/fail", dt_dir);
  gs_error err = {0};
  CHECK(gs_dem_case_run(c, out, 0, &err) == GS_ENUMERIC);
  CHECK(strstr(err.msg, "observer failed at t = 0.006") != NULL);
  gs_dem_case_free(c);
}

/* A mesh turning about z at omega from t = start: its first vertex at each time. */
static void spin_start(void) {
  gs_dem_params p = {.dt = 1e-4, .gravity = {0, 0, 0}, .skin = 1e-3, .lo = {-1, -1, -1}, .hi = {1, 1, 1},
                     .nclass = 1};
  gs_error err = {0};
  gs_dem *d = gs_dem_alloc(&p, &err);
  const gs_dem_material m = {.E = 1e6, .nu = 0.25, .e = 0.5, .mu_s = 0.3, .mu_r = 0, .density = 1000};
  double tri[9 * 8];
  dt_disk(tri, 0.1, 8);
  int w = gs_dem_add_mesh(d, "disk", gs_dem_mesh_from_triangles(tri, 8, &err), &m, &err);
  CHECK(w == 0);
  const double o[3] = {0, 0, 0}, ax[3] = {0, 0, 1}, omega = 3.0, start = 0.05;
  CHECK(gs_dem_wall_set_motion(d, w, o, ax, omega, NULL, &err) == GS_OK);
  CHECK(gs_dem_wall_set_spin_start(d, w, start, &err) == GS_OK);
  CHECK(gs_dem_wall_set_spin_start(d, w, -1, &err) == GS_EINPUT);
  CHECK(gs_dem_wall_set_spin_start(d, w, start, &err) == GS_OK);
  gs_dem_add_type(d, &m, 0, &err);
  double now[9 * 8];
  for (int k = 1; k <= 10; k++) {
    CHECK(gs_dem_run(d, 100, &err) == GS_OK); /* t = 0.01 k */
    const double t = gs_dem_time(d), th = omega * fmax(0, t - start);
    gs_dem_wall_triangles(d, (size_t)w, now);
    /* vertex 1 of triangle 0 starts at (0.1, 0, 0) */
    CHECK_ABS(now[3], 0.1 * cos(th), 1e-12);
    CHECK_ABS(now[4], 0.1 * sin(th), 1e-12);
  }
  gs_dem_free(d);
}

int main(void) {
  if (dt_scratch_begin("dem-observer")) return 1;
  observer_stops_and_opens();
  observer_error_stops();
  spin_start();
  dt_scratch_end();
  TEST_EXIT();
}
