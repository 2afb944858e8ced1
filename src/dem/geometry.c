/* Geometry helpers: closest point on a triangle (with the feature it lies on)
 * and the rigid-motion frames of walls. */
#include <math.h>

#include "dem/dem_internal.h"

static double dot3(const double a[3], const double b[3]) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

/* Voronoi-region test (Ericson, Real-Time Collision Detection, 5.1.5): the
 * feature is reported so that contacts with shared edges and vertices can be
 * de-duplicated by the caller. */
int gs_dem_closest_on_triangle(const double p[3], const double a[3], const double b[3],
                               const double c[3], double q[3]) {
  double ab[3], ac[3], ap[3];
  for (int k = 0; k < 3; k++) {
    ab[k] = b[k] - a[k];
    ac[k] = c[k] - a[k];
    ap[k] = p[k] - a[k];
  }
  double d1 = dot3(ab, ap), d2 = dot3(ac, ap);
  if (d1 <= 0 && d2 <= 0) {
    for (int k = 0; k < 3; k++) q[k] = a[k];
    return 4;
  }
  double bp[3];
  for (int k = 0; k < 3; k++) bp[k] = p[k] - b[k];
  double d3 = dot3(ab, bp), d4 = dot3(ac, bp);
  if (d3 >= 0 && d4 <= d3) {
    for (int k = 0; k < 3; k++) q[k] = b[k];
    return 5;
  }
  double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) {
    double v = d1 / (d1 - d3);
    for (int k = 0; k < 3; k++) q[k] = a[k] + v * ab[k];
    return 1;
  }
  double cp[3];
  for (int k = 0; k < 3; k++) cp[k] = p[k] - c[k];
  double d5 = dot3(ab, cp), d6 = dot3(ac, cp);
  if (d6 >= 0 && d5 <= d6) {
    for (int k = 0; k < 3; k++) q[k] = c[k];
    return 6;
  }
  double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) {
    double w = d2 / (d2 - d6);
    for (int k = 0; k < 3; k++) q[k] = a[k] + w * ac[k];
    return 3;
  }
  double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    for (int k = 0; k < 3; k++) q[k] = b[k] + w * (c[k] - b[k]);
    return 2;
  }
  double den = 1.0 / (va + vb + vc);
  double v = vb * den, w = vc * den;
  for (int k = 0; k < 3; k++) q[k] = a[k] + ab[k] * v + ac[k] * w;
  return 0;
}

/* Rodrigues rotation of v by angle th about unit axis k. */
static void rotate(const double k[3], double th, const double v[3], double out[3]) {
  double c = cos(th), s = sin(th), kd = dot3(k, v);
  double kx[3] = {k[1] * v[2] - k[2] * v[1], k[2] * v[0] - k[0] * v[2], k[0] * v[1] - k[1] * v[0]};
  for (int i = 0; i < 3; i++) out[i] = v[i] * c + kx[i] * s + k[i] * kd * (1 - c);
}

/* A wall's body frame coincides with the world at t = 0; at time t it has
 * turned by omega*(t - spin_start) (nothing before spin_start) about the axis
 * through origin + vel*t and moved by vel*t.
 * The rotation matrix is computed once per step (gs_dem_wall_frame), since
 * every particle near the wall is transformed with it. */
void gs_dem_wall_frame(gs_dem_wall *w, double t) {
  w->tframe = t;
  w->spin = t >= w->spin_start ? w->omega : 0;
  if (!w->moving) return;
  const double e[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  for (int c = 0; c < 3; c++) {
    double col[3];
    rotate(w->axis, w->omega * fmax(0, t - w->spin_start), e[c], col);
    for (int r = 0; r < 3; r++) w->Rm[3 * r + c] = col[r];
  }
  for (int i = 0; i < 3; i++) w->shift[i] = w->origin[i] + w->vel[i] * t;
}

void gs_dem_wall_to_body(const gs_dem_wall *w, const double xw[3], double xb[3]) {
  if (!w->moving) {
    for (int i = 0; i < 3; i++) xb[i] = xw[i];
    return;
  }
  double rel[3];
  for (int i = 0; i < 3; i++) rel[i] = xw[i] - w->shift[i];
  const double *R = w->Rm;
  for (int i = 0; i < 3; i++)
    xb[i] = R[i] * rel[0] + R[3 + i] * rel[1] + R[6 + i] * rel[2] + w->origin[i];
}

void gs_dem_wall_point_to_world(const gs_dem_wall *w, const double xb[3], double xw[3]) {
  if (!w->moving) {
    for (int i = 0; i < 3; i++) xw[i] = xb[i];
    return;
  }
  double rel[3];
  for (int i = 0; i < 3; i++) rel[i] = xb[i] - w->origin[i];
  const double *R = w->Rm;
  for (int i = 0; i < 3; i++)
    xw[i] = R[3 * i] * rel[0] + R[3 * i + 1] * rel[1] + R[3 * i + 2] * rel[2] + w->shift[i];
}

void gs_dem_wall_dir_to_world(const gs_dem_wall *w, const double db[3], double dw[3]) {
  if (!w->moving) {
    for (int i = 0; i < 3; i++) dw[i] = db[i];
    return;
  }
  const double *R = w->Rm;
  for (int i = 0; i < 3; i++) dw[i] = R[3 * i] * db[0] + R[3 * i + 1] * db[1] + R[3 * i + 2] * db[2];
}

void gs_dem_wall_velocity(const gs_dem_wall *w, const double xw[3], double v[3]) {
  if (!w->moving) {
    v[0] = v[1] = v[2] = 0;
    return;
  }
  double rel[3];
  for (int i = 0; i < 3; i++) rel[i] = xw[i] - w->shift[i];
  const double *k = w->axis;
  double om = w->spin;
  v[0] = w->vel[0] + om * (k[1] * rel[2] - k[2] * rel[1]);
  v[1] = w->vel[1] + om * (k[2] * rel[0] - k[0] * rel[2]);
  v[2] = w->vel[2] + om * (k[0] * rel[1] - k[1] * rel[0]);
}
