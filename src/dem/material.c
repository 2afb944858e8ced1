/* Materials: effective contact constants of a pair (with the damping
 * coefficient that realises their coefficient of restitution, from the
 * contact law in src/demdata/hertz.c), and the Rayleigh time. */
#include <math.h>
#include <stdlib.h>

#include "dem/dem_internal.h"

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
