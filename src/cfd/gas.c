/* The gas phase: fields on the staggered grid and one projection step
 * (docs/models.md, "CFD-DEM").  The drag sinks (k, kv) and the void fractions
 * are set by particles.c before each step. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cfd/cfd_internal.h"

size_t gs_cfd_face_index(const gs_cfd *g, int axis, int i, int j, int k) {
  const int m0 = g->n[0] + (axis == 0), m1 = g->n[1] + (axis == 1);
  return (size_t)i + (size_t)m0 * ((size_t)j + (size_t)m1 * (size_t)k);
}

int gs_cfd_face_solved(const gs_cfd *g, int axis, int i, int j, int k) {
  const int c[3] = {i, j, k};
  if (axis < 2) return c[axis] > 0 && c[axis] < g->n[axis]; /* side walls */
  return c[2] > 0;                                           /* inlet below, outlet solved */
}

gs_cfd *gs_cfd_create(const gs_cfd_params *p, gs_error *err) {
  for (int a = 0; a < 3; a++) {
    if (p->n[a] < 1 || !(p->hi[a] > p->lo[a]))
      return gs_error_set(err, GS_EINPUT, "gas: need cells >= 1 and hi > lo on every axis"), NULL;
  }
  if (!(p->rho > 0) || !(p->mu > 0) || !(p->dt > 0) || !p->drag || !isfinite(p->u_inlet))
    return gs_error_set(err, GS_EINPUT, "gas: need density > 0, viscosity > 0, time_step > 0, a drag law"),
           NULL;
  gs_cfd *g = gs_calloc(1, sizeof *g, err);
  if (!g) return NULL;
  g->prm = *p;
  /* per-particle loops on threads from 1024 particles until attached to a DEM,
   * whose dem.threads_from then decides */
  g->par_min = 1024;
  if (!(g->prm.tol > 0)) g->prm.tol = 1e-10;
  if (g->prm.max_iter <= 0) g->prm.max_iter = 500;
  g->ncell = 1;
  g->vol = 1;
  for (int a = 0; a < 3; a++) {
    g->n[a] = p->n[a];
    g->h[a] = (p->hi[a] - p->lo[a]) / p->n[a];
    g->ncell *= (size_t)p->n[a];
    g->vol *= g->h[a];
  }
  int ok = (g->eps = gs_malloc(g->ncell * sizeof(double), err)) &&
           (g->eps_old = gs_malloc(g->ncell * sizeof(double), err)) &&
           (g->p = gs_calloc(g->ncell, sizeof(double), err)) &&
           (g->rhs = gs_calloc(g->ncell, sizeof(double), err)) &&
           (g->nb = gs_calloc(6 * g->ncell, sizeof(double), err)) &&
           (g->diag = gs_calloc(g->ncell, sizeof(double), err));
  for (int a = 0; a < 3 && ok; a++) {
    g->nface[a] = g->ncell / (size_t)g->n[a] * (size_t)(g->n[a] + 1);
    ok = (g->u[a] = gs_calloc(g->nface[a], sizeof(double), err)) &&
         (g->k[a] = gs_calloc(g->nface[a], sizeof(double), err)) &&
         (g->kv[a] = gs_calloc(g->nface[a], sizeof(double), err)) &&
         (g->a[a] = gs_calloc(g->nface[a], sizeof(double), err)) &&
         (g->dg[a] = gs_calloc(g->nface[a], sizeof(double), err)) &&
         (g->ex[a] = gs_calloc(g->nface[a], sizeof(double), err)) &&
         (g->ef[a] = gs_calloc(g->nface[a], sizeof(double), err));
  }
  if (ok) ok = (g->ps = gs_cfd_pressure_create(g->n, err)) != NULL;
  if (!ok) {
    gs_cfd_free(g);
    return NULL;
  }
  for (size_t c = 0; c < g->ncell; c++) g->eps[c] = g->eps_old[c] = 1;
  /* the gas starts at the inlet's interstitial velocity everywhere */
  for (size_t f = 0; f < g->nface[2]; f++) g->u[2][f] = p->u_inlet;
  return g;
}

void gs_cfd_free(gs_cfd *g) {
  if (!g) return;
  if (g->dem) gs_dem_set_hooks(g->dem, NULL);
  gs_cfd_pressure_free(g->ps);
  free(g->eps);
  free(g->eps_old);
  free(g->p);
  free(g->rhs);
  free(g->nb);
  free(g->diag);
  for (int a = 0; a < 3; a++) {
    free(g->u[a]);
    free(g->k[a]);
    free(g->kv[a]);
    free(g->a[a]);
    free(g->dg[a]);
    free(g->ex[a]);
    free(g->ef[a]);
    free(g->st_face[a]);
  }
  free(g->st_cell);
  free(g->beta);
  free(g->epsp);
  free(g->force);
  free(g->vtk_t);
  if (g->csv) fclose(g->csv);
  free(g);
}

/* Void fraction on a face: the mean of its two cells, or its one cell. */
static double face_eps(const gs_cfd *g, int axis, int i, int j, int k) {
  int c[3] = {i, j, k};
  const int hiside = c[axis] < g->n[axis];
  int lo[3] = {i, j, k};
  lo[axis] -= 1;
  const size_t up = hiside ? (size_t)c[0] + (size_t)g->n[0] * ((size_t)c[1] + (size_t)g->n[1] * c[2]) : 0;
  const size_t dn = lo[axis] >= 0 ? (size_t)lo[0] + (size_t)g->n[0] * ((size_t)lo[1] + (size_t)g->n[1] * lo[2]) : 0;
  if (hiside && lo[axis] >= 0) return 0.5 * (g->eps[up] + g->eps[dn]);
  return hiside ? g->eps[up] : g->eps[dn];
}

void gs_cfd_face_void_fractions(gs_cfd *g) {
  for (int a = 0; a < 3; a++) {
    const int m[3] = {g->n[0] + (a == 0), g->n[1] + (a == 1), g->n[2] + (a == 2)};
    for (int k = 0; k < m[2]; k++)
      for (int j = 0; j < m[1]; j++)
        for (int i = 0; i < m[0]; i++) g->ef[a][gs_cfd_face_index(g, a, i, j, k)] = face_eps(g, a, i, j, k);
  }
}

/* The gas-velocity limit: gas crossing more than one cell per step would
 * skip cells of the void fraction and drag it is coupled through. */
static int check_cfl(const gs_cfd *g, gs_error *err) {
  for (int a = 0; a < 3; a++) {
    const int m[3] = {g->n[0] + (a == 0), g->n[1] + (a == 1), g->n[2] + (a == 2)};
    for (int k = 0; k < m[2]; k++)
      for (int j = 0; j < m[1]; j++)
        for (int i = 0; i < m[0]; i++) {
          const double cfl = fabs(g->u[a][gs_cfd_face_index(g, a, i, j, k)]) * g->prm.dt / g->h[a];
          if (cfl > 1)
            return gs_error_set(err, GS_ENUMERIC,
                                "gas step %ld (t = %g s): the gas crosses %.4g cells per step at the %c "
                                "face (%d, %d, %d) (u = %g m/s): above the limit 1; reduce gas.time_step "
                                "or use larger cells", g->steps, g->t, cfl, "xyz"[a], i, j, k,
                                g->u[a][gs_cfd_face_index(g, a, i, j, k)]);
        }
  }
  return GS_OK;
}

int gs_cfd_gas_step(gs_cfd *g, gs_error *err) {
  const double dt = g->prm.dt, rho = g->prm.rho;
  const int n0 = g->n[0], n1 = g->n[1], n2 = g->n[2];
  memset(g->nb, 0, 6 * g->ncell * sizeof(double));
  memset(g->diag, 0, g->ncell * sizeof(double));
  memset(g->rhs, 0, g->ncell * sizeof(double));
  /* the boundary faces: walls at rest, the distributor's superficial velocity */
  for (int a = 0; a < 3; a++) {
    const int m[3] = {n0 + (a == 0), n1 + (a == 1), n2 + (a == 2)};
    for (int k = 0; k < m[2]; k++)
      for (int j = 0; j < m[1]; j++)
        for (int i = 0; i < m[0]; i++)
          if (!gs_cfd_face_solved(g, a, i, j, k)) {
            const size_t f = gs_cfd_face_index(g, a, i, j, k);
            g->u[a][f] = a == 2 ? g->prm.u_inlet / g->ef[a][f] : 0;
            g->a[a][f] = 0;
          }
  }
  gs_cfd_transport(g);
  /* predictor: u* with drag, convection and viscous diagonals implicit,
   * stored in u; a = eps_f / A */
  for (int a = 0; a < 3; a++) {
    const int m[3] = {n0 + (a == 0), n1 + (a == 1), n2 + (a == 2)};
#pragma omp parallel for collapse(2) schedule(static) if (g->nface[a] >= 4096)
    for (int k = 0; k < m[2]; k++)
      for (int j = 0; j < m[1]; j++)
        for (int i = 0; i < m[0]; i++) {
          if (!gs_cfd_face_solved(g, a, i, j, k)) continue;
          const size_t f = gs_cfd_face_index(g, a, i, j, k);
          const double ef = g->ef[a][f];
          const double A = ef * rho / dt + g->k[a][f] + g->dg[a][f];
          g->u[a][f] = (ef * rho * g->u[a][f] / dt + ef * rho * g->prm.gravity[a] + g->kv[a][f] +
                        g->ex[a][f]) / A;
          g->a[a][f] = ef / A;
        }
  }
  /* the pressure equation: div(eps u) = -(eps - eps_old) / dt */
  for (int k = 0; k < n2; k++)
    for (int j = 0; j < n1; j++)
      for (int i = 0; i < n0; i++) {
        const size_t c = (size_t)i + (size_t)n0 * ((size_t)j + (size_t)n1 * k);
        const int cc[3] = {i, j, k};
        double div = 0;
        for (int a = 0; a < 3; a++) {
          int up[3] = {i, j, k};
          up[a]++;
          const size_t fl = gs_cfd_face_index(g, a, i, j, k), fu = gs_cfd_face_index(g, a, up[0], up[1], up[2]);
          const double el = g->ef[a][fl], eu = g->ef[a][fu];
          div += (eu * g->u[a][fu] - el * g->u[a][fl]) / g->h[a];
          const double h2 = g->h[a] * g->h[a];
          if (cc[a] > 0) g->nb[6 * c + 2 * a] = el * g->a[a][fl] / h2;
          if (cc[a] < g->n[a] - 1)
            g->nb[6 * c + 2 * a + 1] = eu * g->a[a][fu] / h2;
          else if (a == 2) /* the outlet plane at p = 0, half a cell away */
            g->diag[c] = 2 * eu * g->a[a][fu] / h2;
        }
        g->rhs[c] = -div - (g->eps[c] - g->eps_old[c]) / dt;
      }
  int rc = gs_cfd_pressure_solve(g->ps, g->nb, g->diag, g->rhs, g->p, g->prm.tol, g->prm.max_iter,
                                 &g->its, &g->res);
  if (rc)
    return gs_error_set(err, GS_ENUMERIC,
                        "gas step %ld (t = %g s): the pressure solve did not converge: relative "
                        "residual %g after %d iterations (gas.solver.tolerance %g, max_iterations %d)",
                        g->steps, g->t, g->res, g->its, g->prm.tol, g->prm.max_iter);
  /* corrector */
  for (int a = 0; a < 3; a++) {
    const int m[3] = {n0 + (a == 0), n1 + (a == 1), n2 + (a == 2)};
    for (int k = 0; k < m[2]; k++)
      for (int j = 0; j < m[1]; j++)
        for (int i = 0; i < m[0]; i++) {
          if (!gs_cfd_face_solved(g, a, i, j, k)) continue;
          const size_t f = gs_cfd_face_index(g, a, i, j, k);
          int lo[3] = {i, j, k};
          lo[a]--;
          const size_t cl = (size_t)lo[0] + (size_t)n0 * ((size_t)lo[1] + (size_t)n1 * lo[2]);
          const int cc[3] = {i, j, k};
          const double grad = cc[a] < g->n[a]
                                  ? (g->p[cl + (a == 0 ? 1 : a == 1 ? (size_t)n0 : (size_t)n0 * n1)] - g->p[cl]) / g->h[a]
                                  : (0 - g->p[cl]) / (0.5 * g->h[a]);
          g->u[a][f] -= g->a[a][f] * grad;
        }
  }
  return check_cfl(g, err);
}

void gs_cfd_set_inlet_velocity(gs_cfd *g, double u) { g->prm.u_inlet = u; }

/* ---- results ------------------------------------------------------------ */
void gs_cfd_dims(const gs_cfd *g, int n[3], double h[3]) {
  for (int a = 0; a < 3; a++) {
    if (n) n[a] = g->n[a];
    if (h) h[a] = g->h[a];
  }
}
long gs_cfd_steps(const gs_cfd *g) { return g->steps; }
double gs_cfd_time(const gs_cfd *g) { return g->t; }
const double *gs_cfd_void_fraction(const gs_cfd *g) { return g->eps; }
const double *gs_cfd_pressure(const gs_cfd *g) { return g->p; }

void gs_cfd_cell_velocity(const gs_cfd *g, size_t c, double u[3]) {
  const int i = (int)(c % (size_t)g->n[0]), j = (int)(c / (size_t)g->n[0] % (size_t)g->n[1]),
            k = (int)(c / ((size_t)g->n[0] * g->n[1]));
  for (int a = 0; a < 3; a++) {
    int up[3] = {i, j, k};
    up[a]++;
    u[a] = 0.5 * (g->u[a][gs_cfd_face_index(g, a, i, j, k)] + g->u[a][gs_cfd_face_index(g, a, up[0], up[1], up[2])]);
  }
}

double gs_cfd_inlet_pressure(const gs_cfd *g) {
  /* the lowest cells' mean: the drag of the particles there acts on the faces
   * above their centres (the inlet face does not move), so nothing is
   * between them and the distributor */
  const size_t layer = (size_t)g->n[0] * g->n[1];
  double s = 0;
  for (size_t c = 0; c < layer; c++) s += g->p[c];
  return s / (double)layer;
}

void gs_cfd_exchange(const gs_cfd *g, double particles[3], double gas[3]) {
  for (int a = 0; a < 3; a++) {
    particles[a] = g->ex_part[a];
    gas[a] = g->ex_gas[a];
  }
}

void gs_cfd_particle_force(const gs_cfd *g, long id, double f[3]) {
  for (int a = 0; a < 3; a++) f[a] = id >= 0 && id < g->force_cap ? g->force[3 * id + a] : 0;
}

void gs_cfd_solver_stats(const gs_cfd *g, int *iterations, double *residual) {
  if (iterations) *iterations = g->its;
  if (residual) *residual = g->res;
}
