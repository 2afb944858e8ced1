/* Compartments distributed over MPI ranks (the parallel scheme of Sampat et al. (2018),
 * without its master bottleneck): each rank owns a contiguous block of
 * compartments, integrates only its own part of the state (its numbers,
 * carried volumes, ledger and mechanisms' scalars: four contiguous segments
 * of the full state vector, packed into one local vector) and evaluates only their rates;
 * before each right-hand side the last compartment of every block goes to
 * the next rank (the inflow of transfer); the integrators agree on every
 * step with all-reduces (max); the full state is assembled on rank 0 only,
 * at output times, without the other ranks waiting for it.  Without MPI (or outside mpirun, or on one rank)
 * one block holds everything. */
#ifndef GRANSIM_DISTRIBUTED_H
#define GRANSIM_DISTRIBUTED_H

#include "gransim/error.h"
#include "gransim/pbm.h"

/* Segments of a rank's packed vector: numbers, carried volumes, ledger, scalars. */
#define GS_DIST_NSEG 4

typedef struct {
  int rank, size;
  const gs_model *m;
  size_t *lo;     /* size + 1: rank r owns compartments [lo[r], lo[r + 1]) */
  size_t off[GS_DIST_NSEG]; /* this rank's segments of the full vector: numbers, */
  size_t len[GS_DIST_NSEG]; /* carried volumes, ledger, mechanisms' scalars */
  size_t nlocal;            /* their sum */
  /* the boundary exchange: one compartment's numbers and carried totals,
   * sent from a ring of GS_DIST_NSEND buffers without waiting (see
   * gs_dist_sync) */
  double *sendbuf, *recvbuf;
  void *requests; /* MPI_Request[GS_DIST_NSEND] under MPI */
  int next_send;
  /* output times: a rank's block on its way to rank 0 (see gs_dist_collect),
   * and the all-reduce of gs_dist_max_lagged in flight */
  double *statebuf;
  void *state_request, *lagged_request;
  double lagged_in, lagged_out;
  int lagged_pending;
  void *sum_request; /* gs_dist_sum_post's all-reduce in flight, if sum_pending */
  int sum_pending;
  void *split_work; /* gs_dist_best_split's, allocated once */
} gs_dist;

/* Boundary messages a rank may have in flight: a rank with cheaper
 * compartments runs ahead by up to a step's evaluations (rkf45: 6 stages). */
#define GS_DIST_NSEND 16

/* Split the compartments of m evenly over the ranks (this rank's block:
 * [lo[rank], lo[rank + 1])); one_process: this process alone holds them all,
 * as without MPI. */
int gs_dist_init(gs_dist *d, const gs_model *m, int one_process, gs_error *err);
/* Another split: rank r owns [lo[r], lo[r + 1]) (size + 1 entries). */
void gs_dist_resplit(gs_dist *d, const size_t *lo);
/* The contiguous split of n compartments of the given costs over nr <= n
 * ranks (lo: nr + 1 entries) that makes the largest block cheapest, block r
 * costing extra[r] (work of that rank alone, such as rank 0's outputs) plus
 * its compartments, each rank with at least one compartment; returns that
 * largest block's cost. */
double gs_dist_balanced_split(const double *cost, size_t n, const double *extra, int nr,
                              size_t *lo);
/* The speed-up that nr ranks could reach at most for a run measured on one
 * rank, when each compartment's work stays with the rank that owns it: the
 * run took `total` seconds, `rates` of them in the compartments' rates (of
 * which cost[j], n entries, were measured for compartment j, the rest is
 * shared evenly), `integrator` in the integrator's own vector work (shared
 * evenly: it grows with the block) and `serial` after the last step (the
 * final write, which no rank can share).  The ranks own contiguous blocks,
 * split at best for these costs (gs_dist_balanced_split); everything else
 * (outputs, checks) is taken to fit wherever a rank has time, and messages
 * and waits to cost nothing:
 *   total / (max(largest block, (total - serial) / nr) + serial).
 * *largest gets that block's seconds.  NAN (and *largest NAN) when nr < 1,
 * nr > n or total <= 0. */
double gs_dist_speedup_bound(const double *cost, size_t n, double rates, double integrator,
                             double serial, double total, int nr, double *largest);
/* The same for this distribution's ranks, with no allocation (so every
 * rank computes the same split from the same costs); extra may be NULL. */
double gs_dist_best_split(gs_dist *d, const double *cost, const double *extra, size_t *lo);
void gs_dist_free(gs_dist *d);
/* This rank's parts of a full vector <-> the packed local vector. */
void gs_dist_pack(const gs_dist *d, const double *full, double *local);
void gs_dist_unpack(const gs_dist *d, const double *local, double *full);
/* Index in the full vector of entry i of the local vector. */
size_t gs_dist_full_index(const gs_dist *d, size_t i);
/* Send the last compartment of this block in the packed local vector y
 * (numbers and carried totals) to the next
 * rank without waiting for it to arrive; receive the compartment before the
 * block from the previous rank and return it (numbers, then carried: the
 * model's halo), NULL on rank 0 or without MPI. */
const double *gs_dist_sync(gs_dist *d, const double *y);
/* Maximum of v over the ranks (v itself on one rank). */
double gs_dist_max(gs_dist *d, double v);
/* The same, calling work(ctx) for as long as the other ranks have not all
 * contributed yet and it returns 1 (it may be NULL).  Every rank must use
 * this one or gs_dist_max at the same call: MPI matches a non-blocking
 * collective only with non-blocking ones. */
double gs_dist_max_while(gs_dist *d, double v, int (*work)(void *), void *ctx);
/* Rank 0 receives every other rank's block of the full vector y (numbers,
 * carried, ledger) into y; the others send theirs without waiting for it to
 * arrive (their y is current only in their own block). */
void gs_dist_collect(gs_dist *d, double *y);
/* A maximum over the ranks that nobody waits for: posts v and returns the
 * maximum posted at the previous call (0 at the first), which every rank has
 * long contributed by then. */
double gs_dist_max_lagged(gs_dist *d, double v);
/* The maximum of the last gs_dist_max_lagged still in flight (0 if none). */
double gs_dist_max_lagged_finish(gs_dist *d);
/* A sum over the ranks of v[0..n), in place, that nobody waits for: v must
 * stay untouched until gs_dist_sum_finish, which completes it (at once if
 * none is in flight; one at a time). */
void gs_dist_sum_post(gs_dist *d, double *v, size_t n);
void gs_dist_sum_finish(gs_dist *d);
#endif
