/* The journal's header (journal_header.h): u64 compartments, state values,
 * ledger values, integrator state values, axes; per axis its name
 * (GS_NAME_LEN bytes), u64 cells and the edges; then the case text and file
 * name, each u64 length (with its NUL) and bytes. */
#include "output/journal_header.h"

#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct {
  char *p;
  size_t n, cap;
  int failed;
} writer;

static void put(writer *w, const void *v, size_t len) {
  if (w->failed) return;
  if (w->n + len > w->cap) {
    size_t cap = w->cap ? w->cap : 256;
    while (cap < w->n + len) cap *= 2;
    char *p = realloc(w->p, cap);
    if (!p) {
      w->failed = 1;
      return;
    }
    w->p = p;
    w->cap = cap;
  }
  memcpy(w->p + w->n, v, len);
  w->n += len;
}

static void put_u64(writer *w, uint64_t v) { put(w, &v, sizeof v); }

static void put_str(writer *w, const char *s) {
  put_u64(w, strlen(s) + 1);
  put(w, s, strlen(s) + 1);
}

int gs_journal_header_encode(const gs_model *m, size_t nresume, const char *text, const char *name,
                             void **buf, size_t *n, gs_error *err) {
  const gs_grid *g = &m->grid;
  writer w = {0};
  put_u64(&w, g->ncomp);
  put_u64(&w, m->nstate);
  put_u64(&w, m->nledger);
  put_u64(&w, nresume);
  put_u64(&w, (uint64_t)g->dim);
  for (int k = 0; k < g->dim; k++) {
    char axis[GS_NAME_LEN] = {0};
    snprintf(axis, sizeof axis, "%s", g->axis[k].name);
    put(&w, axis, sizeof axis);
    put_u64(&w, g->axis[k].n);
    put(&w, g->axis[k].edges, (g->axis[k].n + 1) * sizeof(double));
  }
  put_str(&w, text ? text : "");
  put_str(&w, name ? name : "");
  if (w.failed) {
    free(w.p);
    return gs_error_set(err, GS_ENOMEM, "out of memory for the journal header");
  }
  *buf = w.p;
  *n = w.n;
  return GS_OK;
}

typedef struct {
  const char *p;
  size_t n, at;
  int bad;
} reader;

static const void *take(reader *r, size_t len) {
  if (r->bad || len > r->n - r->at) {
    r->bad = 1;
    return NULL;
  }
  const void *v = r->p + r->at;
  r->at += len;
  return v;
}

static uint64_t take_u64(reader *r) {
  uint64_t v = 0;
  const void *p = take(r, sizeof v);
  if (p) memcpy(&v, p, sizeof v);
  return v;
}

static const char *take_str(reader *r) {
  uint64_t len = take_u64(r);
  const char *s = len ? take(r, len) : NULL;
  if (!s || s[len - 1]) r->bad = 1;
  return r->bad ? NULL : s;
}

static int different(gs_error *err, const char *path, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
static int different(gs_error *err, const char *path, const char *fmt, ...) {
  char why[512];
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(why, sizeof why, fmt, ap);
  va_end(ap);
  return gs_error_set(err, GS_EINPUT, "cannot resume: %s was written for a different grid (%s)",
                      path, why);
}

/* Edges are computed the same way on every run, so they agree to round-off;
 * the tolerance only absorbs libm differences between builds. */
static int same_value(double a, double b) { return fabs(a - b) <= 1e-12 * fmax(fabs(a), fabs(b)); }

static int check_axis(reader *r, const gs_axis *ax, const char *path, gs_error *err) {
  const char *name = take(r, GS_NAME_LEN);
  uint64_t n = take_u64(r);
  if (r->bad || memchr(name, 0, GS_NAME_LEN) == NULL) return -1;
  if (strcmp(name, ax->name)) return different(err, path, "axis '%s', case has '%s'", name, ax->name);
  if (n != ax->n)
    return different(err, path, "axis '%s' has %llu cells, case has %zu", ax->name,
                     (unsigned long long)n, ax->n);
  const char *e = take(r, (n + 1) * sizeof(double));
  for (size_t i = 0; e && i <= n; i++) {
    double v;
    memcpy(&v, e + i * sizeof v, sizeof v);
    if (!same_value(v, ax->edges[i]))
      return different(err, path, "axis '%s' edge %zu is %.10g, case has %.10g", ax->name, i, v,
                       ax->edges[i]);
  }
  return r->bad ? -1 : GS_OK;
}

int gs_journal_header_check(const void *buf, size_t n, const gs_model *m, size_t nresume,
                            const char *path, const char **text, const char **name,
                            gs_error *err) {
  const gs_grid *g = &m->grid;
  reader r = {buf, n, 0, 0};
  uint64_t ncomp = take_u64(&r), nstate = take_u64(&r), nledger = take_u64(&r);
  uint64_t nres = take_u64(&r), dim = take_u64(&r);
  int rc = r.bad ? -1 : GS_OK;
  if (!rc && dim != (uint64_t)g->dim)
    rc = different(err, path, "%llu axes, case has %d", (unsigned long long)dim, g->dim);
  if (!rc && ncomp != g->ncomp)
    rc = different(err, path, "%llu compartments, case has %zu", (unsigned long long)ncomp, g->ncomp);
  for (int k = 0; k < g->dim && !rc; k++) rc = check_axis(&r, &g->axis[k], path, err);
  if (!rc && (nstate != m->nstate || nledger != m->nledger))
    rc = gs_error_set(err, GS_EINPUT,
                      "cannot resume: %s was written for a state of %llu values and a ledger of "
                      "%llu, case has %zu and %zu (other carried quantities or mechanisms)",
                      path, (unsigned long long)nstate, (unsigned long long)nledger, m->nstate,
                      m->nledger);
  if (!rc && nres != nresume)
    rc = gs_error_set(err, GS_EINPUT,
                      "cannot resume: %s was written by a run keeping %llu integrator values per "
                      "output time, this case keeps %zu (solver.steps changed)",
                      path, (unsigned long long)nres, nresume);
  if (!rc) {
    *text = take_str(&r);
    *name = take_str(&r);
    if (r.bad) rc = -1;
  }
  if (rc < 0) rc = gs_error_set(err, GS_EIO, "cannot resume: the header of %s is damaged", path);
  return rc;
}
