/* The steady-state detector's figures (docs/models.md, "Coupled cases").
 * The DEM runs with `statistics.start: steady`: its own detector (the
 * quantities of coupling.steady.quantities, each within `tolerance` of its
 * mean over the last `window` samples: hold-up mass and collision rate as
 * Sampat et al. 2018 for one-way, kinetic energy and collision rate for the
 * two-way cycles, De et al. 2025) starts the statistics window,
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
#include "gransim/dem.h"
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

/* The detector's quantities, in the order of gs_dem_steady_quantities: the
 * timeseries.csv columns summed for each, the steady.csv names, the units. */
static const struct {
  const char *col[2], *name, *label, *unit;
} quantity[3] = {{{"holdup_mass", NULL}, "holdup", "hold-up mass", "kg"},
                 {{"collisions_per_s", NULL}, "collisions", "collision rate", "/s"},
                 {{"kinetic_energy", "rotational_energy"}, "kinetic", "kinetic energy", "J"}};

int gs_couple_steady_report(const char *dem_dir, const gs_couple_settings *s, double *t_steady,
                            gs_error *err) {
  char path[4200], line[8192];
  snprintf(path, sizeof path, "%s/timeseries.csv", dem_dir);
  FILE *fp = fopen(path, "r");
  if (!fp) return gs_error_set(err, GS_EIO, "%s: cannot read: %s", path, strerror(errno));
  int col[3][2], cs = -1, ok = 1;
  if (fgets(line, sizeof line, fp)) {
    for (int q = 0; q < 3; q++)
      for (int j = 0; j < 2; j++) {
        col[q][j] = quantity[q].col[j] ? column(line, quantity[q].col[j]) : -1;
        ok = ok && (col[q][j] >= 0 || !quantity[q].col[j]);
      }
    cs = column(line, "steady");
  }
  if (!ok || cs < 0) {
    fclose(fp);
    return gs_error_set(err, GS_EINPUT, "%s: expected columns holdup_mass, collisions_per_s, kinetic_energy, "
                        "rotational_energy, steady", path);
  }
  size_t cap = 256, n = 0;
  double *t = malloc(cap * sizeof *t), *v[3];
  for (int q = 0; q < 3; q++) v[q] = malloc(cap * sizeof *v[q]);
  int *flag = malloc(cap * sizeof *flag), rc = GS_OK;
  while (t && v[0] && v[1] && v[2] && flag && fgets(line, sizeof line, fp)) {
    double x[64] = {0};
    int i = 0;
    for (char *tok = strtok(line, ",\r\n"); tok && i < 64; tok = strtok(NULL, ",\r\n")) x[i++] = strtod(tok, NULL);
    if (x[0] <= 0) continue; /* t = 0: no interval, no rate */
    if (n == cap) {
      cap *= 2;
      double *a = realloc(t, cap * sizeof *t);
      if (a) t = a;
      for (int q = 0; q < 3 && a; q++)
        if ((a = realloc(v[q], cap * sizeof *v[q]))) v[q] = a;
      int *f = a ? realloc(flag, cap * sizeof *flag) : NULL;
      if (f) flag = f;
      if (!f) break;
    }
    t[n] = x[0];
    for (int q = 0; q < 3; q++) {
      v[q][n] = 0;
      for (int j = 0; j < 2; j++)
        if (col[q][j] >= 0 && col[q][j] < 64) v[q][n] += x[col[q][j]];
    }
    flag[n] = x[cs] > 0.5;
    n++;
  }
  fclose(fp);
  if (!t || !v[0] || !v[1] || !v[2] || !flag)
    rc = gs_error_set(err, GS_ENOMEM, "out of memory");
  char names[96];
  gs_dem_steady_quantities_join(s->quantities, ", ", names, sizeof names);
  snprintf(path, sizeof path, "%s/steady.csv", dem_dir);
  gs_csv_out tab; /* its "#" lines go to steady.json */
  FILE *out = rc ? NULL : gs_csv_open(&tab, path, err);
  if (!rc && !out) rc = err->code;
  double mean[3] = {NAN, NAN, NAN}, dev[3] = {NAN, NAN, NAN}, fired[3] = {NAN, NAN, NAN};
  *t_steady = -1;
  if (out) {
    fprintf(out, "# steady-state detector of gransim couple: over the last %ld samples, %s within %g of their "
            "means (steady: the DEM's detector fired; the figures of the quantities it does not watch are "
            "informative)\n"
            "time,holdup_mass,collisions_per_s,kinetic_energy,holdup_mean,holdup_deviation,collisions_mean,"
            "collisions_deviation,kinetic_mean,kinetic_deviation,steady\n", s->window, names, s->tolerance);
    for (size_t k = 0; k < n; k++) {
      for (int q = 0; q < 3 && (long)k + 1 >= s->window; q++) window_figures(v[q], (long)k + 1, s->window, &mean[q], &dev[q]);
      fprintf(out, "%.9g,%.9g,%.9g,%.9g", t[k], v[0][k], v[1][k], v[2][k]);
      for (int q = 0; q < 3; q++) fprintf(out, ",%.9g,%.6g", mean[q], dev[q]);
      fprintf(out, ",%d\n", flag[k]);
      if (flag[k] && *t_steady < 0) {
        *t_steady = t[k];
        memcpy(fired, mean, sizeof fired);
      }
    }
    fprintf(out, "# %s\n", *t_steady >= 0 ? "steady" : "NOT STEADY");
    /* The detector fires once; a bed still filling or speeding up can pass it on
     * a short window.  The drift of the window means from the firing to the end
     * says whether the statistics window really was steady. */
    if (*t_steady >= 0) {
      double drift[3];
      char fig[3][160];
      int over = 0;
      for (int q = 0; q < 3; q++) {
        drift[q] = fabs(mean[q] - fired[q]) / fired[q];
        over |= (s->quantities & (1u << q)) && drift[q] > s->tolerance;
        snprintf(fig[q], sizeof fig[q], "%s %.6g -> %.6g %s (%.3g %%)", quantity[q].label, fired[q], mean[q],
                 quantity[q].unit, 100 * drift[q]);
      }
      fprintf(out, "# drift of the window means from the firing to the end: hold-up mass %.3g %%, collision rate "
              "%.3g %%, kinetic energy %.3g %%\n", 100 * drift[0], 100 * drift[1], 100 * drift[2]);
      if (over)
        fprintf(stderr, "gransim: warning: the DEM stage (%s): after the detector fired at t = %g s the window means "
                "drifted by more than the tolerance (%.3g %%): %s, %s, %s; the tables average a bed that was not "
                "steady: raise coupling.steady.window or max_time\n", path, *t_steady, 100 * s->tolerance, fig[0],
                fig[1], fig[2]);
    }
    static const char *const units[] = {"time", "s", "holdup_mass", "kg", "collisions_per_s", "1/s",
                                        "kinetic_energy", "J", "holdup_mean", "kg", "holdup_deviation", "1",
                                        "collisions_mean", "1/s", "collisions_deviation", "1", "kinetic_mean", "J",
                                        "kinetic_deviation", "1", "steady", "1", NULL};
    int wrc = gs_csv_close(&tab, "gransim couple", units, err);
    if (!rc) rc = wrc;
  }
  if (!rc && *t_steady < 0) {
    /* the watched quantities' figures first, as the detector judged them */
    char fig[512] = "";
    size_t used = 0;
    for (int pass = 0, k = 0; pass < 2; pass++, k = 0)
      for (int q = 0; q < 3 && used < sizeof fig; q++)
        if (!!(s->quantities & (1u << q)) == !pass)
          used += (size_t)snprintf(fig + used, sizeof fig - used, "%sthe %s is %.6g %s +- %.3g %%",
                                   k++ ? " and " : pass ? " (not watched: " : "", quantity[q].label, mean[q],
                                   quantity[q].unit, 100 * dev[q]);
    if (used < sizeof fig && (s->quantities & 7u) != 7u) snprintf(fig + used, sizeof fig - used, ")");
    rc = gs_error_set(err, GS_ENUMERIC,
                      "the DEM did not reach a steady state by t = %g s (coupling.steady.max_time): over the last "
                      "%ld samples %s (tolerance %.3g %%, coupling.steady.quantities: %s); run longer or loosen "
                      "coupling.steady (figures in %s)",
                      n ? t[n - 1] : 0.0, s->window, fig, 100 * s->tolerance, names, path);
  }
  free(t);
  for (int q = 0; q < 3; q++) free(v[q]);
  free(flag);
  return rc;
}
