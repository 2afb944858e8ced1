/* Growth-type mechanisms and compartments in full runs (gs_case_run, balance
 * checks on):
 *  - T6 aggregation + linear growth (Ramabhadran, Peterson & Seinfeld 1976):
 *    the upwind scheme gives d(sum N x)/dt = sum G N exactly, so with G = sigma v
 *    M1 = N0 v0 e^{sigma t} and M0 = 2 N0/(2 + beta0 N0 t) hold to the
 *    integrator's accuracy; the distribution carries first-order smearing;
 *  - constant growth moves the number-mean by exactly G0 t;
 *  - liquid addition adds exactly rate x time of liquid, shared in proportion
 *    to solid volume (per solid column, the mean liquid grows by Q t s/S);
 *  - consolidation drains gas until the porosity reaches its minimum, and
 *    never moves particles more than one gas cell below it;
 *  - feed + transfer through three compartments against the closed-form
 *    tanks-in-series solutions (constant feed and pulse), with the ledger
 *    balance held = fed - discharged;
 *  - the volume balance holds to round-off under CVODE's Newton iterations,
 *    with preconditioned GMRES and with the dense Jacobian.
 * Tolerances are ~2-3x the errors measured when they were set (stated at
 * each check). */
#include <gsl/gsl_sf_gamma.h>
#include <omp.h>

#include "pbm/growth_scheme.h"
#include "pbm_testlib.h"

/* ---- T6: aggregation + linear growth ----------------------------------------------- */
typedef struct {
  double m0, m1;
} t6_par;
static double t6_density(double v, void *p) {
  const t6_par *q = p;
  return q->m0 * q->m0 / q->m1 * exp(-q->m0 * v / q->m1);
}

static void test_t6(void) {
  /* N0 = v0 = beta0 = 1, sigma = 0.5 to t = 2; grid [0, 1e-3 ... 1e4] ratio
   * 2^(1/4) (nothing reaches the top: lost 3e-22).  Measured: M0 1.9e-12,
   * M1 4.7e-12 (both schemes; closed moment equations, so only the
   * integrator's error); distance to the projected exact solution CA 0.129,
   * FP 0.134 (first-order upwind growth smears the distribution).
   * Tolerances: M0, M1 2e-11 (4x); distance 0.3. */
  static const char *schemes[] = {"cell_average", "fixed_pivot"};
  for (int s = 0; s < 2; s++) {
    double sigma = 0.5, t = 2;
    int cells = 1 + (int)ceil(log(1e4 / 1e-3) / log(pow(2, 0.25)));
    char *yaml = tl_fmt("grid: {axes: [{name: v, type: geometric, min: 1.0e-3, ratio: 1.189207115002721, cells: %d, zero_first: true}]}\n"
                        "initial: {type: exponential, number: 1, mean: 1}\n"
                        "mechanisms:\n"
                        "  - {type: aggregation, redistribution: %s, kernel: {type: constant, beta0: 1}}\n"
                        "  - {type: growth, axis: v, linear: %g}\n"
                        "output: {times: [%g]}\n",
                        cells, schemes[s], sigma, t);
    gs_case c;
    gs_run_report rep;
    double *y = tl_build_run(yaml, &c, &rep);
    if (y) {
      double M0 = tl_mom(&c, y, 0, 0, 0, 0), M1 = tl_mom(&c, y, 0, 1, 0, 0);
      double M1_0 = tl_mom(&c, c.y0, 0, 1, 0, 0);
      double m0 = 2 / (2 + t), m1 = M1_0 * exp(sigma * t);
      const gs_axis *ax = &c.model.grid.axis[0];
      double *P = malloc(ax->n * sizeof(double));
      t6_par q = {m0, m1};
      tl_project(ax, t6_density, &q, P);
      double dist = tl_wl1(ax, y, P);
      printf("T6 aggregation + growth, %s, t = %g: M0 %.3g M1 %.3g dist %.3g (lost %.3g)\n", schemes[s], t,
             tl_relerr(M0, m0), tl_relerr(M1, m1), dist, rep.max_loss);
      CHECK(tl_relerr(M0, m0) < 2e-11);
      CHECK(tl_relerr(M1, m1) < 2e-11);
      CHECK(dist < 0.3);
      /* growth is booked as external volume: M1 - M1(0) = ext - lost */
      const double *L = y + c.model.nstate;
      CHECK_REL(tl_ext(&c.model, L, 0, 0) - tl_lost(&c.model, L, 0, 0), M1 - M1_0, 1e-12);
      free(P);
      free(y);
      gs_case_free(&c);
    }
    free(yaml);
  }
}

/* ---- constant growth, and shrinkage ----------------------------------------------------- */
static void test_constant_growth(void) {
  /* Linear grid [0, 40], 200 cells; Gamma(40) with mean 10; G0 = +-0.5 for
   * t = 4: the mean moves by exactly G0 t while nothing sits at the ends
   * (measured relative error of the displacement: 0 for growth, 2.0e-9 for
   * shrinkage, where 9e-8 particles reach the first pivot and stay;
   * tolerance 1e-8), number unchanged to round-off. */
  for (int sign = 1; sign >= -1; sign -= 2) {
    double G0 = 0.5 * sign, t = 4;
    char *yaml = tl_fmt("grid: {axes: [{name: v, type: linear, min: 0, max: 40, cells: 200}]}\n"
                        "initial: {type: gamma, number: 3, mean: 10, shape: 40}\n"
                        "mechanisms:\n  - {type: growth, axis: v, constant: %g}\n"
                        "output: {end: %g, count: 5}\n",
                        G0, t);
    gs_case c;
    gs_run_report rep;
    double *y = tl_build_run(yaml, &c, &rep);
    if (y) {
      gs_summary s0, s1;
      gs_summarize(&c.model, c.y0, 0, &s0);
      gs_summarize(&c.model, y, 0, &s1);
      printf("constant growth G0 = %g: mean moved by G0 t with relative error %.3g; number changed %.3g; lost %.3g\n", G0,
             fabs(s1.mean[0] - s0.mean[0] - G0 * t) / fabs(G0 * t), s1.m0 / s0.m0 - 1, rep.max_loss);
      CHECK_REL(s1.m0, s0.m0, 1e-13);
      CHECK(fabs(s1.mean[0] - s0.mean[0] - G0 * t) < 1e-8 * fabs(G0 * t));
      CHECK(rep.max_loss < 1e-12); /* measured: nothing reaches the ends (0) */
      free(y);
      gs_case_free(&c);
    }
    free(yaml);
  }
}

/* ---- liquid addition ---------------------------------------------------------------------- */
static void test_liquid_addition(void) {
  /* 2-D solid x liquid (geometric 24 x linear 60 cells), two compartments
   * with spray rates 0.3 and 0.1 during [0, 2), run to t = 3.  Exact for the
   * scheme: liquid added = rate x 2 (measured 1e-15 relative), number and
   * solid unchanged, and within every solid column the mean liquid grows by
   * rate x 2 x s / S_total (measured 3e-13).  Tolerance 1e-12. */
  char *yaml = tl_fmt("grid:\n  compartments: 2\n  axes:\n"
                      "    - {name: solid, type: geometric, min: 0.01, ratio: 1.4, cells: 24, zero_first: true}\n"
                      "    - {name: liquid, type: linear, min: 0, max: 8, cells: 80}\n"
                      "initial:\n"
                      "  - {type: gamma, number: 2, mean: [1, 0.2], shape: [3, 8]}\n"
                      "  - {type: gamma, number: 1, mean: [0.5, 0.2], shape: [3, 8], compartment: 2}\n"
                      "mechanisms:\n  - {type: liquid_addition, rate: [0.3, 0.1], start: 0, end: 2}\n"
                      "output: {times: [1, 2, 3]}\n");
  gs_case c;
  gs_run_report rep;
  double *y = tl_build_run(yaml, &c, &rep);
  if (y) {
    const gs_model *m = &c.model;
    const gs_grid *g = &m->grid;
    const double Q[2] = {0.3, 0.1}, T = 2;
    double worst_col = 0;
    for (size_t comp = 0; comp < 2; comp++) {
      double L0 = tl_mom(&c, c.y0, comp, 0, 1, 0), L = tl_mom(&c, y, comp, 0, 1, 0);
      double S0 = tl_mom(&c, c.y0, comp, 1, 0, 0), S = tl_mom(&c, y, comp, 1, 0, 0);
      double N0 = tl_mom(&c, c.y0, comp, 0, 0, 0), N = tl_mom(&c, y, comp, 0, 0, 0);
      printf("liquid addition, compartment %zu: liquid added %.15g (want %g)\n", comp + 1, L - L0, Q[comp] * T);
      CHECK_REL(L - L0, Q[comp] * T, 1e-12);
      CHECK_REL(tl_ext(m, y + m->nstate, comp, 1), Q[comp] * T, 1e-12);
      CHECK_REL(S, S0, 1e-13);
      CHECK_REL(N, N0, 1e-13);
      /* per solid column: mean liquid grows by Q T s / S_total */
      const gs_axis *sa = &g->axis[0], *la = &g->axis[1];
      for (size_t i = 0; i < sa->n; i++) {
        double n0 = 0, l0 = 0, n1 = 0, l1 = 0;
        for (size_t j = 0; j < la->n; j++) {
          size_t cell = comp * g->ncells + i * g->stride[0] + j;
          n0 += c.y0[cell];
          l0 += c.y0[cell] * la->pivots[j];
          n1 += y[cell];
          l1 += y[cell] * la->pivots[j];
        }
        if (n0 < 1e-12 * N0) continue;
        double want = l0 / n0 + Q[comp] * T * sa->pivots[i] / S0;
        double e = fabs(l1 / n1 - want) / want;
        if (e > worst_col) worst_col = e;
      }
    }
    printf("liquid addition: largest error of the per-column mean liquid %.3g\n", worst_col);
    CHECK(worst_col < 1e-12);
    CHECK(rep.max_loss < 1e-12);
    free(y);
    gs_case_free(&c);
  }
  free(yaml);
}

/* ---- consolidation ------------------------------------------------------------------------- */
static void test_consolidation(void) {
  /* 3-D solid x liquid x gas.  Porosity e = (l + g)/(s + l + g); gas drains
   * where e > e_min = 0.26, at G = -c (s+l+g)(1-e_min)/s * (l + g - e_min s/(1-e_min))
   * with c = 2.  The excess is increasing in g, so in every (s, l) column the
   * gas cells below j* (the highest with e <= e_min) receive nothing and keep
   * their numbers bit for bit (porosity never pushed more than one cell below
   * e_min); cells above j* drain into j*.  At late times the cell j*+1, fed by
   * nothing (the cells above it are empty: measured 1e-24 of the column at
   * t = 24; tolerance 1e-20), decays as exp(-|G| t / dg): its decay rate
   * between t = 20 and 24 matches the formula in 5 columns (measured 9e-13
   * relative at rtol 1e-10; tolerance 1e-10, the integrator's).  Number,
   * solid and liquid conserved to round-off; gas change = the ledger's
   * external entry.  (e_min = 0.26 keeps the threshold off the pivots.) */
  const double emin = 0.26, crate = 2, T1 = 20, T2 = 24;
  char *yaml = tl_fmt("grid: {axes: [{name: solid, type: linear, min: 0.5, max: 2.5, cells: 4},"
                      " {name: liquid, type: linear, min: 0, max: 0.6, cells: 3},"
                      " {name: gas, type: linear, min: 0, max: 1.6, cells: 16}]}\n"
                      "initial: {type: gamma, number: 1, mean: [1.5, 0.3, 0.6], shape: [20, 20, 20], coverage: 0.05}\n"
                      "mechanisms:\n  - {type: consolidation, rate: %g, min_porosity: %g}\n"
                      "output: {times: [%g, %g]}\n"
                      "solver: {rtol: 1.0e-10, atol: 1.0e-30}\n",
                      crate, emin, T1, T2);
  gs_case c;
  if (tl_case(yaml, &c) == 0) {
    const gs_model *m = &c.model;
    const gs_grid *g = &m->grid;
    const size_t ng = g->axis[2].n, n = m->nstate + m->nledger;
    const double dg = g->axis[2].pivots[1] - g->axis[2].pivots[0];
    double *y30 = malloc(n * sizeof(double)), *y = malloc(n * sizeof(double)), t = 0;
    gs_error err;
    memcpy(y, c.y0, n * sizeof(double));
    CHECK(c.integrator.type->advance(c.integrator.self, &c.ode, &t, T1, y, &err) == GS_OK);
    memcpy(y30, y, n * sizeof(double));
    CHECK(c.integrator.type->advance(c.integrator.self, &c.ode, &t, T2, y, &err) == GS_OK);
    int unchanged_bad = 0, columns = 0, rates = 0;
    double worst_above = 0, worst_rate = 0;
    for (size_t col = 0; col < g->ncells / ng; col++) {
      size_t base = col * ng;
      double s = g->x[base * 3], l = g->x[base * 3 + 1], total = 0;
      long jstar = -1;
      for (size_t j = 0; j < ng; j++) {
        double gas = g->axis[2].pivots[j];
        if ((l + gas) / (s + l + gas) <= emin) jstar = (long)j;
        total += c.y0[base + j];
      }
      if (jstar < 0 || jstar + 1 >= (long)ng || total < 1e-12) continue;
      columns++;
      for (size_t j = 0; j < ng; j++) {
        if ((long)j < jstar && y[base + j] != c.y0[base + j]) unchanged_bad++;
        if ((long)j > jstar + 1) worst_above = fmax(worst_above, y[base + j] / total);
      }
      size_t j1 = base + (size_t)jstar + 1;
      if (y[j1] > 1e-12 * total && y30[j1 + 1] < 1e-12 * y30[j1]) {
        double gas = g->axis[2].pivots[jstar + 1];
        double excess = l + gas - emin * s / (1 - emin);
        double lambda = crate * (s + l + gas) * (1 - emin) / s * excess / dg;
        double got = log(y30[j1] / y[j1]) / (T2 - T1);
        worst_rate = fmax(worst_rate, fabs(got - lambda) / lambda);
        rates++;
      }
    }
    double N0 = tl_mom(&c, c.y0, 0, 0, 0, 0), N = tl_mom(&c, y, 0, 0, 0, 0);
    double G0 = tl_mom(&c, c.y0, 0, 0, 0, 1), G = tl_mom(&c, y, 0, 0, 0, 1);
    printf("consolidation: %d columns; cells below the target changed: %d; left above the next cell %.3g;"
           " decay rate of the next cell vs formula (%d columns) %.3g; gas %.6g -> %.6g\n",
           columns, unchanged_bad, worst_above, rates, worst_rate, G0, G);
    CHECK(columns > 5 && rates >= 4);
    CHECK(unchanged_bad == 0);
    CHECK(worst_above < 1e-20);
    CHECK(worst_rate < 1e-10);
    CHECK_REL(N, N0, 1e-13);
    CHECK_REL(tl_mom(&c, y, 0, 1, 0, 0), tl_mom(&c, c.y0, 0, 1, 0, 0), 1e-13);
    CHECK_REL(tl_mom(&c, y, 0, 0, 1, 0), tl_mom(&c, c.y0, 0, 0, 1, 0), 1e-13);
    CHECK(G < G0);
    CHECK_REL(tl_ext(m, y + m->nstate, 0, 2), G - G0, 1e-12);
    free(y);
    free(y30);
    gs_case_free(&c);
  }
  free(yaml);
}

/* ---- compartments: feed + transfer --------------------------------------------------------- */
static void test_tanks_in_series(void) {
  /* (a) constant feed F = 2/s of particles at v = 1.25 (a pivot) into the
   * first of three empty compartments, transfer k = 0.5/s each, feed during
   * [0, 4):  N_n(t) = (F/k) [P(n, k t) - P(n, k (t - 4)) H(t - 4)]
   * (P the regularised lower incomplete gamma function).
   * (b) pulse N0 = 1 in the first, rates 0.5, 1.3, 2.1: the Bateman solutions.
   * Measured worst relative error of N_n over t = 1, 2, 4, 6, 10 at rtol
   * 1e-8: (a) 4.4e-9 (the feed switches off at an output time, where steps
   * end) (b) 5.5e-9; tolerance 1.5e-8.  Ledger: per compartment, held = ext
   * (nothing initially, nothing lost; measured 1e-16, tolerance 1e-10), and
   * the total external volume = fed - discharged with the closed forms
   * (measured 6e-10, tolerance 2e-9). */
  const double F = 2, k = 0.5, v = 1.25, tf = 4;
  char *yaml = tl_fmt("grid: {compartments: 3, axes: [{name: v, type: linear, min: 0, max: 5, cells: 10}]}\n"
                      "mechanisms:\n"
                      "  - {type: feed, compartment: 1, end: %g, distribution: {type: point, number: %g, at: [%g]}}\n"
                      "  - {type: transfer, rate: %g}\n"
                      "output: {times: [1, 2, 4, 6, 10]}\n"
                      "solver: {rtol: 1.0e-8, atol: 1.0e-14}\n"
                      "checks: {mass_tolerance: 1.0e-10}\n",
                      tf, F, v, k);
  gs_case c;
  if (tl_case(yaml, &c) == 0) {
    const gs_model *m = &c.model;
    size_t n = m->nstate + m->nledger;
    double *y = malloc(n * sizeof(double)), t = c.t0, worst = 0, worst_bal = 0, worst_ext = 0;
    memcpy(y, c.y0, n * sizeof(double));
    for (size_t i = 1; i < c.ntimes; i++) {
      gs_error err;
      CHECK(c.integrator.type->advance(c.integrator.self, &c.ode, &t, c.times[i], y, &err) == GS_OK);
      double held_total = 0, discharged = F * fmin(t, tf);
      for (int comp = 0; comp < 3; comp++) {
        double Nx = F / k * (gsl_sf_gamma_inc_P(comp + 1, k * t) - (t > tf ? gsl_sf_gamma_inc_P(comp + 1, k * (t - tf)) : 0));
        double N = tl_mom(&c, y, comp, 0, 0, 0), held = tl_mom(&c, y, comp, 1, 0, 0);
        worst = fmax(worst, tl_relerr(N, Nx));
        worst_bal = fmax(worst_bal, fabs(held - tl_ext(m, y + m->nstate, comp, 0)) / (F * v * tf));
        held_total += tl_ext(m, y + m->nstate, comp, 0);
        discharged -= Nx;
      }
      /* sum of external entries = fed - discharged (volume) */
      worst_ext = fmax(worst_ext, tl_relerr(held_total, F * v * fmin(t, tf) - v * discharged));
    }
    CHECK(worst < 1.5e-8);
    printf("tanks in series, constant feed: worst N error %.3g, worst held - ledger %.3g, worst sum ext vs fed - discharged %.3g\n",
           worst, worst_bal, worst_ext);
    CHECK(worst_ext < 2e-9);
    CHECK(worst_bal < 1e-10);
    free(y);
    gs_case_free(&c);
  }
  free(yaml);

  const double K[3] = {0.5, 1.3, 2.1};
  yaml = tl_fmt("grid: {compartments: 3, axes: [{name: v, type: linear, min: 0, max: 5, cells: 10}]}\n"
                "initial: {type: gamma, number: 1, mean: 1.5, shape: 30, compartment: 1}\n"
                "mechanisms:\n  - {type: transfer, rate: [%g, %g, %g]}\n"
                "output: {times: [1, 2, 4, 6, 10]}\n"
                "solver: {rtol: 1.0e-8, atol: 1.0e-14}\n",
                K[0], K[1], K[2]);
  if (tl_case(yaml, &c) == 0) {
    const gs_model *m = &c.model;
    size_t n = m->nstate + m->nledger;
    double *y = malloc(n * sizeof(double)), t = c.t0, worst = 0;
    memcpy(y, c.y0, n * sizeof(double));
    double N0 = tl_mom(&c, y, 0, 0, 0, 0), V0 = tl_mom(&c, y, 0, 1, 0, 0);
    for (size_t i = 1; i < c.ntimes; i++) {
      gs_error err;
      CHECK(c.integrator.type->advance(c.integrator.self, &c.ode, &t, c.times[i], y, &err) == GS_OK);
      double e1 = exp(-K[0] * t), e2 = exp(-K[1] * t), e3 = exp(-K[2] * t);
      double Nx[3] = {N0 * e1, N0 * K[0] / (K[1] - K[0]) * (e1 - e2),
                      N0 * K[0] * K[1] *
                          (e1 / ((K[1] - K[0]) * (K[2] - K[0])) + e2 / ((K[0] - K[1]) * (K[2] - K[1])) +
                           e3 / ((K[0] - K[2]) * (K[1] - K[2])))};
      double ext = 0, held = 0;
      for (int comp = 0; comp < 3; comp++) {
        worst = fmax(worst, tl_relerr(tl_mom(&c, y, comp, 0, 0, 0), Nx[comp]));
        ext += tl_ext(m, y + m->nstate, comp, 0);
        held += tl_mom(&c, y, comp, 1, 0, 0);
      }
      /* held = initial - discharged; discharged = V0 (1 - sum N_n / N0) */
      CHECK_REL(held, V0 + ext, 1e-12);
      CHECK_REL(-ext, V0 * (1 - (Nx[0] + Nx[1] + Nx[2]) / N0), 1.5e-8);
    }
    printf("tanks in series, pulse: worst N error %.3g\n", worst);
    CHECK(worst < 1.5e-8);
    free(y);
    gs_case_free(&c);
  }
  free(yaml);
}


/* ---- preconditioner: exact inverse of (I - gamma J) ------------------------------------- */
/* Volume of axis k held by the numbers z (absolute values: the size of its terms). */
static double held(const gs_grid *g, const double *z, int k, int absolute) {
  double s = 0;
  for (size_t c = 0; c < g->ncells; c++)
    s += (absolute ? fabs(z[c]) : z[c]) * g->x[c * (size_t)g->dim + (size_t)k];
  return s;
}

/* gs_growth_solve must return z with z - gamma * growth(z) = r exactly (to
 * round-off), growth(z) the upwind transfer of gs_growth_apply, for rates of
 * both signs along an axis of a 2-D grid (tridiagonal systems) and a
 * geometric axis with very different cell widths (stiff).  Residuals are
 * measured against the size of the terms z and gamma J z (round-off). */
static void test_growth_solve(void) {
  const char *yaml =
      "grid:\n  axes:\n"
      "    - {name: s, type: geometric, min: 1.0e-3, ratio: 2, cells: 7}\n"
      "    - {name: l, type: geometric, min: 1.0e-6, ratio: 1.8, cells: 30, zero_first: true}\n"
      "initial: {type: point, number: 1, at: [0.01, 1.0e-5]}\n"
      "output: {end: 1}\n";
  gs_case c;
  if (tl_case(yaml, &c)) return;
  const gs_grid *g = &c.model.grid;
  const size_t n = g->ncells;
  double *G = malloc(n * sizeof *G), *r = malloc(n * sizeof *r), *z = malloc(n * sizeof *z);
  double *Jz = malloc(n * sizeof *Jz), *work = malloc(2 * g->axis[1].n * sizeof *work);
  tl_rng seed = {12345};
  for (int signs = 0; signs < 2; signs++) {
    for (size_t i = 0; i < n; i++) {
      double u = tl_uniform(&seed);
      G[i] = signs == 0 ? 3e-4 * (0.5 + u) : 3e-4 * (u - 0.5); /* one sign / mixed signs */
      r[i] = tl_uniform(&seed) - 0.3;
    }
    for (double gamma = 1e-3; gamma <= 1e3; gamma *= 1e3) {
      memcpy(z, r, n * sizeof *z);
      double zex[GS_MAX_DIM], zlost[GS_MAX_DIM], before[2], after[2];
      for (int k = 0; k < 2; k++) {
        zex[k] = 0.3 * held(g, z, k, 1);
        zlost[k] = -0.1 * held(g, z, k, 1);
        before[k] = held(g, z, k, 0) - zex[k] + zlost[k];
      }
      gs_growth_solve(g, 1, G, gamma, z, zex, zlost, work);
      /* the ledger's rows are solved with the numbers': the solve conserves
       * every axis' volume as the transfer does (without them: off by
       * gamma * sum G z, about 1e-3 of the terms at gamma = 1) */
      for (int k = 0; k < 2; k++) {
        after[k] = held(g, z, k, 0) - zex[k] + zlost[k];
        double size = held(g, z, k, 1) + fabs(zex[k]) + fabs(zlost[k]);
        printf("  axis %d: held - exchanged + lost %.17g -> %.17g\n", k, before[k], after[k]);
        CHECK(fabs(after[k] - before[k]) < 1e-12 * size);
      }
      memset(Jz, 0, n * sizeof *Jz);
      gs_growth_apply(g, 1, G, z, Jz, NULL, NULL);
      double worst = 0, scale = 0;
      for (size_t i = 0; i < n; i++) {
        worst = fmax(worst, fabs(z[i] - gamma * Jz[i] - r[i]));
        scale = fmax(scale, fabs(z[i]) + fabs(gamma * Jz[i])); /* size of the terms */
      }
      printf("growth preconditioner (%s rates), gamma = %g: largest residual %.3g of terms %.3g\n",
             signs ? "mixed" : "positive", gamma, worst, scale);
      /* gamma |k| reaches 3e5 on the finest cells: the row terms that cancel are
       * that much larger than z (measured: <= 1.5e-11 of the terms) */
      CHECK(worst < 1e-9 * scale);
    }
  }
  free(G);
  free(r);
  free(z);
  free(Jz);
  free(work);
  gs_case_free(&c);
}

/* ---- the ledger under CVODE's Newton iterations ------------------------------------------- */
/* The volume balance of every coordinate must hold to round-off in the whole
 * run, also where CVODE solves its Newton systems only approximately:
 *  - GMRES preconditioned by the growth solves (3-D s, l, g: spray,
 *    consolidation, aggregation; 40 outputs).  While the preconditioner left
 *    the ledger's rows as identity, each inexact Krylov solve moved the
 *    balance: 4.9e-8 here (1.5e-3 and a stopped run in the 26-per-axis
 *    benchmark case with 51 outputs); now 7.7e-16.
 *  - the dense difference-quotient Jacobian (2-D s, l: spray, aggregation,
 *    breakage).  Its columns carry f's round-off over the increment; while
 *    they went into the Newton matrix as they were, the balance drifted to
 *    8.8e-8; with each column made to keep the balance (gs_ode.conserve),
 *    8.5e-16. */
static void ledger_under_newton(const char *what, const char *yaml) {
  gs_case c;
  gs_run_report rep;
  double *y = tl_build_run(yaml, &c, &rep);
  if (!y) return;
  printf("ledger under CVODE with %s: largest volume-balance error %.3g (%ld steps)\n", what,
         rep.max_balance_error, (long)rep.stats.steps);
  CHECK(rep.max_balance_error < 1e-13);
  free(y);
  gs_case_free(&c);
}

static void test_ledger_under_newton(void) {
  ledger_under_newton(
      "preconditioned GMRES",
      "grid:\n  axes:\n"
      "    - {name: solid,  type: geometric, min: 2.6e-13, ratio: 3, cells: 10}\n"
      "    - {name: liquid, type: geometric, min: 2.0e-14, ratio: 3.5, cells: 10, zero_first: true}\n"
      "    - {name: gas,    type: geometric, min: 2.0e-14, ratio: 3.5, cells: 10, zero_first: true}\n"
      "initial: {type: point, number: 3.8e8, at: [5.24e-13, 1.0e-14, 3.49e-13]}\n"
      "mechanisms:\n"
      "  - {type: aggregation, kernel: {type: madec, beta0: 1.0e-2, alpha: 1, delta: 1}}\n"
      "  - {type: liquid_addition, rate: 2.0e-7, start: 0, end: 300}\n"
      "  - {type: consolidation, rate: 1.0e-3, min_porosity: 0.2}\n"
      "solver: {method: cvode, rtol: 1.0e-5, atol: 0.1, linear_solver: gmres}\n"
      "output: {end: 400, count: 40}\n"
      "checks: {mass_tolerance: 1, max_loss: 1}\n");
  ledger_under_newton(
      "the dense Jacobian",
      "grid:\n  axes:\n"
      "    - {name: solid,  type: geometric, min: 2.6e-13, ratio: 3, cells: 12}\n"
      "    - {name: liquid, type: geometric, min: 2.0e-14, ratio: 3, cells: 12, zero_first: true}\n"
      "initial: {type: point, number: 3.8e8, at: [5.24e-13, 1.0e-14]}\n"
      "mechanisms:\n"
      "  - {type: aggregation, kernel: {type: madec, beta0: 5.0e-2, alpha: 1, delta: 1, liquid_content: percent}}\n"
      "  - {type: liquid_addition, rate: 1.0e-6, start: 0, end: 60}\n"
      "  - {type: breakage, selection: {type: shear, shear_rate: 64, b: 2.0, min_volume: 2.0e-12},"
      " daughters: {type: halves}}\n"
      "solver: {method: cvode, rtol: 1.0e-5, atol: 0.1, linear_solver: dense}\n"
      "output: {end: 120, count: 24}\n"
      "checks: {mass_tolerance: 1, max_loss: 1}\n");
}

int main(void) {
  omp_set_num_threads(1); /* small grids: threads only add overhead */
  test_t6();
  test_constant_growth();
  test_liquid_addition();
  test_consolidation();
  test_ledger_under_newton();
  test_tanks_in_series();
  test_growth_solve();
  TEST_EXIT();
}
