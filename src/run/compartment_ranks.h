/* Per-compartment steps on several MPI ranks: the transport between them.
 *
 * Each rank advances a contiguous block [lo, hi) of the compartments with
 * its threads, as one process does all of them (compartment_steps.h).  The
 * only coupling between blocks is the record of step ends (t, Z, N, f)
 * that the last compartment of a block publishes for the next: the rank
 * sends every step end as it is published (a message per step, and one at
 * the stretch's end with what the compartment discharged), without waiting
 * for it to arrive, and the next rank files the nodes into the record of
 * its compartment lo - 1, where its first compartment follows them as it
 * follows a thread's (wait_for): it waits only when a step would end past
 * the last step end received.  The records are copied bit for bit, so every
 * compartment takes the steps one process takes, and the results are the
 * same whatever the ranks and threads.
 *
 * At an output time every other rank sends its block of the state and of
 * the integrators' marks to rank 0, which files them into the stretch's
 * full state before the observers see it.  A failure (a step, the
 * coupling check, an observer) goes to every rank at once, so that each
 * stops the tasks after it; at the end the ranks agree on the earliest
 * (stretch, then compartment), whose rank's message every rank returns.
 *
 * MPI is called by one thread at a time (MPI_THREAD_SERIALIZED: whichever
 * thread polls); where the library gives less, a rank runs one thread. */
#ifndef GRANSIM_RUN_COMPARTMENT_RANKS_H
#define GRANSIM_RUN_COMPARTMENT_RANKS_H

#include "gransim/error.h"
#include "gransim/pbm.h"
#include "run/compartment_steps.h"
#include "run/distributed.h"

typedef struct gs_comp_ranks gs_comp_ranks;

/* A failure as the ranks agree on it. */
typedef struct {
  int rc, bad_rate; /* bad_rate: a rate that was not finite, at bad_t, full index bad_index */
  double bad_t;
  size_t bad_index;
  gs_error err;
} gs_comp_ranks_failure;

/* The transport for s on the ranks of d (d->size > 1; its blocks d->lo):
 * s then advances this rank's block only.  Collective. */
int gs_comp_ranks_create(gs_comp_steps *s, const gs_model *m, const gs_dist *d, gs_comp_ranks **out,
                         gs_error *err);
/* Between runs of gs_comp_steps_run: rank r now advances [lo[r], lo[r + 1])
 * (size + 1 entries, the same on every rank). */
void gs_comp_ranks_resplit(gs_comp_ranks *r, const size_t *lo);
/* At the start of gs_comp_steps_run. */
void gs_comp_ranks_start(gs_comp_ranks *r);
/* Send what is ready, file what has arrived; returns at once when another
 * thread is at it. */
void gs_comp_ranks_poll(gs_comp_ranks *r);
/* After poll: 1 when nothing is left to send (a rank's threads stop only
 * then: the next rank may be waiting for it). */
int gs_comp_ranks_flushed(gs_comp_ranks *r);
/* 1 when stretch k can go to the observers: on rank 0 every block of an
 * output time has arrived (filed into the stretch's state and marks); on
 * the others at once. */
int gs_comp_ranks_output_ready(gs_comp_ranks *r, size_t k);
/* Stretch k is complete (Y, marks: its state and marks): the ranks other
 * than 0 send their block of an output time to rank 0. */
int gs_comp_ranks_output(gs_comp_ranks *r, size_t k, const double *Y, const double *marks, gs_error *err);
/* After the threads: the messages still under way, then the earliest
 * failure of all ranks (*key: this rank's, task_key order; SIZE_MAX for
 * none; f: its failure), into *key and *f on every rank.  Collective. */
void gs_comp_ranks_finish(gs_comp_ranks *r, size_t *key, gs_comp_ranks_failure *f);
void gs_comp_ranks_free(gs_comp_ranks *r);

/* What compartment_steps.c gives the transport. */
/* This process advances [lo, hi) (threads 0: one thread). */
void gs_comp_steps_set_block(gs_comp_steps *s, size_t lo, size_t hi, gs_comp_ranks *r, int threads);
/* Doubles of a record's node: t, then Z, N and f of a compartment. */
size_t gs_comp_steps_node_len(const gs_comp_steps *s);
/* Stretch k of the run in progress (NULL past the last). */
const gs_stretch *gs_comp_steps_stretch(const gs_comp_steps *s, size_t k);
/* The full state and the marks that stretch k ends with. */
void gs_comp_steps_slot(gs_comp_steps *s, size_t k, double **Y, double **marks);
/* The record of compartment lo - 1 (another rank's) for stretch k: begin
 * it (0: not yet, the compartment after still reads the one its ring slot
 * holds), add count nodes (node_len doubles each), end it with the volumes
 * that compartment discharged and the earliest failure known there. */
int gs_comp_steps_up_begin(gs_comp_steps *s, size_t k);
int gs_comp_steps_up_nodes(gs_comp_steps *s, size_t k, const double *nodes, size_t count);
void gs_comp_steps_up_end(gs_comp_steps *s, size_t k, const double *sent, size_t fail_key);
/* Another rank failed at key: the tasks after it stop. */
void gs_comp_steps_remote_failure(gs_comp_steps *s, size_t key);
/* This process's own earliest failure (SIZE_MAX: none), and the earliest
 * known of all. */
size_t gs_comp_steps_failure_key(gs_comp_steps *s);
size_t gs_comp_steps_known_failure(const gs_comp_steps *s);
/* The record of compartment hi - 1 that goes to the next rank: the stretch
 * *k next to go and, when its task has begun (else 0), the nodes published
 * and whether it is done; a node, the volumes discharged; gone: all of
 * stretch k went, its ring slot may be reused. */
int gs_comp_steps_down_peek(gs_comp_steps *s, size_t *k, size_t *published, int *done);
const double *gs_comp_steps_down_node(const gs_comp_steps *s, size_t k, size_t j);
const double *gs_comp_steps_down_sent(const gs_comp_steps *s, size_t k);
void gs_comp_steps_down_gone(gs_comp_steps *s, size_t k);

#endif
