/* dem.geometry_scale (src/dem/case_dem.c; docs/models.md, "System scaling"):
 * one case loaded at scale 1 and at s = 1.7 has every length of its geometry
 * times s (box; plane, cylinder, STL and generated walls; the rotation
 * origin; fill, outlet and hold-up regions; compartment origin and edges;
 * the spray point), the rotation's angular speed divided by s (the same tip
 * speed), and the rest unchanged (particle radii, materials, wall and
 * insertion velocities, the STL's own scale kept apart for the LIGGGHTS
 * deck).  A case with a gas section and a scale other than 1 is refused, as
 * are a scale <= 0 and a misspelt key (did you mean). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "check.h"
#include "dem/dem_case.h"
#include "dem/dem_generate.h"
#include "dem/dem_internal.h"
#include "dem/dem_wet.h"
#include "gransim/dem.h"

static const double S = 1.7;

/* The case; %s: the extra dem keys, %s: the STL file */
static const char *CASE =
    "dem: {time_step: 1.0e-5, duration: 0.1, gravity: [0, 0, -9.81], %s\n"
    "      box: {lo: [-0.07, -0.07, -0.02], hi: [0.07, 0.07, 0.12]}}\n"
    "materials:\n"
    "  - {name: granule, E: 5.0e6, nu: 0.3, e: 0.5, mu_s: 0.5, mu_r: 0.1, density: 1668}\n"
    "classes:\n"
    "  - {name: small, radius: [1.0e-3, 1.5e-3], material: granule}\n"
    "walls:\n"
    "  - {name: bowl, material: granule, generate: {type: bowl, diameter: 0.1, height: 0.08}}\n"
    "  - name: impeller\n"
    "    material: granule\n"
    "    generate: {type: impeller, blades: 3, blade_length: 0.03, blade_height: 0.012, blade_thickness: 0.003,\n"
    "               hub_diameter: 0.02, clearance: 0.006, rpm: 200}\n"
    "  - {name: floor, plane: {point: [0, 0, -0.01], normal: [0, 0, 1]}, material: granule, velocity: [0, 0, 0.1]}\n"
    "  - {name: drum, cylinder: {point: [0.01, 0, 0], axis: [0, 0, 1], radius: 0.065}, material: granule,\n"
    "     rotation: {origin: [0.01, 0.002, 0], axis: [0, 0, 1], rpm: 30}}\n"
    "  - {name: lid, mesh: %s, scale: 1.0e-3, material: granule}\n"
    "fill:\n"
    "  - region: {cylinder: {point: [0, 0, 0.001], axis: [0, 0, 1], radius: 0.045, inner_radius: 0.012,\n"
    "                        from: 0.02, to: 0.05}}\n"
    "    count: 10\n"
    "    velocity: [0.1, 0.2, 0.3]\n"
    "outlets:\n"
    "  - region: {box: {lo: [-0.01, -0.01, 0.1], hi: [0.01, 0.02, 0.11]}}\n"
    "statistics:\n"
    "  holdup_region: {box: {lo: [-0.05, -0.05, 0], hi: [0.05, 0.05, 0.08]}}\n"
    "  compartments: {axis: [0, 0, 1], origin: [0, 0.001, 0.002], edges: [0, 0.02, 0.05]}\n"
    "spray: {point: [0.001, 0.002, 0.09], axis: [0, 0, -1], half_angle: 20, droplet_diameter: 2.0e-4,\n"
    "        mass_rate: 1.0e-4, speed: 1}\n";

static gs_dem_case *load(const char *extra, const char *stl, gs_error *err) {
  char yaml[8192];
  snprintf(yaml, sizeof yaml, CASE, extra, stl);
  gs_cfg *cfg = gs_cfg_load_string(yaml, "scale.yaml", err);
  return cfg ? gs_dem_case_from_cfg(cfg, err) : NULL;
}

static void near3(const double *a, const double *b, double f) {
  for (int k = 0; k < 3; k++) CHECK(fabs(a[k] - f * b[k]) <= 1e-12 * (1 + fabs(a[k])));
}

static void region(const gs_dem_region *a, const gs_dem_region *b) {
  CHECK(a->kind == b->kind);
  if (a->kind == GS_DEM_REGION_BOX) {
    near3(a->lo, b->lo, S);
    near3(a->hi, b->hi, S);
  } else {
    near3(a->p, b->p, S);
    near3(a->a, b->a, 1);
    CHECK_REL(a->R, S * b->R, 1e-14);
    CHECK_REL(a->Rin, S * b->Rin, 1e-14);
    CHECK_REL(a->s0, S * b->s0, 1e-14);
    CHECK_REL(a->s1, S * b->s1, 1e-14);
  }
}

static void compare(const char *stl) {
  gs_error err = {0};
  char extra[64];
  snprintf(extra, sizeof extra, "geometry_scale: %.17g,", S);
  gs_dem_case *a = load("", stl, &err), *b = a ? load(extra, stl, &err) : NULL;
  if (!a || !b) {
    fprintf(stderr, "%s\n", err.msg);
    CHECK(0);
    gs_dem_case_free(a);
    return;
  }
  CHECK(a->geom == 1 && b->geom == S);
  near3(b->prm.lo, a->prm.lo, S);
  near3(b->prm.hi, a->prm.hi, S);
  near3(b->prm.gravity, a->prm.gravity, 1);
  CHECK(b->prm.skin == a->prm.skin); /* a particle length */
  CHECK(b->cls[0].rmin == a->cls[0].rmin && b->cls[0].rmax == a->cls[0].rmax);
  CHECK(b->nwall_src == 5 && a->nwall_src == 5);
  const gs_dem_wall *wa = gs_dem_case_sim(a)->walls, *wb = gs_dem_case_sim(b)->walls;
  for (size_t w = 0; w < 5; w++) {
    const gs_dem_wall_src *sa = &a->wall_src[w], *sb = &b->wall_src[w];
    near3(sb->origin, sa->origin, S);
    near3(sb->point, sa->point, S);
    near3(sb->velocity, sa->velocity, 1); /* a speed */
    CHECK_REL(sb->omega * S, sa->omega, 1e-14); /* the same tip speed */
    CHECK(sa->mat.E == sb->mat.E && sa->mat.e == sb->mat.e);
    const gs_dem_wall *ea = &wa[sa->wall], *eb = &wb[sb->wall];
    near3(eb->p, ea->p, S);
    CHECK_REL(eb->R, S * ea->R, 1e-14);
    near3(eb->origin, ea->origin, S);
    CHECK((ea->mesh != NULL) == (eb->mesh != NULL));
    if (ea->mesh && eb->mesh) {
      CHECK(ea->mesh->ntri == eb->mesh->ntri);
      for (size_t i = 0; i < 9 * ea->mesh->ntri; i += 7) CHECK(fabs(eb->mesh->v[i] - S * ea->mesh->v[i]) <= 1e-15);
    }
  }
  CHECK(a->wall_src[1].omega > 0 && a->wall_src[3].omega > 0); /* the impeller and the drum turn */
  CHECK_REL(a->wall_src[1].omega, 200 * 2 * M_PI / 60, 1e-14);
  /* the STL wall: its own scale times the geometry's (the LIGGGHTS deck scales the file so) */
  CHECK_REL(a->wall_src[4].scale, 1e-3, 1e-15);
  CHECK_REL(b->wall_src[4].scale, S * 1e-3, 1e-15);
  region(&b->fill[0].reg, &a->fill[0].reg);
  near3(b->fill[0].v, a->fill[0].v, 1);
  region(&b->outlets[0], &a->outlets[0]);
  region(&b->holdup, &a->holdup);
  near3(b->cmp_origin, a->cmp_origin, S);
  for (size_t k = 0; k < 3; k++) CHECK_REL(b->cmp_edges[k] + 1, S * a->cmp_edges[k] + 1, 1e-14);
  CHECK(a->wet && b->wet);
  if (a->wet && b->wet) {
    near3(b->wet->noz.point, a->wet->noz.point, S);
    CHECK(b->wet->noz.diameter == a->wet->noz.diameter);
  }
  gs_dem_case_free(a);
  gs_dem_case_free(b);
}

static void refused(const char *stl) {
  gs_error err = {0};
  gs_dem_case *c = load("geometry_scale: 0,", stl, &err);
  CHECK(!c && strstr(err.msg, "geometry_scale"));
  gs_dem_case_free(c);
  c = load("geometry_scal: 2,", stl, &err);
  CHECK(!c && strstr(err.msg, "geometry_scale"));
  gs_dem_case_free(c);
  /* the gas grid is not scaled */
  const char *gas = "dem: {time_step: 1.0e-5, duration: 0.1, geometry_scale: 2, box: {lo: [0, 0, 0], hi: [1, 1, 1]}}\n"
                    "materials: [{name: g, E: 5.0e6, nu: 0.3, e: 0.5, mu_s: 0.5, density: 1000}]\n"
                    "classes: [{name: c, radius: 1.0e-3, material: g}]\n"
                    "gas: {}\n";
  gs_cfg *cfg = gs_cfg_load_string(gas, "gas.yaml", &err);
  c = cfg ? gs_dem_case_from_cfg(cfg, &err) : NULL;
  CHECK(!c && strstr(err.msg, "gas.yaml:1") && strstr(err.msg, "cannot be scaled"));
  if (c || !strstr(err.msg, "cannot be scaled")) fprintf(stderr, "%s\n", err.msg);
  gs_dem_case_free(c);
}

int main(void) {
  /* an STL in millimetres: a generated bowl written out */
  char dir[] = "/tmp/gransim_geomscale_XXXXXX", stl[256];
  CHECK(mkdtemp(dir) != NULL);
  snprintf(stl, sizeof stl, "%s/lid.stl", dir);
  gs_error err = {0};
  gs_cfg *g = gs_cfg_load_string("{type: bowl, diameter: 20, height: 5}", "lid.yaml", &err);
  gs_dem_tris tr = {0};
  gs_dem_gen_motion gm;
  CHECK(g && !gs_dem_generate(gs_cfg_root(g), &tr, &gm, &err));
  for (size_t i = 0; i < 3 * tr.ntri; i++) tr.v[3 * i + 2] += 100; /* above the bowl */
  CHECK(!gs_dem_write_stl(stl, "lid", tr.v, tr.ntri, &err));
  gs_dem_tris_free(&tr);
  gs_cfg_free(g);
  compare(stl);
  refused(stl);
  unlink(stl);
  rmdir(dir);
  TEST_EXIT();
}
