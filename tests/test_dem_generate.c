/* Generated walls (walls[].generate, src/dem/generate*.c): the bowl's solid
 * volume and area equal those of the polygonal cylinders it is made of to
 * round-off (open cup, lidded vessel, dished bottom: the two caps are the
 * same shape one wall thickness apart, so the solid's volume is the flat
 * one's); every mesh is closed with outward normals; the dish's vertices lie
 * on its sphere; the impeller's volume is the hub's prism plus the blades'
 * boxes, its tip where the keys put it, its speed the rpm; bad keys are
 * refused naming them; the STL written beside a run reads back as the same
 * triangles; a DEM run with the impeller turning in the bowl loses no
 * particle while the blades push the bed; and the LIGGGHTS deck of the same
 * case names the written files (refused before they exist), with the
 * impeller's rotation.  With `start` the impeller stands still until then
 * (a bed settles with it at rest) and turns by omega (t - start) after it,
 * and the steady-state detector sees only samples after the start. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "check.h"
#include "dem/dem_case.h"
#include "dem/dem_generate.h"
#include "dem/dem_internal.h"
#include "gransim/dem.h"
#include "gransim/liggghts.h"

/* area of the regular n-gon inscribed in a circle of radius r */
static double ngon(int n, double r) { return 0.5 * n * r * r * sin(2 * M_PI / n); }
/* its perimeter */
static double perim(int n, double r) { return 2 * n * r * sin(M_PI / n); }

static int gen(const char *yaml, gs_dem_tris *t, gs_dem_gen_motion *gm, gs_error *err) {
  gs_cfg *cfg = gs_cfg_load_string(yaml, "gen.yaml", err);
  if (!cfg) return err->code;
  memset(t, 0, sizeof *t);
  int rc = gs_dem_generate(gs_cfg_root(cfg), t, gm, err);
  gs_cfg_free(cfg);
  return rc;
}

static size_t open_edges(const gs_dem_tris *t) {
  gs_error err = {0};
  gs_dem_mesh *m = gs_dem_mesh_from_triangles(t->v, t->ntri, &err);
  size_t nopen = 99, tri;
  int k;
  if (m) gs_dem_mesh_open_edges(m, &nopen, &tri, &k, &err);
  gs_dem_mesh_free(m);
  return nopen;
}

static void bowls(void) {
  const double R = 0.05, H = 0.08, t = 0.004, Ro = R + t;
  const int n = 48;
  gs_dem_tris tr;
  gs_dem_gen_motion gm;
  gs_error err = {0};
  double vol, area;
  /* the open cup */
  CHECK(!gen("{type: bowl, diameter: 0.1, height: 0.08, wall_thickness: 0.004, segments: 48}", &tr, &gm, &err));
  gs_dem_tris_measure(tr.v, tr.ntri, &vol, &area);
  CHECK_REL(vol, ngon(n, Ro) * (H + t) - ngon(n, R) * H, 1e-12);
  CHECK_REL(area, perim(n, R) * H + ngon(n, R) + (ngon(n, Ro) - ngon(n, R)) + perim(n, Ro) * (H + t) + ngon(n, Ro),
            1e-12);
  CHECK(open_edges(&tr) == 0);
  CHECK(!gm.rotating);
  CHECK(tr.ntri == (size_t)(n * (1 + 2 + 2 + 2 + 1)));
  gs_dem_tris_free(&tr);
  /* with a lid: the outside and the cavity, whose normals point into it */
  CHECK(!gen("{type: bowl, diameter: 0.1, height: 0.08, wall_thickness: 0.004, segments: 48, lid: true}", &tr, &gm,
             &err));
  gs_dem_tris_measure(tr.v, tr.ntri, &vol, &area);
  CHECK_REL(vol, ngon(n, Ro) * (H + 2 * t) - ngon(n, R) * H, 1e-12);
  CHECK_REL(area, perim(n, R) * H + 2 * ngon(n, R) + perim(n, Ro) * (H + 2 * t) + 2 * ngon(n, Ro), 1e-12);
  CHECK(open_edges(&tr) == 0);
  /* the cavity alone (the second half of the facets: it is built second,
   * with as many facets as the outside) encloses -A(R) H */
  double cav;
  gs_dem_tris_measure(tr.v + 9 * (tr.ntri / 2), tr.ntri / 2, &cav, NULL);
  CHECK_REL(cav, -ngon(n, R) * H, 1e-12);
  gs_dem_tris_free(&tr);
  /* a dished bottom, 1 cm deep, moved to another origin */
  const double h = 0.01, rho = (R * R + h * h) / (2 * h);
  CHECK(!gen("{type: bowl, diameter: 0.1, height: 0.08, wall_thickness: 0.004, segments: 48, bottom: dished, "
             "dish_depth: 0.01, dish_rings: 6, origin: [0.1, 0.2, 0.3]}", &tr, &gm, &err));
  gs_dem_tris_measure(tr.v, tr.ntri, &vol, &area);
  /* the volume about the new origin: shift back (the measure uses the origin) */
  for (size_t k = 0; k < 3 * tr.ntri; k++) tr.v[3 * k] -= 0.1, tr.v[3 * k + 1] -= 0.2, tr.v[3 * k + 2] -= 0.3;
  gs_dem_tris_measure(tr.v, tr.ntri, &vol, &area);
  CHECK_REL(vol, ngon(n, Ro) * (H + t) - ngon(n, R) * H, 1e-9);
  CHECK(open_edges(&tr) == 0);
  double zmin = HUGE_VAL, worst = 0;
  for (size_t k = 0; k < 3 * tr.ntri; k++) {
    const double *p = tr.v + 3 * k;
    zmin = fmin(zmin, p[2]);
    /* vertices of the inner cap: below the rim, inside the wall */
    if (p[2] < -1e-12 && hypot(p[0], p[1]) < R * (1 - 1e-9)) {
      /* a vertex of a cap lies on the inner sphere or on the outer one (the
       * same, t lower) */
      const double r = hypot(p[0], p[1]);
      worst = fmax(worst, fmin(fabs(hypot(r, p[2] - (rho - h)) - rho), fabs(hypot(r, p[2] - (rho - h - t)) - rho)));
    }
  }
  CHECK_REL(zmin, -h - t, 1e-12);
  CHECK(worst < 1e-15); /* on the sphere to round-off (m) */
  gs_dem_tris_free(&tr);
}

static void impeller(void) {
  gs_dem_tris tr;
  gs_dem_gen_motion gm;
  gs_error err = {0};
  double vol;
  const double rh = 0.01, L = 0.035, b = 0.012, th = 0.003, c = 0.003, a = M_PI / 4;
  CHECK(!gen("{type: impeller, blades: 3, blade_length: 0.035, blade_height: 0.012, blade_thickness: 0.003, "
             "pitch: 45, hub_diameter: 0.02, clearance: 0.003, rpm: 300, segments: 24}", &tr, &gm, &err));
  gs_dem_tris_measure(tr.v, tr.ntri, &vol, NULL);
  const double ez = 0.5 * b * cos(a) + 0.5 * th * sin(a), ey = 0.5 * b * sin(a) + 0.5 * th * cos(a);
  /* overlapping closed shells: their volumes add */
  CHECK_REL(vol, ngon(24, rh) * 2 * ez + 3 * (rh + L - 0.5 * rh) * b * th, 1e-12);
  CHECK(open_edges(&tr) == 0);
  double zlo = HUGE_VAL, rmax = 0;
  for (size_t k = 0; k < 3 * tr.ntri; k++) {
    zlo = fmin(zlo, tr.v[3 * k + 2]);
    rmax = fmax(rmax, hypot(tr.v[3 * k], tr.v[3 * k + 1]));
  }
  CHECK_REL(zlo, c, 1e-12);
  CHECK_REL(rmax, hypot(rh + L, ey), 1e-12);
  CHECK(gm.rotating && gm.axis[2] == 1);
  CHECK_REL(gm.omega, 300 * 2 * M_PI / 60, 1e-15);
  CHECK(gm.start == 0);
  gs_dem_tris_free(&tr);
  CHECK(!gen("{type: impeller, blade_length: 0.035, blade_height: 0.012, hub_diameter: 0.02, clearance: 0.003, "
             "rpm: 300, start: 0.25}", &tr, &gm, &err));
  CHECK(gm.rotating && gm.start == 0.25);
  gs_dem_tris_free(&tr);
}

/* The first time the case's detector fired (-1: never). */
static int first_steady(const gs_dem_sample *smp, void *user, int *open_window, int *stop, gs_error *err) {
  (void)open_window;
  (void)stop;
  (void)err;
  double *t = user;
  if (smp->steady && *t < 0) *t = smp->t;
  return GS_OK;
}

/* RUN's bed with the impeller at 200 rpm from start = 0.1 s, run to
 * duration: the impeller's first vertex at the end against where the STL
 * (t = 0) has it, turned by omega (duration - start); the detector (window of
 * 3 samples of 0.005 s, a tolerance any positive rate meets) fires at the
 * third sample after the start, not while the particles fall at rest. */
static void start_at_rest(double duration) {
  gs_error err = {0};
  char dir[] = "/tmp/gransim_generate_XXXXXX", yaml[2048], path[4200];
  CHECK(mkdtemp(dir) != NULL);
  snprintf(yaml, sizeof yaml,
           "dem: {time_step: 1.0e-5, duration: %g, gravity: [0, 0, -9.81], seed: 3,\n"
           "      box: {lo: [-0.07, -0.07, -0.02], hi: [0.07, 0.07, 0.12]}}\n"
           "materials:\n"
           "  - {name: granule, E: 5.0e6, nu: 0.3, e: 0.5, mu_s: 0.5, mu_r: 0.1, density: 1668}\n"
           "classes:\n"
           "  - {name: small, radius: 2.5e-3, material: granule}\n"
           "walls:\n"
           "  - {name: bowl, material: granule, generate: {type: bowl, diameter: 0.1, height: 0.08}}\n"
           "  - name: impeller\n"
           "    material: granule\n"
           "    generate: {type: impeller, blades: 3, blade_length: 0.03, blade_height: 0.012, "
           "hub_diameter: 0.02, clearance: 0.006, rpm: 200, start: 0.1}\n"
           "fill:\n"
           "  - region: {cylinder: {point: [0, 0, 0], axis: [0, 0, 1], radius: 0.045, inner_radius: 0.012, "
           "from: 0.02, to: 0.05}}\n"
           "    count: 100\n"
           "statistics: {sample_every: 0.005, start: steady, steady: {window: 3, tolerance: 100}}\n"
           "output: {every: 0.05}\n",
           duration);
  gs_cfg *cfg = gs_cfg_load_string(yaml, "start.yaml", &err);
  gs_dem_case *c = cfg ? gs_dem_case_from_cfg(cfg, &err) : NULL;
  if (!c) {
    fprintf(stderr, "%s\n", err.msg);
    CHECK(0);
    return;
  }
  double t_steady = -1;
  gs_dem_observer ob = {.sample = first_steady, .user = &t_steady};
  gs_dem_case_set_observer(c, &ob);
  int rc = gs_dem_case_run(c, dir, 0, &err);
  if (rc) fprintf(stderr, "%s\n", err.msg);
  CHECK(rc == 0);
  gs_dem *d = gs_dem_case_sim(c);
  snprintf(path, sizeof path, "%s/geometry/impeller.stl", dir);
  gs_dem_mesh *m = gs_dem_mesh_read_stl(path, 1, &err);
  CHECK(m != NULL);
  const double omega = 200 * 2 * M_PI / 60, th = omega * fmax(0, duration - 0.1);
  if (m) {
    double *now = malloc(9 * m->ntri * sizeof *now);
    CHECK(now != NULL);
    if (now) {
      gs_dem_wall_triangles(d, 1, now);
      /* the STL's outermost vertex (a blade's tip) turned by th about z */
      size_t k = 0;
      for (size_t j = 1; j < 3 * m->ntri; j++)
        if (hypot(m->v[3 * j], m->v[3 * j + 1]) > hypot(m->v[3 * k], m->v[3 * k + 1])) k = j;
      const double x = m->v[3 * k], y = m->v[3 * k + 1];
      CHECK(hypot(x, y) > 0.04);
      CHECK_ABS(now[3 * k], x * cos(th) - y * sin(th), 1e-12);
      CHECK_ABS(now[3 * k + 1], x * sin(th) + y * cos(th), 1e-12);
      CHECK_ABS(now[3 * k + 2], m->v[3 * k + 2], 1e-12);
    }
    free(now);
    gs_dem_mesh_free(m);
  }
  if (duration > 0.1) {
    CHECK_ABS(t_steady, 0.115, 1e-9);
  } else {
    CHECK(t_steady < 0);
  }
  gs_dem_case_free(c);
  char cmd[4300];
  snprintf(cmd, sizeof cmd, "rm -rf %s", dir);
  CHECK(system(cmd) == 0);
}

static int refused(const char *yaml, const char *want) {
  gs_dem_tris tr;
  gs_dem_gen_motion gm;
  gs_error err = {0};
  int rc = gen(yaml, &tr, &gm, &err);
  gs_dem_tris_free(&tr);
  if (!rc || !strstr(err.msg, want)) {
    fprintf(stderr, "expected an error with '%s' for %s, got: %s\n", want, yaml, rc ? err.msg : "(accepted)");
    return 0;
  }
  return 1;
}

static void bad_keys(void) {
  CHECK(refused("{type: bol, diameter: 0.1, height: 0.1}", "did you mean 'bowl'"));
  CHECK(refused("{type: bowl, diameter: 0.1, hieght: 0.1}", "height"));
  CHECK(refused("{type: bowl, diameter: 0.1, height: 0.1, heigth: 0.2}", "heigth"));
  CHECK(refused("{type: bowl, diameter: -0.1, height: 0.1}", "diameter"));
  CHECK(refused("{type: bowl, diameter: 0.1, height: 0.1, dish_depth: 0.01}", "bottom: dished"));
  CHECK(refused("{type: bowl, diameter: 0.1, height: 0.1, bottom: dished, dish_depth: 0.06}", "dish_depth"));
  CHECK(refused("{type: impeller, blade_length: 0.03, blade_height: 0.03, hub_diameter: 0.01, clearance: 0}",
                "narrower than the pitched blade"));
  CHECK(refused("{type: impeller, blade_length: 0.03, blade_height: 0.01, hub_diameter: 0.03, clearance: 0, "
                "hub_height: 0.001}", "hub_height"));
  CHECK(refused("{type: impeller, blade_length: 0.03, blade_height: 0.01, hub_diameter: 0.03, clearance: 0, "
                "pitch: 90}", "pitch"));
  CHECK(refused("{type: impeller, blade_length: 0.03, blade_height: 0.01, hub_diameter: 0.03, clearance: 0, "
                "start: 0.1}", "a start time needs an impeller that turns (rpm)"));
  CHECK(refused("{type: impeller, blade_length: 0.03, blade_height: 0.01, hub_diameter: 0.03, clearance: 0, "
                "rpm: 10, start: -1}", "start"));
}

/* A lid-less bowl with the impeller at 200 rpm under a bed of 300 particles. */
static const char *RUN =
    "dem: {time_step: 1.0e-5, duration: 0.25, gravity: [0, 0, -9.81], seed: 3,\n"
    "      box: {lo: [-0.07, -0.07, -0.02], hi: [0.07, 0.07, 0.12]}}\n"
    "materials:\n"
    "  - {name: granule, E: 5.0e6, nu: 0.3, e: 0.5, mu_s: 0.5, mu_r: 0.1, density: 1668}\n"
    "  - {name: steel, E: 5.0e6, nu: 0.3, e: 0.5, mu_s: 0.5, mu_r: 0.1}\n"
    "classes:\n"
    "  - {name: small, radius: 1.5e-3, material: granule}\n"
    "  - {name: large, radius: 2.5e-3, material: granule}\n"
    "walls:\n"
    "  - {name: bowl, material: steel, generate: {type: bowl, diameter: 0.1, height: 0.08}}\n"
    "  - name: impeller\n"
    "    material: steel\n"
    "    generate: {type: impeller, blades: 3, blade_length: 0.03, blade_height: 0.012, blade_thickness: 0.003,\n"
    "               hub_diameter: 0.02, clearance: 0.006, rpm: 200}\n"
    "fill:\n"
    "  - region: {cylinder: {point: [0, 0, 0], axis: [0, 0, 1], radius: 0.045, inner_radius: 0.012, from: 0.02,\n"
    "                        to: 0.05}}\n"
    "    count: 300\n"
    "output: {every: 0.05}\n";

static void run(void) {
  gs_error err = {0};
  char dir[] = "/tmp/gransim_generate_XXXXXX";
  CHECK(mkdtemp(dir) != NULL);
  gs_cfg *cfg = gs_cfg_load_string(RUN, "bowl.yaml", &err);
  gs_dem_case *c = cfg ? gs_dem_case_from_cfg(cfg, &err) : NULL;
  if (!c) {
    fprintf(stderr, "%s\n", err.msg);
    CHECK(0);
    return;
  }
  int rc = gs_dem_case_run(c, dir, 0, &err);
  if (rc) fprintf(stderr, "%s\n", err.msg);
  CHECK(rc == 0);
  gs_dem *d = gs_dem_case_sim(c);
  gs_dem_counters k;
  gs_dem_get_counters(d, &k);
  gs_dem_view v;
  gs_dem_get_view(d, &v);
  CHECK(k.lost == 0);
  CHECK(v.n == 300);
  /* the blades moved the bed: it turns with them (mean angular velocity
   * about z of the same sign as the impeller's) */
  double lz = 0;
  for (size_t i = 0; i < v.n; i++) lz += v.x[i] * v.vy[i] - v.y[i] * v.vx[i];
  CHECK(lz > 0);
  /* the STL beside the run holds the engine's triangles */
  char path[4200];
  for (size_t w = 0; w < 2; w++) {
    snprintf(path, sizeof path, "%s/geometry/%s.stl", dir, w ? "impeller" : "bowl");
    gs_dem_mesh *m = gs_dem_mesh_read_stl(path, 1, &err);
    CHECK(m != NULL);
    if (!m) continue;
    double got, want;
    gs_dem_tris_measure(m->v, m->ntri, &got, NULL);
    gs_dem_tris_measure(d->walls[w].mesh->v, d->walls[w].mesh->ntri, &want, NULL);
    CHECK(m->ntri == d->walls[w].mesh->ntri);
    CHECK_REL(got, want, 1e-15);
    gs_dem_mesh_free(m);
    remove(path);
  }
  snprintf(path, sizeof path, "%s/geometry", dir);
  rmdir(path);
  gs_dem_case_free(c);
  char cmd[4300];
  snprintf(cmd, sizeof cmd, "rm -rf %s", dir);
  CHECK(system(cmd) == 0);
}

static void liggghts_deck(void) {
  gs_error err = {0};
  char yaml[4096], dir[] = "/tmp/gransim_generate_lig_XXXXXX";
  CHECK(mkdtemp(dir) != NULL);
  /* the run's case on the LIGGGHTS engine */
  const char *at = strstr(RUN, "seed: 3,");
  snprintf(yaml, sizeof yaml, "%.*sengine: liggghts, %s", (int)(at - RUN), RUN, at);
  gs_cfg *cfg = gs_cfg_load_string(yaml, "bowl.yaml", &err);
  gs_dem_case *c = cfg ? gs_dem_case_from_cfg(cfg, &err) : NULL;
  if (!c) {
    fprintf(stderr, "%s\n", err.msg);
    CHECK(0);
    return;
  }
  char *buf = NULL;
  size_t n = 0;
  FILE *m = open_memstream(&buf, &n);
  CHECK(gs_lig_write_deck(c, m, NULL, NULL, &err) != 0); /* no file yet */
  CHECK(strstr(err.msg, "write it first") != NULL);
  fclose(m);
  free(buf);
  size_t nw = 0;
  CHECK(gs_dem_case_write_geometry(c, dir, &nw, &err) == 0 && nw == 2);
  m = open_memstream(&buf, &n);
  CHECK(gs_lig_write_deck(c, m, NULL, NULL, &err) == 0);
  fclose(m);
  /* the deck reads copies beside it, named after the wall and the written file */
  CHECK(buf && strstr(buf, "mesh/surface file wall0_bowl.stl"));
  CHECK(buf && strstr(buf, "mesh/surface/stress file wall1_impeller.stl")); /* turning: its torque */
  CHECK(buf && strstr(buf, "move/mesh mesh wall1 rotate origin 0 0 0 axis 0 0 1 period 0.3"));
  if (buf && !strstr(buf, "wall1_impeller.stl")) fprintf(stderr, "%s\n", buf);
  free(buf);
  gs_dem_case_free(c);
  char cmd[4300];
  snprintf(cmd, sizeof cmd, "rm -rf %s", dir);
  CHECK(system(cmd) == 0);
}

int main(void) {
  liggghts_deck();
  bowls();
  impeller();
  bad_keys();
  run();
  start_at_rest(0.08);
  start_at_rest(0.15);
  TEST_EXIT();
}
