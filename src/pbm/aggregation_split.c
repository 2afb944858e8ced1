/* Fixed-pivot births on non-uniform grids by a near/far split of the pairs.
 *
 * On a grid whose pivots x_0 < x_1 < ... are not equally spaced, the sum of
 * two pivots does not depend on the index sum alone and the births are no
 * convolution.  But along one axis, a partner j < i small enough that
 * x_i + x_j <= x_{i+1} puts the product between pivots i and i+1 with the
 * lever weight w = x_j / h_i (h_i = x_{i+1} - x_i) on i+1, linear in x_j;
 * summed over all such j (a prefix j < J_i of the cells, the pivots being
 * increasing) the births of the pairs (i, j) are
 *   node i:   U_i (S0_i - S1_i / h_i),   node i+1: U_i S1_i / h_i,
 *   S0_i = sum_{j < J_i} V_j,   S1_i = sum_{j < J_i} x_j V_j,
 * two prefix sums of the partner.  So each axis has a short list of
 * entries: the near pairs (i, j) (neither small enough for the other;
 * placed, clamped or lost by the lever rule as the pair scheme does) and
 * per cell i four far entries, pairing U_i with S0_i, S1_i and, the other
 * way round, V_i with the prefix sums of U.  With U and V extended by their
 * prefix sums along every axis (3 n entries per axis), the births of a term
 * beta = phi(a) psi(b), U = phi N, V = psi N, are the sum over one entry per
 * axis (a tuple) of U^[u] V^[v] times the product of the axes' weights:
 * exact, no approximation beyond round-off.  Number and the volume of every
 * coordinate are conserved exactly by every entry (the far entries' weights
 * are the lever rule's; their number weights 1 and 0).
 *
 * The work is the product over the axes of the entries taking part, about
 * n (2 D + 7) per axis for a band of 2 D + 1 near partners: on a geometric
 * grid of ratio r, D ~ log(1 / (r - 1)) / log r (r = 1.6: D = 1; r = 2: 0;
 * r = 2^(1/4): 9), against n^2 / 2 pairs per axis.  Entries whose extended
 * index holds nothing in U^ or V^ (empty slices) are skipped, so a sparse
 * population costs less, as with the pairs.  On equally spaced pivots the
 * band covers everything (use the FFT there). */
#include <limits.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "gransim/pbm.h"
#include "pbm/aggregation_split.h"

enum { PLACED = 0, CLAMPED = 1, OUTSIDE = 2 };

typedef struct {
  size_t u, v;      /* extended indices along the axis */
  size_t lo;        /* lower node times the axis stride */
  double w[2];      /* weights of nodes lo and lo + 1 */
  double num;       /* particles per unit of U^ V^ (1, or 0 for the x-weighted prefix) */
  double vol;       /* this coordinate's volume per unit of U^ V^ (the pivot sum, x_i, or 1) */
  double excess;    /* clamped: volume above the last pivot per unit */
  int state;
} entry;

typedef struct {
  size_t n, ne;     /* cells, extended length (3 n, or 1 on a padding axis) */
  size_t nent;
  entry *e;
  size_t *J;        /* n: the prefix of small partners of each cell */
  double *x;        /* n pivots */
} axis_t;

typedef struct {
  double **E;            /* nphi extended arrays */
  unsigned char **act;   /* nphi x 3: per axis, the slices of E[m] not all zero */
  int **row;             /* nphi x 2 per row (e0, e1) of E[m]: first and last index holding a
                          * non-zero (first > last: none) */
  size_t *list[3];       /* entries taking part */
  double *pre;           /* 2 (n + 1): prefix sums of one fibre */
} slot_t;

struct gs_agg_split {
  int off;          /* real axes at padded positions off..2 */
  axis_t ax[3];
  size_t stride[3];  /* grid strides (0 on padding axes) */
  size_t estride[3]; /* strides of the extended arrays */
  size_t n_ext, ncells;
  int nslots, nphi;
  slot_t *slot;
};

void gs_agg_split_free(gs_agg_split *S) {
  if (!S) return;
  for (int s = 0; S->slot && s < S->nslots; s++) {
    slot_t *T = &S->slot[s];
    for (int m = 0; T->E && m < S->nphi; m++) free(T->E[m]);
    for (int m = 0; T->act && m < 3 * S->nphi; m++) free(T->act[m]);
    for (int m = 0; T->row && m < S->nphi; m++) free(T->row[m]);
    free(T->row);
    free(T->E);
    free(T->act);
    free(T->pre);
    for (int q = 0; q < 3; q++) free(T->list[q]);
  }
  free(S->slot);
  for (int q = 0; q < 3; q++) {
    free(S->ax[q].e);
    free(S->ax[q].J);
    free(S->ax[q].x);
  }
  free(S);
}

double gs_agg_split_tuples(const gs_agg_split *S) {
  return (double)S->ax[0].nent * (double)S->ax[1].nent * (double)S->ax[2].nent;
}

/* The near entry of cells (i, j): the pair scheme's rules (aggregation.c,
 * build_axis_maps) for the pivot sum. */
static entry near_entry(const gs_axis *ax, size_t stride, size_t i, size_t j) {
  const size_t n = ax->n;
  const double s = ax->pivots[i] + ax->pivots[j];
  entry e = {.u = i, .v = j, .num = 1, .vol = s, .state = PLACED};
  size_t lo;
  double w;
  if (gs_axis_lever(ax, s, &lo, &w) == 0) {
    e.lo = lo * stride;
    e.w[0] = 1 - w;
    e.w[1] = w;
  } else if (gs_axis_locate_snapped(ax, s) != GS_NOWHERE) {
    e.lo = (n - 1) * stride;
    e.w[0] = 1;
    e.excess = s - ax->pivots[n - 1];
    e.state = CLAMPED;
  } else {
    e.state = OUTSIDE;
  }
  return e;
}

static int by_u(const void *a, const void *b) {
  const entry *x = a, *y = b;
  return x->u < y->u ? -1 : x->u > y->u ? 1 : x->v < y->v ? -1 : x->v > y->v;
}

static int build_axis(gs_agg_split *S, const gs_grid *g, int q, gs_error *err) {
  axis_t *A = &S->ax[q];
  if (q < S->off) { /* padding: one cell onto itself */
    A->n = A->ne = A->nent = 1;
    if (!(A->e = gs_calloc(1, sizeof(entry), err))) return GS_ENOMEM;
    A->e[0] = (entry){.w = {1, 0}, .num = 1, .vol = 0, .state = PLACED};
    return GS_OK;
  }
  const gs_axis *ax = &g->axis[q - S->off];
  const size_t n = ax->n, stride = S->stride[q];
  A->n = n;
  A->ne = 3 * n;
  A->J = gs_calloc(n, sizeof(size_t), err);
  A->x = gs_malloc(n * sizeof(double), err);
  if (!A->J || !A->x) return GS_ENOMEM;
  memcpy(A->x, ax->pivots, n * sizeof(double));
  /* J_i: the partners j < i with x_i + x_j <= x_{i+1}; none for the last
   * cell, whose products are clamped or lost (near entries) */
  for (size_t i = 0; i + 1 < n; i++) {
    size_t j = 0;
    while (j < i && A->x[i] + A->x[j] <= A->x[i + 1]) j++;
    A->J[i] = j;
  }
  size_t cap = 4 * n;
  for (size_t i = 0; i < n; i++)
    for (size_t j = 0; j < n; j++) cap += !((j < i && j < A->J[i]) || (i < j && i < A->J[j]));
  if (!(A->e = gs_malloc(cap * sizeof(entry), err))) return GS_ENOMEM;
  size_t k = 0;
  for (size_t i = 0; i < n; i++)
    for (size_t j = 0; j < n; j++)
      if (!((j < i && j < A->J[i]) || (i < j && i < A->J[j]))) A->e[k++] = near_entry(ax, stride, i, j);
  for (size_t i = 0; i + 1 < n; i++) {
    if (A->J[i] == 0) continue;
    const double h = A->x[i + 1] - A->x[i];
    /* U_i with the prefixes of V, and V_i with those of U */
    A->e[k++] = (entry){.u = i, .v = n + i, .lo = i * stride, .w = {1, 0}, .num = 1, .vol = A->x[i]};
    A->e[k++] = (entry){.u = i, .v = 2 * n + i, .lo = i * stride, .w = {-1 / h, 1 / h}, .num = 0, .vol = 1};
    A->e[k++] = (entry){.u = n + i, .v = i, .lo = i * stride, .w = {1, 0}, .num = 1, .vol = A->x[i]};
    A->e[k++] = (entry){.u = 2 * n + i, .v = i, .lo = i * stride, .w = {-1 / h, 1 / h}, .num = 0, .vol = 1};
  }
  A->nent = k;
  qsort(A->e, k, sizeof(entry), by_u); /* births look up a range of u */
  return GS_OK;
}

int gs_agg_split_create(const gs_grid *g, int nslots, int nphi, gs_agg_split **out, gs_error *err) {
  gs_agg_split *S = gs_calloc(1, sizeof *S, err);
  if (!S) return GS_ENOMEM;
  S->off = 3 - g->dim;
  S->ncells = g->ncells;
  for (int q = 0; q < 3; q++) S->stride[q] = q >= S->off ? g->stride[q - S->off] : 0;
  int rc = GS_OK;
  for (int q = 0; !rc && q < 3; q++) rc = build_axis(S, g, q, err);
  if (!rc) {
    S->estride[2] = 1;
    S->estride[1] = S->ax[2].ne;
    S->estride[0] = S->ax[2].ne * S->ax[1].ne;
    S->n_ext = S->estride[0] * S->ax[0].ne;
    S->nslots = nslots > 0 ? nslots : 1;
    S->nphi = nphi > 0 ? nphi : 1;
    if (!(S->slot = gs_calloc((size_t)S->nslots, sizeof(slot_t), err))) rc = GS_ENOMEM;
  }
  size_t maxn = 1;
  for (int q = 0; q < 3; q++) maxn = S->ax[q].n > maxn ? S->ax[q].n : maxn;
  for (int s = 0; !rc && s < S->nslots; s++) {
    slot_t *T = &S->slot[s];
    T->E = gs_calloc((size_t)S->nphi, sizeof(double *), err);
    T->act = gs_calloc(3 * (size_t)S->nphi, sizeof(unsigned char *), err);
    T->row = gs_calloc((size_t)S->nphi, sizeof(int *), err);
    T->pre = gs_malloc(2 * (maxn + 1) * sizeof(double), err);
    if (!T->E || !T->act || !T->row || !T->pre) rc = GS_ENOMEM;
    for (int m = 0; !rc && m < S->nphi; m++) {
      if (!(T->E[m] = gs_malloc(S->n_ext * sizeof(double), err))) rc = GS_ENOMEM;
      if (!rc && !(T->row[m] = gs_malloc(2 * S->ax[0].ne * S->ax[1].ne * sizeof(int), err))) rc = GS_ENOMEM;
      for (int q = 0; !rc && q < 3; q++)
        if (!(T->act[3 * m + q] = gs_malloc(S->ax[q].ne, err))) rc = GS_ENOMEM;
    }
    for (int q = 0; !rc && q < 3; q++)
      if (!(T->list[q] = gs_malloc(S->ax[q].nent * sizeof(size_t), err))) rc = GS_ENOMEM;
  }
  if (rc) {
    gs_agg_split_free(S);
    return rc;
  }
  *out = S;
  return GS_OK;
}

/* X (cells) into the extended array E with its prefix sums along every
 * axis: E[.., n + i, ..] = sum_{j < J_i} E[.., j, ..] and E[.., 2n + i, ..]
 * the same weighted by x_j, axis after axis (so the prefixes of prefixes
 * too), and act[q][e]: slice e of axis q holds a non-zero. */
static void extend(const gs_agg_split *S, slot_t *T, const double *X, double *E, unsigned char **act,
                   int *rowact) {
  const axis_t *A = S->ax;
  memset(E, 0, S->n_ext * sizeof(double));
  for (size_t i0 = 0; i0 < A[0].n; i0++)
    for (size_t i1 = 0; i1 < A[1].n; i1++) {
      const double *src = X + (i0 * A[1].n + i1) * A[2].n;
      double *dst = E + i0 * S->estride[0] + i1 * S->estride[1];
      memcpy(dst, src, A[2].n * sizeof(double));
    }
  for (int q = 0; q < 3; q++) {
    if (q < S->off) continue;
    const size_t n = A[q].n, st = S->estride[q];
    /* fibres along q: every extended index of the axes done already (their
     * prefixes get prefixes too), the cells of those still to do */
    const int q1 = (q + 1) % 3, q2 = (q + 2) % 3;
    const size_t n1 = q1 < q ? A[q1].ne : A[q1].n, n2 = q2 < q ? A[q2].ne : A[q2].n;
    double *p0 = T->pre, *p1 = T->pre + n + 1;
    for (size_t a = 0; a < n1; a++)
      for (size_t b = 0; b < n2; b++) {
        double *f = E + a * S->estride[q1] + b * S->estride[q2];
        p0[0] = p1[0] = 0;
        for (size_t j = 0; j < n; j++) {
          p0[j + 1] = p0[j] + f[j * st];
          p1[j + 1] = p1[j] + A[q].x[j] * f[j * st];
        }
        for (size_t i = 0; i < n; i++) {
          f[(n + i) * st] = p0[A[q].J[i]];
          f[(2 * n + i) * st] = p1[A[q].J[i]];
        }
      }
  }
  for (int q = 0; q < 3; q++) memset(act[q], 0, A[q].ne);
  for (size_t e0 = 0; e0 < A[0].ne; e0++)
    for (size_t e1 = 0; e1 < A[1].ne; e1++) {
      const double *row = E + e0 * S->estride[0] + e1 * S->estride[1];
      int any = 0, first = 1, last = 0;
      for (size_t e2 = 0; e2 < A[2].ne; e2++)
        if (row[e2] != 0.0) {
          act[2][e2] = 1;
          if (!any) first = (int)e2;
          last = (int)e2;
          any = 1;
        }
      rowact[2 * (e0 * A[1].ne + e1)] = first;
      rowact[2 * (e0 * A[1].ne + e1) + 1] = last;
      if (any) act[0][e0] = act[1][e1] = 1;
    }
}

void gs_agg_split_births(gs_agg_split *S, int slot, int nphi, const double *const *X, int nterm,
                         const int *m1, const int *m2, const double *scale, double *dN, double *lost,
                         double *born) {
  slot_t *T = &S->slot[slot > 0 ? slot : 0];
  for (int m = 0; m < nphi && m < S->nphi; m++) extend(S, T, X[m], T->E[m], T->act + 3 * m, T->row[m]);
  size_t m[3];
  for (int q = 0; q < 3; q++) { /* entries whose two slices hold something in some term */
    m[q] = 0;
    for (size_t k = 0; k < S->ax[q].nent; k++)
      for (int t = 0; t < nterm; t++)
        if (T->act[3 * m1[t] + q][S->ax[q].e[k].u] && T->act[3 * m2[t] + q][S->ax[q].e[k].v]) {
          T->list[q][m[q]++] = k;
          break;
        }
  }
  const size_t s0 = S->stride[0], s1 = S->stride[1], s2 = S->stride[2];
  const size_t *es = S->estride;
  double placed = 0, lv[3] = {0, 0, 0};
  for (size_t k0 = 0; k0 < m[0]; k0++) {
    const entry *a = &S->ax[0].e[T->list[0][k0]];
    for (size_t k1 = 0; k1 < m[1]; k1++) {
      const entry *b = &S->ax[1].e[T->list[1][k1]];
      /* the terms whose two rows hold something (a population along a
       * curve through the grid fills few of them) */
      const size_t ru = a->u * S->ax[1].ne + b->u, rv = a->v * S->ax[1].ne + b->v;
      int nt = 0, ulo = INT_MAX, uhi = -1, vlo = INT_MAX, vhi = -1;
      const double *ur[GS_SPLIT_MAX_TERMS], *vr[GS_SPLIT_MAX_TERMS];
      double sc[GS_SPLIT_MAX_TERMS];
      for (int t = 0; t < nterm; t++) {
        const int *u = T->row[m1[t]] + 2 * ru, *v = T->row[m2[t]] + 2 * rv;
        if (u[0] > u[1] || v[0] > v[1]) continue;
        ulo = u[0] < ulo ? u[0] : ulo;
        uhi = u[1] > uhi ? u[1] : uhi;
        vlo = v[0] < vlo ? v[0] : vlo;
        vhi = v[1] > vhi ? v[1] : vhi;
        {
          ur[nt] = T->E[m1[t]] + a->u * es[0] + b->u * es[1];
          vr[nt] = T->E[m2[t]] + a->v * es[0] + b->v * es[1];
          sc[nt++] = scale[t];
        }
      }
      if (!nt) continue;
      const int out01 = a->state == OUTSIDE || b->state == OUTSIDE;
      const double n01 = a->num * b->num;
      const double w00 = a->w[0] * b->w[0], w01 = a->w[0] * b->w[1], w10 = a->w[1] * b->w[0],
                   w11 = a->w[1] * b->w[1];
      const size_t lo01 = a->lo + b->lo;
      /* the entries along axis 2 come sorted by u: those in [ulo, uhi] */
      size_t k2 = 0, top = m[2];
      while (top > k2) { /* the first with u >= ulo */
        const size_t mid = k2 + (top - k2) / 2;
        if (S->ax[2].e[T->list[2][mid]].u < (size_t)ulo) k2 = mid + 1;
        else top = mid;
      }
      for (; k2 < m[2]; k2++) {
        const entry *c = &S->ax[2].e[T->list[2][k2]];
        if (c->u > (size_t)uhi) break;
        if (c->v < (size_t)vlo || c->v > (size_t)vhi) continue;
        double p = 0;
        for (int t = 0; t < nt; t++) p += sc[t] * ur[t][c->u] * vr[t][c->v];
        if (p == 0.0) continue;
        if (out01 || c->state == OUTSIDE) { /* the products lie beyond the grid */
          lv[0] += p * a->vol * b->num * c->num;
          lv[1] += p * b->vol * a->num * c->num;
          lv[2] += p * c->vol * n01;
          continue;
        }
        placed += p * n01 * c->num;
        if (a->state | b->state | c->state) { /* clamped on some axis */
          lv[0] += p * a->excess * b->num * c->num;
          lv[1] += p * b->excess * a->num * c->num;
          lv[2] += p * c->excess * n01;
        }
        if (!dN) continue;
        double *d = dN + lo01 + c->lo;
        const double c0 = p * c->w[0], c1 = p * c->w[1];
        d[0] += w00 * c0;
        if (c1 != 0.0) d[s2] += w00 * c1;
        if (w01 != 0.0) {
          d[s1] += w01 * c0;
          if (c1 != 0.0) d[s1 + s2] += w01 * c1;
        }
        if (w10 != 0.0) {
          d[s0] += w10 * c0;
          if (c1 != 0.0) d[s0 + s2] += w10 * c1;
        }
        if (w11 != 0.0) {
          d[s0 + s1] += w11 * c0;
          if (c1 != 0.0) d[s0 + s1 + s2] += w11 * c1;
        }
      }
    }
  }
  *born += placed;
  for (int k = 0; lost && k < 3 - S->off; k++) lost[k] += lv[S->off + k];
}
