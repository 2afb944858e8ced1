/* Lever-rule placement (src/pbm/lever.c):
 *  - on two axes around a known cell (the births of aggregation and
 *    breakage) placement takes a fast path; it must give the same bits as the
 *    general rule (nodes found with gs_lever_near / gs_axis_lever, spread by
 *    gs_lever_spread, clamped at the end pivots) for packets next to their
 *    cell, further away, on a pivot, on the last pivot, and beyond either end;
 *  - a packet inside the pivots keeps its number, its mean coordinates and
 *    its carried totals exactly (to round-off).
 * Every other trial starts from destinations of -0.0 (with guard cells after
 * them): an extra write, even of +0.0 to a node that does not exist or has
 * no share, turns -0.0 into +0.0 and shows in the byte comparison. */
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "gransim/grid.h"
#include "pbm/lever.h"
#include "pbm_testlib.h"

/* The general rule, written out here as the oracle. */
static int place_reference(const gs_grid *g, size_t cell, const double *v, double count,
                           double *dst, double *excess, int nq, const double *qtot,
                           double *const *qdst) {
  int clamped = 0;
  size_t lo[GS_MAX_DIM], idx[GS_MAX_DIM];
  double w[GS_MAX_DIM];
  gs_grid_unindex(g, cell, idx);
  for (int k = 0; k < g->dim; k++) {
    const gs_axis *ax = &g->axis[k];
    int st = gs_lever_near(ax, idx[k], v[k], &lo[k], &w[k]);
    if (st != 0) {
      size_t edge = st < 0 ? 0 : ax->n - 1;
      lo[k] = edge;
      w[k] = 0.0;
      excess[k] += count * (v[k] - ax->pivots[edge]);
      clamped++;
    }
  }
  gs_lever_spread(g, lo, w, count, dst);
  for (int q = 0; q < nq; q++) gs_lever_spread(g, lo, w, qtot[q], qdst[q]);
  return clamped;
}

/* A coordinate for a packet found in cell i of ax: next to its pivot, a
 * few cells away, on a pivot, on the last pivot, or beyond either end. */
static double coordinate(const gs_axis *ax, size_t i, tl_rng *r, int *kind) {
  const double u = tl_uniform(r), p = ax->pivots[i];
  *kind = (int)(u * 6);
  switch (*kind) {
  case 0: return p * (0.6 + 0.8 * tl_uniform(r));            /* the pair around its cell */
  case 1: return p * (0.05 + 20 * tl_uniform(r));            /* possibly not adjacent */
  case 2: return ax->pivots[(size_t)(tl_uniform(r) * (double)ax->n) % ax->n]; /* on a pivot */
  case 3: return ax->pivots[ax->n - 1];                      /* on the last pivot */
  case 4: return ax->pivots[ax->n - 1] * (1 + tl_uniform(r)); /* above the last */
  default: return ax->pivots[0] * (0.2 + 0.7 * tl_uniform(r)); /* below the first */
  }
}

static void check_grid(const char *name, gs_grid *g, tl_rng *r) {
  const size_t n = g->ncells;
  const size_t len = 3 * n + 8; /* numbers, two carried quantities, guard cells */
  double *a = malloc(len * sizeof *a), *b = malloc(len * sizeof *b), *z = calloc(3 * n, sizeof *z);
  long packets = 0, inside = 0, mismatches = 0;
  double worst = 0;
  for (int trial = 0; trial < 20000; trial++) {
    const size_t cell = (size_t)(tl_uniform(r) * (double)n) % n;
    size_t idx[GS_MAX_DIM];
    gs_grid_unindex(g, cell, idx);
    double v[GS_MAX_DIM];
    int kind0, kind1;
    v[0] = coordinate(&g->axis[0], idx[0], r, &kind0);
    v[1] = coordinate(&g->axis[1], idx[1], r, &kind1);
    const double count = 1e6 * tl_uniform(r) - 2e5; /* negative: the sign of a subtracted pass */
    const double qtot[2] = {count * 1e-12 * tl_uniform(r), count * 3e-13 * tl_uniform(r)};
    const int negative_zeros = trial % 2;
    for (size_t i = 0; i < len; i++) a[i] = b[i] = negative_zeros || i >= 3 * n ? -0.0 : tl_uniform(r) - 0.5;
    double ea[2] = {0.25, -0.5}, eb[2] = {0.25, -0.5};
    double *qa[2] = {a + n, a + 2 * n}, *qb[2] = {b + n, b + 2 * n};
    int ca = gs_lever_place_carried(g, cell, v, count, a, ea, 2, qtot, qa);
    int cb = place_reference(g, cell, v, count, b, eb, 2, qtot, qb);
    packets++;
    if (ca != cb || memcmp(a, b, len * sizeof *a) || memcmp(ea, eb, sizeof ea)) mismatches++;
    if (cb) continue;
    /* inside the pivots: number, mean coordinates and carried totals kept */
    inside++;
    memset(z, 0, 3 * n * sizeof *z);
    double e0[2] = {0, 0}, *qz[2] = {z + n, z + 2 * n};
    gs_lever_place_carried(g, cell, v, count, z, e0, 2, qtot, qz);
    double num = 0, m0 = 0, m1 = 0, c0 = 0, c1 = 0;
    for (size_t i = 0; i < n; i++) {
      num += z[i];
      m0 += z[i] * g->x[2 * i];
      m1 += z[i] * g->x[2 * i + 1];
      c0 += qz[0][i];
      c1 += qz[1][i];
    }
    worst = fmax(worst, fabs(num - count) / fabs(count));
    worst = fmax(worst, fabs(m0 - count * v[0]) / fabs(count * v[0]));
    worst = fmax(worst, fabs(m1 - count * v[1]) / fabs(count * v[1]));
    worst = fmax(worst, fabs(c0 - qtot[0]) / fabs(qtot[0]));
    worst = fmax(worst, fabs(c1 - qtot[1]) / fabs(qtot[1]));
  }
  printf("lever, %s: %ld packets (%ld inside the pivots), %ld differ from the general rule; "
         "worst relative change of number, mean coordinates or carried totals %.2g\n",
         name, packets, inside, mismatches, worst);
  CHECK(mismatches == 0);
  CHECK(inside > 2000);
  CHECK(worst < 1e-13);
  free(a);
  free(b);
  free(z);
}

/* Where a computed value on a cell edge goes (gs_axis_locate_snapped): to
 * the cell above whether round-off left it a few ulps below or above the
 * edge; the last edge (and a few ulps past it) to the last cell; further
 * out nowhere; values clearly inside a cell to that cell. */
static void check_snapped(void) {
  gs_axis ax;
  gs_error err;
  CHECK(!gs_axis_linear(&ax, "v", 0, 1, 320, &err));
  for (size_t k = 1; k < ax.n; k++) {
    double e = ax.edges[k];
    CHECK(gs_axis_locate_snapped(&ax, e) == k);
    CHECK(gs_axis_locate_snapped(&ax, nextafter(nextafter(e, 0), 0)) == k);
    CHECK(gs_axis_locate_snapped(&ax, e * (1 + 8 * DBL_EPSILON)) == k);
    CHECK(gs_axis_locate_snapped(&ax, e * (1 - 8 * DBL_EPSILON)) == k);
    CHECK(gs_axis_locate_snapped(&ax, e * (1 - 1e-9)) == k - 1); /* inside the cell below */
    CHECK(gs_axis_locate_snapped(&ax, ax.pivots[k]) == k);
    /* every sum of midpoint pivots lies on an edge: the cell above it */
    CHECK(gs_axis_locate_snapped(&ax, ax.pivots[k - 1] + ax.pivots[0]) == k);
  }
  CHECK(gs_axis_locate_snapped(&ax, 1) == ax.n - 1);
  CHECK(gs_axis_locate_snapped(&ax, nextafter(1, 2)) == ax.n - 1);
  CHECK(gs_axis_locate_snapped(&ax, 1 + 1e-9) == GS_NOWHERE);
  CHECK(gs_axis_locate_snapped(&ax, 0) == 0);
  CHECK(gs_axis_locate_snapped(&ax, -1e-9) == GS_NOWHERE);
  CHECK(gs_axis_locate_snapped(&ax, NAN) == GS_NOWHERE);
  gs_axis_free(&ax);
}

int main(void) {
  tl_rng r = {20261124};
  check_snapped();
  gs_error err;
  /* the CoriMix grid: 16 x 16 geometric bins of ratio 3 */
  gs_axis ax[2];
  CHECK(!gs_axis_geometric(&ax[0], "api", 2.88675e-16, 3, 16, 0, &err));
  CHECK(!gs_axis_geometric(&ax[1], "excipient", 2.88675e-16, 3, 16, 0, &err));
  gs_grid g;
  CHECK(!gs_grid_init(&g, ax, 2, 1, &err));
  check_grid("16 x 16 geometric", &g, &r);
  gs_grid_free(&g);
  /* uneven axes: a linear one and a short geometric one with a zero cell */
  CHECK(!gs_axis_linear(&ax[0], "a", 0.5, 7.5, 9, &err));
  CHECK(!gs_axis_geometric(&ax[1], "b", 1e-3, 2, 5, 1, &err));
  CHECK(!gs_grid_init(&g, ax, 2, 1, &err));
  check_grid("9 linear x 6 geometric", &g, &r);
  gs_grid_free(&g);
  TEST_EXIT();
}
