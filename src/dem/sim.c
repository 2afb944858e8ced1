/* The DEM simulation object: setup (types, walls, particles), the velocity
 * Verlet time loop and read-only views of the state. */
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "dem/dem_internal.h"

static int check_material(const gs_dem_material *m, int wall, gs_error *err) {
  if (!(m->E > 0) || !(m->nu > -1 && m->nu < 0.5) || !(m->e > 0 && m->e <= 1) || !(m->mu_s >= 0) ||
      !(m->mu_r >= 0) || (!wall && !(m->density > 0)))
    return gs_error_set(err, GS_EINPUT,
                        "invalid material: need E > 0, -1 < nu < 0.5, 0 < e <= 1, mu_s >= 0, "
                        "mu_r >= 0%s (got E=%g nu=%g e=%g mu_s=%g mu_r=%g density=%g)",
                        wall ? "" : ", density > 0", m->E, m->nu, m->e, m->mu_s, m->mu_r, m->density);
  return GS_OK;
}

gs_dem *gs_dem_alloc(const gs_dem_params *p, gs_error *err) {
  if (!(p->dt > 0) || !(p->skin > 0) || p->nclass < 1 || p->nclass > 4096)
    return gs_error_set(err, GS_EINPUT, "DEM: need dt > 0, skin > 0 and 1..4096 classes"), NULL;
  for (int a = 0; a < 3; a++)
    if (!(p->hi[a] > p->lo[a]))
      return gs_error_set(err, GS_EINPUT, "DEM: box must have hi > lo on every axis"), NULL;
  gs_dem *d = gs_calloc(1, sizeof *d, err);
  if (!d) return NULL;
  d->prm = *p;
  d->impact_dv = p->impact_dv > 0 ? p->impact_dv : 0.25;
  size_t nc = (size_t)p->nclass, nwc = GS_DEM_MAX_WALLS * nc;
  d->pair_events = calloc(nc * nc, sizeof(uint64_t));
  d->wall_impacts = calloc(nwc, sizeof(uint64_t));
  d->wall_vn_sum = calloc(nwc, sizeof(double));
  d->wall_vn2_sum = calloc(nwc, sizeof(double));
  d->wall_vt_sum = calloc(nwc, sizeof(double));
  d->impact_hist = calloc(nwc * GS_DEM_IMPACT_BINS, sizeof(uint64_t));
  if (!d->pair_events || !d->wall_impacts || !d->wall_vn_sum || !d->wall_vn2_sum ||
      !d->wall_vt_sum || !d->impact_hist) {
    gs_dem_free(d);
    return gs_error_set(err, GS_ENOMEM, "out of memory"), NULL;
  }
  d->need_rebuild = 1;
  d->par_min = 20000;
  return d;
}

void gs_dem_set_parallel_min(gs_dem *d, size_t n) { d->par_min = n; }
size_t gs_dem_parallel_min(const gs_dem *d) { return d->par_min; }

void gs_dem_free(gs_dem *d) {
  if (!d) return;
  gs_dem_particles_free(&d->p);
  gs_dem_particles_free(&d->pend);
  gs_dem_particles_free(&d->tmp);
  for (size_t w = 0; w < d->nwalls; w++) {
    gs_dem_mesh_free(d->walls[w].mesh);
    free(d->walls[w].pt);
  }
  free(d->types);
  free(d->pp);
  free(d->nl_first);
  free(d->nl_j);
  free(d->nl_touch);
  free(d->nl_shear);
  free(d->cell_first);
  free(d->perm);
  free(d->cellof);
  free(d->order);
  free(d->pos);
  free(d->tbuf);
  free(d->pair_events);
  free(d->wall_impacts);
  free(d->wall_vn_sum);
  free(d->wall_vn2_sum);
  free(d->wall_vt_sum);
  free(d->impact_hist);
  free(d->imp_q);
  free(d->imp_lnu);
  free(d->rm_cls);
  free(d->rm_rt);
  free(d->rm_m);
  gs_dem_pair_log_free(d);
  free(d);
}

int gs_dem_add_type(gs_dem *d, const gs_dem_material *m, int size_class, gs_error *err) {
  if (check_material(m, 0, err)) return -1;
  if (size_class < 0 || size_class >= d->prm.nclass) {
    gs_error_set(err, GS_EINPUT, "size class %d outside 0..%d", size_class, d->prm.nclass - 1);
    return -1;
  }
  gs_dem_type *t = realloc(d->types, (d->ntypes + 1) * sizeof *t);
  if (!t) {
    gs_error_set(err, GS_ENOMEM, "out of memory");
    return -1;
  }
  d->types = t;
  t[d->ntypes].mat = *m;
  t[d->ntypes].cls = size_class;
  d->pairs_dirty = 1;
  return (int)d->ntypes++;
}

static gs_dem_wall *new_wall(gs_dem *d, const char *name, const gs_dem_material *m, int kind,
                             gs_error *err) {
  if (check_material(m, 1, err)) return NULL;
  if (d->nwalls >= GS_DEM_MAX_WALLS) {
    gs_error_set(err, GS_EINPUT, "at most %d walls", GS_DEM_MAX_WALLS);
    return NULL;
  }
  gs_dem_wall *w = &d->walls[d->nwalls];
  memset(w, 0, sizeof *w);
  snprintf(w->name, sizeof w->name, "%s", name ? name : "wall");
  w->mat = *m;
  w->kind = kind;
  d->pairs_dirty = 1;
  return w;
}

static int unit(const double v[3], double out[3], const char *what, gs_error *err) {
  double l = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
  if (!(l > 0) || !isfinite(l)) return gs_error_set(err, GS_EINPUT, "%s must be a non-zero vector", what);
  for (int k = 0; k < 3; k++) out[k] = v[k] / l;
  return GS_OK;
}

int gs_dem_add_plane(gs_dem *d, const char *name, const double point[3], const double normal[3],
                     const gs_dem_material *m, gs_error *err) {
  gs_dem_wall *w = new_wall(d, name, m, GS_DEM_WALL_PLANE, err);
  if (!w || unit(normal, w->n, "plane normal", err)) return -1;
  memcpy(w->p, point, sizeof w->p);
  return (int)d->nwalls++;
}

int gs_dem_add_cylinder(gs_dem *d, const char *name, const double point[3], const double axis[3],
                        double radius, int inside, const gs_dem_material *m, gs_error *err) {
  gs_dem_wall *w = new_wall(d, name, m, GS_DEM_WALL_CYLINDER, err);
  if (!w || unit(axis, w->a, "cylinder axis", err)) return -1;
  if (!(radius > 0)) {
    gs_error_set(err, GS_EINPUT, "cylinder radius must be > 0 (got %g)", radius);
    return -1;
  }
  memcpy(w->p, point, sizeof w->p);
  w->R = radius;
  w->inside = inside;
  return (int)d->nwalls++;
}

int gs_dem_add_mesh(gs_dem *d, const char *name, gs_dem_mesh *mesh, const gs_dem_material *m,
                    gs_error *err) {
  const int liggghts = d->prm.mesh_contacts == GS_DEM_MESH_LIGGGHTS;
  gs_dem_wall *w = liggghts && gs_dem_mesh_liggghts_activity(mesh, err)
                       ? NULL
                       : new_wall(d, name, m, GS_DEM_WALL_MESH, err);
  if (!w) {
    gs_dem_mesh_free(mesh);
    return -1;
  }
  w->mesh = mesh;
  return (int)d->nwalls++;
}

int gs_dem_wall_set_motion(gs_dem *d, int wall, const double origin[3], const double axis[3],
                           double omega, const double velocity[3], gs_error *err) {
  if (wall < 0 || (size_t)wall >= d->nwalls) return gs_error_set(err, GS_EINPUT, "no wall %d", wall);
  gs_dem_wall *w = &d->walls[wall];
  if (omega != 0 && unit(axis, w->axis, "rotation axis", err)) return err->code;
  if (omega == 0) w->axis[0] = 1, w->axis[1] = w->axis[2] = 0;
  for (int k = 0; k < 3; k++) {
    w->origin[k] = origin ? origin[k] : 0;
    w->vel[k] = velocity ? velocity[k] : 0;
  }
  w->omega = omega;
  w->moving = omega != 0 || w->vel[0] != 0 || w->vel[1] != 0 || w->vel[2] != 0;
  gs_dem_wall_frame(w, d->t);
  return GS_OK;
}

int gs_dem_wall_set_spin_start(gs_dem *d, int wall, double t_start, gs_error *err) {
  if (wall < 0 || (size_t)wall >= d->nwalls) return gs_error_set(err, GS_EINPUT, "no wall %d", wall);
  if (!(t_start >= 0) || !isfinite(t_start))
    return gs_error_set(err, GS_EINPUT, "wall '%s': rotation start %g s: expected a time >= 0", d->walls[wall].name,
                        t_start);
  d->walls[wall].spin_start = t_start;
  gs_dem_wall_frame(&d->walls[wall], d->t);
  return GS_OK;
}

size_t gs_dem_nwalls(const gs_dem *d) { return d->nwalls; }
const char *gs_dem_wall_name(const gs_dem *d, size_t wall) { return d->walls[wall].name; }

long gs_dem_add_particle(gs_dem *d, int type, double radius, const double x[3], const double v[3],
                         const double w[3], gs_error *err) {
  if (type < 0 || (size_t)type >= d->ntypes) {
    gs_error_set(err, GS_EINPUT, "no particle type %d", type);
    return -1;
  }
  if (!(radius > 0) || !isfinite(x[0] + x[1] + x[2])) {
    gs_error_set(err, GS_EINPUT, "particle needs radius > 0 and a finite position");
    return -1;
  }
  gs_dem_particles *p = &d->pend;
  if (gs_dem_particles_reserve(p, p->n + 1, err)) return -1;
  size_t i = p->n++;
  double mass = d->types[type].mat.density * 4.0 / 3.0 * M_PI * radius * radius * radius;
  p->x[i] = x[0], p->y[i] = x[1], p->z[i] = x[2];
  p->vx[i] = v ? v[0] : 0, p->vy[i] = v ? v[1] : 0, p->vz[i] = v ? v[2] : 0;
  p->wx[i] = w ? w[0] : 0, p->wy[i] = w ? w[1] : 0, p->wz[i] = w ? w[2] : 0;
  p->fx[i] = mass * d->prm.gravity[0];
  p->fy[i] = mass * d->prm.gravity[1];
  p->fz[i] = mass * d->prm.gravity[2];
  p->tx[i] = p->ty[i] = p->tz[i] = 0;
  p->r[i] = radius;
  p->m[i] = mass;
  p->invm[i] = 1.0 / mass;
  p->invI[i] = 1.0 / (0.4 * mass * radius * radius);
  p->x0[i] = x[0], p->y0[i] = x[1], p->z0[i] = x[2];
  p->t_in[i] = d->t;
  p->vs[i] = 4.0 / 3.0 * M_PI * radius * radius * radius;
  p->vl[i] = 0;
  p->type[i] = type;
  p->id[i] = d->next_id;
  p->dead[i] = 0;
  p->wall_mask[i] = 0;
  memset(p->wkey + i * GS_DEM_WSLOTS, 0, GS_DEM_WSLOTS * sizeof(uint64_t));
  memset(p->wshear + i * 3 * GS_DEM_WSLOTS, 0, 3 * GS_DEM_WSLOTS * sizeof(double));
  if (radius > d->rmax) d->rmax = radius;
  return d->next_id++;
}

void gs_dem_remove_if(gs_dem *d, int (*pred)(const double x[3], void *ctx), void *ctx) {
  d->remove_pred = pred;
  d->remove_ctx = ctx;
  d->need_rebuild = 1;
}

/* Everything that depends on the set of types, walls and the largest radius. */
int gs_dem_prepare(gs_dem *d, gs_error *err) {
  if (d->pairs_dirty) {
    int rc = gs_dem_update_pairs(d, err);
    if (rc) return rc;
    d->pairs_dirty = 0;
  }
  for (size_t w = 0; w < d->nwalls; w++) {
    gs_dem_mesh *m = d->walls[w].mesh;
    if (m && m->bin_reach < d->rmax) {
      /* bins sized a little above the largest radius so later insertions of
       * the same sizes do not re-bin */
      int rc = gs_dem_mesh_build_bins(m, d->rmax * 1.05, err);
      if (rc) return rc;
    }
  }
  return GS_OK;
}

static int compute_forces(gs_dem *d, gs_error *err) {
  gs_dem_pair_forces(d);
  gs_dem_wall_forces(d);
  if (d->hooks.forces) {
    gs_dem_view v;
    gs_dem_get_view(d, &v);
    d->hooks.forces(&v, d->p.fx, d->p.fy, d->p.fz, d->hooks.user);
  }
  if (d->oom) return gs_error_set(err, GS_ENOMEM, "DEM: out of memory for the contact counters");
  return GS_OK;
}

int gs_dem_run(gs_dem *d, long nsteps, gs_error *err) {
  int rc = gs_dem_prepare(d, err);
  if (rc) return rc;
  const double dt = d->prm.dt, hdt = 0.5 * dt;
  const double lim = 0.25 * d->prm.skin * d->prm.skin;
  const double g0 = d->prm.gravity[0], g1 = d->prm.gravity[1], g2 = d->prm.gravity[2];
  if (d->step == 0 && nsteps >= 0 && gs_dem_needs_rebuild(d)) {
    /* the very first step needs the initial contact forces for its first kick
     * (this may happen twice at t = 0, e.g. a feed after the fill: start over) */
    if ((rc = gs_dem_rebuild(d, err))) return rc;
    gs_dem_particles *p = &d->p;
    for (size_t i = 0; i < p->n; i++) {
      p->fx[i] = p->m[i] * g0;
      p->fy[i] = p->m[i] * g1;
      p->fz[i] = p->m[i] * g2;
      p->tx[i] = p->ty[i] = p->tz[i] = 0;
    }
    if ((rc = compute_forces(d, err))) return rc;
  }
  for (long s = 0; s < nsteps; s++) {
    gs_dem_particles *p = &d->p;
    size_t n = p->n;
    double maxd2 = 0;
    /* first half kick + drift; forces restart from gravity */
#pragma omp parallel for reduction(max : maxd2) schedule(static) if (n >= d->par_min)
    for (size_t i = 0; i < n; i++) {
      const double im = p->invm[i], iI = p->invI[i];
      p->vx[i] += hdt * p->fx[i] * im;
      p->vy[i] += hdt * p->fy[i] * im;
      p->vz[i] += hdt * p->fz[i] * im;
      p->wx[i] += hdt * p->tx[i] * iI;
      p->wy[i] += hdt * p->ty[i] * iI;
      p->wz[i] += hdt * p->tz[i] * iI;
      p->x[i] += dt * p->vx[i];
      p->y[i] += dt * p->vy[i];
      p->z[i] += dt * p->vz[i];
      const double mi = p->m[i];
      p->fx[i] = mi * g0;
      p->fy[i] = mi * g1;
      p->fz[i] = mi * g2;
      p->tx[i] = p->ty[i] = p->tz[i] = 0;
      const double ex = p->x[i] - p->x0[i], ey = p->y[i] - p->y0[i], ez = p->z[i] - p->z0[i];
      const double d2 = ex * ex + ey * ey + ez * ez;
      if (d2 > maxd2) maxd2 = d2;
    }
    d->t += dt;
    d->step++;
    d->since_rebuild++;
    /* removal regions act at rebuilds; a quiet bed still gets one every 200 steps */
    if (maxd2 > lim || !(maxd2 == maxd2) || gs_dem_needs_rebuild(d) ||
        (d->remove_pred && d->since_rebuild >= 200)) {
      if (d->pend.n) {
        if ((rc = gs_dem_prepare(d, err))) return rc;
      }
      if ((rc = gs_dem_rebuild(d, err))) return rc;
      d->since_rebuild = 0;
      p = &d->p;
      n = p->n;
    }
    if ((rc = compute_forces(d, err))) return rc;
    int bad = 0;
#pragma omp parallel for reduction(| : bad) schedule(static) if (n >= d->par_min)
    for (size_t i = 0; i < n; i++) {
      const double im = p->invm[i], iI = p->invI[i];
      p->vx[i] += hdt * p->fx[i] * im;
      p->vy[i] += hdt * p->fy[i] * im;
      p->vz[i] += hdt * p->fz[i] * im;
      p->wx[i] += hdt * p->tx[i] * iI;
      p->wy[i] += hdt * p->ty[i] * iI;
      p->wz[i] += hdt * p->tz[i] * iI;
      bad |= !isfinite(p->vx[i] + p->vy[i] + p->vz[i]);
    }
    if (bad)
      return gs_error_set(err, GS_ENUMERIC,
                          "DEM: non-finite velocity at t = %g s (step %ld); the time step is "
                          "probably too large for the stiffness", d->t, d->step);
    if (d->hooks.after_step && (rc = d->hooks.after_step(d, d->hooks.user, err))) return rc;
  }
  return GS_OK;
}

void gs_dem_set_hooks(gs_dem *d, const gs_dem_hooks *h) {
  if (h)
    d->hooks = *h;
  else
    memset(&d->hooks, 0, sizeof d->hooks);
}

void gs_dem_get_view(const gs_dem *d, gs_dem_view *v) {
  const gs_dem_particles *p = &d->p;
  v->n = p->n;
  v->x = p->x, v->y = p->y, v->z = p->z;
  v->vx = p->vx, v->vy = p->vy, v->vz = p->vz;
  v->wx = p->wx, v->wy = p->wy, v->wz = p->wz;
  v->r = p->r, v->m = p->m, v->type = p->type, v->id = p->id, v->t_in = p->t_in;
  v->vs = p->vs, v->vl = p->vl;
}

double gs_dem_time(const gs_dem *d) { return d->t; }
double gs_dem_dt(const gs_dem *d) { return d->prm.dt; }
void gs_dem_get_params(const gs_dem *d, gs_dem_params *p) { *p = d->prm; }
long gs_dem_step_count(const gs_dem *d) { return d->step; }
int gs_dem_type_class(const gs_dem *d, int type) { return d->types[type].cls; }
size_t gs_dem_ntypes(const gs_dem *d) { return d->ntypes; }

void gs_dem_get_counters(const gs_dem *d, gs_dem_counters *c) {
  c->nclass = d->prm.nclass;
  c->nwalls = d->nwalls;
  c->pair_events = d->pair_events;
  c->wall_impacts = d->wall_impacts;
  c->wall_vn_sum = d->wall_vn_sum;
  c->wall_vn2_sum = d->wall_vn2_sum;
  c->wall_vt_sum = d->wall_vt_sum;
  c->lost = d->lost;
  c->rebuilds = d->rebuilds;
  c->t0 = d->t_reset;
}

void gs_dem_counters_reset(gs_dem *d) {
  size_t nc = (size_t)d->prm.nclass, nwc = GS_DEM_MAX_WALLS * nc;
  memset(d->pair_events, 0, nc * nc * sizeof(uint64_t));
  memset(d->wall_impacts, 0, nwc * sizeof(uint64_t));
  memset(d->wall_vn_sum, 0, nwc * sizeof(double));
  memset(d->wall_vn2_sum, 0, nwc * sizeof(double));
  memset(d->wall_vt_sum, 0, nwc * sizeof(double));
  memset(d->impact_hist, 0, nwc * GS_DEM_IMPACT_BINS * sizeof(uint64_t));
  d->nimp = 0;
  d->t_reset = d->t;
}

size_t gs_dem_impact_speeds(const gs_dem *d, const int **wall_class, const double **ln_u) {
  *wall_class = d->imp_q;
  *ln_u = d->imp_lnu;
  return d->nimp;
}

const uint64_t *gs_dem_impact_histogram(const gs_dem *d, size_t wall, int cls, int *nbins,
                                        double *dv) {
  *nbins = GS_DEM_IMPACT_BINS;
  *dv = d->impact_dv;
  return d->impact_hist + (wall * (size_t)d->prm.nclass + (size_t)cls) * GS_DEM_IMPACT_BINS;
}

size_t gs_dem_ncontacts(const gs_dem *d) {
  if (!d->nl_first || !d->p.n) return 0;
  size_t c = 0, ne = (size_t)d->nl_first[d->p.n];
  for (size_t k = 0; k < ne; k++) c += d->nl_touch[k];
  return c;
}

void gs_dem_kinetic_energy(const gs_dem *d, double *trans, double *rot) {
  const gs_dem_particles *p = &d->p;
  double et = 0, er = 0;
  for (size_t i = 0; i < p->n; i++) {
    et += 0.5 * p->m[i] * (p->vx[i] * p->vx[i] + p->vy[i] * p->vy[i] + p->vz[i] * p->vz[i]);
    er += 0.5 / p->invI[i] * (p->wx[i] * p->wx[i] + p->wy[i] * p->wy[i] + p->wz[i] * p->wz[i]);
  }
  *trans = et;
  *rot = er;
}

size_t gs_dem_wall_triangles(const gs_dem *d, size_t wall, double *out) {
  const gs_dem_wall *w = &d->walls[wall];
  if (w->kind != GS_DEM_WALL_MESH) return 0;
  if (!out) return w->mesh->ntri;
  gs_dem_wall tmp = *w;
  gs_dem_wall_frame(&tmp, d->t);
  for (size_t k = 0; k < 3 * w->mesh->ntri; k++)
    gs_dem_wall_point_to_world(&tmp, w->mesh->v + 3 * k, out + 3 * k);
  return w->mesh->ntri;
}

size_t gs_dem_take_removed(gs_dem *d, const int **cls, const double **residence,
                           const double **mass) {
  size_t n = d->nrm;
  *cls = d->rm_cls;
  *residence = d->rm_rt;
  *mass = d->rm_m;
  d->nrm = 0; /* the arrays stay valid until the next rebuild */
  return n;
}

double gs_dem_wall_axial_torque(const gs_dem *d, size_t wall) {
  const gs_dem_wall *w = &d->walls[wall];
  return w->torque[0] * w->axis[0] + w->torque[1] * w->axis[1] + w->torque[2] * w->axis[2];
}
