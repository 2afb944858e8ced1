/* Insertion and removal: particles inserted into a region do not overlap
 * each other or the walls, follow the requested mass fractions, and are all
 * removed by an outlet region below, with residence times equal to the fall
 * time; the particles' classes are booked in the removal record. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "gransim/dem.h"

static int below(const double x[3], void *ctx) {
  return x[2] < *(const double *)ctx;
}

int main(void) {
  gs_dem_params p;
  memset(&p, 0, sizeof p);
  p.dt = 5e-6;
  p.skin = 5e-4;
  p.gravity[2] = -9.81;
  p.lo[0] = p.lo[1] = -0.05, p.lo[2] = -0.2;
  p.hi[0] = p.hi[1] = 0.05, p.hi[2] = 0.05;
  p.nclass = 2;
  gs_error err = {0};
  gs_dem *d = gs_dem_alloc(&p, &err);
  gs_dem_material m = {8e6, 0.2, 0.4, 0.5, 0.2, 500};
  int t0 = gs_dem_add_type(d, &m, 0, &err), t1 = gs_dem_add_type(d, &m, 1, &err);
  /* a vertical pipe the particles fall through; it also bounds the region */
  double o[3] = {0, 0, 0}, ax[3] = {0, 0, 1};
  gs_dem_add_cylinder(d, "pipe", o, ax, 0.02, 1, &m, &err);
  gs_dem_region reg;
  memset(&reg, 0, sizeof reg);
  reg.kind = GS_DEM_REGION_CYLINDER;
  reg.a[2] = 1;
  reg.R = 0.0205; /* reaches past the pipe: candidates there must be refused */
  reg.s0 = 0.0;
  reg.s1 = 0.04;
  int types[2] = {t0, t1};
  double rmin[2] = {1e-3, 2e-3}, rmax[2] = {1e-3, 2e-3}, frac[2] = {0.5, 0.5};
  gs_dem_psd psd = {2, types, rmin, rmax, frac, 1, NULL, NULL};
  uint64_t seed = 3;
  long n;
  double mass;
  CHECK(gs_dem_insert(d, &reg, &psd, 600, HUGE_VAL, NULL, &seed, &n, &mass, &err) == 0);
  CHECK(n == 600);
  /* mass fractions 1:1 with radii 1 and 2 mm: eight small per large */
  gs_dem_run(d, 0, &err);
  gs_dem_view v;
  gs_dem_get_view(d, &v);
  double msum[2] = {0, 0}, worst = 0;
  size_t cnt[2] = {0, 0};
  for (size_t i = 0; i < v.n; i++) {
    int c = gs_dem_type_class(d, v.type[i]);
    msum[c] += v.m[i];
    cnt[c]++;
    worst = fmax(worst, hypot(v.x[i], v.y[i]) + v.r[i] - 0.02);
    for (size_t j = i + 1; j < v.n; j++) {
      double dx = v.x[i] - v.x[j], dy = v.y[i] - v.y[j], dz = v.z[i] - v.z[j];
      worst = fmax(worst, v.r[i] + v.r[j] - sqrt(dx * dx + dy * dy + dz * dz));
    }
  }
  fprintf(stderr, "inserted %zu small + %zu large, mass %.4g : %.4g, largest overlap %.3g m\n", cnt[0],
          cnt[1], msum[0], msum[1], worst);
  CHECK(worst <= 0);
  CHECK(fabs(msum[0] / (msum[0] + msum[1]) - 0.5) < 0.1);
  /* all fall out through the outlet 0.1 m below; residence ~ sqrt(2 h / g) */
  double zcut = -0.1;
  gs_dem_remove_if(d, below, &zcut);
  gs_dem_run(d, 40000, &err);
  gs_dem_get_view(d, &v);
  const int *cls;
  const double *rt, *ms;
  size_t nr = gs_dem_take_removed(d, &cls, &rt, &ms);
  double tmin = HUGE_VAL, tmax = 0, mout = 0;
  size_t nc1 = 0;
  for (size_t k = 0; k < nr; k++) {
    tmin = fmin(tmin, rt[k]);
    tmax = fmax(tmax, rt[k]);
    mout += ms[k];
    nc1 += cls[k] == 1;
  }
  gs_dem_counters c;
  gs_dem_get_counters(d, &c);
  fprintf(stderr, "removed %zu (%zu large, %.4g kg), residence %.4f..%.4f s (free fall from the region: "
          "%.4f..%.4f s), %zu left, %llu lost\n", nr, nc1, mout, tmin, tmax, sqrt(2 * 0.1 / 9.81),
          sqrt(2 * 0.14 / 9.81), v.n, (unsigned long long)c.lost);
  CHECK(nr == 600 && v.n == 0 && c.lost == 0);
  CHECK(nc1 == cnt[1]);
  CHECK_REL(mout, msum[0] + msum[1], 1e-12);
  CHECK(tmin > 0.9 * sqrt(2 * 0.1 / 9.81));
  CHECK(tmax < 0.2);
  gs_dem_free(d);
  TEST_EXIT();
}
