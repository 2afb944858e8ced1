/* Materials: effective contact constants of a pair, the damping coefficient
 * that realises a coefficient of restitution, and the Rayleigh time. */
#include <math.h>
#include <stdlib.h>

#include "dem/dem_internal.h"

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

/* The bisection is cached per restitution value for one table update. */
typedef struct {
  double e[64], c[64];
  int n;
} damp_cache;

static double damping_cached(damp_cache *k, double e, int mode) {
  for (int i = 0; i < k->n; i++)
    if (k->e[i] == e) return k->c[i];
  double c = gs_dem_damping_coefficient(e, mode);
  if (k->n < 64) {
    k->e[k->n] = e;
    k->c[k->n++] = c;
  }
  return c;
}

static void pair_constants(const gs_dem_material *a, const gs_dem_material *b, int damping,
                           damp_cache *k, gs_dem_pair *out) {
  out->Estar = 1.0 / ((1 - a->nu * a->nu) / a->E + (1 - b->nu * b->nu) / b->E);
  out->Gstar = 1.0 / (2 * (2 - a->nu) * (1 + a->nu) / a->E + 2 * (2 - b->nu) * (1 + b->nu) / b->E);
  out->damp = damping_cached(k, 0.5 * (a->e + b->e), damping);
  out->mu_s = 0.5 * (a->mu_s + b->mu_s);
  out->mu_r = 0.5 * (a->mu_r + b->mu_r);
}

void gs_dem_pair_constants(const gs_dem_material *a, const gs_dem_material *b, int damping,
                           gs_dem_pair *out) {
  out->Estar = 1.0 / ((1 - a->nu * a->nu) / a->E + (1 - b->nu * b->nu) / b->E);
  out->Gstar = 1.0 / (2 * (2 - a->nu) * (1 + a->nu) / a->E + 2 * (2 - b->nu) * (1 + b->nu) / b->E);
  double e = 0.5 * (a->e + b->e);
  out->damp = gs_dem_damping_coefficient(e, damping);
  out->mu_s = 0.5 * (a->mu_s + b->mu_s);
  out->mu_r = 0.5 * (a->mu_r + b->mu_r);
}

/* Recompute the type-pair and wall-type tables (after a type or wall is added).
 * The damping bisection costs tens of milliseconds, so it runs once per
 * distinct restitution value. */
int gs_dem_update_pairs(gs_dem *d, gs_error *err) {
  size_t nt = d->ntypes;
  damp_cache k;
  k.n = 0;
  free(d->pp);
  d->pp = gs_malloc((nt ? nt * nt : 1) * sizeof *d->pp, err);
  if (!d->pp) return GS_ENOMEM;
  for (size_t i = 0; i < nt; i++)
    for (size_t j = 0; j < nt; j++)
      pair_constants(&d->types[i].mat, &d->types[j].mat, d->prm.damping, &k, &d->pp[i * nt + j]);
  for (size_t w = 0; w < d->nwalls; w++) {
    gs_dem_wall *wl = &d->walls[w];
    free(wl->pt);
    wl->pt = gs_malloc((nt ? nt : 1) * sizeof *wl->pt, err);
    if (!wl->pt) return GS_ENOMEM;
    for (size_t i = 0; i < nt; i++)
      pair_constants(&d->types[i].mat, &wl->mat, d->prm.damping, &k, &wl->pt[i]);
  }
  return GS_OK;
}

/* Rayleigh time pi r sqrt(rho/G) / (0.1631 nu + 0.8766) for the smallest
 * particle of each type seen so far (the time a shear wave needs to cross the
 * sphere); a DEM step should stay a small fraction of it. */
double gs_dem_rayleigh_time(const gs_dem *d) {
  double best = HUGE_VAL;
  for (size_t k = 0; k < d->p.n; k++) {
    const gs_dem_material *m = &d->types[d->p.type[k]].mat;
    double G = m->E / (2 * (1 + m->nu));
    double tr = M_PI * d->p.r[k] * sqrt(m->density / G) / (0.1631 * m->nu + 0.8766);
    if (tr < best) best = tr;
  }
  for (size_t k = 0; k < d->pend.n; k++) {
    const gs_dem_material *m = &d->types[d->pend.type[k]].mat;
    double G = m->E / (2 * (1 + m->nu));
    double tr = M_PI * d->pend.r[k] * sqrt(m->density / G) / (0.1631 * m->nu + 0.8766);
    if (tr < best) best = tr;
  }
  return best;
}
