/* The population balance run inside the DEM, as Sen et al. (2014) do in
 * EDEM: particles fall in classes of solid volume x liquid volume, the DEM
 * logs every collision onset, and every Delta t_PBM the collisions of the
 * interval are turned into aggregations.
 *
 * With the kernel beta = C psi and C_ab = N_ab / (F_a F_b Delta t) (the
 * paper's Eq. 12), one explicit step of the discrete PBM over Delta t
 * aggregates psi N_ab pairs of classes a and b: every logged collision
 * aggregates with the probability psi.  Here that step is carried out on the
 * particles themselves: each logged collision of two particles still present
 * is put to the success rule, and a success merges the two into one particle
 * (summed solid and liquid volume and mass, at their centre of mass with
 * their momentum).  The classes are then a description of the particles, so
 * their populations always add up to the particles present, and no
 * particles have to be removed and re-created as in the paper.  A particle
 * aggregates at most once per update (the explicit step depletes each class
 * from its population at the start of the step). */
#include <gsl/gsl_rng.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "dem/dem_stats.h"
#include "dem/dem_wet.h"

static int write_state(gs_dem_granulation *g, const gs_dem *d, uint64_t nwet, uint64_t ncol,
                       uint64_t nagg, gs_error *err);
static int write_kernel(const gs_dem_granulation *g, gs_error *err);

int gs_dem_granulation_class(const gs_dem_granulation *g, double vs, double vl) {
  double a = floor(vs / g->ds + 0.5), b = floor(vl / g->dl + 0.5);
  int i = a < 1 ? 1 : a > g->ns ? g->ns : (int)a;
  int j = b < 0 ? 0 : b > g->nl - 1 ? g->nl - 1 : (int)b;
  return (i - 1) * g->nl + j;
}

void gs_dem_merge(gs_dem *d, size_t i, size_t j) {
  gs_dem_particles *p = &d->p;
  const double mi = p->m[i], mj = p->m[j], m = mi + mj;
  const double wi = mi / m, wj = mj / m;
  p->x[i] = wi * p->x[i] + wj * p->x[j];
  p->y[i] = wi * p->y[i] + wj * p->y[j];
  p->z[i] = wi * p->z[i] + wj * p->z[j];
  p->vx[i] = (mi * p->vx[i] + mj * p->vx[j]) / m;
  p->vy[i] = (mi * p->vy[i] + mj * p->vy[j]) / m;
  p->vz[i] = (mi * p->vz[i] + mj * p->vz[j]) / m;
  const double Ii = 1.0 / p->invI[i], Ij = 1.0 / p->invI[j];
  p->vs[i] += p->vs[j];
  p->vl[i] += p->vl[j];
  p->r[i] = cbrt(3 * p->vs[i] / (4 * M_PI));
  const double I = 0.4 * m * p->r[i] * p->r[i];
  /* spins: their angular momenta add (the orbital part of the pair is not kept) */
  p->wx[i] = (Ii * p->wx[i] + Ij * p->wx[j]) / I;
  p->wy[i] = (Ii * p->wy[i] + Ij * p->wy[j]) / I;
  p->wz[i] = (Ii * p->wz[i] + Ij * p->wz[j]) / I;
  /* the forces of the last evaluation act on the merged body in the next half kick */
  p->fx[i] += p->fx[j], p->fy[i] += p->fy[j], p->fz[i] += p->fz[j];
  p->tx[i] += p->tx[j], p->ty[i] += p->ty[j], p->tz[i] += p->tz[j];
  p->m[i] = m;
  p->invm[i] = 1.0 / m;
  p->invI[i] = 1.0 / I;
  if (p->r[i] > d->rmax) d->rmax = p->r[i];
  p->vs[j] = p->vl[j] = 0;
  p->m[j] = 0;
  p->vx[j] = p->vy[j] = p->vz[j] = 0;
  p->dead[j] = 1;
  d->need_rebuild = 1;
}

int gs_dem_granulation_start(gs_dem_granulation *g, gs_dem *d, const char *dir, uint64_t seed,
                             gs_error *err) {
  const size_t nc = (size_t)g->ns * g->nl;
  g->ncoll = calloc(nc * nc, sizeof(double));
  g->nagg = calloc(nc * nc, sizeof(double));
  g->kn = calloc((size_t)g->ns * g->ns, sizeof(double));
  g->kexp = calloc((size_t)g->ns * g->ns, sizeof(double));
  g->rng = gsl_rng_alloc(gsl_rng_mt19937);
  if (!g->ncoll || !g->nagg || !g->kn || !g->kexp || !g->rng) return gs_error_set(err, GS_ENOMEM, "out of memory");
  snprintf(g->path_kernel, sizeof g->path_kernel, "%s/granulation_kernel.csv", dir);
  gsl_rng_set(g->rng, (unsigned long)(seed ^ 0x9e3779b9ULL));
  int rc = gs_dem_pair_log_enable(d, err);
  if (rc) return rc;
  g->t_last = d->t;
  if (!(g->f_sum = gs_dem_table_open(dir, "granulation.csv", g->path_sum, sizeof g->path_sum, err)) ||
      !(g->f_cls = gs_dem_table_open(dir, "granulation_classes.csv", g->path_cls, sizeof g->path_cls, err)) ||
      !(g->f_col = gs_dem_table_open(dir, "granulation_collisions.csv", g->path_col, sizeof g->path_col, err)))
    return err->code;
  fprintf(g->f_sum, "time,particles,mean_diameter,mean_liquid_content,collisions,wet_pairs,aggregations,"
                    "solid_volume,liquid_volume\n");
  fprintf(g->f_cls, "time,solid_class,liquid_class,solid_volume,liquid_volume,particles\n");
  fprintf(g->f_col, "time,solid_class_a,liquid_class_a,solid_class_b,liquid_class_b,particles_a,particles_b,"
                    "interval,collisions,aggregations,C_ab\n");
  return (rc = write_kernel(g, err)) ? rc : write_state(g, d, 0, 0, 0, err);
}

static int grow(void **ptr, size_t *cap, size_t need, size_t elem, gs_error *err) {
  if (need <= *cap) return GS_OK;
  void *q = realloc(*ptr, need * elem);
  if (!q) return gs_error_set(err, GS_ENOMEM, "out of memory");
  *ptr = q;
  *cap = need;
  return GS_OK;
}

/* The class populations and the summary row of the particles present: the
 * mean volume-equivalent diameter of solid + liquid (the paper's Eq. 15) and
 * the mean liquid content l / (s + l) (Eq. 16). */
static int write_state(gs_dem_granulation *g, const gs_dem *d, uint64_t nwet, uint64_t ncol,
                       uint64_t nagg, gs_error *err) {
  const gs_dem_particles *p = &d->p;
  const size_t nc = (size_t)g->ns * g->nl;
  double *pop = calloc(nc, sizeof(double));
  if (!pop) return gs_error_set(err, GS_ENOMEM, "out of memory");
  double np = 0, dsum = 0, lcsum = 0, vs = 0, vl = 0;
  for (size_t i = 0; i < p->n; i++) {
    if (p->dead[i]) continue;
    const double v = p->vs[i] + p->vl[i];
    pop[gs_dem_granulation_class(g, p->vs[i], p->vl[i])] += 1;
    np += 1;
    dsum += cbrt(6 * v / M_PI);
    lcsum += v > 0 ? p->vl[i] / v : 0;
    vs += p->vs[i];
    vl += p->vl[i];
  }
  const double t = d->t;
  fprintf(g->f_sum, "%.9g,%.0f,%.9g,%.9g,%llu,%llu,%llu,%.17g,%.17g\n", t, np, np > 0 ? dsum / np : NAN,
          np > 0 ? lcsum / np : NAN, (unsigned long long)ncol, (unsigned long long)nwet,
          (unsigned long long)nagg, vs, vl);
  for (size_t c = 0; c < nc; c++)
    fprintf(g->f_cls, "%.9g,%zu,%zu,%.9g,%.9g,%.0f\n", t, c / g->nl + 1, c % g->nl,
            (double)(c / g->nl + 1) * g->ds, (double)(c % g->nl) * g->dl, pop[c]);
  free(pop);
  fflush(g->f_sum);
  fflush(g->f_cls);
  fflush(g->f_col);
  if (ferror(g->f_sum) || ferror(g->f_cls) || ferror(g->f_col))
    return gs_error_set(err, GS_EIO, "%s: write failed", g->path_sum);
  return GS_OK;
}

/* The run's collision frequencies between solid classes as a `table`
 * kernel file (the writer of gransim dem-reduce), rewritten at every update:
 * C_ab = N_ab / sum(F_a F_b dt) and C_aa = 2 N_aa / sum(F_a^2 dt), the
 * convention of the PBM's pair loop (docs/models.md, "Collision
 * frequencies"). */
static int write_kernel(const gs_dem_granulation *g, gs_error *err) {
  const size_t n = (size_t)g->ns;
  double *C = malloc(n * n * sizeof(double)), *e = malloc((n + 1) * sizeof(double));
  if (!C || !e) {
    free(C);
    free(e);
    return gs_error_set(err, GS_ENOMEM, "out of memory");
  }
  for (size_t a = 0; a < n; a++)
    for (size_t b = 0; b < n; b++) {
      const double x = g->kexp[a * n + b];
      C[a * n + b] = x > 0 ? (a == b ? 2 : 1) * g->kn[a * n + b] / x : 0;
    }
  for (size_t k = 0; k <= n; k++) e[k] = (k + 0.5) * g->ds;
  char comment[400];
  snprintf(comment, sizeof comment,
           "# gransim dem granulation: collision frequency C_ab [1/s per pair of particles] between classes of "
           "solid volume, %ld update(s) to t = %.9g s;\n# C_ab = N_ab / sum(F_a F_b dt), C_aa = 2 N_aa / "
           "sum(F_a^2 dt); 0 for classes never populated\n", g->updates, g->t_last);
  int rc = gs_dem_kernel_table_write(g->path_kernel, comment, n, e, 1, C, err);
  free(C);
  free(e);
  return rc;
}

static gs_dem_partner partner(const gs_dem_particles *p, size_t i) {
  return (gs_dem_partner){p->m[i], p->r[i], p->vs[i], p->vl[i]};
}

int gs_dem_granulation_update(gs_dem_granulation *g, gs_dem *d, gs_error *err) {
  gs_dem_particles *p = &d->p;
  const size_t n = p->n, nc = (size_t)g->ns * g->nl, nid = (size_t)d->next_id;
  size_t cap_idx = g->idx_cap, cap_used = g->idx_cap;
  int rc = grow((void **)&g->idx, &cap_idx, nid + 1, sizeof(int), err);
  if (!rc) rc = grow((void **)&g->used, &cap_used, nid + 1, 1, err);
  g->idx_cap = cap_idx < cap_used ? cap_idx : cap_used;
  if (!rc) rc = grow((void **)&g->cls, &g->cls_cap, n + 1, sizeof(int), err);
  if (rc) return rc;
  for (size_t k = 0; k < nid; k++) g->idx[k] = -1, g->used[k] = 0;
  double *pop = calloc(nc, sizeof(double));
  if (!pop) return gs_error_set(err, GS_ENOMEM, "out of memory");
  for (size_t i = 0; i < n; i++) {
    if (p->dead[i]) continue;
    g->idx[p->id[i]] = (int)i;
    g->cls[i] = gs_dem_granulation_class(g, p->vs[i], p->vl[i]);
    pop[g->cls[i]] += 1;
  }
  memset(g->ncoll, 0, nc * nc * sizeof(double));
  memset(g->nagg, 0, nc * nc * sizeof(double));
  /* the interval's collisions, in the order logged */
  uint64_t ncol = 0, nwet = 0, nagg = 0;
  gs_dem_pair_log *L = d->plog;
  for (size_t k = 0; k < L->n; k++) {
    const gs_dem_pair_rec *q = &L->r[k];
    if (q->idb >= (long)nid) continue;
    const int ia = g->idx[q->ida], ib = g->idx[q->idb];
    if (ia < 0 || ib < 0) continue; /* left through an outlet since */
    int ca = g->cls[ia], cb = g->cls[ib];
    if (ca > cb) { int t = ca; ca = cb; cb = t; }
    g->ncoll[(size_t)ca * nc + cb] += 1;
    ncol++;
    const double u = gsl_rng_uniform(g->rng); /* drawn for every collision: one stream */
    if (g->used[q->ida] || g->used[q->idb]) continue;
    const gs_dem_partner a = partner(p, (size_t)ia), b = partner(p, (size_t)ib);
    nwet += gs_dem_liquid_content(&a) > 0 && gs_dem_liquid_content(&b) > 0;
    if (!g->rule.type->success(&g->rule, &a, &b, q->vn, u)) continue;
    /* the larger solid survives (the earlier particle on a tie) */
    const int keep_a = p->vs[ia] >= p->vs[ib];
    const size_t keep = keep_a ? (size_t)ia : (size_t)ib;
    const double r0 = fmax(p->r[ia], p->r[ib]);
    gs_dem_merge(d, keep, keep_a ? (size_t)ib : (size_t)ia);
    if (g->growth_k > 0 && (rc = gs_dem_growth_add(g, d, keep, r0, err))) {
      free(pop);
      return rc;
    }
    g->used[q->ida] = g->used[q->idb] = 1;
    g->nagg[(size_t)ca * nc + cb] += 1;
    nagg++;
  }
  L->n = 0;
  const double t = d->t, span = t - g->t_last;
  g->t_last = t;
  g->updates++;
  g->collisions += ncol;
  g->aggregations += nagg;
  /* collisions per class pair, with C_ab of the populations at the update's start */
  for (size_t a = 0; a < nc; a++)
    for (size_t b = a; b < nc; b++) {
      const double N = g->ncoll[a * nc + b];
      const size_t sa = a / g->nl, sb = b / g->nl;
      g->kn[sa * g->ns + sb] += N;
      if (sa != sb) g->kn[sb * g->ns + sa] += N;
      if (N == 0) continue;
      const double C = pop[a] > 0 && pop[b] > 0 && span > 0 ? (a == b ? 2 : 1) * N / (pop[a] * pop[b] * span) : 0;
      fprintf(g->f_col, "%.9g,%zu,%zu,%zu,%zu,%.0f,%.0f,%.9g,%.0f,%.0f,%.9g\n", t, a / g->nl + 1, a % g->nl,
              b / g->nl + 1, b % g->nl, pop[a], pop[b], span, N, g->nagg[a * nc + b], C);
    }
  /* the exposure of the solid classes over this interval */
  double *fs = calloc((size_t)g->ns, sizeof(double));
  if (!fs) {
    free(pop);
    return gs_error_set(err, GS_ENOMEM, "out of memory");
  }
  for (size_t a = 0; a < nc; a++) fs[a / g->nl] += pop[a];
  for (int a = 0; a < g->ns; a++)
    for (int b = 0; b < g->ns; b++) g->kexp[a * g->ns + b] += fs[a] * fs[b] * span;
  free(fs);
  free(pop);
  if ((rc = write_kernel(g, err))) return rc;
  /* drop the merged-away particles now, so that every view and output of
   * this time sees the particles the classes describe */
  if (nagg && ((rc = gs_dem_prepare(d, err)) || (rc = gs_dem_rebuild(d, err)))) return rc;
  return write_state(g, d, nwet, ncol, nagg, err);
}

int gs_dem_granulation_finish(gs_dem_granulation *g, gs_error *err) {
  int rc = GS_OK, r;
  FILE **f[3] = {&g->f_sum, &g->f_cls, &g->f_col};
  const char *path[3] = {g->path_sum, g->path_cls, g->path_col};
  for (int k = 0; k < 3; k++)
    if (*f[k]) {
      r = gs_dem_table_close(*f[k], path[k], err);
      if (!rc) rc = r;
      *f[k] = NULL;
    }
  return rc;
}

void gs_dem_granulation_free(gs_dem_granulation *g) {
  gs_error e = {0};
  gs_dem_granulation_finish(g, &e);
  if (g->rng) gsl_rng_free(g->rng);
  free(g->cls);
  free(g->idx);
  free(g->used);
  free(g->ncoll);
  free(g->nagg);
  free(g->kn);
  free(g->kexp);
  free(g->grow);
  g->kn = g->kexp = NULL;
  g->grow = NULL;
  g->ngrow = g->grow_cap = 0;
  g->rng = NULL;
  g->cls = g->idx = NULL;
  g->used = NULL;
  g->ncoll = g->nagg = NULL;
}
