/* Neighbour search: particles sorted by cell, then a half Verlet list with a
 * skin, reused until some particle has moved half the skin.
 *
 * A rebuild is also the only moment the particle set changes: particles marked
 * dead (outlet, left the box) are dropped and pending ones (insertion) join, so
 * the force loops never see the arrays resized under them.  Contact history
 * (the tangential shear of touching pairs) survives a rebuild: the touching
 * pairs of the old list are looked up in the new one. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "dem/dem_internal.h"

static int cell_coord(const gs_dem *d, double v, int axis) {
  int c = (int)floor((v - d->prm.lo[axis]) * d->cell_inv);
  if (c < 0) c = 0;
  if (c >= d->cdim[axis]) c = d->cdim[axis] - 1;
  return c;
}

static int setup_cells(gs_dem *d, gs_error *err) {
  double h = 2 * d->rmax + d->prm.skin;
  double ext[3];
  for (int a = 0; a < 3; a++) ext[a] = d->prm.hi[a] - d->prm.lo[a];
  /* Keep the grid bounded for large boxes with tiny particles. */
  while ((ext[0] / h + 1) * (ext[1] / h + 1) * (ext[2] / h + 1) > 8e6) h *= 1.25;
  if (h == d->cell_h && d->cell_first) return GS_OK;
  d->cell_h = h;
  d->cell_inv = 1.0 / h;
  for (int a = 0; a < 3; a++) d->cdim[a] = (int)(ext[a] / h) + 1;
  d->ncells = (size_t)d->cdim[0] * d->cdim[1] * d->cdim[2];
  free(d->cell_first);
  d->cell_first = gs_malloc((d->ncells + 1) * sizeof(int), err);
  return d->cell_first ? GS_OK : GS_ENOMEM;
}

int gs_dem_needs_rebuild(const gs_dem *d) {
  return d->need_rebuild || d->pend.n > 0;
}

static int out_of_box(const gs_dem *d, const gs_dem_particles *p, size_t i) {
  return !(p->x[i] >= d->prm.lo[0] && p->x[i] <= d->prm.hi[0] && p->y[i] >= d->prm.lo[1] &&
           p->y[i] <= d->prm.hi[1] && p->z[i] >= d->prm.lo[2] && p->z[i] <= d->prm.hi[2]);
}

static int record_removed(gs_dem *d, const gs_dem_particles *p, size_t k) {
  if (d->nrm == d->rm_cap) {
    size_t nc = d->rm_cap ? 2 * d->rm_cap : 256;
    int *c = realloc(d->rm_cls, nc * sizeof(int));
    if (c) d->rm_cls = c;
    double *r = realloc(d->rm_rt, nc * sizeof(double));
    if (r) d->rm_rt = r;
    double *m = realloc(d->rm_m, nc * sizeof(double));
    if (m) d->rm_m = m;
    if (!c || !r || !m) return -1;
    d->rm_cap = nc;
  }
  d->rm_cls[d->nrm] = d->types[p->type[k]].cls;
  d->rm_rt[d->nrm] = d->t - p->t_in[k];
  d->rm_m[d->nrm] = p->m[k];
  d->nrm++;
  return 0;
}

/* Touching pairs of the old list, by new particle index, to carry over. */
typedef struct {
  int i, j;
  double s[3];
} carried;

int gs_dem_rebuild(gs_dem *d, gs_error *err) {
  gs_dem_particles *p = &d->p;
  int rc = setup_cells(d, err);
  if (rc) return rc;
  size_t nold = p->n, ntot = p->n + d->pend.n;

  /* 1. which particles survive; cell of each source (old ones then pending) */
  if (ntot > d->perm_cap) {
    free(d->perm);
    free(d->cellof);
    free(d->order);
    free(d->pos);
    d->perm = gs_malloc((ntot + 1) * sizeof(int), err);
    d->cellof = gs_malloc((ntot + 1) * sizeof(int), err);
    d->order = gs_malloc((ntot + 1) * sizeof(int), err);
    d->pos = gs_malloc((ntot + 1) * sizeof(int), err);
    if (!d->perm || !d->cellof || !d->order || !d->pos) return GS_ENOMEM;
    d->perm_cap = ntot;
  }
  int ndead = 0;
  for (size_t s = 0; s < ntot; s++) {
    const gs_dem_particles *src = s < nold ? p : &d->pend;
    size_t k = s < nold ? s : s - nold;
    double xs[3] = {src->x[k], src->y[k], src->z[k]};
    int dead = src->dead[k];
    if (!dead && out_of_box(d, src, k)) {
      dead = 1;
      d->lost++;
    }
    if (!dead && d->remove_pred && d->remove_pred(xs, d->remove_ctx)) {
      dead = 1;
      if (s < nold && record_removed(d, src, k)) return gs_error_set(err, GS_ENOMEM, "out of memory");
    }
    if (dead && !src->dead[k]) {
      /* leaving the simulation (aggregated-away particles hold nothing) */
      d->vs_removed += src->vs[k];
      d->vl_removed += src->vl[k];
    }
    ndead += dead;
    d->cellof[s] = dead ? -1
                        : (cell_coord(d, xs[2], 2) * d->cdim[1] + cell_coord(d, xs[1], 1)) * d->cdim[0] +
                              cell_coord(d, xs[0], 0);
  }
  /* 2. counting sort by cell */
  memset(d->cell_first, 0, (d->ncells + 1) * sizeof(int));
  for (size_t s = 0; s < ntot; s++)
    if (d->cellof[s] >= 0) d->cell_first[d->cellof[s] + 1]++;
  for (size_t c = 0; c < d->ncells; c++) d->cell_first[c + 1] += d->cell_first[c];
  size_t nnew = (size_t)d->cell_first[d->ncells];
  /* Moving every particle array into cell order costs as much as building the
   * list; between additions and removals the order drifts slowly, so the data
   * are re-sorted only every 8th rebuild and the other rebuilds walk the cells
   * through an index (order: particles by cell, pos: the inverse). */
  const int resort = ndead || d->pend.n || d->rebuilds % 8 == 0;
  {
    int *fill = gs_malloc((d->ncells + 1) * sizeof(int), err);
    if (!fill) return GS_ENOMEM;
    memcpy(fill, d->cell_first, (d->ncells + 1) * sizeof(int));
    if (resort) {
      /* perm[s] = new index of source s (or -1); fill tmp in cell order */
      if ((rc = gs_dem_particles_reserve(&d->tmp, nnew, err))) {
        free(fill);
        return rc;
      }
      for (size_t s = 0; s < ntot; s++) {
        if (d->cellof[s] < 0) {
          d->perm[s] = -1;
          continue;
        }
        int ni = fill[d->cellof[s]]++;
        d->perm[s] = ni;
        if (s < nold) gs_dem_particles_copy(&d->tmp, (size_t)ni, p, s);
        else gs_dem_particles_copy(&d->tmp, (size_t)ni, &d->pend, s - nold);
      }
      for (size_t k = 0; k < nnew; k++) d->order[k] = d->pos[k] = (int)k;
      d->tmp.n = nnew;
    } else {
      for (size_t s = 0; s < ntot; s++) {
        int k = fill[d->cellof[s]]++;
        d->perm[s] = (int)s;
        d->order[k] = (int)s;
        d->pos[s] = k;
      }
    }
    free(fill);
  }

  /* 3. touching pairs of the old list, renumbered */
  size_t ncar = 0;
  carried *car = NULL;
  if (d->nl_first && nold) {
    size_t nent = (size_t)d->nl_first[nold];
    for (size_t k = 0; k < nent; k++) ncar += d->nl_touch[k];
    car = gs_malloc((ncar ? ncar : 1) * sizeof *car, err);
    if (!car) return GS_ENOMEM;
    ncar = 0;
    for (size_t i = 0; i < nold; i++)
      for (int k = d->nl_first[i]; k < d->nl_first[i + 1]; k++) {
        if (!d->nl_touch[k]) continue;
        int ni = d->perm[i], nj = d->perm[d->nl_j[k]];
        if (ni < 0 || nj < 0) continue;
        car[ncar].i = ni;
        car[ncar].j = nj;
        memcpy(car[ncar].s, d->nl_shear + 3 * (size_t)k, 3 * sizeof(double));
        ncar++;
      }
  }

  /* 4. swap buffers */
  if (resort) {
    gs_dem_particles t = *p;
    *p = d->tmp;
    d->tmp = t;
    d->tmp.n = 0;
    d->pend.n = 0;
  }
  size_t n = p->n;
  const int *order = d->order;

  /* 5. half list: own cell (j > i) and the 13 forward neighbour cells */
  free(d->nl_first);
  d->nl_first = gs_malloc((n + 1) * sizeof(int), err);
  if (!d->nl_first) { free(car); return GS_ENOMEM; }
  size_t ne = 0;
  const double skin = d->prm.skin;
  const int cx = d->cdim[0], cy = d->cdim[1], cz = d->cdim[2];
  for (size_t i = 0; i < n; i++) {
    d->nl_first[i] = (int)ne;
    const double xi = p->x[i], yi = p->y[i], zi = p->z[i], ri = p->r[i] + skin;
    int ix = cell_coord(d, xi, 0), iy = cell_coord(d, yi, 1), iz = cell_coord(d, zi, 2);
    for (int dz = 0; dz <= 1; dz++)
      for (int dy = (dz ? -1 : 0); dy <= 1; dy++)
        for (int dx = (dz || dy ? -1 : 0); dx <= 1; dx++) {
          int jx = ix + dx, jy = iy + dy, jz = iz + dz;
          if (jx < 0 || jy < 0 || jx >= cx || jy >= cy || jz >= cz) continue;
          int c = (jz * cy + jy) * cx + jx;
          int k0 = d->cell_first[c], k1 = d->cell_first[c + 1];
          if (!dx && !dy && !dz) k0 = d->pos[i] + 1;
          for (int kk = k0; kk < k1; kk++) {
            const int j = order[kk];
            double ddx = xi - p->x[j], ddy = yi - p->y[j], ddz = zi - p->z[j];
            double cut = ri + p->r[j];
            if (ddx * ddx + ddy * ddy + ddz * ddz >= cut * cut) continue;
            if (ne >= d->nl_cap) {
              size_t nc = d->nl_cap ? 2 * d->nl_cap : 1024;
              int *nj = realloc(d->nl_j, nc * sizeof(int));
              if (nj) d->nl_j = nj;
              uint8_t *nt = realloc(d->nl_touch, nc);
              if (nt) d->nl_touch = nt;
              double *ns = realloc(d->nl_shear, 3 * nc * sizeof(double));
              if (ns) d->nl_shear = ns;
              if (!nj || !nt || !ns) {
                free(car);
                return gs_error_set(err, GS_ENOMEM, "out of memory for %zu neighbour pairs", nc);
              }
              d->nl_cap = nc;
            }
            d->nl_j[ne++] = j;
          }
        }
  }
  d->nl_first[n] = (int)ne;
  if (ne) {
    memset(d->nl_touch, 0, ne);
    memset(d->nl_shear, 0, 3 * ne * sizeof(double));
  }

  /* 6. restore history: the pair sits under one of its two particles */
  for (size_t c = 0; c < ncar; c++) {
    int a = car[c].i, b = car[c].j, found = -1;
    for (int k = d->nl_first[a]; k < d->nl_first[a + 1] && found < 0; k++)
      if (d->nl_j[k] == b) found = k;
    int sign = 1;
    for (int k = d->nl_first[b]; k < d->nl_first[b + 1] && found < 0; k++)
      if (d->nl_j[k] == a) {
        found = k;
        sign = -1; /* roles swapped: the shear of j on i is minus that of i on j */
      }
    if (found < 0) continue;
    d->nl_touch[found] = 1;
    for (int q = 0; q < 3; q++) d->nl_shear[3 * (size_t)found + q] = sign * car[c].s[q];
  }
  free(car);

  for (size_t i = 0; i < n; i++) {
    p->x0[i] = p->x[i];
    p->y0[i] = p->y[i];
    p->z0[i] = p->z[i];
  }
  d->need_rebuild = 0;
  d->rebuilds++;
  return GS_OK;
}
