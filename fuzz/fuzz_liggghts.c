/* Harness: what gransim reads of a LIGGGHTS run (gransim dem with engine:
 * liggghts, src/liggghts): the contact lists of pairs and walls
 * (events_pp.txt, events_wall.txt), a per-atom snapshot (collision<STEP>.atom)
 * and the screen output's thermo lines, reduced into the tables of a small
 * fixed case with two classes and a mesh wall, then a particle frame
 * (vtk/particles_100.dump, the deck's `dump custom` text frame) converted to
 * .vtp and .pvd (frames.c); the steady-state detector (steady.c) on the same
 * lists and snapshot.  The input holds the five files in that order,
 * separated by lines "%%". */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "harness.h"
#include "liggghts/lig_internal.h"

static char dir[256];
static gs_dem_case *the_case;

static void put(const char *name, const char *text, size_t n) {
  char path[512];
  snprintf(path, sizeof path, "%s/%s", dir, name);
  FILE *f = fopen(path, "wb");
  if (!f) return;
  if (n) fwrite(text, 1, n, f);
  fclose(f);
}

static void clean(void) {
  char cmd[600];
  snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
  if (system(cmd)) return;
}

static gs_dem_case *setup(void) {
  const char *tmp = getenv("TMPDIR");
  snprintf(dir, sizeof dir, "%s/gransim-fuzz-lig-%ld", tmp && *tmp ? tmp : "/tmp", (long)getpid());
  char sub[512];
  snprintf(sub, sizeof sub, "%s/liggghts/post", dir);
  if (mkdir(dir, 0777) || (snprintf(sub, sizeof sub, "%s/liggghts", dir), mkdir(sub, 0777)) ||
      (snprintf(sub, sizeof sub, "%s/liggghts/post", dir), mkdir(sub, 0777)) ||
      (snprintf(sub, sizeof sub, "%s/vtk", dir), mkdir(sub, 0777)))
    return NULL;
  atexit(clean);
  static const char stl[] = "solid t\n facet normal 0 0 1\n  outer loop\n   vertex -10 -10 0\n   vertex 10 -10 0\n"
                            "   vertex 10 10 0\n  endloop\n endfacet\nendsolid t\n";
  static const char yaml[] =
      "dem: {time_step: 2.5e-6, duration: 0.01, gravity: [0, -9.81, 0], engine: liggghts, seed: 5,\n"
      "      box: {lo: [-0.02, -0.02, -0.02], hi: [0.02, 0.02, 0.02]}, skin: 5.0e-4}\n"
      "materials:\n  - {name: g, E: 8.0e6, nu: 0.2, e: 0.4, mu_s: 0.5, mu_r: 0.2, density: 500}\n"
      "classes:\n  - {name: a, radius: 1.0e-3, material: g}\n  - {name: b, radius: 1.5e-3, material: g}\n"
      "walls:\n  - {name: plate, mesh: plate.stl, scale: 1.0e-3, material: g}\n"
      "fill:\n  - {region: {box: {lo: [-0.01, -0.01, 0.001], hi: [0.01, 0.01, 0.01]}}, count: 10}\n"
      "statistics: {start: 0, sample_every: 2.5e-4}\n";
  put("plate.stl", stl, sizeof stl - 1);
  put("case.yaml", yaml, sizeof yaml - 1);
  char path[512];
  snprintf(path, sizeof path, "%s/case.yaml", dir);
  gs_error err = {0};
  gs_dem_case *c = gs_dem_case_load(path, &err);
  if (!c) fprintf(stderr, "fuzz_liggghts: the fixed case does not load: %s\n", err.msg);
  return c;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  if (!the_case && !(the_case = setup())) abort();
  static const char *const files[] = {"liggghts/post/events_pp.txt", "liggghts/post/events_wall.txt",
                                      "liggghts/post/collision100.atom"};
  const char *at = (const char *)data, *end = at + size;
  gs_lig_thermo th = {.ncol = gs_lig_thermo_cols(the_case)};
  double cpu_acc[2] = {0, 0};
  for (int part = 0; part < 5; part++) {
    const char *sep = NULL;
    for (const char *p = at; p + 3 <= end && !sep; p++)
      if ((p == at || p[-1] == '\n') && !memcmp(p, "%%\n", 3)) sep = p;
    const char *stop = sep ? sep : end;
    if (part < 3) put(files[part], at, (size_t)(stop - at));
    else if (part == 4) put("vtk/particles_100.dump", at, (size_t)(stop - at));
    else {
      char *text = fuzz_input_text((const uint8_t *)at, (size_t)(stop - at));
      for (char *line = text ? strtok(text, "\n") : NULL; line; line = strtok(NULL, "\n"))
        if (gs_lig_thermo_add(&th, line, 2.5e-6, the_case->out_every, cpu_acc) < 0) break;
      free(text);
    }
    at = sep ? sep + 3 : end;
  }
  gs_error err = {0};
  const gs_lig_window w = {.t0 = 0, .t1 = gs_dem_case_duration(the_case), .t_steady = -1};
  if (gs_lig_reduce(the_case, dir, &th, &w, &err) && getenv("FUZZ_VERBOSE")) fprintf(stderr, "%s\n", err.msg);
  /* statistics.start: steady's detector reads the same lists and snapshot (steady.c) */
  gs_lig_steady sd;
  gs_lig_steady_init(&sd, the_case);
  char post[512];
  snprintf(post, sizeof post, "%s/liggghts/post", dir);
  gs_error serr = {0};
  if (gs_lig_steady_update(&sd, the_case, post, 100, &serr) && getenv("FUZZ_VERBOSE")) fprintf(stderr, "%s\n", serr.msg);
  gs_lig_steady_free(&sd);
  gs_error ferr = {0};
  if (gs_lig_vtk_frames(the_case, dir, &ferr) && getenv("FUZZ_VERBOSE")) fprintf(stderr, "%s\n", ferr.msg);
  free(th.row);
  return 0;
}
