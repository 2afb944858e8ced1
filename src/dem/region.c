/* Regions for insertion, outlets, hold-up and statistics: boxes and finite
 * cylinders along any axis. */
#include <math.h>

#include "gransim/dem.h"

int gs_dem_region_contains(const gs_dem_region *g, const double x[3]) {
  if (g->kind == GS_DEM_REGION_BOX)
    return x[0] >= g->lo[0] && x[0] <= g->hi[0] && x[1] >= g->lo[1] && x[1] <= g->hi[1] &&
           x[2] >= g->lo[2] && x[2] <= g->hi[2];
  double rel[3] = {x[0] - g->p[0], x[1] - g->p[1], x[2] - g->p[2]};
  double s = rel[0] * g->a[0] + rel[1] * g->a[1] + rel[2] * g->a[2];
  if (s < g->s0 || s > g->s1) return 0;
  double q2 = 0;
  for (int k = 0; k < 3; k++) {
    double c = rel[k] - s * g->a[k];
    q2 += c * c;
  }
  return q2 <= g->R * g->R && q2 >= g->Rin * g->Rin;
}

void gs_dem_region_point(const gs_dem_region *g, const double u[3], double x[3]) {
  if (g->kind == GS_DEM_REGION_BOX) {
    for (int k = 0; k < 3; k++) x[k] = g->lo[k] + u[k] * (g->hi[k] - g->lo[k]);
    return;
  }
  /* two unit vectors normal to the axis */
  const double *a = g->a;
  double t[3] = {1, 0, 0};
  if (fabs(a[0]) > 0.9) t[0] = 0, t[1] = 1;
  double e1[3] = {a[1] * t[2] - a[2] * t[1], a[2] * t[0] - a[0] * t[2], a[0] * t[1] - a[1] * t[0]};
  double l = sqrt(e1[0] * e1[0] + e1[1] * e1[1] + e1[2] * e1[2]);
  for (int k = 0; k < 3; k++) e1[k] /= l;
  double e2[3] = {a[1] * e1[2] - a[2] * e1[1], a[2] * e1[0] - a[0] * e1[2], a[0] * e1[1] - a[1] * e1[0]};
  double rho = sqrt(g->Rin * g->Rin + u[0] * (g->R * g->R - g->Rin * g->Rin)), phi = 2 * M_PI * u[1], s = g->s0 + u[2] * (g->s1 - g->s0);
  for (int k = 0; k < 3; k++)
    x[k] = g->p[k] + s * a[k] + rho * (cos(phi) * e1[k] + sin(phi) * e2[k]);
}

double gs_dem_region_volume(const gs_dem_region *g) {
  if (g->kind == GS_DEM_REGION_BOX)
    return (g->hi[0] - g->lo[0]) * (g->hi[1] - g->lo[1]) * (g->hi[2] - g->lo[2]);
  return M_PI * (g->R * g->R - g->Rin * g->Rin) * (g->s1 - g->s0);
}
