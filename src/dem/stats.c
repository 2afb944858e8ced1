/* Statistics for the PBM and the tables they are written to.
 *
 * Collision frequency of classes i and j over the statistics window
 * (length dt, from t0 to the end):  C_ij = N_coll,ij / (N_i N_j dt), with
 * N_coll,ij the collision events (contacts that began) between the classes
 * and N_i the mean number of class-i particles over the samples, as in
 * Sampat et al. (2018) eq. (9); on the diagonal C_ii = 2 N_coll,ii / (N_i^2
 * dt), as the PBM's pair loop counts a like pair once
 * (gs_dem_collision_frequency).  collision_kernel.csv holds C in the format of the PBM's
 * `table` kernel (src/kernel/kernel_table.c) with class edges in particle
 * diameter (use `measure: diameter` there); impact_table.csv holds the wall
 * impacts in the format of the `dem_impact` breakage selection
 * (src/kernel/selection_dem.c), written and fitted by the same functions as
 * `gransim dem-reduce --impacts` (include/gransim/dem_data.h). */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cfg/nearest.h"
#include "dem/dem_stats.h"
#include "gransim/dem_data.h"

int gs_dem_stats_init(gs_dem_stats *s, const gs_dem_case *c, gs_error *err) {
  memset(s, 0, sizeof *s);
  s->ncl = (int)c->nclass;
  s->ncmp = c->ncmp;
  size_t n = (size_t)s->ncl * s->ncmp;
  s->num_sum = calloc((size_t)s->ncl, sizeof(double));
  s->cv_n = calloc(n, sizeof(double));
  s->cv_s = calloc(n, sizeof(double));
  s->cv_s2 = calloc(n, sizeof(double));
  s->cv_a = calloc(n, sizeof(double));
  s->cv_v = calloc(3 * n, sizeof(double));
  s->cv_v2 = calloc(3 * n, sizeof(double));
  s->cv_ref = calloc(4 * n, sizeof(double));
  if (!s->num_sum || !s->cv_n || !s->cv_s || !s->cv_s2 || !s->cv_a || !s->cv_v || !s->cv_v2 || !s->cv_ref)
    return gs_error_set(err, GS_ENOMEM, "out of memory");
  return GS_OK;
}

void gs_dem_stats_free(gs_dem_stats *s) {
  free(s->num_sum);
  free(s->cv_n);
  free(s->cv_s);
  free(s->cv_s2);
  free(s->cv_a);
  free(s->cv_v);
  free(s->cv_v2);
  free(s->cv_ref);
  free(s->rt);
  free(s->rt_cls);
  memset(s, 0, sizeof *s);
}

void gs_dem_stats_reset(gs_dem_stats *s, gs_dem_case *c, double t) {
  size_t n = (size_t)s->ncl * s->ncmp;
  s->t0 = t;
  s->nsamples = 0;
  memset(s->num_sum, 0, (size_t)s->ncl * sizeof(double));
  memset(s->cv_n, 0, n * sizeof(double));
  memset(s->cv_s, 0, n * sizeof(double));
  memset(s->cv_s2, 0, n * sizeof(double));
  memset(s->cv_a, 0, n * sizeof(double));
  memset(s->cv_v, 0, 3 * n * sizeof(double));
  memset(s->cv_v2, 0, 3 * n * sizeof(double));
  memset(s->cv_ref, 0, 4 * n * sizeof(double));
  s->hold_n_sum = s->hold_m_sum = 0;
  s->nrt = 0;
  s->out_mass = 0;
  /* particles that left before t belong to no window */
  const int *cls;
  const double *rt, *ms;
  (void)gs_dem_take_removed(c->dem, &cls, &rt, &ms);
  gs_dem_counters_reset(c->dem);
}

const char *const gs_dem_steady_quantities[] = {"holdup_mass", "collision_rate", "kinetic_energy", NULL};

int gs_dem_steady_quantities_read(gs_cfg_node *list, unsigned *mask, gs_error *err) {
  int rc = gs_cfg_require_kind(list, GS_CFG_SEQ, err);
  if (!rc && !gs_cfg_size(list)) rc = gs_cfg_fail(list, err, "expected one or more of: holdup_mass, collision_rate, "
                                                  "kinetic_energy");
  *mask = 0;
  for (size_t i = 0; i < gs_cfg_size(list) && !rc; i++) {
    gs_cfg_node *it = gs_cfg_item(list, i);
    const char *name = gs_cfg_scalar(it);
    int q = 0;
    while (name && gs_dem_steady_quantities[q] && strcmp(name, gs_dem_steady_quantities[q])) q++;
    if (!name || !gs_dem_steady_quantities[q]) {
      const char *near = name ? gs_nearest_word(name, gs_dem_steady_quantities, 3) : NULL;
      char hint[96] = "";
      if (near) snprintf(hint, sizeof hint, "did you mean '%s'? ", near);
      rc = gs_cfg_fail(it, err, "unknown quantity: %sexpected one of: holdup_mass, collision_rate, kinetic_energy",
                       hint);
    } else if (*mask & (1u << q)) {
      rc = gs_cfg_fail(it, err, "'%s' is listed twice", name);
    } else *mask |= 1u << q;
  }
  return rc;
}

void gs_dem_steady_quantities_join(unsigned mask, const char *sep, char *buf, size_t n) {
  size_t used = 0;
  if (n) buf[0] = '\0';
  for (int q = 0; gs_dem_steady_quantities[q] && used < n; q++)
    if (mask & (1u << q))
      used += (size_t)snprintf(buf + used, n - used, "%s%s", used ? sep : "", gs_dem_steady_quantities[q]);
}

int gs_dem_is_steady_n(const double *const *series, int nq, long n, long w, double tol) {
  if (w < 1 || n < w || nq < 1) return 0;
  for (int q = 0; q < nq; q++) {
    const double *s = series[q] + n - w;
    double mean = 0;
    for (long k = 0; k < w; k++) mean += s[k];
    mean /= (double)w;
    if (!(mean > 0)) return 0;
    for (long k = 0; k < w; k++)
      if (!(fabs(s[k] - mean) <= tol * mean)) return 0;
  }
  return 1;
}

int gs_dem_is_steady(const double *a, const double *b, long n, long w, double tol) {
  const double *const s[2] = {a, b};
  return gs_dem_is_steady_n(s, 2, n, w, tol);
}

void gs_dem_holdup(const gs_dem_case *c, double *n, double *m) {
  gs_dem_view v;
  gs_dem_get_view(c->dem, &v);
  double hn = 0, hm = 0;
  for (size_t i = 0; i < v.n; i++) {
    double x[3] = {v.x[i], v.y[i], v.z[i]};
    if (c->has_holdup && !gs_dem_region_contains(&c->holdup, x)) continue;
    hn += 1;
    hm += v.m[i];
  }
  *n = hn;
  *m = hm;
}

int gs_dem_stats_sample(gs_dem_stats *s, gs_dem_case *c, gs_error *err) {
  gs_dem_view v;
  gs_dem_get_view(c->dem, &v);
  const double *ax = c->cmp_axis, *o = c->cmp_origin;
  for (size_t i = 0; i < v.n; i++) {
    int k = gs_dem_type_class(c->dem, v.type[i]);
    s->num_sum[k] += 1;
    double pos = (v.x[i] - o[0]) * ax[0] + (v.y[i] - o[1]) * ax[1] + (v.z[i] - o[2]) * ax[2];
    if (pos < c->cmp_edges[0] || pos >= c->cmp_edges[c->ncmp]) continue;
    size_t q = 0;
    while (q + 1 < c->ncmp && pos >= c->cmp_edges[q + 1]) q++;
    const double vel[3] = {v.vx[i], v.vy[i], v.vz[i]};
    const double sp = sqrt(vel[0] * vel[0] + vel[1] * vel[1] + vel[2] * vel[2]);
    size_t at = (size_t)k * s->ncmp + q;
    double *ref = s->cv_ref + 4 * at;
    if (s->cv_n[at] == 0) ref[0] = sp, ref[1] = vel[0], ref[2] = vel[1], ref[3] = vel[2];
    s->cv_n[at] += 1;
    s->cv_s[at] += sp - ref[0];
    s->cv_s2[at] += (sp - ref[0]) * (sp - ref[0]);
    s->cv_a[at] += vel[0] * ax[0] + vel[1] * ax[1] + vel[2] * ax[2];
    for (int a = 0; a < 3; a++) {
      s->cv_v[3 * at + a] += vel[a] - ref[1 + a];
      s->cv_v2[3 * at + a] += (vel[a] - ref[1 + a]) * (vel[a] - ref[1 + a]);
    }
  }
  double hn, hm;
  gs_dem_holdup(c, &hn, &hm);
  s->hold_n_sum += hn;
  s->hold_m_sum += hm;
  s->nsamples++;
  const int *cls;
  const double *rt, *ms;
  size_t nr = gs_dem_take_removed(c->dem, &cls, &rt, &ms);
  if (s->nrt + nr > s->rt_cap) {
    size_t nc = s->rt_cap ? s->rt_cap : 256;
    while (nc < s->nrt + nr) nc *= 2;
    double *a = realloc(s->rt, nc * sizeof(double));
    if (a) s->rt = a;
    int *b = realloc(s->rt_cls, nc * sizeof(int));
    if (b) s->rt_cls = b;
    if (!a || !b) return gs_error_set(err, GS_ENOMEM, "out of memory");
    s->rt_cap = nc;
  }
  for (size_t k = 0; k < nr; k++) {
    s->rt[s->nrt] = rt[k];
    s->rt_cls[s->nrt++] = cls[k];
    s->out_mass += ms[k];
  }
  return GS_OK;
}

int gs_dem_stats_have_window(const gs_dem_stats *s, const gs_dem_case *c, double t_end, double t_steady) {
  if (c->start_steady && t_steady < 0) return 0;
  return s->nsamples > 0 && t_end > s->t0;
}

FILE *gs_dem_table_open(const char *dir, const char *name, char *path, size_t n, gs_error *err) {
  snprintf(path, n, "%s/%s", dir, name);
  FILE *fp = fopen(path, "w");
  if (!fp) gs_error_set(err, GS_EIO, "%s: cannot write: %s", path, strerror(errno));
  return fp;
}

int gs_dem_table_close(FILE *fp, const char *path, gs_error *err) {
  int bad = ferror(fp);
  if (fclose(fp) || bad) return gs_error_set(err, GS_EIO, "%s: write failed", path);
  return GS_OK;
}

FILE *gs_dem_table_begin(gs_csv_out *t, const char *dir, const char *name, gs_error *err) {
  return gs_csv_open_in(t, dir, name, err);
}

int gs_dem_table_end(gs_csv_out *t, const char *const *units, gs_error *err) {
  return gs_csv_close(t, "gransim dem", units, err);
}

const char *const gs_dem_units_collisions[] = {
    "class_i", "1", "class_j", "1", "events", "1", "N_i", "1", "N_j", "1", "window_s", "s",
    "events_per_s", "1/s", "C_ij", "1/s", NULL};
const char *const gs_dem_units_kernel[] = {"edges", "m", "C_ij", "1/s", NULL};
const char *const gs_dem_units_impacts[] = {
    "class", "1", "impacts", "1", "impacts_per_s", "1/s", "impacts_per_particle_s", "1/s",
    "mean_vn", "m/s", "std_vn", "m/s", "mean_vt", "m/s", NULL};
const char *const gs_dem_units_impact_velocity[] = {"class", "1", "vn_lo", "m/s", "vn_hi", "m/s",
                                                     "impacts", "1", NULL};
const char *const gs_dem_units_velocity[] = {
    "class", "1", "compartment", "1", "from", "m", "to", "m", "mean_number", "1", "mean_speed", "m/s",
    "std_speed", "m/s", "mean_axial_velocity", "m/s", "mean_vx", "m/s", "mean_vy", "m/s", "mean_vz", "m/s",
    "std_vx", "m/s", "std_vy", "m/s", "std_vz", "m/s", NULL};
const char *const gs_dem_units_residence[] = {"t_lo", "s", "t_hi", "s", "count", "1", "fraction", "1", NULL};
const char *const gs_dem_units_residence_class[] = {"class", "1", "t_lo", "s", "t_hi", "s", "count", "1",
                                                     "fraction", "1", NULL};

/* The class edges of the written tables, in particle diameter: halfway
 * between neighbouring classes' radius ranges, the outer edges just outside
 * the smallest and largest diameters. */
void gs_dem_class_edges(const gs_dem_case *c, double *e) {
  const int ncl = (int)c->nclass;
  for (int i = 0; i <= ncl; i++) {
    if (i == 0) e[i] = 2 * c->cls[0].rmin * 0.999;
    else if (i == ncl) e[i] = 2 * c->cls[ncl - 1].rmax * 1.001;
    else e[i] = c->cls[i - 1].rmax + c->cls[i].rmin; /* halfway in diameter */
    if (i > 0 && i < ncl && !(c->cls[i].rmin > c->cls[i - 1].rmax))
      e[i] = c->cls[i - 1].rmax * 2 * (1 + 1e-6 * i); /* overlapping classes: keep edges increasing */
  }
}

/* impact_table.csv (wall < 0: all walls) or impact_table_WALL.csv */
static int write_impact_table(const gs_dem_stats *s, const gs_dem_case *c, const char *dir, long wall,
                              double win, int have, const char *note, gs_error *err) {
  const int ncl = s->ncl;
  gs_dem_counters k;
  gs_dem_get_counters(c->dem, &k);
  const int *wc;
  const double *lnu;
  size_t nimp = gs_dem_impact_speeds(c->dem, &wc, &lnu);
  double *buf = malloc((nimp + 1) * sizeof(double)), *e = malloc((4 * (size_t)ncl + 1) * sizeof(double));
  if (!buf || !e) {
    free(buf);
    free(e);
    return gs_error_set(err, GS_ENOMEM, "out of memory");
  }
  double *rate = e + ncl + 1, *mu = rate + ncl, *sigma = mu + ncl;
  gs_dem_class_edges(c, e);
  const double ns = s->nsamples ? (double)s->nsamples : 1;
  uint64_t nall = 0;
  for (int i = 0; i < ncl; i++) {
    uint64_t n = 0;
    for (size_t w = 0; w < k.nwalls; w++)
      if (wall < 0 || (size_t)wall == w) n += k.wall_impacts[w * (size_t)ncl + i];
    nall += n;
    double Ni = s->num_sum[i] / ns;
    rate[i] = !have ? NAN : Ni > 0 ? (double)n / (Ni * win) : 0;
  }
  /* fits per class, then the pooled fit for classes with too few speeds */
  size_t npool = 0, m = 0;
  for (size_t q = 0; q < nimp; q++)
    if (wall < 0 || wc[q] / ncl == wall) buf[npool++] = lnu[q];
  double pmu, psig;
  gs_dem_lognormal_fit(buf, npool, &pmu, &psig);
  size_t pooled_classes = 0;
  for (int i = 0; i < ncl; i++) {
    m = 0;
    for (size_t q = 0; q < nimp; q++)
      if (wc[q] % ncl == i && (wall < 0 || wc[q] / ncl == wall)) buf[m++] = lnu[q];
    gs_dem_lognormal_fit(buf, m, &mu[i], &sigma[i]);
    if (!(isfinite(mu[i]) && sigma[i] > 0)) {
      mu[i] = pmu;
      sigma[i] = psig;
      pooled_classes++;
    }
    if (!have) mu[i] = sigma[i] = NAN;
  }
  char name[200], path[4200], comment[2048];
  if (wall < 0) snprintf(name, sizeof name, "impact_table.csv");
  else snprintf(name, sizeof name, "impact_table_%s.csv", gs_dem_wall_name(c->dem, (size_t)wall));
  snprintf(path, sizeof path, "%s/%s", dir, name);
  int len = snprintf(comment, sizeof comment,
                     "# gransim dem: wall impacts (contacts that began) on %s%s, per class, from t = %.9g s (window %.9g s)%s\n"
                     "# rows: impacts per particle per second (impacts / (N_i window));\n"
                     "# mu, sigma of the lognormal fit of the impact speed U = |v - v_wall| (mean and sample sd of ln U,\n"
                     "# ln m/s; %zu of %llu impacts fitted, those slower than %g m/s left out; %zu class(es) with fewer than\n"
                     "# 2 fitted impacts or sigma 0 take the pooled fit of all classes, mu %.6g, sigma %.6g)\n",
                     wall < 0 ? "all walls" : "wall ", wall < 0 ? "" : gs_dem_wall_name(c->dem, (size_t)wall),
                     s->t0, win, note, npool, (unsigned long long)nall, GS_DEM_MIN_IMPACT_SPEED, pooled_classes,
                     pmu, psig);
  if (have && !(isfinite(pmu) && psig > 0) && len > 0 && (size_t)len < sizeof comment)
    snprintf(comment + len, sizeof comment - (size_t)len,
             "# no lognormal fit: fewer than 2 impact speeds (or all equal); mu and sigma are nan\n");
  int rc = gs_dem_impact_table_write(path, comment, (size_t)ncl, e, 0, rate, mu, sigma, err);
  free(buf);
  free(e);
  return rc;
}

int gs_dem_stats_write(const gs_dem_stats *s, const gs_dem_case *c, const char *dir, double t_end,
                       double t_steady, const char *stopped, gs_error *err) {
  const int ncl = s->ncl;
  const double win = t_end - s->t0, ns = s->nsamples ? (double)s->nsamples : 1;
  const int have = gs_dem_stats_have_window(s, c, t_end, t_steady);
  /* why there are no rates, for every file's header */
  const char *why = have ? ""
                    : c->start_steady && t_steady < 0
                        ? "; NO STATISTICS WINDOW: statistics.start is 'steady' and the steady state was not "
                          "reached, so every rate and mean below is nan"
                        : "; NO STATISTICS WINDOW: no sample was taken in it, so every rate and mean below is nan";
  char note[1024];
  snprintf(note, sizeof note, "%s%s%.600s", why, stopped ? "; RUN STOPPED EARLY, tables up to there: " : "",
           stopped ? stopped : "");
  gs_dem_counters k;
  gs_dem_get_counters(c->dem, &k);
  gs_csv_out tab;
  FILE *fp;
  int rc;
  double *C = calloc((size_t)ncl * ncl, sizeof(double)), *e = malloc(((size_t)ncl + 1) * sizeof(double));
  if (!C || !e) {
    free(C);
    free(e);
    return gs_error_set(err, GS_ENOMEM, "out of memory");
  }

  /* collisions per class pair */
  if (!(fp = gs_dem_table_begin(&tab, dir, "collisions.csv", err))) { free(C); free(e); return err->code; }
  fprintf(fp, "# collision events (contacts that began) from t = %.9g to %.9g s (%.9g s, %ld samples)%s%s\n",
          s->t0, t_end, win, s->nsamples, t_steady >= 0 ? "" : "; steady state not detected", note);
  fprintf(fp, "class_i,class_j,name_i,name_j,events,N_i,N_j,window_s,events_per_s,C_ij\n");
  for (int i = 0; i < ncl; i++)
    for (int j = i; j < ncl; j++) {
      double ev = (double)k.pair_events[i * ncl + j];
      double Ni = have ? s->num_sum[i] / ns : NAN, Nj = have ? s->num_sum[j] / ns : NAN;
      double cij = !have ? NAN : gs_dem_collision_frequency(ev, Ni, Nj, win, i == j);
      C[i * ncl + j] = C[j * ncl + i] = cij;
      fprintf(fp, "%d,%d,%s,%s,%.0f,%.6g,%.6g,%.9g,%.9g,%.9g\n", i + 1, j + 1, c->cls[i].name,
              c->cls[j].name, ev, Ni, Nj, win, have ? ev / win : NAN, cij);
    }
  if ((rc = gs_dem_table_end(&tab, gs_dem_units_collisions, err))) { free(C); free(e); return rc; }

  /* the same as a PBM kernel table: edges in diameter halfway between classes */
  if (!(fp = gs_dem_table_begin(&tab, dir, "collision_kernel.csv", err))) { free(C); free(e); return err->code; }
  fprintf(fp, "# DEM collision frequency C_ij = N_coll,ij / (N_i N_j dt), C_ii = 2 N_coll,ii / (N_i^2 dt) [1/s], "
          "window %.9g s%s;\n"
          "# edges are particle diameters [m]: use `kernel: {type: table, measure: diameter, ...}`\n"
          "edges", win, note);
  gs_dem_class_edges(c, e);
  for (int i = 0; i <= ncl; i++) fprintf(fp, ", %.9g", e[i]);
  fprintf(fp, "\n");
  for (int i = 0; i < ncl; i++) {
    for (int j = 0; j < ncl; j++) fprintf(fp, "%s%.9g", j ? ", " : "", C[i * ncl + j]);
    fprintf(fp, "\n");
  }
  free(C);
  free(e);
  if ((rc = gs_dem_table_end(&tab, gs_dem_units_kernel, err))) return rc;

  /* impacts per wall and class */
  if (!(fp = gs_dem_table_begin(&tab, dir, "impacts.csv", err))) return err->code;
  fprintf(fp, "# wall impacts (contacts that began) from t = %.9g to %.9g s (%.9g s)%s; vn: normal speed "
          "relative to the wall, vt: tangential speed of the contact point\n", s->t0, t_end, win, note);
  fprintf(fp, "wall,class,name,impacts,impacts_per_s,impacts_per_particle_s,mean_vn,std_vn,mean_vt\n");
  for (size_t w = 0; w < k.nwalls; w++)
    for (int i = 0; i < ncl; i++) {
      size_t q = w * (size_t)ncl + i;
      double n = (double)k.wall_impacts[q], Ni = s->num_sum[i] / ns;
      double mv = n > 0 ? k.wall_vn_sum[q] / n : NAN;
      double sv = n > 1 ? sqrt(fmax(0, (k.wall_vn2_sum[q] - n * mv * mv) / (n - 1))) : NAN;
      fprintf(fp, "%s,%d,%s,%.0f,%.9g,%.9g,%.6g,%.6g,%.6g\n", gs_dem_wall_name(c->dem, w), i + 1,
              c->cls[i].name, n, have ? n / win : NAN, !have ? NAN : Ni > 0 ? n / (Ni * win) : 0, mv, sv,
              n > 0 ? k.wall_vt_sum[q] / n : NAN);
    }
  if ((rc = gs_dem_table_end(&tab, gs_dem_units_impacts, err))) return rc;

  /* the breakage selection's table: all walls, and each wall alone */
  if ((rc = write_impact_table(s, c, dir, -1, win, have, note, err))) return rc;
  for (size_t w = 0; w < k.nwalls; w++)
    if ((rc = write_impact_table(s, c, dir, (long)w, win, have, note, err))) return rc;

  if (!(fp = gs_dem_table_begin(&tab, dir, "impact_velocity.csv", err))) return err->code;
  fprintf(fp, "# normal impact speed distributions (the last bin holds everything above)%s\n"
          "wall,class,vn_lo,vn_hi,impacts\n", note);
  for (size_t w = 0; w < k.nwalls; w++)
    for (int i = 0; i < ncl; i++) {
      int nb;
      double dv;
      const uint64_t *h = gs_dem_impact_histogram(c->dem, w, i, &nb, &dv);
      for (int b = 0; b < nb; b++)
        fprintf(fp, "%s,%d,%.6g,%.6g,%llu\n", gs_dem_wall_name(c->dem, w), i + 1, b * dv,
                b + 1 < nb ? (b + 1) * dv : HUGE_VAL, (unsigned long long)h[b]);
    }
  if ((rc = gs_dem_table_end(&tab, gs_dem_units_impact_velocity, err))) return rc;

  /* velocities per class and compartment */
  if (!(fp = gs_dem_table_begin(&tab, dir, "velocity.csv", err))) return err->code;
  fprintf(fp, "# over the %ld samples from t = %.9g to %.9g s, every particle of the class in the compartment "
          "once per sample: speed |v|, velocity components and the axial component v.axis; std: sample "
          "standard deviation (n - 1)%s\n", s->nsamples, s->t0, t_end, note);
  fprintf(fp, "class,name,compartment,from,to,mean_number,mean_speed,std_speed,mean_axial_velocity,"
          "mean_vx,mean_vy,mean_vz,std_vx,std_vy,std_vz\n");
  for (int i = 0; i < ncl; i++)
    for (size_t q = 0; q < s->ncmp; q++) {
      size_t at = (size_t)i * s->ncmp + q;
      const double n = s->cv_n[at], *ref = s->cv_ref + 4 * at;
      /* sums of differences d from the reference: mean = ref + sum d / n,
       * sd^2 = (sum d^2 - (sum d)^2 / n) / (n - 1) */
      double m = n > 0 ? s->cv_s[at] / n : NAN;
      double sd = n > 1 ? sqrt(fmax(0, (s->cv_s2[at] - n * m * m) / (n - 1))) : NAN;
      fprintf(fp, "%d,%s,%zu,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g", i + 1, c->cls[i].name, q + 1, c->cmp_edges[q],
              c->cmp_edges[q + 1], have ? n / ns : NAN, ref[0] + m, sd, n > 0 ? s->cv_a[at] / n : NAN);
      double mc[3];
      for (int a = 0; a < 3; a++) {
        mc[a] = n > 0 ? s->cv_v[3 * at + a] / n : NAN;
        fprintf(fp, ",%.6g", ref[1 + a] + mc[a]);
      }
      for (int a = 0; a < 3; a++)
        fprintf(fp, ",%.6g", n > 1 ? sqrt(fmax(0, (s->cv_v2[3 * at + a] - n * mc[a] * mc[a]) / (n - 1))) : NAN);
      fprintf(fp, "\n");
    }
  if ((rc = gs_dem_table_end(&tab, gs_dem_units_velocity, err))) return rc;

  /* residence times of particles that left through an outlet: all, and per class */
  return gs_dem_residence_write(c, dir, s->rt, s->rt_cls, s->nrt, s->out_mass, s->t0, t_end,
                                have ? s->hold_n_sum / ns : NAN, have ? s->hold_m_sum / ns : NAN, note, err);
}

int gs_dem_residence_write(const gs_dem_case *c, const char *dir, const double *rt, const int *rt_cls, size_t nrt,
                           double out_mass, double t0, double t_end, double hold_n, double hold_m, const char *note,
                           gs_error *err) {
  const int ncl = (int)c->nclass;
  gs_csv_out tab;
  FILE *fp;
  int rc;
  double mx = 0, sum = 0;
  for (size_t r = 0; r < nrt; r++) {
    mx = fmax(mx, rt[r]);
    sum += rt[r];
  }
  const int nb = 50;
  const double bw = mx > 0 ? mx / nb * (1 + 1e-9) : 1;
  if (!(fp = gs_dem_table_begin(&tab, dir, "residence.csv", err))) return err->code;
  fprintf(fp, "# %zu particles left through outlets (%.6g kg) from t = %.9g to %.9g s; mean residence %.6g s;"
          " mean hold-up %.6g particles, %.6g kg%s\n",
          nrt, out_mass, t0, t_end, nrt ? sum / (double)nrt : NAN, hold_n,
          hold_m, note);
  fprintf(fp, "t_lo,t_hi,count,fraction\n");
  for (int b = 0; b < nb && nrt; b++) {
    size_t cnt = 0;
    for (size_t r = 0; r < nrt; r++)
      if ((int)(rt[r] / bw) == b) cnt++;
    fprintf(fp, "%.6g,%.6g,%zu,%.6g\n", b * bw, (b + 1) * bw, cnt, (double)cnt / (double)nrt);
  }
  if ((rc = gs_dem_table_end(&tab, gs_dem_units_residence, err))) return rc;

  if (!(fp = gs_dem_table_begin(&tab, dir, "residence_class.csv", err))) return err->code;
  fprintf(fp, "# residence-time distribution per class of the %zu particles that left through outlets from "
          "t = %.9g to %.9g s, bins as in residence.csv; fraction: of the class%s\n", nrt, t0, t_end, note);
  for (int i = 0; i < ncl; i++) {
    size_t n = 0;
    double si = 0;
    for (size_t r = 0; r < nrt; r++)
      if (rt_cls[r] == i) n++, si += rt[r];
    fprintf(fp, "# class %d (%s): %zu particles, mean residence %.6g s\n", i + 1, c->cls[i].name, n,
            n ? si / (double)n : NAN);
  }
  fprintf(fp, "class,name,t_lo,t_hi,count,fraction\n");
  for (int i = 0; i < ncl && nrt; i++) {
    size_t n = 0;
    for (size_t r = 0; r < nrt; r++) n += rt_cls[r] == i;
    for (int b = 0; b < nb; b++) {
      size_t cnt = 0;
      for (size_t r = 0; r < nrt; r++)
        if (rt_cls[r] == i && (int)(rt[r] / bw) == b) cnt++;
      fprintf(fp, "%d,%s,%.6g,%.6g,%zu,%.6g\n", i + 1, c->cls[i].name, b * bw, (b + 1) * bw, cnt,
              n ? (double)cnt / (double)n : NAN);
    }
  }
  return gs_dem_table_end(&tab, gs_dem_units_residence_class, err);
}

int gs_dem_timeseries_meta(const char *path, const char *description, size_t nw,
                           const char *const *wall_names, gs_error *err) {
  static const char *const fixed[] = {
      "time", "s", "particles", "1", "holdup_number", "1", "holdup_mass", "kg", "kinetic_energy", "J",
      "rotational_energy", "J", "contacts", "1", "collisions_per_s", "1/s", "lost", "1", "steady", "1",
      "wall_seconds", "s"};
  enum { NF = sizeof fixed / sizeof fixed[0] };
  const char *units[NF + 4 * GS_DEM_CASE_MAX_WALLS + 1];
  char names[2 * GS_DEM_CASE_MAX_WALLS][96];
  size_t n = 0;
  for (size_t i = 0; i < NF; i++) units[n++] = fixed[i];
  for (size_t w = 0; w < nw && w < GS_DEM_CASE_MAX_WALLS; w++) {
    snprintf(names[2 * w], sizeof names[0], "impacts_per_s_%s", wall_names[w]);
    snprintf(names[2 * w + 1], sizeof names[0], "torque_axis_%s", wall_names[w]);
    units[n++] = names[2 * w], units[n++] = "1/s";
    units[n++] = names[2 * w + 1], units[n++] = "N m";
  }
  units[n] = NULL;
  return gs_csv_meta_write(path, "gransim dem", description, units, err);
}
