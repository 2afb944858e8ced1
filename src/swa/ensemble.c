/* One run's particle ensemble: storage, cached properties, LPDA catch-up,
 * adding and removing particles, contraction and doubling (ensemble control
 * of Lee et al. 2015 as used by McGuire et al. (2018): N(0) = 0.75 N_max, doubling below
 * 3/8 N_max). */
#include <gsl/gsl_randist.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "swa/sim.h"

gs_swa_sim *gs_swa_sim_alloc(const gs_swa_model *m, uint64_t seed, gs_error *err) {
  gs_swa_sim *s = gs_calloc(1, sizeof *s, err);
  if (!s) return NULL;
  s->m = m;
  s->rng = gsl_rng_alloc(gsl_rng_mt19937);
  s->comp = gs_calloc(m->ncomp, sizeof *s->comp, err);
  s->rates = gs_calloc(m->nproc * m->ncomp + 1, sizeof(double), err);
  if (!s->rng || !s->comp || !s->rates) goto fail;
  gsl_rng_set(s->rng, (unsigned long)seed);
  size_t nc = (size_t)m->ncoord;
  for (size_t z = 0; z < m->ncomp; z++) {
    swa_comp *c = &s->comp[z];
    c->x = gs_calloc(m->nmax * nc, sizeof(double), err);
    c->w = gs_calloc(m->nmax, sizeof(double), err);
    if (m->has_continuous) c->stamp = gs_calloc(m->nmax, sizeof(double), err);
    if (!c->x || !c->w || (m->has_continuous && !c->stamp)) goto fail;
    if (gs_fenwick_init(&c->tree, m->nmax, m->nprop, err)) goto fail;
    c->vsamp = 1;
    c->gain = 1;
  }
  s->next_checkpoint = m->lpda_interval > 0 ? m->lpda_interval : HUGE_VAL;
  s->max_jumps = (uint64_t)GS_SWA_MAX_JUMPS_DEFAULT;
  return s;
fail:
  if (err && !err->code) gs_error_set(err, GS_ENOMEM, "out of memory for the SWA ensemble");
  gs_swa_sim_free(s);
  return NULL;
}

void gs_swa_sim_free(gs_swa_sim *s) {
  if (!s) return;
  for (size_t z = 0; s->comp && z < s->m->ncomp; z++) {
    free(s->comp[z].x);
    free(s->comp[z].w);
    free(s->comp[z].stamp);
    gs_fenwick_free(&s->comp[z].tree);
  }
  free(s->comp);
  free(s->rates);
  if (s->rng) gsl_rng_free(s->rng);
  free(s);
}

const gs_swa_model *gs_swa_sim_model(const gs_swa_sim *s) { return s->m; }
void *gs_swa_rng(gs_swa_sim *s) { return s->rng; }
double gs_swa_time(const gs_swa_sim *s) { return s->t; }
size_t gs_swa_count(const gs_swa_sim *s, size_t z) { return s->comp[z].n; }
double gs_swa_vsamp(const gs_swa_sim *s, size_t z) { return s->comp[z].vsamp; }
double gs_swa_gain(const gs_swa_sim *s, size_t z) { return s->comp[z].gain; }
void gs_swa_set_vsamp(gs_swa_sim *s, size_t z, double v) { s->comp[z].vsamp = v; }
double gs_swa_w(const gs_swa_sim *s, size_t z, size_t i) { return s->comp[z].w[i]; }
gs_swa_stats gs_swa_sim_stats(const gs_swa_sim *s) { return s->stats; }
void gs_swa_fictitious(gs_swa_sim *s) { s->stats.fictitious++; }
double gs_swa_uniform01(gs_swa_sim *s) { return gsl_rng_uniform(s->rng); }

double gs_swa_sum(const gs_swa_sim *s, size_t z, int prop) {
  double v = gs_fenwick_total(&s->comp[z].tree, prop);
  return v > 0 ? v : 0; /* round-off in the running totals must not give negative rates */
}

double gs_swa_prop(const gs_swa_sim *s, size_t z, size_t i, int prop) {
  return gs_fenwick_get(&s->comp[z].tree, i, prop);
}

/* Recompute every cached property of particle i from its vector and weight. */
static void refresh(gs_swa_sim *s, swa_comp *c, size_t i) {
  const gs_swa_model *m = s->m;
  const double *x = c->x + i * (size_t)m->ncoord;
  double p[GS_SWA_MAX_PROP];
  p[0] = c->w[i];
  for (int k = 1; k < m->nprop; k++) p[k] = m->prop_fn[k](m->prop_ctx[k], x, c->w[i]);
  gs_fenwick_set(&c->tree, i, p);
}

void gs_swa_update(gs_swa_sim *s, size_t z, size_t i, double w) {
  s->comp[z].w[i] = w;
  refresh(s, &s->comp[z], i);
}

/* LPDA: apply the deferred continuous processes to particle i up to now. */
static void catch_up(gs_swa_sim *s, size_t z, size_t i) {
  swa_comp *c = &s->comp[z];
  double dt = s->t - c->stamp[i];
  if (!(dt > 0)) return;
  const gs_swa_model *m = s->m;
  double *x = c->x + i * (size_t)m->ncoord;
  for (size_t p = 0; p < m->nproc; p++)
    if (m->proc[p].type->advance) m->proc[p].type->advance(m->proc[p].self, z, x, dt);
  c->stamp[i] = s->t;
  refresh(s, c, i);
}

double *gs_swa_x(gs_swa_sim *s, size_t z, size_t i) {
  if (s->m->has_continuous) catch_up(s, z, i);
  return s->comp[z].x + i * (size_t)s->m->ncoord;
}

void gs_swa_sim_sync(gs_swa_sim *s) {
  if (!s->m->has_continuous) return;
  for (size_t z = 0; z < s->m->ncomp; z++)
    for (size_t i = 0; i < s->comp[z].n; i++) catch_up(s, z, i);
}

void gs_swa_remove(gs_swa_sim *s, size_t z, size_t i) {
  swa_comp *c = &s->comp[z];
  size_t last = c->n - 1, nc = (size_t)s->m->ncoord;
  double zero[GS_SWA_MAX_PROP] = {0};
  if (i != last) {
    double p[GS_SWA_MAX_PROP];
    memcpy(c->x + i * nc, c->x + last * nc, nc * sizeof(double));
    c->w[i] = c->w[last];
    if (c->stamp) c->stamp[i] = c->stamp[last];
    for (int k = 0; k < s->m->nprop; k++) p[k] = gs_fenwick_get(&c->tree, last, k);
    gs_fenwick_set(&c->tree, i, p);
  }
  gs_fenwick_set(&c->tree, last, zero);
  c->n--;
}

int gs_swa_sim_place(gs_swa_sim *s, size_t z, const double *x, double w, gs_error *err) {
  swa_comp *c = &s->comp[z];
  if (c->n >= s->m->nmax)
    return gs_error_set(err, GS_ENUMERIC, "compartment %zu is full (%zu particles)", z + 1, c->n);
  if (!(w > 0) || !isfinite(w))
    return gs_error_set(err, GS_ENUMERIC, "particle weight %g in compartment %zu is not > 0", w, z + 1);
  size_t nc = (size_t)s->m->ncoord, i = c->n++;
  memcpy(c->x + i * nc, x, nc * sizeof(double));
  c->w[i] = w;
  if (c->stamp) c->stamp[i] = s->t;
  refresh(s, c, i);
  return GS_OK;
}

/* Merge contraction: two particles become one, chosen by mass, the way the
 * seed's breakage picks a fragment (eqs. 54-56).  For the pair (k, j), with
 * a = w m(x), keeping x_k with probability a_k / (a_k + a_j) and giving it
 * the weight (a_k + a_j) / m_k (else likewise x_j) leaves the mass exact and
 * the expectation of every estimate sum w phi(x) unchanged:
 * a_k/(a_k+a_j) (a_k+a_j)/m_k phi_k + a_j/(a_k+a_j) (a_k+a_j)/m_j phi_j
 * = w_k phi_k + w_j phi_j, for any choice of the pair.  The variance is the
 * smaller the closer the pair, so j is the closest in mass of a few uniform
 * candidates.  Massless pairs are merged by weight (the number kept).  The
 * mass is a function of the stored vector: the continuous processes keep it,
 * so no LPDA catch-up is needed here. */
#define MERGE_CANDIDATES 8
static void merge_pair(gs_swa_sim *s, size_t z) {
  swa_comp *c = &s->comp[z];
  const gs_swa_model *m = s->m;
  size_t n = c->n, nc = (size_t)m->ncoord;
  size_t k = gsl_rng_uniform_int(s->rng, n), j = k;
  double mk = gs_swa_mass(m, c->x + k * nc), best = HUGE_VAL;
  for (int t = 0; t < MERGE_CANDIDATES; t++) {
    size_t cand = gsl_rng_uniform_int(s->rng, n - 1);
    if (cand >= k) cand++;
    double mc = gs_swa_mass(m, c->x + cand * nc);
    double d = mc > 0 && mk > 0 ? fabs(log(mc / mk)) : (mc > 0) != (mk > 0) ? HUGE_VAL : 0;
    if (j == k || d < best) {
      best = d;
      j = cand;
    }
  }
  double mj = gs_swa_mass(m, c->x + j * nc);
  double ak = c->w[k] * mk, aj = c->w[j] * mj, u = gsl_rng_uniform(s->rng);
  size_t keep;
  double w;
  if (ak + aj > 0) {
    keep = u * (ak + aj) < ak ? k : j;
    w = (ak + aj) / (keep == k ? mk : mj);
  } else {
    keep = u * (c->w[k] + c->w[j]) < c->w[k] ? k : j;
    w = c->w[k] + c->w[j];
  }
  gs_swa_update(s, z, keep, w);
  gs_swa_remove(s, z, keep == k ? j : k);
}

int gs_swa_add(gs_swa_sim *s, size_t z, const double *x, double w, gs_error *err) {
  swa_comp *c = &s->comp[z];
  size_t nmax = s->m->nmax;
  if (c->n < nmax) return gs_swa_sim_place(s, z, x, w, err);
  s->stats.contractions++;
  if (s->m->contraction == GS_SWA_MERGE) {
    /* V unchanged: w / V is still what the caller meant.  The n particles
     * now carry what n + 1 carried: later inflow comes in heavier by the same
     * factor (gs_swa_gain), as the drop's smaller V makes it, so the
     * computational inflow adapts to the capacity as in Lee et al. 2015. */
    merge_pair(s, z);
    c->gain *= (double)nmax / (double)(nmax - 1);
    return gs_swa_sim_place(s, z, x, w, err);
  }
  /* Drop: the new particle, weighted for the V before the call, joins the
   * nmax candidates; one of the nmax + 1 is dropped uniformly and V shrinks by
   * nmax / (nmax + 1), so every particle, the new one included, keeps its
   * estimate in expectation (dropping first and adding with the old weight
   * over-weighted the new particle by nmax / (nmax - 1)). */
  if (!(w > 0) || !isfinite(w))
    return gs_error_set(err, GS_ENUMERIC, "particle weight %g in compartment %zu is not > 0", w, z + 1);
  c->vsamp *= (double)nmax / (double)(nmax + 1);
  size_t d = gsl_rng_uniform_int(s->rng, nmax + 1);
  if (d == nmax) return GS_OK; /* the new particle is the one dropped */
  gs_swa_remove(s, z, d);
  return gs_swa_sim_place(s, z, x, w, err);
}

size_t gs_swa_select(gs_swa_sim *s, size_t z, int prop) {
  swa_comp *c = &s->comp[z];
  if (c->n == 0) return GS_NOWHERE;
  if (prop < 0) return gsl_rng_uniform_int(s->rng, c->n);
  double total = gs_fenwick_total(&c->tree, prop);
  if (!(total > 0)) return GS_NOWHERE;
  size_t i = gs_fenwick_find(&c->tree, prop, gsl_rng_uniform(s->rng) * total, c->n);
  /* round-off in the tree can land on a particle whose property is zero */
  return gs_fenwick_get(&c->tree, i, prop) > 0 ? i : GS_NOWHERE;
}

/* Doubling: below nmin every particle is copied and V doubles, so the
 * estimates are unchanged and the statistical noise stays bounded. */
void gs_swa_maintain(gs_swa_sim *s, size_t z) {
  swa_comp *c = &s->comp[z];
  size_t nmin = (size_t)(s->m->nmin_fraction * (double)s->m->nmax), nc = (size_t)s->m->ncoord;
  while (c->n > 0 && c->n < nmin && 2 * c->n <= s->m->nmax) {
    size_t n = c->n;
    memcpy(c->x + n * nc, c->x, n * nc * sizeof(double));
    memcpy(c->w + n, c->w, n * sizeof(double));
    if (c->stamp) memcpy(c->stamp + n, c->stamp, n * sizeof(double));
    memcpy(c->tree.val + n * (size_t)c->tree.ncol, c->tree.val, n * (size_t)c->tree.ncol * sizeof(double));
    c->n = 2 * n;
    gs_fenwick_rebuild(&c->tree);
    c->vsamp *= 2;
    s->stats.doublings++;
  }
}
