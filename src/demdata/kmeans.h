/* k-means clustering (Lloyd's iterations from k-means++ seeds, Arthur &
 * Vassilvitskii 2007) of n points in dim dimensions, and the simplified
 * silhouette that chooses k (Rousseeuw 1987; the centroid form of
 * Vendramin et al. 2010, O(n k) instead of O(n^2)).  Seeds come from GSL's
 * generator (mt19937) with a fixed seed, so results repeat exactly. */
#ifndef GRANSIM_DEMDATA_KMEANS_H
#define GRANSIM_DEMDATA_KMEANS_H
#include <stddef.h>

#include "gransim/error.h"

typedef struct {
  size_t k, dim;
  double *centre;  /* k * dim */
  size_t *label;   /* n: each point's cluster, 0..k-1 */
  double inertia;  /* sum of squared distances to the centres */
  int iterations;  /* Lloyd iterations of the best start */
} gs_kmeans;

/* Best of `starts` k-means++ starts (lowest inertia), seeded with seed. */
int gs_kmeans_run(const double *x, size_t n, size_t dim, size_t k, unsigned long seed, int starts,
                  gs_kmeans *out, gs_error *err);
/* Mean over the points of (b - a) / max(a, b), a the distance to the own
 * centre, b to the nearest other one: near 1 for compact, separated clusters. */
double gs_kmeans_silhouette(const double *x, size_t n, const gs_kmeans *km);
void gs_kmeans_free(gs_kmeans *km);
#endif
