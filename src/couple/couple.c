/* `gransim couple`: a coupled PBM-DEM case with `mode: one_way` (see
 * include/gransim/couple.h).  Stages: read the coupling section and the PBM
 * grid, derive the DEM classes from the grid, write and run the DEM case into
 * DIR/dem.partial (renamed to DIR/dem once its tables are complete and
 * steady, so a complete stage is recognisable after a kill), point the PBM's
 * `table` kernels and `dem_impact` selections at its tables in the cfg tree,
 * and run the PBM with gs_case_run into DIR. */
#define _XOPEN_SOURCE 700
#include <errno.h>
#include <ftw.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "couple/couple_internal.h"
#include "demdata/csv_meta.h"
#include "gransim/case.h"
#include "gransim/couple.h"
#include "gransim/dem.h"
#include "gransim/liggghts.h"
#include "gransim/output.h"
#include "gransim/run.h"

static int read_settings(gs_cfg_node *root, gs_couple_settings *s, gs_cfg_node **classes, gs_error *err) {
  gs_cfg_node *cp, *cls, *st, *im;
  static const char *const modes[] = {"one_way", "two_way", NULL}, *const outside[] = {"nearest", "error", NULL};
  int mode, rc;
  memset(s, 0, sizeof *s);
  if ((rc = gs_cfg_map_req(root, "coupling", &cp, err)) ||
      (rc = gs_cfg_enum_opt(cp, "mode", modes, -1, &mode, err)))
    return rc;
  if (mode < 0) return gs_cfg_missing(cp, "mode", "(one_way | two_way)", err);
  s->two_way = mode == 1;
  if ((rc = gs_couple_read_trigger(cp, s, err))) return rc;
  if ((rc = gs_cfg_map_req(cp, "classes", &cls, err)) ||
      (rc = gs_cfg_double_range(cls, "min_diameter", 1, 0, 0, 0, HUGE_VAL, 0, &s->dmin, err)) ||
      (rc = gs_cfg_double_range(cls, "max_diameter", 1, 0, s->dmin, 0, HUGE_VAL, 0, &s->dmax, err)) ||
      (rc = gs_cfg_long_range(cls, "count", 0, 0, 1, GS_COUPLE_MAX_CLASSES, &s->count, err)) ||
      (rc = gs_cfg_string_req(cls, "material", &s->material, err)) ||
      (rc = gs_cfg_enum_opt(cls, "outside", outside, 0, &s->outside_error, err)) ||
      (rc = gs_cfg_double_range(cls, "min_fraction", 0, 0.02, 0, 0, 0.5, 0, &s->min_fraction, err)) ||
      (rc = gs_cfg_check_unused(cls, err)))
    return rc;
  if ((rc = gs_cfg_map_req(cp, "steady", &st, err)) ||
      (rc = gs_cfg_long_range(st, "window", 0, 5, 2, 100000, &s->window, err)) ||
      (rc = gs_cfg_double_range(st, "tolerance", 0, 0.1, 0, 0, 1, 0, &s->tolerance, err)) ||
      (rc = gs_cfg_double_range(st, "sample_every", 1, 0, 0, 0, HUGE_VAL, 0, &s->sample_every, err)) ||
      (rc = gs_cfg_double_range(st, "max_time", 1, 0, 0, 0, HUGE_VAL, 0, &s->max_time, err)) ||
      (rc = gs_cfg_double_range(st, "collect", 0, (double)s->window * s->sample_every, 0, 1, HUGE_VAL, 0,
                                &s->collect, err)))
    return rc;
  /* a closed batch bowl's hold-up is constant: two-way cycles watch the bed's kinetic energy
   * (De et al. 2025: "agitated until kinetic energy is steady"); one-way runs as Sampat et al. 2018 */
  s->quantities = s->two_way ? GS_DEM_STEADY_KINETIC | GS_DEM_STEADY_COLLISIONS : GS_DEM_STEADY_DEFAULT;
  if ((gs_cfg_get(st, "quantities") &&
       (rc = gs_dem_steady_quantities_read(gs_cfg_get(st, "quantities"), &s->quantities, err))) ||
      (rc = gs_cfg_check_unused(st, err)))
    return rc;
  s->restitution = gs_cfg_get(cp, "restitution");
  s->e_now = NAN;
  s->geom_now = 1;
  gs_cfg_node *sc = gs_cfg_get(cp, "scaling");
  if (sc && !s->two_way)
    return gs_cfg_fail(sc, err, "scaling belongs to mode: two_way (the DEM is sized from the PBM population of each cycle)");
  if (sc && ((rc = gs_cfg_require_kind(sc, GS_CFG_MAP, err)) ||
             (rc = gs_cfg_long_range(sc, "particles", 1, 0, 1, 100000000, &s->scale_n, err)) ||
             (rc = gs_cfg_check_unused(sc, err))))
    return rc;
  if ((im = gs_cfg_get(cp, "impacts")) &&
      ((rc = gs_cfg_string_opt(im, "wall", NULL, &s->wall, err)) || (rc = gs_cfg_check_unused(im, err))))
    return rc;
  *classes = cls;
  return gs_cfg_check_unused(cp, err);
}

void gs_couple_free(couple *k) {
  gs_grid_free(&k->g);
  gs_cfg_free(k->cfg);
  gs_cfg_free(k->dem_cfg);
}

/* coupling.restitution: the restitution coefficient of each component (a
 * grid axis), whose volume-weighted mean over the population is the DEM
 * material's e in a two-way cycle. */
static int read_restitution(couple *k, gs_error *err) {
  gs_cfg_node *r = k->s.restitution;
  for (int a = 0; a < GS_MAX_DIM; a++) k->s.e_axis[a] = NAN;
  if (!r) return GS_OK;
  if (!k->s.two_way) return gs_cfg_fail(r, err, "restitution belongs to mode: two_way (the DEM of the population)");
  int rc = gs_cfg_require_kind(r, GS_CFG_MAP, err);
  if (!rc && !gs_cfg_size(r)) rc = gs_cfg_fail(r, err, "expected the restitution of at least one grid axis (component)");
  for (size_t i = 0; i < gs_cfg_size(r) && !rc; i++) {
    const char *key = gs_cfg_key_at(r, i);
    int a = 0;
    while (a < k->g.dim && strcmp(k->g.axis[a].name, key)) a++;
    if (a == k->g.dim) {
      char names[256] = "";
      for (int b = 0; b < k->g.dim; b++)
        snprintf(names + strlen(names), sizeof names - strlen(names), "%s%s", b ? ", " : "", k->g.axis[b].name);
      rc = gs_cfg_fail(gs_cfg_value_at(r, i), err, "'%s' is not an axis of the grid (expected one of: %s)", key, names);
    } else rc = gs_cfg_double_range(r, key, 1, 0, 0, 0, 1, 0, &k->s.e_axis[a], err);
  }
  return rc;
}

/* Load the case, its coupling section, the grid and the DEM section; derive the classes. */
int gs_couple_load(const char *path, couple *k, int progress, gs_error *err) {
  memset(k, 0, sizeof *k);
  if (!(k->cfg = gs_cfg_load_file(path, err))) return err->code;
  gs_cfg_node *root = gs_cfg_root(k->cfg), *cls = NULL, *section;
  if (!root) return gs_error_set(err, GS_EINPUT, "%s: empty case file", path);
  int rc = gs_cfg_require_kind(root, GS_CFG_MAP, err);
  if (!rc) rc = read_settings(root, &k->s, &cls, err);
  if (rc) return rc;
  gs_cfg_node *dem = gs_cfg_get(root, "dem");
  k->path = path;
  k->dem_line = gs_cfg_line(dem);
  if (!dem)
    return gs_cfg_missing(root, "dem", "(the DEM case: a `gransim dem` case inline, or its file name)", err);
  if (gs_cfg_scalar(dem)) { /* a file name, relative to the coupled case */
    const char *f = gs_cfg_scalar(dem);
    char p[4200];
    snprintf(p, sizeof p, "%s%s%s", f[0] == '/' ? "" : gs_cfg_dir(k->cfg), f[0] == '/' ? "" : "/", f);
    if (!(k->dem_cfg = gs_cfg_load_file(p, err))) return gs_error_prefix(err, "%s:%d: dem: ", path, gs_cfg_line(dem));
    k->dem = gs_cfg_root(k->dem_cfg);
    snprintf(k->dem_dir, sizeof k->dem_dir, "%s", gs_cfg_dir(k->dem_cfg));
  } else {
    k->dem = dem;
    snprintf(k->dem_dir, sizeof k->dem_dir, "%s", gs_cfg_dir(k->cfg));
  }
  if (k->dem_dir[0] != '/') { /* the DEM case is written elsewhere: make its paths absolute */
    char abs[PATH_MAX];
    if (realpath(k->dem_dir, abs)) snprintf(k->dem_dir, sizeof k->dem_dir, "%.4000s", abs);
  }
  if (k->s.wall) { /* a wall of the DEM case, known before the DEM runs */
    gs_cfg_node *walls = gs_cfg_kind_of(k->dem) == GS_CFG_MAP ? gs_cfg_get(k->dem, "walls") : NULL;
    int found = 0;
    for (size_t i = 0; i < gs_cfg_size(walls) && !found; i++) {
      const char *name = gs_cfg_scalar(gs_cfg_get(gs_cfg_item(walls, i), "name"));
      found = name && !strcmp(name, k->s.wall);
    }
    if (!found)
      return gs_cfg_fail(gs_cfg_get(gs_cfg_get(root, "coupling"), "impacts"), err,
                         "wall '%s' is not a wall of the DEM case", k->s.wall);
  }
  gs_grid g;
  int mask = 0;
  memset(&g, 0, sizeof g);
  rc = gs_case_read_grid_only(root, &g, &mask, &section, err);
  if (!rc) rc = gs_couple_classes_derive(&g, (unsigned)mask, &k->s, cls, &k->cl, err);
  size_t ncells = g.ncells;
  k->g = g; /* the two-way loop bins the population with it (gs_couple_free) */
  k->mask = (unsigned)mask;
  if (!rc) rc = read_restitution(k, err);
  if (!rc && k->s.scale_n && (size_t)k->s.scale_n < k->cl.n) /* every class needs a particle to be measured */
    rc = gs_cfg_fail(gs_cfg_get(gs_cfg_get(gs_cfg_get(root, "coupling"), "scaling"), "particles"), err,
                     "fewer than the %zu DEM classes derived from the grid: expected at least "
                     "one particle per class", k->cl.n);
  if (!rc && progress) {
    fprintf(stderr, "gransim couple: %zu DEM classes from the grid, diameters [%g, %g] m", k->cl.n, k->cl.edges[0],
            k->cl.edges[k->cl.n]);
    if (k->cl.outside)
      fprintf(stderr, "; %zu of %zu PBM cells lie outside them and take the nearest class "
              "(coupling.classes.outside: nearest)", k->cl.outside, ncells);
    fputc('\n', stderr);
  }
  return rc;
}

/* Point every `table` kernel and `dem_impact` selection at the DEM's tables. */
int gs_couple_point_at_tables(gs_cfg_node *root, const char *kernel, const char *impacts, gs_error *err) {
  gs_cfg_node *mechs = gs_cfg_get(root, "mechanisms");
  int found = 0, rc = GS_OK;
  for (size_t i = 0; i < gs_cfg_size(mechs) && !rc; i++) {
    gs_cfg_node *m = gs_cfg_item(mechs, i), *kn;
    const char *file = NULL;
    gs_cfg_node *t = gs_cfg_get(m, "kernel");
    if (t && gs_cfg_scalar(gs_cfg_get(t, "type")) && !strcmp(gs_cfg_scalar(gs_cfg_get(t, "type")), "table"))
      file = kernel;
    else if ((t = gs_cfg_get(m, "selection")) && gs_cfg_scalar(gs_cfg_get(t, "type")) &&
             !strcmp(gs_cfg_scalar(gs_cfg_get(t, "type")), "dem_impact"))
      file = impacts;
    if (!file) continue;
    static const char *const taken[] = {"file", "measure", "axes", NULL};
    for (const char *const *q = taken; *q && !rc; q++)
      if ((kn = gs_cfg_get(t, *q)))
        rc = gs_cfg_fail(kn, err, "set by the coupling in a coupled case (the DEM's table, classes measured "
                         "in diameter of grid.size_axes); remove it");
    if (!rc) rc = gs_cfg_set_scalar(t, "file", file, err);
    if (!rc) rc = gs_cfg_set_scalar(t, "measure", "diameter", err);
    found++;
  }
  if (!rc && !found)
    rc = gs_cfg_fail(root, err, "a coupled case needs a `table` aggregation kernel or a `dem_impact` breakage "
                     "selection to receive the DEM's tables; the mechanisms have neither");
  return rc;
}

/* grid.size_axes also measures the PBM's classes: the kernels may not choose other axes */
static int pbm_case(couple *k, const char *kernel, const char *impacts, gs_case *c, gs_error *err) {
  int rc = gs_couple_point_at_tables(gs_cfg_root(k->cfg), kernel, impacts, err);
  memset(c, 0, sizeof *c);
  gs_cfg *cfg = k->cfg;
  k->cfg = NULL; /* taken over by the case, also on failure */
  if (rc) {
    gs_cfg_free(cfg);
    return rc;
  }
  return gs_case_from_cfg(cfg, c, err);
}

static int write_dem_case(couple *k, const char *path, const double *fractions, gs_error *err) {
  FILE *fp = fopen(path, "w");
  if (!fp) return gs_error_set(err, GS_EIO, "%s: cannot write: %s", path, strerror(errno));
  int rc = gs_couple_write_dem_case(fp, k->dem, k->dem_dir, &k->s, &k->cl, fractions, err);
  if (fclose(fp) && !rc) rc = gs_error_set(err, GS_EIO, "%s: cannot write", path);
  return rc;
}

/* The node at a key path ("fill[0].fractions", ending at ' ', ':' or '='), or NULL. */
static gs_cfg_node *find_path(gs_cfg_node *n, const char *p) {
  while (n && *p && !strchr(" :=", *p)) {
    size_t len = strcspn(p, ".[ :=");
    char key[128];
    if (len == 0 || len >= sizeof key) return NULL;
    memcpy(key, p, len);
    key[len] = 0;
    n = gs_cfg_kind_of(n) == GS_CFG_MAP ? gs_cfg_get(n, key) : NULL;
    p += len;
    while (n && *p == '[') {
      char *end;
      long i = strtol(p + 1, &end, 10);
      if (*end != ']') return NULL;
      n = gs_cfg_item(n, (size_t)i);
      p = end + 1;
    }
    if (*p == '.') p++;
  }
  return n;
}

/* The DEM reader names the written file; name the coupled case's dem section
 * instead (the key path stays, e.g. fill[0].fractions). */
static int dem_error(const couple *k, const char *written, gs_error *err) {
  size_t n = strlen(written);
  char rest[sizeof err->msg];
  const char *m = err->msg;
  if (!strncmp(m, written, n) && m[n] == ':') {
    m += n + 1;
    m += strspn(m, "0123456789");
    if (*m == ':') m++;
    m += strspn(m, " ");
  }
  snprintf(rest, sizeof rest, "%s", m);
  /* the line of the key the message names (a path such as fill[0].fractions) */
  const gs_cfg_node *at = find_path(k->dem, rest);
  return gs_error_set(err, GS_EINPUT, "%s:%d: dem: %s", at ? gs_cfg_file(at) : k->path,
                      at ? gs_cfg_line(at) : k->dem_line, rest);
}

/* A DEM stage with the LIGGGHTS engine: what its deck cannot express is
 * refused (src/liggghts), at the key's place in the coupled case. */
static int engine_check(const couple *k, const gs_dem_case *dc, const char *written, gs_error *err) {
  if (gs_dem_case_engine(dc) != 1) return GS_OK;
  return gs_lig_check(dc, err) ? dem_error(k, written, err) : GS_OK;
}

/* --ranks and --launcher start LIGGGHTS: on the embedded engine they could
 * not act, so they are refused (as `gransim dem` refuses --dry-run there),
 * at the line of dem.engine, or of the DEM case's `dem` map without it. */
static int engine_options(const couple *k, const gs_dem_case *dc, const gs_couple_options *opt, gs_error *err) {
  if (!opt || (opt->ranks <= 0 && !opt->launcher) || gs_dem_case_engine(dc) == 1) return GS_OK;
  gs_cfg_node *map = gs_cfg_kind_of(k->dem) == GS_CFG_MAP ? gs_cfg_get(k->dem, "dem") : NULL;
  gs_cfg_node *eng = gs_cfg_kind_of(map) == GS_CFG_MAP ? gs_cfg_get(map, "engine") : NULL;
  const gs_cfg_node *at = eng ? eng : map;
  char value[160] = "not given, so 'embedded'";
  if (eng && gs_cfg_scalar(eng)) snprintf(value, sizeof value, "'%.120s'", gs_cfg_scalar(eng));
  const int both = opt->ranks > 0 && opt->launcher;
  return gs_error_set(err, GS_EINPUT,
                      "%s:%d: dem: dem.engine is %s: %s%s%s %s for DEM stages on LIGGGHTS (its MPI ranks and how they "
                      "start) and cannot act on the embedded engine, which runs on --threads; set dem.engine: liggghts "
                      "or leave %s out",
                      at ? gs_cfg_file(at) : k->path, at ? gs_cfg_line(at) : k->dem_line, value,
                      opt->ranks > 0 ? "--ranks" : "", both ? " and " : "", opt->launcher ? "--launcher" : "",
                      both ? "are" : "is", both ? "them" : "it");
}

/* Placeholder tables of the derived classes, for `check` (no DEM run). */
int gs_couple_write_placeholders(const couple *k, const char *kernel, const char *impacts, gs_error *err) {
  FILE *a = fopen(kernel, "w"), *b = fopen(impacts, "w");
  for (size_t r = 0; a && b && r <= 3 * k->cl.n + 1; r++) {
    fputs(r == 0 ? "edges" : "", a);
    fputs(r == 0 ? "edges" : "", b);
    for (size_t j = 0; j < k->cl.n + (r == 0); j++) {
      if (r == 0) { /* outer edges wide: the outside cells are logged once, by couple_load */
        double e = j == 0 ? 0 : j == k->cl.n ? k->cl.edges[j] * 1e6 : k->cl.edges[j];
        fprintf(a, ", %.17g", e);
        fprintf(b, ", %.17g", e);
        continue;
      }
      if (r <= k->cl.n) fprintf(a, "%s1", j ? ", " : "");
      if (r <= 3) fprintf(b, "%s%s", j ? ", " : "", r == 2 ? "0" : "1");
    }
    if (r <= k->cl.n) fputc('\n', a);
    if (r <= 3) fputc('\n', b);
  }
  int rc = !a || !b ? gs_error_set(err, GS_EIO, "cannot write placeholder tables: %s", strerror(errno)) : GS_OK;
  if (a) fclose(a);
  if (b) fclose(b);
  return rc;
}

int gs_couple_check(const char *path, char *desc, size_t n, gs_error *err) {
  return gs_couple_check_options(path, NULL, desc, n, err);
}

int gs_couple_check_options(const char *path, const gs_couple_options *opt, char *desc, size_t n, gs_error *err) {
  couple k;
  int rc = gs_couple_load(path, &k, 0, err);
  char tmp[] = "/tmp/gransim-couple-XXXXXX", dcase[64], kt[64], it[64];
  int have_tmp = !rc && mkdtemp(tmp);
  if (!rc && !have_tmp) rc = gs_error_set(err, GS_EIO, "cannot create a temporary folder: %s", strerror(errno));
  snprintf(dcase, sizeof dcase, "%s/dem.yaml", tmp);
  snprintf(kt, sizeof kt, "%s/collision_kernel.csv", tmp);
  snprintf(it, sizeof it, "%s/impact_table.csv", tmp);
  char dd[512] = "";
  /* two-way: the fill's fractions come from the population; any will do here */
  double equal[GS_COUPLE_MAX_CLASSES];
  for (size_t c = 0; c < GS_COUPLE_MAX_CLASSES; c++) equal[c] = 1;
  if (!rc) rc = write_dem_case(&k, dcase, k.s.two_way ? equal : NULL, err);
  if (!rc) {
    gs_dem_case *dc = gs_dem_case_load(dcase, err);
    if (!dc) rc = dem_error(&k, dcase, err);
    else if (!(rc = engine_check(&k, dc, dcase, err)) && !(rc = engine_options(&k, dc, opt, err)))
      gs_dem_case_describe(dc, dd, sizeof dd);
    gs_dem_case_free(dc);
  }
  if (!rc) rc = gs_couple_write_placeholders(&k, kt, it, err);
  gs_case c;
  memset(&c, 0, sizeof c);
  size_t nclass = k.cl.n, outside = k.cl.outside;
  const int two = k.s.two_way;
  double lo = k.cl.edges[0], hi = k.cl.edges[k.cl.n];
  if (!rc) rc = pbm_case(&k, kt, it, &c, err);
  if (!rc)
    rc = gs_couple_check_trigger(gs_cfg_get(gs_cfg_root(c.cfg), "coupling"), &k.s, c.t0, c.times[c.ntimes - 1], err);
  if (!rc)
    snprintf(desc, n, "%s: %zu DEM classes from the grid, diameters [%.4g, %.4g] m (%zu PBM cells outside: "
             "nearest class); PBM %zu cells x %zu compartments, %zu mechanisms; DEM: %s",
             two ? "two_way" : "one_way", nclass, lo, hi, outside, c.model.grid.ncells, c.model.grid.ncomp, c.model.nmech, dd);
  gs_case_free(&c);
  gs_couple_free(&k);
  if (have_tmp) {
    unlink(dcase);
    unlink(kt);
    unlink(it);
    rmdir(tmp);
  }
  return rc;
}

/* classes.csv: the derived classes and how many PBM cells each holds, so that
 * a user sees what the DEM sampled and what was extrapolated. */
int gs_couple_write_classes(const couple *k, const char *dir, gs_error *err) {
  gs_csv_out t;
  FILE *fp = gs_csv_open_in(&t, dir, "classes.csv", err);
  if (!fp) return err->code;
  fprintf(fp, "# DEM classes derived from the PBM grid (volume-equivalent diameters of grid.size_axes, "
          "window [%g, %g] m); %zu PBM cells outside them take the nearest class (coupling.classes.outside: %s)\n"
          "class,name,d_lo,d_hi,pbm_cells\n", k->s.dmin, k->s.dmax, k->cl.outside,
          k->s.outside_error ? "error" : "nearest");
  for (size_t c = 0; c < k->cl.n; c++)
    fprintf(fp, "%zu,c%zu,%.9g,%.9g,%zu\n", c + 1, c + 1, k->cl.edges[c], k->cl.edges[c + 1], k->cl.cells_in[c]);
  static const char *const units[] = {"class", "1", "d_lo", "m", "d_hi", "m", "pbm_cells", "1", NULL};
  return gs_csv_close(&t, "gransim couple", units, err);
}

int gs_couple_rm_entry(const char *p, const struct stat *sb, int flag, struct FTW *f) {
  (void)sb;
  (void)flag;
  (void)f;
  return remove(p);
}

/* The DEM stage's observer: once the detector has fired (the statistics
 * window opens then: statistics.start: steady), collect for steady.collect
 * seconds and stop, rather than running on to max_time. */
typedef struct {
  double collect, t_fired, t_stop;
  long steps;       /* at the last sample */
  size_t particles; /* at the last sample */
} stage_stop;

static int stop_when_collected(const gs_dem_sample *smp, void *user, int *open_window, int *stop, gs_error *err) {
  (void)open_window;
  (void)err;
  stage_stop *o = user;
  o->steps = smp->step;
  o->particles = smp->particles;
  if (smp->steady && o->t_fired < 0) o->t_fired = smp->t;
  /* half a sample of slack: the samples' times carry round-off */
  if (o->t_fired >= 0 && smp->t >= o->t_fired + o->collect * (1 - 1e-9)) {
    *stop = 1;
    o->t_stop = smp->t;
  }
  return GS_OK;
}

double gs_couple_now(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

int gs_couple_exists(const char *dir, const char *name) {
  char p[4400];
  struct stat sb;
  snprintf(p, sizeof p, "%s/%s", dir, name);
  return stat(p, &sb) == 0;
}

/* A DEM stage into the folder part (made): its case (fractions: the fill's
 * class fractions by number, NULL for the case's own), classes.csv, the run
 * stopped steady.collect after the detector fired, the case rewritten as run
 * and steady.csv.  rec: what the cycle table records. */
int gs_couple_dem_stage(couple *k, const char *part, const double *fractions, const gs_couple_options *opt,
                        gs_couple_dem_record *rec, gs_error *err) {
  const int progress = opt->progress;
  char dcase[4400];
  int rc = GS_OK;
  memset(rec, 0, sizeof *rec);
  snprintf(dcase, sizeof dcase, "%s/case.yaml", part);
  rc = write_dem_case(k, dcase, fractions, err);
  if (!rc) rc = gs_couple_write_classes(k, part, err);
  gs_dem_case *dc = rc ? NULL : gs_dem_case_load(dcase, err);
  if (!rc && !dc) rc = dem_error(k, dcase, err);
  if (!rc) rc = engine_check(k, dc, dcase, err);
  stage_stop ss = {.collect = k->s.collect, .t_fired = -1, .t_stop = -1};
  const double w0 = gs_couple_now();
  if (!rc) {
    if (progress)
      fprintf(stderr, "gransim couple: DEM stage (%g s at most; %g s of statistics once steady) in %s\n",
              k->s.max_time, k->s.collect, part);
    gs_dem_observer ob = {.sample = stop_when_collected, .user = &ss};
    gs_dem_case_set_observer(dc, &ob);
    const gs_lig_options lig = {.progress = progress, .ranks = opt->ranks, .launcher = opt->launcher};
    rc = gs_dem_case_engine(dc) == 1 ? gs_lig_case_run(dc, part, &lig, err) : gs_dem_case_run(dc, part, progress, err);
    rec->steps = ss.steps;
    rec->e = k->s.e_now;
    rec->particles = ss.particles;
  }
  gs_dem_case_free(dc);
  rec->wall = gs_couple_now() - w0;
  rec->t_dem = ss.t_stop >= 0 ? ss.t_stop : k->s.max_time;
  /* the case as run: its duration ends where the observer stopped it, so that
   * `gransim dem dem/case.yaml` gives the same tables */
  if (!rc && ss.t_stop >= 0) {
    gs_couple_settings as_run = k->s;
    as_run.max_time = ss.t_stop;
    const gs_couple_settings keep = k->s;
    k->s = as_run;
    rc = write_dem_case(k, dcase, fractions, err);
    k->s = keep;
  }
  if (!rc) rc = gs_couple_steady_report(part, &k->s, &rec->t_steady, err);
  return rc;
}

int gs_couple_run(const char *path, const gs_couple_options *opt, gs_error *err) {
  /* the whole case first, so that a PBM error does not wait for the DEM stage */
  char desc[1024];
  couple k;
  memset(&k, 0, sizeof k);
  int rc = gs_couple_check_options(path, opt, desc, sizeof desc, err);
  if (rc) return rc;
  rc = gs_couple_load(path, &k, opt->progress, err);
  if (!rc && k.s.two_way) rc = gs_couple_two_way(&k, path, opt, err);
  if (rc || k.s.two_way) {
    gs_couple_free(&k);
    return rc;
  }
  const char *out = opt->out_dir;
  char dem[4200], part[4200], kt[4400], it[4400];
  snprintf(dem, sizeof dem, "%s/dem", out);
  snprintf(part, sizeof part, "%s/dem.partial", out);
  if (!rc) rc = gs_output_mkdir_p(out, err);
  char impname[300] = "impact_table.csv";
  if (k.s.wall) snprintf(impname, sizeof impname, "impact_table_%s.csv", k.s.wall);
  int have = !rc && opt->resume && gs_couple_exists(dem, "collision_kernel.csv") && gs_couple_exists(dem, impname) && gs_couple_exists(dem, "steady.csv");
  if (!rc && have && opt->progress) fprintf(stderr, "gransim couple: --resume: DEM stage complete in %s, skipped\n", dem);
  if (!rc && !have) {
    nftw(part, gs_couple_rm_entry, 16, FTW_DEPTH | FTW_PHYS);
    nftw(dem, gs_couple_rm_entry, 16, FTW_DEPTH | FTW_PHYS);
    if (mkdir(part, 0777)) rc = gs_error_set(err, GS_EIO, "%s: cannot create: %s", part, strerror(errno));
    gs_couple_dem_record rec;
    if (!rc) rc = gs_couple_dem_stage(&k, part, NULL, opt, &rec, err);
    if (!rc && opt->progress) fprintf(stderr, "gransim couple: DEM steady at t = %g s; tables in %s\n", rec.t_steady, dem);
    /* the stage is complete only once renamed: a kill before leaves dem.partial */
    if (!rc && rename(part, dem)) rc = gs_error_set(err, GS_EIO, "%s: cannot rename to %s: %s", part, dem, strerror(errno));
  }
  /* the tables must have the classes the grid gives now (the case may have changed since) */
  /* absolute: the PBM resolves relative table names against the case file's folder */
  char cwd[2048] = "";
  if (out[0] != '/' && !getcwd(cwd, sizeof cwd)) cwd[0] = 0;
  snprintf(kt, sizeof kt, "%s%s%s/collision_kernel.csv", cwd, cwd[0] ? "/" : "", dem);
  snprintf(it, sizeof it, "%s%s%s/%s", cwd, cwd[0] ? "/" : "", dem, impname);
  if (!rc) {
    FILE *fp = fopen(kt, "r");
    char line[8192] = "";
    size_t ne = 0;
    while (fp && fgets(line, sizeof line, fp))
      if (!strncmp(line, "edges", 5)) {
        for (char *q = line; *q; q++) ne += *q == ',';
        break;
      }
    if (fp) fclose(fp);
    if (ne != k.cl.n + 1)
      rc = gs_error_set(err, GS_EINPUT, "%s: %zu classes, but the grid and coupling.classes give %zu: the case changed "
                        "since the DEM stage; rerun without --resume", kt, ne ? ne - 1 : 0, k.cl.n);
  }
  if (!rc && !gs_couple_exists(dem, impname))
    rc = gs_error_set(err, GS_EINPUT, "%s: no %s (coupling.impacts.wall names no wall of the DEM case?)", dem, impname);
  gs_case c;
  memset(&c, 0, sizeof c);
  /* the PBM resumes from its journal (a kill even while publishing leaves it:
   * docs/design-notes.md); a finished one on tables that were
   * not rerun is complete; otherwise (new tables) it starts again */
  int pbm_resume = opt->resume && gs_couple_exists(out, ".result.journal");
  if (!rc && have && opt->resume && !pbm_resume && gs_couple_exists(out, "result.h5")) {
    if (opt->progress) fprintf(stderr, "gransim couple: --resume: PBM stage complete in %s, nothing to do\n", out);
    gs_couple_free(&k);
    return GS_OK;
  }
  if (!rc) rc = pbm_case(&k, kt, it, &c, err);
  if (!rc) {
    if (pbm_resume && !have) pbm_resume = 0; /* partial files of the old tables' run */
    gs_run_options ro = {.out_dir = out, .resume = pbm_resume, .progress = opt->progress ? -1 : 0};
    gs_run_report rep;
    rc = gs_case_run(&c, &ro, NULL, &rep, err);
    if (!rc && opt->progress)
      fprintf(stderr, "gransim couple: PBM to t = %g in %.2f s; results in %s\n", rep.t_end, rep.wall_seconds, out);
  }
  gs_case_free(&c);
  gs_couple_free(&k);
  return rc;
}
