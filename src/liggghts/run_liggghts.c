/* Running a case with LIGGGHTS: the initial bed (inserted by gransim, so
 * both engines start from the same particles), the deck, one exclusion run
 * per mesh, the real run under mpirun with its thermo output as the progress
 * line, then the reduction (tables.c). */
#include <errno.h>
#include <signal.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include "core/progress.h"
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

/* One thermo row (thermo_style custom step atoms ke c_rke cpu v_hn v_hm) into
 * th, once per output interval: each run command also prints its first and
 * last step (the outlets' runs of 200 steps), which are left out.  LIGGGHTS'
 * cpu column restarts with each run command: summed over them (cpu[0] the
 * last value read, cpu[1] the sum of the finished runs').  Returns 1 for a
 * row kept, 0 otherwise, -1 out of memory. */
/* The deck's lines, to find the one LIGGGHTS echoes before an ERROR. */
typedef struct {
  char **line;
  size_t n;
} deck_lines;

static void deck_lines_read(const char *path, deck_lines *d) {
  d->line = NULL, d->n = 0;
  FILE *fp = fopen(path, "r");
  char buf[4096];
  size_t cap = 0;
  while (fp && fgets(buf, sizeof buf, fp)) {
    buf[strcspn(buf, "\r\n")] = 0;
    if (d->n == cap) {
      char **t = realloc(d->line, (cap = cap ? 2 * cap : 128) * sizeof *t);
      if (!t) break;
      d->line = t;
    }
    if (!(d->line[d->n] = strdup(buf))) break;
    d->n++;
  }
  if (fp) fclose(fp);
}

/* 1-based number of the deck line equal to s (the first such), or 0. */
static size_t deck_line_of(const deck_lines *d, const char *s) {
  if (!(*s >= 'a' && *s <= 'z')) return 0; /* commands start with a lower-case letter */
  for (size_t k = 0; k < d->n; k++)
    if (d->line[k][0] && !strcmp(d->line[k], s)) return k + 1;
  return 0;
}

static void deck_lines_free(deck_lines *d) {
  for (size_t k = 0; k < d->n; k++) free(d->line[k]);
  free(d->line);
}

/* What the runner follows in LIGGGHTS' output: the screen file, the last
 * lines (and those before the first ERROR, to find the deck line among
 * them), thermo rows for the progress line and the time series. */
typedef struct {
  FILE *sc;
  const gs_dem_case *c;
  int progress;
  gs_lig_thermo *th;
  char tail[12][512], first_error[512], before[8][512];
  double cpu_acc[2], t_first, wall_first;
  int nt, saw_error, short_insert, nbefore;
} lig_out;

/* One line of LIGGGHTS' output; -1: out of memory. */
static int out_line(lig_out *o, char *line) {
  fputs(line, o->sc);
  size_t ll = strlen(line);
  if (ll > sizeof o->tail[0] - 1) ll = sizeof o->tail[0] - 1;
  memcpy(o->tail[o->nt % 12], line, ll);
  o->tail[o->nt % 12][ll] = 0;
  o->nt++;
  const int nt = o->nt;
  if (!strncmp(line, "ERROR", 5) && !o->saw_error) {
    o->saw_error = 1;
    memcpy(o->first_error, o->tail[(nt - 1) % 12], sizeof o->first_error);
    o->nbefore = nt - 1 < 8 ? nt - 1 : 8;
    for (int i = 0; i < o->nbefore; i++) {
      memcpy(o->before[i], o->tail[(nt - 2 - i) % 12], sizeof o->before[i]); /* newest first */
      o->before[i][strcspn(o->before[i], "\r\n")] = 0;
    }
  }
  line[strcspn(line, "\r\n")] = 0;
  if (strstr(line, "Less insertions than requested")) o->short_insert++;
  const gs_dem_case *c = o->c;
  int kept = o->th ? gs_lig_thermo_add(o->th, line, c->prm.dt, c->out_every, o->cpu_acc) : 0;
  if (kept < 0) return -1;
  if (kept && o->progress) {
    /* the time left from the simulated time per wall second since the first row */
    const double *r = o->th->row + o->th->ncol * (o->th->n - 1), now = gs_progress_clock();
    char left[64] = "time left not known yet";
    if (o->t_first < 0) o->t_first = r[0], o->wall_first = now;
    else if (r[0] > o->t_first && now > o->wall_first) {
      gs_progress_duration(left, sizeof left - 5, (c->duration - r[0]) * (now - o->wall_first) / (r[0] - o->t_first));
      strcat(left, " left");
    }
    fprintf(stderr, "gransim dem (liggghts): t = %.5f / %.5f s, %.0f particles, kinetic energy %.4g J, %s\n", r[0],
            c->duration, r[1], r[2], left);
  }
  return 0;
}

/* After LIGGGHTS ended with status st: its error, if any, with the line of
 * deck (in dir) it refers to: the last echoed line before it that is one. */
static int out_finish(lig_out *o, const char *dir, const char *deck, const char *screen, int st, gs_error *err) {
  char path[4400];
  fclose(o->sc);
  size_t error_cmd = 0;
  const char *cmd_line = "";
  if (o->saw_error) {
    deck_lines dl;
    snprintf(path, sizeof path, "%s/%s", dir, deck);
    deck_lines_read(path, &dl);
    for (int i = 0; i < o->nbefore && !error_cmd; i++)
      if ((error_cmd = deck_line_of(&dl, o->before[i]))) cmd_line = o->before[i];
    deck_lines_free(&dl);
  }
  /* LIGGGHTS places the largest particles first and drops what finds no room,
   * where the embedded engine keeps a drawn particle until it fits */
  if (o->short_insert && o->progress)
    fprintf(stderr, "gransim: warning: LIGGGHTS inserted less than requested %d time(s) (a crowded feed region): "
            "it drops the particles that find no room, the smallest first, so the fed size distribution leans "
            "to the large classes; enlarge the feed region or insert more often\n", o->short_insert);
  if (st != 0 || o->saw_error) {
    char msg[4096], where[700] = "";
    size_t k = 0;
    for (int i = o->nt > 12 ? o->nt - 12 : 0; i < o->nt && k < sizeof msg - 1; i++)
      k += (size_t)snprintf(msg + k, sizeof msg - k, "  | %s", o->tail[i % 12]);
    if (k >= sizeof msg) k = sizeof msg - 1;
    msg[k] = 0;
    if (o->saw_error && error_cmd) snprintf(where, sizeof where, "%.64s line %zu: %.500s\n", deck, error_cmd, cmd_line);
    return gs_error_set(err, GS_EIO, "LIGGGHTS failed (%s in %s; its output: %s/%s): %s%slast lines:\n%s", deck, dir,
                        dir, screen, o->first_error[0] ? o->first_error : "", where, msg);
  }
  return GS_OK;
}

static int out_open(lig_out *o, const char *dir, const char *screen, const gs_dem_case *c, int progress,
                    gs_lig_thermo *th, gs_error *err) {
  char path[4400];
  memset(o, 0, sizeof *o);
  o->c = c, o->progress = progress, o->th = th, o->t_first = -1;
  snprintf(path, sizeof path, "%s/%s", dir, screen);
  if (!(o->sc = fopen(path, "w"))) return gs_error_set(err, GS_EIO, "%s: cannot write: %s", path, strerror(errno));
  return GS_OK;
}

/* Run `cd dir && launch binary -echo screen -in deck -log log`, following
 * its output (lig_out).  The echo gives the deck line an ERROR refers to. */
static int run_deck(const char *dir, const char *launch, const char *bin, const char *deck, const char *log,
                    const char *screen, const gs_dem_case *c, int progress, gs_lig_thermo *th, gs_error *err) {
  char qd[4400], cmd[9000], line[4096];
  quote(dir, qd, sizeof qd);
  snprintf(cmd, sizeof cmd, "cd %s && %s %s -echo screen -in %s -log %s 2>&1", qd, launch, bin, deck, log);
  lig_out o;
  int rc = out_open(&o, dir, screen, c, progress, th, err);
  if (rc) return rc;
  FILE *pp = popen(cmd, "r");
  if (!pp) {
    fclose(o.sc);
    return gs_error_set(err, GS_EIO, "cannot start '%s': %s", cmd, strerror(errno));
  }
  while (fgets(line, sizeof line, pp))
    if (out_line(&o, line) < 0) break;
  int st = pclose(pp);
  return out_finish(&o, dir, deck, screen, st, err);
}

/* The observer's figures of the detector's sample k (particles and kinetic
 * energy from the last thermo row up to its time). */
static gs_dem_sample sample_of(const gs_lig_steady *sd, size_t k, const gs_lig_thermo *th, double dt) {
  gs_dem_sample smp = {.t = sd->t[k], .step = (long)round(sd->t[k] / dt), .holdup_mass = sd->m[k],
                       .collisions_per_s = sd->cr[k], .steady = sd->t_steady >= 0 && sd->t[k] >= sd->t_steady,
                       .window = sd->t_steady >= 0 && sd->t[k] >= sd->t_steady};
  for (size_t r = 0; r < th->n && th->row[th->ncol * r] <= sd->t[k] * (1 + 1e-12); r++) {
    const double *v = th->row + th->ncol * r;
    smp.particles = (size_t)v[1], smp.kinetic_energy = v[2] + v[3];
  }
  return smp;
}

/* statistics.start: steady: LIGGGHTS reads its commands from standard input,
 * in.setup first, then the runs in chunks of about half the detector's
 * window; after each chunk the detector (steady.c) reads the new samples
 * from the dumps and the case's observer sees them.  One LIGGGHTS process
 * keeps every contact history, insertion and mesh angle (restart files keep
 * not all of them in 3.8), and Open MPI's mpirun forwards its standard input
 * to rank 0, which reads LIGGGHTS' input.  The run stops at dem.duration, or
 * after the sample at which the observer stops it: *t_end. */
static int run_chunks(const char *dir, const char *launch, const char *bin, gs_dem_case *c, int progress,
                      gs_lig_thermo *th, gs_lig_steady *sd, double *t_end, gs_error *err) {
  char qd[4400], cmd[9000], line[4096], post[4400], marker[64];
  quote(dir, qd, sizeof qd);
  snprintf(cmd, sizeof cmd, "cd %s && %s %s -echo screen -log log.liggghts 2>&1", qd, launch, bin);
  snprintf(post, sizeof post, "%s/post", dir);
  const double dt = c->prm.dt;
  const long nsteps = gs_lig_steps(c), chunk = sd->smp_k * (c->steady_window > 1 ? c->steady_window / 2 : 1);
  *t_end = (double)nsteps * dt;
  lig_out o;
  int rc = out_open(&o, dir, "screen.liggghts", c, progress, th, err), in[2] = {-1, -1}, out[2] = {-1, -1};
  if (rc) return rc;
  if (pipe(in) || pipe(out)) {
    rc = gs_error_set(err, GS_EIO, "cannot make a pipe: %s", strerror(errno));
    for (int k = 0; k < 2; k++) {
      if (in[k] >= 0) close(in[k]);
      if (out[k] >= 0) close(out[k]);
    }
    fclose(o.sc);
    return rc;
  }
  fflush(NULL);
  pid_t pid = fork();
  if (pid == 0) {
    dup2(in[0], 0), dup2(out[1], 1);
    close(in[0]), close(in[1]), close(out[0]), close(out[1]);
    execl("/bin/sh", "sh", "-c", cmd, (char *)NULL);
    _exit(127);
  }
  close(in[0]), close(out[1]);
  if (pid < 0) {
    close(in[1]), close(out[0]);
    fclose(o.sc);
    return gs_error_set(err, GS_EIO, "cannot start '%s': %s", cmd, strerror(errno));
  }
  /* LIGGGHTS gone, a write to it fails rather than killing gransim */
  struct sigaction ign = {.sa_handler = SIG_IGN}, old;
  sigaction(SIGPIPE, &ign, &old);
  FILE *to = fdopen(in[1], "w"), *from = fdopen(out[0], "r");
  int ended = !to || !from, stop = 0;
  size_t seen = 0;
  if (to) fprintf(to, "include in.setup\n");
  for (long at = 0; !ended && !stop && !rc && at < nsteps;) {
    const long next = at + chunk < nsteps ? at + chunk : nsteps;
    gs_lig_write_runs(c, to, at, next, 1);
    snprintf(marker, sizeof marker, "gransim: chunk done %ld", next);
    fprintf(to, "print \"%s\"\n", marker);
    if (fflush(to)) { /* LIGGGHTS gone: its error follows */
      ended = 1;
      break;
    }
    for (ended = 1; fgets(line, sizeof line, from);) {
      if (out_line(&o, line) < 0) { rc = gs_error_set(err, GS_ENOMEM, "out of memory"); break; }
      if (!strcmp(line, marker)) { ended = 0; break; }
    }
    if (ended || rc) break;
    at = next;
    rc = gs_lig_steady_update(sd, c, post, at, err);
    for (; !rc && !stop && seen < sd->ns; seen++) {
      if (sd->t_steady == sd->t[seen] && progress)
        fprintf(stderr, "gransim dem (liggghts): steady state at t = %.6g s\n", sd->t_steady);
      if (!c->observer.sample) continue;
      gs_dem_sample smp = sample_of(sd, seen, th, dt);
      int ow = 0;
      rc = c->observer.sample(&smp, c->observer.user, &ow, &stop, err);
      if (stop) *t_end = sd->t[seen];
    }
  }
  if (to) fclose(to); /* the end of LIGGGHTS' input: it finishes */
  else close(in[1]);
  while (from && fgets(line, sizeof line, from)) (void)out_line(&o, line);
  if (from) fclose(from);
  else close(out[0]);
  int st = 0;
  while (waitpid(pid, &st, 0) < 0 && errno == EINTR) {}
  sigaction(SIGPIPE, &old, NULL);
  int frc = out_finish(&o, dir, "in.setup", "screen.liggghts", st != 0 ? st : ended && !rc, err);
  return rc ? rc : frc;
}

/* Copy file from to to (the meshes beside the deck). */
static int copy_file(const char *from, const char *to, gs_error *err) {
  FILE *in = fopen(from, "rb");
  if (!in) return gs_error_set(err, GS_EIO, "%s: cannot read: %s", from, strerror(errno));
  FILE *out = fopen(to, "wb");
  if (!out) {
    fclose(in);
    return gs_error_set(err, GS_EIO, "%s: cannot write: %s", to, strerror(errno));
  }
  char buf[65536];
  size_t n;
  int bad = 0;
  while ((n = fread(buf, 1, sizeof buf, in)) > 0)
    if (fwrite(buf, 1, n, out) != n) bad = 1;
  bad |= ferror(in);
  fclose(in);
  if (fclose(out) || bad) return gs_error_set(err, GS_EIO, "%s: copying %s failed", to, from);
  return GS_OK;
}

/* The thermo rows of a finished run's log; refused when the run did not end
 * (no thermo row at the last step: every run command prints one at its end). */
static int read_log(const gs_dem_case *c, const char *dir, gs_lig_thermo *th, gs_error *err) {
  char path[4400], line[4096];
  snprintf(path, sizeof path, "%s/log.liggghts", dir);
  FILE *fp = fopen(path, "r");
  if (!fp) return gs_error_set(err, GS_EINPUT, "%s: cannot read: %s (no LIGGGHTS run in %s?)", path, strerror(errno), dir);
  double cpu_acc[2] = {0, 0}, last = -1, step;
  const long nsteps = (long)ceil(c->duration / c->prm.dt - 1e-9);
  int rc = GS_OK;
  while (fgets(line, sizeof line, fp) && !rc) {
    if (gs_lig_thermo_step(th, line, &step)) last = fmax(last, step);
    if (gs_lig_thermo_add(th, line, c->prm.dt, c->out_every, cpu_acc) < 0) rc = gs_error_set(err, GS_ENOMEM, "out of memory");
  }
  fclose(fp);
  if (!rc && last != (double)nsteps)
    rc = gs_error_set(err, GS_EINPUT, "%s: the LIGGGHTS run did not finish (its last step is %.0f of %ld): run it to "
                      "the end before reducing its dumps", path, last, nsteps);
  return rc;
}

/* The tables over the statistics window: from statistics.start, or from
 * when the detector sd fired (statistics.start: steady; an error naming the
 * last figures when it did not), to t_end. */
static int reduce_window(const gs_dem_case *c, const char *out, const gs_lig_thermo *th, const gs_lig_steady *sd,
                         double t_end, gs_error *err) {
  if (c->start_steady && sd->t_steady < 0) return gs_lig_steady_not_reached(sd, c, err);
  const gs_lig_window w = {.t0 = c->start_steady ? sd->t_steady : fmin(c->stats_start, c->duration), .t1 = t_end,
                           .t_steady = sd->t_steady};
  return gs_lig_reduce(c, out, th, &w, err);
}

/* run.sh: the exclusion runs and the run, for a job on a cluster
 * (`LAUNCH="srun" sh run.sh`). */
static int write_run_sh(const gs_dem_case *c, const char *dir, int ranks, gs_error *err) {
  char path[4400];
  snprintf(path, sizeof path, "%s/run.sh", dir);
  FILE *fp = fopen(path, "w");
  if (!fp) return gs_error_set(err, GS_EIO, "%s: cannot write: %s", path, strerror(errno));
  fprintf(fp, "#!/bin/sh\n# Runs the LIGGGHTS deck gransim wrote for %s (gransim dem --dry-run).\n"
              "# LAUNCH: the MPI launcher (default: mpirun -np %d; on Slurm: srun); LIGGGHTS: the executable.\n"
              "# Afterwards: gransim dem CASE --out DIR --reduce (DIR: the folder above this one).\n"
              "set -e\ncd \"$(dirname \"$0\")\"\nrm -f post/*\nmkdir -p post\n", c->path, ranks);
  for (size_t w = 0; w < c->nwall_src; w++)
    fprintf(fp, "# the facets LIGGGHTS refuses in mesh %zu (%s), left out by the run\n"
                "rm -f ex_wall%zu.txt\n${LIGGGHTS:-liggghts} -echo screen -in in.exclude%zu -log none > screen.exclude%zu "
                "2>&1 || true\ntouch ex_wall%zu.txt\n", w, c->wall_src[w].name, w, w, w, w);
  fprintf(fp, "${LAUNCH:-mpirun -np %d} ${LIGGGHTS:-liggghts} -echo screen -in in.gransim -log log.liggghts\n", ranks);
  int bad = ferror(fp);
  if (fclose(fp) || bad) return gs_error_set(err, GS_EIO, "%s: write failed", path);
  chmod(path, 0755);
  return GS_OK;
}

int gs_lig_case_run(gs_dem_case *c, const char *out, const gs_lig_options *opt, gs_error *err) {
  int rc = gs_lig_check(c, err);
  if (rc) return rc;
  const int dry = opt && opt->dry_run, reduce = opt && opt->reduce_only, progress = opt ? opt->progress : 0;
  char dir[4200], path[4400], launch[2048];
  snprintf(dir, sizeof dir, "%s/liggghts", out);
  int ranks = opt && opt->ranks > 0 ? opt->ranks : (int)sysconf(_SC_NPROCESSORS_ONLN);
  if (ranks < 1) ranks = 1;
  if (reduce) {
    gs_lig_remove_tables(c, out);
    gs_lig_thermo th = {.ncol = gs_lig_thermo_cols(c)};
    gs_lig_steady sd;
    gs_lig_steady_init(&sd, c);
    rc = read_log(c, dir, &th, err);
    /* statistics.start: steady: the detector on the whole run's dumps */
    snprintf(path, sizeof path, "%s/post", dir);
    if (!rc && c->start_steady) rc = gs_lig_steady_update(&sd, c, path, gs_lig_steps(c), err);
    if (!rc) rc = reduce_window(c, out, &th, &sd, c->duration, err);
    if (!rc) rc = gs_lig_vtk_frames(c, out, err);
    free(th.row);
    gs_lig_steady_free(&sd);
    return rc;
  }
  const char *bin = opt && opt->binary ? opt->binary : getenv("GRANSIM_LIGGGHTS") ? getenv("GRANSIM_LIGGGHTS") : "liggghts";
  if (!dry && !on_path(bin))
    return gs_error_set(err, GS_EINPUT, "the LIGGGHTS executable '%s' is not on PATH (Debian: apt-get install "
                        "liggghts; or set GRANSIM_LIGGGHTS)", bin);
  if (!dry && !(opt && opt->launcher) && !on_path("mpirun"))
    return gs_error_set(err, GS_EINPUT, "mpirun is not on PATH (Debian: apt-get install mpi-default-bin, which "
                        "brings Open MPI's openmpi-bin; or give --launcher, e.g. \"srun -n 64\")");
  if ((mkdir(out, 0777) && errno != EEXIST) || (mkdir(dir, 0777) && errno != EEXIST))
    return gs_error_set(err, GS_EIO, "%s: cannot create: %s", dir, strerror(errno));
  snprintf(path, sizeof path, "%s/post", dir);
  if (mkdir(path, 0777) && errno != EEXIST) return gs_error_set(err, GS_EIO, "%s: cannot create: %s", path, strerror(errno));
  if ((rc = gs_lig_clear_dumps(path, err))) return rc;
  gs_lig_remove_tables(c, out); /* a failed run leaves none of an earlier run's */
  snprintf(path, sizeof path, "%s/vtk", out);
  if (c->vtk_every > 0 && mkdir(path, 0777) && errno != EEXIST)
    return gs_error_set(err, GS_EIO, "%s: cannot create: %s", path, strerror(errno));
  if (opt && opt->launcher) snprintf(launch, sizeof launch, "%s", opt->launcher);
  /* Open MPI refuses root without the first three; other MPIs ignore the variables.  A rank
   * waiting for another yields its core rather than busy-polling (unless the user chose),
   * as the embedded engine's threads wait passively: on a machine shared with other work
   * two polling ranks cost 3.2 times the CPU of two yielding ones (docs/performance.md) */
  else snprintf(launch, sizeof launch, "%s%smpirun -np %d", geteuid() == 0 ?
                "OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1 " : "",
                getenv("OMPI_MCA_mpi_yield_when_idle") ? "" : "OMPI_MCA_mpi_yield_when_idle=1 ", ranks);

  if ((rc = gs_dem_case_write_geometry(c, out, NULL, err))) return rc;
  size_t nbed = 0;
  if (c->nfill) {
    snprintf(path, sizeof path, "%s/bed.data", dir);
    if ((rc = write_bed(c, path, &nbed, err))) return rc;
    if (progress) fprintf(stderr, "gransim dem (liggghts): initial bed of %zu particles in %s\n", nbed, path);
  }
  /* the meshes beside the deck; the exclusion runs: one per mesh, each writes
   * the facets LIGGGHTS refuses and stops */
  for (size_t w = 0; w < c->nwall_src && !rc; w++) {
    char deck[64], ex[4400], name[4200], copy[8500];
    gs_lig_mesh_name(c, w, name, sizeof name);
    snprintf(copy, sizeof copy, "%s/%s", dir, name);
    if ((rc = c->wall_src[w].kind == GS_DEM_SRC_PLANE ? gs_lig_write_plane_mesh(c, w, copy, err)
                                                      : copy_file(c->wall_src[w].mesh, copy, err)))
      return rc;
    snprintf(deck, sizeof deck, "in.exclude%zu", w);
    snprintf(ex, sizeof ex, "%s/ex_wall%zu.txt", dir, w);
    remove(ex);
    snprintf(path, sizeof path, "%s/%s", dir, deck);
    if ((rc = gs_lig_write_exclusion_deck(c, w, path, err))) return rc;
    if (dry) continue;
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
  /* statistics.start: steady: the deck before its runs, which gransim sends in chunks (run_chunks) */
  if (!rc && c->start_steady) {
    snprintf(path, sizeof path, "%s/in.setup", dir);
    if (!(fp = fopen(path, "w"))) return gs_error_set(err, GS_EIO, "%s: cannot write: %s", path, strerror(errno));
    rc = gs_lig_write_setup(c, fp, c->nfill ? "bed.data" : NULL, c->nwall_src ? "read" : NULL, err);
    if (fclose(fp) && !rc) rc = gs_error_set(err, GS_EIO, "%s: write failed", path);
  }
  if (!rc) rc = write_run_sh(c, dir, ranks, err);
  if (rc || dry) {
    if (!rc && progress)
      fprintf(stderr, "gransim dem (liggghts): wrote %s (deck in.gransim, run.sh); run it, then reduce with "
              "gransim dem %s --out %s --reduce\n", dir, c->path, out);
    return rc;
  }
  if (progress && c->start_steady)
    fprintf(stderr, "gransim dem (liggghts): cd %s && %s %s -log log.liggghts, reading in.setup and then the runs in "
            "chunks from gransim (statistics.start: steady)\n", dir, launch, bin);
  else if (progress) fprintf(stderr, "gransim dem (liggghts): cd %s && %s %s -in in.gransim -log log.liggghts\n", dir, launch, bin);
  gs_lig_thermo th = {.ncol = gs_lig_thermo_cols(c)};
  gs_lig_steady sd;
  gs_lig_steady_init(&sd, c);
  double t_end = c->duration;
  if (c->start_steady) rc = run_chunks(dir, launch, bin, c, progress, &th, &sd, &t_end, err);
  else rc = run_deck(dir, launch, bin, "in.gransim", "log.liggghts", "screen.liggghts", c, progress, &th, err);
  if (!rc) rc = reduce_window(c, out, &th, &sd, t_end, err);
  if (!rc) rc = gs_lig_vtk_frames(c, out, err);
  free(th.row);
  gs_lig_steady_free(&sd);
  return rc;
}
