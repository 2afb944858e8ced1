/* Sphere–wall forces: planes, cylinders and triangle meshes, all moving
 * rigidly.  Each particle is taken into a wall's body frame, where a mesh was
 * binned once (a rotating impeller never needs re-binning); the contact point
 * and normal go back to the world frame and the wall velocity at the contact
 * enters the relative velocity.
 *
 * A sphere near a mesh edge or vertex finds the same point on every triangle
 * that shares it, and a sphere on a flat mesh finds the shared edge of the
 * neighbouring triangle: contacts are sorted by distance, faces are always
 * kept, and an edge or vertex contact is dropped when it shares a vertex with
 * a contact already kept on that mesh.
 *
 * Every particle writes only its own force, so the loop is parallel; wall
 * loads and impact counters are reduced per thread.  The impact speeds
 * U = |v - v_wall| are kept one by one (for the lognormal fits of the PBM's
 * breakage table): each thread collects its own, and a step's records are
 * put in the order of the particle ids, so the record is the same for any
 * number of threads. */
#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

#include "dem/contact_hertz.h"

#define MAXC 24

/* one impact speed: particle id, order within the thread's record, class key, ln U */
typedef struct {
  long id;
  size_t seq;
  int q;
  double lnu;
} imp_rec;

typedef struct {
  imp_rec *r;
  size_t n, cap;
  int oom;
} imp_buf;

static void imp_push(imp_buf *b, long id, int q, double lnu) {
  if (b->n == b->cap) {
    size_t nc = b->cap ? 2 * b->cap : 64;
    imp_rec *r = realloc(b->r, nc * sizeof *r);
    if (!r) {
      b->oom = 1;
      return;
    }
    b->r = r;
    b->cap = nc;
  }
  b->r[b->n].id = id;
  b->r[b->n].seq = b->n;
  b->r[b->n].q = q;
  b->r[b->n].lnu = lnu;
  b->n++;
}

static int cmp_rec(const void *a, const void *b) {
  const imp_rec *x = a, *y = b;
  if (x->id != y->id) return x->id < y->id ? -1 : 1;
  return (x->seq > y->seq) - (x->seq < y->seq);
}

/* Append the step's impact speeds of all threads to the engine's record, in
 * the order of the particle ids (a particle's own impacts keep their order). */
static void imp_merge(gs_dem *d, imp_buf *ib, int nt) {
  size_t tot = 0;
  for (int t = 0; t < nt; t++) {
    if (ib[t].oom) d->oom = 1;
    tot += ib[t].n;
  }
  if (!tot) return;
  imp_rec *all = ib[0].r;
  if (nt > 1) {
    all = malloc(tot * sizeof *all);
    if (!all) {
      d->oom = 1;
      return;
    }
    size_t k = 0;
    for (int t = 0; t < nt; t++)
      for (size_t j = 0; j < ib[t].n; j++) {
        all[k] = ib[t].r[j];
        all[k].seq = k; /* a particle's records are consecutive in one thread's buffer */
        k++;
      }
  }
  if (tot > 1) qsort(all, tot, sizeof *all, cmp_rec);
  if (d->nimp + tot > d->imp_cap) {
    size_t nc = d->imp_cap ? d->imp_cap : 1024;
    while (nc < d->nimp + tot) nc *= 2;
    int *q = realloc(d->imp_q, nc * sizeof(int));
    if (q) d->imp_q = q;
    double *l = realloc(d->imp_lnu, nc * sizeof(double));
    if (l) d->imp_lnu = l;
    if (!q || !l) {
      d->oom = 1;
      if (nt > 1) free(all);
      return;
    }
    d->imp_cap = nc;
  }
  for (size_t k = 0; k < tot; k++) {
    d->imp_q[d->nimp] = all[k].q;
    d->imp_lnu[d->nimp++] = all[k].lnu;
  }
  if (nt > 1) free(all);
}

typedef struct {
  int wall, feat;      /* feature: 0 face, 1..3 edge, 4..6 vertex, -1 analytic */
  int nv, v[3];        /* welded vertex ids of the feature */
  uint64_t key;
  double dist;         /* centre to contact point */
  double cp[3], n[3];  /* world frame; n points from the wall to the centre */
} cand;

static void add_cand(cand *c, int *nc, const cand *x) {
  if (*nc >= MAXC) {
    /* keep the closest: replace the farthest if x is closer */
    int far = 0;
    for (int k = 1; k < *nc; k++)
      if (c[k].dist > c[far].dist) far = k;
    if (c[far].dist > x->dist) c[far] = *x;
    return;
  }
  c[(*nc)++] = *x;
}

/* owned_only: in LIGGGHTS mode, only the edges and corners a triangle owns
 * (the force loop); insertion asks for any overlap. */
static void mesh_candidates(const gs_dem_wall *w, int wi, const double xw[3], double r, cand *c,
                            int *nc, int owned_only) {
  const gs_dem_mesh *m = w->mesh;
  double pb[3];
  gs_dem_wall_to_body(w, xw, pb);
  int ic[3];
  for (int a = 0; a < 3; a++) {
    double f = (pb[a] - m->blo[a]) / m->bh;
    if (!(f >= 0) || f >= m->bdim[a]) return;
    ic[a] = (int)f;
  }
  size_t cell = ((size_t)ic[2] * m->bdim[1] + ic[1]) * m->bdim[0] + ic[0];
  if (!(m->bmask[cell / 64] >> (cell % 64) & 1)) return;
  for (int k = m->bfirst[cell]; k < m->bfirst[cell + 1]; k++) {
    int t = m->btri[k];
    const double *v = m->v + 9 * (size_t)t, *nr = m->nrm + 3 * (size_t)t;
    double s = (pb[0] - v[0]) * nr[0] + (pb[1] - v[1]) * nr[1] + (pb[2] - v[2]) * nr[2];
    if (s >= r || s <= -r) continue;
    double q[3];
    int feat = gs_dem_closest_on_triangle(pb, v, v + 3, v + 6, q);
    /* LIGGGHTS mode: an edge (feat 1..3: edge feat-1) or corner (4..6: corner
     * feat-4) this triangle does not own gives no contact */
    if (owned_only && m->active && feat > 0 &&
        !(m->active[t] & (feat <= 3 ? 1u << (feat - 1) : 8u << (feat - 4))))
      continue;
    double dq[3] = {pb[0] - q[0], pb[1] - q[1], pb[2] - q[2]};
    double d2 = dq[0] * dq[0] + dq[1] * dq[1] + dq[2] * dq[2];
    if (d2 >= r * r || d2 <= 0) continue;
    cand x;
    x.wall = wi;
    x.feat = feat;
    x.dist = sqrt(d2);
    const int *vid = m->vid + 3 * (size_t)t;
    uint64_t ids;
    int feat_kind = feat == 0 ? 0 : feat <= 3 ? 1 : 2;
    if (feat == 0) {
      x.nv = 3;
      x.v[0] = vid[0], x.v[1] = vid[1], x.v[2] = vid[2];
      ids = (uint64_t)t;
    } else if (feat <= 3) {
      int a = vid[feat - 1], b = vid[feat % 3];
      if (a > b) { int q2 = a; a = b; b = q2; }
      x.nv = 2;
      x.v[0] = a, x.v[1] = b;
      ids = ((uint64_t)a << 27) | (uint64_t)b;
    } else {
      x.nv = 1;
      x.v[0] = vid[feat - 4];
      ids = (uint64_t)x.v[0];
    }
    /* LIGGGHTS keeps a contact's history per triangle, whichever of its
     * features touches; gransim per feature (a shared edge is one contact) */
    if (m->active) ids = (uint64_t)t, feat_kind = 0;
    x.key = ((uint64_t)(wi + 1) << 56) | ((uint64_t)feat_kind << 54) | ids;
    double nb[3] = {dq[0] / x.dist, dq[1] / x.dist, dq[2] / x.dist};
    gs_dem_wall_point_to_world(w, q, x.cp);
    gs_dem_wall_dir_to_world(w, nb, x.n);
    add_cand(c, nc, &x);
  }
}

/* an overlap with no usable geometry (centre on the axis of an outer cylinder) */
static void analytic_candidate_hit(cand *c, int *nc, int wi) {
  cand x;
  memset(&x, 0, sizeof x);
  x.wall = wi;
  x.feat = -1;
  add_cand(c, nc, &x);
}

/* behind != 0 also reports spheres whose centre is on the wrong side of the
 * wall (insertion must refuse those; the force loop leaves them alone, as a
 * mesh cannot tell its sides apart either). */
static void analytic_candidate(const gs_dem_wall *w, int wi, const double xw[3], double r,
                               cand *c, int *nc, int behind) {
  double pb[3], nb[3], q[3], dist;
  gs_dem_wall_to_body(w, xw, pb);
  double rel[3] = {pb[0] - w->p[0], pb[1] - w->p[1], pb[2] - w->p[2]};
  if (w->kind == GS_DEM_WALL_PLANE) {
    dist = rel[0] * w->n[0] + rel[1] * w->n[1] + rel[2] * w->n[2];
    if (dist >= r || (dist <= 0 && !behind)) return;
    for (int k = 0; k < 3; k++) {
      nb[k] = w->n[k];
      q[k] = pb[k] - dist * w->n[k];
    }
  } else {
    double ax = rel[0] * w->a[0] + rel[1] * w->a[1] + rel[2] * w->a[2];
    double rad[3] = {rel[0] - ax * w->a[0], rel[1] - ax * w->a[1], rel[2] - ax * w->a[2]};
    double rho = sqrt(rad[0] * rad[0] + rad[1] * rad[1] + rad[2] * rad[2]);
    if (rho <= 0) {
      if (behind && !w->inside) analytic_candidate_hit(c, nc, wi);
      return;
    }
    dist = w->inside ? w->R - rho : rho - w->R;
    if (dist >= r || (dist <= 0 && !behind)) return;
    double sgn = w->inside ? -1.0 : 1.0;
    for (int k = 0; k < 3; k++) {
      nb[k] = sgn * rad[k] / rho;
      q[k] = w->p[k] + ax * w->a[k] + rad[k] / rho * w->R;
    }
  }
  cand x;
  x.wall = wi;
  x.feat = -1;
  x.nv = 0;
  x.dist = dist;
  x.key = (uint64_t)(wi + 1) << 56;
  gs_dem_wall_point_to_world(w, q, x.cp);
  gs_dem_wall_dir_to_world(w, nb, x.n);
  add_cand(c, nc, &x);
}

static int shares_vertex(const cand *a, const cand *b) {
  for (int i = 0; i < a->nv; i++)
    for (int j = 0; j < b->nv; j++)
      if (a->v[i] == b->v[j]) return 1;
  return 0;
}

/* Sort by distance, then keep faces and analytic walls, and edge/vertex
 * contacts that share no vertex with a kept contact of the same mesh; in
 * LIGGGHTS mode (`dedup` 0) every contact an owning triangle found. */
static int select_contacts(cand *c, int nc, int dedup) {
  for (int i = 1; i < nc; i++) {
    cand x = c[i];
    int j = i - 1;
    while (j >= 0 && (c[j].dist > x.dist || (c[j].dist == x.dist && c[j].key > x.key))) {
      c[j + 1] = c[j];
      j--;
    }
    c[j + 1] = x;
  }
  int nk = 0;
  for (int i = 0; i < nc; i++) {
    int keep = 1;
    if (dedup && c[i].feat > 0)
      for (int k = 0; k < nk && keep; k++)
        if (c[k].wall == c[i].wall && c[k].feat >= 0 && shares_vertex(&c[k], &c[i])) keep = 0;
    if (keep) c[nk++] = c[i];
  }
  return nk;
}

void gs_dem_wall_forces(gs_dem *d) {
  gs_dem_particles *p = &d->p;
  const size_t n = p->n, nw = d->nwalls;
  if (!n || !nw) return;
  for (size_t w = 0; w < nw; w++) {
    gs_dem_wall_frame(&d->walls[w], d->t);
    memset(d->walls[w].force, 0, sizeof d->walls[w].force);
    memset(d->walls[w].torque, 0, sizeof d->walls[w].torque);
  }
  const int ncl = d->prm.nclass;
  const size_t nctr = nw * (size_t)ncl;
  int nt = n < d->par_min ? 1 : omp_get_max_threads();
  /* per thread: impacts, vn, vn2, vt sums, histogram, wall force+torque */
  const size_t stride = nctr * (4 + GS_DEM_IMPACT_BINS) + 6 * nw;
  double *acc = calloc((size_t)nt * stride, sizeof(double));
  imp_buf *ib = calloc((size_t)nt, sizeof *ib);
  if (!acc || !ib) {
    /* no counters without memory: gs_dem_run reports it */
    d->oom = 1;
    nt = 1;
    free(acc);
    free(ib);
    acc = NULL;
    ib = NULL;
  }
  const double dt = d->prm.dt, dv = d->impact_dv;
  const int liggghts = d->prm.mesh_contacts == GS_DEM_MESH_LIGGGHTS;

#pragma omp parallel num_threads(nt)
  {
    double *my = acc ? acc + (size_t)omp_get_thread_num() * stride : NULL;
    imp_buf *mb = ib ? ib + omp_get_thread_num() : NULL;
    cand c[MAXC];
#pragma omp for schedule(dynamic, 512)
    for (size_t i = 0; i < n; i++) {
      const double xi[3] = {p->x[i], p->y[i], p->z[i]};
      const double r = p->r[i];
      int nc = 0;
      for (size_t w = 0; w < nw; w++) {
        const gs_dem_wall *wl = &d->walls[w];
        if (wl->kind == GS_DEM_WALL_MESH) mesh_candidates(wl, (int)w, xi, r, c, &nc, 1);
        else analytic_candidate(wl, (int)w, xi, r, c, &nc, 0);
      }
      uint64_t *okey = p->wkey + i * GS_DEM_WSLOTS;
      double *oshear = p->wshear + i * 3 * GS_DEM_WSLOTS;
      if (!nc) {
        if (p->wall_mask[i]) {
          p->wall_mask[i] = 0;
          memset(okey, 0, GS_DEM_WSLOTS * sizeof(uint64_t));
        }
        continue;
      }
      nc = select_contacts(c, nc, !liggghts);
      if (nc > GS_DEM_WSLOTS) nc = GS_DEM_WSLOTS;
      uint64_t nkey[GS_DEM_WSLOTS] = {0};
      double nshear[3 * GS_DEM_WSLOTS] = {0};
      uint32_t mask = 0;
      const int ty = p->type[i], cls = d->types[ty].cls;
      for (int k = 0; k < nc; k++) {
        const cand *x = &c[k];
        const gs_dem_wall *wl = &d->walls[x->wall];
        double *sh = nshear + 3 * k;
        nkey[k] = x->key;
        for (int s = 0; s < GS_DEM_WSLOTS; s++)
          if (okey[s] == x->key) {
            memcpy(sh, oshear + 3 * s, 3 * sizeof(double));
            break;
          }
        double vw[3];
        gs_dem_wall_velocity(wl, x->cp, vw);
        const double *nr = x->n, dist = x->dist, delta = r - dist;
        /* lever of the contact point: the wall surface, or LIGGGHTS' r - delta/2 */
        const double lever = liggghts ? r - 0.5 * delta : dist;
        const double vr[3] = {p->vx[i] - vw[0], p->vy[i] - vw[1], p->vz[i] - vw[2]};
        const double vn = vr[0] * nr[0] + vr[1] * nr[1] + vr[2] * nr[2];
        const double wi[3] = {p->wx[i], p->wy[i], p->wz[i]};
        const double wxn[3] = {wi[1] * nr[2] - wi[2] * nr[1], wi[2] * nr[0] - wi[0] * nr[2],
                               wi[0] * nr[1] - wi[1] * nr[0]};
        const double vt[3] = {vr[0] - vn * nr[0] - lever * wxn[0], vr[1] - vn * nr[1] - lever * wxn[1],
                              vr[2] - vn * nr[2] - lever * wxn[2]};
        const uint32_t bit = 1u << x->wall;
        if (!(p->wall_mask[i] & bit) && !(mask & bit) && my) {
          /* a new impact on this wall: book class, normal and tangential speed */
          double vtm = sqrt(vt[0] * vt[0] + vt[1] * vt[1] + vt[2] * vt[2]);
          size_t q = (size_t)x->wall * ncl + cls;
          my[q] += 1;
          my[nctr + q] += fabs(vn);
          my[2 * nctr + q] += vn * vn;
          my[3 * nctr + q] += vtm;
          int b = (int)(fabs(vn) / dv);
          if (b >= GS_DEM_IMPACT_BINS) b = GS_DEM_IMPACT_BINS - 1;
          my[4 * nctr + q * GS_DEM_IMPACT_BINS + b] += 1;
          const double u = sqrt(vr[0] * vr[0] + vr[1] * vr[1] + vr[2] * vr[2]);
          if (u >= GS_DEM_MIN_IMPACT_SPEED) imp_push(mb, p->id[i], (int)q, log(u));
        }
        mask |= bit;
        gs_dem_contact_force cf;
        gs_dem_hertz(&wl->pt[ty], delta, r, p->m[i], nr, vn, vt, sh, dt, &cf);
        const double f[3] = {cf.fn * nr[0] + cf.ft[0], cf.fn * nr[1] + cf.ft[1],
                             cf.fn * nr[2] + cf.ft[2]};
        const double cr[3] = {nr[1] * cf.ft[2] - nr[2] * cf.ft[1], nr[2] * cf.ft[0] - nr[0] * cf.ft[2],
                              nr[0] * cf.ft[1] - nr[1] * cf.ft[0]};
        double rt[3] = {0, 0, 0};
        gs_dem_rolling(wl->pt[ty].mu_r, cf.fe, lever, nr, wi, rt);
        p->fx[i] += f[0];
        p->fy[i] += f[1];
        p->fz[i] += f[2];
        p->tx[i] += -lever * cr[0] + rt[0];
        p->ty[i] += -lever * cr[1] + rt[1];
        p->tz[i] += -lever * cr[2] + rt[2];
        if (my) {
          double *wf = my + nctr * (4 + GS_DEM_IMPACT_BINS) + 6 * (size_t)x->wall;
          const double *o = wl->moving ? wl->shift : wl->origin;
          const double arm[3] = {x->cp[0] - o[0], x->cp[1] - o[1], x->cp[2] - o[2]};
          wf[0] -= f[0];
          wf[1] -= f[1];
          wf[2] -= f[2];
          wf[3] -= arm[1] * f[2] - arm[2] * f[1];
          wf[4] -= arm[2] * f[0] - arm[0] * f[2];
          wf[5] -= arm[0] * f[1] - arm[1] * f[0];
        }
      }
      p->wall_mask[i] = mask;
      memcpy(okey, nkey, sizeof nkey);
      memcpy(oshear, nshear, sizeof nshear);
    }
  }
  if (acc) {
    for (int t = 0; t < nt; t++) {
      const double *a = acc + (size_t)t * stride;
      for (size_t q = 0; q < nctr; q++) {
        d->wall_impacts[q] += (uint64_t)a[q];
        d->wall_vn_sum[q] += a[nctr + q];
        d->wall_vn2_sum[q] += a[2 * nctr + q];
        d->wall_vt_sum[q] += a[3 * nctr + q];
        for (int b = 0; b < GS_DEM_IMPACT_BINS; b++)
          d->impact_hist[q * GS_DEM_IMPACT_BINS + b] +=
              (uint64_t)a[4 * nctr + q * GS_DEM_IMPACT_BINS + b];
      }
      const double *wf = a + nctr * (4 + GS_DEM_IMPACT_BINS);
      for (size_t w = 0; w < nw; w++)
        for (int k = 0; k < 3; k++) {
          d->walls[w].force[k] += wf[6 * w + k];
          d->walls[w].torque[k] += wf[6 * w + 3 + k];
        }
    }
    free(acc);
  }
  if (ib) {
    imp_merge(d, ib, nt);
    for (int t = 0; t < nt; t++) free(ib[t].r);
    free(ib);
  }
}

int gs_dem_touches_wall(gs_dem *d, const double x[3], double r) {
  cand c[MAXC];
  int nc = 0;
  for (size_t w = 0; w < d->nwalls; w++) {
    gs_dem_wall *wl = &d->walls[w];
    gs_dem_wall_frame(wl, d->t);
    if (wl->kind == GS_DEM_WALL_MESH) {
      if (wl->mesh->bin_reach < r) continue; /* cannot happen after gs_dem_prepare */
      mesh_candidates(wl, (int)w, x, r, c, &nc, 0);
    } else {
      analytic_candidate(wl, (int)w, x, r, c, &nc, 1);
    }
    if (nc) return 1;
  }
  return 0;
}
