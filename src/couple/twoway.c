/* The bi-directional loop, coupling.mode: two_way (De et al. 2025; docs/models.md,
 * "Two-way coupling").  Cycle N: a DEM stage built from the PBM population at
 * its start time (class fractions by number, every class at least
 * classes.min_fraction of the particles so its frequencies are measured), into
 * DIR/cycle-N.partial, renamed DIR/cycle-N once its tables are complete; then
 * the PBM stretch with those tables from the cycle's start time until the
 * trigger fires at an output time.  The stretch stops holding its result
 * files (gs_run_options.hold_on_stop) and the next stretch resumes them, so
 * DIR/result.h5 is one run over the whole process time.  A killed run resumes
 * from the last cycle it started: its start state is in cycle-N/start.bin, a
 * DEM stage is rerun whole (fixed seed: the same tables), a stretch resumes
 * from the journal. */
#define _XOPEN_SOURCE 700
#include <errno.h>
#include <ftw.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "couple/couple_internal.h"
#include "demdata/csv_meta.h"
#include "gransim/case.h"
#include "gransim/couple.h"
#include "gransim/output.h"
#include "gransim/run.h"
#include "kernel/class_table.h"

enum { TRIG_START, TRIG_VOLUME, TRIG_INTERVAL, TRIG_END };
static const char *const trig_names[] = {"start", "mean_volume_change", "interval", "end"};

int gs_couple_read_trigger(gs_cfg_node *cp, gs_couple_settings *s, gs_error *err) {
  gs_cfg_node *tr = gs_cfg_get(cp, "trigger");
  s->trig_dv = s->two_way && !tr ? 0.2 : 0;
  s->trig_interval = 0;
  if (!tr) return GS_OK;
  if (!s->two_way) return gs_cfg_fail(tr, err, "a trigger belongs to mode: two_way (one_way runs the DEM once)");
  int rc = gs_cfg_require_kind(tr, GS_CFG_MAP, err);
  /* a misspelt key is named as such (did you mean), before the missing one */
  if (!rc && !gs_cfg_get(tr, "mean_volume_change") && !gs_cfg_get(tr, "interval") &&
      !(rc = gs_cfg_check_unused(tr, err)))
    rc = gs_cfg_missing(tr, "mean_volume_change", "(relative change of the mean granule volume; or interval [s]; or both)",
                        err);
  if (!rc && gs_cfg_get(tr, "mean_volume_change"))
    rc = gs_cfg_double_range(tr, "mean_volume_change", 1, 0, 0, 1, HUGE_VAL, 0, &s->trig_dv, err);
  if (!rc && gs_cfg_get(tr, "interval"))
    rc = gs_cfg_double_range(tr, "interval", 1, 0, 0, 1, HUGE_VAL, 0, &s->trig_interval, err);
  return rc ? rc : gs_cfg_check_unused(tr, err);
}

/* A trigger of interval alone that cannot fire within the process time
 * would make the run one DEM stage: refused before any DEM runs. */
int gs_couple_check_trigger(gs_cfg_node *cp, const gs_couple_settings *s, double t0, double t1, gs_error *err) {
  if (!s->two_way || s->trig_dv > 0 || !(s->trig_interval >= (t1 - t0) * (1 - 1e-9))) return GS_OK;
  return gs_cfg_fail(gs_cfg_get(gs_cfg_get(cp, "trigger"), "interval"), err,
                     "the trigger can never fire: the interval %g s is not shorter than the process time "
                     "(%g s from output.start %g s), so one DEM stage would drive the whole run; shorten it, add "
                     "mean_volume_change, or use mode: one_way", s->trig_interval, t1 - t0, t0);
}

/* A run whose trigger never fired was one-way coupled: an error after its
 * results are complete (change: the mean granule volume's relative change
 * over the whole run, NAN when not known, as on --resume). */
static int never_fired(const couple *k, const char *out, double t0, double t1, double change, gs_error *err) {
  char interval[128] = "", value[160] = "";
  if (k->s.trig_interval > 0)
    snprintf(interval, sizeof interval, " and interval %g s", k->s.trig_interval);
  if (!isnan(change)) snprintf(value, sizeof value, " changed by %.4g", change);
  return gs_error_set(err, GS_ENUMERIC,
                      "%s: coupling.trigger never fired: from t = %g s to the end, t = %g s, the mean granule volume%s "
                      "(relative; trigger.mean_volume_change %g%s), so one DEM stage drove the whole process, which "
                      "is one-way coupling; lower mean_volume_change, add trigger.interval, or use mode: one_way "
                      "(the results of that one cycle are complete in %s)",
                      k->path, t0, t1, isnan(change) ? " did not change enough" : value, k->s.trig_dv, interval, out);
}

/* ---- the population ------------------------------------------------------- */

static double cell_volume(const couple *k, size_t c) {
  double v = 0;
  for (int a = 0; a < k->g.dim; a++)
    if (k->mask & (1u << a)) v += k->g.x[c * (size_t)k->g.dim + a];
  return v;
}

/* Mean granule volume (the size axes) over every compartment. */
static double mean_volume(const couple *k, const double *Y) {
  double n = 0, v = 0;
  for (size_t p = 0; p < k->g.ncomp; p++)
    for (size_t c = 0; c < k->g.ncells; c++) {
      const double N = Y[p * k->g.ncells + c];
      n += N;
      v += N * cell_volume(k, c);
    }
  return n > 0 ? v / n : 0;
}

/* Class fractions by number of the population (cells outside the classes
 * counted in the nearest, as the tables extend to them), each at least
 * min_fraction, summing to 1. */
static int class_fractions(const couple *k, const double *Y, double t, double *fr, gs_error *err) {
  const size_t n = k->cl.n;
  double total = 0;
  for (size_t j = 0; j < n; j++) fr[j] = 0;
  for (size_t c = 0; c < k->g.ncells; c++) {
    const double v = cell_volume(k, c);
    if (!(v > 0)) continue;
    const double d = gs_diameter(v);
    size_t j = 0;
    while (j + 1 < n && d >= k->cl.edges[j + 1]) j++;
    for (size_t p = 0; p < k->g.ncomp; p++) {
      const double N = Y[p * k->g.ncells + c];
      if (N > 0) {
        fr[j] += N;
        total += N;
      }
    }
  }
  if (!(total > 0) || !isfinite(total))
    return gs_error_set(err, GS_ENUMERIC, "the PBM population at t = %g s holds no granules (total number %g): no DEM "
                        "particles to sample for the next cycle", t, total);
  double s = 0;
  for (size_t j = 0; j < n; j++) s += fr[j] = fmax(fr[j] / total, k->s.min_fraction);
  for (size_t j = 0; j < n; j++) fr[j] /= s;
  return GS_OK;
}

/* Total number of granules of the population (every compartment). */
static double total_number(const couple *k, const double *Y) {
  double n = 0;
  for (size_t i = 0; i < k->g.ncomp * k->g.ncells; i++) n += Y[i];
  return n;
}

/* System scaling (coupling.scaling; docs/models.md, "System scaling"): the
 * DEM held scale_n particles of the real sizes at the real fill level, in
 * the case's geometry scaled by geometry_factor, so it stands for a volume
 * l^3 times smaller than the real one, l^3 = N_PBM / N.  A per-pair
 * frequency goes as 1/volume, so the real system's C_ij is the DEM's times
 * l^-3.  The DEM's own table stays as collision_kernel_dem.csv. */
static int scale_kernel(const char *dir, size_t nc, double l, gs_error *err) {
  char p[4600], raw[4600], line[16384];
  snprintf(p, sizeof p, "%s/collision_kernel.csv", dir);
  snprintf(raw, sizeof raw, "%s/collision_kernel_dem.csv", dir);
  if (rename(p, raw)) return gs_error_set(err, GS_EIO, "%s: cannot rename to %s: %s", p, raw, strerror(errno));
  gs_class_table tab = {0};
  int rc = gs_class_table_read(raw, 0, &tab, err);
  if (!rc && tab.n != nc)
    rc = gs_error_set(err, GS_EINPUT, "%s: a table of %zu classes, expected %zu", raw, tab.n, nc);
  FILE *out = rc ? NULL : fopen(p, "w");
  if (!rc && !out) rc = gs_error_set(err, GS_EIO, "%s: cannot write: %s", p, strerror(errno));
  if (out) {
    const double f = 1 / (l * l * l);
    fputs("edges", out);
    for (size_t j = 0; j <= nc; j++) fprintf(out, ", %.17g", tab.edges[j]);
    for (size_t i = 0; i < nc * nc; i++) fprintf(out, "%s%.9g", i % nc ? ", " : "\n", tab.c[i] * f);
    fputc('\n', out);
    if (fclose(out)) rc = gs_error_set(err, GS_EIO, "%s: cannot write: %s", p, strerror(errno));
  }
  gs_class_table_free(&tab);
  if (rc) return gs_error_prefix(err, "system scaling: ");
  int ok = 1;
  /* the DEM's table keeps its units sidecar too */
  snprintf(p, sizeof p, "%s/collision_kernel.json", dir);
  snprintf(raw, sizeof raw, "%s/collision_kernel_dem.json", dir);
  FILE *in = fopen(p, "r");
  out = in ? fopen(raw, "w") : NULL;
  size_t got;
  while (out && (got = fread(line, 1, sizeof line, in)) > 0) ok = fwrite(line, 1, got, out) == got && ok;
  if (in) fclose(in);
  if (out && fclose(out)) ok = 0;
  if (!in || !out || !ok) return gs_error_set(err, GS_EIO, "%s: cannot copy to %s", p, raw);
  return GS_OK;
}

/* The DEM geometry's linear scale for a population of n granules: the
 * case's geometry holds the first cycle's population (n_first granules) at
 * the real fill level in N particles; the real equipment is then l_1 times
 * the case's geometry, and a population of n granules needs l_1 / l_i =
 * (n_first / n)^(1/3) times it for N particles at the same fill level. */
static double geometry_factor(double n_first, double n) { return cbrt(n_first / n); }

/* The volume-weighted mean restitution of the components given in
 * coupling.restitution over the population (NAN: none given, or no volume). */
static double restitution(const couple *k, const double *Y) {
  double ev = 0, v = 0;
  for (int a = 0; a < k->g.dim; a++) {
    if (isnan(k->s.e_axis[a])) continue;
    double va = 0;
    for (size_t p = 0; p < k->g.ncomp; p++)
      for (size_t c = 0; c < k->g.ncells; c++) va += Y[p * k->g.ncells + c] * k->g.x[c * (size_t)k->g.dim + a];
    ev += k->s.e_axis[a] * va;
    v += va;
  }
  return v > 0 ? ev / v : NAN;
}

/* ---- the cycle files ------------------------------------------------------ */

/* cycle-N/start.bin: where the cycle starts. */
typedef struct {
  double t, v0;  /* process time, mean granule volume */
  int trigger;   /* what ended the previous stretch (TRIG_START for the first) */
  double change; /* relative change of the mean volume over the previous stretch */
  size_t n;      /* state values */
} start_head;

#define START_MAGIC 0x67737477u /* "gstw" */

static void cycle_dir(char *p, size_t np, const char *out, long N, int partial) {
  snprintf(p, np, "%s/cycle-%ld%s", out, N, partial ? ".partial" : "");
}

static int write_start(const char *dir, const start_head *h, const double *Y, gs_error *err) {
  char p[4600], tmp[4600];
  snprintf(p, sizeof p, "%s/start.bin", dir);
  snprintf(tmp, sizeof tmp, "%s/.start.bin.new", dir);
  FILE *fp = fopen(tmp, "wb");
  const unsigned magic = START_MAGIC;
  int ok = fp && fwrite(&magic, sizeof magic, 1, fp) == 1 && fwrite(h, sizeof *h, 1, fp) == 1 &&
           fwrite(Y, sizeof *Y, h->n, fp) == h->n;
  if (fp && fclose(fp)) ok = 0;
  if (!ok || rename(tmp, p)) return gs_error_set(err, GS_EIO, "%s: cannot write: %s", p, strerror(errno));
  return GS_OK;
}

/* 1 read, 0 absent or damaged (a kill while writing leaves no start.bin: the
 * temporary name is renamed only when whole). */
static int read_start(const char *dir, start_head *h, double *Y, size_t n) {
  char p[4600];
  snprintf(p, sizeof p, "%s/start.bin", dir);
  FILE *fp = fopen(p, "rb");
  unsigned magic = 0;
  int ok = fp && fread(&magic, sizeof magic, 1, fp) == 1 && magic == START_MAGIC && fread(h, sizeof *h, 1, fp) == 1 &&
           h->n == n && (!Y || fread(Y, sizeof *Y, n, fp) == n);
  if (fp) fclose(fp);
  return ok;
}

static int write_record(const char *dir, const gs_couple_dem_record *r, gs_error *err) {
  char p[4600];
  snprintf(p, sizeof p, "%s/record.bin", dir);
  FILE *fp = fopen(p, "wb");
  int ok = fp && fwrite(r, sizeof *r, 1, fp) == 1;
  if (fp && fclose(fp)) ok = 0;
  return ok ? GS_OK : gs_error_set(err, GS_EIO, "%s: cannot write: %s", p, strerror(errno));
}

static int read_record(const char *dir, gs_couple_dem_record *r) {
  char p[4600];
  snprintf(p, sizeof p, "%s/record.bin", dir);
  FILE *fp = fopen(p, "rb");
  int ok = fp && fread(r, sizeof *r, 1, fp) == 1;
  if (fp) fclose(fp);
  return ok;
}

/* A cycle's row of the cycle table. */
typedef struct {
  start_head h;
  gs_couple_dem_record r;
  double t_end;
  int by;
} cycle_row;

/* The rows of cycles 1..ncycles whose DEM stage is complete; the last ends at t_last. */
static size_t collect_cycles(const char *out, long ncycles, size_t n, double t_last, int last_trigger, cycle_row *rows) {
  char dir[4400];
  size_t m = 0;
  for (long N = 1; N <= ncycles; N++) {
    cycle_row *w = &rows[m];
    start_head next;
    cycle_dir(dir, sizeof dir, out, N, 0);
    if (!read_start(dir, &w->h, NULL, n) || !read_record(dir, &w->r)) break;
    cycle_dir(dir, sizeof dir, out, N + 1, 0);
    int have_next = read_start(dir, &next, NULL, n);
    if (!have_next) {
      cycle_dir(dir, sizeof dir, out, N + 1, 1);
      have_next = read_start(dir, &next, NULL, n);
    }
    w->t_end = have_next ? next.t : t_last;
    w->by = have_next ? next.trigger : last_trigger;
    m++;
  }
  return m;
}

/* DIR/cycles.csv. */
static int write_cycles(const char *out, const cycle_row *rows, size_t m, gs_error *err) {
  gs_csv_out t;
  FILE *fp = gs_csv_open_in(&t, out, "cycles.csv", err);
  if (!fp) return err->code;
  fprintf(fp, "cycle,t_start [s],t_end [s],trigger,volume_change [1],ended_by,particles [1],l_i [1],dem_steps [1],"
              "dem_time [s],dem_wall [s],t_steady [s],restitution [1],geometry_scale [1]\n");
  fprintf(fp, "# the coupling cycles of gransim couple (mode: two_way): cycle N's DEM ran on the population at "
              "t_start (trigger: what started it, volume_change: the relative change of the mean granule volume "
              "since the previous cycle's start), its collision frequencies drove the PBM to t_end (ended_by)\n");
  for (size_t i = 0; i < m; i++) {
    const cycle_row *w = &rows[i];
    fprintf(fp, "%zu,%.9g,%.9g,%s,%.9g,%s,%zu,%.9g,%ld,%.9g,%.6g,%.9g,", i + 1, w->h.t, w->t_end,
            trig_names[w->h.trigger], w->h.change, trig_names[w->by], w->r.particles, w->r.l, w->r.steps, w->r.t_dem,
            w->r.wall, w->r.t_steady);
    if (!isnan(w->r.e)) fprintf(fp, "%.9g", w->r.e); /* empty: the case's own */
    fprintf(fp, ",%.9g\n", w->r.geom);
  }
  static const char *const units[] = {"cycle", "1", "t_start", "s", "t_end", "s", "volume_change", "1",
                                      "particles", "1", "l_i", "1", "dem_steps", "1", "dem_time", "s",
                                      "dem_wall", "s", "t_steady", "s", "restitution", "1",
                                      "geometry_scale", "1", NULL};
  return gs_csv_close(&t, "gransim couple", units, err);
}

/* A cycle's collision_kernel.csv: its nc x nc values, and the nc + 1 edges,
 * read as the PBM's tabulated kernel reads it (comments and blank lines
 * skipped; a value that is not a finite number >= 0, a missing row or an
 * asymmetric table refused naming the line), and refused when its classes
 * are not the nc the case gives now. */
static int read_kernel(const char *dir, size_t nc, double *edges, double *C, gs_error *err) {
  char p[4600];
  snprintf(p, sizeof p, "%s/collision_kernel.csv", dir);
  gs_class_table tab = {0};
  int rc = gs_class_table_read(p, 0, &tab, err);
  if (rc) return rc;
  if (tab.n != nc)
    rc = gs_error_set(err, GS_EINPUT, "%s: a table of %zu classes, but the grid and coupling.classes give %zu: the "
                      "case changed since this cycle's DEM stage; rerun without --resume", p, tab.n, nc);
  if (!rc) {
    memcpy(edges, tab.edges, (nc + 1) * sizeof *edges);
    memcpy(C, tab.c, nc * nc * sizeof *C);
  }
  gs_class_table_free(&tab);
  return rc;
}

/* result.h5's /coupling/cycles: the cycle table's columns (trigger and
 * ended_by as codes: 0 start, 1 mean_volume_change, 2 interval, 3 end) and
 * every cycle's kernel table. */
static int write_cycles_h5(const char *out, const couple *k, const cycle_row *rows, size_t m, gs_error *err) {
  char h5[4400], dir[4400];
  snprintf(h5, sizeof h5, "%s/result.h5", out);
  const size_t nc = k->cl.n;
  double *col = gs_malloc((m * nc * nc + m + nc + 1) * sizeof *col, err), *edges = col + m * nc * nc + m;
  if (!col) return GS_ENOMEM;
  int rc = GS_OK;
  static const struct {
    const char *name, *units;
  } cols[] = {{"t_start", "s"}, {"t_end", "s"}, {"trigger", "1"}, {"volume_change", "1"}, {"ended_by", "1"},
              {"particles", "1"}, {"l_i", "1"}, {"dem_steps", "1"}, {"dem_time", "s"}, {"dem_wall", "s"},
              {"t_steady", "s"}, {"restitution", "1"}, {"geometry_scale", "1"}};
  unsigned long long d1[1] = {m}, d3[3] = {m, nc, nc}, de[1] = {nc + 1};
  for (size_t c = 0; c < sizeof cols / sizeof cols[0] && !rc; c++) {
    for (size_t i = 0; i < m; i++) {
      const cycle_row *w = &rows[i];
      const double v[] = {w->h.t, w->t_end, w->h.trigger, w->h.change, w->by, (double)w->r.particles, w->r.l,
                          (double)w->r.steps, w->r.t_dem, w->r.wall, w->r.t_steady, w->r.e, w->r.geom};
      col[i] = v[c];
    }
    char path[128];
    snprintf(path, sizeof path, "/coupling/cycles/%s", cols[c].name);
    rc = gs_output_add_dataset(h5, path, 1, d1, col, cols[c].units, "cycle", err);
  }
  for (size_t i = 0; i < m && !rc; i++) {
    cycle_dir(dir, sizeof dir, out, (long)i + 1, 0);
    rc = read_kernel(dir, nc, edges, col + i * nc * nc, err);
  }
  if (!rc) rc = gs_output_add_dataset(h5, "/coupling/cycles/collision_frequency", 3, d3, col, "1/s",
                                      "cycle,class,class", err);
  if (!rc) rc = gs_output_add_dataset(h5, "/coupling/class_edges", 1, de, edges, "m", "class_edge", err);
  free(col);
  return rc;
}

/* ---- the trigger, a run observer ------------------------------------------ */

typedef struct {
  const couple *k;
  double t0, v0;   /* the stretch's start */
  int fired;       /* TRIG_VOLUME or TRIG_INTERVAL, 0 none */
  double change;   /* at the last output time */
} trigger_obs;

static int trigger_output(void *self, const gs_run_view *run, double t, const double *Y, int *stop, gs_error *err) {
  (void)run;
  (void)err;
  trigger_obs *o = self;
  const double v = mean_volume(o->k, Y);
  o->change = o->v0 > 0 ? fabs(v - o->v0) / o->v0 : 0;
  if (t <= o->t0) return GS_OK;
  const double dv = o->k->s.trig_dv, dt = o->k->s.trig_interval;
  if (dv > 0 && o->change >= dv) o->fired = TRIG_VOLUME;
  else if (dt > 0 && t - o->t0 >= dt * (1 - 1e-9)) o->fired = TRIG_INTERVAL;
  if (o->fired) *stop = 1;
  return GS_OK;
}

static const gs_observer_type trigger_type = {.name = "coupling trigger", .output = trigger_output};

/* ---- the loop --------------------------------------------------------------- */

/* The PBM case with cycle dir's tables (or placeholders there), read afresh. */
static int load_pbm(const couple *k, const char *path, const char *dir, int placeholders, gs_case *c, gs_error *err) {
  char kt[4600], it[4600], cwd[2048] = "", imp[300] = "impact_table.csv";
  if (k->s.wall) snprintf(imp, sizeof imp, "impact_table_%s.csv", k->s.wall);
  /* absolute: the PBM resolves relative table names against the case file's folder */
  if (dir[0] != '/' && !getcwd(cwd, sizeof cwd)) cwd[0] = 0;
  snprintf(kt, sizeof kt, "%s%s%s/%s", cwd, cwd[0] ? "/" : "", dir, placeholders ? ".placeholder_kernel.csv" : "collision_kernel.csv");
  snprintf(it, sizeof it, "%s%s%s/%s", cwd, cwd[0] ? "/" : "", dir, placeholders ? ".placeholder_impacts.csv" : imp);
  memset(c, 0, sizeof *c);
  int rc = placeholders ? gs_couple_write_placeholders(k, kt, it, err) : GS_OK;
  gs_cfg *cfg = rc ? NULL : gs_cfg_load_file(path, err);
  if (!rc && !cfg) rc = err->code;
  if (!rc) rc = gs_couple_point_at_tables(gs_cfg_root(cfg), kt, it, err);
  if (!rc) { /* read by the coupling (gs_couple_load), not by the PBM case */
    gs_cfg_get(gs_cfg_root(cfg), "dem");
    gs_cfg_get(gs_cfg_root(cfg), "coupling");
  }
  if (rc) {
    gs_cfg_free(cfg);
  } else rc = gs_case_from_cfg(cfg, c, err); /* takes cfg */
  if (placeholders) {
    unlink(kt);
    unlink(it);
  }
  return rc;
}

static void remove_tree(const char *p) { nftw(p, gs_couple_rm_entry, 16, FTW_DEPTH | FTW_PHYS); }

int gs_couple_two_way(couple *k, const char *path, const gs_couple_options *opt, gs_error *err) {
  const char *out = opt->out_dir;
  char dir[4400], part[4400];
  int rc = gs_output_mkdir_p(out, err);
  if (rc) return rc;
  /* the start state: the PBM case's initial population */
  gs_case c;
  rc = load_pbm(k, path, out, 1, &c, err);
  if (rc) return rc;
  const size_t n = c.ode.n;
  const double t_first = c.t0, t_last = c.times[c.ntimes - 1];
  double *Y = gs_malloc(n * sizeof *Y, err);
  if (Y) memcpy(Y, c.y0, n * sizeof *Y);
  gs_case_free(&c);
  if (!Y) return GS_ENOMEM;
  start_head h = {.t = t_first, .v0 = mean_volume(k, Y), .trigger = TRIG_START, .n = n};
  const double n_first = total_number(k, Y); /* the population the case's geometry is for (scaling) */
  /* where to start: the last cycle begun (--resume), or a fresh cycle 1 */
  long N = 0;
  int dem_done = 0;
  if (opt->resume) {
    for (long m = 1;; m++) {
      cycle_dir(dir, sizeof dir, out, m, 0);
      cycle_dir(part, sizeof part, out, m, 1);
      if (read_start(dir, &h, Y, n)) N = m, dem_done = 1;
      else if (read_start(part, &h, Y, n)) N = m, dem_done = 0;
      else break;
    }
    if (N && opt->progress)
      fprintf(stderr, "gransim couple: --resume: from cycle %ld (t = %g s), %s\n", N, h.t,
              dem_done ? "its DEM stage complete, the PBM stretch resumed" : "its DEM stage run again");
    if (N && dem_done && !gs_couple_exists(out, ".result.journal") && gs_couple_exists(out, "result.h5")) {
      if (opt->progress) fprintf(stderr, "gransim couple: --resume: the coupled run is complete in %s\n", out);
      /* its cycle table again, in case a kill came between the result's publication and the table */
      cycle_row *rows = malloc((size_t)(N + 1) * sizeof *rows);
      size_t m = rows ? collect_cycles(out, N, n, t_last, TRIG_END, rows) : 0;
      rc = rows ? write_cycles(out, rows, m, err) : gs_error_set(err, GS_ENOMEM, "out of memory for the cycle table");
      if (!rc) rc = write_cycles_h5(out, k, rows, m, err);
      if (!rc && N == 1) rc = never_fired(k, out, t_first, t_last, NAN, err);
      free(rows);
      free(Y);
      return rc;
    }
  }
  if (!N) { /* a fresh run: earlier cycles go */
    for (long m = 1;; m++) {
      cycle_dir(dir, sizeof dir, out, m, 0);
      cycle_dir(part, sizeof part, out, m, 1);
      int any = gs_couple_exists(dir, ".") || gs_couple_exists(part, ".");
      remove_tree(dir);
      remove_tree(part);
      if (!any) break;
    }
    N = 1;
    cycle_dir(part, sizeof part, out, N, 1);
    if (mkdir(part, 0777)) rc = gs_error_set(err, GS_EIO, "%s: cannot create: %s", part, strerror(errno));
    if (!rc) rc = write_start(part, &h, Y, err);
  }
  const int fresh_pbm = !opt->resume || N == 1;
  cycle_row *rows = NULL;
  for (int first_stretch = 1; !rc; first_stretch = 0) {
    cycle_dir(dir, sizeof dir, out, N, 0);
    cycle_dir(part, sizeof part, out, N, 1);
    if (!dem_done) { /* the DEM stage of cycle N, on the population at h.t */
      double fr[GS_COUPLE_MAX_CLASSES];
      gs_couple_dem_record rec;
      rc = class_fractions(k, Y, h.t, fr, err);
      if (!rc && opt->progress) {
        fprintf(stderr, "gransim couple: cycle %ld at t = %g s: DEM of the population, class fractions", N, h.t);
        for (size_t j = 0; j < k->cl.n; j++) fprintf(stderr, " %.3g", fr[j]);
        fputc('\n', stderr);
      }
      k->s.e_now = restitution(k, Y);
      k->s.geom_now = k->s.scale_n ? geometry_factor(n_first, total_number(k, Y)) : 1;
      if (!rc && opt->progress && !isnan(k->s.e_now))
        fprintf(stderr, "gransim couple: restitution of %s: %.4g (volume-weighted over the components)\n",
                k->s.material, k->s.e_now);
      if (!rc) rc = gs_couple_dem_stage(k, part, fr, opt, &rec, err);
      rec.l = k->s.scale_n ? cbrt(total_number(k, Y) / (double)k->s.scale_n) : 1;
      rec.geom = k->s.geom_now;
      if (!rc && k->s.scale_n) {
        rc = scale_kernel(part, k->cl.n, rec.l, err);
        if (!rc && opt->progress)
          fprintf(stderr, "gransim couple: system scaling: %ld DEM particles for %.6g granules, l_i = %.6g, "
                  "geometry x %.6g, C_ij x l_i^-3 = %.6g\n", k->s.scale_n, total_number(k, Y), rec.l, rec.geom,
                  1 / (rec.l * rec.l * rec.l));
      }
      if (!rc) rc = write_record(part, &rec, err);
      if (!rc && rename(part, dir)) rc = gs_error_set(err, GS_EIO, "%s: cannot rename to %s: %s", part, dir, strerror(errno));
      if (rc) {
        gs_error_prefix(err, "cycle %ld (process time %g s): ", N, h.t);
        break;
      }
      dem_done = 1;
    }
    cycle_row *grown = realloc(rows, (size_t)(N + 1) * sizeof *rows);
    if (!grown) {
      rc = gs_error_set(err, GS_ENOMEM, "out of memory for the cycle table");
      break;
    }
    rows = grown;
    { /* the DEM's frequencies must be finite numbers of the derived classes (an empty or NaN table: an error) */
      double *C = gs_malloc((k->cl.n * k->cl.n + k->cl.n + 1) * sizeof *C, err);
      rc = C ? read_kernel(dir, k->cl.n, C + k->cl.n * k->cl.n, C, err) : GS_ENOMEM;
      free(C);
      if (rc) {
        gs_error_prefix(err, "cycle %ld (process time %g s): ", N, h.t);
        break;
      }
    }
    /* the PBM stretch from h.t with cycle N's tables until the trigger fires */
    rc = load_pbm(k, path, dir, 0, &c, err);
    if (rc) {
      gs_error_prefix(err, "cycle %ld: ", N);
      break;
    }
    trigger_obs tr = {.k = k, .t0 = h.t, .v0 = h.v0};
    gs_observer ob = {.type = &trigger_type, .self = &tr};
    /* the first stretch of a fresh run opens the result files; every later one
     * resumes them, which the previous stretch left held */
    const int resume = !(first_stretch && fresh_pbm) || gs_couple_exists(out, ".result.journal");
    if (resume && !gs_couple_exists(out, ".result.journal"))
      rc = gs_error_set(err, GS_EIO, "%s: no .result.journal of the PBM stretches to continue from (cycle %ld, t = %g s); "
                        "rerun without --resume", out, N, h.t);
    gs_run_options ro = {.out_dir = out, .resume = resume, .progress = opt->progress ? -1 : 0, .hold_on_stop = 1,
                         .observers = &ob, .nobservers = 1};
    gs_run_report rep;
    memset(&rep, 0, sizeof rep);
    if (!rc) rc = gs_case_run(&c, &ro, Y, &rep, err);
    gs_case_free(&c);
    if (rc) {
      gs_error_prefix(err, "cycle %ld, PBM stretch from t = %g s: ", N, h.t);
      break;
    }
    if (!rep.stopped) { /* the process time is over */
      size_t m = collect_cycles(out, N, n, rep.t_end, TRIG_END, rows);
      rc = write_cycles(out, rows, m, err);
      if (!rc) rc = write_cycles_h5(out, k, rows, m, err);
      if (!rc && opt->progress)
        fprintf(stderr, "gransim couple: %ld cycles to t = %g s; results in %s, cycles in %s/cycles.csv\n", N,
                rep.t_end, out, out);
      if (!rc && N == 1) rc = never_fired(k, out, t_first, rep.t_end, tr.change, err);
      break;
    }
    if (opt->progress)
      fprintf(stderr, "gransim couple: cycle %ld ends at t = %g s (%s; mean granule volume changed by %.3g)\n", N,
              rep.t_end, trig_names[tr.fired], tr.change);
    h = (start_head){.t = rep.t_end, .v0 = mean_volume(k, Y), .trigger = tr.fired, .change = tr.change, .n = n};
    N++;
    dem_done = 0;
    cycle_dir(part, sizeof part, out, N, 1);
    remove_tree(part);
    if (mkdir(part, 0777)) rc = gs_error_set(err, GS_EIO, "%s: cannot create: %s", part, strerror(errno));
    if (!rc) rc = write_start(part, &h, Y, err);
    if (!rc) rc = write_cycles(out, rows, collect_cycles(out, N - 1, n, rep.t_end, tr.fired, rows), err);
  }
  free(rows);
  free(Y);
  return rc;
}
