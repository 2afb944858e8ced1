/* One internal-coordinate axis: edges, pivots, location and lever rule. */
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "gransim/grid.h"

static int axis_alloc(gs_axis *ax, const char *name, size_t n, gs_error *err) {
  memset(ax, 0, sizeof *ax);
  if (n < 1) return gs_error_set(err, GS_EINPUT, "axis '%s' needs at least one cell", name);
  if (strlen(name) >= GS_NAME_LEN || !*name)
    return gs_error_set(err, GS_EINPUT, "axis name '%s' must have 1 to %d characters", name,
                        GS_NAME_LEN - 1);
  strcpy(ax->name, name);
  ax->n = n;
  ax->edges = gs_malloc((n + 1) * sizeof(double), err);
  ax->pivots = gs_malloc(n * sizeof(double), err);
  if (!ax->edges || !ax->pivots) {
    gs_axis_free(ax);
    return GS_ENOMEM;
  }
  return GS_OK;
}

static void set_midpoints(gs_axis *ax) {
  for (size_t i = 0; i < ax->n; i++) ax->pivots[i] = 0.5 * (ax->edges[i] + ax->edges[i + 1]);
}

/* Edges far beyond any particle's size overflow the moments (a volume's
 * square in M2, a cell's volume times 1e20 particles) long before they
 * overflow themselves: min * ratio^cells easily does (1e-13 * 2.5^1000). */
#define GS_AXIS_LARGEST_EDGE 1e100

static int check_largest_edge(gs_axis *ax, gs_error *err) {
  const double top = ax->edges[ax->n];
  if (top <= GS_AXIS_LARGEST_EDGE) return GS_OK;
  int rc = gs_error_set(err, GS_EINPUT,
                        "axis '%s': its last edge is %g, beyond %g (the moments would overflow); "
                        "fewer cells, a smaller ratio or max",
                        ax->name, top, GS_AXIS_LARGEST_EDGE);
  gs_axis_free(ax);
  return rc;
}

int gs_axis_linear(gs_axis *ax, const char *name, double lo, double hi, size_t n, gs_error *err) {
  if (!(lo >= 0) || !(hi > lo))
    return gs_error_set(err, GS_EINPUT, "axis '%s': linear grid needs 0 <= min < max (got %g, %g)",
                        name, lo, hi);
  int rc = axis_alloc(ax, name, n, err);
  if (rc) return rc;
  for (size_t i = 0; i <= n; i++) ax->edges[i] = lo + (hi - lo) * (double)i / (double)n;
  set_midpoints(ax);
  return check_largest_edge(ax, err);
}

int gs_axis_geometric(gs_axis *ax, const char *name, double lo, double ratio, size_t n,
                      int zero_first, gs_error *err) {
  if (!(lo > 0) || !(ratio > 1))
    return gs_error_set(err, GS_EINPUT,
                        "axis '%s': geometric grid needs min > 0 and ratio > 1 (got %g, %g)", name,
                        lo, ratio);
  size_t off = zero_first ? 1 : 0;
  int rc = axis_alloc(ax, name, n + off, err);
  if (rc) return rc;
  if (zero_first) ax->edges[0] = 0.0;
  for (size_t k = 0; k <= n; k++) ax->edges[k + off] = lo * pow(ratio, (double)k);
  set_midpoints(ax);
  return check_largest_edge(ax, err);
}

int gs_axis_from_edges(gs_axis *ax, const char *name, const double *edges, size_t n_edges,
                       const double *pivots, gs_error *err) {
  if (n_edges < 2)
    return gs_error_set(err, GS_EINPUT, "axis '%s': need at least 2 edges, got %zu", name,
                        n_edges);
  for (size_t i = 0; i < n_edges; i++) {
    if (!(edges[i] >= 0) || !isfinite(edges[i]))
      return gs_error_set(err, GS_EINPUT, "axis '%s': edge %zu = %g must be finite and >= 0",
                          name, i, edges[i]);
    if (i && !(edges[i] > edges[i - 1]))
      return gs_error_set(err, GS_EINPUT,
                          "axis '%s': edges must increase strictly (edge %zu = %g <= %g)", name, i,
                          edges[i], edges[i - 1]);
  }
  int rc = axis_alloc(ax, name, n_edges - 1, err);
  if (rc) return rc;
  memcpy(ax->edges, edges, n_edges * sizeof(double));
  if (check_largest_edge(ax, err)) return GS_EINPUT;
  if (!pivots) {
    set_midpoints(ax);
    return GS_OK;
  }
  for (size_t i = 0; i < ax->n; i++) {
    if (!(pivots[i] >= edges[i] && pivots[i] <= edges[i + 1]) || (i && pivots[i] <= pivots[i - 1])) {
      rc = gs_error_set(err, GS_EINPUT,
                        "axis '%s': pivot %zu = %g must lie in its cell [%g, %g] and exceed the "
                        "previous pivot",
                        name, i, pivots[i], edges[i], edges[i + 1]);
      gs_axis_free(ax);
      return rc;
    }
    ax->pivots[i] = pivots[i];
  }
  return GS_OK;
}

void gs_axis_free(gs_axis *ax) {
  free(ax->edges);
  free(ax->pivots);
  ax->edges = ax->pivots = NULL;
  ax->n = 0;
}

/* Largest i with a[i] <= v among a[0..n-1] (a increasing, a[0] <= v). */
static size_t bisect(const double *a, size_t n, double v) {
  size_t lo = 0, hi = n - 1;
  while (lo < hi) {
    size_t mid = (lo + hi + 1) / 2;
    if (a[mid] <= v) lo = mid;
    else hi = mid - 1;
  }
  return lo;
}

size_t gs_axis_locate(const gs_axis *ax, double v) {
  if (!(v >= ax->edges[0]) || v > ax->edges[ax->n]) return GS_NOWHERE;
  size_t i = bisect(ax->edges, ax->n + 1, v);
  return i >= ax->n ? ax->n - 1 : i;
}

/* Round-off of an edge (a few operations on the case's numbers) and of a sum
 * of two pivots (each a few more) stays well inside 16 epsilons. */
#define SNAP_EPS (16 * DBL_EPSILON)

size_t gs_axis_locate_snapped(const gs_axis *ax, double v) {
  const double *e = ax->edges;
  const size_t n = ax->n;
  size_t k; /* the edge nearest to v */
  if (!(v >= e[0])) k = 0;
  else if (v > e[n]) k = n;
  else {
    size_t i = bisect(e, n + 1, v);
    k = i < n && e[i + 1] - v < v - e[i] ? i + 1 : i;
  }
  double tol = SNAP_EPS * fmax(fabs(v), fabs(e[k]));
  if (k > 0) tol = fmin(tol, 0.25 * (e[k] - e[k - 1]));
  if (k < n) tol = fmin(tol, 0.25 * (e[k + 1] - e[k]));
  if (fabs(v - e[k]) <= tol) return k < n ? k : n - 1;
  return gs_axis_locate(ax, v);
}

int gs_axis_lever(const gs_axis *ax, double v, size_t *lo, double *w) {
  const double *p = ax->pivots;
  size_t n = ax->n;
  if (v < p[0]) return -1;
  if (v > p[n - 1]) return 1;
  if (n == 1) {
    *lo = 0;
    *w = 0.0;
    return 0;
  }
  size_t i = bisect(p, n, v);
  if (i == n - 1) {
    *lo = n - 1;
    *w = 0.0;
    return 0;
  }
  *lo = i;
  *w = (v - p[i]) / (p[i + 1] - p[i]);
  return 0;
}
