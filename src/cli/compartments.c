/* `gransim compartments`: zones of a granulator from DEM particle frames
 * (LIGGGHTS dumps or the embedded DEM's particles.pvd) by k-means, written
 * as a case fragment the exchange mechanism reads (src/demdata/zones.h). */
#include <dirent.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "cli/commands.h"
#include "cli/options.h"
#include "demdata/vtp_frames.h"
#include "demdata/zones.h"

static void usage(FILE *fp) {
  fprintf(fp,
          "usage: gransim compartments FRAMES... --out FRAGMENT.yaml [--clusters K] [--max-clusters KMAX]\n"
          "                            [--time-step S] [--start T] [--velocity-weight W] [--seed N]\n\n"
          "FRAMES are LIGGGHTS/LAMMPS dump files (one snapshot each, columns id x y z vx vy vz and\n"
          "radius or diameter if known), directories holding them (*.atom, *.dump, *.liggghts), or\n"
          "the embedded DEM's particle collection DIR/vtk/particles.pvd (gransim dem with\n"
          "output.vtk_every).  Every particle of every frame is clustered by k-means on its\n"
          "position / L and W x velocity / U (L, U the RMS spreads of positions and velocities);\n"
          "--clusters gives k, else the k in 2..KMAX (default 6) of largest simplified silhouette\n"
          "is taken.  Exchange rates come from particles seen in one zone in a frame and in another\n"
          "in the next.  Dumps give steps: --time-step is the DEM time step in s.  The seed of the\n"
          "k-means++ starts is fixed (default 1).  --start leaves out the frames before T s (the fill\n"
          "settling).  The fragment gives compartments, rates,\n"
          "velocity (u0 per zone), hold-ups and centres (docs/case-files.md, exchange).\n");
}

static int ends_with(const char *s, const char *suffix) {
  size_t n = strlen(s), m = strlen(suffix);
  return n >= m && !strcmp(s + n - m, suffix);
}

static int by_name(const void *a, const void *b) { return strcmp(*(char *const *)a, *(char *const *)b); }

/* Every dump file of a directory, in name order. */
static int read_dir(gs_zone_frames *fr, const char *dir, double dt, gs_error *err) {
  DIR *d = opendir(dir);
  if (!d) return gs_error_set(err, GS_EIO, "cannot open directory %s: %s", dir, strerror(errno));
  char **names = NULL;
  size_t n = 0, cap = 0;
  int rc = GS_OK;
  for (struct dirent *e; !rc && (e = readdir(d));) {
    if (!ends_with(e->d_name, ".atom") && !ends_with(e->d_name, ".dump") && !ends_with(e->d_name, ".liggghts")) continue;
    if (n == cap) {
      cap = cap ? 2 * cap : 64;
      char **g = realloc(names, cap * sizeof *g);
      if (!g) { rc = gs_error_set(err, GS_ENOMEM, "out of memory"); break; }
      names = g;
    }
    size_t len = strlen(dir) + strlen(e->d_name) + 2;
    if (!(names[n] = malloc(len))) { rc = gs_error_set(err, GS_ENOMEM, "out of memory"); break; }
    snprintf(names[n++], len, "%s/%s", dir, e->d_name);
  }
  closedir(d);
  if (!rc && !n) rc = gs_error_set(err, GS_EINPUT, "%s holds no dump files (*.atom, *.dump, *.liggghts)", dir);
  if (!rc) qsort(names, n, sizeof *names, by_name);
  for (size_t i = 0; !rc && i < n; i++) rc = gs_zone_frames_read_dump(fr, names[i], dt, err);
  for (size_t i = 0; i < n; i++) free(names[i]);
  free(names);
  return rc;
}

static int num(const char *opt, const char *s, double lo, double *out) {
  char *end;
  errno = 0;
  double v = strtod(s, &end);
  if (end == s || *end || errno || !isfinite(v) || !(v > lo)) {
    fprintf(stderr, "gransim compartments: --%s needs a number > %g, got '%s'\n", opt, lo, s);
    return 2;
  }
  *out = v;
  return 0;
}

int gs_cmd_compartments(int argc, char **argv) {
  const char *out = NULL;
  int k = 0, kmax = 6, seed = 1, rc = 0;
  double dt = 0, weight = 1, start = -HUGE_VAL;
  static const struct option opts[] = {
      {"help", no_argument, NULL, GS_CLI_HELP},           {"out", required_argument, NULL, 'o'},
      {"clusters", required_argument, NULL, 'k'},         {"max-clusters", required_argument, NULL, 'K'},
      {"time-step", required_argument, NULL, 't'},        {"velocity-weight", required_argument, NULL, 'w'},
      {"seed", required_argument, NULL, 's'},             {"start", required_argument, NULL, 'S'},
      {0}};
  gs_cli_begin();
  for (int o; !rc && (o = gs_cli_next(argc, argv, opts)) != -1;) switch (o) {
    case GS_CLI_HELP: usage(stdout); return 0;
    case 'o': out = optarg; break;
    case 'k': rc = gs_cli_positive("compartments", "clusters", optarg, &k); break;
    case 'K': rc = gs_cli_positive("compartments", "max-clusters", optarg, &kmax); break;
    case 's': rc = gs_cli_positive("compartments", "seed", optarg, &seed); break;
    case 't': rc = num("time-step", optarg, 0, &dt); break;
    case 'w': rc = num("velocity-weight", optarg, -1e-300, &weight); break;
    case 'S': rc = num("start", optarg, -HUGE_VAL, &start); break;
    default: rc = 2;
    }
  if (!rc && (k > 15 || kmax > 15 || kmax < 2)) {
    fprintf(stderr, "gransim compartments: --clusters and --max-clusters must lie in 1..15 and 2..15\n");
    rc = 2;
  }
  if (!rc && (optind >= argc || !out)) {
    fprintf(stderr, "usage: gransim compartments FRAMES... --out FRAGMENT.yaml (see --help)\n");
    rc = 2;
  }
  if (rc) return rc;
  gs_error err = {0};
  gs_zone_frames fr = {0};
  for (int i = optind; !rc && i < argc; i++) {
    struct stat st;
    const int dump = !ends_with(argv[i], ".pvd");
    if (dump && !(dt > 0)) {
      fprintf(stderr, "gransim compartments: %s: dumps count steps; give --time-step S (the DEM's time step)\n", argv[i]);
      gs_zone_frames_free(&fr);
      return 2;
    }
    if (!dump) rc = gs_vtp_frames_read(&fr, argv[i], &err);
    else if (!stat(argv[i], &st) && S_ISDIR(st.st_mode)) rc = read_dir(&fr, argv[i], dt, &err);
    else rc = gs_zone_frames_read_dump(&fr, argv[i], dt, &err);
  }
  if (!rc) gs_zone_frames_keep_from(&fr, start);
  if (!rc) rc = gs_zone_frames_sort(&fr, &err);
  gs_zones z = {0};
  if (!rc) rc = gs_zones_identify(&fr, (size_t)k, (size_t)kmax, weight, (unsigned long)seed, &z, &err);
  if (!rc) {
    char *tmp = malloc(strlen(out) + 8);
    if (!tmp) rc = gs_error_set(&err, GS_ENOMEM, "out of memory");
    else sprintf(tmp, "%s.tmp", out);
    if (!rc) rc = gs_zones_write(&z, &fr, tmp, &err);
    if (!rc && rename(tmp, out)) rc = gs_error_set(&err, GS_EIO, "cannot rename %s to %s: %s", tmp, out, strerror(errno));
    if (rc && tmp) remove(tmp);
    free(tmp);
  }
  if (!rc) {
    printf("%zu frames, %zu particle samples; %zu zones (silhouette %.3f); largest K dt %.3g\n", fr.nframe,
           z.nsample, z.k, z.silhouette, z.max_rate_dt);
    printf("%4s %10s %10s %10s %10s %10s\n", "zone", "holdup", "speed[m/s]", "x[m]", "y[m]", "z[m]");
    for (size_t c = 0; c < z.k; c++)
      printf("%4zu %10.4g %10.4g %10.4g %10.4g %10.4g\n", c + 1, z.holdup[c], z.speed[c], z.centre[3 * c],
             z.centre[3 * c + 1], z.centre[3 * c + 2]);
    printf("fragment: %s\n", out);
  } else fprintf(stderr, "gransim compartments: %s\n", err.msg);
  gs_zones_free(&z);
  gs_zone_frames_free(&fr);
  return rc ? 1 : 0;
}
