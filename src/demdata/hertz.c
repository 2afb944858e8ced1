/* The damped Hertz contact law shared by the embedded DEM (src/dem) and the
 * reduction of LIGGGHTS dumps (dem_data.c): the scaled head-on impact, the
 * restitution a damping coefficient realises, and its inverse. */
#include <math.h>

#include "gransim/dem_data.h"

/* Head-on damped Hertz impact in units where the undamped law is
 *   xi'' = -xi^{3/2} - c sqrt(3/2) xi^{1/4} xi',  xi(0) = 0, xi'(0) = 1
 * (delta scaled by (v0^2 m* / (4/3 E* sqrt R*))^{2/5}, time by that over v0):
 * with gamma_n = c sqrt(2 E* sqrt(R* delta) m*) every physical impact maps to
 * this one equation, so the realised restitution and the scaled duration
 * depend on c alone.  RK4 with step h; the end of contact (xi back to 0) is
 * found by linear interpolation.  A contact that never separates (fully
 * damped) gives restitution 0 and duration infinity. */
void gs_dem_scaled_impact(double c, double h, double *duration, double *restitution) {
  const double k = c * sqrt(1.5);
  double x = 0, v = 1;
#define ACC(X, V) (-(X) * sqrt(fmax(X, 0.0)) - k * sqrt(sqrt(fmax(X, 0.0))) * (V))
  for (long i = 0; i < (long)(400.0 / h); i++) { /* 400: ~100 contact durations */
    double k1x = v, k1v = ACC(x, v);
    double k2x = v + 0.5 * h * k1v, k2v = ACC(x + 0.5 * h * k1x, v + 0.5 * h * k1v);
    double k3x = v + 0.5 * h * k2v, k3v = ACC(x + 0.5 * h * k2x, v + 0.5 * h * k2v);
    double k4x = v + h * k3v, k4v = ACC(x + h * k3x, v + h * k3v);
    double xn = x + h / 6 * (k1x + 2 * k2x + 2 * k3x + k4x);
    double vn = v + h / 6 * (k1v + 2 * k2v + 2 * k3v + k4v);
    if (i > 0 && xn <= 0) {
      double f = x / (x - xn); /* fraction of the step where xi crosses 0 */
      if (duration) *duration = (i + f) * h;
      if (restitution) *restitution = -(v + f * (vn - v));
      return;
    }
    x = xn;
    v = vn;
  }
#undef ACC
  if (duration) *duration = HUGE_VAL;
  if (restitution) *restitution = 0;
}

double gs_dem_restitution_of(double c) {
  double e;
  gs_dem_scaled_impact(c, 2e-4, NULL, &e);
  return e;
}

double gs_dem_damping_coefficient(double e, int mode) {
  if (e >= 1) return 0;
  if (mode == GS_DEM_DAMPING_LIGGGHTS) {
    double le = log(e);
    return 2.0 * sqrt(5.0 / 6.0) * (-le / sqrt(le * le + M_PI * M_PI));
  }
  /* Bisection on c: restitution falls monotonically with c. */
  double lo = 0, hi = 1;
  while (gs_dem_restitution_of(hi) > e && hi < 1e3) hi *= 2;
  for (int it = 0; it < 50 && hi - lo > 1e-10 * hi; it++) {
    double mid = 0.5 * (lo + hi);
    if (gs_dem_restitution_of(mid) > e) lo = mid;
    else hi = mid;
  }
  return 0.5 * (lo + hi);
}

