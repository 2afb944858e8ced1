/* Aggregation's right-hand side depends on its arguments only.  The
 * mechanism keeps per-thread accumulators between evaluations and clears
 * only the cells the last use wrote (the population of a large grid sits in
 * a band); a cell left uncleared would add an earlier evaluation's sums to a
 * later one.  So: evaluations on states whose populations occupy different
 * cells, one after the other, must give the bits of a fresh model's single
 * evaluation, in each way the work is shared:
 *  - one thread;
 *  - a team sharing one compartment's pair loop (576 cells, 2 threads);
 *  - threads taking whole compartments (8 x 576 cells, 2 threads);
 * with cell-average redistribution and carried loads (wet "either": two
 * passes), and with fixed pivot.  Also: a stray cell holding a denormal
 * number with a finite load (its load per particle overflows) takes part in
 * no event and leaves every rate finite; and a model made for one thread,
 * evaluated after the program asked OpenMP for more, keeps the team it has
 * scratch for (a larger team had written past the per-thread accumulators).
 * And wet "either" (all pairs minus the dry pairs) subtracts only dry pairs
 * among the cells the first pass took part in: outside an integrator the
 * second pass had chosen its cells afresh among the dry ones alone, so a dry
 * cell negligible in the whole compartment got a negative event rate.
 * Every evaluation also keeps each volume coordinate: what the rates move
 * plus what the ledger books as lost is zero to round-off, also when pooled
 * births are clamped at the last pivot in the subtracted dry pass (their
 * clamped volume had been booked with the wrong sign: the CoriMix example
 * with "either" broke its volume balance by 1.2e-9 at t = 38). */
#include <omp.h>

#include "pbm_testlib.h"

#define NAX 24 /* cells per axis: 576 per compartment */

static char *case_yaml(int ncomp, int fixed_pivot) {
  return tl_fmt("grid:\n  compartments: %d\n  axes:\n"
                "    - {name: a, type: geometric, min: 1.0e-3, ratio: 1.6, cells: %d}\n"
                "    - {name: b, type: geometric, min: 1.0e-3, ratio: 1.6, cells: %d}\n"
                "%s"
                "mechanisms:\n"
                "  - {type: aggregation, redistribution: %s, %s kernel: {type: sum, beta0: 1.0e-3}}\n"
                "output: {end: 1}\n",
                ncomp, NAX, NAX, fixed_pivot ? "" : "  carried: [liquid, gas]\n",
                fixed_pivot ? "fixed_pivot" : "cell_average",
                fixed_pivot ? "" : "wet: {min_content: 0.05, partners: either},");
}

/* State k: a population in a box of cells [lo0, hi0) x [lo1, hi1) per
 * compartment, different for each k and compartment; k = 3: the box of k =
 * 1 all wet, plus one dominant wet cell that makes the box negligible
 * (below 1e-14 of number and volume), plus a dry box elsewhere that is
 * negligible against all of it but not against the dry cells alone: with
 * "either", the second pass (the dry pairs) must keep the first pass's
 * cells (check_either_subset), whose loads alone are computed. */
static void fill_state(const gs_model *m, int k, double *y) {
  /* k = 4: at the top of both axes, where pooled births are clamped at the
   * last pivot (and products beyond the last edge are lost) */
  static const size_t boxes[5][4] = {{0, 18, 0, 18}, {12, 20, 14, 22}, {2, 6, 1, 5}, {0, 0, 0, 0},
                                     {19, 24, 19, 24}};
  const gs_grid *g = &m->grid;
  if (k == 3) {
    fill_state(m, 1, y);
    for (size_t comp = 0; comp < g->ncomp; comp++) {
      double *N = gs_model_numbers(m, y, comp);
      const size_t big = 16 * NAX + 17, dry[2] = {2 * NAX + 20, 20 * NAX + 3};
      N[big] = 1e25;
      for (int i = 0; i < 2; i++) N[dry[i]] = 1e3;
      for (int q = 0; q < m->ncarried; q++) {
        double *Q = gs_model_carried(m, y, comp, q);
        for (size_t c = 0; c < g->ncells; c++)
          if (N[c] > 0) Q[c] = N[c] * g->volume[c] * (q == 0 ? 0.3 : 0.2); /* wet */
        for (int i = 0; i < 2; i++) Q[dry[i]] = q == 0 ? 0.01 * N[dry[i]] * g->volume[dry[i]] : Q[dry[i]];
      }
    }
    return;
  }
  memset(y, 0, m->nstate * sizeof *y);
  tl_rng r = {1000u + (uint64_t)k};
  for (size_t comp = 0; comp < g->ncomp; comp++) {
    const size_t *b = boxes[k == 4 ? 4 : (k + comp) % 3];
    double *N = gs_model_numbers(m, y, comp);
    for (size_t i = b[0]; i < b[1]; i++)
      for (size_t j = b[2]; j < b[3]; j++) {
        size_t c = i * NAX + j;
        N[c] = 1e3 * (0.1 + tl_uniform(&r));
        /* liquid / solid: wet (0.3) or dry (0.01) at random; gas 0.2 of the solid */
        for (int q = 0; q < m->ncarried; q++)
          gs_model_carried(m, y, comp, q)[c] =
              N[c] * g->volume[c] * (q == 0 ? (tl_uniform(&r) < 0.6 ? 0.3 : 0.01) : 0.2);
      }
  }
}

/* Largest |volume moved + volume lost| / volume turned over, over the
 * compartments and coordinates of one evaluation. */
static double imbalance(const gs_model *m, const double *d, const double *dl) {
  const gs_grid *g = &m->grid;
  double worst = 0;
  for (size_t comp = 0; comp < g->ncomp; comp++)
    for (int k = 0; k < m->nvol; k++) {
      double change = tl_lost(m, dl, comp, k), scale = 0;
      for (size_t c = 0; c < g->ncells; c++) {
        double dv = k < g->dim ? gs_model_numbers_c(m, d, comp)[c] * g->x[c * (size_t)g->dim + (size_t)k]
                               : gs_model_carried_c(m, d, comp, k - g->dim)[c];
        change += dv;
        scale += fabs(dv);
      }
      if (scale > 0) worst = fmax(worst, fabs(change) / scale);
    }
  return worst;
}

/* Rates of state k: into d (nstate) and dl (nledger). */
static void rates(const gs_model *m, int k, double *y, double *d, double *dl) {
  fill_state(m, k, y);
  gs_model_rhs(m, NULL, 0.1 * k, y, d, dl);
}

/* threads_later: OpenMP's team size set after the models are made */
static void check_history(const char *what, int threads, int ncomp, int fixed_pivot,
                          int threads_later) {
  omp_set_num_threads(threads); /* before the case: the mechanism sizes its slots by it */
  char *yaml = case_yaml(ncomp, fixed_pivot);
  gs_case c;
  if (tl_case(yaml, &c)) {
    free(yaml);
    return;
  }
  const gs_model *m = &c.model;
  const size_t ns = m->nstate, nl = m->nledger;
  double *y = malloc(ns * sizeof *y), *d = malloc(ns * sizeof *d), *dl = malloc(nl * sizeof *dl);
  double *fresh = malloc(ns * sizeof *fresh), *fresh_l = malloc(nl * sizeof *fresh_l);
  /* the states in turn on one model (wide, high, low, wide again) */
  static const int order[] = {0, 1, 2, 0, 3, 4, 2, 1, 3, 4};
  int differ = 0;
  size_t nonfinite = 0; /* a load read where it was not computed is NaN */
  double worst = 0;
  for (size_t i = 0; i < sizeof order / sizeof *order; i++) {
    gs_case other;
    omp_set_num_threads(threads);
    if (tl_case(yaml, &other)) break;
    omp_set_num_threads(threads_later);
    rates(m, order[i], y, d, dl);
    rates(&other.model, order[i], y, fresh, fresh_l);
    if (memcmp(d, fresh, ns * sizeof *d) || memcmp(dl, fresh_l, nl * sizeof *dl)) differ++;
    for (size_t j = 0; j < ns; j++) nonfinite += !isfinite(d[j]) || !isfinite(fresh[j]);
    worst = fmax(worst, imbalance(m, d, dl));
    gs_case_free(&other);
  }
  printf("aggregation history, %s (%d thread(s), then %d asked; %d compartment(s)): %d of %zu "
         "evaluations differ from a fresh model's; worst volume imbalance %.2g of the turnover\n",
         what, threads, threads_later, ncomp, differ, sizeof order / sizeof *order, worst);
  CHECK(differ == 0);
  CHECK(nonfinite == 0);
  CHECK(worst < 1e-13);
  free(y);
  free(d);
  free(dl);
  free(fresh);
  free(fresh_l);
  free(yaml);
  gs_case_free(&c);
}

/* One compartment, one thread, carried loads: a model and its vectors. */
typedef struct {
  char *yaml;
  gs_case c;
  double *y, *d, *dl;
} single_t;

static int single_open(single_t *s) {
  omp_set_num_threads(1);
  s->yaml = case_yaml(1, 0);
  if (tl_case(s->yaml, &s->c)) {
    free(s->yaml);
    return 1;
  }
  const gs_model *m = &s->c.model;
  s->y = malloc(m->nstate * sizeof *s->y);
  s->d = malloc(m->nstate * sizeof *s->d);
  s->dl = malloc(m->nledger * sizeof *s->dl);
  return 0;
}

static void single_close(single_t *s) {
  free(s->y);
  free(s->d);
  free(s->dl);
  free(s->yaml);
  gs_case_free(&s->c);
}

/* A denormal number with a finite load next to the population: no event
 * involves it (its pairs' rates underflow to zero), so no load may be lost
 * from it, and 0 x (an overflowed load) must not turn its rate into NaN. */
static void check_denormal_cell(void) {
  single_t s;
  if (single_open(&s)) return;
  const gs_model *m = &s.c.model;
  double *y = s.y, *d = s.d, *dl = s.dl;
  fill_state(m, 2, y);
  const size_t stray = 3 * NAX + 9; /* inside the range the pairs write, outside the box */
  gs_model_numbers(m, y, 0)[stray] = 4.9e-324;
  gs_model_carried(m, y, 0, 0)[stray] = 1e-3;
  gs_model_rhs(m, NULL, 0, y, d, dl);
  size_t bad = 0;
  for (size_t i = 0; i < m->nstate; i++) bad += !isfinite(d[i]);
  printf("aggregation, a denormal number with a finite load: %zu non-finite rates\n", bad);
  CHECK(bad == 0);
  single_close(&s);
}

/* State 3 outside an integrator: the dry cells are negligible against the
 * whole compartment, so no event involves them. */
static void check_either_subset(void) {
  single_t s;
  if (single_open(&s)) return;
  const gs_model *m = &s.c.model;
  double *d = s.d;
  rates(m, 3, s.y, d, s.dl);
  const size_t dry[2] = {2 * NAX + 20, 20 * NAX + 3};
  double worst = 0;
  for (int i = 0; i < 2; i++) {
    worst = fmax(worst, fabs(d[dry[i]]));
    for (int q = 0; q < m->ncarried; q++) worst = fmax(worst, fabs(gs_model_carried(m, d, 0, q)[dry[i]]));
  }
  printf("aggregation, wet either: largest rate of a negligible dry cell %g (want 0)\n", worst);
  CHECK(worst == 0.0);
  single_close(&s);
}

int main(void) {
  check_history("cell average, carried, wet either", 1, 1, 0, 1);
  check_history("cell average, carried, wet either", 2, 1, 0, 2);
  check_history("cell average, carried, wet either", 2, 8, 0, 2);
  check_history("fixed pivot", 1, 1, 1, 1);
  check_history("fixed pivot", 2, 1, 1, 2);
  check_history("fixed pivot", 2, 8, 1, 2);
  /* made for one thread, evaluated with 4 asked: the team it was made for */
  check_history("cell average, carried, wet either", 1, 1, 0, 4);
  check_history("cell average, carried, wet either", 1, 8, 0, 4);
  check_denormal_cell();
  check_either_subset();
  TEST_EXIT();
}
