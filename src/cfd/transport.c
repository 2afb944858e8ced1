/* Convection and viscous stress of the gas momentum equation (docs/models.md,
 * "CFD-DEM", Gas): per face, the implicit (diagonal) coefficient and the
 * explicit part from the neighbours at step n.  Keeping the diagonal implicit
 * makes the step stable at any time step (its amplification lies in [-1, 1]
 * for both operators, whose coefficients are all positive), so the time step
 * is limited by the coupling (the gas CFL), not by these terms. */
#include <math.h>

#include "cfd/cfd_internal.h"

/* What lies one step s (+-1) along axis b from the face c of axis a: another
 * face of axis a, a no-slip wall or the distributor (ghost value -u: zero
 * velocity half a cell away), or the outlet (ghost +u: zero gradient). */
enum { NB_FACE, NB_WALL, NB_OPEN };

static int neighbour(const gs_cfd *g, int a, int b, const int c[3], int s, size_t *f) {
  int d[3] = {c[0], c[1], c[2]};
  d[b] += s;
  const int last = g->n[b] - (b != a); /* faces of axis a run 0..n[a], cells 0..n-1 */
  if (d[b] < 0) return NB_WALL;
  if (d[b] > last) return b == 2 ? NB_OPEN : NB_WALL;
  *f = gs_cfd_face_index(g, a, d[0], d[1], d[2]);
  return NB_FACE;
}

/* Component b (!= a) of the gas velocity at face c of axis a: the mean of
 * the b faces of the (one or two) cells the face belongs to. */
static double advecting(const gs_cfd *g, int a, int b, const int c[3]) {
  double s = 0;
  int n = 0;
  for (int da = -1; da <= 0; da++) {
    int d[3] = {c[0], c[1], c[2]};
    d[a] += da;
    if (d[a] < 0 || d[a] >= g->n[a]) continue;
    for (int db = 0; db <= 1; db++) {
      int e[3] = {d[0], d[1], d[2]};
      e[b] += db;
      s += g->u[b][gs_cfd_face_index(g, b, e[0], e[1], e[2])];
      n++;
    }
  }
  return s / n;
}

/* eps rho u.grad(u_a) by first-order upwind differences (the paper's FLUENT
 * set-up) and div(eps mu grad u_a) by central differences, eps on the cell
 * between two faces of the same axis and the mean of the two faces' across
 * the others. */
static void face_terms(const gs_cfd *g, int a, const int c[3], size_t f) {
  const double rho = g->prm.rho, mu = g->prm.mu, ef = g->ef[a][f];
  double dg = 0, ex = 0;
  for (int b = 0; b < 3; b++) {
    const double ub = b == a ? g->u[a][f] : advecting(g, a, b, c), h = g->h[b];
    for (int s = -1; s <= 1; s += 2) {
      size_t nf = 0;
      const int kind = neighbour(g, a, b, c, s, &nf);
      if (kind == NB_OPEN) continue; /* zero gradient: no flux */
      double e_between = ef;
      if (kind == NB_FACE && b == a) {
        int d[3] = {c[0], c[1], c[2]};
        d[a] += s > 0 ? 0 : -1;
        e_between = g->eps[(size_t)d[0] + (size_t)g->n[0] * ((size_t)d[1] + (size_t)g->n[1] * d[2])];
      } else if (kind == NB_FACE) {
        e_between = 0.5 * (ef + g->ef[a][nf]);
      }
      double coef = mu * e_between / (h * h);
      if ((s < 0) == (ub > 0)) coef += ef * rho * fabs(ub) / h; /* the upstream neighbour */
      if (kind == NB_FACE) {
        dg += coef;
        ex += coef * g->u[a][nf];
      } else {
        dg += 2 * coef; /* u_f - (-u_f) */
      }
    }
  }
  g->dg[a][f] = dg;
  g->ex[a][f] = ex;
}

void gs_cfd_transport(gs_cfd *g) {
  for (int a = 0; a < 3; a++) {
    const int m[3] = {g->n[0] + (a == 0), g->n[1] + (a == 1), g->n[2] + (a == 2)};
#pragma omp parallel for collapse(2) schedule(static) if (g->nface[a] >= 4096)
    for (int k = 0; k < m[2]; k++)
      for (int j = 0; j < m[1]; j++)
        for (int i = 0; i < m[0]; i++) {
          const int c[3] = {i, j, k};
          const size_t f = gs_cfd_face_index(g, a, i, j, k);
          if (gs_cfd_face_solved(g, a, i, j, k))
            face_terms(g, a, c, f);
          else
            g->dg[a][f] = g->ex[a][f] = 0;
        }
  }
}
