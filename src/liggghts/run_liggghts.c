/* Running a case with LIGGGHTS: the initial bed (inserted by gransim, so
 * both engines start from the same particles), the deck, one exclusion run
 * per mesh, the real run under mpirun with its thermo output as the progress
 * line, then the reduction (tables.c). */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "dem/dem_case.h"
#include "gransim/liggghts.h"
#include "liggghts/lig_internal.h"

/* The initial bed as a LIGGGHTS data file (atom_style granular:
 * id type diameter density x y z; then velocities). */
static int write_bed(gs_dem_case *c, const char *path, size_t *n_out, gs_error *err) {
  uint64_t rng = c->seed;
  int rc = GS_OK;
  for (size_t k = 0; k < c->nfill && !rc; k++) {
    long n;
    double m;
    rc = gs_dem_case_insert(c, &c->fill[k], c->fill[k].count, c->fill[k].mass, &rng, &n, &m, err);
    if (!rc && n < c->fill[k].count && !isfinite(c->fill[k].mass))
      fprintf(stderr, "gransim: warning: fill[%zu]: region full after %ld of %ld particles\n", k, n, c->fill[k].count);
  }
  if (!rc) rc = gs_dem_run(c->dem, 0, err); /* pending particles enter */
  if (rc) return rc;
  gs_dem_view v;
  gs_dem_get_view(c->dem, &v);
  FILE *fp = fopen(path, "w");
  if (!fp) return gs_error_set(err, GS_EIO, "%s: cannot write: %s", path, strerror(errno));
  const gs_dem_params *p = &c->prm;
  fprintf(fp, "gransim initial bed of %s\n\n%zu atoms\n%zu atom types\n\n", c->path, v.n, c->nclass + c->nwall_src);
  const char *ax = "xyz";
  for (int a = 0; a < 3; a++) fprintf(fp, "%.9g %.9g %clo %chi\n", p->lo[a], p->hi[a], ax[a], ax[a]);
  fprintf(fp, "\nAtoms\n\n");
  for (size_t i = 0; i < v.n; i++) {
    int cls = gs_dem_type_class(c->dem, v.type[i]);
    fprintf(fp, "%zu %d %.12g %.9g %.12g %.12g %.12g\n", i + 1, cls + 1, 2 * v.r[i], c->cls[cls].mat.density, v.x[i],
            v.y[i], v.z[i]);
  }
  fprintf(fp, "\nVelocities\n\n");
  for (size_t i = 0; i < v.n; i++)
    fprintf(fp, "%zu %.12g %.12g %.12g %.12g %.12g %.12g\n", i + 1, v.vx[i], v.vy[i], v.vz[i], v.wx[i], v.wy[i], v.wz[i]);
  int bad = ferror(fp);
  if (fclose(fp) || bad) return gs_error_set(err, GS_EIO, "%s: write failed", path);
  *n_out = v.n;
  return GS_OK;
}

static int on_path(const char *prog) {
  if (strchr(prog, '/')) return access(prog, X_OK) == 0;
  const char *path = getenv("PATH");
  char buf[4096];
  while (path && *path) {
    size_t n = strcspn(path, ":");
    snprintf(buf, sizeof buf, "%.*s/%s", (int)n, path, prog);
    if (n && access(buf, X_OK) == 0) return 1;
    path += n + (path[n] == ':');
  }
  return 0;
}

/* 'dir' with single quotes escaped, for sh -c */
static void quote(const char *s, char *out, size_t n) {
  size_t k = 0;
  if (k + 1 < n) out[k++] = '\'';
  for (; *s && k + 5 < n; s++) {
    if (*s == '\'') { memcpy(out + k, "'\\''", 4); k += 4; }
    else out[k++] = *s;
  }
  if (k + 1 < n) out[k++] = '\'';
  out[k] = 0;
}

/* Run `cd dir && launch binary -in deck -log log`, keeping its output in
 * screen (and the last lines for the error), thermo rows for the progress
 * line and the time series. */
static int run_deck(const char *dir, const char *launch, const char *bin, const char *deck, const char *log,
                    const char *screen, const gs_dem_case *c, int progress, gs_lig_thermo *th, gs_error *err) {
  char qd[4400], cmd[9000], path[4400];
  quote(dir, qd, sizeof qd);
  snprintf(cmd, sizeof cmd, "cd %s && %s %s -in %s -log %s 2>&1", qd, launch, bin, deck, log);
  snprintf(path, sizeof path, "%s/%s", dir, screen);
  FILE *sc = fopen(path, "w");
  if (!sc) return gs_error_set(err, GS_EIO, "%s: cannot write: %s", path, strerror(errno));
  FILE *pp = popen(cmd, "r");
  if (!pp) {
    fclose(sc);
    return gs_error_set(err, GS_EIO, "cannot start '%s': %s", cmd, strerror(errno));
  }
  char line[4096], tail[12][512], first_error[512] = "";
  const long out_k = (long)fmax(1, round(c->out_every / c->prm.dt));
  double cpu_last = 0, cpu_sum = 0;
  int nt = 0, saw_error = 0, short_insert = 0;
  while (fgets(line, sizeof line, pp)) {
    fputs(line, sc);
    size_t ll = strlen(line);
    if (ll > sizeof tail[0] - 1) ll = sizeof tail[0] - 1;
    memcpy(tail[nt % 12], line, ll);
    tail[nt % 12][ll] = 0;
    nt++;
    if (!strncmp(line, "ERROR", 5) && !saw_error) {
      saw_error = 1;
      memcpy(first_error, tail[(nt - 1) % 12], sizeof first_error);
    }
    if (strstr(line, "Less insertions than requested")) short_insert++;
    double step, atoms, ke, rke, cpu, hn, hm;
    char extra;
    /* LIGGGHTS' cpu column restarts with each run command: summed over them */
    /* a row per output interval: each run command also prints its first and
     * last step (the outlets' runs of 200 steps), which are left out */
    int is_row = th && sscanf(line, "%lf %lf %lf %lf %lf %lf %lf %c", &step, &atoms, &ke, &rke, &cpu, &hn, &hm, &extra) == 7;
    if (is_row) {
      if (cpu < cpu_last) cpu_sum += cpu_last;
      cpu_last = cpu;
      cpu += cpu_sum;
    }
    if (is_row && fmod(step, (double)out_k) == 0 && (th->n == 0 || step * c->prm.dt > th->row[GS_LIG_THERMO_COLS * (th->n - 1)])) {
      if (th->n == th->cap) {
        size_t cap = th->cap ? 2 * th->cap : 256;
        double *r = realloc(th->row, cap * GS_LIG_THERMO_COLS * sizeof(double));
        if (!r) break;
        th->row = r;
        th->cap = cap;
      }
      double *r = th->row + GS_LIG_THERMO_COLS * th->n++;
      r[0] = step * c->prm.dt, r[1] = atoms, r[2] = ke, r[3] = rke, r[4] = cpu, r[5] = hn, r[6] = hm;
      if (progress)
        fprintf(stderr, "gransim dem (liggghts): t = %.5f / %.5f s, %.0f particles, kinetic energy %.4g J\n", r[0],
                c->duration, atoms, ke);
    }
  }
  int st = pclose(pp);
  fclose(sc);
  /* LIGGGHTS places the largest particles first and drops what finds no room,
   * where the embedded engine keeps a drawn particle until it fits */
  if (short_insert && progress)
    fprintf(stderr, "gransim: warning: LIGGGHTS inserted less than requested %d time(s) (a crowded feed region): "
            "it drops the particles that find no room, the smallest first, so the fed size distribution leans "
            "to the large classes; enlarge the feed region or insert more often\n", short_insert);
  if (st != 0 || saw_error) {
    char msg[4096];
    size_t k = 0;
    for (int i = nt > 12 ? nt - 12 : 0; i < nt && k < sizeof msg - 1; i++)
      k += (size_t)snprintf(msg + k, sizeof msg - k, "  | %s", tail[i % 12]);
    if (k >= sizeof msg) k = sizeof msg - 1;
    msg[k] = 0;
    return gs_error_set(err, GS_EIO, "LIGGGHTS failed (%s in %s; its output: %s/%s): %slast lines:\n%s", deck, dir,
                        dir, screen, first_error[0] ? first_error : "", msg);
  }
  return GS_OK;
}

int gs_lig_case_run(gs_dem_case *c, const char *out, const gs_lig_options *opt, gs_error *err) {
  int rc = gs_lig_check(c, err);
  if (rc) return rc;
  const char *bin = opt && opt->binary ? opt->binary : getenv("GRANSIM_LIGGGHTS") ? getenv("GRANSIM_LIGGGHTS") : "liggghts";
  if (!on_path(bin))
    return gs_error_set(err, GS_EINPUT, "the LIGGGHTS executable '%s' is not on PATH (Debian: apt-get install "
                        "liggghts mpi-default-bin; or set GRANSIM_LIGGGHTS)", bin);
  char dir[4200], path[4400], launch[2048];
  snprintf(dir, sizeof dir, "%s/liggghts", out);
  if ((mkdir(out, 0777) && errno != EEXIST) || (mkdir(dir, 0777) && errno != EEXIST))
    return gs_error_set(err, GS_EIO, "%s: cannot create: %s", dir, strerror(errno));
  snprintf(path, sizeof path, "%s/post", dir);
  if (mkdir(path, 0777) && errno != EEXIST) return gs_error_set(err, GS_EIO, "%s: cannot create: %s", path, strerror(errno));
  if ((rc = gs_lig_clear_dumps(path, err))) return rc;
  snprintf(path, sizeof path, "%s/vtk", out);
  if (c->vtk_every > 0 && mkdir(path, 0777) && errno != EEXIST)
    return gs_error_set(err, GS_EIO, "%s: cannot create: %s", path, strerror(errno));
  int ranks = opt && opt->ranks > 0 ? opt->ranks : (int)sysconf(_SC_NPROCESSORS_ONLN);
  if (ranks < 1) ranks = 1;
  if (opt && opt->launcher) snprintf(launch, sizeof launch, "%s", opt->launcher);
  /* Open MPI refuses root without these; other MPIs ignore the variables */
  else snprintf(launch, sizeof launch, "%smpirun -np %d", geteuid() == 0 ?
                "OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1 " : "",
                ranks);
  int progress = opt ? opt->progress : 0;

  size_t nbed = 0;
  if (c->nfill) {
    snprintf(path, sizeof path, "%s/bed.data", dir);
    if ((rc = write_bed(c, path, &nbed, err))) return rc;
    if (progress) fprintf(stderr, "gransim dem (liggghts): initial bed of %zu particles in %s\n", nbed, path);
  }
  /* the exclusion runs: one per mesh, each writes the facets LIGGGHTS refuses and stops */
  for (size_t w = 0; w < c->nwall_src && !rc; w++) {
    char deck[64], ex[4400];
    snprintf(deck, sizeof deck, "in.exclude%zu", w);
    snprintf(ex, sizeof ex, "%s/ex_wall%zu.txt", dir, w);
    remove(ex);
    snprintf(path, sizeof path, "%s/%s", dir, deck);
    if ((rc = gs_lig_write_exclusion_deck(c, w, path, err))) return rc;
    gs_error ignored = {0};
    (void)run_deck(dir, "", bin, deck, "none", "screen.exclude", c, 0, NULL, &ignored);
    FILE *fp = fopen(ex, "a"); /* an empty list when nothing was refused */
    if (fp) fclose(fp);
  }
  snprintf(path, sizeof path, "%s/in.gransim", dir);
  FILE *fp = fopen(path, "w");
  if (!fp) return gs_error_set(err, GS_EIO, "%s: cannot write: %s", path, strerror(errno));
  rc = gs_lig_write_deck(c, fp, c->nfill ? "bed.data" : NULL, c->nwall_src ? "read" : NULL, err);
  if (fclose(fp) && !rc) rc = gs_error_set(err, GS_EIO, "%s: write failed", path);
  if (rc) return rc;
  if (progress) fprintf(stderr, "gransim dem (liggghts): cd %s && %s %s -in in.gransim -log log.liggghts\n", dir, launch, bin);
  gs_lig_thermo th = {0};
  rc = run_deck(dir, launch, bin, "in.gransim", "log.liggghts", "screen.liggghts", c, progress, &th, err);
  if (!rc) rc = gs_lig_reduce(c, out, &th, err);
  free(th.row);
  return rc;
}
