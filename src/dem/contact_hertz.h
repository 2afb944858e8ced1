/* The Hertz–Mindlin contact law with tangential history, used by both the
 * sphere–sphere and the sphere–wall loops so the two can never drift apart.
 *
 * With overlap delta, effective radius R* and mass m*, a = sqrt(R* delta):
 *   normal:     kn = 4/3 E* a,  Sn = 2 E* a,  gamma_n = c sqrt(Sn m*)
 *               Fn = kn delta - gamma_n vn          (vn < 0 when approaching)
 *   tangential: kt = St = 8 G* a,  gamma_t = c sqrt(St m*)
 *               shear += vt dt, projected on the tangent plane,
 *               Ft = -kt shear - gamma_t vt, and if |kt shear| > mu_s |Fn|
 *               Ft = -mu_s |Fn| shear/|shear| (sliding; shear shortened to match,
 *               no damping while sliding).
 * This is LIGGGHTS' `hertz tangential history` (normal force not clamped at
 * zero, as its default limitForce off); c follows from e (src/demdata/hertz.c,
 * cached per material pair in material.c).
 * Rolling resistance (CDT) is applied by the callers because it needs the
 * angular velocities: torque -mu_r (kn delta) R* w_rel/|w_rel| without its
 * component along n. */
#ifndef GRANSIM_DEM_CONTACT_HERTZ_H
#define GRANSIM_DEM_CONTACT_HERTZ_H

#include <math.h>

#include "dem/dem_internal.h"

typedef struct {
  double fn;    /* total normal force (along n, on i) */
  double fe;    /* elastic part kn*delta (drives rolling friction) */
  double ft[3]; /* tangential force on i */
} gs_dem_contact_force;

static inline void gs_dem_hertz(const gs_dem_pair *restrict c, double delta, double reff,
                                double meff, const double n[3], double vn, const double vt[3],
                                double *restrict shear, double dt, gs_dem_contact_force *out) {
  const double a = sqrt(reff * delta);
  const double kn = (4.0 / 3.0) * c->Estar * a;
  const double sn = 2.0 * c->Estar * a;
  const double kt = 8.0 * c->Gstar * a;
  const double gn = c->damp * sqrt(sn * meff);
  const double gt = c->damp * sqrt(kt * meff);
  out->fe = kn * delta;
  out->fn = out->fe - gn * vn;

  double s0 = shear[0] + vt[0] * dt, s1 = shear[1] + vt[1] * dt, s2 = shear[2] + vt[2] * dt;
  const double sdn = s0 * n[0] + s1 * n[1] + s2 * n[2];
  s0 -= sdn * n[0];
  s1 -= sdn * n[1];
  s2 -= sdn * n[2];
  double f0 = -kt * s0, f1 = -kt * s1, f2 = -kt * s2;
  const double fs2 = f0 * f0 + f1 * f1 + f2 * f2;
  const double flim = c->mu_s * fabs(out->fn);
  if (fs2 > flim * flim) {
    if (fs2 > 0) {
      const double ratio = flim / sqrt(fs2);
      f0 *= ratio;
      f1 *= ratio;
      f2 *= ratio;
      s0 = -f0 / kt;
      s1 = -f1 / kt;
      s2 = -f2 / kt;
    } else {
      f0 = f1 = f2 = 0;
    }
  } else {
    f0 -= gt * vt[0];
    f1 -= gt * vt[1];
    f2 -= gt * vt[2];
  }
  shear[0] = s0;
  shear[1] = s1;
  shear[2] = s2;
  out->ft[0] = f0;
  out->ft[1] = f1;
  out->ft[2] = f2;
}

/* CDT rolling torque on i for relative angular velocity w (i minus j, or i
 * alone against a wall): -mu_r * fe * lever * w/|w|, minus its part along n. */
static inline void gs_dem_rolling(double mu_r, double fe, double lever, const double n[3],
                                  const double w[3], double tq[3]) {
  const double wm2 = w[0] * w[0] + w[1] * w[1] + w[2] * w[2];
  if (wm2 <= 0 || mu_r <= 0) {
    tq[0] = tq[1] = tq[2] = 0;
    return;
  }
  const double s = -mu_r * fe * lever / sqrt(wm2);
  double t0 = s * w[0], t1 = s * w[1], t2 = s * w[2];
  const double tn = t0 * n[0] + t1 * n[1] + t2 * n[2];
  tq[0] = t0 - tn * n[0];
  tq[1] = t1 - tn * n[1];
  tq[2] = t2 - tn * n[2];
}

#endif
