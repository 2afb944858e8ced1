/* Reduction of LIGGGHTS contact dumps to PBM collision and impact rates
 * (include/gransim/dem_data.h; docs/models.md, "DEM data reduction"). */
#include "gransim/dem_data.h"

#include <dirent.h>
#include <errno.h>
#include <gsl/gsl_cdf.h>
#include <gsl/gsl_statistics_double.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "demdata/csv_meta.h"
#include "demdata/dump.h"

void gs_dem_options_default(gs_dem_options *o) {
  memset(o, 0, sizeof *o);
  o->youngs = 8e6;
  o->poisson = 0.2;
  o->density = 500;
  o->restitution = 0.4;
  o->wall_youngs = 9.99e8;
  o->wall_poisson = 0.2;
  o->min_speed = 1e-3;
}

/* ---- Hertz contact duration ------------------------------------------------
 * In units delta0 = (v^2 m* / (4/3 E* sqrt R*))^(2/5), T = delta0 / v the
 * head-on impact is xi'' = -xi^(3/2) - c sqrt(3/2) xi^(1/4) xi', xi(0) = 0,
 * xi'(0) = 1 (the damping gamma = c sqrt(2 E* sqrt(R* delta) m*) of LIGGGHTS
 * and src/dem).  The contact lasts until xi is back to 0: tau(c) T.  For c = 0
 * tau = 3.2181 and tau (3/4)^(2/5) = 2.868, the classical constant. */
static double scaled_duration(double c) {
  double tau;
  gs_dem_scaled_impact(c, 1e-4, &tau, NULL);
  return tau;
}

/* t_c / (m*^2/(R* E*^2 v))^(1/5) for restitution e (no state: safe from any thread) */
static double duration_factor(double e) {
  double c = (e > 0 && e < 1) ? gs_dem_damping_coefficient(e, GS_DEM_DAMPING_LIGGGHTS) : 0;
  return c == 0 ? 2.868 : scaled_duration(c) * pow(0.75, 0.4);
}

static double hertz_time(double factor, double meff, double reff, double estar, double v) {
  if (!(meff > 0 && reff > 0 && estar > 0 && v > 0)) return NAN;
  return factor * pow(meff * meff / (reff * estar * estar * v), 0.2);
}

double gs_dem_hertz_contact_time(double meff, double reff, double estar, double v, double e) {
  return hertz_time(duration_factor(e), meff, reff, estar, v);
}

/* ---- files of a directory ------------------------------------------------- */
typedef struct {
  long step;
  int has_impact, has_pp;
} snap_file;

static int cmp_step(const void *a, const void *b) {
  long x = ((const snap_file *)a)->step, y = ((const snap_file *)b)->step;
  return (x > y) - (x < y);
}

/* "<prefix><digits>.atom" -> step, or -1. */
static long file_step(const char *name, const char *prefix) {
  size_t lp = strlen(prefix);
  if (strncmp(name, prefix, lp) || name[lp] < '0' || name[lp] > '9') return -1;
  char *end;
  long s = strtol(name + lp, &end, 10);
  return strcmp(end, ".atom") ? -1 : s;
}

static int list_snapshots(const char *dir, snap_file **out, size_t *nout, int quiet, gs_error *err) {
  DIR *dp = opendir(dir);
  if (!dp) return gs_error_set(err, GS_EIO, "%s: cannot open DEM dump directory: %s", dir, strerror(errno));
  size_t n = 0, cap = 16;
  long *imp = NULL, *pp = NULL;
  size_t nimp = 0, npp = 0, capi = 16, capp = 16;
  snap_file *s = malloc(cap * sizeof *s);
  imp = malloc(capi * sizeof *imp);
  pp = malloc(capp * sizeof *pp);
  int rc = (!s || !imp || !pp) ? gs_error_set(err, GS_ENOMEM, "out of memory") : GS_OK;
  for (struct dirent *e; !rc && (e = readdir(dp));) {
    long st;
    if ((st = file_step(e->d_name, "collision")) >= 0) {
      if (n == cap) { snap_file *t = realloc(s, 2 * cap * sizeof *s); if (!t) { rc = GS_ENOMEM; break; } s = t; cap *= 2; }
      s[n++] = (snap_file){st, 0, 0};
    } else if ((st = file_step(e->d_name, "impact")) >= 0) {
      if (nimp == capi) { long *t = realloc(imp, 2 * capi * sizeof *t); if (!t) { rc = GS_ENOMEM; break; } imp = t; capi *= 2; }
      imp[nimp++] = st;
    } else if ((st = file_step(e->d_name, "ppcoll")) >= 0) {
      if (npp == capp) { long *t = realloc(pp, 2 * capp * sizeof *t); if (!t) { rc = GS_ENOMEM; break; } pp = t; capp *= 2; }
      pp[npp++] = st;
    }
  }
  closedir(dp);
  if (rc == GS_ENOMEM) gs_error_set(err, GS_ENOMEM, "out of memory");
  size_t m = 0;
  for (size_t i = 0; !rc && i < n; i++) {
    for (size_t k = 0; k < nimp; k++) if (imp[k] == s[i].step) s[i].has_impact = 1;
    for (size_t k = 0; k < npp; k++) if (pp[k] == s[i].step) s[i].has_pp = 1;
    if (s[i].has_impact) s[m++] = s[i];
    else if (!quiet)
      fprintf(stderr, "gransim: warning: %s/collision%ld.atom has no impact%ld.atom; step skipped\n", dir,
              s[i].step, s[i].step);
  }
  if (!rc && !quiet)
    for (size_t k = 0; k < nimp; k++) {
      int found = 0;
      for (size_t i = 0; i < m; i++) found |= s[i].step == imp[k];
      if (!found) fprintf(stderr, "gransim: warning: %s/impact%ld.atom has no collision%ld.atom; step skipped\n",
                          dir, imp[k], imp[k]);
    }
  free(imp);
  free(pp);
  if (!rc && !m)
    rc = gs_error_set(err, GS_EINPUT, "%s: no pair of collision<STEP>.atom and impact<STEP>.atom dumps with "
                      "the same STEP", dir);
  if (rc) { free(s); return rc; }
  qsort(s, m, sizeof *s, cmp_step);
  *out = s;
  *nout = m;
  return GS_OK;
}

/* ---- one snapshot ------------------------------------------------------------ */
typedef struct {
  long id;
  int type;
} id_type;

static int cmp_id(const void *a, const void *b) {
  long x = ((const id_type *)a)->id, y = ((const id_type *)b)->id;
  return (x > y) - (x < y);
}

static int type_of(const id_type *map, size_t n, long id) {
  id_type key = {id, 0};
  const id_type *f = bsearch(&key, map, n, sizeof *map, cmp_id);
  return f ? f->type : -1;
}

typedef struct {
  size_t n;             /* classes */
  size_t nsnap;
  double *N;            /* nsnap * n */
  double *S;            /* nsnap * n * n raw sums */
  double *P;            /* nsnap * n * n ppcoll contacts per type pair (i <= j and mirrored) */
  double *W;            /* nsnap * n * 2 wall contacts: shell, impeller */
  double *rsum, *rcnt;  /* radius sums per class */
  double *ln_u;         /* impact speed samples (ln), with class */
  size_t *u_cls, nu, capu;
  double pp_sum, wall_sum; /* sums of u^(1/5) */
  size_t pp_n, wall_n;
  double vs[3], vs2;    /* particle velocity sums (fluctuation fallback) */
  size_t nv;
} accum;

static int is_count(double x) { return x >= 0 && x == floor(x); }

static int read_collision(const char *path, const char *prefix, accum *a, size_t snap, id_type **map,
                          size_t *nmap, gs_error *err) {
  gs_dump d;
  int rc = gs_dump_read(path, &d, err);
  if (rc) return rc;
  const char *need[] = {"id", "type", "vx", "vy", "vz", "radius"};
  long col[6];
  for (int k = 0; k < 6 && !rc; k++)
    if ((col[k] = gs_dump_col(&d, need[k])) < 0)
      rc = gs_error_set(err, GS_EINPUT, "%s:%ld: no column '%s' in the ITEM: ATOMS line (expected id, type, "
                        "vx, vy, vz, radius and %s1..%sN)", path, d.first_row_line - 1, need[k], prefix, prefix);
  size_t n = 0;
  long *cc = NULL;
  char name[256];
  for (;;) {
    snprintf(name, sizeof name, "%s%zu", prefix, n + 1);
    if (gs_dump_col(&d, name) < 0) break;
    n++;
  }
  if (!rc && !n)
    rc = gs_error_set(err, GS_EINPUT, "%s:%ld: no column '%s1' (contacts with type-1 atoms; compute "
                      "contact/atom per type group)", path, d.first_row_line - 1, prefix);
  if (!rc && a->n && n != a->n)
    rc = gs_error_set(err, GS_EINPUT, "%s:%ld: %zu contact columns %s1..%s%zu, but the first snapshot had %zu",
                      path, d.first_row_line - 1, n, prefix, prefix, n, a->n);
  if (!rc && !a->n) {
    a->n = n;
    a->N = calloc(a->nsnap * n, sizeof(double));
    a->S = calloc(a->nsnap * n * n, sizeof(double));
    a->W = calloc(a->nsnap * n * 2, sizeof(double));
    a->P = calloc(a->nsnap * n * n, sizeof(double));
    a->rsum = calloc(n, sizeof(double));
    a->rcnt = calloc(n, sizeof(double));
    if (!a->N || !a->S || !a->W || !a->P || !a->rsum || !a->rcnt) rc = gs_error_set(err, GS_ENOMEM, "out of memory");
  }
  if (!rc && !(cc = malloc(n * sizeof(long)))) rc = gs_error_set(err, GS_ENOMEM, "out of memory");
  for (size_t k = 0; !rc && k < n; k++) {
    snprintf(name, sizeof name, "%s%zu", prefix, k + 1);
    cc[k] = gs_dump_col(&d, name);
  }
  free(*map);
  *map = NULL;
  if (!rc && !(*map = malloc((d.nrows ? d.nrows : 1) * sizeof(id_type))))
    rc = gs_error_set(err, GS_ENOMEM, "out of memory");
  double *N = rc ? NULL : a->N + snap * n, *S = rc ? NULL : a->S + snap * n * n;
  for (size_t r = 0; !rc && r < d.nrows; r++) {
    const double *v = d.v + r * d.ncols;
    long line = d.first_row_line + (long)r;
    double t = v[col[1]], rad = v[col[5]];
    if (!(t >= 1 && t <= (double)n && t == floor(t))) {
      rc = gs_error_set(err, GS_EINPUT, "%s:%ld: type %g: expected an integer 1..%zu (one type per %s column)",
                        path, line, t, n, prefix);
      break;
    }
    if (!(rad > 0)) { rc = gs_error_set(err, GS_EINPUT, "%s:%ld: radius %g: expected > 0", path, line, rad); break; }
    if (!is_count(v[col[0]])) { rc = gs_error_set(err, GS_EINPUT, "%s:%ld: id %g: expected an integer >= 0", path, line, v[col[0]]); break; }
    size_t i = (size_t)t - 1;
    (*map)[r] = (id_type){(long)v[col[0]], (int)i};
    N[i] += 1;
    a->rsum[i] += rad;
    a->rcnt[i] += 1;
    for (int x = 0; x < 3; x++) a->vs[x] += v[col[2 + x]];
    a->vs2 += v[col[2]] * v[col[2]] + v[col[3]] * v[col[3]] + v[col[4]] * v[col[4]];
    a->nv++;
    for (size_t j = 0; j < n; j++) {
      double c = v[cc[j]];
      if (!is_count(c)) {
        rc = gs_error_set(err, GS_EINPUT, "%s:%ld: %s%zu = %g: expected a contact count (integer >= 0)", path,
                          line, prefix, j + 1, c);
        break;
      }
      S[i * n + j] += c;
    }
  }
  if (!rc) {
    *nmap = d.nrows;
    qsort(*map, d.nrows, sizeof(id_type), cmp_id);
    for (size_t r = 1; !rc && r < d.nrows; r++)
      if ((*map)[r].id == (*map)[r - 1].id)
        rc = gs_error_set(err, GS_EINPUT, "%s: atom id %ld appears twice", path, (*map)[r].id);
  }
  free(cc);
  gs_dump_free(&d);
  return rc;
}

/* Columns 1..14 of a local dump, located by their "[k]" suffix: those of the
 * keywords id vel force contactArea delta, or with force_normal too (17
 * columns, as gransim's decks write wall contacts: contact area and overlap
 * are then [16] and [17]). */
static int local_columns(const gs_dump *d, long col[14], const char *what, gs_error *err) {
  if (d->ncols != 14 && d->ncols != 17)
    return gs_error_set(err, GS_EINPUT, "%s:%ld: %zu columns, expected the 14 of %s (keywords id vel force "
                        "contactArea delta) or 17 (id vel force force_normal contactArea delta)", d->path,
                        d->first_row_line - 1, d->ncols, what);
  for (int k = 0; k < 14; k++)
    if ((col[k] = gs_dump_col_index(d, k < 12 || d->ncols == 14 ? k + 1 : k + 3)) < 0)
      return gs_error_set(err, GS_EINPUT, "%s:%ld: no column named '...[%d]' (expected c_<compute>[1] .. [14] "
                          "of %s)", d->path, d->first_row_line - 1, k + 1, what);
  return GS_OK;
}

static int push_speed(accum *a, size_t cls, double u) {
  if (a->nu == a->capu) {
    size_t cap = a->capu ? 2 * a->capu : 1024;
    double *l = realloc(a->ln_u, cap * sizeof(double));
    if (l) a->ln_u = l;
    size_t *c = realloc(a->u_cls, cap * sizeof(size_t));
    if (c) a->u_cls = c;
    if (!l || !c) return GS_ENOMEM;
    a->capu = cap;
  }
  a->ln_u[a->nu] = log(u);
  a->u_cls[a->nu++] = cls;
  return GS_OK;
}

static int read_impact(const char *path, long step, accum *a, size_t snap, const id_type *map, size_t nmap,
                       double min_speed, size_t *nresting, gs_error *err) {
  gs_dump d;
  long col[14];
  int rc = gs_dump_read(path, &d, err);
  if (rc) return rc;
  rc = local_columns(&d, col, "compute wall/gran/local", err);
  if (!rc && d.step != step)
    rc = gs_error_set(err, GS_EINPUT, "%s: ITEM: TIMESTEP is %ld but the file name says %ld", path, d.step, step);
  double *W = a->W + snap * a->n * 2;
  for (size_t r = 0; !rc && r < d.nrows; r++) {
    const double *v = d.v + r * d.ncols;
    long line = d.first_row_line + (long)r;
    double mesh = v[col[6]], id = v[col[8]];
    if (!(mesh == 0 || mesh == 1)) {
      rc = gs_error_set(err, GS_EINPUT, "%s:%ld: column 7 (impact type / mesh) = %g: expected 0 (static shell) or "
                        "1 (moving mesh)", path, line, mesh);
      break;
    }
    int t = is_count(id) ? type_of(map, nmap, (long)id) : -1;
    if (t < 0) {
      rc = gs_error_set(err, GS_EINPUT, "%s:%ld: column 9 (atom id) = %g: no such atom in collision%ld.atom",
                        path, line, id, step);
      break;
    }
    W[(size_t)t * 2 + (mesh == 1)] += 1;
    double du[3] = {v[col[3]] - v[col[0]], v[col[4]] - v[col[1]], v[col[5]] - v[col[2]]};
    double u = sqrt(du[0] * du[0] + du[1] * du[1] + du[2] * du[2]);
    a->wall_sum += pow(u, 0.2);
    a->wall_n++;
    if (u > 0 && u >= min_speed) {
      if (push_speed(a, (size_t)t, u)) rc = gs_error_set(err, GS_ENOMEM, "out of memory");
    } else (*nresting)++;
  }
  gs_dump_free(&d);
  return rc;
}

static int read_ppcoll(const char *path, long step, accum *a, size_t snap, const id_type *map, size_t nmap,
                       gs_error *err) {
  gs_dump d;
  long col[14];
  int rc = gs_dump_read(path, &d, err);
  if (rc) return rc;
  rc = local_columns(&d, col, "compute pair/gran/local", err);
  if (!rc && d.step != step)
    rc = gs_error_set(err, GS_EINPUT, "%s: ITEM: TIMESTEP is %ld but the file name says %ld", path, d.step, step);
  size_t n = a->n;
  double *P = a->P + snap * n * n;
  for (size_t r = 0; !rc && r < d.nrows; r++) {
    const double *v = d.v + r * d.ncols;
    double id1 = v[col[6]], id2 = v[col[7]];
    int t1 = is_count(id1) ? type_of(map, nmap, (long)id1) : -1;
    int t2 = is_count(id2) ? type_of(map, nmap, (long)id2) : -1;
    if (t1 < 0 || t2 < 0) {
      rc = gs_error_set(err, GS_EINPUT, "%s:%ld: column %d (atom id) = %g: no such atom in collision%ld.atom",
                        path, d.first_row_line + (long)r, t1 < 0 ? 7 : 8, t1 < 0 ? id1 : id2, step);
      break;
    }
    if (v[col[13]] > 0) { /* overlapping: a current contact */
      P[(size_t)t1 * n + (size_t)t2] += 1;
      if (t1 != t2) P[(size_t)t2 * n + (size_t)t1] += 1;
    }
    int zero = 1;
    for (int k = 0; k < 6; k++) zero &= v[col[k]] == 0;
    if (zero) continue; /* velocities not written for this contact */
    double du[3] = {v[col[0]] - v[col[3]], v[col[1]] - v[col[4]], v[col[2]] - v[col[5]]};
    a->pp_sum += pow(sqrt(du[0] * du[0] + du[1] * du[1] + du[2] * du[2]), 0.2);
    a->pp_n++;
  }
  gs_dump_free(&d);
  return rc;
}

/* ---- the reduction --------------------------------------------------------------- */
void gs_dem_data_free(gs_dem_data *d) {
  if (!d) return;
  free(d->steps); free(d->diameter); free(d->count); free(d->count_sd);
  free(d->pair_contact_time); free(d->wall_contact_time); free(d->contacts); free(d->cc_sum);
  free(d->collision); free(d->collision_sd); free(d->impact_rate); free(d->impact_rate_sd);
  free(d->impeller_rate); free(d->shell_rate); free(d->wall_contacts); free(d->nvel);
  free(d->vel_mu); free(d->vel_sigma); free(d->edges);
  memset(d, 0, sizeof *d);
}

static void accum_free(accum *a) {
  free(a->N); free(a->S); free(a->P); free(a->W); free(a->rsum); free(a->rcnt); free(a->ln_u); free(a->u_cls);
}

/* mean and sample sd of the finite values x[k*stride], k < n */
static void mean_sd(const double *x, size_t stride, size_t n, double *buf, double *mean, double *sd) {
  size_t m = 0;
  for (size_t k = 0; k < n; k++)
    if (isfinite(x[k * stride])) buf[m++] = x[k * stride];
  *mean = m ? gsl_stats_mean(buf, 1, m) : 0;
  *sd = m > 1 ? gsl_stats_sd_m(buf, 1, m, *mean) : 0;
}

static int alloc_out(gs_dem_data *o, size_t n, size_t ns, gs_error *err) {
  o->nclass = n;
  o->nsnap = ns;
  o->steps = calloc(ns, sizeof(long));
  o->diameter = calloc(n, sizeof(double));
  o->count = calloc(n, sizeof(double));
  o->count_sd = calloc(n, sizeof(double));
  o->pair_contact_time = calloc(n * n, sizeof(double));
  o->wall_contact_time = calloc(n, sizeof(double));
  o->contacts = calloc(n * n, sizeof(double));
  o->cc_sum = calloc(n * n, sizeof(double));
  o->collision = calloc(n * n, sizeof(double));
  o->collision_sd = calloc(n * n, sizeof(double));
  o->impact_rate = calloc(n, sizeof(double));
  o->impact_rate_sd = calloc(n, sizeof(double));
  o->impeller_rate = calloc(n, sizeof(double));
  o->shell_rate = calloc(n, sizeof(double));
  o->wall_contacts = calloc(n, sizeof(double));
  o->nvel = calloc(n, sizeof(size_t));
  o->vel_mu = calloc(n, sizeof(double));
  o->vel_sigma = calloc(n, sizeof(double));
  if (!o->steps || !o->diameter || !o->count || !o->count_sd || !o->pair_contact_time ||
      !o->wall_contact_time || !o->contacts || !o->cc_sum || !o->collision || !o->collision_sd || !o->impact_rate ||
      !o->impact_rate_sd || !o->impeller_rate || !o->shell_rate || !o->wall_contacts || !o->nvel ||
      !o->vel_mu || !o->vel_sigma)
    return gs_error_set(err, GS_ENOMEM, "out of memory");
  return GS_OK;
}

double gs_dem_collision_frequency(double events, double Ni, double Nj, double window, int same_class) {
  if (!(Ni > 0 && Nj > 0)) return 0;
  return (same_class ? 2 : 1) * events / (Ni * Nj * window);
}

void gs_dem_lognormal_fit(const double *ln_u, size_t n, double *mu, double *sigma) {
  if (n < 2) { *mu = *sigma = NAN; return; }
  *mu = gsl_stats_mean(ln_u, 1, n);
  *sigma = gsl_stats_sd_m(ln_u, 1, n, *mu);
}

static int check_options(const gs_dem_options *o, gs_error *err) {
  if (o->contact_time < 0 || !isfinite(o->contact_time))
    return gs_error_set(err, GS_EINPUT, "contact_time = %g: expected > 0 (given) or 0 (Hertz theory)", o->contact_time);
  if (o->contact_time == 0) {
    if (!(o->youngs > 0)) return gs_error_set(err, GS_EINPUT, "Young's modulus %g: expected > 0", o->youngs);
    if (!(o->poisson > -1 && o->poisson < 0.5)) return gs_error_set(err, GS_EINPUT, "Poisson's ratio %g: expected in (-1, 0.5)", o->poisson);
    if (!(o->density > 0)) return gs_error_set(err, GS_EINPUT, "density %g: expected > 0", o->density);
    if (!(o->restitution >= 0 && o->restitution <= 1)) return gs_error_set(err, GS_EINPUT, "restitution %g: expected in [0, 1]", o->restitution);
    if (!(o->wall_youngs >= 0)) return gs_error_set(err, GS_EINPUT, "wall Young's modulus %g: expected > 0, or 0 (rigid)", o->wall_youngs);
    if (!(o->wall_poisson > -1 && o->wall_poisson < 0.5)) return gs_error_set(err, GS_EINPUT, "wall Poisson's ratio %g: expected in (-1, 0.5)", o->wall_poisson);
  }
  if (o->contacts_from < GS_DEM_CONTACTS_AUTO || o->contacts_from > GS_DEM_CONTACTS_CC_PARTNER)
    return gs_error_set(err, GS_EINPUT, "contacts_from = %d: expected one of GS_DEM_CONTACTS_*", o->contacts_from);
  if (!(o->min_speed >= 0)) return gs_error_set(err, GS_EINPUT, "min_speed %g: expected >= 0", o->min_speed);
  return GS_OK;
}

int gs_dem_data_read(const char *dir, const gs_dem_options *opt_in, gs_dem_data *out, gs_error *err) {
  gs_dem_options opt;
  if (opt_in) opt = *opt_in;
  else gs_dem_options_default(&opt);
  memset(out, 0, sizeof *out);
  const char *prefix = opt.contact_prefix ? opt.contact_prefix : "c_cc_";
  int rc = check_options(&opt, err);
  if (rc) return rc;
  snap_file *files = NULL;
  size_t ns = 0;
  if ((rc = list_snapshots(dir, &files, &ns, opt.quiet, err))) return rc;
  int src = opt.contacts_from;
  size_t missing_pp = ns;
  for (size_t s = 0; s < ns; s++)
    if (!files[s].has_pp && missing_pp == ns) missing_pp = s;
  if (src == GS_DEM_CONTACTS_AUTO) src = missing_pp == ns ? GS_DEM_CONTACTS_PPCOLL : GS_DEM_CONTACTS_CC_OWNER;
  if (src == GS_DEM_CONTACTS_PPCOLL && missing_pp < ns) {
    rc = gs_error_set(err, GS_EINPUT, "%s/ppcoll%ld.atom: missing, but the contacts are to come from the ppcoll "
                      "pair dumps", dir, files[missing_pp].step);
    free(files);
    return rc;
  }
  if (opt.contacts_from == GS_DEM_CONTACTS_AUTO && missing_pp < ns && !opt.quiet)
    fprintf(stderr, "gransim: warning: %s/ppcoll%ld.atom missing: contacts from the per-type contact columns "
            "(like-type contacts may be missing from them; docs/models.md)\n", dir, files[missing_pp].step);
  accum a;
  memset(&a, 0, sizeof a);
  a.nsnap = ns;
  id_type *map = NULL;
  size_t nmap = 0, nresting = 0;
  char path[4096];
  for (size_t s = 0; !rc && s < ns; s++) {
    long st = files[s].step;
    snprintf(path, sizeof path, "%s/collision%ld.atom", dir, st);
    rc = read_collision(path, prefix, &a, s, &map, &nmap, err);
    snprintf(path, sizeof path, "%s/impact%ld.atom", dir, st);
    if (!rc) rc = read_impact(path, st, &a, s, map, nmap, opt.min_speed, &nresting, err);
    snprintf(path, sizeof path, "%s/ppcoll%ld.atom", dir, st);
    if (!rc && files[s].has_pp) rc = read_ppcoll(path, st, &a, s, map, nmap, err);
  }
  free(map);
  size_t n = a.n;
  double *buf = NULL, *per = NULL;
  if (!rc) rc = alloc_out(out, n, ns, err);
  if (!rc && (!(buf = malloc((ns + a.nu + 1) * sizeof(double))) || !(per = malloc(ns * n * n * sizeof(double)))))
    rc = gs_error_set(err, GS_ENOMEM, "out of memory");
  if (rc) {
    free(files); free(buf); free(per); accum_free(&a); gs_dem_data_free(out);
    return rc;
  }
  for (size_t s = 0; s < ns; s++) out->steps[s] = files[s].step;
  free(files);
  out->nresting = nresting;
  out->contacts_from = src;

  /* classes: diameter, mass */
  for (size_t i = 0; i < n; i++) {
    out->diameter[i] = a.rcnt[i] > 0 ? 2 * a.rsum[i] / a.rcnt[i] : NAN;
    mean_sd(a.N + i, n, ns, buf, &out->count[i], &out->count_sd[i]);
  }

  /* effective velocities and contact durations */
  out->nv_pair = a.pp_n;
  out->nv_wall = a.wall_n;
  if (opt.contact_time > 0) {
    out->v_pair_source = "given";
    for (size_t k = 0; k < n * n; k++) out->pair_contact_time[k] = opt.contact_time;
    for (size_t i = 0; i < n; i++) out->wall_contact_time[i] = opt.contact_time;
  } else {
    if (a.pp_n) {
      out->v_pair = pow(a.pp_sum / (double)a.pp_n, 5);
      out->v_pair_source = "ppcoll relative velocities";
    } else if (a.nv) {
      double m2 = 0;
      for (int x = 0; x < 3; x++) m2 += (a.vs[x] / (double)a.nv) * (a.vs[x] / (double)a.nv);
      out->v_pair = sqrt(2 * fmax(a.vs2 / (double)a.nv - m2, 0));
      out->nv_pair = a.nv;
      out->v_pair_source = "particle velocity fluctuations";
    }
    out->v_wall = a.wall_n ? pow(a.wall_sum / (double)a.wall_n, 5) : out->v_pair;
    double f = 2 * (1 - opt.poisson * opt.poisson) / opt.youngs;
    double estar = 1 / f;
    double fw = (1 - opt.poisson * opt.poisson) / opt.youngs +
                (opt.wall_youngs > 0 ? (1 - opt.wall_poisson * opt.wall_poisson) / opt.wall_youngs : 0);
    double factor = duration_factor(opt.restitution);
    for (size_t i = 0; i < n; i++) {
      double ri = out->diameter[i] / 2, mi = opt.density * 4.0 / 3.0 * M_PI * ri * ri * ri;
      out->wall_contact_time[i] = hertz_time(factor, mi, ri, 1 / fw, out->v_wall);
      for (size_t j = 0; j < n; j++) {
        double rj = out->diameter[j] / 2, mj = opt.density * 4.0 / 3.0 * M_PI * rj * rj * rj;
        out->pair_contact_time[i * n + j] =
            hertz_time(factor, mi * mj / (mi + mj), ri * rj / (ri + rj), estar, out->v_pair);
      }
    }
    if (!(out->v_pair > 0) || !(out->v_wall > 0)) {
      gs_dem_data_free(out);
      free(buf); free(per); accum_free(&a);
      return gs_error_set(err, GS_EINPUT, "%s: no relative velocities to estimate the Hertz contact time from "
                          "(no ppcoll rows with velocities and no moving particles); give a contact time", dir);
    }
  }
  out->contact_time = out->pair_contact_time[0];

  /* current contacts K_ij per snapshot, then C_ij = E_ij/(N_i N_j), C_ii = 2 E_ii/N_i^2, E = K/t_c */
  double asym = 0, offd = 0, like_cc = 0, all_cc = 0, like_pp = 0, all_pp = 0;
  double *K = malloc(n * n * sizeof(double));
  if (!K) {
    gs_dem_data_free(out); free(buf); free(per); accum_free(&a);
    return gs_error_set(err, GS_ENOMEM, "out of memory");
  }
  for (size_t s = 0; s < ns; s++) {
    const double *S = a.S + s * n * n, *N = a.N + s * n, *P = a.P + s * n * n;
    double *C = per + s * n * n;
    for (size_t i = 0; i < n; i++) {
      double R = 0, off = 0;
      for (size_t j = 0; j < n; j++) {
        R += S[i * n + j];
        if (j != i) off += S[i * n + j] + S[j * n + i];
        if (j != i) { asym += fabs(S[i * n + j] - S[j * n + i]); offd += S[i * n + j]; }
        out->cc_sum[i * n + j] += S[i * n + j] / (double)ns;
        if (j >= i) { all_pp += P[i * n + j]; if (j == i) like_pp += P[i * n + j]; }
        if (j > i) all_cc += S[i * n + j] + S[j * n + i];
      }
      double kii = 0.5 * (R - off);
      like_cc += kii;
      all_cc += kii;
      for (size_t j = 0; j < n; j++) {
        double k;
        if (src == GS_DEM_CONTACTS_PPCOLL) k = P[i * n + j];
        else if (src == GS_DEM_CONTACTS_CC_OWNER) k = i == j ? fmax(kii, 0) : S[i * n + j] + S[j * n + i];
        else k = i == j ? 0.5 * S[i * n + i] : 0.5 * (S[i * n + j] + S[j * n + i]);
        K[i * n + j] = k;
      }
    }
    for (size_t i = 0; i < n; i++)
      for (size_t j = 0; j < n; j++) {
        double E = K[i * n + j] / out->pair_contact_time[i * n + j];
        /* undefined without particles */
        C[i * n + j] = N[i] > 0 && N[j] > 0 ? gs_dem_collision_frequency(E, N[i], N[j], 1, i == j) : NAN;
        out->contacts[i * n + j] += K[i * n + j] / (double)ns;
      }
  }
  free(K);
  out->like_share_cc = all_cc > 0 ? like_cc / all_cc : NAN;
  out->like_share_pp = missing_pp == ns && all_pp > 0 ? like_pp / all_pp : NAN;
  out->asymmetry = offd > 0 ? asym / offd : 0;
  for (size_t k = 0; k < n * n; k++) mean_sd(per + k, n * n, ns, buf, &out->collision[k], &out->collision_sd[k]);
  for (size_t i = 0; i < n; i++) /* exact symmetry (the per-snapshot values already are) */
    for (size_t j = 0; j < i; j++) {
      out->collision[j * n + i] = out->collision[i * n + j];
      out->collision_sd[j * n + i] = out->collision_sd[i * n + j];
    }

  /* wall impacts per particle per second */
  for (int which = 0; which < 3; which++)
    for (size_t i = 0; i < n; i++) {
      for (size_t s = 0; s < ns; s++) {
        const double *W = a.W + (s * n + i) * 2;
        double c = which == 0 ? W[0] + W[1] : which == 1 ? W[1] : W[0];
        double Ni = a.N[s * n + i];
        per[s] = Ni > 0 ? c / out->wall_contact_time[i] / Ni : NAN;
        if (which == 0) out->wall_contacts[i] += c / (double)ns;
      }
      double mean, sd;
      mean_sd(per, 1, ns, buf, &mean, &sd);
      if (which == 0) { out->impact_rate[i] = mean; out->impact_rate_sd[i] = sd; }
      else if (which == 1) out->impeller_rate[i] = mean;
      else out->shell_rate[i] = mean;
    }

  /* lognormal fits of the impact speeds */
  for (size_t i = 0; i < n; i++) {
    size_t m = 0;
    for (size_t k = 0; k < a.nu; k++)
      if (a.u_cls[k] == i) buf[m++] = a.ln_u[k];
    out->nvel[i] = m;
    gs_dem_lognormal_fit(buf, m, &out->vel_mu[i], &out->vel_sigma[i]);
  }
  out->all_nvel = a.nu;
  gs_dem_lognormal_fit(a.ln_u, a.nu, &out->all_mu, &out->all_sigma);

  if (opt.edges) {
    if (!(out->edges = malloc((n + 1) * sizeof(double)))) rc = gs_error_set(err, GS_ENOMEM, "out of memory");
    else memcpy(out->edges, opt.edges, (n + 1) * sizeof(double));
    out->edges_volume = opt.edges_volume;
  }
  free(buf);
  free(per);
  accum_free(&a);
  if (rc) gs_dem_data_free(out);
  return rc;
}

double gs_dem_break_probability(const gs_dem_data *d, size_t cls, double u_break) {
  double mu = d->all_mu, sigma = d->all_sigma;
  if (cls < d->nclass && d->nvel[cls] >= 2 && isfinite(d->vel_mu[cls]) && d->vel_sigma[cls] > 0) {
    mu = d->vel_mu[cls];
    sigma = d->vel_sigma[cls];
  }
  if (!(u_break > 0)) return 1;
  if (!isfinite(mu) || !(sigma > 0)) return NAN;
  return gsl_cdf_lognormal_Q(u_break, mu, sigma);
}

/* The n + 1 class edges of the written tables: the given ones, or geometric
 * midpoints between the class diameters (as volumes when edges_volume). */
static int table_edges(const gs_dem_data *d, const char *path, double *e, gs_error *err) {
  size_t n = d->nclass;
  int volume = d->edges_volume;
  if (d->edges) {
    memcpy(e, d->edges, (n + 1) * sizeof(double));
    for (size_t i = 0; i < n; i++)
      if (!(e[i] >= 0 && e[i + 1] > e[i]))
        return gs_error_set(err, GS_EINPUT, "%s: class edges must be >= 0 and increasing (edge %zu = %g, edge %zu = %g)",
                            path, i, d->edges[i], i + 1, d->edges[i + 1]);
    return GS_OK;
  }
  for (size_t i = 0; i + 1 < n; i++)
    if (!(d->diameter[i + 1] > d->diameter[i] * (1 + 1e-9)) || !(d->diameter[i] > 0))
      return gs_error_set(err, GS_EINPUT, "%s: the DEM classes do not have increasing diameters (class %zu: %g m, "
                          "class %zu: %g m), so they cannot define the table's class edges; give the PBM's class "
                          "edges (nclass + 1 = %zu values)", path, i + 1, d->diameter[i], i + 2, d->diameter[i + 1], n + 1);
  if (!(d->diameter[0] > 0)) return gs_error_set(err, GS_EINPUT, "%s: class 1 has no diameter", path);
  /* geometric midpoints; the outer edges as far out as the neighbouring ones */
  for (size_t i = 1; i < n; i++) e[i] = sqrt(d->diameter[i - 1] * d->diameter[i]);
  e[0] = n > 1 ? d->diameter[0] * d->diameter[0] / e[1] : d->diameter[0] / 1.5;
  e[n] = n > 1 ? d->diameter[n - 1] * d->diameter[n - 1] / e[n - 1] : d->diameter[0] * 1.5;
  if (volume)
    for (size_t i = 0; i <= n; i++) e[i] = M_PI / 6 * e[i] * e[i] * e[i];
  return GS_OK;
}

int gs_dem_impact_table_write(const char *path, const char *comment, size_t nclass, const double *edges,
                              int edges_volume, const double *rate, const double *mu, const double *sigma,
                              gs_error *err) {
  gs_csv_out t;
  FILE *fp = gs_csv_open(&t, path, err);
  if (!fp) return err->code;
  if (comment) fputs(comment, fp);
  fprintf(fp, "# edges measure particle %s: use `selection: {type: dem_impact, measure: %s, file: ...}`\nedges",
          edges_volume ? "volume [m^3]" : "diameter [m]", edges_volume ? "volume" : "diameter");
  for (size_t i = 0; i <= nclass; i++) fprintf(fp, ", %.10g", edges[i]);
  fprintf(fp, "\n");
  const double *row[3] = {rate, mu, sigma};
  for (int r = 0; r < 3; r++) {
    for (size_t i = 0; i < nclass; i++) fprintf(fp, "%s%.10g", i ? ", " : "", row[r][i]);
    fprintf(fp, "\n");
  }
  const char *const units[] = {"edges", edges_volume ? "m^3" : "m", "rate", "1/s", "mu", "ln(m/s)",
                               "sigma", "1", NULL};
  return gs_csv_close(&t, "gransim", units, err);
}

int gs_dem_data_write_impacts(const gs_dem_data *d, const char *path, gs_error *err) {
  size_t n = d->nclass;
  double *e = malloc((3 * n + 1) * sizeof(double));
  if (!e) return gs_error_set(err, GS_ENOMEM, "out of memory");
  int rc = table_edges(d, path, e, err);
  if (rc) {
    free(e);
    return rc;
  }
  double *mu = e + n + 1, *sigma = mu + n;
  for (size_t i = 0; i < n; i++) {
    mu[i] = isnan(d->vel_mu[i]) ? d->all_mu : d->vel_mu[i];
    sigma[i] = isnan(d->vel_sigma[i]) ? d->all_sigma : d->vel_sigma[i];
  }
  char comment[1024];
  snprintf(comment, sizeof comment,
           "# gransim dem-reduce: wall impacts per class, mean of %zu snapshot(s) (steps %ld..%ld)\n"
           "# rows: impacts per particle per second (current wall contacts / contact time / particles);\n"
           "# mu, sigma of the lognormal fit of the impact speed (ln m/s; classes with < 2 samples: the pooled fit)\n",
           d->nsnap, d->nsnap ? d->steps[0] : 0, d->nsnap ? d->steps[d->nsnap - 1] : 0);
  rc = gs_dem_impact_table_write(path, comment, n, e, d->edges_volume, d->impact_rate, mu, sigma, err);
  free(e);
  return rc;
}

int gs_dem_kernel_table_write(const char *path, const char *comment, size_t nclass, const double *edges,
                              int edges_volume, const double *C, gs_error *err) {
  gs_csv_out t;
  FILE *fp = gs_csv_open(&t, path, err);
  if (!fp) return err->code;
  if (comment) fputs(comment, fp);
  fprintf(fp, "# edges measure particle %s: use `kernel: {type: table, measure: %s, file: ...}`\nedges",
          edges_volume ? "volume [m^3]" : "diameter [m]", edges_volume ? "volume" : "diameter");
  for (size_t i = 0; i <= nclass; i++) fprintf(fp, ", %.10g", edges[i]);
  fprintf(fp, "\n");
  for (size_t i = 0; i < nclass; i++) {
    for (size_t j = 0; j < nclass; j++) fprintf(fp, "%s%.10g", j ? ", " : "", C[i * nclass + j]);
    fprintf(fp, "\n");
  }
  const char *const units[] = {"edges", edges_volume ? "m^3" : "m", "C_ij", "1/s", NULL};
  return gs_csv_close(&t, "gransim", units, err);
}

int gs_dem_data_write_table(const gs_dem_data *d, const char *path, gs_error *err) {
  size_t n = d->nclass;
  double *e = malloc((n + 1) * sizeof(double));
  if (!e) return gs_error_set(err, GS_ENOMEM, "out of memory");
  int rc = table_edges(d, path, e, err);
  if (rc) {
    free(e);
    return rc;
  }
  char comment[600];
  snprintf(comment, sizeof comment,
           "# gransim dem-reduce: DEM collision frequency C_ij [1/s per pair of particles], mean of %zu "
           "snapshot(s) (steps %ld..%ld);\n# C_ij = E_ij/(N_i N_j), C_ii = 2 E_ii/N_i^2, E = current contacts / "
           "contact time (t_c = %.6g s for class 1-1)\n",
           d->nsnap, d->nsnap ? d->steps[0] : 0, d->nsnap ? d->steps[d->nsnap - 1] : 0, d->contact_time);
  rc = gs_dem_kernel_table_write(path, comment, n, e, d->edges_volume, d->collision, err);
  free(e);
  return rc;
}
