/* A pile poured onto a round table (a triangle-mesh disk; what rolls off the
 * edge falls out of the box) settles at a sensible angle of repose, clearly
 * steeper with rolling friction than without: spheres without rolling
 * resistance keep rolling. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "dem_testlib.h"
#include "gransim/dem.h"

/* Slope of the pile's upper surface: the highest particle top in rings of
 * width 2r, fitted by least squares between 25 % and 75 % of the pile radius. */
static double repose_angle(gs_dem *d, double r, double R) {
  gs_dem_view v;
  gs_dem_get_view(d, &v);
  int nb = (int)(R / (2 * r)) + 1;
  double *top = calloc((size_t)nb, sizeof(double));
  for (size_t i = 0; i < v.n; i++) {
    int b = (int)(hypot(v.x[i], v.y[i]) / (2 * r));
    if (b < nb) top[b] = fmax(top[b], v.z[i] + r);
  }
  double sx = 0, sy = 0, sxx = 0, sxy = 0, n = 0;
  for (int b = 0; b < nb; b++) {
    double rc = (b + 0.5) * 2 * r;
    if (rc < 0.25 * R || rc > 0.75 * R) continue;
    sx += rc, sy += top[b], sxx += rc * rc, sxy += rc * top[b], n++;
  }
  free(top);
  double slope = (n * sxy - sx * sy) / (n * sxx - sx * sx);
  return atan(-slope) * 180 / M_PI;
}

static int cmp_double(const void *a, const void *b) {
  double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

static double pour(double mu_r, size_t *n_out) {
  gs_dem_params p;
  memset(&p, 0, sizeof p);
  p.dt = 5e-6;
  p.skin = 1e-3;
  p.gravity[2] = -9.81;
  p.lo[0] = p.lo[1] = -0.1, p.lo[2] = -0.01;
  p.hi[0] = p.hi[1] = 0.1, p.hi[2] = 0.15;
  p.nclass = 1;
  gs_error err = {0};
  gs_dem *d = gs_dem_alloc(&p, &err);
  gs_dem_material m = {8e6, 0.2, 0.4, 0.5, mu_r, 500};
  int t = gs_dem_add_type(d, &m, 0, &err);
  double o[3] = {0, 0, 0}, nz[3] = {0, 0, 1};
  (void)o, (void)nz;
  /* the table: a disk of radius 20 mm in 64 triangles */
  const double rt = 0.020;
  double tri[64 * 9];
  dt_disk(tri, rt, 64);
  gs_dem_add_mesh(d, "table", gs_dem_mesh_from_triangles(tri, 64, &err), &m, &err);
  const double r = 1e-3;
  gs_dem_region reg;
  memset(&reg, 0, sizeof reg);
  reg.kind = GS_DEM_REGION_CYLINDER;
  reg.a[2] = 1;
  reg.R = 0.006;
  double rmin = r * 0.95, rmax = r * 1.05, frac = 1;
  gs_dem_psd psd = {1, &t, &rmin, &rmax, &frac, 0, NULL, NULL};
  uint64_t seed = 42;
  long total = 0;
  /* rain 4 particles every 2.5 ms, 1000 in all, from a little above the
   * height the pile can reach (about 12 mm), then let the pile settle */
  reg.s0 = 0.016;
  reg.s1 = 0.026;
  for (int k = 0; k < 250; k++) {
    long n;
    double mass;
    gs_dem_insert(d, &reg, &psd, 4, HUGE_VAL, NULL, &seed, &n, &mass, &err);
    total += n;
    if (gs_dem_run(d, 500, &err)) fprintf(stderr, "%s\n", err.msg);
  }
  gs_dem_run(d, 40000, &err);
  double angle = repose_angle(d, r, rt);
  gs_dem_view v;
  gs_dem_get_view(d, &v);
  double et, er;
  gs_dem_kinetic_energy(d, &et, &er);
  gs_dem_counters c;
  gs_dem_get_counters(d, &c);
  fprintf(stderr, "mu_r = %.2f: %ld poured, %zu on the table, %llu fell off, angle of repose %.1f deg, "
          "kinetic energy %.3g J\n", mu_r, total, v.n, (unsigned long long)c.lost, angle, et + er);
  CHECK(total == 1000);                         /* the pour region never jammed */
  CHECK(v.n + c.lost == (size_t)total);         /* nothing vanished otherwise */
  /* settled: the median particle is at rest (a few may still roll off the edge) */
  double *sp = malloc(v.n * sizeof(double));
  for (size_t i = 0; i < v.n; i++) sp[i] = sqrt(v.vx[i] * v.vx[i] + v.vy[i] * v.vy[i] + v.vz[i] * v.vz[i]);
  qsort(sp, v.n, sizeof(double), cmp_double);
  double median = v.n ? sp[v.n / 2] : 0;
  free(sp);
  fprintf(stderr, "  median speed %.3g m/s\n", median);
  if (mu_r > 0) CHECK(median < 1e-3);
  *n_out = v.n;
  gs_dem_free(d);
  return angle;
}

int main(void) {
  size_t n1, n0;
  double with = pour(0.2, &n1), without = pour(0.0, &n0);
  CHECK(n1 > n0); /* rolling friction holds more on the table */
  /* spheres with sliding and rolling friction pile at some 15-40 degrees;
   * without rolling resistance they roll off and leave a flat layer */
  CHECK(with > 15 && with < 45);
  CHECK(without < with - 10);
  TEST_EXIT();
}
