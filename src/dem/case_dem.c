/* Reading a DEM case file (YAML) into a simulation; every key is validated
 * where it is read (gs_cfg_*), so errors name file:line, key and value.
 * The keys are documented in docs/case-files.md, section "DEM cases". */
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "dem/dem_case.h"
#include "dem/dem_generate.h"
#include "dem/dem_internal.h"

typedef struct {
  const char *name;
  gs_dem_material m;
} named_mat;

static int vec3(gs_cfg_node *map, const char *key, int required, const double *def, double out[3],
                gs_error *err) {
  gs_cfg_node *n = gs_cfg_get(map, key);
  if (!n) {
    if (required) return gs_cfg_missing(map, key, "(a list of 3 numbers)", err);
    memcpy(out, def, 3 * sizeof(double));
    return GS_OK;
  }
  double *v = NULL;
  size_t k = 0;
  int rc = gs_cfg_doubles_req(map, key, 0, &v, &k, err);
  if (!rc && k != 3) rc = gs_cfg_fail(n, err, "expected a list of 3 numbers, got %zu", k);
  if (!rc) memcpy(out, v, 3 * sizeof(double));
  free(v);
  return rc;
}

/* A position or length vector, times the case's dem.geometry_scale. */
static int point3(const gs_dem_case *c, gs_cfg_node *map, const char *key, int required, const double *def,
                  double out[3], gs_error *err) {
  int rc = vec3(map, key, required, def, out, err);
  for (int k = 0; k < 3 && !rc; k++) out[k] *= c->geom;
  return rc;
}

static int unit_vec(gs_cfg_node *map, const char *key, double out[3], gs_error *err) {
  int rc = vec3(map, key, 1, NULL, out, err);
  if (rc) return rc;
  double l = sqrt(out[0] * out[0] + out[1] * out[1] + out[2] * out[2]);
  if (!(l > 0)) return gs_cfg_fail(gs_cfg_get(map, key), err, "expected a non-zero vector");
  for (int k = 0; k < 3; k++) out[k] /= l;
  return GS_OK;
}

/* region: {box: {lo, hi}} or {cylinder: {point, axis, radius, inner_radius, from, to}};
 * every length times dem.geometry_scale */
static int read_region(const gs_dem_case *dc, gs_cfg_node *n, gs_dem_region *g, gs_error *err) {
  int rc = gs_cfg_require_kind(n, GS_CFG_MAP, err);
  if (rc) return rc;
  memset(g, 0, sizeof *g);
  gs_cfg_node *b = gs_cfg_get(n, "box"), *c = gs_cfg_get(n, "cylinder");
  if (!!b == !!c) return gs_cfg_fail(n, err, "expected exactly one of 'box' or 'cylinder'");
  if (b) {
    g->kind = GS_DEM_REGION_BOX;
    if ((rc = gs_cfg_require_kind(b, GS_CFG_MAP, err)) || (rc = point3(dc, b, "lo", 1, NULL, g->lo, err)) ||
        (rc = point3(dc, b, "hi", 1, NULL, g->hi, err)))
      return rc;
    for (int a = 0; a < 3; a++)
      if (!(g->hi[a] > g->lo[a])) return gs_cfg_fail(gs_cfg_get(b, "hi"), err, "expected hi > lo on every axis");
    rc = gs_cfg_check_unused(b, err);
  } else {
    g->kind = GS_DEM_REGION_CYLINDER;
    if ((rc = gs_cfg_require_kind(c, GS_CFG_MAP, err)) || (rc = point3(dc, c, "point", 1, NULL, g->p, err)) ||
        (rc = unit_vec(c, "axis", g->a, err)) ||
        (rc = gs_cfg_double_range(c, "radius", 1, 0, 0, 1, HUGE_VAL, 0, &g->R, err)) ||
        (rc = gs_cfg_double_range(c, "inner_radius", 0, 0, 0, 0, g->R, 1, &g->Rin, err)) ||
        (rc = gs_cfg_double_req(c, "from", &g->s0, err)) ||
        (rc = gs_cfg_double_range(c, "to", 1, 0, g->s0, 1, HUGE_VAL, 0, &g->s1, err)))
      return rc;
    g->R *= dc->geom;
    g->Rin *= dc->geom;
    g->s0 *= dc->geom;
    g->s1 *= dc->geom;
    rc = gs_cfg_check_unused(c, err);
  }
  if (!rc) rc = gs_cfg_check_unused(n, err);
  return rc;
}

/* radius: {type: lognormal, median, gsd, min, max}; without min and max the
 * distribution is truncated to median * gsd^(-/+3) (99.73 % of it), since the
 * cells and mesh bins need a largest radius */
static int read_lognormal(gs_cfg_node *n, gs_dem_class *cl, gs_error *err) {
  static const char *const types[] = {"lognormal", NULL};
  int type = 0;
  double med, gsd;
  int rc = gs_cfg_get(n, "type") ? gs_cfg_enum_opt(n, "type", types, 0, &type, err)
                                  : gs_cfg_missing(n, "type", "(a radius distribution: lognormal)", err);
  if (!rc) rc = gs_cfg_double_range(n, "median", 1, 0, 0, 1, HUGE_VAL, 0, &med, err);
  if (!rc) rc = gs_cfg_double_range(n, "gsd", 1, 0, 1, 1, HUGE_VAL, 0, &gsd, err);
  if (rc) return rc;
  double s3 = pow(gsd, 3);
  if (!rc) rc = gs_cfg_double_range(n, "min", 0, med / s3, 0, 1, HUGE_VAL, 0, &cl->rmin, err);
  if (!rc) rc = gs_cfg_double_range(n, "max", 0, med * s3, cl->rmin, 1, HUGE_VAL, 0, &cl->rmax, err);
  if (!rc) rc = gs_cfg_check_unused(n, err);
  if (rc) return rc;
  cl->median = med;
  cl->gsd = gsd;
  /* rejection sampling: the range must hold a fair share of the distribution */
  int t = 0;
  double rmin = cl->rmin, rmax = cl->rmax, share;
  gs_dem_psd one = {1, &t, &rmin, &rmax, NULL, 0, &med, &gsd};
  gs_dem_psd_moment3(&one, 0, NULL, &share);
  if (!(share >= 0.01))
    return gs_cfg_fail(n, err, "the range [min, max] = [%g, %g] holds only %.3g of the lognormal (median %g, gsd %g); "
                       "expected at least 1 %%", cl->rmin, cl->rmax, share, med, gsd);
  return GS_OK;
}

static int read_material(gs_cfg_node *n, named_mat *nm, gs_error *err) {
  int rc = gs_cfg_require_kind(n, GS_CFG_MAP, err);
  gs_dem_material *m = &nm->m;
  if (!rc) rc = gs_cfg_string_req(n, "name", &nm->name, err);
  if (!rc) rc = gs_cfg_double_range(n, "E", 1, 0, 0, 1, HUGE_VAL, 0, &m->E, err);
  if (!rc) rc = gs_cfg_double_range(n, "nu", 1, 0, -1, 1, 0.5, 1, &m->nu, err);
  if (!rc) rc = gs_cfg_double_range(n, "e", 1, 0, 0, 1, 1, 0, &m->e, err);
  if (!rc) rc = gs_cfg_double_range(n, "mu_s", 1, 0, 0, 0, HUGE_VAL, 0, &m->mu_s, err);
  if (!rc) rc = gs_cfg_double_range(n, "mu_r", 0, 0, 0, 0, HUGE_VAL, 0, &m->mu_r, err);
  if (!rc) rc = gs_cfg_double_range(n, "density", 0, 0, 0, 0, HUGE_VAL, 0, &m->density, err);
  if (!rc) rc = gs_cfg_check_unused(n, err);
  return rc;
}

static int find_mat(gs_cfg_node *map, const named_mat *mats, size_t nm, const gs_dem_material **out,
                    gs_error *err) {
  const char *name;
  int rc = gs_cfg_string_req(map, "material", &name, err);
  if (rc) return rc;
  for (size_t k = 0; k < nm; k++)
    if (!strcmp(mats[k].name, name)) {
      *out = &mats[k].m;
      return GS_OK;
    }
  return gs_cfg_fail(gs_cfg_get(map, "material"), err, "no material of that name in 'materials'");
}

/* A wall marked `closed: true` must have no hole: a particle would leave
 * through it (the edge is named in metres, after `scale`). */
static int mesh_closed(gs_cfg_node *n, const gs_dem_mesh *me, const char *file, gs_error *err) {
  size_t nopen = 0, tri = 0;
  int k = 0;
  int rc = gs_dem_mesh_open_edges(me, &nopen, &tri, &k, err);
  if (rc || !nopen) return rc;
  const double *a = me->v + 9 * tri + 3 * k, *b = me->v + 9 * tri + 3 * ((k + 1) % 3);
  return gs_cfg_fail(gs_cfg_get(n, "closed"), err,
                     "the mesh %s is not closed: %zu edges belong to one facet only (a hole), the first of "
                     "facet %zu (counted from 1), from (%g, %g, %g) to (%g, %g, %g) m; repair the mesh, or "
                     "leave `closed` out if the wall is meant to be open", file, nopen, tri + 1, a[0], a[1],
                     a[2], b[0], b[1], b[2]);
}

static int read_wall(gs_dem_case *c, gs_cfg_node *n, const named_mat *mats, size_t nm, gs_error *err) {
  int rc = gs_cfg_require_kind(n, GS_CFG_MAP, err);
  const char *name = NULL;
  const gs_dem_material *m = NULL;
  if (!rc) rc = gs_cfg_string_req(n, "name", &name, err);
  if (!rc) rc = find_mat(n, mats, nm, &m, err);
  if (rc) return rc;
  gs_cfg_node *mesh = gs_cfg_get(n, "mesh"), *pl = gs_cfg_get(n, "plane"), *cy = gs_cfg_get(n, "cylinder");
  gs_cfg_node *gen = gs_cfg_get(n, "generate");
  if ((mesh != NULL) + (pl != NULL) + (cy != NULL) + (gen != NULL) != 1)
    return gs_cfg_fail(n, err, "expected exactly one of 'mesh' (an STL file), 'plane', 'cylinder' or 'generate' "
                       "(a bowl or impeller)");
  gs_dem_gen_motion gm = {0};
  int w = -1;
  if (c->nwall_src >= GS_DEM_CASE_MAX_WALLS)
    return gs_cfg_fail(n, err, "at most %d walls", GS_DEM_CASE_MAX_WALLS);
  gs_dem_wall_src *src = &c->wall_src[c->nwall_src++];
  snprintf(src->name, sizeof src->name, "%s", name);
  src->mat = *m;
  src->scale = 1;
  src->kind = mesh || gen ? GS_DEM_SRC_MESH : pl ? GS_DEM_SRC_PLANE : GS_DEM_SRC_CYLINDER;
  if (gen) {
    /* generated: the triangles go to the engine now and to an STL file in
     * the output folder when the case runs (gs_dem_case_write_geometry) */
    gs_dem_tris tr = {0};
    gs_dem_mesh *me = NULL;
    rc = gs_cfg_require_kind(gen, GS_CFG_MAP, err);
    if (!rc) rc = gs_dem_generate(gen, &tr, &gm, err);
    for (size_t i = 0; !rc && i < 9 * tr.ntri; i++) tr.v[i] *= c->geom;
    for (int a = 0; a < 3; a++) gm.origin[a] *= c->geom;
    if (!rc && !(me = gs_dem_mesh_from_triangles(tr.v, tr.ntri, err))) rc = err->code;
    gs_dem_tris_free(&tr);
    if (rc) return rc;
    src->generated = 1;
    src->mesh[0] = '\0';
    w = gs_dem_add_mesh(c->dem, name, me, m, err);
  } else if (mesh) {
    const char *file;
    double scale;
    if ((rc = gs_cfg_string_req(n, "mesh", &file, err)) ||
        (rc = gs_cfg_double_range(n, "scale", 0, 1, 0, 1, HUGE_VAL, 0, &scale, err)))
      return rc;
    char path[4096];
    snprintf(path, sizeof path, "%s%s%s", file[0] == '/' ? "" : gs_cfg_dir(c->cfg),
             file[0] == '/' ? "" : "/", file);
    /* absolute, since LIGGGHTS runs in another folder */
    char *abs = realpath(path, NULL);
    snprintf(src->mesh, sizeof src->mesh, "%s", abs ? abs : path);
    free(abs);
    src->scale = scale * c->geom;
    gs_dem_mesh *me = gs_dem_mesh_read_stl(path, src->scale, err);
    if (!me) return gs_error_prefix(err, "%s:%d: walls: ", gs_cfg_file(mesh), gs_cfg_line(mesh));
    int closed;
    if ((rc = gs_cfg_bool_opt(n, "closed", 0, &closed, err)) || (rc = closed ? mesh_closed(n, me, file, err) : 0)) {
      gs_dem_mesh_free(me);
      return rc;
    }
    w = gs_dem_add_mesh(c->dem, name, me, m, err);
  } else if (pl) {
    double p[3], nv[3];
    if ((rc = gs_cfg_require_kind(pl, GS_CFG_MAP, err)) || (rc = point3(c, pl, "point", 1, NULL, p, err)) ||
        (rc = unit_vec(pl, "normal", nv, err)) || (rc = gs_cfg_check_unused(pl, err)))
      return rc;
    memcpy(src->point, p, sizeof p);
    memcpy(src->normal, nv, sizeof nv);
    w = gs_dem_add_plane(c->dem, name, p, nv, m, err);
  } else {
    double p[3], a[3], R;
    int inside;
    if ((rc = gs_cfg_require_kind(cy, GS_CFG_MAP, err)) || (rc = point3(c, cy, "point", 1, NULL, p, err)) ||
        (rc = unit_vec(cy, "axis", a, err)) ||
        (rc = gs_cfg_double_range(cy, "radius", 1, 0, 0, 1, HUGE_VAL, 0, &R, err)) ||
        (rc = gs_cfg_bool_opt(cy, "inside", 1, &inside, err)) || (rc = gs_cfg_check_unused(cy, err)))
      return rc;
    R *= c->geom;
    w = gs_dem_add_cylinder(c->dem, name, p, a, R, inside, m, err);
  }
  if (w < 0) return gs_error_prefix(err, "%s:%d: %s: ", gs_cfg_file(n), gs_cfg_line(n), gs_cfg_path(n));
  /* motion: rotation {origin, axis, rpm | rad_per_s}, velocity */
  double origin[3] = {0, 0, 0}, axis[3] = {1, 0, 0}, omega = 0, vel[3] = {0, 0, 0}, spin_start = 0;
  gs_cfg_node *rot = gs_cfg_get(n, "rotation");
  if (rot && gm.rotating)
    return gs_cfg_fail(rot, err, "the generated wall turns at its own 'rpm' about the bowl's axis; give one or "
                       "the other");
  if (gm.rotating) {
    memcpy(origin, gm.origin, sizeof origin);
    memcpy(axis, gm.axis, sizeof axis);
    omega = gm.omega;
    spin_start = gm.start;
  }
  if (rot) {
    if ((rc = gs_cfg_require_kind(rot, GS_CFG_MAP, err)) || (rc = point3(c, rot, "origin", 1, NULL, origin, err)) ||
        (rc = unit_vec(rot, "axis", axis, err)))
      return rc;
    gs_cfg_node *rpm = gs_cfg_get(rot, "rpm"), *rad = gs_cfg_get(rot, "rad_per_s");
    if (!!rpm == !!rad) return gs_cfg_fail(rot, err, "expected exactly one of 'rpm' or 'rad_per_s'");
    if (rpm) {
      if ((rc = gs_cfg_double_req(rot, "rpm", &omega, err))) return rc;
      omega *= 2 * M_PI / 60;
    } else if ((rc = gs_cfg_double_req(rot, "rad_per_s", &omega, err))) {
      return rc;
    }
    if ((rc = gs_cfg_double_range(rot, "start", 0, 0, 0, 0, HUGE_VAL, 0, &spin_start, err)) ||
        (rc = gs_cfg_check_unused(rot, err)))
      return rc;
  }
  /* a geometry scaled by dem.geometry_scale turns at the same tip speed (docs/models.md, "System scaling") */
  omega /= c->geom;
  const double zero[3] = {0, 0, 0};
  if ((rc = vec3(n, "velocity", 0, zero, vel, err))) return rc;
  src->rotating = rot != NULL || gm.rotating;
  src->wall = w;
  memcpy(src->origin, origin, sizeof origin);
  memcpy(src->axis, axis, sizeof axis);
  src->omega = omega;
  src->spin_start = spin_start;
  memcpy(src->velocity, vel, sizeof vel);
  if (src->rotating || vel[0] != 0 || vel[1] != 0 || vel[2] != 0)
    if ((rc = gs_dem_wall_set_motion(c->dem, w, origin, axis, omega, vel, err)) ||
        (rc = gs_dem_wall_set_spin_start(c->dem, w, spin_start, err)))
      return rc;
  return gs_cfg_check_unused(n, err);
}

static int read_inserter(gs_dem_case *c, gs_cfg_node *n, int feed, gs_dem_inserter *in, gs_error *err) {
  int rc = gs_cfg_require_kind(n, GS_CFG_MAP, err);
  gs_cfg_node *r;
  memset(in, 0, sizeof *in);
  if (!rc) rc = gs_cfg_map_req(n, "region", &r, err);
  if (!rc) rc = read_region(c, r, &in->reg, err);
  if (rc) return rc;
  if (feed) {
    gs_cfg_node *mr = gs_cfg_get(n, "mass_rate"), *nr = gs_cfg_get(n, "number_rate");
    if (!!mr == !!nr) return gs_cfg_fail(n, err, "expected exactly one of 'mass_rate' [kg/s] or 'number_rate' [1/s]");
    if (mr) rc = gs_cfg_double_range(n, "mass_rate", 1, 0, 0, 1, HUGE_VAL, 0, &in->mass_rate, err);
    else rc = gs_cfg_double_range(n, "number_rate", 1, 0, 0, 1, HUGE_VAL, 0, &in->number_rate, err);
    if (!rc) rc = gs_cfg_double_range(n, "every", 0, 1e-3, 0, 1, HUGE_VAL, 0, &in->every, err);
    if (!rc) rc = gs_cfg_double_range(n, "start", 0, 0, 0, 0, HUGE_VAL, 0, &in->start, err);
    if (!rc) rc = gs_cfg_double_range(n, "end", 0, HUGE_VAL, in->start, 0, HUGE_VAL, 0, &in->end, err);
    in->next_t = in->start;
  } else {
    gs_cfg_node *cn = gs_cfg_get(n, "count"), *mn = gs_cfg_get(n, "mass");
    if (!!cn == !!mn) return gs_cfg_fail(n, err, "expected exactly one of 'count' or 'mass' [kg]");
    in->count = LONG_MAX;
    in->mass = HUGE_VAL;
    if (cn) rc = gs_cfg_long_range(n, "count", 1, 0, 1, 100000000, &in->count, err);
    else rc = gs_cfg_double_range(n, "mass", 1, 0, 0, 1, HUGE_VAL, 0, &in->mass, err);
  }
  const double zero[3] = {0, 0, 0};
  if (!rc) rc = vec3(n, "velocity", 0, zero, in->v, err);
  static const char *const by[] = {"number", "mass", NULL};
  if (!rc) rc = gs_cfg_enum_opt(n, "fractions_by", by, 0, &in->by_mass, err);
  size_t nf = 0;
  if (!rc && gs_cfg_get(n, "fractions")) {
    rc = gs_cfg_doubles_req(n, "fractions", 0, &in->frac, &nf, err);
    if (!rc && nf != c->nclass)
      rc = gs_cfg_fail(gs_cfg_get(n, "fractions"), err, "expected %zu fractions (one per class), got %zu",
                       c->nclass, nf);
    double s = 0;
    for (size_t k = 0; !rc && k < nf; k++) {
      if (in->frac[k] < 0) rc = gs_cfg_fail(gs_cfg_get(n, "fractions"), err, "fractions must be >= 0");
      s += in->frac[k];
    }
    if (!rc && !(s > 0)) rc = gs_cfg_fail(gs_cfg_get(n, "fractions"), err, "fractions must not all be 0");
  } else if (!rc) {
    in->frac = malloc(c->nclass * sizeof(double));
    if (!in->frac) return gs_error_set(err, GS_ENOMEM, "out of memory");
    for (size_t k = 0; k < c->nclass; k++) in->frac[k] = 1;
  }
  if (!rc) rc = gs_cfg_check_unused(n, err);
  return rc;
}

static int read_list(gs_dem_case *c, gs_cfg_node *root, const char *key, int feed,
                     gs_dem_inserter **out, size_t *nout, gs_error *err) {
  gs_cfg_node *s = gs_cfg_get(root, key);
  if (!s) return GS_OK;
  int rc = gs_cfg_require_kind(s, GS_CFG_SEQ, err);
  if (rc) return rc;
  *nout = gs_cfg_size(s);
  *out = calloc(*nout ? *nout : 1, sizeof **out);
  if (!*out) return gs_error_set(err, GS_ENOMEM, "out of memory");
  for (size_t k = 0; k < *nout && !rc; k++) rc = read_inserter(c, gs_cfg_item(s, k), feed, &(*out)[k], err);
  return rc;
}

static int read_statistics(gs_dem_case *c, gs_cfg_node *root, gs_error *err) {
  gs_cfg_node *s = gs_cfg_get(root, "statistics");
  c->sample_every = c->duration / 100;
  c->steady_window = 10;
  c->steady_tol = 0.1;
  c->steady_q = GS_DEM_STEADY_DEFAULT;
  c->ncmp = 1;
  c->cmp_axis[0] = 1;
  c->cmp_edges = malloc(2 * sizeof(double));
  if (!c->cmp_edges) return gs_error_set(err, GS_ENOMEM, "out of memory");
  c->cmp_edges[0] = -HUGE_VAL;
  c->cmp_edges[1] = HUGE_VAL;
  if (!s) return GS_OK;
  int rc = gs_cfg_require_kind(s, GS_CFG_MAP, err);
  gs_cfg_node *st = rc ? NULL : gs_cfg_get(s, "start");
  if (st && gs_cfg_scalar(st) && !strcmp(gs_cfg_scalar(st), "steady")) c->start_steady = 1;
  else if (!rc) rc = gs_cfg_double_range(s, "start", 0, 0, 0, 0, c->duration, 1, &c->stats_start, err);
  if (!rc) rc = gs_cfg_double_range(s, "sample_every", 0, c->sample_every, 0, 1, HUGE_VAL, 0, &c->sample_every, err);
  if (!rc) rc = gs_cfg_double_range(s, "impact_bin", 0, 0.25, 0, 1, HUGE_VAL, 0, &c->prm.impact_dv, err);
  gs_cfg_node *cm = rc ? NULL : gs_cfg_get(s, "compartments");
  if (cm) {
    size_t ne = 0;
    free(c->cmp_edges);
    c->cmp_edges = NULL;
    const double zero[3] = {0, 0, 0};
    if ((rc = gs_cfg_require_kind(cm, GS_CFG_MAP, err)) || (rc = unit_vec(cm, "axis", c->cmp_axis, err)) ||
        (rc = point3(c, cm, "origin", 0, zero, c->cmp_origin, err)) ||
        (rc = gs_cfg_doubles_req(cm, "edges", 0, &c->cmp_edges, &ne, err)))
      return rc;
    for (size_t k = 0; k < ne; k++) c->cmp_edges[k] *= c->geom;
    if (ne < 2) return gs_cfg_fail(gs_cfg_get(cm, "edges"), err, "expected 2 or more increasing edges");
    for (size_t k = 1; k < ne; k++)
      if (!(c->cmp_edges[k] > c->cmp_edges[k - 1]))
        return gs_cfg_fail(gs_cfg_get(cm, "edges"), err, "edges must increase");
    c->ncmp = ne - 1;
    if ((rc = gs_cfg_check_unused(cm, err))) return rc;
  }
  gs_cfg_node *h = rc ? NULL : gs_cfg_get(s, "holdup_region");
  if (h) {
    c->has_holdup = 1;
    rc = read_region(c, h, &c->holdup, err);
  }
  gs_cfg_node *sd = rc ? NULL : gs_cfg_get(s, "steady");
  if (sd) {
    if ((rc = gs_cfg_require_kind(sd, GS_CFG_MAP, err)) ||
        (rc = gs_cfg_long_range(sd, "window", 0, 10, 2, 100000, &c->steady_window, err)) ||
        (rc = gs_cfg_double_range(sd, "tolerance", 0, 0.1, 0, 1, HUGE_VAL, 0, &c->steady_tol, err)) ||
        (gs_cfg_get(sd, "quantities") &&
         (rc = gs_dem_steady_quantities_read(gs_cfg_get(sd, "quantities"), &c->steady_q, err))) ||
        (rc = gs_cfg_check_unused(sd, err)))
      return rc;
  }
  if (!rc) rc = gs_cfg_check_unused(s, err);
  return rc;
}

static int load(gs_dem_case *c, gs_error *err) {
  gs_cfg_node *root = gs_cfg_root(c->cfg), *dem, *mats, *classes, *n;
  if (!root) return gs_error_set(err, GS_EINPUT, "%s: empty case file", c->path);
  int rc = gs_cfg_require_kind(root, GS_CFG_MAP, err);
  if (!rc) rc = gs_cfg_map_req(root, "dem", &dem, err);
  if (rc) return rc;
  gs_dem_params *p = &c->prm;
  memset(p, 0, sizeof *p);
  static const char *const damp[] = {"exact", "liggghts", NULL};
  static const char *const mesh_contacts[] = {"closest", "liggghts", NULL};
  static const char *const engines[] = {"embedded", "liggghts", NULL};
  const double g0[3] = {0, 0, -9.81};
  long seed = 1, threads_from = 20000;
  gs_cfg_node *box;
  if ((rc = gs_cfg_double_range(dem, "time_step", 1, 0, 0, 1, 1, 0, &p->dt, err)) ||
      (rc = gs_cfg_double_range(dem, "geometry_scale", 0, 1, 0, 1, HUGE_VAL, 0, &c->geom, err)) ||
      (rc = gs_cfg_double_range(dem, "max_lost", 0, 0.01, 0, 0, 1, 0, &c->max_lost, err)) ||
      (rc = gs_cfg_double_range(dem, "duration", 1, 0, 0, 1, HUGE_VAL, 0, &c->duration, err)) ||
      (rc = vec3(dem, "gravity", 0, g0, p->gravity, err)) ||
      (rc = gs_cfg_enum_opt(dem, "damping", damp, 0, &p->damping, err)) ||
      (rc = gs_cfg_enum_opt(dem, "engine", engines, GS_DEM_ENGINE_EMBEDDED, &c->engine, err)) ||
      (rc = gs_cfg_enum_opt(dem, "mesh_contacts", mesh_contacts, 0, &p->mesh_contacts, err)) ||
      (rc = gs_cfg_long_range(dem, "seed", 0, 1, 0, LONG_MAX, &seed, err)) ||
      (rc = gs_cfg_long_range(dem, "threads_from", 0, 20000, 1, LONG_MAX, &threads_from, err)) ||
      (rc = gs_cfg_map_req(dem, "box", &box, err)) || (rc = point3(c, box, "lo", 1, NULL, p->lo, err)) ||
      (rc = point3(c, box, "hi", 1, NULL, p->hi, err)) || (rc = gs_cfg_check_unused(box, err)))
    return rc;
  for (int a = 0; a < 3; a++)
    if (!(p->hi[a] > p->lo[a])) return gs_cfg_fail(gs_cfg_get(box, "hi"), err, "expected hi > lo on every axis");
  c->seed = (uint64_t)seed;
  c->damping_given = gs_cfg_get(dem, "damping") != NULL;
  c->mesh_contacts_given = gs_cfg_get(dem, "mesh_contacts") != NULL;
  gs_cfg_node *skin = gs_cfg_get(dem, "skin");
  /* materials */
  if ((rc = gs_cfg_seq_req(root, "materials", &mats, err))) return rc;
  size_t nm = gs_cfg_size(mats);
  named_mat *mt = calloc(nm ? nm : 1, sizeof *mt);
  if (!mt) return gs_error_set(err, GS_ENOMEM, "out of memory");
  for (size_t k = 0; k < nm && !rc; k++) rc = read_material(gs_cfg_item(mats, k), &mt[k], err);
  /* classes: one particle type each */
  if (!rc) rc = gs_cfg_seq_req(root, "classes", &classes, err);
  if (!rc) {
    c->nclass = gs_cfg_size(classes);
    if (c->nclass < 1 || c->nclass > GS_DEM_MAX_CLASSES)
      rc = gs_cfg_fail(classes, err, "expected 1 to %d classes", GS_DEM_MAX_CLASSES);
  }
  double rmin_all = HUGE_VAL, rmax_all = 0;
  const gs_dem_material *cmat[GS_DEM_MAX_CLASSES];
  for (size_t k = 0; k < c->nclass && !rc; k++) {
    gs_cfg_node *cn = gs_cfg_item(classes, k);
    const char *name;
    if ((rc = gs_cfg_require_kind(cn, GS_CFG_MAP, err)) || (rc = gs_cfg_string_req(cn, "name", &name, err)) ||
        (rc = find_mat(cn, mt, nm, &cmat[k], err)))
      break;
    if (!(cmat[k]->density > 0)) {
      rc = gs_cfg_fail(gs_cfg_get(cn, "material"), err, "a particle material needs 'density' > 0");
      break;
    }
    snprintf(c->cls[k].name, sizeof c->cls[k].name, "%s", name);
    c->cls[k].mat = *cmat[k];
    gs_cfg_node *rn = gs_cfg_get(cn, "radius");
    if (rn && gs_cfg_kind_of(rn) == GS_CFG_MAP) {
      if ((rc = read_lognormal(rn, &c->cls[k], err))) break;
    } else {
      double *r = NULL;
      size_t nr = 0;
      if ((rc = gs_cfg_doubles_req(cn, "radius", 1, &r, &nr, err))) break;
      if (nr == 1) c->cls[k].rmin = c->cls[k].rmax = r[0];
      else if (nr == 2) c->cls[k].rmin = r[0], c->cls[k].rmax = r[1];
      free(r);
      if (nr > 2 || !(c->cls[k].rmin > 0) || c->cls[k].rmax < c->cls[k].rmin) {
        rc = gs_cfg_fail(rn, err, "expected a radius > 0 [m], a range [min, max] or "
                         "{type: lognormal, median, gsd, min, max}");
        break;
      }
    }
    rmin_all = fmin(rmin_all, c->cls[k].rmin);
    rmax_all = fmax(rmax_all, c->cls[k].rmax);
    rc = gs_cfg_check_unused(cn, err);
  }
  if (!rc) rc = gs_cfg_double_range(dem, "skin", 0, rmin_all, 0, 1, HUGE_VAL, 0, &p->skin, err);
  (void)skin;
  p->nclass = (int)c->nclass;
  if (!rc) rc = read_statistics(c, root, err);
  if (!rc) {
    rc = gs_cfg_check_unused(dem, err);
  }
  if (!rc && !(c->dem = gs_dem_alloc(p, err))) rc = err->code;
  if (!rc) gs_dem_set_parallel_min(c->dem, (size_t)threads_from);
  for (size_t k = 0; k < c->nclass && !rc; k++) {
    c->cls[k].type = gs_dem_add_type(c->dem, cmat[k], (int)k, err);
    if (c->cls[k].type < 0) rc = err->code;
  }
  /* walls */
  n = rc ? NULL : gs_cfg_get(root, "walls");
  if (n && !(rc = gs_cfg_require_kind(n, GS_CFG_SEQ, err)))
    for (size_t k = 0; k < gs_cfg_size(n) && !rc; k++) rc = read_wall(c, gs_cfg_item(n, k), mt, nm, err);
  if (!rc) rc = read_list(c, root, "fill", 0, &c->fill, &c->nfill, err);
  if (!rc) rc = read_list(c, root, "feed", 1, &c->feed, &c->nfeed, err);
  n = rc ? NULL : gs_cfg_get(root, "outlets");
  if (n && !(rc = gs_cfg_require_kind(n, GS_CFG_SEQ, err))) {
    c->noutlets = gs_cfg_size(n);
    c->outlets = calloc(c->noutlets ? c->noutlets : 1, sizeof *c->outlets);
    if (!c->outlets) rc = gs_error_set(err, GS_ENOMEM, "out of memory");
    for (size_t k = 0; k < c->noutlets && !rc; k++) {
      gs_cfg_node *o = gs_cfg_item(n, k), *r;
      if (!(rc = gs_cfg_require_kind(o, GS_CFG_MAP, err)) && !(rc = gs_cfg_map_req(o, "region", &r, err)) &&
          !(rc = read_region(c, r, &c->outlets[k], err)))
        rc = gs_cfg_check_unused(o, err);
    }
  }
  gs_cfg_node *out = rc ? NULL : gs_cfg_get(root, "output");
  c->out_every = c->duration / 20;
  if (out) {
    if (!(rc = gs_cfg_require_kind(out, GS_CFG_MAP, err)) &&
        !(rc = gs_cfg_double_range(out, "every", 0, c->out_every, 0, 1, HUGE_VAL, 0, &c->out_every, err)) &&
        !(rc = gs_cfg_double_range(out, "vtk_every", 0, 0, 0, 0, HUGE_VAL, 0, &c->vtk_every, err)))
      rc = gs_cfg_check_unused(out, err);
  }
  if (!rc) rc = gs_dem_wet_read(c, root, rmin_all, err);
  /* sections read by the layers above when they run the case: `gas` (the
   * gas phase, src/cfd, through gs_dem_case_section) */
  if (!rc) c->gas = gs_cfg_get(root, "gas");
  /* the gas grid is read by src/cfd, which does not scale it */
  if (!rc && c->gas && c->geom != 1)
    rc = gs_cfg_fail(gs_cfg_get(dem, "geometry_scale"), err, "a case with a `gas` section cannot be scaled (its grid "
                     "and inlets are not): expected geometry_scale 1");
  if (!rc) rc = gs_dem_case_check_limits(c, root, err);
  if (!rc) rc = gs_cfg_check_unused(root, err);
  /* the time step against the Rayleigh time of the smallest particle */
  if (!rc) {
    double tr = HUGE_VAL;
    for (size_t k = 0; k < c->nclass; k++) {
      const gs_dem_material *m = cmat[k];
      double G = m->E / (2 * (1 + m->nu));
      tr = fmin(tr, M_PI * c->cls[k].rmin * sqrt(m->density / G) / (0.1631 * m->nu + 0.8766));
    }
    /* Above half the Rayleigh time a contact lasts a few steps only: overlaps
     * overshoot, energy grows and particles pass through each other and the
     * walls (at 2.4 times it, 492 of 500 particles left the box). */
    if (p->dt > GS_DEM_MAX_RAYLEIGH_FRACTION * tr)
      rc = gs_cfg_fail(gs_cfg_get(dem, "time_step"), err,
                       "the time step is %.0f %% of the Rayleigh time %g s of the smallest particle; at most "
                       "%.0f %% is accepted (20 %% or less is recommended)", 100 * p->dt / tr, tr,
                       100 * GS_DEM_MAX_RAYLEIGH_FRACTION);
    else if (p->dt > 0.2 * tr)
      fprintf(stderr, "gransim: warning: %s: time_step %g s is %.0f %% of the Rayleigh time %g s of the "
              "smallest particle; more than 20 %% risks an unstable or inaccurate run\n",
              c->path, p->dt, 100 * p->dt / tr, tr);
  }
  free(mt);
  return rc;
}

gs_dem_case *gs_dem_case_load(const char *path, gs_error *err) {
  gs_cfg *cfg = gs_cfg_load_file(path, err);
  return cfg ? gs_dem_case_from_cfg(cfg, err) : NULL;
}

gs_dem_case *gs_dem_case_from_cfg(gs_cfg *cfg, gs_error *err) {
  gs_dem_case *c = calloc(1, sizeof *c);
  if (!c) {
    gs_cfg_free(cfg);
    gs_error_set(err, GS_ENOMEM, "out of memory");
    return NULL;
  }
  snprintf(c->path, sizeof c->path, "%s", gs_cfg_name(cfg));
  c->cfg = cfg;
  if (load(c, err)) {
    gs_dem_case_free(c);
    return NULL;
  }
  return c;
}

void gs_dem_case_describe(const gs_dem_case *c, char *buf, size_t n) {
  snprintf(buf, n, "%zu size classes, %zu walls, %zu fill and %zu feed insertions, %zu outlets, "
           "%.4g s at dt = %.3g s (%.0f steps)",
           c->nclass, gs_dem_nwalls(c->dem), c->nfill, c->nfeed, c->noutlets, c->duration, c->prm.dt,
           ceil(c->duration / c->prm.dt - 1e-9));
}

int gs_dem_case_engine(const gs_dem_case *c) { return c->engine; }
void gs_dem_case_set_engine(gs_dem_case *c, int engine) { c->engine = engine; }
gs_dem *gs_dem_case_sim(gs_dem_case *c) { return c->dem; }
gs_cfg_node *gs_dem_case_gas(gs_dem_case *c) { return c->gas; }
double gs_dem_case_duration(const gs_dem_case *c) { return c->duration; }

void gs_dem_case_set_observer(gs_dem_case *c, const gs_dem_observer *o) {
  c->observer = o ? *o : (gs_dem_observer){0};
}

void gs_dem_case_free(gs_dem_case *c) {
  if (!c) return;
  for (size_t k = 0; k < c->nfill; k++) free(c->fill[k].frac);
  for (size_t k = 0; k < c->nfeed; k++) free(c->feed[k].frac);
  free(c->fill);
  free(c->feed);
  free(c->outlets);
  free(c->cmp_edges);
  gs_dem_wet_free(c);
  gs_dem_free(c->dem);
  gs_cfg_free(c->cfg);
  free(c);
}

int gs_dem_case_vec3(gs_cfg_node *map, const char *key, int required, const double *def, double out[3],
                     gs_error *err) {
  return vec3(map, key, required, def, out, err);
}

int gs_dem_case_unit_vec(gs_cfg_node *map, const char *key, double out[3], gs_error *err) {
  return unit_vec(map, key, out, err);
}
