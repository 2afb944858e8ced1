/* The OpenMP force loops give the same motion with 1 and 4 threads (to
 * round-off: only the order of the force sums differs) on a dense, colliding
 * bed (threads forced on for its 3072 particles), and count the same
 * collision events. */
#include <omp.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "gransim/dem.h"

typedef struct {
  size_t n;
  double *x, *w;
  long *id;
  unsigned long long events, impacts;
} snapshot;

static snapshot run(int threads) {
  omp_set_num_threads(threads);
  gs_dem_params p;
  memset(&p, 0, sizeof p);
  p.dt = 2e-6;
  p.skin = 5e-4;
  p.gravity[2] = -9.81;
  for (int a = 0; a < 3; a++) p.lo[a] = -0.001, p.hi[a] = 0.061;
  p.nclass = 2;
  gs_error err = {0};
  gs_dem *d = gs_dem_alloc(&p, &err);
  gs_dem_set_parallel_min(d, 0);
  gs_dem_material m = {8e6, 0.2, 0.4, 0.5, 0.2, 500};
  int t0 = gs_dem_add_type(d, &m, 0, &err), t1 = gs_dem_add_type(d, &m, 1, &err);
  const double zero[3] = {0, 0, 0};
  for (int a = 0; a < 3; a++) {
    double pl[3] = {0, 0, 0}, nl[3] = {0, 0, 0}, ph[3] = {0, 0, 0}, nh[3] = {0, 0, 0};
    pl[a] = 0, nl[a] = 1, ph[a] = 0.06, nh[a] = -1;
    gs_dem_add_plane(d, "lo", pl, nl, &m, &err);
    gs_dem_add_plane(d, "hi", ph, nh, &m, &err);
  }
  (void)zero;
  /* a lattice with random velocities: collisions from the first steps */
  unsigned s = 7;
  for (int i = 0; i < 16; i++)
    for (int j = 0; j < 16; j++)
      for (int k = 0; k < 12; k++) {
        s = s * 1103515245u + 12345u;
        double x[3] = {0.002 + 0.0037 * i, 0.002 + 0.0037 * j, 0.002 + 0.0037 * k};
        double v[3] = {((s >> 8) % 1000) / 500.0 - 1, ((s >> 12) % 1000) / 500.0 - 1,
                       ((s >> 16) % 1000) / 500.0 - 1};
        int big = (s >> 20) % 3 == 0;
        gs_dem_add_particle(d, big ? t1 : t0, big ? 1.7e-3 : 1.2e-3, x, v, NULL, &err);
      }
  if (gs_dem_run(d, 1500, &err)) fprintf(stderr, "%s\n", err.msg);
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
  for (int q = 0; q < 4; q++) out.events += c.pair_events[q];
  out.impacts = 0;
  for (size_t q = 0; q < 12; q++) out.impacts += c.wall_impacts[q];
  gs_dem_free(d);
  return out;
}

int main(void) {
  snapshot a = run(1), b = run(4);
  double dx = 0, dw = 0, wmax = 0;
  CHECK(a.n == b.n && a.n == 3072);
  for (size_t k = 0; k < 3 * a.n && a.n == b.n; k++) {
    dx = fmax(dx, fabs(a.x[k] - b.x[k]));
    dw = fmax(dw, fabs(a.w[k] - b.w[k]));
    wmax = fmax(wmax, fabs(a.w[k]));
  }
  fprintf(stderr, "1 vs 4 threads: %llu vs %llu collisions, %llu vs %llu wall impacts, largest position "
          "difference %.3g m, angular velocity %.3g rad/s (of %.3g)\n", a.events, b.events, a.impacts,
          b.impacts, dx, dw, wmax);
  CHECK(a.events > 1000);
  CHECK(a.events == b.events);
  CHECK(a.impacts == b.impacts);
  CHECK(dx < 1e-12);
  CHECK(dw < 1e-8 * wmax);
  free(a.x), free(a.w), free(a.id), free(b.x), free(b.w), free(b.id);
  TEST_EXIT();
}
