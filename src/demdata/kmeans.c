/* k-means: k-means++ seeding, Lloyd's iterations, simplified silhouette (kmeans.h). */
#include "demdata/kmeans.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <gsl/gsl_rng.h>

#define KMEANS_MAX_ITER 500

static double dist2(const double *a, const double *b, size_t dim) {
  double s = 0;
  for (size_t d = 0; d < dim; d++) s += (a[d] - b[d]) * (a[d] - b[d]);
  return s;
}

static size_t nearest(const double *p, const double *centre, size_t k, size_t dim, double *d2) {
  size_t best = 0;
  double bd = HUGE_VAL;
  for (size_t c = 0; c < k; c++) {
    double d = dist2(p, centre + c * dim, dim);
    if (d < bd) {
      bd = d;
      best = c;
    }
  }
  if (d2) *d2 = bd;
  return best;
}

/* k-means++: the first centre uniformly, each next one with probability
 * proportional to the squared distance to the nearest chosen (w: n scratch). */
static void seed_pp(const double *x, size_t n, size_t dim, size_t k, gsl_rng *r, double *centre, double *w) {
  memcpy(centre, x + gsl_rng_uniform_int(r, n) * dim, dim * sizeof(double));
  for (size_t i = 0; i < n; i++) w[i] = dist2(x + i * dim, centre, dim);
  for (size_t c = 1; c < k; c++) {
    double total = 0;
    for (size_t i = 0; i < n; i++) total += w[i];
    size_t pick = gsl_rng_uniform_int(r, n); /* all points coincide: any */
    if (total > 0) {
      double u = gsl_rng_uniform(r) * total, s = 0;
      for (pick = 0; pick + 1 < n; pick++)
        if ((s += w[pick]) > u) break;
    }
    memcpy(centre + c * dim, x + pick * dim, dim * sizeof(double));
    for (size_t i = 0; i < n; i++) w[i] = fmin(w[i], dist2(x + i * dim, centre + c * dim, dim));
  }
}

/* Lloyd's iterations until no label changes; an emptied cluster takes the
 * point farthest from its centre.  Returns the inertia. */
static double lloyd(const double *x, size_t n, size_t dim, size_t k, double *centre, size_t *label,
                    size_t *count, int *iterations) {
  for (size_t i = 0; i < n; i++) label[i] = (size_t)-1;
  double inertia = 0;
  for (int it = 0; it < KMEANS_MAX_ITER; it++) {
    size_t changed = 0;
    inertia = 0;
    for (size_t i = 0; i < n; i++) {
      double d2;
      size_t c = nearest(x + i * dim, centre, k, dim, &d2);
      changed += c != label[i];
      label[i] = c;
      inertia += d2;
    }
    *iterations = it + 1;
    if (!changed) break;
    memset(centre, 0, k * dim * sizeof(double));
    memset(count, 0, k * sizeof(size_t));
    for (size_t i = 0; i < n; i++) {
      count[label[i]]++;
      for (size_t d = 0; d < dim; d++) centre[label[i] * dim + d] += x[i * dim + d];
    }
    for (size_t c = 0; c < k; c++) {
      if (count[c]) {
        for (size_t d = 0; d < dim; d++) centre[c * dim + d] /= (double)count[c];
        continue;
      }
      size_t far = 0;
      double fd = -1;
      for (size_t i = 0; i < n; i++) {
        double d2 = dist2(x + i * dim, centre + label[i] * dim, dim);
        if (d2 > fd) {
          fd = d2;
          far = i;
        }
      }
      memcpy(centre + c * dim, x + far * dim, dim * sizeof(double));
      label[far] = c;
    }
  }
  return inertia;
}

int gs_kmeans_run(const double *x, size_t n, size_t dim, size_t k, unsigned long seed, int starts,
                  gs_kmeans *out, gs_error *err) {
  memset(out, 0, sizeof *out);
  if (k < 1 || k > n) return gs_error_set(err, GS_EINPUT, "k-means: %zu clusters asked of %zu points", k, n);
  out->k = k;
  out->dim = dim;
  out->inertia = HUGE_VAL;
  out->centre = malloc(k * dim * sizeof(double));
  out->label = malloc(n * sizeof(size_t));
  double *centre = malloc(k * dim * sizeof(double)), *w = malloc(n * sizeof(double));
  size_t *label = malloc(n * sizeof(size_t)), *count = malloc(k * sizeof(size_t));
  gsl_rng *r = gsl_rng_alloc(gsl_rng_mt19937);
  int rc = out->centre && out->label && centre && w && label && count && r ? GS_OK : GS_ENOMEM;
  if (rc) gs_error_set(err, rc, "k-means: out of memory for %zu points", n);
  if (!rc) gsl_rng_set(r, seed);
  for (int s = 0; !rc && s < starts; s++) {
    int iterations = 0;
    seed_pp(x, n, dim, k, r, centre, w);
    double inertia = lloyd(x, n, dim, k, centre, label, count, &iterations);
    if (inertia < out->inertia) {
      out->inertia = inertia;
      out->iterations = iterations;
      memcpy(out->centre, centre, k * dim * sizeof(double));
      memcpy(out->label, label, n * sizeof(size_t));
    }
  }
  free(centre);
  free(w);
  free(label);
  free(count);
  gsl_rng_free(r);
  if (rc) gs_kmeans_free(out);
  return rc;
}

double gs_kmeans_silhouette(const double *x, size_t n, const gs_kmeans *km) {
  if (km->k < 2 || !n) return 0;
  double sum = 0;
  for (size_t i = 0; i < n; i++) {
    const double *p = x + i * km->dim;
    double a = sqrt(dist2(p, km->centre + km->label[i] * km->dim, km->dim)), b = HUGE_VAL;
    for (size_t c = 0; c < km->k; c++)
      if (c != km->label[i]) b = fmin(b, sqrt(dist2(p, km->centre + c * km->dim, km->dim)));
    const double m = fmax(a, b);
    sum += m > 0 ? (b - a) / m : 0;
  }
  return sum / (double)n;
}

void gs_kmeans_free(gs_kmeans *km) {
  free(km->centre);
  free(km->label);
  memset(km, 0, sizeof *km);
}
