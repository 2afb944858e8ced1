/* The particle side of the coupling: void fraction and drag coefficients
 * deposited on the gas grid, the forces interpolated back, and the DEM hooks
 * that hold them between gas steps.  Deposit and interpolation use the same
 * trilinear weights, so the drag the particles receive is what the gas
 * loses (docs/models.md, "CFD-DEM"). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cfd/cfd_internal.h"

/* Cells up to 2 diameters wide make the deposited void fraction too rough for
 * a drag closure fitted to bed averages; beyond 50 the cell no longer
 * resolves the bed at all. */
#define MIN_CELL_DIAMETERS 2.0
#define MAX_CELL_DIAMETERS 50.0

/* Linear weights of coordinate s (in lattice units, nodes at integers) on
 * the nodes first..last, clamped to the end nodes. */
static void lin(double s, long first, long last, long idx[2], double w[2]) {
  if (s <= first || last == first) {
    idx[0] = idx[1] = first;
    w[0] = 1, w[1] = 0;
    return;
  }
  if (s >= last) {
    idx[0] = idx[1] = last;
    w[0] = 1, w[1] = 0;
    return;
  }
  long i = (long)floor(s);
  if (i > last - 1) i = last - 1;
  idx[0] = i, idx[1] = i + 1;
  w[1] = s - (double)i;
  w[0] = 1 - w[1];
}

/* Weights on the faces of one axis that the gas moves (interior faces and
 * the outlet; the wall and inlet faces only where an axis has no other), so
 * a particle's drag is felt by the gas, not by a wall or the distributor. */
void gs_cfd_stencil_at(const gs_cfd *g, int axis, const double x[3], gs_cfd_stencil *s) {
  long id[3][2];
  double w[3][2];
  long m[3];
  for (int d = 0; d < 3; d++) {
    m[d] = g->n[d] + (d == axis);
    long first = 0, last = m[d] - 1;
    double off = 0.5;
    if (d == axis) {
      off = 0;
      first = 1;
      last = axis == 2 ? g->n[2] : g->n[d] - 1;
      if (last < first) first = 0, last = m[d] - 1;
    }
    lin((x[d] - g->prm.lo[d]) / g->h[d] - off, first, last, id[d], w[d]);
  }
  int q = 0;
  for (int c = 0; c < 2; c++)
    for (int b = 0; b < 2; b++)
      for (int a = 0; a < 2; a++, q++) {
        s->idx[q] = id[0][a] + m[0] * (id[1][b] + m[1] * id[2][c]);
        s->w[q] = w[0][a] * w[1][b] * w[2][c];
      }
}

/* Share of a sphere of radius r whose centre is s from a plane (s < 0: the
 * centre is beyond it) lying on the centre's side: 1 - cap volume. */
static double side_share(double s, double r) {
  if (s >= r) return 1;
  const double hc = r - s; /* height of the cap beyond the plane */
  return 1 - hc * hc * (3 * r - hc) / (4 * r * r * r);
}

/* The shares of a sphere's volume in the (at most 2 per axis, the cells being
 * 2 diameters or more) cells it overlaps. */
static void divide_volume(const gs_cfd *g, const double x[3], double r, gs_cfd_stencil *st) {
  long id[3][2];
  double w[3][2];
  for (int a = 0; a < 3; a++) {
    const double s = (x[a] - g->prm.lo[a]) / g->h[a];
    long c = (long)floor(s);
    if (c > g->n[a] - 1) c = g->n[a] - 1;
    if (c < 0) c = 0;
    const double below = x[a] - (g->prm.lo[a] + c * g->h[a]), above = g->prm.lo[a] + (c + 1) * g->h[a] - x[a];
    id[a][0] = id[a][1] = c;
    w[a][0] = 1, w[a][1] = 0;
    if (below < r && c > 0) { /* part of it in the cell below */
      w[a][1] = 1 - side_share(below, r);
      id[a][1] = c - 1;
    } else if (above < r && c < g->n[a] - 1) {
      w[a][1] = 1 - side_share(above, r);
      id[a][1] = c + 1;
    }
    w[a][0] = 1 - w[a][1];
  }
  int q = 0;
  for (int c = 0; c < 2; c++)
    for (int b = 0; b < 2; b++)
      for (int a = 0; a < 2; a++, q++) {
        st->idx[q] = id[0][a] + (long)g->n[0] * (id[1][b] + (long)g->n[1] * id[2][c]);
        st->w[q] = w[0][a] * w[1][b] * w[2][c];
      }
}

static double interp(const gs_cfd_stencil *s, const double *f) {
  double v = 0;
  for (int q = 0; q < 8; q++) v += s->w[q] * f[s->idx[q]];
  return v;
}

/* The interstitial gas velocity (axis a) at particle i: the superficial
 * velocity eps_f u_f interpolated from the faces, over the particle's void
 * fraction.  In a uniform stream eps u is the same on every face, so a
 * particle at the edge of a bed sees the bed's interstitial velocity, not a
 * mean with the freeboard's. */
static double gas_at(const gs_cfd *g, size_t i, int a) {
  const gs_cfd_stencil *s = &g->st_face[a][i];
  double v = 0;
  for (int q = 0; q < 8; q++) v += s->w[q] * g->ef[a][s->idx[q]] * g->u[a][s->idx[q]];
  return v / g->epsp[i];
}

static int reserve(gs_cfd *g, size_t n, long max_id, gs_error *err) {
  if (n > g->pcap) {
    size_t cap = n + n / 2 + 16;
    free(g->beta);
    free(g->epsp);
    free(g->st_cell);
    g->beta = gs_malloc(cap * sizeof(double), err);
    g->epsp = gs_malloc(cap * sizeof(double), err);
    g->st_cell = gs_malloc(cap * sizeof(gs_cfd_stencil), err);
    int ok = g->beta && g->epsp && g->st_cell;
    for (int a = 0; a < 3; a++) {
      free(g->st_face[a]);
      g->st_face[a] = ok ? gs_malloc(cap * sizeof(gs_cfd_stencil), err) : NULL;
      ok = ok && g->st_face[a];
    }
    if (!ok) {
      g->pcap = 0;
      return GS_ENOMEM;
    }
    g->pcap = cap;
  }
  if (max_id >= g->force_cap) {
    long cap = max_id + max_id / 2 + 64;
    double *f = realloc(g->force, (size_t)cap * 3 * sizeof(double));
    if (!f) return gs_error_set(err, GS_ENOMEM, "out of memory");
    memset(f + 3 * g->force_cap, 0, (size_t)(cap - g->force_cap) * 3 * sizeof(double));
    g->force = f;
    g->force_cap = cap;
  }
  return GS_OK;
}

/* Where a particle may be: inside the box, within a cell's reach per gas
 * step, of a size the cells suit. */
static int check_particle(const gs_cfd *g, const gs_dem_view *v, size_t i, gs_error *err) {
  const double x[3] = {v->x[i], v->y[i], v->z[i]}, d = 2 * v->r[i];
  for (int a = 0; a < 3; a++)
    if (!(x[a] >= g->prm.lo[a] && x[a] <= g->prm.hi[a]))
      return gs_error_set(err, GS_ENUMERIC,
                          "gas step %ld (t = %g s): particle %ld left the gas domain at (%g, %g, %g) m "
                          "(gas.box %c from %g to %g m)",
                          g->steps, g->t, v->id[i], x[0], x[1], x[2], "xyz"[a], g->prm.lo[a], g->prm.hi[a]);
  /* the particle CFL: a particle crossing more than one cell per gas step
   * would skip the cells its volume and drag are deposited in */
  const double vel[3] = {v->vx[i], v->vy[i], v->vz[i]};
  for (int a = 0; a < 3; a++) {
    const double cfl = fabs(vel[a]) * g->prm.dt / g->h[a];
    if (!(cfl <= 1))
      return gs_error_set(err, GS_ENUMERIC,
                          "gas step %ld (t = %g s): particle %ld crosses %.4g cells per gas step along %c "
                          "(v = %g m/s, cells %g m): above the limit 1; reduce gas.time_step or use larger cells",
                          g->steps, g->t, v->id[i], cfl, "xyz"[a], vel[a], g->h[a]);
  }
  for (int a = 0; a < 3; a++) {
    if (g->h[a] < MIN_CELL_DIAMETERS * d)
      return gs_error_set(err, GS_EINPUT,
                          "gas step %ld (t = %g s): gas cells are %g m along %c, %.4g diameters of particle "
                          "%ld (d = %g m); the drag closure needs at least %g: use fewer gas.cells",
                          g->steps, g->t, g->h[a], "xyz"[a], g->h[a] / d, v->id[i], d, MIN_CELL_DIAMETERS);
    if (g->h[a] > MAX_CELL_DIAMETERS * d && g->prm.coupling == GS_CFD_TWO_WAY)
      return gs_error_set(err, GS_EINPUT,
                          "gas step %ld (t = %g s): gas cells are %g m along %c, %.4g diameters of particle "
                          "%ld (d = %g m); more than %g do not resolve the bed: use more gas.cells",
                          g->steps, g->t, g->h[a], "xyz"[a], g->h[a] / d, v->id[i], d, MAX_CELL_DIAMETERS);
  }
  return GS_OK;
}

int gs_cfd_step(gs_cfd *g, const gs_dem_view *v, gs_error *err) {
  const size_t n = v->n;
  long max_id = -1;
  for (size_t i = 0; i < n; i++) max_id = v->id[i] > max_id ? v->id[i] : max_id;
  int rc = reserve(g, n, max_id, err);
  if (rc) return rc;
  const int two_way = g->prm.coupling == GS_CFD_TWO_WAY;
  for (size_t i = 0; i < n; i++)
    if ((rc = check_particle(g, v, i, err))) return rc;
  /* void fraction: each sphere's volume divided between the cells it
   * overlaps (per axis, the exact share of a sphere on either side of a
   * plane; their product for the corners), so a particle inside one cell
   * counts in that cell only and the volume is kept exactly; the drag sees
   * the void fraction averaged with the same shares */
  memcpy(g->eps_old, g->eps, g->ncell * sizeof(double));
  for (size_t c = 0; c < g->ncell; c++) g->eps[c] = 1;
  /* the stencils, each particle's own, on threads; the deposits that sum
   * over particles stay in view order on one thread, so every result is
   * the same on any number of threads (bit for bit, tests/test_cfd.c) */
#pragma omp parallel for schedule(static) if (n >= g->par_min)
  for (size_t i = 0; i < n; i++) {
    const double x[3] = {v->x[i], v->y[i], v->z[i]};
    divide_volume(g, x, v->r[i], &g->st_cell[i]);
    for (int a = 0; a < 3; a++) gs_cfd_stencil_at(g, a, x, &g->st_face[a][i]);
  }
  for (size_t i = 0; i < n && two_way; i++) {
    const double vp = 4.0 / 3.0 * M_PI * v->r[i] * v->r[i] * v->r[i] / g->vol;
    for (int q = 0; q < 8; q++) g->eps[g->st_cell[i].idx[q]] -= g->st_cell[i].w[q] * vp;
  }
  for (size_t c = 0; c < g->ncell; c++)
    if (!(g->eps[c] > 0)) {
      const int i = (int)(c % (size_t)g->n[0]), j = (int)(c / (size_t)g->n[0] % (size_t)g->n[1]),
                k = (int)(c / ((size_t)g->n[0] * g->n[1]));
      return gs_error_set(err, GS_ENUMERIC,
                          "gas step %ld (t = %g s): void fraction %g <= 0 in gas cell (%d, %d, %d): the "
                          "particles there overfill it; use larger cells (fewer gas.cells)",
                          g->steps, g->t, g->eps[c], i, j, k);
    }
  if (g->steps == 0) memcpy(g->eps_old, g->eps, g->ncell * sizeof(double));
  gs_cfd_face_void_fractions(g);
  /* drag coefficients from the gas as it is, deposited on the faces */
  for (int a = 0; a < 3; a++) {
    memset(g->k[a], 0, g->nface[a] * sizeof(double));
    memset(g->kv[a], 0, g->nface[a] * sizeof(double));
  }
#pragma omp parallel for schedule(static) if (n >= g->par_min)
  for (size_t i = 0; i < n; i++) {
    const double vel[3] = {v->vx[i], v->vy[i], v->vz[i]};
    g->epsp[i] = interp(&g->st_cell[i], g->eps);
    double s2 = 0;
    for (int a = 0; a < 3; a++) {
      const double du = gas_at(g, i, a) - vel[a];
      s2 += du * du;
    }
    const gs_cfd_drag_in in = {.eps = g->epsp[i], .d = 2 * v->r[i], .slip = sqrt(s2),
                               .rho = g->prm.rho, .mu = g->prm.mu};
    g->beta[i] = g->prm.drag->beta(&in);
  }
  for (size_t i = 0; i < n; i++) {
    const double vel[3] = {v->vx[i], v->vy[i], v->vz[i]};
    const double b = g->beta[i];
    /* the drag is held over the DEM steps of a gas step: explicit in the
     * particle velocity, stable only if the step is below m / beta */
    if (!(b * g->prm.dt < v->m[i]))
      return gs_error_set(err, GS_ENUMERIC,
                          "gas step %ld (t = %g s): gas.time_step %g s is above the drag response time "
                          "m/beta = %g s of particle %ld (d = %g m, void fraction %g): reduce gas.time_step",
                          g->steps, g->t, g->prm.dt, v->m[i] / b, v->id[i], 2 * v->r[i], g->epsp[i]);
    if (!two_way) continue;
    for (int a = 0; a < 3; a++)
      for (int q = 0; q < 8; q++) {
        const long f = g->st_face[a][i].idx[q];
        const double wb = g->st_face[a][i].w[q] * b / g->vol;
        g->k[a][f] += wb * g->ef[a][f] / g->epsp[i];
        g->kv[a][f] += wb * vel[a];
      }
  }
  if ((rc = gs_cfd_gas_step(g, err))) return rc;
  /* the forces held until the next step: drag with the new gas velocity and
   * the pressure gradient (interpolated from the faces) */
  double *grad[3];
  for (int a = 0; a < 3; a++) grad[a] = g->a[a]; /* reused as scratch below */
  for (int a = 0; a < 3; a++) {
    const int m[3] = {g->n[0] + (a == 0), g->n[1] + (a == 1), g->n[2] + (a == 2)};
    const size_t stride = a == 0 ? 1 : a == 1 ? (size_t)g->n[0] : (size_t)g->n[0] * g->n[1];
    for (int k = 0; k < m[2]; k++)
      for (int j = 0; j < m[1]; j++)
        for (int i = 0; i < m[0]; i++) {
          const int cc[3] = {i, j, k};
          const size_t f = gs_cfd_face_index(g, a, i, j, k);
          const size_t cup = (size_t)(cc[0] - (a == 0 && i == m[0] - 1)) +
                             (size_t)g->n[0] * ((size_t)(cc[1] - (a == 1 && j == m[1] - 1)) +
                                                (size_t)g->n[1] * (size_t)(cc[2] - (a == 2 && k == m[2] - 1)));
          double gr;
          if (cc[a] > 0 && cc[a] < g->n[a])
            gr = (g->p[cup] - g->p[cup - stride]) / g->h[a];
          else if (a == 2 && cc[a] == g->n[a])
            gr = -g->p[cup] / (0.5 * g->h[a]);
          else if (a == 2) /* the inlet: the gradient of the face above */
            gr = g->n[2] > 1 ? (g->p[cup + stride] - g->p[cup]) / g->h[a] : -g->p[cup] / (0.5 * g->h[a]);
          else
            gr = 0; /* a wall: no flow through it, no gradient across it */
          grad[a][f] = gr;
        }
  }
#pragma omp parallel for schedule(static) if (n >= g->par_min)
  for (size_t i = 0; i < n; i++) {
    const double vel[3] = {v->vx[i], v->vy[i], v->vz[i]};
    const double vp = 4.0 / 3.0 * M_PI * v->r[i] * v->r[i] * v->r[i];
    double *f = g->force + 3 * v->id[i];
    for (int a = 0; a < 3; a++)
      f[a] = g->beta[i] * (gas_at(g, i, a) - vel[a]) - vp * interp(&g->st_face[a][i], grad[a]);
  }
  /* the drag the particles received, summed in view order (the same
   * expression as above, so it matches the forces bit for bit) */
  double exp_[3] = {0, 0, 0};
  for (size_t i = 0; i < n && two_way; i++) {
    const double vel[3] = {v->vx[i], v->vy[i], v->vz[i]};
    for (int a = 0; a < 3; a++) exp_[a] += g->beta[i] * (gas_at(g, i, a) - vel[a]);
  }
  /* what the gas lost: its sinks k u - kv over every face */
  for (int a = 0; a < 3; a++) {
    double s = 0;
    for (size_t f = 0; f < g->nface[a]; f++) s += (g->k[a][f] * g->u[a][f] - g->kv[a][f]) * g->vol;
    g->ex_gas[a] = s;
    g->ex_part[a] = exp_[a];
  }
  g->steps++;
  return gs_cfd_write_outputs(g, v, err);
}
