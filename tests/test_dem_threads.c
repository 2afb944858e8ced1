/* The OpenMP force loops give the same motion with 1 and 4 threads (to
 * round-off: only the order of the force sums differs) on a dense, colliding
 * bed (threads forced on for its 3072 particles) in a box of planes, and
 * count the same collision events and wall impacts; and the same with 1 and
 * 2 threads in a box of triangle meshes with a turning mesh paddle, where the
 * record of impact speeds (the breakage table's input) must match too, with
 * either mesh-contact rule. */
#include <omp.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "check.h"
#include "gransim/dem.h"

typedef struct {
  size_t n;
  double *x, *w;
  long *id;
  unsigned long long events, impacts;
  size_t nspeed;
  int *wc;
  double *lnu;
} snapshot;

/* unit cube [0,1]^3 as 12 triangles, scaled by s and shifted by o */
static void cube(double *t, double s, double o) {
  static const int Q[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (int f = 0; f < 6; f++) {
    int tri[2][3] = {{Q[f][0], Q[f][1], Q[f][2]}, {Q[f][0], Q[f][2], Q[f][3]}};
    for (int h = 0; h < 2; h++)
      for (int c = 0; c < 3; c++)
        for (int a = 0; a < 3; a++) t[9 * (2 * f + h) + 3 * c + a] = o + s * ((tri[h][c] >> a) & 1);
  }
}

static snapshot take(gs_dem *d, size_t nwc) {
  gs_dem_view v;
  gs_dem_get_view(d, &v);
  snapshot out;
  out.n = v.n;
  out.x = malloc(3 * v.n * sizeof(double));
  out.w = malloc(3 * v.n * sizeof(double));
  out.id = malloc(v.n * sizeof(long));
  for (size_t i = 0; i < v.n; i++) {
    /* arrays are in cell order, which is the same for both runs only up to
     * round-off; store by id */
    size_t k = (size_t)v.id[i];
    out.x[3 * k] = v.x[i], out.x[3 * k + 1] = v.y[i], out.x[3 * k + 2] = v.z[i];
    out.w[3 * k] = v.wx[i], out.w[3 * k + 1] = v.wy[i], out.w[3 * k + 2] = v.wz[i];
  }
  gs_dem_counters c;
  gs_dem_get_counters(d, &c);
  out.events = 0;
  for (int q = 0; q < c.nclass * c.nclass; q++) out.events += c.pair_events[q];
  out.impacts = 0;
  for (size_t q = 0; q < nwc; q++) out.impacts += c.wall_impacts[q];
  const int *wc;
  const double *lnu;
  out.nspeed = gs_dem_impact_speeds(d, &wc, &lnu);
  out.wc = malloc((out.nspeed + 1) * sizeof(int));
  out.lnu = malloc((out.nspeed + 1) * sizeof(double));
  memcpy(out.wc, wc, out.nspeed * sizeof(int));
  memcpy(out.lnu, lnu, out.nspeed * sizeof(double));
  return out;
}

static void drop(snapshot *s) {
  free(s->x), free(s->w), free(s->id), free(s->wc), free(s->lnu);
}

/* both runs agree: same events, impacts and impact-speed record, motion to round-off */
static void compare(const char *what, snapshot a, snapshot b, size_t n, unsigned long long min_events) {
  double dx = 0, dw = 0, wmax = 0, dl = 0;
  CHECK(a.n == b.n && a.n == n);
  for (size_t k = 0; k < 3 * a.n && a.n == b.n; k++) {
    dx = fmax(dx, fabs(a.x[k] - b.x[k]));
    dw = fmax(dw, fabs(a.w[k] - b.w[k]));
    wmax = fmax(wmax, fabs(a.w[k]));
  }
  int same_wc = a.nspeed == b.nspeed;
  for (size_t k = 0; same_wc && k < a.nspeed; k++) {
    same_wc &= a.wc[k] == b.wc[k];
    dl = fmax(dl, fabs(a.lnu[k] - b.lnu[k]));
  }
  fprintf(stderr, "%s: %llu vs %llu collisions, %llu vs %llu wall impacts, %zu vs %zu impact speeds (%s order, "
          "largest ln U difference %.3g), largest position difference %.3g m, angular velocity %.3g rad/s (of "
          "%.3g)\n", what, a.events, b.events, a.impacts, b.impacts, a.nspeed, b.nspeed, same_wc ? "same" : "DIFFERENT",
          dl, dx, dw, wmax);
  CHECK(a.events > min_events);
  CHECK(a.impacts > 100);
  CHECK(a.events == b.events);
  CHECK(a.impacts == b.impacts);
  CHECK(a.nspeed > 100 && same_wc);
  CHECK(dl < 1e-9);
  CHECK(dx < 1e-12);
  CHECK(dw < 1e-8 * wmax);
}

/* An engine on `threads` threads (forced on whatever the particle count),
 * domain [lo, hi]^3, two particle types t[0], t[1] of one material *m,
 * mesh contacts by rule `contacts` (GS_DEM_MESH_*). */
static gs_dem *engine(int threads, double lo, double hi, gs_dem_material *m, int t[2], int contacts) {
  omp_set_num_threads(threads);
  gs_dem_params p;
  memset(&p, 0, sizeof p);
  p.dt = 2e-6;
  p.skin = 5e-4;
  p.gravity[2] = -9.81;
  for (int a = 0; a < 3; a++) p.lo[a] = lo, p.hi[a] = hi;
  p.nclass = 2;
  p.mesh_contacts = contacts;
  gs_error err = {0};
  gs_dem *d = gs_dem_alloc(&p, &err);
  gs_dem_set_parallel_min(d, 0);
  *m = (gs_dem_material){8e6, 0.2, 0.4, 0.5, 0.2, 500};
  t[0] = gs_dem_add_type(d, m, 0, &err);
  t[1] = gs_dem_add_type(d, m, 1, &err);
  return d;
}

/* n[0] x n[1] x n[2] particles on a lattice of spacing h from x0, velocity
 * components uniform in [-vmax, vmax], a third of them (at random) of type
 * t[1] and radius r_big, the rest t[0] of radius 1.2 mm; a fixed LCG seed.
 * Sites with |y - band_y| < band_half are left empty (band_half 0: none). */
static void lattice(gs_dem *d, const int t[2], const int n[3], double x0, double h, double vmax, double r_big,
                    unsigned seed, double band_y, double band_half) {
  gs_error err = {0};
  for (int i = 0; i < n[0]; i++)
    for (int j = 0; j < n[1]; j++)
      for (int k = 0; k < n[2]; k++) {
        seed = seed * 1103515245u + 12345u;
        double x[3] = {x0 + h * i, x0 + h * j, x0 + h * k};
        if (fabs(x[1] - band_y) < band_half) continue;
        double v[3] = {vmax * (((seed >> 8) % 1000) / 500.0 - 1), vmax * (((seed >> 12) % 1000) / 500.0 - 1),
                       vmax * (((seed >> 16) % 1000) / 500.0 - 1)};
        int big = (seed >> 20) % 3 == 0;
        gs_dem_add_particle(d, t[big], big ? r_big : 1.2e-3, x, v, NULL, &err);
      }
}

static snapshot run(int threads) {
  gs_dem_material m;
  int t[2];
  gs_dem *d = engine(threads, -0.001, 0.061, &m, t, GS_DEM_MESH_CLOSEST);
  gs_error err = {0};
  for (int a = 0; a < 3; a++) {
    double pl[3] = {0, 0, 0}, nl[3] = {0, 0, 0}, ph[3] = {0, 0, 0}, nh[3] = {0, 0, 0};
    pl[a] = 0, nl[a] = 1, ph[a] = 0.06, nh[a] = -1;
    gs_dem_add_plane(d, "lo", pl, nl, &m, &err);
    gs_dem_add_plane(d, "hi", ph, nh, &m, &err);
  }
  /* a lattice with random velocities: collisions from the first steps */
  lattice(d, t, (const int[3]){16, 16, 12}, 0.002, 0.0037, 1.0, 1.7e-3, 7, 0, 0);
  if (gs_dem_run(d, 1500, &err)) fprintf(stderr, "%s\n", err.msg);
  snapshot out = take(d, 12);
  gs_dem_free(d);
  return out;
}

/* A closed box of 12 triangles (62 mm) with a vertical paddle (2 triangles,
 * 40 x 30 mm) turning at 1000 rpm about z through the box's centre, and a
 * lattice of particles flying about at up to 2 m/s; threads forced on. */
static snapshot run_mesh(int threads, int contacts) {
  gs_dem_material m;
  int t[2];
  gs_dem *d = engine(threads, -0.002, 0.062, &m, t, contacts);
  gs_error err = {0};
  double box[108];
  cube(box, 0.062, -0.001);
  CHECK(gs_dem_add_mesh(d, "box", gs_dem_mesh_from_triangles(box, 12, &err), &m, &err) == 0);
  const double c0 = 0.03, h = 0.02;
  double paddle[18] = {c0 - h, c0, 0.005, c0 + h, c0, 0.005, c0 + h, c0, 0.035,
                       c0 - h, c0, 0.005, c0 + h, c0, 0.035, c0 - h, c0, 0.035};
  int pw = gs_dem_add_mesh(d, "paddle", gs_dem_mesh_from_triangles(paddle, 2, &err), &m, &err);
  const double o[3] = {c0, c0, 0}, z[3] = {0, 0, 1};
  CHECK(gs_dem_wall_set_motion(d, pw, o, z, 1000 * 2 * M_PI / 60, NULL, &err) == 0);
  lattice(d, t, (const int[3]){10, 10, 10}, 0.003, 0.006, 2.0, 1.6e-3, 11, c0, 0.003); /* clear of the paddle */
  if (gs_dem_run(d, 1500, &err)) fprintf(stderr, "%s\n", err.msg);
  snapshot out = take(d, 4);
  gs_dem_free(d);
  return out;
}

static double now(void) { return omp_get_wtime(); }

int main(int argc, char **argv) {
  /* Threads spinning at the barriers of these small steps starve each other
   * on a machine whose cores are shared (10 s instead of 0.3 s here): wait
   * passively.  The runtime reads the policy before main, hence the re-exec. */
  if (argc >= 1 && !getenv("OMP_WAIT_POLICY")) {
    setenv("OMP_WAIT_POLICY", "passive", 1);
    execv("/proc/self/exe", argv);
  }
  double t0 = now();
  snapshot a = run(1), b = run(4);
  fprintf(stderr, "planes: %.2f s\n", now() - t0);
  t0 = now();
  compare("planes, 1 vs 4 threads", a, b, 3072, 1000);
  drop(&a), drop(&b);
  a = run_mesh(1, GS_DEM_MESH_CLOSEST);
  fprintf(stderr, "meshes, 1 thread: %.2f s\n", now() - t0);
  b = run_mesh(2, GS_DEM_MESH_CLOSEST);
  fprintf(stderr, "meshes, both: %.2f s\n", now() - t0);
  compare("meshes and a turning paddle, 1 vs 2 threads", a, b, a.n, 100);
  CHECK(a.n > 800);
  drop(&a), drop(&b);
  /* LIGGGHTS' contact rule (mesh_contacts: liggghts): the same for any thread count */
  a = run_mesh(1, GS_DEM_MESH_LIGGGHTS);
  b = run_mesh(2, GS_DEM_MESH_LIGGGHTS);
  compare("meshes with LIGGGHTS' contact rule, 1 vs 2 threads", a, b, a.n, 100);
  drop(&a), drop(&b);
  TEST_EXIT();
}
