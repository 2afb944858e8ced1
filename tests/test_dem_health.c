/* The DEM run's health checks (src/dem/health.c): overlapping particles at
 * the start (the insertion never places them so, so they are added by hand),
 * coincident centres among them,
 * a non-finite position, particles lost beyond dem.max_lost (at the limit
 * and one past it), and the engine's own failure explained with the
 * particle.  The command-line cases (time step, soft particles, meshes) are
 * in tests/cli_dem_refuses.sh. */
#include <math.h>
#include <string.h>

#include "dem/dem_internal.h"
#include "dem_testlib.h"

static const char *case_yaml =
    "dem:\n  time_step: 1.0e-6\n  duration: 1.0e-4\n  gravity: [0, 0, 0]\n"
    "  box: {lo: [-0.01, -0.01, -0.01], hi: [0.01, 0.01, 0.01]}\n"
    "materials:\n  - {name: g, E: 8.0e6, nu: 0.2, e: 0.4, mu_s: 0.5, density: 500}\n"
    "classes:\n  - {name: a, radius: 1.0e-3, material: g}\n";

static int has(const char *msg, const char *part) {
  if (strstr(msg, part)) return 1;
  fprintf(stderr, "message lacks '%s': %s\n", part, msg);
  return 0;
}

/* Two particles of radius 1 mm with centres `gap` apart, run for 100 steps. */
static int run_pair(double gap, gs_error *err) {
  gs_dem_case *c = dt_load("pair", case_yaml);
  if (!c) return -1;
  const double x1[3] = {0, 0, 0}, x2[3] = {gap, 0, 0};
  CHECK(gs_dem_add_particle(c->dem, c->cls[0].type, 1e-3, x1, NULL, NULL, err) >= 0);
  CHECK(gs_dem_add_particle(c->dem, c->cls[0].type, 1e-3, x2, NULL, NULL, err) >= 0);
  char out[600];
  snprintf(out, sizeof out, "%s/pair", dt_dir);
  int rc = gs_dem_case_run(c, out, 0, err);
  gs_dem_case_free(c);
  return rc;
}

/* Loads case_yaml with `extra` appended; its status and message in err. */
static int load_with(const char *name, const char *extra, gs_error *err) {
  char path[600];
  snprintf(path, sizeof path, "%s/%s.yaml", dt_dir, name);
  FILE *fp = fopen(path, "w");
  if (!fp) return -1;
  fprintf(fp, "%s%s", case_yaml, extra);
  fclose(fp);
  *err = (gs_error){0};
  gs_dem_case *c = gs_dem_case_load(path, err);
  gs_dem_case_free(c);
  return c ? GS_OK : err->code;
}

int main(void) {
  if (dt_scratch_begin("dem-health")) return 1;
  gs_error err = {0};

  /* resources stated before the run (src/dem/resources.c): 10 000 particles
   * need 3.45 MB at least; 200 frames of them 168 MB */
  const char *fill = "fill:\n  - {count: 10000, region: {box: {lo: [-0.01, -0.01, -0.01], hi: [0.01, 0.01, 0.01]}}}\n";
  char extra[800];
  snprintf(extra, sizeof extra, "%slimits: {memory_gb: 0.003}\n", fill);
  CHECK(load_with("mem", extra, &err) == GS_EINPUT);
  CHECK(has(err.msg, "limits: the case asks for 10000 particles (fill and feeds), which need at least 0.00345 GB"));
  snprintf(extra, sizeof extra, "%slimits: {memory_gb: 0.004}\n", fill);
  CHECK(load_with("mem-ok", extra, &err) == GS_OK);
  snprintf(extra, sizeof extra, "%soutput: {vtk_every: 5.0e-7}\nlimits: {output_gb: 0.1}\n", fill);
  CHECK(load_with("frames", extra, &err) == GS_EINPUT);
  CHECK(has(err.msg, "the particle frames (output.vtk_every) would take at least 0.169 GB (201 frames of 10000"));
  snprintf(extra, sizeof extra, "%soutput: {vtk_every: 5.0e-7}\nlimits: {output_gb: 0.2}\n", fill);
  CHECK(load_with("frames-ok", extra, &err) == GS_OK);

  /* 30 % of a radius at the start: refused before the first step, naming both */
  CHECK(run_pair(1.7e-3, &err) == GS_ENUMERIC);
  CHECK(has(err.msg, "particles 0 and 1 overlap by 30 % of the smaller radius (0.001 m) at step 0"));
  CHECK(has(err.msg, "the particles were placed inside each other"));
  /* coincident centres (distance 0, where the pair force's normal divides by
   * zero): refused by the same check before any force is used, with finite
   * figures, not a non-finite position or a crash */
  memset(&err, 0, sizeof err);
  CHECK(run_pair(0, &err) == GS_ENUMERIC);
  fprintf(stderr, "coincident centres: %s\n", err.msg);
  CHECK(has(err.msg, "particles 0 and 1 overlap by 200 % of the smaller radius (0.001 m) at step 0"));
  CHECK(has(err.msg, "the particles were placed inside each other"));
  CHECK(!strstr(err.msg, "nan") && !strstr(err.msg, "inf"));
  /* 5 %: accepted, and the pair is pushed apart without reaching 50 % */
  memset(&err, 0, sizeof err);
  if (run_pair(1.95e-3, &err) != GS_OK) {
    fprintf(stderr, "%s\n", err.msg);
    CHECK(!"a 5 percent overlap refused");
  }

  gs_dem_case *c = dt_load("health", case_yaml);
  if (!c) return 1;
  const double x[3] = {0, 0, 0};
  long id = gs_dem_add_particle(c->dem, c->cls[0].type, 1e-3, x, NULL, NULL, &err);
  CHECK(id >= 0);
  CHECK(gs_dem_run(c->dem, 0, &err) == GS_OK);
  gs_dem_health h;
  gs_dem_health_init(&h, c);
  h.inserted = 100;
  CHECK(gs_dem_health_check(&h, c, 0, &err) == GS_OK);
  /* 1 of 100 lost is the limit (dem.max_lost 0.01); 2 is past it */
  c->dem->lost += 1;
  CHECK(gs_dem_health_check(&h, c, 0, &err) == GS_OK);
  c->dem->lost += 1;
  CHECK(gs_dem_health_check(&h, c, 0, &err) == GS_ENUMERIC);
  CHECK(has(err.msg, "2 of the 100 particles inserted have left the box other than through an outlet by step 0"));
  c->dem->lost -= 2;
  /* a non-finite position, named with the particle */
  c->dem->p.y[0] = NAN;
  CHECK(gs_dem_health_check(&h, c, 0, &err) == GS_ENUMERIC);
  char want[128];
  snprintf(want, sizeof want, "particle %ld has a non-finite position (0, nan, 0)", id);
  CHECK(has(err.msg, want));
  CHECK(has(err.msg, "at step 0 (t = 0 s)"));
  /* the engine's own message keeps its place after the particle */
  gs_error_set(&err, GS_ENUMERIC, "engine said so");
  CHECK(gs_dem_health_explain(c, GS_ENUMERIC, &err) == GS_ENUMERIC);
  CHECK(has(err.msg, want) && has(err.msg, ": engine said so"));
  c->dem->p.y[0] = 0;
  gs_error_set(&err, GS_ENUMERIC, "engine said so");
  CHECK(gs_dem_health_explain(c, GS_ENUMERIC, &err) == GS_ENUMERIC && !strcmp(err.msg, "engine said so"));
  gs_dem_case_free(c);
  dt_scratch_end();
  return check_failures != 0;
}
