/* The exchange network (src/pbm/exchange.c) against exact solutions:
 *  - two compartments exchanging both ways (k12 = a, k21 = b): every cell
 *    relaxes as N1 = N0 (b + a e^{-(a+b)t})/(a+b), N2 = N0 - N1;
 *  - a directed cycle 1 -> 2 -> 3 -> 1 at rate k with discharge d from every
 *    compartment: the matrix exponential's column
 *    N_j = N0 e^{-dt} (1/3 + 2/3 e^{-3kt/2} cos(sqrt(3) k t/2 - 2 pi (j-1)/3));
 *  - the matrix and the links forms give the same rates bit for bit;
 *  - the ledger: what the exchange moves leaves one compartment and enters
 *    another, so the total changes only by the discharge, to round-off;
 *  - bad input is refused naming the key. */
#include <omp.h>

#include "pbm_testlib.h"

#define GRID1                                                                                     \
  "grid:\n  compartments: %d\n  axes:\n"                                                          \
  "    - {name: solid, type: geometric, min: 1.0e-16, ratio: 2, cells: 24}\n"                     \
  "  carried: [liquid]\n"
#define INITIAL1                                                                                  \
  "initial: {type: gamma, number: 1.0e6, mean: 1.0e-14, shape: 6, compartment: 1,"               \
  " carried_ratio: {liquid: 0.25}}\n"

/* Worst relative error of every cell's number and liquid in compartment comp
 * of y against f times the initial compartment 1 of y0. */
static double cell_error(const gs_model *m, const double *y0, const double *y, size_t comp, double f) {
  double worst = 0, top = 0;
  const size_t n = m->grid.ncells;
  for (size_t i = 0; i < n; i++) top = fmax(top, y0[i]);
  for (size_t i = 0; i < n; i++) {
    if (y0[i] < 1e-6 * top) continue; /* the tails: absolute accuracy only */
    worst = fmax(worst, tl_relerr(gs_model_numbers_c(m, y, comp)[i], f * y0[i]));
    worst = fmax(worst, tl_relerr(gs_model_carried_c(m, y, comp, 0)[i], f * gs_model_carried_c(m, y0, 0, 0)[i]));
  }
  return worst;
}

/* Per compartment: held = initial + exchanged (no loss), relative to the total held. */
static double ledger_error(const gs_model *m, const double *y0, const double *y) {
  double worst = 0;
  for (int k = 0; k < m->nvol; k++) {
    double scale = 0;
    for (size_t comp = 0; comp < m->grid.ncomp; comp++) scale += gs_model_held(m, y0, comp, k);
    for (size_t comp = 0; comp < m->grid.ncomp; comp++) {
      const double *L = y + m->nstate;
      double want = gs_model_held(m, y0, comp, k) + tl_ext(m, L, comp, k) - tl_lost(m, L, comp, k);
      worst = fmax(worst, fabs(gs_model_held(m, y, comp, k) - want) / scale);
    }
  }
  return worst;
}

static void test_two_way(void) {
  const double a = 0.3, b = 0.7;
  const double ends[] = {0.5, 2, 6};
  for (size_t e = 0; e < 3; e++) {
    const double t = ends[e];
    char *yaml = tl_fmt(GRID1 INITIAL1
                        "mechanisms:\n  - {type: exchange, rates: [[0, %g], [%g, 0]]}\n"
                        "solver: {rtol: 1.0e-11, atol: 1.0e-9}\n"
                        "output: {end: %g}\n", 2, a, b, t);
    gs_case c;
    double *y = tl_build_run(yaml, &c, NULL);
    free(yaml);
    if (!y) continue;
    const double f1 = (b + a * exp(-(a + b) * t)) / (a + b);
    const double e1 = cell_error(&c.model, c.y0, y, 0, f1), e2 = cell_error(&c.model, c.y0, y, 1, 1 - f1);
    const double el = ledger_error(&c.model, c.y0, y);
    printf("two-way exchange, t = %g: cells' worst relative error %.3g / %.3g, ledger %.3g\n", t, e1, e2, el);
    CHECK(e1 < 1e-10 && e2 < 1e-10); /* 2e-12 measured at the integrator's rtol 1e-11 */
    CHECK(el < 1e-13);
    free(y);
    gs_case_free(&c);
  }
}

static double cycle_share(double k, double d, double t, int j) {
  return exp(-d * t) * (1.0 / 3 + 2.0 / 3 * exp(-1.5 * k * t) * cos(sqrt(3) / 2 * k * t - 2 * M_PI * j / 3));
}

static void test_cycle(void) {
  const double k = 0.8, d = 0.1, t = 1.7;
  /* the same network three ways: matrix, links by rate, links by residence time */
  char *forms[3] = {
      tl_fmt("rates: [[0, %g, 0], [0, 0, %g], [%g, 0, 0]], discharge: %g", k, k, k, d),
      tl_fmt("links: [{from: 1, to: 2, rate: %g}, {from: 2, to: 3, rate: %g}, {from: 3, to: 1, rate: %g}],"
             " discharge: [%g, %g, %g]", k, k, k, d, d, d),
      tl_fmt("links: [{from: 3, to: 1, residence_time: %.17g}, {from: 1, to: 2, residence_time: %.17g},"
             " {from: 2, to: 3, residence_time: %.17g}], discharge: %g", 1 / k, 1 / k, 1 / k, d)};
  double *first = NULL;
  for (int f = 0; f < 3; f++) {
    char *yaml = tl_fmt(GRID1 INITIAL1 "mechanisms:\n  - {type: exchange, %s}\n"
                        "solver: {rtol: 1.0e-11, atol: 1.0e-9}\noutput: {end: %g}\n", 3, forms[f], t);
    gs_case c;
    if (tl_case(yaml, &c) == 0) {
      const gs_model *m = &c.model;
      /* rates at a state with all three compartments filled */
      double *y = calloc(m->nstate, sizeof *y), *dy = calloc(m->nstate, sizeof *dy);
      double *dl = calloc(m->nledger, sizeof *dl);
      tl_rng r = {2024};
      for (size_t i = 0; i < m->nstate; i++) y[i] = tl_uniform(&r);
      gs_model_rhs(m, NULL, 0, y, dy, dl);
      if (!first) {
        first = dy;
        dy = NULL;
      } else {
        double diff = 0;
        for (size_t i = 0; i < m->nstate; i++) diff = fmax(diff, fabs(dy[i] - first[i]));
        CHECK(diff <= (f == 2 ? 1e-15 : 0)); /* 1/(1/k) may differ from k by an ulp */
      }
      /* the ledger's total change is the discharge alone */
      for (int q = 0; q < m->nvol; q++) {
        double total = 0, held = 0;
        for (size_t comp = 0; comp < 3; comp++) {
          total += tl_ext(m, dl, comp, q);
          held += gs_model_held(m, y, comp, q);
        }
        CHECK(fabs(total + d * held) <= 1e-15 * k * held);
      }
      free(y);
      free(dy);
      free(dl);
      y = tl_run(&c, NULL, NULL, NULL);
      if (y) {
        double worst = 0;
        for (int j = 0; j < 3; j++) worst = fmax(worst, cell_error(m, c.y0, y, (size_t)j, cycle_share(k, d, t, j)));
        const double el = ledger_error(m, c.y0, y);
        printf("cycle 1->2->3->1 with discharge (form %d): cells' worst relative error %.3g, ledger %.3g\n", f,
               worst, el);
        CHECK(worst < 1e-10);
        CHECK(el < 1e-13);
      }
      free(y);
      gs_case_free(&c);
    }
    free(yaml);
    free(forms[f]);
  }
  free(first);
}

static void test_bad_input(void) {
  const char *grid = "grid: {compartments: 2, axes: [{name: v, type: geometric, min: 1, ratio: 2, cells: 4}]}\n";
  char *y;
#define BAD(mech, ...)                                                                            \
  do {                                                                                            \
    y = tl_fmt("%smechanisms:\n  - {type: exchange, %s}\noutput: {end: 1}\n", grid, mech);        \
    EXPECT_INPUT(y, __VA_ARGS__);                                                                 \
    free(y);                                                                                      \
  } while (0)
  BAD("rates: [[0, 1]]", "expected 2 rows", "rates");
  BAD("rates: [[0, 1], [1]]", "expected 2 rates", "rates[1]");
  BAD("rates: [[1, 1], [1, 0]]", "diagonal", "rates[0][0]");
  BAD("rates: [[0, -1], [1, 0]]", ">= 0", "rates[0][1]");
  BAD("rates: [[0, 1], [1, 0]], links: []", "exactly one of 'rates'");
  BAD("discharge: 1", "exactly one of 'rates'");
  BAD("file: no-such-fragment.yaml", "no-such-fragment.yaml");
  BAD("links: [{from: 1, to: 1, rate: 1}]", "to itself");
  BAD("links: [{from: 1, to: 3, rate: 1}]", "to");
  BAD("links: [{from: 1, to: 2}]", "exactly one of 'rate'");
  BAD("links: [{from: 1, to: 2, rate: 1}, {from: 1, to: 2, residence_time: 2}]", "second link");
  BAD("links: [{from: 1, to: 2, residence_time: 0}]", "residence_time");
  BAD("rates: [[0, 1], [1, 0]], discharge: [1, -1]", "discharge");
  BAD("rates: [[0, 1], [1, 0]], rate: 1", "rate");
  y = tl_fmt("%smechanisms:\n  - {type: exchange, rates: [[0, 1], [1, 0]]}\n"
             "solver: {method: rk, steps: per_compartment}\noutput: {end: 1}\n", grid);
  EXPECT_INPUT(y, "steps", "exchange network");
  free(y);
#undef BAD
}

int main(void) {
  omp_set_num_threads(2);
  test_two_way();
  test_cycle();
  test_bad_input();
  TEST_EXIT();
}
