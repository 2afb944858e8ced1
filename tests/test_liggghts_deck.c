/* The LIGGGHTS deck of a small case (src/liggghts/deck.c) holds the commands
 * and values the case gives: material properties (per type and pair means),
 * time step, gravity, the mesh and its scale, the impeller's rotation as a
 * period, the feed's insertion, the outlet, the dumps; and keys a deck cannot
 * express are refused naming them.  A plane wall's mesh is the polygon in
 * which it cuts the box: for x + y + z = 0 through a cube of half-size a the
 * regular hexagon of area 3 sqrt(3) a^2.  Runs without LIGGGHTS. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "check.h"
#include "gransim/dem.h"
#include "gransim/dem_data.h"
#include "gransim/liggghts.h"
#include "liggghts/lig_internal.h"

static const char *stl =
    "solid t\n facet normal 0 0 1\n  outer loop\n   vertex -10 -10 0\n   vertex 10 -10 0\n   vertex 10 10 0\n"
    "  endloop\n endfacet\nendsolid t\n";

static char *deck_of(const char *yaml, gs_error *err, int *rc) {
  FILE *fp = fopen("liggghts_deck_case.yaml", "w");
  fputs(yaml, fp);
  fclose(fp);
  gs_dem_case *c = gs_dem_case_load("liggghts_deck_case.yaml", err);
  if (!c) { *rc = err->code; return NULL; }
  char *buf = NULL;
  size_t n = 0;
  FILE *m = open_memstream(&buf, &n);
  *rc = gs_lig_write_deck(c, m, "bed.data", "read", err);
  fclose(m);
  CHECK(gs_dem_case_engine(c) == 1);
  gs_dem_case_free(c);
  return buf;
}

#define HAS(deck, s) do { if (!strstr(deck, s)) { fprintf(stderr, "deck lacks: %s\n", s); CHECK(0); } } while (0)

int main(void) {
  /* the case and its mesh in a folder of their own */
  char tmp[] = "/tmp/gransim_lig_deck_XXXXXX";
  if (!mkdtemp(tmp) || chdir(tmp)) {
    perror("test_liggghts_deck: temporary folder");
    return 1;
  }
  FILE *fp = fopen("liggghts_deck_plate.stl", "w");
  fputs(stl, fp);
  fclose(fp);
  const char *base =
      "dem: {time_step: 2.5e-6, duration: 0.01, gravity: [0, -9.81, 0], engine: liggghts, seed: 5,\n"
      "      box: {lo: [-0.02, -0.02, -0.02], hi: [0.02, 0.02, 0.02]}, skin: 5.0e-4}\n"
      "materials:\n"
      "  - {name: g, E: 8.0e6, nu: 0.2, e: 0.4, mu_s: 0.5, mu_r: 0.2, density: 500}\n"
      "  - {name: steel, E: 2.0e8, nu: 0.3, e: 0.6, mu_s: 0.3, mu_r: 0.1}\n"
      "classes:\n  - {name: a, radius: 1.0e-3, material: g}\n  - {name: b, radius: 1.5e-3, material: g}\n"
      "walls:\n  - name: imp\n    mesh: liggghts_deck_plate.stl\n    scale: 1.0e-3\n    material: steel\n"
      "    rotation: {origin: [0, 0, 0], axis: [0, 0, 1], rpm: 600}\n"
      "fill:\n  - {region: {box: {lo: [-0.01, -0.01, 0.001], hi: [0.01, 0.01, 0.01]}}, count: 10}\n"
      "feed:\n  - {region: {cylinder: {point: [0, 0.01, 0], axis: [0, 1, 0], radius: 0.005, from: 0, to: 0.004}},\n"
      "     mass_rate: 0.1, every: 0.001, fractions: [1, 3], fractions_by: mass, velocity: [0, -1, 0]}\n"
      "outlets:\n  - region: {box: {lo: [-0.02, -0.02, -0.02], hi: [0.02, -0.015, 0.02]}}\n"
      "statistics: {start: 0.005, sample_every: 0.0005}\n";
  gs_error err = {0};
  int rc;
  char *d = deck_of(base, &err, &rc);
  if (rc) fprintf(stderr, "%s\n", err.msg);
  CHECK(rc == 0 && d);
  if (d) {
    HAS(d, "read_data bed.data\n");
    CHECK(strstr(d, "dump dvtk") == NULL); /* no output.vtk_every */
    CHECK(strstr(d, "custom/vtk") == NULL); /* never: legacy VTK (frames.c makes VTK XML) */
    HAS(d, "timestep 2.5e-06\n");
    HAS(d, "neighbor 0.0005 bin\n");
    HAS(d, "fix gravi all gravity 9.81 vector 0 -1 0\n");
    /* types 1, 2 the classes, 3 the wall */
    HAS(d, "youngsModulus peratomtype 8000000 8000000 200000000\n");
    HAS(d, "poissonsRatio peratomtype 0.2 0.2 0.3\n");
    HAS(d, "coefficientRestitution peratomtypepair 3 &\n    0.4 0.4 0.5 &\n    0.4 0.4 0.5 &\n    0.5 0.5 0.6\n");
    HAS(d, "coefficientRollingFriction peratomtypepair 3 &\n    0.2 0.2 0.15");
    HAS(d, "pair_style gran model hertz tangential history rolling_friction cdt\n");
    /* the turning wall sums the particles' force and torque about its rotation origin */
    HAS(d, "fix wall0 all mesh/surface/stress file wall0_liggghts_deck_plate.stl type 3 heal auto_remove_duplicates "
           "element_exclusion_list read ex_wall0.txt scale 0.001 curvature_tolerant yes reference_point 0 0 0  # ");
    HAS(d, "mesh n_meshes 1 meshes wall0\n");
    HAS(d, "fix rot0 all move/mesh mesh wall0 rotate origin 0 0 0 axis 0 0 1 period 0.1\n"); /* 600 rpm */
    HAS(d, "particletemplate/sphere");
    HAS(d, "atom_type 2 density constant 500 radius constant 0.0015\n");
    HAS(d, "particledistribution/discrete");
    HAS(d, " 2 pts1 0.25 pts2 0.75\n");
    HAS(d, "region feed0 cylinder y 0 0 0.005 0.01 0.014 units box\n");
    HAS(d, "massrate 0.1 insert_every 400 overlapcheck yes all_in yes vel constant 0 -1 0 region feed0\n");
    HAS(d, "region outlet0 block -0.02 0.02 -0.02 -0.015 -0.02 0.02 units box\n");
    HAS(d, "delete_atoms region outlet0 compress no\n");
    HAS(d, "compute pgl all pair/gran/local id vel force contactArea delta\n");
    HAS(d, "compute wgl all wall/gran/local id vel force force_normal contactArea delta\n");
    HAS(d, "write_dump all custom post/left*_0.atom id type mass f_rtime modify region outlet0\n");
    HAS(d, "fix rtime all property/atom/regiontracer/time\n");
    HAS(d, "fix pdd_types all particledistribution/discrete");
    /* the time series' contacts, feed insertions and the torque about the axis (0, 0, 1) */
    HAS(d, "compute cca all contact/atom\ncompute ncon all reduce sum c_cca\nvariable nc equal c_ncon/2\n"
           "variable nin equal 0+f_ins0[1]\nvariable tq0 equal f_wall0[4]*(0)+f_wall0[5]*(0)+f_wall0[6]*(1)\n");
    HAS(d, "thermo_style custom step atoms ke c_rke cpu v_hn v_hm v_nc v_nin v_tq0\n");
    HAS(d, "dump dcol all custom 200 post/collision*.atom id type x y z vx vy vz radius omegax omegay omegaz c_cc_1 c_cc_2\n");
    HAS(d, "dump dimp all local 200 post/impact*.atom c_wgl[1]");
    /* the contact lists of the events: every third of the Hertz contact of two 1 mm spheres at 10 m/s */
    double r = 1e-3, m = 500 * 4.0 / 3.0 * M_PI * r * r * r;
    double tc = gs_dem_hertz_contact_time(m / 2, r / 2, 8e6 / (2 * (1 - 0.04)), 10, 0.4);
    long ek = (long)floor(tc / 3 / 2.5e-6);
    CHECK(ek >= 5 && ek <= 20);
    char want[200];
    snprintf(want, sizeof want, "dump dev all local %ld post/events_pp.txt c_pgl[7] c_pgl[8] c_pgl[14]\n", ek);
    HAS(d, want);
    snprintf(want, sizeof want, "dump dwev all local %ld post/events_wall.txt c_wgl[1]", ek);
    HAS(d, want);
    /* 2000 steps before the window (10 chunks of 200 with the outlet emptied), 2000 in it */
    HAS(d, "variable seg0 loop 10\n");
    HAS(d, "variable seg2000 loop 10\n");
    CHECK(strstr(d, "variable seg0 ") < strstr(d, "dump dcol") && strstr(d, "dump dcol") < strstr(d, "variable seg2000 "));
  }
  free(d);
  /* number fractions 1:3 become mass weights 1 : 3 * 1.5^3 */
  {
    char y[4096];
    const char *at = strstr(base, "fractions_by: mass");
    snprintf(y, sizeof y, "%.*sfractions_by: number%s", (int)(at - base), base, at + strlen("fractions_by: mass"));
    d = deck_of(y, &err, &rc);
    CHECK(rc == 0 && d);
    char want[200];
    snprintf(want, sizeof want, " 2 pts1 %.9g pts2 %.9g\n", 1 / 11.125, 10.125 / 11.125);
    if (d) HAS(d, want);
    free(d);
  }
  /* a fed class with a range of radii: 16 templates for 16 equal-number
   * bins [a, b] = 1 + [j - 1, j]/16 mm, r_j^3 the bin's mean r^3
   * (b^4 - a^4) / (4 (b - a)), their mass weights in proportion to r_j^3
   * and adding up to the class's mass fraction 3/4 */
  {
    char y[4096];
    const char *from = "{name: b, radius: 1.5e-3,", *at = strstr(base, from);
    CHECK(at != NULL);
    snprintf(y, sizeof y, "%.*s{name: b, radius: [1.0e-3, 2.0e-3],%s", (int)(at - base), base, at + strlen(from));
    d = deck_of(y, &err, &rc);
    if (rc) fprintf(stderr, "%s\n", err.msg);
    CHECK(rc == 0 && d);
    if (d) {
      double r3[17], s3 = 0, wb = 0, w1 = 0, w16 = 0;
      for (int j = 1; j <= 16; j++) {
        double a = 1 + (j - 1) / 16.0, b = 1 + j / 16.0;
        r3[j] = (pow(b, 4) - pow(a, 4)) / (4 * (b - a));
        s3 += r3[j];
      }
      char want[160];
      for (int j = 1; j <= 16; j += 15) {
        snprintf(want, sizeof want, "atom_type 2 density constant 500 radius constant %.9g\n", 1e-3 * cbrt(r3[j]));
        HAS(d, want);
      }
      HAS(d, "fix pdd0 all particledistribution/discrete ");
      const char *p = strstr(d, "fix pdd0 all particledistribution/discrete ");
      char key[32];
      for (int j = 1; p && j <= 16; j++) {
        snprintf(key, sizeof key, " pts2_%d ", j);
        const char *q = strstr(p, key);
        CHECK(q != NULL);
        double w = q ? atof(q + strlen(key)) : 0;
        wb += w;
        if (j == 1) w1 = w;
        if (j == 16) w16 = w;
      }
      CHECK(fabs(wb - 0.75) < 1e-8);
      CHECK(fabs(w1 - 0.75 * r3[1] / s3) < 1e-8 && fabs(w16 - 0.75 * r3[16] / s3) < 1e-8);
    }
    free(d);
  }
  /* a lognormal class (median 1 mm, gsd 1.3, truncated at gsd^-+3): the
   * templates' mean r^3 is the truncated distribution's E[r^3] =
   * exp(3 mu + 9 s^2/2) (P(3 - 3 s) - P(-3 - 3 s)) / (P(3) - P(-3)) */
  {
    char y[4096];
    const char *from = "{name: b, radius: 1.5e-3,", *at = strstr(base, from);
    snprintf(y, sizeof y, "%.*s{name: b, radius: {type: lognormal, median: 1.0e-3, gsd: 1.3},%s", (int)(at - base),
             base, at + strlen(from));
    fp = fopen("liggghts_deck_case.yaml", "w");
    fputs(y, fp);
    fclose(fp);
    gs_dem_case *c = gs_dem_case_load("liggghts_deck_case.yaml", &err);
    CHECK(c != NULL);
    double r[GS_LIG_RADII], m3 = 0;
    int n = c ? gs_lig_class_radii(c, 1, r) : 0;
    CHECK(n == GS_LIG_RADII);
    for (int j = 0; j < n; j++) m3 += r[j] * r[j] * r[j] / n;
    const double sg = log(1.3);
#define PHI(x) (0.5 * erfc(-(x) / sqrt(2.0)))
    const double want = 1e-9 * exp(4.5 * sg * sg) * (PHI(3 - 3 * sg) - PHI(-3 - 3 * sg)) / (PHI(3.0) - PHI(-3.0));
#undef PHI
    printf("test_liggghts_deck: lognormal class: mean r^3 of the templates %.12g, of the distribution %.12g\n", m3,
           want);
    CHECK(fabs(m3 / want - 1) < 1e-9);
    for (int j = 1; j < n; j++) CHECK(r[j] > r[j - 1] && r[0] >= 1e-3 / pow(1.3, 3) && r[n - 1] <= 1e-3 * pow(1.3, 3));
    gs_dem_case_free(c);
  }
  /* a static plane: read as the mesh of its polygon in the box; an oblique
   * one through the centre of a cube widened by the largest radius, rmax */
  {
    const char *rot = "    rotation: {origin: [0, 0, 0], axis: [0, 0, 1], rpm: 600}\n";
    const char *mesh = "    mesh: liggghts_deck_plate.stl\n    scale: 1.0e-3\n";
    char y[4096];
    const char *at = strstr(base, mesh), *at2 = strstr(base, rot);
    CHECK(at && at2 && at < at2);
    snprintf(y, sizeof y, "%.*s    plane: {point: [0, 0, 0], normal: [1, 1, 1]}\n%.*s%s", (int)(at - base), base,
             (int)(at2 - at - strlen(mesh)), at + strlen(mesh), at2 + strlen(rot));
    d = deck_of(y, &err, &rc);
    if (rc) fprintf(stderr, "%s\n", err.msg);
    CHECK(rc == 0 && d);
    if (d) HAS(d, "fix wall0 all mesh/surface file wall0_plane.stl type 3 ");
    free(d);
    fp = fopen("liggghts_deck_case.yaml", "w");
    fputs(y, fp);
    fclose(fp);
    gs_dem_case *c = gs_dem_case_load("liggghts_deck_case.yaml", &err);
    CHECK(c != NULL);
    if (c) CHECK(gs_lig_write_plane_mesh(c, 0, "plane.stl", &err) == 0);
    gs_dem_case_free(c);
    const double a = 0.02 + 1.5e-3; /* the box's half-size and class b's radius */
    double area = 0, x[3][3];
    int ntri = 0, nv = 0, bad_v = 0;
    char line[256];
    FILE *in = fopen("plane.stl", "r");
    while (in && fgets(line, sizeof line, in)) {
      if (sscanf(line, " vertex %lf %lf %lf", &x[nv][0], &x[nv][1], &x[nv][2]) != 3) continue;
      /* on the plane, and on the widened box's surface */
      double on = fabs(x[nv][0] + x[nv][1] + x[nv][2]), m = 0;
      for (int k = 0; k < 3; k++) m = fmax(m, fabs(x[nv][k]));
      bad_v += on > 1e-15 || fabs(m - a) > 1e-15;
      if (++nv < 3) continue;
      double u[3], v[3];
      for (int k = 0; k < 3; k++) u[k] = x[1][k] - x[0][k], v[k] = x[2][k] - x[0][k];
      double cx = u[1] * v[2] - u[2] * v[1], cy = u[2] * v[0] - u[0] * v[2], cz = u[0] * v[1] - u[1] * v[0];
      area += 0.5 * sqrt(cx * cx + cy * cy + cz * cz);
      ntri++, nv = 0;
    }
    if (in) fclose(in);
    remove("plane.stl");
    printf("test_liggghts_deck: oblique plane: %d triangles, area %.12g m^2 (hexagon %.12g)\n", ntri, area,
           3 * sqrt(3.0) * a * a);
    CHECK(ntri == 4 && bad_v == 0);
    CHECK(fabs(area / (3 * sqrt(3.0) * a * a) - 1) < 1e-12);
  }
  /* refused keys name themselves */
  struct { const char *from, *to, *msg; } bad[] = {
      {"    mesh: liggghts_deck_plate.stl\n    scale: 1.0e-3\n", "    plane: {point: [0, 0, 0], normal: [0, 0, 1]}\n",
       "walls[0] (imp).rotation: a moving plane"},
      {"    mesh: liggghts_deck_plate.stl\n    scale: 1.0e-3\n",
       "    cylinder: {point: [0, 0, 0], axis: [0, 0, 1], radius: 0.015}\n", "walls[0] (imp): cylinder walls"},
      {"axis: [0, 1, 0], radius: 0.005,", "axis: [0, 1, 0], radius: 0.005, inner_radius: 0.001,", "feed[0].region.cylinder"},
      {"seed: 5,", "seed: 5, damping: exact,", "dem.damping"},
      {"seed: 5,", "seed: 5, mesh_contacts: closest,", "dem.mesh_contacts"},
      {"statistics: {start: 0.005", "spray: {point: [0, 0, 0.01], axis: [0, 0, -1], half_angle: 25, droplet_diameter: "
       "1.0e-3, mass_rate: 1.0e-4, density: 1000, speed: 1.0}\nstatistics: {start: 0.005", "spray: "},
  };
  for (size_t k = 0; k < sizeof bad / sizeof bad[0]; k++) {
    char y[4096];
    const char *at = strstr(base, bad[k].from);
    CHECK(at != NULL);
    if (!at) continue;
    snprintf(y, sizeof y, "%.*s%s%s", (int)(at - base), base, bad[k].to, at + strlen(bad[k].from));
    gs_error e2 = {0};
    char *d2 = deck_of(y, &e2, &rc);
    free(d2);
    CHECK(rc != 0);
    if (!strstr(e2.msg, bad[k].msg)) fprintf(stderr, "case %zu: '%s' lacks '%s'\n", k, e2.msg, bad[k].msg);
    CHECK(strstr(e2.msg, bad[k].msg) != NULL);
  }
  remove("liggghts_deck_case.yaml");
  remove("liggghts_deck_plate.stl");
  if (chdir("/") == 0) rmdir(tmp);
  TEST_EXIT();
}
