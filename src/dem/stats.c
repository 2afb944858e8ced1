/* Statistics for the PBM and the tables they are written to.
 *
 * Collision frequency of classes i and j over the statistics window
 * (length dt, from t0 to the end):  C_ij = N_coll,ij / (N_i N_j dt), with
 * N_coll,ij the collision events (contacts that began) between the classes
 * and N_i the mean number of class-i particles over the samples, as in
 * seed 000 eq. (9).  collision_kernel.csv holds C in the format of the PBM's
 * `table` kernel (src/kernel/kernel_table.c) with class edges in particle
 * diameter (use `measure: diameter` there). */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "dem/dem_stats.h"

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
  if (!s->num_sum || !s->cv_n || !s->cv_s || !s->cv_s2 || !s->cv_a)
    return gs_error_set(err, GS_ENOMEM, "out of memory");
  return GS_OK;
}

void gs_dem_stats_free(gs_dem_stats *s) {
  free(s->num_sum);
  free(s->cv_n);
  free(s->cv_s);
  free(s->cv_s2);
  free(s->cv_a);
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
  s->hold_n_sum = s->hold_m_sum = 0;
  s->nrt = 0;
  s->out_mass = 0;
  gs_dem_counters_reset(c->dem);
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
    double sp2 = v.vx[i] * v.vx[i] + v.vy[i] * v.vy[i] + v.vz[i] * v.vz[i];
    size_t at = (size_t)k * s->ncmp + q;
    s->cv_n[at] += 1;
    s->cv_s[at] += sqrt(sp2);
    s->cv_s2[at] += sp2;
    s->cv_a[at] += v.vx[i] * ax[0] + v.vy[i] * ax[1] + v.vz[i] * ax[2];
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

static FILE *open_table(const char *dir, const char *name, char *path, size_t n, gs_error *err) {
  snprintf(path, n, "%s/%s", dir, name);
  FILE *fp = fopen(path, "w");
  if (!fp) gs_error_set(err, GS_EIO, "%s: cannot write: %s", path, strerror(errno));
  return fp;
}

static int close_table(FILE *fp, const char *path, gs_error *err) {
  int bad = ferror(fp);
  if (fclose(fp) || bad) return gs_error_set(err, GS_EIO, "%s: write failed", path);
  return GS_OK;
}

int gs_dem_stats_write(const gs_dem_stats *s, const gs_dem_case *c, const char *dir, double t_end,
                       double t_steady, gs_error *err) {
  const int ncl = s->ncl;
  const double win = t_end - s->t0, ns = s->nsamples ? (double)s->nsamples : 1;
  gs_dem_counters k;
  gs_dem_get_counters(c->dem, &k);
  char path[4200];
  FILE *fp;
  int rc;
  double *C = calloc((size_t)ncl * ncl, sizeof(double));
  if (!C) return gs_error_set(err, GS_ENOMEM, "out of memory");

  /* collisions per class pair */
  if (!(fp = open_table(dir, "collisions.csv", path, sizeof path, err))) { free(C); return err->code; }
  fprintf(fp, "# collision events (contacts that began) from t = %.9g to %.9g s (%.9g s, %ld samples)%s\n",
          s->t0, t_end, win, s->nsamples, t_steady >= 0 ? "" : "; steady state not detected");
  fprintf(fp, "class_i,class_j,name_i,name_j,events,N_i,N_j,window_s,events_per_s,C_ij\n");
  for (int i = 0; i < ncl; i++)
    for (int j = i; j < ncl; j++) {
      double ev = (double)k.pair_events[i * ncl + j], Ni = s->num_sum[i] / ns, Nj = s->num_sum[j] / ns;
      double cij = Ni > 0 && Nj > 0 && win > 0 ? ev / (Ni * Nj * win) : 0;
      C[i * ncl + j] = C[j * ncl + i] = cij;
      fprintf(fp, "%d,%d,%s,%s,%.0f,%.6g,%.6g,%.9g,%.9g,%.9g\n", i + 1, j + 1, c->cls[i].name,
              c->cls[j].name, ev, Ni, Nj, win, win > 0 ? ev / win : 0, cij);
    }
  if ((rc = close_table(fp, path, err))) { free(C); return rc; }

  /* the same as a PBM kernel table: edges in diameter halfway between classes */
  if (!(fp = open_table(dir, "collision_kernel.csv", path, sizeof path, err))) { free(C); return err->code; }
  fprintf(fp, "# DEM collision frequency C_ij = N_coll,ij / (N_i N_j dt) [1/s], window %.9g s;\n"
          "# edges are particle diameters [m]: use `kernel: {type: table, measure: diameter, ...}`\n"
          "edges", win);
  for (int i = 0; i <= ncl; i++) {
    double e;
    if (i == 0) e = 2 * c->cls[0].rmin * 0.999;
    else if (i == ncl) e = 2 * c->cls[ncl - 1].rmax * 1.001;
    else e = c->cls[i - 1].rmax + c->cls[i].rmin; /* halfway in diameter */
    if (i > 0 && i < ncl && !(c->cls[i].rmin > c->cls[i - 1].rmax))
      e = c->cls[i - 1].rmax * 2 * (1 + 1e-6 * i); /* overlapping classes: keep edges increasing */
    fprintf(fp, ", %.9g", e);
  }
  fprintf(fp, "\n");
  for (int i = 0; i < ncl; i++) {
    for (int j = 0; j < ncl; j++) fprintf(fp, "%s%.9g", j ? ", " : "", C[i * ncl + j]);
    fprintf(fp, "\n");
  }
  free(C);
  if ((rc = close_table(fp, path, err))) return rc;

  /* impacts per wall and class */
  if (!(fp = open_table(dir, "impacts.csv", path, sizeof path, err))) return err->code;
  fprintf(fp, "wall,class,name,impacts,impacts_per_s,impacts_per_particle_s,mean_vn,std_vn,mean_vt\n");
  for (size_t w = 0; w < k.nwalls; w++)
    for (int i = 0; i < ncl; i++) {
      size_t q = w * (size_t)ncl + i;
      double n = (double)k.wall_impacts[q], Ni = s->num_sum[i] / ns;
      double mv = n > 0 ? k.wall_vn_sum[q] / n : 0;
      double sv = n > 1 ? sqrt(fmax(0, (k.wall_vn2_sum[q] - n * mv * mv) / (n - 1))) : 0;
      fprintf(fp, "%s,%d,%s,%.0f,%.9g,%.9g,%.6g,%.6g,%.6g\n", gs_dem_wall_name(c->dem, w), i + 1,
              c->cls[i].name, n, win > 0 ? n / win : 0, win > 0 && Ni > 0 ? n / (Ni * win) : 0, mv, sv,
              n > 0 ? k.wall_vt_sum[q] / n : 0);
    }
  if ((rc = close_table(fp, path, err))) return rc;

  if (!(fp = open_table(dir, "impact_velocity.csv", path, sizeof path, err))) return err->code;
  fprintf(fp, "# normal impact speed distributions (the last bin holds everything above)\n"
          "wall,class,vn_lo,vn_hi,impacts\n");
  for (size_t w = 0; w < k.nwalls; w++)
    for (int i = 0; i < ncl; i++) {
      int nb;
      double dv;
      const uint64_t *h = gs_dem_impact_histogram(c->dem, w, i, &nb, &dv);
      for (int b = 0; b < nb; b++)
        fprintf(fp, "%s,%d,%.6g,%.6g,%llu\n", gs_dem_wall_name(c->dem, w), i + 1, b * dv,
                b + 1 < nb ? (b + 1) * dv : HUGE_VAL, (unsigned long long)h[b]);
    }
  if ((rc = close_table(fp, path, err))) return rc;

  /* velocities per class and compartment */
  if (!(fp = open_table(dir, "velocity.csv", path, sizeof path, err))) return err->code;
  fprintf(fp, "class,name,compartment,from,to,mean_number,mean_speed,std_speed,mean_axial_velocity\n");
  for (int i = 0; i < ncl; i++)
    for (size_t q = 0; q < s->ncmp; q++) {
      size_t at = (size_t)i * s->ncmp + q;
      double n = s->cv_n[at], m = n > 0 ? s->cv_s[at] / n : 0;
      double sd = n > 1 ? sqrt(fmax(0, (s->cv_s2[at] - n * m * m) / (n - 1))) : 0;
      fprintf(fp, "%d,%s,%zu,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g\n", i + 1, c->cls[i].name, q + 1,
              c->cmp_edges[q], c->cmp_edges[q + 1], n / ns, m, sd, n > 0 ? s->cv_a[at] / n : 0);
    }
  if ((rc = close_table(fp, path, err))) return rc;

  /* residence times of particles that left through an outlet */
  if (!(fp = open_table(dir, "residence.csv", path, sizeof path, err))) return err->code;
  double mx = 0, sum = 0;
  for (size_t r = 0; r < s->nrt; r++) {
    mx = fmax(mx, s->rt[r]);
    sum += s->rt[r];
  }
  fprintf(fp, "# %zu particles left through outlets (%.6g kg) from t = %.9g to %.9g s; mean residence %.6g s;"
          " mean hold-up %.6g particles, %.6g kg\n",
          s->nrt, s->out_mass, s->t0, t_end, s->nrt ? sum / (double)s->nrt : 0, s->hold_n_sum / ns,
          s->hold_m_sum / ns);
  fprintf(fp, "t_lo,t_hi,count,fraction\n");
  const int nb = 50;
  double bw = mx > 0 ? mx / nb * (1 + 1e-9) : 1;
  for (int b = 0; b < nb && s->nrt; b++) {
    size_t cnt = 0;
    for (size_t r = 0; r < s->nrt; r++)
      if ((int)(s->rt[r] / bw) == b) cnt++;
    fprintf(fp, "%.6g,%.6g,%zu,%.6g\n", b * bw, (b + 1) * bw, cnt, (double)cnt / (double)s->nrt);
  }
  return close_table(fp, path, err);
}
