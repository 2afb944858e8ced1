/* LIGGGHTS' particle frames as the embedded engine writes them: the deck
 * dumps text frames (`dump custom`, DIR/vtk/particles_<step>.dump: LIGGGHTS'
 * own custom/vtk writes ASCII legacy VTK without times, which ParaView
 * cannot put in a series and meshio misreads); after the run, or on
 * --reduce of a cluster run, each becomes DIR/vtk/particles_NNNNNN.vtp
 * (src/dem/vtk.c) at time step x dt, with the series particles.pvd. */
#include <dirent.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "dem/dem_vtk.h"
#include "demdata/dump.h"
#include "liggghts/lig_internal.h"

static int cmp_long(const void *a, const void *b) {
  const long x = *(const long *)a, y = *(const long *)b;
  return (x > y) - (x < y);
}

/* The steps of the frames in vdir, sorted; *n of them (0: none). */
static int frame_steps(const char *vdir, long **steps, size_t *n, gs_error *err) {
  *steps = NULL;
  *n = 0;
  DIR *dp = opendir(vdir);
  if (!dp) return errno == ENOENT ? GS_OK : gs_error_set(err, GS_EIO, "%s: cannot open: %s", vdir, strerror(errno));
  size_t cap = 0;
  int rc = GS_OK;
  for (struct dirent *e; !rc && (e = readdir(dp));) {
    long st;
    int end = 0;
    if (sscanf(e->d_name, "particles_%ld.dump%n", &st, &end) != 1 || e->d_name[end] || st < 0) continue;
    if (*n == cap) {
      cap = cap ? 2 * cap : 64;
      long *s = realloc(*steps, cap * sizeof *s);
      if (!s) rc = gs_error_set(err, GS_ENOMEM, "out of memory");
      else *steps = s;
    }
    if (!rc) (*steps)[(*n)++] = st;
  }
  closedir(dp);
  if (*n) qsort(*steps, *n, sizeof **steps, cmp_long);
  return rc;
}

/* One dump as a .vtp frame: every column checked (a class is a type 1..ncl). */
static int convert(const gs_dem_case *c, const char *dump, double t, const char *vtp, gs_error *err) {
  gs_dump d;
  int rc = gs_dump_read(dump, &d, err);
  if (rc) return rc;
  static const char *const need[] = {"id", "type", "radius", "x", "y", "z", "vx", "vy", "vz"};
  long col[9];
  for (int k = 0; k < 9 && !rc; k++)
    if ((col[k] = gs_dump_col(&d, need[k])) < 0) rc = gs_error_set(err, GS_EINPUT, "%s: no column '%s'", dump, need[k]);
  const size_t n = d.nrows, m = n ? n : 1;
  double *a = rc ? NULL : malloc(7 * m * sizeof *a);
  int32_t *cls = rc ? NULL : malloc(m * sizeof *cls);
  int64_t *id = rc ? NULL : malloc(m * sizeof *id);
  if (!rc && (!a || !cls || !id)) rc = gs_error_set(err, GS_ENOMEM, "out of memory");
  for (size_t i = 0; !rc && i < n; i++) {
    const double *v = d.v + i * d.ncols, type = v[col[1]], ident = v[col[0]];
    if (!(type >= 1 && type <= (double)c->nclass && type == floor(type))) {
      rc = gs_error_set(err, GS_EINPUT, "%s: type %g is no class (1 to %zu)", dump, type, c->nclass);
      break;
    }
    if (!(ident >= 0 && ident <= 9007199254740992.0 && ident == floor(ident))) {
      rc = gs_error_set(err, GS_EINPUT, "%s: atom id %g is not an id", dump, ident);
      break;
    }
    cls[i] = (int32_t)type; /* atom type k is class k (src/liggghts/deck.c) */
    id[i] = (int64_t)ident;
    for (int k = 0; k < 7; k++) a[k * m + i] = v[col[2 + k]];
  }
  gs_dump_free(&d);
  if (!rc) {
    const gs_dem_vtp_frame f = {.n = n, .t = t, .r = a, .x = a + m, .y = a + 2 * m, .z = a + 3 * m,
                                .vx = a + 4 * m, .vy = a + 5 * m, .vz = a + 6 * m, .cls = cls, .id = id};
    rc = gs_dem_write_vtp_frame(&f, vtp, err);
  }
  free(a), free(cls), free(id);
  return rc;
}

int gs_lig_vtk_frames(const gs_dem_case *c, const char *out, gs_error *err) {
  char vdir[4200], dump[4400], vtp[4400];
  snprintf(vdir, sizeof vdir, "%s/vtk", out);
  long *steps;
  size_t n;
  int rc = frame_steps(vdir, &steps, &n, err);
  if (rc || !n) return rc;
  double *times = malloc(n * sizeof *times);
  if (!times) rc = gs_error_set(err, GS_ENOMEM, "out of memory");
  for (size_t k = 0; !rc && k < n; k++) {
    times[k] = (double)steps[k] * c->prm.dt;
    snprintf(dump, sizeof dump, "%s/particles_%ld.dump", vdir, steps[k]);
    snprintf(vtp, sizeof vtp, "%s/particles_%06zu.vtp", vdir, k);
    rc = convert(c, dump, times[k], vtp, err);
  }
  if (!rc) {
    snprintf(vtp, sizeof vtp, "%s/particles.pvd", vdir);
    rc = gs_dem_write_pvd(vtp, "particles", times, (long)n, err);
  }
  /* the text frames go once the series is whole (a failed conversion keeps them for --reduce) */
  for (size_t k = 0; !rc && k < n; k++) {
    snprintf(dump, sizeof dump, "%s/particles_%ld.dump", vdir, steps[k]);
    remove(dump);
  }
  free(times);
  free(steps);
  return rc;
}
