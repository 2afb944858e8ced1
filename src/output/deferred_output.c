/* See deferred_output.h. */
#include "output/deferred_output.h"

#include <stdlib.h>
#include <string.h>
#include <time.h>

struct gs_deferred_output {
  gs_output *out;
  const gs_model *m;
  size_t n;        /* values per held state: m->nstate + m->nledger + nresume */
  size_t nresume;  /* integrator state values, after the ledger */
  int depth;       /* slots */
  int first, held; /* oldest slot, slots in use */
  int part;        /* next piece of the oldest */
  double *t, *y;   /* depth times, depth * n values */
  int failed;      /* a write failed: nothing more is written */
  double seconds;
};

static double wall_seconds(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

gs_deferred_output *gs_deferred_output_create(gs_output *o, const gs_model *m, size_t nresume,
                                              int depth, gs_error *err) {
  gs_deferred_output *q = gs_calloc(1, sizeof *q, err);
  if (!q) return NULL;
  q->out = o;
  q->m = m;
  q->nresume = nresume;
  q->n = m->nstate + m->nledger + nresume;
  q->depth = depth > 0 ? depth : 1;
  q->t = gs_malloc((size_t)q->depth * sizeof *q->t, err);
  q->y = gs_malloc((size_t)q->depth * q->n * sizeof *q->y, err);
  if (!q->t || !q->y) {
    gs_deferred_output_free(q);
    return NULL;
  }
  /* touched now, before the steps: first touches of fresh pages are slow,
   * and in the first pushes of large cases they held up rank 0 at output
   * times while the other ranks waited */
  memset(q->y, 0, (size_t)q->depth * q->n * sizeof *q->y);
  return q;
}

int gs_deferred_output_pending(const gs_deferred_output *q) { return q->held > 0 && !q->failed; }

int gs_deferred_output_work(gs_deferred_output *q, gs_error *err) {
  if (!gs_deferred_output_pending(q)) return GS_OK;
  const double start = wall_seconds();
  const double *y = q->y + (size_t)q->first * q->n;
  const double *ledger = y + q->m->nstate, *resume = ledger + q->m->nledger;
  int rc = gs_output_write_part(q->out, q->m, q->t[q->first], y, ledger, resume, q->part, err);
  q->seconds += wall_seconds() - start;
  if (rc) {
    q->failed = 1;
    return rc;
  }
  if (++q->part == gs_output_parts(q->out)) { /* that output time is written */
    q->part = 0;
    q->first = (q->first + 1) % q->depth;
    q->held--;
  }
  return GS_OK;
}

/* Write the oldest held output time to its end. */
static int finish_oldest(gs_deferred_output *q, gs_error *err) {
  const int held = q->held;
  int rc = GS_OK;
  while (!rc && q->held == held) rc = gs_deferred_output_work(q, err);
  return rc;
}

int gs_deferred_output_push(gs_deferred_output *q, double t, const double *y,
                            const double *resume, gs_error *err) {
  if (q->failed) return gs_error_set(err, GS_EIO, "result files: an earlier write failed");
  if (q->held == q->depth) {
    int rc = finish_oldest(q, err);
    if (rc) return rc;
  }
  const int slot = (q->first + q->held) % q->depth;
  q->t[slot] = t;
  const size_t nstate = q->n - q->nresume;
  memcpy(q->y + (size_t)slot * q->n, y, nstate * sizeof *y);
  if (q->nresume) memcpy(q->y + (size_t)slot * q->n + nstate, resume, q->nresume * sizeof *y);
  q->held++;
  return GS_OK;
}

int gs_deferred_output_drain(gs_deferred_output *q, gs_error *err) {
  if (q->failed) return gs_error_set(err, GS_EIO, "result files: an earlier write failed");
  int rc = GS_OK;
  while (!rc && gs_deferred_output_pending(q)) rc = gs_deferred_output_work(q, err);
  return rc;
}

double gs_deferred_output_seconds(const gs_deferred_output *q) { return q ? q->seconds : 0; }

void gs_deferred_output_free(gs_deferred_output *q) {
  if (!q) return;
  free(q->t);
  free(q->y);
  free(q);
}
