/* The LIGGGHTS 3.8 deck of a `gransim dem` case.  Every key the embedded
 * engine reads becomes the LIGGGHTS command with the same physics (the table
 * is in docs/design-notes.md, "LIGGGHTS engine"); a key no deck can express
 * is refused here, naming it, rather than silently dropped.
 *
 * Atom types: 1..nclass are the size classes (so that demdata's readers find
 * the class in the `type` column), nclass+1.. one per wall, each with the
 * wall's material. */
#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include <gsl/gsl_cdf.h>

#include "dem/dem_case.h"
#include "dem/dem_wet.h"
#include "gransim/dem_data.h"
#include "gransim/liggghts.h"
#include "liggghts/lig_internal.h"


/* LIGGGHTS wants prime seeds above 10000; the case seed picks where to start. */
static long next_prime(long n) {
  for (;; n++) {
    int prime = n > 1;
    for (long d = 2; d * d <= n && prime; d++) prime = n % d != 0;
    if (prime) return n;
  }
}

static long lig_seed(const gs_dem_case *c, int k) {
  long p = 10007 + (long)(c->seed % 100000) * 97;
  for (int i = 0; i <= k; i++) p = next_prime(p + 1);
  return p;
}

static double mean2(double a, double b) { return 0.5 * (a + b); }

/* A refusal of key (a path such as "walls[1].rotation") at its place in the
 * case file, "FILE:LINE: " (the file alone where the key is not in it). */
static int lig_fail(const gs_dem_case *c, gs_error *err, const char *key, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));
static int lig_fail(const gs_dem_case *c, gs_error *err, const char *key, const char *fmt, ...) {
  char dotted[160], msg[sizeof err->msg];
  size_t k = 0;
  for (const char *p = key; *p && k + 1 < sizeof dotted; p++)
    if (*p != ']') dotted[k++] = *p == '[' ? '.' : *p;
  dotted[k] = 0;
  gs_error scratch = {0};
  gs_cfg_node *n = c->cfg ? gs_cfg_find(c->cfg, dotted, &scratch) : NULL;
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(msg, sizeof msg, fmt, ap);
  va_end(ap);
  if (n) return gs_error_set(err, GS_EINPUT, "%s:%d: %s", gs_cfg_file(n), gs_cfg_line(n), msg);
  return gs_error_set(err, GS_EINPUT, "%s: %s", c->path, msg);
}

/* Material value of atom type t (1-based): a class or a wall. */
static const gs_dem_material *type_mat(const gs_dem_case *c, size_t t) {
  return t <= c->nclass ? &c->cls[t - 1].mat : &c->wall_src[t - 1 - c->nclass].mat;
}

/* fix property/global ... peratomtypepair: the pair's value is the mean of
 * the two materials', as the embedded engine combines e, mu_s and mu_r. */
static void pair_prop(FILE *fp, const gs_dem_case *c, size_t nt, const char *id, const char *name, int which) {
  fprintf(fp, "fix %s all property/global %s peratomtypepair %zu", id, name, nt);
  for (size_t i = 1; i <= nt; i++) {
    fprintf(fp, " &\n   ");
    for (size_t j = 1; j <= nt; j++) {
      const gs_dem_material *a = type_mat(c, i), *b = type_mat(c, j);
      double v = which == 0 ? mean2(a->e, b->e) : which == 1 ? mean2(a->mu_s, b->mu_s) : mean2(a->mu_r, b->mu_r);
      fprintf(fp, " %.9g", v);
    }
  }
  fprintf(fp, "\n");
}

/* The axis (0, 1, 2) of a cylinder region along x, y or z, or -1. */
static int cyl_axis(const gs_dem_region *g) {
  int ax = -1;
  for (int a = 0; a < 3; a++)
    if (fabs(fabs(g->a[a]) - 1) < 1e-12) ax = a;
  return ax;
}

/* Whether a LIGGGHTS region can be g: boxes, and cylinders along x, y or z;
 * an annulus (inner_radius) only where feed is 0, as the intersection of two
 * cylinders, which insert/rate/region cannot fill. */
static int region_check(const gs_dem_case *c, const gs_dem_region *g, const char *key, int feed, gs_error *err) {
  if (g->kind == GS_DEM_REGION_BOX) return GS_OK;
  if (cyl_axis(g) < 0)
    return lig_fail(c, err, key, "%s.cylinder: the LIGGGHTS engine takes cylinders along x, y or z only "
                        "(axis (%g, %g, %g)); use a box or such a cylinder", key, g->a[0], g->a[1], g->a[2]);
  if (feed && g->Rin > 0)
    return lig_fail(c, err, key, "%s.cylinder.inner_radius: a LIGGGHTS feed region cannot be an annulus "
                        "(insert/rate/region fills simple regions); use a box or a full cylinder", key);
  return GS_OK;
}

/* A region as LIGGGHTS region commands (checked by region_check). */
static int region_cmd(const gs_dem_case *c, FILE *fp, const char *id, const gs_dem_region *g, const char *key, int feed,
                      gs_error *err) {
  int rc = region_check(c, g, key, feed, err);
  if (rc) return rc;
  if (g->kind == GS_DEM_REGION_BOX) {
    fprintf(fp, "region %s block %.9g %.9g %.9g %.9g %.9g %.9g units box\n", id, g->lo[0], g->hi[0], g->lo[1],
            g->hi[1], g->lo[2], g->hi[2]);
    return GS_OK;
  }
  const int ax = cyl_axis(g);
  double lo = g->p[ax] + g->a[ax] * g->s0, hi = g->p[ax] + g->a[ax] * g->s1;
  int c1 = ax == 0 ? 1 : 0, c2 = ax == 2 ? 1 : 2;
  const char *sfx = g->Rin > 0 ? "_outer" : "";
  fprintf(fp, "region %s%s cylinder %c %.9g %.9g %.9g %.9g %.9g units box\n", id, sfx, "xyz"[ax], g->p[c1], g->p[c2],
          g->R, fmin(lo, hi), fmax(lo, hi));
  if (g->Rin > 0)
    fprintf(fp, "region %s_inner cylinder %c %.9g %.9g %.9g %.9g %.9g side out units box\n"
                "region %s intersect 2 %s_outer %s_inner\n", id, "xyz"[ax], g->p[c1], g->p[c2], g->Rin,
            fmin(lo, hi), fmax(lo, hi), id, id, id);
  return GS_OK;
}

/* Runs nsteps; with outlets, in chunks of 200 steps with the outlet regions
 * emptied after each (the embedded engine removes at least every 200 steps). */
static void empty_outlets(FILE *fp, const gs_dem_case *c) {
  /* the atoms about to leave, with their time in the domain (fix rtime), for
   * residence.csv: left<STEP>_<OUTLET>.atom (tables.c) */
  for (size_t k = 0; k < c->noutlets; k++)
    fprintf(fp, "write_dump all custom post/left*_%zu.atom id type mass f_rtime modify region outlet%zu\n"
                "delete_atoms region outlet%zu compress no\n", k, k, k);
}

static void run_cmd(FILE *fp, const gs_dem_case *c, long nsteps, const char *label, int unrolled) {
  if (nsteps <= 0) return;
  if (!c->noutlets) {
    fprintf(fp, "run %ld\n", nsteps);
    return;
  }
  long q = nsteps / 200, r = nsteps % 200;
  /* commands on standard input cannot loop (jump SELF rereads a file) */
  for (long k = 0; unrolled && k < q; k++) {
    fprintf(fp, "run 200\n");
    empty_outlets(fp, c);
  }
  if (q > 0 && !unrolled) {
    fprintf(fp, "variable %s loop %ld\nlabel %s\nrun 200\n", label, q, label);
    empty_outlets(fp, c);
    fprintf(fp, "next %s\njump SELF %s\n", label, label);
  }
  if (r > 0) {
    fprintf(fp, "run %ld\n", r);
    empty_outlets(fp, c);
  }
}

/* Whether wall s has a motion (a rotation, even at 0 rpm, or a velocity):
 * its mesh then sums the torque, as the embedded engine's walls with motion. */
static int wall_moves(const gs_dem_wall_src *s) {
  return s->rotating || s->velocity[0] != 0 || s->velocity[1] != 0 || s->velocity[2] != 0;
}

/* Whether wall s turns (a rotation at a rate other than 0). */
static int wall_turns(const gs_dem_wall_src *s) { return s->rotating && s->omega != 0; }

/* The step at which wall s starts to turn (rotation.start), or 0. */
static long spin_step(const gs_dem_case *c, const gs_dem_wall_src *s) {
  return s->spin_start > 0 ? (long)round(s->spin_start / c->prm.dt) : 0;
}

/* Wall w's rotation as a period (a negative rate turns the axis round).
 * LIGGGHTS' move/mesh turns the mesh by omega (t - t_fix), t_fix the time the
 * fix was defined: defined after the run up to rotation.start, it turns from
 * the position at rest as the embedded engine's omega (t - start). */
static void rotate_cmd(FILE *fp, const gs_dem_wall_src *s, size_t w) {
  double sg = s->omega > 0 ? 1 : -1;
  fprintf(fp, "fix rot%zu all move/mesh mesh wall%zu rotate origin %.9g %.9g %.9g axis %.9g %.9g %.9g period %.9g\n", w,
          w, s->origin[0], s->origin[1], s->origin[2], sg * s->axis[0] + 0.0, sg * s->axis[1] + 0.0,
          sg * s->axis[2] + 0.0, 2 * M_PI / fabs(s->omega));
}

/* Everything before the walls: atoms, box, materials, contact law, time
 * step and gravity. */
static void preamble(const gs_dem_case *c, FILE *fp, const char *data_file) {
  const gs_dem_params *p = &c->prm;
  const size_t ncl = c->nclass, nt = ncl + c->nwall_src;
  const double dt = p->dt;
  fprintf(fp, "atom_style granular\natom_modify map array\nboundary f f f\nnewton off\n"
              "communicate single vel yes\nunits si\n");
  if (data_file) {
    fprintf(fp, "read_data %s\n", data_file);
  } else {
    fprintf(fp, "region domain block %.9g %.9g %.9g %.9g %.9g %.9g units box\ncreate_box %zu domain\n", p->lo[0],
            p->hi[0], p->lo[1], p->hi[1], p->lo[2], p->hi[2], nt);
  }
  fprintf(fp, "neighbor %.9g bin\nneigh_modify delay 0\n", p->skin);

  fprintf(fp, "# materials: types 1..%zu the size classes, %zu.. the walls\n", ncl, ncl + 1);
  fprintf(fp, "fix m1 all property/global youngsModulus peratomtype");
  for (size_t t = 1; t <= nt; t++) fprintf(fp, " %.9g", type_mat(c, t)->E);
  fprintf(fp, "\nfix m2 all property/global poissonsRatio peratomtype");
  for (size_t t = 1; t <= nt; t++) fprintf(fp, " %.9g", type_mat(c, t)->nu);
  fprintf(fp, "\n");
  pair_prop(fp, c, nt, "m3", "coefficientRestitution", 0);
  pair_prop(fp, c, nt, "m4", "coefficientFriction", 1);
  pair_prop(fp, c, nt, "m5", "coefficientRollingFriction", 2);
  fprintf(fp, "pair_style gran model hertz tangential history rolling_friction cdt\npair_coeff * *\n");
  fprintf(fp, "timestep %.9g\n", dt);
  double g = sqrt(p->gravity[0] * p->gravity[0] + p->gravity[1] * p->gravity[1] + p->gravity[2] * p->gravity[2]);
  if (g > 0)
    fprintf(fp, "fix gravi all gravity %.9g vector %.9g %.9g %.9g\n", g, p->gravity[0] / g, p->gravity[1] / g,
            p->gravity[2] / g);

}

void gs_lig_mesh_name(const gs_dem_case *c, size_t w, char *buf, size_t n) {
  if (c->wall_src[w].kind == GS_DEM_SRC_PLANE) {
    snprintf(buf, n, "wall%zu_plane.stl", w);
    return;
  }
  const char *base = strrchr(c->wall_src[w].mesh, '/');
  snprintf(buf, n, "wall%zu_%s", w, base ? base + 1 : c->wall_src[w].mesh);
}

long gs_lig_event_every(const gs_dem_case *c) {
  /* the contact time falls with the impact speed as v^(-1/5): at 10 m/s it is
   * shorter than nearly every contact in a granulator */
  double tc = HUGE_VAL;
  for (size_t i = 0; i < c->nclass; i++) {
    const gs_dem_material *m = &c->cls[i].mat;
    double r = c->cls[i].rmin, mass = m->density * 4.0 / 3.0 * M_PI * r * r * r;
    double estar = m->E / (2 * (1 - m->nu * m->nu));
    tc = fmin(tc, gs_dem_hertz_contact_time(mass / 2, r / 2, estar, 10.0, m->e));
  }
  return (long)fmax(1, floor(tc / 3 / c->prm.dt));
}

/* The radii by which a feed inserts class i: its radius, or for a range or a
 * truncated lognormal one per each of GS_LIG_RADII bins of equal number,
 * since particletemplate/sphere takes a constant radius only in LIGGGHTS 3.8
 * and a distribution of templates stands for the class.  A bin's radius is
 * the cube root of its mean r^3, so that the class's mean particle mass is
 * the distribution's (the bins' midpoints would make it 2.4 % light for a
 * lognormal of gsd 1.3).  Returns how many. */
int gs_lig_class_radii(const gs_dem_case *c, size_t i, double *r) {
  const gs_dem_class *k = &c->cls[i];
  if (k->rmin == k->rmax) {
    r[0] = k->rmin;
    return 1;
  }
  const int lognormal = k->gsd > 1;
  const double mu = lognormal ? log(k->median) : 0, sg = lognormal ? log(k->gsd) : 0;
  const double za = lognormal ? (log(k->rmin) - mu) / sg : 0, zb = lognormal ? (log(k->rmax) - mu) / sg : 0;
  const double pa = lognormal ? gsl_cdf_ugaussian_P(za) : 0, pb = lognormal ? gsl_cdf_ugaussian_P(zb) : 1;
  for (int j = 0; j < GS_LIG_RADII; j++) {
    const double q0 = pa + (double)j / GS_LIG_RADII * (pb - pa), q1 = pa + (j + 1.0) / GS_LIG_RADII * (pb - pa);
    double m3;
    if (lognormal) { /* E[r^3] over z in [z0, z1]: exp(3 mu + 9 s^2/2) (P(z1 - 3 s) - P(z0 - 3 s)) / (q1 - q0) */
      const double z0 = j ? gsl_cdf_ugaussian_Pinv(q0) : za, z1 = j + 1 < GS_LIG_RADII ? gsl_cdf_ugaussian_Pinv(q1) : zb;
      m3 = exp(3 * mu + 4.5 * sg * sg) * (gsl_cdf_ugaussian_P(z1 - 3 * sg) - gsl_cdf_ugaussian_P(z0 - 3 * sg)) / (q1 - q0);
    } else {
      const double a = k->rmin + q0 * (k->rmax - k->rmin), b = k->rmin + q1 * (k->rmax - k->rmin);
      m3 = (b * b * b * b - a * a * a * a) / (4 * (b - a));
    }
    r[j] = cbrt(m3);
  }
  return GS_LIG_RADII;
}

/* What a deck cannot express, named by key. */
int gs_lig_check(const gs_dem_case *c, gs_error *err) {
  if (c->wet)
    return lig_fail(c, err, c->wet->has_spray ? "spray" : "granulation", "%s: not expressible in a LIGGGHTS deck (droplets, the liquid on the "
                        "particles and their aggregation live in the embedded engine); use engine: embedded",
                        c->wet->has_spray ? "spray" : "granulation");
  /* a plane becomes a mesh (plane_mesh.c) of the box's size: it may not move out of it */
  for (size_t w = 0; w < c->nwall_src; w++) {
    const gs_dem_wall_src *s = &c->wall_src[w];
    char key[64];
    snprintf(key, sizeof key, "walls[%zu]", w);
    if (s->kind == GS_DEM_SRC_CYLINDER)
      return lig_fail(c, err, key, "walls[%zu] (%s): cylinder walls are not expressible in the LIGGGHTS "
                          "engine (a primitive cylinder's contacts are not reported by compute wall/gran/local, "
                          "and a faceted one gets two contacts at each fold by LIGGGHTS' mesh rule); give the "
                          "wall as an STL mesh", w, s->name);
    if (s->kind == GS_DEM_SRC_PLANE && (s->rotating || s->velocity[0] != 0 || s->velocity[1] != 0 ||
                                        s->velocity[2] != 0)) {
      snprintf(key, sizeof key, "walls[%zu].%s", w, s->rotating ? "rotation" : "velocity");
      return lig_fail(c, err, key, "walls[%zu] (%s).%s: a moving plane is not expressible in the LIGGGHTS "
                          "engine (the deck meshes the plane where it cuts the box at t = 0); give the wall as "
                          "an STL mesh", w, s->name, s->rotating ? "rotation" : "velocity");
    }
  }
  if (c->damping_given && c->prm.damping != GS_DEM_DAMPING_LIGGGHTS)
    return lig_fail(c, err, "dem.damping", "dem.damping: 'exact' is not expressible in LIGGGHTS, whose damping follows "
                        "from e by its closed form; give 'liggghts' or leave the key out");
  if (c->mesh_contacts_given && c->prm.mesh_contacts != GS_DEM_MESH_LIGGGHTS)
    return lig_fail(c, err, "dem.mesh_contacts", "dem.mesh_contacts: 'closest' is not expressible in LIGGGHTS, which counts "
                        "mesh contacts by its own rule; give 'liggghts' or leave the key out");
  char key[64];
  int rc = GS_OK;
  for (size_t k = 0; k < c->nfeed && !rc; k++) {
    snprintf(key, sizeof key, "feed[%zu].region", k);
    rc = region_check(c, &c->feed[k].reg, key, 1, err);
  }
  for (size_t k = 0; k < c->noutlets && !rc; k++) {
    snprintf(key, sizeof key, "outlets[%zu].region", k);
    rc = region_check(c, &c->outlets[k], key, 0, err);
  }
  if (!rc && c->has_holdup) rc = region_check(c, &c->holdup, "statistics.holdup_region", 0, err);
  if (rc) return rc;
  for (size_t i = 0; i < c->nclass; i++)
    if (memcmp(&c->cls[i].mat, &c->cls[0].mat, sizeof c->cls[0].mat)) {
      snprintf(key, sizeof key, "classes[%zu].material", i);
      return lig_fail(c, err, key, "classes[%zu].material: the LIGGGHTS engine's reduction assumes one "
                          "particle material (that of classes[0]) for its Hertz contact times", i);
    }
  return GS_OK;
}

/* The step the deck's statistics window opens at: statistics.start, or 0
 * for statistics.start: steady, whose detector reads the dumps from t = 0
 * (steady.c) and whose reduction leaves out what came before it fired. */
static long window_step(const gs_dem_case *c) {
  const long nsteps = (long)ceil(c->duration / c->prm.dt - 1e-9), k = (long)round(c->stats_start / c->prm.dt);
  return c->start_steady ? 0 : k < nsteps ? k : nsteps;
}

long gs_lig_steps(const gs_dem_case *c) { return (long)ceil(c->duration / c->prm.dt - 1e-9); }

int gs_lig_write_setup(const gs_dem_case *c, FILE *fp, const char *data_file, const char *exclusion,
                       gs_error *err) {
  int rc = gs_lig_check(c, err);
  if (rc) return rc;
  for (size_t w = 0; w < c->nwall_src; w++)
    if (!c->wall_src[w].mesh[0] && c->wall_src[w].kind == GS_DEM_SRC_MESH)
      return gs_error_set(err, GS_EINPUT, "walls[%zu] (%s): the generated mesh has no file yet; write it first "
                          "(gs_dem_case_write_geometry)", w, c->wall_src[w].name);
  const gs_dem_params *p = &c->prm;
  const size_t ncl = c->nclass;
  const double dt = p->dt;
  const long out_k = (long)fmax(1, round(c->out_every / dt));

  fprintf(fp, "# LIGGGHTS 3.8 deck written by gransim from %s (dem.engine: liggghts)\n", c->path);
  fprintf(fp, "# Hertz-Mindlin with tangential history and CDT rolling friction; LIGGGHTS' damping from e\n"
              "# (the embedded engine's `damping: liggghts`); mesh contacts by LIGGGHTS' own rule.\n");
  preamble(c, fp, data_file);

  /* walls: the STL files as the case gives them, scaled by LIGGGHTS */
  if (c->nwall_src) {
    for (size_t w = 0; w < c->nwall_src; w++) {
      const gs_dem_wall_src *s = &c->wall_src[w];
      /* LIGGGHTS wants its keywords in this order: type, heal, element_exclusion_list, scale */
      char mesh[4200];
      gs_lig_mesh_name(c, w, mesh, sizeof mesh);
      /* a moving wall's mesh also sums the particles' force and torque (mesh/surface/stress,
       * about its rotation origin: the time series' torque_axis) */
      fprintf(fp, "fix wall%zu all mesh/surface%s file %s type %zu heal auto_remove_duplicates", w,
              wall_moves(s) ? "/stress" : "", mesh, ncl + 1 + w);
      /* LIGGGHTS refuses facets with more than two edge neighbours (the CoriMix
       * shell has such rings); its remedy: a first run writes them, this one excludes them */
      if (exclusion) fprintf(fp, " element_exclusion_list %s ex_wall%zu.txt", exclusion, w);
      fprintf(fp, " scale %.9g curvature_tolerant yes", s->scale);
      if (wall_moves(s)) fprintf(fp, " reference_point %.9g %.9g %.9g", s->origin[0], s->origin[1], s->origin[2]);
      fprintf(fp, "  # %s\n", s->name);
    }
    fprintf(fp, "fix walls all wall/gran model hertz tangential history rolling_friction cdt mesh n_meshes %zu meshes",
            c->nwall_src);
    for (size_t w = 0; w < c->nwall_src; w++) fprintf(fp, " wall%zu", w);
    fprintf(fp, "\n");
  }

  /* one particle template per class (a class with a radius range, which no
   * feed may insert, at its smallest radius), and a distribution of them all
   * that no feed uses: LIGGGHTS stops ("Atom types must start from 1") once
   * no atom, wall or distribution of type 1 is left, e.g. when the outlets
   * have emptied class 1 */
  for (size_t i = 0; i < ncl; i++)
    fprintf(fp, "fix pts%zu all particletemplate/sphere %ld atom_type %zu density constant %.9g radius constant %.9g\n",
            i + 1, lig_seed(c, (int)i), i + 1, c->cls[i].mat.density, c->cls[i].rmin);
  fprintf(fp, "fix pdd_types all particledistribution/discrete %ld %zu", lig_seed(c, 63), ncl);
  for (size_t i = 0; i < ncl; i++) fprintf(fp, " pts%zu %.9g", i + 1, 1.0 / (double)ncl);
  fprintf(fp, "\n");
  /* a fed class with a range of radii: one template per radius of gs_lig_class_radii */
  double rad[GS_DEM_MAX_CLASSES][GS_LIG_RADII], mr3[GS_DEM_MAX_CLASSES];
  int nrad[GS_DEM_MAX_CLASSES];
  for (size_t i = 0; i < ncl; i++) {
    nrad[i] = gs_lig_class_radii(c, i, rad[i]);
    mr3[i] = 0;
    for (int j = 0; j < nrad[i]; j++) mr3[i] += rad[i][j] * rad[i][j] * rad[i][j] / nrad[i];
    int fed = 0;
    for (size_t k = 0; k < c->nfeed; k++) fed |= c->feed[k].frac[i] > 0;
    for (int j = 0; fed && nrad[i] > 1 && j < nrad[i]; j++)
      fprintf(fp, "fix pts%zu_%d all particletemplate/sphere %ld atom_type %zu density constant %.9g radius constant "
              "%.9g\n", i + 1, j + 1, lig_seed(c, 200 + GS_LIG_RADII * (int)i + j), i + 1, c->cls[i].mat.density,
              rad[i][j]);
  }
  /* feeds: one distribution and inserter per feed */
  for (size_t k = 0; k < c->nfeed; k++) {
    const gs_dem_inserter *f = &c->feed[k];
    size_t nz = 0;
    for (size_t i = 0; i < ncl; i++) nz += f->frac[i] > 0 ? (size_t)nrad[i] : 0;
    /* mass-based weights (particledistribution/discrete): number fractions become mass
     * fractions f_i m_i, m_i the mean mass of the class's templates, which have equal
     * numbers within the class; one convention, checked against the embedded engine
     * (a 1:1 number feed gave 29:29 and 30:28 particles) */
    double w[GS_DEM_MAX_CLASSES], fs = 0;
    for (size_t i = 0; i < ncl; i++) {
      w[i] = f->frac[i] * (f->by_mass ? 1 : c->cls[i].mat.density * mr3[i]);
      fs += w[i];
    }
    fprintf(fp, "fix pdd%zu all particledistribution/discrete %ld %zu", k, lig_seed(c, 64 + 2 * (int)k), nz);
    for (size_t i = 0; i < ncl; i++) {
      if (!(f->frac[i] > 0)) continue;
      if (nrad[i] == 1) fprintf(fp, " pts%zu %.9g", i + 1, w[i] / fs);
      for (int j = 0; nrad[i] > 1 && j < nrad[i]; j++) /* the class's mass split by r^3 */
        fprintf(fp, " pts%zu_%d %.9g", i + 1, j + 1,
                w[i] / fs * rad[i][j] * rad[i][j] * rad[i][j] / (nrad[i] * mr3[i]));
    }
    fprintf(fp, "\n");
    char key[64];
    snprintf(key, sizeof key, "feed[%zu].region", k);
    char rid[32];
    snprintf(rid, sizeof rid, "feed%zu", k);
    if ((rc = region_cmd(c, fp, rid, &f->reg, key, 1, err))) return rc;
    double span = fmin(f->end, c->duration) - f->start;
    long every = (long)fmax(1, round(f->every / dt)), start = (long)round(f->start / dt);
    /* LIGGGHTS reads these keywords in this order only */
    fprintf(fp, "fix ins%zu all insert/rate/region seed %ld distributiontemplate pdd%zu verbose no ", k,
            lig_seed(c, 65 + 2 * (int)k), k);
    if (f->mass_rate > 0) fprintf(fp, "mass %.9g massrate %.9g", f->mass_rate * span * (1 + 1e-9), f->mass_rate);
    else fprintf(fp, "nparticles %.0f particlerate %.9g", ceil(f->number_rate * span), f->number_rate);
    fprintf(fp, " insert_every %ld", every);
    if (start > 0) fprintf(fp, " start %ld", start);
    fprintf(fp, " overlapcheck yes all_in yes vel constant %.9g %.9g %.9g region %s\n", f->v[0], f->v[1], f->v[2], rid);
  }
  for (size_t k = 0; k < c->noutlets; k++) {
    char key[64], rid[32];
    snprintf(key, sizeof key, "outlets[%zu].region", k);
    snprintf(rid, sizeof rid, "outlet%zu", k);
    if ((rc = region_cmd(c, fp, rid, &c->outlets[k], key, 0, err))) return rc;
  }
  /* each atom's time since it entered (its residence time when it leaves) */
  if (c->noutlets) fprintf(fp, "fix rtime all property/atom/regiontracer/time\n");
  /* the hold-up of the time series: in the hold-up region, or everything */
  if (c->has_holdup) {
    if ((rc = region_cmd(c, fp, "holdup", &c->holdup, "statistics.holdup_region", 0, err))) return rc;
    fprintf(fp, "variable hn equal count(all,holdup)\nvariable hm equal mass(all,holdup)\n");
  } else {
    fprintf(fp, "variable hn equal count(all)\nvariable hm equal mass(all)\n");
  }
  fprintf(fp, "fix integr all nve/sphere\n");

  /* prescribed wall motion: the walls that turn from t = 0 (the others from
   * their rotation.start, between the runs below) and the moving ones */
  for (size_t w = 0; w < c->nwall_src; w++) {
    const gs_dem_wall_src *s = &c->wall_src[w];
    if (wall_turns(s) && spin_step(c, s) == 0) rotate_cmd(fp, s, w);
    if (s->velocity[0] != 0 || s->velocity[1] != 0 || s->velocity[2] != 0)
      fprintf(fp, "fix lin%zu all move/mesh mesh wall%zu linear %.9g %.9g %.9g\n", w, w, s->velocity[0],
              s->velocity[1], s->velocity[2]);
  }

  /* computes must exist before the first run (LIGGGHTS 3.8); the dumps are
   * the files src/demdata reads (collision/impact/ppcoll<STEP>.atom) */
  fprintf(fp, "# contacts and impacts: the dumps gransim reduces (src/demdata)\n");
  for (size_t i = 1; i <= ncl; i++) fprintf(fp, "group t%zu type %zu\ncompute cc_%zu t%zu contact/atom\n", i, i, i, i);
  fprintf(fp, "compute pgl all pair/gran/local id vel force contactArea delta\n");
  /* the normal force's direction is the contact normal (impacts.csv's vn, vt); LIGGGHTS allows
   * one wall/gran/local only, so its columns are: wall and particle velocity 1-6, mesh,
   * triangle, atom 7-9, force 10-12, normal force 13-15, contact area 16, overlap 17 */
  if (c->nwall_src) fprintf(fp, "compute wgl all wall/gran/local id vel force force_normal contactArea delta\n");
  /* the time series' columns beyond the energies: pair contacts (contact/atom counts each at
   * both atoms), the particles the feeds inserted (fix insert's first output; the runner finds
   * the lost ones from them), each wall's torque about its rotation axis (as the embedded
   * engine: about the x axis through the origin for a wall without a turning axis, 0 for a
   * wall without motion) */
  fprintf(fp, "compute rke all erotate/sphere\ncompute cca all contact/atom\ncompute ncon all reduce sum c_cca\n"
              "variable nc equal c_ncon/2\nvariable nin equal 0");
  for (size_t k = 0; k < c->nfeed; k++) fprintf(fp, "+f_ins%zu[1]", k);
  fprintf(fp, "\n");
  for (size_t w = 0; w < c->nwall_src; w++) {
    const gs_dem_wall_src *s = &c->wall_src[w];
    const int turns = s->rotating && s->omega != 0; /* gs_dem_wall_set_motion's axis */
    const double ax[3] = {turns ? s->axis[0] : 1, turns ? s->axis[1] : 0, turns ? s->axis[2] : 0};
    if (wall_moves(s))
      fprintf(fp, "variable tq%zu equal f_wall%zu[4]*(%.9g)+f_wall%zu[5]*(%.9g)+f_wall%zu[6]*(%.9g)\n", w, w, ax[0], w,
              ax[1], w, ax[2]);
    else fprintf(fp, "variable tq%zu equal 0\n", w);
  }
  fprintf(fp, "thermo_style custom step atoms ke c_rke cpu v_hn v_hm v_nc v_nin");
  for (size_t w = 0; w < c->nwall_src; w++) fprintf(fp, " v_tq%zu", w);
  fprintf(fp, "\nthermo %ld\nthermo_modify lost ignore norm no\n", out_k);

  if (c->vtk_every > 0) { /* text frames in DIR/vtk, named by step: gransim makes them VTK XML (frames.c) */
    long vk = (long)fmax(1, round(c->vtk_every / dt));
    fprintf(fp, "dump dvtk all custom %ld ../vtk/particles_*.dump id type radius x y z vx vy vz\n", vk);
    /* all digits: a frame's radius is its class's (LIGGGHTS' default %g keeps 6) */
    fprintf(fp, "dump_modify dvtk format \"%%d %%d%s\"\n", " %.17g %.17g %.17g %.17g %.17g %.17g %.17g");
    if (c->nwall_src) fprintf(fp, "dump dstl all mesh/stl %ld ../vtk/walls_*.stl\n", vk);
  }
  return ferror(fp) ? gs_error_set(err, GS_EIO, "cannot write the LIGGGHTS deck") : GS_OK;
}

/* What the deck does at step at: the walls that start to turn then, and the
 * statistics window's dumps when it opens then. */
static void events_at(const gs_dem_case *c, FILE *fp, long at) {
  const long nsteps = gs_lig_steps(c), smp_k = (long)fmax(1, round(c->sample_every / c->prm.dt));
  const size_t ncl = c->nclass;
  const double dt = c->prm.dt;
  for (size_t w = 0; w < c->nwall_src && at > 0 && at < nsteps; w++)
    if (wall_turns(&c->wall_src[w]) && spin_step(c, &c->wall_src[w]) == at) {
      fprintf(fp, "# %s starts to turn (rotation.start %.9g s)\n", c->wall_src[w].name, c->wall_src[w].spin_start);
      rotate_cmd(fp, &c->wall_src[w], w);
    }
  if (at != window_step(c)) return;
  {
    if (c->start_steady)
      fprintf(fp, "# statistics.start: steady: the snapshots and contact lists from t = 0, for the detector\n");
    fprintf(fp, "# the statistics window: a snapshot every %ld steps (%.9g s)\n", smp_k, smp_k * dt);
    fprintf(fp, "dump dcol all custom %ld post/collision*.atom id type x y z vx vy vz radius omegax omegay omegaz", smp_k);
    for (size_t i = 1; i <= ncl; i++) fprintf(fp, " c_cc_%zu", i);
    fprintf(fp, "\ndump dpp all local %ld post/ppcoll*.atom", smp_k);
    for (int q = 1; q <= 14; q++) fprintf(fp, " c_pgl[%d]", q);
    fprintf(fp, "\n");
    /* (without walls the runner writes an empty impact file per snapshot) */
    if (c->nwall_src) {
      fprintf(fp, "dump dimp all local %ld post/impact*.atom", smp_k);
      for (int q = 1; q <= 17; q++) fprintf(fp, " c_wgl[%d]", q);
      fprintf(fp, "\n");
    }
    /* the contact lists the collision events are counted from (tables.c) */
    const long ek = gs_lig_event_every(c);
    fprintf(fp, "dump dev all local %ld post/events_pp.txt c_pgl[7] c_pgl[8] c_pgl[14]\n", ek);
    if (c->nwall_src) {
      fprintf(fp, "dump dwev all local %ld post/events_wall.txt", ek);
      for (int q = 1; q <= 9; q++) fprintf(fp, " c_wgl[%d]", q);
      fprintf(fp, " c_wgl[17] c_wgl[13] c_wgl[14] c_wgl[15]\n");
    }
  }
}

void gs_lig_write_runs(const gs_dem_case *c, FILE *fp, long from, long to, int unrolled) {
  const long start_k = window_step(c);
  /* in time order: up to each rotation.start (the wall's move/mesh defined
   * there) and up to the statistics window (its dumps defined there); the
   * events at from belong to the runs before it, but for from = 0 */
  for (long at = from;;) {
    if (at > from || from == 0) events_at(c, fp, at);
    if (at >= to) break;
    long next = to;
    if (start_k > at && start_k < next) next = start_k;
    for (size_t w = 0; w < c->nwall_src; w++) {
      const long k = spin_step(c, &c->wall_src[w]);
      if (wall_turns(&c->wall_src[w]) && k > at && k < next) next = k;
    }
    char label[40];
    snprintf(label, sizeof label, "seg%ld", at);
    fprintf(fp, "# to t = %.9g s\n", next * c->prm.dt);
    run_cmd(fp, c, next - at, label, unrolled);
    at = next;
  }
}

int gs_lig_write_deck(const gs_dem_case *c, FILE *fp, const char *data_file, const char *exclusion,
                      gs_error *err) {
  int rc = gs_lig_write_setup(c, fp, data_file, exclusion, err);
  if (rc) return rc;
  gs_lig_write_runs(c, fp, 0, gs_lig_steps(c), 0);
  return ferror(fp) ? gs_error_set(err, GS_EIO, "cannot write the LIGGGHTS deck") : GS_OK;
}

int gs_lig_write_exclusion_deck(const gs_dem_case *c, size_t wall, const char *path, gs_error *err) {
  FILE *fp = fopen(path, "w");
  if (!fp) return gs_error_set(err, GS_EIO, "%s: cannot write: %s", path, strerror(errno));
  preamble(c, fp, NULL);
  /* no atoms, hence no cutoff: LIGGGHTS would refuse to sort them by bins of size 0 */
  fprintf(fp, "atom_modify sort 0 0.0\n");
  const gs_dem_wall_src *s = &c->wall_src[wall];
  char mesh[4200];
  gs_lig_mesh_name(c, wall, mesh, sizeof mesh);
  fprintf(fp, "fix wall%zu all mesh/surface file %s type %zu heal auto_remove_duplicates "
          "element_exclusion_list write ex_wall%zu.txt scale %.9g curvature_tolerant yes\n", wall, mesh,
          c->nclass + 1 + wall, wall, s->scale);
  fprintf(fp, "fix walls all wall/gran model hertz tangential history rolling_friction cdt mesh n_meshes 1 "
          "meshes wall%zu\nrun 1\n", wall);
  int bad = ferror(fp);
  if (fclose(fp) || bad) return gs_error_set(err, GS_EIO, "%s: write failed", path);
  return GS_OK;
}
