/* See compartment_ranks.h.  Compiled with MPI when GRANSIM_HAVE_MPI is
 * defined; otherwise one process holds every compartment and nothing here
 * is used. */
#include "run/compartment_ranks.h"

#include <limits.h>
#include <omp.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "gransim/integrator.h"

#ifdef GRANSIM_HAVE_MPI
#include <mpi.h>

/* Message kinds (tags): a record's nodes (to the next rank), a block of an
 * output time (to rank 0), a failure (to every rank). */
enum { TAG_RECORD, TAG_OUTPUT, TAG_FAILURE, NTAG };
/* A record message: its stretch, the nodes it carries, whether the stretch
 * is done (then the volumes discharged follow the nodes), the earliest
 * failure known to the sender (-1: none); then the nodes. */
#define HEADER 4

typedef struct {
  MPI_Request req;
  double *buf;
} send_t;

struct gs_comp_ranks {
  gs_comp_steps *s;
  const gs_model *m;
  MPI_Comm comm; /* its own: no message of the driver's can match these */
  int has_comm;
  int rank, size;
  int serialized; /* any thread may call MPI, one at a time */
  size_t ncomp, lo, hi, *blo; /* blo: every rank's first compartment (size + 1) */
  size_t ncells, nqc, nl, node_len; /* per compartment: numbers, carried, ledger; a node */
  omp_lock_t lock; /* MPI calls and everything below */
  send_t *q;       /* sends in flight, each with its own buffer */
  size_t nq, capq;
  long *sent, *got; /* per rank and tag: messages sent to it, received from it */
  size_t down_from; /* nodes of the stretch going to the next rank sent so far */
  double *stage;    /* a message received from the rank before, not yet filed */
  size_t stage_cap;
  int staged, up_begun; /* up_begun: its stretch's record was begun */
  size_t *out_got;      /* rank 0: per rank, 1 + the last stretch whose block arrived */
  double *out_buf;
  size_t out_cap;
  size_t failure_sent; /* the earliest failure sent to the others */
  size_t own_key;      /* a failure of the transport itself (out of memory), its message: */
  gs_error own_err;
};

static size_t key_of(const gs_comp_ranks *r, size_t k, size_t c) { return k * (r->ncomp + 1) + c; }

static double *grow(double **buf, size_t *cap, size_t n) {
  if (n > *cap) {
    double *b = realloc(*buf, n * sizeof(double));
    if (!b) return NULL;
    *buf = b;
    *cap = n;
  }
  return *buf;
}

/* A failure of the transport on this rank, at stretch k, compartment c. */
static void own_failure(gs_comp_ranks *r, size_t k, size_t c, const char *what) {
  const size_t key = key_of(r, k, c);
  if (key >= r->own_key) return;
  r->own_key = key;
  gs_error_set(&r->own_err, GS_ENOMEM, "per-compartment steps on MPI rank %d: out of memory for %s",
               r->rank, what);
  gs_comp_steps_remote_failure(r->s, key); /* the tasks after it stop */
}

/* Send n doubles of buf (malloc'ed; freed once sent) without waiting. */
static void send(gs_comp_ranks *r, int dest, int tag, double *buf, size_t n) {
  if (r->nq == r->capq) {
    const size_t cap = r->capq ? 2 * r->capq : 16;
    send_t *q = realloc(r->q, cap * sizeof *q);
    if (!q) { /* no room to keep it in flight: this one goes blocking */
      MPI_Send(buf, (int)n, MPI_DOUBLE, dest, tag, r->comm);
      free(buf);
      r->sent[dest * NTAG + tag]++;
      return;
    }
    r->q = q;
    r->capq = cap;
  }
  send_t *e = &r->q[r->nq++];
  e->buf = buf;
  MPI_Isend(buf, (int)n, MPI_DOUBLE, dest, tag, r->comm, &e->req);
  r->sent[dest * NTAG + tag]++;
}

/* Free the buffers of the sends that arrived. */
static void reap(gs_comp_ranks *r) {
  for (size_t i = 0; i < r->nq;) {
    int done = 0;
    MPI_Test(&r->q[i].req, &done, MPI_STATUS_IGNORE);
    if (!done) {
      i++;
      continue;
    }
    free(r->q[i].buf);
    r->q[i] = r->q[--r->nq];
  }
}

/* The earliest failure this rank knows of its own goes to every rank. */
static void send_failure(gs_comp_ranks *r) {
  size_t key = gs_comp_steps_failure_key(r->s);
  if (r->own_key < key) key = r->own_key;
  if (key >= r->failure_sent) return;
  r->failure_sent = key;
  for (int dest = 0; dest < r->size; dest++) {
    if (dest == r->rank) continue;
    double *buf = malloc(sizeof(double));
    if (!buf) continue; /* it also reaches them at the end (gs_comp_ranks_finish) */
    *buf = (double)key;
    send(r, dest, TAG_FAILURE, buf, 1);
  }
}

static void receive_failures(gs_comp_ranks *r) {
  for (;;) {
    int flag = 0;
    MPI_Status st;
    MPI_Iprobe(MPI_ANY_SOURCE, TAG_FAILURE, r->comm, &flag, &st);
    if (!flag) return;
    double key;
    MPI_Recv(&key, 1, MPI_DOUBLE, st.MPI_SOURCE, TAG_FAILURE, r->comm, MPI_STATUS_IGNORE);
    r->got[st.MPI_SOURCE * NTAG + TAG_FAILURE]++;
    gs_comp_steps_remote_failure(r->s, (size_t)key);
  }
}

/* The record of the block's last compartment: what was published since the
 * last message, the stretch's end with it. */
static void send_record(gs_comp_ranks *r) {
  if (r->hi == r->ncomp) return;
  for (;;) {
    size_t k, published;
    int done;
    if (!gs_comp_steps_down_peek(r->s, &k, &published, &done)) return;
    if (published <= r->down_from && !done) return;
    const size_t count = published > r->down_from ? published - r->down_from : 0;
    const size_t nvol = (size_t)r->m->nvol, n = HEADER + count * r->node_len + (done ? nvol : 0);
    double *buf = malloc(n * sizeof(double));
    if (!buf) {
      own_failure(r, k, r->hi - 1, "the record sent to the next rank");
      return;
    }
    const size_t known = gs_comp_steps_known_failure(r->s);
    buf[0] = (double)k;
    buf[1] = (double)count;
    buf[2] = done;
    buf[3] = known == SIZE_MAX ? -1.0 : (double)known;
    for (size_t j = 0; j < count; j++)
      memcpy(buf + HEADER + j * r->node_len, gs_comp_steps_down_node(r->s, k, r->down_from + j),
             r->node_len * sizeof(double));
    if (done) memcpy(buf + HEADER + count * r->node_len, gs_comp_steps_down_sent(r->s, k), nvol * sizeof(double));
    send(r, r->rank + 1, TAG_RECORD, buf, n);
    r->down_from = published;
    if (!done) return;
    r->down_from = 0;
    gs_comp_steps_down_gone(r->s, k);
  }
}

/* Messages of the rank before into the record of compartment lo - 1, as far
 * as its ring has room (the rest stays with MPI, in order). */
static void receive_records(gs_comp_ranks *r) {
  if (!r->lo) return;
  for (;;) {
    if (!r->staged) {
      int flag = 0, count = 0;
      MPI_Status st;
      MPI_Iprobe(r->rank - 1, TAG_RECORD, r->comm, &flag, &st);
      if (!flag) return;
      MPI_Get_count(&st, MPI_DOUBLE, &count);
      if (!grow(&r->stage, &r->stage_cap, (size_t)count)) {
        own_failure(r, gs_comp_steps_known_failure(r->s) / (r->ncomp + 1), r->lo, "a record from the rank before");
        return;
      }
      MPI_Recv(r->stage, count, MPI_DOUBLE, r->rank - 1, TAG_RECORD, r->comm, MPI_STATUS_IGNORE);
      r->got[(r->rank - 1) * NTAG + TAG_RECORD]++;
      r->staged = 1;
    }
    const double *m = r->stage;
    const size_t k = (size_t)m[0], count = (size_t)m[1];
    if (!r->up_begun) {
      if (!gs_comp_steps_up_begin(r->s, k)) return; /* its ring slot is still read */
      r->up_begun = 1;
    }
    if (count && gs_comp_steps_up_nodes(r->s, k, m + HEADER, count))
      own_failure(r, k, r->lo, "a record from the rank before");
    if (m[2] != 0) {
      gs_comp_steps_up_end(r->s, k, m + HEADER + count * r->node_len, m[3] < 0 ? SIZE_MAX : (size_t)m[3]);
      r->up_begun = 0;
    }
    r->staged = 0;
  }
}

/* Rank 0: the blocks of output times, into their stretches' states and marks. */
static void receive_outputs(gs_comp_ranks *r) {
  for (int src = 1; src < r->size; src++) {
    for (;;) {
      int flag = 0, count = 0;
      MPI_Status st;
      MPI_Iprobe(src, TAG_OUTPUT, r->comm, &flag, &st);
      if (!flag) break;
      MPI_Get_count(&st, MPI_DOUBLE, &count);
      double *buf = grow(&r->out_buf, &r->out_cap, (size_t)count);
      if (!buf) { /* it waits: nothing is lost, the run goes on when there is room */
        own_failure(r, gs_comp_steps_known_failure(r->s) / (r->ncomp + 1), r->ncomp, "an output time's block");
        return;
      }
      MPI_Recv(buf, count, MPI_DOUBLE, src, TAG_OUTPUT, r->comm, MPI_STATUS_IGNORE);
      r->got[src * NTAG + TAG_OUTPUT]++;
      const size_t k = (size_t)buf[0], lo = r->blo[src], nb = r->blo[src + 1] - lo;
      double *Y, *marks;
      gs_comp_steps_slot(r->s, k, &Y, &marks);
      const double *at = buf + 1;
      memcpy(Y + lo * r->ncells, at, nb * r->ncells * sizeof(double));
      at += nb * r->ncells;
      memcpy(Y + r->m->nnum + lo * r->nqc, at, nb * r->nqc * sizeof(double));
      at += nb * r->nqc;
      memcpy(Y + r->m->nstate + lo * r->nl, at, nb * r->nl * sizeof(double));
      at += nb * r->nl;
      memcpy(marks + lo * GS_INTEGRATOR_MARK, at, nb * GS_INTEGRATOR_MARK * sizeof(double));
      r->out_got[src] = k + 1;
    }
  }
}

/* Under r->lock: everything a poll does. */
static void poll_locked(gs_comp_ranks *r) {
  send_failure(r);
  send_record(r);
  receive_records(r);
  receive_failures(r);
  if (!r->rank) receive_outputs(r);
  reap(r);
}

/* Only one thread at a time, and under MPI_THREAD_FUNNELED only the main one. */
static int may_call(gs_comp_ranks *r, int wait) {
  if (!r->serialized && omp_get_thread_num() != 0) return 0;
  if (wait) omp_set_lock(&r->lock);
  else if (!omp_test_lock(&r->lock)) return 0;
  return 1;
}

void gs_comp_ranks_poll(gs_comp_ranks *r) {
  if (!may_call(r, 0)) return;
  poll_locked(r);
  omp_unset_lock(&r->lock);
}

int gs_comp_ranks_flushed(gs_comp_ranks *r) {
  if (!may_call(r, 1)) return 0;
  poll_locked(r);
  size_t k, published;
  int done;
  const int left = r->hi < r->ncomp && gs_comp_steps_down_peek(r->s, &k, &published, &done);
  omp_unset_lock(&r->lock);
  return !left;
}

int gs_comp_ranks_output_ready(gs_comp_ranks *r, size_t k) {
  const gs_stretch *st = gs_comp_steps_stretch(r->s, k);
  if (r->rank || !st || !st->mark) return 1;
  if (!may_call(r, 0)) return 0;
  poll_locked(r);
  int ready = 1;
  for (int src = 1; src < r->size; src++)
    if (r->out_got[src] <= k) ready = 0;
  omp_unset_lock(&r->lock);
  return ready;
}

int gs_comp_ranks_output(gs_comp_ranks *r, size_t k, const double *Y, const double *marks, gs_error *err) {
  const gs_stretch *st = gs_comp_steps_stretch(r->s, k);
  if (!r->rank || !st || !st->mark) return GS_OK;
  const size_t nb = r->hi - r->lo;
  const size_t n = 1 + nb * (r->ncells + r->nqc + r->nl + GS_INTEGRATOR_MARK);
  double *buf = malloc(n * sizeof(double)), *at = buf;
  if (!buf) return gs_error_set(err, GS_ENOMEM, "out of memory for an output time's block on MPI rank %d", r->rank);
  *at++ = (double)k;
  memcpy(at, Y + r->lo * r->ncells, nb * r->ncells * sizeof(double));
  at += nb * r->ncells;
  memcpy(at, Y + r->m->nnum + r->lo * r->nqc, nb * r->nqc * sizeof(double));
  at += nb * r->nqc;
  memcpy(at, Y + r->m->nstate + r->lo * r->nl, nb * r->nl * sizeof(double));
  at += nb * r->nl;
  memcpy(at, marks + r->lo * GS_INTEGRATOR_MARK, nb * GS_INTEGRATOR_MARK * sizeof(double));
  omp_set_lock(&r->lock);
  send(r, 0, TAG_OUTPUT, buf, n);
  omp_unset_lock(&r->lock);
  return GS_OK;
}

void gs_comp_ranks_resplit(gs_comp_ranks *r, const size_t *lo) {
  memcpy(r->blo, lo, ((size_t)r->size + 1) * sizeof(size_t));
  r->lo = lo[r->rank];
  r->hi = lo[r->rank + 1];
  gs_comp_steps_set_block(r->s, r->lo, r->hi, r, r->serialized);
}

void gs_comp_ranks_start(gs_comp_ranks *r) {
  r->down_from = 0;
  r->staged = r->up_begun = 0;
  memset(r->out_got, 0, (size_t)r->size * sizeof(size_t));
  r->failure_sent = r->own_key = SIZE_MAX;
}

void gs_comp_ranks_finish(gs_comp_ranks *r, size_t *key, gs_comp_ranks_failure *f) {
  omp_set_lock(&r->lock);
  send_failure(r);
  send_record(r);
  /* every message sent to this rank is received (those a failure left
   * unread included), so that every send completes */
  const size_t nc = (size_t)r->size * NTAG;
  long *expect = malloc(nc * sizeof(long));
  double *scratch = NULL;
  size_t scratch_cap = 0;
  if (!expect) MPI_Abort(r->comm, 1); /* the ranks cannot agree without it */
  MPI_Alltoall(r->sent, NTAG, MPI_LONG, expect, NTAG, MPI_LONG, r->comm);
  for (int src = 0; src < r->size; src++)
    for (int tag = 0; tag < NTAG; tag++)
      while (r->got[src * NTAG + tag] < expect[src * NTAG + tag]) {
        MPI_Status st;
        int count = 0;
        MPI_Probe(src, tag, r->comm, &st);
        MPI_Get_count(&st, MPI_DOUBLE, &count);
        if (!grow(&scratch, &scratch_cap, (size_t)count)) MPI_Abort(r->comm, 1);
        MPI_Recv(scratch, count, MPI_DOUBLE, src, tag, r->comm, MPI_STATUS_IGNORE);
        r->got[src * NTAG + tag]++;
      }
  free(scratch);
  free(expect);
  for (size_t i = 0; i < r->nq; i++) {
    MPI_Wait(&r->q[i].req, MPI_STATUS_IGNORE);
    free(r->q[i].buf);
  }
  r->nq = 0;
  memset(r->sent, 0, nc * sizeof(long));
  memset(r->got, 0, nc * sizeof(long));
  r->staged = 0;
  /* the earliest failure of all ranks, and its rank's message */
  if (r->own_key < *key) {
    *key = r->own_key;
    *f = (gs_comp_ranks_failure){.rc = GS_ENOMEM, .err = r->own_err};
  }
  unsigned long long mine = *key == SIZE_MAX ? ULLONG_MAX : (unsigned long long)*key, first;
  MPI_Allreduce(&mine, &first, 1, MPI_UNSIGNED_LONG_LONG, MPI_MIN, r->comm);
  if (first == ULLONG_MAX) {
    *key = SIZE_MAX;
    f->rc = GS_OK;
  } else {
    int me = mine == first ? r->rank : r->size, owner;
    MPI_Allreduce(&me, &owner, 1, MPI_INT, MPI_MIN, r->comm);
    MPI_Bcast(f, (int)sizeof *f, MPI_BYTE, owner, r->comm);
    *key = (size_t)first;
    /* rank 0 says what went wrong (as one process would), and so does the
     * rank where it did; the others only that it did */
    if (r->rank && r->rank != owner && f->rc > 0) {
      f->bad_rate = 0;
      gs_error_set(&f->err, f->rc, "the run failed on another MPI rank");
    }
  }
  omp_unset_lock(&r->lock);
}

int gs_comp_ranks_create(gs_comp_steps *s, const gs_model *m, const gs_dist *d, gs_comp_ranks **out,
                         gs_error *err) {
  *out = NULL;
  gs_comp_ranks *r = gs_calloc(1, sizeof *r, err);
  if (!r) return GS_ENOMEM;
  r->s = s;
  r->m = m;
  r->rank = d->rank;
  r->size = d->size;
  r->ncomp = m->grid.ncomp;
  r->lo = d->lo[d->rank];
  r->hi = d->lo[d->rank + 1];
  r->ncells = m->grid.ncells;
  r->nqc = (size_t)m->ncarried * m->grid.ncells;
  r->nl = 2 * (size_t)m->nvol;
  r->node_len = gs_comp_steps_node_len(s);
  r->blo = gs_malloc(((size_t)d->size + 1) * sizeof(size_t), err);
  r->sent = gs_calloc((size_t)d->size * NTAG, sizeof(long), err);
  r->got = gs_calloc((size_t)d->size * NTAG, sizeof(long), err);
  r->out_got = gs_calloc((size_t)d->size, sizeof(size_t), err);
  if (!r->blo || !r->sent || !r->got || !r->out_got) {
    gs_comp_ranks_free(r);
    return GS_ENOMEM;
  }
  memcpy(r->blo, d->lo, ((size_t)d->size + 1) * sizeof(size_t));
  int level = MPI_THREAD_SINGLE;
  MPI_Query_thread(&level);
  r->serialized = level >= MPI_THREAD_SERIALIZED;
  MPI_Comm_dup(MPI_COMM_WORLD, &r->comm);
  r->has_comm = 1;
  omp_init_lock(&r->lock);
  r->failure_sent = r->own_key = SIZE_MAX;
  gs_comp_steps_set_block(s, r->lo, r->hi, r, r->serialized);
  *out = r;
  return GS_OK;
}

void gs_comp_ranks_free(gs_comp_ranks *r) {
  if (!r) return;
  if (r->has_comm) {
    MPI_Comm_free(&r->comm);
    omp_destroy_lock(&r->lock);
  }
  for (size_t i = 0; i < r->nq; i++) free(r->q[i].buf); /* finish waited for them */
  free(r->q);
  free(r->blo);
  free(r->sent);
  free(r->got);
  free(r->out_got);
  free(r->stage);
  free(r->out_buf);
  free(r);
}

#else /* without MPI: one process, never on ranks */

int gs_comp_ranks_create(gs_comp_steps *s, const gs_model *m, const gs_dist *d, gs_comp_ranks **out,
                         gs_error *err) {
  (void)s, (void)m, (void)d;
  *out = NULL;
  return gs_error_set(err, GS_EINPUT, "per-compartment steps on MPI ranks need a build with -DGRANSIM_MPI=ON");
}
void gs_comp_ranks_start(gs_comp_ranks *r) { (void)r; }
void gs_comp_ranks_resplit(gs_comp_ranks *r, const size_t *lo) { (void)r, (void)lo; }
void gs_comp_ranks_poll(gs_comp_ranks *r) { (void)r; }
int gs_comp_ranks_flushed(gs_comp_ranks *r) { return (void)r, 1; }
int gs_comp_ranks_output_ready(gs_comp_ranks *r, size_t k) { return (void)r, (void)k, 1; }
int gs_comp_ranks_output(gs_comp_ranks *r, size_t k, const double *Y, const double *marks, gs_error *err) {
  (void)r, (void)k, (void)Y, (void)marks, (void)err;
  return GS_OK;
}
void gs_comp_ranks_finish(gs_comp_ranks *r, size_t *key, gs_comp_ranks_failure *f) {
  (void)r, (void)key, (void)f;
}
void gs_comp_ranks_free(gs_comp_ranks *r) { (void)r; }

#endif
