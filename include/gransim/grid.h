/* gransim — internal-coordinate grids and compartments.
 *
 * A grid has 1..GS_MAX_DIM internal coordinates ("axes": e.g. solid, liquid,
 * gas volume) and any number of spatial compartments.  Each axis is a list of
 * n cells given by n+1 increasing edges, with one pivot (representative
 * point) per cell, edge[i] <= pivot[i] <= edge[i+1] and pivots strictly
 * increasing.  Particles are represented as point masses at the pivots
 * (cell-average and fixed-pivot discretisations).
 *
 * Storage of any per-cell field is flat and contiguous: compartment outermost,
 * then axis 0, ..., axis dim-1 (last axis fastest):
 *     index = comp * ncells + sum_k i_k * stride[k]. */
#ifndef GRANSIM_GRID_H
#define GRANSIM_GRID_H

#include <stddef.h>
#include "gransim/error.h"

#ifdef __cplusplus
extern "C" {
#endif

#define GS_MAX_DIM 3
#define GS_NAME_LEN 32
#define GS_NOWHERE ((size_t)-1)

typedef struct gs_axis {
  char name[GS_NAME_LEN]; /* e.g. "solid", "liquid", "gas" */
  size_t n;               /* number of cells */
  double *edges;          /* n+1 increasing edges */
  double *pivots;         /* n increasing pivots, one per cell */
} gs_axis;

/* Builders.  They allocate edges/pivots; free with gs_axis_free.
 * linear:    n equal cells on [lo, hi].
 * geometric: edges lo*ratio^k, k = 0..n (lo > 0, ratio > 1); if zero_first,
 *            an extra first cell [0, lo] is prepended (n+1 cells in total).
 * edges:     explicit edges; pivots NULL = midpoints, else explicit pivots.
 * Pivots default to cell midpoints (as in the nonlinear-grid cell average of Chaudhury 2015). */
int gs_axis_linear(gs_axis *ax, const char *name, double lo, double hi, size_t n, gs_error *err);
int gs_axis_geometric(gs_axis *ax, const char *name, double lo, double ratio, size_t n,
                      int zero_first, gs_error *err);
int gs_axis_from_edges(gs_axis *ax, const char *name, const double *edges, size_t n_edges,
                       const double *pivots, gs_error *err);
void gs_axis_free(gs_axis *ax);

/* Cell containing v (edge[i] <= v < edge[i+1]; the last cell includes its
 * upper edge), or GS_NOWHERE if v is outside [edge[0], edge[n]]. */
size_t gs_axis_locate(const gs_axis *ax, double v);

/* The cell of a computed value v that stands for an exact one (a sum of
 * pivots, a fragment's mean): a v within a few ulps of an edge (16 machine
 * epsilons relative, at most a quarter of the adjacent cells) counts as on
 * that edge, and an edge belongs to the cell above it, the last edge to the
 * last cell.  So the order of floating-point operations that gave v never
 * decides its cell (docs/models.md, "Sums on cell edges").  GS_NOWHERE if v
 * lies further outside [edge[0], edge[n]]. */
size_t gs_axis_locate_snapped(const gs_axis *ax, double v);

/* Lever rule around the pivots: for v in [pivot[0], pivot[n-1]] finds lo with
 * pivot[lo] <= v <= pivot[lo+1] and the fraction w of the pair that goes to
 * lo+1 (so lo*(1-w) + (lo+1)*w reproduces v).  If v sits exactly on the last
 * pivot, lo = n-1 and w = 0.  Returns 0 on success, -1 below pivot[0], +1
 * above pivot[n-1]. */
int gs_axis_lever(const gs_axis *ax, double v, size_t *lo, double *w);

typedef struct gs_grid {
  int dim;                    /* number of internal coordinates, 1..3 */
  gs_axis axis[GS_MAX_DIM];
  size_t ncells;              /* cells per compartment = product of axis[k].n */
  size_t stride[GS_MAX_DIM];  /* row-major strides, stride[dim-1] = 1 */
  size_t ncomp;               /* number of spatial compartments (>= 1) */
  double *x;                  /* ncells*dim pivot coordinates, cell-major */
  double *volume;             /* ncells: sum of the coordinates at the pivot (granule volume) */
} gs_grid;

/* Take ownership of dim axes (moved into the grid) and build the tables. */
int gs_grid_init(gs_grid *g, gs_axis *axes, int dim, size_t ncomp, gs_error *err);
void gs_grid_free(gs_grid *g);

/* Index helpers. */
size_t gs_grid_index(const gs_grid *g, const size_t *idx);       /* multi-index -> cell */
void gs_grid_unindex(const gs_grid *g, size_t cell, size_t *idx); /* cell -> multi-index */
int gs_grid_axis_by_name(const gs_grid *g, const char *name);     /* -1 if absent */

/* Volume-equivalent diameter of a granule volume v: (6 v / pi)^(1/3). */
double gs_diameter(double v);

/* A point mass of a size distribution: granule volume v > 0 and its weight
 * w >= 0 (for volume-weighted percentiles, number times volume). */
typedef struct gs_size_point {
  double v, w;
} gs_size_point;

/* Weighted percentiles p[0..np) (fractions, ascending) of the
 * volume-equivalent diameter of pts[0..n) (src/grid/percentiles.c): the
 * cumulative fraction taken at each distinct volume by the midpoint rule
 * (half of a point's own weight counted below it) and interpolated linearly
 * in the diameter in between, so a single point gives its own diameter for
 * every percentile; NaN when there is no weight.  pts is reordered; scratch
 * holds n points. */
void gs_size_percentiles(gs_size_point *pts, gs_size_point *scratch, size_t n, const double *p,
                         int np, double *out);

/* A cell's part of a size distribution: weight w >= 0 spread evenly over
 * the granule volumes [lo, hi] (lo < hi), so that the cumulative
 * distribution is linear in the volume between the volumes of the cells'
 * edges. */
typedef struct gs_size_range {
  double lo, hi, w;
} gs_size_range;

/* Weighted percentiles p[0..np) (fractions, ascending) of the
 * volume-equivalent diameter of the ranges r[0..n): the diameter of the
 * volume where the cumulative weight reaches p times the total.  Unlike
 * point masses they move continuously with the weights (a percentile jumps
 * only across volumes that hold no weight at all, to the start of the next
 * weight).  NaN when there is no weight; scratch holds 4 n points. */
void gs_size_percentiles_ranges(const gs_size_range *r, size_t n, gs_size_point *scratch,
                                const double *p, int np, double *out);

/* The fractions of the ranges' total weight in the granule-volume classes
 * [v[k], v[k+1]) for k < nclass (v increasing; v[0] may be 0 and
 * v[nclass] infinite), each range's weight spread evenly as above: weight
 * outside the classes counts in none.  NaN when there is no weight. */
void gs_size_fractions_ranges(const gs_size_range *r, size_t n, const double *v, size_t nclass,
                              double *frac);

#ifdef __cplusplus
}
#endif
#endif
