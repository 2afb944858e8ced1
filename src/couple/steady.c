/* The steady-state detector's figures (docs/models.md, "Coupled cases").
 * The DEM runs with `statistics.start: steady`: its own detector (hold-up
 * mass and collision rate both within `tolerance` of their means over the
 * last `window` samples; Sampat et al. 2018) starts the statistics window,
 * and the coupling's observer stops it steady.collect seconds later (at
 * coupling.steady.max_time at the latest).  With one time-series row per sample, the same figures are
 * recomputed here from timeseries.csv and written to steady.csv, so that a
 * user sees how close the bed came, and a DEM that never became steady is an
 * error naming the last figures rather than tables of nan. */
#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "couple/couple_internal.h"
#include "demdata/csv_meta.h"

/* Mean and largest relative deviation from it of the w values ending at a[n-1]. */
static void window_figures(const double *a, long n, long w, double *mean, double *dev) {
  double m = 0, d = 0;
  for (long k = n - w; k < n; k++) m += a[k];
  m /= (double)w;
  for (long k = n - w; k < n; k++) d = fmax(d, fabs(a[k] - m) / (m > 0 ? m : 1));
  *mean = m;
  *dev = m > 0 ? d : INFINITY;
}

static int column(const char *header, const char *name) {
  char h[8192];
  snprintf(h, sizeof h, "%s", header);
  int i = 0;
  for (char *tok = strtok(h, ",\r\n"); tok; tok = strtok(NULL, ",\r\n"), i++)
    if (!strcmp(tok, name)) return i;
  return -1;
}

int gs_couple_steady_report(const char *dem_dir, const gs_couple_settings *s, double *t_steady,
                            gs_error *err) {
  char path[4200], line[8192];
  snprintf(path, sizeof path, "%s/timeseries.csv", dem_dir);
  FILE *fp = fopen(path, "r");
  if (!fp) return gs_error_set(err, GS_EIO, "%s: cannot read: %s", path, strerror(errno));
  int cm = -1, cc = -1, cs = -1;
  if (fgets(line, sizeof line, fp)) {
    cm = column(line, "holdup_mass");
    cc = column(line, "collisions_per_s");
    cs = column(line, "steady");
  }
  if (cm < 0 || cc < 0 || cs < 0) {
    fclose(fp);
    return gs_error_set(err, GS_EINPUT, "%s: expected columns holdup_mass, collisions_per_s, steady", path);
  }
  size_t cap = 256, n = 0;
  double *t = malloc(cap * sizeof *t), *m = malloc(cap * sizeof *m), *c = malloc(cap * sizeof *c);
  int *flag = malloc(cap * sizeof *flag), rc = GS_OK;
  while (t && m && c && flag && fgets(line, sizeof line, fp)) {
    double v[64] = {0};
    int i = 0;
    for (char *tok = strtok(line, ",\r\n"); tok && i < 64; tok = strtok(NULL, ",\r\n")) v[i++] = strtod(tok, NULL);
    if (v[0] <= 0) continue; /* t = 0: no interval, no rate */
    if (n == cap) {
      cap *= 2;
      double *a = realloc(t, cap * sizeof *t), *b = a ? realloc(m, cap * sizeof *m) : NULL,
             *d = b ? realloc(c, cap * sizeof *c) : NULL;
      int *f = d ? realloc(flag, cap * sizeof *flag) : NULL;
      if (a) t = a;
      if (b) m = b;
      if (d) c = d;
      if (f) flag = f;
      if (!f) break;
    }
    t[n] = v[0];
    m[n] = v[cm];
    c[n] = v[cc];
    flag[n] = v[cs] > 0.5;
    n++;
  }
  fclose(fp);
  if (!t || !m || !c || !flag) rc = gs_error_set(err, GS_ENOMEM, "out of memory");
  snprintf(path, sizeof path, "%s/steady.csv", dem_dir);
  gs_csv_out tab; /* its "#" lines go to steady.json */
  FILE *out = rc ? NULL : gs_csv_open(&tab, path, err);
  if (!rc && !out) rc = err->code;
  double mm = NAN, md = NAN, cmn = NAN, cd = NAN, mm_f = NAN, cm_f = NAN;
  *t_steady = -1;
  if (out) {
    fprintf(out, "# steady-state detector of gransim couple: over the last %ld samples, hold-up mass and "
            "collision rate within %g of their means (steady: the DEM's detector fired)\n"
            "time,holdup_mass,collisions_per_s,holdup_mean,holdup_deviation,collisions_mean,"
            "collisions_deviation,steady\n", s->window, s->tolerance);
    for (size_t k = 0; k < n; k++) {
      if ((long)k + 1 >= s->window) {
        window_figures(m, (long)k + 1, s->window, &mm, &md);
        window_figures(c, (long)k + 1, s->window, &cmn, &cd);
      }
      fprintf(out, "%.9g,%.9g,%.9g,%.9g,%.6g,%.9g,%.6g,%d\n", t[k], m[k], c[k], mm, md, cmn, cd, flag[k]);
      if (flag[k] && *t_steady < 0) {
        *t_steady = t[k];
        mm_f = mm;
        cm_f = cmn;
      }
    }
    fprintf(out, "# %s\n", *t_steady >= 0 ? "steady" : "NOT STEADY");
    /* The detector fires once; a bed still filling or speeding up can pass it on
     * a short window.  The drift of the window means from the firing to the end
     * says whether the statistics window really was steady. */
    if (*t_steady >= 0) {
      double dm = fabs(mm - mm_f) / mm_f, dc = fabs(cmn - cm_f) / cm_f;
      fprintf(out, "# drift of the window means from the firing to the end: hold-up mass %.3g %%, collision rate "
              "%.3g %%\n", 100 * dm, 100 * dc);
      if (dm > s->tolerance || dc > s->tolerance)
        fprintf(stderr, "gransim: warning: the DEM stage (%s): after the detector fired at t = %g s the window means drifted by more "
                "than the tolerance (%.3g %%): hold-up mass %.6g -> %.6g kg (%.3g %%), collision rate %.6g -> %.6g /s "
                "(%.3g %%); the tables average a bed that was not steady: raise coupling.steady.window or "
                "max_time\n", path, *t_steady, 100 * s->tolerance, mm_f, mm, 100 * dm, cm_f, cmn, 100 * dc);
    }
    static const char *const units[] = {"time", "s", "holdup_mass", "kg", "collisions_per_s", "1/s",
                                        "holdup_mean", "kg", "holdup_deviation", "1", "collisions_mean", "1/s",
                                        "collisions_deviation", "1", "steady", "1", NULL};
    int wrc = gs_csv_close(&tab, "gransim couple", units, err);
    if (!rc) rc = wrc;
  }
  if (!rc && *t_steady < 0)
    rc = gs_error_set(err, GS_ENUMERIC,
                      "the DEM did not reach a steady state by t = %g s (coupling.steady.max_time): over the last "
                      "%ld samples the hold-up mass is %.6g kg +- %.3g %% and the collision rate %.6g /s +- %.3g %% "
                      "(tolerance %.3g %%); run longer or loosen coupling.steady (figures in %s)",
                      n ? t[n - 1] : 0.0, s->window, mm, 100 * md, cmn, 100 * cd, 100 * s->tolerance, path);
  free(t);
  free(m);
  free(c);
  free(flag);
  return rc;
}
