/* Per-compartment time steps: see compartment_steps.h for the scheme, why it
 * conserves exactly, and how threads share the compartments. */
#include "run/compartment_steps.h"

#include <float.h>
#include <math.h>
#include <omp.h>
#include <sched.h>
#include <stdatomic.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <stdio.h>
#include <time.h>

#include "core/block_pool.h"
#include "gransim/pbm.h"
#include "pbm/all_finite.h"
#include "run/compartment_ranks.h"
#include "run/distributed.h"

/* A stretch's accepted step ends of one compartment: times, the integral Z
 * of its numbers and carried totals since the stretch began, those numbers
 * and totals N (Z's slope) and their rates f (Z's second derivative).  Kept
 * in blocks that never move, so that the next compartment reads the nodes
 * published so far while this one appends. */
#define NODE_MAX 32768          /* steps one compartment may take in one stretch */
/* nodes per block: as many as fit in NODE_BLOCK_BYTES, 1 to 16; the
 * blocks come from the run's pool (gs_block_pool: reused while still in
 * cache, on huge pages) and go back to it as soon as the next compartment
 * has read the record */
#define NODE_BLOCK_BYTES 65536
/* a stretch's record, as the ring's depth budgets it (RING_BYTES) */
#define NODE_KEEP_BYTES ((size_t)256 << 10)
#define DIR_SIZE 512 /* block pointers per directory page */
#define DIR_PAGES (NODE_MAX / DIR_SIZE)
typedef struct {
  size_t per;    /* nodes per block */
  /* doubles from one node to the next, 1 + 3 nflow rounded up to whole
   * pages (GS_APART): the next compartment reads a node while this one
   * writes the one after */
  size_t stride;
  gs_block_pool *pool; /* where its blocks come from */
  /* blocks of per * stride doubles, through pages of DIR_SIZE pointers made
   * as needed (a reader only looks up published nodes, whose pages and
   * blocks exist) */
  double **dir[DIR_PAGES];
  /* nodes the next compartment may read, and whether the stretch is over
   * (or failed): on a cache line of their own, which the next compartment's
   * thread reads while this one works */
  _Alignas(64) atomic_size_t published;
  atomic_int done;
  /* this compartment's alone, written at every step: off the lines the
   * next one reads */
  _Alignas(64) size_t count; /* nodes written */
  int start_f_known;         /* the first node has its rates */
} node_list;

/* Stretches a compartment may run ahead of the next one, at most (its
 * records, and the full states waiting for their output, are kept in rings
 * this deep; shallower when the records of many large compartments would
 * take too much memory, gs_comp_steps.depth). */
#define RING 8
#define RING_BYTES ((size_t)16 << 20)

static double *node_at(const node_list *L, size_t j) {
  const size_t b = j / L->per;
  return L->dir[b / DIR_SIZE][b % DIR_SIZE] + (j % L->per) * L->stride;
}
/* a node: t, then z, n, f (nflow each) */
static double node_t(const node_list *L, size_t j) { return *node_at(L, j); }

struct worker;

/* A compartment: on pages of its own (GS_APART), since the threads
 * advancing neighbouring compartments write theirs at every step. */
typedef struct {
  _Alignas(GS_APART) struct gs_comp_steps *s;
  struct worker *w; /* the thread advancing it */
  size_t comp;
  int has_next; /* feeds the next compartment: integrates Z and keeps a record */
  size_t n;     /* local length */
  double *y, *scale;
  double t;            /* the integrator's time during an advance */
  double try_s, try_h; /* the step it tries */
  double *end_f;       /* rates at the end of the last stretch (has_next) */
  /* what its outflow removed in the last step, per number and carried
   * total (gs_ode.decayed; NULL without an outflow) */
  double *decayed;
  int end_f_valid;
  gs_integrator it;
  gs_ode ode;
  node_list rec[RING];  /* per stretch k, in rec[k % s->depth] */
  node_list *cur;       /* the record of the stretch being advanced */
  double sent[RING][GS_MAX_VOL]; /* what it discharged in a stretch */
  double t_rhs; /* seconds in its rates */
} comp_t;

/* One thread's model view and scratch. */
typedef struct worker {
  _Alignas(GS_APART) struct gs_comp_steps *s; /* threads write their own: pages apart */
  gs_eval ev; /* its evaluation: one compartment on its local vector, its slot */
  /* the step being tried by its compartment: Z_H and its first two
   * derivatives at both ends, and the inflow state P' */
  double try_s, try_h;
  double *p0, *p1, *d0, *d1, *s0, *s1, *halo;
  double at0, at1; /* the times p0, d0, s0 and p1, d1, s1 hold (NAN: none) */
  /* the inflow k P'(t) over the step tried as a quartic in (t - t0) / h
   * (gs_ode.forcing), GS_ODE_FORCING_TERMS x nflow; valid while fc_ok */
  double *fc;
  int fc_ok;
  size_t key;       /* task_key of its task */
  int stop;         /* its task comes after a failure: it stops */
  const node_list *up; /* the record of the compartment before, or NULL */
  size_t up_count;  /* nodes of up's record read for the step tried */
  /* the last evaluation's rates N' of numbers and totals (the integrator's
   * buffer, or nprime where the integrator sees them without the outflow) */
  const double *last_f;
  double *nprime;
  double last_t, stretch_t0; /* its time; the start of the stretch advanced */
  double *scratch, *ytmp; /* rates and a state outside the integrator */
  /* seconds: in the rates, waiting for the compartment before, with no
   * task to take, in tasks (all of it), passing stretches to done_fn */
  double t_rhs, t_wait, t_idle, t_busy, t_done;
  int bad, off_stretch;
  double bad_t;
  size_t bad_index;
} worker_t;

struct gs_comp_steps {
  gs_model *m;
  gs_eval base; /* the case's evaluation context (noise floor) */
  size_t ncomp, ncells, nflow; /* nflow: numbers and carried totals of one compartment */
  int nvol, dim, nq;
  size_t off_ledger, off_recv, off_z; /* in a compartment's local vector */
  double *k;                          /* transfer rate out of each compartment */
  comp_t *comp;
  worker_t *workers;
  int nworkers;
  int nworkers_made; /* the workers made (and freed): a rank's block may shrink below them and grow again */
  /* the run of gs_comp_steps_run in progress: its stretches and the full
   * states at their ends (RING of them, until written) */
  const gs_stretch *st;
  size_t nst;
  double *ring[RING];
  /* per ring slot, each compartment's integrator mark at the end of a
   * stretch that ends at an output time (gs_comp_steps_marks) */
  double *marks[RING];
  size_t depth; /* of the rings in use, 2 to RING */
  gs_stretch_done_fn done_fn;
  void *done_ctx;
  /* the schedule, under `lock`: per compartment the first stretch it has
   * not finished and whether a thread advances it; per ring slot the
   * compartments done with its stretch; the stretches passed to done_fn.
   * Every thread writes it: pages away from the fields above, which the
   * rates read at every evaluation */
  _Alignas(GS_APART) omp_lock_t lock;
  omp_lock_t out_lock;
  atomic_int outputs_ready; /* a stretch is complete and not yet passed to done_fn */
  size_t *next_k, outputs_done;
  int *running;
  /* each thread's block of compartments [home[w], home[w + 1]), split
   * (gs_dist_balanced_split, resplit) by the seconds each compartment's
   * tasks took lately, the thread that writes the outputs carrying their
   * seconds too: a thread keeps its compartments' data in its own cache, and
   * a compartment is followed, not waited for, by the next block's thread */
  size_t *home;
  double *cost, t_out;
  /* the split's figures: per compartment the seconds of its tasks, then
   * those of the outputs, each fading by RECENT_KEEP per stretch written,
   * so that the split follows the case's phases (the spray's onset, the
   * last compartments filling); then nworkers of scratch; and the thread
   * that writes the outputs between its tasks, chosen with the split */
  double *recent;
  size_t *home_try;
  int writer;
  size_t complete[RING];
  /* the earliest failure so far, as task_key(stretch, compartment) (ncomp
   * for done_fn), SIZE_MAX while none: tasks after it stop, tasks before it
   * go on (one of them may fail earlier), so the failure reported is the one
   * a single thread meets first, whatever the number of threads */
  atomic_size_t fail_key;
  int locks;        /* lock and out_lock initialised */
  int bad_rate;     /* the failure was a rate that was not finite, at: */
  double bad_t;
  size_t bad_index;
  /* the first failure (earliest stretch, then compartment; ncomp for
   * done_fn) */
  int fail_rc;
  size_t fail_k, fail_c;
  gs_error fail_err;
  double worst_coupling;
  gs_block_pool *pool; /* the records' blocks */
  /* Under MPI (compartment_ranks.h): this process advances compartments
   * [lo, hi) only; the record of lo - 1 arrives from the rank before
   * (which keeps next_k[lo - 1] and running[lo - 1] as a thread would), and
   * next_k[hi] counts the stretches whose record of hi - 1 has gone to the
   * rank after.  Without MPI: [0, ncomp) and ranks NULL. */
  size_t lo, hi;
  gs_comp_ranks *ranks;
};

static double now_seconds(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

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

/* Append a node (z NULL: zero; f NULL: filled in later). */
static int nodes_push(node_list *L, size_t nflow, double t, const double *z, const double *n,
                      const double *f) {
  const size_t b = L->count / L->per;
  if (L->count >= NODE_MAX) return GS_ENUMERIC;
  double ***page = &L->dir[b / DIR_SIZE];
  if (!*page) { /* a page of its own (GS_APART): the next compartment reads it */
    if (!(*page = aligned_alloc(GS_APART, (DIR_SIZE * sizeof(double *) + GS_APART - 1) / GS_APART * GS_APART)))
      return GS_ENOMEM;
    memset(*page, 0, DIR_SIZE * sizeof(double *));
  }
  double **block = &(*page)[b % DIR_SIZE];
  if (!*block && !(*block = gs_block_pool_get(L->pool))) return GS_ENOMEM;
  double *at = node_at(L, L->count);
  at[0] = t;
  if (z) memcpy(at + 1, z, nflow * sizeof(double));
  else memset(at + 1, 0, nflow * sizeof(double));
  memcpy(at + 1 + nflow, n, nflow * sizeof(double));
  if (f) memcpy(at + 1 + 2 * nflow, f, nflow * sizeof(double));
  L->count++;
  return GS_OK;
}

/* Z_H and its first two derivatives at t, from the first count nodes: node
 * values where t is a node (or outside them), else the quintic Hermite piece
 * through the two nodes around t (values, slopes and second derivatives at
 * both: as accurate as a fifth-order step). */
static void nodes_eval(const node_list *L, size_t count, size_t nflow, double t, double *z,
                       double *dz, double *d2z) {
  const size_t last = count - 1;
  size_t j = 0;
  if (t >= node_t(L, last)) j = last;
  else if (t > node_t(L, 0)) {
    size_t lo = 0, hi = last; /* t[lo] <= t < t[hi] */
    while (hi - lo > 1) {
      size_t mid = lo + (hi - lo) / 2;
      if (node_t(L, mid) <= t) lo = mid;
      else hi = mid;
    }
    j = lo;
    const double *a = node_at(L, lo), *b = node_at(L, lo + 1);
    if (t != a[0]) {
      const double H = b[0] - a[0], u = (t - a[0]) / H;
      double bs[3][6]; /* the basis and its first two derivatives in u */
      quintic_basis(u, bs);
      const double *za = a + 1, *na = za + nflow, *fa = na + nflow;
      const double *zb = b + 1, *nb = zb + nflow, *fb = nb + nflow;
      for (int k = 0; k < 3; k++) {
        /* d^k/dt^k = H^-k d^k/du^k; slopes carry H, second derivatives H^2 */
        const double sc = k == 0 ? 1.0 : k == 1 ? 1.0 / H : 1.0 / (H * H);
        const double c0 = sc * bs[k][0], c1 = sc * H * bs[k][1], c2 = sc * H * H * bs[k][2];
        const double c3 = sc * H * H * bs[k][3], c4 = sc * H * bs[k][4], c5 = sc * bs[k][5];
        double *out = k == 0 ? z : k == 1 ? dz : d2z;
        for (size_t i = 0; i < nflow; i++)
          out[i] = c0 * za[i] + c1 * na[i] + c2 * fa[i] + c3 * fb[i] + c4 * nb[i] + c5 * zb[i];
      }
      return;
    }
  }
  const double *at = node_at(L, j);
  memcpy(z, at + 1, nflow * sizeof(double));
  memcpy(dz, at + 1 + nflow, nflow * sizeof(double));
  memcpy(d2z, at + 1 + 2 * nflow, nflow * sizeof(double));
}

static size_t task_key(const struct gs_comp_steps *s, size_t k, size_t c) {
  return k * (s->ncomp + 1) + c;
}

/* A task after the earliest failure: it stops. */
static int stopped(const struct gs_comp_steps *s, size_t key) {
  return key > atomic_load_explicit(&s->fail_key, memory_order_acquire);
}

static void relax(unsigned spins) {
  if (spins > 1000) sched_yield(); /* more threads than free cores */
#if defined(__x86_64__) || defined(__i386__)
  else __builtin_ia32_pause();
#endif
}

/* A wait that may be long: for another MPI rank, whose messages come
 * every step of a compartment there (milliseconds), a rank sleeps after a
 * while instead of taking the core from the processes beside it. */
static void relax_long(const struct gs_comp_steps *s, unsigned spins) {
  if (s->ranks && spins > 4000) { /* naps of 50 us, then 250 us: each wake-up costs CPU */
    const struct timespec nap = {0, spins > 8000 ? 250000 : 50000};
    nanosleep(&nap, NULL);
  } else {
    relax(spins);
  }
}

/* Wait until the compartment before has published nodes up to t (or is
 * done); returns how many may be read, 0 when the task must stop (it comes
 * after a failure, or the compartment before ended short of t: it failed). */
static void outputs(struct gs_comp_steps *s, int wait);

static size_t wait_for(struct gs_comp_steps *s, const node_list *up, double t, size_t key) {
  for (unsigned spins = 0;; spins++) {
    if (stopped(s, key)) return 0;
    const size_t count = atomic_load_explicit(&up->published, memory_order_acquire);
    if (count && node_t(up, count - 1) >= t) return count;
    if (atomic_load_explicit(&up->done, memory_order_acquire)) {
      const size_t all = atomic_load_explicit(&up->published, memory_order_acquire);
      return all && node_t(up, all - 1) >= t ? all : 0;
    }
    /* rather than wait, write the stretches every compartment is done with */
    if (spins % 64 == 63 && (s->nworkers > 1 || s->ranks) && s->outputs_ready) outputs(s, 0);
    if (s->ranks && spins % 8 == 0) gs_comp_ranks_poll(s->ranks); /* the record may be in */
    relax_long(s, spins);
  }
}

/* The rate k of the compartment before cp (which feeds it). */
static double s_k_up(const comp_t *cp) { return cp->s->k[cp->comp - 1]; }

/* The inflow k P'(t) over the step tried, [t0, t0 + h], as the quartic sum_m
 * e_m theta^m, theta = (t - t0) / h, into w->fc: P is the quintic through
 * P, P', P'' at both ends (p, d, s), P(theta) = p0 + d0 h theta + s0 h^2
 * theta^2 / 2 + A theta^3 + B theta^4 + C theta^5.  The same curve as
 * inflow_state's, in the form gs_ode.forcing takes. */
static void inflow_curve(worker_t *w, double k) {
  const double h = w->try_h;
  const size_t nflow = w->s->nflow;
  double *e = w->fc;
  for (size_t i = 0; i < nflow; i++) {
    const double d0 = w->d0[i], s0 = w->s0[i];
    const double D0 = w->p1[i] - w->p0[i] - d0 * h - 0.5 * s0 * h * h;
    const double D1 = (w->d1[i] - d0 - s0 * h) * h, D2 = (w->s1[i] - s0) * h * h;
    const double A = 10 * D0 - 4 * D1 + 0.5 * D2, B = -15 * D0 + 7 * D1 - D2, C = 6 * D0 - 3 * D1 + 0.5 * D2;
    e[i] = k * d0;
    e[nflow + i] = k * s0 * h;
    e[2 * nflow + i] = k * 3 * A / h;
    e[3 * nflow + i] = k * 4 * B / h;
    e[4 * nflow + i] = k * 5 * C / h;
  }
  /* a step so short that the differences overflow: the frame does without
   * (it is only a change of variables; the rates still see the curve) */
  w->fc_ok = gs_all_finite(e, GS_ODE_FORCING_TERMS * nflow);
}

/* gs_ode.forcing: the inflow's curve over the step tried, if it has one. */
static const double *comp_forcing(void *ctx) {
  const comp_t *cp = ctx;
  return cp->w->fc_ok ? cp->w->fc : NULL;
}

/* gs_ode.trying: the step about to be tried; for a compartment fed by
 * another, Z_H and its derivatives at the step's ends (once the compartment
 * before has got that far). */
static void comp_trying(void *ctx, double t0, double h) {
  comp_t *cp = ctx;
  worker_t *w = cp->w;
  const size_t nflow = cp->s->nflow;
  cp->try_s = t0;
  cp->try_h = h;
  w->fc_ok = 0;
  if (stopped(cp->s, w->key)) w->stop = 1; /* comp_rhs fails */
  if (!cp->comp || w->stop) return;
  w->try_s = t0;
  w->try_h = h;
  const double wait_start = now_seconds();
  w->up_count = wait_for(cp->s, w->up, t0 + h, w->key);
  w->t_wait += now_seconds() - wait_start;
  if (!w->up_count) {
    w->stop = 1;
    return;
  }
  /* Z_H at a time, once the record reaches past it, never changes: a retry
   * keeps the start's values, and a step after an accepted one starts where
   * that one ended */
  if (t0 != w->at0 && t0 == w->at1) {
    double *tmp;
    tmp = w->p0, w->p0 = w->p1, w->p1 = tmp;
    tmp = w->d0, w->d0 = w->d1, w->d1 = tmp;
    tmp = w->s0, w->s0 = w->s1, w->s1 = tmp;
    w->at0 = t0;
    w->at1 = NAN;
  }
  if (t0 != w->at0) nodes_eval(w->up, w->up_count, nflow, t0, w->p0, w->d0, w->s0);
  nodes_eval(w->up, w->up_count, nflow, t0 + h, w->p1, w->d1, w->s1);
  w->at0 = t0;
  w->at1 = t0 + h;
  if (h > 0) inflow_curve(w, s_k_up(cp));
}

/* The upstream numbers and totals whose flow k P'(t) enters at t: P' of the
 * quintic Hermite P through Z_H's values and first two derivatives at the
 * ends of the step tried.  P' is a quartic: the weights of a Runge-Kutta
 * step of order >= 5 (rkf45, rkck, rk8pd) integrate it exactly, and only
 * its first term has a non-zero integral, (P1 - P0) / h.  0 when t lies
 * outside the step tried (an integrator that does not say which step it
 * tries). */
static int inflow_state(worker_t *w, double t) {
  const double h = w->try_h, th = h > 0 ? (t - w->try_s) / h : 0.0;
  /* stage times carry the round-off of t + c h: a few ulps of t, which a
   * short step late in a run makes a sizeable fraction of h */
  const double slack = 1e-9 + (h > 0 ? 8 * DBL_EPSILON * fabs(t) / h : 0.0);
  if (!(th >= -slack && th <= 1 + slack)) return 0;
  double b[3][6];
  quintic_basis(th, b);
  /* P' = (P1 - P0) b5' / h + D0 b1' + D1 b4' + h (S0 b2' + S1 b3'), b0' = -b5' */
  const double a = h > 0 ? b[1][5] / h : 0.0, c1 = b[1][1], c4 = b[1][4], c2 = h * b[1][2],
               c3 = h * b[1][3];
  const double *p0 = w->p0, *p1 = w->p1, *d0 = w->d0, *d1 = w->d1, *s0 = w->s0, *s1 = w->s1;
  double *q = w->halo;
  for (size_t i = 0; i < w->s->nflow; i++)
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

/* Publish the nodes written so far to the next compartment (the first only
 * once its rates are known). */
static void publish(node_list *L) {
  if (L->start_f_known) atomic_store_explicit(&L->published, L->count, memory_order_release);
}

/* The rates as the integrator takes them where the outflow -k N is stepped
 * on its own (gs_ode.ndecay): the numbers' and totals' without it (kept
 * first as N', the record's second derivatives), the ledger's exchanged
 * volumes without what leaves (booked after each step from what the step
 * removed, book_outflow), and Z' = 0 (Z is advanced by that too). */
static void without_outflow(comp_t *cp, const double *y, double *f) {
  struct gs_comp_steps *s = cp->s;
  worker_t *w = cp->w;
  const double k = cp->ode.decay;
  memcpy(w->nprime, f, s->nflow * sizeof(double));
  w->last_f = w->nprime;
  for (size_t i = 0; i < s->nflow; i++) f[i] += k * y[i];
  double vol[GS_MAX_VOL];
  volumes_of(s, y, vol);
  for (int a = 0; a < s->nvol; a++) f[s->off_ledger + (size_t)a] += k * vol[a];
  if (cp->has_next) memset(f + s->off_z, 0, s->nflow * sizeof(double));
}

/* After an accepted step where the outflow is stepped on its own: what it
 * removed (gs_ode.decayed, by the step's balance) leaves the ledger's
 * exchanged volumes, and Z, the integral of N whose k-multiple the next
 * compartment receives, grows by it / k, so that received = discharged
 * still telescopes to round-off. */
static void book_outflow(comp_t *cp) {
  struct gs_comp_steps *s = cp->s;
  const double *out = cp->decayed, k = cp->ode.decay;
  double vol[GS_MAX_VOL];
  volumes_of(s, out, vol);
  for (int a = 0; a < s->nvol; a++) cp->y[s->off_ledger + (size_t)a] -= vol[a];
  if (!cp->has_next) return;
  double *z = cp->y + s->off_z;
  for (size_t i = 0; i < s->nflow; i++) z[i] += out[i] / k;
}

static int comp_rhs(void *ctx, double t, const double *y, double *f) {
  comp_t *cp = ctx;
  worker_t *w = cp->w;
  struct gs_comp_steps *s = cp->s;
  const double start = now_seconds();
  if (w->stop) return 1; /* after a failure elsewhere */
  if (cp->comp && !inflow_state(w, t)) {
    w->off_stretch = 1;
    w->bad_t = t;
    return 1;
  }
  w->ev.in_integrator = 1;
  gs_model_rhs(s->m, &w->ev, t, y, f, f + s->off_ledger);
  w->ev.in_integrator = 0;
  double *recv = f + s->off_recv;
  if (cp->comp) {
    volumes_of(s, w->halo, recv);
    for (int a = 0; a < s->nvol; a++) recv[a] *= s->k[cp->comp - 1];
  } else {
    memset(recv, 0, (size_t)s->nvol * sizeof(double));
  }
  /* read at the step's end, before the integrator writes f again */
  w->last_f = f;
  w->last_t = t;
  if (cp->ode.ndecay) without_outflow(cp, y, f);
  else if (cp->has_next) memcpy(f + s->off_z, y, s->nflow * sizeof(double)); /* Z' = N */
  if (cp->has_next) {
    /* the first node's rates: the integrator's own evaluation at the start */
    node_list *L = cp->cur;
    if (!L->start_f_known && t == w->stretch_t0 && L->count == 1) {
      memcpy(node_at(L, 0) + 1 + 2 * s->nflow, w->last_f, s->nflow * sizeof(double));
      L->start_f_known = 1;
      publish(L);
    }
  }
  const double spent = now_seconds() - start;
  w->t_rhs += spent;
  cp->t_rhs += spent;
  if (gs_all_finite(f, cp->n)) return 0;
  for (size_t i = 0; i < cp->n; i++)
    if (!isfinite(f[i])) {
      w->bad = 1;
      w->bad_t = t;
      w->bad_index = full_index(s, cp->comp, i);
      break;
    }
  return 1;
}

/* The rates of compartment cp at (t, y) into its worker's last_f, outside
 * the integrator's own evaluations (rarely needed: see comp_step_done). */
static int extra_rates(comp_t *cp, double t, const double *y) {
  return comp_rhs(cp, t, y, cp->w->scratch);
}

/* The first node's rates, when the integrator did not evaluate them at the
 * stretch's start (GSL's evolve does after a reset and on its first step;
 * otherwise it reuses the last stretch's, end_f): evaluated here from the
 * node's numbers and totals, with the inflow at t0. */
static int start_rates(comp_t *cp, double t0) {
  struct gs_comp_steps *s = cp->s;
  worker_t *w = cp->w;
  double *y = w->ytmp, *node0 = node_at(cp->cur, 0);
  memset(y, 0, cp->n * sizeof(double));
  memcpy(y, node0 + 1 + s->nflow, s->nflow * sizeof(double));
  if (cp->comp) {
    w->try_s = t0;
    w->try_h = 0; /* the inflow is then Z_H'(t0) */
    w->up_count = wait_for(s, w->up, t0, w->key);
    if (!w->up_count) {
      w->stop = 1;
      return GS_ENUMERIC;
    }
    nodes_eval(w->up, w->up_count, s->nflow, t0, w->p0, w->d0, w->s0);
    w->at0 = t0;
    w->at1 = NAN;
  }
  if (extra_rates(cp, t0, y)) return GS_ENUMERIC;
  memcpy(node0 + 1 + 2 * s->nflow, w->last_f, s->nflow * sizeof(double));
  cp->cur->start_f_known = 1;
  return GS_OK;
}

/* gs_ode.between_steps: record the step end for the next compartment.  Its
 * rates are those of the integrator's last evaluation, at the end of the
 * accepted step (GSL's steppers evaluate the end-of-step derivative, which
 * the next step reuses); otherwise they are evaluated here. */
static int comp_step_done(void *ctx) {
  comp_t *cp = ctx;
  worker_t *w = cp->w;
  if (cp->ode.ndecay) book_outflow(cp);
  if (!cp->has_next) return 0;
  if (w->last_t != cp->try_s + cp->try_h && extra_rates(cp, cp->t, cp->y)) {
    w->bad = w->bad ? w->bad : 3;
    return 1;
  }
  int rc = nodes_push(cp->cur, cp->s->nflow, cp->t, cp->y + cp->s->off_z, cp->y, w->last_f);
  if (rc) {
    w->bad = rc == GS_ENOMEM ? 2 : 4;
    return 1;
  }
  publish(cp->cur);
  /* the last compartment of a rank's block: the step end goes to the next rank now */
  if (cp->s->ranks && cp->comp + 1 == cp->s->hi) gs_comp_ranks_poll(cp->s->ranks);
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

static int worker_init(struct gs_comp_steps *s, worker_t *w, gs_error *err) {
  w->s = s;
  double **bufs[] = {&w->p0, &w->p1, &w->d0, &w->d1, &w->s0, &w->s1, &w->halo, &w->nprime};
  for (size_t i = 0; i < sizeof bufs / sizeof *bufs; i++)
    if (!(*bufs[i] = gs_calloc_apart(s->nflow * sizeof(double), err))) return GS_ENOMEM;
  if (!(w->fc = gs_calloc_apart(GS_ODE_FORCING_TERMS * s->nflow * sizeof(double), err))) return GS_ENOMEM;
  if (!(w->scratch = gs_calloc_apart((s->off_z + s->nflow) * sizeof(double), err)) ||
      !(w->ytmp = gs_calloc_apart((s->off_z + s->nflow) * sizeof(double), err)))
    return GS_ENOMEM;
  return GS_OK;
}

int gs_comp_steps_create(gs_case *c, gs_comp_steps **out, gs_error *err) {
  gs_model *m = &c->model;
  *out = NULL;
  struct gs_comp_steps *s = gs_calloc_apart(sizeof *s, err); /* its schedule: pages of its own */
  if (!s) return GS_ENOMEM;
  s->m = m;
  s->base = c->eval;
  s->ncomp = m->grid.ncomp;
  s->lo = 0;
  s->hi = s->ncomp; /* all of them: one process */
  s->ncells = m->grid.ncells;
  s->nq = m->ncarried;
  s->nflow = s->ncells * (1 + (size_t)s->nq);
  s->nvol = m->nvol;
  s->dim = m->grid.dim;
  s->off_ledger = s->nflow;
  s->off_recv = s->off_ledger + 2 * (size_t)s->nvol;
  s->off_z = s->off_recv + (size_t)s->nvol;
  *out = s;
  /* threads: OpenMP's, at most one per compartment and per slot the
   * mechanisms keep scratch for */
  int nw = omp_get_max_threads();
  if (nw > m->nslots) nw = m->nslots;
  if ((size_t)nw > s->ncomp) nw = (int)s->ncomp;
  s->nworkers = s->nworkers_made = nw < 1 ? 1 : nw;
  s->k = gs_calloc(s->ncomp, sizeof(double), err);
  /* on pages of their own (GS_APART): threads write neighbouring
   * compartments and workers at every step, and the schedule at every task */
  s->comp = gs_calloc_apart(s->ncomp * sizeof(comp_t), err);
  s->workers = gs_calloc_apart((size_t)s->nworkers * sizeof(worker_t), err);
  if (!s->comp || !s->workers) return GS_ENOMEM;
  s->next_k = gs_calloc_apart(s->ncomp * sizeof(size_t), err);
  s->running = gs_calloc_apart(s->ncomp * sizeof(int), err);
  s->home = gs_calloc_apart(((size_t)s->nworkers + 1) * sizeof(size_t), err);
  s->cost = gs_calloc_apart(s->ncomp * sizeof(double), err);
  s->recent = gs_calloc_apart((s->ncomp + 1 + (size_t)s->nworkers) * sizeof(double), err);
  s->home_try = gs_calloc_apart(((size_t)s->nworkers + 1) * sizeof(size_t), err);
  if (!s->k || !s->comp || !s->workers || !s->next_k || !s->running || !s->home || !s->cost ||
      !s->recent || !s->home_try)
    return GS_ENOMEM;
  for (int r = 0; r <= s->nworkers; r++) s->home[r] = s->ncomp * (size_t)r / (size_t)s->nworkers;
  for (int r = 0; r < RING; r++)
    if (!(s->ring[r] = gs_calloc(c->ode.n, sizeof(double), err)) ||
        !(s->marks[r] = gs_calloc(s->ncomp * GS_INTEGRATOR_MARK, sizeof(double), err)))
      return GS_ENOMEM;
  omp_init_lock(&s->lock);
  omp_init_lock(&s->out_lock);
  s->locks = 1;
  for (int i = 0; i < s->nworkers; i++)
    if (worker_init(s, &s->workers[i], err)) return GS_ENOMEM;
  for (size_t comp = 0; comp < s->ncomp; comp++) s->k[comp] = gs_model_transfer_rate(m, comp);
  const size_t node_stride = gs_doubles_apart(1 + 3 * s->nflow), node_bytes = node_stride * sizeof(double);
  size_t per = NODE_BLOCK_BYTES / node_bytes;
  per = per < 1 ? 1 : per > 16 ? 16 : per;
  /* one thread takes the stretches in order and needs no lead: 2 slots
   * (more only cost cache); several run as deep as RING while a block of
   * records per compartment and ring slot stays within RING_BYTES, else 2.
   * A deep ring lets the first compartments bank a lead that the others
   * work off while the first are slow (the spray's onset), and absorbs a
   * vCPU that runs slower for a while */
  s->depth = s->nworkers > 1 ? RING : 2;
  const size_t slot_bytes = per * node_bytes > NODE_KEEP_BYTES ? per * node_bytes : NODE_KEEP_BYTES;
  while (s->depth > 2 && s->depth * (s->ncomp - 1) * slot_bytes > RING_BYTES) s->depth--;
  if (s->ncomp > 1 && !(s->pool = gs_block_pool_create(per * node_bytes, err))) return GS_ENOMEM;
  /* a block for each record of the rings, taken and touched now: otherwise
   * the first piece of a run pays for the fresh memory alone (costly where a
   * hypervisor backs freshly touched pages), the other threads waiting for
   * it */
  if (s->pool) {
    int rc = gs_block_pool_reserve(s->pool, s->depth * (s->ncomp - 1), err);
    if (rc) return rc;
  }
  for (size_t comp = 0; comp < s->ncomp; comp++) {
    comp_t *cp = &s->comp[comp];
    cp->s = s;
    cp->comp = comp;
    cp->has_next = comp + 1 < s->ncomp;
    cp->n = s->off_z + (cp->has_next ? s->nflow : 0);
    /* pages apart from the other compartments' (GS_APART); its integrator's
     * own vectors come after them, and before the next compartment's */
    cp->y = gs_calloc_apart(cp->n * sizeof(double), err);
    cp->scale = gs_calloc_apart(cp->n * sizeof(double), err); /* received and Z: no error control */
    cp->end_f = cp->has_next ? gs_calloc_apart(s->nflow * sizeof(double), err) : NULL;
    /* the outflow, which the integrator steps on its own (solver.outflow) */
    cp->decayed = s->k[comp] > 0 ? gs_calloc_apart(s->nflow * sizeof(double), err) : NULL;
    if (!cp->y || !cp->scale || (cp->has_next && !cp->end_f) || (s->k[comp] > 0 && !cp->decayed))
      return GS_ENOMEM;
    for (int r = 0; r < RING; r++) {
      node_list *L = &cp->rec[r];
      L->per = per;
      L->stride = node_stride;
      L->pool = s->pool;
      atomic_init(&L->published, 0);
      atomic_init(&L->done, 0);
    }
    pack(s, comp, c->abs_scale, cp->scale);
    cp->ode = (gs_ode){.n = cp->n,
                       .f = comp_rhs,
                       .ctx = cp,
                       .abs_scale = cp->scale,
                       .npositive = s->nflow,
                       .rates_checked = 1,
                       .between_steps = comp_step_done,
                       .trying = comp_trying,
                       .forcing = comp_forcing,
                       .ndecay = cp->decayed ? s->nflow : 0,
                       .decay = s->k[comp],
                       .decayed = cp->decayed};
    if (!c->integrator_setup.type->per_compartment)
      return gs_error_set(err, GS_EINPUT,
                          "solver.steps: per_compartment needs method rk (its coupling uses the "
                          "Runge-Kutta steps' exact quadrature), not %s",
                          c->integrator_setup.type->name);
    int rc = gs_integrator_create(&c->integrator_setup, &cp->ode, &cp->it, err);
    if (rc) return rc;
  }
  return GS_OK;
}

/* Worker w evaluates compartment comp alone, on its local vector. */
static void view_one(worker_t *w, size_t comp, const gs_stretch *st) {
  gs_eval *ev = &w->ev;
  *ev = w->s->base;
  ev->switch_lo = st->t0; /* windows decide once for the stretch (gs_window_on) */
  ev->switch_hi = st->t1;
  ev->era = st->era;
  ev->comp_lo = comp;
  ev->comp_hi = comp + 1;
  ev->view_lo = comp;
  ev->view_carried = w->s->ncells;
  ev->halo = comp ? w->halo : NULL;
  ev->slot = (int)(w - w->s->workers);
}

static int check_coupling(struct gs_comp_steps *s, const comp_t *cp, size_t k, gs_error *err);

/* Record a failure at stretch k, compartment c (c = ncomp: done_fn) by
 * worker w (NULL: done_fn); the earliest one is the run's. */
static void fail(struct gs_comp_steps *s, size_t k, size_t c, int rc, const gs_error *err,
                 const worker_t *w) {
  omp_set_lock(&s->lock);
  const size_t key = task_key(s, k, c);
  if (!s->fail_rc || key < task_key(s, s->fail_k, s->fail_c)) { /* this process's earliest */
    s->fail_rc = rc;
    s->fail_err = *err;
    s->fail_k = k;
    s->fail_c = c;
    /* a rate that was not finite: where, for the run's message */
    s->bad_rate = w && w->bad == 1;
    if (s->bad_rate) {
      s->bad_t = w->bad_t;
      s->bad_index = w->bad_index;
    }
  }
  /* under MPI another rank's failure may have come earlier */
  if (key < atomic_load(&s->fail_key)) atomic_store_explicit(&s->fail_key, key, memory_order_release);
  omp_unset_lock(&s->lock);
}

/* Give a record's blocks back to the pool. */
static void release_blocks(node_list *L) {
  for (size_t b = 0; L->dir[b / DIR_SIZE] && L->dir[b / DIR_SIZE][b % DIR_SIZE]; b++) {
    gs_block_pool_put(L->pool, L->dir[b / DIR_SIZE][b % DIR_SIZE]);
    L->dir[b / DIR_SIZE][b % DIR_SIZE] = NULL;
  }
}

/* Advance compartment comp over stretch k on worker w: from its state at
 * the end of stretch k - 1 (Y for the first), into the ring's full state of
 * stretch k.  Returns 0, or 1 when it failed because another did. */
static int run_compartment(struct gs_comp_steps *s, worker_t *w, size_t comp, size_t k, const double *Y) {
  comp_t *cp = &s->comp[comp];
  const gs_stretch *st = &s->st[k];
  const double t0 = st->t0, stop = st->t1;
  gs_error errbuf, *err = &errbuf;
  node_list *L = &cp->rec[k % s->depth];
  cp->w = w;
  w->key = task_key(s, k, comp);
  w->stop = 0;
  cp->cur = L;
  w->up = comp ? &s->comp[comp - 1].rec[k % s->depth] : NULL;
  w->up_count = 0;
  w->at0 = w->at1 = NAN; /* a new record */
  w->bad = 0;
  w->off_stretch = 0;
  w->stretch_t0 = t0;
  w->last_t = NAN;
  if (k == 0) pack(s, comp, Y, cp->y);
  memset(cp->y + s->off_recv, 0, (cp->n - s->off_recv) * sizeof(double)); /* received, Z */
  cp->t = t0;
  release_blocks(L); /* those the next compartment did not give back (it failed) */
  L->count = 0;
  L->start_f_known = 0; /* published and done were reset when the task was taken */
  int rc = GS_OK;
  if (cp->has_next) {
    rc = nodes_push(L, s->nflow, t0, NULL, cp->y, NULL);
    if (rc) rc = gs_error_set(err, GS_ENOMEM, "out of memory for the per-compartment step record");
    /* without a jump the integrator starts from the rates it ended the last
     * stretch with, and evaluates none at t0 */
    if (!rc && !st->jumped && cp->end_f_valid) {
      memcpy(node_at(L, 0) + 1 + 2 * s->nflow, cp->end_f, s->nflow * sizeof(double));
      L->start_f_known = 1;
      publish(L);
    }
  }
  cp->ode.jumped = st->jumped;
  view_one(w, comp, st);
  if (!rc) {
    rc = cp->it.type->advance(cp->it.self, &cp->ode, &cp->t, stop, cp->y, err);
    if (rc && !w->stop && !w->off_stretch && w->bad != 1) { /* say which compartment */
      char msg[sizeof err->msg];
      snprintf(msg, sizeof msg, "%s", err->msg);
      gs_error_set(err, rc, "compartment %zu: %s", comp + 1, msg);
    }
  }
  if (!rc && cp->has_next && !L->start_f_known && start_rates(cp, t0))
    rc = gs_error_set(err, GS_ENUMERIC, "per-compartment steps: compartment %zu: rates at t = %.9g failed", comp + 1, t0);
  if (!rc && w->bad == 2) rc = gs_error_set(err, GS_ENOMEM, "out of memory for the per-compartment step record");
  if (!rc && w->bad == 4)
    rc = gs_error_set(err, GS_ENUMERIC, "per-compartment steps: compartment %zu took more than %d steps between t = %.9g and %.9g", comp + 1, NODE_MAX, t0, stop);
  if (!rc && w->bad) /* 1 or 3: rates evaluated at a step's end were not finite */
    rc = gs_error_set(err, GS_ENUMERIC, "integrator rk: right-hand side failed at t = %.9g", w->bad_t);
  if (!rc && cp->t != stop)
    rc = gs_error_set(err, GS_ENUMERIC, "per-compartment steps: compartment %zu stopped at t = %.17g short of %.17g", comp + 1, cp->t, stop);
  if (rc && w->off_stretch)
    rc = gs_error_set(err, GS_ENUMERIC,
                      "per-compartment steps: compartment %zu evaluated at t = %.17g outside "
                      "the step its integrator announced [%.17g, %.17g]",
                      comp + 1, w->bad_t, w->try_s, w->try_s + w->try_h);
  int aborted = 0;
  if (rc) {
    /* a task stopped for a failure elsewhere did not fail on its own */
    aborted = w->stop;
    if (!aborted) fail(s, k, comp, rc, err, w);
  } else {
    unpack(s, comp, cp->y, s->ring[k % s->depth]);
    /* at an output time, what a run resumed there keeps: the integrator's
     * mark, not the rates at the stretch's end (end_f) */
    if (st->mark) cp->it.type->mark(cp->it.self, s->marks[k % s->depth] + comp * GS_INTEGRATOR_MARK);
    if (cp->has_next) {
      memcpy(cp->end_f, node_at(L, L->count - 1) + 1 + 2 * s->nflow, s->nflow * sizeof(double));
      cp->end_f_valid = !st->mark;
      double *sent = cp->sent[k % s->depth];
      volumes_of(s, cp->y + s->off_z, sent);
      for (int a = 0; a < s->nvol; a++) sent[a] *= s->k[comp];
      atomic_store_explicit(&L->published, L->count, memory_order_release);
    }
    if (comp) { /* once the one before has booked what it discharged */
      const node_list *up = w->up;
      for (unsigned spins = 0; !atomic_load_explicit(&up->done, memory_order_acquire) && !stopped(s, w->key); spins++) {
        if (s->ranks && spins % 8 == 0) gs_comp_ranks_poll(s->ranks); /* its end may be in */
        relax_long(s, spins);
      }
      if (stopped(s, w->key)) {
        aborted = 1; /* the one before may still be writing its record */
      } else {
        if ((rc = check_coupling(s, cp, k, err))) fail(s, k, comp, rc, err, w);
        /* read to the end, and the one before is done with it: its blocks
         * serve the records still to be written (the one before writes this
         * slot again only after this task has ended, pick_task) */
        release_blocks(&s->comp[comp - 1].rec[k % s->depth]);
      }
    }
  }
  atomic_store_explicit(&L->done, 1, memory_order_release);
  if (s->ranks && comp + 1 == s->hi) gs_comp_ranks_poll(s->ranks); /* its end to the next rank */
  return aborted;
}

/* What compartment cp received in stretch k against what the one before
 * discharged; the run stops when they differ beyond round-off. */
static int check_coupling(struct gs_comp_steps *s, const comp_t *cp, size_t k, gs_error *err) {
  const double *recv = cp->y + s->off_recv, *sent = s->comp[cp->comp - 1].sent[k % s->depth];
  double worst = 0;
  for (int a = 0; a < s->nvol; a++) {
    const double big = fmax(fabs(recv[a]), fabs(sent[a]));
    const double rel = big > 0 ? fabs(recv[a] - sent[a]) / big : 0.0;
    if (rel > worst) worst = rel;
    if (!(rel <= 1e-10))
      return gs_error_set(err, GS_ENUMERIC,
                          "per-compartment steps: from t = %.9g to %.9g compartment %zu received "
                          "%.17g of %s where compartment %zu discharged %.17g (relative %.3g); the "
                          "coupling lost volume",
                          s->st[k].t0, s->st[k].t1, cp->comp + 1, recv[a],
                          gs_model_vol_name(s->m, a), cp->comp, sent[a], rel);
  }
  omp_set_lock(&s->lock);
  if (worst > s->worst_coupling) s->worst_coupling = worst;
  omp_unset_lock(&s->lock);
  return GS_OK;
}

/* Under s->lock: the task thread wi takes, as a compartment whose next
 * stretch may start now, or -1; *finished: nothing is left to take.  In
 * order of preference, the oldest stretch first within each: a task of its
 * own block whose compartment before is done with that stretch (it will not
 * wait); such a task of another block (its thread is behind: the spray's
 * onset makes the first compartments costly for a while); a task of its own
 * block that follows the compartment before through a stretch it is still
 * advancing. */
static long pick_task(struct gs_comp_steps *s, int wi, int *finished) {
  long best = -1;
  int best_rank = 4;
  *finished = 1;
  for (size_t c = s->lo; c < s->hi; c++) {
    const size_t k = s->next_k[c];
    /* left: a task not after the earliest failure, or one running (which may
     * make the next of its compartment available) */
    const int left = k < s->nst && !stopped(s, task_key(s, k, c));
    if (left || s->running[c]) *finished = 0;
    if (!left || s->running[c]) continue;
    /* the one before has started this stretch (its record is being written) */
    const int up_done = !c || s->next_k[c - 1] > k;
    if (!up_done && !(s->running[c - 1] && s->next_k[c - 1] == k)) continue;
    /* the next one has read this ring slot's record, and its full state was written */
    if (c + 1 < s->ncomp && k >= s->next_k[c + 1] + s->depth) continue;
    if (k >= s->outputs_done + s->depth) continue;
    const int own = c >= s->home[wi] && c < s->home[wi + 1];
    const int rank = up_done ? (own ? 1 : 2) : own ? 3 : 4;
    if (rank == 4) continue;
    if (rank < best_rank || (rank == best_rank && k < s->next_k[best])) {
      best = (long)c;
      best_rank = rank;
    }
  }
  return best;
}

/* Under s->lock, after an output: the blocks of the threads, and which of
 * them writes the outputs, from the recent seconds (the outputs' in the
 * writer's block: the choice that leaves the largest block the smallest). */
#define RECENT_KEEP 0.9
static void resplit(struct gs_comp_steps *s) {
  double *extra = s->recent + s->ncomp + 1, best = INFINITY;
  for (int wr = 0; wr < s->nworkers; wr++) {
    memset(extra, 0, (size_t)s->nworkers * sizeof(double));
    extra[wr] = s->recent[s->ncomp];
    const double worst = gs_dist_balanced_split(s->recent + s->lo, s->hi - s->lo, extra, s->nworkers, s->home_try);
    if (worst < best) {
      best = worst;
      s->writer = wr;
      for (int r = 0; r <= s->nworkers; r++) s->home[r] = s->lo + s->home_try[r];
    }
  }
  for (size_t i = 0; i <= s->ncomp; i++) s->recent[i] *= RECENT_KEEP;
}

/* The stretch of the earliest failure so far (none: beyond any stretch). */
static size_t fail_stretch(const struct gs_comp_steps *s) {
  return atomic_load_explicit(&s->fail_key, memory_order_acquire) / (s->ncomp + 1);
}

/* Stretches every compartment is done with go to done_fn, in order, one
 * thread at a time; without wait, nothing when another thread is at it (it
 * writes what is ready before it stops). */
static void outputs(struct gs_comp_steps *s, int wait) {
  if (wait) omp_set_lock(&s->out_lock);
  else if (!omp_test_lock(&s->out_lock)) return;
  for (;;) {
    omp_set_lock(&s->lock);
    const size_t k = s->outputs_done;
    /* every compartment done with it, and before the earliest failure (a
     * stretch every compartment is done with ends before it) */
    const int ready = k < s->nst && s->complete[k % s->depth] == s->hi - s->lo && k < fail_stretch(s);
    if (!ready) atomic_store(&s->outputs_ready, 0);
    omp_unset_lock(&s->lock);
    if (!ready) break;
    /* under MPI rank 0 needs the other ranks' blocks of an output time */
    if (s->ranks && !gs_comp_ranks_output_ready(s->ranks, k)) break;
    gs_error err = {0};
    const double start = now_seconds();
    worker_t *me = &s->workers[omp_get_thread_num() < s->nworkers ? omp_get_thread_num() : 0];
    int rc = s->ranks ? gs_comp_ranks_output(s->ranks, k, s->ring[k % s->depth], s->marks[k % s->depth], &err)
                      : GS_OK;
    if (!rc && s->done_fn) rc = s->done_fn(s->done_ctx, k, s->st[k].t1, s->ring[k % s->depth], &err);
    if (rc) {
      fail(s, k, s->ncomp, rc, &err, NULL);
      break;
    }
    omp_set_lock(&s->lock);
    s->complete[k % s->depth] = 0;
    s->outputs_done++;
    s->t_out += now_seconds() - start;
    me->t_done += now_seconds() - start;
    s->recent[s->ncomp] += now_seconds() - start;
    if (s->nworkers > 1) resplit(s);
    omp_unset_lock(&s->lock);
  }
  omp_unset_lock(&s->out_lock);
}

/* Stretches not yet passed to done_fn that will be (none after a failure). */
static int outputs_left(struct gs_comp_steps *s) {
  omp_set_lock(&s->lock);
  const size_t end = s->nst < fail_stretch(s) ? s->nst : fail_stretch(s);
  const int left = s->outputs_done < end;
  omp_unset_lock(&s->lock);
  return left;
}

/* One thread: take tasks until none is left (after a failure: none before
 * it). */
static void work(struct gs_comp_steps *s, worker_t *w, const double *Y) {
  for (unsigned idle = 0;;) {
    int finished = 0;
    omp_set_lock(&s->lock);
    const long c = pick_task(s, (int)(w - s->workers), &finished);
    const size_t k = c >= 0 ? s->next_k[c] : 0;
    if (c >= 0) {
      s->running[c] = 1;
      /* before another thread may follow it: nothing of this stretch's
       * record is published yet (the slot held stretch k - depth's) */
      node_list *L = &s->comp[c].rec[k % s->depth];
      atomic_store_explicit(&L->published, 0, memory_order_relaxed);
      atomic_store_explicit(&L->done, 0, memory_order_relaxed);
    }
    omp_unset_lock(&s->lock);
    if (c < 0) {
      if (finished) { /* the last stretches' outputs */
        outputs(s, 1);
        /* under MPI they may wait for the other ranks' blocks */
        if (!s->ranks || (!outputs_left(s) && gs_comp_ranks_flushed(s->ranks))) break;
      }
      if (s->ranks) gs_comp_ranks_poll(s->ranks);
      /* a free thread writes the stretches every compartment is done with */
      outputs(s, 0);
      const double t_idle0 = now_seconds();
      if (s->ranks) relax_long(s, idle * 50); /* waiting for another rank's record, or a thread's task */
      else
        for (int i = 0; i < 50; i++) relax(idle); /* waiting for another thread's task */
      idle++;
      w->t_idle += now_seconds() - t_idle0;
      continue;
    }
    idle = 0;
    const double start = now_seconds(), waited = w->t_wait;
    run_compartment(s, w, (size_t)c, k, Y);
    const double spent = now_seconds() - start - (w->t_wait - waited);
    w->t_busy += now_seconds() - start;
    omp_set_lock(&s->lock);
    s->cost[c] += spent;
    s->recent[c] += spent;
    s->running[c] = 0;
    s->next_k[c]++;
    const int all = ++s->complete[k % s->depth] == s->hi - s->lo; /* this rank's block */
    if (all) atomic_store(&s->outputs_ready, 1);
    const int writes = (int)(w - s->workers) == s->writer;
    omp_unset_lock(&s->lock);
    /* One thread writes the outputs between its tasks, the one chosen with
     * the split: the outputs are work the split counts in its block
     * (resplit), which balances the blocks with fewer compartments taken
     * from another thread's block (each such move carries the compartment's
     * data to another core), and their own data (the output file's buffers,
     * HDF5's) stays in one core's cache.  As soon as
     * complete: outputs written late hold the ring's slots, and a burst of
     * them had stalled the first compartments.  Any thread without a task
     * writes them too (above, and wait_for). */
    if (s->nworkers == 1 ? all : writes && atomic_load(&s->outputs_ready)) outputs(s, s->nworkers == 1);
    if (s->ranks) gs_comp_ranks_poll(s->ranks);
  }
}

int gs_comp_steps_run(gs_comp_steps *s, const gs_stretch *st, size_t nst, double *Y,
                      gs_stretch_done_fn done, void *ctx, gs_error *err) {
  if (!nst) return GS_OK;
  s->st = st;
  s->nst = nst;
  s->done_fn = done;
  s->done_ctx = ctx;
  memset(s->next_k, 0, s->ncomp * sizeof(size_t));
  memset(s->running, 0, s->ncomp * sizeof(int));
  memset(s->complete, 0, sizeof s->complete);
  s->outputs_done = 0;
  atomic_store(&s->outputs_ready, 0);
  s->fail_rc = 0;
  s->bad_rate = 0;
  atomic_store(&s->fail_key, SIZE_MAX);
  if (s->ranks) gs_comp_ranks_start(s->ranks);
  /* Threads take (compartment, stretch) tasks: a compartment runs ahead of
   * the next one by up to RING stretches, and follows the one before through
   * a stretch they share, waiting only when it would step past the last
   * step end published (wait_for).  A task starts only once the one before
   * has started that stretch, so the furthest upstream of the running tasks
   * never waits, and the waits end. */
  const size_t tasks = nst * (s->hi - s->lo);
  const int nw = (size_t)s->nworkers < tasks ? s->nworkers : (int)tasks;
  if (nw > 1) {
#pragma omp parallel num_threads(nw)
    work(s, &s->workers[omp_get_thread_num()], Y);
  } else {
    work(s, &s->workers[0], Y);
  }
  /* under MPI: the messages left, and the earliest failure of all ranks */
  if (s->ranks) {
    size_t key = s->fail_rc ? task_key(s, s->fail_k, s->fail_c) : SIZE_MAX;
    gs_comp_ranks_failure fl = {s->fail_rc, s->bad_rate, s->bad_t, s->bad_index, s->fail_err};
    gs_comp_ranks_finish(s->ranks, &key, &fl);
    s->fail_rc = fl.rc;
    s->bad_rate = fl.bad_rate;
    s->bad_t = fl.bad_t;
    s->bad_index = fl.bad_index;
    s->fail_err = fl.err;
  }
  if (s->fail_rc) {
    *err = s->fail_err;
    return s->fail_rc;
  }
  memcpy(Y, s->ring[(nst - 1) % s->depth], (s->m->nstate + s->m->nledger) * sizeof(double));
  return GS_OK;
}

int gs_comp_steps_advance(gs_comp_steps *s, double *t, double stop, double *Y, int jumped,
                          gs_error *err) {
  if (!(stop > *t)) return GS_OK;
  const gs_stretch one = {*t, stop, jumped, 0, 0};
  int rc = gs_comp_steps_run(s, &one, 1, Y, NULL, NULL, err);
  if (!rc) *t = stop;
  return rc;
}

const double *gs_comp_steps_marks(const gs_comp_steps *s, size_t k) {
  return s->marks[k % s->depth];
}

void gs_comp_steps_resume_comps(gs_comp_steps *s, const double *marks, size_t lo, size_t hi) {
  for (size_t comp = lo; comp < hi; comp++) {
    comp_t *cp = &s->comp[comp];
    cp->it.type->resume(cp->it.self, marks + comp * GS_INTEGRATOR_MARK);
  }
}

void gs_comp_steps_resume(gs_comp_steps *s, const double *marks) { gs_comp_steps_resume_comps(s, marks, 0, s->ncomp); }

double gs_comp_steps_output_seconds(const gs_comp_steps *s) { return s->t_out; }

void gs_comp_steps_comp_stats(const gs_comp_steps *s, size_t comp, gs_integrator_stats *st) {
  const comp_t *cp = &s->comp[comp];
  cp->it.type->get_stats(cp->it.self, st);
}

void gs_comp_steps_comp_seconds(const gs_comp_steps *s, size_t comp, double *rates, double *tasks) {
  *rates = s->comp[comp].t_rhs;
  *tasks = s->cost[comp];
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

int gs_comp_steps_threads(const gs_comp_steps *s) { return s->nworkers; }

double gs_comp_steps_rhs_seconds(const gs_comp_steps *s) {
  double sum = 0;
  for (int i = 0; i < s->nworkers_made; i++) sum += s->workers[i].t_rhs;
  return sum / s->nworkers_made;
}

int gs_comp_steps_bad_rate(const gs_comp_steps *s, double *t, size_t *full) {
  if (!s->bad_rate) return 0;
  *t = s->bad_t;
  *full = s->bad_index;
  return 1;
}

double gs_comp_steps_worst_coupling(const gs_comp_steps *s) { return s->worst_coupling; }

void gs_comp_steps_free(gs_comp_steps *s) {
  if (!s) return;
  for (size_t comp = 0; s->comp && comp < s->ncomp; comp++) {
    comp_t *cp = &s->comp[comp];
    if (cp->it.type) gs_integrator_free(&cp->it);
    free(cp->y);
    free(cp->scale);
    free(cp->end_f);
    free(cp->decayed);
    for (int r = 0; r < RING; r++) {
      node_list *L = &cp->rec[r];
      for (size_t p = 0; p < DIR_PAGES && L->dir[p]; p++) free(L->dir[p]); /* blocks: the pool's */
    }
  }
  for (int i = 0; s->workers && i < s->nworkers_made; i++) {
    worker_t *w = &s->workers[i];
    double *bufs[] = {w->p0, w->p1, w->d0, w->d1, w->s0, w->s1, w->halo, w->nprime, w->scratch, w->ytmp, w->fc};
    for (size_t j = 0; j < sizeof bufs / sizeof *bufs; j++) free(bufs[j]);
  }
  free(s->workers);
  for (int r = 0; r < RING; r++) {
    free(s->ring[r]);
    free(s->marks[r]);
  }
  free(s->next_k);
  free(s->running);
  free(s->home);
  free(s->cost);
  free(s->recent);
  free(s->home_try);
  if (s->locks) {
    omp_destroy_lock(&s->lock);
    omp_destroy_lock(&s->out_lock);
  }
  free(s->k);
  free(s->comp);
  gs_block_pool_free(s->pool);
  free(s);
}

double gs_comp_steps_wait_seconds(const gs_comp_steps *s) {
  double sum = 0;
  for (int i = 0; i < s->nworkers_made; i++) sum += s->workers[i].t_wait;
  return sum;
}

void gs_comp_steps_print_threads(const gs_comp_steps *s, FILE *f) {
  for (int i = 0; i < s->nworkers_made; i++) {
    const worker_t *w = &s->workers[i];
    fprintf(f, "  thread %d: compartments %.4f s (rates %.4f, waiting for the one before %.4f), "
               "outputs %.4f, without a task %.4f\n",
            i, w->t_busy, w->t_rhs, w->t_wait, w->t_done, w->t_idle);
  }
}

/* What the transport between MPI ranks reads and writes (compartment_ranks.h). */

void gs_comp_steps_set_block(gs_comp_steps *s, size_t lo, size_t hi, gs_comp_ranks *r, int threads) {
  s->lo = lo;
  s->hi = hi;
  s->ranks = r;
  /* rings as deep as for several threads: the ranks before and after run
   * ahead and behind by stretches (rank 0 only as far as its outputs, which
   * wait for the last rank) */
  const size_t node_bytes = s->comp[0].rec[0].stride * sizeof(double), per = s->comp[0].rec[0].per;
  const size_t slot_bytes = per * node_bytes > NODE_KEEP_BYTES ? per * node_bytes : NODE_KEEP_BYTES;
  s->depth = RING;
  while (s->depth > 2 && s->depth * (s->ncomp - 1) * slot_bytes > RING_BYTES) s->depth--;
  s->nworkers = threads ? s->nworkers_made : 1;
  if ((size_t)s->nworkers > hi - lo) s->nworkers = (int)(hi - lo);
  for (int w = 0; w <= s->nworkers; w++) s->home[w] = lo + (hi - lo) * (size_t)w / (size_t)s->nworkers;
  s->writer = 0;
}

size_t gs_comp_steps_node_len(const gs_comp_steps *s) { return 1 + 3 * s->nflow; }

const gs_stretch *gs_comp_steps_stretch(const gs_comp_steps *s, size_t k) {
  return k < s->nst ? &s->st[k] : NULL;
}

void gs_comp_steps_slot(gs_comp_steps *s, size_t k, double **Y, double **marks) {
  *Y = s->ring[k % s->depth];
  *marks = s->marks[k % s->depth];
}

int gs_comp_steps_up_begin(gs_comp_steps *s, size_t k) {
  const size_t c = s->lo - 1;
  node_list *L = &s->comp[c].rec[k % s->depth];
  omp_set_lock(&s->lock);
  /* the compartment after is done with what the slot held */
  const int free_slot = k == s->next_k[c] && k < s->next_k[s->lo] + s->depth;
  if (free_slot) {
    release_blocks(L); /* those a stopped task did not give back */
    L->count = 0;
    L->start_f_known = 1; /* the nodes come with their rates */
    atomic_store_explicit(&L->published, 0, memory_order_relaxed);
    atomic_store_explicit(&L->done, 0, memory_order_relaxed);
    s->running[c] = 1;
  }
  omp_unset_lock(&s->lock);
  return free_slot;
}

int gs_comp_steps_up_nodes(gs_comp_steps *s, size_t k, const double *nodes, size_t count) {
  node_list *L = &s->comp[s->lo - 1].rec[k % s->depth];
  const size_t nflow = s->nflow, len = 1 + 3 * nflow;
  for (size_t j = 0; j < count; j++) {
    const double *at = nodes + j * len;
    int rc = nodes_push(L, nflow, at[0], at + 1, at + 1 + nflow, at + 1 + 2 * nflow);
    if (rc) return rc;
  }
  publish(L);
  return GS_OK;
}

void gs_comp_steps_up_end(gs_comp_steps *s, size_t k, const double *sent, size_t fail_key) {
  const size_t c = s->lo - 1;
  node_list *L = &s->comp[c].rec[k % s->depth];
  memcpy(s->comp[c].sent[k % s->depth], sent, (size_t)s->nvol * sizeof(double));
  /* a failure there comes first: the compartment after sees it before the end */
  if (fail_key != SIZE_MAX) gs_comp_steps_remote_failure(s, fail_key);
  atomic_store_explicit(&L->done, 1, memory_order_release);
  omp_set_lock(&s->lock);
  s->running[c] = 0;
  s->next_k[c]++;
  omp_unset_lock(&s->lock);
}

void gs_comp_steps_remote_failure(gs_comp_steps *s, size_t key) {
  omp_set_lock(&s->lock);
  if (key < atomic_load(&s->fail_key)) atomic_store_explicit(&s->fail_key, key, memory_order_release);
  omp_unset_lock(&s->lock);
}

size_t gs_comp_steps_failure_key(gs_comp_steps *s) {
  omp_set_lock(&s->lock);
  const size_t key = s->fail_rc ? task_key(s, s->fail_k, s->fail_c) : SIZE_MAX;
  omp_unset_lock(&s->lock);
  return key;
}

size_t gs_comp_steps_known_failure(const gs_comp_steps *s) {
  return atomic_load_explicit(&s->fail_key, memory_order_acquire);
}

int gs_comp_steps_down_peek(gs_comp_steps *s, size_t *k, size_t *published, int *done) {
  const size_t c = s->hi - 1;
  omp_set_lock(&s->lock);
  *k = s->next_k[s->hi];
  const int begun = *k < s->nst && (s->next_k[c] > *k || (s->next_k[c] == *k && s->running[c]));
  omp_unset_lock(&s->lock);
  if (!begun) return 0;
  const node_list *L = &s->comp[c].rec[*k % s->depth];
  /* done first: once it is set, published is final */
  *done = atomic_load_explicit(&L->done, memory_order_acquire);
  *published = atomic_load_explicit(&L->published, memory_order_acquire);
  return 1;
}

const double *gs_comp_steps_down_node(const gs_comp_steps *s, size_t k, size_t j) {
  return node_at(&s->comp[s->hi - 1].rec[k % s->depth], j);
}

const double *gs_comp_steps_down_sent(const gs_comp_steps *s, size_t k) {
  return s->comp[s->hi - 1].sent[k % s->depth];
}

void gs_comp_steps_down_gone(gs_comp_steps *s, size_t k) {
  omp_set_lock(&s->lock);
  s->next_k[s->hi] = k + 1; /* its ring slot may take another stretch */
  omp_unset_lock(&s->lock);
}
