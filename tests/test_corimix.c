/* The CoriMix granulator of Sampat et al. (2018) as shipped (examples/corimix-continuous.yaml: 4
 * compartments x 16 x 16 bins, liquid and gas carried, feed, spray, pore
 * consolidation, DEM aggregation with the wet switch, DEM-impact breakage,
 * transfer), integrated over its whole 85 s with checks at EVERY right-hand
 * side evaluation the integrator makes:
 *  - aggregation: number formation / depletion = 1/2 in every compartment
 *    with events; breakage (binary halves): = 2 (both to 1e-13);
 *  - aggregation and breakage each conserve the volume of every solid
 *    component and of the carried liquid and gas in every compartment (their
 *    net rate below 1e-12 of their turnover);
 * and at every output time:
 *  - no number or carried volume negative beyond round-off;
 *  - the ledger balance held = initial + exchanged - lost for every
 *    component, liquid and gas, in every compartment (1e-10), with nothing
 *    lost through the grid;
 *  - held = fed - discharged in closed form: aggregation and breakage conserve
 *    solid volume, so each component's solid volume per compartment obeys the
 *    tanks-in-series equations V_n' = F [n = 1] + k V_{n-1} - k V_n (feed F,
 *    k = v/d), V_n(t) = F/k P(n, k t) with P the regularised incomplete gamma
 *    function; the sprayed liquid (s per compartment from t_s) likewise:
 *    L_n = s/k sum_{j <= n} P(j, k (t - t_s)).  Held totals must match these
 *    to the integrator's accuracy (rtol 1e-6; the stretches between rate
 *    switches advanced as the run driver does, tl_advance_to; measured worst
 *    9.9e-7 for the solids, 8.4e-10 for the liquid; tolerances 3e-6 and 1e-6).
 * Measured: ratios and conservation to 2e-15, ledger 3e-16. */

#include "corimix_testlib.h"

/* Parameters of the example, checked against its text below. */

typedef struct {
  gs_case *c;
  double *birth, *death, *d1, *dl1;
  long evals, with_events;
  double worst_ratio_agg, worst_ratio_brk, worst_cons;
} probe_t;

/* Net volume rate of coordinate k in compartment comp of rates d (numbers and
 * carried), and its turnover (sum of absolute cell contributions). */
static void net_rate(const gs_model *m, const double *d, size_t comp, int k, double *net, double *turn) {
  const gs_grid *g = &m->grid;
  *net = *turn = 0;
  for (size_t cell = 0; cell < g->ncells; cell++) {
    double v = k < g->dim ? d[comp * g->ncells + cell] * g->x[cell * (size_t)g->dim + (size_t)k]
                          : gs_model_carried_c(m, d, comp, k - g->dim)[cell];
    *net += v;
    *turn += fabs(v);
  }
}

static void check_mechanism(probe_t *p, const gs_mechanism *mech, double t, const double *y, double ratio,
                            double *worst_ratio) {
  const gs_model *m = &p->c->model;
  const size_t ncomp = m->grid.ncomp;
  gs_eval ev;
  gs_eval_init(&ev, m);
  ev.in_integrator = 1; /* the discrete choices the integrator's own f makes */
  gs_mech_number_rates(m, mech, &ev, t, y, p->birth, p->death);
  for (size_t comp = 0; comp < ncomp; comp++) {
    if (p->death[comp] <= 0) continue;
    p->with_events++;
    *worst_ratio = fmax(*worst_ratio, fabs(p->birth[comp] / p->death[comp] - ratio) / ratio);
  }
  memset(p->d1, 0, m->nstate * sizeof(double));
  memset(p->dl1, 0, m->nledger * sizeof(double));
  gs_mech_rhs(m, mech, &ev, t, y, p->d1, p->dl1);
  for (size_t comp = 0; comp < ncomp; comp++)
    for (int k = 0; k < m->nvol; k++) {
      double net, turn;
      net_rate(m, p->d1, comp, k, &net, &turn);
      if (turn > 0) p->worst_cons = fmax(p->worst_cons, fabs(net) / turn);
    }
}

static int probed_rhs(void *ctx, double t, const double *y, double *dydt) {
  probe_t *p = ctx;
  gs_model *m = &p->c->model;
  p->evals++;
  for (size_t i = 0; i < m->nmech; i++) {
    const gs_mechanism *mech = &m->mech[i];
    if (!strcmp(mech->type->name, "aggregation")) check_mechanism(p, mech, t, y, 0.5, &p->worst_ratio_agg);
    if (!strcmp(mech->type->name, "breakage")) check_mechanism(p, mech, t, y, 2.0, &p->worst_ratio_brk);
  }
  return p->c->ode.f(p->c->ode.ctx, t, y, dydt);
}

/* Solid volume fed per second of axis k, from the example's feed (the
 * right-hand side of the empty state at t = 0 holds only the feed). */
static double fed_rate(gs_case *c, int k) {
  const gs_model *m = &c->model;
  size_t n = m->nstate + m->nledger;
  double *y = calloc(n, sizeof(double)), *f = calloc(n, sizeof(double)), rate = 0;
  c->ode.f(c->ode.ctx, 0.0, y, f);
  for (size_t cell = 0; cell < m->grid.ncells; cell++) rate += f[cell] * m->grid.x[cell * (size_t)m->grid.dim + (size_t)k];
  for (size_t i = m->grid.ncells; i < m->nnum; i++) CHECK(f[i] == 0.0); /* feed into compartment 1 only */
  free(y);
  free(f);
  return rate;
}

/* The case's integrator on the probed system (tl_advance_to). */
typedef struct {
  gs_case *c;
  gs_ode *ode;
  double *y;
} seed_advance;

static int integrator_advance(void *ctx, double *t, double stop, int jumped, gs_error *err) {
  seed_advance *a = ctx;
  a->ode->jumped = jumped;
  return a->c->integrator.type->advance(a->c->integrator.self, a->ode, t, stop, a->y, err);
}

int main(void) {
  const char *src = getenv("GRANSIM_SOURCE_DIR");
  char path[1024];
  snprintf(path, sizeof path, "%s/examples/corimix-continuous.yaml", src ? src : "..");
  char *text = cx_read_text(path);
  CHECK(text != NULL);
  if (!text) return 1;
  /* the closed forms below use these values of the example */
  CHECK(strstr(text, "{type: spray, rate: 3.645833e-7, start: 10}") != NULL);
  CHECK(strstr(text, "{type: transfer, velocity: 7.7551e-3, length: 0.095}") != NULL);
  CHECK(strstr(text, "compartment: 1\n") != NULL);
  free(text);

  gs_case c;
  gs_error err = {0};
  CHECK(gs_case_load(path, &c, &err) == GS_OK);
  if (err.code) {
    fprintf(stderr, "%s\n", err.msg);
    TEST_EXIT();
  }
  gs_model *m = &c.model;
  const gs_grid *g = &m->grid;
  const size_t ncomp = g->ncomp, n = m->nstate + m->nledger;
  CHECK(ncomp == 4 && g->dim == 2 && m->ncarried == 2);
  const double F[2] = {fed_rate(&c, 0), fed_rate(&c, 1)};
  CHECK(F[0] > 0 && F[1] > 0);

  probe_t p = {&c, calloc(ncomp, sizeof(double)), calloc(ncomp, sizeof(double)), calloc(m->nstate, sizeof(double)),
               calloc(m->nledger, sizeof(double)), 0, 0, 0, 0, 0};
  gs_ode ode = c.ode;
  ode.f = probed_rhs;
  ode.ctx = &p;
  double *y = malloc(n * sizeof(double)), t = c.t0;
  memcpy(y, c.y0, n * sizeof(double));
  cx_worst w = {0};
  seed_advance adv = {&c, &ode, y};
  CHECK(cx_walk(&c, y, &t, F, integrator_advance, &adv, 1, &w) == GS_OK);
  printf("CoriMix example: %ld right-hand sides checked (%ld compartment evaluations with events)\n", p.evals,
         p.with_events);
  printf("  worst |birth/death - 1/2| / (1/2) aggregation %.3g, |birth/death - 2| / 2 breakage %.3g\n",
         p.worst_ratio_agg, p.worst_ratio_brk);
  printf("  worst net volume rate / turnover (aggregation, breakage; solids, liquid, gas) %.3g\n", p.worst_cons);
  printf("  worst solid vs tanks in series %.3g, liquid vs closed form %.3g\n", w.solid, w.liquid);
  printf("  worst ledger balance %.3g, largest loss through the grid %.3g, most negative density %.3g of the largest\n",
         w.ledger, w.lost, w.most_negative);
  CHECK(t == c.times[c.ntimes - 1]);
  CHECK(p.evals > 100 && p.with_events > 100);
  CHECK(p.worst_ratio_agg < 1e-13);
  CHECK(p.worst_ratio_brk < 1e-13);
  CHECK(p.worst_cons < 1e-12);
  CHECK(w.solid < 3e-6);
  CHECK(w.liquid < 1e-6);
  CHECK(w.ledger < 1e-10);
  CHECK(w.lost < 1e-12);
  CHECK(w.most_negative > -1e-9);
  free(y);
  free(p.birth);
  free(p.death);
  free(p.d1);
  free(p.dl1);
  gs_case_free(&c);
  TEST_EXIT();
}
