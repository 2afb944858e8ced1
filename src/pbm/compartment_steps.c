/* Per-compartment time steps: see compartment_steps.h for the scheme and why
 * it conserves exactly. */
#include "pbm/compartment_steps.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "gransim/pbm.h"
#include "pbm/all_finite.h"

/* A stretch's accepted step ends of one compartment: times, the integral Z
 * of its numbers and carried totals since the stretch began, those numbers
 * and totals N (Z's slope) and their rates f (Z's second derivative). */
typedef struct {
  size_t count, cap;
  double *t, *z, *n, *f; /* cap, then cap * nflow each */
} node_list;

typedef struct {
  struct gs_comp_steps *s;
  size_t comp;
  int has_next; /* feeds the next compartment: integrates Z and keeps a record */
  size_t n;     /* local length */
  double *y, *scale;
  double t; /* the integrator's time during an advance */
  double try_s, try_h; /* the step it tries */
  double *end_f;       /* rates at the end of the last stretch (has_next) */
  int end_f_valid;
  gs_integrator it;
  gs_ode ode;
} comp_t;

struct gs_comp_steps {
  gs_model *m;
  size_t ncomp, ncells, nflow; /* nflow: numbers and carried totals of one compartment */
  int nvol, dim, nq;
  size_t off_ledger, off_recv, off_z; /* in a compartment's local vector */
  double *k;                          /* transfer rate out of each compartment */
  comp_t *comp;
  node_list nodes[2];  /* compartment c records into nodes[c % 2] */
  const node_list *up; /* the record the compartment being advanced reads */
  node_list *rec;      /* the record it writes (NULL for the last) */
  /* the step being tried by the compartment being advanced: [try_s, try_s +
   * try_h], Z_H and its first two derivatives at both ends, and the inflow
   * state P' */
  double try_s, try_h;
  double *p0, *p1, *d0, *d1, *s0, *s1, *halo;
  /* the rates of the last evaluation (numbers and totals) and its time; the
   * stretch's start, and whether its first node has its rates yet */
  double *last_f, last_t, stretch_t0;
  double *scratch, *ytmp; /* rates and a state outside the integrator (longest local length) */
  int start_f_known;
  double sent[GS_MAX_VOL]; /* what the last compartment advanced discharged in the stretch */
  double worst_coupling;
  double t_rhs;
  int bad, off_stretch;
  double bad_t;
  size_t bad_index;
};

static double now_seconds(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* Append a node (z NULL: zero; f NULL: filled in later). */
/* The quintic Hermite basis on [0, 1] (b[0]) and its first (b[1]) and
 * second (b[2]) derivatives at u, in the order: value at 0, slope at 0,
 * second derivative at 0, second derivative at 1, slope at 1, value at 1. */
static void quintic_basis(double u, double b[3][6]) {
  const double u2 = u * u, u3 = u2 * u, u4 = u3 * u, u5 = u4 * u;
  b[0][0] = 1 - 10 * u3 + 15 * u4 - 6 * u5;
  b[0][1] = u - 6 * u3 + 8 * u4 - 3 * u5;
  b[0][2] = 0.5 * u2 - 1.5 * u3 + 1.5 * u4 - 0.5 * u5;
  b[0][3] = 0.5 * u3 - u4 + 0.5 * u5;
  b[0][4] = -4 * u3 + 7 * u4 - 3 * u5;
  b[0][5] = 10 * u3 - 15 * u4 + 6 * u5;
  b[1][0] = -30 * u2 + 60 * u3 - 30 * u4;
  b[1][1] = 1 - 18 * u2 + 32 * u3 - 15 * u4;
  b[1][2] = u - 4.5 * u2 + 6 * u3 - 2.5 * u4;
  b[1][3] = 1.5 * u2 - 4 * u3 + 2.5 * u4;
  b[1][4] = -12 * u2 + 28 * u3 - 15 * u4;
  b[1][5] = 30 * u2 - 60 * u3 + 30 * u4;
  b[2][0] = -60 * u + 180 * u2 - 120 * u3;
  b[2][1] = -36 * u + 96 * u2 - 60 * u3;
  b[2][2] = 1 - 9 * u + 18 * u2 - 10 * u3;
  b[2][3] = 3 * u - 12 * u2 + 10 * u3;
  b[2][4] = -24 * u + 84 * u2 - 60 * u3;
  b[2][5] = 60 * u - 180 * u2 + 120 * u3;
}

static int nodes_push(node_list *L, size_t nflow, double t, const double *z, const double *n,
                      const double *f) {
  if (L->count == L->cap) {
    size_t cap = L->cap ? 2 * L->cap : 64;
    double *tt = realloc(L->t, cap * sizeof(double));
    if (!tt) return GS_ENOMEM;
    L->t = tt;
    double **arrays[] = {&L->z, &L->n, &L->f};
    for (int i = 0; i < 3; i++) {
      double *grown = realloc(*arrays[i], cap * nflow * sizeof(double));
      if (!grown) return GS_ENOMEM;
      *arrays[i] = grown;
    }
    L->cap = cap;
  }
  const size_t at = L->count * nflow;
  L->t[L->count] = t;
  if (z) memcpy(L->z + at, z, nflow * sizeof(double));
  else memset(L->z + at, 0, nflow * sizeof(double));
  memcpy(L->n + at, n, nflow * sizeof(double));
  if (f) memcpy(L->f + at, f, nflow * sizeof(double));
  L->count++;
  return GS_OK;
}

/* Z_H and its first two derivatives at t: node values where t is a node (or
 * outside the record), else the quintic Hermite piece through the two nodes
 * around t (values, slopes and second derivatives at both: as accurate as a
 * fifth-order step). */
static void nodes_eval(const node_list *L, size_t nflow, double t, double *z, double *dz,
                       double *d2z) {
  const size_t last = L->count - 1;
  size_t j = 0;
  if (t >= L->t[last]) j = last;
  else if (t > L->t[0]) {
    size_t lo = 0, hi = last; /* t[lo] <= t < t[hi] */
    while (hi - lo > 1) {
      size_t mid = lo + (hi - lo) / 2;
      if (L->t[mid] <= t) lo = mid;
      else hi = mid;
    }
    j = lo;
    if (t != L->t[lo]) {
      const double H = L->t[lo + 1] - L->t[lo], u = (t - L->t[lo]) / H;
      double b[3][6]; /* the basis and its first two derivatives in u */
      quintic_basis(u, b);
      const double *za = L->z + lo * nflow, *zb = za + nflow;
      const double *na = L->n + lo * nflow, *nb = na + nflow;
      const double *fa = L->f + lo * nflow, *fb = fa + nflow;
      for (int k = 0; k < 3; k++) {
        /* d^k/dt^k = H^-k d^k/du^k; slopes carry H, second derivatives H^2 */
        const double sc = k == 0 ? 1.0 : k == 1 ? 1.0 / H : 1.0 / (H * H);
        const double c0 = sc * b[k][0], c1 = sc * H * b[k][1], c2 = sc * H * H * b[k][2];
        const double c3 = sc * H * H * b[k][3], c4 = sc * H * b[k][4], c5 = sc * b[k][5];
        double *out = k == 0 ? z : k == 1 ? dz : d2z;
        for (size_t i = 0; i < nflow; i++)
          out[i] = c0 * za[i] + c1 * na[i] + c2 * fa[i] + c3 * fb[i] + c4 * nb[i] + c5 * zb[i];
      }
      return;
    }
  }
  memcpy(z, L->z + j * nflow, nflow * sizeof(double));
  memcpy(dz, L->n + j * nflow, nflow * sizeof(double));
  memcpy(d2z, L->f + j * nflow, nflow * sizeof(double));
}

/* gs_ode.trying: the step about to be tried; for a compartment fed by
 * another, Z_H and its derivatives at the step's ends. */
static void comp_trying(void *ctx, double t0, double h) {
  comp_t *cp = ctx;
  struct gs_comp_steps *s = cp->s;
  cp->try_s = t0;
  cp->try_h = h;
  if (!cp->comp) return;
  s->try_s = t0;
  s->try_h = h;
  nodes_eval(s->up, s->nflow, t0, s->p0, s->d0, s->s0);
  nodes_eval(s->up, s->nflow, t0 + h, s->p1, s->d1, s->s1);
}

/* The upstream numbers and totals whose flow k P'(t) enters at t: P' of the
 * quintic Hermite P through Z_H's values and first two derivatives at the
 * ends of the step tried.  P' is a quartic: the weights of a Runge-Kutta
 * step of order >= 5 (rkf45, rkck, rk8pd) integrate it exactly.  0 when t
 * lies outside the step tried (an integrator that does not say which step
 * it tries). */
static int inflow_state(struct gs_comp_steps *s, double t) {
  const double h = s->try_h, th = h > 0 ? (t - s->try_s) / h : 0.0;
  if (!(th >= -1e-9 && th <= 1 + 1e-9)) return 0;
  double b[3][6];
  quintic_basis(th, b);
  /* P' = (P1 - P0) b5' / h + D0 b1' + D1 b4' + h (S0 b2' + S1 b3'), b0' = -b5' */
  const double a = h > 0 ? b[1][5] / h : 0.0, c1 = b[1][1], c4 = b[1][4], c2 = h * b[1][2],
               c3 = h * b[1][3];
  const double *p0 = s->p0, *p1 = s->p1, *d0 = s->d0, *d1 = s->d1, *s0 = s->s0, *s1 = s->s1;
  double *q = s->halo;
  for (size_t i = 0; i < s->nflow; i++)
    q[i] = a * (p1[i] - p0[i]) + c1 * d0[i] + c4 * d1[i] + c2 * s0[i] + c3 * s1[i];
  return 1;
}

/* Volumes (per axis, then per carried quantity) of numbers and totals v. */
static void volumes_of(const struct gs_comp_steps *s, const double *v, double *vol) {
  const gs_grid *g = &s->m->grid;
  const size_t n = s->ncells;
  for (int a = 0; a < s->dim; a++) {
    double sum = 0;
    for (size_t c = 0; c < n; c++) sum += g->x[c * (size_t)s->dim + (size_t)a] * v[c];
    vol[a] = sum;
  }
  for (int q = 0; q < s->nq; q++) {
    double sum = 0;
    for (size_t c = 0; c < n; c++) sum += v[(1 + (size_t)q) * n + c];
    vol[s->dim + q] = sum;
  }
}


/* Index in the full state of entry i of compartment comp's local vector
 * (the received volumes and Z map to its ledger). */
static size_t full_index(const struct gs_comp_steps *s, size_t comp, size_t i) {
  const gs_model *m = s->m;
  if (i < s->ncells) return comp * s->ncells + i;
  if (i < s->nflow) return m->nnum + comp * (s->nflow - s->ncells) + (i - s->ncells);
  size_t j = i - s->nflow;
  return m->nstate + comp * 2 * (size_t)s->nvol + (j < 2 * (size_t)s->nvol ? j : 0);
}

static int comp_rhs(void *ctx, double t, const double *y, double *f) {
  comp_t *cp = ctx;
  struct gs_comp_steps *s = cp->s;
  gs_model *m = s->m;
  const double start = now_seconds();
  if (cp->comp && !inflow_state(s, t)) {
    s->off_stretch = 1;
    s->bad_t = t;
    return 1;
  }
  m->in_integrator = 1;
  gs_model_rhs(m, t, y, f, f + s->off_ledger);
  m->in_integrator = 0;
  double *recv = f + s->off_recv;
  if (cp->comp) {
    volumes_of(s, s->halo, recv);
    for (int a = 0; a < s->nvol; a++) recv[a] *= s->k[cp->comp - 1];
  } else {
    memset(recv, 0, (size_t)s->nvol * sizeof(double));
  }
  if (cp->has_next) {
    memcpy(f + s->off_z, y, s->nflow * sizeof(double));
    memcpy(s->last_f, f, s->nflow * sizeof(double));
    s->last_t = t;
    /* the first node's rates: the integrator's own evaluation at the start */
    if (!s->start_f_known && t == s->stretch_t0 && s->rec->count == 1) {
      memcpy(s->rec->f, f, s->nflow * sizeof(double));
      s->start_f_known = 1;
    }
  }
  s->t_rhs += now_seconds() - start;
  if (gs_all_finite(f, cp->n)) return 0;
  for (size_t i = 0; i < cp->n; i++)
    if (!isfinite(f[i])) {
      s->bad = 1;
      s->bad_t = t;
      s->bad_index = full_index(s, cp->comp, i);
      break;
    }
  return 1;
}

/* The rates of compartment cp at (t, y) into s->last_f, outside the
 * integrator's own evaluations (rarely needed: see comp_step_done). */
static int extra_rates(comp_t *cp, double t, const double *y) {
  struct gs_comp_steps *s = cp->s;
  double *f = s->scratch;
  int rc = comp_rhs(cp, t, y, f);
  if (!rc) memcpy(s->last_f, f, s->nflow * sizeof(double));
  return rc;
}

/* The first node's rates, when the integrator did not evaluate them at the
 * stretch's start (GSL's evolve does after a reset and on its first step;
 * otherwise it reuses the last stretch's, end_f): evaluated here from the
 * node's numbers and totals, with the inflow at t0. */
static int start_rates(comp_t *cp, double t0, gs_error *err) {
  struct gs_comp_steps *s = cp->s;
  double *y = s->ytmp;
  memset(y, 0, cp->n * sizeof(double));
  memcpy(y, s->rec->n, s->nflow * sizeof(double));
  if (cp->comp) {
    s->try_s = t0;
    s->try_h = 0; /* the inflow is then Z_H'(t0) */
    nodes_eval(s->up, s->nflow, t0, s->p0, s->d0, s->s0);
  }
  if (extra_rates(cp, t0, y))
    return gs_error_set(err, GS_ENUMERIC, "per-compartment steps: compartment %zu: rates not finite at t = %.9g", cp->comp + 1, t0);
  memcpy(s->rec->f, s->last_f, s->nflow * sizeof(double));
  s->start_f_known = 1;
  return GS_OK;
}

/* gs_ode.between_steps: record the step end for the next compartment.  Its
 * rates are those of the integrator's last evaluation, at the end of the
 * accepted step (GSL's steppers evaluate the end-of-step derivative, which
 * the next step reuses); otherwise they are evaluated here. */
static int comp_step_done(void *ctx) {
  comp_t *cp = ctx;
  struct gs_comp_steps *s = cp->s;
  if (!cp->has_next) return 0;
  if (s->last_t != cp->try_s + cp->try_h && extra_rates(cp, cp->t, cp->y)) {
    s->bad = s->bad ? s->bad : 3;
    return 1;
  }
  if (nodes_push(s->rec, s->nflow, cp->t, cp->y + s->off_z, cp->y, s->last_f)) {
    s->bad = 2;
    return 1;
  }
  return 0;
}

static void pack(const struct gs_comp_steps *s, size_t comp, const double *Y, double *y) {
  const gs_model *m = s->m;
  const size_t nc = s->ncells, nqc = s->nflow - nc, nl = 2 * (size_t)s->nvol;
  memcpy(y, Y + comp * nc, nc * sizeof(double));
  memcpy(y + nc, Y + m->nnum + comp * nqc, nqc * sizeof(double));
  memcpy(y + s->off_ledger, Y + m->nstate + comp * nl, nl * sizeof(double));
}

static void unpack(const struct gs_comp_steps *s, size_t comp, const double *y, double *Y) {
  const gs_model *m = s->m;
  const size_t nc = s->ncells, nqc = s->nflow - nc, nl = 2 * (size_t)s->nvol;
  memcpy(Y + comp * nc, y, nc * sizeof(double));
  memcpy(Y + m->nnum + comp * nqc, y + nc, nqc * sizeof(double));
  memcpy(Y + m->nstate + comp * nl, y + s->off_ledger, nl * sizeof(double));
}

int gs_comp_steps_create(gs_case *c, gs_cfg_node *solver, gs_comp_steps **out, gs_error *err) {
  gs_model *m = &c->model;
  *out = NULL;
  struct gs_comp_steps *s = gs_calloc(1, sizeof *s, err);
  if (!s) return GS_ENOMEM;
  s->m = m;
  s->ncomp = m->grid.ncomp;
  s->ncells = m->grid.ncells;
  s->nq = m->ncarried;
  s->nflow = s->ncells * (1 + (size_t)s->nq);
  s->nvol = m->nvol;
  s->dim = m->grid.dim;
  s->off_ledger = s->nflow;
  s->off_recv = s->off_ledger + 2 * (size_t)s->nvol;
  s->off_z = s->off_recv + (size_t)s->nvol;
  *out = s;
  s->k = gs_calloc(s->ncomp, sizeof(double), err);
  s->comp = gs_calloc(s->ncomp, sizeof(comp_t), err);
  if (!s->k || !s->comp) return GS_ENOMEM;
  double **bufs[] = {&s->p0, &s->p1, &s->d0, &s->d1, &s->s0, &s->s1, &s->halo, &s->last_f};
  for (size_t i = 0; i < sizeof bufs / sizeof *bufs; i++)
    if (!(*bufs[i] = gs_calloc(s->nflow, sizeof(double), err))) return GS_ENOMEM;
  for (size_t comp = 0; comp < s->ncomp; comp++) s->k[comp] = gs_model_transfer_rate(m, comp);
  if (!(s->scratch = gs_calloc(s->off_z + s->nflow, sizeof(double), err)) ||
      !(s->ytmp = gs_calloc(s->off_z + s->nflow, sizeof(double), err)))
    return GS_ENOMEM;
  for (size_t comp = 0; comp < s->ncomp; comp++) {
    comp_t *cp = &s->comp[comp];
    cp->s = s;
    cp->comp = comp;
    cp->has_next = comp + 1 < s->ncomp;
    cp->n = s->off_z + (cp->has_next ? s->nflow : 0);
    cp->y = gs_calloc(cp->n, sizeof(double), err);
    cp->scale = gs_calloc(cp->n, sizeof(double), err); /* received and Z: no error control */
    cp->end_f = cp->has_next ? gs_calloc(s->nflow, sizeof(double), err) : NULL;
    if (!cp->y || !cp->scale || (cp->has_next && !cp->end_f)) return GS_ENOMEM;
    pack(s, comp, c->abs_scale, cp->scale);
    cp->ode = (gs_ode){cp->n, comp_rhs, cp, cp->scale, s->nflow, NULL, NULL, NULL, 1,
                       comp_step_done, 0, comp_trying};
    int rc = gs_integrator_create(solver, &cp->ode, &cp->it, err);
    if (rc) return rc;
    if (!cp->it.type->carry || strcmp(cp->it.type->name, "rk"))
      return gs_error_set(err, GS_EINPUT,
                          "solver.steps: per_compartment needs method rk (its coupling uses the "
                          "Runge-Kutta steps' exact quadrature), not %s",
                          cp->it.type->name);
  }
  return GS_OK;
}

/* The model evaluates compartment comp alone, on its local vector. */
static void view_one(gs_model *m, const struct gs_comp_steps *s, size_t comp) {
  m->comp_lo = comp;
  m->comp_hi = comp + 1;
  m->view_lo = comp;
  m->view_carried = s->ncells;
  m->halo = comp ? s->halo : NULL;
}

static void view_all(gs_model *m, const struct gs_comp_steps *s) {
  m->comp_lo = 0;
  m->comp_hi = s->ncomp;
  m->view_lo = 0;
  m->view_carried = m->nnum;
  m->halo = NULL;
}

/* What compartment comp received in the stretch against what the one before
 * discharged (s->sent); the run stops when they differ beyond round-off. */
static int check_coupling(struct gs_comp_steps *s, const comp_t *cp, double t0, double t1,
                          gs_error *err) {
  const double *recv = cp->y + s->off_recv;
  for (int a = 0; a < s->nvol; a++) {
    const double big = fmax(fabs(recv[a]), fabs(s->sent[a]));
    const double rel = big > 0 ? fabs(recv[a] - s->sent[a]) / big : 0.0;
    if (rel > s->worst_coupling) s->worst_coupling = rel;
    if (!(rel <= 1e-10))
      return gs_error_set(err, GS_ENUMERIC,
                          "per-compartment steps: from t = %.9g to %.9g compartment %zu received "
                          "%.17g of %s where compartment %zu discharged %.17g (relative %.3g); the "
                          "coupling lost volume",
                          t0, t1, cp->comp + 1, recv[a], gs_model_vol_name(s->m, a), cp->comp,
                          s->sent[a], rel);
  }
  return GS_OK;
}

int gs_comp_steps_advance(gs_comp_steps *s, double *t, double stop, double *Y, int jumped,
                          gs_error *err) {
  gs_model *m = s->m;
  const double t0 = *t;
  if (!(stop > t0)) return GS_OK;
  s->bad = 0;
  s->off_stretch = 0;
  for (size_t comp = 0; comp < s->ncomp; comp++) {
    comp_t *cp = &s->comp[comp];
    pack(s, comp, Y, cp->y);
    memset(cp->y + s->off_recv, 0, (cp->n - s->off_recv) * sizeof(double)); /* received, Z */
    cp->t = t0;
    s->up = comp ? &s->nodes[(comp - 1) % 2] : NULL;
    s->rec = cp->has_next ? &s->nodes[comp % 2] : NULL;
    s->stretch_t0 = t0;
    s->last_t = NAN;
    s->start_f_known = 0;
    if (s->rec) {
      s->rec->count = 0;
      if (nodes_push(s->rec, s->nflow, t0, NULL, cp->y, NULL))
        return gs_error_set(err, GS_ENOMEM, "out of memory for the per-compartment step record");
      /* without a jump the integrator starts from the rates it ended the
       * last stretch with, and evaluates none at t0 */
      if (!jumped && cp->end_f_valid) {
        memcpy(s->rec->f, cp->end_f, s->nflow * sizeof(double));
        s->start_f_known = 1;
      }
    }
    cp->ode.jumped = jumped;
    view_one(m, s, comp);
    int rc = cp->it.type->advance(cp->it.self, &cp->ode, &cp->t, stop, cp->y, err);
    if (!rc && s->rec && !s->start_f_known) rc = start_rates(cp, t0, err);
    view_all(m, s);
    if (!rc && s->bad == 2) rc = gs_error_set(err, GS_ENOMEM, "out of memory for the per-compartment step record");
    if (!rc && s->bad) /* 1 or 3: rates evaluated at a step's end were not finite */
      rc = gs_error_set(err, GS_ENUMERIC, "integrator rk: right-hand side failed at t = %.9g", s->bad_t);
    if (!rc && cp->t != stop)
      rc = gs_error_set(err, GS_ENUMERIC, "per-compartment steps: compartment %zu stopped at t = %.17g short of %.17g", comp + 1, cp->t, stop);
    if (rc && s->off_stretch)
      rc = gs_error_set(err, GS_ENUMERIC,
                        "per-compartment steps: compartment %zu evaluated at t = %.17g outside "
                        "the step its integrator announced [%.17g, %.17g]",
                        comp + 1, s->bad_t, s->try_s, s->try_s + s->try_h);
    if (rc) return rc;
    unpack(s, comp, cp->y, Y);
    if (comp) {
      rc = check_coupling(s, cp, t0, stop, err);
      if (rc) return rc;
    }
    if (cp->has_next) {
      memcpy(cp->end_f, s->rec->f + (s->rec->count - 1) * s->nflow, s->nflow * sizeof(double));
      cp->end_f_valid = 1;
      volumes_of(s, cp->y + s->off_z, s->sent);
      for (int a = 0; a < s->nvol; a++) s->sent[a] *= s->k[comp];
    }
  }
  *t = stop;
  return GS_OK;
}

void gs_comp_steps_comp_stats(const gs_comp_steps *s, size_t comp, gs_integrator_stats *st) {
  const comp_t *cp = &s->comp[comp];
  cp->it.type->get_stats(cp->it.self, st);
}

void gs_comp_steps_stats(const gs_comp_steps *s, gs_integrator_stats *st) {
  memset(st, 0, sizeof *st);
  for (size_t comp = 0; comp < s->ncomp; comp++) {
    gs_integrator_stats one;
    gs_comp_steps_comp_stats(s, comp, &one);
    st->steps += one.steps;
    st->rejected += one.rejected;
    st->rhs_evals += one.rhs_evals;
    st->last_step = one.last_step;
  }
}

double gs_comp_steps_rhs_seconds(const gs_comp_steps *s) { return s->t_rhs; }

int gs_comp_steps_bad_rate(const gs_comp_steps *s, double *t, size_t *full) {
  if (s->bad != 1) return 0;
  *t = s->bad_t;
  *full = s->bad_index;
  return 1;
}

double gs_comp_steps_worst_coupling(const gs_comp_steps *s) { return s->worst_coupling; }

void gs_comp_steps_free(gs_comp_steps *s) {
  if (!s) return;
  for (size_t comp = 0; s->comp && comp < s->ncomp; comp++) {
    gs_integrator_free(&s->comp[comp].it);
    free(s->comp[comp].y);
    free(s->comp[comp].scale);
    free(s->comp[comp].end_f);
  }
  for (int i = 0; i < 2; i++) {
    free(s->nodes[i].t);
    free(s->nodes[i].z);
    free(s->nodes[i].n);
  }
  double *bufs[] = {s->p0, s->p1, s->d0, s->d1, s->s0, s->s1, s->halo, s->last_f, s->scratch, s->ytmp};
  for (size_t i = 0; i < sizeof bufs / sizeof *bufs; i++) free(bufs[i]);
  for (int i = 0; i < 2; i++) free(s->nodes[i].f);
  free(s->k);
  free(s->comp);
  free(s);
}
