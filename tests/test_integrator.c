/* Time integrators: accuracy against closed forms, conservation of linear
 * invariants, exact landing on output times, stiffness, error paths and
 * settings validation, for every registered method. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "gransim/cfg.h"
#include "gransim/integrator.h"

/* ---- helpers ---------------------------------------------------------------- */

static int make(const char *yaml, const gs_ode *ode, gs_integrator *it, gs_error *err) {
  gs_cfg *cfg = gs_cfg_load_string(yaml, "test.yaml", err);
  if (!cfg) return err->code;
  gs_cfg_node *solver = gs_cfg_get(gs_cfg_root(cfg), "solver");
  gs_integrator_setup setup;
  int rc = gs_integrator_setup_read(solver, &setup, err);
  if (!rc && solver) rc = gs_cfg_check_unused(solver, err);
  gs_cfg_free(cfg); /* neither settings nor integrators may keep pointers into the tree */
  if (!rc) rc = gs_integrator_create(&setup, ode, it, err);
  gs_integrator_setup_free(&setup);
  return rc;
}

static int advance(gs_integrator *it, const gs_ode *ode, double *t, double t_out, double *y,
                   gs_error *err) {
  return it->type->advance(it->self, ode, t, t_out, y, err);
}

static gs_integrator_stats stats_of(const gs_integrator *it) {
  gs_integrator_stats s;
  it->type->get_stats(it->self, &s);
  return s;
}

/* Creation that must succeed; prints the message otherwise. */
static int make_ok(const char *yaml, const gs_ode *ode, gs_integrator *it) {
  gs_error err = {0};
  int rc = make(yaml, ode, it, &err);
  if (rc) fprintf(stderr, "create failed: %s\n", err.msg);
  CHECK(rc == GS_OK);
  return rc;
}

static int contains(const char *s, const char *part) { return strstr(s, part) != NULL; }

/* ---- test systems ----------------------------------------------------------- */

typedef struct {
  double k;
  double t_max; /* latest time f was called at */
  double fail_after; /* f fails for t > fail_after */
} decay_ctx;

static int decay_f(void *vctx, double t, const double *y, double *dydt) {
  decay_ctx *c = vctx;
  if (t > c->t_max) c->t_max = t;
  if (t > c->fail_after) return 1;
  dydt[0] = -c->k * y[0];
  return 0;
}

/* A -> B -> C with rates k1, k2, plus a ledger L' = k2 B outside error
 * control: A + B + C and C - L are exact linear invariants. */
static int chain_f(void *vctx, double t, const double *y, double *dydt) {
  (void)t;
  const double *k = vctx;
  double r1 = k[0] * y[0], r2 = k[1] * y[1];
  dydt[0] = -r1;
  dydt[1] = r1 - r2;
  dydt[2] = r2;
  dydt[3] = r2;
  return 0;
}

/* Eigenvalues -1 and -1e5: y1' = -y1, y2' = -a (y2 - y1). */
static const double stiff_a = 1e5;
static int stiff_f(void *vctx, double t, const double *y, double *dydt) {
  (void)vctx;
  (void)t;
  dydt[0] = -y[0];
  dydt[1] = -stiff_a * (y[1] - y[0]);
  return 0;
}

/* Diffusion with decay on a line of n cells (moderately stiff, coupled). */
typedef struct {
  size_t n;
  double d, k;
} diffusion_ctx;

static int diffusion_f(void *vctx, double t, const double *y, double *dydt) {
  (void)t;
  const diffusion_ctx *c = vctx;
  for (size_t i = 0; i < c->n; i++) {
    double left = i ? y[i - 1] : y[i], right = i + 1 < c->n ? y[i + 1] : y[i];
    dydt[i] = c->d * (left - 2 * y[i] + right) - c->k * y[i];
  }
  return 0;
}

/* Independent decays with rates 1 + 0.001 i. */
static int decays_f(void *vctx, double t, const double *y, double *dydt) {
  (void)t;
  const size_t *n = vctx;
  for (size_t i = 0; i < *n; i++) dydt[i] = -(1 + 0.001 * (double)i) * y[i];
  return 0;
}

/* Returns success but NaN derivatives after t = 0.5. */
static int nan_f(void *vctx, double t, const double *y, double *dydt) {
  (void)vctx;
  dydt[0] = t > 0.5 ? (double)NAN : -y[0];
  return 0;
}

/* Constant depletion: the Euler controller drives dt to min_step near 0. */
static int drain_f(void *vctx, double t, const double *y, double *dydt) {
  (void)vctx;
  (void)t;
  (void)y;
  dydt[0] = -10;
  return 0;
}

/* A compartment filling from empty: y0' = q, y1' = q - y1 / 2 from zero. */
static int fill_f(void *vctx, double t, const double *y, double *dydt) {
  (void)t;
  const double q = *(const double *)vctx;
  dydt[0] = q;
  dydt[1] = q - 0.5 * y[1];
  return 0;
}

/* The first step: from an empty state, the change of f over an Euler probe
 * sets it (before, h0 = 0.01 atol / |f| = 1e-11 s and 16 steps growing by 5x
 * before t = 1); from a full one, it is accepted at once. */
static void test_rk_first_step(const char *variant) {
  char yaml[160];
  snprintf(yaml, sizeof yaml, "solver:\n  method: rk\n  variant: %s\n  rtol: 1e-6\n  atol: 1\n", variant);
  double q = 1e9;
  gs_ode ode = {2, fill_f, &q, NULL, 2, NULL, NULL, NULL, 0, NULL, 0, NULL, 0, 0, NULL, NULL, NULL};
  gs_integrator it;
  if (make_ok(yaml, &ode, &it)) return;
  gs_error err = {0};
  double t = 0, y[2] = {0, 0};
  CHECK(advance(&it, &ode, &t, 1.0, y, &err) == GS_OK);
  gs_integrator_stats s = stats_of(&it);
  if (!(s.steps <= 8 && s.rejected <= 2))
    fprintf(stderr, "rk %s filling: %ld steps, %ld rejected\n", variant, s.steps, s.rejected);
  CHECK(s.steps <= 8 && s.rejected <= 2);
  CHECK_REL(y[0], q, 1e-12);
  CHECK_REL(y[1], 2 * q * (1 - exp(-0.5)), 1e-6);
  gs_integrator_free(&it);

  snprintf(yaml, sizeof yaml, "solver:\n  method: rk\n  variant: %s\n  rtol: 1e-9\n  atol: 1e-12\n", variant);
  decay_ctx c = {1.3, 0, HUGE_VAL};
  gs_ode dec = {1, decay_f, &c, NULL, 1, NULL, NULL, NULL, 0, NULL, 0, NULL, 0, 0, NULL, NULL, NULL};
  if (make_ok(yaml, &dec, &it)) return;
  t = 0;
  y[0] = 1;
  CHECK(advance(&it, &dec, &t, 2.0, y, &err) == GS_OK);
  s = stats_of(&it);
  CHECK(s.rejected == 0);
  CHECK_REL(y[0], exp(-2.6), 1e-7);
  gs_integrator_free(&it);
}

/* ---- accuracy and landing on t_out ----------------------------------------- */

/* y' = -k y over 50 outputs at t = 0.1 i (none representable exactly). */
static void test_decay(const char *yaml, double tol, double y0) {
  decay_ctx c = {1.3, 0, HUGE_VAL};
  gs_ode ode = {1, decay_f, &c, NULL, 1, NULL, NULL, NULL, 0, NULL, 0, NULL, 0, 0, NULL, NULL, NULL};
  gs_integrator it;
  if (make_ok(yaml, &ode, &it)) return;
  gs_error err = {0};
  double t = 0, y = y0, worst = 0;
  for (int i = 1; i <= 50; i++) {
    double t_out = 0.1 * i;
    int rc = advance(&it, &ode, &t, t_out, &y, &err);
    if (rc) fprintf(stderr, "%s\n", err.msg);
    CHECK(rc == GS_OK);
    CHECK(t == t_out); /* bitwise: output times are hit exactly */
    CHECK(c.t_max <= t_out * (1 + 4e-16)); /* never sampled past the output */
    worst = fmax(worst, fabs(y - y0 * exp(-c.k * t_out)) / (y0 * exp(-c.k * t_out)));
  }
  if (!(worst <= tol)) fprintf(stderr, "decay %s: worst rel err %.3g\n", it.type->name, worst);
  CHECK(worst <= tol);
  gs_integrator_stats s = stats_of(&it);
  CHECK(s.steps > 0 && s.rhs_evals >= s.steps && s.last_step > 0);
  gs_integrator_free(&it);
  CHECK(it.self == NULL);
}

/* Error of explicit Euler at t = 1 with dt fixed at max_step. */
static double euler_error(double h) {
  char yaml[256];
  snprintf(yaml, sizeof yaml,
           "solver:\n  method: euler\n  initial_step: %.17g\n  max_step: %.17g\n", h, h);
  decay_ctx c = {1.0, 0, HUGE_VAL};
  gs_ode ode = {1, decay_f, &c, NULL, 1, NULL, NULL, NULL, 0, NULL, 0, NULL, 0, 0, NULL, NULL, NULL};
  gs_integrator it;
  if (make_ok(yaml, &ode, &it)) return NAN;
  gs_error err = {0};
  double t = 0, y = 1;
  CHECK(advance(&it, &ode, &t, 1.0, &y, &err) == GS_OK);
  gs_integrator_stats s = stats_of(&it);
  CHECK(s.steps == s.rhs_evals);
  CHECK_REL(s.last_step, h, 1e-12);
  gs_integrator_free(&it);
  return fabs(y - exp(-1.0));
}

static void test_euler_order(void) {
  double e1 = euler_error(1.0 / 64), e2 = euler_error(1.0 / 128), e3 = euler_error(1.0 / 256);
  double p1 = log2(e1 / e2), p2 = log2(e2 / e3);
  CHECK(p1 >= 0.8 && p1 <= 1.2);
  CHECK(p2 >= 0.8 && p2 <= 1.2);
}

/* ---- linear invariants ------------------------------------------------------ */

static void test_invariants(const char *yaml, double tol) {
  double k[2] = {2.0, 0.7};
  const double scale[4] = {1, 1, 1, 0};
  gs_ode ode = {4, chain_f, k, scale, 3, NULL, NULL, NULL, 0, NULL, 0, NULL, 0, 0, NULL, NULL, NULL};
  gs_integrator it;
  if (make_ok(yaml, &ode, &it)) return;
  gs_error err = {0};
  double y[4] = {1.0, 0.3, 0.1, 0.0}, t = 0;
  double total0 = y[0] + y[1] + y[2], gap0 = y[2] - y[3];
  double worst_total = 0, worst_gap = 0;
  for (int i = 1; i <= 20; i++) {
    CHECK(advance(&it, &ode, &t, 0.25 * i, y, &err) == GS_OK);
    worst_total = fmax(worst_total, fabs(y[0] + y[1] + y[2] - total0) / total0);
    worst_gap = fmax(worst_gap, fabs(y[2] - y[3] - gap0) / total0);
  }
  if (!(worst_total <= tol && worst_gap <= tol))
    fprintf(stderr, "invariants %s: total %.3g, ledger %.3g\n", yaml, worst_total, worst_gap);
  CHECK(worst_total <= tol);
  CHECK(worst_gap <= tol);
  CHECK(y[0] < 1e-3 && y[2] > 1.0); /* it did integrate */
  gs_integrator_free(&it);
}

/* ---- stiffness -------------------------------------------------------------- */

static long stiff_evals(const char *yaml) {
  gs_ode ode = {2, stiff_f, NULL, NULL, 2, NULL, NULL, NULL, 0, NULL, 0, NULL, 0, 0, NULL, NULL, NULL};
  gs_integrator it;
  if (make_ok(yaml, &ode, &it)) return -1;
  gs_error err = {0};
  double y[2] = {1, 0}, t = 0;
  int rc = advance(&it, &ode, &t, 10.0, y, &err);
  if (rc) fprintf(stderr, "%s\n", err.msg);
  CHECK(rc == GS_OK);
  double c = stiff_a / (stiff_a - 1);
  CHECK_REL(y[0], exp(-10.0), 1e-4);
  CHECK_REL(y[1], c * exp(-10.0) - c * exp(-stiff_a * 10), 1e-4);
  long evals = stats_of(&it).rhs_evals;
  gs_integrator_free(&it);
  return evals;
}

static void test_stiff(void) {
  long rk = stiff_evals("solver:\n  method: rk\n  rtol: 1e-6\n");
  long cv = stiff_evals("solver:\n  method: cvode\n  rtol: 1e-6\n");
  fprintf(stderr, "stiff problem: rk %ld rhs evaluations, cvode %ld\n", rk, cv);
  CHECK(cv > 0 && rk > 0);
  CHECK(cv < rk / 5);
}

/* ---- CVODE linear solvers --------------------------------------------------- */

static void diffusion_run(const char *yaml, double *y, size_t n) {
  diffusion_ctx c = {n, 400.0, 0.5};
  gs_ode ode = {n, diffusion_f, &c, NULL, n, NULL, NULL, NULL, 0, NULL, 0, NULL, 0, 0, NULL, NULL, NULL};
  gs_integrator it;
  if (make_ok(yaml, &ode, &it)) return;
  for (size_t i = 0; i < n; i++) y[i] = i < n / 3 ? 1.0 : 0.01;
  gs_error err = {0};
  double t = 0;
  for (int i = 1; i <= 4; i++) CHECK(advance(&it, &ode, &t, 0.05 * i, y, &err) == GS_OK);
  gs_integrator_free(&it);
}

static void test_gmres_matches_dense(void) {
  enum { N = 40 };
  double a[N], b[N], worst = 0, ymax = 0;
  diffusion_run("solver:\n  method: cvode\n  linear_solver: dense\n  rtol: 1e-9\n", a, N);
  diffusion_run("solver:\n  method: cvode\n  linear_solver: gmres\n  rtol: 1e-9\n", b, N);
  for (size_t i = 0; i < N; i++) {
    worst = fmax(worst, fabs(a[i] - b[i]));
    ymax = fmax(ymax, fabs(a[i]));
  }
  CHECK(worst <= 1e-6 * ymax);
}

/* n > 1000 picks GMRES under `auto`; still accurate. */
static void test_cvode_auto_large(void) {
  size_t n = 1200;
  gs_ode ode = {n, decays_f, &n, NULL, n, NULL, NULL, NULL, 0, NULL, 0, NULL, 0, 0, NULL, NULL, NULL};
  gs_integrator it;
  if (make_ok("solver:\n  method: cvode\n  rtol: 1e-8\n", &ode, &it)) return;
  double *y = malloc(n * sizeof *y), t = 0, worst = 0;
  for (size_t i = 0; i < n; i++) y[i] = 1;
  gs_error err = {0};
  CHECK(advance(&it, &ode, &t, 2.0, y, &err) == GS_OK);
  for (size_t i = 0; i < n; i++) {
    double want = exp(-(1 + 0.001 * (double)i) * 2.0);
    worst = fmax(worst, fabs(y[i] - want) / want);
  }
  CHECK(worst <= 1e-5);
  free(y);
  gs_integrator_free(&it);
}

/* CVODE continues its history only when handed back its own state; a state
 * changed between calls must restart the integration from that state. */
static void test_cvode_restart(void) {
  decay_ctx c = {1.0, 0, HUGE_VAL};
  gs_ode ode = {1, decay_f, &c, NULL, 1, NULL, NULL, NULL, 0, NULL, 0, NULL, 0, 0, NULL, NULL, NULL};
  gs_integrator it;
  if (make_ok("solver:\n  method: cvode\n  rtol: 1e-9\n", &ode, &it)) return;
  gs_error err = {0};
  double t = 0, y = 1;
  CHECK(advance(&it, &ode, &t, 1.0, &y, &err) == GS_OK);
  y *= 2; /* e.g. a feed added between outputs */
  CHECK(advance(&it, &ode, &t, 2.0, &y, &err) == GS_OK);
  CHECK_REL(y, 2 * exp(-2.0), 1e-6);
  double t_back = 0.5; /* and a restart at an earlier time */
  y = 1;
  CHECK(advance(&it, &ode, &t_back, 1.5, &y, &err) == GS_OK);
  CHECK_REL(y, exp(-1.0), 1e-6);
  gs_integrator_free(&it);
}

/* ---- interrupted advances (gs_ode.between_steps) --------------------------------- */

typedef struct {
  double k[2];
  int every, calls; /* ask for a return after every `every`-th accepted step */
} interrupt_ctx;

/* The chain slowing down as exp(-2 t): Euler's steps keep growing, up to
 * what the interval allows. */
static int interrupt_f(void *vctx, double t, const double *y, double *dydt) {
  interrupt_ctx *c = vctx;
  double k[2] = {c->k[0] * exp(-2 * t), c->k[1] * exp(-2 * t)};
  return chain_f(k, t, y, dydt);
}

static int interrupt_between(void *vctx) {
  interrupt_ctx *c = vctx;
  return ++c->calls % c->every == 0;
}

/* Two output intervals, each advance asked to return early after every
 * `every`-th step and called again, and each time continued by a fresh
 * integrator carrying on from the old one when `rebuild` (what an MPI move
 * of compartments does): the very steps and state of an uninterrupted run. */
static void test_between_steps(const char *yaml, int every, int rebuild) {
  interrupt_ctx plain = {{3.0, 0.5}, 1, 0}, cut = {{3.0, 0.5}, every, 0};
  gs_ode ode = {4, interrupt_f, &plain, NULL, 3, NULL, NULL, NULL, 0, NULL, 0, NULL, 0, 0, NULL, NULL, NULL};
  gs_ode ode_cut = {4, interrupt_f, &cut, NULL, 3, NULL, NULL, NULL, 0, interrupt_between, 0, NULL, 0, 0, NULL, NULL, NULL};
  gs_integrator a, b;
  if (make_ok(yaml, &ode, &a) || make_ok(yaml, &ode_cut, &b)) return;
  gs_error err = {0};
  double ya[4] = {1, 0, 0, 0}, yb[4] = {1, 0, 0, 0}, ta = 0, tb = 0;
  int returns = 0;
  for (double t_out = 0.25; t_out <= 3; t_out += 0.25) {
    CHECK(advance(&a, &ode, &ta, t_out, ya, &err) == GS_OK);
    while (tb < t_out) {
      CHECK(advance(&b, &ode_cut, &tb, t_out, yb, &err) == GS_OK);
      if (tb < t_out) returns++;
      if (tb < t_out && rebuild) {
        gs_integrator fresh;
        if (make_ok(yaml, &ode_cut, &fresh)) return;
        fresh.type->carry(fresh.self, b.self);
        gs_integrator_free(&b);
        b = fresh;
      }
    }
  }
  CHECK(returns > 2);
  CHECK(ta == tb);
  CHECK(memcmp(ya, yb, sizeof ya) == 0);
  CHECK(stats_of(&a).steps == stats_of(&b).steps);
  gs_integrator_free(&a);
  gs_integrator_free(&b);
  /* max_steps_per_output counts the steps of the interval, not of a call */
  char limited[256];
  snprintf(limited, sizeof limited, "%s  max_steps_per_output: 3\n", yaml);
  cut.calls = 0;
  if (make_ok(limited, &ode_cut, &b)) return;
  tb = 0;
  double y0[4] = {1, 0, 0, 0};
  int rc = GS_OK;
  while (!rc && tb < 1) {
    rc = advance(&b, &ode_cut, &tb, 1.0, y0, &err);
    if (!rc && rebuild) {
      gs_integrator fresh;
      if (make_ok(limited, &ode_cut, &fresh)) return;
      fresh.type->carry(fresh.self, b.self);
      gs_integrator_free(&b);
      b = fresh;
    }
  }
  CHECK(rc == GS_ENUMERIC && contains(err.msg, "max_steps_per_output"));
  gs_integrator_free(&b);
}

/* ---- rates that jump (gs_ode.jumped) and steps after a rejection ----------------- */

/* y' = rate, a constant the caller switches between advances (what the run
 * driver does at a spray's start: the rate holds over each interval). */
static int phase_f(void *vctx, double t, const double *y, double *dydt) {
  (void)t;
  (void)y;
  dydt[0] = *(const double *)vctx;
  return 0;
}

/* Rate 0 up to t = 1, then 1: with gs_ode.jumped the second interval starts
 * from f evaluated afresh and is exact in one step; rk without it reuses
 * the end-of-step derivative from before the switch (0) as its first stage,
 * and steps fail until they are tiny. */
static void test_jump(const char *yaml, int rk) {
  for (int jumped = rk ? 0 : 1; jumped <= 1; jumped++) {
    double rate = 0;
    gs_ode ode = {1, phase_f, &rate, NULL, 1, NULL, NULL, NULL, 0, NULL, 0, NULL, 0, 0, NULL, NULL, NULL};
    gs_integrator it;
    if (make_ok(yaml, &ode, &it)) return;
    gs_error err = {0};
    double y[1] = {1}, t = 0;
    CHECK(advance(&it, &ode, &t, 1.0, y, &err) == GS_OK);
    CHECK(t == 1.0 && y[0] == 1.0);
    rate = 1;
    ode.jumped = jumped;
    long rejected = stats_of(&it).rejected;
    CHECK(advance(&it, &ode, &t, 2.0, y, &err) == GS_OK);
    rejected = stats_of(&it).rejected - rejected;
    if (jumped) {
      CHECK(fabs(y[0] - 2.0) < 1e-12);
      CHECK(rejected == 0);
    } else {
      CHECK(rejected > 5); /* the stale first stage, which the flag avoids */
    }
    gs_integrator_free(&it);
  }
}

typedef struct {
  const gs_integrator *it;
  int n;
  double h[64];
  long rejected[64]; /* rejected attempts before each accepted step, in all */
} steps_ctx;

static int record_step(void *vctx) {
  steps_ctx *c = vctx;
  if (c->n < 64) {
    gs_integrator_stats s = stats_of(c->it);
    c->h[c->n] = s.last_step;
    c->rejected[c->n++] = s.rejected;
  }
  return 0;
}

/* y' = 0 before t = 0.5 and 1 from then on, a jump no advance is told of:
 * steps short of it are exact (zero error) and steps across it fail. */
static int steps_jump_f(void *vctx, double t, const double *y, double *dydt) {
  (void)vctx;
  (void)y;
  dydt[0] = t < 0.5 ? 0.0 : 1.0;
  return 0;
}

/* Steps retried after a rejection, over [0, 20]; returns how many retried
 * steps were followed by a larger one. */
static int grown_after_retry(int (*f)(void *, double, const double *, double *), const char *yaml,
                             double exact, double tol) {
  steps_ctx c = {NULL, 0, {0}, {0}};
  gs_ode ode = {1, f, &c, NULL, 1, NULL, NULL, NULL, 0, record_step, 0, NULL, 0, 0, NULL, NULL, NULL};
  gs_integrator it;
  if (make_ok(yaml, &ode, &it)) return -1;
  c.it = &it;
  gs_error err = {0};
  double y[1] = {1}, t = 0;
  CHECK(advance(&it, &ode, &t, 20.0, y, &err) == GS_OK);
  CHECK(fabs(y[0] - exact) < tol);
  int retried = 0, grown_after = 0, grown = 0;
  for (int i = 1; i + 1 < c.n; i++) { /* the last step may be cut short at t_out */
    long before = i > 1 ? c.rejected[i - 2] : 0;
    if (c.rejected[i - 1] > before) {
      retried++;
      grown_after += c.h[i] > c.h[i - 1];
    } else if (c.h[i] > c.h[i - 1]) {
      grown++;
    }
  }
  CHECK(retried >= 1 && grown >= 1);
  gs_integrator_free(&it);
  return grown_after;
}

/* For f with a jump the error of a rejected try is far above what the
 * accepted retry predicts for it (zero: f is constant short of the jump),
 * and the next step is no larger: growing by 5 had run into the jump again
 * at once.  (An RK step across a jump is only first order.) */
static void test_growth_after_rejection(void) {
  CHECK(grown_after_retry(steps_jump_f, "solver:\n  method: rk\n  rtol: 1e-6\n  atol: 1e-10\n  initial_step: 0.1\n",
                          20.5, 1e-4) == 0);
}

/* ---- failures ----------------------------------------------------------------- */

static void test_rhs_failure(const char *yaml) {
  decay_ctx c = {1.0, 0, 0.5};
  gs_ode ode = {1, decay_f, &c, NULL, 1, NULL, NULL, NULL, 0, NULL, 0, NULL, 0, 0, NULL, NULL, NULL};
  gs_integrator it;
  if (make_ok(yaml, &ode, &it)) return;
  gs_error err = {0};
  double t = 0, y = 1;
  int rc = advance(&it, &ode, &t, 2.0, &y, &err);
  CHECK(rc == GS_ENUMERIC);
  CHECK(contains(err.msg, "right-hand side"));
  CHECK(contains(err.msg, it.type->name));
  /* (t, y) is the last state the method accepted: consistent, before 2. */
  CHECK(t >= 0 && t < 2.0);
  CHECK_REL(y, exp(-t), 0.1);
  gs_integrator_free(&it);
}

/* NaN must surface as an error, not as a NaN state at t_out. */
static void test_nan(const char *yaml) {
  gs_ode ode = {1, nan_f, NULL, NULL, 1, NULL, NULL, NULL, 0, NULL, 0, NULL, 0, 0, NULL, NULL, NULL};
  gs_integrator it;
  if (make_ok(yaml, &ode, &it)) return;
  gs_error err = {0};
  double t = 0, y = 1;
  CHECK(advance(&it, &ode, &t, 2.0, &y, &err) == GS_ENUMERIC);
  CHECK(contains(err.msg, it.type->name));
  gs_integrator_free(&it);
}

/* GSL has no step floor of its own; min_step is enforced by the wrapper. */
static void test_rk_min_step(void) {
  gs_ode ode = {2, stiff_f, NULL, NULL, 2, NULL, NULL, NULL, 0, NULL, 0, NULL, 0, 0, NULL, NULL, NULL};
  gs_integrator it;
  if (make_ok("solver:\n  method: rk\n  min_step: 1e-3\n", &ode, &it)) return;
  gs_error err = {0};
  double y[2] = {1, 0}, t = 0;
  CHECK(advance(&it, &ode, &t, 10.0, y, &err) == GS_ENUMERIC);
  CHECK(contains(err.msg, "min_step"));
  gs_integrator_free(&it);
}

static void test_euler_negative(void) {
  gs_ode ode = {1, drain_f, NULL, NULL, 1, NULL, NULL, NULL, 0, NULL, 0, NULL, 0, 0, NULL, NULL, NULL};
  gs_integrator it;
  if (make_ok("solver:\n  method: euler\n  initial_step: 0.01\n", &ode, &it)) return;
  gs_error err = {0};
  double t = 0, y = 1;
  int rc = advance(&it, &ode, &t, 1.0, &y, &err);
  CHECK(rc == GS_ENUMERIC);
  CHECK(contains(err.msg, "negative number density"));
  CHECK(contains(err.msg, "y[0]"));
  CHECK(t > 0 && t < 1 && y >= 0); /* the last good state is kept */
  gs_integrator_free(&it);
}

static void test_max_steps(const char *method) {
  char yaml[128];
  snprintf(yaml, sizeof yaml, "solver:\n  method: %s\n  max_steps_per_output: 5\n", method);
  decay_ctx c = {1.0, 0, HUGE_VAL};
  gs_ode ode = {1, decay_f, &c, NULL, 1, NULL, NULL, NULL, 0, NULL, 0, NULL, 0, 0, NULL, NULL, NULL};
  gs_integrator it;
  if (make_ok(yaml, &ode, &it)) return;
  gs_error err = {0};
  double t = 0, y = 1;
  CHECK(advance(&it, &ode, &t, 100.0, &y, &err) == GS_ENUMERIC);
  CHECK(contains(err.msg, "integrator"));
  CHECK(t < 100.0);
  gs_integrator_free(&it);
}

/* ---- settings ------------------------------------------------------------------ */

static void expect_input_error(const char *yaml, const char *part1, const char *part2) {
  decay_ctx c = {1.0, 0, HUGE_VAL};
  gs_ode ode = {1, decay_f, &c, NULL, 1, NULL, NULL, NULL, 0, NULL, 0, NULL, 0, 0, NULL, NULL, NULL};
  gs_integrator it = {NULL, NULL};
  gs_error err = {0};
  int rc = make(yaml, &ode, &it, &err);
  CHECK(rc == GS_EINPUT);
  CHECK(it.type == NULL && it.self == NULL);
  if (!contains(err.msg, part1) || !contains(err.msg, part2))
    fprintf(stderr, "unexpected message for\n%s-> %s\n", yaml, err.msg);
  CHECK(contains(err.msg, part1));
  CHECK(contains(err.msg, part2));
}

static void test_settings(void) {
  expect_input_error("solver:\n  method: rk45\n", "test.yaml:2", "rk45");
  expect_input_error("solver:\n  method: rk45\n", "cvode", "euler");
  const char *methods[] = {"rk", "cvode", "euler"};
  for (int i = 0; i < 3; i++) {
    char yaml[256];
    snprintf(yaml, sizeof yaml, "solver:\n  method: %s\n  rtol: -1\n", methods[i]);
    expect_input_error(yaml, "rtol", "test.yaml:3");
    snprintf(yaml, sizeof yaml, "solver:\n  method: %s\n  rtoll: 1e-6\n", methods[i]);
    expect_input_error(yaml, "unknown key 'rtoll'", "rtol");
    snprintf(yaml, sizeof yaml, "solver:\n  method: %s\n  min_step: 1\n  max_step: 0.5\n",
             methods[i]);
    expect_input_error(yaml, "min_step", "max_step");
  }
  expect_input_error("solver:\n  atol: 0\n", "atol", "> 0");
  expect_input_error("solver:\n  max_steps_per_output: 0\n", "max_steps_per_output", ">= 1");
  expect_input_error("solver:\n  method: rk\n  variant: rk4\n", "variant", "rk8pd");
  expect_input_error("solver:\n  method: cvode\n  max_order: 6\n", "max_order", "5");
  expect_input_error("solver:\n  method: cvode\n  linear_solver: lu\n", "linear_solver", "gmres");
  expect_input_error("solver:\n  method: euler\n  safety: 0\n", "safety", "> 0");
  expect_input_error("solver:\n  method: rk\n  max_order: 3\n", "unknown key 'max_order'", "variant");
  expect_input_error("solver: rk\n", "solver", "map");
}

/* Every method accepts every common key, so `method` can be switched alone. */
static void test_common_keys(void) {
  const char *methods[] = {"rk", "cvode", "euler"};
  for (int i = 0; i < 3; i++) {
    char yaml[512];
    snprintf(yaml, sizeof yaml,
             "solver:\n  method: %s\n  rtol: 1e-7\n  atol: 1e-14\n  initial_step: 0.001\n"
             "  min_step: 1e-12\n  max_step: 0.05\n  max_steps_per_output: 100000\n",
             methods[i]);
    test_decay(yaml, 0.3, 1.0);
  }
}

static void test_registry(void) {
  const gs_integrator_type *const *types = gs_integrator_types();
  int count = 0;
  for (; types[count]; count++) CHECK(gs_integrator_lookup(types[count]->name) == types[count]);
  CHECK(count == 4);
  CHECK(gs_integrator_lookup("cvode") && gs_integrator_lookup("euler") && gs_integrator_lookup("auto"));
  CHECK(gs_integrator_lookup("nope") == NULL);
  /* capabilities the run driver and case reader consult instead of names */
  const gs_integrator_type *rk = gs_integrator_lookup("rk"), *cv = gs_integrator_lookup("cvode"),
                           *eu = gs_integrator_lookup("euler");
  CHECK(rk->ranks && rk->per_compartment && rk->exact_invariants && rk->carry);
  CHECK(eu->ranks && !eu->per_compartment && eu->exact_invariants && eu->carry);
  CHECK(!cv->ranks && !cv->per_compartment && !cv->exact_invariants && !cv->carry);
  /* No solver map at all: auto with default settings. */
  decay_ctx c = {1.0, 0, HUGE_VAL};
  gs_ode ode = {1, decay_f, &c, NULL, 1, NULL, NULL, NULL, 0, NULL, 0, NULL, 0, 0, NULL, NULL, NULL};
  gs_integrator it;
  gs_error err = {0};
  gs_integrator_setup setup;
  CHECK(gs_integrator_setup_read(NULL, &setup, &err) == GS_OK);
  CHECK(gs_integrator_create(&setup, &ode, &it, &err) == GS_OK);
  CHECK(it.type == gs_integrator_lookup("auto"));
  double t = 0, y = 1;
  CHECK(advance(&it, &ode, &t, 1.0, &y, &err) == GS_OK);
  CHECK_REL(y, exp(-1.0), 1e-5);
  gs_integrator_free(&it);
  gs_integrator_free(&it); /* idempotent */
  gs_ode bad = {2, decay_f, &c, NULL, 3, NULL, NULL, NULL, 0, NULL, 0, NULL, 0, 0, NULL, NULL, NULL};
  CHECK(gs_integrator_create(&setup, &bad, &it, &err) == GS_EINPUT);
  gs_integrator_setup_free(&setup);
}


/* ---- a decay left to rk, with a forcing it is told of ------------------------ */

/* y0' = -k y0 + q(t), the decay -k y0 left out of f (gs_ode.ndecay = 1), q a
 * quartic offered over each step tried as gs_ode.forcing; y1' = q (a ledger
 * entry that does not decay).  Exact: y0 = y_p(t) + (y0(0) - y_p(0)) e^{-k t}
 * with y_p = sum_j (-1)^j q^(j) / k^(j+1); y1 = its integral; what the decay
 * removed, summed over the steps, is int k y0 dt = y1(T) - (y0(T) - y0(0)). */
typedef struct {
  double k, c[5]; /* q(t) = sum_m c[m] t^m */
  double t0, h, fc[5], removed;
  double decayed[1];
  int offer; /* 0: no forcing offered */
} forced_ctx;

static double forced_q(const forced_ctx *p, double t, int deriv) {
  double sum = 0.0;
  for (int m = deriv; m < 5; m++) {
    double d = p->c[m];
    for (int j = 0; j < deriv; j++) d *= (double)(m - j);
    sum += d * pow(t, m - deriv);
  }
  return sum;
}

static int forced_f(void *ctx, double t, const double *y, double *f) {
  (void)y;
  f[0] = f[1] = forced_q(ctx, t, 0);
  return 0;
}

static void forced_trying(void *ctx, double t0, double h) {
  forced_ctx *p = ctx;
  p->t0 = t0;
  p->h = h;
}

/* q(t0 + theta h) = sum_m fc[m] theta^m: fc[m] = h^m q^(m)(t0) / m! */
static const double *forced_forcing(void *ctx) {
  forced_ctx *p = ctx;
  if (!p->offer) return NULL;
  double hm = 1.0, fact = 1.0;
  for (int m = 0; m < 5; m++) {
    if (m) fact *= m, hm *= p->h;
    p->fc[m] = hm * forced_q(p, p->t0, m) / fact;
  }
  return p->fc;
}

static int forced_step(void *ctx) {
  forced_ctx *p = ctx;
  p->removed += p->decayed[0];
  return 0;
}

static double forced_exact(const forced_ctx *p, double t) {
  double yp = 0.0, kp = p->k;
  for (int j = 0; j < 5; j++, kp *= p->k) yp += ((j & 1) ? -1.0 : 1.0) * forced_q(p, t, j) / kp;
  return yp;
}

/* Returns the steps; *err the worst error of y0 relative to its scale. */
static long forced_run(const char *outflow, int offer, double *err, double *balance) {
  char yaml[160];
  snprintf(yaml, sizeof yaml, "solver:\n  method: rk\n  rtol: 1e-8\n  atol: 1e-12\n  outflow: %s\n", outflow);
  forced_ctx p = {.k = 20.0, .c = {1.0, 3.0, -2.0, 0.5, 0.25}, .offer = offer};
  gs_ode ode = {.n = 2, .f = forced_f, .ctx = &p, .npositive = 0, .between_steps = forced_step,
                .trying = forced_trying, .forcing = forced_forcing, .ndecay = 1, .decay = p.k,
                .decayed = p.decayed};
  gs_integrator it;
  *err = INFINITY;
  if (make_ok(yaml, &ode, &it)) return -1;
  const double y00 = forced_exact(&p, 0.0) + 1.0; /* a transient of amplitude 1 */
  double y[2] = {y00, 0.0}, t = 0.0, worst = 0.0;
  gs_error e = {0};
  for (int k = 1; k <= 8; k++) {
    const double t_out = 0.25 * k;
    if (advance(&it, &ode, &t, t_out, y, &e)) {
      fprintf(stderr, "forced run: %s\n", e.msg);
      CHECK(0);
      break;
    }
    const double exact = forced_exact(&p, t) + exp(-p.k * t);
    worst = fmax(worst, fabs(y[0] - exact) / fabs(exact));
  }
  const gs_integrator_stats st = stats_of(&it);
  *err = worst;
  *balance = fabs(p.removed - (y[1] - (y[0] - y00))) / fabs(y[1]);
  gs_integrator_free(&it);
  return st.steps;
}

static void test_rk_forcing(void) {
  double err[3], bal[3];
  long steps[3];
  steps[0] = forced_run("exponential", 1, &err[0], &bal[0]);
  steps[1] = forced_run("exponential", 0, &err[1], &bal[1]); /* no forcing offered */
  steps[2] = forced_run("integrating_factor", 1, &err[2], &bal[2]);
  for (int i = 0; i < 3; i++) {
    printf("decay with a quartic forcing (%s): %ld steps, worst %.3g, removed against the balance %.3g\n",
           i == 0 ? "exponential, forcing offered" : i == 1 ? "exponential, none offered" : "integrating_factor",
           steps[i], err[i], bal[i]);
    CHECK(err[i] < 1e-7); /* rtol 1e-8 */
    CHECK(bal[i] < 1e-13);
  }
  /* a forcing it steps exactly (the frame's phi-functions, both where they
   * are summed and where recurred, k h from 0 to 5): round-off, and steps
   * that follow the transient and the outputs only (measured 3.4e-16 in 48
   * steps against 3.7e-9 in 158) */
  CHECK(err[0] < 1e-13);
  CHECK(steps[0] < steps[1] / 2);
  CHECK(steps[1] == steps[2]); /* without a forcing the default is the held rates' step */
}

int main(void) {
  test_registry();
  test_settings();
  test_common_keys();

  test_decay("solver:\n  method: rk\n  variant: rkf45\n  rtol: 1e-9\n", 1e-7, 1.0);
  test_decay("solver:\n  method: rk\n  rtol: 1e-9\n", 1e-7, 1.0);
  test_decay("solver:\n  method: rk\n  variant: rk8pd\n  rtol: 1e-9\n", 1e-7, 1.0);
  test_decay("solver:\n  method: cvode\n  rtol: 1e-8\n", 1e-6, 1.0);
  test_decay("solver:\n  method: cvode\n  linear_solver: gmres\n  rtol: 1e-8\n", 1e-6, 1.0);
  test_decay("solver:\n  method: euler\n", 0.3, 1.0);
  /* Tiny densities need an atol below them: atol is absolute, in state units. */
  test_decay("solver:\n  method: rk\n  rtol: 1e-9\n  atol: 1e-24\n", 1e-7, 1e-12);
  test_decay("solver:\n  method: cvode\n  rtol: 1e-8\n  atol: 1e-24\n", 1e-6, 1e-12);
  test_euler_order();

  test_invariants("solver:\n  method: rk\n  variant: rkf45\n", 1e-13);
  test_invariants("solver:\n  method: rk\n", 1e-13);
  test_invariants("solver:\n  method: rk\n  variant: rk8pd\n", 1e-13);
  test_invariants("solver:\n  method: cvode\n  linear_solver: dense\n", 1e-13);
  test_invariants("solver:\n  method: cvode\n  linear_solver: gmres\n", 1e-13);
  test_invariants("solver:\n  method: euler\n", 1e-13);

  test_rk_forcing();
  test_stiff();
  test_gmres_matches_dense();
  test_cvode_auto_large();
  test_cvode_restart();

  test_between_steps("solver:\n  method: rk\n", 1, 0);
  test_between_steps("solver:\n  method: rk\n", 3, 1);
  test_between_steps("solver:\n  method: rk\n  variant: rk8pd\n", 2, 1);
  test_between_steps("solver:\n  method: euler\n", 1, 0);
  test_between_steps("solver:\n  method: euler\n", 2, 1);

  test_jump("solver:\n  method: rk\n", 1);
  test_jump("solver:\n  method: cvode\n", 0);
  test_jump("solver:\n  method: euler\n", 0);
  test_growth_after_rejection();

  test_rhs_failure("solver:\n  method: rk\n");
  test_rhs_failure("solver:\n  method: cvode\n");
  test_rhs_failure("solver:\n  method: euler\n");
  test_euler_negative();
  test_nan("solver:\n  method: rk\n");
  test_nan("solver:\n  method: cvode\n");
  test_nan("solver:\n  method: euler\n");
  test_rk_min_step();
  test_rk_first_step("rkf45");
  test_rk_first_step("rkck");
  test_rk_first_step("rk8pd");
  test_max_steps("rk");
  test_max_steps("cvode");
  test_max_steps("euler");
  TEST_EXIT();
}
