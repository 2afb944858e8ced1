/* The semi-mechanistic kernel (src/kernel/kernel_semimech.c; Chaudhury 2015
 * ch. 4, docs/models.md):
 *  - Phi(theta) of eq. 4.4 at 10, 90 and 150 degrees; the droplet of eqs.
 *    4.3 (cube root) and 4.5 for V = 1e-12 m3 (hemisphere at 90 degrees:
 *    depth = cap height = wetted radius);
 *  - the surface liquid: x* l below the pores' hold, the excess above it,
 *    continuous, and rising as consolidation lowers g (squeezed out);
 *  - St_v of two equal spheres = 4 rho d u0 / (9 mu); Psi switches at St = St*;
 *  - on a 3-D (solid, liquid, gas) grid: dry cells have K = 0, K is symmetric,
 *    at() equals row() at the pivots bit for bit, K <= the majorant, the
 *    trends of Fig. 4.2 (K rises with liquid, falls with gas and with solid),
 *    the impeller rule equals the velocity it gives, a DEM collision table
 *    multiplies K by C_ab;
 *  - u0 from the fragment of `gransim compartments` (velocity: {fragment}):
 *    the same kernel as the fragment's speeds written inline, and moving one
 *    zone's speed across the Stokes threshold u* = St* 3 pi mu d~^2 / (8 m~)
 *    of a pair switches that pair's K from B0 A to 0 in that zone alone;
 *  - input errors name the key;
 *  - the induction behaviour of a porous feed (HP, eps0 = 0.74) against the
 *    steady growth of a dense one (LP, eps0 = 0.263) with spray and
 *    consolidation. */
#include "pbm_testlib.h"
#include "gransim/grid.h"
#include "gransim/kernel.h"
#include "kernel/semimech.h"

#define PI 3.14159265358979323846

static void near(double got, double want, double rel, const char *what) {
  if (!(fabs(got - want) <= rel * fabs(want))) {
    fprintf(stderr, "%s: got %.10g, want %.10g\n", what, got, want);
    check_failures++;
  }
}

static void droplet_numbers(void) {
  near(gs_semimech_phi(10 * PI / 180), 7.60064, 1e-5, "Phi(10)");
  near(gs_semimech_phi(PI / 2), 0.5, 1e-14, "Phi(90)");
  near(gs_semimech_phi(150 * PI / 180), 0.03166, 2e-4, "Phi(150)");
  double r, a, h;
  gs_semimech_droplet(1e-12, 0.5, &r, &a, &h);
  near(r, cbrt(3e-12 / (2 * PI)), 1e-14, "hemisphere radius");
  near(r, 7.8159e-5, 1e-4, "R_wet(90)");
  near(h, r, 1e-13, "depth of a hemisphere = its radius");
  gs_semimech_droplet(1e-12, gs_semimech_phi(30 * PI / 180), &r, &a, &h);
  near(r, 1.3239e-4, 1e-4, "R_wet(30)");
  near(a, 5.5062e-8, 1e-4, "A_wet(30)");
  near(h, 2.7242e-5, 1e-4, "h0(30)");
  gs_semimech_droplet(0, 0.5, &r, &a, &h);
  CHECK(r == 0 && a == 0 && h == 0);
}

static gs_semimech_params params(void) {
  return (gs_semimech_params){.rho_solid = 1500, .rho_liquid = 1000, .viscosity = 0.1, .phi = 0.5,
                              .pore_ratio = 0.25, .surface_fraction = 0.05,
                              .asperity_fraction = 0.02, .asperity_max = 3e-6};
}

static void surface_liquid(void) {
  gs_semimech_params p = params();
  const double g = 4e-12; /* holds 1e-12 of liquid */
  near(gs_semimech_surface_liquid(&p, 0.5e-12, g), 0.05 * 0.5e-12, 1e-14, "below the hold");
  near(gs_semimech_surface_liquid(&p, 3e-12, g), 2e-12 + 0.05e-12, 1e-14, "above the hold");
  near(gs_semimech_surface_liquid(&p, 1e-12, g), 0.05e-12, 1e-14, "at the hold");
  CHECK(gs_semimech_surface_liquid(&p, 3e-12, 2e-12) > gs_semimech_surface_liquid(&p, 3e-12, g));
  CHECK(gs_semimech_surface_liquid(&p, 0, g) == 0);
}

static void stokes(void) {
  gs_semimech_params p = params();
  const double d = 200e-6, s = PI * d * d * d / 6, u0 = 2.0;
  gs_semimech_particle a = gs_semimech_particle_of(&p, s, 0, 0);
  near(gs_semimech_stokes(&p, &a, &a, u0), 4 * 1500 * d * u0 / (9 * p.viscosity), 1e-12, "St_v");
  /* a wet pair: Psi A = A below St*, 0 above */
  gs_semimech_particle w = gs_semimech_particle_of(&p, s, 0.3 * s, 0.1 * s);
  CHECK(w.wet > 0 && w.wet < 1 && w.h0 > 3e-6);
  const double star = 2 * log(w.h0 / 3e-6), u_star = u0 * star / gs_semimech_stokes(&p, &w, &w, u0);
  near(gs_semimech_pair(&p, &w, &w, u_star * (1 - 1e-9)), w.wet * w.wet, 1e-14, "Psi = 1 below St*");
  CHECK(gs_semimech_pair(&p, &w, &w, u_star * (1 + 1e-9)) == 0);
  CHECK(gs_semimech_pair(&p, &a, &w, 1e-9) == 0); /* a dry partner */
}

typedef struct {
  gs_grid g;
  gs_cfg *cfg;
  gs_kernel k;
} kfix;

/* A 3-D (solid, liquid, gas) grid of n^3 geometric cells (m3) and the kernel of yaml. */
static int kernel_on_grid(const char *yaml, size_t n, kfix *f, gs_error *err) {
  memset(f, 0, sizeof *f);
  gs_axis ax[3];
  if (gs_axis_geometric(&ax[0], "solid", 1e-12, 2.0, n, 0, err) ||
      gs_axis_geometric(&ax[1], "liquid", 1e-13, 2.0, n, 1, err) ||
      gs_axis_geometric(&ax[2], "gas", 1e-13, 2.0, n, 1, err) || gs_grid_init(&f->g, ax, 3, 2, err))
    return GS_EINPUT;
  f->cfg = gs_cfg_load_string(yaml, "kernel", err);
  if (!f->cfg) return GS_EINPUT;
  return gs_kernel_create(gs_cfg_root(f->cfg), &f->g, "/tmp", &f->k, err);
}

static void kfix_free(kfix *f) {
  gs_kernel_free(&f->k);
  gs_cfg_free(f->cfg);
  gs_grid_free(&f->g);
}

#define BASE0 "type: semi_mechanistic\nbeta0: [2.0, 3.0]\nviscosity: 0.05\ncontact_angle: 60\n" \
              "solid_density: 1500\ncritical_saturation: 0.3\n"
#define BASE BASE0 "surface_fraction: 0.02\n"

/* K of the pivots of cells (is, il, ig) and (js, jl, jg) in compartment 0. */
static double k_of(const kfix *f, size_t is, size_t il, size_t ig, size_t js, size_t jl, size_t jg) {
  size_t i[3] = {is, il, ig}, j[3] = {js, jl, jg};
  double out;
  size_t b = gs_grid_index(&f->g, j);
  f->k.type->row(f->k.self, 0, gs_grid_index(&f->g, i), b, b + 1, &out);
  return out;
}

static void on_grid(void) {
  kfix f;
  gs_error err;
  const size_t n = 8;
  int rc = kernel_on_grid(BASE "velocity: [0.5, 1.0]\n", n, &f, &err);
  CHECK(rc == 0);
  if (rc) {
    fprintf(stderr, "%s\n", err.msg);
    kfix_free(&f);
    return;
  }
  const gs_grid *g = &f.g;
  const size_t nc = g->ncells;
  double *row = malloc(nc * sizeof(double)), *col = malloc(nc * sizeof(double));
  gs_kernel_form form;
  f.k.type->form(f.k.self, &form);
  CHECK(f.k.type->per_compartment(f.k.self));
  size_t dry = 0, wet = 0, asym = 0, off_at = 0, above = 0;
  for (size_t comp = 0; comp < 2; comp++)
    for (size_t a = 0; a < nc; a++) {
      f.k.type->row(f.k.self, comp, a, 0, nc, row);
      for (size_t b = 0; b < nc; b++) {
        f.k.type->row(f.k.self, comp, b, a, a + 1, col);
        asym += row[b] != col[0];
        off_at += f.k.type->at(f.k.self, comp, g->x + 3 * a, g->x + 3 * b) != row[b];
        above += row[b] > form.coef[comp];
        const int a_dry = g->x[3 * a + 1] == 0, b_dry = g->x[3 * b + 1] == 0;
        if (a_dry || b_dry) dry += row[b] != 0;
        else wet += row[b] > 0;
      }
    }
  fprintf(stderr, "grid of %zu cells: %zu wet pairs aggregate\n", nc, wet);
  CHECK(dry == 0 && asym == 0 && off_at == 0 && above == 0 && wet > 0);
  CHECK(form.kind == GS_KERNEL_FORM_CONSTANT && form.coef[0] == 2.0 && form.coef[1] == 3.0);
  free(row);
  free(col);
  kfix_free(&f);
}

/* Fig. 4.2, where the Stokes criterion holds (slow collisions): K rises with
 * liquid (more surface liquid), falls with gas (pores hold more of it, larger
 * area) and with solid (larger area).  Without x*, liquid the pores hold
 * gives K = 0: the induction of a porous feed. */
static void trends(void) {
  kfix f;
  gs_error err;
  const size_t n = 8;
  int rc = kernel_on_grid(BASE0 "velocity: 1e-4\n", n, &f, &err);
  CHECK(rc == 0);
  if (rc) {
    fprintf(stderr, "%s\n", err.msg);
    kfix_free(&f);
    return;
  }
  size_t up_l = 0, up_g = 0, up_s = 0, steps = 0;
  for (size_t x = 0; x + 1 < n; x++)
    for (size_t y = 0; y < n; y++) {
      steps++;
      up_l += k_of(&f, 3, x + 1, y, 3, x + 1, y) < k_of(&f, 3, x, y, 3, x, y);
      up_g += k_of(&f, 3, y, x + 1, 3, y, x + 1) > k_of(&f, 3, y, x, 3, y, x);
      up_s += k_of(&f, x + 1, y, 2, x + 1, y, 2) > k_of(&f, x, y, 2, x, y, 2);
    }
  fprintf(stderr, "against the trends of Fig. 4.2 in %zu steps: liquid %zu, gas %zu, solid %zu\n", steps,
          up_l, up_g, up_s);
  CHECK(up_l == 0 && up_g == 0 && up_s == 0);
  CHECK(k_of(&f, 3, 7, 0, 3, 7, 0) > k_of(&f, 3, 7, 3, 3, 7, 3) && k_of(&f, 3, 7, 3, 3, 7, 3) > 0);
  CHECK(k_of(&f, 3, 2, 7, 3, 2, 7) == 0 && k_of(&f, 3, 2, 7, 3, 7, 0) == 0);
  kfix_free(&f);
}

/* The impeller rule gives the same kernel as the velocity it stands for. */
static void impeller(void) {
  kfix a, b;
  gs_error err;
  const double u0 = 0.5 * PI * 0.2 * 300 / 60;
  char *yaml = tl_fmt(BASE "velocity: %.17g\n", u0);
  int rc = kernel_on_grid(yaml, 8, &a, &err) ||
           kernel_on_grid(BASE "impeller_speed: 300\nimpeller_diameter: 0.2\ntip_speed_fraction: 0.5\n", 8, &b, &err);
  CHECK(rc == 0);
  size_t differ = 0, zero = 0;
  for (size_t c = 0; !rc && c < a.g.ncells; c++)
    for (size_t d = 0; d < a.g.ncells; d++) {
      double ka, kb;
      a.k.type->row(a.k.self, 1, c, d, d + 1, &ka);
      b.k.type->row(b.k.self, 1, c, d, d + 1, &kb);
      differ += fabs(ka - kb) > 1e-12 * ka;
      zero += ka == 0 && a.g.x[3 * c + 1] > 0 && a.g.x[3 * d + 1] > 0;
    }
  CHECK(differ == 0 && zero > 0); /* and Psi = 0 for some wet pairs at this speed */
  free(yaml);
  kfix_free(&a);
  kfix_free(&b);
}

/* A DEM table C over diameter classes multiplies each pair's K by C_ab. */
static void collision_table(void) {
  FILE *fp = fopen("/tmp/semimech_test_collisions.csv", "w");
  CHECK(fp != NULL);
  if (!fp) return;
  fprintf(fp, "# test table\nedges, 0, 2e-4, 1\n1, 2\n2, 5\n");
  fclose(fp);
  kfix a, b;
  gs_error err;
  int rc = kernel_on_grid(BASE "velocity: 0.5\n", 8, &a, &err) ||
           kernel_on_grid(BASE "velocity: 0.5\ncollisions: semimech_test_collisions.csv\n"
                               "collisions_measure: diameter\n", 8, &b, &err);
  CHECK(rc == 0);
  size_t bad = 0, classes[2] = {0, 0};
  for (size_t c = 0; !rc && c < a.g.ncells; c++)
    for (size_t d = 0; d < a.g.ncells; d++) {
      double ka, kb;
      a.k.type->row(a.k.self, 0, c, d, d + 1, &ka);
      b.k.type->row(b.k.self, 0, c, d, d + 1, &kb);
      const int i = gs_diameter(a.g.volume[c]) >= 2e-4, j = gs_diameter(a.g.volume[d]) >= 2e-4;
      const double C = i && j ? 5 : i || j ? 2 : 1;
      bad += kb != ka * C || b.k.type->at(b.k.self, 0, b.g.x + 3 * c, b.g.x + 3 * d) != kb;
      if (ka > 0) classes[i]++;
    }
  CHECK(bad == 0 && classes[0] > 0 && classes[1] > 0);
  gs_kernel_form form;
  if (!rc) b.k.type->form(b.k.self, &form);
  CHECK(!rc && form.coef[0] == 2.0 * 5);
  kfix_free(&a);
  kfix_free(&b);
  remove("/tmp/semimech_test_collisions.csv");
}

/* A fragment as `gransim compartments` writes it, with speeds u[0..1]. */
static void write_fragment(const char *path, double u0, double u1) {
  FILE *fp = fopen(path, "w");
  CHECK(fp != NULL);
  if (!fp) return;
  fprintf(fp, "compartments: 2\nrates:\n  - [0, 1.5]\n  - [2.5, 0]\nvelocity: [%.17g, %.17g]\n"
              "holdup: [10, 12]\n", u0, u1);
  fclose(fp);
}

/* The kernel's u0 per compartment from the fragment: K equals that of the
 * same speeds written inline bit for bit, and a zone's speed moved across a
 * pair's Stokes threshold u* (eq. 4.8, St = St*) switches that pair's K in
 * that zone from B0 A_a A_b to 0, leaving the other zone's as it was. */
static void fragment_velocity(void) {
  const char *frag = "/tmp/semimech_test_fragment.yaml";
  const size_t n = 8;
  kfix a, f;
  gs_error err;
  write_fragment(frag, 0.5, 1.0);
  int rc = kernel_on_grid(BASE "velocity: [0.5, 1.0]\n", n, &a, &err) ||
           kernel_on_grid(BASE "velocity: {fragment: semimech_test_fragment.yaml}\n", n, &f, &err);
  CHECK(rc == 0);
  if (rc) fprintf(stderr, "%s\n", err.msg);
  size_t differ = 0;
  for (size_t comp = 0; !rc && comp < 2; comp++)
    for (size_t c = 0; c < a.g.ncells; c += 3)
      for (size_t d = 0; d < a.g.ncells; d++) {
        double ka, kf;
        a.k.type->row(a.k.self, comp, c, d, d + 1, &ka);
        f.k.type->row(f.k.self, comp, c, d, d + 1, &kf);
        differ += ka != kf;
      }
  CHECK(differ == 0);
  kfix_free(&f);
  /* a wet pair of different cells and its threshold, from the formula */
  gs_semimech_params p = params();
  p.viscosity = 0.05;
  p.phi = gs_semimech_phi(60 * PI / 180);
  p.pore_ratio = 0.3 / 0.7;
  p.surface_fraction = 0.02;
  size_t ca = 0, cb = 0;
  double ustar = 0;
  gs_semimech_particle pa = {0}, pb = {0};
  for (size_t c = 0; !rc && c < a.g.ncells && !(ustar > 0); c++)
    for (size_t d = c + 1; d < a.g.ncells && !(ustar > 0); d++) {
      const double *xa = a.g.x + 3 * c, *xb = a.g.x + 3 * d;
      pa = gs_semimech_particle_of(&p, xa[0], xa[1], xa[2]);
      pb = gs_semimech_particle_of(&p, xb[0], xb[1], xb[2]);
      const double m = 2 * pa.m * pb.m / (pa.m + pb.m), dd = 2 * pa.d * pb.d / (pa.d + pb.d);
      const double lambda = 0.5 * (pa.h0 + pb.h0), ha = fmin(p.asperity_fraction * dd, p.asperity_max);
      if (pa.wet > 0 && pb.wet > 0 && lambda > 1.01 * ha && pa.d != pb.d) {
        ustar = 2 * log(lambda / ha) * 3 * PI * p.viscosity * dd * dd / (8 * m);
        ca = c;
        cb = d;
      }
    }
  const double area = pa.wet * pb.wet;
  fprintf(stderr, "pair threshold u* = %.6g m/s, A = %.6g\n", ustar, area);
  CHECK(ustar > 0 && area > 0);
  for (int side = 0; !rc && side < 2; side++) {
    const double u = ustar * (side ? 1 + 1e-9 : 1 - 1e-9);
    write_fragment(frag, u, 1e-6);
    int rc2 = kernel_on_grid(BASE "velocity: {fragment: semimech_test_fragment.yaml}\n", n, &f, &err);
    CHECK(rc2 == 0);
    if (rc2) {
      fprintf(stderr, "%s\n", err.msg);
      kfix_free(&f);
      continue;
    }
    double k0, k1;
    f.k.type->row(f.k.self, 0, ca, cb, cb + 1, &k0);
    f.k.type->row(f.k.self, 1, ca, cb, cb + 1, &k1);
    near(k1, 3.0 * area, 1e-12, "zone 2 (slow) K = B0 A");
    if (side) CHECK(k0 == 0);
    else near(k0, 2.0 * area, 1e-12, "zone 1 below u*: K = B0 A");
    kfix_free(&f);
  }
  kfix_free(&a);
  remove(frag);
}

static void expect_error(const char *yaml, const char *part) {
  kfix f;
  gs_error err;
  int rc = kernel_on_grid(yaml, 4, &f, &err);
  CHECK(rc == GS_EINPUT || rc == GS_EIO);
  if (rc && !strstr(err.msg, part)) {
    fprintf(stderr, "message lacks '%s': %s\n", part, err.msg);
    check_failures++;
  }
  kfix_free(&f);
}

static void input_errors(void) {
  expect_error(BASE, "velocity");
  expect_error(BASE "velocity: 1\nimpeller_speed: 300\n", "not both");
  expect_error(BASE "impeller_speed: 300\n", "impeller_diameter");
  expect_error(BASE "velocity: -1\n", "velocity");
  expect_error("type: semi_mechanistic\nbeta0: 1\nviscosity: 0.05\ncontact_angle: 180\nsolid_density: 1500\n"
               "critical_saturation: 0.3\nvelocity: 1\n", "contact_angle");
  expect_error("type: semi_mechanistic\nbeta0: 1\nviscosity: 0.05\ncontact_angle: 60\nsolid_density: 1500\n"
               "critical_saturation: 1\nvelocity: 1\n", "critical_saturation");
  expect_error(BASE "velocity: 1\nliquid_axis: water\n", "liquid_axis");
  expect_error(BASE "velocity: 1\ncollisions: no_such_file.csv\n", "no_such_file.csv");
  expect_error(BASE "velocity: 1\nspeed: 3\n", "speed");
  expect_error(BASE "velocity: 1\ncollisions_measure: diameter\n", "without 'collisions'");
  expect_error(BASE "velocity: 1\ngas_axis: liquid\n", "needs a solid axis");
  expect_error(BASE "velocity: {file: x.yaml}\n", "{fragment: FILE}");
  expect_error(BASE "velocity: {fragment: no_such_fragment.yaml}\n", "no_such_fragment.yaml");
  write_fragment("/tmp/semimech_test_fragment.yaml", 0.5, -1);
  expect_error(BASE "velocity: {fragment: semimech_test_fragment.yaml}\n", "the fragment's velocity");
  FILE *fp = fopen("/tmp/semimech_test_fragment.yaml", "w");
  if (fp) {
    fputs("compartments: 3\nvelocity: [1, 1, 1]\n", fp);
    fclose(fp);
  }
  expect_error(BASE "velocity: {fragment: semimech_test_fragment.yaml}\n", "grid.compartments: 3");
  remove("/tmp/semimech_test_fragment.yaml");
}

/* Mean solid volume (in primary particles) at time `end` of a batch with
 * 0.3 L/S of binder sprayed over 60 s and consolidation, from a feed of
 * 100 um solid with pore gas g0 (examples/high-shear-semimech.yaml). */
static double growth(double g0, double end) {
  char *yaml = tl_fmt(
      "grid:\n  axes:\n"
      "    - {name: solid,  type: geometric, min: 2.6e-13, ratio: 2, cells: 10}\n"
      "    - {name: liquid, type: geometric, min: 1.0e-14, ratio: 2.5, cells: 12, zero_first: true}\n"
      "    - {name: gas,    type: geometric, min: 1.0e-14, ratio: 2.5, cells: 12, zero_first: true}\n"
      "initial: {type: point, number: 3.8e8, at: [5.24e-13, 5.0e-15, %.17g]}\n"
      "mechanisms:\n"
      "  - type: aggregation\n"
      "    kernel: {type: semi_mechanistic, beta0: 5.0e-9, velocity: 0.5, viscosity: 0.1, contact_angle: 60,\n"
      "             solid_density: 1500, critical_saturation: 0.05}\n"
      "  - {type: liquid_addition, rate: 1.0e-6, start: 0, end: 60}\n"
      "  - {type: consolidation, rate: 0.005, min_porosity: 0.2}\n"
      "solver: {method: cvode, rtol: 1.0e-5, atol: 0.1}\n"
      "output: {end: %g, count: 2}\n", g0, end);
  gs_case c;
  gs_run_report rep;
  double *y = tl_build_run(yaml, &c, &rep), r = NAN;
  if (y) r = tl_mom(&c, y, 0, 1, 0, 0) / tl_mom(&c, y, 0, 0, 0, 0) / 5.24e-13;
  free(y);
  free(yaml);
  gs_case_free(&c);
  return r;
}

/* Chaudhury (2015) ch. 4: a porous feed (HP, eps0 = 0.74) holds the binder in
 * its pores and does not grow until consolidation squeezes it out, then grows
 * ever faster (induction); a dense feed (LP, eps0 = 0.263) wets its surface
 * within seconds and grows steadily. */
static void induction(void) {
  const double s0 = 5.24e-13, hp = s0 * 0.74 / 0.26, lp = s0 * 0.263 / 0.737;
  double h[3] = {growth(hp, 20), growth(hp, 60), growth(hp, 240)};
  double l[3] = {growth(lp, 20), growth(lp, 60), growth(lp, 240)};
  /* growth rate over [60, 240] against that over [0, 60] */
  const double accel_hp = (h[2] - h[1]) / 180 / ((h[1] - 1) / 60), accel_lp = (l[2] - l[1]) / 180 / ((l[1] - 1) / 60);
  fprintf(stderr, "mean solid / primary at 20, 60, 240 s: HP %.4f %.4f %.4f, LP %.4f %.4f %.4f; "
          "acceleration HP %.2f, LP %.2f\n", h[0], h[1], h[2], l[0], l[1], l[2], accel_hp, accel_lp);
  CHECK(h[0] < 1.005 && l[0] > 1.03);  /* induction: HP has not started */
  CHECK(h[2] > 3 && l[2] > 3);         /* both grow */
  CHECK(accel_hp > 1.5 * accel_lp);    /* HP takes off late, LP steadier */
}

int main(void) {
  droplet_numbers();
  surface_liquid();
  stokes();
  on_grid();
  trends();
  impeller();
  collision_table();
  fragment_velocity();
  input_errors();
  induction();
  TEST_EXIT();
}
