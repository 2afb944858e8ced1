/* Shared helpers for the mechanism tests (tests/test_identities.c,
 * test_aggregation.c, test_breakage.c, test_growth.c, test_errors.c):
 * building a case from a YAML string, running it, moments, a fixed-seed
 * random generator.  Header-only; every function is static. */
#ifndef GRANSIM_PBM_TESTLIB_H
#define GRANSIM_PBM_TESTLIB_H

#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <gsl/gsl_integration.h>

#include "check.h"
#include "gransim/case.h"
#include "gransim/run.h"

/* every helper is static; not every test uses every helper */
#define TL_FN static __attribute__((unused))

/* printf into a malloc'ed string (the YAML of a case). */
static char *tl_fmt(const char *fmt, ...) __attribute__((format(printf, 1, 2)));
TL_FN char *tl_fmt(const char *fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  int n = vsnprintf(NULL, 0, fmt, ap);
  va_end(ap);
  char *s = malloc((size_t)n + 1);
  va_start(ap, fmt);
  vsnprintf(s, (size_t)n + 1, fmt, ap);
  va_end(ap);
  return s;
}

/* Build a case from YAML; on failure returns the status with err filled (the
 * case is freed).  Use tl_case() when the case must build. */
TL_FN int tl_case_try(const char *yaml, const char *name, gs_case *c, gs_error *err) {
  memset(c, 0, sizeof *c);
  memset(err, 0, sizeof *err);
  gs_cfg *cfg = gs_cfg_load_string(yaml, name, err);
  if (!cfg) return err->code ? err->code : GS_EINPUT;
  int rc = gs_case_from_cfg(cfg, c, err);
  if (rc) gs_case_free(c);
  return rc;
}

/* A case that must fail to build with status code and a message holding
 * every string of the NULL-terminated parts (EXPECT_INPUT below). */
TL_FN void tl_expect_input(const char *yaml, int code, const char *const *parts) {
  gs_case c;
  gs_error err;
  int rc = tl_case_try(yaml, "bad.yaml", &c, &err);
  if (rc != code) {
    fprintf(stderr, "expected status %d, got %d (%s) for:\n%s\n", code, rc, rc ? err.msg : "built", yaml);
    check_failures++;
    if (!rc) gs_case_free(&c);
    return;
  }
  for (size_t i = 0; parts[i]; i++)
    if (!strstr(err.msg, parts[i])) {
      fprintf(stderr, "message lacks '%s':\n  %s\n", parts[i], err.msg);
      check_failures++;
    }
}
#define EXPECT_INPUT(yaml, ...) tl_expect_input(yaml, GS_EINPUT, (const char *const[]){__VA_ARGS__, NULL})

/* The mechanisms' tests measured their errors with the integrator that was
 * the default then (rk, atol 1e-12 particles) and keep it: a case without a
 * solver section gets that one, and one whose solver map names no method gets
 * rk (the default "auto" and its case-scaled atol have tests of their own,
 * test_auto). */
TL_FN char *tl_pin_solver(const char *yaml) {
  const char *sv = strstr(yaml, "solver:");
  if (!sv) return tl_fmt("%s\nsolver: {method: rk, atol: 1.0e-12}\n", yaml);
  const char *brace = strchr(sv, '{'), *nl = strchr(sv, '\n');
  if (strstr(sv, "method") || !brace || (nl && nl < brace)) return tl_fmt("%s", yaml);
  return tl_fmt("%.*smethod: rk, %s", (int)(brace + 1 - yaml), yaml, brace + 1);
}

TL_FN int tl_case(const char *yaml_in, gs_case *c) {
  gs_error err;
  char *yaml = tl_pin_solver(yaml_in);
  int rc = tl_case_try(yaml, "t.yaml", c, &err);
  free(yaml);
  yaml = (char *)yaml_in;
  if (rc) {
    fprintf(stderr, "case did not build: %s\n--- yaml ---\n%s\n", err.msg, yaml);
    check_failures++;
  }
  return rc;
}

/* Build a case from yaml (taken over and freed) and evaluate its rates at
 * the initial state into *d (nstate) and *dl (nledger), both malloc'ed;
 * returns 0 (free them with tl_rates_free), or non-zero (counted as a failed
 * check, nothing to free) when the case does not build. */
TL_FN int tl_rates_at_start(char *yaml, gs_case *c, double **d, double **dl) {
  const int failed = tl_case(yaml, c);
  free(yaml);
  if (failed) return 1;
  *d = calloc(c->model.nstate, sizeof **d);
  *dl = calloc(c->model.nledger, sizeof **dl);
  gs_model_rhs(&c->model, &c->eval, 0, c->y0, *d, *dl);
  return 0;
}
TL_FN void tl_rates_free(gs_case *c, double *d, double *dl) {
  free(d);
  free(dl);
  gs_case_free(c);
}

/* Run a built case; returns the final state (nstate + nledger, malloc'ed) or
 * NULL on failure (counted as a failed check unless expect_fail). */
TL_FN double *tl_run(gs_case *c, gs_run_report *rep, int *rc_out, gs_error *err_out) {
  gs_error err;
  memset(&err, 0, sizeof err);
  size_t n = c->model.nstate + c->model.nledger;
  double *y = calloc(n, sizeof(double));
  gs_run_report r;
  gs_run_options opt = {0};
  int rc = gs_case_run(c, &opt, y, &r, &err);
  if (rep) *rep = r;
  if (err_out) *err_out = err;
  if (rc_out) *rc_out = rc;
  else if (rc) {
    fprintf(stderr, "run failed (%d): %s\n", rc, err.msg);
    check_failures++;
  }
  return y;
}

/* Build + run; returns the final state or NULL (case left built in *c). */
TL_FN double *tl_build_run(const char *yaml, gs_case *c, gs_run_report *rep) {
  if (tl_case(yaml, c)) return NULL;
  return tl_run(c, rep, NULL, NULL);
}

/* Mixed moment of compartment comp: sum N x0^p0 x1^p1 x2^p2. */
TL_FN double tl_mom(const gs_case *c, const double *y, size_t comp, int p0, int p1, int p2) {
  int p[3] = {p0, p1, p2};
  return gs_moment(&c->model, y, comp, p);
}

TL_FN double tl_relerr(double got, double want) { return fabs(got - want) / fabs(want); }

/* Fixed-seed generator (64-bit LCG, Knuth's MMIX constants), uniform in (0, 1). */
typedef struct { uint64_t s; } tl_rng;
TL_FN double tl_uniform(tl_rng *r) {
  r->s = r->s * 6364136223846793005ULL + 1442695040888963407ULL;
  return ((double)(r->s >> 11) + 0.5) / 9007199254740992.0;
}

/* The ledger entries of compartment comp for volume coordinate k (axes, then
 * carried quantities): ext[k] = ledger[comp*2*nvol + k], lost[k] = ledger[comp*2*nvol + nvol + k]. */
TL_FN double tl_ext(const gs_model *m, const double *ledger, size_t comp, int k) {
  return ledger[comp * 2 * (size_t)m->nvol + (size_t)k];
}
TL_FN double tl_lost(const gs_model *m, const double *ledger, size_t comp, int k) {
  return ledger[comp * 2 * (size_t)m->nvol + (size_t)m->nvol + (size_t)k];
}

/* Advance a case's state from *t to t_out the way the run driver does: one
 * advance per stretch between rate switches (gs_model_next_switch), the
 * switch interval of the evaluation context ev set for it, and `jumped` when a stretch starts at a
 * switch.  advance(ctx, t, stop, jumped, err) moves *t to stop; *switched
 * keeps the last switch reached across calls (NAN at first). */
typedef int (*tl_advance_fn)(void *ctx, double *t, double stop, int jumped, gs_error *err);
TL_FN int tl_advance_to(const gs_model *m, gs_eval *ev, double *t, double t_out, double *switched, tl_advance_fn advance,
                        void *ctx, gs_error *err) {
  while (*t < t_out) {
    const double sw = gs_model_next_switch(m, *t), stop = fmin(t_out, sw);
    const int jumped = *t == *switched;
    ev->switch_lo = *t;
    ev->switch_hi = stop;
    int rc = advance(ctx, t, stop, jumped, err);
    ev->switch_lo = 1;
    ev->switch_hi = 0;
    if (rc) return rc;
    if (*t == sw) *switched = *t;
  }
  return GS_OK;
}

/* At an output time: the most negative number relative to the largest
 * (*most_negative, kept as the minimum over calls), and per volume
 * coordinate and compartment the ledger balance held = initial + exchanged -
 * lost and the loss through the grid, relative to the coordinate's turnover
 * over all compartments (*worst_ledger, *worst_lost: maxima over calls). */
TL_FN void tl_state_checks(const gs_model *m, const double *y0, const double *y, double *most_negative,
                           double *worst_ledger, double *worst_lost) {
  double ymax = 0;
  for (size_t j = 0; j < m->nstate; j++) ymax = fmax(ymax, fabs(y[j]));
  for (size_t j = 0; ymax > 0 && j < m->nstate; j++) *most_negative = fmin(*most_negative, y[j] / ymax);
  const double *L = y + m->nstate;
  const size_t ncomp = m->grid.ncomp;
  for (int k = 0; k < m->nvol; k++) {
    double scale = 0;
    for (size_t comp = 0; comp < ncomp; comp++)
      scale += fabs(gs_model_held(m, y, comp, k)) + fabs(tl_ext(m, L, comp, k)) + fabs(gs_model_held(m, y0, comp, k));
    for (size_t comp = 0; scale > 0 && comp < ncomp; comp++) {
      double held = gs_model_held(m, y, comp, k), ext = tl_ext(m, L, comp, k), lost = tl_lost(m, L, comp, k);
      *worst_ledger = fmax(*worst_ledger, fabs(held - (gs_model_held(m, y0, comp, k) + ext - lost)) / scale);
      *worst_lost = fmax(*worst_lost, fabs(lost) / scale);
    }
  }
}

/* Projection of a 1-D density f(v) onto the pivots the way gransim
 * discretises initial distributions: per cell, the number and first moment of
 * f are integrated (adaptive quadrature) and placed on the two pivots around
 * the cell's mean volume by the lever rule (clamped at the ends).  Comparing a
 * computed state with the projection of the exact solution measures the
 * error of the scheme, not of the representation. */
typedef struct {
  double (*f)(double v, void *p);
  void *p;
  int moment;
} tl_qfun;

TL_FN double tl_qeval(double v, void *vp) {
  const tl_qfun *q = vp;
  double f = q->f(v, q->p);
  return q->moment ? v * f : f;
}

TL_FN void tl_project(const gs_axis *ax, double (*f)(double, void *), void *p, double *out) {
  gsl_integration_workspace *ws = gsl_integration_workspace_alloc(2000);
  memset(out, 0, ax->n * sizeof(double));
  for (size_t i = 0; i < ax->n; i++) {
    double cn, cm, e;
    tl_qfun q = {f, p, 0};
    gsl_function F = {tl_qeval, &q};
    gsl_integration_qags(&F, ax->edges[i], ax->edges[i + 1], 1e-300, 1e-11, 2000, ws, &cn, &e);
    q.moment = 1;
    gsl_integration_qags(&F, ax->edges[i], ax->edges[i + 1], 1e-300, 1e-11, 2000, ws, &cm, &e);
    if (!(cn > 0)) continue;
    double v = cm / cn;
    const double *x = ax->pivots;
    size_t lo = i;
    if (v < x[i]) lo = i > 0 ? i - 1 : 0;
    if (lo + 1 >= ax->n || v <= x[lo]) {
      out[lo] += cn; /* at or beyond an end pivot: number kept there */
      continue;
    }
    double w = (v - x[lo]) / (x[lo + 1] - x[lo]);
    if (w > 1) w = 1;
    out[lo] += cn * (1 - w);
    out[lo + 1] += cn * w;
  }
  gsl_integration_workspace_free(ws);
}

/* Volume-weighted L1 distance  sum |N_i - P_i| x_i / sum P_i x_i. */
TL_FN double tl_wl1(const gs_axis *ax, const double *N, const double *P) {
  double s = 0, t = 0;
  for (size_t i = 0; i < ax->n; i++) {
    s += fabs(N[i] - P[i]) * ax->pivots[i];
    t += P[i] * ax->pivots[i];
  }
  return s / t;
}
#endif
