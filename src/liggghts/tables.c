/* LIGGGHTS dumps -> the tables `gransim dem` writes (src/dem/stats.c), same
 * files, columns and conventions, so that the PBM cannot tell the engines
 * apart.
 *
 * LIGGGHTS lists current contacts, not collision events: src/demdata turns
 * the contacts K_ij of each snapshot into events per second E_ij = K_ij / t_c
 * with the Hertz contact duration t_c of the pair (docs/models.md, "DEM data
 * reduction").  The collision frequency is then written with the embedded
 * engine's convention C_ij = E_ij / (N_i N_j) for every pair, the diagonal
 * included (demdata's own C_ii is 2 E_ii / N_i^2, the PBM pair loop's).  Wall
 * impacts likewise: per wall and class, current wall contacts / t_c,wall. */
#include <dirent.h>
#include <errno.h>
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
    if (strstr(e->d_name, ".atom") &&
        (!strncmp(e->d_name, "collision", 9) || !strncmp(e->d_name, "impact", 6) || !strncmp(e->d_name, "ppcoll", 6))) {
      snprintf(path, sizeof path, "%s/%s", dir, e->d_name);
      remove(path);
    }
  closedir(dp);
  return GS_OK;
}

/* What the per-snapshot pass gathers beyond demdata's reduction. */
typedef struct {
  size_t ncl, ncmp, nw;
  double *num;             /* per class: sum over snapshots of N_i */
  double *cv_n, *cv_s, *cv_s2, *cv_a, *cv_v, *cv_v2; /* per class x compartment, as stats.c */
  double *wall_contacts;   /* nw x ncl: sum over snapshots */
  double *ln_u;            /* impact speeds (ln) ... */
  int *u_wc;               /* ... and wall * ncl + class */
  size_t nu, capu;
  double *hist;            /* nw x ncl x nbins: relative impact speeds */
  int nbins;
  double dv;
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

static int snapshot(pass *a, const gs_dem_case *c, const char *post, long step, gs_error *err) {
  char path[4600];
  gs_dump d, w;
  snprintf(path, sizeof path, "%s/collision%ld.atom", post, step);
  int rc = gs_dump_read(path, &d, err);
  if (rc) return rc;
  const char *need[] = {"id", "type", "x", "y", "z", "vx", "vy", "vz"};
  long col[8];
  for (int k = 0; k < 8 && !rc; k++)
    if ((col[k] = gs_dump_col(&d, need[k])) < 0) rc = gs_error_set(err, GS_EINPUT, "%s: no column '%s'", path, need[k]);
  id_cls *map = rc ? NULL : malloc((d.nrows + 1) * sizeof *map);
  if (!rc && !map) rc = gs_error_set(err, GS_ENOMEM, "out of memory");
  for (size_t r = 0; !rc && r < d.nrows; r++) {
    const double *v = d.v + r * d.ncols;
    int k = (int)v[col[1]] - 1;
    if (k < 0 || (size_t)k >= a->ncl) { rc = gs_error_set(err, GS_EINPUT, "%s: type %g is no class", path, v[col[1]]); break; }
    map[r] = (id_cls){(long)v[col[0]], k};
    a->num[k] += 1;
    const double x[3] = {v[col[2]], v[col[3]], v[col[4]]}, u[3] = {v[col[5]], v[col[6]], v[col[7]]};
    cmp_add(a, c, k, x, u);
  }
  size_t nmap = d.nrows;
  gs_dump_free(&d);
  if (rc || !a->nw) { free(map); return rc; }
  qsort(map, nmap, sizeof *map, cmp_id);
  snprintf(path, sizeof path, "%s/impact%ld.atom", post, step);
  if ((rc = gs_dump_read(path, &w, err))) { free(map); return rc; }
  long lc[14];
  for (int k = 0; k < 14 && !rc; k++)
    if ((lc[k] = gs_dump_col_index(&w, k + 1)) < 0) rc = gs_error_set(err, GS_EINPUT, "%s: no column [%d]", path, k + 1);
  for (size_t r = 0; !rc && r < w.nrows; r++) {
    const double *v = w.v + r * w.ncols;
    size_t wall = (size_t)v[lc[6]];
    id_cls key = {(long)v[lc[8]], 0}, *f = bsearch(&key, map, nmap, sizeof *map, cmp_id);
    if (!f || wall >= a->nw) continue; /* an atom deleted between the two dumps */
    a->wall_contacts[wall * a->ncl + (size_t)f->cls] += 1;
    double du[3] = {v[lc[3]] - v[lc[0]], v[lc[4]] - v[lc[1]], v[lc[5]] - v[lc[2]]};
    double u = sqrt(du[0] * du[0] + du[1] * du[1] + du[2] * du[2]);
    int b = (int)(u / a->dv);
    if (b >= a->nbins) b = a->nbins - 1;
    a->hist[(wall * a->ncl + (size_t)f->cls) * (size_t)a->nbins + (size_t)b] += 1;
    if (!(u >= GS_DEM_MIN_IMPACT_SPEED)) continue; /* resting contacts: no speed, as the embedded engine */
    if (a->nu == a->capu) {
      size_t cap = a->capu ? 2 * a->capu : 1024;
      double *l = realloc(a->ln_u, cap * sizeof(double));
      if (l) a->ln_u = l;
      int *q = realloc(a->u_wc, cap * sizeof(int));
      if (q) a->u_wc = q;
      if (!l || !q) { rc = gs_error_set(err, GS_ENOMEM, "out of memory"); break; }
      a->capu = cap;
    }
    a->ln_u[a->nu] = log(u);
    a->u_wc[a->nu++] = (int)(wall * a->ncl + (size_t)f->cls);
  }
  gs_dump_free(&w);
  free(map);
  return rc;
}

/* impact_table.csv (wall < 0: all walls) or impact_table_WALL.csv */
static int impact_table(const pass *a, const gs_dem_case *c, const gs_dem_data *dd, const char *dir, long wall,
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
    double Ni = a->num[i] / ns;
    rate[i] = Ni > 0 ? contacts / ns / dd->wall_contact_time[i] / Ni : 0;
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
           "# gransim dem (engine liggghts): wall impacts on %s%s, per class, from t = %.9g s: current wall contacts\n"
           "# of %.0f snapshots / Hertz wall contact time (src/demdata); rows: impacts per particle per second;\n"
           "# mu, sigma of the lognormal fit of the relative speed U = |v - v_wall| of the contacts in the snapshots\n"
           "# (%zu speeds fitted, those slower than %g m/s left out; %zu class(es) take the pooled fit mu %.6g, sigma %.6g)\n",
           wall < 0 ? "all walls" : "wall ", wall < 0 ? "" : c->wall_src[wall].name, c->stats_start, ns, np,
           GS_DEM_MIN_IMPACT_SPEED, pooled, pmu, psg);
  return gs_dem_impact_table_write(path, comment, ncl, e, 0, rate, mu, sg, err);
}

int gs_lig_reduce(const gs_dem_case *c, const char *out, const gs_lig_thermo *th, gs_error *err) {
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
      for (int q = 1; q <= 14; q++) fprintf(fp, " c_wgl[%d]", q);
      fprintf(fp, "\n");
      fclose(fp);
    }
    closedir(dp);
  }
  int rc = gs_dem_data_read(post, &opt, &dd, err);
  if (rc) return gs_error_prefix(err, "reducing the LIGGGHTS dumps: ");
  pass a = {.ncl = ncl, .ncmp = c->ncmp, .nw = nw, .nbins = 40, .dv = c->prm.impact_dv > 0 ? c->prm.impact_dv : 0.25};
  size_t nc = ncl * c->ncmp;
  a.num = calloc(ncl, sizeof(double));
  a.cv_n = calloc(nc, sizeof(double)), a.cv_s = calloc(nc, sizeof(double)), a.cv_s2 = calloc(nc, sizeof(double));
  a.cv_a = calloc(nc, sizeof(double)), a.cv_v = calloc(3 * nc, sizeof(double)), a.cv_v2 = calloc(3 * nc, sizeof(double));
  a.wall_contacts = calloc(nw * ncl + 1, sizeof(double));
  a.hist = calloc(nw * ncl * (size_t)a.nbins + 1, sizeof(double));
  if (!a.num || !a.cv_n || !a.cv_s || !a.cv_s2 || !a.cv_a || !a.cv_v || !a.cv_v2 || !a.wall_contacts || !a.hist)
    rc = gs_error_set(err, GS_ENOMEM, "out of memory");
  for (size_t s = 0; !rc && s < dd.nsnap; s++) rc = snapshot(&a, c, post, dd.steps[s], err);
  const double ns = dd.nsnap ? (double)dd.nsnap : 1;
  const double t0 = dd.nsnap ? dd.steps[0] * dt : NAN, t1 = dd.nsnap ? dd.steps[dd.nsnap - 1] * dt : NAN;
  const double win = c->duration - c->stats_start;
  FILE *fp = NULL;
  double e[GS_DEM_MAX_CLASSES + 1];
  gs_dem_class_edges(c, e);
  const char *note = "; engine liggghts: events = current contacts / Hertz contact time (src/demdata)";

  /* collisions per class pair */
  double *C = calloc(ncl * ncl, sizeof(double));
  if (!rc && !C) rc = gs_error_set(err, GS_ENOMEM, "out of memory");
  if (!rc && (fp = gs_dem_table_open(out, "collisions.csv", path, sizeof path, err))) {
    fprintf(fp, "# collision events from t = %.9g to %.9g s (%.9g s, %.0f snapshots from t = %.9g to %.9g s)%s\n",
            c->stats_start, c->duration, win, ns, t0, t1, note);
    fprintf(fp, "class_i,class_j,name_i,name_j,events,N_i,N_j,window_s,events_per_s,C_ij\n");
    for (size_t i = 0; i < ncl; i++)
      for (size_t j = i; j < ncl; j++) {
        double eps = dd.contacts[i * ncl + j] / dd.pair_contact_time[i * ncl + j];
        double Ni = a.num[i] / ns, Nj = a.num[j] / ns;
        double cij = Ni > 0 && Nj > 0 ? eps / (Ni * Nj) : 0;
        C[i * ncl + j] = C[j * ncl + i] = cij;
        fprintf(fp, "%zu,%zu,%s,%s,%.0f,%.6g,%.6g,%.9g,%.9g,%.9g\n", i + 1, j + 1, c->cls[i].name, c->cls[j].name,
                eps * win, Ni, Nj, win, eps, cij);
      }
    rc = gs_dem_table_close(fp, path, err);
  } else if (!rc) rc = err->code;
  if (!rc && (fp = gs_dem_table_open(out, "collision_kernel.csv", path, sizeof path, err))) {
    fprintf(fp, "# DEM collision frequency C_ij = N_coll,ij / (N_i N_j dt) [1/s], window %.9g s%s;\n"
            "# edges are particle diameters [m]: use `kernel: {type: table, measure: diameter, ...}`\nedges", win, note);
    for (size_t i = 0; i <= ncl; i++) fprintf(fp, ", %.9g", e[i]);
    fprintf(fp, "\n");
    for (size_t i = 0; i < ncl; i++) {
      for (size_t j = 0; j < ncl; j++) fprintf(fp, "%s%.9g", j ? ", " : "", C[i * ncl + j]);
      fprintf(fp, "\n");
    }
    rc = gs_dem_table_close(fp, path, err);
  } else if (!rc) rc = err->code;
  free(C);

  /* impacts per wall and class; the breakage selection's tables */
  if (!rc && (fp = gs_dem_table_open(out, "impacts.csv", path, sizeof path, err))) {
    fprintf(fp, "# wall impacts from t = %.9g to %.9g s (%.9g s)%s; vn, vt: not in LIGGGHTS' contact dumps (nan); "
            "impact_table.csv holds the fits of the relative speed\n", c->stats_start, c->duration, win, note);
    fprintf(fp, "wall,class,name,impacts,impacts_per_s,impacts_per_particle_s,mean_vn,std_vn,mean_vt\n");
    for (size_t w = 0; w < nw; w++)
      for (size_t i = 0; i < ncl; i++) {
        double Ni = a.num[i] / ns, per_s = a.wall_contacts[w * ncl + i] / ns / dd.wall_contact_time[i];
        fprintf(fp, "%s,%zu,%s,%.0f,%.9g,%.9g,nan,nan,nan\n", c->wall_src[w].name, i + 1, c->cls[i].name, per_s * win,
                per_s, Ni > 0 ? per_s / Ni : 0);
      }
    rc = gs_dem_table_close(fp, path, err);
  } else if (!rc) rc = err->code;
  if (!rc) rc = impact_table(&a, c, &dd, out, -1, ns, NULL, err);
  for (size_t w = 0; w < nw && !rc; w++) rc = impact_table(&a, c, &dd, out, (long)w, ns, NULL, err);
  if (!rc && (fp = gs_dem_table_open(out, "impact_velocity.csv", path, sizeof path, err))) {
    fprintf(fp, "# impact speed distributions (the last bin holds everything above); engine liggghts: the relative "
            "speed |v - v_wall| of the wall contacts in the snapshots, not the normal speed at first contact\n"
            "wall,class,vn_lo,vn_hi,impacts\n");
    for (size_t w = 0; w < nw; w++)
      for (size_t i = 0; i < ncl; i++)
        for (int b = 0; b < a.nbins; b++)
          fprintf(fp, "%s,%zu,%.6g,%.6g,%.0f\n", c->wall_src[w].name, i + 1, b * a.dv,
                  b + 1 < a.nbins ? (b + 1) * a.dv : HUGE_VAL, a.hist[(w * ncl + i) * (size_t)a.nbins + (size_t)b]);
    rc = gs_dem_table_close(fp, path, err);
  } else if (!rc) rc = err->code;

  /* velocities per class and compartment */
  if (!rc && (fp = gs_dem_table_open(out, "velocity.csv", path, sizeof path, err))) {
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
    rc = gs_dem_table_close(fp, path, err);
  } else if (!rc) rc = err->code;

  /* residence times: LIGGGHTS' delete_atoms keeps no record of who left when */
  if (!rc && (fp = gs_dem_table_open(out, "residence.csv", path, sizeof path, err))) {
    fprintf(fp, "# engine liggghts: residence times are not measured (delete_atoms keeps no record)\n"
            "t_lo,t_hi,count,fraction\n");
    rc = gs_dem_table_close(fp, path, err);
  } else if (!rc) rc = err->code;
  if (!rc && (fp = gs_dem_table_open(out, "residence_class.csv", path, sizeof path, err))) {
    fprintf(fp, "# engine liggghts: residence times are not measured (delete_atoms keeps no record)\n"
            "class,name,t_lo,t_hi,count,fraction\n");
    rc = gs_dem_table_close(fp, path, err);
  } else if (!rc) rc = err->code;

  /* the time series from LIGGGHTS' thermo rows; what it does not report is nan */
  if (!rc && (fp = gs_dem_table_open(out, "timeseries.csv", path, sizeof path, err))) {
    fprintf(fp, "time,particles,holdup_number,holdup_mass,kinetic_energy,rotational_energy,contacts,collisions_per_s");
    for (size_t w = 0; w < nw; w++) fprintf(fp, ",impacts_per_s_%s", c->wall_src[w].name);
    for (size_t w = 0; w < nw; w++) fprintf(fp, ",torque_axis_%s", c->wall_src[w].name);
    fprintf(fp, ",lost,steady,wall_seconds\n");
    for (size_t r = 0; r < th->n; r++) {
      const double *v = th->row + 5 * r;
      fprintf(fp, "%.9g,%.0f,%.0f,nan,%.9g,%.9g,nan,nan", v[0], v[1], v[1], v[2], v[3]);
      for (size_t w = 0; w < 2 * nw; w++) fprintf(fp, ",nan");
      fprintf(fp, ",nan,0,%.6f\n", v[4]);
    }
    rc = gs_dem_table_close(fp, path, err);
  } else if (!rc) rc = err->code;

  free(a.num), free(a.cv_n), free(a.cv_s), free(a.cv_s2), free(a.cv_a), free(a.cv_v), free(a.cv_v2);
  free(a.wall_contacts), free(a.ln_u), free(a.u_wc), free(a.hist);
  gs_dem_data_free(&dd);
  return rc;
}
