/* Shared helpers of the DEM tests (tests/test_dem_*.c): a scratch directory
 * for case files and outputs, loading and running a DEM case written from a
 * string, reading an output file back, and a triangulated disk.  Header-only;
 * every function is static. */
#ifndef GRANSIM_DEM_TESTLIB_H
#define GRANSIM_DEM_TESTLIB_H

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "check.h"
#include "dem/dem_case.h"

/* every helper is static; not every test uses every helper */
#define DT_FN static __attribute__((unused))

static char dt_dir[64];

/* Create the scratch directory /tmp/gransim-NAME-XXXXXX; 0 on success. */
DT_FN int dt_scratch_begin(const char *name) {
  snprintf(dt_dir, sizeof dt_dir, "/tmp/gransim-%s-XXXXXX", name);
  if (mkdtemp(dt_dir)) return 0;
  CHECK(!"mkdtemp");
  return -1;
}

/* Remove it, unless a check failed (then its files help to see why). */
DT_FN void dt_scratch_end(void) {
  char cmd[128];
  snprintf(cmd, sizeof cmd, "rm -rf %s", dt_dir);
  if (!check_failures) CHECK(system(cmd) == 0);
}

/* Write yaml to SCRATCH/NAME.yaml and load it (NULL, with a failed check and
 * the message on stderr, when it does not load). */
DT_FN gs_dem_case *dt_load(const char *name, const char *yaml) {
  char path[600];
  snprintf(path, sizeof path, "%s/%s.yaml", dt_dir, name);
  FILE *fp = fopen(path, "w");
  CHECK(fp != NULL);
  if (!fp) return NULL;
  fputs(yaml, fp);
  fclose(fp);
  gs_error err = {0};
  gs_dem_case *c = gs_dem_case_load(path, &err);
  if (!c) fprintf(stderr, "%s\n", err.msg);
  CHECK(c != NULL);
  return c;
}

/* Run a loaded case with its outputs in SCRATCH/NAME; the status. */
DT_FN int dt_run(gs_dem_case *c, const char *name) {
  char out[600];
  snprintf(out, sizeof out, "%s/%s", dt_dir, name);
  gs_error err = {0};
  int rc = gs_dem_case_run(c, out, 0, &err);
  if (rc) fprintf(stderr, "%s\n", err.msg);
  CHECK(rc == 0);
  return rc;
}

/* The text of output FILE of run NAME (malloc'ed; empty when missing). */
DT_FN char *dt_slurp(const char *name, const char *file) {
  char path[800];
  snprintf(path, sizeof path, "%s/%s/%s", dt_dir, name, file);
  FILE *fp = fopen(path, "r");
  if (!fp) {
    fprintf(stderr, "cannot read %s\n", path);
    CHECK(!"output file missing");
    return calloc(1, 1);
  }
  fseek(fp, 0, SEEK_END);
  long n = ftell(fp);
  rewind(fp);
  char *s = calloc((size_t)n + 1, 1);
  if (fread(s, 1, (size_t)n, fp) != (size_t)n) CHECK(!"short read");
  fclose(fp);
  return s;
}

/* A disk of radius R in the plane z = 0 centred on the origin, as nseg
 * triangles (9 coordinates each) fanned from the centre, normals +z. */
DT_FN void dt_disk(double *tri, double R, int nseg) {
  for (int k = 0; k < nseg; k++) {
    double a0 = 2 * M_PI * k / nseg, a1 = 2 * M_PI * (k + 1) / nseg;
    double t9[9] = {0, 0, 0, R * cos(a0), R * sin(a0), 0, R * cos(a1), R * sin(a1), 0};
    memcpy(tri + 9 * k, t9, sizeof t9);
  }
}

#endif
