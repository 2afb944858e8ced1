/* statistics.start: steady with LIGGGHTS: the embedded engine's detector
 * (gs_dem_is_steady_n: the quantities statistics.steady.quantities names,
 * each within `tolerance` of its mean over the last `window` samples) on the
 * deck's dumps, which start at t = 0 in this mode.  A sample every
 * statistics.sample_every as in the embedded engine: the hold-up mass and
 * the kinetic energy (translational + rotational, every particle) of its
 * collision<STEP>.atom snapshot, and the pair contacts that began since the
 * previous sample (tables.c's rule: a pair of the contact list absent from
 * the list before) per second.  The runner feeds it each chunk as LIGGGHTS
 * finishes it; --reduce the whole run at once. */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "dem/dem_stats.h"
#include "demdata/dump.h"
#include "liggghts/lig_internal.h"

void gs_lig_steady_init(gs_lig_steady *s, const gs_dem_case *c) {
  memset(s, 0, sizeof *s);
  s->smp_k = (long)fmax(1, round(c->sample_every / c->prm.dt));
  s->t_steady = -1;
  /* a bed at rest before its walls turn is not the steady state sought (run_dem.c) */
  for (size_t w = 0; w < c->nwall_src; w++)
    if (c->wall_src[w].rotating) s->t_agitate = fmax(s->t_agitate, c->wall_src[w].spin_start);
}

void gs_lig_steady_free(gs_lig_steady *s) {
  free(s->prev), free(s->cur), free(s->rows), free(s->ev), free(s->t), free(s->m), free(s->cr), free(s->ke);
  memset(s, 0, sizeof *s);
}

static int cmp_key(const void *a, const void *b) {
  unsigned long long x = *(const unsigned long long *)a, y = *(const unsigned long long *)b;
  return (x > y) - (x < y);
}

/* Room for sample interval j in s->ev. */
static int ev_room(gs_lig_steady *s, size_t j) {
  if (j < s->cap_ev) return 0;
  size_t cap = s->cap_ev ? s->cap_ev : 256;
  while (cap <= j) cap *= 2;
  double *e = realloc(s->ev, cap * sizeof *e);
  if (!e) return -1;
  memset(e + s->cap_ev, 0, (cap - s->cap_ev) * sizeof *e);
  s->ev = e, s->cap_ev = cap;
  return 0;
}

/* The pair contact lists of post/events_pp.txt up to step upto: each
 * contact that began counts in its sample interval. */
static int read_lists(gs_lig_steady *s, const char *post, long upto, gs_error *err) {
  char path[4400];
  snprintf(path, sizeof path, "%s/events_pp.txt", post);
  FILE *fp = fopen(path, "r");
  if (!fp) return gs_error_set(err, GS_EIO, "%s: cannot read: %s", path, strerror(errno));
  int rc = fseek(fp, s->pos, SEEK_SET) ? gs_error_set(err, GS_EIO, "%s: cannot seek", path) : GS_OK;
  size_t n = 0;
  for (long st; !rc && (st = gs_lig_next_list(fp, 3, &s->rows, &s->caprows, &n)) != 0;) {
    if (st < 0) { rc = gs_error_set(err, GS_EINPUT, "%s: unreadable contact list", path); break; }
    if (st - 1 > upto) break; /* the next chunk's: read again from s->pos then */
    unsigned long long *t = realloc(s->cur, (n + 1) * sizeof *t);
    if (!t) { rc = gs_error_set(err, GS_ENOMEM, "out of memory"); break; }
    s->cur = t;
    size_t ncur = 0;
    for (size_t r = 0; r < n; r++) {
      const double *v = s->rows + 3 * r;
      if (!(v[2] > 0)) continue; /* not overlapping */
      if (!(v[0] >= 0 && v[0] <= 2147483647.0 && v[1] >= 0 && v[1] <= 2147483647.0)) {
        rc = gs_error_set(err, GS_EINPUT, "%s: list at step %ld: row %zu: atom id %g or %g is not an id", path, st - 1,
                          r + 1, v[0], v[1]);
        break;
      }
      unsigned long long i1 = (unsigned long long)v[0], i2 = (unsigned long long)v[1];
      s->cur[ncur++] = i1 < i2 ? i1 << 32 | i2 : i2 << 32 | i1;
    }
    qsort(s->cur, ncur, sizeof *s->cur, cmp_key);
    const size_t j = (size_t)((st - 1 + s->smp_k - 1) / s->smp_k);
    if (!rc && s->lists && ev_room(s, j)) rc = gs_error_set(err, GS_ENOMEM, "out of memory");
    for (size_t q = 0; !rc && s->lists && q < ncur; q++)
      if ((q == 0 || s->cur[q] != s->cur[q - 1]) && !bsearch(&s->cur[q], s->prev, s->nprev, sizeof *s->prev, cmp_key))
        s->ev[j] += 1;
    unsigned long long *sw = s->prev;
    s->prev = s->cur, s->nprev = ncur, s->cur = sw;
    s->lists++;
    s->pos = ftell(fp);
  }
  fclose(fp);
  return rc;
}

/* The hold-up mass (gs_dem_holdup's) and the kinetic energy (gs_dem_kinetic_energy's:
 * every particle, translation and rotation) of snapshot post/collision<step>.atom. */
static int snapshot_figures(const gs_dem_case *c, const char *post, long step, double *m, double *ke,
                            gs_error *err) {
  char path[4400];
  snprintf(path, sizeof path, "%s/collision%ld.atom", post, step);
  gs_dump d;
  int rc = gs_dump_read(path, &d, err);
  if (rc) return rc;
  static const char *const need[] = {"type", "x", "y", "z", "radius", "vx", "vy", "vz", "omegax", "omegay", "omegaz"};
  long col[11];
  for (int k = 0; !rc && k < 11; k++)
    if ((col[k] = gs_dump_col(&d, need[k])) < 0)
      rc = gs_error_set(err, GS_EINPUT, "%s: expected a column '%s' (type, x, y, z, radius, vx, vy, vz, omegax, "
                        "omegay, omegaz)", path, need[k]);
  *m = 0, *ke = 0;
  for (size_t r = 0; !rc && r < d.nrows; r++) {
    const double *v = d.v + r * d.ncols, x[3] = {v[col[1]], v[col[2]], v[col[3]]}, rad = v[col[4]];
    if (!(v[col[0]] >= 1 && v[col[0]] <= (double)c->nclass && v[col[0]] == floor(v[col[0]]))) {
      rc = gs_error_set(err, GS_EINPUT, "%s: type %g is no class (1 to %zu)", path, v[col[0]], c->nclass);
      break;
    }
    const double mass = c->cls[(int)v[col[0]] - 1].mat.density * 4.0 / 3.0 * M_PI * rad * rad * rad;
    if (!c->has_holdup || gs_dem_region_contains(&c->holdup, x)) *m += mass;
    const double v2 = v[col[5]] * v[col[5]] + v[col[6]] * v[col[6]] + v[col[7]] * v[col[7]];
    const double w2 = v[col[8]] * v[col[8]] + v[col[9]] * v[col[9]] + v[col[10]] * v[col[10]];
    *ke += 0.5 * mass * v2 + 0.5 * (0.4 * mass * rad * rad) * w2; /* I = 2/5 m r^2 */
  }
  gs_dump_free(&d);
  return rc;
}

/* The series the case watches (in the order of gs_dem_steady_quantities), from sample k0. */
static int watched(const gs_lig_steady *s, const gs_dem_case *c, size_t k0, const double **out) {
  const double *all[3] = {s->m + k0, s->cr + k0, s->ke + k0};
  int nq = 0;
  for (int q = 0; q < 3; q++)
    if (c->steady_q & (1u << q)) out[nq++] = all[q];
  return nq;
}

int gs_lig_steady_update(gs_lig_steady *s, const gs_dem_case *c, const char *post, long upto, gs_error *err) {
  int rc = read_lists(s, post, upto, err);
  const double dt = c->prm.dt;
  for (long j = (long)s->ns + 1; !rc && j * s->smp_k <= upto; j++) {
    if (s->ns == s->cap) {
      size_t cap = s->cap ? 2 * s->cap : 256;
      double *t = realloc(s->t, cap * sizeof *t), *m = t ? realloc(s->m, cap * sizeof *m) : NULL;
      double *cr = m ? realloc(s->cr, cap * sizeof *cr) : NULL, *ke = cr ? realloc(s->ke, cap * sizeof *ke) : NULL;
      if (t) s->t = t;
      if (m) s->m = m;
      if (cr) s->cr = cr;
      if (ke) s->ke = ke, s->cap = cap;
      if (!ke) { rc = gs_error_set(err, GS_ENOMEM, "out of memory"); break; }
    }
    if (ev_room(s, (size_t)j)) { rc = gs_error_set(err, GS_ENOMEM, "out of memory"); break; }
    double m, ke;
    if ((rc = snapshot_figures(c, post, j * s->smp_k, &m, &ke, err))) break;
    const size_t k = s->ns++;
    s->t[k] = (double)(j * s->smp_k) * dt;
    s->m[k] = m;
    s->ke[k] = ke;
    s->cr[k] = s->ev[j] / ((double)s->smp_k * dt);
    if (s->t[k] <= s->t_agitate * (1 + 1e-12)) s->k_ag = s->ns;
    const double *w[3];
    const int nq = watched(s, c, s->k_ag, w);
    if (s->t_steady < 0 && gs_dem_is_steady_n(w, nq, (long)(s->ns - s->k_ag), c->steady_window, c->steady_tol))
      s->t_steady = s->t[k];
  }
  return rc;
}

/* The largest relative deviation from the mean over the last w of a[0..n). */
static double deviation(const double *a, size_t n, long w) {
  if (w < 1 || n < (size_t)w) return NAN;
  double mean = 0, dev = 0;
  for (size_t k = n - (size_t)w; k < n; k++) mean += a[k] / (double)w;
  for (size_t k = n - (size_t)w; k < n; k++) dev = fmax(dev, fabs(a[k] - mean));
  return mean > 0 ? dev / mean : NAN;
}

int gs_lig_steady_not_reached(const gs_lig_steady *s, const gs_dem_case *c, gs_error *err) {
  const size_t n = s->ns - s->k_ag;
  const double *w[3];
  const int nq = watched(s, c, s->k_ag, w);
  char names[128], figs[256];
  gs_dem_steady_quantities_join(c->steady_q, ", ", names, sizeof names);
  size_t used = 0;
  for (int q = 0; q < nq && used < sizeof figs; q++)
    used += (size_t)snprintf(figs + used, sizeof figs - used, "%s%.3g", q ? ", " : "", deviation(w[q], n, c->steady_window));
  return gs_error_set(err, GS_ENUMERIC,
                      "%s: statistics.start is 'steady' but the steady state was not reached by t = %.6g s (%s "
                      "within %g of their means over %ld samples; over the last %ld samples they are within %s of "
                      "their means, nan without collisions; %zu samples seen): no statistics window, so no tables "
                      "(the thermo rows are in liggghts/log.liggghts); run longer, or set statistics.start to a time "
                      "or loosen statistics.steady",
                      c->path, s->ns ? s->t[s->ns - 1] : 0.0, names, c->steady_tol, c->steady_window,
                      c->steady_window, figs, n);
}
