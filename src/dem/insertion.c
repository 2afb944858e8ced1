/* Insertion of particles at random points of a region with no overlaps.
 *
 * Candidates are checked against the particles already there (present and
 * pending) through a temporary grid over the region, and against the walls
 * with the same contact search the forces use.  Radii and types are drawn
 * from the size distribution (fixed, uniform, or truncated lognormal); mass
 * fractions are turned into number fractions with each entry's mean particle
 * mass.  Random numbers: GSL's mt19937, seeded per call from the caller's
 * state (advanced by a splitmix64 step, so successive calls differ). */
#include <gsl/gsl_cdf.h>
#include <gsl/gsl_randist.h>
#include <gsl/gsl_rng.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "dem/dem_internal.h"

static uint64_t splitmix(uint64_t *s) {
  uint64_t z = (*s += 0x9E3779B97F4A7C15ull);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

static int lognormal_entry(const gs_dem_psd *psd, size_t k) {
  return psd->gsd && psd->median && psd->gsd[k] > 1;
}

void gs_dem_psd_moment3(const gs_dem_psd *psd, size_t k, double *mean_r3, double *share) {
  const double r0 = psd->rmin[k], r1 = psd->rmax[k];
  double m3, sh = 1;
  if (lognormal_entry(psd, k)) {
    /* ln r ~ N(mu, s) truncated to [a, b]:
     * E[r^3] = exp(3 mu + 9 s^2 / 2) (P(b - 3 s) - P(a - 3 s)) / (P(b) - P(a)),
     * P the standard normal CDF of (ln x - mu) / s shifted as written */
    const double mu = log(psd->median[k]), sg = log(psd->gsd[k]);
    const double a = r0 > 0 ? (log(r0) - mu) / sg : -HUGE_VAL, b = (log(r1) - mu) / sg;
    sh = gsl_cdf_ugaussian_P(b) - gsl_cdf_ugaussian_P(a);
    double num = gsl_cdf_ugaussian_P(b - 3 * sg) - gsl_cdf_ugaussian_P(a - 3 * sg);
    m3 = sh > 0 ? exp(3 * mu + 4.5 * sg * sg) * num / sh : r0 * r0 * r0;
  } else {
    m3 = r1 > r0 ? (pow(r1, 4) - pow(r0, 4)) / (4 * (r1 - r0)) : r0 * r0 * r0;
  }
  if (mean_r3) *mean_r3 = m3;
  if (share) *share = sh;
}

typedef struct {
  double lo[3], h;
  int dim[3];
  int *head, *next;
  double *x, *r; /* 3 per particle, 1 per particle */
  size_t n, cap;
} grid;

static int grid_cell(const grid *g, const double x[3], int c[3]) {
  for (int a = 0; a < 3; a++) {
    double f = (x[a] - g->lo[a]) / g->h;
    if (!(f >= 0) || f >= g->dim[a]) return 0;
    c[a] = (int)f;
  }
  return 1;
}

static int grid_add(grid *g, const double x[3], double r) {
  int c[3];
  if (!grid_cell(g, x, c)) return 0;
  if (g->n == g->cap) {
    size_t nc = g->cap ? 2 * g->cap : 1024;
    int *nn = realloc(g->next, nc * sizeof(int));
    if (nn) g->next = nn;
    double *nx = realloc(g->x, 3 * nc * sizeof(double));
    if (nx) g->x = nx;
    double *nr = realloc(g->r, nc * sizeof(double));
    if (nr) g->r = nr;
    if (!nn || !nx || !nr) return -1;
    g->cap = nc;
  }
  size_t k = g->n++, cell = ((size_t)c[2] * g->dim[1] + c[1]) * g->dim[0] + c[0];
  memcpy(g->x + 3 * k, x, 3 * sizeof(double));
  g->r[k] = r;
  g->next[k] = g->head[cell];
  g->head[cell] = (int)k;
  return 0;
}

static int grid_overlaps(const grid *g, const double x[3], double r) {
  int c[3];
  if (!grid_cell(g, x, c)) return 0;
  for (int dz = -1; dz <= 1; dz++)
    for (int dy = -1; dy <= 1; dy++)
      for (int dx = -1; dx <= 1; dx++) {
        int ix = c[0] + dx, iy = c[1] + dy, iz = c[2] + dz;
        if (ix < 0 || iy < 0 || iz < 0 || ix >= g->dim[0] || iy >= g->dim[1] || iz >= g->dim[2]) continue;
        for (int k = g->head[((size_t)iz * g->dim[1] + iy) * g->dim[0] + ix]; k >= 0; k = g->next[k]) {
          double ex = x[0] - g->x[3 * k], ey = x[1] - g->x[3 * k + 1], ez = x[2] - g->x[3 * k + 2];
          double s = r + g->r[k];
          if (ex * ex + ey * ey + ez * ez < s * s) return 1;
        }
      }
  return 0;
}

static void region_bounds(const gs_dem_region *reg, double lo[3], double hi[3]) {
  if (reg->kind == GS_DEM_REGION_BOX) {
    memcpy(lo, reg->lo, 3 * sizeof(double));
    memcpy(hi, reg->hi, 3 * sizeof(double));
    return;
  }
  for (int k = 0; k < 3; k++) {
    double a = reg->p[k] + reg->s0 * reg->a[k], b = reg->p[k] + reg->s1 * reg->a[k];
    lo[k] = fmin(a, b) - reg->R;
    hi[k] = fmax(a, b) + reg->R;
  }
}

int gs_dem_insert(gs_dem *d, const gs_dem_region *reg, const gs_dem_psd *psd, long count,
                  double mass, const double v[3], uint64_t *rng_state, long *n_out, double *m_out,
                  gs_error *err) {
  *n_out = 0;
  *m_out = 0;
  if (!psd->n) return gs_error_set(err, GS_EINPUT, "insertion needs a size distribution");
  /* number fractions and the largest radius */
  double *cum = malloc(psd->n * sizeof(double)), tot = 0, rbig = 0;
  if (!cum) return gs_error_set(err, GS_ENOMEM, "out of memory");
  for (size_t k = 0; k < psd->n; k++) {
    double w = psd->frac[k];
    if (lognormal_entry(psd, k)) {
      double share;
      gs_dem_psd_moment3(psd, k, NULL, &share);
      if (!(share >= 1e-6)) {
        free(cum);
        return gs_error_set(err, GS_EINPUT, "lognormal radius (median %g, gsd %g): the range [%g, %g] holds "
                            "only %.3g of it", psd->median[k], psd->gsd[k], psd->rmin[k], psd->rmax[k], share);
      }
    }
    if (psd->by_mass) {
      double r3;
      gs_dem_psd_moment3(psd, k, &r3, NULL);
      w /= d->types[psd->type[k]].mat.density * r3;
    }
    tot += w;
    cum[k] = tot;
    if (psd->rmax[k] > rbig) rbig = psd->rmax[k];
  }
  if (rbig > d->rmax) d->rmax = rbig;
  int rc = gs_dem_prepare(d, err);
  grid g;
  memset(&g, 0, sizeof g);
  double lo[3], hi[3], rall = fmax(rbig, d->rmax);
  region_bounds(reg, lo, hi);
  g.h = 2 * rall;
  size_t ncell = 1;
  for (int a = 0; a < 3; a++) {
    g.lo[a] = lo[a] - 2 * rall;
    double ext = hi[a] - lo[a] + 4 * rall;
    while (ext / g.h > 400) g.h *= 1.5;
  }
  for (int a = 0; a < 3; a++) {
    g.dim[a] = (int)((hi[a] - lo[a] + 4 * rall) / g.h) + 1;
    ncell *= (size_t)g.dim[a];
  }
  g.head = rc ? NULL : malloc(ncell * sizeof(int));
  if (!rc && !g.head) rc = gs_error_set(err, GS_ENOMEM, "out of memory");
  gsl_rng *rng = rc ? NULL : gsl_rng_alloc(gsl_rng_mt19937);
  if (!rc && !rng) rc = gs_error_set(err, GS_ENOMEM, "out of memory");
  if (rng) gsl_rng_set(rng, (unsigned long)(splitmix(rng_state) >> 32));
  if (!rc) memset(g.head, 0xff, ncell * sizeof(int));
  for (int src = 0; src < 2 && !rc; src++) {
    const gs_dem_particles *p = src ? &d->pend : &d->p;
    for (size_t i = 0; i < p->n && !rc; i++) {
      double x[3] = {p->x[i], p->y[i], p->z[i]};
      if (grid_add(&g, x, p->r[i]) < 0) rc = gs_error_set(err, GS_ENOMEM, "out of memory");
    }
  }
  /* Draw the class and size first, then look for a free spot for that very
   * particle, and keep it until it is placed: redrawing the class after a
   * failed spot would favour small particles in a crowded region and bias the
   * size distribution.  20 rounds of 50 spots without success: region full. */
  long fails = 0;
  int drawn = 0;
  size_t k = 0;
  double r = 0;
  while (!rc && *n_out < count && *m_out < mass && fails < 20) {
    if (!drawn) {
      double u = gsl_rng_uniform(rng) * tot;
      k = 0;
      while (k + 1 < psd->n && u > cum[k]) k++;
      if (lognormal_entry(psd, k)) {
        const double mu = log(psd->median[k]), sg = log(psd->gsd[k]);
        do r = gsl_ran_lognormal(rng, mu, sg);
        while (r < psd->rmin[k] || r > psd->rmax[k]);
      } else {
        r = psd->rmin[k] + gsl_rng_uniform(rng) * (psd->rmax[k] - psd->rmin[k]);
      }
      drawn = 1;
    }
    double x[3];
    int ok = 0;
    for (int attempt = 0; attempt < 50 && !ok; attempt++) {
      double uu[3] = {gsl_rng_uniform(rng), gsl_rng_uniform(rng), gsl_rng_uniform(rng)};
      gs_dem_region_point(reg, uu, x);
      ok = !grid_overlaps(&g, x, r) && !gs_dem_touches_wall(d, x, r);
    }
    if (!ok) {
      fails++;
      continue;
    }
    fails = 0;
    drawn = 0;
    if (gs_dem_add_particle(d, psd->type[k], r, x, v, NULL, err) < 0) rc = err->code;
    else if (grid_add(&g, x, r) < 0) rc = gs_error_set(err, GS_ENOMEM, "out of memory");
    else {
      (*n_out)++;
      *m_out += d->pend.m[d->pend.n - 1];
    }
  }
  gsl_rng_free(rng);
  free(cum);
  free(g.head);
  free(g.next);
  free(g.x);
  free(g.r);
  return rc;
}
