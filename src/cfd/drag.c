/* Drag closures (docs/models.md, "CFD-DEM"): the coefficient beta of one
 * particle, drag = beta (u - v), with u the interstitial gas velocity. */
#include <math.h>

#include "gransim/cfd.h"

/* Di Felice (1994): the single-sphere drag with the Dallavalle coefficient
 * (0.63 + 4.8/sqrt(Re))^2, times eps^(2 - chi) for the neighbours; Re uses
 * the superficial slip eps |u - v|. */
static double di_felice(const gs_cfd_drag_in *in) {
  const double re = in->eps * in->rho * in->d * in->slip / in->mu;
  if (!(re > 1e-12)) /* the Stokes limit, Cd |u - v| -> 4.8^2 mu / (eps rho d), chi -> 3.7 */
    return 0.125 * M_PI * 23.04 * in->mu * in->d * pow(in->eps, 1 - 3.7);
  const double cd = (0.63 + 4.8 / sqrt(re)) * (0.63 + 4.8 / sqrt(re));
  const double lr = 1.5 - log10(re);
  const double chi = 3.7 - 0.65 * exp(-0.5 * lr * lr);
  return 0.125 * cd * in->rho * M_PI * in->d * in->d * pow(in->eps, 2 - chi) * in->slip;
}

/* Gidaspow (1994): Ergun (1952) in dense beds (eps < 0.8), Wen & Yu (1966)
 * with the Schiller-Naumann coefficient above.  Both give the momentum
 * exchange per unit bed volume, beta_v; one particle of volume Vp takes the
 * share Vp / (1 - eps) of it, which makes the steady packed-bed pressure
 * gradient exactly Ergun's. */
static double gidaspow(const gs_cfd_drag_in *in) {
  const double e = in->eps, d = in->d, vp = M_PI / 6 * d * d * d;
  if (e < 0.8) {
    const double bv_per_solid = 150 * (1 - e) * in->mu / (e * d * d) + 1.75 * in->rho * in->slip / d;
    return bv_per_solid * vp; /* beta_v / (1 - eps) * Vp */
  }
  const double re = e * in->rho * d * in->slip / in->mu;
  const double cd = re < 1000 ? (re > 1e-12 ? 24 / re * (1 + 0.15 * pow(re, 0.687)) : 0) : 0.44;
  if (re <= 1e-12) /* Stokes limit: Cd |u - v| -> 24 mu / (eps rho d) */
    return 0.75 * 24 * in->mu / (e * d) * pow(e, -2.65) * e / d * vp;
  return 0.75 * cd * e * in->rho * in->slip / d * pow(e, -2.65) * vp;
}

static const gs_cfd_drag_type di_felice_type = {
    .name = "di_felice",
    .summary = "Di Felice (1994): Dallavalle drag of one sphere times eps^(2-chi)",
    .beta = di_felice,
};
static const gs_cfd_drag_type gidaspow_type = {
    .name = "gidaspow",
    .summary = "Gidaspow (1994): Ergun (1952) below eps = 0.8, Wen & Yu (1966) above",
    .beta = gidaspow,
};

const gs_cfd_drag_type *const gs_cfd_drags[] = {&di_felice_type, &gidaspow_type, NULL};
