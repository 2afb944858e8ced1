/* Sphere–sphere forces over the half Verlet list.
 *
 * OpenMP without races: a pair writes to both of its particles, so each thread
 * other than the first accumulates into its own force/torque buffer and the
 * buffers are summed afterwards (thread 0 writes the particle arrays
 * directly, so one thread costs nothing extra).  Collision events are counted
 * where a contact begins (its touch flag goes 0 -> 1) into per-thread class
 * matrices, so a contact is counted once however many steps it lasts. */
#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

#include "dem/contact_hertz.h"

static int ensure_buffers(gs_dem *d, int nt) {
  size_t need = (size_t)(nt - 1) * 6 * d->p.n;
  if (need > d->tbuf_cap) {
    free(d->tbuf);
    d->tbuf = malloc(need * sizeof(double));
    if (!d->tbuf) {
      d->tbuf_cap = 0;
      return -1;
    }
    d->tbuf_cap = need;
  }
  return 0;
}

void gs_dem_pair_forces(gs_dem *d) {
  gs_dem_particles *p = &d->p;
  const size_t n = p->n;
  if (!n) return;
  int nt = omp_get_max_threads();
  if (nt > 1 && (n < d->par_min || ensure_buffers(d, nt))) nt = 1;
  const int ncl = d->prm.nclass;
  const size_t ntypes = d->ntypes;
  const double dt = d->prm.dt;
  uint64_t *ev_all = calloc((size_t)nt * ncl * ncl, sizeof(uint64_t));
  /* per-thread logs of collision onsets, when the granulation asks for them */
  gs_dem_pair_log *plog = d->plog ? calloc((size_t)nt, sizeof *plog) : NULL;
  if (d->plog && !plog) d->oom = 1;

#pragma omp parallel num_threads(nt)
  {
    const int tid = omp_get_thread_num();
    double *restrict fx = p->fx, *restrict fy = p->fy, *restrict fz = p->fz;
    double *restrict tx = p->tx, *restrict ty = p->ty, *restrict tz = p->tz;
    if (tid > 0) {
      double *b = d->tbuf + (size_t)(tid - 1) * 6 * n;
      memset(b, 0, 6 * n * sizeof(double));
      fx = b, fy = b + n, fz = b + 2 * n, tx = b + 3 * n, ty = b + 4 * n, tz = b + 5 * n;
    }
    uint64_t *ev = ev_all ? ev_all + (size_t)tid * ncl * ncl : NULL;
    const double *restrict x = p->x, *restrict y = p->y, *restrict z = p->z;
    const double *restrict vx = p->vx, *restrict vy = p->vy, *restrict vz = p->vz;
    const double *restrict wx = p->wx, *restrict wy = p->wy, *restrict wz = p->wz;
    const double *restrict r = p->r, *restrict m = p->m;
    const int *restrict type = p->type;
    const int *restrict first = d->nl_first, *restrict nj = d->nl_j;
    uint8_t *restrict touch = d->nl_touch;
    double *restrict shear = d->nl_shear;

#pragma omp for schedule(static)
    for (size_t i = 0; i < n; i++) {
      const double xi = x[i], yi = y[i], zi = z[i], ri = r[i];
      double fxi = 0, fyi = 0, fzi = 0, txi = 0, tyi = 0, tzi = 0;
      const int ti = type[i];
      for (int k = first[i]; k < first[i + 1]; k++) {
        const int j = nj[k];
        const double dx = xi - x[j], dy = yi - y[j], dz = zi - z[j];
        const double rs = ri + r[j];
        const double d2 = dx * dx + dy * dy + dz * dz;
        if (d2 >= rs * rs) {
          if (touch[k]) {
            touch[k] = 0;
            shear[3 * k] = shear[3 * k + 1] = shear[3 * k + 2] = 0;
          }
          continue;
        }
        const int tj = type[j];
        const int onset = !touch[k];
        if (onset) {
          touch[k] = 1;
          if (ev) {
            int ci = d->types[ti].cls, cj = d->types[tj].cls;
            if (ci > cj) { int q = ci; ci = cj; cj = q; }
            ev[ci * ncl + cj]++;
          }
        }
        const double dist = sqrt(d2);
        const double inv = 1.0 / dist;
        const double nrm[3] = {dx * inv, dy * inv, dz * inv};
        const double delta = rs - dist;
        const double rj = r[j];
        const double reff = ri * rj / rs;
        const double meff = m[i] * m[j] / (m[i] + m[j]);
        const double ci = ri - 0.5 * delta, cj = rj - 0.5 * delta;
        const double vrx = vx[i] - vx[j], vry = vy[i] - vy[j], vrz = vz[i] - vz[j];
        const double vn = vrx * nrm[0] + vry * nrm[1] + vrz * nrm[2];
        if (onset && plog) gs_dem_pair_log_push(&plog[tid], p->id[i], p->id[j], fabs(vn));
        /* (ci wi + cj wj) x n: rotation's share of the contact-point velocity */
        const double ax = ci * wx[i] + cj * wx[j], ay = ci * wy[i] + cj * wy[j],
                     az = ci * wz[i] + cj * wz[j];
        const double vt[3] = {vrx - vn * nrm[0] - (ay * nrm[2] - az * nrm[1]),
                              vry - vn * nrm[1] - (az * nrm[0] - ax * nrm[2]),
                              vrz - vn * nrm[2] - (ax * nrm[1] - ay * nrm[0])};
        const gs_dem_pair *pc = &d->pp[(size_t)ti * ntypes + tj];
        gs_dem_contact_force cf;
        gs_dem_hertz(pc, delta, reff, meff, nrm, vn, vt, shear + 3 * (size_t)k, dt, &cf);
        const double f0 = cf.fn * nrm[0] + cf.ft[0], f1 = cf.fn * nrm[1] + cf.ft[1],
                     f2 = cf.fn * nrm[2] + cf.ft[2];
        /* torque from the tangential force: -c (n x Ft) on both spheres */
        const double c0 = nrm[1] * cf.ft[2] - nrm[2] * cf.ft[1];
        const double c1 = nrm[2] * cf.ft[0] - nrm[0] * cf.ft[2];
        const double c2 = nrm[0] * cf.ft[1] - nrm[1] * cf.ft[0];
        double rt[3] = {0, 0, 0};
        if (pc->mu_r > 0) {
          const double wrel[3] = {wx[i] - wx[j], wy[i] - wy[j], wz[i] - wz[j]};
          gs_dem_rolling(pc->mu_r, cf.fe, reff, nrm, wrel, rt);
        }
        fxi += f0;
        fyi += f1;
        fzi += f2;
        txi += -ci * c0 + rt[0];
        tyi += -ci * c1 + rt[1];
        tzi += -ci * c2 + rt[2];
        fx[j] -= f0;
        fy[j] -= f1;
        fz[j] -= f2;
        tx[j] += -cj * c0 - rt[0];
        ty[j] += -cj * c1 - rt[1];
        tz[j] += -cj * c2 - rt[2];
      }
      fx[i] += fxi;
      fy[i] += fyi;
      fz[i] += fzi;
      tx[i] += txi;
      ty[i] += tyi;
      tz[i] += tzi;
    }
    /* implicit barrier: all buffers complete */
    if (nt > 1) {
#pragma omp for schedule(static)
      for (size_t i = 0; i < n; i++) {
        for (int t = 1; t < nt; t++) {
          const double *b = d->tbuf + (size_t)(t - 1) * 6 * n;
          p->fx[i] += b[i];
          p->fy[i] += b[n + i];
          p->fz[i] += b[2 * n + i];
          p->tx[i] += b[3 * n + i];
          p->ty[i] += b[4 * n + i];
          p->tz[i] += b[5 * n + i];
        }
      }
    }
  }
  if (plog) {
    gs_dem_pair_log_merge(d, plog, nt);
    free(plog);
  }
  if (ev_all) {
    for (int t = 0; t < nt; t++)
      for (int q = 0; q < ncl * ncl; q++) d->pair_events[q] += ev_all[(size_t)t * ncl * ncl + q];
    free(ev_all);
  }
}
