/* Zones of a granulator from DEM particle frames (zones.h). */
#include "demdata/zones.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "demdata/dump.h"
#include "demdata/kmeans.h"

#define ZONES_STARTS 4 /* k-means++ starts; the lowest inertia is kept */

int gs_zone_frames_add(gs_zone_frames *fr, gs_zone_frame *f, gs_error *err) {
  if (fr->nframe == fr->cap) {
    size_t cap = fr->cap ? 2 * fr->cap : 16;
    gs_zone_frame *g = realloc(fr->f, cap * sizeof *g);
    if (!g) return gs_error_set(err, GS_ENOMEM, "out of memory for %zu frames", cap);
    fr->f = g;
    fr->cap = cap;
  }
  fr->f[fr->nframe++] = *f;
  memset(f, 0, sizeof *f);
  return GS_OK;
}

static void frame_free(gs_zone_frame *f) {
  free(f->id);
  free(f->x);
  free(f->v);
  free(f->volume);
  memset(f, 0, sizeof *f);
}

void gs_zone_frames_free(gs_zone_frames *fr) {
  for (size_t i = 0; i < fr->nframe; i++) frame_free(&fr->f[i]);
  free(fr->f);
  memset(fr, 0, sizeof *fr);
}

int gs_zone_frames_read_dump(gs_zone_frames *fr, const char *path, double time_step, gs_error *err) {
  gs_dump d;
  if (gs_dump_read(path, &d, err)) return GS_EINPUT;
  static const char *const need[] = {"id", "x", "y", "z", "vx", "vy", "vz"};
  long col[7];
  int rc = GS_OK;
  for (int c = 0; c < 7 && !rc; c++)
    if ((col[c] = gs_dump_col(&d, need[c])) < 0)
      rc = gs_error_set(err, GS_EINPUT, "%s: no column '%s' (a particle frame needs id x y z vx vy vz)", path,
                        need[c]);
  long rcol = gs_dump_col(&d, "radius"), dcol = rcol < 0 ? gs_dump_col(&d, "diameter") : -1;
  gs_zone_frame f = {.t = (double)d.step * time_step, .n = d.nrows};
  if (!rc) {
    f.id = malloc((d.nrows + 1) * sizeof(long));
    f.x = malloc((3 * d.nrows + 1) * sizeof(double));
    f.v = malloc((3 * d.nrows + 1) * sizeof(double));
    f.volume = rcol >= 0 || dcol >= 0 ? malloc((d.nrows + 1) * sizeof(double)) : NULL;
    if (!f.id || !f.x || !f.v || ((rcol >= 0 || dcol >= 0) && !f.volume))
      rc = gs_error_set(err, GS_ENOMEM, "%s: out of memory for %zu particles", path, d.nrows);
  }
  for (size_t i = 0; !rc && i < d.nrows; i++) {
    const double *row = d.v + i * d.ncols;
    const long line = d.first_row_line + (long)i;
    for (int c = 0; c < 7 && !rc; c++)
      if (!isfinite(row[col[c]]))
        rc = gs_error_set(err, GS_EINPUT, "%s:%ld: column '%s' is not a finite number", path, line, need[c]);
    if (!rc && (row[col[0]] != floor(row[col[0]]) || fabs(row[col[0]]) > 1e15))
      rc = gs_error_set(err, GS_EINPUT, "%s:%ld: id %g is not an integer", path, line, row[col[0]]);
    if (rc) break;
    f.id[i] = (long)row[col[0]];
    for (int a = 0; a < 3; a++) {
      f.x[3 * i + (size_t)a] = row[col[1 + a]];
      f.v[3 * i + (size_t)a] = row[col[4 + a]];
    }
    if (f.volume) {
      const double r = rcol >= 0 ? row[rcol] : 0.5 * row[dcol];
      if (!(r > 0 && r < 1))
        rc = gs_error_set(err, GS_EINPUT, "%s:%ld: %s %g is not a particle size in (0, 1) m", path, line,
                          rcol >= 0 ? "radius" : "diameter", rcol >= 0 ? r : 2 * r);
      else f.volume[i] = 4.0 / 3.0 * M_PI * r * r * r;
    }
  }
  gs_dump_free(&d);
  if (!rc) rc = gs_zone_frames_add(fr, &f, err);
  frame_free(&f);
  if (!rc && !fr->source[0]) snprintf(fr->source, sizeof fr->source, "%s", path);
  return rc;
}

void gs_zone_frames_keep_from(gs_zone_frames *fr, double t0) {
  size_t kept = 0;
  for (size_t i = 0; i < fr->nframe; i++) {
    if (fr->f[i].t >= t0) fr->f[kept++] = fr->f[i];
    else frame_free(&fr->f[i]);
  }
  fr->nframe = kept;
}

static int by_time(const void *a, const void *b) {
  const double ta = ((const gs_zone_frame *)a)->t, tb = ((const gs_zone_frame *)b)->t;
  return (ta > tb) - (ta < tb);
}

static int by_id(const void *a, const void *b) {
  const long ia = *(const long *)a, ib = *(const long *)b;
  return (ia > ib) - (ia < ib);
}

int gs_zone_frames_sort(gs_zone_frames *fr, gs_error *err) {
  if (fr->nframe < 2) return gs_error_set(err, GS_EINPUT, "%zu particle frame(s): crossings need at least two", fr->nframe);
  qsort(fr->f, fr->nframe, sizeof *fr->f, by_time);
  for (size_t i = 1; i < fr->nframe; i++)
    if (!(fr->f[i].t > fr->f[i - 1].t))
      return gs_error_set(err, GS_EINPUT, "two particle frames at t = %g s (a repeated step, or --time-step missing)",
                          fr->f[i].t);
  int volumes = fr->f[0].volume != NULL;
  for (size_t i = 0; i < fr->nframe; i++) {
    if ((fr->f[i].volume != NULL) != volumes)
      return gs_error_set(err, GS_EINPUT, "some particle frames give radii and some do not");
    long *ids = malloc((fr->f[i].n + 1) * sizeof(long));
    if (!ids) return gs_error_set(err, GS_ENOMEM, "out of memory");
    memcpy(ids, fr->f[i].id, fr->f[i].n * sizeof(long));
    qsort(ids, fr->f[i].n, sizeof(long), by_id);
    size_t dup = 0;
    for (size_t j = 1; j < fr->f[i].n && !dup; j++) dup = ids[j] == ids[j - 1] ? j : 0;
    const long id = dup ? ids[dup] : 0;
    free(ids);
    if (dup) return gs_error_set(err, GS_EINPUT, "particle id %ld appears twice in the frame at t = %g s", id, fr->f[i].t);
  }
  return GS_OK;
}

/* The feature scales: L the RMS distance from the mean position, U the RMS
 * deviation from the mean velocity (1 where they vanish). */
static void scales(const gs_zone_frames *fr, double *L, double *U) {
  double n = 0, mx[3] = {0}, mv[3] = {0}, sx = 0, sv = 0;
  for (size_t f = 0; f < fr->nframe; f++)
    for (size_t i = 0; i < fr->f[f].n; i++, n++)
      for (int a = 0; a < 3; a++) {
        mx[a] += fr->f[f].x[3 * i + (size_t)a];
        mv[a] += fr->f[f].v[3 * i + (size_t)a];
      }
  for (int a = 0; a < 3; a++) {
    mx[a] /= n;
    mv[a] /= n;
  }
  for (size_t f = 0; f < fr->nframe; f++)
    for (size_t i = 0; i < fr->f[f].n; i++)
      for (int a = 0; a < 3; a++) {
        sx += pow(fr->f[f].x[3 * i + (size_t)a] - mx[a], 2);
        sv += pow(fr->f[f].v[3 * i + (size_t)a] - mv[a], 2);
      }
  *L = sx > 0 ? sqrt(sx / n) : 1;
  *U = sv > 0 ? sqrt(sv / n) : 1;
}

/* Renumber the zones by increasing mean height (z), then x, so that the
 * numbering does not depend on the seeds. */
static void renumber(gs_kmeans *km, size_t n) {
  const size_t k = km->k, dim = km->dim;
  size_t order[64], rank[64];
  for (size_t c = 0; c < k; c++) order[c] = c;
  for (size_t a = 1; a < k; a++)
    for (size_t b = a; b > 0; b--) {
      const double *p = km->centre + order[b - 1] * dim, *q = km->centre + order[b] * dim;
      if (p[2] < q[2] || (p[2] == q[2] && p[0] <= q[0])) break;
      size_t s = order[b];
      order[b] = order[b - 1];
      order[b - 1] = s;
    }
  double *c2 = malloc(k * dim * sizeof(double));
  if (!c2) return; /* keep k-means' numbering */
  for (size_t c = 0; c < k; c++) {
    rank[order[c]] = c;
    memcpy(c2 + c * dim, km->centre + order[c] * dim, dim * sizeof(double));
  }
  memcpy(km->centre, c2, k * dim * sizeof(double));
  free(c2);
  for (size_t i = 0; i < n; i++) km->label[i] = rank[km->label[i]];
}

static int alloc_zones(gs_zones *z, size_t k, int volumes, gs_error *err) {
  z->k = k;
  z->centre = calloc(3 * k, sizeof(double));
  z->holdup = calloc(k, sizeof(double));
  z->solid = volumes ? calloc(k, sizeof(double)) : NULL;
  z->speed = calloc(k, sizeof(double));
  z->rate = calloc(k * k, sizeof(double));
  z->rate_sd = calloc(k * k, sizeof(double));
  z->crossings = calloc(k * k, sizeof(double));
  z->exposure = calloc(k, sizeof(double));
  if (!z->centre || !z->holdup || (volumes && !z->solid) || !z->speed || !z->rate || !z->rate_sd ||
      !z->crossings || !z->exposure)
    return gs_error_set(err, GS_ENOMEM, "out of memory");
  return GS_OK;
}

/* Index of id in frame f (ids sorted in sorted, with their positions in pos), or -1. */
static long find_id(const long *sorted, const size_t *pos, size_t n, long id) {
  size_t lo = 0, hi = n;
  while (lo < hi) {
    size_t mid = lo + (hi - lo) / 2;
    if (sorted[mid] < id) lo = mid + 1;
    else hi = mid;
  }
  return lo < n && sorted[lo] == id ? (long)pos[lo] : -1;
}

typedef struct {
  long id;
  size_t pos;
} id_pos;
static int by_idpos(const void *a, const void *b) { return by_id(&((const id_pos *)a)->id, &((const id_pos *)b)->id); }

/* Hold-ups, speeds, centres, and crossings between successive frames. */
static int statistics(const gs_zone_frames *fr, gs_zones *z, gs_error *err) {
  const size_t k = z->k;
  size_t s0 = 0, maxn = 0;
  for (size_t f = 0; f < fr->nframe; f++) maxn = maxn > fr->f[f].n ? maxn : fr->f[f].n;
  id_pos *ip = malloc((maxn + 1) * sizeof *ip);
  long *sorted = malloc((maxn + 1) * sizeof(long));
  size_t *pos = malloc((maxn + 1) * sizeof(size_t)), *count = calloc(k, sizeof(size_t));
  if (!ip || !sorted || !pos || !count) {
    free(ip), free(sorted), free(pos), free(count);
    return gs_error_set(err, GS_ENOMEM, "out of memory");
  }
  for (size_t f = 0; f < fr->nframe; f++) {
    const gs_zone_frame *F = &fr->f[f];
    const size_t *lab = z->label + s0;
    for (size_t i = 0; i < F->n; i++) {
      const size_t c = lab[i];
      count[c]++;
      z->holdup[c] += 1.0 / (double)fr->nframe;
      if (z->solid) z->solid[c] += F->volume[i] / (double)fr->nframe;
      z->speed[c] += sqrt(F->v[3 * i] * F->v[3 * i] + F->v[3 * i + 1] * F->v[3 * i + 1] + F->v[3 * i + 2] * F->v[3 * i + 2]);
      for (int a = 0; a < 3; a++) z->centre[3 * c + (size_t)a] += F->x[3 * i + (size_t)a];
    }
    if (f + 1 < fr->nframe) { /* crossings to the next frame */
      const gs_zone_frame *G = &fr->f[f + 1];
      const size_t *next = lab + F->n;
      const double dt = G->t - F->t;
      for (size_t j = 0; j < G->n; j++) ip[j] = (id_pos){G->id[j], j};
      qsort(ip, G->n, sizeof *ip, by_idpos);
      for (size_t j = 0; j < G->n; j++) {
        sorted[j] = ip[j].id;
        pos[j] = ip[j].pos;
      }
      for (size_t i = 0; i < F->n; i++) {
        const long j = find_id(sorted, pos, G->n, F->id[i]);
        if (j < 0) continue; /* left the simulation: no crossing seen */
        z->exposure[lab[i]] += dt;
        if (next[j] != lab[i]) z->crossings[lab[i] * k + next[j]] += 1;
      }
    }
    s0 += F->n;
  }
  const double dt_mean = (fr->f[fr->nframe - 1].t - fr->f[0].t) / (double)(fr->nframe - 1);
  for (size_t c = 0; c < k; c++) {
    if (count[c]) {
      z->speed[c] /= (double)count[c];
      for (int a = 0; a < 3; a++) z->centre[3 * c + (size_t)a] /= (double)count[c];
    }
    double out = 0;
    for (size_t j = 0; j < k; j++) {
      if (j == c || !(z->exposure[c] > 0)) continue;
      z->rate[c * k + j] = z->crossings[c * k + j] / z->exposure[c];
      z->rate_sd[c * k + j] = sqrt(z->crossings[c * k + j]) / z->exposure[c];
      out += z->rate[c * k + j];
    }
    z->max_rate_dt = fmax(z->max_rate_dt, out * dt_mean);
  }
  free(ip), free(sorted), free(pos), free(count);
  return GS_OK;
}

int gs_zones_identify(const gs_zone_frames *fr, size_t k, size_t kmax, double velocity_weight,
                      unsigned long seed, gs_zones *z, gs_error *err) {
  memset(z, 0, sizeof *z);
  size_t n = 0;
  for (size_t f = 0; f < fr->nframe; f++) n += fr->f[f].n;
  if (k > 15 || kmax > 15)
    return gs_error_set(err, GS_EINPUT, "at most 15 zones (asked %zu)", k ? k : kmax);
  z->kmin = k ? k : 2;
  z->kmax = k ? k : kmax;
  if (z->kmax < z->kmin) return gs_error_set(err, GS_EINPUT, "the largest k tried must be >= 2");
  if (n < 2 * z->kmax)
    return gs_error_set(err, GS_EINPUT, "%zu particle samples are too few for %zu zones", n, z->kmax);
  z->velocity_weight = velocity_weight;
  z->nsample = n;
  scales(fr, &z->L, &z->U);
  double *x = malloc(6 * n * sizeof(double));
  if (!x) return gs_error_set(err, GS_ENOMEM, "out of memory for %zu particle samples", n);
  size_t s = 0;
  for (size_t f = 0; f < fr->nframe; f++)
    for (size_t i = 0; i < fr->f[f].n; i++, s++)
      for (int a = 0; a < 3; a++) {
        x[6 * s + (size_t)a] = fr->f[f].x[3 * i + (size_t)a] / z->L;
        x[6 * s + 3 + (size_t)a] = velocity_weight * fr->f[f].v[3 * i + (size_t)a] / z->U;
      }
  gs_kmeans best = {0};
  int rc = GS_OK;
  z->silhouette = -HUGE_VAL;
  for (size_t kk = z->kmin; !rc && kk <= z->kmax; kk++) {
    gs_kmeans km;
    rc = gs_kmeans_run(x, n, 6, kk, seed, ZONES_STARTS, &km, err);
    if (rc) break;
    const double sil = gs_kmeans_silhouette(x, n, &km);
    z->sil_by_k[kk] = sil;
    if (sil > z->silhouette) {
      z->silhouette = sil;
      gs_kmeans_free(&best);
      best = km;
    } else gs_kmeans_free(&km);
  }
  free(x);
  if (!rc) {
    renumber(&best, n);
    z->label = best.label;
    best.label = NULL;
    rc = alloc_zones(z, best.k, fr->f[0].volume != NULL, err);
  }
  gs_kmeans_free(&best);
  if (!rc) rc = statistics(fr, z, err);
  if (rc) gs_zones_free(z);
  return rc;
}

static void write_list(FILE *fp, const double *v, size_t n, size_t stride) {
  fputc('[', fp);
  for (size_t i = 0; i < n; i++) fprintf(fp, "%s%.6g", i ? ", " : "", v[i * stride]);
  fputc(']', fp);
}

int gs_zones_write(const gs_zones *z, const gs_zone_frames *fr, const char *path, gs_error *err) {
  FILE *fp = fopen(path, "w");
  if (!fp) return gs_error_set(err, GS_EIO, "cannot write %s: %s", path, strerror(errno));
  const size_t k = z->k;
  fprintf(fp, "# Compartments identified by `gransim compartments` from %s and %zu more frame(s):\n", fr->source,
          fr->nframe - 1);
  fprintf(fp, "# %zu particle samples over t = %.6g .. %.6g s, clustered by k-means on position / %.4g m and\n",
          z->nsample, fr->f[0].t, fr->f[fr->nframe - 1].t, z->L);
  fprintf(fp, "# %g x velocity / %.4g m/s; ", z->velocity_weight, z->U);
  if (z->kmin == z->kmax) fprintf(fp, "k = %zu given (silhouette %.3f).\n", k, z->silhouette);
  else {
    fprintf(fp, "k = %zu of largest simplified silhouette (", k);
    for (size_t kk = z->kmin; kk <= z->kmax; kk++) fprintf(fp, "%sk=%zu: %.3f", kk > z->kmin ? ", " : "", kk, z->sil_by_k[kk]);
    fprintf(fp, ").\n");
  }
  fprintf(fp, "# Zones are numbered by increasing mean height (z).  Largest K_i dt %.3g (the rates are\n"
              "# biased low by about half of it: write frames more often if it is not small).\n",
          z->max_rate_dt);
  fprintf(fp, "# Use: grid.compartments = compartments; the exchange mechanism reads this file\n"
              "# (mechanisms: [{type: exchange, file: THIS.yaml}]); velocity is each zone's u0 for\n"
              "# the semi_mechanistic kernel (kernel: {velocity: {fragment: THIS.yaml}}).\n");
  fprintf(fp, "compartments: %zu\n", k);
  fprintf(fp, "rates:            # K_ij [1/s], row = from, column = to\n");
  for (size_t i = 0; i < k; i++) {
    fprintf(fp, "  - ");
    write_list(fp, z->rate + i * k, k, 1);
    fputc('\n', fp);
  }
  fprintf(fp, "rates_sd:         # standard errors sqrt(n_ij) / T_i [1/s]\n");
  for (size_t i = 0; i < k; i++) {
    fprintf(fp, "  - ");
    write_list(fp, z->rate_sd + i * k, k, 1);
    fputc('\n', fp);
  }
  fprintf(fp, "velocity: ");
  write_list(fp, z->speed, k, 1);
  fprintf(fp, "      # mean particle speed [m/s]\nholdup: ");
  write_list(fp, z->holdup, k, 1);
  fprintf(fp, "        # mean particles per frame\n");
  if (z->solid) {
    fprintf(fp, "solid_volume: ");
    write_list(fp, z->solid, k, 1);
    fprintf(fp, "  # mean solid volume per frame [m^3]\n");
  }
  for (int a = 0; a < 3; a++) {
    fprintf(fp, "centre_%c: ", "xyz"[a]);
    write_list(fp, z->centre + a, k, 3);
    fprintf(fp, "      # mean position [m]\n");
  }
  const int bad = ferror(fp);
  if (fclose(fp) || bad) return gs_error_set(err, GS_EIO, "writing %s failed", path);
  return GS_OK;
}

void gs_zones_free(gs_zones *z) {
  free(z->centre);
  free(z->holdup);
  free(z->solid);
  free(z->speed);
  free(z->rate);
  free(z->rate_sd);
  free(z->crossings);
  free(z->exposure);
  free(z->label);
  memset(z, 0, sizeof *z);
}
