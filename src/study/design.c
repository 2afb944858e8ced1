/* Study designs: parsing --set / --range, the full grid and the Latin
 * hypercube (see gransim/study.h). */
#include "gransim/study.h"

#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <gsl/gsl_randist.h>
#include <gsl/gsl_rng.h>

/* A grid larger than this is a typo (a list pasted twice), not a study. */
#define GS_DESIGN_MAX_RUNS 10000000u

static char *dup_n(const char *s, size_t n, gs_error *err) {
  char *d = gs_malloc(n + 1, err);
  if (d) {
    memcpy(d, s, n);
    d[n] = '\0';
  }
  return d;
}

/* Split "KEY=REST" into a->key and *rest. */
static int split_key(const char *arg, const char *opt, const char *form, gs_study_axis *a,
                     const char **rest, gs_error *err) {
  memset(a, 0, sizeof *a);
  const char *eq = arg ? strchr(arg, '=') : NULL;
  if (!eq || eq == arg)
    return gs_error_set(err, GS_EINPUT, "%s '%s': expected %s", opt, arg ? arg : "", form);
  for (const char *p = arg; p < eq; p++)
    if (isspace((unsigned char)*p))
      return gs_error_set(err, GS_EINPUT, "%s '%s': the key has a space", opt, arg);
  a->key = dup_n(arg, (size_t)(eq - arg), err);
  *rest = eq + 1;
  return a->key ? GS_OK : GS_ENOMEM;
}

int gs_study_parse_set(const char *arg, gs_study_axis *a, gs_error *err) {
  const char *rest;
  int rc = split_key(arg, "--set", "KEY=V1,V2,...", a, &rest, err);
  if (rc) return rc;
  size_t n = 1;
  for (const char *p = rest; *p; p++) n += *p == ',';
  a->values = gs_calloc(n, sizeof *a->values, err);
  if (!a->values) return GS_ENOMEM;
  for (const char *p = rest;; p++) {
    size_t len = strcspn(p, ",");
    if (len == 0)
      return gs_error_set(err, GS_EINPUT, "--set '%s': empty value in the list of %s", arg, a->key);
    if (!(a->values[a->nvalues++] = dup_n(p, len, err))) return GS_ENOMEM;
    p += len;
    if (!*p) break;
  }
  return GS_OK;
}

static int parse_number(const char *s, size_t len, double *out) {
  char buf[64], *end = NULL;
  if (len == 0 || len >= sizeof buf) return 0;
  memcpy(buf, s, len);
  buf[len] = '\0';
  errno = 0;
  *out = strtod(buf, &end);
  return end != buf && *end == '\0' && isfinite(*out);
}

int gs_study_parse_range(const char *arg, gs_study_axis *a, gs_error *err) {
  const char *rest;
  int rc = split_key(arg, "--range", "KEY=LO:HI or KEY=LO:HI:log", a, &rest, err);
  if (rc) return rc;
  const char *c1 = strchr(rest, ':'), *c2 = c1 ? strchr(c1 + 1, ':') : NULL;
  if (!c1 || !parse_number(rest, (size_t)(c1 - rest), &a->lo) ||
      !parse_number(c1 + 1, c2 ? (size_t)(c2 - c1 - 1) : strlen(c1 + 1), &a->hi))
    return gs_error_set(err, GS_EINPUT, "--range '%s': expected KEY=LO:HI with two numbers", arg);
  if (c2) {
    if (strcmp(c2 + 1, "log"))
      return gs_error_set(err, GS_EINPUT, "--range '%s': after LO:HI only ':log' may follow", arg);
    a->log = 1;
  }
  if (!(a->lo < a->hi))
    return gs_error_set(err, GS_EINPUT, "--range '%s': LO must be below HI (got %g >= %g)", arg,
                        a->lo, a->hi);
  if (a->log && !(a->lo > 0))
    return gs_error_set(err, GS_EINPUT, "--range '%s': a log range needs LO > 0", arg);
  return GS_OK;
}

void gs_study_axis_free(gs_study_axis *a) {
  if (!a) return;
  for (size_t i = 0; i < a->nvalues; i++) free(a->values[i]);
  free(a->values);
  free(a->key);
  memset(a, 0, sizeof *a);
}

void gs_design_free(gs_design *d) {
  if (!d) return;
  for (size_t i = 0; d->values && i < d->nruns * d->nkeys; i++) free(d->values[i]);
  for (size_t k = 0; d->keys && k < d->nkeys; k++) free(d->keys[k]);
  free(d->values);
  free(d->keys);
  free(d->unit);
  memset(d, 0, sizeof *d);
}

/* Keys copied, values table allocated; the same key twice is refused (the
 * second would silently win). */
static int design_start(const gs_study_axis *axes, size_t naxes, size_t nruns, gs_design *d,
                        gs_error *err) {
  memset(d, 0, sizeof *d);
  if (naxes == 0) return gs_error_set(err, GS_EINPUT, "nothing to vary: no --set or --range");
  for (size_t k = 0; k < naxes; k++)
    for (size_t j = 0; j < k; j++)
      if (!strcmp(axes[k].key, axes[j].key))
        return gs_error_set(err, GS_EINPUT, "key '%s' is varied twice", axes[k].key);
  d->nkeys = naxes;
  d->nruns = nruns;
  d->keys = gs_calloc(naxes, sizeof *d->keys, err);
  d->values = gs_calloc(nruns * naxes, sizeof *d->values, err);
  if (!d->keys || !d->values) return GS_ENOMEM;
  for (size_t k = 0; k < naxes; k++)
    if (!(d->keys[k] = dup_n(axes[k].key, strlen(axes[k].key), err))) return GS_ENOMEM;
  return GS_OK;
}

int gs_design_grid(const gs_study_axis *axes, size_t naxes, gs_design *d, gs_error *err) {
  size_t nruns = 1;
  for (size_t k = 0; k < naxes; k++) {
    if (!axes[k].values || !axes[k].nvalues)
      return gs_error_set(err, GS_EINPUT, "key '%s': a grid needs a list of values (--set)",
                          axes[k].key);
    if (nruns > GS_DESIGN_MAX_RUNS / axes[k].nvalues)
      return gs_error_set(err, GS_EINPUT, "the grid has more than %u runs", GS_DESIGN_MAX_RUNS);
    nruns *= axes[k].nvalues;
  }
  int rc = design_start(axes, naxes, nruns, d, err);
  if (rc) {
    gs_design_free(d);
    return rc;
  }
  for (size_t r = 0; r < nruns; r++) {
    size_t rem = r; /* mixed-radix digits of r, the last axis fastest */
    for (size_t k = naxes; k-- > 0;) {
      const gs_study_axis *a = &axes[k];
      const char *v = a->values[rem % a->nvalues];
      rem /= a->nvalues;
      if (!(d->values[r * naxes + k] = dup_n(v, strlen(v), err))) {
        gs_design_free(d);
        return GS_ENOMEM;
      }
    }
  }
  return GS_OK;
}

int gs_design_lhs(const gs_study_axis *axes, size_t naxes, size_t n, unsigned long seed,
                  gs_design *d, gs_error *err) {
  if (n < 1) return gs_error_set(err, GS_EINPUT, "a Latin hypercube needs N >= 1 runs");
  if (n > GS_DESIGN_MAX_RUNS)
    return gs_error_set(err, GS_EINPUT, "a Latin hypercube of more than %u runs", GS_DESIGN_MAX_RUNS);
  for (size_t k = 0; k < naxes; k++)
    if (axes[k].values)
      return gs_error_set(err, GS_EINPUT,
                          "key '%s': a Latin hypercube needs a range (--range KEY=LO:HI), not a list",
                          axes[k].key);
  int rc = design_start(axes, naxes, n, d, err);
  size_t *perm = rc ? NULL : gs_malloc(n * sizeof *perm, err);
  d->unit = perm ? gs_malloc(n * naxes * sizeof *d->unit, err) : NULL;
  gsl_rng *rng = d->unit ? gsl_rng_alloc(gsl_rng_mt19937) : NULL;
  if (!rng) {
    free(perm);
    gs_design_free(d);
    return rc ? rc : gs_error_set(err, GS_ENOMEM, "out of memory for the design");
  }
  gsl_rng_set(rng, seed);
  for (size_t k = 0; k < naxes && !rc; k++) {
    const gs_study_axis *a = &axes[k];
    for (size_t i = 0; i < n; i++) perm[i] = i;
    gsl_ran_shuffle(rng, perm, n, sizeof *perm);
    for (size_t r = 0; r < n && !rc; r++) {
      /* run r lies in stratum perm[r], uniformly within it */
      double u = ((double)perm[r] + gsl_rng_uniform(rng)) / (double)n;
      d->unit[r * naxes + k] = u;
      char buf[40];
      snprintf(buf, sizeof buf, "%.17g", gs_study_axis_value(a, u));
      if (!(d->values[r * naxes + k] = dup_n(buf, strlen(buf), err))) rc = GS_ENOMEM;
    }
  }
  gsl_rng_free(rng);
  free(perm);
  if (rc) gs_design_free(d);
  return rc;
}

double gs_study_axis_value(const gs_study_axis *a, double u) {
  const double lo = a->log ? log(a->lo) : a->lo, hi = a->log ? log(a->hi) : a->hi;
  double x = lo + (hi - lo) * u;
  if (a->log) x = exp(x);
  /* rounding may step past an end; the case must see a value inside */
  return x < a->lo ? a->lo : x > a->hi ? a->hi : x;
}

int gs_design_values(const gs_study_axis *axes, size_t naxes, const double *x, size_t n,
                     gs_design *d, gs_error *err) {
  if (n < 1 || n > GS_DESIGN_MAX_RUNS)
    return gs_error_set(err, GS_EINPUT, "a design of %zu runs (1 to %u)", n, GS_DESIGN_MAX_RUNS);
  int rc = design_start(axes, naxes, n, d, err);
  for (size_t i = 0; i < n * naxes && !rc; i++) {
    char buf[40];
    snprintf(buf, sizeof buf, "%.17g", x[i]); /* 17 digits: the case sees the number itself */
    if (!(d->values[i] = dup_n(buf, strlen(buf), err))) rc = GS_ENOMEM;
  }
  if (rc) gs_design_free(d);
  return rc;
}
