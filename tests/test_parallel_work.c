/* How work is shared between MPI ranks and OpenMP threads:
 *  - gs_dist_balanced_split (src/run/distributed.c), the contiguous split of
 *    compartments over ranks used when rebalancing: on 4,000 random cases
 *    (up to 9 compartments, 1-4 ranks, a fixed extra cost on some ranks) the
 *    split it returns is valid (contiguous, every rank at least one
 *    compartment), its largest block costs what it reports, and that is the
 *    optimum found by trying every split;
 *  - gs_dist_speedup_bound, the most a split over ranks can gain: exact on
 *    hand-worked cases, never above the rank count, and its largest block
 *    the optimum found by trying every split on 2,000 random cases;
 *  - gs_threads_for: one thread below the work threshold and inside a
 *    parallel region, OpenMP's team size otherwise. */
#include <omp.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "gransim/threads.h"
#include "run/distributed.h"

/* Cost of the largest block of split lo. */
static double largest_block(const double *cost, size_t n, const double *extra, int nr,
                            const size_t *lo) {
  double worst = 0;
  for (int r = 0; r < nr; r++) {
    double s = extra[r];
    for (size_t j = lo[r]; j < lo[r + 1]; j++) s += cost[j];
    if (s > worst) worst = s;
  }
  (void)n;
  return worst;
}

/* The best largest block over every split with non-empty blocks: the
 * boundaries lo[1] < ... < lo[nr-1] tried in lexicographic order. */
static double brute_force(const double *cost, size_t n, const double *extra, int nr) {
  size_t lo[8];
  lo[0] = 0;
  lo[nr] = n;
  for (int r = 1; r < nr; r++) lo[r] = (size_t)r;
  double best = INFINITY;
  for (;;) {
    double v = largest_block(cost, n, extra, nr, lo);
    if (v < best) best = v;
    int r = nr - 1;
    while (r >= 1 && lo[r] == n - (size_t)(nr - r)) r--;
    if (r < 1) break;
    lo[r]++;
    for (int k = r + 1; k < nr; k++) lo[k] = lo[k - 1] + 1;
  }
  return best;
}

static double uniform(unsigned *s) {
  *s = *s * 1664525u + 1013904223u;
  return (double)(*s >> 8) / 16777216.0;
}

/* One random case of n compartments over nr ranks, drawing the rest from
 * seed; 1 when it fails (said on stderr when report is set). */
typedef int (*trial_fn)(unsigned *seed, int trial, size_t n, int nr, int report);

/* `trials` random cases of 1-9 compartments over 1-4 ranks (at most one
 * rank per compartment); every one must pass. */
static void random_trials(unsigned seed, int trials, trial_fn one) {
  int bad = 0;
  for (int trial = 0; trial < trials; trial++) {
    const size_t n = 1 + (size_t)(uniform(&seed) * 9);
    int nr = 1 + (int)(uniform(&seed) * 4);
    if ((size_t)nr > n) nr = (int)n;
    bad += one(&seed, trial, n, nr, bad < 5);
  }
  CHECK(bad == 0);
}

/* The split is valid, costs what it reports, and no split does better. */
static int split_trial(unsigned *seed, int trial, size_t n, int nr, int report) {
  double cost[9] = {0}, extra[4] = {0};
  for (size_t j = 0; j < n; j++) cost[j] = 0.1 + uniform(seed);
  for (int r = 0; r < nr; r++) extra[r] = uniform(seed) < 0.5 ? 0.0 : 2 * uniform(seed);
  size_t lo[5];
  double got = gs_dist_balanced_split(cost, n, extra, nr, lo);
  int valid = lo[0] == 0 && lo[nr] == n;
  for (int r = 0; r < nr; r++) valid = valid && lo[r] < lo[r + 1];
  if (!valid) {
    if (report) fprintf(stderr, "trial %d: n %zu ranks %d: invalid split\n", trial, n, nr);
    return 1;
  }
  double actual = largest_block(cost, n, extra, nr, lo), best = brute_force(cost, n, extra, nr);
  if (fabs(got - actual) <= 1e-12 * actual && actual <= best * (1 + 1e-9)) return 0;
  if (report)
    fprintf(stderr, "trial %d: n %zu ranks %d: split gives %.15g (reported %.15g), best %.15g\n",
            trial, n, nr, actual, got, best);
  return 1;
}

static void split_is_optimal(void) {
  random_trials(12345, 4000, split_trial);
  /* the CoriMix example's shape: costs growing downstream, rank 0 writing */
  const double cost[4] = {16, 20.5, 21.2, 21.3}, extra[2] = {10, 0};
  size_t lo[3];
  CHECK_REL(gs_dist_balanced_split(cost, 4, extra, 2, lo), 46.5, 1e-12);
  CHECK(lo[1] == 2);
  const double none[2] = {0, 0};
  CHECK_REL(gs_dist_balanced_split(cost, 4, none, 2, lo), 42.5, 1e-12);
  CHECK(lo[1] == 2);
}

/* The bound lies in [1, nr], its largest block is the best split of the
 * costs with the unmeasured rates and the integrator shared evenly. */
static int bound_trial(unsigned *seed, int trial, size_t n, int nr, int report) {
  double c[9], measured = 0, largest;
  for (size_t j = 0; j < n; j++) measured += c[j] = uniform(seed);
  const double rates = measured * (1 + uniform(seed)), integ = uniform(seed);
  const double serial = 0.2 * uniform(seed), total = rates + integ + serial + uniform(seed);
  double b = gs_dist_speedup_bound(c, n, rates, integ, serial, total, nr, &largest);
  double shared[9], none[4] = {0, 0, 0, 0};
  for (size_t j = 0; j < n; j++) shared[j] = c[j] + (rates - measured + integ) / (double)n;
  const double best = brute_force(shared, n, none, nr);
  const double expect = total / (fmax(best, (total - serial) / nr) + serial);
  if (b >= 1 - 1e-12 && b <= nr * (1 + 1e-12) && fabs(largest - best) <= 1e-12 * best &&
      fabs(b - expect) <= 1e-12 * expect)
    return 0;
  if (report)
    fprintf(stderr, "trial %d: n %zu ranks %d: bound %.15g (expected %.15g), block %.15g (best %.15g)\n",
            trial, n, nr, b, expect, largest, best);
  return 1;
}

static void speedup_bound(void) {
  double largest;
  /* rates measured whole; integrator 1 s per compartment; 1 s serial:
   * blocks {19, 26 | 30, 30}: 60 s > (120 - 1) / 2 */
  const double cost[4] = {18, 25, 29, 29};
  CHECK_REL(gs_dist_speedup_bound(cost, 4, 101, 4, 1, 120, 2, &largest), 120.0 / 61.0, 1e-14);
  CHECK_REL(largest, 60, 1e-12);
  /* 20 s of the rates unmeasured: 5 s more for each; then the parallel
   * rest, not the largest block, sets the bound */
  const double even[4] = {10, 10, 10, 10};
  CHECK_REL(gs_dist_speedup_bound(even, 4, 60, 0, 0, 70, 2, &largest), 2.0, 1e-14);
  CHECK_REL(largest, 30, 1e-12);
  CHECK_REL(gs_dist_speedup_bound(even, 4, 60, 0, 0, 70, 4, &largest), 4.0, 1e-14);
  CHECK_REL(gs_dist_speedup_bound(even, 4, 60, 0, 10, 70, 4, &largest), 70.0 / 25.0, 1e-14);
  /* no such split, or nothing measured */
  CHECK(isnan(gs_dist_speedup_bound(even, 4, 60, 0, 0, 70, 5, &largest)) && isnan(largest));
  CHECK(isnan(gs_dist_speedup_bound(even, 4, 60, 0, 0, 0, 2, &largest)));
  CHECK(isnan(gs_dist_speedup_bound(even, 4, 60, 0, 0, 70, 0, &largest)));
  random_trials(777, 2000, bound_trial);
}

static void threads_for(void) {
  omp_set_num_threads(2);
  CHECK(gs_threads_for(10, 100) == 1);
  CHECK(gs_threads_for(100, 100) == 2);
  int inner = 0;
#pragma omp parallel num_threads(2)
  {
#pragma omp single
    inner = gs_threads_for(1000, 1);
  }
  CHECK(inner == 1);
  omp_set_num_threads(1);
  CHECK(gs_threads_for(1000, 1) == 1);
}

int main(void) {
  split_is_optimal();
  speedup_bound();
  threads_for();
  TEST_EXIT();
}
