/* See distributed.h.  Compiled with MPI when GRANSIM_HAVE_MPI is defined
 * (cmake -DGRANSIM_MPI=ON); otherwise one process owns every compartment. */
#include "run/distributed.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/mpi_errors.h"
#include "gransim/parallel.h"

#ifdef GRANSIM_HAVE_MPI
#include <mpi.h>
#endif

static void *split_work_alloc(size_t n, int nr);

int gs_dist_init(gs_dist *d, const gs_model *m, int one_process, gs_error *err) {
  memset(d, 0, sizeof *d);
  d->rank = one_process ? 0 : gs_parallel_rank();
  d->size = one_process ? 1 : gs_parallel_size();
  d->m = m;
  const size_t ncomp = m->grid.ncomp;
  if ((size_t)d->size > ncomp)
    return gs_error_set(err, GS_EINPUT, "%d MPI ranks for %zu compartments: use at most one rank per compartment",
                        d->size, ncomp);
  d->lo = gs_malloc(((size_t)d->size + 1) * sizeof(size_t), err);
  if (d->size > 1) { /* the boundary exchange's buffers */
    const size_t comp_len = (1 + (size_t)m->ncarried) * m->grid.ncells;
    d->sendbuf = gs_malloc(GS_DIST_NSEND * comp_len * sizeof(double), err);
    d->recvbuf = gs_malloc(comp_len * sizeof(double), err);
    /* a block of any split fits: the whole state */
    d->statebuf = gs_malloc((m->nstate + m->nledger) * sizeof(double), err);
#ifdef GRANSIM_HAVE_MPI
    MPI_Request *req = gs_malloc((GS_DIST_NSEND + 3) * sizeof(MPI_Request), err);
    for (int i = 0; req && i < GS_DIST_NSEND + 3; i++) req[i] = MPI_REQUEST_NULL;
    d->requests = req;
    if (req) {
      d->state_request = req + GS_DIST_NSEND;
      d->lagged_request = req + GS_DIST_NSEND + 1;
      d->sum_request = req + GS_DIST_NSEND + 2;
    }
#endif
  }
  d->split_work = split_work_alloc(ncomp, d->size);
  if (!d->split_work) gs_error_set(err, GS_ENOMEM, "out of memory");
  if (!d->lo || !d->split_work ||
      (d->size > 1 && (!d->sendbuf || !d->recvbuf || !d->statebuf || !d->requests))) {
    gs_dist_free(d);
    return GS_ENOMEM;
  }
  for (int r = 0; r <= d->size; r++) d->lo[r] = ncomp * (size_t)r / (size_t)d->size; /* contiguous, even */
  gs_dist_resplit(d, d->lo);
  return GS_OK;
}

/* The runs of the full vector that compartments [lo, hi) hold: per compartment
 * ncells numbers, ncarried * ncells carried, 2 nvol ledger and nscalar
 * mechanisms' scalars (a fluid bed's balances, each compartment's own, so a
 * block carries its compartments' and the ranks need no reduction).  Returns
 * their total length. */
static size_t segments(const gs_model *m, size_t lo, size_t hi, size_t off[GS_DIST_NSEG],
                       size_t len[GS_DIST_NSEG]) {
  const size_t unit[GS_DIST_NSEG] = {m->grid.ncells, (size_t)m->ncarried * m->grid.ncells, 2 * (size_t)m->nvol,
                                     m->nscalar};
  const size_t base[GS_DIST_NSEG] = {0, m->nnum, m->nstate, m->scalar_at};
  size_t total = 0;
  for (int s = 0; s < GS_DIST_NSEG; s++) {
    off[s] = base[s] + lo * unit[s];
    len[s] = (hi - lo) * unit[s];
    total += len[s];
  }
  return total;
}

void gs_dist_resplit(gs_dist *d, const size_t *lo) {
  if (lo != d->lo) memcpy(d->lo, lo, ((size_t)d->size + 1) * sizeof *lo);
  d->nlocal = segments(d->m, d->lo[d->rank], d->lo[d->rank + 1], d->off, d->len);
}

/* Prefix sums P[0..n] of the costs. */
static void prefix_sums(const double *cost, size_t n, double *P) {
  P[0] = 0;
  for (size_t j = 0; j < n; j++) P[j + 1] = P[j] + cost[j];
}

/* reach[r * (n + 1) + j] = 1 when the first j compartments can go to ranks
 * 0..r, each taking at least one, rank q's block costing extra[q] plus its
 * compartments, none above T.  Rank r's block [k, j) fits when k >= the
 * smallest k with P[j] - P[k] + extra[r] <= T, which grows with j; a count of
 * the reachable ends of the ranks before makes each test O(1): O(nr n) in
 * all.  Returns 1 when all n compartments reach the last rank. */
static int reachable(const double *P, size_t n, const double *extra, int nr, double T,
                     unsigned char *reach, size_t *count) {
  const size_t w = n + 1;
  memset(reach, 0, (size_t)nr * w);
  for (int r = 0; r < nr; r++) {
    /* count[k + 1] = reachable ends among 0..k of the ranks before r (for
     * r = 0: only the empty start, 0) */
    count[0] = 0;
    for (size_t k = 0; k <= n; k++)
      count[k + 1] = count[k] + (r ? reach[(size_t)(r - 1) * w + k] : k == 0);
    size_t lb = 0;
    for (size_t j = 1; j <= n; j++) {
      while (lb < j && P[j] - P[lb] + extra[r] > T) lb++;
      /* a start k in [lb, j - 1] reachable before */
      if (lb < j && count[j] > count[lb]) reach[(size_t)r * w + j] = 1;
    }
  }
  return reach[(size_t)(nr - 1) * w + n];
}

/* Workspace of a split of n compartments over nr ranks: prefix sums P
 * (n + 1), counts (n + 2), reachable ends (nr (n + 1)) in one block. */
typedef struct {
  double *P;
  size_t *count;
  unsigned char *reach;
} split_work;

static void *split_work_alloc(size_t n, int nr) {
  const size_t head = sizeof(split_work), p = (n + 1) * sizeof(double), c = (n + 2) * sizeof(size_t);
  split_work *w = malloc(head + p + c + (size_t)(nr > 0 ? nr : 1) * (n + 1));
  if (!w) return NULL;
  w->P = (double *)(w + 1); /* head is a multiple of 8 */
  w->count = (size_t *)((char *)w->P + p);
  w->reach = (unsigned char *)((char *)w->count + c);
  return w;
}

static double split_with(split_work *ws, const double *cost, size_t n, const double *extra,
                         int nr, size_t *lo);

double gs_dist_balanced_split(const double *cost, size_t n, const double *extra, int nr,
                              size_t *lo) {
  split_work *w = nr >= 1 && (size_t)nr <= n ? split_work_alloc(n, nr) : NULL;
  if (!w) { /* keep an even split */
    for (int r = 0; r <= nr; r++) lo[r] = n * (size_t)r / (size_t)(nr > 0 ? nr : 1);
    return INFINITY;
  }
  double worst = split_with(w, cost, n, extra, nr, lo);
  free(w);
  return worst;
}

double gs_dist_speedup_bound(const double *cost, size_t n, double rates, double integrator,
                             double serial, double total, int nr, double *largest) {
  *largest = NAN;
  if (nr < 1 || (size_t)nr > n || !(total > 0)) return NAN;
  double measured = 0;
  for (size_t j = 0; j < n; j++) measured += cost[j];
  /* what the compartments' own clocks did not see (zeroing the rates, the
   * calls around the model) counts as the same for each, as does the
   * integrator's work */
  const double even = (fmax(0.0, rates - measured) + fmax(0.0, integrator)) / (double)n;
  double *c = malloc(n * sizeof *c), *none = calloc((size_t)nr, sizeof *none);
  size_t *lo = malloc(((size_t)nr + 1) * sizeof *lo);
  if (c && none && lo) {
    for (size_t j = 0; j < n; j++) c[j] = cost[j] + even;
    *largest = gs_dist_balanced_split(c, n, none, nr, lo);
  }
  free(c);
  free(none);
  free(lo);
  if (!isfinite(*largest)) {
    *largest = NAN;
    return NAN;
  }
  serial = fmax(0.0, serial);
  return total / (fmax(*largest, (total - serial) / nr) + serial);
}

double gs_dist_best_split(gs_dist *d, const double *cost, const double *extra, size_t *lo) {
  double none[d->size];
  if (!extra) {
    memset(none, 0, sizeof none);
    extra = none;
  }
  return split_with(d->split_work, cost, d->m->grid.ncomp, extra, d->size, lo);
}

/* Bisection on the largest block's cost with an exact feasibility test,
 * then the split read back from the reachable ends. */
static double split_with(split_work *ws, const double *cost, size_t n, const double *extra,
                         int nr, size_t *lo) {
  double *P = ws->P;
  size_t *count = ws->count;
  unsigned char *reach = ws->reach;
  prefix_sums(cost, n, P);
  double low = 0, hi = P[n];
  for (int r = 0; r < nr; r++) hi = fmax(hi, P[n] + extra[r]);
  for (int it = 0; it < 200 && hi - low > 1e-12 * hi; it++) {
    double mid = 0.5 * (low + hi);
    if (reachable(P, n, extra, nr, mid, reach, count)) hi = mid;
    else low = mid;
  }
  reachable(P, n, extra, nr, hi, reach, count);
  /* back from the end: rank r's block [k, j) with k reachable by rank r - 1 */
  const size_t w = n + 1;
  size_t j = n;
  double worst = 0;
  lo[nr] = n;
  for (int r = nr - 1; r >= 0; r--) {
    size_t k = j - 1;
    if (r == 0) k = 0;
    else
      while (k > 0 && !(reach[(size_t)(r - 1) * w + k] && P[j] - P[k] + extra[r] <= hi)) k--;
    worst = fmax(worst, P[j] - P[k] + extra[r]);
    lo[r] = k;
    j = k;
  }
  return worst;
}

void gs_dist_pack(const gs_dist *d, const double *full, double *local) {
  for (int s = 0; s < GS_DIST_NSEG; s++) {
    memcpy(local, full + d->off[s], d->len[s] * sizeof(double));
    local += d->len[s];
  }
}

void gs_dist_unpack(const gs_dist *d, const double *local, double *full) {
  for (int s = 0; s < GS_DIST_NSEG; s++) {
    memcpy(full + d->off[s], local, d->len[s] * sizeof(double));
    local += d->len[s];
  }
}

size_t gs_dist_full_index(const gs_dist *d, size_t i) {
  int s = 0;
  while (s < GS_DIST_NSEG - 1 && i >= d->len[s]) i -= d->len[s++];
  return d->off[s] + i;
}

void gs_dist_free(gs_dist *d) {
#ifdef GRANSIM_HAVE_MPI
  /* the last messages are received by now or soon: every evaluation on one
   * rank has its counterpart on the next */
  if (d->requests) {
    gs_dist_max_lagged_finish(d);
    gs_dist_sum_finish(d);
    gs_mpi_doing("the last boundary messages of the run (MPI_Waitall)");
    MPI_Waitall(GS_DIST_NSEND + 1, d->requests, MPI_STATUSES_IGNORE);
  }
#endif
  free(d->split_work);
  d->split_work = NULL;
  free(d->requests);
  d->requests = d->state_request = d->lagged_request = NULL;
  free(d->lo);
  free(d->sendbuf);
  free(d->recvbuf);
  free(d->statebuf);
  d->lo = NULL;
  d->sendbuf = d->recvbuf = d->statebuf = NULL;
}

#ifdef GRANSIM_HAVE_MPI
/* Numbers and carried totals of compartment comp are separate runs of the
 * rank's packed vector yl: they travel as one message (fewer messages). */
static void pack_comp(const gs_dist *d, const double *yl, size_t comp, double *buf) {
  const gs_model *m = d->m;
  const size_t n = m->grid.ncells, nq = (size_t)m->ncarried * n, at = comp - d->lo[d->rank];
  memcpy(buf, yl + at * n, n * sizeof(double));
  if (nq) memcpy(buf + n, yl + d->len[0] + at * nq, nq * sizeof(double));
}

/* The send does not wait for the message to arrive: Open MPI's blocking
 * send of a message above 256 bytes returns only once the receiver has taken
 * it, which made a rank with cheaper compartments wait at every evaluation
 * instead of running ahead to
 * the step's agreement, where rank 0 can use the time for output work.
 * Messages are matched in order, and the ring's slot is reused only once
 * its earlier send is complete. */
static const double *exchange(gs_dist *d, const double *y, size_t send_comp, int to, int from) {
  const gs_model *m = d->m;
  const size_t len = (1 + (size_t)m->ncarried) * m->grid.ncells;
  gs_mpi_doing("the boundary exchange between neighbouring ranks (MPI_Isend, MPI_Recv)");
  if (to != MPI_PROC_NULL) {
    MPI_Request *req = (MPI_Request *)d->requests + d->next_send;
    double *buf = d->sendbuf + (size_t)d->next_send * len;
    MPI_Wait(req, MPI_STATUS_IGNORE);
    pack_comp(d, y, send_comp, buf);
    MPI_Isend(buf, (int)len, MPI_DOUBLE, to, 0, MPI_COMM_WORLD, req);
    d->next_send = (d->next_send + 1) % GS_DIST_NSEND;
  }
  if (from == MPI_PROC_NULL) return NULL;
  MPI_Recv(d->recvbuf, (int)len, MPI_DOUBLE, from, 0, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
  return d->recvbuf;
}
#endif

const double *gs_dist_sync(gs_dist *d, const double *y) {
#ifdef GRANSIM_HAVE_MPI
  if (d->size < 2) return NULL;
  const int r = d->rank;
  int to = r + 1 < d->size ? r + 1 : MPI_PROC_NULL, from = r > 0 ? r - 1 : MPI_PROC_NULL;
  return exchange(d, y, d->lo[r + 1] - 1, to, from);
#else
  (void)d;
  (void)y;
  return NULL;
#endif
}

double gs_dist_max(gs_dist *d, double v) { return d->size > 1 ? gs_parallel_max(v) : v; }

double gs_dist_max_while(gs_dist *d, double v, int (*work)(void *), void *ctx) {
#ifdef GRANSIM_HAVE_MPI
  if (d->size < 2) return v;
  /* a non-blocking all-reduce progresses only inside MPI calls: test
   * between pieces, so that a rank late for the others delays them by at
   * most one piece */
  double in = v, out = v;
  MPI_Request req;
  gs_mpi_doing("the step agreement over ranks (MPI_Iallreduce)");
  MPI_Iallreduce(&in, &out, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD, &req);
  int done = 0;
  if (work) MPI_Test(&req, &done, MPI_STATUS_IGNORE);
  while (!done && work && work(ctx)) MPI_Test(&req, &done, MPI_STATUS_IGNORE);
  if (!done) MPI_Wait(&req, MPI_STATUS_IGNORE);
  return out;
#else
  (void)d;
  (void)work;
  (void)ctx;
  return v;
#endif
}

#ifdef GRANSIM_HAVE_MPI
#endif

void gs_dist_collect(gs_dist *d, double *y) {
#ifdef GRANSIM_HAVE_MPI
  if (d->size < 2) return;
  enum { TAG_STATE = 1 }; /* the boundary exchange uses tag 0 */
  gs_mpi_doing("gathering the state on rank 0 for output (MPI_Isend, MPI_Recv)");
  if (d->rank) {
    /* the last output time's block has long arrived: rank 0 received it
     * before this rank could pass that time's step agreements */
    MPI_Wait(d->state_request, MPI_STATUS_IGNORE);
    gs_dist_pack(d, y, d->statebuf);
    MPI_Isend(d->statebuf, (int)d->nlocal, MPI_DOUBLE, 0, TAG_STATE, MPI_COMM_WORLD, d->state_request);
    return;
  }
  for (int r = 1; r < d->size; r++) {
    size_t off[GS_DIST_NSEG], len[GS_DIST_NSEG];
    const size_t total = segments(d->m, d->lo[r], d->lo[r + 1], off, len);
    MPI_Recv(d->statebuf, (int)total, MPI_DOUBLE, r, TAG_STATE, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
    const double *b = d->statebuf;
    for (int s = 0; s < GS_DIST_NSEG; s++) {
      memcpy(y + off[s], b, len[s] * sizeof(double));
      b += len[s];
    }
  }
#else
  (void)d;
  (void)y;
#endif
}

double gs_dist_max_lagged(gs_dist *d, double v) {
  double previous = gs_dist_max_lagged_finish(d);
#ifdef GRANSIM_HAVE_MPI
  if (d->size > 1) {
    d->lagged_in = v;
    gs_mpi_doing("the lagged maximum over ranks (MPI_Iallreduce)");
    MPI_Iallreduce(&d->lagged_in, &d->lagged_out, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD,
                   d->lagged_request);
    d->lagged_pending = 1;
  }
#else
  (void)v;
#endif
  return previous;
}

double gs_dist_max_lagged_finish(gs_dist *d) {
  if (!d->lagged_pending) return 0;
#ifdef GRANSIM_HAVE_MPI
  gs_mpi_doing("the lagged maximum over ranks (MPI_Wait)");
  MPI_Wait(d->lagged_request, MPI_STATUS_IGNORE);
#endif
  d->lagged_pending = 0;
  return d->lagged_out;
}

void gs_dist_sum_post(gs_dist *d, double *v, size_t n) {
  gs_dist_sum_finish(d);
#ifdef GRANSIM_HAVE_MPI
  if (d->size > 1) {
    gs_mpi_doing("the sum over ranks (MPI_Iallreduce)");
    MPI_Iallreduce(MPI_IN_PLACE, v, (int)n, MPI_DOUBLE, MPI_SUM, MPI_COMM_WORLD, d->sum_request);
    d->sum_pending = 1;
  }
#else
  (void)v;
  (void)n;
#endif
}

void gs_dist_sum_finish(gs_dist *d) {
  if (!d->sum_pending) return;
#ifdef GRANSIM_HAVE_MPI
  gs_mpi_doing("the sum over ranks (MPI_Wait)");
  MPI_Wait(d->sum_request, MPI_STATUS_IGNORE);
#endif
  d->sum_pending = 0;
}
