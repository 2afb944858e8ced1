/* Binder spray: droplets leave a nozzle in a solid cone at a liquid mass
 * rate, fly ballistically with the DEM's step, and a droplet that touches a
 * particle is removed and its volume credited to that particle's liquid
 * (Sen et al. 2014: one droplet wets one particle).
 *
 * Droplets are point masses of the DEM's time step, not DEM particles: they
 * exert no contact force in the paper either, and outside the particle
 * arrays they neither widen the neighbour cells nor enter the force loops.
 * A droplet is looked up in the cell grid of the last neighbour-list rebuild,
 * wide enough for the half skin the particles may have moved since. */
#include <gsl/gsl_rng.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "dem/dem_wet.h"

static void cross(const double a[3], const double b[3], double c[3]) {
  c[0] = a[1] * b[2] - a[2] * b[1];
  c[1] = a[2] * b[0] - a[0] * b[2];
  c[2] = a[0] * b[1] - a[1] * b[0];
}

int gs_dem_spray_init(gs_dem_spray *s, const gs_dem_nozzle *noz, uint64_t seed, gs_error *err) {
  memset(s, 0, sizeof *s);
  s->noz = *noz;
  s->rd = 0.5 * noz->diameter;
  s->vd = M_PI / 6 * noz->diameter * noz->diameter * noz->diameter;
  s->md = noz->density * s->vd;
  /* two unit vectors normal to the axis: cross with the coordinate axis least aligned */
  const double *a = noz->axis;
  int k = fabs(a[0]) <= fabs(a[1]) && fabs(a[0]) <= fabs(a[2]) ? 0 : fabs(a[1]) <= fabs(a[2]) ? 1 : 2;
  double ek[3] = {0, 0, 0}, l;
  ek[k] = 1;
  cross(a, ek, s->e1);
  l = sqrt(s->e1[0] * s->e1[0] + s->e1[1] * s->e1[1] + s->e1[2] * s->e1[2]);
  for (int q = 0; q < 3; q++) s->e1[q] /= l;
  cross(a, s->e1, s->e2);
  s->rng = gsl_rng_alloc(gsl_rng_mt19937);
  if (!s->rng) return gs_error_set(err, GS_ENOMEM, "out of memory");
  gsl_rng_set(s->rng, (unsigned long)(seed ^ 0x5b1a7e3dULL));
  return GS_OK;
}

void gs_dem_spray_free(gs_dem_spray *s) {
  if (s->rng) gsl_rng_free(s->rng);
  free(s->drop);
  memset(s, 0, sizeof *s);
}

void gs_dem_spray_direction(const gs_dem_spray *s, const double u[2], double dir[3]) {
  const double c = 1 - u[0] * (1 - cos(s->noz.half_angle)), sn = sqrt(fmax(0, 1 - c * c));
  const double ph = 2 * M_PI * u[1], cp = cos(ph), sp = sin(ph);
  for (int q = 0; q < 3; q++) dir[q] = c * s->noz.axis[q] + sn * (cp * s->e1[q] + sp * s->e2[q]);
}

void gs_dem_absorb(gs_dem *d, size_t i, double vol, double mass, const double v[3]) {
  gs_dem_particles *p = &d->p;
  const double m = p->m[i] + mass;
  p->vx[i] = (p->m[i] * p->vx[i] + mass * v[0]) / m;
  p->vy[i] = (p->m[i] * p->vy[i] + mass * v[1]) / m;
  p->vz[i] = (p->m[i] * p->vz[i] + mass * v[2]) / m;
  /* spin: the droplet brings no angular momentum about the centre it joins;
   * the moment of inertia grows with the mass at the same size (not from the
   * contact radius, which lags behind the size of a growing aggregate) */
  const double I0 = 1.0 / p->invI[i], I1 = I0 * m / p->m[i];
  p->wx[i] *= I0 / I1;
  p->wy[i] *= I0 / I1;
  p->wz[i] *= I0 / I1;
  p->m[i] = m;
  p->invm[i] = 1.0 / m;
  p->invI[i] = 1.0 / I1;
  p->vl[i] += vol;
}

/* Index of the particle the droplet at x overlaps most, or -1. */
static long touched_particle(const gs_dem *d, const double x[3], double rd) {
  const gs_dem_particles *p = &d->p;
  if (!p->n || !d->cell_first || !d->order) return -1;
  const double reach = d->rmax + rd + 0.5 * d->prm.skin;
  const int m = (int)ceil(reach * d->cell_inv);
  int c[3];
  for (int a = 0; a < 3; a++) {
    c[a] = (int)floor((x[a] - d->prm.lo[a]) * d->cell_inv);
    if (c[a] < 0) c[a] = 0;
    if (c[a] >= d->cdim[a]) c[a] = d->cdim[a] - 1;
  }
  long best = -1;
  double best_gap = 0;
  for (int iz = c[2] - m; iz <= c[2] + m; iz++)
    for (int iy = c[1] - m; iy <= c[1] + m; iy++)
      for (int ix = c[0] - m; ix <= c[0] + m; ix++) {
        if (ix < 0 || iy < 0 || iz < 0 || ix >= d->cdim[0] || iy >= d->cdim[1] || iz >= d->cdim[2]) continue;
        const int cell = (iz * d->cdim[1] + iy) * d->cdim[0] + ix;
        for (int k = d->cell_first[cell]; k < d->cell_first[cell + 1]; k++) {
          const int i = d->order[k];
          if (p->dead[i]) continue;
          const double dx = x[0] - p->x[i], dy = x[1] - p->y[i], dz = x[2] - p->z[i];
          const double gap = sqrt(dx * dx + dy * dy + dz * dz) - p->r[i] - rd;
          if (gap < best_gap) best_gap = gap, best = i;
        }
      }
  return best;
}

static int outside(const gs_dem *d, const double x[3]) {
  for (int a = 0; a < 3; a++)
    if (!(x[a] >= d->prm.lo[a] && x[a] <= d->prm.hi[a])) return 1;
  return d->remove_pred && d->remove_pred(x, d->remove_ctx);
}

int gs_dem_spray_step(gs_dem_spray *s, gs_dem *d, gs_error *err) {
  const gs_dem_nozzle *z = &s->noz;
  const double t = d->t, dt = d->prm.dt;
  /* inject: the droplets due by now at the mass rate, whole droplets only */
  if (t >= z->start) {
    const long due = (long)floor(z->mass_rate * (fmin(t, z->end) - z->start) / s->md + 1e-9);
    if (due > s->injected) {
      size_t need = s->n + (size_t)(due - s->injected);
      if (need > s->cap) {
        size_t nc = s->cap ? s->cap : 256;
        while (nc < need) nc *= 2;
        gs_dem_drop *q = realloc(s->drop, nc * sizeof *q);
        if (!q) return gs_error_set(err, GS_ENOMEM, "out of memory for %zu droplets", nc);
        s->drop = q;
        s->cap = nc;
      }
      for (; s->injected < due; s->injected++) {
        double u[2] = {gsl_rng_uniform(s->rng), gsl_rng_uniform(s->rng)}, dir[3];
        gs_dem_spray_direction(s, u, dir);
        gs_dem_drop *q = &s->drop[s->n++];
        for (int a = 0; a < 3; a++) q->x[a] = z->point[a], q->v[a] = z->speed * dir[a];
      }
    }
  }
  /* move (semi-implicit Euler under gravity and the optional acceleration),
   * then settle each droplet */
  size_t keep = 0;
  for (size_t k = 0; k < s->n; k++) {
    gs_dem_drop q = s->drop[k];
    double acc[3] = {0, 0, 0};
    if (s->accel) s->accel(s->accel_ctx, q.x, q.v, acc);
    for (int a = 0; a < 3; a++) {
      q.v[a] += dt * (d->prm.gravity[a] + acc[a]);
      q.x[a] += dt * q.v[a];
    }
    if (!isfinite(q.x[0] + q.x[1] + q.x[2] + q.v[0] + q.v[1] + q.v[2]))
      return gs_error_set(err, GS_ENUMERIC,
                          "spray: droplet %zu of %zu airborne has a non-finite position or velocity at t = %g s "
                          "(step %ld); its acceleration besides gravity is not finite",
                          k, s->n, t, d->step);
    long i = touched_particle(d, q.x, s->rd);
    if (i >= 0) {
      gs_dem_absorb(d, (size_t)i, s->vd, s->md, q.v);
      s->absorbed++;
    } else if (outside(d, q.x)) {
      s->left++;
    } else if (gs_dem_touches_wall(d, q.x, s->rd)) {
      s->walls++;
    } else {
      s->drop[keep++] = q;
    }
  }
  s->n = keep;
  return GS_OK;
}

void gs_dem_spray_ledger(const gs_dem_spray *s, const gs_dem *d, gs_dem_liquid_ledger *l) {
  double on = 0;
  for (size_t i = 0; i < d->p.n; i++) on += d->p.vl[i];
  for (size_t i = 0; i < d->pend.n; i++) on += d->pend.vl[i];
  l->injected = (double)s->injected * s->vd;
  l->on_particles = on;
  l->airborne = (double)s->n * s->vd;
  l->on_walls = (double)s->walls * s->vd;
  l->left = (double)s->left * s->vd + d->vl_removed;
}
