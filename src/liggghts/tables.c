/* LIGGGHTS dumps -> the tables `gransim dem` writes (src/dem/stats.c), same
 * files, columns and conventions, so that the PBM cannot tell the engines
 * apart.
 *
 * LIGGGHTS lists current contacts, not collision events.  The deck dumps the
 * contact lists of compute pair/gran/local and wall/gran/local every few
 * steps (a third of the shortest Hertz contact, deck.c), and a pair (or an
 * atom on a mesh) absent from the previous list is a contact that began: the
 * embedded engine's event, with the same C_ij = N_coll,ij / (N_i N_j window)
 * and the impact speed |v - v_wall| at the first list that holds the wall
 * contact.  Contacts shorter than the interval can be missed.  Numbers and
 * velocities per class come from the `collision*.atom` snapshots (src/demdata's
 * dump reader); demdata's own reduction of the contact snapshots (contacts /
 * Hertz contact time, docs/models.md) is written alongside, as a comment, for
 * comparison. */
#include <dirent.h>
#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "dem/dem_stats.h"
#include "demdata/dump.h"
#include "gransim/dem_data.h"
#include "liggghts/lig_internal.h"

typedef struct {
  long id;
  int cls;
} id_cls;

static int cmp_id(const void *a, const void *b) {
  long x = ((const id_cls *)a)->id, y = ((const id_cls *)b)->id;
  return (x > y) - (x < y);
}

int gs_lig_clear_dumps(const char *dir, gs_error *err) {
  DIR *dp = opendir(dir);
  if (!dp) return gs_error_set(err, GS_EIO, "%s: cannot open: %s", dir, strerror(errno));
  char path[4400];
  for (struct dirent *e; (e = readdir(dp));)
    if ((strstr(e->d_name, ".atom") && (!strncmp(e->d_name, "collision", 9) || !strncmp(e->d_name, "impact", 6) ||
                                        !strncmp(e->d_name, "ppcoll", 6))) ||
        !strncmp(e->d_name, "events_", 7) || (!strncmp(e->d_name, "left", 4) && strstr(e->d_name, ".atom"))) {
      snprintf(path, sizeof path, "%s/%s", dir, e->d_name);
      remove(path);
    }
  closedir(dp);
  return GS_OK;
}

void gs_lig_remove_tables(const gs_dem_case *c, const char *out) {
  static const char *const names[] = {"collisions", "collision_kernel", "impacts", "impact_table", "impact_velocity",
                                      "velocity", "residence", "residence_class", "timeseries"};
  char path[4400];
  for (size_t k = 0; k < sizeof names / sizeof names[0] + c->nwall_src; k++)
    for (int j = 0; j < 2; j++) {
      if (k < sizeof names / sizeof names[0]) snprintf(path, sizeof path, "%s/%s.%s", out, names[k], j ? "json" : "csv");
      else snprintf(path, sizeof path, "%s/impact_table_%s.%s", out, c->wall_src[k - sizeof names / sizeof names[0]].name,
                    j ? "json" : "csv");
      remove(path);
    }
}

/* What the per-snapshot pass gathers beyond demdata's reduction. */
typedef struct {
  size_t ncl, ncmp, nw;
  double *num;             /* per class: sum over snapshots of N_i */
  double *cv_n, *cv_s, *cv_s2, *cv_a, *cv_v, *cv_v2; /* per class x compartment, as stats.c */
  double *pair_events;     /* ncl x ncl (i <= j) */
  double *wall_contacts;   /* nw x ncl: wall impacts (contacts that began) */
  id_cls *ids;             /* every atom seen in a snapshot (the class of an id never changes) */
  size_t nids, capids, unknown;
  double *ln_u;            /* impact speeds (ln) ... */
  int *u_wc;               /* ... and wall * ncl + class */
  size_t nu, capu;
  double *hist;            /* nw x ncl x nbins: relative impact speeds */
  int nbins;
  double dv;
  double hold_n, hold_m;   /* sums over the snapshots of the hold-up */
  double *vn_n, *vn_s, *vn_s2, *vt_s; /* nw x ncl: impacts with a normal, sums of |vn|, vn^2, |vt| */
  long out_k, nout;        /* output interval (steps) and the number of intervals up to the end */
  double *ts_ev;           /* (1 + nw) x nout: pair events, then wall impacts per wall, per output interval */
  double *rt;              /* residence times of the atoms that left through outlets ... */
  int *rt_cls;             /* ... their classes */
  size_t nrt, caprt;
  double out_mass;
  long k0, k1;             /* the statistics window: from step k0 to k1 */
  double t0, t1;           /* ... in seconds */
  long first_list;         /* the step of the first pair contact list (event rates from there on) */
  long *left_step;         /* every outlet dump (the whole run): its step ... */
  double *left_n;          /* ... and how many atoms it removed */
  size_t nleft, capleft;
} pass;

static void cmp_add(pass *a, const gs_dem_case *c, int k, const double x[3], const double v[3]) {
  const double *ax = c->cmp_axis, *o = c->cmp_origin;
  double pos = (x[0] - o[0]) * ax[0] + (x[1] - o[1]) * ax[1] + (x[2] - o[2]) * ax[2];
  if (pos < c->cmp_edges[0] || pos >= c->cmp_edges[c->ncmp]) return;
  size_t q = 0;
  while (q + 1 < c->ncmp && pos >= c->cmp_edges[q + 1]) q++;
  size_t at = (size_t)k * a->ncmp + q;
  double sp = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
  a->cv_n[at] += 1;
  a->cv_s[at] += sp;
  a->cv_s2[at] += sp * sp;
  a->cv_a[at] += v[0] * ax[0] + v[1] * ax[1] + v[2] * ax[2];
  for (int d = 0; d < 3; d++) {
    a->cv_v[3 * at + d] += v[d];
    a->cv_v2[3 * at + d] += v[d] * v[d];
  }
}

/* A whole number in [0, max] read as a double from a dump (an atom id, a
 * type, a mesh id): anything else would make the conversion to an integer
 * undefined, so it is refused. */
static int whole(double v, double max) { return v >= 0 && v <= max && v == floor(v); }

static int snapshot(pass *a, const gs_dem_case *c, const char *post, long step, gs_error *err) {
  char path[4600];
  gs_dump d;
  snprintf(path, sizeof path, "%s/collision%ld.atom", post, step);
  int rc = gs_dump_read(path, &d, err);
  if (rc) return rc;
  const char *need[] = {"id", "type", "x", "y", "z", "vx", "vy", "vz", "radius"};
  long col[9];
  for (int k = 0; k < 9 && !rc; k++)
    if ((col[k] = gs_dump_col(&d, need[k])) < 0) rc = gs_error_set(err, GS_EINPUT, "%s: no column '%s'", path, need[k]);
  id_cls *map = rc ? NULL : malloc((d.nrows + 1) * sizeof *map);
  if (!rc && !map) rc = gs_error_set(err, GS_ENOMEM, "out of memory");
  for (size_t r = 0; !rc && r < d.nrows; r++) {
    const double *v = d.v + r * d.ncols;
    if (!whole(v[col[0]], 2147483647.0)) { rc = gs_error_set(err, GS_EINPUT, "%s: atom id %g is not an id (a whole number from 0 to 2^31 - 1)", path, v[col[0]]); break; }
    if (!whole(v[col[1]], (double)a->ncl) || v[col[1]] < 1) { rc = gs_error_set(err, GS_EINPUT, "%s: type %g is no class (1 to %zu)", path, v[col[1]], a->ncl); break; }
    int k = (int)v[col[1]] - 1;
    map[r] = (id_cls){(long)v[col[0]], k};
    a->num[k] += 1;
    const double x[3] = {v[col[2]], v[col[3]], v[col[4]]}, u[3] = {v[col[5]], v[col[6]], v[col[7]]};
    cmp_add(a, c, k, x, u);
    if (!c->has_holdup || gs_dem_region_contains(&c->holdup, x)) { /* as gs_dem_holdup */
      const double r = v[col[8]];
      a->hold_n += 1;
      a->hold_m += c->cls[k].mat.density * 4.0 / 3.0 * M_PI * r * r * r;
    }
  }
  size_t nmap = d.nrows;
  gs_dump_free(&d);
  if (!rc && a->nids + nmap > a->capids) {
    size_t cap = a->capids ? a->capids : 1024;
    while (cap < a->nids + nmap) cap *= 2;
    id_cls *t = realloc(a->ids, cap * sizeof *t);
    if (!t) rc = gs_error_set(err, GS_ENOMEM, "out of memory");
    else a->ids = t, a->capids = cap;
  }
  if (!rc) memcpy(a->ids + a->nids, map, nmap * sizeof *map), a->nids += nmap;
  free(map);
  return rc;
}

static int cmp_u64(const void *a, const void *b) {
  unsigned long long x = *(const unsigned long long *)a, y = *(const unsigned long long *)b;
  return (x > y) - (x < y);
}

static int class_of(pass *a, double id) {
  id_cls key = {(long)id, 0}, *f = bsearch(&key, a->ids, a->nids, sizeof *a->ids, cmp_id);
  return f ? f->cls : -1;
}

/* One contact list of an events file: its rows (ncol numbers each), or 0 at the end. */
long gs_lig_next_list(FILE *fp, size_t ncol, double **rows, size_t *cap, size_t *n) {
  char line[1024];
  long step = -1, nrow = -1;
  while (fgets(line, sizeof line, fp)) {
    if (!strncmp(line, "ITEM: TIMESTEP", 14) && fgets(line, sizeof line, fp)) step = atol(line);
    else if (!strncmp(line, "ITEM: NUMBER OF ENTRIES", 23) && fgets(line, sizeof line, fp)) nrow = atol(line);
    else if (!strncmp(line, "ITEM: ENTRIES", 13)) break;
  }
  if (step < 0 || nrow < 0) return 0;
  if ((unsigned long)nrow > (1ul << 32)) return -1; /* beyond any contact list, and beyond memory */
  if ((size_t)nrow * ncol > *cap) {
    double *r = realloc(*rows, ((size_t)nrow * ncol + 1) * sizeof(double));
    if (!r) return -1;
    *rows = r, *cap = (size_t)nrow * ncol;
  }
  for (long r = 0; r < nrow; r++)
    for (size_t k = 0; k < ncol; k++)
      if (fscanf(fp, "%lf", *rows + (size_t)r * ncol + k) != 1) return -1;
  *n = (size_t)nrow;
  return step + 1; /* > 0 */
}

/* Contacts that began: keys of the list not in the previous list.  Pairs
 * (ncol 3: id1 id2 overlap) or wall contacts (ncol 13: wall and particle
 * velocities, mesh, triangle, atom, overlap, normal force); an atom on a mesh
 * is one contact whichever triangles it touches. */
static int count_events(pass *a, const char *path, int wall, gs_error *err) {
  FILE *fp = fopen(path, "r");
  if (!fp) return gs_error_set(err, GS_EIO, "%s: cannot read: %s", path, strerror(errno));
  const size_t ncol = wall ? 13 : 3, cdelta = wall ? 9 : 2;
  double *rows = NULL;
  size_t cap = 0, n = 0, nprev = 0, ncur = 0;
  unsigned long long *prev = NULL, *cur = NULL;
  int rc = GS_OK, first = 1;
  long st;
  while (!rc && (st = gs_lig_next_list(fp, ncol, &rows, &cap, &n)) != 0) {
    unsigned long long *t = st < 0 ? NULL : realloc(cur, (n + 1) * sizeof *cur);
    if (!t) { rc = gs_error_set(err, GS_EINPUT, "%s: unreadable contact list", path); break; }
    cur = t;
    ncur = 0;
    for (size_t r = 0; !rc && r < n; r++) {
      const double *v = rows + r * ncol;
      if (!(v[cdelta] > 0)) continue; /* not overlapping */
      /* atom ids (LIGGGHTS tags are int) and mesh ids below 2^16 make the keys */
      if (!whole(v[wall ? 8 : 0], 2147483647.0) || !whole(v[wall ? 6 : 1], wall ? 65535.0 : 2147483647.0)) {
        rc = gs_error_set(err, GS_EINPUT, "%s: list at step %ld: row %zu: %s %g or %g is not an id", path, st - 1,
                          r + 1, wall ? "atom or mesh id" : "atom id", v[wall ? 8 : 0], v[wall ? 6 : 1]);
        break;
      }
      unsigned long long i1 = (unsigned long long)(wall ? v[8] : v[0]), i2 = (unsigned long long)(wall ? v[6] : v[1]);
      unsigned long long key = wall ? i1 << 16 | i2 : (i1 < i2 ? i1 << 32 | i2 : i2 << 32 | i1);
      if (ncur && cur[ncur - 1] == key) continue; /* the same atom on another triangle of the mesh */
      int dup = 0;
      for (size_t q = ncur; wall && q-- > 0 && cur[q] >> 16 == i1;) dup |= cur[q] == key;
      if (dup) continue;
      cur[ncur++] = key;
      if (first || (nprev && bsearch(&key, prev, nprev, sizeof *prev, cmp_u64))) continue;
      /* the output interval (ts_ev) the event falls in: steps ((k-1) out_k, k out_k] */
      long ko = (st - 1 + a->out_k - 1) / a->out_k;
      /* before the statistics window (statistics.start: steady lists contacts from t = 0)
       * an event counts in the time series only */
      if (st - 1 <= a->k0 || st - 1 > a->k1) {
        size_t w = wall ? (size_t)v[6] : 0;
        if (ko < a->nout && w < a->nw + !wall) a->ts_ev[(wall ? 1 + w : 0) * (size_t)a->nout + (size_t)ko] += 1;
        continue;
      }
      int c1 = class_of(a, wall ? v[8] : v[0]), c2 = wall ? 0 : class_of(a, v[1]);
      if (c1 < 0 || c2 < 0) { a->unknown++; continue; }
      if (!wall) {
        size_t i = (size_t)(c1 < c2 ? c1 : c2), j = (size_t)(c1 < c2 ? c2 : c1);
        a->pair_events[i * a->ncl + j] += 1;
        if (ko < a->nout) a->ts_ev[ko] += 1;
        continue;
      }
      size_t w = (size_t)v[6];
      if (w >= a->nw) continue;
      size_t at = w * a->ncl + (size_t)c1;
      a->wall_contacts[at] += 1;
      if (ko < a->nout) a->ts_ev[(1 + w) * (size_t)a->nout + (size_t)ko] += 1;
      double du[3] = {v[0] - v[3], v[1] - v[4], v[2] - v[5]};
      double u = sqrt(du[0] * du[0] + du[1] * du[1] + du[2] * du[2]);
      if (!isfinite(u)) {
        rc = gs_error_set(err, GS_EINPUT, "%s: list at step %ld: row %zu: a velocity is not finite", path, st - 1, r + 1);
        break;
      }
      /* normal and tangential speed relative to the wall, the normal along the
       * normal force (the spin's part of the contact point's speed is not in the lists) */
      const double fn = sqrt(v[10] * v[10] + v[11] * v[11] + v[12] * v[12]);
      if (!isfinite(fn)) {
        rc = gs_error_set(err, GS_EINPUT, "%s: list at step %ld: row %zu: a force is not finite", path, st - 1, r + 1);
        break;
      }
      if (fn > 0) {
        const double vn = (du[0] * v[10] + du[1] * v[11] + du[2] * v[12]) / fn;
        const double vt = sqrt(fmax(0, u * u - vn * vn));
        a->vn_n[at] += 1, a->vn_s[at] += fabs(vn), a->vn_s2[at] += vn * vn, a->vt_s[at] += vt;
        int b = (int)(fabs(vn) / a->dv);
        if (b >= a->nbins) b = a->nbins - 1;
        a->hist[at * (size_t)a->nbins + (size_t)b] += 1;
      }
      if (!(u >= GS_DEM_MIN_IMPACT_SPEED)) continue; /* resting contacts: no speed, as the embedded engine */
      if (a->nu == a->capu) {
        size_t nc = a->capu ? 2 * a->capu : 1024;
        double *l = realloc(a->ln_u, nc * sizeof(double));
        if (l) a->ln_u = l;
        int *q = realloc(a->u_wc, nc * sizeof(int));
        if (q) a->u_wc = q;
        if (!l || !q) { rc = gs_error_set(err, GS_ENOMEM, "out of memory"); break; }
        a->capu = nc;
      }
      a->ln_u[a->nu] = log(u);
      a->u_wc[a->nu++] = (int)at;
    }
    qsort(cur, ncur, sizeof *cur, cmp_u64);
    if (first && !wall) a->first_list = st - 1;
    unsigned long long *sw = prev;
    prev = cur, nprev = ncur;
    cur = sw;
    first = 0;
  }
  free(rows), free(prev), free(cur);
  fclose(fp);
  return rc;
}

/* impact_table.csv (wall < 0: all walls) or impact_table_WALL.csv */
static int impact_table(const pass *a, const gs_dem_case *c, const char *dir, long wall,
                        double ns, double *rate_all, gs_error *err) {
  const size_t ncl = a->ncl;
  double e[GS_DEM_MAX_CLASSES + 1], rate[GS_DEM_MAX_CLASSES], mu[GS_DEM_MAX_CLASSES], sg[GS_DEM_MAX_CLASSES];
  double *buf = malloc((a->nu + 1) * sizeof(double));
  if (!buf) return gs_error_set(err, GS_ENOMEM, "out of memory");
  gs_dem_class_edges(c, e);
  size_t np = 0;
  for (size_t q = 0; q < a->nu; q++)
    if (wall < 0 || (size_t)a->u_wc[q] / ncl == (size_t)wall) buf[np++] = a->ln_u[q];
  double pmu, psg;
  gs_dem_lognormal_fit(buf, np, &pmu, &psg);
  size_t pooled = 0;
  for (size_t i = 0; i < ncl; i++) {
    double contacts = 0;
    for (size_t w = 0; w < a->nw; w++)
      if (wall < 0 || (size_t)wall == w) contacts += a->wall_contacts[w * ncl + i];
    double Ni = a->num[i] / ns, win = a->t1 - a->t0;
    rate[i] = Ni > 0 ? contacts / (Ni * win) : 0;
    if (rate_all) rate_all[i] = rate[i];
    size_t m = 0;
    for (size_t q = 0; q < a->nu; q++)
      if ((size_t)a->u_wc[q] % ncl == i && (wall < 0 || (size_t)a->u_wc[q] / ncl == (size_t)wall)) buf[m++] = a->ln_u[q];
    gs_dem_lognormal_fit(buf, m, &mu[i], &sg[i]);
    if (!(isfinite(mu[i]) && sg[i] > 0)) mu[i] = pmu, sg[i] = psg, pooled++;
  }
  free(buf);
  char path[4400], comment[2048];
  if (wall < 0) snprintf(path, sizeof path, "%s/impact_table.csv", dir);
  else snprintf(path, sizeof path, "%s/impact_table_%s.csv", dir, c->wall_src[wall].name);
  snprintf(comment, sizeof comment,
           "# gransim dem (engine liggghts): wall impacts (contacts that began) on %s%s, per class, from t = %.9g s;\n"
           "# N_i over %.0f snapshots; rows: impacts per particle per second (impacts / (N_i window));\n"
           "# mu, sigma of the lognormal fit of U = |v - v_wall| at the first contact list holding the impact\n"
           "# (%zu speeds fitted, those slower than %g m/s left out; %zu class(es) take the pooled fit mu %.6g, sigma %.6g)\n",
           wall < 0 ? "all walls" : "wall ", wall < 0 ? "" : c->wall_src[wall].name, a->t0, ns, np,
           GS_DEM_MIN_IMPACT_SPEED, pooled, pmu, psg);
  return gs_dem_impact_table_write(path, comment, ncl, e, 0, rate, mu, sg, err);
}

static int cmp_long(const void *a, const void *b) {
  long x = *(const long *)a, y = *(const long *)b;
  return (x > y) - (x < y);
}

/* The steps from k0 to k1 of the collision<STEP>.atom snapshots in dir, increasing. */
static int snapshot_steps(const char *dir, long k0, long k1, long **out, size_t *n, gs_error *err) {
  DIR *dp = opendir(dir);
  if (!dp) return gs_error_set(err, GS_EIO, "%s: cannot open: %s", dir, strerror(errno));
  size_t cap = 64;
  long *s = malloc(cap * sizeof *s);
  *n = 0;
  for (struct dirent *e; s && (e = readdir(dp));) {
    long st;
    char tail[8];
    if (sscanf(e->d_name, "collision%ld%7s", &st, tail) != 2 || strcmp(tail, ".atom") || st < k0 || st > k1) continue;
    if (*n == cap) {
      long *t = realloc(s, 2 * cap * sizeof *t);
      if (!t) { free(s); s = NULL; break; }
      s = t, cap *= 2;
    }
    s[(*n)++] = st;
  }
  closedir(dp);
  if (!s) return gs_error_set(err, GS_ENOMEM, "out of memory");
  if (!*n) {
    free(s);
    return gs_error_set(err, GS_EINPUT, "%s: LIGGGHTS wrote no collision<STEP>.atom snapshot (is the statistics "
                        "window empty?)", dir);
  }
  qsort(s, *n, sizeof *s, cmp_long);
  *out = s;
  return GS_OK;
}

/* The atoms that left through the outlets in the statistics window: the
 * left<STEP>_<OUTLET>.atom dumps the deck writes before each delete_atoms,
 * with each atom's time in the domain (fix property/atom/regiontracer/time);
 * and how many each dump removed, over the whole run (the lost particles). */
static int residence(pass *a, const char *post, gs_error *err) {
  const long k0 = a->k0;
  DIR *dp = opendir(post);
  if (!dp) return gs_error_set(err, GS_EIO, "%s: cannot open: %s", post, strerror(errno));
  int rc = GS_OK;
  for (struct dirent *e; !rc && (e = readdir(dp));) {
    long st;
    size_t k;
    char tail[8], path[4900];
    if (sscanf(e->d_name, "left%ld_%zu%7s", &st, &k, tail) != 3 || strcmp(tail, ".atom")) continue;
    snprintf(path, sizeof path, "%s/%s", post, e->d_name);
    gs_dump d;
    if ((rc = gs_dump_read(path, &d, err))) break;
    if (a->nleft == a->capleft) {
      size_t cap = a->capleft ? 2 * a->capleft : 256;
      long *t = realloc(a->left_step, cap * sizeof *t);
      if (t) a->left_step = t;
      double *q = realloc(a->left_n, cap * sizeof *q);
      if (q) a->left_n = q;
      if (!t || !q) rc = gs_error_set(err, GS_ENOMEM, "out of memory");
      else a->capleft = cap;
    }
    if (!rc) a->left_step[a->nleft] = st, a->left_n[a->nleft++] = (double)d.nrows;
    if (rc || st <= k0 || st > a->k1) {
      gs_dump_free(&d);
      continue;
    }
    long ct = gs_dump_col(&d, "type"), cm = gs_dump_col(&d, "mass"), cr = gs_dump_col(&d, "f_rtime");
    if (ct < 0 || cm < 0 || cr < 0) rc = gs_error_set(err, GS_EINPUT, "%s: no columns type, mass, f_rtime", path);
    if (!rc && a->nrt + d.nrows > a->caprt) {
      size_t cap = a->caprt ? a->caprt : 256;
      while (cap < a->nrt + d.nrows) cap *= 2;
      double *t = realloc(a->rt, cap * sizeof *t);
      if (t) a->rt = t;
      int *q = realloc(a->rt_cls, cap * sizeof *q);
      if (q) a->rt_cls = q;
      if (!t || !q) rc = gs_error_set(err, GS_ENOMEM, "out of memory");
      else a->caprt = cap;
    }
    for (size_t r = 0; !rc && r < d.nrows; r++) {
      const double *v = d.v + r * d.ncols;
      int cls = (int)v[ct] - 1;
      if (cls < 0 || (size_t)cls >= a->ncl) rc = gs_error_set(err, GS_EINPUT, "%s: type %g is no class", path, v[ct]);
      else a->rt[a->nrt] = v[cr], a->rt_cls[a->nrt++] = cls, a->out_mass += v[cm];
    }
    gs_dump_free(&d);
  }
  closedir(dp);
  return rc;
}

/* The particles lost (left the box other than through an outlet) by thermo
 * row r: those at t = 0 (the bed, and what the feeds inserted then) and
 * inserted since, less those held and those the outlets removed (after the
 * thermo row of their step); *inserted: the particles inserted by then. */
static double lost_at(const pass *a, const gs_lig_thermo *th, size_t r, double dt, double *inserted) {
  const double *v0 = th->row, *v = th->row + th->ncol * r;
  const long step = (long)round(v[0] / dt);
  double gone = 0;
  for (size_t q = 0; q < a->nleft; q++) gone += a->left_step[q] < step ? a->left_n[q] : 0;
  if (inserted) *inserted = v0[1] - v0[8] + v[8];
  return v0[1] - v0[8] + v[8] - v[1] - gone;
}

int gs_lig_reduce(const gs_dem_case *c, const char *out, const gs_lig_thermo *th, const gs_lig_window *wdw,
                  gs_error *err) {
  char post[4400], path[4600];
  snprintf(post, sizeof post, "%s/liggghts/post", out);
  const size_t ncl = c->nclass, nw = c->nwall_src;
  const double dt = c->prm.dt;
  gs_dem_data dd;
  gs_dem_options opt;
  gs_dem_options_default(&opt);
  opt.youngs = c->cls[0].mat.E;
  opt.poisson = c->cls[0].mat.nu;
  opt.density = c->cls[0].mat.density;
  opt.restitution = c->cls[0].mat.e;
  opt.wall_youngs = nw ? c->wall_src[0].mat.E : 0;
  opt.wall_poisson = nw ? c->wall_src[0].mat.nu : 0;
  opt.min_speed = GS_DEM_MIN_IMPACT_SPEED;
  opt.contacts_from = GS_DEM_CONTACTS_PPCOLL;
  opt.quiet = 1;
  /* without walls there is no impact dump: an empty one per snapshot */
  if (!nw) {
    DIR *dp = opendir(post);
    if (!dp) return gs_error_set(err, GS_EIO, "%s: cannot open: %s", post, strerror(errno));
    for (struct dirent *e; (e = readdir(dp));) {
      long st;
      if (sscanf(e->d_name, "collision%ld.atom", &st) != 1) continue;
      snprintf(path, sizeof path, "%s/impact%ld.atom", post, st);
      FILE *fp = fopen(path, "w");
      if (!fp) { closedir(dp); return gs_error_set(err, GS_EIO, "%s: cannot write", path); }
      fprintf(fp, "ITEM: TIMESTEP\n%ld\nITEM: NUMBER OF ENTRIES\n0\nITEM: BOX BOUNDS ff ff ff\n0 1\n0 1\n0 1\n"
              "ITEM: ENTRIES", st);
      for (int q = 1; q <= 17; q++) fprintf(fp, " c_wgl[%d]", q);
      fprintf(fp, "\n");
      fclose(fp);
    }
    closedir(dp);
  }
  /* demdata's snapshot estimate is only a comparison: without it (more than two
   * meshes, or no relative velocities) the tables are written all the same */
  gs_error derr = {0};
  int have_dd = wdw->t_steady < 0 && gs_dem_data_read(post, &opt, &dd, &derr) == GS_OK;
  /* (demdata reads every snapshot: with statistics.start: steady they begin at t = 0) */
  if (wdw->t_steady >= 0) gs_error_set(&derr, GS_EINPUT, "the snapshots of statistics.start: steady span the whole run");
  long *steps = NULL;
  size_t nsnap = 0;
  const long k0 = (long)round(wdw->t0 / dt), k1 = (long)round(wdw->t1 / dt);
  int rc = snapshot_steps(post, k0, k1, &steps, &nsnap, err);
  if (rc) {
    if (have_dd) gs_dem_data_free(&dd);
    return rc;
  }
  pass a = {.ncl = ncl, .ncmp = c->ncmp, .nw = nw, .nbins = 40, .dv = c->prm.impact_dv > 0 ? c->prm.impact_dv : 0.25,
            .k0 = k0, .k1 = k1, .t0 = wdw->t0, .t1 = wdw->t1, .first_list = LONG_MAX};
  size_t nc = ncl * c->ncmp;
  a.num = calloc(ncl, sizeof(double));
  a.cv_n = calloc(nc, sizeof(double)), a.cv_s = calloc(nc, sizeof(double)), a.cv_s2 = calloc(nc, sizeof(double));
  a.cv_a = calloc(nc, sizeof(double)), a.cv_v = calloc(3 * nc, sizeof(double)), a.cv_v2 = calloc(3 * nc, sizeof(double));
  a.wall_contacts = calloc(nw * ncl + 1, sizeof(double));
  a.hist = calloc(nw * ncl * (size_t)a.nbins + 1, sizeof(double));
  a.vn_n = calloc(nw * ncl + 1, sizeof(double)), a.vn_s = calloc(nw * ncl + 1, sizeof(double));
  a.vn_s2 = calloc(nw * ncl + 1, sizeof(double)), a.vt_s = calloc(nw * ncl + 1, sizeof(double));
  a.out_k = (long)fmax(1, round(c->out_every / dt));
  a.nout = (long)ceil(c->duration / dt - 1e-9) / a.out_k + 1;
  a.ts_ev = calloc((1 + nw) * (size_t)a.nout, sizeof(double));
  if (!a.num || !a.cv_n || !a.cv_s || !a.cv_s2 || !a.cv_a || !a.cv_v || !a.cv_v2 || !a.wall_contacts || !a.hist ||
      !a.vn_n || !a.vn_s || !a.vn_s2 || !a.vt_s || !a.ts_ev)
    rc = gs_error_set(err, GS_ENOMEM, "out of memory");
  a.pair_events = calloc(ncl * ncl, sizeof(double));
  if (!rc && !a.pair_events) rc = gs_error_set(err, GS_ENOMEM, "out of memory");
  for (size_t s = 0; !rc && s < nsnap; s++) rc = snapshot(&a, c, post, steps[s], err);
  if (!rc) qsort(a.ids, a.nids, sizeof *a.ids, cmp_id);
  snprintf(path, sizeof path, "%s/events_pp.txt", post);
  if (!rc) rc = count_events(&a, path, 0, err);
  snprintf(path, sizeof path, "%s/events_wall.txt", post);
  if (!rc && nw) rc = count_events(&a, path, 1, err);
  if (!rc && c->noutlets) rc = residence(&a, post, err);
  /* dem.max_lost, as the embedded engine's health check (which stops the run there) */
  for (size_t r = 0; !rc && r < th->n; r++) {
    double ins, lost = lost_at(&a, th, r, dt, &ins);
    if (ins > 0 && lost > c->max_lost * ins)
      rc = gs_error_set(err, GS_ENUMERIC, "DEM (LIGGGHTS): %.0f of the %.0f particles inserted had left the box "
                        "other than through an outlet by t = %g s, more than dem.max_lost = %g of them: they "
                        "escaped through a hole in a wall or were thrown out by overlapping contacts", lost, ins,
                        th->row[th->ncol * r], c->max_lost);
  }
  const double ns = nsnap ? (double)nsnap : 1;
  const double t0 = nsnap ? steps[0] * dt : NAN, t1 = nsnap ? steps[nsnap - 1] * dt : NAN;
  const double win = a.t1 - a.t0;
  FILE *fp = NULL;
  gs_csv_out tab;
  double e[GS_DEM_MAX_CLASSES + 1];
  gs_dem_class_edges(c, e);
  char note[512];
  snprintf(note, sizeof note, "; engine liggghts: contacts that began between contact lists %ld steps apart%s",
           gs_lig_event_every(c), a.unknown ? " (contacts of atoms inserted after the last snapshot left out)" : "");

  /* collisions per class pair */
  double *C = calloc(ncl * ncl, sizeof(double));
  if (!rc && !C) rc = gs_error_set(err, GS_ENOMEM, "out of memory");
  if (!rc && (fp = gs_dem_table_begin(&tab, out, "collisions.csv", err))) {
    fprintf(fp, "# collision events from t = %.9g to %.9g s (%.9g s, %.0f snapshots from t = %.9g to %.9g s)%s\n",
            a.t0, a.t1, win, ns, t0, t1, note);
    /* demdata's estimate from the contact snapshots, for comparison (it
     * over-counts enduring contacts of a resting bed: each counts as a collision per t_c) */
    fprintf(fp, "# contacts / Hertz contact time of the snapshots (src/demdata), C_ij:");
    if (!have_dd) fprintf(fp, " not available (%s)", derr.msg);
    for (size_t i = 0; have_dd && i < ncl; i++)
      for (size_t j = i; j < ncl; j++) {
        double Ni = a.num[i] / ns, Nj = a.num[j] / ns;
        double eps = dd.contacts[i * ncl + j] / dd.pair_contact_time[i * ncl + j];
        fprintf(fp, " %zu-%zu %.6g", i + 1, j + 1, gs_dem_collision_frequency(eps, Ni, Nj, 1, i == j));
      }
    fprintf(fp, "\nclass_i,class_j,name_i,name_j,events,N_i,N_j,window_s,events_per_s,C_ij\n");
    for (size_t i = 0; i < ncl; i++)
      for (size_t j = i; j < ncl; j++) {
        double ev = a.pair_events[i * ncl + j];
        double Ni = a.num[i] / ns, Nj = a.num[j] / ns;
        double cij = gs_dem_collision_frequency(ev, Ni, Nj, win, i == j);
        C[i * ncl + j] = C[j * ncl + i] = cij;
        fprintf(fp, "%zu,%zu,%s,%s,%.0f,%.6g,%.6g,%.9g,%.9g,%.9g\n", i + 1, j + 1, c->cls[i].name, c->cls[j].name,
                ev, Ni, Nj, win, ev / win, cij);
      }
    rc = gs_dem_table_end(&tab, gs_dem_units_collisions, err);
  } else if (!rc) rc = err->code;
  if (!rc && (fp = gs_dem_table_begin(&tab, out, "collision_kernel.csv", err))) {
    fprintf(fp, "# DEM collision frequency C_ij = N_coll,ij / (N_i N_j dt), C_ii = 2 N_coll,ii / (N_i^2 dt) [1/s], "
            "window %.9g s%s;\n"
            "# edges are particle diameters [m]: use `kernel: {type: table, measure: diameter, ...}`\nedges", win, note);
    for (size_t i = 0; i <= ncl; i++) fprintf(fp, ", %.9g", e[i]);
    fprintf(fp, "\n");
    for (size_t i = 0; i < ncl; i++) {
      for (size_t j = 0; j < ncl; j++) fprintf(fp, "%s%.9g", j ? ", " : "", C[i * ncl + j]);
      fprintf(fp, "\n");
    }
    rc = gs_dem_table_end(&tab, gs_dem_units_kernel, err);
  } else if (!rc) rc = err->code;
  free(C);

  /* impacts per wall and class; the breakage selection's tables */
  if (!rc && (fp = gs_dem_table_begin(&tab, out, "impacts.csv", err))) {
    fprintf(fp, "# wall impacts (contacts that began) from t = %.9g to %.9g s (%.9g s)%s; vn: normal speed "
            "relative to the wall, vt: tangential speed relative to the wall without the particle's spin (LIGGGHTS' "
            "contact lists hold no angular velocity), both at the first contact list holding the impact\n",
            a.t0, a.t1, win, note);
    fprintf(fp, "wall,class,name,impacts,impacts_per_s,impacts_per_particle_s,mean_vn,std_vn,mean_vt\n");
    for (size_t w = 0; w < nw; w++)
      for (size_t i = 0; i < ncl; i++) {
        const size_t q = w * ncl + i;
        double Ni = a.num[i] / ns, n = a.wall_contacts[q], m = a.vn_n[q];
        double mv = m > 0 ? a.vn_s[q] / m : NAN, sv = m > 1 ? sqrt(fmax(0, (a.vn_s2[q] - m * mv * mv) / (m - 1))) : NAN;
        fprintf(fp, "%s,%zu,%s,%.0f,%.9g,%.9g,%.6g,%.6g,%.6g\n", c->wall_src[w].name, i + 1, c->cls[i].name, n, n / win,
                Ni > 0 ? n / (Ni * win) : 0, mv, sv, m > 0 ? a.vt_s[q] / m : NAN);
      }
    rc = gs_dem_table_end(&tab, gs_dem_units_impacts, err);
  } else if (!rc) rc = err->code;
  if (!rc) rc = impact_table(&a, c, out, -1, ns, NULL, err);
  for (size_t w = 0; w < nw && !rc; w++) rc = impact_table(&a, c, out, (long)w, ns, NULL, err);
  if (!rc && (fp = gs_dem_table_begin(&tab, out, "impact_velocity.csv", err))) {
    fprintf(fp, "# normal impact speed distributions (the last bin holds everything above); engine liggghts: at the "
            "first contact list holding the impact\n"
            "wall,class,vn_lo,vn_hi,impacts\n");
    for (size_t w = 0; w < nw; w++)
      for (size_t i = 0; i < ncl; i++)
        for (int b = 0; b < a.nbins; b++)
          fprintf(fp, "%s,%zu,%.6g,%.6g,%.0f\n", c->wall_src[w].name, i + 1, b * a.dv,
                  b + 1 < a.nbins ? (b + 1) * a.dv : HUGE_VAL, a.hist[(w * ncl + i) * (size_t)a.nbins + (size_t)b]);
    rc = gs_dem_table_end(&tab, gs_dem_units_impact_velocity, err);
  } else if (!rc) rc = err->code;

  /* velocities per class and compartment */
  if (!rc && (fp = gs_dem_table_begin(&tab, out, "velocity.csv", err))) {
    fprintf(fp, "# over the %.0f snapshots from t = %.9g to %.9g s, every particle of the class in the compartment "
            "once per snapshot: speed |v|, velocity components and the axial component v.axis; std: sample "
            "standard deviation (n - 1); engine liggghts\n", ns, t0, t1);
    fprintf(fp, "class,name,compartment,from,to,mean_number,mean_speed,std_speed,mean_axial_velocity,"
            "mean_vx,mean_vy,mean_vz,std_vx,std_vy,std_vz\n");
    for (size_t i = 0; i < ncl; i++)
      for (size_t q = 0; q < c->ncmp; q++) {
        size_t at = i * c->ncmp + q;
        double n = a.cv_n[at], m = n > 0 ? a.cv_s[at] / n : NAN;
        double sd = n > 1 ? sqrt(fmax(0, (a.cv_s2[at] - n * m * m) / (n - 1))) : NAN;
        fprintf(fp, "%zu,%s,%zu,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g", i + 1, c->cls[i].name, q + 1, c->cmp_edges[q],
                c->cmp_edges[q + 1], n / ns, m, sd, n > 0 ? a.cv_a[at] / n : NAN);
        double mc[3];
        for (int d = 0; d < 3; d++) fprintf(fp, ",%.6g", mc[d] = n > 0 ? a.cv_v[3 * at + d] / n : NAN);
        for (int d = 0; d < 3; d++)
          fprintf(fp, ",%.6g", n > 1 ? sqrt(fmax(0, (a.cv_v2[3 * at + d] - n * mc[d] * mc[d]) / (n - 1))) : NAN);
        fprintf(fp, "\n");
      }
    rc = gs_dem_table_end(&tab, gs_dem_units_velocity, err);
  } else if (!rc) rc = err->code;

  /* residence times: the atoms that left through outlets */
  if (!rc)
    rc = gs_dem_residence_write(c, out, a.rt, a.rt_cls, a.nrt, a.out_mass, a.t0, a.t1, a.hold_n / ns,
                                a.hold_m / ns, "; engine liggghts: outlets emptied every 200 steps, residence time "
                                "from fix property/atom/regiontracer/time", err);

  /* the time series from LIGGGHTS' thermo rows; what it does not report is nan */
  if (!rc && (fp = gs_dem_table_begin(&tab, out, "timeseries.csv", err))) {
    fprintf(fp, "time,particles,holdup_number,holdup_mass,kinetic_energy,rotational_energy,contacts,collisions_per_s");
    for (size_t w = 0; w < nw; w++) fprintf(fp, ",impacts_per_s_%s", c->wall_src[w].name);
    for (size_t w = 0; w < nw; w++) fprintf(fp, ",torque_axis_%s", c->wall_src[w].name);
    fprintf(fp, ",lost,steady,wall_seconds\n");
    for (size_t r = 0; r < th->n; r++) {
      const double *v = th->row + th->ncol * r;
      if (v[0] > a.t1 * (1 + 1e-12)) break; /* past where an observer stopped the run */
      /* event rates of the interval that ends at this row, where the contact
       * lists (from statistics.start on) cover all of it */
      const long step = (long)round(v[0] / dt), ko = step / a.out_k;
      const int have_rate = step > 0 && step - a.out_k >= a.first_list && ko < a.nout;
      const double span = a.out_k * dt;
      fprintf(fp, "%.9g,%.0f,%.0f,%.9g,%.9g,%.9g,%.0f,", v[0], v[1], v[5], v[6], v[2], v[3], v[7]);
      fprintf(fp, have_rate ? "%.9g" : "nan", have_rate ? a.ts_ev[ko] / span : 0.0);
      for (size_t w = 0; w < nw; w++)
        fprintf(fp, have_rate ? ",%.9g" : ",nan", have_rate ? a.ts_ev[(1 + w) * (size_t)a.nout + (size_t)ko] / span : 0.0);
      for (size_t w = 0; w < nw; w++) fprintf(fp, ",%.9g", v[GS_LIG_THERMO_COLS + w]);
      fprintf(fp, ",%.0f,%d,%.6f\n", lost_at(&a, th, r, dt, NULL), wdw->t_steady >= 0 && v[0] >= wdw->t_steady * (1 - 1e-12),
              v[4]);
    }
    const char *names[GS_DEM_CASE_MAX_WALLS];
    for (size_t w = 0; w < nw; w++) names[w] = c->wall_src[w].name;
    rc = gs_dem_table_end(&tab, NULL, err);
    if (!rc)
      rc = gs_dem_timeseries_meta(tab.path, "engine liggghts: LIGGGHTS' thermo rows (pair contacts from compute contact/atom, the "
                                  "torque from fix mesh/surface/stress, lost: inserted minus held minus removed by "
                                  "outlets); steady: 1 from the time the steady-state detector fired (statistics.start: steady only)",
                                  nw, names, err);
  } else if (!rc) rc = err->code;

  free(a.num), free(a.cv_n), free(a.cv_s), free(a.cv_s2), free(a.cv_a), free(a.cv_v), free(a.cv_v2);
  free(a.wall_contacts), free(a.ln_u), free(a.u_wc), free(a.hist), free(a.pair_events), free(a.ids);
  free(a.rt), free(a.rt_cls), free(a.left_step), free(a.left_n), free(a.vn_n), free(a.vn_s), free(a.vn_s2), free(a.vt_s), free(a.ts_ev);
  if (have_dd) gs_dem_data_free(&dd);
  free(steps);
  if (rc) gs_lig_remove_tables(c, out); /* all the tables or none */
  return rc;
}
