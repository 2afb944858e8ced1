/* Size statistics of a compartment (src/pbm/summary.c) against a direct
 * evaluation of their definition: volume-weighted percentiles of the
 * volume-equivalent diameter, each cell's volume (at its granule volume:
 * size axes plus carried volume per particle) spread evenly between its
 * edges' granule volumes.  Random populations on a 2-D grid with
 * carried volumes, many with equal volumes (the grid's symmetric cells), one
 * occupied cell, and an empty compartment; and continuity: a change of one
 * part in 1e9 in one cell (or a new cell of that weight) moves no
 * percentile by more than a few parts in 1e9 of the diameter (as point
 * masses they jumped by up to a whole cell).  Sieve fractions
 * (gs_sieve_fractions) on the same distribution: classes cut at d10, d50,
 * d90 hold 0.1, 0.4, 0.4, 0.1; one cell's classes the parts of its volume
 * range. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "gransim/case.h"
#include "gransim/pbm.h"
#include "pbm_testlib.h"

typedef struct {
  double lo, hi, w;
} range;

/* The cumulative volume fraction at granule volume d: each cell's volume
 * spread evenly over its edges' granule volumes. */
static double cumulative(const range *r, size_t n, double d) {
  double F = 0;
  for (size_t i = 0; i < n; i++) F += r[i].w * fmin(1, fmax(0, (d - r[i].lo) / (r[i].hi - r[i].lo)));
  return F;
}

/* The definition, written plainly: the ranges of the occupied cells, then
 * each percentile by bisection of the cumulative fraction to the last bit. */
static void reference(const gs_model *m, const double *y, size_t comp, double out[3]) {
  const gs_grid *g = &m->grid;
  const double *N = gs_model_numbers_c(m, y, comp);
  range *r = malloc(g->ncells * sizeof *r);
  size_t k = 0;
  double total = 0, vmin = INFINITY, vmax = 0;
  for (size_t c = 0; c < g->ncells; c++) {
    if (!(N[c] > 0)) continue;
    double carried = 0;
    for (int q = 0; q < m->ncarried; q++) carried += gs_model_carried_c(m, y, comp, q)[c] / N[c];
    size_t idx[2];
    gs_grid_unindex(g, c, idx);
    double lo = carried, hi = carried;
    for (int a = 0; a < g->dim; a++) {
      lo += g->axis[a].edges[idx[a]];
      hi += g->axis[a].edges[idx[a] + 1];
    }
    r[k] = (range){lo, hi, N[c] * (m->size_volume[c] + carried)};
    total += r[k].w;
    vmin = fmin(vmin, r[k].lo);
    vmax = fmax(vmax, r[k].hi);
    k++;
  }
  const double p[3] = {0.1, 0.5, 0.9};
  for (int j = 0; j < 3; j++) {
    double a = vmin, b = vmax;
    if (!k) a = b = NAN;
    while (k && b - a > 1e-16 * b) {
      double mid = 0.5 * (a + b);
      if (mid <= a || mid >= b) break;
      if (cumulative(r, k, mid) < p[j] * total) a = mid;
      else b = mid;
    }
    out[j] = gs_diameter(b);
  }
  free(r);
}

static double worst_rel(const double a[3], const double b[3]) {
  double w = 0;
  for (int i = 0; i < 3; i++) w = fmax(w, fabs(a[i] - b[i]) / fabs(b[i]));
  return w;
}

int main(void) {
  const char *yaml = "grid:\n  compartments: 3\n  axes:\n"
                     "    - {name: api, type: geometric, min: 5.0e-16, ratio: 3, cells: 16}\n"
                     "    - {name: excipient, type: geometric, min: 5.0e-16, ratio: 3, cells: 16}\n"
                     "  carried: [liquid, gas]\n"
                     "initial: {type: cell, number: 1, index: [1, 1]}\n"
                     "output: {end: 1, count: 2}\n";
  gs_case c;
  if (tl_case(yaml, &c)) TEST_EXIT();
  const gs_model *m = &c.model;
  const gs_grid *g = &m->grid;
  double *y = calloc(m->nstate + m->nledger, sizeof *y);
  tl_rng r = {2024};
  double worst = 0, worst_jump = 0, worst_frac = 0;
  for (int trial = 0; trial < 200; trial++) {
    memset(y, 0, m->nstate * sizeof *y);
    /* compartment 0: a random population, with loads that are the same
     * fraction of the solid volume in half the trials (equal volumes in
     * the grid's symmetric cells survive then) */
    double *N = gs_model_numbers(m, y, 0);
    const int proportional = trial % 2;
    for (size_t cell = 0; cell < g->ncells; cell++) {
      if (tl_uniform(&r) < 0.3) continue;
      N[cell] = 1e6 * tl_uniform(&r);
      for (int q = 0; q < m->ncarried; q++)
        gs_model_carried(m, y, 0, q)[cell] =
            N[cell] * m->size_volume[cell] * (proportional ? 0.25 * (q + 1) : tl_uniform(&r));
    }
    /* compartment 1: one occupied cell */
    size_t one = (size_t)(tl_uniform(&r) * (double)g->ncells) % g->ncells;
    gs_model_numbers(m, y, 1)[one] = 42;
    gs_summary s;
    double got[3], want[3];
    gs_summarize(m, y, 0, &s);
    got[0] = s.d10, got[1] = s.d50, got[2] = s.d90;
    reference(m, y, 0, want);
    worst = fmax(worst, worst_rel(got, want));
    CHECK(s.d10 <= s.d50 && s.d50 <= s.d90);
    /* sieve fractions on the same cumulative distribution: the classes cut
     * at the percentiles hold 0.1, 0.4, 0.4, 0.1 of the volume */
    const double cuts[5] = {0, s.d10, s.d50, s.d90, INFINITY}, want_frac[4] = {0.1, 0.4, 0.4, 0.1};
    double frac[4];
    gs_sieve_fractions(m, y, 0, cuts, 4, frac);
    for (int k = 0; k < 4; k++) worst_frac = fmax(worst_frac, fabs(frac[k] - want_frac[k]));
    /* continuity: one cell's number changed by one part in 1e9 (from 0 in
     * an empty cell) */
    size_t moved = (size_t)(tl_uniform(&r) * (double)g->ncells) % g->ncells;
    const double before = N[moved];
    N[moved] = before > 0 ? before * (1 + 1e-9) : 1e-9 * s.m1 / m->size_volume[moved];
    gs_summary s2;
    gs_summarize(m, y, 0, &s2);
    const double jump = fmax(fabs(s2.d10 - s.d10) / s.d10,
                             fmax(fabs(s2.d50 - s.d50) / s.d50, fabs(s2.d90 - s.d90) / s.d90));
    worst_jump = fmax(worst_jump, jump);
    N[moved] = before;
    gs_summarize(m, y, 1, &s);
    size_t idx[2];
    gs_grid_unindex(g, one, idx);
    const double vlo = g->axis[0].edges[idx[0]] + g->axis[1].edges[idx[1]],
                 vhi = g->axis[0].edges[idx[0] + 1] + g->axis[1].edges[idx[1] + 1];
    CHECK(fabs(s.d10 / gs_diameter(vlo + 0.1 * (vhi - vlo)) - 1) <= 1e-14);
    CHECK(fabs(s.d50 / gs_diameter(vlo + 0.5 * (vhi - vlo)) - 1) <= 1e-14);
    CHECK(fabs(s.d90 / gs_diameter(vlo + 0.9 * (vhi - vlo)) - 1) <= 1e-14);
    /* one cell: a class over 0.3 of its volume range holds 0.3; classes
     * beside it nothing */
    const double one_cuts[4] = {gs_diameter(0.5 * vlo), gs_diameter(vlo + 0.2 * (vhi - vlo)),
                                gs_diameter(vlo + 0.5 * (vhi - vlo)), gs_diameter(2 * vhi)};
    double one_frac[3];
    gs_sieve_fractions(m, y, 1, one_cuts, 3, one_frac);
    CHECK(fabs(one_frac[0] - 0.2) <= 1e-12 && fabs(one_frac[1] - 0.3) <= 1e-12 &&
          fabs(one_frac[2] - 0.5) <= 1e-12);
    gs_sieve_fractions(m, y, 1, one_cuts + 2, 1, one_frac);
    CHECK(fabs(one_frac[0] - 0.5) <= 1e-12);
    gs_sieve_fractions(m, y, 2, cuts, 1, one_frac);
    CHECK(isnan(one_frac[0]));
    gs_summarize(m, y, 2, &s);
    CHECK(isnan(s.d10) && isnan(s.d50) && isnan(s.d90) && s.m0 == 0);
  }
  printf("summary percentiles, 200 random compartments: worst relative difference %.3g; "
         "largest move for a change of 1e-9 in one cell %.3g\n", worst, worst_jump);
  /* a different algorithm (bisection of the cumulative sum): round-off */
  CHECK(worst < 1e-12);
  CHECK(worst_jump < 1e-7);
  printf("sieve fractions between the percentiles: worst difference %.3g\n", worst_frac);
  CHECK(worst_frac < 1e-12);
  free(y);
  gs_case_free(&c);
  TEST_EXIT();
}
